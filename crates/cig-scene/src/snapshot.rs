//! The plain per-frame snapshot of the world the renderer consumes, and entity placement.
//!
//! Algorithm: the world model (terrain cache, entities, time, atmosphere) is read once per frame
//! into plain values; the renderer never reaches back into the world. Entities asked to sit on
//! the ground are clamped with the database's HOT query on the finest triangulated surface —
//! the surface the renderer draws at full detail — and may be pitched and rolled to its normal.
//!
//! An eye found below the terrain is lifted onto it ([`lift_eyes_above_terrain`]): the host or
//! the user placed it there by mistake, and a picture from inside the hill tells a trainee
//! nothing; the binary warns.
//!
//! Limits: clamping uses the finest surface; where a far entity's terrain is drawn coarser,
//! it may float or sink by at most the terrain's allowed screen error (under a pixel).

use crate::lighting::{Fog, FogMode, SkySettings};
use crate::view::{Hpr, View};
use cig_geo::Geodetic;
use cig_terrain::{QueryError, QuerySession};
use serde::{Deserialize, Serialize};

/// How an entity meets the ground.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Clamp {
    /// The altitude is used as given (above the ellipsoid).
    #[default]
    None,
    /// The altitude becomes the terrain height plus `alt_m` (as an offset).
    Height,
    /// As `Height`, and pitch and roll follow the terrain's slope.
    HeightAndAttitude,
}

/// An entity as the scenario or host states it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct EntitySpec {
    pub id: u32,
    /// Model name (built-in or loaded).
    pub model: String,
    pub position: Geodetic,
    #[serde(default)]
    pub orientation: Hpr,
    #[serde(default)]
    pub clamp: Clamp,
}

/// An entity ready to draw.
#[derive(Clone, Debug, PartialEq)]
pub struct EntityInstance {
    pub id: u32,
    pub model: String,
    /// Body origin, altitude above the ellipsoid.
    pub position: Geodetic,
    pub orientation: Hpr,
    /// Marked as an important cue in the model table: drawn at the nominal `K_LOD` whatever
    /// the overload control does (source 004 §4.6, [`crate::overload`]).
    pub cue_important: bool,
    /// The model table's critical radius for the entity's model, metres (`None`: the model's
    /// own, its bounding radius unless the model sets one).
    pub critical_radius_m: Option<f32>,
}

/// Places an entity, clamping it to the terrain when asked.
pub fn place_entity(
    session: &mut QuerySession,
    spec: &EntitySpec,
) -> Result<EntityInstance, QueryError> {
    let mut position = spec.position;
    let mut orientation = spec.orientation;
    if spec.clamp != Clamp::None {
        let surface = session.hot(spec.position.lat_deg, spec.position.lon_deg)?;
        position.alt_m = surface.height_ellipsoid_m() + spec.position.alt_m;
        if spec.clamp == Clamp::HeightAndAttitude {
            (orientation.pitch_deg, orientation.roll_deg) =
                attitude_on_slope(surface.normal_enu, orientation.heading_deg);
        }
    }
    Ok(EntityInstance {
        id: spec.id,
        cue_important: false,
        critical_radius_m: None,
        model: spec.model.clone(),
        position,
        orientation,
    })
}

/// Pitch and roll, degrees, of a body heading `heading_deg` resting on a surface whose unit
/// normal (east, north, up) is `normal_enu`.
pub fn attitude_on_slope(normal_enu: [f64; 3], heading_deg: f64) -> (f64, f64) {
    let [e, n, u] = normal_enu;
    let (sh, ch) = heading_deg.to_radians().sin_cos();
    // Slope along the body's forward and right axes.
    let forward_slope = -(e * sh + n * ch) / u.max(1e-6);
    let right_slope = -(e * ch - n * sh) / u.max(1e-6);
    (
        forward_slope.atan().to_degrees(),
        -right_slope.atan().to_degrees(),
    )
}

