//! Builds a database's tile pyramid from a finished raster.
//!
//! Source: NPSNET (source 003) built its coarser resolutions by combining four finer areas and
//! chose each coarse polygon's colour by majority. Here level `k + 1` keeps every other post of
//! level `k` (so every coarse vertex lies on the finest surface, which lets a renderer morph
//! between levels without popping), its materials are the majority of the 3 x 3 finer posts
//! around each kept post, and every quadtree node of every level records the min/max of the
//! *finest* surface below it and the largest vertical error of its own surface against the
//! finest posts — the bounds culling, line of sight and level-of-detail selection need — and
//! every post the error of the triangulated irregular network over its level ([`crate::rtin`]),
//! from which the renderer draws adaptive meshes that nest across levels.
//!
//! Limits: the whole raster is held in memory while building (5 bytes per post plus the tiles
//! of one level); the error bound is measured at the finest posts, which is exact for the
//! triangulated surfaces because both are piecewise linear with vertices at those posts.

use crate::material::Material;
use crate::pyramid::{quadtree_index, quadtree_node_count, PyramidLayout, TileKey};
use crate::raster::Raster;
use crate::rtin::{level_errors, own_errors, LevelErrorGrid};
use crate::tile::{even_posts_per_side, quadtree_depth_for, LodErrors, NodeBounds, Tile};
use rayon::prelude::*;

/// Why a pyramid could not be built.
#[derive(Debug, thiserror::Error)]
pub enum BuildError {
    #[error("tile size {0} cells is not a power of two between 16 and 4096")]
    TileCells(u32),
    #[error("raster has {rows} x {cols} posts; at least 2 x 2 are needed")]
    TooSmall { rows: usize, cols: usize },
    #[error("raster still has {0} void posts; fill them before building")]
    Voids(usize),
    #[error("raster has no materials; classify it before building")]
    NoMaterials,
    #[error("raster arrays hold {found} values for {expected} posts")]
    Size { found: usize, expected: usize },
}

/// Summary of a built pyramid.
#[derive(Clone, Debug, PartialEq)]
pub struct BuildSummary {
    pub layout: PyramidLayout,
    pub tiles: u64,
    pub min_elevation_m: f32,
    pub max_elevation_m: f32,
    /// Posts of each material at the finest level, in [`Material::ALL`] order.
    pub material_posts: [u64; 9],
}

/// Builds every tile of the pyramid, finest level first, handing each to `emit` (which may
/// write it out; an error from `emit` stops the build and is returned).
pub fn build_pyramid<E: From<BuildError>>(
    raster: &Raster,
    tile_cells: u32,
    emit: &mut dyn FnMut(&Tile) -> Result<(), E>,
) -> Result<BuildSummary, E> {
    if !tile_cells.is_power_of_two() || !(16..=4096).contains(&tile_cells) {
        return Err(BuildError::TileCells(tile_cells).into());
    }
    let grid = raster.grid;
    if grid.rows < 2 || grid.cols < 2 {
        return Err(BuildError::TooSmall {
            rows: grid.rows,
            cols: grid.cols,
        }
        .into());
    }
    if raster.elevation_m.len() != grid.len() {
        return Err(BuildError::Size {
            found: raster.elevation_m.len(),
            expected: grid.len(),
        }
        .into());
    }
    let materials = match &raster.material {
        Some(m) if m.len() == grid.len() => m,
        Some(m) => {
            return Err(BuildError::Size {
                found: m.len(),
                expected: grid.len(),
            }
            .into())
        }
        None => return Err(BuildError::NoMaterials.into()),
    };
    let voids = raster.void_count();
    if voids > 0 {
        return Err(BuildError::Voids(voids).into());
    }
    let layout = PyramidLayout::new(grid, tile_cells);
    let material_posts = material_histogram(materials);
    let mut level_materials = LevelGrid {
        rows: grid.rows,
        cols: grid.cols,
        values: materials.iter().map(|m| m.to_byte()).collect(),
    };
    let mut tiles = 0u64;
    let mut min_elevation_m = f32::INFINITY;
    let mut max_elevation_m = f32::NEG_INFINITY;
    let own = own_errors(raster);
    let mut errors = level_errors(raster, &own, 0);
    for level in 0..layout.levels {
        if level > 0 {
            level_materials = level_materials.majority_halved();
        }
        let coarser = (level + 1 < layout.levels).then(|| level_errors(raster, &own, level + 1));
        let keys: Vec<TileKey> = layout.keys_at(level).collect();
        let built: Vec<Tile> = keys
            .par_iter()
            .map(|&key| {
                let mut tile = build_tile(raster, &layout, &level_materials, key);
                tile.lod_errors = Some(tile_lod_errors(&layout, key, &errors, coarser.as_ref()));
                tile
            })
            .collect();
        if let Some(next) = coarser {
            errors = next;
        }
        for tile in &built {
            let b = tile.bounds();
            min_elevation_m = min_elevation_m.min(b.min_m);
            max_elevation_m = max_elevation_m.max(b.max_m);
            emit(tile)?;
            tiles += 1;
        }
    }
    Ok(BuildSummary {
        layout,
        tiles,
        min_elevation_m,
        max_elevation_m,
        material_posts,
    })
}

