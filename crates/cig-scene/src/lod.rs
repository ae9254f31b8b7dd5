//! Terrain level of detail: a quadtree of nodes over the database pyramid, selected each frame
//! by screen-space geometric error, with continuous vertex morphing between levels.
//!
//! Algorithm: Strugar's continuous distance-dependent level of detail (CDLOD, 2010) adapted to
//! error-driven ranges on a round earth. Every node covers `node_cells` cells of its pyramid
//! level; a node of level `L` has four children of level `L - 1`. A node whose geometric error
//! `e` (the exact vertical error of its level against the finest posts, stored in each tile's
//! min/max/error quadtree) would cover more than the allowed pixels anywhere in its bounding box
//! is refined; its error distance is `R = e * K / max_pixel_error` with `K` the view's pixels
//! per unit tangent, so a narrow (e.g. 6x periscope) view or a bigger frame refines further.
//! A node refines when its box comes nearer than `MORPH_SPAN * R`; its children's vertices
//! morph towards the parent's grid between `R_parent` and `MORPH_SPAN * R_parent` from the eye,
//! so the drawn surface changes continuously as the eye moves (the gradual transition of the
//! GE study, source 004 section 4.7) and never shows more than `max_pixel_error` pixels of
//! error. Nodes are culled against the frustum with the per-node min/max heights (source 003:
//! quadtree culling). Node boxes are built from 9 sample points at the lowest and highest
//! heights, in the node's local east-north-up frame, so curvature is included.
//!
//! Streaming: a node refines only when its children's tile is resident in the paging cache, so
//! the renderer always draws what is in memory; the renderer fades newly refined nodes in from
//! their parent's shape over half a second (a floor on the morph factor), so finer data morphs
//! in as it arrives. The selection lists the tiles it would have refined into.
//!
//! Limits: morph ranges come from each node's own error, not one range per level, so
//! neighbours may differ by more than one level or meet while one is still partly morphed, and a
//! node may be drawn from coarser data than its level while its tile loads; the resulting
//! T-junction gaps are hidden by skirts (see `terrain_mesh`). Node boxes sample 9 points per height, which is conservative
//! for nodes up to about 1000 km across.

use crate::view::Camera;
use cig_geo::{EnuFrame, Geodetic};
use cig_terrain::database::GeoidLookup;
use cig_terrain::pyramid::quadtree_index;
use cig_terrain::tile::NodeBounds;
use cig_terrain::{PyramidLayout, TileCache, TileKey};
use glam::DVec3;
use std::collections::HashMap;

/// Ratio between the distance where a node's children are fully morphed into it and the
/// distance where they start to morph.
pub const MORPH_SPAN: f64 = 1.3;

/// Default cells along a node's side.
pub const DEFAULT_NODE_CELLS: u32 = 16;

/// One node of the level-of-detail quadtree: `node_cells` cells of pyramid level `level`,
/// starting at node row `row` (south first) and column `col`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct NodeKey {
    pub level: u8,
    pub row: u32,
    pub col: u32,
}

impl NodeKey {
    /// The node one level coarser that contains this one.
    pub fn parent(self) -> NodeKey {
        NodeKey {
            level: self.level + 1,
            row: self.row / 2,
            col: self.col / 2,
        }
    }

    pub fn children(self) -> [NodeKey; 4] {
        let level = self.level.saturating_sub(1);
        let (r, c) = (self.row * 2, self.col * 2);
        [
            NodeKey {
                level,
                row: r,
                col: c,
            },
            NodeKey {
                level,
                row: r,
                col: c + 1,
            },
            NodeKey {
                level,
                row: r + 1,
                col: c,
            },
            NodeKey {
                level,
                row: r + 1,
                col: c + 1,
            },
        ]
    }
}

/// How the quadtree maps onto a database's pyramid.
#[derive(Clone, Copy, Debug)]
pub struct NodeLayout {
    pub pyramid: PyramidLayout,
    pub node_cells: u32,
}

impl NodeLayout {
    pub fn new(pyramid: PyramidLayout) -> NodeLayout {
        NodeLayout {
            pyramid,
            // A node's four children must lie in one tile of the finer level.
            node_cells: DEFAULT_NODE_CELLS.min(pyramid.tile_cells / 2).max(1),
        }
    }

