//! The IG side of a CIGI session: the host's messages applied to the IG's state, and each
//! frame's message back (Start of Frame, then the answers).
//!
//! Algorithm (CIGI ICD 3.3 §2.3 and §4, ICD 4.0 the same with Entity Position / Entity Control
//! / Velocity Control split): every IG frame the IG sends one message that opens with Start of
//! Frame (IG frame number, IG mode, database, 10 µs timestamp, and the host frame number of the
//! last IG Control it received, so the host can measure latency). It applies each host message
//! as it arrives, in packet order:
//!
//! - IG Control: mode (reset clears every entity but the ownship and every standing request),
//!   host frame number, database request (only the served database exists: any other number is
//!   answered with -128, "not available").
//! - Entity Control (3.3), Entity Position + Entity Control (4.0), Conformal Clamped Entity:
//!   entities are created when first named active, moved, attached to a parent (body-axis
//!   offsets), clamped to the terrain (non-conformal: altitude is an offset above the terrain;
//!   conformal: pitch and roll also follow the slope), hidden (inactive) and deleted
//!   (destroyed). The entity type picks the model through the scenario's table.
//! - Rate Control / Velocity Control: the IG moves the entity by these rates every frame
//!   between host updates (world or body axes, and yaw/pitch/roll rates).
//! - Articulated Part, Short Articulated Part, Component, Short Component, Animation Control:
//!   kept per entity and reported through Position Request (parts); the built-in models have no
//!   articulated parts to move.
//! - View Control and View Definition: views attach to entities with offsets and relative
//!   orientation, and take asymmetric frusta (left, right, bottom, top half-angles).
//! - Celestial Sphere: date and time of day set the simulation clock; the moon and star field
//!   switches and the star field intensity (clamped to 0..100 %, reported) reach the renderer.
//!   Atmosphere, Weather
//!   (global, regional and entity layers), Environmental Region, Maritime and Terrestrial
//!   Surface Conditions, Wave Control: kept; Maritime Surface Conditions and Wave Control drive
//!   the sea ([`crate::sea`]: its level, water and explicit waves); visibility and fog come
//!   from them, rain, snow,
//!   sleet and hail layers (4-7) give the precipitation over the eye (rate from the layer's
//!   aerosol concentration as liquid water content, else its severity; clamped to 200 mm/h
//!   and reported), and a layer's random lightning enable a storm around the eye.
//! - Sensor Control: sensor modes per view (on/off, polarity, gain, level, track mode).
//! - HAT/HOT, LOS Segment and Vector, Position and Environmental Conditions requests and
//!   Collision Detection Segment and Volume definitions: answered in the next frame's message
//!   (standing requests with an update period every that many frames), from the terrain
//!   database's query service, the surface the renderer draws at full detail. Over the sea
//!   (off the database, or its water posts at mean sea level) HAT/HOT and line of sight answer
//!   the wave surface at the frame's time (material water, the wave's normal), and a clamped
//!   entity there floats; collision segments and volumes test the terrain only (its sea posts
//!   at mean sea level, not the waves).
//! - User-defined packets: kept with the version and byte order of the message they came in
//!   (`take_user_packets`, [`UserPacket`]) and counted; the world's step takes them and
//!   carries out cig's Terrain Edit Requests (`crate::terrain_edits::TerrainEditRequest`,
//!   what came of them in [`IgSession::edit_requests`]); other user-defined packets are
//!   dropped.
//!
//! Line of sight also sees the obscurants: the smoke, flame and dust on the clear part of the
//! line are a translucent surface of alpha 255·(1 − T), T the Beer–Lambert transmittance
//! through the puffs (thesis 000 Eq 1-4), which stops the line when it reaches the request's
//! alpha threshold.
//!
//! Line of sight and collision segments also see the database's culture as its simple volumes
//! (`cig_terrain::culture_hit`): line of sight is stopped by every object but fences, collision
//! segments by every object. A hit on an object reports the material code
//! [`CULTURE_MATERIAL_CODE_BASE`] + the object's kind byte (`CultureKind`: 16 conifer ...
//! 24 power pole; terrain materials are 0-8), which a collision segment's material mask
//! selects like any other, and (extended LOS) the normal of the object's volume. HAT/HOT
//! answers the bare terrain (`QuerySession::hot_with_culture` is not wired to CIGI).
//!
//! Limits: line-of-sight and collision segments test the terrain and the culture's simple
//! volumes only (not entity geometry); collision volumes test other entities' volumes as
//! bounding spheres; sensor tracking is not simulated (a sensor in a track mode reports
//! "searching"); motion trackers and trajectory packets are not supported (the codec skips them
//! with a warning). Answers that do not fit one message (over [`MAX_PACKETS_PER_MESSAGE`]) wait
//! for the next frame.

use crate::model_table::{CigiEntityType, ModelTable};
use crate::pose::{
    azimuth_elevation_deg, child_pose, direction_enu, displaced, offset_enu, offset_of, point_from,
    relative, wrap_deg, BodyOffset, Pose,
};
use cig_cigi::{
    AerosolConcentrationResponse, AnimationControl, ArticulatedPart, AtmosphereControl, ByteOrder,
    CelestialSphereControl, CollisionSegmentDefinition, CollisionSegmentNotification,
    CollisionVolumeDefinition, CollisionVolumeNotification, EntityControl, EntityControl4,
    EntityPosition, EnvironmentalConditionsRequest, EnvironmentalRegionControl,
    HatHotExtendedResponse, HatHotRequest, HatHotResponse, IgControl, ImageGeneratorMessage,
    LosExtendedResponse, LosResponse, LosSegmentRequest, LosVectorRequest,
    MaritimeSurfaceConditionsControl, MaritimeSurfaceConditionsResponse, Message, Packet,
    PositionRequest, PositionResponse, RateControl, SensorControl, SensorExtendedResponse,
    SensorResponse, StartOfFrame, TerrestrialSurfaceConditionsControl,
    TerrestrialSurfaceConditionsResponse, UserDefined, Version, ViewControl, ViewDefinition,
    WaveControl, WeatherConditionsResponse, WeatherControl,
};
use cig_effects::EffectSystem;
use cig_environment::UtcTime;
use cig_geo::Geodetic;
use cig_scene::snapshot::Clamp;
use cig_scene::{FovDeg, Hpr};
use cig_terrain::{LosHit, QuerySession, SurfacePoint};
use glam::DVec3;
use std::collections::{BTreeMap, VecDeque};

/// At most this many packets (Start of Frame included) go in one IG message; a CIGI 3.3
/// response is at most 64 bytes, so a message stays under 60 kB.
pub const MAX_PACKETS_PER_MESSAGE: usize = 900;

/// How deep attachment chains may go (longer chains, or cycles, leave the entity unplaced).
pub const MAX_ATTACH_DEPTH: usize = 16;

/// At most this many entities the host may create.
pub const MAX_ENTITIES: usize = 65_536;

/// At most this many standing requests of each kind.
pub const MAX_STANDING_REQUESTS: usize = 4096;

/// At most this many answers wait for a later message; beyond, the oldest are dropped (counted).
pub const MAX_DEFERRED_ANSWERS: usize = 4 * MAX_PACKETS_PER_MESSAGE;

/// CIGI material code of a culture object: this plus its kind's byte (terrain materials use
/// their own bytes, 0-8).
pub const CULTURE_MATERIAL_CODE_BASE: u32 = 16;

/// The CIGI material code of what a line of sight or collision segment met.
pub fn hit_material_code(hit: &LosHit) -> u32 {
    match hit.culture {
        Some(c) => CULTURE_MATERIAL_CODE_BASE + u32::from(c.kind as u8),
        None => u32::from(hit.material.to_byte()),
    }
}

/// At most this many collision notifications a frame.
pub const MAX_COLLISION_NOTES: usize = 256;

/// At most this many collision volumes are tested against each other a frame.
pub const MAX_COLLISION_VOLUMES: usize = 1024;

/// Distinct problems remembered as told to the host.
const MAX_TOLD: usize = 1024;

/// An entity's life state.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EntityLife {
    /// Kept but not drawn.
    Inactive,
    /// Drawn.
    Active,
}

/// How an entity's position is given.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Placement {
    /// Latitude, longitude (degrees), altitude above MSL (or above the terrain when clamped).
    Geodetic {
        lat_deg: f64,
        lon_deg: f64,
        alt_m: f64,
    },
    /// Attached to a parent: body-axis offset and orientation relative to the parent.
    Attached { parent_id: u16, offset: BodyOffset },
}

/// Linear and angular rates the IG applies between host updates.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Rates {
    /// Linear rates, m/s: body axes (x forward, y right, z down) when `body_axes`, else world
    /// (x north, y east, z down).
    pub linear_mps: [f64; 3],
    /// Roll, pitch, yaw rates, degrees per second.
    pub angular_dps: [f64; 3],
    pub body_axes: bool,
}

impl Rates {
    /// The linear rates as a velocity in the local east, north, up frame, m/s, for an entity
    /// of this orientation (body axes turn with it; world axes are x north, y east, z down).
    pub fn velocity_enu_mps(&self, orientation: Hpr) -> DVec3 {
        let [x, y, z] = self.linear_mps;
        if self.body_axes {
            offset_enu(
                orientation,
                BodyOffset {
                    x_m: x,
                    y_m: y,
                    z_m: z,
                },
            )
        } else {
            DVec3::new(y, x, -z)
        }
    }
}

/// An articulated part's state.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PartState {
    pub enabled: bool,
    pub offset: BodyOffset,
    pub orientation: Hpr,
}

/// An entity of the session.
#[derive(Clone, Debug, PartialEq)]
pub struct IgEntity {
    pub id: u16,
    pub entity_type: CigiEntityType,
    pub model: String,
    pub life: EntityLife,
    pub placement: Placement,
    /// Orientation: local north-east-down (geodetic placement) or relative to the parent.
    pub orientation: Hpr,
    pub clamp: Clamp,
    pub rates: Option<Rates>,
    pub alpha: u8,
    pub collision_detection: bool,
    pub segments: BTreeMap<u8, CollisionSegmentDefinition>,
    pub volumes: BTreeMap<u8, CollisionVolumeDefinition>,
    pub parts: BTreeMap<u8, PartState>,
    pub animations: BTreeMap<u16, AnimationControl>,
    /// The host has never placed it (it came from the scenario and follows its script).
    pub scripted: bool,
    /// Lamps the host switched on (Component Control [`crate::lights::LIGHTS_COMPONENT`]);
    /// `None` until the host sets them (a scenario entity keeps its scenario's lamps).
    pub lights: Option<cig_scene::lights::LightSwitches>,
}

impl IgEntity {
    /// A new active entity at a geodetic place.
    pub fn new(id: u16, entity_type: CigiEntityType, model: String) -> IgEntity {
        IgEntity {
            id,
            entity_type,
            model,
            life: EntityLife::Active,
            placement: Placement::Geodetic {
                lat_deg: 0.0,
                lon_deg: 0.0,
                alt_m: 0.0,
            },
            orientation: Hpr::default(),
            clamp: Clamp::None,
            rates: None,
            alpha: 255,
            collision_detection: false,
            segments: BTreeMap::new(),
            volumes: BTreeMap::new(),
            parts: BTreeMap::new(),
            animations: BTreeMap::new(),
            scripted: false,
            lights: None,
        }
    }
}

/// A view of the session.
#[derive(Clone, Debug, PartialEq)]
pub struct IgView {
    pub id: u16,
    pub group_id: u8,
    pub entity_id: u16,
    pub offset: BodyOffset,
    pub orientation: Hpr,
    /// Frustum half-angles; `None` until a View Definition gives them.
    pub fov: Option<FovDeg>,
    /// Where the trainee looks within the view (a head or eye tracker's point of interest),
    /// degrees right and up of the view's centre, as the host last set it through Component
    /// Control ([`POINT_OF_INTEREST_COMPONENT`]); `None` is the view's centre.
    pub point_of_interest_deg: Option<[f64; 2]>,
    /// View Definition's view type (IG-defined; `crate::thermal::VIEW_TYPE_LWIR`, `..._MWIR`).
    pub view_type: u8,
}

/// Component Control of a view (component class 1, instance = the view's identifier) that
/// moves its area-of-interest point: component state 1 sets it to data words 0 and 1 (32-bit
/// floats: degrees right and up of the view's centre, within 90), state 0 puts it back at
/// the centre. Level of detail falls off with a model's angle from it (source 004, §3.4).
pub const POINT_OF_INTEREST_COMPONENT: u16 = 1;

/// Component class of a view in Component Control.
const COMPONENT_CLASS_VIEW: u8 = 1;

impl IgView {
    /// A view on an entity, with no offset, no relative orientation and no frustum yet.
    pub fn new(id: u16, group_id: u8, entity_id: u16) -> IgView {
        IgView {
            id,
            group_id,
            entity_id,
            offset: BodyOffset::default(),
            orientation: Hpr::default(),
            fov: None,
            point_of_interest_deg: None,
            view_type: 0,
        }
    }
}

