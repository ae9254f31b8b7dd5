// The sky-view table of one frame (Hillaire 2020 section 5.3): the sky's radiance around the
// eye, latitude concentrated at the horizon, longitude from the sun's azimuth, by a ray march
// of single scattering (sun and moon, the planet's shadow) and the multiple-scattering table.
// Stored pre-exposed (π L × light units × exposure) so the half floats keep their precision.

struct LutOut {
    @builtin(position) clip: vec4<f32>,
};

// The two tables of a texel: the sky's radiance along the ray, and its source function (the
// radiance over the ray's in-scattering share 1 − T(ray)), which aerial perspective scales by a
// surface's own share 1 − T(d).
struct SkyViewOut {
    @location(0) radiance: vec4<f32>,
    @location(1) source: vec4<f32>,
};

@vertex
fn vs_main(@builtin(vertex_index) i: u32) -> LutOut {
    let xy = vec2<f32>(f32((i << 1u) & 2u), f32(i & 2u)) * 2.0 - 1.0;
    var out: LutOut;
    out.clip = vec4<f32>(xy, 0.0, 1.0);
    return out;
}

fn rayleigh_phase(nu: f32) -> f32 {
    return 3.0 / (16.0 * PI) * (1.0 + nu * nu);
}

fn cornette_shanks_phase(nu: f32) -> f32 {
    let g2 = ATM_MIE_G * ATM_MIE_G;
    let denom = max(1.0 + g2 - 2.0 * ATM_MIE_G * nu, 1e-5);
    return 3.0 / (8.0 * PI) * (1.0 - g2) * (1.0 + nu * nu) / ((2.0 + g2) * denom * sqrt(denom));
}

const STEPS: i32 = 24;

// 1: the moon lights the sky, 0: it does not (a pipeline for each, so a sky without the moon
// is not charged for it where every branch runs); -1 decides from the globals.
override MOON_SKY: i32 = -1;

@fragment
fn fs_main(in: LutOut) -> SkyViewOut {
    let uv = in.clip.xy / SKY_VIEW_SIZE;
    let dir = sky_view_dir(uv);
    let up = g.eye_up.xyz;
    let r = eye_radius();
    let mu = dot(dir, up);
    var ray_length = distance_to_ground(r, mu);
    if (ray_length < 0.0) {
        ray_length = distance_to_top(r, mu);
    }
    let sun = g.sun_dir.xyz;
    let moon = g.moon_dir.xyz;
    let nu_sun = dot(dir, sun);
    let nu_moon = dot(dir, moon);
    let phase_sun_r = rayleigh_phase(nu_sun);
    let phase_sun_m = cornette_shanks_phase(nu_sun);
    let phase_moon_r = rayleigh_phase(nu_moon);
    let phase_moon_m = cornette_shanks_phase(nu_moon);
    var with_moon = g.moon_toa.w > 0.5;
    if (MOON_SKY >= 0) {
        with_moon = MOON_SKY == 1;
    }
    var radiance = vec3<f32>(0.0);
    var throughput = vec3<f32>(1.0);
    var t_prev = 0.0;
    for (var i = 0; i < STEPS; i++) {
        let f1 = f32(i + 1) / f32(STEPS);
        let t1 = ray_length * f1 * f1;
        let t = 0.5 * (t_prev + t1);
        let dt = t1 - t_prev;
        t_prev = t1;
        let pos = up * r + dir * t;
        let rs = length(pos);
        let h = rs - ATM_BOTTOM;
        let local_up = pos / rs;
        let rayleigh = ATM_RAYLEIGH * exp(-h / ATM_RAYLEIGH_H);
        let mie_density = exp(-h / ATM_MIE_H);
        let mie = ATM_MIE_SCAT * mie_density;
        let ozone = clamp(1.0 - abs(h - ATM_OZONE_PEAK) / ATM_OZONE_HALF, 0.0, 1.0);
        let extinction = rayleigh + vec3<f32>(ATM_MIE_EXT * mie_density) + ATM_OZONE * ozone;
        let mu_s = dot(local_up, sun);
        var source = g.sun_toa.rgb * (
            (rayleigh * phase_sun_r + vec3<f32>(mie * phase_sun_m)) * sun_transmittance(rs, mu_s)
            + (rayleigh + vec3<f32>(mie)) * multi_scattering(rs, mu_s));
        if (with_moon) {
            let mu_m = dot(local_up, moon);
            source += g.moon_toa.rgb * (
                (rayleigh * phase_moon_r + vec3<f32>(mie * phase_moon_m)) * sun_transmittance(rs, mu_m)
                + (rayleigh + vec3<f32>(mie)) * multi_scattering(rs, mu_m));
        }
        let step_t = exp(-extinction * dt);
        let integral = (source - source * step_t) / max(extinction, vec3<f32>(1e-12));
        radiance += throughput * integral;
        throughput *= step_t;
    }
    let shown = min(exposed(PI * radiance + g.night_sky.rgb), vec3<f32>(60000.0));
    var out: SkyViewOut;
    out.radiance = vec4<f32>(shown, 1.0);
    let in_scattering_share = max(vec3<f32>(1.0) - throughput, vec3<f32>(1e-4));
    out.source = vec4<f32>(min(shown / in_scattering_share, vec3<f32>(60000.0)), 1.0);
    return out;
}