/// Height above the terrain an eye found below it is lifted to, metres: above the near plane
/// (0.5 m) so the surface is seen from above, as from a vehicle's lowest sight.
pub const EYE_CLEARANCE_M: f64 = 1.0;

/// An eye that was below the terrain and was lifted onto it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EyeBelowTerrain {
    /// The view's index in the snapshot.
    pub view: usize,
    /// The eye as given.
    pub eye: Geodetic,
    /// The eye's height above the terrain as given (negative: below it), metres.
    pub height_above_terrain_m: f64,
}

impl std::fmt::Display for EyeBelowTerrain {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "view {}'s eye is {:.1} m below the terrain (height above terrain {:.1} m) at {:.6}, {:.6}: drawn from {EYE_CLEARANCE_M} m above the surface",
            self.view,
            -self.height_above_terrain_m,
            self.height_above_terrain_m,
            self.eye.lat_deg,
            self.eye.lon_deg,
        )
    }
}

/// Lifts every view whose eye lies below the terrain's finest surface (the one HAT answers on)
/// to [`EYE_CLEARANCE_M`] above it, so the picture shows the terrain from its surface rather
/// than inside out, and returns those views with the height above terrain they had. Views
/// outside the database, or where the terrain cannot be read, are left as they are. Limits: an
/// eye less than the near plane (0.5 m) above the ground is left where it is, and may clip the
/// ground in front of it; the query may load the eye's finest tile in the calling thread.
pub fn lift_eyes_above_terrain(
    session: &mut QuerySession,
    views: &mut [View],
) -> Vec<EyeBelowTerrain> {
    let mut lifted = Vec::new();
    for (index, view) in views.iter_mut().enumerate() {
        let Ok(hat_m) = session.hat_m(view.eye) else {
            continue;
        };
        if hat_m.is_finite() && hat_m < 0.0 {
            lifted.push(EyeBelowTerrain {
                view: index,
                eye: view.eye,
                height_above_terrain_m: hat_m,
            });
            view.eye.alt_m += EYE_CLEARANCE_M - hat_m;
        }
    }
    lifted
}

/// A layer of ground fog or haze: below `top_m` the air is as thick as `visibility_m` says,
/// on top of the global fog, so a valley can be fogged while the hills above are clear.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct FogLayer {
    /// Top of the layer, metres above the WGS84 ellipsoid.
    pub top_m: f64,
    /// Meteorological visibility inside the layer, metres (Koschmieder: 3.912 / extinction).
    pub visibility_m: f64,
}

impl FogLayer {
    /// Extinction coefficient inside the layer, 1/m.
    pub fn extinction_per_m(&self) -> f64 {
        crate::lighting::KOSCHMIEDER / self.visibility_m.max(1.0)
    }

    /// Transmittance of the layer along a straight ray `distance_m` long from an eye at
    /// `eye_alt_m` to a point at `point_alt_m` (altitudes above the ellipsoid): the ray's share
    /// below the layer's top, heights linear along it, times the layer's extinction (the
    /// shaders' `fog_layer_transmittance`, so a model is removed where it is drawn faded).
    pub fn transmittance(&self, eye_alt_m: f64, point_alt_m: f64, distance_m: f64) -> f64 {
        let (lo, hi) = (eye_alt_m.min(point_alt_m), eye_alt_m.max(point_alt_m));
        let inside = if self.top_m >= hi {
            1.0
        } else if self.top_m > lo {
            (self.top_m - lo) / (hi - lo).max(1e-3)
        } else {
            0.0
        };
        (-self.extinction_per_m() * distance_m.max(0.0) * inside).exp()
    }
}

