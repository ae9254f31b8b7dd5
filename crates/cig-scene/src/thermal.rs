//! What a sensor view (thermal infrared) needs beyond the visible frame: the surface
//! temperature table, the infrared atmosphere, the entities' hot parts, and each view's sensor
//! settings; and the thermal codes models carry.
//!
//! A model's vertex colour keeps its RGB for the visible channel; its alpha is a thermal code:
//! `0..=17` a [`ThermalMaterial`] (its index), `32 + i` the hot part `HotPart::ALL[i]` (its
//! temperature is the part's rise over the instance's default material), and 255 "the
//! instance's default material" (the model's, [`default_material_for_model`]). glTF models set
//! codes through their materials' names (`docs/models.md`).
//!
//! Manual gain and level are CIGI's (Sensor Control: gain "contrast" and level "brightness",
//! both 0..1), shown as a window of apparent (brightness) temperature: its centre
//! `220 + 140 level` K and its width `2 x 10^(2 (1 - gain))` K (gain 1: 2 K, gain 0: 200 K).

use cig_thermal::{HotPart, IrAtmosphere, IrBand, ThermalMaterial};

/// Code of "the instance's default material".
pub const DEFAULT_CODE: u8 = 255;
/// First hot-part code.
pub const HOT_CODE_BASE: u8 = 32;

/// A vertex's thermal code for a material.
pub fn material_code(material: ThermalMaterial) -> u8 {
    material.index() as u8
}

/// A vertex's thermal code for a hot part.
pub fn hot_code(part: HotPart) -> u8 {
    HOT_CODE_BASE + part.index() as u8
}

/// What a thermal code means.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ThermalCode {
    Material(ThermalMaterial),
    Hot(HotPart),
    InstanceDefault,
}

/// Decodes a vertex's thermal code (unknown codes are the instance's default).
pub fn decode(code: u8) -> ThermalCode {
    if let Some(m) = ThermalMaterial::ALL.get(usize::from(code)) {
        return ThermalCode::Material(*m);
    }
    if code >= HOT_CODE_BASE {
        if let Some(p) = HotPart::ALL.get(usize::from(code - HOT_CODE_BASE)) {
            return ThermalCode::Hot(*p);
        }
    }
    ThermalCode::InstanceDefault
}

/// The material a model's uncoded surfaces are made of, by model name: ships are painted
/// steel, buildings concrete, trees foliage, anything else a vehicle's armour.
pub fn default_material_for_model(name: &str) -> ThermalMaterial {
    match name {
        "ship" | "destroyer" | "merchant" | "patrol_craft" => ThermalMaterial::HullPaint,
        "building" => ThermalMaterial::BuildingWall,
        "tree" => ThermalMaterial::CanopyFoliage,
        _ => ThermalMaterial::VehicleArmour,
    }
}

/// Extinction of an obscurant in an infrared band relative to its visible extinction (the same
/// mass of smoke or dust). Typical values from R. H. Farmer, "Obscuration by smokes and
/// dusts" (*The Infrared and Electro-Optical Systems Handbook*, vol. 2, ch. 3, 1993) and E. W.
/// Stuebing and J. Embury's collected mass extinction coefficients: hydrocarbon soot about
/// 8 m2/g visible against about 1 (LWIR) and 2 (MWIR); soil dust about 0.6 visible against
/// 0.45 (LWIR) and 0.5 (MWIR) (large particles are nearly grey); flames' hot gas and soot
/// absorb in both bands about as in the visible (CO2 and H2O emission). Fog-oil screening
/// smoke (0.02 in LWIR) is thinner still; cig's plumes are fire smoke.
pub fn obscurant_ir_ratio(kind: cig_effects::ObscurantKind, band: IrBand) -> f32 {
    use cig_effects::ObscurantKind as K;
    match (kind, band) {
        (K::Smoke, IrBand::Lwir) => 0.12,
        (K::Smoke, IrBand::Mwir) => 0.25,
        (K::Dust, IrBand::Lwir) => 0.75,
        (K::Dust, IrBand::Mwir) => 0.85,
        (K::Flame, _) => 1.0,
    }
}

/// White-hot or black-hot.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Polarity {
    #[default]
    WhiteHot,
    BlackHot,
}

impl Polarity {
    /// Parses `white-hot` or `black-hot`.
    pub fn from_name(name: &str) -> Option<Polarity> {
        match name {
            "white-hot" => Some(Polarity::WhiteHot),
            "black-hot" => Some(Polarity::BlackHot),
            _ => None,
        }
    }
}

