// Shared declarations of every cig shader (concatenated in front of each module).

struct Globals {
    view_proj: mat4x4<f32>,
    // Camera basis (ECEF axes): xyz; cam_forward.w: vertices per terrain node slot;
    // cam_right.w: 1 to draw the ground's detail.
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
    // The eye's place in the detail plane (east, north) modulo each noise's period, in its
    // cells; w the cell size (m).
    noise0: vec4<f32>,
    noise1: vec4<f32>,
    noise2: vec4<f32>,
    // x: wireframe flag, y: exposure, z: key the background (and a linear tone map), w: pixels
    // per unit tangent.
    flags: vec4<f32>,
    // Ground fog layer: top height relative to the eye (m), extinction (1/m), enabled; w: the
    // earth's radius at the eye (m).
    fog_layer: vec4<f32>,
    // Towards the moon; w = moon elevation (degrees). Direct moonlight (light units).
    moon_dir: vec4<f32>,
    moon_colour: vec4<f32>,
    // Sun's and moon's illuminance above the atmosphere (light units); moon_toa.w: 1 where the
    // moon lights the sky (cig_scene's Lighting::moon_lights_the_sky), else 0.
    sun_toa: vec4<f32>,
    moon_toa: vec4<f32>,
    // x: eye radius from the planet's centre (m), y: sky model (0 physical, 1 flat), z and w:
    // the Rayleigh and Mie profiles' relative densities at the eye.
    atmos: vec4<f32>,
    // Night-sky background radiance (π L, light units).
    night_sky: vec4<f32>,
    // x: encode sRGB in the tone map, y: scotopic blend, z: natural illuminance (lux), w: the
    // terrestrial refraction coefficient (`refracted`).
    tonemap: vec4<f32>,
    // The sky-view table's frame (its third axis is eye_up), worked out once per frame:
    // x axis with the horizon's zenith angle for the eye in w, and the y axis with the table
    // row of the fog's horizon sky in w.
    sky_frame_x: vec4<f32>,
    sky_frame_y: vec4<f32>,
    // East and north (ECEF) of the database centre's tangent plane: the ground detail's plane.
    detail_east: vec4<f32>,
    detail_north: vec4<f32>,
    // Thermal sensor view (sensor.rs): x 1 when this view is a sensor, y the band (0 LWIR,
    // 1 MWIR), z the sky's radiance a horizontal surface reflects, w the sun's band
    // irradiance at the ground (W m-2).
    sensor: vec4<f32>,
    // The sky's band radiance at 0, 1, 3, 6 and 10, 20, 40, 90 degrees of elevation.
    sensor_sky0: vec4<f32>,
    sensor_sky1: vec4<f32>,
    // The sensor's display: x polarity (1 black-hot), y colour (0 white, 1 green, 2 black),
    // z temporal noise (radiance, one sigma), w fixed-pattern noise (fraction of z).
    sensor_display: vec4<f32>,
    // x optics blur (pixels, one sigma), y line dropout on, z the frame's number, w the clouds'
    // band radiance.
    sensor_display2: vec4<f32>,
    // Night-vision view (nvg.rs): x 1 when this view is an intensifier, y photoelectrons a
    // frame per pre-exposed scene unit in one pixel, z the microchannel plate's excess noise
    // (F - 1), w tan of half the goggle's circular field.
    nvg: vec4<f32>,
    // The phosphor's colour at full output (xyz); w the tube's blur, pixels (one sigma).
    nvg2: vec4<f32>,
    // x: photoelectron noise on, y: flames' factor (their NVG weighting), z: local lights in
    // use, w: unused.
    nvg3: vec4<f32>,
    // Lights that light the surfaces around them (flares, fires, headlights; lights.rs), three
    // vec4s each: eye-relative position and intensity (light units at 1 m); colour and the
    // cosine of the beam's half width (< -1: all round); the beam's axis and its back share.
    local_lights: array<vec4<f32>, 24>,
};

@group(0) @binding(0) var<uniform> g: Globals;

// The frame's uniform switches, for pipelines built for them (crate::renderer::ShaderSwitches),
// so the compiler folds the other settings' paths away; -1 (the default) reads the switch from
// the globals each frame.
override FOG_MODE: i32 = -1;
override GROUND_FOG: i32 = -1;
override PHYSICAL_SKY: i32 = -1;
override GROUND_DETAIL: i32 = -1;
override SEA_CUT: i32 = -1;

// 0 off, 1 linear, 2 exponential, 3 exponential-squared.
fn fog_mode() -> i32 {
    if (FOG_MODE >= 0) {
        return FOG_MODE;
    }
    return i32(g.fog.x + 0.5);
}

fn ground_fog_on() -> bool {
    if (GROUND_FOG >= 0) {
        return GROUND_FOG == 1;
    }
    return g.fog_layer.z > 0.5;
}

// Standard terrestrial refraction (coefficient k in g.tonemap.w; 0.13 standard, 0 off): a
// sightline curves down with curvature k/R, so what stands at horizontal distance d appears
// raised by k d^2 / (2R) (the effective earth radius R / (1 - k) of the navigation tables;
// source 001's earth curvature). Only where things are drawn moves; their shading keeps the
// true eye-relative position.
fn refracted(rel: vec3<f32>) -> vec3<f32> {
    let up = g.eye_up.xyz;
    let along = dot(rel, up);
    let across2 = max(dot(rel, rel) - along * along, 0.0);
    return rel + up * (g.tonemap.w * across2 / (2.0 * max(g.fog_layer.w, 1.0e6)));
}

