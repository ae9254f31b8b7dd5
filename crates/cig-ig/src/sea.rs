//! The sea in the IG's world: which waves the scenario and the host ask for, the surface at the
//! frame's time, and the sea's answers to height and clamping questions.
//!
//! Algorithm, per frame ([`WorldSea::update`]):
//! 1. The wind sea and swell are the scenario's `[sea]` (a WMO sea state or a wind with its
//!    fetch); without one, a fully developed sea of the host's global wind (CIGI Atmosphere
//!    Control), calm when it sets none. The sea exists when the scenario has a `[sea]` or the
//!    host enables global Maritime Surface Conditions or a Wave Control wave that applies
//!    (global, over an active region, or around an entity this IG has placed last frame: an
//!    entity's waves start on its second frame).
//! 2. The host's enabled Wave Control waves are added as explicit Gerstner waves
//!    (`cig_sea::surface::WaveComponent`); CIGI's Leading (the phase angle of the crest, ±180°)
//!    sharpens the crest, `|leading| / 90°` of a trochoid's displacement (a Gerstner wave has no
//!    forward lean). Values outside the sea model's ranges are clamped and told to the host once.
//!    A global wave applies everywhere; a regional one over its active Environmental Region
//!    (its rounded rectangle, fading out across its transition perimeter, [`region_area`]);
//!    an entity's within [`ENTITY_WAVES_RADIUS_M`] of where the entity stood last frame,
//!    fading out over [`ENTITY_WAVES_TRANSITION_M`] more ([`entity_area`]). As CIGI's regional
//!    conditions take precedence over its global ones, entities' waves take precedence over
//!    regions' and regions' over the global ones (`cig_sea::surface::WaveArea`): the height
//!    queries, line of sight, the ships and the renderer all weigh them so.
//! 3. The water's level, temperature, clarity and whitecaps: the host's Maritime Surface
//!    Conditions (a region's where the point lies in an active region, else the global ones),
//!    else the scenario's.
//! 4. The surface (`cig_sea::surface::SeaSurface`, rebuilt only when the wind sea changes) is
//!    computed at the wave clock of the world time ([`cig_scene::sea::wave_clock_s`]) in the
//!    tangent plane of the database centre's whole degrees, so every channel and IG on the
//!    database draws and answers the same waves.
//!
//! What is sea: every point off the database, and every water post at or below mean sea level
//! or the sea's level, whichever is higher (plus [`SEA_POST_TOLERANCE_M`]); lakes and rivers
//! above it keep the terrain's answer. Height
//! of terrain there is the wave surface's height above MSL with the material water and the
//! wave's normal; a clamped entity floats: its height is the sea's, and a ship's model (one
//! with a hull, `cig_scene::sea::builtin_hull`) heaves, pitches and rolls with the waves it
//! spans when clamped for attitude: its steady response to the wind sea (cached per hull,
//! heading and velocity) plus its response to the host's waves as they apply where it is,
//! and, after a change of course, speed or sea, the transient that rings down into the new
//! steady state (`cig_sea::response::ShipRide`, kept per ship, [`ShipKey`], from frame to
//! frame; forgotten after [`RIDE_FORGOTTEN_S`] unused).
//!
//! Line of sight over the sea ([`SeaNow::first_hit`]): standard terrestrial refraction
//! bends a nearly horizontal ray toward the earth with a curvature `k / R` (`k` =
//! [`STANDARD_REFRACTION_K`], 0.13, the value behind the navigation tables' 3.83 √h km
//! horizon, as `cig_sea::horizon` uses for the drawn horizon); the usual equivalent is a
//! straight sightline over an earth of effective radius `R_e = R / (1 − k)`, `R` the
//! ellipsoid's radius of curvature in the sightline's azimuth at its middle (Euler's formula).
//! At the distance `x` along a sightline of length `D` (horizontal length `D_h`), its height
//! above the sea's mean surface is `h₁ + (h₂ − h₁) x / D − (D_h / D)² x (D − x) / (2 R_e)`,
//! `h₁` and `h₂` its ends' heights above the sea's level (the geoid interpolated between the
//! ends). Without waves the first root of that parabola is the hit, exactly. With waves only
//! the stretch where the parabola comes within the crest bound (the highest point of each
//! cascade's grid, summed, plus the host's waves' amplitudes) of the mean surface is searched,
//! front to back, like the terrain's min/max quadtrees: each cascade's heights are kept as a
//! pyramid of maxima (built once per frame, when a sightline first asks: about 0.25 ms), a
//! piece of the stretch whose lowest point is above the sum of the cascades' maxima under it
//! (widened by the largest horizontal displacement, since the choppy crests move) is skipped
//! whole, others are halved down to 8 m. There the sightline is marched in steps no crest can
//! rise into: its clearance over the waves less what the shorter cascades can add (twice
//! their largest height), over the longer ones' steepest slope (each over its own
//! compression) plus the sightline's own, the best of the splits, at least 0.25 m; the first
//! sample under the surface is bisected to 1 cm. A 30 km sightline over sea state 5 takes no
//! sample of the surface where it clears the crest bound; grazing the waves for kilometres it
//! took 160 samples on average and 630 at most over 150 such sightlines (each sample inverts
//! the choppy displacement, about 0.4 µs), a CIGI answer about 0.1 to 0.2 ms in all. A hit
//! counts only where the point is sea ([`SeaNow::covers`]), so over land the terrain answers
//! (where land lies under the sightline below the crests the search goes on 8 m at a time, so
//! a hit where the sea meets that land may be up to 8 m late).
//!
//! The IG's CIGI line-of-sight answers use the waves (a periscope or a boat's sensor just
//! above the water is hidden by the crests that would hide it) and take the nearer of the
//! sea's hit and the terrain's own sightline's (bent by the same refraction,
//! [`sightline_refraction`]), the sea's search ending at the
//! terrain's hit; the terrain's hits on sea posts give way to the sea's (the terrain is asked
//! again beyond them), and a sightline that leaves the database is answered by the sea there.
//!
//! Limits: one wind sea for the whole world (the host's explicit waves may be regional or an
//! entity's; regional Maritime Surface Conditions set the level, temperature and clarity where
//! they apply, the drawn sea takes those at the eye; entity-scoped Maritime Surface Conditions
//! are kept, not applied); the renderer draws the 8 highest explicit waves; a ship that
//! appears on an IG after a change of its course carries no transient from it there; the sea
//! over a water post
//! does not test whether the post's water is connected to the open sea. Line of sight: one
//! refraction coefficient along the ray (no ducting or mirage), the parabolic approximation
//! of the earth (0.1 mm over 30 km), one sea level along the sightline (the level at its
//! middle); a line of sight vector is bent between its two ends like a segment, not launched
//! along its direction (they differ by `k x D / (2 R)`, 1 cm at 500 m of a 2 km vector); the
//! slope bound is the grids' (the surface's steepest slope between grid points may be a
//! little more), so the sightline may pass through a ripple's tip by millimetres to a
//! centimetre; after [`MAX_LOS_SAMPLES`] samples the search gives up and counts the sightline
//! blocked where its unresolved stretch begins. Over land the sightline is the terrain's, bent
//! by the same standard refraction (with or without a sea, as the eye sees it drawn); where
//! the terrain's sightline runs under the sea posts, land is looked for in steps of half a
//! post (culture objects there are not seen).