/// Everything the renderer needs for one frame.
#[derive(Clone, Debug)]
pub struct FrameSnapshot {
    /// Simulation time, seconds since 1970-01-01 UTC.
    pub unix_time_s: f64,
    pub views: Vec<View>,
    pub fog: Fog,
    /// A ground fog or haze layer, if any.
    pub ground_fog: Option<FogLayer>,
    pub max_pixel_error: f64,
    pub wireframe: bool,
    /// Draw the materials' detail noise and smooth material borders (on by default; off is
    /// the flat colour per post, the benchmarks' plain baseline).
    pub ground_detail: bool,
    /// Draw the culture standing on the database (trees, buildings, walls, fences, poles; on
    /// by default, off for `cig render --culture off`).
    pub culture: bool,
    /// `false`: culture drawn with every object of the resident tiles at its finest level and
    /// none removed (the unmanaged reference of `cig bench culture`); `true` by default.
    pub culture_managed: bool,
    /// Per view, the point level of detail centres on (source 004's area of interest: where a
    /// head or eye tracker says the trainee looks), degrees right and up of the view's centre;
    /// `None`, or no entry, is the view's centre.
    pub points_of_interest_deg: Vec<Option<[f64; 2]>>,
    pub entities: Vec<EntityInstance>,
    /// Obscurant puffs to draw (smoke, flame, dust), positions relative to
    /// `puff_origin_ecef_m` (fill with `cig_effects::EffectSystem::snapshot(origin, ..)`).
    /// The renderer re-bases them on each view's eye, the difference taken in f64.
    pub puffs: Vec<cig_effects::PuffInstance>,
    /// ECEF point the puff positions are relative to, m (best: near the eyes, so the f32
    /// offsets stay small).
    pub puff_origin_ecef_m: glam::DVec3,
    /// Fraction of the sky covered by cloud, 0..1 (the natural illuminance's sky-condition
    /// input; set from the cloud layers).
    pub cloud_cover_fraction: f64,
    /// Sky model and exposure (compensation, fixed exposure).
    pub sky: SkySettings,
    /// Draw the stars (they also fade by themselves in daylight).
    pub stars_visible: bool,
    /// Brightness of the star field, 0..1 of the catalogue's (CIGI's star field intensity).
    pub star_intensity: f64,
    /// Draw the moon.
    pub moon_visible: bool,
    /// Cloud layers to draw (at most `cig_environment::clouds::MAX_CLOUD_LAYERS`; bases
    /// above the WGS84 ellipsoid — the world adds the geoid to the layers' MSL heights).
    pub cloud_layers: Vec<cig_environment::clouds::CloudLayer>,
    /// The world-fixed origin of the clouds' noise plane (keep it fixed while the eye moves).
    pub cloud_origin: cig_environment::clouds::CloudOrigin,
    /// Lightning bolts lit now (drawn as emissive lines).
    pub bolts: Vec<BoltDraw>,
    /// Extra illuminance at the eye from lightning flashes now, lux (0 without).
    pub flash_lux: f64,
    /// Rain or snow falling around the eye, if any.
    pub precipitation: Option<PrecipitationDraw>,
    /// Per view, its thermal sensor (`None`, or no entry: the visible channel).
    pub sensors: Vec<Option<crate::thermal::SensorView>>,
    /// The world's light points (entities' lamps, fires, flares, lights the host or the
    /// command line placed); the database's street and settlement lights come from its
    /// resident culture (`culture::CultureSelector::culture_lights_near`), switched by
    /// [`Self::street_lights`].
    pub lights: Vec<crate::lights::LightPoint>,
    /// Street and settlement lights: `None` switches them by the natural illuminance
    /// (`lights::street_lights_on`), `Some` forces them on or off.
    pub street_lights: Option<bool>,
    /// Per view, its night-vision goggle (index as `views`; missing entries are visible
    /// views). A view with a thermal sensor shows the thermal picture.
    pub nvg: Vec<Option<crate::nvg::NvgView>>,
    /// The wakes of the ships under way on the sea (drawn with [`Self::sea`]).
    pub wakes: Vec<crate::sea::WakeDraw>,
    /// Terrestrial refraction's coefficient for what the eye sees (0.13 standard, 0 the
    /// geometric earth): what stands `d` away is drawn raised by `k d² / 2R`, and the sea's
    /// horizon dips by `√(2h (1 - k) / R)`.
    pub refraction_k: f64,
    /// The thermal state the sensor views draw (needed when any view is a sensor).
    pub thermal: Option<std::sync::Arc<crate::thermal::ThermalScene>>,
    /// Trackers' gates to read back after drawing: (view index, `[x, y, width, height]`
    /// pixels), for `cig_ig`'s sensor trackers.
    pub track_gates: Vec<(usize, [u32; 4])>,
    /// The sea over the open ocean and the database's sea areas, when the scene has one.
    pub sea: Option<std::sync::Arc<crate::sea::SeaDraw>>,
}