/// What a sensor's tracker reports (CIGI Sensor Response and Sensor Extended Response).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct TrackReport {
    /// 0 searching, 1 tracking, 2 impending breaklock, 3 breaklock.
    pub status: u8,
    pub gate_px: [u16; 2],
    /// The gate's centre, degrees right and up of the view's centre.
    pub gate_deg: [f32; 2],
    /// The host's entity tracked, if the target is one.
    pub entity_id: Option<u16>,
    /// The track point (the entity's position), geodetic, altitude above the ellipsoid.
    pub point: Option<Geodetic>,
}

/// A sensor's selected mode.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SensorMode {
    pub view_id: u16,
    pub sensor_id: u8,
    pub on: bool,
    pub black_hot: bool,
    pub gain: f64,
    pub level: f64,
    pub noise: f64,
    pub track_mode: u8,
    pub extended_response: bool,
    pub automatic_gain: bool,
    pub line_dropout: bool,
    /// AC coupling time constant, microseconds (0 and more).
    pub ac_coupling_us: f64,
    pub track_black: bool,
}

/// The weather and surface state the host has set.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct EnvironmentState {
    pub atmosphere: Option<AtmosphereControl>,
    pub celestial: Option<CelestialSphereControl>,
    /// Weather layers by (scope, entity or region, layer).
    pub weather: BTreeMap<(u8, u16, u8), WeatherControl>,
    pub regions: BTreeMap<u16, EnvironmentalRegionControl>,
    pub maritime: BTreeMap<(u8, u16), MaritimeSurfaceConditionsControl>,
    pub waves: BTreeMap<(u8, u16, u8), WaveControl>,
    pub terrestrial: BTreeMap<(u8, u16, u16), TerrestrialSurfaceConditionsControl>,
}

/// Weather scopes of CIGI's Weather Control.
const SCOPE_GLOBAL: u8 = 0;
const SCOPE_REGIONAL: u8 = 1;

/// Standard atmosphere at sea level, used where the host set none.
const DEFAULT_TEMPERATURE_C: f32 = 15.0;
const DEFAULT_PRESSURE_MBAR: f32 = 1013.25;

impl EnvironmentState {
    /// Whether a point lies in a region (its rounded rectangle, rotation included).
    fn region_contains(region: &EnvironmentalRegionControl, point: Geodetic) -> bool {
        // 0 inactive, 1 active, 2 destroyed.
        if region.region_state != 1 {
            return false;
        }
        let centre = Geodetic::new(region.latitude_deg, region.longitude_deg, point.alt_m);
        let enu = cig_geo::EnuFrame::new(centre).geodetic_to_enu(point);
        let (s, c) = f64::from(region.rotation_deg).to_radians().sin_cos();
        // Region X is along the rotated north axis' perpendicular (east at rotation 0).
        let x = enu.x * c - enu.y * s;
        let y = enu.x * s + enu.y * c;
        x.abs() <= f64::from(region.size_x_m) / 2.0 && y.abs() <= f64::from(region.size_y_m) / 2.0
    }

    /// The host's maritime surface conditions at a point: an active region's where the point
    /// lies in one, else the global ones (enabled only; entity-scoped ones are not positional).
    pub fn maritime_at(&self, point: Geodetic) -> Option<&MaritimeSurfaceConditionsControl> {
        self.maritime
            .iter()
            .find(|((scope, region), m)| {
                *scope == SCOPE_REGIONAL
                    && m.surface_conditions_enable
                    && self
                        .regions
                        .get(region)
                        .is_some_and(|r| Self::region_contains(r, point))
            })
            .map(|(_, m)| m)
            .or_else(|| {
                self.maritime
                    .get(&(SCOPE_GLOBAL, 0))
                    .filter(|m| m.surface_conditions_enable)
            })
    }

    /// The weather layers that apply at a point: regional ones where the point is inside an
    /// active region, else global ones (entity-scoped layers are not positional).
    fn layers_at(&self, point: Geodetic) -> Vec<&WeatherControl> {
        let regional: Vec<&WeatherControl> = self
            .weather
            .iter()
            .filter(|((scope, region, _), w)| {
                *scope == SCOPE_REGIONAL
                    && w.weather_enable
                    && self
                        .regions
                        .get(region)
                        .is_some_and(|r| Self::region_contains(r, point))
            })
            .map(|(_, w)| w)
            .collect();
        if !regional.is_empty() {
            return regional;
        }
        self.weather
            .iter()
            .filter(|((scope, _, _), w)| *scope == SCOPE_GLOBAL && w.weather_enable)
            .map(|(_, w)| w)
            .collect()
    }

    /// Visibility at a point (altitude above MSL): the global atmosphere's, reduced inside any
    /// weather layer containing the point (ground fog, clouds) and below precipitation layers'
    /// tops (rain, snow, sleet, hail, sand, dust: layers 4-9).
    pub fn visibility_at_m(&self, point: Geodetic, default_m: f64) -> f64 {
        self.visibility_with(point, default_m, true)
    }

    /// The host's enabled cloud layers (CIGI weather layers 1-3) over a point (regional ones
    /// inside an active region, else global ones), by layer id.
    pub fn cloud_layers_at(&self, point: Geodetic) -> Vec<WeatherControl> {
        let mut layers: Vec<WeatherControl> = self
            .layers_at(point)
            .into_iter()
            .filter(|l| (1..=3).contains(&l.layer_id))
            .cloned()
            .collect();
        layers.sort_by_key(|l| l.layer_id);
        layers
    }

    /// The ground fog layer (CIGI weather layer 0) over a point: its top above MSL and the
    /// visibility inside it.
    pub fn ground_fog_at(&self, point: Geodetic) -> Option<(f64, f64)> {
        self.layers_at(point)
            .into_iter()
            .filter(|l| l.layer_id == 0)
            .map(|l| {
                (
                    f64::from(l.base_elevation_m) + f64::from(l.thickness_m),
                    f64::from(l.visibility_range_m),
                )
            })
            .find(|(top, v)| top.is_finite() && v.is_finite() && *v > 0.0)
    }

    /// The visibility the whole view has: as [`Self::visibility_at_m`] but without the ground
    /// fog layer, which the renderer draws as a layer.
    pub fn visibility_above_ground_fog_m(&self, point: Geodetic, default_m: f64) -> f64 {
        self.visibility_with(point, default_m, false)
    }

    fn visibility_with(&self, point: Geodetic, default_m: f64, ground_fog: bool) -> f64 {
        let mut visibility = self
            .atmosphere
            .as_ref()
            .map(|a| f64::from(a.visibility_range_m))
            .filter(|v| v.is_finite() && *v > 0.0)
            .unwrap_or(default_m);
        for layer in self.layers_at(point) {
            if layer.layer_id == 0 && !ground_fog {
                continue;
            }
            let base = f64::from(layer.base_elevation_m);
            let top = base + f64::from(layer.thickness_m);
            let inside = match layer.layer_id {
                0..=3 => point.alt_m >= base && point.alt_m <= top,
                _ => point.alt_m <= top,
            };
            let v = f64::from(layer.visibility_range_m);
            if inside && v.is_finite() && v > 0.0 {
                visibility = visibility.min(v);
            }
        }
        visibility
    }

    /// The host's precipitation layer (rain 4, snow 5, sleet 6, hail 7) over a point (altitude
    /// above MSL, below the layer's top), with its rate in mm/h and a note when the rate had to
    /// be clamped. CIGI gives no rate: it is the one whose liquid water content is the layer's
    /// aerosol concentration (g/m³, Marshall-Palmer / Gunn-Marshall), else this project's
    /// reading of the severity 0-5 (rain 1, 2.5, 5, 10, 25, 50 mm/h; snow a tenth of that in
    /// water). Hail is drawn as sleet.
    fn precipitation_layer_at(
        &self,
        point: Geodetic,
    ) -> Option<(
        &WeatherControl,
        cig_environment::Precipitation,
        Option<String>,
    )> {
        use cig_environment::{Precipitation, PrecipitationKind};
        let layer = self.layers_at(point).into_iter().find(|l| {
            (4..=7).contains(&l.layer_id) && {
                let top = f64::from(l.base_elevation_m) + f64::from(l.thickness_m);
                !top.is_finite() || point.alt_m <= top
            }
        })?;
        let kind = match layer.layer_id {
            4 => PrecipitationKind::Rain,
            5 => PrecipitationKind::Snow,
            _ => PrecipitationKind::Sleet,
        };
        let concentration = f64::from(layer.aerosol_concentration_gpm3);
        let severity = usize::from(layer.severity.min(5));
        let rain_by_severity = [1.0, 2.5, 5.0, 10.0, 25.0, 50.0];
        let (rate, source) = if concentration.is_finite() && concentration > 0.0 {
            (
                Precipitation::rate_for_water_content(kind, concentration),
                format!("aerosol concentration {concentration} g/m³"),
            )
        } else {
            let r = rain_by_severity.get(severity).copied().unwrap_or(10.0);
            (
                if kind == PrecipitationKind::Snow {
                    r / 10.0
                } else {
                    r
                },
                format!("severity {}", layer.severity),
            )
        };
        let p = Precipitation::clamped(kind, rate);
        let note = (p.rate_mm_per_h != rate || layer.severity > 5).then(|| {
            format!(
                "Weather Control layer {}: {} rate {rate:.0} mm/h from {source} clamped to {} mm/h",
                layer.layer_id,
                kind.name(),
                p.rate_mm_per_h
            )
        });
        Some((layer, p, note))
    }

    /// The host's random lightning over a point (CIGI Weather Control's random lightning
    /// enable on a layer that applies there): strikes per minute from the layer's severity
    /// 0-5 (1, 2, 4, 8, 15, 30: this project's reading; the ICD leaves it to the IG) and the
    /// layer's id.
    pub fn random_lightning_at(&self, point: Geodetic) -> Option<(f64, u8)> {
        const RATES: [f64; 6] = [1.0, 2.0, 4.0, 8.0, 15.0, 30.0];
        self.layers_at(point)
            .into_iter()
            .find(|l| l.random_lightning_enable)
            .map(|l| {
                let rate = RATES
                    .get(usize::from(l.severity.min(5)))
                    .copied()
                    .unwrap_or(4.0);
                (rate, l.layer_id)
            })
    }

    /// The host's rain, snow or sleet over a point (altitude above MSL), if any.
    pub fn precipitation_at(&self, point: Geodetic) -> Option<cig_environment::Precipitation> {
        self.precipitation_layer_at(point).map(|(_, p, _)| p)
    }

    /// Whether the host's precipitation layer over a point states its own visibility (which
    /// then applies instead of the one its rate gives).
    pub fn precipitation_sets_visibility(&self, point: Geodetic) -> bool {
        self.precipitation_layer_at(point).is_some_and(|(l, _, _)| {
            let v = f64::from(l.visibility_range_m);
            v.is_finite() && v > 0.0
        })
    }

    /// Why a host precipitation layer's rate was clamped, for any enabled layer.
    pub fn precipitation_clamped(&self) -> Option<String> {
        self.weather
            .values()
            .filter(|w| w.weather_enable && (4..=7).contains(&w.layer_id))
            .find_map(|w| {
                let probe = Geodetic::new(0.0, 0.0, f64::NEG_INFINITY);
                let single = EnvironmentState {
                    weather: [((SCOPE_GLOBAL, 0, w.layer_id), w.clone())]
                        .into_iter()
                        .collect(),
                    ..EnvironmentState::default()
                };
                single
                    .precipitation_layer_at(probe)
                    .and_then(|(_, _, note)| note)
            })
    }

    fn weather_response(
        &self,
        request_id: u8,
        point: Geodetic,
        default_vis_m: f64,
    ) -> WeatherConditionsResponse {
        let a = self.atmosphere.clone().unwrap_or(AtmosphereControl {
            humidity_pct: 50,
            air_temperature_c: DEFAULT_TEMPERATURE_C,
            visibility_range_m: default_vis_m as f32,
            barometric_pressure_mbar: DEFAULT_PRESSURE_MBAR,
            ..AtmosphereControl::default()
        });
        let mut response = WeatherConditionsResponse {
            request_id,
            humidity_pct: a.humidity_pct,
            air_temperature_c: a.air_temperature_c,
            visibility_range_m: self.visibility_at_m(point, default_vis_m) as f32,
            horizontal_wind_speed_mps: a.horizontal_wind_speed_mps,
            vertical_wind_speed_mps: a.vertical_wind_speed_mps,
            wind_direction_deg: a.wind_direction_deg,
            barometric_pressure_mbar: a.barometric_pressure_mbar,
        };
        // A layer containing the point overrides the air it holds.
        for layer in self.layers_at(point) {
            let base = f64::from(layer.base_elevation_m);
            if point.alt_m >= base && point.alt_m <= base + f64::from(layer.thickness_m) {
                response.humidity_pct = layer.humidity_pct;
                response.air_temperature_c = layer.air_temperature_c;
                response.horizontal_wind_speed_mps = layer.horizontal_wind_speed_mps;
                response.vertical_wind_speed_mps = layer.vertical_wind_speed_mps;
                response.wind_direction_deg = layer.wind_direction_deg;
                response.barometric_pressure_mbar = layer.barometric_pressure_mbar;
            }
        }
        response
    }
}