use cig_cigi::{MaritimeSurfaceConditionsControl, WaveControl};
use cig_geo::{EnuFrame, Geodetic};
use cig_scene::sea::SeaDraw;
use cig_sea::response::{ResponseCache, SeawayResponse, ShipRide};
use cig_sea::spectrum::SeaConditions;
use cig_sea::surface::{AreaKind, SeaSurface, SurfaceConfig, WaveArea, WaveComponent};
use cig_terrain::{Material, QueryError, QuerySession, SurfacePoint};
use std::sync::Arc;

pub use cig_scene::sea::SEA_POST_TOLERANCE_M;
/// The standard terrestrial refraction coefficient (0.13) the IG's line of sight over the sea
/// uses ([`SeaNow::first_hit`]), the same as the drawn horizon's.
pub use cig_sea::horizon::STANDARD_REFRACTION_K;

/// The line-of-sight march over the waves gives up after this many samples of the surface
/// (the sightline counts as blocked where it stands).
pub const MAX_LOS_SAMPLES: usize = 4096;
/// The search splits the sightline down to stretches of this, metres, then marches along
/// them in steps of at least [`LOS_MIN_STEP_M`].
const LOS_LEAF_M: f64 = 8.0;
const LOS_MIN_STEP_M: f64 = 0.25;
/// A hit is bisected to this, metres.
const LOS_TOLERANCE_M: f64 = 0.01;
/// Where the sightline is under the sea's level over land, the sea's edge is looked for in
/// steps of this, metres.
const LOS_SEA_SCAN_M: f64 = 10.0;

/// The water's settings at a point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Water {
    /// The sea surface's mean level above MSL, metres.
    pub level_msl_m: f64,
    pub temperature_c: f64,
    /// 0 turbid, 100 clear.
    pub clarity_pct: f64,
    pub whitecaps: bool,
}

impl Water {
    /// The scenario's water, or the default open sea.
    pub fn of_scenario(sea: Option<&crate::scenario::ScenarioSea>) -> Water {
        sea.map_or(
            Water {
                level_msl_m: 0.0,
                temperature_c: 15.0,
                clarity_pct: 100.0,
                whitecaps: true,
            },
            |s| Water {
                level_msl_m: s.level_m,
                temperature_c: s.water_temperature_c,
                clarity_pct: s.clarity_pct,
                whitecaps: s.whitecaps,
            },
        )
    }

    /// The host's conditions over `self` (values out of range clamped).
    pub fn with_host(self, host: Option<&MaritimeSurfaceConditionsControl>) -> Water {
        let Some(m) = host.filter(|m| m.surface_conditions_enable) else {
            return self;
        };
        Water {
            level_msl_m: host_value(m.sea_surface_height_m, -20.0, 20.0, self.level_msl_m),
            temperature_c: host_value(
                m.surface_water_temperature_c,
                -2.0,
                40.0,
                self.temperature_c,
            ),
            clarity_pct: host_value(m.surface_clarity_pct, 0.0, 100.0, self.clarity_pct),
            whitecaps: m.whitecap_enable,
        }
    }

    /// The water body's colour: Morel's clear ocean (about 2 % reflectance in the blue, under
    /// 0.5 % in the red) toward a turbid coastal green as the clarity falls.
    pub fn body_rgb(&self) -> [f32; 3] {
        let clear = [0.004_f32, 0.016, 0.028];
        let turbid = [0.020_f32, 0.036, 0.030];
        let t = (self.clarity_pct / 100.0).clamp(0.0, 1.0) as f32;
        [0, 1, 2].map(|i| turbid[i] + (clear[i] - turbid[i]) * t)
    }
}

/// A host's value inside `lo..=hi` (clamped into it), or `fallback` where it is not finite.
fn host_value(v: f32, lo: f64, hi: f64, fallback: f64) -> f64 {
    let v = f64::from(v);
    if v.is_finite() {
        v.clamp(lo, hi)
    } else {
        fallback
    }
}

/// A host wave as the sea model takes it, and whether any value had to be clamped.
pub fn wave_component(w: &WaveControl) -> (WaveComponent, bool) {
    let mut clamped = false;
    let mut fit = |v: f32, lo: f64, hi: f64, fallback: f64| {
        let fitted = host_value(v, lo, hi, fallback);
        clamped |= fitted != f64::from(v);
        fitted
    };
    let height_m = fit(w.height_m, 0.0, 30.0, 0.0);
    let wavelength_m = fit(w.wavelength_m, 0.1, 5000.0, 100.0);
    let period_s = fit(w.period_s, 0.1, 100.0, 8.0);
    let direction_deg = fit(w.direction_deg, -1.0e6, 1.0e6, 0.0);
    let phase_deg = fit(w.phase_offset_deg, -1.0e6, 1.0e6, 0.0);
    let leading_deg = fit(w.leading_deg, -180.0, 180.0, 0.0);
    let wave = WaveComponent {
        height_m,
        wavelength_m,
        period_s,
        direction_deg: direction_deg.rem_euclid(360.0),
        phase_deg: phase_deg.rem_euclid(360.0),
        leading: (leading_deg.abs() / 90.0).min(1.0),
    };
    (wave, clamped)
}

/// A host's wave: its key (scope, entity or region, wave), the packet, the area it applies in.
type HostWave<'a> = (&'a (u8, u16, u8), &'a WaveControl, Option<usize>);

/// CIGI's scopes of Wave Control (and the other environment packets).
const SCOPE_GLOBAL: u8 = 0;
const SCOPE_REGIONAL: u8 = 1;
const SCOPE_ENTITY: u8 = 2;

/// An entity's waves (CIGI Wave Control of entity scope) apply in full within this distance of
/// it, metres...
pub const ENTITY_WAVES_RADIUS_M: f64 = 1000.0;
/// ...and fade out over this much further, metres.
pub const ENTITY_WAVES_TRANSITION_M: f64 = 1000.0;

/// The area of the sea's plane a CIGI environmental region covers: its rounded rectangle
/// (sizes, rotation, corner radius) and its transition perimeter, centred where its centre
/// falls in the plane (the region's rotation is taken from true north at its centre; the
/// plane's north differs by the meridians' convergence, under a degree within 100 km of the
/// plane's origin at mid-latitudes). Host values out of range are clamped.
pub fn region_area(plane: &EnuFrame, region: &cig_cigi::EnvironmentalRegionControl) -> WaveArea {
    let size = |v: f32| host_value(v, 0.0, 2.0e7, 0.0);
    WaveArea {
        centre_m: area_centre_m(plane, region.latitude_deg, region.longitude_deg),
        half_size_m: [size(region.size_x_m) / 2.0, size(region.size_y_m) / 2.0],
        rotation_deg: host_value(region.rotation_deg, -1.0e6, 1.0e6, 0.0),
        corner_radius_m: host_value(region.corner_radius_m, 0.0, 1.0e7, 0.0),
        transition_m: host_value(region.transition_perimeter_m, 0.0, 1.0e7, 0.0),
        kind: AreaKind::Region,
    }
}

