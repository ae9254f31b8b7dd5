//! The terrain queries' view of the culture: segments against the objects' simple volumes, the
//! highest surface at a point, and the per-tile block index the queries walk.
//!
//! Algorithm: every object is one or two convex simple volumes in its local frame
//! ([`CultureItem::volume`]: x along its heading, y to its left, z up from its base). A segment
//! `p0 + t (p1 - p0)` is inside a convex volume on one interval of `t`; it is the intersection
//! of one interval per bounding constraint, each solved in closed form: a vertical cylinder is
//! `x^2 + y^2 <= r^2` (a quadratic in `t`) and a slab `bottom <= z <= top`; an ellipsoid is
//! scaled to the unit sphere (a quadratic); a box is three slabs (Kay and Kajiya's slab method,
//! the box already turned into its own frame). The first `t` of the interval within `[0, 1]` is
//! the entry, and the constraint that set it gives the outward normal there. The highest
//! surface over a point is the volume's top over that point (flat for cylinders and boxes, the
//! upper half of the ellipsoid otherwise).
//!
//! A query finds an object's frame from the tile's fractional post indices: the offsets in
//! posts from the object's centre times the post spacing in metres at the object's latitude
//! (WGS84 metres per degree) give east and north, turned by the heading (clockwise from north)
//! into x and y; z is the height above mean sea level less the object's base (`base_m`, the
//! terrain under its centre, set when the tile is loaded). Objects are found through
//! [`CultureIndex`]: the tile's items are stored in 8 x 8-cell blocks ([`CultureTile::blocks`]),
//! and the index keeps each non-empty block's item range, its highest top and its widest
//! footprint, so a query visits only the blocks it passes within a footprint of, and only when
//! it comes below the block's highest top.
//!
//! Source: the simple volumes of `crate::culture` (NPSNET's features kept on the terrain tiles,
//! source 003; the GE study's culture, source 004 §2.5); the slab test of Kay and Kajiya,
//! "Ray tracing complex scenes", SIGGRAPH 1986.
//!
//! Limits: the volumes are the culture module's simple shapes (a gable roof is its ridge height
//! over the whole footprint, a crown an ellipsoid), not the drawn meshes. A segment that only
//! touches a volume (tangent, or along a face) counts as entering it. The queries look for an
//! object's tile only within the database's recorded widest footprint and tallest object (the
//! culture manifest's bounds, at most [`widest_footprint_m`] and [`tallest_object_m`], the
//! largest a valid placement allows): an object beyond them (a tile written without its
//! manifest) is tested only where the query looks for its tile anyway.

use crate::culture::{CultureItem, CultureKind, CultureTile, CultureVolume, CULTURE_BLOCK_CELLS};
use crate::pyramid::{PyramidLayout, TileKey};
use crate::tile::Tile;
use std::sync::Arc;

/// Which culture a segment query sees.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
pub enum CultureTest {
    /// The bare terrain only.
    Ignore,
    /// Objects that stop a line of sight: every kind but fences
    /// ([`CultureKind::blocks_line_of_sight`]).
    #[default]
    LineOfSight,
    /// Every object, fences included (collision detection).
    Collision,
}

impl CultureTest {
    /// Whether an object of `kind` counts.
    pub fn counts(self, kind: CultureKind) -> bool {
        match self {
            CultureTest::Ignore => false,
            CultureTest::LineOfSight => kind.blocks_line_of_sight(),
            CultureTest::Collision => true,
        }
    }
}

/// A culture object met by a query.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CultureHit {
    pub kind: CultureKind,
    /// The finest tile holding the object.
    pub tile: TileKey,
    /// The object's index in that tile's [`CultureTile::items`].
    pub index: usize,
    /// The object, with its base and sink as loaded.
    pub item: CultureItem,
    /// Unit outward normal of the object's volume where it was met, in the local east-north-up
    /// frame (for a segment that starts inside a volume: against the segment's direction).
    pub normal_enu: [f64; 3],
}

/// Where a segment enters a volume.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VolumeEntry {
    /// Parameter along the segment, 0 at its start, 1 at its end.
    pub t: f64,
    /// Unit outward normal there, in the object's frame.
    pub normal: [f64; 3],
}

/// Tallest object a valid placement may have (the culture module's size check), metres.
pub fn tallest_object_m() -> f64 {
    CultureKind::ALL
        .iter()
        .map(|k| f64::from(k.max_height_m()))
        .fold(0.0, f64::max)
}

