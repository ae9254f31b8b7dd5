//! A terrain database: its manifest, its geoid grid and the store its tiles come from.
//!
//! The manifest is the database's table of contents (layout, vertical datum, statistics, where
//! the posts came from); the [`TileStore`] hands out tile bytes (a directory on disk in
//! `cig-terrain-io`, memory in tests). Heights in tiles are above mean sea level (EGM96), as in
//! DTED and SRTM and as CIGI 3 reports them; a coarse grid of EGM96 undulations carried in the
//! manifest turns them into heights above the WGS84 ellipsoid where geodetic altitudes are
//! compared (line of sight, height above terrain).

use crate::culture::CultureTile;
use crate::imagery::{ImageryDecodeError, ImageryKey, ImageryTile};
use crate::pyramid::{PyramidLayout, TileKey};
use crate::tile::{Tile, TileDecodeError};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::sync::Arc;

/// Version of the database layout (manifest + tiles) written by this build.
pub const DB_FORMAT_VERSION: u32 = 1;
/// Most finest-level tiles a database may have (query sessions index them densely).
pub const MAX_FINEST_TILES: u64 = 1 << 22;
/// The manifest's `format` field.
pub const DB_FORMAT_NAME: &str = "cig-terrain-db";

/// EGM96 geoid undulations on a coarse regular grid over the database (bilinear between nodes).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct GeoidGrid {
    pub south_lat_deg: f64,
    pub west_lon_deg: f64,
    pub step_deg: f64,
    pub rows: usize,
    pub cols: usize,
    /// Geoid height above the ellipsoid, metres, row-major, south row first.
    pub undulation_m: Vec<f32>,
}

impl GeoidGrid {
    /// Samples `undulation(lat, lon)` every `step_deg` over a rectangle (plus one node margin).
    pub fn sample(
        south_lat_deg: f64,
        west_lon_deg: f64,
        north_lat_deg: f64,
        east_lon_deg: f64,
        step_deg: f64,
        undulation: impl Fn(f64, f64) -> f64,
    ) -> GeoidGrid {
        let south = (south_lat_deg / step_deg).floor() * step_deg - step_deg;
        let west = (west_lon_deg / step_deg).floor() * step_deg - step_deg;
        let rows = ((north_lat_deg - south) / step_deg).ceil() as usize + 2;
        let cols = ((east_lon_deg - west) / step_deg).ceil() as usize + 2;
        let mut values = Vec::with_capacity(rows * cols);
        for r in 0..rows {
            for c in 0..cols {
                let lat = (south + r as f64 * step_deg).clamp(-90.0, 90.0);
                values.push(undulation(lat, west + c as f64 * step_deg) as f32);
            }
        }
        GeoidGrid {
            south_lat_deg: south,
            west_lon_deg: west,
            step_deg,
            rows,
            cols,
            undulation_m: values,
        }
    }

    /// A grid that says the geoid and the ellipsoid coincide (N = 0 everywhere).
    pub fn zero() -> GeoidGrid {
        GeoidGrid {
            south_lat_deg: -90.0,
            west_lon_deg: -180.0,
            step_deg: 180.0,
            rows: 2,
            cols: 3,
            undulation_m: vec![0.0; 6],
        }
    }

    fn is_consistent(&self) -> bool {
        self.rows >= 2
            && self.cols >= 2
            && self.rows <= 100_000
            && self.cols <= 100_000
            && self.step_deg.is_finite()
            && self.step_deg > 0.0
            && self.rows.checked_mul(self.cols) == Some(self.undulation_m.len())
            && self.undulation_m.iter().all(|v| v.is_finite())
    }
}

/// A [`GeoidGrid`] prepared for many lookups: no division per lookup.
#[derive(Clone, Debug)]
pub struct GeoidLookup {
    south_lat_deg: f64,
    west_lon_deg: f64,
    nodes_per_deg: f64,
    max_row: f64,
    max_col: f64,
    last_cell_row: usize,
    last_cell_col: usize,
    cols: usize,
    undulation_m: Vec<f32>,
}

