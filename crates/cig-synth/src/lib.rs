//! Deterministic synthetic terrain for training databases: ridges and valleys, lakes and rivers,
//! settlements and roads, and a material (soil) class for every post.
//!
//! # Pipeline
//!
//! 1. `landform`: tectonic uplift from a ridged multifractal, a steady-state stream-power
//!    landform on a coarse grid (Cordonnier et al. 2016), resampled with domain warping, dressed
//!    with ridged-multifractal detail (Musgrave 2003) down to twice the post spacing, and cut by
//!    smoothed valleys.
//!    On request ([`SynthOptions::sea_side`]), `coast`: the land falls into open sea on one
//!    side, over a coastal plain with beaches or down cliffs, along a fractal shore about a third
//!    of the way in (16-48 %), the sea floor 25-130 m deep at the edge; the landform's base
//!    level is lowered toward that side, so its valleys and rivers run to the sea.
//! 2. `hydro`: sea below 0 m (set to its surface, 0 m above mean sea level), Priority-Flood depression filling (Barnes et al. 2014) into flat
//!    lakes of sensible size, D8 flow routing (O'Callaghan & Mark 1984) and accumulation, rivers
//!    above a catchment threshold in km^2, incised and non-increasing downstream.
//! 3. `roads`: settlements on flat low ground joined by least-cost paved roads (Dijkstra on a
//!    coarse grid, grade- and side-slope-penalised) and dirt tracks branching off, graded and
//!    rasterised without cross slope.
//! 4. `materials`: a rule cascade (water, roads, snow, rock, sand, dry clay, forest, grass).
//! 5. `features`: the roads, rivers and lakes as shapes ([`Feature`]: road centre lines, river
//!    polylines along the D8 receivers, lake shores traced between the posts where the ground
//!    meets the water level), for draped imagery and `cig_terrain::features::level_terrain`.
//!    They do not change the raster.
//! 6. `culture` (on request, [`culture::place_culture`]): buildings, garden walls and fences
//!    along the roads in and between the settlements, power poles beside the paved roads, and
//!    trees and bushes scattered by material in stands with clearings
//!    ([`culture::scatter_by_material`], which also serves imported rasters).
//!
//! Everything is in metres, so the landscape does not depend on the post spacing: a 90 m and a
//! 30 m database of the same seed, origin and size show the same hills.
//!
//! # Determinism
//!
//! The same [`SynthParams`] and [`SynthOptions`] give byte-identical rasters on every machine
//! and thread count (the default options, the bytes of [`synthesize`]): one
//! `ChaCha8` generator seeded from `seed` draws every random choice in a fixed order, noise is
//! an integer-hashed lattice, every transcendental function comes from `libm`, queues break ties
//! on the post index, and the only parallel work (per-post heights and materials) writes each
//! post independently with no reduction.
//!
//! # Limits
//!
//! The landscape belongs to the area: two adjacent databases do not join seamlessly, because the
//! coarse landform's outlets and the road network depend on the area's extent. The local metric
//! frame is a flat square of `size_km` on a side about the area's centre latitude.

mod coast;
pub mod culture;
mod features;
mod flood;
mod hydro;
mod landform;
mod materials;
mod noise;
mod roads;

#[cfg(test)]
mod tests;

use cig_terrain::material::Material;
use cig_terrain::raster::{GeoGrid, Raster};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

pub use cig_terrain::features::Feature;
pub use coast::{SeaSide, UnknownSeaSide};
pub use features::{DIRT_ROAD_WIDTH_M, PAVED_ROAD_WIDTH_M};
pub use hydro::Lake;
pub use roads::RoadKind;

/// Parameters of a synthetic database.
#[derive(Clone, Debug, PartialEq)]
pub struct SynthParams {
    /// Latitude of the south-west corner post, degrees (|lat| <= 80).
    pub origin_lat_deg: f64,
    /// Longitude of the south-west corner post, degrees.
    pub origin_lon_deg: f64,
    /// Side of the square area, km, in (0, 1000].
    pub size_km: f64,
    /// Post spacing, metres, in [1, 10000].
    pub spacing_m: f64,
    /// Seed of every random choice.
    pub seed: u64,
}