/// One straight piece of a lightning bolt, relative to its bolt's origin (ECEF axes, metres).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BoltLine {
    pub start_m: [f32; 3],
    pub end_m: [f32; 3],
    /// Relative brightness: 1 on the main channel, less on side branches.
    pub brightness: f32,
}

/// A lightning bolt to draw.
#[derive(Clone, Debug, PartialEq)]
pub struct BoltDraw {
    /// ECEF point the lines are relative to (the strike point), m.
    pub origin_ecef_m: glam::DVec3,
    /// The bolt's lines (shared between frames: a bolt is generated once).
    pub lines: std::sync::Arc<[BoltLine]>,
    /// Brightness now relative to the bolt's peak, 0..1 (the flash envelope times the strike's
    /// intensity).
    pub intensity: f32,
}

/// Rain or snow around the eye, as the renderer draws it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PrecipitationDraw {
    pub precipitation: cig_environment::Precipitation,
    /// Horizontal wind the particles drift with, east and north, m/s.
    pub wind_en_mps: [f64; 2],
    /// Seed of the particles' places.
    pub seed: u64,
}

impl FrameSnapshot {
    /// A frame with default fog (exponential, 40 km visibility) and the default 1-pixel error.
    pub fn new(unix_time_s: f64, views: Vec<View>) -> FrameSnapshot {
        FrameSnapshot {
            unix_time_s,
            views,
            fog: Fog::from_visibility(FogMode::Exponential, 40_000.0),
            ground_fog: None,
            max_pixel_error: 1.0,
            wireframe: false,
            ground_detail: true,
            culture: true,
            culture_managed: true,
            points_of_interest_deg: Vec::new(),
            entities: Vec::new(),
            puffs: Vec::new(),
            puff_origin_ecef_m: glam::DVec3::ZERO,
            cloud_cover_fraction: 0.0,
            sky: SkySettings::default(),
            stars_visible: true,
            star_intensity: 1.0,
            moon_visible: true,
            cloud_layers: Vec::new(),
            cloud_origin: cig_environment::clouds::CloudOrigin::default(),
            bolts: Vec::new(),
            flash_lux: 0.0,
            precipitation: None,
            sensors: Vec::new(),
            nvg: Vec::new(),
            lights: Vec::new(),
            street_lights: None,
            thermal: None,
            sea: None,
            wakes: Vec::new(),
            refraction_k: cig_sea::horizon::STANDARD_REFRACTION_K,
            track_gates: Vec::new(),
        }
    }

    /// The night-vision goggle of view `view_index`, unless it has a thermal sensor.
    pub fn nvg_of(&self, view_index: usize) -> Option<crate::nvg::NvgView> {
        if self.sensor_of(view_index).is_some() {
            return None;
        }
        self.nvg.get(view_index).copied().flatten()
    }

    /// The sensor of view `view_index` when it is a sensor view and the thermal state is
    /// there to draw it.
    pub fn sensor_of(
        &self,
        view_index: usize,
    ) -> Option<(crate::thermal::SensorView, &crate::thermal::ThermalScene)> {
        let sensor = self.sensors.get(view_index).copied().flatten()?;
        Some((sensor, self.thermal.as_deref()?))
    }
}

