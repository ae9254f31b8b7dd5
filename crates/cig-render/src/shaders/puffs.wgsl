// Obscurant puffs: order-independent accumulation of optical depth and in-scattered light
// (see puffs.rs for the algorithm). Rust prepends `NEAR_PLANE_M`, `SCENE_SAMPLES` and one of
// puff_depth_samples.wgsl (soft contact read from the depth samples) or puff_depth_test.wgsl
// (the GL fallback: a depth test at the front of each puff), which define
// `FRONT_BILLBOARD` and `scene_fraction`.

// Billboard radius in the puff's sigmas, and the Gaussian's value there (exp(-2.5^2 / 2)).
const RADIUS_SIGMAS: f32 = 2.5;
const EDGE_GAUSS: f32 = 0.043936934;
// Radiance of fully glowing flame gas, in units of the frame's white.
const FLAME_RADIANCE: f32 = 2.5;
// Largest centre optical depth (opacity 0.9999).
const MAX_TAU: f32 = 9.21;

struct PuffOut {
    @builtin(position) clip: vec4<f32>,
    // Eye-relative point on the billboard (or the view ray): the pixel's ray direction.
    @location(0) ray: vec3<f32>,
    @location(1) @interpolate(flat) centre_radius: vec4<f32>,
    // Albedo (the part of the colour that scatters light) and the centre optical depth.
    @location(2) @interpolate(flat) albedo_tau: vec4<f32>,
    @location(3) @interpolate(flat) emission: vec4<f32>,
};

@vertex
fn vs_main(
    @builtin(vertex_index) vertex: u32,
    @location(0) position_radius: vec4<f32>,
    @location(1) colour_opacity: vec4<f32>,
    @location(2) emissive_temperature: vec2<f32>,
) -> PuffOut {
    var out: PuffOut;
    let c = position_radius.xyz;
    let r = position_radius.w;
    let d2 = dot(c, c);
    let d = sqrt(d2);
    let emissive = clamp(emissive_temperature.x, 0.0, 1.0);
    out.centre_radius = position_radius;
    out.albedo_tau = vec4<f32>(
        colour_opacity.rgb * (1.0 - emissive),
        min(-log(max(1.0 - colour_opacity.w, 1e-4)), MAX_TAU),
    );
    out.emission = vec4<f32>(colour_opacity.rgb * emissive * FLAME_RADIANCE, 0.0);
    if (d2 < 1.21 * r * r || (FRONT_BILLBOARD && d - r < 2.0 * NEAR_PLANE_M)) {
        // The eye is in (or at the edge of) the puff: a full-screen triangle of view rays.
        if (vertex >= 3u) {
            out.clip = vec4<f32>(0.0, 0.0, 0.5, 1.0);
            out.ray = g.cam_forward.xyz;
            return out;
        }
        let xy = vec2<f32>(f32((vertex << 1u) & 2u), f32(vertex & 2u)) * 2.0 - 1.0;
        let t = g.tangents;
        let x_tan = mix(-t.x, t.y, xy.x * 0.5 + 0.5);
        let y_tan = mix(-t.z, t.w, xy.y * 0.5 + 0.5);
        out.clip = vec4<f32>(xy, 0.5, 1.0);
        out.ray = g.cam_forward.xyz + g.cam_right.xyz * x_tan + g.cam_up.xyz * y_tan;
        return out;
    }
    // A square facing the eye through the centre (or, for the depth test, through the
    // sphere's nearest point), large enough to hold the sphere's outline.
    let n = c / d;
    var plane_m = d;
    if (FRONT_BILLBOARD) {
        plane_m = d - r;
    }
    var side = cross(n, g.cam_up.xyz);
    if (dot(side, side) < 1e-6) {
        side = cross(n, g.cam_right.xyz);
    }
    side = normalize(side);
    let up = cross(side, n);
    let half_size = r * plane_m / sqrt(d2 - r * r);
    let corners = array<vec2<f32>, 6>(
        vec2<f32>(-1.0, -1.0), vec2<f32>(1.0, -1.0), vec2<f32>(1.0, 1.0),
        vec2<f32>(-1.0, -1.0), vec2<f32>(1.0, 1.0), vec2<f32>(-1.0, 1.0),
    );
    let k = corners[min(vertex, 5u)];
    let p = n * plane_m + (side * k.x + up * k.y) * half_size;
    out.clip = g.view_proj * vec4<f32>(refracted(p), 1.0);
    out.ray = p;
    return out;
}

