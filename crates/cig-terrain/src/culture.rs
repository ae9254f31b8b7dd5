//! Culture: trees, bushes, buildings, walls, fences and power poles standing on the terrain.
//!
//! Model: each object is a [`CultureItem`] of a [`CultureKind`] with a position, a height, a
//! width and a length (along its heading) and a variant seed; placements arrive in geodetic
//! form ([`CulturePlacement`], from the synthetic generator or a feature file) and are binned
//! into the finest level's tiles ([`bin_placements`]). A tile's objects are stored beside its
//! elevation tile in a [`CultureTile`] and are loaded, paged and evicted with it (the paging
//! cache counts a finest tile's bytes with its culture's), so culture is never all in memory.
//! Positions are the tile's fractional post indices; heights are not stored: every object is
//! clamped on load to the one terrain surface ([`CultureTile::clamp_to`]), the surface HOT,
//! LOS and the renderer use, so a tree's base is HOT at its trunk.
//!
//! Source: NPSNET's features on the terrain tiles (source 003: "the features of the terrain
//! ... are stored with the tile", objects kept in the same quadtree as the posts) and the GE
//! study's culture (source 004 §1.2, §2.5: trees, houses and poles as the cues a trainee reads
//! for speed and height). Each object is seen by the terrain queries as a *simple volume*
//! ([`CultureItem::volume`]): a tree as a trunk cylinder and an ellipsoidal crown (conifers a
//! narrow one), a bush as an ellipsoid, a building as a box to its ridge, a wall as a thin box,
//! a power pole as a cylinder. Fences are drawn but do not block a line of sight (a wire fence
//! is seen through); they are still volumes for collision.
//!
//! Tile format (little-endian): a 32-byte header (magic `CIGCULT\0`, format version (u32),
//! level (u8, always 0), three reserved bytes, row and column (u32 each), item count (u32),
//! CRC-32 of the payload (u32)), then 24 bytes per item: fractional row and column (f32 each),
//! height, width and length in metres (f32 each), heading in 1/65536 turns (u16), kind (u8),
//! variant (u8).
//!
//! Limits: objects are placed on the finest level only (coarser tiles carry none; the renderer
//! removes culture long before coarse tiles are drawn); power lines between poles, bridges and
//! roofs other than a gable are not modelled; a building on a slope stands on the surface at
//! its centre and is drawn with its walls carried down to the lowest corner of its footprint.

use crate::pyramid::{PyramidLayout, TileKey};
use crate::tile::Tile;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// Version of the culture tile format written by this build.
pub const CULTURE_FORMAT_VERSION: u32 = 1;
const MAGIC: &[u8; 8] = b"CIGCULT\0";
const HEADER_BYTES: usize = 32;
const ITEM_BYTES: usize = 24;
/// Most objects one finest tile may hold (a bound on a tile's memory, 24 MB at 32 bytes each).
pub const MAX_ITEMS_PER_TILE: usize = 750_000;

/// What a culture object is.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
#[repr(u8)]
pub enum CultureKind {
    /// A conifer (spruce, pine, fir): a narrow conical crown on a short bare trunk.
    ConiferTree = 0,
    /// A broadleaf tree (oak, beech): a round crown on a taller bare trunk.
    BroadleafTree = 1,
    /// A bush or shrub.
    Bush = 2,
    /// A dwelling house with a gable roof.
    House = 3,
    /// A shed, barn or garage with a gable roof.
    Shed = 4,
    /// A larger building (block of flats, hall, warehouse) with a low roof.
    LargeBuilding = 5,
    /// A stone or brick wall (its length along the heading).
    Wall = 6,
    /// A post-and-wire fence (its length along the heading).
    Fence = 7,
    /// A wooden or concrete power pole.
    PowerPole = 8,
}