/// Where a host's point falls in the sea's plane, within the range `WaveArea` takes (a
/// non-finite one at the origin).
fn area_centre_m(plane: &EnuFrame, lat_deg: f64, lon_deg: f64) -> [f64; 2] {
    cig_scene::sea::sea_plane_xy(plane, lat_deg, lon_deg).map(|v| {
        if v.is_finite() {
            v.clamp(-1e9, 1e9)
        } else {
            0.0
        }
    })
}

/// The area around an entity at (`lat_deg`, `lon_deg`) its waves cover: a disc of
/// [`ENTITY_WAVES_RADIUS_M`] fading out over [`ENTITY_WAVES_TRANSITION_M`].
pub fn entity_area(plane: &EnuFrame, lat_deg: f64, lon_deg: f64) -> WaveArea {
    WaveArea {
        centre_m: area_centre_m(plane, lat_deg, lon_deg),
        half_size_m: [0.0, 0.0],
        rotation_deg: 0.0,
        corner_radius_m: ENTITY_WAVES_RADIUS_M,
        transition_m: ENTITY_WAVES_TRANSITION_M,
        kind: AreaKind::Entity,
    }
}

/// The sea at the frame's time.
pub struct SeaNow {
    surface: SeaSurface,
    draw: Arc<SeaDraw>,
    plane: EnuFrame,
    /// The scenario's water under the host's global conditions.
    water: Water,
    /// The surface's bounds for the line of sight, computed when first asked.
    bounds: std::sync::OnceLock<WaveBounds>,
    /// The ships' responses to this wind sea and swell, kept from frame to frame while they
    /// last (the host's waves are each ship's own, `SeaNow::ride`).
    responses: Arc<std::sync::Mutex<ResponseCache>>,
    /// The ships' rides, kept from frame to frame (and across changes of the waves).
    rides: Arc<std::sync::Mutex<Rides>>,
}

/// Which ship a ride belongs to: one of this IG's entities or one of the DIS exercise's.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum ShipKey {
    /// A CIGI entity of this IG, by its id.
    Own(u16),
    /// A DIS exercise's entity, by the IG's instance id for it.
    Remote(u32),
}

/// A ship's ride, the hull it is of, and where (in the sea's plane, metres) and when (sea
/// time, seconds) it was last used.
#[derive(Clone, Debug)]
struct KeptRide {
    ride: ShipRide,
    hull: [u64; 7],
    at_m: [f64; 2],
    used_s: f64,
}

/// The ships' rides by ship.
type Rides = std::collections::BTreeMap<ShipKey, KeptRide>;

/// A ride not used for this long (sea time, seconds) is forgotten: the ship starts again in
/// the steady state when it comes back.
pub const RIDE_FORGOTTEN_S: f64 = 10.0;

impl SeaNow {
    /// What the renderer draws.
    pub fn draw(&self) -> &Arc<SeaDraw> {
        &self.draw
    }

    /// The wave surface at the frame's time.
    pub fn surface(&self) -> &SeaSurface {
        &self.surface
    }

    /// The water where no region sets its own.
    pub fn water(&self) -> Water {
        self.water
    }

    /// The sea's surface at a point (its mean level `level_msl_m`), as a terrain answer: the
    /// wave height above MSL, material water, the wave's normal.
    pub fn surface_point(
        &self,
        lat_deg: f64,
        lon_deg: f64,
        level_msl_m: f64,
        geoid_m: f64,
    ) -> SurfacePoint {
        let [x, y] = cig_scene::sea::sea_plane_xy(&self.plane, lat_deg, lon_deg);
        let sample = self.surface.sample(x, y);
        SurfacePoint {
            lat_deg,
            lon_deg,
            height_msl_m: level_msl_m + sample.height_m,
            geoid_undulation_m: geoid_m,
            normal_enu: sample.normal,
            material: Material::Water,
            level: 0,
        }
    }

    /// Whether the terrain's answer at a point (`Err` off the database) is sea when the sea
    /// stands at `level_msl_m`: off the database, or a water post no higher than MSL or the
    /// level (a database's sea posts lie at MSL whatever the tide).
    pub fn covers(terrain: &Result<SurfacePoint, QueryError>, level_msl_m: f64) -> bool {
        match terrain {
            Err(QueryError::Outside { .. }) => true,
            Ok(s) => {
                s.material == Material::Water
                    && s.height_msl_m <= level_msl_m.max(0.0) + SEA_POST_TOLERANCE_M
            }
            Err(_) => false,
        }
    }

    /// Height of the surface at a point: the sea's where it is sea, else the terrain's.
    ///
    /// # Errors
    /// The terrain's, where the point is not sea.
    pub fn hot(
        &self,
        query: &mut QuerySession,
        lat_deg: f64,
        lon_deg: f64,
        level_msl_m: f64,
    ) -> Result<SurfacePoint, QueryError> {
        let terrain = query.hot(lat_deg, lon_deg);
        if SeaNow::covers(&terrain, level_msl_m) && lat_deg.abs() <= 90.0 && lon_deg.is_finite() {
            let geoid_m = query.geoid_undulation_m(lat_deg, lon_deg);
            return Ok(self.surface_point(lat_deg, lon_deg, level_msl_m, geoid_m));
        }
        terrain
    }
}

/// How a sightline sees the sea ([`SeaNow::first_hit`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SeaSightline {
    /// The sea's mean level above MSL along the sightline, metres.
    pub level_msl_m: f64,
    /// The geoid's undulation at the sightline's start and end, metres (linear between).
    pub geoid_m: [f64; 2],
    /// The refraction coefficient `k`, `-1..=0.9` (0: a geometric sightline; the IG answers
    /// with [`STANDARD_REFRACTION_K`]).
    pub refraction_k: f64,
    /// Whether the waves stop the sightline (else the sea's calm mean surface).
    pub with_waves: bool,
    /// How far from the start to look, metres (`f64::INFINITY`: to the end), e.g. to the
    /// terrain's own hit.
    pub max_range_m: f64,
}

/// Where a sightline first meets the sea.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SeaHit {
    /// The point on the sea's surface; altitude above the ellipsoid.
    pub point: Geodetic,
    /// Distance from the sightline's start, metres.
    pub range_m: f64,
    /// The surface's height above MSL there, metres.
    pub height_msl_m: f64,
    /// The surface's unit normal there (east, north, up).
    pub normal_enu: [f64; 3],
}

