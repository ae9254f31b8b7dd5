//! The IG's terrain answers: height of terrain (HOT), height above terrain (HAT) with normal and
//! material, and line of sight (LOS).
//!
//! Every answer is taken on the finest level's triangulated surface (see
//! [`crate::raster::triangulated_height`]), the surface the renderer draws at full detail; the
//! finest tile is loaded on demand. Where a finest tile is unreadable the answer comes from the
//! nearest readable coarser level, resampled onto the finest grid, and says so (`level`).
//!
//! Line of sight follows the straight chord between two geodetic points (through the ellipsoid's
//! curvature, so long sightlines drop towards the ground as they should). The chord is split into
//! pieces of at most 2 km; in each, latitude and longitude are linear and altitude is the
//! quadratic through the piece's exact end and middle points (error well under a millimetre).
//! The walk in grid space skips whole quadtree nodes whose highest point is below the chord (the
//! tiles' min/max quadtree, down to 8 x 8-cell leaves) and tests each remaining cell's two
//! triangles: the terrain is linear along the sightline within a triangle, and the sightline's
//! altitude is taken as linear across one cell (its curvature there is far below a millimetre).
//!
//! Culture: line of sight also stops at the first culture object it enters before the terrain
//! (`crate::culture_hit`: each object's simple volumes, found through its tile's 8 x 8-cell
//! blocks). After the terrain walk of a piece, the objects of the finest tiles within a
//! footprint of the piece's stretch up to the terrain hit are tested: blocks and objects whose
//! footprint the piece does not pass over, or whose highest top it stays above, are skipped;
//! the rest are tested exactly in the object's frame, where the piece's altitude is taken as
//! linear over the object's footprint (under a millimetre from the quadratic). Fences are seen
//! through ([`CultureTest::LineOfSight`]); the collision form ([`QuerySession::collision`])
//! counts every object. A sightline that starts inside an object meets it at once. HOT and HAT
//! answer the bare terrain (a tree's base is HOT at its trunk);
//! [`QuerySession::hot_with_culture`] gives the highest surface counting the objects' tops.
//!
//! Limits: a chord that leaves the database sees no terrain outside it; the geoid undulation is
//! bilinear on the manifest's coarse grid (EGM96 varies by centimetres per kilometre). Culture
//! is tested on every finest tile whose objects could reach the sightline: those it passes
//! within the database's widest footprint radius of (the manifest's
//! [`crate::culture::CultureManifest::footprint_bound_m`]) while below its highest top (the
//! highest post plus the tallest object, [`crate::culture::CultureManifest::height_bound_m`]).
//! Each is loaded through the session and the paging cache like the tiles under the sightline,
//! whether or not it is resident, so the answer never depends on what is in memory (the same
//! scenario gives the same answers on every IG). A tile whose objects overhang into the
//! sightline's tile is thus loaded for its culture alone; with the recorded radius (a few
//! metres for trees, tens for buildings) that is a sightline within that distance of a tile's
//! edge. A database whose manifest predates the recorded bounds is searched with the largest
//! any valid placement allows (283 m and 400 m), loading more tiles near its culture. The
//! culture index a session builds for each tile it uses (a few bytes per non-empty block) is
//! outside the paging budget.

use crate::cache::TileCache;
use crate::culture::CULTURE_BLOCK_CELLS;
use crate::culture_hit::{segment_entry, top_at, CultureHit, CultureIndex, CultureTest, ItemFrame};
use crate::database::{GeoidLookup, LoadError, TerrainDatabase};
use crate::edits::{CellLattice, EditLayer, RefinedCell, BLOCK_SUB_CELLS};
use crate::material::Material;
use crate::pyramid::{quadtree_index, PyramidLayout, TileKey};
use crate::raster::{triangulated_height, triangulated_slopes, Diagonal};
use crate::tile::Tile;
use cig_geo::Geodetic;
use std::collections::HashMap;
use std::sync::Arc;

/// A point on the terrain surface.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfacePoint {
    pub lat_deg: f64,
    pub lon_deg: f64,
    /// Height of the terrain above mean sea level (EGM96), metres.
    pub height_msl_m: f64,
    /// Geoid undulation there: height above the ellipsoid = `height_msl_m + geoid_undulation_m`.
    pub geoid_undulation_m: f64,
    /// Unit surface normal in the local east-north-up frame.
    pub normal_enu: [f64; 3],
    pub material: Material,
    /// Level the answer came from: 0 unless the finest tile was unreadable.
    pub level: u8,
}

impl SurfacePoint {
    /// Height of the terrain above the WGS84 ellipsoid, metres.
    pub fn height_ellipsoid_m(&self) -> f64 {
        self.height_msl_m + self.geoid_undulation_m
    }
}

/// Where a sightline first meets the terrain or a culture object.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LosHit {
    /// The intersection; altitude above the ellipsoid.
    pub point: Geodetic,
    /// Distance from the sightline's start, metres.
    pub range_m: f64,
    /// The terrain's material at the hit, or under the object's centre for a culture hit.
    pub material: Material,
    pub level: u8,
    /// The culture object the sightline met before the terrain, if any.
    pub culture: Option<CultureHit>,
}

/// The highest surface at a point counting the culture objects' tops
/// ([`QuerySession::hot_with_culture`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CultureSurface {
    /// The bare terrain there (HOT).
    pub terrain: SurfacePoint,
    /// The highest surface above mean sea level: the terrain or an object's top, metres.
    pub height_msl_m: f64,
    /// Unit normal of that surface in the local east-north-up frame.
    pub normal_enu: [f64; 3],
    /// The object whose top it is, if any.
    pub culture: Option<CultureHit>,
}

impl CultureSurface {
    /// Height of the highest surface above the WGS84 ellipsoid, metres.
    pub fn height_ellipsoid_m(&self) -> f64 {
        self.height_msl_m + self.terrain.geoid_undulation_m
    }
}

/// Answer to a line-of-sight query.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LosResult {
    pub visible: bool,
    pub hit: Option<LosHit>,
}

/// Why a query has no answer.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum QueryError {
    #[error("point {lat_deg:.7}, {lon_deg:.7} is outside the database")]
    Outside { lat_deg: f64, lon_deg: f64 },
    #[error("point {lat_deg:.7}, {lon_deg:.7} is not a valid coordinate")]
    Invalid { lat_deg: f64, lon_deg: f64 },
    #[error("no level of the terrain is readable there ({0})")]
    Unavailable(LoadError),
    #[error("tile {0} is not part of the database")]
    NoSuchTile(TileKey),
    #[error("altitude {alt_m} m is outside -12000..1000000 m")]
    Altitude { alt_m: f64 },
    #[error("sightline from {lat_deg:.7}, {lon_deg:.7} does not cross the database")]
    Misses { lat_deg: f64, lon_deg: f64 },
}

/// A thread's query context: keeps the finest tiles it has used at hand so repeated queries cost
/// no lock. Create one per thread from a shared [`TileCache`].
pub struct QuerySession {
    db: Arc<TerrainDatabase>,
    layout: PyramidLayout,
    tiles: TileSlots,
    /// Precomputed for the per-query path: no division, no search.
    fast: FastIndex,
    geoid: GeoidLookup,
    /// The database's culture as the queries bound it; `None` without culture.
    culture: Option<CultureBounds>,
    /// The terrain edits as of `edits_revision` of the cache.
    edits: Arc<EditLayer>,
    edits_revision: u64,
}

/// How far the database's culture may reach: the culture queries load every finest tile
/// within these bounds of a query, and only those.
#[derive(Clone, Copy, Debug)]
struct CultureBounds {
    /// Posts (east, north) that hold the widest footprint radius
    /// ([`crate::culture::CultureManifest::footprint_bound_m`]) anywhere on the database.
    footprint_posts: (f64, f64),
    /// Highest any object's top may be above mean sea level: the highest post plus the
    /// tallest object ([`crate::culture::CultureManifest::height_bound_m`]), metres.
    top_msl_m: f64,
}

/// What the per-query path needs to find a point's finest cell with multiplications and shifts.
struct FastIndex {
    south_lat_deg: f64,
    west_lon_deg: f64,
    rows_per_deg: f64,
    cols_per_deg: f64,
    max_row: f64,
    max_col: f64,
    last_cell_row: usize,
    last_cell_col: usize,
    tile_shift: u32,
}

/// A point's place on the finest grid: tile, cell in the tile, fractions in the cell.
#[derive(Clone, Copy)]
struct CellRef {
    key: TileKey,
    i: usize,
    j: usize,
    u: f64,
    v: f64,
}

