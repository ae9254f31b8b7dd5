//! Thermal sensor views on the GPU: what the shaders read to draw band radiance instead of
//! light.
//!
//! Algorithm (per sensor view and frame, on the CPU; the shaders interpolate):
//! - the surface temperature table of every material and standard orientation
//!   (`cig_thermal::table`, interpolated by each pixel's normal as the source's twelve-direction
//!   look-up: source 001, "Infrared Gray Level Prediction"), the materials' band emissivities;
//! - black-body band radiance `L_band(T)` for 150..1685 K at 1 K steps (the exact series of
//!   `cig_thermal::planck`), so the shaders never integrate Planck's law;
//! - the atmosphere's band transmittance and path radiance (`cig_thermal::infrared`) from the
//!   eye over 32 ranges (1 m..100 km, logarithmic) and 9 elevations (-90..90 degrees), and
//!   the sky's band radiance (the path radiance of a ray to space) at 8 elevations;
//! - the entities' hot parts (rise over their surroundings, per entity), and the ground's hot
//!   spots (fresh craters and impact points: Gaussian patches, eye-relative).
//!
//! A surface shows `eps L_band(T) + (1 - eps) L_refl + (1 - eps) E_sun cos i / pi` (the
//! reflected sun matters in MWIR), where `L_refl` is the sky's hemispherical radiance and the
//! ground's (at the air's temperature) by the normal's view factors `(1 +- cos tilt) / 2`,
//! then `tau L + L_path` along the line of sight. The display (tonemap.wgsl) maps radiance to
//! grey with the automatic gain (adaptation.rs) or the manual window.
//!
//! Clouds emit at their lowest layer's mid-height temperature (every layer alike) with 0.7 of
//! their visible extinction (liquid water absorbs in both windows); a ground fog layer's
//! droplets with half theirs, emitting at the air's temperature; the global fog of the
//! visibility is the aerosol's (the infrared table scales with the visibility).
//!
//! Limits: rain and lightning are not drawn in sensor views; clouds and puffs are seen without
//! the infrared path between them and the eye (their contrast is overstated at long range);
//! the sky is uniform in
//! azimuth (no sun disc); one material per surface (no sub-pixel mixtures besides the
//! terrain's smooth borders, which pick the dominant material).

use cig_scene::thermal::{SensorView, ThermalScene};
use cig_thermal::planck::band_radiance_unchecked;
use cig_thermal::{IrBand, ThermalMaterial};

/// Standard orientations of the surface table.
pub(crate) const ORIENTATIONS: usize = 26;
/// Offsets into the thermal buffer, in f32 (thermal.wgsl has the same numbers).
pub(crate) const OFF_EMISSIVITY: usize = 480;
pub(crate) const OFF_PLANCK: usize = 512;
pub(crate) const PLANCK_T0_K: f64 = 150.0;
pub(crate) const PLANCK_ENTRIES: usize = 1536;
pub(crate) const OFF_PATH: usize = 2048;
pub(crate) const PATH_RANGES: usize = 32;
pub(crate) const PATH_ELEVATIONS_DEG: [f64; 9] =
    [-90.0, -30.0, -10.0, -3.0, 0.0, 3.0, 10.0, 30.0, 90.0];
/// Log10 of the shortest and longest range of the path table, metres.
pub(crate) const PATH_LOG10_M: (f64, f64) = (0.0, 5.0);
pub(crate) const OFF_ENTITY: usize = 2688;
/// Entities with hot parts a frame can draw (more keep their materials' temperatures).
pub(crate) const MAX_HOT_ENTITIES: usize = 255;
pub(crate) const ENTITY_STRIDE: usize = 8;
/// The hot spots' count, then the spots (eye-relative centre, radius, rise; 8 floats each).
pub(crate) const OFF_SPOT_COUNT: usize = OFF_ENTITY + (MAX_HOT_ENTITIES + 1) * ENTITY_STRIDE;
pub(crate) const OFF_SPOTS: usize = OFF_SPOT_COUNT + 8;
pub(crate) const MAX_SPOTS: usize = 32;
pub(crate) const SPOT_STRIDE: usize = 8;
/// The buffer's length, f32.
pub(crate) const THERMAL_LEN: usize = OFF_SPOTS + MAX_SPOTS * SPOT_STRIDE;
/// Sky radiance elevations, degrees (the globals' `sensor_sky0/1`).
pub(crate) const SKY_ELEVATIONS_DEG: [f64; 8] = [0.0, 1.0, 3.0, 6.0, 10.0, 20.0, 40.0, 90.0];
/// Solid angle of the sun's disc, sr.
const SUN_SOLID_ANGLE_SR: f64 = 6.794e-5;
/// The sun's effective black-body temperature, K.
const SUN_K: f64 = 5772.0;