/// The adaptive-mesh errors of tile `key`'s posts and of its even posts one level coarser.
fn tile_lod_errors(
    layout: &PyramidLayout,
    key: TileKey,
    own: &LevelErrorGrid,
    coarser: Option<&LevelErrorGrid>,
) -> LodErrors {
    let n = layout.posts_per_side();
    let span = layout.tile_cells as usize;
    let (i0, j0) = (key.row as usize * span, key.col as usize * span);
    let own_m = (0..n * n).map(|k| own.at(i0 + k / n, j0 + k % n)).collect();
    let m = even_posts_per_side(n);
    let coarser_m = (0..m * m)
        .map(|k| coarser.map_or(0.0, |c| c.at(i0 / 2 + k / m, j0 / 2 + k % m)))
        .collect();
    LodErrors { own_m, coarser_m }
}

/// A whole-area grid of material bytes at one level's resolution.
struct LevelGrid {
    rows: usize,
    cols: usize,
    values: Vec<u8>,
}

impl LevelGrid {
    fn at(&self, row: usize, col: usize) -> u8 {
        self.values[row.min(self.rows - 1) * self.cols + col.min(self.cols - 1)]
    }

    /// Keeps every other post; each kept post takes the majority material of the 3 x 3 posts
    /// around it (ties keep the centre's material).
    fn majority_halved(&self) -> LevelGrid {
        let rows = (self.rows - 1).div_ceil(2) + 1;
        let cols = (self.cols - 1).div_ceil(2) + 1;
        let values = (0..rows * cols)
            .into_par_iter()
            .map(|k| {
                let (r, c) = ((k / cols) * 2, (k % cols) * 2);
                let mut counts = [0u8; 9];
                for dr in -1i64..=1 {
                    for dc in -1i64..=1 {
                        let rr = (r as i64 + dr).clamp(0, self.rows as i64 - 1) as usize;
                        let cc = (c as i64 + dc).clamp(0, self.cols as i64 - 1) as usize;
                        counts[self.at(rr, cc) as usize % 9] += 1;
                    }
                }
                let centre = self.at(r, c);
                let mut best = centre;
                for (m, &n) in counts.iter().enumerate() {
                    if n > counts[best as usize % 9] {
                        best = m as u8;
                    }
                }
                best
            })
            .collect();
        LevelGrid { rows, cols, values }
    }
}

fn build_tile(
    raster: &Raster,
    layout: &PyramidLayout,
    materials: &LevelGrid,
    key: TileKey,
) -> Tile {
    let grid = raster.grid;
    let n = layout.posts_per_side();
    let mut elevation_m = Vec::with_capacity(n * n);
    let mut material = Vec::with_capacity(n * n);
    let span = layout.tile_cells as usize;
    for i in 0..n {
        for j in 0..n {
            let (r, c) = layout.finest_index_of_post(key, i, j);
            elevation_m.push(raster.elevation_m[r * grid.cols + c]);
            material.push(materials.at(key.row as usize * span + i, key.col as usize * span + j));
        }
    }
    let depth = quadtree_depth_for(span);
    let mut tile = Tile {
        key,
        posts_per_side: n,
        elevation_m,
        material,
        nodes: vec![NodeBounds::EMPTY; quadtree_node_count(depth)],
        quadtree_depth: depth,
        lod_errors: None,
        degraded_from_level: None,
        culture: None,
    };
    fill_bounds(&mut tile, raster, layout);
    tile
}