impl SynthParams {
    /// The demonstration area: 50 km x 50 km at 30 m posts around Fort Hunter Liggett,
    /// California (south-west corner 35.98 N 121.23 W).
    pub fn demo() -> SynthParams {
        SynthParams {
            origin_lat_deg: 35.98,
            origin_lon_deg: -121.23,
            size_km: 50.0,
            spacing_m: 30.0,
            seed: 1,
        }
    }
}

/// What a synthesis makes beyond the area and seed of [`SynthParams`]. The default is the
/// landscape of [`synthesize`], unchanged: inland hills with no sea.
///
/// New options may be added: build one from [`SynthOptions::default`] and its `with_` methods.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[non_exhaustive]
pub struct SynthOptions {
    /// The side on which the land falls into open sea (`None`: no sea). The sea covers about
    /// the outer third of the area on that side and goes on beyond its edge; its posts are
    /// water at 0 m, the sea's surface at mean sea level (the heights' datum).
    pub sea_side: Option<SeaSide>,
}

impl SynthOptions {
    /// These options with the sea on `side` (`None`: no sea).
    #[must_use]
    pub fn with_sea_side(mut self, side: Option<SeaSide>) -> SynthOptions {
        self.sea_side = side;
        self
    }
}

/// Most posts a synthetic database may hold.
pub const MAX_POSTS: u64 = 100_000_000;

/// Invalid synthesis parameters.
#[derive(Debug, thiserror::Error)]
pub enum SynthError {
    /// A parameter is out of range.
    #[error("{name} = {value}: {reason}")]
    InvalidParameter {
        /// Parameter name, as in [`SynthParams`].
        name: &'static str,
        /// The value given.
        value: f64,
        /// Why it was refused.
        reason: String,
    },
    /// The grid would hold more than [`MAX_POSTS`] posts.
    #[error(
        "size_km = {size_km} at spacing_m = {spacing_m} gives {posts} posts, more than the {max} \
         allowed: raise spacing_m or lower size_km"
    )]
    TooManyPosts {
        /// The area side, km.
        size_km: f64,
        /// The post spacing, metres.
        spacing_m: f64,
        /// Posts the grid would hold.
        posts: u64,
        /// The limit.
        max: u64,
    },
}

fn invalid(name: &'static str, value: f64, reason: impl Into<String>) -> SynthError {
    SynthError::InvalidParameter {
        name,
        value,
        reason: reason.into(),
    }
}

/// A road centre line.
#[derive(Clone, Debug, PartialEq)]
pub struct Road {
    /// Paved road or dirt track.
    pub kind: RoadKind,
    /// Centre-line vertices, `(lat_deg, lon_deg)`, from the junction to the end.
    pub points_deg: Vec<(f64, f64)>,
    /// Length, km.
    pub length_km: f64,
}

/// What was generated, for `cig db synth` output and tests.
#[derive(Clone, Debug, PartialEq)]
pub struct SynthReport {
    /// Post rows (south to north).
    pub rows: usize,
    /// Post columns (west to east).
    pub cols: usize,
    /// Lowest post, metres.
    pub elevation_min_m: f32,
    /// Highest post, metres.
    pub elevation_max_m: f32,
    /// Lakes, in raster scan order of their first post.
    pub lakes: Vec<Lake>,
    /// Posts on a river centre line.
    pub river_centre_posts: usize,
    /// Posts of river water (the centre lines widened by catchment).
    pub river_water_posts: usize,
    /// Settlements, `(lat_deg, lon_deg)`.
    pub settlements_deg: Vec<(f64, f64)>,
    /// Road centre lines.
    pub roads: Vec<Road>,
    /// Total length of paved roads, km.
    pub paved_road_km: f64,
    /// Total length of dirt tracks, km.
    pub dirt_road_km: f64,
    /// Fraction of posts of each material, in [`Material::ALL`] order.
    pub material_fractions: Vec<(Material, f64)>,
}