#[cfg(test)]
mod eye_tests {
    use super::*;
    use crate::view::FovDeg;
    use cig_terrain::build::{build_pyramid, BuildError};
    use cig_terrain::database::{GeoidGrid, Manifest, MemoryTileStore};
    use cig_terrain::raster::{GeoGrid, Raster};
    use cig_terrain::{Material, PagingConfig, TerrainDatabase, TileCache};
    use std::sync::Arc;

    /// A 64 x 64 post slope rising 1 m a post to the east, at 100 m above sea level in the west.
    fn slope_session() -> QuerySession {
        let grid = GeoGrid {
            south_lat_deg: 36.0,
            west_lon_deg: -121.0,
            dlat_deg: 0.0003,
            dlon_deg: 0.0003,
            rows: 64,
            cols: 64,
        };
        let raster = Raster {
            grid,
            elevation_m: (0..64 * 64).map(|i| 100.0 + (i % 64) as f32).collect(),
            material: Some(vec![Material::Grass; 64 * 64]),
        };
        let store = Arc::new(MemoryTileStore::new());
        let summary = build_pyramid::<BuildError>(&raster, 16, &mut |t| {
            store.insert(t.key, t.encode());
            Ok(())
        })
        .expect("the slope builds");
        let manifest = Manifest::from_build(&summary, GeoidGrid::zero(), 0, vec![]);
        let db = Arc::new(TerrainDatabase::new(manifest, store).expect("the slope opens"));
        QuerySession::new(Arc::new(
            TileCache::new(db, PagingConfig::default()).expect("cache"),
        ))
    }

    fn view_at(lat_deg: f64, lon_deg: f64, alt_m: f64) -> View {
        View {
            eye: Geodetic::new(lat_deg, lon_deg, alt_m),
            orientation: Hpr::default(),
            fov: FovDeg::symmetric(60.0, 45.0),
            width_px: 64,
            height_px: 48,
        }
    }

    #[test]
    fn an_eye_below_the_terrain_is_lifted_onto_it_and_reported() {
        let mut session = slope_session();
        // Post column 20 (120 m there), rows well inside; one eye 30 m under, one 50 m over,
        // one outside the database.
        let (lat, lon) = (36.0 + 30.0 * 0.0003, -121.0 + 20.0 * 0.0003);
        let mut views = vec![
            view_at(lat, lon, 90.0),
            view_at(lat, lon, 170.0),
            view_at(10.0, 10.0, -500.0),
        ];
        let before = views.clone();
        let lifted = lift_eyes_above_terrain(&mut session, &mut views);
        assert_eq!(lifted.len(), 1, "{lifted:?}");
        assert_eq!(lifted[0].view, 0);
        assert!(
            (lifted[0].height_above_terrain_m + 30.0).abs() < 0.01,
            "{lifted:?}"
        );
        let hat_after = session.hat_m(views[0].eye).expect("inside");
        assert!((hat_after - EYE_CLEARANCE_M).abs() < 1e-6, "{hat_after}");
        assert_eq!(views[1], before[1]);
        assert_eq!(views[2], before[2]);
        // Once lifted, nothing more is reported.
        assert!(lift_eyes_above_terrain(&mut session, &mut views).is_empty());
        let line = lifted[0].to_string();
        assert!(line.contains("30.0 m below the terrain"), "{line}");
    }
}

#[cfg(test)]
mod fog_layer_tests {
    use super::*;

    #[test]
    fn a_fog_layer_dims_only_the_part_of_a_ray_below_its_top() {
        let layer = FogLayer {
            top_m: 100.0,
            visibility_m: 391.2,
        };
        // Both ends above the top: clear; both below: the whole ray (extinction 0.01 / m).
        assert_eq!(layer.transmittance(200.0, 150.0, 1000.0), 1.0);
        assert!((layer.transmittance(50.0, 20.0, 100.0) - (-1.0f64).exp()).abs() < 1e-12);
        // Half the height below the top: half the ray.
        assert!((layer.transmittance(150.0, 50.0, 100.0) - (-0.5f64).exp()).abs() < 1e-12);
    }
}