/// What one sensor view's frame uploads.
pub(crate) struct SensorFrame {
    /// The thermal buffer's contents.
    pub buffer: Vec<f32>,
    /// Sky band radiance at [`SKY_ELEVATIONS_DEG`].
    pub sky: [f32; 8],
    /// Hemispherical mean of the sky's radiance (what a horizontal surface reflects).
    pub down_radiance: f32,
    /// The sun's band irradiance on a surface facing it, at the ground, W m-2.
    pub sun_irradiance: f32,
    /// `dL/dT` at the air temperature, W m-2 sr-1 K-1 (the noise's scale).
    pub slope: f32,
    /// Radiance of the automatic gain's histogram range (low, high).
    pub histogram_range: (f32, f32),
    /// The manual window as radiance (low, high), if set.
    pub manual: Option<(f32, f32)>,
    /// Band radiance of the lowest cloud layer at its mid-height temperature (the air's lapse
    /// of 6.5 K/km above sea level), for the cloud pass.
    pub cloud_radiance: f32,
}

/// The band's black-body radiance at `PLANCK_T0_K + i` kelvin, worked out once per band.
fn planck_table(band: IrBand) -> &'static [f32] {
    static TABLES: [std::sync::OnceLock<Vec<f32>>; 2] =
        [std::sync::OnceLock::new(), std::sync::OnceLock::new()];
    let slot = match band {
        IrBand::Lwir => 0,
        IrBand::Mwir => 1,
    };
    TABLES[slot].get_or_init(|| {
        (0..PLANCK_ENTRIES)
            .map(|i| band_radiance_unchecked(band.band(), PLANCK_T0_K + i as f64) as f32)
            .collect()
    })
}

