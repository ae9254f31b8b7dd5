//! The scenario file: what an IG shows when it starts, which model each entity type gets, which
//! entities it owns and publishes, and how it joins the DIS exercise.
//!
//! Format: TOML (one document, unknown keys refused so a misspelt key is an error rather than a
//! silent default). Parsing is pure: the binary reads the file and hands the text here; paths in
//! it (glTF models) are returned as written, relative to the scenario's folder. Every number is
//! checked (finite, in range) and every error is one line naming the key and the reason.
//!
//! ```toml
//! name = "tank range"
//! start_time = "2026-06-21T09:30:00Z"   # UTC
//! time_rate = 1.0
//! visibility_m = 20000
//! fog = "exp"                          # off, linear, exp, exp2
//! ground_fog = { top_m = 250, visibility_m = 400 }   # a fogged valley (top above MSL)
//! sky = { model = "physical", exposure_compensation_ev = 0.5 }  # or fixed_exposure_ev = 12
//!
//! [[clouds]]                           # cloud layers (at most 4)
//! base_m = 1200                        # above MSL
//! thickness_m = 600
//! coverage = 0.5                       # 0..1 of the sky
//! kind = "cumulus"                     # cumulus, stratus, stratocumulus, cirrus, ... (CIGI's)
//! wind_speed_mps = 8                   # the layer drifts with it
//! wind_from_deg = 270
//! seed = 1
//! default_model = "truck"              # for entity types the table does not name
//!
//! [[models]]                           # the entity-type table
//! model = "tank"
//! cigi_type = 1                        # CIGI entity type (3.3 Entity Control, 4.0 short type)
//! dis_type = "1:1:225:1"               # DIS kind:domain:country:category[:sub[:spec[:extra]]]
//!
//! [[models]]
//! model = "frigate"
//! gltf = "models/frigate.glb"          # relative to this file
//! dis_type = "1:3:*:6"                 # "*" matches any value
//! cue_important = true                 # keeps its detail under overload (default false)
//! critical_radius_m = 60.0             # r_c of the detail control parameter (default: the
//!                                      # model's bounding radius)
//! dust = false                         # entities of this model raise no dust trail on soil
//!                                      # (default: on for tank and truck)
//! mass_kg = 62000.0                    # with contact_area_m2: the ruts its vehicles leave
//! contact_area_m2 = 5.8                # (Bekker sinkage; default: tank 62 t on 5.8 m2,
//! running_gear = "tracked"             # truck 10 t on 0.8 m2 wheeled; others none)
//!
//! [[entities]]                         # entities this IG owns (drawn, and published on DIS)
//! id = 1                               # CIGI entity id space (0 is the ownship)
//! model = "tank"
//! dis_id = "1:3001:1"                  # site:application:entity
//! dis_type = "1:1:225:1:1:0:0"
//! lat_deg = 51.02
//! lon_deg = -1.48
//! alt_m = 0.0                          # above the terrain when clamped, else above MSL
//! heading_deg = 90
//! clamp = "height_and_attitude"        # none, height, height_and_attitude
//! speed_mps = 8.0                      # along `path`, from `lat_deg`/`lon_deg`
//! path = [[51.02, -1.45], [51.03, -1.44]]
//! loop_path = true
//! dust = true                          # trail of dust when moving on soil (tank, truck: on)
//! lights = ["head", "tail"]            # lamps on: head, tail, brake, blackout, blackout_brake,
//!                                      # spot, landing, navigation, anti_collision, strobe,
//!                                      # running, interior (as the model's light set has them)
//!
//! [view]                               # the view when no host defines one
//! entity = 1                           # attached to an entity (body offsets), or
//! eye = [51.0, -1.5, 300.0]            # a fixed eye (lat, lon, alt MSL)
//! offset_m = [-20.0, 0.0, -5.0]        # x forward, y right, z down
//! hpr_deg = [90.0, -5.0, 0.0]
//! fov_deg = 60.0
//! sensor = "visible"                   # visible, lwir, mwir or nvg
//!
//! [view.nvg]                           # the goggle, for sensor = "nvg"
//! gain = 1.0                           # 0.1..10, 1 nominal
//! phosphor = "p43"                     # p43 (green) or p45 / white
//!
//! [[light]]                            # a lamp standing in the world (all frames)
//! lat_deg = 51.01
//! lon_deg = -1.47
//! alt_m = 105.0                        # above the ellipsoid
//! candela = 500.0
//! colour = "warm"                      # white, warm, red, green, amber, blue or sodium
//!
//! [[flare]]                            # an illumination flare
//! lat_deg = 51.01
//! lon_deg = -1.46
//! alt_m = 700.0                        # where it ignites, above the ellipsoid
//! at_s = 30.0                          # lit this long after the start
//! kind = "155mm"                       # 155mm (M485, 120 s) or 81mm (M853A1, 60 s)
//!
//! [[smoke]]                          # smoke and fire sources (DIS Environmental Processes)
//! id = 1
//! kind = "smoke"                       # smoke or flame
//! lat_deg = 51.01
//! lon_deg = -1.47
//! size_m = 5                           # fire footprint
//! heat_release_w = 5e6
//! start_s = 0                          # after start_time
//! duration_s = 900
//!
//! [precipitation]                    # rain or snow around the eye
//! kind = "rain"                        # rain, snow or sleet
//! rate_mm_per_h = 8.0                  # water equivalent, 0..200
//! seed = 1                             # the particles' places
//!
//! [sea]                                # the sea over the database's water and beyond its edge
//! sea_state = 4                        # WMO code 0-9: a fully developed sea, or
//! wind_mps = 12.0                      # the wind (at 10 m) the sea grows in
//! wind_from_deg = 270
//! fetch_km = 40                        # the wind's run over water (default: unlimited)
//! swell = { height_m = 1.5, period_s = 11.0, from_deg = 240.0 }
//! level_m = 0.0                        # the sea surface above MSL (the tide)
//! water_temperature_c = 15.0
//! clarity_pct = 80.0                   # 0 turbid, 100 clear open ocean
//! whitecaps = true
//! seed = 1                             # every IG with this seed draws the same waves
//!
//! [lightning]                          # a thunderstorm that strikes by itself
//! lat_deg = 51.05                      # centre
//! lon_deg = -1.45
//! radius_m = 8000                      # strikes anywhere within this distance
//! cloud_base_m = 1500                  # the bolts' roots, above the ground
//! strikes_per_minute = 6
//! seed = 42                            # every IG with this seed draws the same bolts
//! enabled = true
//!
//! [dis]
//! exercise = 1
//! site = 3001
//! application = 1
//! port = 3000
//! delivery = "broadcast"               # unicast:HOST:PORT, broadcast, multicast:GROUP
//! bind = "loopback"                    # loopback, any, an address or an interface name
//! time_master = false                  # seed the exercise's world time from start_time
//! remote_ruts = false                  # as the time master, lay ruts for the exercise's
//!                                      # ground vehicles whose nodes lay none
//! accepted_sites = []                  # empty: all
//! ```
//!
//! Limits: one database per scenario (given on the command line); owned entities move along
//! straight geodesic-free segments at constant speed (enough for demos and tests, not a
//! vehicle model).

use cig_dis::EntityTypeCode;
use cig_environment::UtcTime;
use cig_scene::lighting::FogMode;
use cig_scene::snapshot::Clamp;
use serde::Deserialize;
use std::path::PathBuf;

/// Why a scenario cannot be used.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum ScenarioError {
    #[error("not a valid scenario: {0}")]
    Syntax(String),
    #[error("{key}: {reason}")]
    Value { key: String, reason: String },
}

pub(crate) fn value_error(key: impl Into<String>, reason: impl Into<String>) -> ScenarioError {
    ScenarioError::Value {
        key: key.into(),
        reason: reason.into(),
    }
}