/// The finest tiles a session has used, by tile index. Tiles the cache also holds cost nothing
/// more; at most [`SESSION_TILES`] that it does not hold are kept on top of its budget, and all
/// are forgotten when the cache evicts anything.
struct TileSlots {
    cache: Arc<TileCache>,
    layout: PyramidLayout,
    tile_cols: usize,
    slots: Vec<Option<Arc<Tile>>>,
    /// Slots holding tiles the cache does not (they did not fit its budget, or were rebuilt
    /// from a coarser level).
    uncached: usize,
    epoch: u64,
    /// Culture indices of slotted tiles that have culture (forgotten with the slots).
    culture: HashMap<TileKey, Arc<CultureIndex>>,
}

/// Most finest tiles outside the paging cache one query session keeps at hand (about 5.6 MB of
/// 128-cell tiles).
pub const SESSION_TILES: usize = 64;

/// How the air bends a sightline: the coefficient of refraction `k` (the ratio of the earth's
/// radius to the light path's; 0.13 is the standard terrestrial value) and the earth's radius
/// of curvature along the sightline.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Refraction {
    pub k: f64,
    pub earth_radius_m: f64,
}

impl Refraction {
    /// Straight sightlines.
    pub const NONE: Refraction = Refraction {
        k: 0.0,
        earth_radius_m: 6_371_000.0,
    };

    /// How far, metres, a path of chord `length_m` bows above its chord at its middle:
    /// `k D² / 8R` (0 for a `k` or radius that is not finite, a `k` outside `-1..1` or a
    /// radius under 1 km).
    pub fn bow_m(&self, length_m: f64) -> f64 {
        let usable = self.k.is_finite()
            && self.k.abs() < 1.0
            && self.earth_radius_m.is_finite()
            && self.earth_radius_m >= 1_000.0;
        if usable {
            self.k * length_m * length_m / (8.0 * self.earth_radius_m)
        } else {
            0.0
        }
    }

    /// How far, metres, the path of chord `length_m` lies above its chord at the fraction
    /// `t` of its length: `k s (D − s) / 2R`.
    pub fn lift_m(&self, length_m: f64, t: f64) -> f64 {
        self.bow_m(length_m) * 4.0 * t * (1.0 - t)
    }
}

const PIECE_M: f64 = 2_000.0;
/// Lowest end-point altitude a sightline may have (below the deepest ocean trench).
pub const LOS_MIN_ALT_M: f64 = -12_000.0;
/// Highest end-point altitude a sightline may have (low earth orbit).
pub const LOS_MAX_ALT_M: f64 = 1_000_000.0;
/// How far outside the database's edge (in posts; 1e-6 is 0.03 mm at 30 m posts) a point still
/// counts as on it: geodetic round trips of edge points land a hair outside.
const EDGE_TOLERANCE_POSTS: f64 = 1e-6;
/// Snap distance to a post, in posts: a query this close to a post returns the post.
const POST_SNAP: f64 = 1e-7;

impl QuerySession {
    pub fn new(cache: Arc<TileCache>) -> QuerySession {
        let layout = *cache.database().layout();
        let (rows, cols) = layout.tiles_at(0);
        let g = layout.grid;
        let fast = FastIndex {
            south_lat_deg: g.south_lat_deg,
            west_lon_deg: g.west_lon_deg,
            rows_per_deg: 1.0 / g.dlat_deg,
            cols_per_deg: 1.0 / g.dlon_deg,
            max_row: (g.rows - 1) as f64,
            max_col: (g.cols - 1) as f64,
            last_cell_row: g.rows - 2,
            last_cell_col: g.cols - 2,
            tile_shift: layout.tile_cells.trailing_zeros(),
        };
        // The fewest metres per post anywhere on the database: at its poleward edge
        // eastwards, at the latitude nearest the equator northwards.
        let (south, north) = (g.south_lat_deg, g.north_lat_deg());
        let mut min_m = (f64::INFINITY, f64::INFINITY);
        for lat in [south, north, 0.0f64.clamp(south, north)] {
            let (north_m_per_deg, east_m_per_deg) =
                cig_geo::metres_per_degree(lat.clamp(-90.0, 90.0));
            min_m.0 = min_m.0.min(g.dlon_deg * east_m_per_deg);
            min_m.1 = min_m.1.min(g.dlat_deg * north_m_per_deg);
        }
        let manifest = cache.database().manifest();
        let culture = manifest.culture.as_ref().filter(|c| c.tiles > 0).map(|c| {
            let bound_m = c.footprint_bound_m();
            CultureBounds {
                footprint_posts: (bound_m / min_m.0.max(1e-9), bound_m / min_m.1.max(1e-9)),
                top_msl_m: f64::from(manifest.max_elevation_m) + c.height_bound_m(),
            }
        });
        QuerySession {
            edits_revision: cache.edits_revision(),
            edits: cache.edits(),
            geoid: GeoidLookup::new(&cache.database().manifest().geoid),
            db: Arc::clone(cache.database()),
            layout,
            fast,
            culture,
            tiles: TileSlots {
                epoch: cache.eviction_epoch(),
                cache,
                layout,
                tile_cols: cols as usize,
                slots: vec![None; rows as usize * cols as usize],
                uncached: 0,
                culture: HashMap::new(),
            },
        }
    }

    pub fn cache(&self) -> &Arc<TileCache> {
        &self.tiles.cache
    }

    /// Takes the cache's terrain edits when they changed since the last query.
    #[inline]
    fn refresh_edits(&mut self) {
        let revision = self.tiles.cache.edits_revision();
        if revision != self.edits_revision {
            self.edits = self.tiles.cache.edits();
            self.edits_revision = revision;
        }
    }

    /// The terrain edits this session answers on.
    pub fn edits(&mut self) -> &Arc<EditLayer> {
        self.refresh_edits();
        &self.edits
    }

    /// The finest cell holding a point (snapped onto a post when within [`POST_SNAP`] of one),
    /// or why the point has no answer.
    #[inline]
    fn cell(&self, lat_deg: f64, lon_deg: f64) -> Result<CellRef, QueryError> {
        let f = &self.fast;
        let row_f = (lat_deg - f.south_lat_deg) * f.rows_per_deg;
        let col_f = (lon_deg - f.west_lon_deg) * f.cols_per_deg;
        const EDGE: f64 = EDGE_TOLERANCE_POSTS;
        // Written so that NaN fails the test.
        if !(row_f >= -EDGE
            && row_f <= f.max_row + EDGE
            && col_f >= -EDGE
            && col_f <= f.max_col + EDGE)
        {
            return Err(if lat_deg.is_finite() && lon_deg.is_finite() {
                QueryError::Outside { lat_deg, lon_deg }
            } else {
                QueryError::Invalid { lat_deg, lon_deg }
            });
        }
        let row_f = snap(row_f.max(0.0)).min(f.max_row);
        let col_f = snap(col_f.max(0.0)).min(f.max_col);
        let r = (row_f as usize).min(f.last_cell_row);
        let c = (col_f as usize).min(f.last_cell_col);
        let (tr, tc) = (r >> f.tile_shift, c >> f.tile_shift);
        Ok(CellRef {
            key: TileKey {
                level: 0,
                row: tr as u32,
                col: tc as u32,
            },
            i: r - (tr << f.tile_shift),
            j: c - (tc << f.tile_shift),
            u: col_f - c as f64,
            v: row_f - r as f64,
        })
    }

    /// Height of terrain above mean sea level at a point: the HOT answer without normal and
    /// material (CIGI's basic HAT/HOT response).
    #[inline]
    pub fn height_msl_m(&mut self, lat_deg: f64, lon_deg: f64) -> Result<f64, QueryError> {
        self.refresh_edits();
        let cell = self.cell(lat_deg, lon_deg)?;
        let lattice = self.edits.lattice(self.global_cell(&cell));
        height_in_cell(&mut self.tiles, &cell, lattice)
    }

    /// The finest lattice's (row, column) of a cell.
    #[inline]
    fn global_cell(&self, cell: &CellRef) -> (u32, u32) {
        let shift = self.fast.tile_shift;
        (
            (cell.key.row << shift) + cell.i as u32,
            (cell.key.col << shift) + cell.j as u32,
        )
    }

    /// Heights above terrain of many points (a frame's worth of host requests), height only:
    /// the same answers as [`QuerySession::hat_m`] one by one, with the memory they read
    /// requested ahead so that cache misses overlap: without edits, each point's cell a few
    /// points ahead; with edits, in chunks: first every point's cell and the edits' posts
    /// under it, then the answers.
    pub fn hat_batch_m(&mut self, points: &[Geodetic], out: &mut Vec<Result<f64, QueryError>>) {
        const AHEAD: usize = 8;
        const CHUNK: usize = 32;
        self.refresh_edits();
        out.clear();
        out.reserve(points.len());
        if self.edits.is_empty() {
            for (k, p) in points.iter().enumerate() {
                if let Some(next) = points.get(k + AHEAD) {
                    self.prefetch_cell(next.lat_deg, next.lon_deg);
                }
                out.push(self.hat_m(*p));
            }
            return;
        }
        let edits = Arc::clone(&self.edits);
        let mut cells: [Option<(CellRef, Option<&CellLattice>)>; CHUNK] = [None; CHUNK];
        for chunk in points.chunks(CHUNK) {
            for (slot, p) in cells.iter_mut().zip(chunk) {
                *slot = self.cell(p.lat_deg, p.lon_deg).ok().map(|cell| {
                    self.prefetch_tile_cell(&cell);
                    let lattice = edits.lattice(self.global_cell(&cell));
                    if let Some(l) = lattice {
                        l.prefetch_posts(cell.u, cell.v);
                    }
                    (cell, lattice)
                });
            }
            for (slot, p) in cells.iter().zip(chunk) {
                out.push(match slot {
                    Some((cell, lattice)) => height_in_cell(&mut self.tiles, cell, *lattice)
                        .map(|h| p.alt_m - h - self.geoid.undulation_m(p.lat_deg, p.lon_deg)),
                    // The error the point's own query gives.
                    None => self.hat_m(*p),
                });
            }
        }
    }