/// Builds a sensor view's tables for an eye at `eye_alt_m` and the sun at `sun_elevation_deg`.
pub(crate) fn sensor_frame(
    sensor: &SensorView,
    scene: &ThermalScene,
    eye_alt_m: f64,
    sun_elevation_deg: f64,
    cloud_layers: &[cig_environment::clouds::CloudLayer],
    eye_ecef_m: glam::DVec3,
) -> SensorFrame {
    let band = sensor.band;
    let b = band.band();
    let mut buffer = vec![0f32; THERMAL_LEN];
    let materials = ThermalMaterial::ALL.len();
    for (i, t) in scene
        .surface_k
        .iter()
        .take(materials * ORIENTATIONS)
        .enumerate()
    {
        buffer[i] = *t;
    }
    for (i, m) in ThermalMaterial::ALL.iter().enumerate() {
        let p = m.properties();
        buffer[OFF_EMISSIVITY + i] = match band {
            IrBand::Lwir => p.emissivity_lwir,
            IrBand::Mwir => p.emissivity_mwir,
        } as f32;
    }
    buffer[OFF_PLANCK..OFF_PLANCK + PLANCK_ENTRIES].copy_from_slice(planck_table(band));
    let atmosphere = &scene.atmosphere;
    // Heights above the ground where the air's temperature was given.
    let above_ground = eye_alt_m - scene.base_alt_m;
    let eye = if above_ground.is_finite() {
        above_ground.clamp(-400.0, 29_000.0)
    } else {
        0.0
    };
    for (j, elevation) in PATH_ELEVATIONS_DEG.iter().enumerate() {
        let s = elevation.to_radians().sin();
        for i in 0..PATH_RANGES {
            let f = i as f64 / (PATH_RANGES - 1) as f64;
            let range = 10f64.powf(PATH_LOG10_M.0 + (PATH_LOG10_M.1 - PATH_LOG10_M.0) * f);
            let end = (eye + range * s).clamp(-400.0, 30_000.0);
            let path = atmosphere.slant_unchecked(band, eye, end, range);
            let k = OFF_PATH + 2 * (j * PATH_RANGES + i);
            buffer[k] = path.transmittance as f32;
            buffer[k + 1] = path.path_radiance_w_m2_sr as f32;
        }
    }
    let to_space = |elevation_deg: f64| {
        let s = elevation_deg.to_radians().sin().max(0.0);
        let top = 30_000.0;
        let range = if s > 1e-3 {
            ((top - eye) / s).min(300_000.0)
        } else {
            300_000.0
        };
        atmosphere.slant_unchecked(band, eye, top.min(eye + range * s.max(0.0)), range)
    };
    let mut sky = [0f32; 8];
    for (k, e) in SKY_ELEVATIONS_DEG.iter().enumerate() {
        sky[k] = to_space(*e).path_radiance_w_m2_sr as f32;
    }
    // What a horizontal surface reflects: the cosine-weighted mean of the sky.
    let mut down = 0.0;
    let mut weight = 0.0;
    for step in 0..90 {
        let e = (step as f64 + 0.5).to_radians();
        let w = e.sin() * e.cos();
        down += w * f64::from(sky_at(&sky, e.to_degrees()));
        weight += w;
    }
    let sun_irradiance = if sun_elevation_deg > 0.0 {
        band_radiance_unchecked(b, SUN_K)
            * SUN_SOLID_ANGLE_SR
            * to_space(sun_elevation_deg).transmittance
    } else {
        0.0
    };
    // Entity slots are 1-based in the order of `entity_heat` (the renderer's entity draws
    // give each entity its slot in the same order).
    for (slot, (_, rise)) in scene.entity_heat.iter().take(MAX_HOT_ENTITIES).enumerate() {
        let base = OFF_ENTITY + (slot + 1) * ENTITY_STRIDE;
        buffer[base..base + 5].copy_from_slice(rise);
    }
    // Hot spots within 20 km, nearest first, relative to the eye (f64 difference, then f32).
    let mut spots: Vec<(f64, [f32; 5])> = scene
        .hot_spots
        .iter()
        .filter_map(|(p, radius, rise)| {
            let rel = glam::DVec3::from_array(*p) - eye_ecef_m;
            let d = rel.length();
            (d < 20_000.0 && d.is_finite()).then_some((
                d,
                [rel.x as f32, rel.y as f32, rel.z as f32, *radius, *rise],
            ))
        })
        .collect();
    spots.sort_by(|a, b| a.0.total_cmp(&b.0));
    spots.truncate(MAX_SPOTS);
    buffer[OFF_SPOT_COUNT] = spots.len() as f32;
    // The ground a tilted surface sees, at the air's temperature (thermal.wgsl's reflection).
    buffer[OFF_SPOT_COUNT + 1] = scene.air_k as f32;
    for (i, (_, spot)) in spots.iter().enumerate() {
        let base = OFF_SPOTS + i * SPOT_STRIDE;
        buffer[base..base + 5].copy_from_slice(spot);
    }
    let air = scene.air_k;
    let radiance = |t: f64| band_radiance_unchecked(b, t.max(1.0)) as f32;
    let cloud_mid_m = cloud_layers
        .iter()
        .map(|l| l.base_m + 0.5 * l.thickness_m)
        .fold(f64::INFINITY, f64::min);
    let cloud_k = if cloud_mid_m.is_finite() {
        air - 0.0065 * (cloud_mid_m - scene.base_alt_m).max(0.0)
    } else {
        air
    };
    SensorFrame {
        cloud_radiance: radiance(cloud_k),
        buffer,
        sky,
        down_radiance: (down / weight) as f32,
        sun_irradiance: sun_irradiance as f32,
        slope: cig_thermal::planck::band_radiance_slope(b, air) as f32,
        // Cold sky and hot engines fall into the end bins: the bins resolve the scene (1.2 K).
        histogram_range: (radiance(air - 30.0), radiance(air + 45.0)),
        manual: sensor
            .manual_window_k()
            .map(|(lo, hi)| (radiance(lo), radiance(hi))),
    }
}

/// The sky's radiance at `elevation_deg`, interpolated between the table's elevations.
fn sky_at(sky: &[f32; 8], elevation_deg: f64) -> f32 {
    let e = elevation_deg.clamp(0.0, 90.0);
    for k in 1..SKY_ELEVATIONS_DEG.len() {
        let (e0, e1) = (SKY_ELEVATIONS_DEG[k - 1], SKY_ELEVATIONS_DEG[k]);
        if e <= e1 {
            let f = ((e - e0) / (e1 - e0)) as f32;
            return sky[k - 1] * (1.0 - f) + sky[k] * f;
        }
    }
    sky[7]
}

/// Offset of the terrain materials' mean visible luminance in a night-vision view's buffer
/// (thermal.wgsl's `NVG_OFF_TERRAIN_LUMA`).
pub(crate) const NVG_OFF_TERRAIN_LUMA: usize = 32;

/// A night-vision view's table, written where a thermal view's tables go (binding 9): each
/// thermal material's NVG reflectance (`cig_scene::nvg::NVG_REFLECTANCE`), then each terrain
/// material's mean visible luminance (linear, from its base colour), by which the shader
/// scales the drawn colour's texture onto the NVG reflectance. Made once.
pub(crate) fn nvg_buffer() -> &'static [f32] {
    static BUFFER: std::sync::OnceLock<Vec<f32>> = std::sync::OnceLock::new();
    BUFFER.get_or_init(make_nvg_buffer)
}