// erf(x), Abramowitz and Stegun 7.1.26 (absolute error below 1.5e-7).
fn erf_approx(x: f32) -> f32 {
    let a = abs(x);
    let t = 1.0 / (1.0 + 0.3275911 * a);
    let poly = t * (0.254829592 + t * (-0.284496736 + t * (1.421413741 + t * (-1.453152027 + t * 1.061405429))));
    let y = 1.0 - poly * exp(-a * a);
    return select(y, -y, x < 0.0);
}

struct Accumulated {
    // rgb: optical depth times in-scattered radiance; a: optical depth.
    @location(0) scatter: vec4<f32>,
    // rgb: emitted radiance reaching the eye.
    @location(1) emission: vec4<f32>,
};

@fragment
fn fs_main(in: PuffOut) -> Accumulated {
    let dir = normalize(in.ray);
    let c = in.centre_radius.xyz;
    let r = in.centre_radius.w;
    let sigma = r / RADIUS_SIGMAS;
    let s0 = dot(c, dir);
    let b2 = max(dot(c, c) - s0 * s0, 0.0);
    // Column optical depth of the Gaussian at this ray's distance from the centre, windowed to
    // reach zero at the billboard's radius (no visible rim).
    let window = (exp(-0.5 * b2 / (sigma * sigma)) - EDGE_GAUSS) / (1.0 - EDGE_GAUSS);
    if (window <= 0.0) {
        discard;
    }
    let fraction = scene_fraction(vec2<i32>(in.clip.xy), dir, s0, sigma);
    let tau = in.albedo_tau.w * window * fraction;
    if (tau <= 0.0) {
        discard;
    }
    if (g.sensor.x > 0.5) {
        // A thermal sensor (puffs.rs's infrared_puff): the colour is the gas's band radiance,
        // a flame's is emission.
        var sensed: Accumulated;
        sensed.scatter = vec4<f32>(in.albedo_tau.rgb * tau, tau);
        sensed.emission = vec4<f32>(in.emission.rgb / FLAME_RADIANCE * (1.0 - exp(-tau)), 0.0);
        return sensed;
    }
    // Light: the sun on the side of the puff it faces (wrapped, light passes through thin
    // smoke) and the sky's ambient, as the terrain is lit.
    var n = -dir;
    if (b2 < r * r) {
        n = (dir * (s0 - sqrt(r * r - b2)) - c) / r;
    }
    let sun = g.sun_colour.rgb * (0.5 + 0.5 * dot(n, g.sun_dir.xyz));
    let moon = g.moon_colour.rgb * (0.5 + 0.5 * dot(n, g.moon_dir.xyz));
    let sky = g.ambient.rgb * (0.6 + 0.4 * dot(n, g.eye_up.xyz));
    let distance_m = max(s0, 0.0);
    let f = fog_factor(distance_m) * fog_layer_transmittance(dir * distance_m);
    // Aerial perspective, the fog and the ground fog layer, as on the terrain.
    let shown = apply_atmosphere_exposed(exposed(in.albedo_tau.rgb * (sun + moon + sky)), dir * distance_m);
    var out: Accumulated;
    out.scatter = vec4<f32>(shown * tau, tau);
    // On goggles a flame's glow is weighted by its spectrum (rich in the near infrared).
    let flame = select(1.0, g.nvg3.y, nvg_on());
    out.emission = vec4<f32>(exposed(in.emission.rgb) * (flame * f * (1.0 - exp(-tau))), 0.0);
    return out;
}
