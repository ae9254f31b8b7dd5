struct Instance {
    // Body to eye-relative ECEF: columns of the rotation (scaled), and the origin (w unused).
    col0: vec4<f32>,
    col1: vec4<f32>,
    col2: vec4<f32>,
    origin: vec4<f32>,
};

@group(0) @binding(1) var<storage, read> instances: array<Instance>;

struct ModelOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) rel: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) colour: vec3<f32>,
    // Share of the model's pixels this draw covers, [x, y) in dither thresholds.
    @location(3) @interpolate(flat) share: vec2<f32>,
};

// Ordered 4x4 (Bayer) dither threshold of a pixel, in (0, 1).
fn dither_threshold(pixel: vec2<f32>) -> f32 {
    let bayer = array<f32, 16>(0.0, 8.0, 2.0, 10.0, 12.0, 4.0, 14.0, 6.0, 3.0, 11.0, 1.0, 9.0, 15.0, 7.0, 13.0, 5.0);
    let x = u32(pixel.x) & 3u;
    let y = u32(pixel.y) & 3u;
    return (bayer[y * 4u + x] + 0.5) / 16.0;
}

@vertex
fn vs_main(
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) colour: vec4<f32>,
    @builtin(instance_index) instance: u32,
) -> ModelOut {
    let m = instances[instance];
    let rel = m.col0.xyz * position.x + m.col1.xyz * position.y + m.col2.xyz * position.z + m.origin.xyz;
    var out: ModelOut;
    out.clip = g.view_proj * vec4<f32>(rel, 1.0);
    out.rel = rel;
    out.normal = normalize(m.col0.xyz * normal.x + m.col1.xyz * normal.y + m.col2.xyz * normal.z);
    // origin.w: a culture instance's tint (0 for entities).
    out.colour = pow(colour.rgb, vec3<f32>(2.2)) * (1.0 + m.origin.w);
    out.share = vec2<f32>(m.col0.w, m.col1.w);
    return out;
}

@fragment
fn fs_main(in: ModelOut) -> @location(0) vec4<f32> {
    // Level-of-detail blending: two levels cover complementary shares of the pixels.
    let threshold = dither_threshold(in.clip.xy);
    if (threshold < in.share.x || threshold >= in.share.y) {
        discard;
    }
    if (g.flags.x > 0.5) {
        return vec4<f32>(1.0, 0.6, 0.2, 1.0);
    }
    var n = normalize(in.normal);
    let colour = lit(in.colour, n);
    return vec4<f32>(apply_atmosphere_exposed(exposed(colour), in.rel), 1.0);
}