impl GeoidLookup {
    pub fn new(grid: &GeoidGrid) -> GeoidLookup {
        GeoidLookup {
            south_lat_deg: grid.south_lat_deg,
            west_lon_deg: grid.west_lon_deg,
            nodes_per_deg: 1.0 / grid.step_deg,
            max_row: (grid.rows - 1) as f64,
            max_col: (grid.cols - 1) as f64,
            last_cell_row: grid.rows.saturating_sub(2),
            last_cell_col: grid.cols.saturating_sub(2),
            cols: grid.cols,
            undulation_m: grid.undulation_m.clone(),
        }
    }

    /// Undulation at a point, metres (bilinear; clamped at the grid's edges).
    #[inline]
    pub fn undulation_m(&self, lat_deg: f64, lon_deg: f64) -> f64 {
        let fr = ((lat_deg - self.south_lat_deg) * self.nodes_per_deg).clamp(0.0, self.max_row);
        let fc = ((lon_deg - self.west_lon_deg) * self.nodes_per_deg).clamp(0.0, self.max_col);
        let r0 = (fr as usize).min(self.last_cell_row);
        let c0 = (fc as usize).min(self.last_cell_col);
        let (tr, tc) = (fr - r0 as f64, fc - c0 as f64);
        let k = r0 * self.cols + c0;
        let n = &self.undulation_m[k..k + self.cols + 2];
        let (a, b, c, d) = (
            f64::from(n[0]),
            f64::from(n[1]),
            f64::from(n[self.cols]),
            f64::from(n[self.cols + 1]),
        );
        (1.0 - tr) * ((1.0 - tc) * a + tc * b) + tr * ((1.0 - tc) * c + tc * d)
    }
}

/// The database's table of contents (`manifest.json` on disk).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Manifest {
    /// Always [`DB_FORMAT_NAME`].
    pub format: String,
    /// [`DB_FORMAT_VERSION`] of the writer.
    pub format_version: u32,
    pub layout: PyramidLayout,
    /// Post spacing at the finest level in metres at the centre (north-south, east-west).
    pub spacing_m: [f64; 2],
    /// Datum of tile heights: "egm96" (mean sea level).
    pub vertical_datum: String,
    pub geoid: GeoidGrid,
    pub min_elevation_m: f32,
    pub max_elevation_m: f32,
    /// Void posts that were filled at build time.
    pub void_posts_filled: u64,
    /// Finest-level posts of each material.
    pub material_posts: BTreeMap<String, u64>,
    /// Where the posts came from (one line each: importer and file, or generator and seed).
    pub sources: Vec<String>,
    /// Total number of tiles over all levels.
    pub tile_count: u64,
    /// Draped imagery, when the database has any (`crate::imagery`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub imagery: Option<crate::imagery::ImageryManifest>,
    /// Culture on the finest tiles, when the database has any (`crate::culture`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub culture: Option<crate::culture::CultureManifest>,
}

/// Why a manifest is not usable.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum ManifestError {
    #[error("not a cig terrain database (format {0:?})")]
    Format(String),
    #[error(
        "database format version {found} is not supported (this build reads {DB_FORMAT_VERSION})"
    )]
    Version { found: u32 },
    #[error("manifest is inconsistent: {0}")]
    Inconsistent(String),
}

