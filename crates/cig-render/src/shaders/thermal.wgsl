// Thermal sensor views (sensor.rs): the thermal buffer's tables and the band radiance a surface
// shows through the atmosphere. The offsets are sensor.rs's.

@group(0) @binding(9) var<storage, read> thermal: array<f32>;

const TH_ORIENTATIONS: u32 = 26u;
const TH_MATERIALS: u32 = 18u;
const TH_OFF_EMISSIVITY: u32 = 480u;
const TH_OFF_PLANCK: u32 = 512u;
const TH_PLANCK_T0: f32 = 150.0;
const TH_PLANCK_N: u32 = 1536u;
const TH_OFF_PATH: u32 = 2048u;
const TH_PATH_RANGES: u32 = 32u;
const TH_OFF_ENTITY: u32 = 2688u;
const TH_ENTITY_STRIDE: u32 = 8u;
const TH_OFF_SPOT_COUNT: u32 = 4736u;
const TH_OFF_SPOTS: u32 = 4744u;
const TH_SPOT_STRIDE: u32 = 8u;
const TH_HOT_BASE: u32 = 32u;
const TH_HOT_PARTS: u32 = 5u;
// ThermalMaterial::Skin.
const TH_SKIN: u32 = 15u;
// Emissivity of hot parts (painted grilles, sooty exhausts, rubber, skin).
const TH_HOT_EMISSIVITY: f32 = 0.95;

fn sensor_on() -> bool {
    return g.sensor.x > 0.5;
}

// Black-body band radiance at t_k (the table's 1 K steps, linear between).
fn th_band_radiance(t_k: f32) -> f32 {
    let x = clamp(t_k - TH_PLANCK_T0, 0.0, f32(TH_PLANCK_N - 2u));
    let i = u32(floor(x));
    return mix(thermal[TH_OFF_PLANCK + i], thermal[TH_OFF_PLANCK + i + 1u], x - f32(i));
}

fn th_ring(base: u32, r: u32, a0: u32, a1: u32, wa: f32) -> f32 {
    if (r == 0u) {
        return thermal[base];
    }
    if (r >= 4u) {
        return thermal[base + 25u];
    }
    let o = base + 1u + (r - 1u) * 8u;
    return mix(thermal[o + a0], thermal[o + a1], wa);
}

// Surface temperature of a material for a normal (eye-relative ECEF axes): the table's 26
// standard directions, bilinear in tilt and azimuth (cig_thermal::table::standard_weights).
fn th_surface_temp(material: u32, n: vec3<f32>) -> f32 {
    let up = g.eye_up.xyz;
    var east = cross(vec3<f32>(0.0, 0.0, 1.0), up);
    if (dot(east, east) < 1e-8) {
        east = vec3<f32>(0.0, 1.0, 0.0);
    }
    east = normalize(east);
    let north = cross(up, east);
    let tilt = degrees(acos(clamp(dot(n, up), -1.0, 1.0)));
    var azimuth = degrees(atan2(dot(n, east), dot(n, north)));
    if (azimuth < 0.0) {
        azimuth += 360.0;
    }
    let ring_f = clamp(tilt / 45.0, 0.0, 4.0);
    let r0 = min(u32(floor(ring_f)), 3u);
    let sector = azimuth / 45.0;
    let a0 = u32(floor(sector)) % 8u;
    let a1 = (a0 + 1u) % 8u;
    let wa = sector - floor(sector);
    let base = min(material, TH_MATERIALS - 1u) * TH_ORIENTATIONS;
    return mix(th_ring(base, r0, a0, a1, wa), th_ring(base, r0 + 1u, a0, a1, wa), ring_f - f32(r0));
}

fn th_emissivity(material: u32) -> f32 {
    return thermal[TH_OFF_EMISSIVITY + min(material, TH_MATERIALS - 1u)];
}

fn th_path_at(j: u32, x: f32) -> vec2<f32> {
    let i = min(u32(floor(x)), TH_PATH_RANGES - 2u);
    let f = clamp(x - f32(i), 0.0, 1.0);
    let k = TH_OFF_PATH + 2u * (j * TH_PATH_RANGES + i);
    let a = vec2<f32>(thermal[k], thermal[k + 1u]);
    let b = vec2<f32>(thermal[k + 2u], thermal[k + 3u]);
    return mix(a, b, f);
}