/// A scenario, checked.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Scenario {
    #[serde(default)]
    pub name: String,
    /// Start of the simulation, ISO 8601 UTC (default: the command line's or now).
    #[serde(default)]
    pub start_time: Option<String>,
    /// Simulation seconds per real second.
    #[serde(default = "one")]
    pub time_rate: f64,
    #[serde(default)]
    pub visibility_m: Option<f64>,
    #[serde(default)]
    pub fog: Option<String>,
    /// A ground fog or haze layer: valleys below its top are fogged, hills above are clear.
    #[serde(default)]
    pub ground_fog: Option<GroundFog>,
    /// Model for entity types the table does not name.
    #[serde(default = "default_model")]
    pub default_model: String,
    #[serde(default)]
    pub models: Vec<ModelMapping>,
    #[serde(default)]
    pub entities: Vec<ScenarioEntity>,
    #[serde(default)]
    pub view: Option<ScenarioView>,
    #[serde(default)]
    pub dis: Option<DisSettings>,
    /// Smoke and fire sources (processes, published as DIS Environmental Process PDUs).
    #[serde(default)]
    pub smoke: Vec<SmokeSource>,
    /// The sky model and the exposure.
    #[serde(default)]
    pub sky: Option<SkySection>,
    /// Cloud layers (the host's CIGI cloud layers replace them while it sets any).
    #[serde(default)]
    pub clouds: Vec<ScenarioCloud>,
    /// Rain or snow.
    #[serde(default)]
    pub precipitation: Option<ScenarioPrecipitation>,
    /// A thunderstorm.
    #[serde(default)]
    pub lightning: Option<ScenarioLightning>,
    /// The sea (the host's Maritime Surface Conditions and Wave Control add to it).
    #[serde(default)]
    pub sea: Option<ScenarioSea>,
    /// The thermal sensors' weather history (`crate::thermal`).
    #[serde(default)]
    pub thermal: Option<ThermalSection>,
    /// Lamps standing in the world, lit every frame.
    #[serde(default, rename = "light")]
    pub lights: Vec<ScenarioLight>,
    /// Illumination flares, lit at their time.
    #[serde(default, rename = "flare")]
    pub flares: Vec<ScenarioFlare>,
}

/// `[[light]]`: a lamp standing in the world.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ScenarioLight {
    pub lat_deg: f64,
    pub lon_deg: f64,
    /// Above the ellipsoid.
    #[serde(default)]
    pub alt_m: f64,
    pub candela: f64,
    /// A lamp name (`cig_scene::lights::named_lamp`).
    #[serde(default = "default_lamp_colour")]
    pub colour: String,
}

fn default_lamp_colour() -> String {
    "warm".to_string()
}

/// `[[flare]]`: an illumination flare.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ScenarioFlare {
    pub lat_deg: f64,
    pub lon_deg: f64,
    /// Where it ignites, above the ellipsoid.
    pub alt_m: f64,
    /// Seconds after the scenario's start when it is lit.
    #[serde(default)]
    pub at_s: f64,
    /// `155mm` or `81mm`.
    pub kind: String,
}

impl ScenarioFlare {
    /// The flare, its ignition `at_s` after `start_unix_s`; `None` for an unknown kind (refused
    /// when the scenario is checked).
    pub fn flare(&self, start_unix_s: f64) -> Option<cig_scene::lights::Flare> {
        let start = cig_geo::Geodetic::new(self.lat_deg, self.lon_deg, self.alt_m);
        let at = start_unix_s + self.at_s;
        match self.kind.as_str() {
            "155mm" => Some(cig_scene::lights::Flare::artillery_155mm(start, at)),
            "81mm" => Some(cig_scene::lights::Flare::mortar_81mm(start, at)),
            _ => None,
        }
    }
}

/// `[view.nvg]`: the night-vision goggle of a `sensor = "nvg"` view.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ScenarioNvg {
    /// Manual gain, 0.1..10 (1 nominal).
    #[serde(default)]
    pub gain: Option<f32>,
    /// `p43` (green) or `p45` / `white`.
    #[serde(default)]
    pub phosphor: Option<String>,
}

/// `[thermal]`: what heated the world's surfaces before the start, for the thermal sensors.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ThermalSection {
    /// Daily minimum air temperature, Celsius (at sunrise).
    #[serde(default)]
    pub air_min_c: Option<f64>,
    /// Daily maximum air temperature, Celsius (at 14:00 local solar time).
    #[serde(default)]
    pub air_max_c: Option<f64>,
    /// 24 hourly air temperatures at 00:00..23:00 local solar time, Celsius (instead of the
    /// minimum and maximum).
    #[serde(default)]
    pub air_hourly_c: Option<Vec<f64>>,
    /// Relative humidity, percent (the host's Atmosphere Control replaces it).
    #[serde(default)]
    pub humidity_pct: Option<f64>,
    /// Wind speed near the ground, m/s (the host's replaces it).
    #[serde(default)]
    pub wind_mps: Option<f64>,
    /// Deep-ground temperature at about 1 m, Celsius (default: the air's daily mean).
    #[serde(default)]
    pub deep_ground_c: Option<f64>,
    /// Aerosol model of the infrared atmosphere: none, rural (default), maritime, urban.
    #[serde(default)]
    pub aerosol: Option<String>,
}

/// `[sky]`: the sky model and the exposure.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SkySection {
    /// "physical" (default) or "flat".
    #[serde(default)]
    pub model: Option<String>,
    /// Added to the automatic exposure, EV (-10..10).
    #[serde(default)]
    pub exposure_compensation_ev: f64,
    /// Expose for this incident-light EV (`log2(lux / 2.5)`, -20..20) instead of the natural
    /// illuminance.
    #[serde(default)]
    pub fixed_exposure_ev: Option<f64>,
}

/// A cloud layer of the scenario.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ScenarioCloud {
    /// Base, metres above MSL.
    pub base_m: f64,
    pub thickness_m: f64,
    /// Covered fraction of the sky, 0..1.
    pub coverage: f64,
    /// Cloud type name (`cig_environment::clouds::CloudKind`), default cumulus.
    #[serde(default = "cumulus")]
    pub kind: String,
    #[serde(default)]
    pub wind_speed_mps: f64,
    #[serde(default)]
    pub wind_from_deg: f64,
    #[serde(default = "one_u64")]
    pub seed: u64,
}

/// The scenario's rain or snow.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ScenarioPrecipitation {
    /// "rain", "snow" or "sleet".
    #[serde(default = "rain_kind")]
    pub kind: String,
    /// Water-equivalent rate, mm/h.
    pub rate_mm_per_h: f64,
    #[serde(default = "one_u64")]
    pub seed: u64,
}

fn cumulus() -> String {
    "cumulus".to_string()
}

fn one_u64() -> u64 {
    1
}

impl Scenario {
    /// The scenario's cloud layers (checked when the scenario was parsed).
    pub fn cloud_layers(&self) -> Vec<cig_environment::clouds::CloudLayer> {
        self.clouds.iter().filter_map(|c| c.layer().ok()).collect()
    }
}

impl ScenarioCloud {
    fn layer(&self) -> Result<cig_environment::clouds::CloudLayer, String> {
        let kind = cig_environment::clouds::CloudKind::from_name(&self.kind)
            .ok_or_else(|| format!("\"{}\" is not a cloud type", self.kind))?;
        Ok(cig_environment::clouds::CloudLayer {
            base_m: self.base_m,
            thickness_m: self.thickness_m,
            coverage: self.coverage,
            kind,
            wind_speed_mps: self.wind_speed_mps,
            wind_from_deg: self.wind_from_deg,
            seed: self.seed,
            drift: cig_environment::CloudDrift::default(),
        })
    }