/// Widest footprint radius a valid placement may have (half the diagonal of the largest
/// width and length), metres.
pub fn widest_footprint_m() -> f64 {
    CultureKind::ALL
        .iter()
        .map(|k| f64::from(k.max_extent_m()) * std::f64::consts::FRAC_1_SQRT_2)
        .fold(0.0, f64::max)
}

/// Which bounding constraint an interval's lower end comes from.
#[derive(Clone, Copy)]
enum Face {
    /// The segment starts inside.
    Start,
    /// `z >= bottom`.
    Bottom,
    /// `z <= top`.
    Top,
    /// The cylinder's side.
    Side,
    /// The ellipsoid's surface.
    Shell,
    /// `x >= -l/2` (normal -x) or `x <= l/2` (normal +x).
    X(f64),
    /// `y >= -w/2` or `y <= w/2`.
    Y(f64),
}

/// A running intersection of intervals of `t`, starting as `[0, 1]`.
struct Span {
    lo: f64,
    hi: f64,
    face: Face,
}

impl Span {
    fn new() -> Span {
        Span {
            lo: 0.0,
            hi: 1.0,
            face: Face::Start,
        }
    }

    /// Intersects with `[lo, hi]` whose lower end is on `face`; false once empty.
    fn cut(&mut self, lo: f64, hi: f64, face: Face) -> bool {
        if lo > self.lo {
            self.lo = lo;
            self.face = face;
        }
        self.hi = self.hi.min(hi);
        self.lo <= self.hi
    }

    /// `lo <= p + t d <= hi`; the lower end's face is `below` when entering upwards (`d > 0`)
    /// and `above` when entering downwards.
    fn slab(&mut self, p: f64, d: f64, lo: f64, hi: f64, below: Face, above: Face) -> bool {
        if d == 0.0 {
            return if p >= lo && p <= hi {
                true
            } else {
                self.cut(1.0, 0.0, Face::Start)
            };
        }
        let (ta, tb) = ((lo - p) / d, (hi - p) / d);
        if d > 0.0 {
            self.cut(ta, tb, below)
        } else {
            self.cut(tb, ta, above)
        }
    }

    /// `a t^2 + b t + c <= 0` with `a >= 0`.
    fn quadratic(&mut self, a: f64, b: f64, c: f64, face: Face) -> bool {
        if a <= 0.0 {
            // Only a segment parallel to the axis (then b = 0 too): inside or not throughout.
            return if c <= 0.0 {
                true
            } else {
                self.cut(1.0, 0.0, Face::Start)
            };
        }
        let disc = b * b - 4.0 * a * c;
        if disc < 0.0 {
            return self.cut(1.0, 0.0, Face::Start);
        }
        // Numerically stable roots.
        let q = -0.5 * (b + b.signum() * disc.sqrt());
        let (r1, r2) = if q == 0.0 { (0.0, 0.0) } else { (q / a, c / q) };
        self.cut(r1.min(r2), r1.max(r2), face)
    }
}

fn normalized(v: [f64; 3]) -> [f64; 3] {
    let len = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    if len > 0.0 && len.is_finite() {
        [v[0] / len, v[1] / len, v[2] / len]
    } else {
        [0.0, 0.0, 1.0]
    }
}