/// Measures each leaf against the finest posts under it, then folds leaves up to the root.
fn fill_bounds(tile: &mut Tile, raster: &Raster, layout: &PyramidLayout) {
    let grid = raster.grid;
    let depth = tile.quadtree_depth;
    let leaves = 1usize << depth;
    let step = 1usize << tile.key.level;
    let leaf_fine = (layout.tile_cells as usize >> depth) * step;
    let tile_fine = layout.tile_cells as usize * step;
    let row0 = tile.key.row as usize * tile_fine;
    let col0 = tile.key.col as usize * tile_fine;
    let inv_step = 1.0 / step as f64;
    for y in 0..leaves {
        for x in 0..leaves {
            let mut b = NodeBounds::EMPTY;
            let r_start = row0 + y * leaf_fine;
            let c_start = col0 + x * leaf_fine;
            let r_end = (r_start + leaf_fine).min(grid.rows - 1);
            let c_end = (c_start + leaf_fine).min(grid.cols - 1);
            if r_start > r_end || c_start > c_end {
                // Wholly past the database edge: bound it by the clamped edge posts it repeats.
                let h = tile.elevation(
                    (y * (tile.cells() >> depth)).min(tile.cells()),
                    (x * (tile.cells() >> depth)).min(tile.cells()),
                );
                b = NodeBounds {
                    min_m: h,
                    max_m: h,
                    error_m: 0.0,
                };
            } else {
                for r in r_start..=r_end {
                    let fi = (r - row0) as f64 * inv_step;
                    for c in c_start..=c_end {
                        let h = raster.elevation_m[r * grid.cols + c];
                        b.min_m = b.min_m.min(h);
                        b.max_m = b.max_m.max(h);
                        if step > 1 {
                            let fj = (c - col0) as f64 * inv_step;
                            let coarse = tile.surface_height(fi, fj);
                            b.error_m = b.error_m.max((coarse - f64::from(h)).abs() as f32);
                        }
                    }
                }
            }
            tile.nodes[quadtree_index(depth, x, y)] = b;
        }
    }
    for d in (0..depth).rev() {
        for y in 0..(1usize << d) {
            for x in 0..(1usize << d) {
                let kids = [
                    tile.nodes[quadtree_index(d + 1, 2 * x, 2 * y)],
                    tile.nodes[quadtree_index(d + 1, 2 * x + 1, 2 * y)],
                    tile.nodes[quadtree_index(d + 1, 2 * x, 2 * y + 1)],
                    tile.nodes[quadtree_index(d + 1, 2 * x + 1, 2 * y + 1)],
                ];
                tile.nodes[quadtree_index(d, x, y)] =
                    kids.iter().fold(NodeBounds::EMPTY, |acc, k| acc.union(*k));
            }
        }
    }
}

/// Counts of each material in a raster, in [`Material::ALL`] order.
pub fn material_histogram(materials: &[Material]) -> [u64; 9] {
    let mut counts = [0u64; 9];
    for m in materials {
        counts[m.to_byte() as usize] += 1;
    }
    counts
}

/// What [`prepare_raster`] did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PrepareReport {
    pub void_posts_filled: usize,
    pub materials_derived: bool,
}

/// Makes a raster ready to build: fills its voids and derives materials when it has none.
pub fn prepare_raster(raster: &mut Raster) -> Result<PrepareReport, crate::fill::FillError> {
    let void_posts_filled = crate::fill::fill_voids(raster)?;
    let materials_derived = raster.material.is_none();
    if materials_derived {
        crate::classify::classify_materials(raster);
    }
    Ok(PrepareReport {
        void_posts_filled,
        materials_derived,
    })
}