/// A request waiting for its answer (standing ones carry their period).
#[derive(Clone, Debug)]
struct Pending<T> {
    request: T,
    /// Frames until the next answer (0: this frame).
    countdown: u8,
}

/// Counters of what the session has done.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SessionCounters {
    pub messages_applied: u64,
    /// IG Control packets applied: host frames.
    pub host_frames: u64,
    pub packets_applied: u64,
    pub packets_ignored: u64,
    pub hat_hot_answered: u64,
    pub los_answered: u64,
    pub position_answered: u64,
    pub environment_answered: u64,
    pub collisions_reported: u64,
    pub answers_deferred: u64,
    pub answers_dropped: u64,
    pub los_obscured: u64,
    /// User-defined packets received (cig's Terrain Edit Requests among them).
    pub user_defined_packets: u64,
}

/// A user-defined packet as the host sent it: its fields are in the byte order of its
/// message, which the codec cannot read for it.
#[derive(Clone, Debug, PartialEq)]
pub struct UserPacket {
    pub packet: UserDefined,
    pub version: Version,
    pub byte_order: ByteOrder,
}

/// One line-of-sight request to answer.
struct LosJob {
    los_id: u16,
    extended: bool,
    entity_relative: bool,
    entity_id: u16,
    lsn: u8,
    segment: Option<(Geodetic, Geodetic)>,
    range_offset_m: f64,
    alpha_threshold: u8,
}

/// Configuration of a session.
#[derive(Clone, Debug, PartialEq)]
pub struct SessionConfig {
    /// The database number the IG reports (the one it serves).
    pub database_number: i8,
    /// Visibility where the host sets none, metres.
    pub default_visibility_m: f64,
    /// Whether this IG answers the host (a multi-channel IG's master does; its slaves keep
    /// the host's state to draw it but answer nothing: no HAT/HOT, LOS, position, environment,
    /// collision or sensor answers and no IG messages, only the Start of Frame they never send).
    pub answers_host: bool,
}

impl Default for SessionConfig {
    fn default() -> Self {
        SessionConfig {
            database_number: 1,
            default_visibility_m: 40_000.0,
            answers_host: true,
        }
    }
}

/// A time of day the host set (Celestial Sphere Control), as a channel needs it to agree with
/// the others: the host's clock of the message that told it (a channel that read several host
/// frames at once carries it forward to the frame it steps to) and how finely it was told
/// (CIGI 3.3 has no seconds field: a host restating the time every second must not pull the
/// clock back to the start of the minute).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HostTimeSet {
    /// The time told; in CIGI 3.3 the start of its minute.
    pub time: UtcTime,
    /// The span the true time lies in from `time`: 60 s in CIGI 3.3, 0 in 4.0.
    pub resolution_s: f64,
    /// The host's clock ([`IgSession::host_clock_s`]) of the message that told it.
    pub told_at_host_s: Option<f64>,
}

impl HostTimeSet {
    /// The time to set the clock to, or `None` when the clock (`clock_unix_s`) already agrees
    /// with what the host told within its resolution and `tolerance_s`. `stepped_to_host_s` is
    /// the host clock the world is stepped to, `rate` the simulation clock's rate. Inside a
    /// minute told by CIGI 3.3 the seconds are taken from the host's clock (its seconds modulo
    /// the minute), so channels that join at different times pick the same instant.
    pub fn time_to_take(
        &self,
        clock_unix_s: f64,
        stepped_to_host_s: Option<f64>,
        rate: f64,
        tolerance_s: f64,
    ) -> Option<UtcTime> {
        let carried_s = match (stepped_to_host_s, self.told_at_host_s) {
            (Some(now_s), Some(at_s)) if now_s > at_s => (now_s - at_s) * rate,
            _ => 0.0,
        };
        let start = self.time.plus_seconds(carried_s);
        let behind_s = clock_unix_s - start.unix_seconds();
        if (-tolerance_s..self.resolution_s + tolerance_s).contains(&behind_s)
            && (self.resolution_s > 0.0 || behind_s <= tolerance_s)
        {
            return None;
        }
        let within_s = match self.told_at_host_s {
            Some(at_s) if self.resolution_s > 0.0 && (at_s * rate).is_finite() => {
                (at_s * rate).rem_euclid(self.resolution_s)
            }
            _ => 0.0,
        };
        Some(start.plus_seconds(within_s))
    }
}

/// The IG's CIGI state.
pub struct IgSession {
    config: SessionConfig,
    models: ModelTable,
    entities: BTreeMap<u16, IgEntity>,
    views: BTreeMap<u16, IgView>,
    sensors: BTreeMap<(u16, u8), SensorMode>,
    /// What each sensor's tracker reported last.
    tracks: BTreeMap<(u16, u8), TrackReport>,
    /// Sensors whose out-of-range values the host has been told about.
    sensors_clamped: std::collections::BTreeSet<(u16, u8)>,
    environment: EnvironmentState,
    hat_hot: BTreeMap<u16, Pending<HatHotRequest>>,
    los_segment: BTreeMap<u16, Pending<LosSegmentRequest>>,
    los_vector: BTreeMap<u16, Pending<LosVectorRequest>>,
    position: BTreeMap<(u8, u16, u8), Pending<PositionRequest>>,
    environment_requests: Vec<EnvironmentalConditionsRequest>,
    deferred: VecDeque<Packet>,
    ig_messages: VecDeque<String>,
    /// Problems already told to the host (each is told once).
    told: std::collections::BTreeSet<String>,
    /// The scenario's entities, restored after a reset.
    initial_entities: Vec<IgEntity>,
    user_packets: Vec<UserPacket>,
    /// What came of the host's Terrain Edit Requests.
    edit_requests: crate::terrain_edits::HostEditRequests,
    /// Host version and byte order, from the last message.
    host_format: Option<(Version, ByteOrder)>,
    ig_mode: u8,
    ig_frame_number: u32,
    last_host_frame_number: u32,
    /// The host's clock from its IG Control timestamps, unwrapped: (last ticks, seconds).
    host_clock: Option<(u32, f64)>,
    requested_database: i8,
    time_set: Option<HostTimeSet>,
    poses: BTreeMap<u16, Pose>,
    counters: SessionCounters,
    /// The sea at the frame's time (set by the world each frame), and the scenario's water.
    sea: Option<std::sync::Arc<crate::sea::SeaNow>>,
    scenario_water: crate::sea::Water,
    /// The velocity (east, north, m/s) each ship made good, as the world last measured it.
    ship_velocities: BTreeMap<u16, [f64; 2]>,
}

fn geodetic_msl(lat_deg: f64, lon_deg: f64, alt_msl_m: f64, query: &QuerySession) -> Geodetic {
    Geodetic::new(
        lat_deg,
        lon_deg,
        alt_msl_m + query.geoid_undulation_m(lat_deg, lon_deg),
    )
}

fn msl_altitude(point: Geodetic, query: &QuerySession) -> f64 {
    point.alt_m - query.geoid_undulation_m(point.lat_deg, point.lon_deg)
}

fn finite3(a: f64, b: f64, c: f64) -> bool {
    a.is_finite() && b.is_finite() && c.is_finite()
}

fn hpr_f32(yaw: f32, pitch: f32, roll: f32) -> Option<Hpr> {
    let h = Hpr {
        heading_deg: f64::from(yaw),
        pitch_deg: f64::from(pitch),
        roll_deg: f64::from(roll),
    };
    finite3(h.heading_deg, h.pitch_deg, h.roll_deg).then_some(h)
}

/// Azimuth and elevation of a surface normal, degrees.
fn normal_az_el(surface: &SurfacePoint) -> (f32, f32) {
    let [e, n, u] = surface.normal_enu;
    let (az, el) = azimuth_elevation_deg(DVec3::new(e, n, u));
    (az as f32, el as f32)
}

impl IgSession {
    pub fn new(config: SessionConfig, models: ModelTable) -> IgSession {
        IgSession {
            requested_database: config.database_number,
            config,
            models,
            entities: BTreeMap::new(),
            views: BTreeMap::new(),
            sensors: BTreeMap::new(),
            sensors_clamped: std::collections::BTreeSet::new(),
            tracks: BTreeMap::new(),
            environment: EnvironmentState::default(),
            hat_hot: BTreeMap::new(),
            los_segment: BTreeMap::new(),
            los_vector: BTreeMap::new(),
            position: BTreeMap::new(),
            environment_requests: Vec::new(),
            deferred: VecDeque::new(),
            ig_messages: VecDeque::new(),
            told: std::collections::BTreeSet::new(),
            initial_entities: Vec::new(),
            user_packets: Vec::new(),
            edit_requests: crate::terrain_edits::HostEditRequests::default(),
            host_format: None,
            ig_mode: 1,
            ig_frame_number: 0,
            last_host_frame_number: 0,
            host_clock: None,
            time_set: None,
            poses: BTreeMap::new(),
            counters: SessionCounters::default(),
            sea: None,
            ship_velocities: BTreeMap::new(),
            scenario_water: crate::sea::Water::of_scenario(None),
        }
    }

    /// The sea at the frame's time (`None`: no sea), for the height answers and the clamping.
    pub fn set_sea(&mut self, sea: Option<std::sync::Arc<crate::sea::SeaNow>>) {
        self.sea = sea;
    }

    /// The velocity (east, north, m/s) each of this IG's ships made good (the others are taken
    /// at rest): their motion in the seaway depends on it (the encounter frequency).
    pub fn set_ship_velocities(&mut self, velocities: BTreeMap<u16, [f64; 2]>) {
        self.ship_velocities = velocities;
    }

    /// Sets one ship's velocity (east, north, m/s) before the poses are resolved: one the
    /// scenario's script or the host's rates give this frame.
    pub fn set_ship_velocity(&mut self, id: u16, velocity_enu_mps: [f64; 2]) {
        self.ship_velocities.insert(id, velocity_enu_mps);
    }

    /// The scenario's water, which the host's Maritime Surface Conditions override.
    pub fn set_scenario_water(&mut self, water: crate::sea::Water) {
        self.scenario_water = water;
    }

    /// The sea at the frame's time, if there is one.
    pub fn sea(&self) -> Option<&std::sync::Arc<crate::sea::SeaNow>> {
        self.sea.as_ref()
    }

    /// The water at a point (altitude above MSL): the host's region there, else its global
    /// conditions, else the scenario's.
    pub fn water_at(&self, point_msl: Geodetic) -> crate::sea::Water {
        self.scenario_water
            .with_host(self.environment.maritime_at(point_msl))
    }

    /// The surface under a point: the sea's waves where it is sea, else the terrain.
    ///
    /// # Errors
    /// The terrain query's, where the point is not sea.
    pub fn surface_hot(
        &self,
        query: &mut QuerySession,
        lat_deg: f64,
        lon_deg: f64,
    ) -> Result<SurfacePoint, cig_terrain::QueryError> {
        match &self.sea {
            Some(sea) => {
                let level = self
                    .water_at(Geodetic::new(lat_deg, lon_deg, 0.0))
                    .level_msl_m;
                sea.hot(query, lat_deg, lon_deg, level)
            }
            None => query.hot(lat_deg, lon_deg),
        }
    }

    /// The sea's level above MSL at a point where the session has a sea and the point is sea
    /// (off the database, or a water post at sea level: [`crate::sea::SeaNow::covers`]).
    pub fn sea_level_at(
        &self,
        query: &mut QuerySession,
        lat_deg: f64,
        lon_deg: f64,
    ) -> Option<f64> {
        self.sea.as_ref()?;
        let level = self
            .water_at(Geodetic::new(lat_deg, lon_deg, 0.0))
            .level_msl_m;
        crate::sea::SeaNow::covers(&query.hot(lat_deg, lon_deg), level).then_some(level)
    }

    pub fn models(&self) -> &ModelTable {
        &self.models
    }
    pub fn entities(&self) -> &BTreeMap<u16, IgEntity> {
        &self.entities
    }
    pub fn views(&self) -> &BTreeMap<u16, IgView> {
        &self.views
    }
    pub fn sensors(&self) -> &BTreeMap<(u16, u8), SensorMode> {
        &self.sensors
    }
    pub fn environment(&self) -> &EnvironmentState {
        &self.environment
    }
    pub fn counters(&self) -> SessionCounters {
        self.counters
    }
    pub fn ig_frame_number(&self) -> u32 {
        self.ig_frame_number
    }
    pub fn last_host_frame_number(&self) -> u32 {
        self.last_host_frame_number
    }
    /// The host's clock, seconds, from the valid timestamps of its IG Control packets,
    /// unwrapped across the 32-bit field's wrap (every 11.9 h) from the first one heard: an IG
    /// that starts after a wrap counts from there (channels started together agree).
    pub fn host_clock_s(&self) -> Option<f64> {
        self.host_clock.map(|(_, s)| s)
    }
    pub fn ig_mode(&self) -> u8 {
        self.ig_mode
    }
    /// The version and byte order of the host's last message.
    pub fn host_format(&self) -> Option<(Version, ByteOrder)> {
        self.host_format
    }
    /// Poses resolved by the last [`IgSession::resolve_poses`], altitudes above the ellipsoid.
    pub fn poses(&self) -> &BTreeMap<u16, Pose> {
        &self.poses
    }
    /// The 4 low bits of the last host frame number, as answers carry them.
    fn host_frame_lsn(&self) -> u8 {
        (self.last_host_frame_number & 0xF) as u8
    }