    /// Asks the memory system for the cell under a point without waiting for it.
    #[inline]
    fn prefetch_cell(&self, lat_deg: f64, lon_deg: f64) {
        if let Ok(cell) = self.cell(lat_deg, lon_deg) {
            self.prefetch_tile_cell(&cell);
        }
    }

    /// Asks the memory system for a cell's posts without waiting for them.
    #[inline(always)]
    fn prefetch_tile_cell(&self, cell: &CellRef) {
        let slot = cell.key.row as usize * self.tiles.tile_cols + cell.key.col as usize;
        if let Some(Some(tile)) = self.tiles.slots.get(slot) {
            let base = cell.i * tile.posts_per_side + cell.j;
            if let Some(row) = tile.elevation_m.get(base..base + tile.posts_per_side + 2) {
                crate::hint::prefetch(&row[..2]);
                crate::hint::prefetch(&row[tile.posts_per_side..]);
            }
        }
    }

    /// EGM96 geoid undulation (ellipsoid height minus MSL height) at a point, metres, from the
    /// database's geoid grid: bilinear inside the database, the nearest edge value outside it.
    pub fn geoid_undulation_m(&self, lat_deg: f64, lon_deg: f64) -> f64 {
        self.geoid.undulation_m(lat_deg, lon_deg)
    }

    /// Height above terrain of a geodetic point (altitude above the ellipsoid), height only.
    #[inline]
    pub fn hat_m(&mut self, point: Geodetic) -> Result<f64, QueryError> {
        let h = self.height_msl_m(point.lat_deg, point.lon_deg)?;
        Ok(point.alt_m - h - self.geoid.undulation_m(point.lat_deg, point.lon_deg))
    }

    /// Height of terrain at a point, with normal and material.
    pub fn hot(&mut self, lat_deg: f64, lon_deg: f64) -> Result<SurfacePoint, QueryError> {
        self.refresh_edits();
        let cell = self.cell(lat_deg, lon_deg)?;
        let global = self.global_cell(&cell);
        let CellRef { key, i, j, u, v } = cell;
        let g = self.layout.grid;
        let tile = self.tiles.get(key)?;
        let n = tile.posts_per_side;
        let corners = tile.cell_corners(i, j);
        let diagonal = Tile::cell_diagonal(i, j);
        let mut height = triangulated_height(corners, u, v, diagonal);
        // Slopes of the cell's triangle, per post, then per metre.
        let (mut dh_du, mut dh_dv) = triangulated_slopes(corners, u, v, diagonal);
        if let Some(refined) = self.edits.cell(global) {
            height += refined.delta_m(u, v, diagonal);
            let (du, dv) = refined.slopes(u, v, diagonal);
            dh_du += du * f64::from(refined.lattice.split);
            dh_dv += dv * f64::from(refined.lattice.split);
        }
        let (north_m_per_deg, east_m_per_deg) = cig_geo::metres_per_degree(lat_deg);
        let dx_m = g.dlon_deg * east_m_per_deg;
        let dy_m = g.dlat_deg * north_m_per_deg;
        let (gx, gy) = (dh_du / dx_m, dh_dv / dy_m);
        let len = (gx * gx + gy * gy + 1.0).sqrt();
        let ni = (i + usize::from(v >= 0.5)).min(n - 1);
        let nj = (j + usize::from(u >= 0.5)).min(n - 1);
        Ok(SurfacePoint {
            lat_deg,
            lon_deg,
            height_msl_m: height,
            geoid_undulation_m: self.geoid.undulation_m(lat_deg, lon_deg),
            normal_enu: [-gx / len, -gy / len, 1.0 / len],
            material: tile.material_at(ni, nj),
            level: tile.degraded_from_level.unwrap_or(0),
        })
    }

    /// Height above terrain of a geodetic point (altitude above the ellipsoid), with the
    /// surface point below it.
    pub fn hat(&mut self, point: Geodetic) -> Result<(f64, SurfacePoint), QueryError> {
        let s = self.hot(point.lat_deg, point.lon_deg)?;
        Ok((point.alt_m - s.height_ellipsoid_m(), s))
    }

    /// Line of sight between two geodetic points (altitudes above the ellipsoid): stopped by
    /// the terrain and by every culture object but fences ([`CultureTest::LineOfSight`]).
    pub fn los(&mut self, from: Geodetic, to: Geodetic) -> Result<LosResult, QueryError> {
        self.los_with(from, to, CultureTest::LineOfSight)
    }

    /// A collision segment between two geodetic points: where it first meets the terrain or
    /// any culture object, fences included ([`CultureTest::Collision`]).
    pub fn collision(&mut self, from: Geodetic, to: Geodetic) -> Result<LosResult, QueryError> {
        self.los_with(from, to, CultureTest::Collision)
    }

    /// Line of sight seeing the culture objects `test` counts (none: the bare terrain).
    pub fn los_with(
        &mut self,
        from: Geodetic,
        to: Geodetic,
        test: CultureTest,
    ) -> Result<LosResult, QueryError> {
        self.los_refracted(from, to, test, Refraction::NONE)
    }

    /// Line of sight along the path light takes through the air: bent by `refraction` (the
    /// sightline bows up from the chord by `k s (D − s) / 2R` at `s` along its length `D`,
    /// which is the straight line over an earth of radius `R / (1 − k)`), seeing the culture
    /// objects `test` counts. A hit's point and range are on that path.
    pub fn los_refracted(
        &mut self,
        from: Geodetic,
        to: Geodetic,
        test: CultureTest,
        refraction: Refraction,
    ) -> Result<LosResult, QueryError> {
        for p in [from, to] {
            if !(p.lat_deg.is_finite() && p.lon_deg.is_finite())
                || p.lat_deg.abs() > 90.0
                || p.lon_deg.abs() > 360.0
            {
                return Err(QueryError::Invalid {
                    lat_deg: p.lat_deg,
                    lon_deg: p.lon_deg,
                });
            }
            if !(LOS_MIN_ALT_M..=LOS_MAX_ALT_M).contains(&p.alt_m) {
                return Err(QueryError::Altitude { alt_m: p.alt_m });
            }
        }
        self.refresh_edits();
        let a = from.to_ecef();
        let b = to.to_ecef();
        let length_m = (b - a).length();
        let lifted = |t: f64| refraction.lift_m(length_m, t);
        let pieces = ((length_m / PIECE_M).ceil() as usize).max(1);
        let g = self.layout.grid;
        let mut start = from;
        let mut crosses = false;
        for p in 0..pieces {
            let t0 = p as f64 / pieces as f64;
            let t1 = (p + 1) as f64 / pieces as f64;
            let mid = Geodetic::from_ecef(a + (b - a) * (0.5 * (t0 + t1)));
            let end = if p + 1 == pieces {
                to
            } else {
                Geodetic::from_ecef(a + (b - a) * t1)
            };
            let piece = Piece {
                x0: (start.lon_deg - g.west_lon_deg) / g.dlon_deg,
                y0: (start.lat_deg - g.south_lat_deg) / g.dlat_deg,
                x1: (end.lon_deg - g.west_lon_deg) / g.dlon_deg,
                y1: (end.lat_deg - g.south_lat_deg) / g.dlat_deg,
                alt: quadratic(
                    start.alt_m - self.geoid.undulation_m(start.lat_deg, start.lon_deg)
                        + lifted(t0),
                    mid.alt_m - self.geoid.undulation_m(mid.lat_deg, mid.lon_deg)
                        + lifted(0.5 * (t0 + t1)),
                    end.alt_m - self.geoid.undulation_m(end.lat_deg, end.lon_deg) + lifted(t1),
                ),
            };
            let terrain = self.trace_piece(&piece, &mut crosses)?;
            let culture = self.trace_culture(&piece, terrain.map_or(1.0, |(s, _, _)| s), test)?;
            let hit = match (culture, terrain) {
                (Some((s, hit, material)), _) => Some((s, material, 0, Some(hit))),
                (None, Some((s, material, level))) => Some((s, material, level, None)),
                (None, None) => None,
            };
            if let Some((s, material, level, culture)) = hit {
                let t = t0 + s * (t1 - t0);
                let mut point = Geodetic::from_ecef(a + (b - a) * t);
                point.alt_m += lifted(t);
                return Ok(LosResult {
                    visible: false,
                    hit: Some(LosHit {
                        point,
                        range_m: t * length_m,
                        material,
                        level,
                        culture,
                    }),
                });
            }
            start = end;
        }
        if !crosses {
            return Err(QueryError::Misses {
                lat_deg: from.lat_deg,
                lon_deg: from.lon_deg,
            });
        }
        Ok(LosResult {
            visible: true,
            hit: None,
        })
    }