    fn check(&self, key: &str) -> Result<(), ScenarioError> {
        use cig_environment::clouds::{BASE_RANGE_M, MAX_THICKNESS_M, MAX_WIND_SPEED_MPS};
        check_finite(
            &format!("{key}.base_m"),
            self.base_m,
            BASE_RANGE_M.0,
            BASE_RANGE_M.1,
        )?;
        if !(self.thickness_m.is_finite() && self.thickness_m > 0.0) {
            return Err(value_error(
                format!("{key}.thickness_m"),
                format!("{} is not above 0", self.thickness_m),
            ));
        }
        check_finite(
            &format!("{key}.thickness_m"),
            self.thickness_m,
            0.0,
            MAX_THICKNESS_M,
        )?;
        check_finite(&format!("{key}.coverage"), self.coverage, 0.0, 1.0)?;
        check_finite(
            &format!("{key}.wind_speed_mps"),
            self.wind_speed_mps,
            0.0,
            MAX_WIND_SPEED_MPS,
        )?;
        check_finite(
            &format!("{key}.wind_from_deg"),
            self.wind_from_deg,
            -360.0,
            360.0,
        )?;
        self.layer()
            .map_err(|reason| value_error(format!("{key}.kind"), reason))?;
        Ok(())
    }
}

/// `[sea]`: the sea's waves and water.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ScenarioSea {
    /// A WMO sea state code, 0-9: the fully developed sea of its wind (excludes `wind_mps`).
    #[serde(default)]
    pub sea_state: Option<f64>,
    /// The wind the sea grows in, at 10 m, m/s (excludes `sea_state`).
    #[serde(default)]
    pub wind_mps: Option<f64>,
    /// Where the wind blows from, degrees true.
    #[serde(default = "west_deg")]
    pub wind_from_deg: f64,
    /// The wind's run over water, km (none: fully developed).
    #[serde(default)]
    pub fetch_km: Option<f64>,
    /// A swell from a distant storm.
    #[serde(default)]
    pub swell: Option<ScenarioSwell>,
    /// The sea surface above mean sea level, metres (the tide).
    #[serde(default)]
    pub level_m: f64,
    #[serde(default = "fifteen")]
    pub water_temperature_c: f64,
    /// 0 turbid, 100 clear open ocean.
    #[serde(default = "hundred")]
    pub clarity_pct: f64,
    #[serde(default = "yes")]
    pub whitecaps: bool,
    #[serde(default = "one_u64")]
    pub seed: u64,
}

/// `[sea] swell = {..}`.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ScenarioSwell {
    pub height_m: f64,
    pub period_s: f64,
    pub from_deg: f64,
}

fn west_deg() -> f64 {
    270.0
}

fn fifteen() -> f64 {
    15.0
}

fn hundred() -> f64 {
    100.0
}

impl ScenarioSea {
    /// The wind sea and swell the section describes.
    ///
    /// # Errors
    /// A value out of range, as a one-line error naming the key.
    pub fn conditions(&self) -> Result<cig_sea::spectrum::SeaConditions, ScenarioError> {
        use cig_sea::spectrum::{SeaConditions, Swell};
        let base = match (self.sea_state, self.wind_mps) {
            (Some(code), None) => {
                if !(code.is_finite() && (0.0..=9.0).contains(&code) && code.fract() == 0.0) {
                    return Err(value_error(
                        "sea.sea_state",
                        format!("{code} is not a WMO sea state code, a whole number 0-9"),
                    ));
                }
                #[expect(
                    clippy::cast_possible_truncation,
                    clippy::cast_sign_loss,
                    reason = "a whole number in 0..=9, checked above"
                )]
                let code = code as u8;
                SeaConditions::for_sea_state(code, self.wind_from_deg)
                    .map_err(|e| value_error("sea.sea_state", e.to_string()))?
            }
            (None, Some(wind)) => SeaConditions::new(wind, self.wind_from_deg)
                .map_err(|e| value_error("sea.wind_mps", e.to_string()))?,
            (None, None) => SeaConditions::new(0.0, self.wind_from_deg)
                .map_err(|e| value_error("sea.wind_from_deg", e.to_string()))?,
            (Some(_), Some(_)) => {
                return Err(value_error("sea", "give sea_state or wind_mps, not both"))
            }
        };
        let with_fetch = match self.fetch_km {
            Some(km) => base
                .with_fetch_m(km * 1000.0)
                .map_err(|e| value_error("sea.fetch_km", e.to_string()))?,
            None => base,
        };
        match self.swell {
            Some(s) => {
                let swell = Swell::new(s.height_m, s.period_s, s.from_deg)
                    .map_err(|e| value_error("sea.swell", e.to_string()))?;
                with_fetch
                    .with_swell(swell)
                    .map_err(|e| value_error("sea.swell", e.to_string()))
            }
            None => Ok(with_fetch),
        }
    }

    fn check(&self) -> Result<(), ScenarioError> {
        self.conditions()?;
        check_finite("sea.level_m", self.level_m, -20.0, 20.0)?;
        check_finite(
            "sea.water_temperature_c",
            self.water_temperature_c,
            -2.0,
            40.0,
        )?;
        check_finite("sea.clarity_pct", self.clarity_pct, 0.0, 100.0)
    }
}

/// The scenario's thunderstorm.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ScenarioLightning {
    pub lat_deg: f64,
    pub lon_deg: f64,
    #[serde(default = "storm_radius")]
    pub radius_m: f64,
    #[serde(default = "cloud_base")]
    pub cloud_base_m: f64,
    #[serde(default = "strike_rate")]
    pub strikes_per_minute: f64,
    #[serde(default = "one_u64")]
    pub seed: u64,
    #[serde(default = "yes")]
    pub enabled: bool,
}

impl ScenarioPrecipitation {
    /// The checked precipitation.
    pub fn precipitation(&self) -> Option<cig_environment::Precipitation> {
        let kind = cig_environment::PrecipitationKind::parse(&self.kind)?;
        cig_environment::Precipitation::new(kind, self.rate_mm_per_h).ok()
    }
}

impl ScenarioLightning {
    /// The storm, when enabled.
    pub fn storm(&self) -> Option<crate::weather::LightningStorm> {
        self.enabled.then_some(crate::weather::LightningStorm {
            centre_lat_deg: self.lat_deg,
            centre_lon_deg: self.lon_deg,
            radius_m: self.radius_m,
            cloud_base_m: self.cloud_base_m,
            strikes_per_minute: self.strikes_per_minute,
            seed: self.seed,
        })
    }
}

fn rain_kind() -> String {
    "rain".to_string()
}
fn storm_radius() -> f64 {
    10_000.0
}
fn cloud_base() -> f64 {
    1500.0
}
fn strike_rate() -> f64 {
    6.0
}
fn yes() -> bool {
    true
}

/// A smoke or fire source the scenario starts.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SmokeSource {
    /// Process number (the DIS process id is SITE:APPLICATION:id).
    pub id: u16,
    /// "smoke" or "flame".
    #[serde(default = "smoke_kind")]
    pub kind: String,
    pub lat_deg: f64,
    pub lon_deg: f64,
    /// Above the terrain, metres.
    #[serde(default)]
    pub alt_m: f64,
    /// Fire footprint diameter, metres.
    #[serde(default = "five")]
    pub size_m: f64,
    /// Convective heat release, watts.
    #[serde(default = "five_mw")]
    pub heat_release_w: f64,
    /// Seconds after the scenario's start.
    #[serde(default)]
    pub start_s: f64,
    #[serde(default = "hour")]
    pub duration_s: f64,
}

fn smoke_kind() -> String {
    "smoke".to_string()
}
fn five() -> f64 {
    5.0
}
fn five_mw() -> f64 {
    5.0e6
}
fn hour() -> f64 {
    3600.0
}

fn one() -> f64 {
    1.0
}

fn default_model() -> String {
    "truck".to_string()
}

/// A ground fog layer of the scenario.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GroundFog {
    /// Top of the layer, metres above MSL.
    pub top_m: f64,
    /// Visibility inside the layer, metres.
    pub visibility_m: f64,
}

