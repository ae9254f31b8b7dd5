// Light points (lights.rs): each light a screen-aligned square around its projected point,
// filled with the display's point spread (a Gaussian of frame.viewport.z pixels) carrying the
// light's illuminance at the eye (vs_main, fs_main: in the multisampled scene, depth-tested,
// writing no depth), and on goggles a halo disc of constant angular size carrying
// frame.viewport.w of it, drawn over everything when the light's centre is seen (vs_halo,
// fs_halo: after the scene is resolved, the centre tested against the depth samples); where
// depth samples cannot be read (GL), the halo is drawn with the core (frame.mode.x 1).

struct Light {
    // Eye-relative position (pulled half a metre toward the eye, so a lamp on a model's face
    // is not hidden by it); w: the light's illuminance at the eye as pre-exposed scene units
    // per unit of the spread's weight (pi E ppt^2 units exposure).
    rel: vec4<f32>,
    // Colour (unit luminance, or grey on goggles); w: the halo's radius, pixels (0: none).
    colour: vec4<f32>,
};

struct LightFrame {
    // Viewport width and height (pixels), the point spread's sigma (pixels), the halo's share.
    viewport: vec4<f32>,
    // x: 1 to draw the halo with the core (no halo pass).
    mode: vec4<f32>,
};

@group(0) @binding(1) var<storage, read> lights: array<Light>;
@group(0) @binding(2) var<uniform> frame: LightFrame;

struct LightOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) offset_px: vec2<f32>,
    @location(1) @interpolate(flat) colour: vec4<f32>,
    @location(2) @interpolate(flat) value: f32,
};

// The light's clip position, pulled half a metre toward the eye.
fn light_clip(l: Light) -> vec4<f32> {
    let d = max(length(l.rel.xyz), 1e-3);
    return g.view_proj * vec4<f32>(refracted(l.rel.xyz) * max(1.0 - 0.5 / d, 0.0), 1.0);
}

@vertex
fn vs_main(@builtin(vertex_index) vertex: u32, @builtin(instance_index) instance: u32) -> LightOut {
    return corner(vertex, instance, frame.mode.x > 0.5);
}

fn corner(vertex: u32, instance: u32, with_halo: bool) -> LightOut {
    let l = lights[instance];
    var out: LightOut;
    let c = light_clip(l);
    out.colour = l.colour;
    if (!with_halo) {
        // Negative: the halo pass draws it (the core still gives it its share).
        out.colour.w = -out.colour.w;
    }
    out.value = l.rel.w;
    if (c.w < 0.05) {
        out.clip = vec4<f32>(0.0, 0.0, -1.0, 1.0);
        out.offset_px = vec2<f32>(0.0);
        return out;
    }
    let sigma = frame.viewport.z;
    let half_px = max(3.0 * sigma, max(out.colour.w, 0.0) * 1.05 + 1.0);
    let corners = array<vec2<f32>, 6>(
        vec2<f32>(-1.0, -1.0), vec2<f32>(1.0, -1.0), vec2<f32>(1.0, 1.0),
        vec2<f32>(-1.0, -1.0), vec2<f32>(1.0, 1.0), vec2<f32>(-1.0, 1.0),
    );
    let offset = corners[vertex % 6u] * half_px;
    out.offset_px = offset;
    out.clip = c + vec4<f32>(offset / (0.5 * frame.viewport.xy) * c.w, 0.0, 0.0);
    return out;
}

@fragment
fn fs_main(in: LightOut) -> @location(0) vec4<f32> {
    let r2 = dot(in.offset_px, in.offset_px);
    let s2 = frame.viewport.z * frame.viewport.z;
    let halo_r = in.colour.w;
    var core_share = 1.0;
    var halo = 0.0;
    if (halo_r != 0.0) {
        core_share = 1.0 - frame.viewport.w;
    }
    if (halo_r > 0.0) {
        // A disc with a soft pixel-wide edge, its weight spread over its area.
        let edge = clamp(halo_r - sqrt(r2) + 0.5, 0.0, 1.0);
        halo = frame.viewport.w * edge / (3.14159265 * halo_r * halo_r);
    }
    let core = core_share * exp(-0.5 * r2 / s2) / (6.2831853 * s2);
    let value = in.value * (core + halo);
    if (value <= 0.0) {
        discard;
    }
    return vec4<f32>(in.colour.rgb * value, 0.0);
}

@group(0) @binding(3) var scene_depth: texture_multisampled_2d<f32>;

// A halo's square, degenerate where the scene hides the light's centre (or the light has no
// halo).
@vertex
fn vs_halo(@builtin(vertex_index) vertex: u32, @builtin(instance_index) instance: u32) -> LightOut {
    var out = corner(vertex, instance, true);
    let c = light_clip(lights[instance]);
    let dims = vec2<i32>(textureDimensions(scene_depth));
    let ndc = c.xyz / max(c.w, 1e-6);
    let px = vec2<i32>(vec2<f32>((ndc.x * 0.5 + 0.5) * f32(dims.x), (0.5 - ndc.y * 0.5) * f32(dims.y)));
    var hidden = out.colour.w <= 0.0 || c.w < 0.05;
    if (!hidden && all(px >= vec2<i32>(0)) && all(px < dims)) {
        // Reversed depth: a larger sample is nearer than the light.
        hidden = textureLoad(scene_depth, px, 0).x > ndc.z * 1.0001;
    }
    if (hidden) {
        out.clip = vec4<f32>(0.0, 0.0, -1.0, 1.0);
    }
    return out;
}

@fragment
fn fs_halo(in: LightOut) -> @location(0) vec4<f32> {
    let halo_r = in.colour.w;
    let edge = clamp(halo_r - length(in.offset_px) + 0.5, 0.0, 1.0);
    let value = in.value * frame.viewport.w * edge / (3.14159265 * halo_r * halo_r);
    if (value <= 0.0) {
        discard;
    }
    return vec4<f32>(in.colour.rgb * value, 0.0);
}