    /// Finest cells along a node's side at `level`.
    pub fn finest_span(&self, level: u8) -> u64 {
        u64::from(self.node_cells) << level
    }

    /// Finest-grid (row, col) of the node's south-west post.
    pub fn finest_origin(&self, key: NodeKey) -> (u64, u64) {
        let span = self.finest_span(key.level);
        (u64::from(key.row) * span, u64::from(key.col) * span)
    }

    /// True when the node starts inside the database.
    pub fn exists(&self, key: NodeKey) -> bool {
        let (r0, c0) = self.finest_origin(key);
        key.level < self.pyramid.levels
            && r0 < (self.pyramid.grid.rows.max(2) - 1) as u64
            && c0 < (self.pyramid.grid.cols.max(2) - 1) as u64
    }

    /// The tile of `level >= key.level` that contains the node.
    pub fn tile_of(&self, key: NodeKey, level: u8) -> TileKey {
        let (r0, c0) = self.finest_origin(key);
        let tile_span = self.pyramid.finest_cells_per_tile(level);
        TileKey {
            level,
            row: (r0 / tile_span) as u32,
            col: (c0 / tile_span) as u32,
        }
    }

    /// Nodes of the whole quadtree, every level.
    pub fn node_count(&self) -> u64 {
        (0..self.pyramid.levels)
            .map(|level| {
                let span = self.finest_span(level);
                let rows = ((self.pyramid.grid.rows.max(2) - 1) as u64).div_ceil(span);
                let cols = ((self.pyramid.grid.cols.max(2) - 1) as u64).div_ceil(span);
                rows * cols
            })
            .sum()
    }

    /// The coarsest level's nodes: the roots of the quadtree.
    pub fn roots(&self) -> Vec<NodeKey> {
        let level = self.pyramid.levels - 1;
        let span = self.finest_span(level);
        let rows = ((self.pyramid.grid.rows.max(2) - 1) as u64).div_ceil(span) as u32;
        let cols = ((self.pyramid.grid.cols.max(2) - 1) as u64).div_ceil(span) as u32;
        (0..rows)
            .flat_map(|row| (0..cols).map(move |col| NodeKey { level, row, col }))
            .collect()
    }

    /// Geodetic latitude and longitude of a finest-grid (row, col) index, clamped to the
    /// database.
    pub fn lat_lon_of_finest(&self, row: f64, col: f64) -> (f64, f64) {
        let g = &self.pyramid.grid;
        let row = row.clamp(0.0, (g.rows.max(1) - 1) as f64);
        let col = col.clamp(0.0, (g.cols.max(1) - 1) as f64);
        (
            g.south_lat_deg + row * g.dlat_deg,
            g.west_lon_deg + col * g.dlon_deg,
        )
    }

    /// Min/max/error bounds of a node read from a resident tile of level `tile.level >=
    /// key.level` (the deepest quadtree node of that tile that covers the whole node).
    pub fn node_bounds_in(&self, key: NodeKey, tile: TileKey, nodes: &[NodeBounds]) -> NodeBounds {
        let depth_max = cig_terrain::tile::quadtree_depth_for(self.pyramid.tile_cells as usize);
        let tile_span = self.pyramid.finest_cells_per_tile(tile.level);
        let span = self.finest_span(key.level).min(tile_span);
        let mut depth = 0u32;
        while depth < depth_max && (tile_span >> (depth + 1)) >= span {
            depth += 1;
        }
        let q_span = tile_span >> depth;
        let (r0, c0) = self.finest_origin(key);
        let y = ((r0 - u64::from(tile.row) * tile_span) / q_span) as usize;
        let x = ((c0 - u64::from(tile.col) * tile_span) / q_span) as usize;
        nodes
            .get(quadtree_index(depth, x, y))
            .copied()
            .unwrap_or(NodeBounds::EMPTY)
    }
}

/// Settings of the selection.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LodSettings {
    /// Largest geometric error allowed on screen, pixels; 0 forces full detail everywhere.
    pub max_pixel_error: f64,
}

impl Default for LodSettings {
    fn default() -> Self {
        LodSettings {
            max_pixel_error: 1.0,
        }
    }
}