impl Manifest {
    /// Checks what the rest of the code relies on.
    pub fn validate(&self) -> Result<(), ManifestError> {
        if self.format != DB_FORMAT_NAME {
            return Err(ManifestError::Format(self.format.clone()));
        }
        if self.format_version != DB_FORMAT_VERSION {
            return Err(ManifestError::Version {
                found: self.format_version,
            });
        }
        let g = &self.layout.grid;
        let bad = |what: &str| Err(ManifestError::Inconsistent(what.to_string()));
        if !(g.dlat_deg.is_finite()
            && g.dlat_deg > 0.0
            && g.dlon_deg.is_finite()
            && g.dlon_deg > 0.0)
        {
            return bad("post spacing must be positive");
        }
        if !(g.south_lat_deg.is_finite() && g.west_lon_deg.is_finite()) {
            return bad("origin is not a number");
        }
        if g.rows < 2 || g.cols < 2 || g.rows > 10_000_000 || g.cols > 10_000_000 {
            return bad("grid size out of range");
        }
        if g.south_lat_deg < -90.0 || g.north_lat_deg() > 90.0 {
            return bad("grid extends past a pole");
        }
        let t = self.layout.tile_cells;
        if !t.is_power_of_two() || !(16..=4096).contains(&t) {
            return bad("tile size must be a power of two from 16 to 4096");
        }
        if PyramidLayout::new(*g, t) != self.layout {
            return bad("level count does not match the grid");
        }
        let (tile_rows, tile_cols) = self.layout.tiles_at(0);
        if u64::from(tile_rows) * u64::from(tile_cols) > MAX_FINEST_TILES {
            return bad("more finest tiles than this build handles (4 194 304)");
        }
        if !self.geoid.is_consistent() {
            return bad("geoid grid");
        }
        if let Some(imagery) = &self.imagery {
            imagery
                .layout
                .validate(g)
                .map_err(ManifestError::Inconsistent)?;
        }
        Ok(())
    }
}

/// Why a store could not hand out a tile's bytes.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum StoreError {
    #[error("tile file is missing: {0}")]
    Missing(String),
    #[error("cannot read tile: {reason}: {location}")]
    Io { reason: String, location: String },
}

/// Where tile bytes come from. Implementations must be cheap to call from several threads.
pub trait TileStore: Send + Sync {
    /// The bytes of one tile file.
    fn read_tile(&self, key: TileKey) -> Result<Vec<u8>, StoreError>;
    /// Where a tile lives, for messages (a path, or "memory").
    fn location(&self, key: TileKey) -> String;
    /// The bytes of one imagery tile (`crate::imagery`); `Missing` where none is stored.
    fn read_imagery_tile(&self, key: ImageryKey) -> Result<Vec<u8>, StoreError> {
        Err(StoreError::Missing(self.imagery_location(key)))
    }
    /// Where an imagery tile lives, for messages.
    fn imagery_location(&self, key: ImageryKey) -> String {
        format!("{key}")
    }
    /// The bytes of one finest tile's culture (`crate::culture`); `Missing` where none is
    /// stored.
    fn read_culture_tile(&self, key: TileKey) -> Result<Vec<u8>, StoreError> {
        Err(StoreError::Missing(self.culture_location(key)))
    }
    /// Where a culture tile lives, for messages.
    fn culture_location(&self, key: TileKey) -> String {
        format!("culture of {key}")
    }
}

/// Tiles held in memory (for tests and for databases built on the fly).
#[derive(Default)]
pub struct MemoryTileStore {
    tiles: parking_lot::RwLock<std::collections::HashMap<TileKey, Vec<u8>>>,
    imagery: parking_lot::RwLock<std::collections::HashMap<ImageryKey, Vec<u8>>>,
    culture: parking_lot::RwLock<std::collections::HashMap<TileKey, Vec<u8>>>,
}

impl MemoryTileStore {
    pub fn new() -> MemoryTileStore {
        MemoryTileStore::default()
    }

    /// Stores (or replaces) a tile's bytes.
    pub fn insert(&self, key: TileKey, bytes: Vec<u8>) {
        self.tiles.write().insert(key, bytes);
    }

    /// Stores (or replaces) an imagery tile's bytes.
    pub fn insert_imagery(&self, key: ImageryKey, bytes: Vec<u8>) {
        self.imagery.write().insert(key, bytes);
    }

    /// Stores (or replaces) a finest tile's culture bytes.
    pub fn insert_culture(&self, key: TileKey, bytes: Vec<u8>) {
        self.culture.write().insert(key, bytes);
    }
}

impl TileStore for MemoryTileStore {
    fn read_tile(&self, key: TileKey) -> Result<Vec<u8>, StoreError> {
        self.tiles
            .read()
            .get(&key)
            .cloned()
            .ok_or_else(|| StoreError::Missing(self.location(key)))
    }