/// Bounds of the surface at the frame's time, for the line-of-sight search.
#[derive(Debug)]
struct WaveBounds {
    /// No point of the surface is higher than this above its mean, metres.
    crest_m: f64,
    /// Each cascade's heights as a pyramid of maxima.
    pyramids: Vec<MaxPyramid>,
    /// The host's waves' amplitudes, summed, metres.
    explicit_m: f64,
    /// No surface point is displaced further than this horizontally, metres.
    displacement_m: f64,
    /// How far the surface may rise along a step of `s` metres: by `rise + slope · s` for
    /// each pair; the first cascades' steepest slopes (each over its own compression) and the
    /// host's waves' summed, the others' (shorter) waves by twice their largest height.
    rises: Vec<(f64, f64)>,
}

/// A cascade's heights as a pyramid of maxima: level 0 the grid's points, each next level the
/// maximum of 2 × 2 nodes of the one below, to one node (the tile is periodic).
#[derive(Debug)]
struct MaxPyramid {
    tile_m: f64,
    size: usize,
    levels: Vec<Vec<f32>>,
}

impl MaxPyramid {
    fn new(grid: &cig_sea::surface::CascadeGrid) -> MaxPyramid {
        let mut levels = vec![grid
            .height_displacement
            .iter()
            .map(|v| v[0])
            .collect::<Vec<f32>>()];
        let mut side = grid.size;
        while side > 1 {
            let below = levels.last().map_or(&[][..], |l| l.as_slice());
            let half = side / 2;
            let mut level = Vec::with_capacity(half * half);
            for j in 0..half {
                for i in 0..half {
                    let at = |di: usize, dj: usize| below[(2 * j + dj) * side + 2 * i + di];
                    level.push(at(0, 0).max(at(1, 0)).max(at(0, 1)).max(at(1, 1)));
                }
            }
            levels.push(level);
            side = half;
        }
        MaxPyramid {
            tile_m: grid.tile_m,
            size: grid.size,
            levels,
        }
    }

    /// The highest the cascade's surface reaches anywhere.
    fn top(&self) -> f32 {
        self.levels
            .last()
            .and_then(|l| l.first())
            .copied()
            .unwrap_or(0.0)
    }

    /// The highest the cascade's (bilinear) surface reaches at undisplaced positions in the box
    /// `x0..=x1` east, `y0..=y1` north (metres).
    fn max_in(&self, [x0, x1, y0, y1]: [f64; 4]) -> f32 {
        let top = self.top();
        let cell = self.tile_m / self.size as f64;
        // The points the box's cells interpolate from.
        let (px0, px1) = ((x0 / cell).floor(), (x1 / cell).floor() + 1.0);
        let (py0, py1) = ((y0 / cell).floor(), (y1 / cell).floor() + 1.0);
        let span = (px1 - px0).max(py1 - py0) + 1.0;
        let inside = span < self.size as f64 && px0.abs() < 1e12 && py0.abs() < 1e12;
        if !inside {
            return top;
        }
        // Nodes at least half the span: up to 3 × 3 of them.
        let level = ((span.log2().ceil() as usize).max(1) - 1).min(self.levels.len() - 1);
        let side = (1_i64 << level) as f64;
        let nodes = (self.size >> level) as i64;
        let grid = &self.levels[level];
        let (ix0, ix1) = ((px0 / side).floor() as i64, (px1 / side).floor() as i64);
        let (iy0, iy1) = ((py0 / side).floor() as i64, (py1 / side).floor() as i64);
        let mut max = f32::NEG_INFINITY;
        for iy in iy0..=iy1 {
            for ix in ix0..=ix1 {
                let k = iy.rem_euclid(nodes) * nodes + ix.rem_euclid(nodes);
                max = max.max(grid[k as usize]);
            }
        }
        max
    }
}

/// A straight sightline over the effective earth, by the distance `x` along it.
struct Chord {
    a: glam::DVec3,
    dir: glam::DVec3,
    length_m: f64,
    /// Height of the start above the sea's mean surface, and its rate along the chord.
    h1: f64,
    slope: f64,
    /// The bulge's coefficient: the earth rises `curvature · x (D − x)` under the chord.
    curvature: f64,
    geoid_m: f64,
    geoid_rate: f64,
}

impl Chord {
    fn height(&self, x: f64) -> f64 {
        self.h1 + self.slope * x - self.curvature * x * (self.length_m - x)
    }

    /// The lowest the chord is over `x0..=x1` (it is convex).
    fn lowest(&self, x0: f64, x1: f64) -> f64 {
        let vertex = if self.curvature > 0.0 {
            0.5 * (self.length_m - self.slope / self.curvature)
        } else {
            x0
        };
        self.height(x0)
            .min(self.height(x1))
            .min(self.height(vertex.clamp(x0, x1)))
    }

    fn height_rate(&self, x: f64) -> f64 {
        self.slope - self.curvature * (self.length_m - 2.0 * x)
    }

    fn at(&self, x: f64) -> Geodetic {
        Geodetic::from_ecef(self.a + self.dir * x)
    }

    /// The stretch of the chord (`0..=D`) no higher than `top` above the mean surface.
    fn below(&self, top: f64) -> Option<(f64, f64)> {
        // curvature x² + (slope − curvature D) x + (h1 − top) ≤ 0.
        let (qa, qb, qc) = (
            self.curvature,
            self.slope - self.curvature * self.length_m,
            self.h1 - top,
        );
        let (lo, hi) = if qa > 1e-15 {
            let disc = qb * qb - 4.0 * qa * qc;
            if disc < 0.0 {
                return None;
            }
            let q = -0.5 * (qb + disc.sqrt().copysign(qb));
            if q == 0.0 {
                (0.0, 0.0)
            } else {
                let (r1, r2) = (q / qa, qc / q);
                (r1.min(r2), r1.max(r2))
            }
        } else if qb > 0.0 {
            (f64::NEG_INFINITY, -qc / qb)
        } else if qb < 0.0 {
            (-qc / qb, f64::INFINITY)
        } else if qc <= 0.0 {
            (f64::NEG_INFINITY, f64::INFINITY)
        } else {
            return None;
        };
        let (lo, hi) = (lo.max(0.0), hi.min(self.length_m));
        (lo <= hi).then_some((lo, hi))
    }
}

/// The standard refraction ([`STANDARD_REFRACTION_K`]) of the sightline from `a` to `b`, with
/// the earth's radius of curvature in its azimuth at its middle: what the terrain's line of
/// sight bends by where the sea's does.
pub fn sightline_refraction(a: Geodetic, b: Geodetic) -> cig_terrain::Refraction {
    sightline_refraction_with_k(a, b, STANDARD_REFRACTION_K)
}

