// Upsamples the half-resolution cloud frame (see clouds.rs) onto the frame, with blending
// `src + dst * src_alpha`: the clouds' radiance over the scene times what it keeps.

struct CompositeOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) ndc: vec2<f32>,
};

@vertex
fn vs_main(@builtin(vertex_index) i: u32) -> CompositeOut {
    let xy = vec2<f32>(f32((i << 1u) & 2u), f32(i & 2u)) * 2.0 - 1.0;
    var out: CompositeOut;
    out.clip = vec4<f32>(xy, 0.0, 1.0);
    out.ndc = xy;
    return out;
}

@group(0) @binding(1) var half_frame: texture_2d<f32>;
@group(0) @binding(2) var half_sampler: sampler;

@fragment
fn fs_main(in: CompositeOut) -> @location(0) vec4<f32> {
    let uv = vec2<f32>(0.5 + 0.5 * in.ndc.x, 0.5 - 0.5 * in.ndc.y);
    // Four bilinear taps half a half-frame texel apart diagonally: a smooth kernel (weights
    // 1/8, 1/2, 3/8 per axis, centred on this pixel) that evens out the march's per-pixel
    // sample offsets and leaves no trace of the half-resolution grid, since both quarters of a
    // half-frame texel get the same kernel shape. (Taps 0.75 or 1 texel apart weigh the texels
    // unevenly by quarter: a 2-pixel checker.)
    let d = 0.5 / vec2<f32>(textureDimensions(half_frame));
    let sum = textureSampleLevel(half_frame, half_sampler, uv + vec2<f32>(-d.x, -d.y), 0.0)
        + textureSampleLevel(half_frame, half_sampler, uv + vec2<f32>(d.x, -d.y), 0.0)
        + textureSampleLevel(half_frame, half_sampler, uv + vec2<f32>(-d.x, d.y), 0.0)
        + textureSampleLevel(half_frame, half_sampler, uv + vec2<f32>(d.x, d.y), 0.0);
    return 0.25 * sum;
}