/// First parameter `t` in `[0, 1]` where the segment from `p0` to `p1` (object frame, metres)
/// is inside or on `volume`, with the outward normal there.
pub fn segment_entry(volume: &CultureVolume, p0: [f64; 3], p1: [f64; 3]) -> Option<VolumeEntry> {
    let d = [p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2]];
    let mut span = Span::new();
    let inside = match *volume {
        CultureVolume::Cylinder {
            radius_m,
            bottom_m,
            top_m,
        } => {
            span.slab(p0[2], d[2], bottom_m, top_m, Face::Bottom, Face::Top)
                && span.quadratic(
                    d[0] * d[0] + d[1] * d[1],
                    2.0 * (p0[0] * d[0] + p0[1] * d[1]),
                    p0[0] * p0[0] + p0[1] * p0[1] - radius_m * radius_m,
                    Face::Side,
                )
        }
        CultureVolume::Ellipsoid {
            centre_m,
            horizontal_m,
            vertical_m,
        } => {
            if !(horizontal_m > 0.0 && vertical_m > 0.0) {
                return None;
            }
            let s = [
                p0[0] / horizontal_m,
                p0[1] / horizontal_m,
                (p0[2] - centre_m) / vertical_m,
            ];
            let e = [d[0] / horizontal_m, d[1] / horizontal_m, d[2] / vertical_m];
            span.quadratic(
                e[0] * e[0] + e[1] * e[1] + e[2] * e[2],
                2.0 * (s[0] * e[0] + s[1] * e[1] + s[2] * e[2]),
                s[0] * s[0] + s[1] * s[1] + s[2] * s[2] - 1.0,
                Face::Shell,
            )
        }
        CultureVolume::Box {
            length_m,
            width_m,
            bottom_m,
            top_m,
        } => {
            let (hl, hw) = (0.5 * length_m, 0.5 * width_m);
            span.slab(p0[0], d[0], -hl, hl, Face::X(-1.0), Face::X(1.0))
                && span.slab(p0[1], d[1], -hw, hw, Face::Y(-1.0), Face::Y(1.0))
                && span.slab(p0[2], d[2], bottom_m, top_m, Face::Bottom, Face::Top)
        }
    };
    if !inside {
        return None;
    }
    let t = span.lo;
    let p = [p0[0] + t * d[0], p0[1] + t * d[1], p0[2] + t * d[2]];
    let normal = match span.face {
        Face::Start => normalized([-d[0], -d[1], -d[2]]),
        Face::Bottom => [0.0, 0.0, -1.0],
        Face::Top => [0.0, 0.0, 1.0],
        Face::Side => normalized([p[0], p[1], 0.0]),
        Face::Shell => match *volume {
            CultureVolume::Ellipsoid {
                centre_m,
                horizontal_m,
                vertical_m,
            } => normalized([
                p[0] / (horizontal_m * horizontal_m),
                p[1] / (horizontal_m * horizontal_m),
                (p[2] - centre_m) / (vertical_m * vertical_m),
            ]),
            _ => [0.0, 0.0, 1.0],
        },
        Face::X(sign) => [sign, 0.0, 0.0],
        Face::Y(sign) => [0.0, sign, 0.0],
    };
    Some(VolumeEntry { t, normal })
}

/// Whether the point `p` (object frame, metres) is inside or on `volume`.
pub fn contains(volume: &CultureVolume, p: [f64; 3]) -> bool {
    match *volume {
        CultureVolume::Cylinder {
            radius_m,
            bottom_m,
            top_m,
        } => p[2] >= bottom_m && p[2] <= top_m && p[0] * p[0] + p[1] * p[1] <= radius_m * radius_m,
        CultureVolume::Ellipsoid {
            centre_m,
            horizontal_m,
            vertical_m,
        } => {
            let (x, y, z) = (
                p[0] / horizontal_m,
                p[1] / horizontal_m,
                (p[2] - centre_m) / vertical_m,
            );
            x * x + y * y + z * z <= 1.0
        }
        CultureVolume::Box {
            length_m,
            width_m,
            bottom_m,
            top_m,
        } => {
            p[0].abs() <= 0.5 * length_m
                && p[1].abs() <= 0.5 * width_m
                && p[2] >= bottom_m
                && p[2] <= top_m
        }
    }
}

/// Top of `volume` over the point `(x, y)` of the object's frame (metres above the base), with
/// the unit outward normal there; `None` where the volume is not over the point.
pub fn top_at(volume: &CultureVolume, x: f64, y: f64) -> Option<(f64, [f64; 3])> {
    match *volume {
        CultureVolume::Cylinder {
            radius_m, top_m, ..
        } => (x * x + y * y <= radius_m * radius_m).then_some((top_m, [0.0, 0.0, 1.0])),
        CultureVolume::Ellipsoid {
            centre_m,
            horizontal_m,
            vertical_m,
        } => {
            let q = (x * x + y * y) / (horizontal_m * horizontal_m);
            if q.is_nan() || q > 1.0 {
                return None;
            }
            let dz = vertical_m * (1.0 - q).sqrt();
            let normal = normalized([
                x / (horizontal_m * horizontal_m),
                y / (horizontal_m * horizontal_m),
                dz / (vertical_m * vertical_m),
            ]);
            Some((centre_m + dz, normal))
        }
        CultureVolume::Box {
            length_m,
            width_m,
            top_m,
            ..
        } => (x.abs() <= 0.5 * length_m && y.abs() <= 0.5 * width_m)
            .then_some((top_m, [0.0, 0.0, 1.0])),
    }
}