/// The simple volume a terrain query sees of an object, in the object's local frame (metres,
/// x along its heading, y to its left, z up from its base).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum CultureVolume {
    /// A vertical cylinder of `radius_m` from `bottom_m` to `top_m`.
    Cylinder {
        radius_m: f64,
        bottom_m: f64,
        top_m: f64,
    },
    /// An ellipsoid centred `centre_m` above the base with horizontal and vertical semi-axes.
    Ellipsoid {
        centre_m: f64,
        horizontal_m: f64,
        vertical_m: f64,
    },
    /// A box `length_m` x `width_m` centred on the base, from `bottom_m` to `top_m`.
    Box {
        length_m: f64,
        width_m: f64,
        bottom_m: f64,
        top_m: f64,
    },
}

impl CultureKind {
    /// Every kind, in on-disk byte order.
    pub const ALL: [CultureKind; 9] = [
        CultureKind::ConiferTree,
        CultureKind::BroadleafTree,
        CultureKind::Bush,
        CultureKind::House,
        CultureKind::Shed,
        CultureKind::LargeBuilding,
        CultureKind::Wall,
        CultureKind::Fence,
        CultureKind::PowerPole,
    ];

    /// The name used in feature files, manifests and reports.
    pub fn name(self) -> &'static str {
        match self {
            CultureKind::ConiferTree => "conifer_tree",
            CultureKind::BroadleafTree => "broadleaf_tree",
            CultureKind::Bush => "bush",
            CultureKind::House => "house",
            CultureKind::Shed => "shed",
            CultureKind::LargeBuilding => "large_building",
            CultureKind::Wall => "wall",
            CultureKind::Fence => "fence",
            CultureKind::PowerPole => "power_pole",
        }
    }

    /// The kind a name (as [`CultureKind::name`]) stands for.
    pub fn from_name(name: &str) -> Option<CultureKind> {
        CultureKind::ALL.into_iter().find(|k| k.name() == name)
    }

    /// The kind of an on-disk byte.
    pub fn from_byte(byte: u8) -> Option<CultureKind> {
        CultureKind::ALL.get(usize::from(byte)).copied()
    }

    pub fn is_tree(self) -> bool {
        matches!(self, CultureKind::ConiferTree | CultureKind::BroadleafTree)
    }

    pub fn is_building(self) -> bool {
        matches!(
            self,
            CultureKind::House | CultureKind::Shed | CultureKind::LargeBuilding
        )
    }

    /// Long objects placed as segments of a line (walls and fences).
    pub fn is_linear(self) -> bool {
        matches!(self, CultureKind::Wall | CultureKind::Fence)
    }

    /// Whether a line of sight is stopped by the object (every kind but the see-through fence).
    pub fn blocks_line_of_sight(self) -> bool {
        self != CultureKind::Fence
    }

    /// Typical height, width and length in metres, for placements that give only a height or
    /// nothing (a feature file's point without sizes).
    pub fn typical_size_m(self) -> [f32; 3] {
        match self {
            CultureKind::ConiferTree => [18.0, 5.0, 5.0],
            CultureKind::BroadleafTree => [15.0, 9.0, 9.0],
            CultureKind::Bush => [2.0, 2.5, 2.5],
            CultureKind::House => [8.0, 8.0, 11.0],
            CultureKind::Shed => [4.5, 5.0, 7.0],
            CultureKind::LargeBuilding => [14.0, 16.0, 30.0],
            CultureKind::Wall => [2.0, 0.4, 10.0],
            CultureKind::Fence => [1.4, 0.1, 10.0],
            CultureKind::PowerPole => [10.0, 0.3, 0.3],
        }
    }

    /// Tallest a valid object of this kind may be, metres.
    pub fn max_height_m(self) -> f32 {
        self.max_extent_m().max(60.0)
    }

    /// Widest a valid object of this kind may be (a sanity bound on feature files), metres.
    pub fn max_extent_m(self) -> f32 {
        match self {
            CultureKind::Wall | CultureKind::Fence => 200.0,
            CultureKind::LargeBuilding => 400.0,
            _ => 60.0,
        }
    }
}