/// One row of the entity-type table.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ModelMapping {
    /// Model name: a built-in one (tank, truck, destroyer or ship, merchant, patrol_craft,
    /// building, tree) or the name a glTF file
    /// is loaded under.
    pub model: String,
    /// glTF 2.0 file, relative to the scenario's folder.
    #[serde(default)]
    pub gltf: Option<PathBuf>,
    /// CIGI entity type.
    #[serde(default)]
    pub cigi_type: Option<u16>,
    /// DIS entity type pattern.
    #[serde(default)]
    pub dis_type: Option<String>,
    /// An important cue (the runway, a target vehicle): the model keeps the nominal detail
    /// control parameter when the renderer's overload control lowers it for the rest (source
    /// 004 §4.6). The mark belongs to the model: any row marking a model marks it for every
    /// entity drawn with it.
    #[serde(default)]
    pub cue_important: bool,
    /// The model's critical radius `r_c` in the detail control parameter (source 004 Eq 16),
    /// metres, when the modeller sets it apart from the bounding radius (a long thin ship is
    /// seen by its hull's length, a mast by less than its height). Like `cue_important` it
    /// belongs to the model.
    #[serde(default)]
    pub critical_radius_m: Option<f64>,
    /// Whether entities drawn with this model raise a dust trail when they move on soil (the
    /// host's and the exercise's as well as the scenario's own; default: on for the ground
    /// vehicles, tank and truck). Like `cue_important` it belongs to the model.
    #[serde(default)]
    pub dust: Option<bool>,
    /// The vehicle's mass, kg, for the ruts it leaves (with `contact_area_m2`; default: the
    /// tank's and truck's in `ModelTable::vehicle_load`).
    #[serde(default)]
    pub mass_kg: Option<f64>,
    /// Its ground contact area, all tracks or wheels together, square metres.
    #[serde(default)]
    pub contact_area_m2: Option<f64>,
    /// "tracked" or "wheeled" (default tracked).
    #[serde(default)]
    pub running_gear: Option<String>,
}

/// An entity the IG owns.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ScenarioEntity {
    pub id: u16,
    #[serde(default)]
    pub model: Option<String>,
    #[serde(default)]
    pub dis_id: Option<String>,
    #[serde(default)]
    pub dis_type: Option<String>,
    pub lat_deg: f64,
    pub lon_deg: f64,
    #[serde(default)]
    pub alt_m: f64,
    #[serde(default)]
    pub heading_deg: f64,
    #[serde(default)]
    pub clamp: Clamp,
    #[serde(default)]
    pub speed_mps: f64,
    #[serde(default)]
    pub path: Vec<[f64; 2]>,
    #[serde(default)]
    pub loop_path: bool,
    /// DIS appearance bits, hexadecimal ("0x..." or digits).
    #[serde(default)]
    pub appearance: Option<String>,
    /// Raise a dust trail when moving on soil (default: for ground vehicle models, tank and
    /// truck).
    #[serde(default)]
    pub dust: Option<bool>,
    /// Engine running (thermal sensors: engine deck, exhaust and running gear warm); default:
    /// the DIS appearance's power-plant bit, else running.
    #[serde(default)]
    pub engine: Option<bool>,
    /// Lamps switched on (`crate::lights::SWITCH_NAMES`); lamps its model's light set lacks
    /// are not drawn.
    #[serde(default)]
    pub lights: Vec<String>,
}

/// The view used when no host defines one.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ScenarioView {
    #[serde(default)]
    pub entity: Option<u16>,
    #[serde(default)]
    pub eye: Option<[f64; 3]>,
    #[serde(default)]
    pub offset_m: [f64; 3],
    #[serde(default)]
    pub hpr_deg: [f64; 3],
    #[serde(default = "default_fov")]
    pub fov_deg: f64,
    /// The view's sensor: visible (default), lwir, mwir or nvg.
    #[serde(default)]
    pub sensor: Option<String>,
    /// The goggle of an `nvg` view (defaults without it).
    #[serde(default)]
    pub nvg: Option<ScenarioNvg>,
}

fn default_fov() -> f64 {
    60.0
}

/// How the IG joins a DIS exercise.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DisSettings {
    #[serde(default = "one_u8")]
    pub exercise: u8,
    #[serde(default = "default_site")]
    pub site: u16,
    #[serde(default = "one_u16")]
    pub application: u16,
    #[serde(default = "default_dis_port")]
    pub port: u16,
    #[serde(default = "default_delivery")]
    pub delivery: String,
    #[serde(default = "default_bind")]
    pub bind: String,
    #[serde(default)]
    pub time_master: bool,
    /// While this IG keeps the exercise's time, it lays ruts for the exercise's land
    /// platforms whose own nodes lay none (`Exercise::remote_rut_vehicles`). Off by default:
    /// each rut refines cells on every node, and hundreds of vehicles' ruts cost memory
    /// (see `terrain_edits::MAX_RUTS_PER_S`).
    #[serde(default)]
    pub remote_ruts: bool,
    #[serde(default)]
    pub accepted_sites: Vec<u16>,
    /// Protocol version written: 7 (default) or 6.
    #[serde(default = "seven")]
    pub version: u8,
}

fn one_u8() -> u8 {
    1
}
fn one_u16() -> u16 {
    1
}
fn seven() -> u8 {
    7
}
fn default_site() -> u16 {
    1
}
fn default_dis_port() -> u16 {
    3000
}
fn default_delivery() -> String {
    "broadcast".to_string()
}
fn default_bind() -> String {
    "loopback".to_string()
}

impl Default for DisSettings {
    fn default() -> Self {
        DisSettings {
            exercise: 1,
            site: 1,
            application: 1,
            port: 3000,
            delivery: default_delivery(),
            bind: default_bind(),
            time_master: false,
            remote_ruts: false,
            accepted_sites: Vec::new(),
            version: 7,
        }
    }
}

/// A DIS entity type pattern: each of the seven fields a value or "any".
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub struct DisTypePattern {
    /// kind, domain, country, category, subcategory, specific, extra; `None` matches any.
    pub fields: [Option<u16>; 7],
}

impl DisTypePattern {
    /// Parses "K:D:C:CAT[:SUB[:SPEC[:EXTRA]]]"; omitted trailing fields and "*" match any.
    pub fn parse(text: &str) -> Option<DisTypePattern> {
        let parts: Vec<&str> = text.split(':').map(str::trim).collect();
        if parts.is_empty() || parts.len() > 7 {
            return None;
        }
        let mut fields = [None; 7];
        for (slot, part) in fields.iter_mut().zip(&parts) {
            if *part != "*" {
                *slot = Some(part.parse::<u16>().ok()?);
            }
        }
        // Kind, domain, category, subcategory, specific and extra are octets.
        for (i, field) in fields.iter().enumerate() {
            if i != 2 && field.is_some_and(|v| v > 255) {
                return None;
            }
        }
        Some(DisTypePattern { fields })
    }

    /// The exact type, when every field is given.
    pub fn exact(&self) -> Option<EntityTypeCode> {
        let f = self.fields;
        let octet = |i: usize| f[i].and_then(|v| u8::try_from(v).ok());
        Some(EntityTypeCode {
            kind: octet(0)?,
            domain: octet(1)?,
            country: f[2]?,
            category: octet(3)?,
            subcategory: octet(4).unwrap_or(0),
            specific: octet(5).unwrap_or(0),
            extra: octet(6).unwrap_or(0),
        })
    }

    /// How many leading fields match (`None`: the pattern does not match).
    pub fn specificity(&self, t: &EntityTypeCode) -> Option<usize> {
        let values = [
            u16::from(t.kind),
            u16::from(t.domain),
            t.country,
            u16::from(t.category),
            u16::from(t.subcategory),
            u16::from(t.specific),
            u16::from(t.extra),
        ];
        let mut score = 0;
        for (pattern, value) in self.fields.iter().zip(values) {
            match pattern {
                Some(p) if *p != value => return None,
                Some(_) => score += 1,
                None => {}
            }
        }
        Some(score)
    }
}

/// Parses a DIS entity id "SITE:APP:ID".
pub fn parse_dis_id(text: &str) -> Option<(u16, u16, u16)> {
    let mut parts = text.split(':').map(|p| p.trim().parse::<u16>());
    let site = parts.next()?.ok()?;
    let application = parts.next()?.ok()?;
    let entity = parts.next()?.ok()?;
    if parts.next().is_some() {
        return None;
    }
    Some((site, application, entity))
}