/// An object's local frame as a query sees it: from finest-grid coordinates (fractional
/// column and row of the whole database) and heights above mean sea level to the object's
/// metres.
#[derive(Clone, Copy, Debug)]
pub struct ItemFrame {
    /// The object's centre, finest-grid column and row.
    pub centre_col: f64,
    pub centre_row: f64,
    /// Metres per post eastwards and northwards at the object's latitude.
    pub east_m_per_post: f64,
    pub north_m_per_post: f64,
    pub base_m: f64,
    sin_heading: f64,
    cos_heading: f64,
}

impl ItemFrame {
    /// The frame of `item` in tile `key` of `layout`.
    pub fn new(layout: &PyramidLayout, key: TileKey, item: &CultureItem) -> ItemFrame {
        let g = &layout.grid;
        let cells = f64::from(layout.tile_cells);
        let centre_row = f64::from(key.row) * cells + f64::from(item.fi);
        let centre_col = f64::from(key.col) * cells + f64::from(item.fj);
        let lat_deg = g.south_lat_deg + centre_row * g.dlat_deg;
        let (north_m_per_deg, east_m_per_deg) = cig_geo::metres_per_degree(lat_deg);
        let (sin_heading, cos_heading) = item.heading_deg().to_radians().sin_cos();
        ItemFrame {
            centre_col,
            centre_row,
            east_m_per_post: g.dlon_deg * east_m_per_deg,
            north_m_per_post: g.dlat_deg * north_m_per_deg,
            base_m: f64::from(item.base_m),
            sin_heading,
            cos_heading,
        }
    }

    /// The object-frame point of finest-grid `(col, row)` at `height_msl_m`.
    #[inline]
    pub fn local(&self, col: f64, row: f64, height_msl_m: f64) -> [f64; 3] {
        let east = (col - self.centre_col) * self.east_m_per_post;
        let north = (row - self.centre_row) * self.north_m_per_post;
        [
            east * self.sin_heading + north * self.cos_heading,
            -east * self.cos_heading + north * self.sin_heading,
            height_msl_m - self.base_m,
        ]
    }

    /// An object-frame direction in the local east-north-up frame.
    pub fn to_enu(&self, v: [f64; 3]) -> [f64; 3] {
        [
            v[0] * self.sin_heading - v[1] * self.cos_heading,
            v[0] * self.cos_heading + v[1] * self.sin_heading,
            v[2],
        ]
    }
}

/// One non-empty 8 x 8-cell block of a tile's culture, as the queries use it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct IndexBlock {
    pub block_row: u32,
    pub block_col: u32,
    /// Range of the index's item order.
    start: u32,
    end: u32,
    /// Highest top of the block's objects above mean sea level, metres.
    pub top_msl_m: f32,
    /// Widest footprint radius of the block's objects, metres.
    pub footprint_m: f32,
}

/// A finest tile's culture arranged for the queries: its non-empty blocks in (row, column)
/// order with their highest top and widest footprint. Built once per tile a query session
/// uses (a few bytes per non-empty block; a permutation of the items only when a tile's items
/// are not stored block by block).
#[derive(Debug)]
pub struct CultureIndex {
    /// The tile the index describes (its culture holds the items).
    pub tile: Arc<Tile>,
    /// Item indices in block order, when the stored order is not.
    order: Option<Vec<u32>>,
    blocks: Vec<IndexBlock>,
    /// Highest top of the tile's objects above mean sea level, metres.
    pub top_msl_m: f64,
    /// Widest footprint radius of the tile's objects, metres.
    pub footprint_m: f64,
    /// Fewest metres per post (eastwards, northwards) anywhere on the tile: footprints in posts
    /// are at most their metres over these.
    pub min_m_per_post: [f64; 2],
}

fn block_of(f: f32) -> u32 {
    (f.max(0.0) as u32) / CULTURE_BLOCK_CELLS as u32
}