impl SynthReport {
    /// Fraction of posts of `material`.
    pub fn material_fraction(&self, material: Material) -> f64 {
        self.material_fractions
            .iter()
            .find(|(m, _)| *m == material)
            .map_or(0.0, |(_, f)| *f)
    }
}

impl std::fmt::Display for SynthReport {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        writeln!(
            f,
            "{} x {} posts, elevation {:.0} .. {:.0} m",
            self.rows, self.cols, self.elevation_min_m, self.elevation_max_m
        )?;
        let lake_km2 = self.lakes.iter().fold(0.0, |a, l| a + l.area_km2);
        writeln!(
            f,
            "{} lakes ({:.2} km^2), {} river centre posts, {} river water posts",
            self.lakes.len(),
            lake_km2,
            self.river_centre_posts,
            self.river_water_posts
        )?;
        writeln!(
            f,
            "{} settlements, {:.1} km paved roads, {:.1} km dirt tracks",
            self.settlements_deg.len(),
            self.paved_road_km,
            self.dirt_road_km
        )?;
        let parts: Vec<String> = self
            .material_fractions
            .iter()
            .map(|(m, frac)| format!("{m} {:.1}%", 100.0 * frac))
            .collect();
        write!(f, "materials: {}", parts.join(", "))
    }
}

/// Metres per degree of latitude (north) and longitude (east) on the WGS84 ellipsoid.
///
/// Meridian radius of curvature `M = a (1 - e^2) / (1 - e^2 sin^2 lat)^1.5` and prime-vertical
/// radius `N = a / sqrt(1 - e^2 sin^2 lat)`; a degree is `M pi / 180` north and
/// `N cos(lat) pi / 180` east. This is `cig_geo::metres_per_degree` (a test checks they agree
/// to 1e-6 m), computed with `libm`'s sine and cosine: `cig_geo` uses `std`'s, whose last bit
/// may differ between platforms, and the grid's `dlat_deg`/`dlon_deg` must be bit-identical
/// everywhere.
fn metres_per_degree(lat_deg: f64) -> (f64, f64) {
    const A: f64 = 6_378_137.0;
    const F: f64 = 1.0 / 298.257_223_563;
    let e2 = F * (2.0 - F);
    let phi = lat_deg.to_radians();
    let s = libm::sin(phi);
    let w = 1.0 - e2 * s * s;
    let m = A * (1.0 - e2) / (w * w.sqrt());
    let n = A / w.sqrt();
    let rad = std::f64::consts::PI / 180.0;
    (m * rad, n * libm::cos(phi) * rad)
}

/// The validated grid of a request.
struct Plan {
    grid: GeoGrid,
    centre_lat_deg: f64,
}