/// Parses hexadecimal appearance bits.
pub fn parse_hex_u32(text: &str) -> Option<u32> {
    let digits = text
        .trim()
        .trim_start_matches("0x")
        .trim_start_matches("0X");
    u32::from_str_radix(digits, 16).ok()
}

fn check_lat_lon(key: &str, lat_deg: f64, lon_deg: f64) -> Result<(), ScenarioError> {
    if !(lat_deg.is_finite() && (-90.0..=90.0).contains(&lat_deg)) {
        return Err(value_error(
            format!("{key}.lat_deg"),
            format!("{lat_deg} is outside -90..90"),
        ));
    }
    if !(lon_deg.is_finite() && (-180.0..=360.0).contains(&lon_deg)) {
        return Err(value_error(
            format!("{key}.lon_deg"),
            format!("{lon_deg} is outside -180..360"),
        ));
    }
    Ok(())
}

fn check_finite(key: &str, value: f64, lo: f64, hi: f64) -> Result<(), ScenarioError> {
    if value.is_finite() && (lo..=hi).contains(&value) {
        Ok(())
    } else {
        Err(value_error(key, format!("{value} is outside {lo}..{hi}")))
    }
}

impl Scenario {
    /// Parses and checks a scenario.
    pub fn from_toml(text: &str) -> Result<Scenario, ScenarioError> {
        let scenario: Scenario = toml::from_str(text).map_err(|e| {
            // toml's messages span lines (source excerpt); keep the first.
            let message = e
                .message()
                .lines()
                .next()
                .unwrap_or("syntax error")
                .to_string();
            let at = e
                .span()
                .map(|s| {
                    let line = text.get(..s.start).map_or(0, |t| t.lines().count().max(1));
                    format!(" (line {line})")
                })
                .unwrap_or_default();
            ScenarioError::Syntax(format!("{message}{at}"))
        })?;
        scenario.check()?;
        Ok(scenario)
    }

