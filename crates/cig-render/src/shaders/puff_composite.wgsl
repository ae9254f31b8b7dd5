// Composites the accumulated obscurants onto the resolved frame (see puffs.rs): with blending
// `src + dst * src_alpha`, the frame becomes scene * T + mean radiance * (1 - T) + emission,
// T = exp(-sum of optical depths).

@group(0) @binding(1) var scatter_sum: texture_2d<f32>;
@group(0) @binding(2) var emission_sum: texture_2d<f32>;

struct CompositeOut {
    @builtin(position) clip: vec4<f32>,
};

@vertex
fn vs_main(@builtin(vertex_index) i: u32) -> CompositeOut {
    let xy = vec2<f32>(f32((i << 1u) & 2u), f32(i & 2u)) * 2.0 - 1.0;
    var out: CompositeOut;
    out.clip = vec4<f32>(xy, 0.0, 1.0);
    return out;
}

@fragment
fn fs_main(in: CompositeOut) -> @location(0) vec4<f32> {
    let pixel = vec2<i32>(in.clip.xy);
    let a = textureLoad(scatter_sum, pixel, 0);
    let e = textureLoad(emission_sum, pixel, 0).rgb;
    let tau = max(a.w, 0.0);
    let transmittance = exp(-tau);
    var scattered = vec3<f32>(0.0);
    if (tau > 1e-6) {
        scattered = a.rgb / tau * (1.0 - transmittance);
    }
    return vec4<f32>(scattered + e, transmittance);
}