// The sea is drawn and the terrain leaves its sea posts (water at or below the sea's level) to it.
fn sea_cut_on() -> bool {
    if (SEA_CUT >= 0) {
        return SEA_CUT == 1 && g.detail_east.w > 0.5;
    }
    return g.detail_east.w > 0.5;
}

fn ground_detail_on() -> bool {
    if (GROUND_DETAIL >= 0) {
        return GROUND_DETAIL == 1;
    }
    return g.cam_right.w > 0.5;
}

fn physical_sky() -> bool {
    if (PHYSICAL_SKY >= 0) {
        return PHYSICAL_SKY == 1;
    }
    return g.atmos.y < 0.5;
}

// The sky's keyed background (tests): pure magenta; with the key on, the tone map passes
// linear radiance through unchanged (clamped to 1), so tests can read it back.
const KEY_RADIANCE: f32 = 1.0;

fn fog_factor(distance_m: f32) -> f32 {
    let mode = fog_mode();
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

// Height of an eye-relative point above the eye, with the earth's curvature (a point d metres
// away is d^2 / 2R lower than the eye's tangent plane says).
fn height_above_eye(rel: vec3<f32>) -> f32 {
    let up = dot(rel, g.eye_up.xyz);
    let horizontal2 = max(dot(rel, rel) - up * up, 0.0);
    return up - horizontal2 / (2.0 * 6371000.0);
}

// Transmittance of the ground fog layer along the straight ray from the eye to `rel`: the
// length of the ray below the layer's top times its extinction (heights vary linearly along
// the ray).
fn fog_layer_transmittance(rel: vec3<f32>) -> f32 {
    if (!ground_fog_on()) {
        return 1.0;
    }
    let top = g.fog_layer.x;
    let h = height_above_eye(rel);
    let lo = min(0.0, h);
    let hi = max(0.0, h);
    var inside = 0.0;
    if (top >= hi) {
        inside = 1.0;
    } else if (top > lo) {
        inside = (top - lo) / max(hi - lo, 1e-3);
    }
    return exp(-g.fog_layer.y * length(rel) * inside);
}

fn apply_fog(colour: vec3<f32>, distance_m: f32) -> vec3<f32> {
    let f = fog_factor(distance_m);
    return f * colour + (1.0 - f) * g.fog_colour.rgb;
}

// Global fog and the ground fog layer along the ray to an eye-relative point.
fn apply_fog_at(colour: vec3<f32>, rel: vec3<f32>) -> vec3<f32> {
    let f = fog_factor(length(rel)) * fog_layer_transmittance(rel);
    return f * colour + (1.0 - f) * g.fog_colour.rgb;
}

// Every pass writes pre-exposed linear radiance: the scene's radiance (in the units of the
// frame's light colours) times the frame's exposure, so the colour target's range holds a moonless
// night and noon alike. The environment's exposure control sets `g.flags.y`.
fn exposed(radiance: vec3<f32>) -> vec3<f32> {
    return radiance * g.flags.y;
}

fn nvg_on() -> bool {
    return g.nvg.x > 0.5;
}

// The local lights' illuminance on a surface at eye-relative `rel` with normal `n` (light
// units): inverse square, Lambert, the beam's lobe (cig_scene::lights::Lobe::Beam's Gaussian
// in angle, its back share behind).
fn local_light(rel: vec3<f32>, n: vec3<f32>) -> vec3<f32> {
    var sum = vec3<f32>(0.0);
    let count = min(u32(g.nvg3.z), 8u);
    for (var i = 0u; i < count; i++) {
        let a = g.local_lights[3u * i];
        let b = g.local_lights[3u * i + 1u];
        let c = g.local_lights[3u * i + 2u];
        let d = a.xyz - rel;
        let d2 = max(dot(d, d), 1.0);
        let l = d * inverseSqrt(d2);
        var lobe = 1.0;
        if (b.w > -1.5) {
            // A Gaussian in the angle off the axis, half maximum at the half width.
            let off = acos(clamp(dot(-l, c.xyz), -1.0, 1.0));
            let half_width = max(acos(clamp(b.w, -1.0, 1.0)), 1e-3);
            let x = off / half_width;
            lobe = max(c.w, exp(-0.6931472 * x * x));
        }
        sum += b.xyz * (a.w * lobe * max(dot(n, l), 0.0) / d2);
    }
    return sum;
}

// Sun, moon, sky and the local lights on a surface.
fn lit_at(albedo: vec3<f32>, n: vec3<f32>, rel: vec3<f32>) -> vec3<f32> {
    if (g.nvg3.z > 0.5) {
        return lit(albedo, n) + albedo * local_light(rel, n);
    }
    return lit(albedo, n);
}

fn lit(albedo: vec3<f32>, n: vec3<f32>) -> vec3<f32> {
    let diffuse = max(dot(n, g.sun_dir.xyz), 0.0);
    let sky = 0.6 + 0.4 * dot(n, g.eye_up.xyz);
    let moon = max(dot(n, g.moon_dir.xyz), 0.0);
    return albedo * (g.sun_colour.rgb * diffuse + g.moon_colour.rgb * moon + g.ambient.rgb * sky);
}