    fn check(&self) -> Result<(), ScenarioError> {
        if let Some(t) = &self.thermal {
            t.weather()?;
        }
        if let Some(sensor) = self.view.as_ref().and_then(|v| v.sensor.as_deref()) {
            if sensor != "nvg" && cig_scene::thermal::sensor_of_name(sensor).is_err() {
                return Err(value_error(
                    "view.sensor",
                    format!("\"{sensor}\" is not visible, lwir, mwir or nvg"),
                ));
            }
        }
        if let Some(n) = self.view.as_ref().and_then(|v| v.nvg.as_ref()) {
            if let Some(p) = &n.phosphor {
                cig_scene::nvg::Phosphor::from_name(p)
                    .map_err(|e| value_error("view.nvg.phosphor", e.to_string()))?;
            }
            if let Some(g) = n.gain {
                let view = cig_scene::nvg::NvgView {
                    gain: g,
                    ..cig_scene::nvg::NvgView::default()
                };
                view.validate()
                    .map_err(|e| value_error("view.nvg.gain", e.to_string()))?;
            }
        }
        for (i, l) in self.lights.iter().enumerate() {
            let key = format!("light[{i}]");
            check_lat_lon(&key, l.lat_deg, l.lon_deg)?;
            check_finite(&format!("{key}.alt_m"), l.alt_m, -12_000.0, 1.0e6)?;
            if !(l.candela.is_finite() && l.candela > 0.0 && l.candela <= 1.0e9) {
                return Err(value_error(
                    format!("{key}.candela"),
                    format!("{} must be more than 0 and at most 1e9", l.candela),
                ));
            }
            if cig_scene::lights::named_lamp(&l.colour).is_none() {
                return Err(value_error(
                    format!("{key}.colour"),
                    format!("\"{}\" is not {}", l.colour, cig_scene::lights::LAMP_NAMES),
                ));
            }
        }
        for (i, f) in self.flares.iter().enumerate() {
            let key = format!("flare[{i}]");
            check_lat_lon(&key, f.lat_deg, f.lon_deg)?;
            check_finite(&format!("{key}.alt_m"), f.alt_m, -12_000.0, 1.0e6)?;
            check_finite(&format!("{key}.at_s"), f.at_s, 0.0, 1.0e7)?;
            if f.flare(0.0).is_none() {
                return Err(value_error(
                    format!("{key}.kind"),
                    format!("\"{}\" is not 155mm or 81mm", f.kind),
                ));
            }
        }
        if let Some(t) = &self.start_time {
            UtcTime::parse_iso8601(t).map_err(|e| value_error("start_time", e.to_string()))?;
        }
        check_finite("time_rate", self.time_rate, -1000.0, 1000.0)?;
        if let Some(v) = self.visibility_m {
            check_finite("visibility_m", v, 1.0, 1.0e7)?;
        }
        if let Some(g) = &self.ground_fog {
            check_finite("ground_fog.top_m", g.top_m, -500.0, 10_000.0)?;
            check_finite("ground_fog.visibility_m", g.visibility_m, 1.0, 1.0e6)?;
        }
        if let Some(sky) = &self.sky {
            check_finite(
                "sky.exposure_compensation_ev",
                sky.exposure_compensation_ev,
                -10.0,
                10.0,
            )?;
            if let Some(ev) = sky.fixed_exposure_ev {
                check_finite("sky.fixed_exposure_ev", ev, -20.0, 20.0)?;
            }
            if let Some(m) = &sky.model {
                if sky_model(m).is_none() {
                    return Err(value_error(
                        "sky.model",
                        format!("\"{m}\" is not physical or flat"),
                    ));
                }
            }
        }
        if self.clouds.len() > cig_environment::clouds::MAX_CLOUD_LAYERS {
            return Err(value_error(
                "clouds",
                format!(
                    "{} layers; at most {}",
                    self.clouds.len(),
                    cig_environment::clouds::MAX_CLOUD_LAYERS
                ),
            ));
        }
        for (i, c) in self.clouds.iter().enumerate() {
            c.check(&format!("clouds[{i}]"))?;
        }
        if let Some(f) = &self.fog {
            if FogMode::parse(f).is_none() {
                return Err(value_error(
                    "fog",
                    format!("\"{f}\" is not off, linear, exp or exp2"),
                ));
            }
        }
        for (i, m) in self.models.iter().enumerate() {
            let key = format!("models[{i}]");
            if m.model.trim().is_empty() {
                return Err(value_error(format!("{key}.model"), "is empty"));
            }
            if m.cigi_type.is_none() && m.dis_type.is_none() {
                return Err(value_error(key, "names neither cigi_type nor dis_type"));
            }
            if let Some(r) = m.critical_radius_m {
                if !(r.is_finite() && r > 0.0 && r <= 100_000.0) {
                    return Err(value_error(
                        format!("{key}.critical_radius_m"),
                        format!("{r} must be more than 0 and at most 100 km"),
                    ));
                }
            }
            if let Some(gear) = &m.running_gear {
                if !matches!(gear.as_str(), "tracked" | "wheeled") {
                    return Err(value_error(
                        format!("{key}.running_gear"),
                        format!("\"{gear}\" is not tracked or wheeled"),
                    ));
                }
            }
            match (m.mass_kg, m.contact_area_m2) {
                (None, None) => {}
                (Some(mass_kg), Some(area_m2)) => {
                    if let Err(e) = cig_dynterrain::soil::VehicleLoad::new(
                        mass_kg,
                        area_m2,
                        cig_dynterrain::soil::RunningGear::Tracked,
                    ) {
                        return Err(value_error(format!("{key}.mass_kg"), e.to_string()));
                    }
                }
                _ => {
                    return Err(value_error(
                        key,
                        "gives one of mass_kg and contact_area_m2 without the other",
                    ))
                }
            }
            if let Some(t) = &m.dis_type {
                if DisTypePattern::parse(t).is_none() {
                    return Err(value_error(
                        format!("{key}.dis_type"),
                        format!("\"{t}\" is not KIND:DOMAIN:COUNTRY:CATEGORY[:SUB[:SPEC[:EXTRA]]]"),
                    ));
                }
            }
        }
        let known_model = |name: &str| {
            cig_scene::models::BUILTIN_MODELS.contains(&name)
                || self
                    .models
                    .iter()
                    .any(|m| m.model == name && m.gltf.is_some())
        };
        let mut names: Vec<(String, &str)> = self
            .models
            .iter()
            .enumerate()
            .map(|(i, m)| (format!("models[{i}].model"), m.model.as_str()))
            .collect();
        names.push(("default_model".to_string(), self.default_model.as_str()));
        for (i, e) in self.entities.iter().enumerate() {
            if let Some(m) = &e.model {
                names.push((format!("entities[{i}].model"), m.as_str()));
            }
        }
        for (key, name) in names {
            if !known_model(name) {
                return Err(value_error(
                    key,
                    format!(
                        "\"{name}\" is neither a built-in model ({}) nor a model given a gltf file",
                        cig_scene::models::BUILTIN_MODELS.join(", ")
                    ),
                ));
            }
        }
        let mut ids = std::collections::BTreeSet::new();
        for (i, e) in self.entities.iter().enumerate() {
            let key = format!("entities[{i}]");
            if !ids.insert(e.id) {
                return Err(value_error(
                    format!("{key}.id"),
                    format!("{} is used twice", e.id),
                ));
            }
            check_lat_lon(&key, e.lat_deg, e.lon_deg)?;
            check_finite(&format!("{key}.alt_m"), e.alt_m, -12_000.0, 1.0e6)?;
            check_finite(&format!("{key}.heading_deg"), e.heading_deg, -720.0, 720.0)?;
            check_finite(&format!("{key}.speed_mps"), e.speed_mps, 0.0, 10_000.0)?;
            for (j, p) in e.path.iter().enumerate() {
                check_lat_lon(&format!("{key}.path[{j}]"), p[0], p[1])?;
            }
            if let Some(id) = &e.dis_id {
                if parse_dis_id(id).is_none() {
                    return Err(value_error(
                        format!("{key}.dis_id"),
                        format!("\"{id}\" is not SITE:APPLICATION:ENTITY"),
                    ));
                }
            }
            if let Some(t) = &e.dis_type {
                if DisTypePattern::parse(t).and_then(|p| p.exact()).is_none() {
                    return Err(value_error(
                        format!("{key}.dis_type"),
                        format!("\"{t}\" is not KIND:DOMAIN:COUNTRY:CATEGORY[:SUB[:SPEC[:EXTRA]]]"),
                    ));
                }
            }
            for (j, name) in e.lights.iter().enumerate() {
                if crate::lights::switch_of_name(name).is_none() {
                    return Err(value_error(
                        format!("{key}.lights[{j}]"),
                        format!(
                            "\"{name}\" is not {}",
                            crate::lights::SWITCH_NAMES.join(", ")
                        ),
                    ));
                }
            }
            if let Some(a) = &e.appearance {
                if parse_hex_u32(a).is_none() {
                    return Err(value_error(
                        format!("{key}.appearance"),
                        format!("\"{a}\" is not a hexadecimal 32-bit value"),
                    ));
                }
            }
        }
        let mut smoke_ids = std::collections::BTreeSet::new();
        for (i, m) in self.smoke.iter().enumerate() {
            let key = format!("smoke[{i}]");
            if !smoke_ids.insert(m.id) {
                return Err(value_error(
                    format!("{key}.id"),
                    format!("{} is used twice", m.id),
                ));
            }
            if m.kind != "smoke" && m.kind != "flame" {
                return Err(value_error(
                    format!("{key}.kind"),
                    format!("\"{}\" is not smoke or flame", m.kind),
                ));
            }
            check_lat_lon(&key, m.lat_deg, m.lon_deg)?;
            check_finite(&format!("{key}.alt_m"), m.alt_m, -100.0, 10_000.0)?;
            check_finite(&format!("{key}.size_m"), m.size_m, 0.1, 1000.0)?;
            check_finite(
                &format!("{key}.heat_release_w"),
                m.heat_release_w,
                1.0,
                1.0e12,
            )?;
            check_finite(&format!("{key}.start_s"), m.start_s, 0.0, 1.0e7)?;
            check_finite(&format!("{key}.duration_s"), m.duration_s, 0.1, 1.0e7)?;
        }
        if let Some(p) = &self.precipitation {
            if cig_environment::PrecipitationKind::parse(&p.kind).is_none() {
                return Err(value_error(
                    "precipitation.kind",
                    format!("\"{}\" is not rain, snow or sleet", p.kind),
                ));
            }
            check_finite(
                "precipitation.rate_mm_per_h",
                p.rate_mm_per_h,
                0.0,
                cig_environment::precipitation::MAX_RATE_MM_PER_H,
            )?;
        }
        if let Some(sea) = &self.sea {
            sea.check()?;
        }
        if let Some(l) = &self.lightning {
            check_lat_lon("lightning", l.lat_deg, l.lon_deg)?;
            check_finite("lightning.radius_m", l.radius_m, 0.0, 200_000.0)?;
            check_finite("lightning.cloud_base_m", l.cloud_base_m, 100.0, 10_000.0)?;
            check_finite(
                "lightning.strikes_per_minute",
                l.strikes_per_minute,
                0.0,
                crate::weather::MAX_STRIKES_PER_MINUTE,
            )?;
        }
        if let Some(v) = &self.view {
            match (v.entity, v.eye) {
                (Some(id), None) => {
                    if !ids.contains(&id) {
                        return Err(value_error(
                            "view.entity",
                            format!("{id} is not an entity of the scenario"),
                        ));
                    }
                }
                (None, Some(eye)) => {
                    check_lat_lon("view.eye", eye[0], eye[1])?;
                    check_finite("view.eye altitude", eye[2], -1000.0, 1.0e7)?;
                }
                _ => return Err(value_error("view", "needs exactly one of entity and eye")),
            }
            for (i, o) in v.offset_m.iter().enumerate() {
                check_finite(&format!("view.offset_m[{i}]"), *o, -1.0e6, 1.0e6)?;
            }
            for (i, a) in v.hpr_deg.iter().enumerate() {
                check_finite(&format!("view.hpr_deg[{i}]"), *a, -720.0, 720.0)?;
            }
            check_finite("view.fov_deg", v.fov_deg, 0.1, 179.0)?;
        }
        if let Some(d) = &self.dis {
            if d.version != 6 && d.version != 7 {
                return Err(value_error(
                    "dis.version",
                    format!("{} is not 6 or 7", d.version),
                ));
            }
            if d.port == 0 {
                return Err(value_error("dis.port", "must not be 0"));
            }
        }
        Ok(())
    }

    /// The start time, when the scenario gives one.
    pub fn start(&self) -> Option<UtcTime> {
        self.start_time
            .as_deref()
            .and_then(|t| UtcTime::parse_iso8601(t).ok())
    }

    /// The sky settings the scenario asks for (defaults without `[sky]`).
    pub fn sky_settings(&self) -> cig_scene::lighting::SkySettings {
        let mut settings = cig_scene::lighting::SkySettings::default();
        if let Some(sky) = &self.sky {
            settings.model = sky.model.as_deref().and_then(sky_model).unwrap_or_default();
            settings.exposure_compensation_ev = sky.exposure_compensation_ev;
            settings.fixed_exposure_ev = sky.fixed_exposure_ev;
        }
        settings
    }

    /// The fog mode, when the scenario gives one.
    pub fn fog_mode(&self) -> Option<FogMode> {
        self.fog.as_deref().and_then(FogMode::parse)
    }

