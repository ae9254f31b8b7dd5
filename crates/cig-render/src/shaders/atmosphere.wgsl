// The physical atmosphere on the GPU (included after common.wgsl by the sky, sky-view,
// terrain, model and puff shaders; the ATM_* constants are generated from
// cig_environment::AtmosphereParams::EARTH by crate::atmosphere). Same maths as
// cig_environment::atmosphere (Bruneton 2017 mapping, Hillaire 2020 sky-view table).

@group(1) @binding(0) var sky_view_lut: texture_2d<f32>;
@group(1) @binding(1) var transmittance_lut: texture_2d<f32>;
@group(1) @binding(2) var multi_scattering_lut: texture_2d<f32>;
@group(1) @binding(3) var lut_sampler: sampler;
@group(1) @binding(4) var sky_view_sampler: sampler;
// The sky-view pass's second table: the source function L / (1 − T(ray)) of each direction.
@group(1) @binding(5) var sky_source_lut: texture_2d<f32>;

const PI: f32 = 3.14159265;

// The unit range [0, 1] onto texel centres (first and last texel hold the ends).
fn unit_to_tex(u: f32, n: f32) -> f32 {
    return 0.5 / n + clamp(u, 0.0, 1.0) * (1.0 - 1.0 / n);
}

fn distance_to_top(r: f32, mu: f32) -> f32 {
    let disc = r * r * (mu * mu - 1.0) + ATM_TOP * ATM_TOP;
    return max(-r * mu + sqrt(max(disc, 0.0)), 0.0);
}

// Distance to the ground, or -1 when the ray misses it.
fn distance_to_ground(r: f32, mu: f32) -> f32 {
    let disc = r * r * (mu * mu - 1.0) + ATM_BOTTOM * ATM_BOTTOM;
    if (mu < 0.0 && disc >= 0.0) {
        return max(-r * mu - sqrt(disc), 0.0);
    }
    return -1.0;
}

fn transmittance_uv(r: f32, mu: f32) -> vec2<f32> {
    let h = sqrt(ATM_TOP * ATM_TOP - ATM_BOTTOM * ATM_BOTTOM);
    let rho = sqrt(max(r * r - ATM_BOTTOM * ATM_BOTTOM, 0.0));
    let d = distance_to_top(r, mu);
    let d_min = ATM_TOP - r;
    let d_max = rho + h;
    let x_mu = (d - d_min) / max(d_max - d_min, 1.0);
    let x_r = rho / h;
    let size = vec2<f32>(textureDimensions(transmittance_lut));
    return vec2<f32>(unit_to_tex(x_mu, size.x), unit_to_tex(x_r, size.y));
}

// Transmittance from radius r along zenith cosine mu to the top (0 into the ground).
fn transmittance_to_top(r: f32, mu: f32) -> vec3<f32> {
    if (distance_to_ground(r, mu) >= 0.0) {
        return vec3<f32>(0.0);
    }
    return textureSampleLevel(transmittance_lut, lut_sampler, transmittance_uv(r, mu), 0.0).rgb;
}

// Sunlight reaching radius r with the sun at zenith cosine mu_s, the disc fading through the
// horizon.
fn sun_transmittance(r: f32, mu_s: f32) -> vec3<f32> {
    let sin_h = ATM_BOTTOM / r;
    let cos_h = -sqrt(max(1.0 - sin_h * sin_h, 0.0));
    let visible = clamp((mu_s - cos_h) / (2.0 * ATM_SUN_RADIUS * sin_h) + 0.5, 0.0, 1.0);
    let t = textureSampleLevel(transmittance_lut, lut_sampler, transmittance_uv(r, max(mu_s, cos_h)), 0.0).rgb;
    return t * visible;
}

fn multi_scattering(r: f32, mu_s: f32) -> vec3<f32> {
    let size = vec2<f32>(textureDimensions(multi_scattering_lut));
    let uv = vec2<f32>(
        unit_to_tex(mu_s * 0.5 + 0.5, size.x),
        unit_to_tex((r - ATM_BOTTOM) / (ATM_TOP - ATM_BOTTOM), size.y),
    );
    return textureSampleLevel(multi_scattering_lut, lut_sampler, uv, 0.0).rgb;
}

// Eye radius from the planet's centre.
fn eye_radius() -> f32 {
    return g.atmos.x;
}

// The sky-view frame: the horizontal toward the sun's azimuth, the third axis and local up
// (from the globals, worked out once per frame by the renderer).
fn sky_frame() -> mat3x3<f32> {
    return mat3x3<f32>(g.sky_frame_x.xyz, g.sky_frame_y.xyz, g.eye_up.xyz);
}

// Hillaire's latitude mapping (concentrated at the horizon) for the eye's radius.
fn horizon_zenith_angle() -> f32 {
    return g.sky_frame_x.w;
}