/// [`sightline_refraction`] with the coefficient `k` (0: a straight sightline).
pub fn sightline_refraction_with_k(a: Geodetic, b: Geodetic, k: f64) -> cig_terrain::Refraction {
    let (ea, eb) = (a.to_ecef(), b.to_ecef());
    let mid = Geodetic::from_ecef((ea + eb) * 0.5);
    let along = EnuFrame::new(mid).ecef_vector_to_enu(eb - ea);
    cig_terrain::Refraction {
        k,
        earth_radius_m: radius_of_curvature_m(mid.lat_deg, along.x, along.y),
    }
}

/// The WGS84 ellipsoid's radius of curvature, metres, at `lat_deg` in the azimuth of the
/// horizontal direction (`east`, `north`) (Euler's formula; the Gaussian mean radius for no
/// horizontal direction).
fn radius_of_curvature_m(lat_deg: f64, east: f64, north: f64) -> f64 {
    let s = lat_deg.to_radians().sin();
    let w2 = 1.0 - cig_geo::WGS84_E2 * s * s;
    let prime_vertical = cig_geo::WGS84_A_M / w2.sqrt();
    let meridian = prime_vertical * (1.0 - cig_geo::WGS84_E2) / w2;
    let h2 = east * east + north * north;
    if h2 > 0.0 {
        1.0 / (north * north / h2 / meridian + east * east / h2 / prime_vertical)
    } else {
        (meridian * prime_vertical).sqrt()
    }
}

impl SeaNow {
    /// The surface's bounds (computed once per frame's sea, when a sightline first asks).
    fn bounds(&self) -> &WaveBounds {
        self.bounds.get_or_init(|| {
            let grids = self.surface.grids();
            let pyramids: Vec<MaxPyramid> = grids.iter().map(MaxPyramid::new).collect();
            let mut bounds = WaveBounds {
                crest_m: pyramids.iter().map(|p| f64::from(p.top())).sum(),
                pyramids,
                explicit_m: 0.0,
                displacement_m: 0.0,
                rises: Vec::new(),
            };
            let mut cascades = Vec::new();
            for grid in grids {
                // Squares, rooted once: the largest displacement, the displaced surface's
                // steepest slope (the height's over the compression), the largest height.
                let (mut displaced, mut steepest, mut highest) = (0.0_f32, 0.0_f32, 0.0_f32);
                for (v, s) in grid.height_displacement.iter().zip(&grid.slopes) {
                    let compression = v[3].max(0.3);
                    displaced = displaced.max(v[1] * v[1] + v[2] * v[2]);
                    steepest =
                        steepest.max((s[0] * s[0] + s[1] * s[1]) / (compression * compression));
                    highest = highest.max(v[0].abs());
                }
                let (displaced, steepest) = (displaced.sqrt(), steepest.sqrt());
                bounds.displacement_m += f64::from(displaced);
                cascades.push((2.0 * f64::from(highest), f64::from(steepest)));
            }
            let mut explicit_slope = 0.0;
            let waves = self.surface.explicit_waves();
            let compression: f64 = waves
                .iter()
                .map(|w| std::f64::consts::PI * w.height_m * w.leading / w.wavelength_m)
                .sum();
            // A wave confined to an area also rises across the area's band: by at most
            // 1.5 / band of its amplitude a metre (smoothstep's steepest slope).
            let bands = self.surface.wave_areas();
            for (w, area) in waves.iter().zip(self.surface.explicit_wave_areas()) {
                bounds.explicit_m += 0.5 * w.height_m;
                bounds.displacement_m += 0.5 * w.height_m * w.leading;
                explicit_slope += std::f64::consts::PI * w.height_m
                    / w.wavelength_m
                    / (1.0 - compression).max(0.1);
                if let Some(band) = area.and_then(|i| bands.get(i)) {
                    explicit_slope += 0.5 * w.height_m * 1.5 / band.band_m();
                }
            }
            // Global and regional waves fade where areas take precedence over them: by at
            // most the areas' slopes summed.
            let fading: f64 = bands.iter().map(|b| 1.5 / b.band_m()).sum();
            explicit_slope += waves.iter().map(|w| 0.5 * w.height_m).sum::<f64>() * fading;
            bounds.rises = (0..=cascades.len())
                .map(|m| {
                    let (long, short) = cascades.split_at(m);
                    (
                        short.iter().map(|c| c.0).sum(),
                        explicit_slope + long.iter().map(|c| c.1).sum::<f64>(),
                    )
                })
                .collect();
            bounds.crest_m += bounds.explicit_m;
            bounds
        })
    }

    /// The highest the surface reaches over the plane's segment from `p` to `q` (east, north,
    /// metres): each cascade's maximum in the box around the segment widened by the largest
    /// displacement, plus the host's waves' amplitudes.
    fn highest_over(&self, bounds: &WaveBounds, p: glam::DVec3, q: glam::DVec3) -> f64 {
        // A margin for the ground's plane coordinates taken as linear along the sightline.
        let widen = bounds.displacement_m + 1.0;
        let bbox = [
            p.x.min(q.x) - widen,
            p.x.max(q.x) + widen,
            p.y.min(q.y) - widen,
            p.y.max(q.y) + widen,
        ];
        bounds
            .pyramids
            .iter()
            .map(|pyramid| f64::from(pyramid.max_in(bbox)))
            .sum::<f64>()
            + bounds.explicit_m
    }