fn make_nvg_buffer() -> Vec<f32> {
    let mut buffer = vec![0f32; THERMAL_LEN];
    buffer[..cig_scene::nvg::NVG_REFLECTANCE.len()]
        .copy_from_slice(&cig_scene::nvg::NVG_REFLECTANCE);
    for (i, m) in cig_terrain::Material::ALL.iter().enumerate() {
        let [r, g, b, _] = cig_scene::terrain_mesh::material_colour(*m);
        // The atlas is an sRGB texture: its exact decoding.
        let lin = |c: u8| {
            let v = f32::from(c) / 255.0;
            if v <= 0.04045 {
                v / 12.92
            } else {
                ((v + 0.055) / 1.055).powf(2.4)
            }
        };
        buffer[NVG_OFF_TERRAIN_LUMA + i] = 0.2126 * lin(r) + 0.7152 * lin(g) + 0.0722 * lin(b);
    }
    buffer
}

#[cfg(test)]
mod tests {
    use super::*;
    use cig_thermal::{Aerosol, HotPart, IrAtmosphere, ModelAtmosphere};

    #[test]
    fn the_shader_uses_the_same_layout_and_codes() {
        let wgsl = include_str!("shaders/thermal.wgsl");
        assert!(wgsl.contains(&format!(
            "const NVG_OFF_TERRAIN_LUMA: u32 = {NVG_OFF_TERRAIN_LUMA}u;"
        )));
        for (name, value) in [
            ("TH_ORIENTATIONS", ORIENTATIONS),
            ("TH_MATERIALS", ThermalMaterial::ALL.len()),
            ("TH_OFF_EMISSIVITY", OFF_EMISSIVITY),
            ("TH_OFF_PLANCK", OFF_PLANCK),
            ("TH_PLANCK_N", PLANCK_ENTRIES),
            ("TH_OFF_PATH", OFF_PATH),
            ("TH_PATH_RANGES", PATH_RANGES),
            ("TH_OFF_ENTITY", OFF_ENTITY),
            ("TH_ENTITY_STRIDE", ENTITY_STRIDE),
            ("TH_OFF_SPOT_COUNT", OFF_SPOT_COUNT),
            ("TH_OFF_SPOTS", OFF_SPOTS),
            ("TH_SPOT_STRIDE", SPOT_STRIDE),
            (
                "TH_HOT_BASE",
                usize::from(cig_scene::thermal::HOT_CODE_BASE),
            ),
            ("TH_HOT_PARTS", HotPart::ALL.len()),
            ("TH_SKIN", ThermalMaterial::Skin.index()),
        ] {
            let line = format!("const {name}: u32 = {value}u;");
            assert!(wgsl.contains(&line), "thermal.wgsl lacks {line}");
        }
        assert!(wgsl.contains(&format!("const TH_PLANCK_T0: f32 = {PLANCK_T0_K:.1};")));
        assert_eq!(
            HotPart::BurningHull.index(),
            4,
            "model.wgsl reads the burning hull as part 4"
        );
    }

    #[test]
    fn the_sky_is_coldest_overhead_and_the_tables_are_filled() {
        let scene = ThermalScene {
            surface_k: vec![290.0; ThermalMaterial::ALL.len() * ORIENTATIONS],
            air_k: 290.0,
            atmosphere: IrAtmosphere::model(ModelAtmosphere::MidLatitudeSummer, Aerosol::Rural),
            entity_heat: vec![(7, [50.0, 250.0, 10.0, 17.0, 0.0])],
            hot_spots: vec![
                ([0.0, 0.0, 10.0], 2.0, 300.0),
                ([0.0, 0.0, 9e9], 2.0, 300.0),
            ],
            base_alt_m: 0.0,
        };
        let f = sensor_frame(
            &SensorView::new(IrBand::Lwir),
            &scene,
            100.0,
            40.0,
            &[],
            glam::DVec3::ZERO,
        );
        assert!(f.sky[0] > f.sky[7] * 1.5, "{:?}", f.sky);
        assert!(f.down_radiance > f.sky[7] && f.down_radiance < f.sky[0]);
        assert_eq!(f.buffer[OFF_ENTITY + ENTITY_STRIDE + 1], 250.0);
        // L_band at 300 K sits at entry 150.
        assert!((f.buffer[OFF_PLANCK + 150] - 38.5004).abs() < 1e-3);
        // Transmittance falls with range along the horizontal.
        let h = OFF_PATH + 2 * 4 * PATH_RANGES;
        assert!(f.buffer[h] > 0.99 && f.buffer[h + 2 * 31] < 0.3);
        assert!(f.histogram_range.0 < f.histogram_range.1);
        // The near hot spot is kept relative to the eye; the far one is left out.
        assert_eq!(f.buffer[OFF_SPOT_COUNT], 1.0);
        assert_eq!(f.buffer[OFF_SPOTS + 2], 10.0);
        assert_eq!(f.buffer[OFF_SPOTS + 4], 300.0);
    }
}
