// The frame's tone map: pre-exposed linear radiance (the HDR scene target), times the eye's
// adaptation to the view, to display values.
// Below 10 lux the colour shifts toward the scotopic blue-grey (rods see no colour; the
// blue-shift of H. W. Jensen et al., "A Night Rendering", 2000); then the ACES filmic curve
// (K. Narkowicz's fit, 2015) per channel; the sRGB curve is applied here when the target is
// not an sRGB format (the hardware encodes sRGB targets).

@group(1) @binding(0) var scene: texture_2d<f32>;
// The eye's adaptation to the view (adaptation.rs): x the log2 factor on the pre-exposed scene.
@group(1) @binding(1) var<uniform> adaptation: vec4<f32>;

struct ToneOut {
    @builtin(position) clip: vec4<f32>,
};

@vertex
fn vs_main(@builtin(vertex_index) i: u32) -> ToneOut {
    let xy = vec2<f32>(f32((i << 1u) & 2u), f32(i & 2u)) * 2.0 - 1.0;
    var out: ToneOut;
    out.clip = vec4<f32>(xy, 0.0, 1.0);
    return out;
}

fn aces(x: vec3<f32>) -> vec3<f32> {
    return clamp((x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14), vec3<f32>(0.0), vec3<f32>(1.0));
}

fn srgb_encode(c: vec3<f32>) -> vec3<f32> {
    let lo = c * 12.92;
    let hi = 1.055 * pow(c, vec3<f32>(1.0 / 2.4)) - 0.055;
    return select(hi, lo, c <= vec3<f32>(0.0031308));
}

@fragment
fn fs_main(in: ToneOut) -> @location(0) vec4<f32> {
    var c = textureLoad(scene, vec2<i32>(in.clip.xy), 0).rgb;
    // A NaN or infinity from any pass becomes black or the brightest value, on every GPU.
    c = select(c, vec3<f32>(0.0), c != c);
    c = clamp(c, vec3<f32>(0.0), vec3<f32>(65504.0));
    var out: vec3<f32>;
    if (g.flags.z > 0.5) {
        // Keyed test frames: linear radiance, clamped.
        out = min(c, vec3<f32>(1.0));
    } else {
        c *= exp2(adaptation.x);
        let s = g.tonemap.y;
        if (s > 0.0) {
            // Rod response over the sRGB primaries (peak near 507 nm), shown blue-grey.
            let rods = dot(c, vec3<f32>(0.06, 0.55, 0.39));
            c = mix(c, rods * vec3<f32>(0.80, 0.95, 1.30), s);
        }
        out = aces(c);
    }
    if (g.tonemap.x > 0.5) {
        out = srgb_encode(out);
    }
    return vec4<f32>(out, 1.0);
}