    /// Where the sightline from `from` to `to` (altitudes above the ellipsoid) first meets the
    /// sea, as the module doc describes: the refracted sightline against the waves (or the calm
    /// mean surface), counted only where `is_sea(lat_deg, lon_deg)`. `None`: it does not meet
    /// the sea (after [`MAX_LOS_SAMPLES`] samples the march gives up: blocked where the
    /// stretch it could not resolve begins).
    pub fn first_hit(
        &self,
        from: Geodetic,
        to: Geodetic,
        sightline: &SeaSightline,
        mut is_sea: impl FnMut(f64, f64) -> bool,
    ) -> Option<SeaHit> {
        let (a, b) = (from.to_ecef(), to.to_ecef());
        let length_m = (b - a).length();
        let k = sightline.refraction_k;
        let [g1, g2] = sightline.geoid_m;
        let level = sightline.level_msl_m;
        if !(length_m > 1e-3
            && length_m.is_finite()
            && sightline.max_range_m >= 0.0
            && (-1.0..=0.9).contains(&k)
            && g1.is_finite()
            && g2.is_finite()
            && level.is_finite())
        {
            return None;
        }
        let h1 = from.alt_m - g1 - level;
        let h2 = to.alt_m - g2 - level;
        // The earth under the sightline: the ellipsoid's curvature in its azimuth at its
        // middle, on its horizontal length, over the effective radius R / (1 - k).
        let mid = Geodetic::from_ecef((a + b) * 0.5);
        let along = EnuFrame::new(mid).ecef_vector_to_enu(b - a);
        let horizontal = (along.x * along.x + along.y * along.y) / (length_m * length_m);
        let radius = radius_of_curvature_m(mid.lat_deg, along.x, along.y);
        let chord = Chord {
            a,
            dir: (b - a) / length_m,
            length_m,
            h1,
            slope: (h2 - h1) / length_m,
            curvature: (1.0 - k) * horizontal / (2.0 * radius),
            geoid_m: g1,
            geoid_rate: (g2 - g1) / length_m,
        };
        let hit = |x: f64, p: Geodetic, height_m: f64, normal_enu: [f64; 3]| SeaHit {
            point: Geodetic::new(
                p.lat_deg,
                p.lon_deg,
                level + height_m + chord.geoid_m + chord.geoid_rate * x,
            ),
            range_m: x,
            height_msl_m: level + height_m,
            normal_enu,
        };
        let waves = if sightline.with_waves {
            Some(self.bounds()).filter(|b| b.crest_m > 0.0)
        } else {
            None
        };
        let Some(bounds) = waves else {
            // The mean surface: the parabola's first root, then the sea's edge if it is land.
            let (lo, hi) = chord.below(0.0)?;
            let hi = hi.min(sightline.max_range_m);
            if lo > hi {
                return None;
            }
            let mut sea_at = |x: f64| {
                let p = chord.at(x);
                is_sea(p.lat_deg, p.lon_deg)
            };
            let mut x = lo;
            if !sea_at(lo) {
                let mut land = lo;
                let steps = ((hi - lo) / LOS_SEA_SCAN_M)
                    .ceil()
                    .min(MAX_LOS_SAMPLES as f64);
                let found = (1..=steps as usize).find_map(|i| {
                    let next = (lo + i as f64 * LOS_SEA_SCAN_M).min(hi);
                    if sea_at(next) {
                        Some(next)
                    } else {
                        land = next;
                        None
                    }
                });
                x = found?;
                while x - land > LOS_TOLERANCE_M {
                    let m = 0.5 * (land + x);
                    if sea_at(m) {
                        x = m;
                    } else {
                        land = m;
                    }
                }
            }
            return Some(hit(x, chord.at(x), 0.0, [0.0, 0.0, 1.0]));
        };
        let (lo, hi) = chord.below(bounds.crest_m)?;
        let hi = hi.min(sightline.max_range_m);
        if lo > hi {
            return None;
        }
        let plane_at = |x: f64| {
            let p = chord.at(x);
            let ground = Geodetic::new(p.lat_deg, p.lon_deg, 0.0);
            (p, self.plane.geodetic_to_enu(ground))
        };
        // The plane's coordinates of the ground under the chord: linear between the stretch's
        // ends (the chord is within metres of the sea there, so this is off by about a
        // centimetre over 30 km: the margin in `highest_over` covers it; a hit is sampled
        // again at its exact place).
        let (start, end) = (plane_at(lo).1, plane_at(hi).1);
        let ground = |x: f64| start + (end - start) * ((x - lo) / (hi - lo).max(1e-9));
        let samples = std::cell::Cell::new(0);
        let gap_at = |x: f64| {
            samples.set(samples.get() + 1);
            let at = ground(x);
            chord.height(x) - self.surface.sample(at.x, at.y).height_m
        };
        // The last point known clear of the waves.
        let mut clear: Option<f64> = None;
        // Front to back: the stretches still to search, the nearest on top.
        let mut stack = vec![(lo, hi)];
        while let Some((x0, x1)) = stack.pop() {
            if samples.get() >= MAX_LOS_SAMPLES {
                // Given up: blocked (the safe answer for a sightline that grazes the crests
                // this long) where the unresolved stretch begins, over the sea.
                let (p, at) = plane_at(x0);
                if is_sea(p.lat_deg, p.lon_deg) {
                    let s = self.surface.sample(at.x, at.y);
                    return Some(hit(x0, p, s.height_m, s.normal));
                }
                return None;
            }
            let highest = self.highest_over(bounds, ground(x0), ground(x1));
            if chord.lowest(x0, x1) > highest {
                clear = Some(x1);
                continue;
            }
            if x1 - x0 > LOS_LEAF_M {
                let m = 0.5 * (x0 + x1);
                stack.push((m, x1));
                stack.push((x0, m));
                continue;
            }
            // A leaf: march in steps no crest can rise into (the slope bound), bisect a hit.
            let mut x = x0;
            loop {
                let gap = gap_at(x);
                if gap <= 0.0 {
                    let mut under = x;
                    if let Some(mut over) = clear {
                        while under - over > LOS_TOLERANCE_M && samples.get() < MAX_LOS_SAMPLES {
                            let m = 0.5 * (over + under);
                            if gap_at(m) <= 0.0 {
                                under = m;
                            } else {
                                over = m;
                            }
                        }
                    }
                    let (p, at) = plane_at(under);
                    if is_sea(p.lat_deg, p.lon_deg) {
                        let s = self.surface.sample(at.x, at.y);
                        return Some(hit(under, p, s.height_m, s.normal));
                    }
                    // Land under the sightline: the terrain answers there; search on, a leaf
                    // at a time.
                    clear = None;
                    if x >= x1 || samples.get() >= MAX_LOS_SAMPLES {
                        break;
                    }
                    x = (x + LOS_LEAF_M).min(x1);
                    continue;
                }
                clear = Some(x);
                if x >= x1 || samples.get() >= MAX_LOS_SAMPLES {
                    break;
                }
                let rate = chord.height_rate(x).abs();
                let step = bounds
                    .rises
                    .iter()
                    .map(|&(rise, slope)| (gap - rise) / (rate + slope).max(1e-9))
                    .fold(f64::NEG_INFINITY, f64::max);
                x = (x + step.clamp(LOS_MIN_STEP_M, LOS_LEAF_M)).min(x1);
            }
        }
        None
    }
}

/// The sea's state over a run.
pub struct WorldSea {
    /// The scenario's wind sea and swell, if it has a `[sea]`.
    scenario_conditions: Option<SeaConditions>,
    scenario_water: Water,
    seed: u64,
    /// Explicit waves of the sea's own (`cig render --sea-wave`), before the host's.
    own_waves: Vec<WaveComponent>,
    /// Explicit waves of the sea's own confined to regions, before the host's.
    own_regional_waves: Vec<(WaveComponent, cig_cigi::EnvironmentalRegionControl)>,
    /// Waves already told to the host as clamped.
    told_waves: std::collections::BTreeSet<(u8, u16, u8)>,
    now: Option<Arc<SeaNow>>,
    /// The ships' responses to the present wind sea and swell (made anew when they change).
    responses: Option<Arc<std::sync::Mutex<ResponseCache>>>,
    /// The ships' rides (their transients outlive a change of the waves).
    rides: Arc<std::sync::Mutex<Rides>>,
}

/// Why the sea could not be updated (told to the host once by the caller).
#[derive(Debug, thiserror::Error)]
pub enum WorldSeaError {
    #[error("the sea: {0}")]
    Sea(#[from] cig_sea::SeaError),
}

impl WorldSea {
    /// The sea a scenario describes (checked when it was parsed).
    pub fn new(scenario: Option<&crate::scenario::ScenarioSea>) -> WorldSea {
        WorldSea::of_conditions(
            scenario.and_then(|s| s.conditions().ok()),
            Water::of_scenario(scenario),
            scenario.map_or(1, |s| s.seed),
        )
    }

