// Shared declarations of every cig shader (concatenated in front of each module).

struct Globals {
    view_proj: mat4x4<f32>,
    // Camera basis (ECEF axes): xyz, w unused.
    cam_forward: vec4<f32>,
    cam_right: vec4<f32>,
    cam_up: vec4<f32>,
    // Frustum tangents: left, right, down, up.
    tangents: vec4<f32>,
    // Local up at the eye; w = horizon dip (radians).
    eye_up: vec4<f32>,
    // Towards the sun; w = sun elevation (degrees).
    sun_dir: vec4<f32>,
    sun_colour: vec4<f32>,
    ambient: vec4<f32>,
    sky_zenith: vec4<f32>,
    sky_horizon: vec4<f32>,
    fog_colour: vec4<f32>,
    // mode (0 off, 1 linear, 2 exp, 3 exp2), density, start, end.
    fog: vec4<f32>,
    // Eye position modulo each detail-noise period, in noise cells.
    noise0: vec4<f32>,
    noise1: vec4<f32>,
    noise2: vec4<f32>,
    // x: wireframe flag, y: exposure, z: key the background, w: pixels per unit tangent.
    flags: vec4<f32>,
};

@group(0) @binding(0) var<uniform> g: Globals;

fn fog_factor(distance_m: f32) -> f32 {
    let mode = i32(g.fog.x + 0.5);
    if (mode == 1) {
        return clamp((g.fog.w - distance_m) / max(g.fog.w - g.fog.z, 1e-3), 0.0, 1.0);
    } else if (mode == 2) {
        return exp(-g.fog.y * distance_m);
    } else if (mode == 3) {
        let x = g.fog.y * distance_m;
        return exp(-x * x);
    }
    return 1.0;
}

fn apply_fog(colour: vec3<f32>, distance_m: f32) -> vec3<f32> {
    let f = fog_factor(distance_m);
    return f * colour + (1.0 - f) * g.fog_colour.rgb;
}

fn lit(albedo: vec3<f32>, n: vec3<f32>) -> vec3<f32> {
    let diffuse = max(dot(n, g.sun_dir.xyz), 0.0);
    let sky = 0.6 + 0.4 * dot(n, g.eye_up.xyz);
    return albedo * (g.sun_colour.rgb * diffuse + g.ambient.rgb * sky);
}