impl std::fmt::Display for CultureKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// One object as a generator or a feature file gives it: geodetic position and sizes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CulturePlacement {
    pub kind: CultureKind,
    pub lat_deg: f64,
    pub lon_deg: f64,
    /// Top above the base (for a building its ridge), metres.
    pub height_m: f32,
    /// Across the heading (a tree's crown diameter), metres.
    pub width_m: f32,
    /// Along the heading (equal to the width for trees, bushes and poles), metres.
    pub length_m: f32,
    /// Direction of the length axis, degrees clockwise from north.
    pub heading_deg: f32,
    /// Seed of the object's look (shape jitter, colour): same seed, same object.
    pub variant: u8,
}

/// Why a placement or a culture tile is not usable.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum CultureError {
    #[error("{kind} at {lat_deg:.6}, {lon_deg:.6} lies outside the database")]
    OutsideDatabase {
        kind: CultureKind,
        lat_deg: f64,
        lon_deg: f64,
    },
    #[error("{kind} at {lat_deg:.6}, {lon_deg:.6}: {what} {value} m is not a positive size up to {max} m")]
    BadSize {
        kind: CultureKind,
        lat_deg: f64,
        lon_deg: f64,
        what: &'static str,
        value: f32,
        max: f32,
    },
    #[error("tile {key} would hold {count} culture objects (at most {MAX_ITEMS_PER_TILE})")]
    TooManyInTile { key: TileKey, count: usize },
    #[error("culture tile is too short ({len} bytes)")]
    TooShort { len: usize },
    #[error("not a culture tile (bad magic)")]
    BadMagic,
    #[error(
        "culture tile format {0} is not supported (this build reads {CULTURE_FORMAT_VERSION})"
    )]
    Version(u32),
    #[error("culture tile is for {found}, expected {expected}")]
    WrongKey { found: TileKey, expected: TileKey },
    #[error("culture tile checksum mismatch")]
    Checksum,
    #[error("culture tile is corrupt: {0}")]
    Corrupt(String),
}

/// One object in a tile.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CultureItem {
    pub kind: CultureKind,
    pub variant: u8,
    /// Heading in 1/65536 turns clockwise from north.
    pub heading: u16,
    /// Fractional post row (northwards) within the tile.
    pub fi: f32,
    /// Fractional post column (eastwards) within the tile.
    pub fj: f32,
    pub height_m: f32,
    pub width_m: f32,
    pub length_m: f32,
    /// The terrain surface at the object's centre, metres above mean sea level (set on load by
    /// [`CultureTile::clamp_to`]; not stored).
    pub base_m: f32,
    /// How far the lowest corner of the footprint lies below the base, metres (set on load).
    pub sink_m: f32,
}

impl CultureItem {
    pub fn heading_deg(&self) -> f64 {
        f64::from(self.heading) * (360.0 / 65536.0)
    }

    /// Radius of the smallest vertical cylinder about the centre holding the footprint.
    pub fn footprint_radius_m(&self) -> f32 {
        0.5 * self.width_m.hypot(self.length_m)
    }

    /// Radius of the sphere that bounds the object (the GE study's critical radius of a
    /// culture object: its size as the eye judges it).
    pub fn bounding_radius_m(&self) -> f32 {
        0.5 * (self.height_m * self.height_m
            + self.width_m * self.width_m
            + self.length_m * self.length_m)
            .sqrt()
    }