    /// A sea of these waves and water (`conditions`: the wind sea and swell; `None`: only
    /// when the host asks for one), its random amplitudes from `seed`.
    pub fn of_conditions(conditions: Option<SeaConditions>, water: Water, seed: u64) -> WorldSea {
        WorldSea {
            scenario_conditions: conditions,
            scenario_water: water,
            seed,
            own_waves: Vec::new(),
            own_regional_waves: Vec::new(),
            told_waves: std::collections::BTreeSet::new(),
            now: None,
            responses: None,
            rides: Arc::default(),
        }
    }

    /// Adds explicit waves of the sea's own (the host's are added to them).
    ///
    /// # Errors
    /// A wave out of range (see `cig_sea::surface::WaveComponent::new`).
    pub fn with_waves(mut self, waves: Vec<WaveComponent>) -> Result<WorldSea, WorldSeaError> {
        for wave in &waves {
            wave.validate()?;
        }
        self.own_waves = waves;
        Ok(self)
    }

    /// Adds explicit waves of the sea's own, each applying only over its region (as a host's
    /// regional Wave Control would; `cig render --sea-wave ...@REGION`).
    ///
    /// # Errors
    /// A wave out of range (see `cig_sea::surface::WaveComponent::new`).
    pub fn with_regional_waves(
        mut self,
        waves: Vec<(WaveComponent, cig_cigi::EnvironmentalRegionControl)>,
    ) -> Result<WorldSea, WorldSeaError> {
        for (wave, _) in &waves {
            wave.validate()?;
        }
        self.own_regional_waves = waves;
        Ok(self)
    }

    /// The sea at the frame's time (after [`WorldSea::update`]), if there is one.
    pub fn now(&self) -> Option<&Arc<SeaNow>> {
        self.now.as_ref()
    }

    /// Computes the sea at `unix_time_s` for the host's environment, in the tangent plane of
    /// `origin` (`entity_poses`: where this IG's entities are, for the host's entity-scoped
    /// waves); returns the host waves whose values had to be clamped (each told once). The
    /// surface is rebuilt only when the wind sea changes, and reused in place when no one else
    /// holds the last frame's sea.
    ///
    /// # Errors
    /// When the surface cannot be built or computed (the sea is then gone this frame).
    pub fn update(
        &mut self,
        environment: &crate::session::EnvironmentState,
        eye_msl: Option<Geodetic>,
        origin: Geodetic,
        unix_time_s: f64,
        entity_poses: &std::collections::BTreeMap<u16, crate::pose::Pose>,
    ) -> Result<Vec<String>, WorldSeaError> {
        let host_global = environment
            .maritime
            .get(&(0, 0))
            .filter(|m| m.surface_conditions_enable);
        let plane = EnuFrame::new(origin);
        // The host's enabled waves with where each applies: everywhere, an active region, or
        // around an entity this IG has placed (one area per region or entity).
        let mut areas: Vec<WaveArea> = Vec::new();
        let mut area_of: std::collections::BTreeMap<(u8, u16), usize> =
            std::collections::BTreeMap::new();
        let mut host_waves: Vec<HostWave> = Vec::new();
        for (key, w) in environment.waves.iter().filter(|(_, w)| w.wave_enable) {
            let (scope, id) = (key.0, key.1);
            let area = match scope {
                SCOPE_GLOBAL => None,
                SCOPE_REGIONAL | SCOPE_ENTITY => {
                    let shape = if scope == SCOPE_REGIONAL {
                        environment
                            .regions
                            .get(&id)
                            .filter(|r| r.region_state == 1)
                            .map(|r| region_area(&plane, r))
                    } else {
                        entity_poses
                            .get(&id)
                            .map(|p| entity_area(&plane, p.position.lat_deg, p.position.lon_deg))
                    };
                    let Some(shape) = shape else { continue };
                    Some(*area_of.entry((scope, id)).or_insert_with(|| {
                        areas.push(shape);
                        areas.len() - 1
                    }))
                }
                _ => continue,
            };
            host_waves.push((key, w, area));
        }
        let present = self.scenario_conditions.is_some()
            || host_global.is_some()
            || !host_waves.is_empty()
            || !self.own_waves.is_empty()
            || !self.own_regional_waves.is_empty();
        if !present {
            self.now = None;
            return Ok(Vec::new());
        }
        let conditions = match &self.scenario_conditions {
            Some(c) => c.clone(),
            None => {
                let (speed, from) = environment.atmosphere.as_ref().map_or((0.0, 270.0), |a| {
                    (
                        host_value(a.horizontal_wind_speed_mps, 0.0, 60.0, 0.0),
                        host_value(a.wind_direction_deg, -1.0e6, 1.0e6, 270.0),
                    )
                });
                // In steps of 0.5 m/s and 5 degrees: a gusting host wind does not rebuild
                // the surface (and make its waves jump) every frame.
                SeaConditions::new(
                    (speed * 2.0).round() / 2.0,
                    ((from / 5.0).round() * 5.0).rem_euclid(360.0),
                )?
            }
        };
        let mut told = Vec::new();
        let mut waves = self.own_waves.clone();
        let mut placed = vec![None; waves.len()];
        for (wave, region) in &self.own_regional_waves {
            areas.push(region_area(&plane, region));
            waves.push(*wave);
            placed.push(Some(areas.len() - 1));
        }
        for (key, w, area) in host_waves {
            let (wave, clamped) = wave_component(w);
            if clamped && self.told_waves.insert(*key) {
                told.push(format!(
                    "Wave Control {}: clamped to height 0-30 m, length 0.1-5000 m, period 0.1-100 s",
                    key.2
                ));
            }
            waves.push(wave);
            placed.push(area);
        }
        let last = self.now.take().map(|now| {
            Arc::try_unwrap(now).map_or_else(|shared| shared.surface.clone(), |own| own.surface)
        });
        let mut surface = match last {
            Some(s) if *s.conditions() == conditions => s,
            _ => {
                self.responses = None;
                SeaSurface::new(&conditions, self.seed, SurfaceConfig::default())?
            }
        };
        // The ships' cached responses are to the wind sea and swell alone: the host's waves,
        // which apply by place, are each ship's own (`SeaNow::ride`).
        if surface.explicit_waves() != waves.as_slice()
            || surface.explicit_wave_areas() != placed.as_slice()
            || surface.wave_areas() != areas.as_slice()
        {
            surface.set_placed_waves(waves, placed, areas)?;
        }
        surface.update(cig_scene::sea::wave_clock_s(unix_time_s))?;
        let water = self.scenario_water.with_host(host_global);
        let at_eye = eye_msl
            .and_then(|eye| environment.maritime_at(eye))
            .map_or(water, |m| self.scenario_water.with_host(Some(m)));
        let mut draw = SeaDraw::new(&surface, origin, at_eye.level_msl_m);
        draw.water_rgb = at_eye.body_rgb();
        draw.water_temperature_c = at_eye.temperature_c;
        if !at_eye.whitecaps {
            draw.whitecap_jacobian = f64::NEG_INFINITY;
        }
        let responses =
            Arc::clone(self.responses.get_or_insert_with(|| {
                Arc::new(std::sync::Mutex::new(ResponseCache::of(&surface)))
            }));
        let now_s = surface.time_s();
        self.rides
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner)
            .retain(|_, kept| kept.used_s <= now_s && kept.used_s >= now_s - RIDE_FORGOTTEN_S);
        self.now = Some(Arc::new(SeaNow {
            surface,
            draw: Arc::new(draw),
            plane: EnuFrame::new(origin),
            water,
            bounds: std::sync::OnceLock::new(),
            responses,
            rides: Arc::clone(&self.rides),
        }));
        Ok(told)
    }