fn plan(p: &SynthParams) -> Result<Plan, SynthError> {
    if !p.origin_lat_deg.is_finite() || p.origin_lat_deg.abs() > 80.0 {
        return Err(invalid(
            "origin_lat_deg",
            p.origin_lat_deg,
            "must be a finite latitude within [-80, 80] degrees",
        ));
    }
    if !p.origin_lon_deg.is_finite() || p.origin_lon_deg.abs() > 180.0 {
        return Err(invalid(
            "origin_lon_deg",
            p.origin_lon_deg,
            "must be a finite longitude within [-180, 180] degrees",
        ));
    }
    if !p.size_km.is_finite() || p.size_km <= 0.0 || p.size_km > 1000.0 {
        return Err(invalid(
            "size_km",
            p.size_km,
            "must be finite, greater than 0 and at most 1000 km",
        ));
    }
    if !p.spacing_m.is_finite() || p.spacing_m < 1.0 || p.spacing_m > 10_000.0 {
        return Err(invalid(
            "spacing_m",
            p.spacing_m,
            "must be finite and within [1, 10000] metres",
        ));
    }
    let size_m = p.size_km * 1000.0;
    let side = (size_m / p.spacing_m).round() + 1.0;
    if side < 2.0 {
        return Err(invalid(
            "size_km",
            p.size_km,
            format!(
                "is less than half a post spacing ({} m): the grid needs at least 2 posts a side",
                p.spacing_m
            ),
        ));
    }
    let posts = side * side;
    if posts > MAX_POSTS as f64 {
        return Err(SynthError::TooManyPosts {
            size_km: p.size_km,
            spacing_m: p.spacing_m,
            posts: posts as u64,
            max: MAX_POSTS,
        });
    }
    let side = side as usize;
    let half_m = 0.5 * (side - 1) as f64 * p.spacing_m;
    let mut centre = p.origin_lat_deg;
    for _ in 0..2 {
        centre = p.origin_lat_deg + half_m / metres_per_degree(centre).0;
    }
    let (north, east) = metres_per_degree(centre);
    let grid = GeoGrid {
        south_lat_deg: p.origin_lat_deg,
        west_lon_deg: p.origin_lon_deg,
        dlat_deg: p.spacing_m / north,
        dlon_deg: p.spacing_m / east,
        rows: side,
        cols: side,
    };
    if grid.east_lon_deg() > 180.0 {
        return Err(invalid(
            "origin_lon_deg",
            p.origin_lon_deg,
            format!(
                "the area would reach {:.4} degrees east, across the antimeridian",
                grid.east_lon_deg()
            ),
        ));
    }
    Ok(Plan {
        grid,
        centre_lat_deg: centre,
    })
}

/// Everything a run makes; tests look at the internals.
pub(crate) struct Generated {
    /// The ground before the hydrology (the sea's floor still below 0 m).
    #[cfg(test)]
    pub ground: Vec<f32>,
    pub raster: Raster,
    pub report: SynthReport,
    /// Lakes, rivers and roads as shapes.
    pub features: Vec<Feature>,
    #[cfg_attr(not(test), allow(dead_code, reason = "only the tests read it"))]
    pub flags: Vec<u16>,
    #[cfg_attr(not(test), allow(dead_code, reason = "only the tests read it"))]
    pub receiver: Vec<u32>,
}

/// Generates a synthetic terrain raster.
///
/// `progress` is called with a stage name (`"landform"`, `"elevation"`, `"hydrology"`,
/// `"roads"`, `"materials"`) and the fraction of that stage done.
pub fn synthesize(
    params: &SynthParams,
    progress: &mut dyn FnMut(&str, f32),
) -> Result<Raster, SynthError> {
    Ok(generate(params, &SynthOptions::default(), progress)?.raster)
}

/// [`synthesize_with_features`] with `options` (a sea on one side); with the default options
/// it makes the same bytes.
pub fn synthesize_with_options(
    params: &SynthParams,
    options: &SynthOptions,
    progress: &mut dyn FnMut(&str, f32),
) -> Result<(Raster, SynthReport, Vec<Feature>), SynthError> {
    let g = generate(params, options, progress)?;
    Ok((g.raster, g.report, g.features))
}

/// [`synthesize_with_report`], also returning the roads, rivers and lakes as shapes: lakes
/// (outline and level), then rivers, then roads, in a deterministic order.
pub fn synthesize_with_features(
    params: &SynthParams,
    progress: &mut dyn FnMut(&str, f32),
) -> Result<(Raster, SynthReport, Vec<Feature>), SynthError> {
    synthesize_with_options(params, &SynthOptions::default(), progress)
}

/// [`synthesize`], also returning a [`SynthReport`].
pub fn synthesize_with_report(
    params: &SynthParams,
    progress: &mut dyn FnMut(&str, f32),
) -> Result<(Raster, SynthReport), SynthError> {
    let g = generate(params, &SynthOptions::default(), progress)?;
    Ok((g.raster, g.report))
}