    /// First hit along one piece: (parameter in the piece, material, level).
    ///
    /// Walks the tiles' min/max quadtrees from the root down: a node whose highest point is
    /// below the sightline over the node's stretch is skipped whole; in a leaf that cannot be
    /// skipped, cells are walked one by one (Amanatides and Woo's grid traversal) and a cell is
    /// tested exactly only when the sightline comes below its highest corner.
    /// Sets `crosses` when the piece passes over the database.
    fn trace_piece(
        &mut self,
        piece: &Piece,
        crosses: &mut bool,
    ) -> Result<Option<(f64, Material, u8)>, QueryError> {
        let g = self.layout.grid;
        let max_x = (g.cols - 1) as f64;
        let max_y = (g.rows - 1) as f64;
        let (dx, dy) = (piece.x1 - piece.x0, piece.y1 - piece.y0);
        // Clip to the database widened by half a post, where the edge posts' terrain extends: a
        // chord along an edge bows off the parallel or meridian it joins (by 0.1 m over 3 km)
        // and must still see the terrain it runs along.
        const EDGE: f64 = 0.5;
        let Some((mut s, s_end)) = clip(piece.x0, dx, -EDGE, max_x + EDGE, 0.0, 1.0)
            .and_then(|(a, b)| clip(piece.y0, dy, -EDGE, max_y + EDGE, a, b))
        else {
            return Ok(None);
        };
        *crosses = true;
        let edits = Arc::clone(&self.edits);
        let db_max = f64::from(self.db.manifest().max_elevation_m) + f64::from(edits.max_raise_m());
        if piece.alt.min_on(s, s_end) > db_max {
            return Ok(None);
        }
        let walk = Walk::new(piece);
        let nudge = 1e-9 / (dx.abs() + dy.abs()).max(1.0);
        let shift = self.fast.tile_shift;
        let tile_cells = 1usize << shift;
        let (last_cx, last_cy) = (self.fast.last_cell_col, self.fast.last_cell_row);
        while s < s_end {
            let probe = (s + nudge).min(s_end);
            let cx = ((piece.x0 + dx * probe).max(0.0) as usize).min(last_cx);
            let cy = ((piece.y0 + dy * probe).max(0.0) as usize).min(last_cy);
            let key = TileKey {
                level: 0,
                row: (cy >> shift) as u32,
                col: (cx >> shift) as u32,
            };
            let tile = self.tiles.get(key)?;
            let (ti0, tj0) = ((cy >> shift) << shift, (cx >> shift) << shift);
            let depth = tile.quadtree_depth;
            let raise_m = edits.tile_range_m(key.row, key.col).0;
            // Descend the quadtree to the largest node that can be skipped, or to a leaf.
            let mut leaf_end = s_end;
            let mut leaf_lo = (tj0, ti0);
            let mut skipped = false;
            for d in 0..=depth {
                let node_cells = tile_cells >> d;
                let (nx, ny) = ((cx - tj0) / node_cells, (cy - ti0) / node_cells);
                let (x_lo, y_lo) = (tj0 + nx * node_cells, ti0 + ny * node_cells);
                let out = walk
                    .exit_widened(
                        (x_lo, x_lo + node_cells, max_x),
                        (y_lo, y_lo + node_cells, max_y),
                        EDGE,
                        s,
                    )
                    .min(s_end);
                let bounds = tile.nodes[quadtree_index(d, nx, ny)];
                if piece.alt.min_on(s, out) > f64::from(bounds.max_m + raise_m) {
                    s = out.max(s + nudge);
                    skipped = true;
                    break;
                }
                leaf_end = out;
                leaf_lo = (x_lo, y_lo);
            }
            if skipped {
                continue;
            }
            // The leaf's cells, clamped so that a probe landing exactly on the leaf's edge (a
            // sightline through a post) stays in this leaf and this tile.
            let leaf_cells = tile_cells >> depth;
            let (leaf_x_hi, leaf_y_hi) = (
                (leaf_lo.0 + leaf_cells - 1).min(last_cx),
                (leaf_lo.1 + leaf_cells - 1).min(last_cy),
            );
            // Walk the leaf's cells.
            let mut sc = s;
            while sc < leaf_end {
                let probe = (sc + nudge).min(leaf_end);
                let cx = ((piece.x0 + dx * probe).max(0.0) as usize).clamp(leaf_lo.0, leaf_x_hi);
                let cy = ((piece.y0 + dy * probe).max(0.0) as usize).clamp(leaf_lo.1, leaf_y_hi);
                let cell_out = walk
                    .exit_widened((cx, cx + 1, max_x), (cy, cy + 1, max_y), EDGE, sc)
                    .min(leaf_end)
                    .max(sc + nudge);
                let (i, j) = (cy - ti0, cx - tj0);
                let corners = tile.cell_corners(i, j);
                let refined = edits.cell((cy as u32, cx as u32));
                let top = corners.iter().fold(f32::NEG_INFINITY, |m, &h| m.max(h))
                    + refined.map_or(0.0, |r| r.max_m);
                if piece.alt.min_on(sc, cell_out) <= f64::from(top) {
                    let (fx, fy) = (cx as f64, cy as f64);
                    let hit = match refined {
                        Some(r) => refined_cell_hit(corners, r, piece, fx, fy, sc, cell_out),
                        None => cell_hit(corners, piece, fx, fy, sc, cell_out),
                    };
                    if let Some(hit) = hit {
                        let (hx, hy) = (piece.x0 + dx * hit, piece.y0 + dy * hit);
                        let ni = ((hy - ti0 as f64).round().max(0.0) as usize)
                            .min(tile.posts_per_side - 1);
                        let nj = ((hx - tj0 as f64).round().max(0.0) as usize)
                            .min(tile.posts_per_side - 1);
                        return Ok(Some((
                            hit,
                            tile.material_at(ni, nj),
                            tile.degraded_from_level.unwrap_or(0),
                        )));
                    }
                }
                sc = cell_out;
            }
            s = leaf_end.max(s + nudge);
        }
        Ok(None)
    }

    /// Height of the highest surface at a point counting the culture objects' tops (a
    /// building's roof, as its box, a crown's top, a pole's top), with the bare terrain. Every
    /// object counts, fences included. Objects are taken from the point's finest tile and from
    /// every tile within the widest footprint of it, loaded where not resident (see the
    /// module's limits).
    pub fn hot_with_culture(
        &mut self,
        lat_deg: f64,
        lon_deg: f64,
    ) -> Result<CultureSurface, QueryError> {
        let terrain = self.hot(lat_deg, lon_deg)?;
        let mut out = CultureSurface {
            terrain,
            height_msl_m: terrain.height_msl_m,
            normal_enu: terrain.normal_enu,
            culture: None,
        };
        let Some(bounds) = self.culture else {
            return Ok(out);
        };
        if terrain.height_msl_m >= bounds.top_msl_m {
            return Ok(out);
        }
        let home = self.cell(lat_deg, lon_deg)?.key;
        let g = self.layout.grid;
        let col = (lon_deg - g.west_lon_deg) / g.dlon_deg;
        let row = (lat_deg - g.south_lat_deg) / g.dlat_deg;
        let (bx, by) = bounds.footprint_posts;
        let cells = f64::from(self.layout.tile_cells);
        let (tiles_r, tiles_c) = self.layout.tiles_at(0);
        let (c_lo, c_hi) = tile_span(col - bx, col + bx, cells, tiles_c);
        let (r_lo, r_hi) = tile_span(row - by, row + by, cells, tiles_r);
        for tr in r_lo..=r_hi {
            for tc in c_lo..=c_hi {
                let key = TileKey {
                    level: 0,
                    row: tr,
                    col: tc,
                };
                // Every tile within the widest footprint is loaded, so the answer does not
                // depend on what is resident; one that cannot be read beside the point's own
                // holds no culture.
                let tile = match self.tiles.get_arc(key) {
                    Ok(tile) => tile,
                    Err(e) if key == home => return Err(e),
                    Err(_) => continue,
                };
                let Some(index) = self.tiles.culture_index(key, &tile) else {
                    continue;
                };
                self.culture_top_in_tile(&index, key, col, row, &mut out);
            }
        }
        Ok(out)
    }

