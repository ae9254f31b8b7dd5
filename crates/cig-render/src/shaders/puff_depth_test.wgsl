// The GL fallback (wgpu's GL backend cannot sample multisampled textures): puffs are drawn at
// their nearest point and depth-tested against the scene, per sample; no soft contact.

const FRONT_BILLBOARD: bool = true;

// The part of the puff's column in front of the eye.
fn scene_fraction(pixel: vec2<i32>, dir: vec3<f32>, s0: f32, sigma: f32) -> f32 {
    return 0.5 * (1.0 - erf_approx(-s0 * 0.70710678 / sigma));
}