impl CultureIndex {
    /// The index of `tile`'s culture; `None` where it has none.
    pub fn new(layout: &PyramidLayout, tile: Arc<Tile>) -> Option<CultureIndex> {
        let culture: &CultureTile = tile.culture.as_ref().filter(|c| !c.items.is_empty())?;
        let items = &culture.items;
        let key_of = |k: usize| (block_of(items[k].fi), block_of(items[k].fj));
        let in_order = (1..items.len()).all(|k| key_of(k - 1) <= key_of(k));
        let order: Option<Vec<u32>> = (!in_order).then(|| {
            let mut order: Vec<u32> = (0..items.len() as u32).collect();
            order.sort_by_key(|&k| key_of(k as usize));
            order
        });
        let at = |n: usize| order.as_ref().map_or(n, |o| o[n] as usize);
        let mut blocks: Vec<IndexBlock> = Vec::new();
        for n in 0..items.len() {
            let item = &items[at(n)];
            let (r, c) = (block_of(item.fi), block_of(item.fj));
            let top = item.base_m + item.height_m;
            let footprint = item.footprint_radius_m();
            match blocks.last_mut() {
                Some(b) if b.block_row == r && b.block_col == c => {
                    b.end = n as u32 + 1;
                    b.top_msl_m = b.top_msl_m.max(top);
                    b.footprint_m = b.footprint_m.max(footprint);
                }
                _ => blocks.push(IndexBlock {
                    block_row: r,
                    block_col: c,
                    start: n as u32,
                    end: n as u32 + 1,
                    top_msl_m: top,
                    footprint_m: footprint,
                }),
            }
        }
        let top_msl_m = blocks
            .iter()
            .map(|b| f64::from(b.top_msl_m))
            .fold(f64::NEG_INFINITY, f64::max);
        let footprint_m = blocks
            .iter()
            .map(|b| f64::from(b.footprint_m))
            .fold(0.0, f64::max);
        let g = &layout.grid;
        let span = f64::from(layout.tile_cells) * g.dlat_deg;
        let south = g.south_lat_deg + f64::from(tile.key.row) * span;
        let (mut min_east, mut min_north) = (f64::INFINITY, f64::INFINITY);
        for lat in [south, south + span] {
            let (north_m_per_deg, east_m_per_deg) =
                cig_geo::metres_per_degree(lat.clamp(-90.0, 90.0));
            min_east = min_east.min(g.dlon_deg * east_m_per_deg);
            min_north = min_north.min(g.dlat_deg * north_m_per_deg);
        }
        Some(CultureIndex {
            order,
            blocks,
            top_msl_m,
            footprint_m,
            min_m_per_post: [min_east.max(1e-9), min_north.max(1e-9)],
            tile,
        })
    }

    /// The tile's items (empty where the tile has no culture).
    pub fn items(&self) -> &[CultureItem] {
        self.tile.culture.as_ref().map_or(&[], |c| &c.items)
    }

    /// The non-empty blocks of block row `row` with block columns `col_lo..=col_hi`.
    pub fn blocks_in_row(&self, row: u32, col_lo: u32, col_hi: u32) -> &[IndexBlock] {
        let lo = self
            .blocks
            .partition_point(|b| (b.block_row, b.block_col) < (row, col_lo));
        let hi = self
            .blocks
            .partition_point(|b| (b.block_row, b.block_col) <= (row, col_hi));
        &self.blocks[lo..hi.max(lo)]
    }

    /// Every non-empty block.
    pub fn blocks(&self) -> &[IndexBlock] {
        &self.blocks
    }