    fn location(&self, key: TileKey) -> String {
        format!("memory tile {key}")
    }

    fn read_imagery_tile(&self, key: ImageryKey) -> Result<Vec<u8>, StoreError> {
        self.imagery
            .read()
            .get(&key)
            .cloned()
            .ok_or_else(|| StoreError::Missing(self.imagery_location(key)))
    }

    fn imagery_location(&self, key: ImageryKey) -> String {
        format!("memory {key}")
    }

    fn read_culture_tile(&self, key: TileKey) -> Result<Vec<u8>, StoreError> {
        self.culture
            .read()
            .get(&key)
            .cloned()
            .ok_or_else(|| StoreError::Missing(self.culture_location(key)))
    }

    fn culture_location(&self, key: TileKey) -> String {
        format!("memory culture of {key}")
    }
}

/// Why a tile could not be loaded.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum LoadError {
    #[error(transparent)]
    Store(#[from] StoreError),
    #[error("{error}: {location}")]
    Decode {
        error: TileDecodeError,
        location: String,
    },
    #[error("{error}: {location}")]
    ImageryDecode {
        error: ImageryDecodeError,
        location: String,
    },
}

/// An open terrain database.
pub struct TerrainDatabase {
    manifest: Manifest,
    store: Arc<dyn TileStore>,
}

impl TerrainDatabase {
    /// Opens a database over a validated manifest and its store.
    pub fn new(
        manifest: Manifest,
        store: Arc<dyn TileStore>,
    ) -> Result<TerrainDatabase, ManifestError> {
        manifest.validate()?;
        Ok(TerrainDatabase { manifest, store })
    }

    pub fn manifest(&self) -> &Manifest {
        &self.manifest
    }

    pub fn layout(&self) -> &PyramidLayout {
        &self.manifest.layout
    }

    /// Where a tile lives, for messages.
    pub fn tile_location(&self, key: TileKey) -> String {
        self.store.location(key)
    }

    /// Reads and decodes one tile (checksum and key checked). Blocks on the store.
    pub fn load_tile(&self, key: TileKey) -> Result<Tile, LoadError> {
        let bytes = self.store.read_tile(key)?;
        let decode_error = |error| LoadError::Decode {
            error,
            location: self.store.location(key),
        };
        let tile = Tile::decode(&bytes, Some(key)).map_err(decode_error)?;
        let posts = self.manifest.layout.posts_per_side();
        let depth = crate::tile::quadtree_depth_for(self.manifest.layout.tile_cells as usize);
        if tile.posts_per_side != posts || tile.quadtree_depth != depth {
            return Err(decode_error(TileDecodeError::Header(format!(
                "tile has {} posts per side and quadtree depth {}; the database has {posts} and {depth}",
                tile.posts_per_side, tile.quadtree_depth
            ))));
        }
        let mut tile = tile;
        if key.level == 0 {
            tile.culture = self.load_culture(&tile)?;
        }
        Ok(tile)
    }

    /// Reads a finest tile's culture and clamps it to `tile`'s surface; `Ok(None)` where the
    /// database has none there, or where its file fails its checks (logged; the terrain tile
    /// is still used). Blocks on the store.
    fn load_culture(&self, tile: &Tile) -> Result<Option<CultureTile>, LoadError> {
        if self.manifest.culture.is_none() {
            return Ok(None);
        }
        let bytes = match self.store.read_culture_tile(tile.key) {
            Ok(bytes) => bytes,
            Err(StoreError::Missing(_)) => return Ok(None),
            Err(e) => return Err(e.into()),
        };
        // A damaged culture file costs its culture, not the terrain under it.
        let mut culture =
            match CultureTile::decode(&bytes, Some(tile.key), self.manifest.layout.tile_cells) {
                Ok(culture) => culture,
                Err(error) => {
                    let location = self.store.culture_location(tile.key);
                    tracing::warn!("culture skipped, the terrain kept: {error}: {location}");
                    return Ok(None);
                }
            };
        culture.clamp_to(tile, self.manifest.spacing_m);
        Ok(Some(culture))
    }

