//! The quadtree pyramid of tiles over a database's finest post grid.
//!
//! Source: NPSNET's terrain structure (source 003): an array of tiles, each the root of a
//! quadtree, with coarser resolutions built by combining four finer areas. Here the finest level
//! (level 0) holds the source posts unchanged; level `k` samples every `2^k`-th finest post, so a
//! level-`k+1` tile covers exactly the area of four level-`k` tiles with the same post count.
//! Neighbouring tiles share their edge posts. Level `levels - 1` is a single tile covering the
//! whole database.
//!
//! Limits: the finest grid is one regular geographic lattice; tiles past the database's north or
//! east edge repeat the edge posts (queries there are refused as outside the database).

use crate::raster::GeoGrid;
use serde::{Deserialize, Serialize};

/// Identifies one tile: its level (0 = finest) and its tile row (south first) and column.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
pub struct TileKey {
    pub level: u8,
    pub row: u32,
    pub col: u32,
}

impl TileKey {
    /// The tile one level coarser that contains this one.
    pub fn parent(self) -> TileKey {
        TileKey {
            level: self.level + 1,
            row: self.row / 2,
            col: self.col / 2,
        }
    }

    /// The four tiles one level finer (south-west, south-east, north-west, north-east).
    /// Only meaningful for `level > 0`; children outside the database are filtered by the layout.
    pub fn children(self) -> [TileKey; 4] {
        let level = self.level.saturating_sub(1);
        let (r, c) = (self.row * 2, self.col * 2);
        [
            TileKey {
                level,
                row: r,
                col: c,
            },
            TileKey {
                level,
                row: r,
                col: c + 1,
            },
            TileKey {
                level,
                row: r + 1,
                col: c,
            },
            TileKey {
                level,
                row: r + 1,
                col: c + 1,
            },
        ]
    }
}

impl std::fmt::Display for TileKey {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "L{}/{}_{}", self.level, self.row, self.col)
    }
}

/// The layout of a database's pyramid: finest grid, tile size and number of levels.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct PyramidLayout {
    /// The finest level's post grid (the whole database).
    pub grid: GeoGrid,
    /// Cells along a tile's side at every level (a power of two); a tile has
    /// `tile_cells + 1` posts along a side.
    pub tile_cells: u32,
    /// Number of levels, finest (0) to a single tile (`levels - 1`).
    pub levels: u8,
}

impl PyramidLayout {
    /// The layout for a finest grid and tile size, with as many levels as it takes to reach one
    /// tile. `tile_cells` must be a power of two of at least 2.
    pub fn new(grid: GeoGrid, tile_cells: u32) -> PyramidLayout {
        let mut layout = PyramidLayout {
            grid,
            tile_cells,
            levels: 1,
        };
        while layout.tiles_at(layout.levels - 1) != (1, 1) && layout.levels < 32 {
            layout.levels += 1;
        }
        layout
    }

    /// Posts along a tile's side.
    pub fn posts_per_side(&self) -> usize {
        self.tile_cells as usize + 1
    }

    /// Finest cells spanned by one tile side at `level`.
    pub fn finest_cells_per_tile(&self, level: u8) -> u64 {
        u64::from(self.tile_cells) << level
    }

    /// (tile rows, tile columns) at `level`.
    pub fn tiles_at(&self, level: u8) -> (u32, u32) {
        let span = self.finest_cells_per_tile(level);
        let cells_r = (self.grid.rows.max(2) - 1) as u64;
        let cells_c = (self.grid.cols.max(2) - 1) as u64;
        (cells_r.div_ceil(span) as u32, cells_c.div_ceil(span) as u32)
    }

    /// True when `key` names a tile of this pyramid.
    pub fn contains_key(&self, key: TileKey) -> bool {
        if key.level >= self.levels {
            return false;
        }
        let (rows, cols) = self.tiles_at(key.level);
        key.row < rows && key.col < cols
    }

    /// Every tile key of one level, row-major from the south-west.
    pub fn keys_at(&self, level: u8) -> impl Iterator<Item = TileKey> {
        let (rows, cols) = self.tiles_at(level);
        (0..rows).flat_map(move |row| (0..cols).map(move |col| TileKey { level, row, col }))
    }

    /// Total number of tiles over all levels.
    pub fn tile_count(&self) -> u64 {
        (0..self.levels)
            .map(|l| {
                let (r, c) = self.tiles_at(l);
                u64::from(r) * u64::from(c)
            })
            .sum()
    }

    /// Post spacing (dlat, dlon) at `level`, degrees.
    pub fn spacing_deg(&self, level: u8) -> (f64, f64) {
        let scale = (1u64 << level) as f64;
        (self.grid.dlat_deg * scale, self.grid.dlon_deg * scale)
    }