    /// Indices (into [`CultureIndex::items`]) of a block's items.
    pub fn block_items(&self, block: &IndexBlock) -> impl Iterator<Item = usize> + '_ {
        (block.start as usize..block.end as usize)
            .map(move |n| self.order.as_ref().map_or(n, |o| o[n] as usize))
    }

    /// Blocks per side a tile of `tile_cells` cells may use (items on the tile's last post
    /// row or column fall in one block past the cells).
    pub fn blocks_per_side(tile_cells: u32) -> u32 {
        tile_cells / CULTURE_BLOCK_CELLS as u32 + 1
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// `volume` grown by `eps` metres in every dimension (it holds the original).
    fn grown(volume: &CultureVolume, eps: f64) -> CultureVolume {
        match *volume {
            CultureVolume::Cylinder {
                radius_m,
                bottom_m,
                top_m,
            } => CultureVolume::Cylinder {
                radius_m: radius_m + eps,
                bottom_m: bottom_m - eps,
                top_m: top_m + eps,
            },
            CultureVolume::Ellipsoid {
                centre_m,
                horizontal_m,
                vertical_m,
            } => CultureVolume::Ellipsoid {
                centre_m,
                horizontal_m: horizontal_m + eps,
                vertical_m: vertical_m + eps,
            },
            CultureVolume::Box {
                length_m,
                width_m,
                bottom_m,
                top_m,
            } => CultureVolume::Box {
                length_m: length_m + 2.0 * eps,
                width_m: width_m + 2.0 * eps,
                bottom_m: bottom_m - eps,
                top_m: top_m + eps,
            },
        }
    }

    fn volume_strategy() -> impl Strategy<Value = CultureVolume> {
        prop_oneof![
            (0.1f64..10.0, -3.0f64..0.0, 0.5f64..30.0).prop_map(|(r, b, t)| {
                CultureVolume::Cylinder {
                    radius_m: r,
                    bottom_m: b,
                    top_m: t,
                }
            }),
            (1.0f64..20.0, 0.3f64..10.0, 0.3f64..15.0).prop_map(|(c, h, v)| {
                CultureVolume::Ellipsoid {
                    centre_m: c,
                    horizontal_m: h,
                    vertical_m: v,
                }
            }),
            (0.2f64..40.0, 0.1f64..20.0, -3.0f64..0.0, 0.5f64..20.0).prop_map(|(l, w, b, t)| {
                CultureVolume::Box {
                    length_m: l,
                    width_m: w,
                    bottom_m: b,
                    top_m: t,
                }
            }),
        ]
    }

    fn point() -> impl Strategy<Value = [f64; 3]> {
        [-25.0f64..25.0, -25.0f64..25.0, -5.0f64..35.0]
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(2000))]

        /// The closed-form entry agrees with a march of 2000 samples: where a sample is
        /// inside, the entry is at or before it and after the sample before; where the
        /// segment is inside over more than two samples' spacing, a sample is inside; the
        /// entry and the middle of the inside stretch lie on or in the volume.
        #[test]
        fn segment_entry_agrees_with_a_sampled_march(
            volume in volume_strategy(),
            p0 in point(),
            p1 in point(),
        ) {
            const SAMPLES: usize = 2000;
            let at = |t: f64| [
                p0[0] + t * (p1[0] - p0[0]),
                p0[1] + t * (p1[1] - p0[1]),
                p0[2] + t * (p1[2] - p0[2]),
            ];
            let step = 1.0 / (SAMPLES - 1) as f64;
            let first = (0..SAMPLES).find(|&n| contains(&volume, at(n as f64 * step)));
            let entry = segment_entry(&volume, p0, p1);
            // The exit, from the reversed segment (the volumes are convex).
            let exit = segment_entry(&volume, p1, p0).map(|e| 1.0 - e.t);
            let on = grown(&volume, 1e-7);
            match (first, entry) {
                (Some(n), Some(e)) => {
                    let t_n = n as f64 * step;
                    prop_assert!(e.t <= t_n + 1e-9, "entry {} after inside sample {t_n}", e.t);
                    if n > 0 {
                        prop_assert!(e.t >= t_n - step - 1e-9, "entry {} before sample {}", e.t, t_n - step);
                    }
                }
                (Some(n), None) => prop_assert!(false, "sample {n} is inside, no entry found"),
                (None, _) => {}
            }
            prop_assert_eq!(entry.is_some(), exit.is_some());
            if let (Some(e), Some(x)) = (entry, exit) {
                prop_assert!(x >= e.t - 1e-9, "exit {x} before entry {}", e.t);
                prop_assert!(contains(&on, at(e.t)), "entry point {:?} is not on the volume", at(e.t));
                prop_assert!(contains(&on, at(0.5 * (e.t + x))));
                let n: f64 = e.normal.iter().map(|v| v * v).sum();
                prop_assert!((n - 1.0).abs() < 1e-9, "normal {:?}", e.normal);
                if x - e.t > 2.0 * step {
                    prop_assert!(first.is_some(), "inside over [{}, {x}] but no sample is", e.t);
                }
            }
        }
    }

    fn cylinder() -> CultureVolume {
        CultureVolume::Cylinder {
            radius_m: 2.0,
            bottom_m: -1.0,
            top_m: 10.0,
        }
    }

    #[test]
    fn a_segment_across_a_cylinder_enters_at_its_side() {
        let e = segment_entry(&cylinder(), [-10.0, 0.0, 5.0], [10.0, 0.0, 5.0]).expect("hit");
        assert!((e.t - 0.4).abs() < 1e-12, "{e:?}");
        assert_eq!(e.normal, [-1.0, 0.0, 0.0]);
        // Over the top: a miss; down through the top: the top's normal.
        assert!(segment_entry(&cylinder(), [-10.0, 0.0, 10.5], [10.0, 0.0, 10.5]).is_none());
        let down = segment_entry(&cylinder(), [0.5, 0.0, 20.0], [0.5, 0.0, 0.0]).expect("hit");
        assert!((down.t - 0.5).abs() < 1e-12);
        assert_eq!(down.normal, [0.0, 0.0, 1.0]);
        // Starting inside: entered at once, normal against the direction.
        let inside = segment_entry(&cylinder(), [0.0, 0.0, 5.0], [5.0, 0.0, 5.0]).expect("hit");
        assert_eq!(inside.t, 0.0);
        assert_eq!(inside.normal, [-1.0, 0.0, 0.0]);
        // Ending short of it: a miss.
        assert!(segment_entry(&cylinder(), [-10.0, 0.0, 5.0], [-2.5, 0.0, 5.0]).is_none());
    }

    #[test]
    fn an_ellipsoid_is_its_scaled_sphere() {
        let v = CultureVolume::Ellipsoid {
            centre_m: 10.0,
            horizontal_m: 3.0,
            vertical_m: 6.0,
        };
        let e = segment_entry(&v, [0.0, -9.0, 10.0], [0.0, 9.0, 10.0]).expect("hit");
        assert!((e.t - 1.0 / 3.0).abs() < 1e-12);
        assert!((e.normal[1] + 1.0).abs() < 1e-12);
        let top = segment_entry(&v, [0.0, 0.0, 30.0], [0.0, 0.0, 0.0]).expect("hit");
        assert!((top.t - 14.0 / 30.0).abs() < 1e-12);
        assert!(segment_entry(&v, [3.1, -9.0, 10.0], [3.1, 9.0, 10.0]).is_none());
        let (z, n) = top_at(&v, 0.0, 0.0).expect("over");
        assert_eq!((z, n), (16.0, [0.0, 0.0, 1.0]));
        assert!(top_at(&v, 3.01, 0.0).is_none());
    }

    #[test]
    fn the_heading_turns_the_frame_clockwise_from_north() {
        let layout = PyramidLayout::new(
            crate::raster::GeoGrid {
                south_lat_deg: 45.0,
                west_lon_deg: 7.0,
                dlat_deg: 1.0 / 3600.0,
                dlon_deg: 1.0 / 3600.0,
                rows: 129,
                cols: 129,
            },
            64,
        );
        // A house 20 m long heading east (16384 / 65536 turns).
        let item = CultureItem {
            kind: CultureKind::House,
            variant: 0,
            heading: 16384,
            fi: 10.0,
            fj: 10.0,
            height_m: 8.0,
            width_m: 4.0,
            length_m: 20.0,
            base_m: 100.0,
            sink_m: 0.0,
        };
        let key = TileKey {
            level: 0,
            row: 0,
            col: 0,
        };
        let frame = ItemFrame::new(&layout, key, &item);
        let [volume, _] = item.volume();
        let volume = volume.expect("a box");
        let east_8m = 8.0 / frame.east_m_per_post;
        let north_8m = 8.0 / frame.north_m_per_post;
        let p = frame.local(10.0 + east_8m, 10.0, 104.0);
        assert!((p[0] - 8.0).abs() < 1e-9 && p[1].abs() < 1e-9, "{p:?}");
        assert!(contains(&volume, p));
        // North of the centre is the house's left.
        let q = frame.local(10.0, 10.0 + north_8m, 104.0);
        assert!(q[0].abs() < 1e-9 && (q[1] - 8.0).abs() < 1e-9, "{q:?}");
        assert!(!contains(&volume, q));
        assert_eq!(
            frame.to_enu([1.0, 0.0, 0.0]).map(|v| v.round()),
            [1.0, 0.0, 0.0]
        );
        assert_eq!(
            frame.to_enu([0.0, 1.0, 0.0]).map(|v| v.round()),
            [0.0, 1.0, 0.0]
        );
    }

    #[test]
    fn the_bounds_cover_every_valid_placement() {
        assert_eq!(tallest_object_m(), 400.0);
        assert!(widest_footprint_m() >= 0.5 * 400f64.hypot(400.0) - 1e-9);
    }
}