    /// Height above the highest surface counting culture ([`QuerySession::hot_with_culture`])
    /// of a geodetic point (altitude above the ellipsoid), with that surface.
    pub fn hat_with_culture(
        &mut self,
        point: Geodetic,
    ) -> Result<(f64, CultureSurface), QueryError> {
        let s = self.hot_with_culture(point.lat_deg, point.lon_deg)?;
        Ok((point.alt_m - s.height_ellipsoid_m(), s))
    }

    /// Raises `out` to the highest top of `index`'s objects over finest-grid `(col, row)`.
    fn culture_top_in_tile(
        &self,
        index: &CultureIndex,
        key: TileKey,
        col: f64,
        row: f64,
        out: &mut CultureSurface,
    ) {
        let cells = f64::from(self.layout.tile_cells);
        let (ox, oy) = (f64::from(key.col) * cells, f64::from(key.row) * cells);
        let [east_m, north_m] = index.min_m_per_post;
        let (mx, my) = (index.footprint_m / east_m, index.footprint_m / north_m);
        let (lx, ly) = (col - ox, row - oy);
        if lx < -mx || lx > cells + mx || ly < -my || ly > cells + my {
            return;
        }
        let block = CULTURE_BLOCK_CELLS as f64;
        let max_block = CultureIndex::blocks_per_side(self.layout.tile_cells) - 1;
        let (br_lo, br_hi) = block_span(ly - my, ly + my, block, max_block);
        let (bc_lo, bc_hi) = block_span(lx - mx, lx + mx, block, max_block);
        let items = index.items();
        for br in br_lo..=br_hi {
            for b in index.blocks_in_row(br, bc_lo, bc_hi) {
                if f64::from(b.top_msl_m) <= out.height_msl_m {
                    continue;
                }
                let (bmx, bmy) = (
                    f64::from(b.footprint_m) / east_m,
                    f64::from(b.footprint_m) / north_m,
                );
                let (x0, y0) = (
                    f64::from(b.block_col) * block,
                    f64::from(b.block_row) * block,
                );
                if lx < x0 - bmx || lx > x0 + block + bmx || ly < y0 - bmy || ly > y0 + block + bmy
                {
                    continue;
                }
                for k in index.block_items(b) {
                    let item = &items[k];
                    let r = f64::from(item.footprint_radius_m());
                    if f64::from(item.base_m + item.height_m) <= out.height_msl_m
                        || (lx - f64::from(item.fj)).abs() > r / east_m
                        || (ly - f64::from(item.fi)).abs() > r / north_m
                    {
                        continue;
                    }
                    let frame = ItemFrame::new(&self.layout, key, item);
                    let p = frame.local(col, row, 0.0);
                    for volume in item.volume().into_iter().flatten() {
                        if let Some((z, normal)) = top_at(&volume, p[0], p[1]) {
                            let top = frame.base_m + z;
                            if top > out.height_msl_m {
                                out.height_msl_m = top;
                                out.normal_enu = frame.to_enu(normal);
                                out.culture = Some(CultureHit {
                                    kind: item.kind,
                                    tile: key,
                                    index: k,
                                    item: *item,
                                    normal_enu: out.normal_enu,
                                });
                            }
                        }
                    }
                }
            }
        }
    }

    /// First culture object `test` counts that the piece enters in `[0, s_hi]`: (parameter in
    /// the piece, the object, the terrain's material under its centre).
    fn trace_culture(
        &mut self,
        piece: &Piece,
        s_hi: f64,
        test: CultureTest,
    ) -> Result<Option<(f64, CultureHit, Material)>, QueryError> {
        let Some(bounds) = self.culture else {
            return Ok(None);
        };
        if test == CultureTest::Ignore || s_hi.is_nan() || s_hi < 0.0 {
            return Ok(None);
        }
        let g = self.layout.grid;
        let (max_x, max_y) = ((g.cols - 1) as f64, (g.rows - 1) as f64);
        let (dx, dy) = (piece.x1 - piece.x0, piece.y1 - piece.y0);
        let (bx, by) = bounds.footprint_posts;
        let Some((s0, s1)) = clip(piece.x0, dx, -bx, max_x + bx, 0.0, s_hi)
            .and_then(|(a, b)| clip(piece.y0, dy, -by, max_y + by, a, b))
        else {
            return Ok(None);
        };
        let highest_top = bounds.top_msl_m;
        if piece.alt.min_on(s0, s1) > highest_top {
            return Ok(None);
        }
        // The stretch over the database proper: the tiles under it are the terrain walk's.
        let over = clip(piece.x0, dx, 0.0, max_x, s0, s1)
            .and_then(|(a, b)| clip(piece.y0, dy, 0.0, max_y, a, b));
        let cells = f64::from(self.layout.tile_cells);
        let (tiles_r, tiles_c) = self.layout.tiles_at(0);
        let (xa, xb) = (piece.x0 + dx * s0, piece.x0 + dx * s1);
        let (ya, yb) = (piece.y0 + dy * s0, piece.y0 + dy * s1);
        let (c_lo, c_hi) = tile_span(xa.min(xb) - bx, xa.max(xb) + bx, cells, tiles_c);
        let (r_lo, r_hi) = tile_span(ya.min(yb) - by, ya.max(yb) + by, cells, tiles_r);
        let mut best: Option<(f64, CultureHit, Material)> = None;
        // Tiles, block rows and blocks are visited in the piece's direction, so that the first
        // hit found caps the stretch the rest are tested over.
        for tr in along(r_lo, r_hi, dy) {
            for tc in along(c_lo, c_hi, dx) {
                let key = TileKey {
                    level: 0,
                    row: tr,
                    col: tc,
                };
                let (x_lo, y_lo) = (f64::from(tc) * cells, f64::from(tr) * cells);
                let (x_hi, y_hi) = ((x_lo + cells).min(max_x), (y_lo + cells).min(max_y));
                let s_cap = best.map_or(s1, |(s, _, _)| s);
                // Not within the widest footprint of the tile, or above the highest top while
                // within it: nothing of it can be met.
                let Some((sa, sb)) = clip(piece.x0, dx, x_lo - bx, x_hi + bx, s0, s_cap)
                    .and_then(|(a, b)| clip(piece.y0, dy, y_lo - by, y_hi + by, a, b))
                else {
                    continue;
                };
                if piece.alt.min_on(sa, sb) > highest_top {
                    continue;
                }
                // Every other tile is loaded, whether or not it is resident, so that the answer
                // does not depend on the paging cache's state. One the piece does not pass
                // over that cannot be read (nor rebuilt from a coarser level) holds no culture.
                let tile = match self.tiles.get_arc(key) {
                    Ok(tile) => tile,
                    Err(e) => {
                        let passes_over = over
                            .and_then(|(a, b)| clip(piece.x0, dx, x_lo, x_hi, a, b.min(s_cap)))
                            .and_then(|(a, b)| clip(piece.y0, dy, y_lo, y_hi, a, b))
                            .is_some();
                        if passes_over {
                            return Err(e);
                        }
                        continue;
                    }
                };
                let Some(index) = self.tiles.culture_index(key, &tile) else {
                    continue;
                };
                if let Some(hit) = self.culture_in_tile(&index, key, piece, s0, s_cap, test) {
                    if best.is_none_or(|(s, _, _)| hit.0 < s) {
                        best = Some(hit);
                    }
                }
            }
        }
        Ok(best)
    }