    /// A time the host set with Celestial Sphere Control since the last call.
    pub fn take_time_set(&mut self) -> Option<HostTimeSet> {
        self.time_set.take()
    }
    /// User-defined packets received since the last call (at most
    /// [`MAX_STANDING_REQUESTS`] wait), with their message's version and byte order.
    pub fn take_user_packets(&mut self) -> Vec<UserPacket> {
        std::mem::take(&mut self.user_packets)
    }
    /// What came of the host's Terrain Edit Requests.
    pub fn edit_requests(&self) -> &crate::terrain_edits::HostEditRequests {
        &self.edit_requests
    }
    pub fn edit_requests_mut(&mut self) -> &mut crate::terrain_edits::HostEditRequests {
        &mut self.edit_requests
    }
    /// Queues an IG Message for the host (deduplicated; at most 16 wait).
    /// A Component Control: a view's point of interest ([`POINT_OF_INTEREST_COMPONENT`]) and
    /// an entity's lamps ([`crate::lights::LIGHTS_COMPONENT`]) are the components defined;
    /// anything else is not applied.
    fn apply_component(
        &mut self,
        class: u8,
        instance: u16,
        component: u16,
        state: u8,
        data: [u32; 2],
    ) -> bool {
        if class == crate::lights::COMPONENT_CLASS_ENTITY
            && component == crate::lights::LIGHTS_COMPONENT
        {
            let mask = if state == 0 { 0 } else { data[0] };
            if mask >> crate::lights::SWITCH_NAMES.len() != 0 {
                self.tell_host(format!(
                    "Component Control: entity {instance}'s lights mask {mask:#x} has bits above {}; they are ignored",
                    crate::lights::SWITCH_NAMES.len() - 1
                ));
            }
            return match self.entities.get_mut(&instance) {
                Some(e) => {
                    e.lights = Some(crate::lights::switches_of_mask(mask));
                    true
                }
                None => false,
            };
        }
        if class != COMPONENT_CLASS_VIEW || component != POINT_OF_INTEREST_COMPONENT {
            return false;
        }
        let point = match state {
            0 => None,
            _ => {
                let (right, up) = (
                    f64::from(f32::from_bits(data[0])),
                    f64::from(f32::from_bits(data[1])),
                );
                if !(right.is_finite() && up.is_finite() && right.abs() <= 90.0 && up.abs() <= 90.0)
                {
                    self.tell_host(format!(
                        "Component Control: view {instance}'s point of interest ({right}, {up}) degrees must lie within 90 of its centre"
                    ));
                    return false;
                }
                Some([right, up])
            }
        };
        match self.views.get_mut(&instance) {
            Some(view) => {
                view.point_of_interest_deg = point;
                true
            }
            None => false,
        }
    }

    pub fn tell_host(&mut self, text: String) {
        if self.told.len() >= MAX_TOLD {
            // Forget old problems rather than grow: they may be told again.
            self.told.clear();
        }
        if self.ig_messages.len() < 16 && self.told.insert(text.clone()) {
            self.ig_messages.push_back(text);
        }
    }

    /// Adds or replaces an entity of the scenario; it comes back as it was after an IG reset.
    pub fn insert_entity(&mut self, entity: IgEntity) {
        self.initial_entities.retain(|e| e.id != entity.id);
        self.initial_entities.push(entity.clone());
        self.entities.insert(entity.id, entity);
    }

    /// Removes an entity and, as the ICD requires, every entity attached to it (transitively).
    fn destroy(&mut self, id: u16) -> bool {
        if self.entities.remove(&id).is_none() {
            return false;
        }
        let mut doomed = vec![id];
        while let Some(parent) = doomed.pop() {
            let children: Vec<u16> = self
                .entities
                .values()
                .filter(|e| matches!(e.placement, Placement::Attached { parent_id, .. } if parent_id == parent))
                .map(|e| e.id)
                .collect();
            for child in children {
                self.entities.remove(&child);
                doomed.push(child);
            }
        }
        true
    }

    /// Mutable access for the scenario's scripts (they move only entities still `scripted`).
    pub fn entity_mut(&mut self, id: u16) -> Option<&mut IgEntity> {
        self.entities.get_mut(&id)
    }

    /// Applies one host message.
    pub fn apply(&mut self, message: &Message) {
        self.host_format = Some((message.version, message.byte_order));
        self.counters.messages_applied += 1;
        for packet in &message.packets {
            if self.apply_packet(packet) {
                self.counters.packets_applied += 1;
            } else {
                self.counters.packets_ignored += 1;
            }
        }
    }

    fn entity_or_create(&mut self, id: u16, entity_type: CigiEntityType) -> Option<&mut IgEntity> {
        if !self.entities.contains_key(&id) {
            if self.entities.len() >= MAX_ENTITIES {
                return None;
            }
            let model = self.models.model_for_cigi(entity_type).to_string();
            self.entities
                .insert(id, IgEntity::new(id, entity_type, model));
        }
        let entity = self.entities.get_mut(&id)?;
        if entity.entity_type != entity_type {
            entity.entity_type = entity_type;
            entity.model = self.models.model_for_cigi(entity_type).to_string();
        }
        Some(entity)
    }

    fn reset(&mut self) {
        self.entities.retain(|id, _| *id == 0);
        for e in &self.initial_entities {
            self.entities.insert(e.id, e.clone());
        }
        self.told.clear();
        self.hat_hot.clear();
        self.los_segment.clear();
        self.los_vector.clear();
        self.position.clear();
        self.environment_requests.clear();
        self.deferred.clear();
    }

    /// Applies one packet; `false` when it was not applicable (counted as ignored).
    fn apply_packet(&mut self, packet: &Packet) -> bool {
        match packet {
            Packet::IgControl(c) => self.apply_ig_control(c),
            Packet::EntityControl(c) => self.apply_entity_control_3(c),
            Packet::EntityPosition(p) => self.apply_entity_position(p),
            Packet::EntityControl4(c) => self.apply_entity_control_4(c),
            Packet::ConformalClampedEntity(c) => {
                let Some(e) = self.entities.get_mut(&c.entity_id) else {
                    return false;
                };
                if !(c.latitude_deg.is_finite()
                    && c.longitude_deg.is_finite()
                    && c.yaw_deg.is_finite())
                {
                    return false;
                }
                let alt_m = match e.placement {
                    Placement::Geodetic { alt_m, .. } if e.clamp != Clamp::None => alt_m,
                    _ => 0.0,
                };
                e.placement = Placement::Geodetic {
                    lat_deg: c.latitude_deg,
                    lon_deg: c.longitude_deg,
                    alt_m,
                };
                e.orientation.heading_deg = f64::from(c.yaw_deg);
                e.clamp = Clamp::HeightAndAttitude;
                e.scripted = false;
                true
            }
            Packet::RateControl(r) => self.apply_rates(r),
            Packet::ArticulatedPart(p) => self.apply_part(p),
            Packet::ShortArticulatedPart(p) => {
                let Some(e) = self.entities.get_mut(&p.entity_id) else {
                    return false;
                };
                for (id, dof, enable, value) in [
                    (p.part_id_1, p.dof_select_1, p.part_enable_1, p.dof_1),
                    (p.part_id_2, p.dof_select_2, p.part_enable_2, p.dof_2),
                ] {
                    if dof == 0 || !value.is_finite() {
                        continue;
                    }
                    let part = e.parts.entry(id).or_default();
                    part.enabled = enable;
                    let v = f64::from(value);
                    match dof {
                        1 => part.offset.x_m = v,
                        2 => part.offset.y_m = v,
                        3 => part.offset.z_m = v,
                        4 => part.orientation.heading_deg = v,
                        5 => part.orientation.pitch_deg = v,
                        _ => part.orientation.roll_deg = v,
                    }
                }
                true
            }
            Packet::AnimationControl(a) => match self.entities.get_mut(&a.entity_id) {
                Some(e) => {
                    e.animations.insert(a.animation_id, a.clone());
                    true
                }
                None => false,
            },
            Packet::ComponentControl(c) => self.apply_component(
                c.component_class,
                c.instance_id,
                c.component_id,
                c.component_state,
                [c.data[0], c.data[1]],
            ),
            Packet::ShortComponentControl(c) => self.apply_component(
                c.component_class,
                c.instance_id,
                c.component_id,
                c.component_state,
                c.data,
            ),
            Packet::CelestialSphereControl(c) => {
                if c.date_time_valid {
                    let month = c.date_mmddyyyy / 1_000_000;
                    let day = (c.date_mmddyyyy / 10_000) % 100;
                    let year = (c.date_mmddyyyy % 10_000) as i32;
                    let seconds = if c.seconds.is_finite() {
                        f64::from(c.seconds).clamp(0.0, 59.999)
                    } else {
                        0.0
                    };
                    match UtcTime::from_calendar(
                        year,
                        month,
                        day,
                        u32::from(c.hour),
                        u32::from(c.minute),
                        seconds,
                    ) {
                        Ok(t) => {
                            self.time_set = Some(HostTimeSet {
                                time: t,
                                // CIGI 3.3's packet has no seconds: it tells the minute.
                                resolution_s: match self.host_format {
                                    Some((Version::V3_3, _)) => 60.0,
                                    _ => 0.0,
                                },
                                told_at_host_s: self.host_clock_s(),
                            });
                        }
                        Err(e) => {
                            self.tell_host(format!("Celestial Sphere Control: {e}"));
                            return false;
                        }
                    }
                }
                let mut c = c.clone();
                let pct = c.star_field_intensity_pct;
                if !(0.0..=100.0).contains(&pct) {
                    let clamped = if pct.is_nan() {
                        100.0
                    } else {
                        pct.clamp(0.0, 100.0)
                    };
                    self.tell_host(format!(
                        "Celestial Sphere Control: star field intensity {pct}% is outside [0, 100]; {clamped}% used"
                    ));
                    c.star_field_intensity_pct = clamped;
                }
                self.environment.celestial = Some(c);
                true
            }
            Packet::AtmosphereControl(a) => {
                self.environment.atmosphere = Some(a.clone());
                true
            }
            Packet::EnvironmentalRegionControl(r) => {
                if r.region_state == 2 {
                    self.environment.regions.remove(&r.region_id);
                } else {
                    self.environment.regions.insert(r.region_id, r.clone());
                }
                true
            }
            Packet::WeatherControl(w) => {
                self.environment
                    .weather
                    .insert((w.scope, w.entity_or_region_id, w.layer_id), w.clone());
                true
            }
            Packet::MaritimeSurfaceConditionsControl(m) => {
                self.environment
                    .maritime
                    .insert((m.scope, m.entity_or_region_id), m.clone());
                true
            }
            Packet::WaveControl(w) => {
                self.environment
                    .waves
                    .insert((w.scope, w.entity_or_region_id, w.wave_id), w.clone());
                true
            }
            Packet::TerrestrialSurfaceConditionsControl(t) => {
                self.environment.terrestrial.insert(
                    (t.scope, t.entity_or_region_id, t.surface_condition_id),
                    t.clone(),
                );
                true
            }
            Packet::ViewControl(v) => self.apply_view_control(v),
            Packet::ViewDefinition(d) => self.apply_view_definition(d),
            Packet::SensorControl(s) => self.apply_sensor(s),
            Packet::CollisionSegmentDefinition(s) => match self.entities.get_mut(&s.entity_id) {
                Some(e) => {
                    e.segments.insert(s.segment_id, s.clone());
                    true
                }
                None => false,
            },
            Packet::CollisionVolumeDefinition(v) => match self.entities.get_mut(&v.entity_id) {
                Some(e) => {
                    e.volumes.insert(v.volume_id, v.clone());
                    true
                }
                None => false,
            },
            Packet::HatHotRequest(r) => standing(&mut self.hat_hot, r.hat_hot_id, r.clone()),
            Packet::LosSegmentRequest(r) => standing(&mut self.los_segment, r.los_id, r.clone()),
            Packet::LosVectorRequest(r) => standing(&mut self.los_vector, r.los_id, r.clone()),
            Packet::PositionRequest(r) => {
                let key = (r.object_class, r.object_id, r.part_id);
                standing(&mut self.position, key, r.clone())
            }
            Packet::EnvironmentalConditionsRequest(r)
                if self.environment_requests.len() < MAX_STANDING_REQUESTS =>
            {
                self.environment_requests.push(r.clone());
                true
            }
            Packet::UserDefined(u) => {
                self.counters.user_defined_packets += 1;
                // Set by `apply` for the message this packet came in.
                let Some((version, byte_order)) = self.host_format else {
                    return false;
                };
                if self.user_packets.len() < MAX_STANDING_REQUESTS {
                    self.user_packets.push(UserPacket {
                        packet: u.clone(),
                        version,
                        byte_order,
                    });
                }
                true
            }
            // Packets an IG sends, not receives.
            _ => false,
        }
    }