/// The colour the sensor's display shows its grey levels in.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum DisplayColour {
    /// Grey on a monochrome monitor.
    #[default]
    White,
    /// A green phosphor.
    Green,
    /// Amber-black: grey levels on a black background with no colour (as white; kept for
    /// CIGI hosts that ask for a "black" display).
    Black,
}

impl DisplayColour {
    /// Parses white, green or black.
    pub fn from_name(name: &str) -> Option<DisplayColour> {
        match name {
            "white" => Some(DisplayColour::White),
            "green" => Some(DisplayColour::Green),
            "black" => Some(DisplayColour::Black),
            _ => None,
        }
    }
}

/// The sensor a name asks for: `visible` (`Ok(None)`), `lwir` or `mwir` (the names of the
/// command line and the scenario); `Err(())` for any other name.
#[allow(
    clippy::result_unit_err,
    reason = "callers say which option or key was wrong, with its value"
)]
pub fn sensor_of_name(name: &str) -> Result<Option<SensorView>, ()> {
    match name {
        "visible" => Ok(None),
        "lwir" => Ok(Some(SensorView::new(IrBand::Lwir))),
        "mwir" => Ok(Some(SensorView::new(IrBand::Mwir))),
        _ => Err(()),
    }
}

/// One view's sensor settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SensorView {
    /// The band the view sees.
    pub band: IrBand,
    pub polarity: Polarity,
    /// Manual gain and level (CIGI's 0..1 contrast and brightness); `None`: automatic gain.
    pub manual_gain_level: Option<(f32, f32)>,
    /// Noise-equivalent temperature difference of the detector, kelvin (temporal noise).
    pub netd_k: f32,
    /// Fixed-pattern noise, as a fraction of the NETD (per column and pixel, constant in time).
    pub fixed_pattern: f32,
    /// Optics blur: standard deviation of the point spread, pixels.
    pub blur_px: f32,
    /// AC coupling: time constant of the line-wise decay, microseconds of line time (0: off;
    /// a line of the frame lasts 63.5 us, RS-170).
    pub ac_coupling_us: f32,
    /// Line-by-line dropout on.
    pub line_dropout: bool,
    pub display: DisplayColour,
}

impl SensorView {
    /// A view in `band` with the defaults: white-hot, automatic gain, 50 mK NETD, fixed
    /// pattern 0.5 NETD, 0.6 px blur, no AC coupling, no dropout, white display.
    pub fn new(band: IrBand) -> SensorView {
        SensorView {
            band,
            polarity: Polarity::WhiteHot,
            manual_gain_level: None,
            netd_k: 0.05,
            fixed_pattern: 0.5,
            blur_px: 0.6,
            ac_coupling_us: 0.0,
            line_dropout: false,
            display: DisplayColour::White,
        }
    }

    /// The manual window of apparent temperature, kelvin (low, high), if set.
    pub fn manual_window_k(&self) -> Option<(f64, f64)> {
        self.manual_gain_level.map(|(gain, level)| {
            let centre = 220.0 + 140.0 * f64::from(level.clamp(0.0, 1.0));
            let width = 2.0 * 10f64.powf(2.0 * (1.0 - f64::from(gain.clamp(0.0, 1.0))));
            (centre - 0.5 * width, centre + 0.5 * width)
        })
    }
}

/// The thermal state of the world for one frame.
#[derive(Clone, Debug, PartialEq)]
pub struct ThermalScene {
    /// Surface temperatures, material-major: `[m * 26 + o]` for material `m` (index of
    /// `ThermalMaterial::ALL`) and standard orientation `o` (`cig_thermal::Orientation::standard`),
    /// kelvin.
    pub surface_k: Vec<f32>,
    /// The air temperature, kelvin.
    pub air_k: f64,
    /// The infrared atmosphere the lines of sight cross.
    pub atmosphere: IrAtmosphere,
    /// Hot parts of entities: the entity's id and each part's rise over its surroundings,
    /// kelvin, per `HotPart::ALL`.
    pub entity_heat: Vec<(u32, [f32; 5])>,
    /// Hot spots on the ground (fresh craters, impact points): ECEF centre, radius (metres,
    /// the Gaussian's 1/e) and the rise over the ground now (kelvin).
    pub hot_spots: Vec<([f64; 3], f32, f32)>,
    /// The ground's height above the ellipsoid where `air_k` is (the infrared paths count
    /// heights from there), metres.
    pub base_alt_m: f64,
}