    /// [`QuerySession::trace_culture`] on one tile's objects, over `[s_lo, s_hi]`.
    fn culture_in_tile(
        &self,
        index: &CultureIndex,
        key: TileKey,
        piece: &Piece,
        s_lo: f64,
        s_hi: f64,
        test: CultureTest,
    ) -> Option<(f64, CultureHit, Material)> {
        let cells = f64::from(self.layout.tile_cells);
        let (ox, oy) = (f64::from(key.col) * cells, f64::from(key.row) * cells);
        let [east_m, north_m] = index.min_m_per_post;
        let (mx, my) = (index.footprint_m / east_m, index.footprint_m / north_m);
        let (dx, dy) = (piece.x1 - piece.x0, piece.y1 - piece.y0);
        let (sa, sb) = clip(piece.x0, dx, ox - mx, ox + cells + mx, s_lo, s_hi)
            .and_then(|(a, b)| clip(piece.y0, dy, oy - my, oy + cells + my, a, b))?;
        if piece.alt.min_on(sa, sb) > index.top_msl_m {
            return None;
        }
        let block = CULTURE_BLOCK_CELLS as f64;
        let max_block = CultureIndex::blocks_per_side(self.layout.tile_cells) - 1;
        let (ya, yb) = (piece.y0 + dy * sa - oy, piece.y0 + dy * sb - oy);
        let (br_lo, br_hi) = block_span(ya.min(yb) - my, ya.max(yb) + my, block, max_block);
        let items = index.items();
        let tile = &index.tile;
        let mut best: Option<(f64, CultureHit, Material)> = None;
        let mut s_cap = sb;
        for br in along(br_lo, br_hi, dy) {
            let y_band = oy + f64::from(br) * block;
            let Some((sc, sd)) = clip(piece.y0, dy, y_band - my, y_band + block + my, sa, s_cap)
            else {
                continue;
            };
            let (xc, xd) = (piece.x0 + dx * sc - ox, piece.x0 + dx * sd - ox);
            let (bc_lo, bc_hi) = block_span(xc.min(xd) - mx, xc.max(xd) + mx, block, max_block);
            let row_blocks = index.blocks_in_row(br, bc_lo, bc_hi);
            for n in along(0, row_blocks.len() as u32, dx) {
                let Some(b) = row_blocks.get(n as usize) else {
                    continue;
                };
                let (bmx, bmy) = (
                    f64::from(b.footprint_m) / east_m,
                    f64::from(b.footprint_m) / north_m,
                );
                let bx0 = ox + f64::from(b.block_col) * block;
                let by0 = oy + f64::from(b.block_row) * block;
                let Some((se, sf)) = clip(piece.x0, dx, bx0 - bmx, bx0 + block + bmx, sc, s_cap)
                    .and_then(|(a, b)| clip(piece.y0, dy, by0 - bmy, by0 + block + bmy, a, b))
                else {
                    continue;
                };
                if piece.alt.min_on(se, sf) > f64::from(b.top_msl_m) {
                    continue;
                }
                for k in index.block_items(b) {
                    let item = &items[k];
                    if !test.counts(item.kind) {
                        continue;
                    }
                    let r = f64::from(item.footprint_radius_m());
                    let (gx, gy) = (ox + f64::from(item.fj), oy + f64::from(item.fi));
                    let Some((sg, sh)) = clip(
                        piece.x0,
                        dx,
                        gx - r / east_m,
                        gx + r / east_m,
                        se,
                        sf.min(s_cap),
                    )
                    .and_then(|(a, b)| {
                        clip(piece.y0, dy, gy - r / north_m, gy + r / north_m, a, b)
                    }) else {
                        continue;
                    };
                    if piece.alt.min_on(sg, sh) > f64::from(item.base_m + item.height_m) {
                        continue;
                    }
                    // Straight across the footprint: the altitude's chord between its ends.
                    let frame = ItemFrame::new(&self.layout, key, item);
                    let at =
                        |s: f64| frame.local(piece.x0 + dx * s, piece.y0 + dy * s, piece.alt.at(s));
                    let (p0, p1) = (at(sg), at(sh));
                    for volume in item.volume().into_iter().flatten() {
                        let Some(entry) = segment_entry(&volume, p0, p1) else {
                            continue;
                        };
                        let s = sg + entry.t * (sh - sg);
                        if s > s_cap || best.is_some_and(|(b, _, _)| s >= b) {
                            continue;
                        }
                        let n = tile.posts_per_side;
                        let ni = (f64::from(item.fi).round().max(0.0) as usize).min(n - 1);
                        let nj = (f64::from(item.fj).round().max(0.0) as usize).min(n - 1);
                        s_cap = s;
                        best = Some((
                            s,
                            CultureHit {
                                kind: item.kind,
                                tile: key,
                                index: k,
                                item: *item,
                                normal_enu: frame.to_enu(entry.normal),
                            },
                            tile.material_at(ni, nj),
                        ));
                    }
                }
            }
        }
        best
    }
}

impl TileSlots {
    /// The finest tile `key`, from the slots, the cache, the store, or rebuilt from the nearest
    /// readable coarser level.
    #[inline]
    fn get(&mut self, key: TileKey) -> Result<&Tile, QueryError> {
        self.get_slot(key).map(|t| &**t)
    }

    /// [`TileSlots::get`], as the shared tile.
    fn get_arc(&mut self, key: TileKey) -> Result<Arc<Tile>, QueryError> {
        self.get_slot(key).map(Arc::clone)
    }

    #[inline]
    fn get_slot(&mut self, key: TileKey) -> Result<&Arc<Tile>, QueryError> {
        let epoch = self.cache.eviction_epoch();
        let slot = key.row as usize * self.tile_cols + key.col as usize;
        let missing = !matches!(self.slots.get(slot), Some(Some(_)));
        if epoch != self.epoch || (missing && self.uncached >= SESSION_TILES) {
            self.forget(epoch);
        }
        let entry = self
            .slots
            .get_mut(slot)
            .ok_or(QueryError::NoSuchTile(key))?;
        if entry.is_none() {
            let (tile, cached) = fetch(&self.cache, &self.layout, key)?;
            *entry = Some(tile);
            self.uncached += usize::from(!cached);
        }
        entry.as_ref().ok_or(QueryError::NoSuchTile(key))
    }

    /// Forgets every slotted tile and culture index.
    fn forget(&mut self, epoch: u64) {
        self.slots.iter_mut().for_each(|s| *s = None);
        self.culture.clear();
        self.uncached = 0;
        self.epoch = epoch;
    }

    /// The culture index of `tile` (slotted as `key`), built on first use; `None` where the
    /// tile has no culture.
    fn culture_index(&mut self, key: TileKey, tile: &Arc<Tile>) -> Option<Arc<CultureIndex>> {
        if tile.culture.as_ref().is_none_or(|c| c.items.is_empty()) {
            return None;
        }
        if let Some(index) = self.culture.get(&key) {
            if Arc::ptr_eq(&index.tile, tile) {
                return Some(Arc::clone(index));
            }
        }
        let index = Arc::new(CultureIndex::new(&self.layout, Arc::clone(tile))?);
        self.culture.insert(key, Arc::clone(&index));
        Some(index)
    }
}

/// Tiles `lo..=hi` of `count` that finest-grid coordinates `lo..=hi` fall in (clamped).
fn tile_span(lo: f64, hi: f64, cells: f64, count: u32) -> (u32, u32) {
    let last = count.saturating_sub(1);
    let at = |v: f64| ((v / cells).floor().max(0.0) as u32).min(last);
    (at(lo), at(hi))
}

/// `lo..=hi`, upwards where `d` is not negative and downwards where it is.
fn along(lo: u32, hi: u32, d: f64) -> impl Iterator<Item = u32> {
    let forward = d >= 0.0;
    (0..=hi.saturating_sub(lo)).map(move |k| if forward { lo + k } else { hi - k })
}

/// Blocks `lo..=hi` (at most `max_block`) that tile-local coordinates `lo..=hi` fall in.
fn block_span(lo: f64, hi: f64, block: f64, max_block: u32) -> (u32, u32) {
    let at = |v: f64| ((v / block).floor().max(0.0) as u32).min(max_block);
    (at(lo), at(hi))
}

/// Loads a finest tile, or rebuilds it from the nearest readable coarser level.
/// Returns the tile and whether the cache holds it too.
fn fetch(
    cache: &TileCache,
    layout: &PyramidLayout,
    key: TileKey,
) -> Result<(Arc<Tile>, bool), QueryError> {
    match cache.load_now_reporting(key) {
        Ok(t) => Ok(t),
        Err(first_error) => {
            let mut parent = key;
            loop {
                if parent.level + 1 >= layout.levels {
                    return Err(QueryError::Unavailable(first_error));
                }
                parent = parent.parent();
                if let Ok(p) = cache.load_now(parent) {
                    return Ok((Arc::new(resample_from_parent(layout, &p, key)), false));
                }
            }
        }
    }
}

/// A level-0 stand-in for an unreadable tile, sampled from a coarser tile's surface.
fn resample_from_parent(layout: &PyramidLayout, coarse: &Tile, key: TileKey) -> Tile {
    let n = layout.posts_per_side();
    let scale = (1u64 << coarse.key.level) as f64;
    let span = f64::from(layout.tile_cells);
    let mut elevation_m = Vec::with_capacity(n * n);
    let mut material = Vec::with_capacity(n * n);
    let coarse_span = span * scale;
    for i in 0..n {
        for j in 0..n {
            let row = f64::from(key.row) * span + i as f64;
            let col = f64::from(key.col) * span + j as f64;
            let fi = (row - f64::from(coarse.key.row) * coarse_span) / scale;
            let fj = (col - f64::from(coarse.key.col) * coarse_span) / scale;
            elevation_m.push(coarse.surface_height(fi, fj) as f32);
            let ni = (fi.round().max(0.0) as usize).min(coarse.posts_per_side - 1);
            let nj = (fj.round().max(0.0) as usize).min(coarse.posts_per_side - 1);
            material.push(coarse.material[ni * coarse.posts_per_side + nj]);
        }
    }
    // Bounds: the coarse tile's bounds hold the finest surface, so they stay conservative.
    let depth = coarse.quadtree_depth;
    Tile {
        key,
        posts_per_side: n,
        elevation_m,
        material,
        nodes: vec![coarse.bounds(); crate::pyramid::quadtree_node_count(depth)],
        quadtree_depth: depth,
        lod_errors: None,
        degraded_from_level: Some(coarse.key.level),
        culture: None,
    }
}