    fn apply_ig_control(&mut self, c: &IgControl) -> bool {
        self.counters.host_frames += 1;
        if c.ig_mode == 0 && self.ig_mode != 0 {
            self.reset();
        }
        self.ig_mode = c.ig_mode;
        self.last_host_frame_number = c.host_frame_number;
        if c.timestamp_valid {
            let ticks = c.timestamp_10us;
            let seconds = match self.host_clock {
                // The signed difference: a host whose clock went back goes back.
                Some((last, s)) => s + f64::from(ticks.wrapping_sub(last) as i32) * 1e-5,
                None => f64::from(ticks) * 1e-5,
            };
            self.host_clock = Some((ticks, seconds));
        }
        if c.database_number != 0 {
            self.requested_database = c.database_number;
            if c.database_number != self.config.database_number {
                self.tell_host(format!(
                    "database {} is not available; this IG serves database {}",
                    c.database_number, self.config.database_number
                ));
            }
        }
        true
    }

    fn apply_entity_control_3(&mut self, c: &EntityControl) -> bool {
        if c.entity_state == 2 {
            return self.destroy(c.entity_id);
        }
        let values = [c.lat_deg_or_x_m, c.lon_deg_or_y_m, c.alt_m_or_z_m];
        let Some(orientation) =
            checked_orientation(c.attach, values, c.yaw_deg, c.pitch_deg, c.roll_deg)
        else {
            return false;
        };
        let Some(e) = self.entity_or_create(c.entity_id, CigiEntityType::Short(c.entity_type))
        else {
            return false;
        };
        set_state(e, c.entity_state, c.alpha, c.collision_detection_enable);
        set_placement(
            e,
            c.attach,
            c.parent_id,
            values,
            orientation,
            c.ground_ocean_clamp,
        );
        true
    }

    fn apply_entity_position(&mut self, p: &EntityPosition) -> bool {
        let values = [p.lat_deg_or_x_m, p.lon_deg_or_y_m, p.alt_m_or_z_m];
        let Some(orientation) =
            checked_orientation(p.attach, values, p.yaw_deg, p.pitch_deg, p.roll_deg)
        else {
            return false;
        };
        let entity_type = self
            .entities
            .get(&p.entity_id)
            .map_or(CigiEntityType::Short(0), |e| e.entity_type);
        let Some(e) = self.entity_or_create(p.entity_id, entity_type) else {
            return false;
        };
        set_placement(
            e,
            p.attach,
            p.parent_id,
            values,
            orientation,
            p.ground_ocean_clamp,
        );
        true
    }

    fn apply_entity_control_4(&mut self, c: &EntityControl4) -> bool {
        if c.entity_state == 2 {
            return self.destroy(c.entity_id);
        }
        let entity_type = if c.extended_entity_type {
            CigiEntityType::Dis(cig_dis::EntityTypeCode {
                kind: c.entity_kind,
                domain: c.entity_domain,
                country: c.entity_type_or_country,
                category: c.entity_category,
                subcategory: c.entity_subcategory,
                specific: c.entity_specific,
                extra: c.entity_extra,
            })
        } else {
            CigiEntityType::Short(c.entity_type_or_country)
        };
        let Some(e) = self.entity_or_create(c.entity_id, entity_type) else {
            return false;
        };
        set_state(e, c.entity_state, c.alpha, c.collision_detection_enable);
        true
    }

    fn apply_rates(&mut self, r: &RateControl) -> bool {
        let values = [
            r.x_rate_mps,
            r.y_rate_mps,
            r.z_rate_mps,
            r.roll_rate_dps,
            r.pitch_rate_dps,
            r.yaw_rate_dps,
        ];
        if values.iter().any(|v| !v.is_finite()) {
            return false;
        }
        let Some(e) = self.entities.get_mut(&r.entity_id) else {
            return false;
        };
        if r.apply_to_part {
            // Part rates: the parts have no geometry to move; keep the part enabled.
            e.parts.entry(r.part_id).or_default();
            return true;
        }
        let rates = Rates {
            linear_mps: [
                f64::from(r.x_rate_mps),
                f64::from(r.y_rate_mps),
                f64::from(r.z_rate_mps),
            ],
            angular_dps: [
                f64::from(r.roll_rate_dps),
                f64::from(r.pitch_rate_dps),
                f64::from(r.yaw_rate_dps),
            ],
            body_axes: r.coordinate_system_local,
        };
        e.rates = (rates
            != Rates {
                body_axes: rates.body_axes,
                ..Rates::default()
            })
        .then_some(rates);
        true
    }

    fn apply_part(&mut self, p: &ArticulatedPart) -> bool {
        let Some(e) = self.entities.get_mut(&p.entity_id) else {
            return false;
        };
        let part = e.parts.entry(p.part_id).or_default();
        part.enabled = p.part_enable;
        set_enabled(
            &mut part.offset,
            &mut part.orientation,
            [
                (p.x_offset_enable, p.x_offset_m),
                (p.y_offset_enable, p.y_offset_m),
                (p.z_offset_enable, p.z_offset_m),
                (p.roll_enable, p.roll_deg),
                (p.pitch_enable, p.pitch_deg),
                (p.yaw_enable, p.yaw_deg),
            ],
        );
        true
    }

    /// View Control: to the view named, or, with a non-zero group, to every view of that group
    /// (group membership comes from View Definition; ICD 3.3 §4.1.16).
    fn apply_view_control(&mut self, v: &ViewControl) -> bool {
        let targets: Vec<u16> = if v.group_id != 0 {
            self.views
                .values()
                .filter(|view| view.group_id == v.group_id)
                .map(|view| view.id)
                .collect()
        } else {
            vec![v.view_id]
        };
        if targets.is_empty() {
            return false;
        }
        for id in targets {
            let view = self
                .views
                .entry(id)
                .or_insert_with(|| IgView::new(id, 0, v.entity_id));
            view.entity_id = v.entity_id;
            set_enabled(
                &mut view.offset,
                &mut view.orientation,
                [
                    (v.x_offset_enable, v.x_offset_m),
                    (v.y_offset_enable, v.y_offset_m),
                    (v.z_offset_enable, v.z_offset_m),
                    (v.roll_enable, v.roll_deg),
                    (v.pitch_enable, v.pitch_deg),
                    (v.yaw_enable, v.yaw_deg),
                ],
            );
        }
        true
    }

    fn apply_view_definition(&mut self, d: &ViewDefinition) -> bool {
        let view = self
            .views
            .entry(d.view_id)
            .or_insert_with(|| IgView::new(d.view_id, d.group_id, 0));
        view.group_id = d.group_id;
        view.view_type = d.view_type;
        let mut fov = view.fov.unwrap_or(FovDeg::symmetric(60.0, 45.0));
        let set = |enable: bool, value: f32, slot: &mut f64| {
            if enable && value.is_finite() {
                *slot = f64::from(value).abs();
            }
        };
        set(d.left_enable, d.left_deg, &mut fov.left_deg);
        set(d.right_enable, d.right_deg, &mut fov.right_deg);
        set(d.bottom_enable, d.bottom_deg, &mut fov.down_deg);
        set(d.top_enable, d.top_deg, &mut fov.up_deg);
        let ok = [fov.left_deg, fov.right_deg, fov.down_deg, fov.up_deg]
            .iter()
            .all(|a| *a < 89.9)
            && fov.left_deg + fov.right_deg > 0.01
            && fov.down_deg + fov.up_deg > 0.01;
        if ok {
            view.fov = Some(fov);
            true
        } else {
            let id = d.view_id;
            self.tell_host(format!(
                "View Definition {id}: the frustum is empty or too wide"
            ));
            false
        }
    }

    fn apply_sensor(&mut self, s: &SensorControl) -> bool {
        let finite = [s.gain, s.level, s.noise, s.ac_coupling_us]
            .iter()
            .all(|v| v.is_finite());
        if !finite {
            return false;
        }
        // Values outside their ranges are clamped, and the host told once per sensor.
        let outside = [s.gain, s.level, s.noise]
            .iter()
            .any(|v| !(0.0..=1.0).contains(v))
            || s.ac_coupling_us < 0.0;
        if outside && self.sensors_clamped.insert((s.view_id, s.sensor_id)) {
            self.tell_host(format!(
                "Sensor Control {}/{}: gain {}, level {}, noise {} (0..1) or AC coupling {} us (0 or more) clamped",
                s.view_id, s.sensor_id, s.gain, s.level, s.noise, s.ac_coupling_us
            ));
        }
        self.sensors.insert(
            (s.view_id, s.sensor_id),
            SensorMode {
                view_id: s.view_id,
                sensor_id: s.sensor_id,
                on: s.sensor_on,
                black_hot: s.polarity_black_hot,
                gain: f64::from(s.gain).clamp(0.0, 1.0),
                level: f64::from(s.level).clamp(0.0, 1.0),
                noise: f64::from(s.noise).clamp(0.0, 1.0),
                track_mode: s.track_mode,
                extended_response: s.response_type_extended,
                automatic_gain: s.automatic_gain,
                line_dropout: s.line_dropout_enable,
                ac_coupling_us: f64::from(s.ac_coupling_us).max(0.0),
                track_black: s.track_black,
            },
        );
        true
    }

    /// Moves entities by their rates over `dt_s` seconds (between host updates).
    pub fn advance(&mut self, dt_s: f64, query: &QuerySession) {
        if !(dt_s.is_finite() && dt_s > 0.0) {
            return;
        }
        for e in self.entities.values_mut() {
            let Some(rates) = e.rates else { continue };
            let [x, y, z] = rates.linear_mps;
            let [roll, pitch, yaw] = rates.angular_dps;
            match &mut e.placement {
                Placement::Geodetic {
                    lat_deg,
                    lon_deg,
                    alt_m,
                } => {
                    let enu = rates.velocity_enu_mps(e.orientation) * dt_s;
                    let here = geodetic_msl(*lat_deg, *lon_deg, *alt_m, query);
                    let there = displaced(here, enu);
                    *lat_deg = there.lat_deg;
                    *lon_deg = there.lon_deg;
                    *alt_m += enu.z;
                }
                Placement::Attached { offset, .. } => {
                    // Body-axis rates turn with the entity's orientation in its parent's frame
                    // (the parent's x, y, z taken as north, east, down).
                    let (dx, dy, dz) = if rates.body_axes {
                        let enu = offset_enu(
                            e.orientation,
                            BodyOffset {
                                x_m: x,
                                y_m: y,
                                z_m: z,
                            },
                        );
                        (enu.y, enu.x, -enu.z)
                    } else {
                        (x, y, z)
                    };
                    offset.x_m += dx * dt_s;
                    offset.y_m += dy * dt_s;
                    offset.z_m += dz * dt_s;
                }
            }
            e.orientation.heading_deg = wrap_deg(e.orientation.heading_deg + yaw * dt_s);
            e.orientation.pitch_deg = (e.orientation.pitch_deg + pitch * dt_s).clamp(-90.0, 90.0);
            e.orientation.roll_deg =
                (e.orientation.roll_deg + roll * dt_s + 180.0).rem_euclid(360.0) - 180.0;
        }
    }

    /// Resolves every entity's pose (clamping through the terrain, attachments through their
    /// parents). Entities whose chain is broken, cyclic or off the database are left out and
    /// reported to the host once.
    pub fn resolve_poses(&mut self, query: &mut QuerySession) {
        let mut poses = BTreeMap::new();
        let ids: Vec<u16> = self.entities.keys().copied().collect();
        let mut problems = Vec::new();
        for id in ids {
            if let Err(problem) = self.resolve_one(id, query, &mut poses, 0) {
                problems.push(problem);
            }
        }
        for p in problems {
            self.tell_host(p);
        }
        self.poses = poses;
    }