    /// The simple volumes the terrain queries test (see the module docs).
    pub fn volume(&self) -> [Option<CultureVolume>; 2] {
        let h = f64::from(self.height_m);
        let w = f64::from(self.width_m);
        let l = f64::from(self.length_m);
        let sink = f64::from(self.sink_m);
        match self.kind {
            CultureKind::ConiferTree => [
                Some(CultureVolume::Cylinder {
                    radius_m: (0.04 * w).max(0.12),
                    bottom_m: -sink,
                    top_m: 0.25 * h,
                }),
                Some(CultureVolume::Ellipsoid {
                    centre_m: 0.58 * h,
                    horizontal_m: 0.42 * w,
                    vertical_m: 0.42 * h,
                }),
            ],
            CultureKind::BroadleafTree => [
                Some(CultureVolume::Cylinder {
                    radius_m: (0.04 * w).max(0.15),
                    bottom_m: -sink,
                    top_m: 0.45 * h,
                }),
                Some(CultureVolume::Ellipsoid {
                    centre_m: 0.66 * h,
                    horizontal_m: 0.5 * w,
                    vertical_m: 0.34 * h,
                }),
            ],
            CultureKind::Bush => [
                Some(CultureVolume::Ellipsoid {
                    centre_m: 0.5 * h,
                    horizontal_m: 0.5 * w,
                    vertical_m: 0.5 * h,
                }),
                None,
            ],
            CultureKind::PowerPole => [
                Some(CultureVolume::Cylinder {
                    radius_m: 0.5 * w,
                    bottom_m: -sink,
                    top_m: h,
                }),
                None,
            ],
            CultureKind::House
            | CultureKind::Shed
            | CultureKind::LargeBuilding
            | CultureKind::Wall
            | CultureKind::Fence => [
                Some(CultureVolume::Box {
                    length_m: l,
                    width_m: w,
                    bottom_m: -sink,
                    top_m: h,
                }),
                None,
            ],
        }
    }
}

/// The objects of one finest tile.
#[derive(Clone, Debug, PartialEq)]
pub struct CultureTile {
    pub key: TileKey,
    pub items: Vec<CultureItem>,
}

/// Counts of a database's culture, for the manifest (`culture` section).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct CultureManifest {
    /// Objects of each kind, by [`CultureKind::name`].
    pub counts: BTreeMap<String, u64>,
    /// Finest tiles that hold any culture.
    pub tiles: u64,
    /// Objects in the fullest tile (the paging cache counts this many per finest tile).
    pub max_items_per_tile: u64,
    /// Widest footprint radius of any object ([`CultureItem::footprint_radius_m`]), metres: how
    /// far an object reaches from its centre, so how far past its tile's edge a query must look.
    /// 0 in manifests written before it was recorded: read through
    /// [`CultureManifest::footprint_bound_m`].
    #[serde(default)]
    pub max_footprint_radius_m: f32,
    /// Tallest object (its top above its base), metres; 0 in manifests written before it was
    /// recorded: read through [`CultureManifest::height_bound_m`].
    #[serde(default)]
    pub max_height_m: f32,
}

impl CultureManifest {
    /// Trees (conifer and broadleaf).
    pub fn trees(&self) -> u64 {
        self.count_where(CultureKind::is_tree)
    }

    /// Buildings (houses, sheds, larger buildings).
    pub fn buildings(&self) -> u64 {
        self.count_where(CultureKind::is_building)
    }

    fn count_where(&self, pred: fn(CultureKind) -> bool) -> u64 {
        self.counts
            .iter()
            .filter(|(name, _)| CultureKind::from_name(name).is_some_and(pred))
            .map(|(_, n)| n)
            .sum()
    }

    /// Memory one resident culture tile may take at most.
    pub fn max_tile_bytes(&self) -> u64 {
        self.max_items_per_tile * std::mem::size_of::<CultureItem>() as u64
    }

    pub fn total(&self) -> u64 {
        self.counts.values().sum()
    }

    /// How far any object of the database reaches from its centre, metres: the recorded
    /// [`CultureManifest::max_footprint_radius_m`], or where it is not recorded (0, an old
    /// manifest) the widest a valid placement allows (`crate::culture_hit::widest_footprint_m`,
    /// 283 m). Never more than that.
    pub fn footprint_bound_m(&self) -> f64 {
        recorded_or(
            self.max_footprint_radius_m,
            crate::culture_hit::widest_footprint_m(),
        )
    }

    /// How high any object of the database stands above its base, metres: the recorded
    /// [`CultureManifest::max_height_m`], or where it is not recorded (0, an old manifest) the
    /// tallest a valid placement allows (`crate::culture_hit::tallest_object_m`, 400 m).
    pub fn height_bound_m(&self) -> f64 {
        recorded_or(self.max_height_m, crate::culture_hit::tallest_object_m())
    }
}

