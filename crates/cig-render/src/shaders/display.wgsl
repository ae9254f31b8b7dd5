// Display correction (cig_scene::display): the warp grid's triangles placed at their display
// positions, textured with the view; then the edge-blend ramps. Works on gamma-encoded values
// (both textures are viewed as plain Rgba8Unorm), so the blend multiplies the projector's input.

struct DisplayParams {
    // Source (view) size in pixels, xy; target (display) size in pixels, zw.
    sizes: vec4<f32>,
    // Ramp widths as fractions of the display: left, right, top, bottom.
    ramps: vec4<f32>,
    // x: 1 / gamma; y: 1 when the target is viewed with sRGB encoding (write linear values,
    // which its store encodes back to the frame's); z: 1 when the frame is read through an
    // sRGB view (its values arrive decoded: encode them first).
    gamma: vec4<f32>,
};

@group(0) @binding(0) var view_frame: texture_2d<f32>;
@group(0) @binding(1) var view_sampler: sampler;
@group(0) @binding(2) var<uniform> params: DisplayParams;

struct VsOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) view_uv: vec2<f32>,
};

@vertex
fn vs_main(@location(0) display: vec2<f32>, @location(1) view_uv: vec2<f32>) -> VsOut {
    var out: VsOut;
    out.clip = vec4<f32>(display.x * 2.0 - 1.0, 1.0 - display.y * 2.0, 0.0, 1.0);
    out.view_uv = view_uv;
    return out;
}

fn ramp(distance: f32, width: f32) -> f32 {
    if width <= 0.0 {
        return 1.0;
    }
    let t = clamp(distance / width, 0.0, 1.0);
    return t * t * (3.0 - 2.0 * t);
}

@fragment
fn fs_main(in: VsOut) -> @location(0) vec4<f32> {
    let source_size = params.sizes.xy;
    let texel = in.view_uv * source_size - 0.5;
    let nearest = round(texel);
    var colour: vec4<f32>;
    // On a texel's centre (within a 64th of a texel: the identity, or a whole-pixel shift) the
    // texel itself, exactly; elsewhere bilinear.
    if all(abs(texel - nearest) < vec2<f32>(1.0 / 64.0)) {
        let at = vec2<i32>(clamp(nearest, vec2<f32>(0.0), source_size - 1.0));
        colour = textureLoad(view_frame, at, 0);
    } else {
        colour = textureSampleLevel(view_frame, view_sampler, in.view_uv, 0.0);
    }
    let p = in.clip.xy / params.sizes.zw;
    let weight = ramp(p.x, params.ramps.x) * ramp(1.0 - p.x, params.ramps.y)
        * ramp(p.y, params.ramps.z) * ramp(1.0 - p.y, params.ramps.w);
    var encoded = colour.rgb;
    if params.gamma.z > 0.5 {
        encoded = linear_to_srgb(colour.rgb);
    }
    let shown = encoded * pow(weight, params.gamma.x);
    if params.gamma.y > 0.5 {
        return vec4<f32>(srgb_to_linear(shown), 1.0);
    }
    return vec4<f32>(shown, 1.0);
}

fn linear_to_srgb(c: vec3<f32>) -> vec3<f32> {
    let low = c * 12.92;
    let high = 1.055 * pow(c, vec3<f32>(1.0 / 2.4)) - 0.055;
    return select(high, low, c <= vec3<f32>(0.0031308));
}

fn srgb_to_linear(c: vec3<f32>) -> vec3<f32> {
    let low = c / 12.92;
    let high = pow((c + 0.055) / 1.055, vec3<f32>(2.4));
    return select(high, low, c <= vec3<f32>(0.04045));
}