/// A node chosen for drawing.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SelectedNode {
    pub key: NodeKey,
    /// Pyramid level of the data its mesh is built from (`>= key.level`; greater while the
    /// node's own tile is still loading).
    pub data_level: u8,
    /// Distance from the eye (metres) where vertices start morphing towards the parent grid,
    /// and where they have fully morphed; infinite for nodes that never morph.
    pub morph_start_m: f32,
    pub morph_end_m: f32,
    /// The node's geometric error against the finest posts, metres.
    pub error_m: f32,
    /// Distance from the eye to the node's box, metres.
    pub distance_m: f64,
}

/// Result of one selection.
#[derive(Clone, Debug, Default)]
pub struct Selection {
    pub nodes: Vec<SelectedNode>,
    /// Tiles the selection would have refined into but are not resident (nearest first).
    pub wanted_tiles: Vec<TileKey>,
    /// Nodes visited (for statistics).
    pub visited: usize,
}

#[derive(Clone, Copy, Debug)]
struct NodeGeometry {
    data_level: u8,
    bounds: NodeBounds,
    /// Sample points (ECEF) at the lowest and highest heights.
    points: [DVec3; 18],
    frame_origin: DVec3,
    /// Local ENU axes of the node centre.
    axes: [DVec3; 3],
    box_min: DVec3,
    box_max: DVec3,
}

/// The persistent part of the selection: node boxes cached across frames.
pub struct TerrainLod {
    pub layout: NodeLayout,
    geoid: GeoidLookup,
    geometry: HashMap<NodeKey, NodeGeometry>,
}

/// Margin added to node boxes for the geoid's variation across a node and rounding, metres.
const BOX_MARGIN_M: f64 = 2.0;

impl TerrainLod {
    pub fn new(layout: NodeLayout, geoid: GeoidLookup) -> TerrainLod {
        TerrainLod {
            layout,
            geoid,
            geometry: HashMap::new(),
        }
    }

    pub fn geoid(&self) -> &GeoidLookup {
        &self.geoid
    }

    /// The finest resident tile holding `key` (its level, the tile), walking up the pyramid.
    pub fn resident_source(
        &self,
        cache: &TileCache,
        key: NodeKey,
    ) -> Option<(TileKey, std::sync::Arc<cig_terrain::tile::Tile>)> {
        let mut level = key.level;
        while level < self.layout.pyramid.levels {
            let tk = self.layout.tile_of(key, level);
            if let Some(t) = cache.resident(tk) {
                return Some((tk, t));
            }
            level += 1;
        }
        None
    }

    fn geometry(&mut self, cache: &TileCache, key: NodeKey) -> Option<NodeGeometry> {
        let (tile_key, tile) = self.resident_source(cache, key)?;
        if let Some(g) = self.geometry.get(&key) {
            if g.data_level == tile_key.level {
                return Some(*g);
            }
        }
        let bounds = self.layout.node_bounds_in(key, tile_key, &tile.nodes);
        let g = self.build_geometry(key, tile_key.level, bounds);
        self.geometry.insert(key, g);
        Some(g)
    }

    fn build_geometry(&self, key: NodeKey, data_level: u8, bounds: NodeBounds) -> NodeGeometry {
        let (r0, c0) = self.layout.finest_origin(key);
        let span = self.layout.finest_span(key.level) as f64;
        let (lat_c, lon_c) = self
            .layout
            .lat_lon_of_finest(r0 as f64 + span / 2.0, c0 as f64 + span / 2.0);
        let n_c = self.geoid.undulation_m(lat_c, lon_c);
        let (lo, hi) = if bounds.min_m <= bounds.max_m {
            (f64::from(bounds.min_m), f64::from(bounds.max_m))
        } else {
            (0.0, 0.0)
        };
        // The surface bulges above the chords between the 9 sample points by up to
        // D^2 / (32 R) for a node D across.
        let span_m = span * self.layout.pyramid.grid.dlat_deg * 111_000.0;
        let bulge_m = span_m * span_m / (32.0 * 6_356_000.0);
        let mut points = [DVec3::ZERO; 18];
        let mut k = 0;
        for (fr, fc) in [
            (0.0, 0.0),
            (0.0, 0.5),
            (0.0, 1.0),
            (0.5, 0.0),
            (0.5, 0.5),
            (0.5, 1.0),
            (1.0, 0.0),
            (1.0, 0.5),
            (1.0, 1.0),
        ] {
            let (lat, lon) = self
                .layout
                .lat_lon_of_finest(r0 as f64 + fr * span, c0 as f64 + fc * span);
            let n = self.geoid.undulation_m(lat, lon);
            for h in [lo - BOX_MARGIN_M, hi + BOX_MARGIN_M + bulge_m] {
                points[k] = Geodetic::new(lat, lon, h + n).to_ecef();
                k += 1;
            }
        }
        let frame = EnuFrame::new(Geodetic::new(lat_c, lon_c, n_c + (lo + hi) / 2.0));
        let axes = [
            frame.enu_vector_to_ecef(DVec3::X),
            frame.enu_vector_to_ecef(DVec3::Y),
            frame.enu_vector_to_ecef(DVec3::Z),
        ];
        let mut box_min = DVec3::splat(f64::INFINITY);
        let mut box_max = DVec3::splat(f64::NEG_INFINITY);
        for p in &points {
            let d = *p - frame.origin_ecef();
            let local = DVec3::new(d.dot(axes[0]), d.dot(axes[1]), d.dot(axes[2]));
            box_min = box_min.min(local);
            box_max = box_max.max(local);
        }
        NodeGeometry {
            data_level,
            bounds,
            points,
            frame_origin: frame.origin_ecef(),
            axes,
            box_min,
            box_max,
        }
    }