/// `recorded` where it is a positive number (at most `bound`), else `bound`.
fn recorded_or(recorded: f32, bound: f64) -> f64 {
    let v = f64::from(recorded);
    if v.is_finite() && v > 0.0 {
        v.min(bound)
    } else {
        bound
    }
}

impl CulturePlacement {
    /// Checks the placement's sizes: each positive and at most the kind's bounds
    /// ([`CultureKind::max_extent_m`], [`CultureKind::max_height_m`]); what
    /// [`bin_placements`] checks.
    pub fn check(&self) -> Result<(), CultureError> {
        check_placement(self)
    }
}

/// Checks one placement's sizes.
fn check_placement(p: &CulturePlacement) -> Result<(), CultureError> {
    let max = p.kind.max_extent_m();
    // Round objects take their length from their width.
    let length_m = if p.kind.is_linear() || p.kind.is_building() {
        p.length_m
    } else {
        p.width_m
    };
    for (what, value, max) in [
        ("height", p.height_m, p.kind.max_height_m()),
        ("width", p.width_m, max),
        ("length", length_m, max),
    ] {
        if !(value.is_finite() && value > 0.0 && value <= max) {
            return Err(CultureError::BadSize {
                kind: p.kind,
                lat_deg: p.lat_deg,
                lon_deg: p.lon_deg,
                what,
                value,
                max,
            });
        }
    }
    Ok(())
}

/// Sorts placements into the finest tiles of `layout`, with the manifest's counts. Every
/// placement must lie inside the database and have sane sizes; the first that does not is the
/// error. Items within a tile are ordered south to north, west to east in 8 x 8-cell blocks so
/// a renderer can cull them block by block ([`CultureTile::blocks`]).
pub fn bin_placements(
    layout: &PyramidLayout,
    placements: &[CulturePlacement],
) -> Result<(Vec<CultureTile>, CultureManifest), CultureError> {
    let grid = &layout.grid;
    let mut tiles: BTreeMap<TileKey, Vec<CultureItem>> = BTreeMap::new();
    let mut manifest = CultureManifest::default();
    for p in placements {
        check_placement(p)?;
        let row_f = (p.lat_deg - grid.south_lat_deg) / grid.dlat_deg;
        let col_f = (p.lon_deg - grid.west_lon_deg) / grid.dlon_deg;
        let max_row = (grid.rows - 1) as f64;
        let max_col = (grid.cols - 1) as f64;
        if !(row_f.is_finite() && col_f.is_finite())
            || row_f < 0.0
            || col_f < 0.0
            || row_f > max_row
            || col_f > max_col
        {
            return Err(CultureError::OutsideDatabase {
                kind: p.kind,
                lat_deg: p.lat_deg,
                lon_deg: p.lon_deg,
            });
        }
        let (key, fi, fj) = layout.locate(0, row_f, col_f);
        let heading = (p.heading_deg.rem_euclid(360.0) / 360.0 * 65536.0).round() as u32 % 65536;
        let (width_m, length_m) = if p.kind.is_linear() || p.kind.is_building() {
            (p.width_m, p.length_m)
        } else {
            (p.width_m, p.width_m)
        };
        let item = CultureItem {
            kind: p.kind,
            variant: p.variant,
            heading: heading as u16,
            fi: fi as f32,
            fj: fj as f32,
            height_m: p.height_m,
            width_m,
            length_m,
            base_m: 0.0,
            sink_m: 0.0,
        };
        manifest.max_footprint_radius_m = manifest
            .max_footprint_radius_m
            .max(item.footprint_radius_m());
        manifest.max_height_m = manifest.max_height_m.max(item.height_m);
        tiles.entry(key).or_default().push(item);
        *manifest
            .counts
            .entry(p.kind.name().to_string())
            .or_default() += 1;
    }
    let mut out = Vec::with_capacity(tiles.len());
    for (key, mut items) in tiles {
        if items.len() > MAX_ITEMS_PER_TILE {
            return Err(CultureError::TooManyInTile {
                key,
                count: items.len(),
            });
        }
        items.sort_by_key(|it| (block_of(it.fi), block_of(it.fj)));
        manifest.max_items_per_tile = manifest.max_items_per_tile.max(items.len() as u64);
        out.push(CultureTile { key, items });
    }
    manifest.tiles = out.len() as u64;
    Ok((out, manifest))
}