// Transmittance (x) and path radiance (y) from the eye to an eye-relative point.
fn th_path(rel: vec3<f32>) -> vec2<f32> {
    let d = max(length(rel), 1.0);
    let elevation = degrees(asin(clamp(dot(rel / d, g.eye_up.xyz), -1.0, 1.0)));
    let x = clamp(log2(d) / log2(10.0) / 5.0 * f32(TH_PATH_RANGES - 1u), 0.0, f32(TH_PATH_RANGES - 1u));
    let elevations = array<f32, 9>(-90.0, -30.0, -10.0, -3.0, 0.0, 3.0, 10.0, 30.0, 90.0);
    var j = 0u;
    for (var k = 0u; k < 7u; k++) {
        if (elevation > elevations[k + 1u]) {
            j = k + 1u;
        }
    }
    let w = clamp((elevation - elevations[j]) / (elevations[j + 1u] - elevations[j]), 0.0, 1.0);
    return mix(th_path_at(j, x), th_path_at(j + 1u, x), w);
}

// What the sensor sees of a surface at temperature t_k with emissivity eps and normal n:
// emission, the reflected sky (and sun), then the path.
fn th_shown(t_k: f32, eps: f32, n: vec3<f32>, rel: vec3<f32>) -> vec4<f32> {
    // Reflected: the sky above the surface's horizon, the ground (at the air's temperature)
    // below it, by the view factors (1 +- cos tilt) / 2.
    let sky_view = 0.5 * (1.0 + clamp(dot(n, g.eye_up.xyz), -1.0, 1.0));
    let ground = th_band_radiance(thermal[TH_OFF_SPOT_COUNT + 1u]);
    var l = eps * th_band_radiance(t_k) + (1.0 - eps) * mix(ground, g.sensor.z, sky_view);
    l += (1.0 - eps) * g.sensor.w * max(dot(n, g.sun_dir.xyz), 0.0) / 3.14159265;
    let p = th_path(rel);
    var shown = p.x * l + p.y;
    // A ground fog layer's droplets: half their visible optical depth in the infrared, emitting
    // at the air's temperature.
    let fog = sqrt(fog_layer_transmittance(rel));
    shown = fog * shown + (1.0 - fog) * ground;
    return vec4<f32>(vec3<f32>(shown), 1.0);
}

// A hot part's rise over its surroundings for the instance word's entity slot (0: none).
fn th_entity_rise(slot: u32, part: u32) -> f32 {
    if (slot == 0u || part >= TH_HOT_PARTS) {
        return 0.0;
    }
    return thermal[TH_OFF_ENTITY + slot * TH_ENTITY_STRIDE + part];
}


// The ground's hot spots (fresh craters, impact points) at an eye-relative point: the sum of
// their Gaussian rises, kelvin.
fn th_hot_spots(rel: vec3<f32>) -> f32 {
    let count = u32(thermal[TH_OFF_SPOT_COUNT]);
    var rise = 0.0;
    for (var i = 0u; i < count; i++) {
        let b = TH_OFF_SPOTS + i * TH_SPOT_STRIDE;
        let d = rel - vec3<f32>(thermal[b], thermal[b + 1u], thermal[b + 2u]);
        let r = max(thermal[b + 3u], 0.1);
        rise += thermal[b + 4u] * exp(-dot(d, d) / (r * r));
    }
    return rise;
}

// A night-vision view's reflectances (sensor.rs's nvg_buffer, written where a thermal view's
// tables go): each thermal material's NVG-band reflectance at 0..18, each terrain material's
// mean visible luminance (linear) at NVG_OFF_TERRAIN_LUMA..+9.
const NVG_OFF_TERRAIN_LUMA: u32 = 32u;

// A terrain material's albedo on goggles: its NVG reflectance, times how much lighter or
// darker the drawn colour (detail, imagery) is than the material's mean, within 0.5..2.
fn nvg_terrain_albedo(kind: u32, albedo: vec3<f32>) -> vec3<f32> {
    let k = min(kind, 8u);
    let luma = dot(albedo, vec3<f32>(0.2126, 0.7152, 0.0722));
    let ratio = clamp(luma / max(thermal[NVG_OFF_TERRAIN_LUMA + k], 1e-3), 0.5, 2.0);
    return vec3<f32>(thermal[k] * ratio);
}

// A model surface's albedo on goggles: the NVG reflectance of its thermal code's material (the
// instance's default for uncoded surfaces and hot parts, skin for crew).
fn nvg_model_albedo(code: u32, word: u32) -> vec3<f32> {
    var material = word & 255u;
    if (code < TH_MATERIALS) {
        material = code;
    } else if (code == TH_HOT_BASE + 3u) {
        material = TH_SKIN;
    }
    return vec3<f32>(thermal[min(material, TH_MATERIALS - 1u)]);
}