    /// The water at a point (the host's region there, else its global conditions, else the
    /// scenario's).
    pub fn water_at(
        &self,
        environment: &crate::session::EnvironmentState,
        point_msl: Geodetic,
    ) -> Water {
        self.scenario_water
            .with_host(environment.maritime_at(point_msl))
    }
}

impl SeaNow {
    /// A ship of `hull` rides the sea: `entity` (its position, heading) is set on the waves
    /// at the sea's mean level `level_ellipsoid_m` (above the ellipsoid) with the heave, pitch
    /// and roll of its response to them at its heading and `velocity_enu_mps` (east, north,
    /// the velocity it makes good), at the sea's time. A `ship` named keeps its ride from
    /// frame to frame: a change of its heading, velocity or the waves rings down through
    /// its natural periods (`cig_sea::response::ShipRide`); `None`, the steady state.
    pub fn ride(
        &self,
        entity: &mut cig_scene::EntityInstance,
        hull: &cig_sea::motion::HullParameters,
        velocity_enu_mps: [f64; 2],
        level_ellipsoid_m: f64,
        ship: Option<ShipKey>,
    ) {
        let response = self
            .responses
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner)
            .response(hull, entity.orientation.heading_deg, velocity_enu_mps);
        let t_s = self.surface.time_s();
        let at = cig_scene::sea::sea_plane_xy(
            &self.plane,
            entity.position.lat_deg,
            entity.position.lon_deg,
        );
        // The host's waves as they apply where the ship is, made at the cache's steps of
        // heading and velocity and with the weights in 1/256ths, so that the response only
        // changes (and starts a transient) when one of them steps.
        let weights: Vec<f64> = self
            .surface
            .explicit_weights_at(at[0], at[1])
            .iter()
            .map(|w| (w * 256.0).round() / 256.0)
            .collect();
        let explicit_waves = self.surface.explicit_linear_waves(&weights);
        let explicit = (!explicit_waves.is_empty()).then(|| {
            let (heading_deg, velocity) =
                cig_sea::response::quantised(entity.orientation.heading_deg, velocity_enu_mps);
            SeawayResponse::new(hull, &explicit_waves, heading_deg, velocity)
        });
        let ride = match ship {
            None => ShipRide::steady(response, explicit, velocity_enu_mps),
            Some(key) => {
                let mut rides = self
                    .rides
                    .lock()
                    .unwrap_or_else(std::sync::PoisonError::into_inner);
                let steady = || KeptRide {
                    ride: ShipRide::steady(
                        Arc::clone(&response),
                        explicit.clone(),
                        velocity_enu_mps,
                    ),
                    hull: hull.bits(),
                    at_m: at,
                    used_s: t_s,
                };
                let kept = rides.entry(key).or_insert_with(steady);
                // Another hull under the same key (an id used again), or a jump: start again.
                let moved_m = (at[0] - kept.at_m[0]).hypot(at[1] - kept.at_m[1]);
                let jumped =
                    moved_m > cig_scene::sea::SHIP_JUMP_MPS * (t_s - kept.used_s).abs() + 1.0;
                if kept.hull != hull.bits() || jumped {
                    *kept = steady();
                }
                kept.ride
                    .change(hull, (response, explicit), velocity_enu_mps, at, t_s);
                kept.used_s = t_s;
                kept.at_m = at;
                kept.ride.clone()
            }
        };
        cig_scene::sea::ride_the_sea(entity, &ride, t_s, self.draw.origin, level_ellipsoid_m);
    }

    /// An entity of `model` afloat at `at` (latitude, longitude, degrees; the height above the
    /// surface, metres): on the waves at the sea's level `level_msl_m`; a ship (a model with a
    /// hull) heaves, pitches and rolls as it responds to the waves at its heading and
    /// `velocity_enu_mps` (east, north: the velocity it makes good), anything else follows the
    /// wave under it; pitch and roll come from the sea only when `clamp` asks for the attitude.
    /// A `ship` named keeps its ride from frame to frame ([`SeaNow::ride`]).
    #[expect(
        clippy::too_many_arguments,
        reason = "an entity's model, attitude, clamp, place, velocity, the sea's level and which ship it is: each needed, none grouped elsewhere"
    )]
    pub fn float(
        &self,
        query: &QuerySession,
        model: &str,
        orientation: cig_scene::Hpr,
        clamp: cig_scene::snapshot::Clamp,
        at: [f64; 3],
        velocity_enu_mps: [f64; 2],
        level_msl_m: f64,
        ship: Option<ShipKey>,
    ) -> crate::pose::Pose {
        let [lat_deg, lon_deg, above_m] = at;
        let level_ellipsoid_m = level_msl_m + query.geoid_undulation_m(lat_deg, lon_deg);
        let mut instance = cig_scene::EntityInstance {
            id: 0,
            model: String::new(),
            position: Geodetic::new(lat_deg, lon_deg, level_ellipsoid_m),
            orientation,
            cue_important: false,
            critical_radius_m: None,
        };
        let attitude = clamp == cig_scene::snapshot::Clamp::HeightAndAttitude;
        if let Some(hull) = cig_scene::sea::builtin_hull(model) {
            self.ride(
                &mut instance,
                &hull,
                velocity_enu_mps,
                level_ellipsoid_m,
                ship,
            );
        } else {
            let [x, y] = cig_scene::sea::sea_plane_xy(&self.plane, lat_deg, lon_deg);
            let wave = self.surface.sample(x, y);
            instance.position.alt_m = level_ellipsoid_m + wave.height_m;
            (
                instance.orientation.pitch_deg,
                instance.orientation.roll_deg,
            ) = cig_scene::snapshot::attitude_on_slope(wave.normal, orientation.heading_deg);
        }
        if !attitude {
            instance.orientation.pitch_deg = orientation.pitch_deg;
            instance.orientation.roll_deg = orientation.roll_deg;
        }
        instance.position.alt_m += above_m;
        crate::pose::Pose {
            position: instance.position,
            orientation: instance.orientation,
        }
    }
}