    /// Selects the nodes to draw for one camera.
    pub fn select(
        &mut self,
        cache: &TileCache,
        camera: &Camera,
        settings: &LodSettings,
    ) -> Selection {
        let mut selection = Selection::default();
        if self.geometry.len() > 50_000 {
            self.geometry.clear();
        }
        let pixels_per_metre_at_1m = if settings.max_pixel_error > 0.0 {
            camera.pixels_per_tangent / settings.max_pixel_error
        } else {
            f64::INFINITY
        };
        let mut stack: Vec<(NodeKey, f64)> = self
            .layout
            .roots()
            .into_iter()
            .map(|k| (k, f64::INFINITY))
            .collect();
        let mut wanted: Vec<(f64, TileKey)> = Vec::new();
        while let Some((key, parent_range_m)) = stack.pop() {
            selection.visited += 1;
            let Some(g) = self.geometry(cache, key) else {
                wanted.push((f64::INFINITY, self.layout.tile_of(key, key.level)));
                continue;
            };
            let rel: [DVec3; 18] = g.points.map(|p| p - camera.eye_ecef);
            if camera.culls(&rel) {
                continue;
            }
            let d = camera.eye_ecef - g.frame_origin;
            let local = DVec3::new(d.dot(g.axes[0]), d.dot(g.axes[1]), d.dot(g.axes[2]));
            let distance_m = (local.clamp(g.box_min, g.box_max) - local).length();
            let error_m = f64::from(g.bounds.error_m.max(0.0));
            let range_m = if error_m > 0.0 {
                error_m * pixels_per_metre_at_1m
            } else {
                0.0
            };
            let wants_refine = key.level > 0 && distance_m < range_m * MORPH_SPAN;
            if wants_refine {
                let child_tile = self.layout.tile_of(key, key.level - 1);
                if cache.resident(child_tile).is_some() {
                    for child in key.children() {
                        if self.layout.exists(child) {
                            stack.push((child, range_m));
                        }
                    }
                    continue;
                }
                wanted.push((distance_m, child_tile));
            }
            let (morph_start_m, morph_end_m) = if parent_range_m.is_finite() {
                (parent_range_m, parent_range_m * MORPH_SPAN)
            } else {
                (f64::INFINITY, f64::INFINITY)
            };
            selection.nodes.push(SelectedNode {
                key,
                data_level: g.data_level,
                morph_start_m: morph_start_m as f32,
                morph_end_m: morph_end_m as f32,
                error_m: error_m as f32,
                distance_m,
            });
        }
        wanted.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        wanted.dedup_by(|a, b| a.1 == b.1);
        let mut seen = std::collections::HashSet::new();
        selection.wanted_tiles = wanted
            .into_iter()
            .filter(|(_, k)| seen.insert(*k))
            .map(|(_, k)| k)
            .collect();
        selection
            .nodes
            .sort_by(|a, b| a.distance_m.total_cmp(&b.distance_m));
        selection
    }

    /// Forgets cached node boxes (e.g. after tiles were evicted and reloaded at another level).
    pub fn clear(&mut self) {
        self.geometry.clear();
    }
}