// Sky-view table coordinates of a world direction.
fn sky_view_uv(dir: vec3<f32>) -> vec2<f32> {
    let f = sky_frame();
    let local = vec3<f32>(dot(dir, f[0]), dot(dir, f[1]), dot(dir, f[2]));
    let zenith = acos(clamp(local.z, -1.0, 1.0));
    let zh = horizon_zenith_angle();
    let beta = PI - zh;
    var v: f32;
    if (zenith < zh) {
        v = 0.5 * (1.0 - sqrt(max(1.0 - zenith / zh, 0.0)));
    } else {
        v = 0.5 + 0.5 * sqrt(clamp((zenith - zh) / beta, 0.0, 1.0));
    }
    let azimuth = atan2(local.y, local.x);
    return vec2<f32>(fract(azimuth / (2.0 * PI) + 1.0), v);
}

// World direction of sky-view table coordinates.
fn sky_view_dir(uv: vec2<f32>) -> vec3<f32> {
    let zh = horizon_zenith_angle();
    let beta = PI - zh;
    var zenith: f32;
    if (uv.y < 0.5) {
        let c = 1.0 - 2.0 * uv.y;
        zenith = zh * (1.0 - c * c);
    } else {
        let c = uv.y * 2.0 - 1.0;
        zenith = zh + beta * c * c;
    }
    let azimuth = uv.x * 2.0 * PI;
    let f = sky_frame();
    let s = sin(zenith);
    return normalize(f[0] * (s * cos(azimuth)) + f[1] * (s * sin(azimuth)) + f[2] * cos(zenith));
}

// Pre-exposed sky radiance (π L × light units × exposure) along a world direction.
fn sky_radiance(dir: vec3<f32>) -> vec3<f32> {
    return textureSampleLevel(sky_view_lut, sky_view_sampler, sky_view_uv(dir), 0.0).rgb;
}

// Optical depth from the eye to a point `dh` metres above it and `d` metres away (flat-layer
// exponential profiles, exact for a plane-parallel atmosphere; ozone omitted near the ground).
// The profiles' densities at the eye are the frame's `g.atmos.zw`.
fn optical_depth_from_eye(dh: f32, d: f32) -> vec3<f32> {
    var kr = d;
    var km = d;
    if (abs(dh) > 1.0) {
        kr = d * ATM_RAYLEIGH_H / dh * (1.0 - exp(-dh / ATM_RAYLEIGH_H));
        km = d * ATM_MIE_H / dh * (1.0 - exp(-dh / ATM_MIE_H));
    }
    return ATM_RAYLEIGH * (g.atmos.z * kr) + vec3<f32>(ATM_MIE_EXT * g.atmos.w * km);
}

// Aerial perspective on a pre-exposed surface colour at the eye-relative point `rel`: the
// atmosphere's transmittance T(d) over the path and the in-scattered light, the sky-view
// source function along the ray (its radiance over the whole ray's in-scattering share,
// L / (1 − T(ray)), tabled by the sky-view pass) times the surface's share 1 − T(d). Then the
// classic fog and the ground fog layer toward the horizon sky of the ray's azimuth (the sky
// 0.02 rad above the horizontal, whose table row `g.sky_frame_y.w` is worked out per frame).
// A surface beyond the end of the table's ray (below the sea-level sphere) gathers more light
// than the ray's radiance, tending to the source function, as a longer path of the same air
// would.
fn apply_atmosphere_exposed(exposed_colour: vec3<f32>, rel: vec3<f32>) -> vec3<f32> {
    let d = length(rel);
    let dir = rel / max(d, 1e-3);
    var colour = exposed_colour;
    var fog_colour = exposed(g.fog_colour.rgb);
    if (physical_sky()) {
        let t = exp(-optical_depth_from_eye(height_above_eye(rel), d));
        let uv = sky_view_uv(dir);
        let source = textureSampleLevel(sky_source_lut, sky_view_sampler, uv, 0.0).rgb;
        colour = colour * t + source * (vec3<f32>(1.0) - t);
        let row = g.sky_frame_y.w;
        fog_colour = textureSampleLevel(sky_view_lut, sky_view_sampler, vec2<f32>(uv.x, row), 0.0).rgb;
        // The fog's colour is the horizon sky of the ray's azimuth: what a thick fog looks like
        // toward the horizon. A steep ray's azimuth turns half a circle through the nadir (a
        // seamed cone on a calm sea below it), and a thick fog seen steeply down is lit from
        // all around: toward the horizon's mean over azimuth as the ray steepens past 37
        // degrees, all of it at 72, from four fixed azimuths a quarter turn apart (the
        // horizon's first three harmonics in azimuth average out exactly over them).
        let steep = smoothstep(0.6, 0.95, abs(dot(dir, g.eye_up.xyz)));
        if (steep > 0.0) {
            var mean = vec3<f32>(0.0);
            for (var k = 0u; k < 4u; k++) {
                let around = vec2<f32>(0.125 + 0.25 * f32(k), row);
                mean += 0.25 * textureSampleLevel(sky_view_lut, sky_view_sampler, around, 0.0).rgb;
            }
            fog_colour = mix(fog_colour, mean, steep);
        }
    }
    let f = fog_factor(d) * fog_layer_transmittance(rel);
    return f * colour + (1.0 - f) * fog_colour;
}