    /// Finest-grid (row, col) of a tile's post `(i, j)` (`i` northwards, `j` eastwards), clamped
    /// to the grid's last row and column.
    pub fn finest_index_of_post(&self, key: TileKey, i: usize, j: usize) -> (usize, usize) {
        let step = 1usize << key.level;
        let span = self.tile_cells as usize;
        let row = (key.row as usize * span + i) * step;
        let col = (key.col as usize * span + j) * step;
        (
            row.min(self.grid.rows.saturating_sub(1)),
            col.min(self.grid.cols.saturating_sub(1)),
        )
    }

    /// The tile of `level` containing the finest-grid fractional index `(row_f, col_f)`, and
    /// the fractional index within that tile's posts. Points on a shared edge go to the tile
    /// to the north/east, except at the database's last row/column.
    pub fn locate(&self, level: u8, row_f: f64, col_f: f64) -> (TileKey, f64, f64) {
        let span = self.finest_cells_per_tile(level) as f64;
        let (rows, cols) = self.tiles_at(level);
        let tr = ((row_f / span).floor().max(0.0) as u32).min(rows - 1);
        let tc = ((col_f / span).floor().max(0.0) as u32).min(cols - 1);
        let scale = (1u64 << level) as f64;
        let i = (row_f - f64::from(tr) * span) / scale;
        let j = (col_f - f64::from(tc) * span) / scale;
        (
            TileKey {
                level,
                row: tr,
                col: tc,
            },
            i,
            j,
        )
    }
}

/// Number of nodes of a tile's min/max quadtree of `depth` levels below the root
/// (NPSNET: a 4-level tree has 85 nodes).
pub const fn quadtree_node_count(depth: u32) -> usize {
    // 1 + 4 + 16 + ... + 4^depth
    ((1usize << (2 * (depth + 1))) - 1) / 3
}

/// Heap index of node `(x, y)` at depth `d` of a quadtree (root is depth 0, index 0; nodes of
/// one depth are stored row-major, lowest resolution first as in NPSNET).
pub const fn quadtree_index(d: u32, x: usize, y: usize) -> usize {
    quadtree_node_count(d) - (1usize << (2 * d)) + y * (1usize << d) + x
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grid(rows: usize, cols: usize) -> GeoGrid {
        GeoGrid {
            south_lat_deg: 35.0,
            west_lon_deg: -121.0,
            dlat_deg: 1.0 / 3600.0,
            dlon_deg: 1.0 / 3600.0,
            rows,
            cols,
        }
    }

    #[test]
    fn levels_end_in_one_tile() {
        let l = PyramidLayout::new(grid(3601, 3601), 128);
        assert_eq!(l.tiles_at(0), (29, 29));
        assert_eq!(l.tiles_at(l.levels - 1), (1, 1));
        assert_ne!(l.tiles_at(l.levels - 2), (1, 1));
        assert_eq!(l.levels, 6);
        let small = PyramidLayout::new(grid(129, 129), 128);
        assert_eq!(small.levels, 1);
    }

    #[test]
    fn npsnet_tree_has_85_nodes() {
        assert_eq!(quadtree_node_count(3), 85);
        assert_eq!(quadtree_index(0, 0, 0), 0);
        assert_eq!(quadtree_index(1, 0, 0), 1);
        assert_eq!(quadtree_index(3, 7, 7), 84);
    }

    proptest::proptest! {
        #[test]
        fn parent_contains_child(level in 0u8..6, row in 0u32..1000, col in 0u32..1000) {
            let key = TileKey { level, row, col };
            let parent = key.parent();
            proptest::prop_assert!(parent.children().contains(&key));
        }

        #[test]
        fn locate_finds_the_tile_whose_bounds_hold_the_point(
            rows in 2usize..5000, cols in 2usize..5000, fr in 0.0f64..1.0, fc in 0.0f64..1.0, level in 0u8..4
        ) {
            let l = PyramidLayout::new(grid(rows, cols), 64);
            let level = level.min(l.levels - 1);
            let row_f = fr * (rows - 1) as f64;
            let col_f = fc * (cols - 1) as f64;
            let (key, i, j) = l.locate(level, row_f, col_f);
            proptest::prop_assert!(l.contains_key(key));
            proptest::prop_assert!((-1e-9..=64.0 + 1e-9).contains(&i), "i={}", i);
            proptest::prop_assert!((-1e-9..=64.0 + 1e-9).contains(&j), "j={}", j);
            // The tile's post (i, j) maps back onto the point.
            let scale = (1u64 << level) as f64;
            let back_r = (key.row as f64 * 64.0 + i) * scale;
            let back_c = (key.col as f64 * 64.0 + j) * scale;
            proptest::prop_assert!((back_r - row_f).abs() < 1e-6);
            proptest::prop_assert!((back_c - col_f).abs() < 1e-6);
        }
    }
}