/// Cells along the side of a culling block.
pub const CULTURE_BLOCK_CELLS: usize = 8;

fn block_of(f: f32) -> u32 {
    (f.max(0.0) as u32) / CULTURE_BLOCK_CELLS as u32
}

/// A run of a tile's items in one 8 x 8-cell block.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CultureBlock {
    /// Block row and column within the tile.
    pub block_row: u32,
    pub block_col: u32,
    /// Range of [`CultureTile::items`].
    pub start: usize,
    pub end: usize,
}

impl CultureTile {
    /// The items' blocks in storage order (items are stored block by block).
    pub fn blocks(&self) -> Vec<CultureBlock> {
        let mut out: Vec<CultureBlock> = Vec::new();
        for (index, item) in self.items.iter().enumerate() {
            let (r, c) = (block_of(item.fi), block_of(item.fj));
            match out.last_mut() {
                Some(b) if b.block_row == r && b.block_col == c => b.end = index + 1,
                _ => out.push(CultureBlock {
                    block_row: r,
                    block_col: c,
                    start: index,
                    end: index + 1,
                }),
            }
        }
        out
    }

    /// Sets every item's base on `tile`'s surface (the one terrain surface) and its sink to
    /// the lowest corner of its footprint. `tile` must be this tile's elevation tile.
    pub fn clamp_to(&mut self, tile: &Tile, spacing_m: [f64; 2]) {
        let cells = tile.cells() as f64;
        let clamp = |f: f64| f.clamp(0.0, cells);
        for item in &mut self.items {
            let (fi, fj) = (f64::from(item.fi), f64::from(item.fj));
            let base = tile.surface_height(clamp(fi), clamp(fj));
            item.base_m = base as f32;
            let r = f64::from(item.footprint_radius_m());
            let (di, dj) = (r / spacing_m[0].max(1e-6), r / spacing_m[1].max(1e-6));
            let mut lowest = base;
            for (si, sj) in [(-1.0, -1.0), (-1.0, 1.0), (1.0, -1.0), (1.0, 1.0)] {
                lowest = lowest.min(tile.surface_height(clamp(fi + si * di), clamp(fj + sj * dj)));
            }
            item.sink_m = (base - lowest) as f32;
        }
    }

    /// Bytes the tile takes in memory.
    pub fn memory_bytes(&self) -> u64 {
        (self.items.capacity() * std::mem::size_of::<CultureItem>()) as u64
    }

    /// Encodes the tile in its file format.
    pub fn encode(&self) -> Vec<u8> {
        let mut payload = Vec::with_capacity(self.items.len() * ITEM_BYTES);
        for item in &self.items {
            for v in [item.fi, item.fj, item.height_m, item.width_m, item.length_m] {
                payload.extend_from_slice(&v.to_le_bytes());
            }
            payload.extend_from_slice(&item.heading.to_le_bytes());
            payload.push(item.kind as u8);
            payload.push(item.variant);
        }
        let mut out = Vec::with_capacity(HEADER_BYTES + payload.len());
        out.extend_from_slice(MAGIC);
        out.extend_from_slice(&CULTURE_FORMAT_VERSION.to_le_bytes());
        out.push(self.key.level);
        out.extend_from_slice(&[0, 0, 0]);
        out.extend_from_slice(&self.key.row.to_le_bytes());
        out.extend_from_slice(&self.key.col.to_le_bytes());
        out.extend_from_slice(&(self.items.len() as u32).to_le_bytes());
        out.extend_from_slice(&crc32fast::hash(&payload).to_le_bytes());
        out.extend_from_slice(&payload);
        out
    }

