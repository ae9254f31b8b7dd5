// Soft contact with the scene: the frame's depth samples, read as plain floats (GLSL has no
// textureLoad of depth textures), cut the Gaussian's distribution along the ray.

@group(0) @binding(1) var scene_depth: texture_multisampled_2d<f32>;

const FRONT_BILLBOARD: bool = false;

// The part of the puff's column (sigma `sigma`, nearest the ray at `s0` along it) between the
// eye and the scene behind, averaged over the pixel's depth samples.
fn scene_fraction(pixel: vec2<i32>, dir: vec3<f32>, s0: f32, sigma: f32) -> f32 {
    let along = max(dot(dir, g.cam_forward.xyz), 1e-4);
    let inv = 0.70710678 / sigma;
    let behind_eye = erf_approx(-s0 * inv);
    var erf_sum = 0.0;
    for (var s = 0; s < SCENE_SAMPLES; s++) {
        let depth = textureLoad(scene_depth, pixel, s).x;
        var reach = 1.0;
        if (depth > 0.0) {
            // Reversed-Z infinite projection: depth = near / distance along the view axis.
            reach = erf_approx((NEAR_PLANE_M / depth / along - s0) * inv);
        }
        erf_sum += max(reach - behind_eye, 0.0);
    }
    return 0.5 * erf_sum / f32(SCENE_SAMPLES);
}