#[inline]
fn snap(x: f64) -> f64 {
    // For the non-negative indices this sees, a cast rounds without a libm call.
    let r = (x.max(0.0) + 0.5) as u64 as f64;
    if (x - r).abs() < POST_SNAP {
        r
    } else {
        x
    }
}

/// One piece of a sightline: linear in grid space, quadratic in altitude above sea level.
#[derive(Clone, Copy)]
struct Piece {
    x0: f64,
    y0: f64,
    x1: f64,
    y1: f64,
    alt: Quadratic,
}

#[derive(Clone, Copy)]
struct Quadratic {
    a: f64,
    b: f64,
    c: f64,
}

/// The quadratic through (0, v0), (0.5, vm), (1, v1).
fn quadratic(v0: f64, vm: f64, v1: f64) -> Quadratic {
    Quadratic {
        a: v0,
        b: 4.0 * vm - 3.0 * v0 - v1,
        c: 2.0 * v0 + 2.0 * v1 - 4.0 * vm,
    }
}

impl Quadratic {
    #[inline]
    fn at(&self, s: f64) -> f64 {
        self.a + s * (self.b + s * self.c)
    }

    /// Lowest value on `[s0, s1]`.
    #[inline]
    fn min_on(&self, s0: f64, s1: f64) -> f64 {
        let mut m = self.at(s0).min(self.at(s1));
        if self.c > 0.0 {
            let v = -self.b / (2.0 * self.c);
            if v > s0 && v < s1 {
                m = m.min(self.at(v));
            }
        }
        m
    }
}

/// Clips the parameter range `[s0, s1]` to `lo <= p0 + d s <= hi`.
fn clip(p0: f64, d: f64, lo: f64, hi: f64, s0: f64, s1: f64) -> Option<(f64, f64)> {
    if d.abs() < 1e-15 {
        return (p0 >= lo && p0 <= hi).then_some((s0, s1));
    }
    let (a, b) = ((lo - p0) / d, (hi - p0) / d);
    let (a, b) = if a < b { (a, b) } else { (b, a) };
    let (s0, s1) = (s0.max(a), s1.min(b));
    (s0 <= s1).then_some((s0, s1))
}

/// Exit parameters of a piece from axis-aligned boxes, with the divisions done once.
struct Walk {
    x0: f64,
    y0: f64,
    inv_dx: f64,
    inv_dy: f64,
    dx_sign: f64,
    dy_sign: f64,
}

impl Walk {
    fn new(piece: &Piece) -> Walk {
        let (dx, dy) = (piece.x1 - piece.x0, piece.y1 - piece.y0);
        Walk {
            x0: piece.x0,
            y0: piece.y0,
            inv_dx: if dx != 0.0 { 1.0 / dx } else { 0.0 },
            inv_dy: if dy != 0.0 { 1.0 / dy } else { 0.0 },
            dx_sign: dx.signum() * f64::from(u8::from(dx != 0.0)),
            dy_sign: dy.signum() * f64::from(u8::from(dy != 0.0)),
        }
    }

    /// Parameter where the piece leaves the box `[x_lo, x_hi] x [y_lo, y_hi]` going forward
    /// from `s` (never before `s`).
    #[inline]
    fn exit(&self, x_lo: f64, x_hi: f64, y_lo: f64, y_hi: f64, s: f64) -> f64 {
        let tx = if self.dx_sign > 0.0 {
            (x_hi - self.x0) * self.inv_dx
        } else if self.dx_sign < 0.0 {
            (x_lo - self.x0) * self.inv_dx
        } else {
            f64::INFINITY
        };
        let ty = if self.dy_sign > 0.0 {
            (y_hi - self.y0) * self.inv_dy
        } else if self.dy_sign < 0.0 {
            (y_lo - self.y0) * self.inv_dy
        } else {
            f64::INFINITY
        };
        tx.min(ty).max(s)
    }

    /// [`Walk::exit`] for a box of whole cells `(lo, hi, grid_max)` along each axis, widened by
    /// `edge` where it reaches the grid's first or last post: the piece runs on past the edge
    /// posts for up to `edge` cells and must leave such a box there, not at the edge.
    #[inline]
    fn exit_widened(
        &self,
        x: (usize, usize, f64),
        y: (usize, usize, f64),
        edge: f64,
        s: f64,
    ) -> f64 {
        let widen = |(lo, hi, max): (usize, usize, f64)| {
            let lo_f = if lo == 0 { -edge } else { lo as f64 };
            let hi_f = if hi as f64 >= max {
                max + edge
            } else {
                hi as f64
            };
            (lo_f, hi_f)
        };
        let ((x_lo, x_hi), (y_lo, y_hi)) = (widen(x), widen(y));
        self.exit(x_lo, x_hi, y_lo, y_hi, s)
    }
}

/// First parameter in `[s0, s1]` where the piece is at or below the triangles of the cell whose
/// south-west post is `(cx, cy)` and whose corners are `[h00, h01, h10, h11]`.
#[inline]
fn cell_hit(corners: [f32; 4], piece: &Piece, cx: f64, cy: f64, s0: f64, s1: f64) -> Option<f64> {
    split_cell_hit(
        corners,
        Diagonal::of_cell(cy as usize, cx as usize),
        piece,
        cx,
        cy,
        s0,
        s1,
    )
}

/// The surface's height above mean sea level at a point of `cell`: the tile's triangulated
/// height plus the edits' change where the cell is refined.
#[inline(always)]
fn height_in_cell(
    tiles: &mut TileSlots,
    cell: &CellRef,
    refined: Option<&CellLattice>,
) -> Result<f64, QueryError> {
    let tile = tiles.get(cell.key)?;
    let diagonal = Tile::cell_diagonal(cell.i, cell.j);
    let height = triangulated_height(tile.cell_corners(cell.i, cell.j), cell.u, cell.v, diagonal);
    Ok(match refined {
        Some(refined) => height + refined.delta_m(cell.u, cell.v, diagonal),
        None => height,
    })
}