pub(crate) fn generate(
    params: &SynthParams,
    options: &SynthOptions,
    progress: &mut dyn FnMut(&str, f32),
) -> Result<Generated, SynthError> {
    let plan = plan(params)?;
    let grid = plan.grid;
    let (rows, cols) = (grid.rows, grid.cols);
    let n = rows * cols;
    let s = params.spacing_m;
    let size_m = params.size_km * 1000.0;
    let dims = flood::Dims { nx: cols, ny: rows };
    let mut rng = ChaCha8Rng::seed_from_u64(params.seed);
    let coast = options
        .sea_side
        .map(|side| coast::Coast::new(side, size_m, params.seed));

    progress("landform", 0.0);
    let reach_m = (rows.max(cols) - 1) as f64 * s;
    let landform = landform::Landform::new(size_m, reach_m.max(size_m), &mut rng, coast.as_ref());
    progress("landform", 1.0);

    progress("elevation", 0.0);
    let mut h = vec![0.0f32; n];
    let batch_rows = (262_144 / cols).max(1);
    let mut r0 = 0;
    while r0 < rows {
        let r1 = (r0 + batch_rows).min(rows);
        h[r0 * cols..r1 * cols]
            .par_chunks_mut(cols)
            .enumerate()
            .for_each(|(k, row)| {
                let y = (r0 + k) as f64 * s;
                for (c, v) in row.iter_mut().enumerate() {
                    *v = landform.height(c as f64 * s, y, s) as f32;
                }
            });
        r0 = r1;
        progress("elevation", 0.9 * r0 as f32 / rows as f32);
    }
    landform.carve(&mut h, cols, s);
    if let Some(coast) = &coast {
        coast.apply(&mut h, cols, s);
    }
    progress("elevation", 1.0);
    #[cfg(test)]
    let ground = h.clone();

    let mut flags = vec![0u16; n];
    let hydrology = hydro::run(&mut h, &mut flags, dims, s, progress);
    let network = roads::build(&mut h, &mut flags, dims, s, size_m, &mut rng, progress);
    let material = materials::classify(
        &materials::Inputs {
            h: &h,
            flags: &flags,
            acc: &hydrology.acc,
            dims,
            spacing_m: s,
            centre_lat_deg: plan.centre_lat_deg,
        },
        &mut rng,
        progress,
    );

    let to_deg = |(x, y): (f64, f64)| {
        (
            grid.south_lat_deg + y / s * grid.dlat_deg,
            grid.west_lon_deg + x / s * grid.dlon_deg,
        )
    };
    let mut counts = [0usize; 9];
    for m in &material {
        counts[m.to_byte() as usize] += 1;
    }
    let (mut lo, mut hi) = (f32::INFINITY, f32::NEG_INFINITY);
    for &v in &h {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    let roads: Vec<Road> = network
        .roads
        .iter()
        .map(|r| Road {
            kind: r.kind,
            points_deg: r.points_m.iter().map(|&p| to_deg(p)).collect(),
            length_km: r.length_m * 1e-3,
        })
        .collect();
    let km = |kind: RoadKind| -> f64 {
        roads
            .iter()
            .filter(|r| r.kind == kind)
            .fold(0.0, |a, r| a + r.length_km)
    };
    let report = SynthReport {
        rows,
        cols,
        elevation_min_m: lo,
        elevation_max_m: hi,
        lakes: hydrology.lakes.clone(),
        river_centre_posts: hydrology.river_centre_posts,
        river_water_posts: hydrology.river_water_posts,
        settlements_deg: network.settlements_m.iter().map(|&p| to_deg(p)).collect(),
        paved_road_km: km(RoadKind::Paved),
        dirt_road_km: km(RoadKind::Dirt),
        roads,
        material_fractions: Material::ALL
            .iter()
            .map(|&m| (m, counts[m.to_byte() as usize] as f64 / n as f64))
            .collect(),
    };
    let features = features::build(&features::Sources {
        grid,
        dims,
        spacing_m: s,
        h: &h,
        bed: &hydrology.bed,
        flags: &flags,
        receiver: &hydrology.flood.receiver,
        acc: &hydrology.acc,
        roads: &report.roads,
    });
    Ok(Generated {
        #[cfg(test)]
        ground,
        features,
        raster: Raster {
            grid,
            elevation_m: h,
            material: Some(material),
        },
        report,
        flags,
        receiver: hydrology.flood.receiver,
    })
}