    /// Reads and decodes one imagery tile (checksum and key checked); `Ok(None)` where the
    /// database has no imagery there. Blocks on the store.
    pub fn load_imagery_tile(&self, key: ImageryKey) -> Result<Option<ImageryTile>, LoadError> {
        let Some(imagery) = &self.manifest.imagery else {
            return Ok(None);
        };
        if !imagery.layout.contains_key(key) {
            return Ok(None);
        }
        let bytes = match self.store.read_imagery_tile(key) {
            Ok(bytes) => bytes,
            Err(StoreError::Missing(_)) => return Ok(None),
            Err(e) => return Err(e.into()),
        };
        ImageryTile::decode(&bytes, Some(key))
            .map(Some)
            .map_err(|error| LoadError::ImageryDecode {
                error,
                location: self.store.imagery_location(key),
            })
    }
}

impl Manifest {
    /// The manifest of a freshly built pyramid.
    pub fn from_build(
        summary: &crate::build::BuildSummary,
        geoid: GeoidGrid,
        void_posts_filled: u64,
        sources: Vec<String>,
    ) -> Manifest {
        let g = summary.layout.grid;
        let centre_lat = 0.5 * (g.south_lat_deg + g.north_lat_deg());
        let (north_m_per_deg, east_m_per_deg) = cig_geo::metres_per_degree(centre_lat);
        Manifest {
            format: DB_FORMAT_NAME.to_string(),
            format_version: DB_FORMAT_VERSION,
            layout: summary.layout,
            spacing_m: [g.dlat_deg * north_m_per_deg, g.dlon_deg * east_m_per_deg],
            vertical_datum: "egm96".to_string(),
            geoid,
            min_elevation_m: summary.min_elevation_m,
            max_elevation_m: summary.max_elevation_m,
            void_posts_filled,
            material_posts: crate::material::Material::ALL
                .iter()
                .map(|m| {
                    (
                        m.name().to_string(),
                        summary.material_posts[m.to_byte() as usize],
                    )
                })
                .collect(),
            sources,
            tile_count: summary.tiles,
            imagery: None,
            culture: None,
        }
    }
}

impl GeoidGrid {
    /// EGM96 undulations every `step_deg` over a post grid (the spherical-harmonic synthesis
    /// costs about a millisecond a node, so the grid is coarse; EGM96 is smooth at that scale).
    pub fn egm96_over(grid: &crate::raster::GeoGrid, step_deg: f64) -> GeoidGrid {
        GeoidGrid::sample(
            grid.south_lat_deg,
            grid.west_lon_deg,
            grid.north_lat_deg(),
            grid.east_lon_deg(),
            step_deg,
            cig_geo::geoid::egm96_undulation_m,
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_geoid_grid_whose_size_overflows_is_refused() {
        let grid = GeoidGrid {
            south_lat_deg: 0.0,
            west_lon_deg: 0.0,
            step_deg: 1.0,
            rows: 1 << 32,
            cols: 1 << 32,
            undulation_m: vec![],
        };
        assert!(!grid.is_consistent());
        let ok = GeoidGrid::zero();
        assert!(ok.is_consistent());
        assert_eq!(GeoidLookup::new(&ok).undulation_m(12.0, 34.0), 0.0);
    }

    #[test]
    fn geoid_lookup_is_bilinear_and_clamped() {
        let grid = GeoidGrid::sample(0.0, 0.0, 1.0, 1.0, 0.5, |lat, lon| 10.0 * lat + lon);
        let lookup = GeoidLookup::new(&grid);
        for (lat, lon) in [(0.1, 0.2), (0.77, 0.33), (1.0, 1.0)] {
            assert!((lookup.undulation_m(lat, lon) - (10.0 * lat + lon)).abs() < 1e-5);
        }
        // Far outside: the edge value, not a panic.
        assert!(lookup.undulation_m(80.0, -170.0).is_finite());
    }
}