impl ThermalScene {
    /// The table's temperature of `material` at standard orientation `orientation`.
    pub fn surface_k(&self, material: ThermalMaterial, orientation: usize) -> f32 {
        self.surface_k
            .get(material.index() * 26 + orientation)
            .copied()
            .unwrap_or(self.air_k as f32)
    }

    /// A scene from a spun-up table (which must hold every material, in
    /// `ThermalMaterial::ALL` order, on the standard orientations).
    pub fn from_table(
        table: &cig_thermal::SurfaceTable,
        atmosphere: IrAtmosphere,
        entity_heat: Vec<(u32, [f32; 5])>,
    ) -> ThermalScene {
        ThermalScene {
            surface_k: table.surface_temperatures_k(),
            air_k: table.air_k(),
            atmosphere,
            entity_heat,
            hot_spots: Vec::new(),
            base_alt_m: 0.0,
        }
    }
}

/// The infrared atmosphere over a surface table: the table's air (within the atmosphere
/// table's range) and humidity, with an aerosol model and visibility.
pub fn atmosphere_over(
    table: &cig_thermal::SurfaceTable,
    aerosol: cig_thermal::Aerosol,
    visibility_m: f64,
) -> IrAtmosphere {
    IrAtmosphere {
        air_k: table.air_k().clamp(200.0, 330.0),
        relative_humidity_pct: table.weather().relative_humidity_pct,
        aerosol,
        visibility_m,
    }
}

/// The thermal state of a still frame (a render, a benchmark, the demo): every material spun
/// up at a place (the ground `ground_alt_m` above the ellipsoid) over the two days before
/// `time`, the infrared atmosphere over it, and `entities` with their engines steady in
/// `engine`'s state.
#[allow(
    clippy::too_many_arguments,
    reason = "a frame's place, time, weather, air and vehicles"
)]
pub fn still_scene(
    lat_deg: f64,
    lon_deg: f64,
    ground_alt_m: f64,
    time: cig_environment::UtcTime,
    weather: cig_thermal::ThermalWeather,
    (aerosol, visibility_m): (cig_thermal::Aerosol, f64),
    entities: &[u32],
    engine: &cig_thermal::EntityThermalInput,
) -> Result<ThermalScene, cig_thermal::ThermalError> {
    let table = cig_thermal::SurfaceTable::spin_up(
        lat_deg,
        lon_deg,
        time,
        weather,
        &ThermalMaterial::ALL,
        cig_thermal::Orientations::Standard,
    )?;
    let atmosphere = atmosphere_over(&table, aerosol, visibility_m);
    atmosphere.validate()?;
    let heat = cig_thermal::EntityHeat::steady(engine, table.air_k());
    let rise = heat.rise_k.map(|r| r as f32);
    let mut scene = ThermalScene::from_table(
        &table,
        atmosphere,
        entities.iter().map(|id| (*id, rise)).collect(),
    );
    scene.base_alt_m = ground_alt_m;
    Ok(scene)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn codes_round_trip() {
        for m in ThermalMaterial::ALL {
            assert_eq!(decode(material_code(m)), ThermalCode::Material(m));
        }
        for p in HotPart::ALL {
            assert_eq!(decode(hot_code(p)), ThermalCode::Hot(p));
        }
        assert_eq!(decode(DEFAULT_CODE), ThermalCode::InstanceDefault);
        assert_eq!(decode(100), ThermalCode::InstanceDefault);
    }

    #[test]
    fn manual_window_follows_gain_and_level() {
        let mut s = SensorView::new(IrBand::Lwir);
        assert_eq!(s.manual_window_k(), None);
        s.manual_gain_level = Some((1.0, 0.5));
        let (lo, hi) = s.manual_window_k().expect("manual");
        assert!((hi - lo - 2.0).abs() < 1e-9 && ((lo + hi) / 2.0 - 290.0).abs() < 1e-9);
        s.manual_gain_level = Some((0.0, 0.0));
        let (lo, hi) = s.manual_window_k().expect("manual");
        assert!((hi - lo - 200.0).abs() < 1e-9 && ((lo + hi) / 2.0 - 220.0).abs() < 1e-9);
    }
}