    /// Decodes a tile, checking magic, version, size, checksum, (when given) its key and every
    /// item's kind and values. `cells` is the database's cells per tile side.
    pub fn decode(
        bytes: &[u8],
        expected: Option<TileKey>,
        cells: u32,
    ) -> Result<CultureTile, CultureError> {
        if bytes.len() < HEADER_BYTES {
            return Err(CultureError::TooShort { len: bytes.len() });
        }
        if &bytes[0..8] != MAGIC {
            return Err(CultureError::BadMagic);
        }
        let u32_at =
            |o: usize| u32::from_le_bytes([bytes[o], bytes[o + 1], bytes[o + 2], bytes[o + 3]]);
        let version = u32_at(8);
        if version != CULTURE_FORMAT_VERSION {
            return Err(CultureError::Version(version));
        }
        let key = TileKey {
            level: bytes[12],
            row: u32_at(16),
            col: u32_at(20),
        };
        if let Some(expected) = expected {
            if key != expected {
                return Err(CultureError::WrongKey {
                    found: key,
                    expected,
                });
            }
        }
        let count = u32_at(24) as usize;
        if count > MAX_ITEMS_PER_TILE {
            return Err(CultureError::Corrupt(format!("{count} items")));
        }
        let payload = &bytes[HEADER_BYTES..];
        if payload.len() != count * ITEM_BYTES {
            return Err(CultureError::Corrupt(format!(
                "{} payload bytes for {count} items",
                payload.len()
            )));
        }
        if crc32fast::hash(payload) != u32_at(28) {
            return Err(CultureError::Checksum);
        }
        let cells = cells as f32;
        let mut items = Vec::with_capacity(count);
        for (index, chunk) in payload.chunks_exact(ITEM_BYTES).enumerate() {
            let f =
                |o: usize| f32::from_le_bytes([chunk[o], chunk[o + 1], chunk[o + 2], chunk[o + 3]]);
            let kind = CultureKind::from_byte(chunk[22]).ok_or_else(|| {
                CultureError::Corrupt(format!("item {index}: kind {}", chunk[22]))
            })?;
            let item = CultureItem {
                kind,
                variant: chunk[23],
                heading: u16::from_le_bytes([chunk[20], chunk[21]]),
                fi: f(0),
                fj: f(4),
                height_m: f(8),
                width_m: f(12),
                length_m: f(16),
                base_m: 0.0,
                sink_m: 0.0,
            };
            let inside = |v: f32| v.is_finite() && (0.0..=cells).contains(&v);
            let size = |v: f32| v.is_finite() && v > 0.0 && v <= 1000.0;
            if !(inside(item.fi)
                && inside(item.fj)
                && size(item.height_m)
                && size(item.width_m)
                && size(item.length_m))
            {
                return Err(CultureError::Corrupt(format!(
                    "item {index} has a position or size out of range"
                )));
            }
            items.push(item);
        }
        Ok(CultureTile { key, items })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::raster::GeoGrid;

    fn layout() -> PyramidLayout {
        PyramidLayout::new(
            GeoGrid {
                south_lat_deg: 45.0,
                west_lon_deg: 7.0,
                dlat_deg: 1.0 / 3600.0,
                dlon_deg: 1.0 / 3600.0,
                rows: 129,
                cols: 129,
            },
            64,
        )
    }

    fn tree(lat_deg: f64, lon_deg: f64) -> CulturePlacement {
        CulturePlacement {
            kind: CultureKind::ConiferTree,
            lat_deg,
            lon_deg,
            height_m: 20.0,
            width_m: 6.0,
            length_m: 6.0,
            heading_deg: 30.0,
            variant: 7,
        }
    }

    #[test]
    fn placements_bin_into_finest_tiles_and_round_trip() {
        let placements = vec![
            tree(45.001, 7.001),
            tree(45.03, 7.03),
            CulturePlacement {
                kind: CultureKind::House,
                length_m: 12.0,
                width_m: 8.0,
                height_m: 7.5,
                heading_deg: -90.0,
                ..tree(45.02, 7.005)
            },
        ];
        let (tiles, manifest) = bin_placements(&layout(), &placements).unwrap();
        assert_eq!(manifest.trees(), 2);
        assert_eq!(manifest.buildings(), 1);
        assert_eq!(manifest.total(), 3);
        assert!(tiles.len() >= 2);
        for tile in &tiles {
            assert_eq!(tile.key.level, 0);
            let back = CultureTile::decode(&tile.encode(), Some(tile.key), 64).unwrap();
            assert_eq!(&back, tile);
        }
        let house = tiles
            .iter()
            .flat_map(|t| &t.items)
            .find(|i| i.kind == CultureKind::House)
            .unwrap();
        assert!((house.heading_deg() - 270.0).abs() < 0.01);
        assert_eq!((house.length_m, house.width_m), (12.0, 8.0));
    }

    #[test]
    fn the_manifest_records_the_widest_and_tallest_object() {
        let house = CulturePlacement {
            kind: CultureKind::House,
            length_m: 12.0,
            width_m: 8.0,
            height_m: 7.5,
            ..tree(45.02, 7.005)
        };
        let (_, manifest) = bin_placements(&layout(), &[tree(45.001, 7.001), house]).unwrap();
        // The house's half diagonal; the tree's height.
        assert_eq!(manifest.max_footprint_radius_m, 0.5 * 8f32.hypot(12.0));
        assert_eq!(manifest.max_height_m, 20.0);
        assert_eq!(
            manifest.footprint_bound_m(),
            f64::from(0.5 * 8f32.hypot(12.0))
        );
        assert_eq!(manifest.height_bound_m(), 20.0);
        // A manifest from before the fields were recorded reads them as 0 (serde default): the
        // bounds are the largest any valid placement allows.
        let old = CultureManifest {
            max_footprint_radius_m: 0.0,
            max_height_m: 0.0,
            ..manifest
        };
        assert_eq!(
            old.footprint_bound_m(),
            crate::culture_hit::widest_footprint_m()
        );
        assert!((old.footprint_bound_m() - 282.84).abs() < 0.01);
        assert_eq!(old.height_bound_m(), 400.0);
    }

    #[test]
    fn bad_placements_are_named() {
        let err = bin_placements(&layout(), &[tree(46.0, 7.0)]).unwrap_err();
        assert!(err.to_string().contains("outside the database"), "{err}");
        let err = bin_placements(
            &layout(),
            &[CulturePlacement {
                height_m: -1.0,
                ..tree(45.01, 7.01)
            }],
        )
        .unwrap_err();
        assert!(err.to_string().contains("height -1"), "{err}");
    }

    #[test]
    fn damaged_tiles_are_refused() {
        let (tiles, _) = bin_placements(&layout(), &[tree(45.001, 7.001)]).unwrap();
        let bytes = tiles[0].encode();
        let mut flipped = bytes.clone();
        let last = flipped.len() - 3;
        flipped[last] ^= 0x40;
        assert_eq!(
            CultureTile::decode(&flipped, None, 64),
            Err(CultureError::Checksum)
        );
        assert!(CultureTile::decode(&bytes[..40], None, 64).is_err());
        assert!(CultureTile::decode(&bytes[..10], None, 64).is_err());
        let other = TileKey {
            level: 0,
            row: 1,
            col: 1,
        };
        assert!(matches!(
            CultureTile::decode(&bytes, Some(other), 64),
            Err(CultureError::WrongKey { .. })
        ));
    }

    #[test]
    fn blocks_cover_every_item_once() {
        let placements: Vec<_> = (0..200)
            .map(|i| {
                tree(
                    45.0 + (i % 37) as f64 * 0.0009,
                    7.0 + (i / 37) as f64 * 0.0011,
                )
            })
            .collect();
        let (tiles, _) = bin_placements(&layout(), &placements).unwrap();
        for tile in &tiles {
            let blocks = tile.blocks();
            let covered: usize = blocks.iter().map(|b| b.end - b.start).sum();
            assert_eq!(covered, tile.items.len());
            let mut seen = std::collections::HashSet::new();
            for b in &blocks {
                assert!(seen.insert((b.block_row, b.block_col)), "block repeated");
            }
        }
    }
}