    fn resolve_one(
        &self,
        id: u16,
        query: &mut QuerySession,
        poses: &mut BTreeMap<u16, Pose>,
        depth: usize,
    ) -> Result<Pose, String> {
        if let Some(p) = poses.get(&id) {
            return Ok(*p);
        }
        if depth > MAX_ATTACH_DEPTH {
            return Err(format!("entity {id}: attachment chain too deep or cyclic"));
        }
        let e = self
            .entities
            .get(&id)
            .ok_or_else(|| format!("entity {id} does not exist"))?;
        let pose = match e.placement {
            Placement::Geodetic {
                lat_deg,
                lon_deg,
                alt_m,
            } => {
                let mut orientation = e.orientation;
                let afloat = match (&self.sea, e.clamp) {
                    (_, Clamp::None) | (None, _) => None,
                    (Some(sea), _) => self.sea_level_at(query, lat_deg, lon_deg).map(|level| {
                        sea.float(
                            query,
                            &e.model,
                            e.orientation,
                            e.clamp,
                            [lat_deg, lon_deg, alt_m],
                            self.ship_velocities.get(&id).copied().unwrap_or_default(),
                            level,
                            Some(crate::sea::ShipKey::Own(id)),
                        )
                    }),
                };
                let position = if let Some(afloat) = afloat {
                    orientation = afloat.orientation;
                    afloat.position
                } else if e.clamp == Clamp::None {
                    geodetic_msl(lat_deg, lon_deg, alt_m, query)
                } else {
                    let spec = cig_scene::snapshot::EntitySpec {
                        id: u32::from(id),
                        model: String::new(),
                        position: Geodetic::new(lat_deg, lon_deg, alt_m),
                        orientation,
                        clamp: e.clamp,
                    };
                    let placed = cig_scene::snapshot::place_entity(query, &spec)
                        .map_err(|err| format!("entity {id} cannot be clamped: {err}"))?;
                    orientation = placed.orientation;
                    placed.position
                };
                Pose {
                    position,
                    orientation,
                }
            }
            Placement::Attached { parent_id, offset } => {
                let parent = self
                    .resolve_one(parent_id, query, poses, depth + 1)
                    .map_err(|err| {
                        format!("entity {id} is attached to a parent that cannot be placed ({err})")
                    })?;
                child_pose(parent, offset, e.orientation)
            }
        };
        poses.insert(id, pose);
        Ok(pose)
    }

    /// The pose of a view: its entity's pose with the view's offset and orientation.
    pub fn view_pose(&self, view: &IgView) -> Option<Pose> {
        let parent = self.poses.get(&view.entity_id)?;
        Some(child_pose(*parent, view.offset, view.orientation))
    }

    /// The point a request names: geodetic (MSL altitude) or an offset from an entity.
    fn request_point(
        &self,
        entity_relative: bool,
        entity_id: u16,
        values: [f64; 3],
        query: &QuerySession,
    ) -> Option<Geodetic> {
        if !finite3(values[0], values[1], values[2]) {
            return None;
        }
        if entity_relative {
            let pose = self.poses.get(&entity_id)?;
            Some(point_from(
                *pose,
                BodyOffset {
                    x_m: values[0],
                    y_m: values[1],
                    z_m: values[2],
                },
            ))
        } else {
            if values[0].abs() > 90.0 || values[1].abs() > 360.0 {
                return None;
            }
            Some(geodetic_msl(values[0], values[1], values[2], query))
        }
    }

    /// Ends the IG frame: Start of Frame, then the answers to every request due, collision
    /// notifications, sensor responses and IG messages, in the host's version and byte order.
    /// `timestamp_10us` is the IG's clock in 10 µs ticks (wrapping). Resolve poses first.
    /// `obscurants`: the smoke, flame and dust line-of-sight answers see through (or not).
    pub fn end_frame(
        &mut self,
        query: &mut QuerySession,
        obscurants: Option<&EffectSystem>,
        timestamp_10us: u32,
    ) -> Message {
        self.ig_frame_number = self.ig_frame_number.wrapping_add(1);
        let (version, byte_order) = self
            .host_format
            .unwrap_or((Version::V3_3, ByteOrder::LittleEndian));
        let database_number = if self.requested_database == self.config.database_number
            || self.requested_database == 0
        {
            self.config.database_number
        } else {
            -128
        };
        let mut packets = vec![Packet::StartOfFrame(StartOfFrame {
            database_number,
            ig_status: 0,
            ig_mode: self.ig_mode,
            timestamp_valid: true,
            earth_reference_model_host_defined: false,
            ig_frame_number: self.ig_frame_number,
            timestamp_10us,
            last_host_frame_number: self.last_host_frame_number,
            overframing: false,
            paging: false,
            excessive_variable_length_data: false,
        })];
        if !self.config.answers_host {
            // A slave channel: requests are heard (and dropped when due) but never answered.
            self.deferred.clear();
            self.ig_messages.clear();
            let lsn_now = self.host_frame_lsn();
            let _ = due(&mut self.hat_hot, lsn_now);
            let _ = due(&mut self.los_segment, lsn_now);
            let _ = due(&mut self.los_vector, lsn_now);
            let _ = due(&mut self.position, lsn_now);
            self.environment_requests.clear();
            return Message::new(version, byte_order, packets);
        }
        let mut answers: Vec<Packet> = self.deferred.drain(..).collect();
        self.answer_hat_hot(query, &mut answers);
        self.answer_los(query, obscurants, &mut answers);
        self.answer_positions(query, &mut answers);
        self.answer_environment(&mut answers);
        self.detect_collisions(query, &mut answers);
        self.sensor_responses(&mut answers);
        while let Some(text) = self.ig_messages.pop_front() {
            let mut end = text.len().min(cig_cigi::MAX_IG_MESSAGE_TEXT_BYTES);
            while !text.is_char_boundary(end) {
                end -= 1;
            }
            answers.push(Packet::ImageGeneratorMessage(ImageGeneratorMessage {
                message_id: 0,
                text: text.get(..end).unwrap_or_default().to_string(),
            }));
        }
        let room = MAX_PACKETS_PER_MESSAGE - 1;
        if answers.len() > room {
            let rest = answers.split_off(room);
            self.counters.answers_deferred += rest.len() as u64;
            self.deferred.extend(rest);
            while self.deferred.len() > MAX_DEFERRED_ANSWERS {
                self.deferred.pop_front();
                self.counters.answers_dropped += 1;
            }
        }
        packets.extend(answers);
        Message::new(version, byte_order, packets)
    }

    fn answer_hat_hot(&mut self, query: &mut QuerySession, out: &mut Vec<Packet>) {
        let lsn_now = self.host_frame_lsn();
        for (r, lsn) in due(&mut self.hat_hot, lsn_now) {
            self.counters.hat_hot_answered += 1;
            let point = self.request_point(
                r.coordinate_system_entity,
                r.entity_id,
                [r.lat_deg_or_x_m, r.lon_deg_or_y_m, r.alt_m_or_z_m],
                query,
            );
            let answer = point.and_then(|p| {
                let s = self.surface_hot(query, p.lat_deg, p.lon_deg).ok()?;
                Some((p.alt_m - s.height_ellipsoid_m(), s))
            });
            match (r.request_type, answer) {
                (2, Some((hat, s))) => {
                    let (az, el) = normal_az_el(&s);
                    out.push(Packet::HatHotExtendedResponse(HatHotExtendedResponse {
                        hat_hot_id: r.hat_hot_id,
                        valid: true,
                        host_frame_lsn: lsn,
                        hat_m: hat,
                        hot_m: s.height_msl_m,
                        material_code: u32::from(s.material.to_byte()),
                        normal_azimuth_deg: az,
                        normal_elevation_deg: el,
                    }));
                }
                (2, None) => out.push(Packet::HatHotExtendedResponse(HatHotExtendedResponse {
                    hat_hot_id: r.hat_hot_id,
                    valid: false,
                    host_frame_lsn: lsn,
                    ..HatHotExtendedResponse::default()
                })),
                (t, answer) => out.push(Packet::HatHotResponse(HatHotResponse {
                    hat_hot_id: r.hat_hot_id,
                    valid: answer.is_some(),
                    response_type_hot: t == 1,
                    host_frame_lsn: lsn,
                    height_m: answer
                        .map_or(0.0, |(hat, s)| if t == 1 { s.height_msl_m } else { hat }),
                })),
            }
        }
    }

    fn answer_los(
        &mut self,
        query: &mut QuerySession,
        obscurants: Option<&EffectSystem>,
        out: &mut Vec<Packet>,
    ) {
        let lsn_now = self.host_frame_lsn();
        let mut jobs = Vec::new();
        for (r, lsn) in due(&mut self.los_segment, lsn_now) {
            let from = self.request_point(
                r.source_coordinate_entity,
                r.entity_id,
                [
                    r.source_lat_deg_or_x_m,
                    r.source_lon_deg_or_y_m,
                    r.source_alt_m_or_z_m,
                ],
                query,
            );
            let to = self.request_point(
                r.destination_coordinate_entity,
                if r.destination_entity_id_valid {
                    r.destination_entity_id
                } else {
                    r.entity_id
                },
                [
                    r.destination_lat_deg_or_x_m,
                    r.destination_lon_deg_or_y_m,
                    r.destination_alt_m_or_z_m,
                ],
                query,
            );
            jobs.push(LosJob {
                los_id: r.los_id,
                extended: r.request_type_extended,
                entity_relative: r.response_coordinate_entity,
                entity_id: r.entity_id,
                lsn,
                segment: from.zip(to),
                range_offset_m: 0.0,
                alpha_threshold: r.alpha_threshold,
            });
        }
        for (r, lsn) in due(&mut self.los_vector, lsn_now) {
            let from = self.request_point(
                r.source_coordinate_entity,
                r.entity_id,
                [
                    r.source_lat_deg_or_x_m,
                    r.source_lon_deg_or_y_m,
                    r.source_alt_m_or_z_m,
                ],
                query,
            );
            let ok = r.min_range_m.is_finite()
                && r.max_range_m.is_finite()
                && r.min_range_m >= 0.0
                && r.max_range_m > r.min_range_m
                && r.azimuth_deg.is_finite()
                && r.elevation_deg.is_finite();
            // From an entity, azimuth and elevation are measured in its body axes.
            let body = r
                .source_coordinate_entity
                .then(|| self.poses.get(&r.entity_id).map(|p| p.orientation))
                .flatten();
            let segment = from.filter(|_| ok).map(|source| {
                let (az, el) = (f64::from(r.azimuth_deg), f64::from(r.elevation_deg));
                let d = match body {
                    Some(orientation) => {
                        let (sa, ca) = az.to_radians().sin_cos();
                        let (se, ce) = el.to_radians().sin_cos();
                        offset_enu(
                            orientation,
                            BodyOffset {
                                x_m: ce * ca,
                                y_m: ce * sa,
                                z_m: -se,
                            },
                        )
                    }
                    None => direction_enu(az, el),
                };
                (
                    displaced(source, d * f64::from(r.min_range_m)),
                    displaced(source, d * f64::from(r.max_range_m)),
                )
            });
            jobs.push(LosJob {
                los_id: r.los_id,
                extended: r.request_type_extended,
                entity_relative: r.response_coordinate_entity,
                entity_id: r.entity_id,
                lsn,
                segment,
                range_offset_m: f64::from(r.min_range_m),
                alpha_threshold: r.alpha_threshold,
            });
        }
        for job in jobs {
            let LosJob {
                los_id,
                extended,
                entity_relative,
                entity_id,
                lsn,
                segment,
                range_offset_m,
                alpha_threshold,
            } = job;
            self.counters.los_answered += 1;
            let (result, sea_normal) = match segment {
                Some((a, b)) => self.los_with_sea(query, a, b),
                None => (None, None),
            };
            let hit = result.and_then(|r| r.hit);
            let mut visible = result.is_some_and(|r| r.visible);
            // Smoke, flame and dust on the clear part of the line are a translucent surface of
            // opacity 1 - T (T = exp(-optical depth)): as alpha, it stops the line when it
            // reaches the request's alpha threshold (ICD 3.3: surfaces below it are ignored).
            let obscurant_alpha = match (obscurants, segment) {
                (Some(effects), Some((a, b))) if result.is_some() => {
                    let end = hit.map_or(b, |h| h.point);
                    let t = effects.transmittance_ecef(a.to_ecef(), end.to_ecef());
                    (255.0 * (1.0 - t.transmittance)).round().clamp(0.0, 255.0) as u8
                }
                _ => 0,
            };
            let obscured = visible && obscurant_alpha > 0 && obscurant_alpha >= alpha_threshold;
            if obscured {
                visible = false;
                self.counters.los_obscured += 1;
            }
            if extended {
                let mut response = LosExtendedResponse {
                    los_id,
                    valid: result.is_some(),
                    visible,
                    host_frame_lsn: lsn,
                    response_count: 1,
                    alpha: if obscured { obscurant_alpha } else { 0 },
                    ..LosExtendedResponse::default()
                };
                if let Some(h) = hit {
                    response.range_valid = true;
                    response.range_m = h.range_m + range_offset_m;
                    response.material_code = hit_material_code(&h);
                    let position = match (entity_relative, self.poses.get(&entity_id)) {
                        (true, Some(pose)) => {
                            let o = offset_of(*pose, h.point);
                            [o.x_m, o.y_m, o.z_m]
                        }
                        _ => [
                            h.point.lat_deg,
                            h.point.lon_deg,
                            msl_altitude(h.point, query),
                        ],
                    };
                    [
                        response.lat_deg_or_x_m,
                        response.lon_deg_or_y_m,
                        response.alt_m_or_z_m,
                    ] = position;
                    if let Some([e, n, u]) = h.culture.map(|c| c.normal_enu).or(sea_normal) {
                        let (az, el) = azimuth_elevation_deg(DVec3::new(e, n, u));
                        response.normal_azimuth_deg = az as f32;
                        response.normal_elevation_deg = el as f32;
                    } else if let Ok(s) = query.hot(h.point.lat_deg, h.point.lon_deg) {
                        let (az, el) = normal_az_el(&s);
                        response.normal_azimuth_deg = az;
                        response.normal_elevation_deg = el;
                    }
                    response.alpha = 255;
                }
                out.push(Packet::LosExtendedResponse(response));
            } else {
                out.push(Packet::LosResponse(LosResponse {
                    los_id,
                    valid: result.is_some(),
                    visible,
                    host_frame_lsn: lsn,
                    response_count: 1,
                    range_m: hit.map_or(0.0, |h| h.range_m + range_offset_m),
                    ..LosResponse::default()
                }));
            }
        }
    }