    /// The goggle of the scenario's view, when its sensor is `nvg`.
    pub fn nvg_view(&self) -> Option<cig_scene::nvg::NvgView> {
        let view = self.view.as_ref()?;
        if view.sensor.as_deref() != Some("nvg") {
            return None;
        }
        let mut nvg = cig_scene::nvg::NvgView::default();
        if let Some(n) = &view.nvg {
            if let Some(g) = n.gain {
                nvg.gain = g;
            }
            if let Some(p) = n.phosphor.as_deref() {
                nvg.phosphor = cig_scene::nvg::Phosphor::from_name(p).unwrap_or(nvg.phosphor);
            }
        }
        Some(nvg)
    }

    /// The scenario's standing lamps (`[[light]]`), as checked.
    pub fn light_points(&self) -> Vec<cig_scene::lights::LightPoint> {
        self.lights
            .iter()
            .filter_map(|l| {
                let lamp = cig_scene::lights::named_lamp(&l.colour)?;
                let at = cig_geo::Geodetic::new(l.lat_deg, l.lon_deg, l.alt_m);
                cig_scene::lights::omni_lamp(at, l.candela as f32, lamp).ok()
            })
            .collect()
    }
}

/// Parses a sky model name.
fn sky_model(name: &str) -> Option<cig_scene::lighting::SkyModel> {
    match name.to_ascii_lowercase().as_str() {
        "physical" => Some(cig_scene::lighting::SkyModel::Physical),
        "flat" => Some(cig_scene::lighting::SkyModel::Flat),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const FULL: &str = r#"
name = "range"
start_time = "2026-06-21T09:30:00Z"
visibility_m = 15000
fog = "exp2"
[[models]]
model = "tank"
cigi_type = 1
dis_type = "1:1:225:1"
[[entities]]
id = 1
model = "tank"
dis_id = "1:3001:1"
dis_type = "1:1:225:1:1:0:0"
lat_deg = 51.0
lon_deg = -1.5
clamp = "height_and_attitude"
speed_mps = 5
path = [[51.001, -1.5]]
appearance = "0x8000"
[view]
entity = 1
offset_m = [-20, 0, -5]
[dis]
exercise = 3
delivery = "multicast:239.1.2.3"
"#;

    #[test]
    fn a_full_scenario_parses() {
        let s = Scenario::from_toml(FULL).expect("parses");
        assert_eq!(s.entities.len(), 1);
        assert_eq!(s.entities[0].clamp, Clamp::HeightAndAttitude);
        assert_eq!(s.dis.as_ref().map(|d| d.exercise), Some(3));
        assert_eq!(s.fog_mode(), Some(FogMode::ExponentialSquared));
        assert!(s.start().is_some());
    }

    #[test]
    fn the_sky_section_sets_the_exposure_and_refuses_bad_values() {
        let with_sky = FULL.replace(
            "fog = \"exp2\"\n",
            "fog = \"exp2\"\nsky = { model = \"flat\", exposure_compensation_ev = 1.5 }\n",
        );
        let s = Scenario::from_toml(&with_sky).expect("parses");
        let sky = s.sky_settings();
        assert_eq!(sky.model, cig_scene::lighting::SkyModel::Flat);
        assert_eq!(sky.exposure_compensation_ev, 1.5);
        assert_eq!(sky.fixed_exposure_ev, None);
        assert_eq!(
            Scenario::from_toml(FULL).expect("parses").sky_settings(),
            cig_scene::lighting::SkySettings::default()
        );
        for (text, key) in [
            (
                "sky = { exposure_compensation_ev = 40 }",
                "sky.exposure_compensation_ev",
            ),
            ("sky = { fixed_exposure_ev = nan }", "sky.fixed_exposure_ev"),
            ("sky = { model = \"cartoon\" }", "sky.model"),
        ] {
            let bad = FULL.replace("fog = \"exp2\"\n", &format!("fog = \"exp2\"\n{text}\n"));
            let e = Scenario::from_toml(&bad).expect_err("refused").to_string();
            assert!(e.starts_with(key), "{e}");
        }
    }

    #[test]
    fn nvg_views_lamps_flares_and_entity_lights_parse() {
        let text = FULL.replace(
            "appearance = \"0x8000\"\n",
            "appearance = \"0x8000\"\nlights = [\"head\", \"tail\", \"blackout\"]\n",
        ) + r#"
[[light]]
lat_deg = 51.01
lon_deg = -1.47
alt_m = 105.0
candela = 500.0
[[light]]
lat_deg = 51.02
lon_deg = -1.47
candela = 20.0
colour = "red"
[[flare]]
lat_deg = 51.01
lon_deg = -1.46
alt_m = 700.0
at_s = 30.0
kind = "81mm"
"#;
        let text = text.replace(
            "offset_m = [-20, 0, -5]\n",
            "offset_m = [-20, 0, -5]\nsensor = \"nvg\"\n[view.nvg]\ngain = 2.5\nphosphor = \"white\"\n",
        );
        let s = Scenario::from_toml(&text).expect("parses");
        let nvg = s.nvg_view().expect("an NVG view");
        assert_eq!(nvg.gain, 2.5);
        assert_eq!(nvg.phosphor, cig_scene::nvg::Phosphor::White);
        let lamps = s.light_points();
        assert_eq!(lamps.len(), 2);
        assert_eq!(lamps[0].intensity_cd, 500.0);
        assert_eq!(
            Some(lamps[0].spectrum),
            cig_scene::lights::named_lamp("warm").map(|l| l.1)
        );
        let flare = s.flares[0].flare(1000.0).expect("a flare");
        assert_eq!(flare.ignition_unix_s, 1030.0);
        assert_eq!(flare.burn_s, 60.0);
        assert!(flare.light_at(1029.0, None).is_none());
        assert!(flare.light_at(1031.0, None).is_some());
        let sw = crate::lights::switches_of_names(&s.entities[0].lights);
        assert!(sw.head && sw.tail && sw.blackout && !sw.brake);
        // Without the goggle's sensor there is no NVG view; without [view.nvg], defaults.
        assert_eq!(Scenario::from_toml(FULL).expect("parses").nvg_view(), None);
        let plain = FULL.replace(
            "offset_m = [-20, 0, -5]\n",
            "offset_m = [-20, 0, -5]\nsensor = \"nvg\"\n",
        );
        let nvg = Scenario::from_toml(&plain).expect("parses").nvg_view();
        assert_eq!(nvg, Some(cig_scene::nvg::NvgView::default()));
    }

    #[test]
    fn bad_nvg_lamp_flare_and_light_values_name_their_key() {
        let view = |extra: &str| {
            FULL.replace(
                "offset_m = [-20, 0, -5]\n",
                &format!("offset_m = [-20, 0, -5]\n{extra}\n"),
            )
        };
        let light = |body: &str| format!("{FULL}\n[[light]]\n{body}\n");
        let flare = |body: &str| format!("{FULL}\n[[flare]]\n{body}\n");
        let cases = [
            (view("sensor = \"uv\""), "view.sensor"),
            (view("[view.nvg]\ngain = 50.0"), "view.nvg.gain"),
            (view("[view.nvg]\ngain = nan"), "view.nvg.gain"),
            (view("[view.nvg]\nphosphor = \"p99\""), "view.nvg.phosphor"),
            (
                light("lat_deg = 51.0\nlon_deg = -1.5\ncandela = 0.0"),
                "light[0].candela",
            ),
            (
                light("lat_deg = 51.0\nlon_deg = -1.5\ncandela = inf"),
                "light[0].candela",
            ),
            (
                light("lat_deg = 51.0\nlon_deg = -1.5\ncandela = 5.0\ncolour = \"pink\""),
                "light[0].colour",
            ),
            (
                light("lat_deg = 99.0\nlon_deg = -1.5\ncandela = 5.0"),
                "light[0].lat_deg",
            ),
            (
                light("lat_deg = 51.0\nlon_deg = -1.5\nalt_m = nan\ncandela = 5.0"),
                "light[0].alt_m",
            ),
            (
                flare("lat_deg = 51.0\nlon_deg = -1.5\nalt_m = 600.0\nkind = \"60mm\""),
                "flare[0].kind",
            ),
            (
                flare(
                    "lat_deg = 51.0\nlon_deg = -1.5\nalt_m = 600.0\nat_s = -1.0\nkind = \"155mm\"",
                ),
                "flare[0].at_s",
            ),
            (
                FULL.replace(
                    "appearance = \"0x8000\"\n",
                    "appearance = \"0x8000\"\nlights = [\"head\", \"headlights\"]\n",
                ),
                "entities[0].lights[1]",
            ),
        ];
        for (text, key) in cases {
            let e = Scenario::from_toml(&text).expect_err(key).to_string();
            assert!(e.starts_with(key), "{key}: {e}");
            assert!(!e.contains('\n'), "{e}");
        }
        let e = Scenario::from_toml(&view("sensor = \"uv\""))
            .expect_err("uv")
            .to_string();
        assert!(e.contains("nvg"), "{e}");
    }

    #[test]
    fn errors_name_the_key() {
        let bad = FULL.replace("lat_deg = 51.0", "lat_deg = 95.0");
        let e = Scenario::from_toml(&bad).expect_err("refused").to_string();
        assert_eq!(e, "entities[0].lat_deg: 95 is outside -90..90");
        let bad = FULL.replace("fog = \"exp2\"", "fgo = \"exp2\"");
        let e = Scenario::from_toml(&bad).expect_err("refused").to_string();
        assert!(
            e.contains("unknown field `fgo`") && e.contains("line"),
            "{e}"
        );
        assert!(!e.contains('\n'));
        let bad = FULL.replace("dis_id = \"1:3001:1\"", "dis_id = \"1:3001\"");
        assert!(Scenario::from_toml(&bad).is_err());
        let bad = FULL.replace("entity = 1\n", "entity = 9\n");
        let e = Scenario::from_toml(&bad).expect_err("refused").to_string();
        assert!(e.starts_with("view.entity"), "{e}");
    }

    #[test]
    fn weather_tables_parse_and_bad_values_name_their_key() {
        let text = format!(
            "{FULL}\n[precipitation]\nkind = \"snow\"\nrate_mm_per_h = 2.5\n\
             [lightning]\nlat_deg = 51.0\nlon_deg = -1.5\nstrikes_per_minute = 12\nseed = 9\n"
        );
        let s = Scenario::from_toml(&text).expect("parses");
        let p = s
            .precipitation
            .as_ref()
            .and_then(|p| p.precipitation())
            .expect("snow");
        assert_eq!(p.kind, cig_environment::PrecipitationKind::Snow);
        assert_eq!(p.rate_mm_per_h, 2.5);
        let storm = s.lightning.as_ref().and_then(|l| l.storm()).expect("storm");
        assert_eq!(
            (storm.seed, storm.strikes_per_minute, storm.radius_m),
            (9, 12.0, 10_000.0)
        );
        for (bad, key) in [
            (
                "rate_mm_per_h = 2.5",
                "precipitation.rate_mm_per_h: 500 is outside 0..200",
            ),
            (
                "kind = \"snow\"",
                "precipitation.kind: \"hail\" is not rain, snow or sleet",
            ),
            (
                "strikes_per_minute = 12",
                "lightning.strikes_per_minute: -1 is outside 0..600",
            ),
            (
                "lat_deg = 51.0\nlon_deg = -1.5\nstrikes",
                "lightning.lat_deg: 91 is outside -90..90",
            ),
        ] {
            let replaced = match key.split(':').next() {
                Some("precipitation.rate_mm_per_h") => text.replace(bad, "rate_mm_per_h = 500"),
                Some("precipitation.kind") => text.replace(bad, "kind = \"hail\""),
                Some("lightning.strikes_per_minute") => {
                    text.replace(bad, "strikes_per_minute = -1")
                }
                _ => text.replace(bad, "lat_deg = 91.0\nlon_deg = -1.5\nstrikes"),
            };
            let e = Scenario::from_toml(&replaced)
                .expect_err("refused")
                .to_string();
            assert_eq!(e, key);
        }
        let e = Scenario::from_toml(&format!("{text}\ncolour = 1\n")).expect_err("refused");
        assert!(e.to_string().contains("unknown field `colour`"), "{e}");
        let disabled = text.replace("seed = 9", "seed = 9\nenabled = false");
        let s = Scenario::from_toml(&disabled).expect("parses");
        assert!(s.lightning.and_then(|l| l.storm()).is_none());
    }

    #[test]
    fn dis_patterns_match_most_specific() {
        let t = EntityTypeCode {
            kind: 1,
            domain: 1,
            country: 225,
            category: 1,
            subcategory: 3,
            specific: 0,
            extra: 0,
        };
        let broad = DisTypePattern::parse("1:1:*").expect("pattern");
        let narrow = DisTypePattern::parse("1:1:225:1:3").expect("pattern");
        let other = DisTypePattern::parse("1:3").expect("pattern");
        assert_eq!(broad.specificity(&t), Some(2));
        assert_eq!(narrow.specificity(&t), Some(5));
        assert_eq!(other.specificity(&t), None);
        assert!(DisTypePattern::parse("1:300").is_none());
        assert!(DisTypePattern::parse("1:1:70000").is_none());
    }

    const CLOUDS: &str = r#"
[[clouds]]
base_m = 1200
thickness_m = 600
coverage = 0.5
kind = "stratocumulus"
wind_speed_mps = 8
wind_from_deg = 270
seed = 3

[[clouds]]
base_m = 7000
thickness_m = 300
coverage = 0.2
kind = "Cirrus"
"#;

    #[test]
    fn cloud_layers_parse() {
        use cig_environment::clouds::CloudKind;
        let s = Scenario::from_toml(CLOUDS).expect("parses");
        let layers = s.cloud_layers();
        assert_eq!(layers.len(), 2);
        assert_eq!(layers[0].kind, CloudKind::Stratocumulus);
        assert_eq!((layers[0].base_m, layers[0].thickness_m), (1200.0, 600.0));
        assert_eq!(
            (layers[0].wind_speed_mps, layers[0].wind_from_deg),
            (8.0, 270.0)
        );
        assert_eq!(layers[0].seed, 3);
        assert_eq!(layers[1].kind, CloudKind::Cirrus);
        assert_eq!((layers[1].wind_speed_mps, layers[1].seed), (0.0, 1));
        assert!(layers.iter().all(|l| l.validate().is_ok()));
    }

    #[test]
    fn bad_cloud_values_name_the_key() {
        let cases = [
            (
                "coverage = 0.5",
                "coverage = 1.5",
                "clouds[0].coverage: 1.5 is outside 0..1",
            ),
            (
                "thickness_m = 600",
                "thickness_m = 0",
                "clouds[0].thickness_m: 0 is not above 0",
            ),
            (
                "base_m = 7000",
                "base_m = 90000",
                "clouds[1].base_m: 90000 is outside -500..25000",
            ),
            (
                "kind = \"Cirrus\"",
                "kind = \"fog\"",
                "clouds[1].kind: \"fog\" is not a cloud type",
            ),
            (
                "wind_speed_mps = 8",
                "wind_speed_mps = -2",
                "clouds[0].wind_speed_mps: -2 is outside 0..150",
            ),
            (
                "wind_from_deg = 270",
                "wind_from_deg = nan",
                "clouds[0].wind_from_deg: NaN is outside -360..360",
            ),
        ];
        for (from, to, expected) in cases {
            let bad = CLOUDS.replace(from, to);
            let e = Scenario::from_toml(&bad).expect_err("refused").to_string();
            assert_eq!(e, expected);
        }
        let bad = CLOUDS.replace("seed = 3", "seed = 3\ncolour = 1");
        let e = Scenario::from_toml(&bad).expect_err("refused").to_string();
        assert!(
            e.contains("unknown field `colour`") && !e.contains('\n'),
            "{e}"
        );
        let five = CLOUDS.repeat(3);
        let e = Scenario::from_toml(&five).expect_err("refused").to_string();
        assert_eq!(e, "clouds: 6 layers; at most 4");
    }
}