/// [`cell_hit`] on a refined cell (`crate::edits`): the cell's own triangles outside the
/// refined window, the window's sub-cells (split along the cell's diagonal, carrying the cell's
/// height plus the edits' change) inside it, in the order the piece meets them.
fn refined_cell_hit(
    corners: [f32; 4],
    refined: &RefinedCell,
    piece: &Piece,
    cx: f64,
    cy: f64,
    s0: f64,
    s1: f64,
) -> Option<f64> {
    let diagonal = Diagonal::of_cell(cy as usize, cx as usize);
    let f = f64::from(refined.lattice.split);
    let (ox, oy) = (
        cx + f64::from(refined.lattice.origin.0) / f,
        cy + f64::from(refined.lattice.origin.1) / f,
    );
    let (na, nb) = (
        refined.lattice.posts.0 as usize,
        refined.lattice.posts.1 as usize,
    );
    // The piece in the window's sub-cells.
    let fine = Piece {
        x0: (piece.x0 - ox) * f,
        y0: (piece.y0 - oy) * f,
        x1: (piece.x1 - ox) * f,
        y1: (piece.y1 - oy) * f,
        alt: piece.alt,
    };
    let (dx, dy) = (fine.x1 - fine.x0, fine.y1 - fine.y0);
    let Some((w0, w1)) = clip(fine.x0, dx, 0.0, (na - 1) as f64, s0, s1)
        .and_then(|(a, b)| clip(fine.y0, dy, 0.0, (nb - 1) as f64, a, b))
    else {
        return cell_hit(corners, piece, cx, cy, s0, s1);
    };
    // Outside the window the cell's own triangles; a stretch shorter than a hair (a piece
    // entering the window across the cell's edge, by rounding) is the window's border, which
    // lies on the cell's triangles or its edge, and is not tested.
    const HAIR: f64 = 1e-6;
    let sub_cells = dx.abs() + dy.abs();
    if let Some(hit) = ((w0 - s0) * sub_cells > HAIR)
        .then(|| cell_hit(corners, piece, cx, cy, s0, w0))
        .flatten()
    {
        return Some(hit);
    }
    let base = |a: usize, b: usize| {
        triangulated_height(
            corners,
            (f64::from(refined.lattice.origin.0) + a as f64) / f,
            (f64::from(refined.lattice.origin.1) + b as f64) / f,
            diagonal,
        ) as f32
    };
    let walk = Walk::new(&fine);
    let nudge = 1e-9 / (dx.abs() + dy.abs()).max(1.0);
    // The highest the cell's own triangles reach over a block of the window: at its corners
    // or where the cell's diagonal crosses its sides (the surface is linear on each side).
    let (ox_f, oy_f) = (
        f64::from(refined.lattice.origin.0),
        f64::from(refined.lattice.origin.1),
    );
    let block_base_top = |a_lo: usize, a_hi: usize, b_lo: usize, b_hi: usize| -> f64 {
        let (x0, x1) = (ox_f + a_lo as f64, ox_f + a_hi as f64);
        let (y0, y1) = (oy_f + b_lo as f64, oy_f + b_hi as f64);
        let at = |x: f64, y: f64| triangulated_height(corners, x / f, y / f, diagonal);
        let mut top = at(x0, y0).max(at(x1, y0)).max(at(x0, y1)).max(at(x1, y1));
        // The diagonal: y = x (south-west to north-east) or y = f - x.
        let on = |x: f64| match diagonal {
            Diagonal::SouthWestNorthEast => x,
            Diagonal::NorthWestSouthEast => f - x,
        };
        for x in [x0, x1] {
            let y = on(x);
            if (y0..=y1).contains(&y) {
                top = top.max(at(x, y));
            }
        }
        for y in [y0, y1] {
            let x = on(y);
            if (x0..=x1).contains(&x) {
                top = top.max(at(x, y));
            }
        }
        top
    };
    let bs = BLOCK_SUB_CELLS as usize;
    let blocks_east = refined.blocks.0 as usize;
    let mut s = w0;
    while s < w1 {
        let probe = (s + nudge).min(w1);
        let a = ((fine.x0 + dx * probe).max(0.0) as usize).min(na - 2);
        let b = ((fine.y0 + dy * probe).max(0.0) as usize).min(nb - 2);
        let (ba, bb) = (a / bs, b / bs);
        let (a_lo, a_hi) = (ba * bs, ((ba + 1) * bs).min(na - 1));
        let (b_lo, b_hi) = (bb * bs, ((bb + 1) * bs).min(nb - 1));
        let block_out = walk
            .exit(a_lo as f64, a_hi as f64, b_lo as f64, b_hi as f64, s)
            .min(w1)
            .max(s + nudge);
        let block_max = refined
            .block_max_m
            .get(bb * blocks_east + ba)
            .copied()
            .unwrap_or(refined.max_m);
        // The sightline passes over a block above the cell's own triangles there plus the
        // block's highest rise; a block that only lowers the ground is met only where the
        // cell's own triangles are.
        let lowest = piece.alt.min_on(s, block_out);
        let skip = lowest > block_base_top(a_lo, a_hi, b_lo, b_hi) + f64::from(block_max.max(0.0))
            || (block_max <= 0.0 && cell_hit(corners, piece, cx, cy, s, block_out).is_none());
        if !skip {
            let mut sc = s;
            while sc < block_out {
                let probe = (sc + nudge).min(block_out);
                let a = ((fine.x0 + dx * probe).max(0.0) as usize).clamp(a_lo, a_hi - 1);
                let b = ((fine.y0 + dy * probe).max(0.0) as usize).clamp(b_lo, b_hi - 1);
                let out = walk
                    .exit(a as f64, a as f64 + 1.0, b as f64, b as f64 + 1.0, sc)
                    .min(block_out)
                    .max(sc + nudge);
                let change = refined.lattice.corners(a, b);
                let sub = [
                    base(a, b) + change[0],
                    base(a + 1, b) + change[1],
                    base(a, b + 1) + change[2],
                    base(a + 1, b + 1) + change[3],
                ];
                let top = sub.iter().fold(f32::NEG_INFINITY, |m, &h| m.max(h));
                if piece.alt.min_on(sc, out) <= f64::from(top) {
                    if let Some(hit) =
                        split_cell_hit(sub, diagonal, &fine, a as f64, b as f64, sc, out)
                    {
                        return Some(hit);
                    }
                }
                sc = out;
            }
        }
        s = block_out;
    }
    ((s1 - w1) * sub_cells > HAIR)
        .then(|| cell_hit(corners, piece, cx, cy, w1, s1))
        .flatten()
}

/// [`cell_hit`] on a unit cell at `(cx, cy)` split along `diagonal`.
#[inline]
fn split_cell_hit(
    corners: [f32; 4],
    diagonal: Diagonal,
    piece: &Piece,
    cx: f64,
    cy: f64,
    s0: f64,
    s1: f64,
) -> Option<f64> {
    match diagonal {
        Diagonal::SouthWestNorthEast => south_west_split_hit(corners, piece, cx, cy, s0, s1),
        Diagonal::NorthWestSouthEast => {
            // Mirrored east-west about the cell's middle, the cell is split south-west to
            // north-east; the piece's parameter (and so the answer) is unchanged.
            let [h00, h01, h10, h11] = corners;
            let mirrored = Piece {
                x0: 2.0 * cx + 1.0 - piece.x0,
                x1: 2.0 * cx + 1.0 - piece.x1,
                ..*piece
            };
            south_west_split_hit([h01, h00, h11, h10], &mirrored, cx, cy, s0, s1)
        }
    }
}

/// [`cell_hit`] on a cell split south-west to north-east.
fn south_west_split_hit(
    corners: [f32; 4],
    piece: &Piece,
    cx: f64,
    cy: f64,
    s0: f64,
    s1: f64,
) -> Option<f64> {
    let (dx, dy) = (piece.x1 - piece.x0, piece.y1 - piece.y0);
    let uv = |s: f64| {
        (
            (piece.x0 + dx * s - cx).clamp(0.0, 1.0),
            (piece.y0 + dy * s - cy).clamp(0.0, 1.0),
        )
    };
    // Split at the diagonal u = v.
    let du = dx - dy;
    let w0 = piece.x0 - cx - (piece.y0 - cy);
    let mut bounds = [s0, s1, s1];
    let mut count = 2;
    if du.abs() > 1e-15 {
        let sd = -w0 / du;
        if sd > s0 && sd < s1 {
            bounds = [s0, sd, s1];
            count = 3;
        }
    }
    for k in 0..count - 1 {
        let (sa, sb) = (bounds[k], bounds[k + 1]);
        // Within one triangle the terrain is linear along the piece: its ends decide.
        let height = |s: f64| {
            let (u, v) = uv(s);
            triangulated_height(corners, u, v, Diagonal::SouthWestNorthEast)
        };
        let fa = piece.alt.at(sa) - height(sa);
        if fa <= 0.0 {
            return Some(sa);
        }
        let fb = piece.alt.at(sb) - height(sb);
        if fb <= 0.0 {
            return Some(sa + fa / (fa - fb) * (sb - sa));
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::build::{build_pyramid, BuildError};
    use crate::database::{GeoidGrid, Manifest, MemoryTileStore};
    use crate::raster::{GeoGrid, Raster};
    use crate::{Material, PagingConfig};
    use proptest::prelude::*;

    proptest! {
        /// The division-free per-query index and the layout's general `locate` name the same
        /// tile and the same point in it.
        #[test]
        fn fast_cell_agrees_with_the_layout(rows in 2usize..300, cols in 2usize..300, fr in 0.0f64..=1.0, fc in 0.0f64..=1.0) {
            let grid = GeoGrid { south_lat_deg: 36.0, west_lon_deg: -121.0, dlat_deg: 0.00027, dlon_deg: 0.00033, rows, cols };
            let raster = Raster { grid, elevation_m: vec![1.0; rows * cols], material: Some(vec![Material::Grass; rows * cols]) };
            let store = Arc::new(MemoryTileStore::new());
            let summary = build_pyramid::<BuildError>(&raster, 16, &mut |t| { store.insert(t.key, t.encode()); Ok(()) }).expect("build");
            let db = Arc::new(TerrainDatabase::new(Manifest::from_build(&summary, GeoidGrid::zero(), 0, vec![]), store).expect("db"));
            let q = QuerySession::new(Arc::new(TileCache::new(db, PagingConfig::default()).expect("cache")));
            let (row_f, col_f) = (fr * (rows - 1) as f64, fc * (cols - 1) as f64);
            let lat = grid.south_lat_deg + row_f * grid.dlat_deg;
            let lon = grid.west_lon_deg + col_f * grid.dlon_deg;
            let cell = q.cell(lat, lon).expect("inside");
            let (key, fi, fj) = q.layout.locate(0, row_f, col_f);
            // Both name a cell holding the point; on a tile edge they may pick either side.
            let back = |k: TileKey, i: f64, j: f64| (f64::from(k.row) * 16.0 + i, f64::from(k.col) * 16.0 + j);
            let (r1, c1) = back(cell.key, cell.i as f64 + cell.v, cell.j as f64 + cell.u);
            let (r2, c2) = back(key, fi, fj);
            prop_assert!((r1 - r2).abs() < 1e-6 && (c1 - c2).abs() < 1e-6, "{:?} vs {:?}", (r1, c1), (r2, c2));
            prop_assert!(cell.u >= 0.0 && cell.u <= 1.0 && cell.v >= 0.0 && cell.v <= 1.0);
            prop_assert!(cell.i < 16 && cell.j < 16);
        }
    }
}