    /// Line of sight from `a` to `b` (altitudes above the ellipsoid) seeing the terrain, its
    /// culture and, where the session has a sea, the waves ([`crate::sea::SeaNow::first_hit`],
    /// refracted, with the waves: the crests block what they would hide): the nearer of the
    /// terrain's hit and the sea's, with the sea's normal when it is the sea's. Over the sea
    /// the sea replaces the terrain's sea posts ([`crate::sea::SeaNow::covers`]), and a
    /// sightline that misses the database is answered by the sea alone. `None`: no answer.
    fn los_with_sea(
        &self,
        query: &mut QuerySession,
        a: Geodetic,
        b: Geodetic,
    ) -> (Option<cig_terrain::LosResult>, Option<[f64; 3]>) {
        // The sightline bends as what the eye sees does (standard terrestrial refraction),
        // over land and sea alike.
        let refraction = crate::sea::sightline_refraction(a, b);
        let Some(sea) = &self.sea else {
            let terrain =
                query.los_refracted(a, b, cig_terrain::CultureTest::LineOfSight, refraction);
            return (terrain.ok(), None);
        };
        let terrain =
            match query.los_refracted(a, b, cig_terrain::CultureTest::LineOfSight, refraction) {
                Ok(r) => r.hit,
                Err(cig_terrain::QueryError::Misses { .. }) => None,
                Err(_) => return (None, None),
            };
        let level_at = |lat_deg: f64, lon_deg: f64| {
            self.water_at(Geodetic::new(lat_deg, lon_deg, 0.0))
                .level_msl_m
        };
        let sea_post = terrain.is_some_and(|h| {
            Self::is_sea_post(query, &h, level_at(h.point.lat_deg, h.point.lon_deg))
        });
        let land_hit = terrain.filter(|_| !sea_post);
        let mid = Geodetic::from_ecef((a.to_ecef() + b.to_ecef()) * 0.5);
        let sightline = crate::sea::SeaSightline {
            level_msl_m: level_at(mid.lat_deg, mid.lon_deg),
            geoid_m: [a, b].map(|p| query.geoid_undulation_m(p.lat_deg, p.lon_deg)),
            refraction_k: refraction.k,
            with_waves: true,
            // Nothing beyond the land's hit matters.
            max_range_m: land_hit.map_or(f64::INFINITY, |h| h.range_m),
        };
        let sea_hit = sea.first_hit(a, b, &sightline, |lat_deg, lon_deg| {
            crate::sea::SeaNow::covers(&query.hot(lat_deg, lon_deg), level_at(lat_deg, lon_deg))
        });
        let limit_m = sea_hit.map_or(f64::INFINITY, |h| h.range_m);
        let land = match terrain {
            // The terrain's sightline went under the sea posts: look for land beyond, up to
            // the sea's own hit.
            Some(h) if sea_post && h.range_m < limit_m => {
                match Self::land_beyond_sea(query, (a, b, refraction), h.range_m, limit_m, level_at)
                {
                    Ok(land) => land,
                    Err(_) => return (None, None),
                }
            }
            _ => land_hit,
        };
        let hit = match (land, sea_hit) {
            (Some(l), Some(s)) if l.range_m <= s.range_m => Ok(l),
            (Some(l), None) => Ok(l),
            (_, Some(s)) => Err(s),
            (None, None) => {
                return (
                    Some(cig_terrain::LosResult {
                        visible: true,
                        hit: None,
                    }),
                    None,
                )
            }
        };
        let (hit, normal) = match hit {
            Ok(l) => (l, None),
            Err(s) => (
                LosHit {
                    point: s.point,
                    range_m: s.range_m,
                    material: cig_terrain::Material::Water,
                    level: 0,
                    culture: None,
                },
                Some(s.normal_enu),
            ),
        };
        (
            Some(cig_terrain::LosResult {
                visible: false,
                hit: Some(hit),
            }),
            normal,
        )
    }

    /// Whether a terrain hit is on a sea post, where the sea answers instead.
    fn is_sea_post(query: &mut QuerySession, hit: &LosHit, level_msl_m: f64) -> bool {
        hit.culture.is_none()
            && crate::sea::SeaNow::covers(
                &query.hot(hit.point.lat_deg, hit.point.lon_deg),
                level_msl_m,
            )
    }

    /// The first land or culture the sightline from `a` to `b` meets between `from_m`, where
    /// the terrain's sightline met a sea post (the sea answers there), and `limit_m` (the
    /// sea's own hit): walks on along the sightline while it is under the sea posts' top, in
    /// steps of half a post, watching for land (bisected to 1 cm), then asks the terrain again
    /// from where the sightline rises above them (a few times at most).
    fn land_beyond_sea(
        query: &mut QuerySession,
        (a, b, refraction): (Geodetic, Geodetic, cig_terrain::Refraction),
        from_m: f64,
        limit_m: f64,
        level_at: impl Fn(f64, f64) -> f64,
    ) -> Result<Option<LosHit>, cig_terrain::QueryError> {
        const RESTARTS: usize = 4;
        let (ea, eb) = (a.to_ecef(), b.to_ecef());
        let length_m = (eb - ea).length();
        // The point of the refracted path `x` metres along its chord.
        let on_path = |x: f64| {
            let t = x / length_m;
            let mut p = Geodetic::from_ecef(ea + (eb - ea) * t);
            p.alt_m += refraction.lift_m(length_m, t);
            p
        };
        let end_m = length_m.min(limit_m);
        let grid = query.cache().database().layout().grid;
        let (north, east) = cig_geo::metres_per_degree(a.lat_deg);
        let step_m = (0.5 * (grid.dlat_deg * north).min(grid.dlon_deg * east)).max(1.0);
        // Land above the sightline at `x`: the point on the sightline and the land's material.
        let land_at = |query: &mut QuerySession, x: f64| {
            let p = on_path(x);
            let terrain = query.hot(p.lat_deg, p.lon_deg);
            let sea = crate::sea::SeaNow::covers(&terrain, level_at(p.lat_deg, p.lon_deg));
            match terrain {
                Ok(s) if !sea && p.alt_m <= s.height_ellipsoid_m() => Some((p, s)),
                _ => None,
            }
        };
        let mut x = from_m;
        for _ in 0..RESTARTS {
            let mut last_sea = x;
            while x < end_m {
                x = (x + step_m).min(end_m);
                if let Some((mut p, mut s)) = land_at(query, x) {
                    while x - last_sea > 0.01 {
                        let m = 0.5 * (last_sea + x);
                        match land_at(query, m) {
                            Some(found) => ((p, s), x) = (found, m),
                            None => last_sea = m,
                        }
                    }
                    return Ok(Some(LosHit {
                        point: p,
                        range_m: x,
                        material: s.material,
                        level: s.level,
                        culture: None,
                    }));
                }
                let p = on_path(x);
                let level = level_at(p.lat_deg, p.lon_deg);
                let sea = crate::sea::SeaNow::covers(&query.hot(p.lat_deg, p.lon_deg), level);
                let above_m = p.alt_m - query.geoid_undulation_m(p.lat_deg, p.lon_deg);
                if !sea || above_m > level.max(0.0) + crate::sea::SEA_POST_TOLERANCE_M {
                    break;
                }
                last_sea = x;
            }
            if x >= end_m {
                return Ok(None);
            }
            // The sightline is above the sea posts again (or over land below it): the terrain
            // from here.
            // The rest of the same arc: the path of the same curvature from here to `b`.
            let start = on_path(x);
            let hit = match query.los_refracted(
                start,
                b,
                cig_terrain::CultureTest::LineOfSight,
                refraction,
            ) {
                Ok(r) => r.hit,
                Err(cig_terrain::QueryError::Misses { .. }) => None,
                Err(e) => return Err(e),
            };
            let Some(mut h) = hit else {
                return Ok(None);
            };
            h.range_m += x;
            if h.range_m >= limit_m {
                return Ok(None);
            }
            if !Self::is_sea_post(query, &h, level_at(h.point.lat_deg, h.point.lon_deg)) {
                return Ok(Some(h));
            }
            x = h.range_m;
        }
        Ok(None)
    }

    fn answer_positions(&mut self, query: &mut QuerySession, out: &mut Vec<Packet>) {
        let lsn_now = self.host_frame_lsn();
        for (r, _lsn) in due(&mut self.position, lsn_now) {
            self.counters.position_answered += 1;
            let response = match r.object_class {
                0 => self.entity_position(&r, query),
                1 => self.entities.get(&r.object_id).and_then(|e| {
                    e.parts.get(&r.part_id).map(|part| PositionResponse {
                        object_id: r.object_id,
                        part_id: r.part_id,
                        object_class: 1,
                        coordinate_system: 2,
                        lat_deg_or_x_m: part.offset.x_m,
                        lon_deg_or_y_m: part.offset.y_m,
                        alt_m_or_z_m: part.offset.z_m,
                        roll_deg: part.orientation.roll_deg as f32,
                        pitch_deg: part.orientation.pitch_deg as f32,
                        yaw_deg: part.orientation.heading_deg as f32,
                    })
                }),
                2 | 3 => {
                    let view = if r.object_class == 2 {
                        self.views.get(&r.object_id)
                    } else {
                        self.views
                            .values()
                            .find(|v| u16::from(v.group_id) == r.object_id)
                    };
                    view.and_then(|v| self.view_pose(v))
                        .map(|pose| PositionResponse {
                            object_id: r.object_id,
                            part_id: 0,
                            object_class: r.object_class,
                            coordinate_system: 0,
                            lat_deg_or_x_m: pose.position.lat_deg,
                            lon_deg_or_y_m: pose.position.lon_deg,
                            alt_m_or_z_m: msl_altitude(pose.position, query),
                            roll_deg: pose.orientation.roll_deg as f32,
                            pitch_deg: pose.orientation.pitch_deg as f32,
                            yaw_deg: pose.orientation.heading_deg as f32,
                        })
                }
                _ => None,
            };
            match response {
                Some(p) => out.push(Packet::PositionResponse(p)),
                None => self.tell_host(format!(
                    "Position Request: object {} of class {} is not known",
                    r.object_id, r.object_class
                )),
            }
        }
    }

    fn entity_position(
        &self,
        r: &PositionRequest,
        query: &QuerySession,
    ) -> Option<PositionResponse> {
        let e = self.entities.get(&r.object_id)?;
        let pose = self.poses.get(&r.object_id)?;
        let mut response = PositionResponse {
            object_id: r.object_id,
            part_id: 0,
            object_class: 0,
            coordinate_system: 0,
            lat_deg_or_x_m: pose.position.lat_deg,
            lon_deg_or_y_m: pose.position.lon_deg,
            alt_m_or_z_m: msl_altitude(pose.position, query),
            roll_deg: pose.orientation.roll_deg as f32,
            pitch_deg: pose.orientation.pitch_deg as f32,
            yaw_deg: pose.orientation.heading_deg as f32,
        };
        if r.coordinate_system == 1 {
            if let Placement::Attached { parent_id, .. } = e.placement {
                if let Some(parent) = self.poses.get(&parent_id) {
                    let o = offset_of(*parent, pose.position);
                    let rel = relative(parent.orientation, pose.orientation);
                    response.coordinate_system = 1;
                    response.lat_deg_or_x_m = o.x_m;
                    response.lon_deg_or_y_m = o.y_m;
                    response.alt_m_or_z_m = o.z_m;
                    response.roll_deg = rel.roll_deg as f32;
                    response.pitch_deg = rel.pitch_deg as f32;
                    response.yaw_deg = rel.heading_deg as f32;
                }
            }
        }
        Some(response)
    }

    fn answer_environment(&mut self, out: &mut Vec<Packet>) {
        let requests = std::mem::take(&mut self.environment_requests);
        for r in requests {
            self.counters.environment_answered += 1;
            if !finite3(r.latitude_deg, r.longitude_deg, r.altitude_m)
                || r.latitude_deg.abs() > 90.0
            {
                self.tell_host(format!(
                    "Environmental Conditions Request {}: the point is not valid",
                    r.request_id
                ));
                continue;
            }
            let point = Geodetic::new(r.latitude_deg, r.longitude_deg, r.altitude_m);
            if r.request_type & 1 != 0 {
                // The water there: the host's region, its global conditions, the scenario's.
                let water =
                    self.water_at(Geodetic::new(r.latitude_deg, r.longitude_deg, r.altitude_m));
                out.push(Packet::MaritimeSurfaceConditionsResponse(
                    MaritimeSurfaceConditionsResponse {
                        request_id: r.request_id,
                        sea_surface_height_m: water.level_msl_m as f32,
                        surface_water_temperature_c: water.temperature_c as f32,
                        surface_clarity_pct: water.clarity_pct as f32,
                    },
                ));
            }
            if r.request_type & 2 != 0 {
                let conditions: Vec<u32> = self
                    .environment
                    .terrestrial
                    .values()
                    .filter(|t| t.surface_condition_enable && t.scope == SCOPE_GLOBAL)
                    .map(|t| u32::from(t.surface_condition_id))
                    .collect();
                if conditions.is_empty() {
                    out.push(Packet::TerrestrialSurfaceConditionsResponse(
                        TerrestrialSurfaceConditionsResponse {
                            request_id: r.request_id,
                            surface_condition_id: 0,
                        },
                    ));
                }
                for id in conditions {
                    out.push(Packet::TerrestrialSurfaceConditionsResponse(
                        TerrestrialSurfaceConditionsResponse {
                            request_id: r.request_id,
                            surface_condition_id: id,
                        },
                    ));
                }
            }
            if r.request_type & 4 != 0 {
                out.push(Packet::WeatherConditionsResponse(
                    self.environment.weather_response(
                        r.request_id,
                        point,
                        self.config.default_visibility_m,
                    ),
                ));
            }
            if r.request_type & 8 != 0 {
                let layers = self.environment.layers_at(point);
                for layer in layers {
                    out.push(Packet::AerosolConcentrationResponse(
                        AerosolConcentrationResponse {
                            request_id: r.request_id,
                            layer_id: layer.layer_id,
                            aerosol_concentration_gpm3: layer.aerosol_concentration_gpm3,
                        },
                    ));
                }
            }
        }
    }

    fn detect_collisions(&mut self, query: &mut QuerySession, out: &mut Vec<Packet>) {
        // Segments against the terrain.
        let mut notes = Vec::new();
        for e in self.entities.values() {
            if !e.collision_detection || e.life != EntityLife::Active {
                continue;
            }
            let Some(pose) = self.poses.get(&e.id) else {
                continue;
            };
            for s in e.segments.values().filter(|s| s.segment_enable) {
                let ends = [s.x1_m, s.y1_m, s.z1_m, s.x2_m, s.y2_m, s.z2_m];
                if ends.iter().any(|v| !v.is_finite()) {
                    continue;
                }
                let a = point_from(
                    *pose,
                    BodyOffset {
                        x_m: f64::from(s.x1_m),
                        y_m: f64::from(s.y1_m),
                        z_m: f64::from(s.z1_m),
                    },
                );
                let b = point_from(
                    *pose,
                    BodyOffset {
                        x_m: f64::from(s.x2_m),
                        y_m: f64::from(s.y2_m),
                        z_m: f64::from(s.z2_m),
                    },
                );
                // Terrain and every culture object, fences included.
                let hit = query.collision(a, b).ok().and_then(|r| r.hit);
                // A segment whose start is already below the surface is in contact too.
                let start_below = query
                    .hat(a)
                    .ok()
                    .filter(|(hat, _)| *hat < 0.0)
                    .map(|(_, s)| u32::from(s.material.to_byte()));
                let contact = hit
                    .map(|h| (h.range_m, hit_material_code(&h)))
                    .or(start_below.map(|m| (0.0, m)));
                if let Some((range_m, material_code)) = contact {
                    if s.material_mask == 0 || s.material_mask & (1 << (material_code % 32)) != 0 {
                        notes.push(Packet::CollisionSegmentNotification(
                            CollisionSegmentNotification {
                                entity_id: e.id,
                                segment_id: s.segment_id,
                                collision_with_entity: false,
                                contacted_entity_id: 0,
                                material_code,
                                intersection_distance_m: range_m as f32,
                            },
                        ));
                    }
                }
            }
        }
        // Volumes against other entities' volumes, as bounding spheres.
        let mut spheres = Vec::new();
        for e in self.entities.values() {
            if !e.collision_detection || e.life != EntityLife::Active {
                continue;
            }
            let Some(pose) = self.poses.get(&e.id) else {
                continue;
            };
            for v in e.volumes.values().filter(|v| v.volume_enable) {
                let c = [
                    v.x_m,
                    v.y_m,
                    v.z_m,
                    v.height_or_radius_m,
                    v.width_m,
                    v.depth_m,
                ];
                if c.iter().any(|x| !x.is_finite()) {
                    continue;
                }
                let centre = point_from(
                    *pose,
                    BodyOffset {
                        x_m: f64::from(v.x_m),
                        y_m: f64::from(v.y_m),
                        z_m: f64::from(v.z_m),
                    },
                );
                let radius = if v.volume_type_cuboid {
                    0.5 * (f64::from(v.height_or_radius_m).powi(2)
                        + f64::from(v.width_m).powi(2)
                        + f64::from(v.depth_m).powi(2))
                    .sqrt()
                } else {
                    f64::from(v.height_or_radius_m).abs()
                };
                if spheres.len() < MAX_COLLISION_VOLUMES {
                    spheres.push((e.id, v.volume_id, centre.to_ecef(), radius));
                }
            }
        }
        for (i, a) in spheres.iter().enumerate() {
            for b in spheres.iter().skip(i + 1) {
                if a.0 != b.0 && (a.2 - b.2).length() <= a.3 + b.3 {
                    for (me, other) in [(a, b), (b, a)] {
                        notes.push(Packet::CollisionVolumeNotification(
                            CollisionVolumeNotification {
                                entity_id: me.0,
                                volume_id: me.1,
                                collision_with_entity: true,
                                contacted_entity_id: other.0,
                                contacted_volume_id: other.1,
                            },
                        ));
                    }
                }
            }
        }
        notes.truncate(MAX_COLLISION_NOTES);
        self.counters.collisions_reported += notes.len() as u64;
        out.extend(notes);
    }

    /// Sets what a sensor's tracker found in the last frame drawn (`crate::tracker`).
    pub fn set_track(&mut self, view_id: u16, sensor_id: u8, track: TrackReport) {
        self.tracks.insert((view_id, sensor_id), track);
    }

    fn sensor_responses(&self, out: &mut Vec<Packet>) {
        for s in self.sensors.values().filter(|s| s.on && s.track_mode != 0) {
            // Searching until the renderer's tracker has seen the view.
            let t = self
                .tracks
                .get(&(s.view_id, s.sensor_id))
                .copied()
                .unwrap_or_default();
            if s.extended_response {
                let point = t.point.unwrap_or(Geodetic::new(0.0, 0.0, 0.0));
                out.push(Packet::SensorExtendedResponse(SensorExtendedResponse {
                    view_id: s.view_id,
                    sensor_id: s.sensor_id,
                    sensor_status: t.status,
                    entity_id_valid: t.entity_id.is_some(),
                    entity_id: t.entity_id.unwrap_or(0),
                    gate_x_size_px: t.gate_px[0],
                    gate_y_size_px: t.gate_px[1],
                    gate_x_position_deg: t.gate_deg[0],
                    gate_y_position_deg: t.gate_deg[1],
                    frame_counter: self.ig_frame_number,
                    track_latitude_deg: point.lat_deg,
                    track_longitude_deg: point.lon_deg,
                    track_altitude_m: point.alt_m,
                }));
            } else {
                out.push(Packet::SensorResponse(SensorResponse {
                    view_id: s.view_id,
                    sensor_id: s.sensor_id,
                    sensor_status: t.status,
                    gate_x_size_px: t.gate_px[0],
                    gate_y_size_px: t.gate_px[1],
                    gate_x_position_deg: t.gate_deg[0],
                    gate_y_position_deg: t.gate_deg[1],
                    frame_counter: self.ig_frame_number,
                }));
            }
        }
    }

    /// Visibility at a point (altitude above MSL).
    pub fn visibility_at_m(&self, point: Geodetic) -> f64 {
        self.environment
            .visibility_at_m(point, self.config.default_visibility_m)
    }

    /// Visibility for the whole view from a point (above MSL), the ground fog layer apart.
    pub fn view_visibility_m(&self, point: Geodetic) -> f64 {
        self.environment
            .visibility_above_ground_fog_m(point, self.config.default_visibility_m)
    }
}

/// The orientation of a host's placement, when its numbers can be used: all finite, and a
/// geodetic (unattached) position on the globe.
fn checked_orientation(
    attach: bool,
    values: [f64; 3],
    yaw: f32,
    pitch: f32,
    roll: f32,
) -> Option<Hpr> {
    if !finite3(values[0], values[1], values[2]) {
        return None;
    }
    if !attach && (values[0].abs() > 90.0 || values[1].abs() > 360.0) {
        return None;
    }
    hpr_f32(yaw, pitch, roll)
}

/// Entity state (1 active, other values inactive; 2, destroyed, is handled before), alpha
/// and collision detection, as Entity Control (3.3 and 4.0) give them.
fn set_state(e: &mut IgEntity, state: u8, alpha: u8, collision_detection: bool) {
    e.life = if state == 1 {
        EntityLife::Active
    } else {
        EntityLife::Inactive
    };
    e.alpha = alpha;
    e.collision_detection = collision_detection;
}

/// Sets the offset (x, y, z) and orientation (roll, pitch, yaw) fields whose enable flag is
/// set and whose value is finite, as Articulated Part and View Control give them.
fn set_enabled(offset: &mut BodyOffset, orientation: &mut Hpr, fields: [(bool, f32); 6]) {
    let slots = [
        &mut offset.x_m,
        &mut offset.y_m,
        &mut offset.z_m,
        &mut orientation.roll_deg,
        &mut orientation.pitch_deg,
        &mut orientation.heading_deg,
    ];
    for (slot, (enable, value)) in slots.into_iter().zip(fields) {
        if enable && value.is_finite() {
            *slot = f64::from(value);
        }
    }
}

fn set_placement(
    e: &mut IgEntity,
    attach: bool,
    parent_id: u16,
    values: [f64; 3],
    orientation: Hpr,
    clamp_code: u8,
) {
    e.placement = if attach && parent_id != e.id {
        Placement::Attached {
            parent_id,
            offset: BodyOffset {
                x_m: values[0],
                y_m: values[1],
                z_m: values[2],
            },
        }
    } else {
        Placement::Geodetic {
            lat_deg: values[0],
            lon_deg: values[1],
            alt_m: values[2],
        }
    };
    e.orientation = orientation;
    e.clamp = match clamp_code {
        1 => Clamp::Height,
        2 => Clamp::HeightAndAttitude,
        _ => Clamp::None,
    };
    e.scripted = false;
}

/// Files a request: one-shot (period 0) or standing (answered every `period` frames); a
/// request with the ID of a standing one replaces it.
fn standing<K: Ord, T>(map: &mut BTreeMap<K, Pending<T>>, key: K, request: T) -> bool {
    if map.len() >= MAX_STANDING_REQUESTS && !map.contains_key(&key) {
        return false;
    }
    map.insert(
        key,
        Pending {
            request,
            countdown: 0,
        },
    );
    true
}

/// Requests due this frame, each with `lsn` (the 4 low bits of the host frame the answer is
/// computed in, ICD 3.3 §4.2.2); one-shot ones leave the map, standing ones restart their count.
fn due<K: Ord + Clone, T: Clone + HasPeriod>(
    map: &mut BTreeMap<K, Pending<T>>,
    lsn: u8,
) -> Vec<(T, u8)> {
    let mut out = Vec::new();
    let mut finished = Vec::new();
    for (key, pending) in map.iter_mut() {
        if pending.countdown > 0 {
            pending.countdown -= 1;
            continue;
        }
        out.push((pending.request.clone(), lsn));
        let period = pending.request.period();
        if period == 0 {
            finished.push(key.clone());
        } else {
            pending.countdown = period - 1;
        }
    }
    for key in finished {
        map.remove(&key);
    }
    out
}

/// The update period of a standing request (0: one answer).
trait HasPeriod {
    fn period(&self) -> u8;
}
impl HasPeriod for HatHotRequest {
    fn period(&self) -> u8 {
        self.update_period
    }
}
impl HasPeriod for LosSegmentRequest {
    fn period(&self) -> u8 {
        self.update_period
    }
}
impl HasPeriod for LosVectorRequest {
    fn period(&self) -> u8 {
        self.update_period
    }
}
impl HasPeriod for PositionRequest {
    fn period(&self) -> u8 {
        u8::from(self.update_mode_continuous)
    }
}
