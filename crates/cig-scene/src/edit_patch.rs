//! The drawn form of the terrain's edits in one full-detail node: each refined cell
//! (`cig_terrain::edits::RefinedCell`) as a patch of triangles on its fine posts, which the
//! renderer draws in place of the node's own triangles over that cell.
//!
//! Algorithm: a refined cell of split `f` is cut into aligned squares, halved down to single
//! sub-cells where the edits changed a post of them; those are drawn at the fine posts (the
//! cell's triangulated height plus the edits' change there), every square where nothing
//! changed as two triangles (a 155 mm crater's cell of split 128 is its window's 12 x 12 posts
//! and about 50 squares, not 256 blocks of 8 x 8; a rut crossing a cell diagonally is its
//! band of changed posts, not the square window around it). Every triangle is split along the cell's own diagonal, so each lies on the
//! surface the queries answer on (`cig_terrain::query`): drawn and queried are one surface. The
//! T-junctions where fine blocks meet plain ones, and where the patch meets the node's own
//! triangles or a neighbour's patch of another split, are coplanar (no change on those edges,
//! or the edits' T-junction map along shared refined edges). A skirt hangs from the cell's
//! edges (lowered by the shader as the node's skirts are) to close the hair-wide gaps that
//! rasterisation and the node's level-of-detail tolerance leave. The renderer discards the
//! node's own fragments over the patched cells ([`NodePatch::refined_mask`]).
//!
//! Patches are made for nodes drawn from the finest level's data only; a coarser node over an
//! edit draws the ground without it, so the level-of-detail selection counts the edits' largest
//! change under a coarser node in its error (`lod::TerrainLod`, from the edits' block pyramid):
//! the finest level is drawn over an edit as far as its change would show by more than the
//! allowed pixels, like any other relief. Limits: patch
//! vertices do not morph: while a node morphs to its parent, its skirts cover the difference;
//! their morph target field carries the edits' own slope instead (ECEF: `-grad(change)` along
//! the ground, from the fine posts around), plus the local up times one plus how disturbed the
//! ground is (bare earth where the edits other than ruts moved it by a centimetre or more,
//! which the shader draws as dark soil). The shader tilts the node's own smooth normal by that
//! slope, so a patched cell shades like the ground around it where nothing changed.

use crate::node::{NodeKey, NodeLayout};
use crate::terrain_mesh::TerrainVertex;
use cig_geo::Geodetic;
use cig_terrain::database::GeoidLookup;
use cig_terrain::edits::{CellKey, EditLayer, GroundMarks, RefinedCell};
use cig_terrain::raster::{triangulated_height, Diagonal};
use cig_terrain::tile::Tile;
use cig_terrain::TileKey;
use glam::DVec3;
use std::collections::HashMap;
use std::sync::Arc;

/// Sub-cells a side of the smallest squares (the fine posts): squares are halved down to
/// single sub-cells where the edits changed a post, so only the changed ground is drawn fine.
const BLOCK: u32 = 1;

/// One node's patches: vertices relative to the node's centre (skirt 0 on the surface, 1 at
/// a skirt's foot), triangles, and which of the node's cells they replace.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct NodePatch {
    pub vertices: Vec<TerrainVertex>,
    pub indices: Vec<u32>,
    /// Bit `row * node_cells + col` set for each patched cell (row and column in the node).
    pub refined_mask: [u32; 8],
    /// Per vertex, the ground's dynamic texture ([`PatchMarks`]).
    pub marks: Vec<PatchMarks>,
}

impl NodePatch {
    /// Bytes its vertices, marks and triangles take.
    pub fn bytes(&self) -> usize {
        std::mem::size_of_val(&self.vertices[..])
            + std::mem::size_of_val(&self.marks[..])
            + std::mem::size_of_val(&self.indices[..])
    }
}

/// A node's patches as the cells' own pieces (each a [`NodePatch`] of one cell, indices from
/// its first vertex), shared with the cache that keeps them: remaking a node after an edit
/// copies no cell it did not change; the renderer concatenates the pieces as it fills a
/// frame.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct NodePatches {
    pub pieces: Vec<Arc<NodePatch>>,
    /// Bit `row * node_cells + col` set for each patched cell.
    pub refined_mask: [u32; 8],
}

impl NodePatches {
    /// The pieces in one patch.
    pub fn joined(&self) -> NodePatch {
        let mut patch = NodePatch {
            refined_mask: self.refined_mask,
            ..NodePatch::default()
        };
        self.append_to(
            (&mut patch.vertices, &mut patch.indices, &mut patch.marks),
            |v| *v,
        );
        patch
    }

    /// Appends the pieces' vertices (each as `vertex` makes it), triangles (indices counted
    /// from the vertices already there) and marks to a frame's buffers.
    pub fn append_to(
        &self,
        (vertices, indices, marks): (&mut Vec<TerrainVertex>, &mut Vec<u32>, &mut Vec<PatchMarks>),
        vertex: impl Fn(&TerrainVertex) -> TerrainVertex,
    ) {
        for piece in &self.pieces {
            let first = vertices.len() as u32;
            vertices.extend(piece.vertices.iter().map(&vertex));
            indices.extend(piece.indices.iter().map(|&k| first + k));
            marks.extend_from_slice(&piece.marks);
        }
    }
}

/// A patch vertex's marks (`cig_terrain::edits::GroundMarks`) as the shader reads them:
/// track weight, the freshest track's time, scorch weight, the freshest scorch's time
/// (times in seconds from the renderer's time origin, so they keep their precision in
/// single floats; the shader fades each with its age).
pub type PatchMarks = [f32; 4];

/// The patches of a finest-level node `key` over `tile` (its finest tile), or `None` when no
/// edit touches it. `centre_ecef` is the node mesh's centre; the marks' times count from
/// `time_origin_utc_s`.
pub fn build_node_patch(
    layout: &NodeLayout,
    geoid: &GeoidLookup,
    key: NodeKey,
    tile: (TileKey, &Tile),
    centre_ecef: DVec3,
    edits: &EditLayer,
    time_origin_utc_s: f64,
) -> Option<NodePatch> {
    let node = PatchedNode {
        layout,
        geoid,
        key,
        tile,
        centre_ecef,
        edits,
        time_origin_utc_s,
    };
    node.build(&mut CellPatches::default()).map(|p| p.joined())
}

/// A node whose patches are made: everything a cell's patch depends on but the cell.
#[derive(Clone, Copy)]
pub struct PatchedNode<'a> {
    pub layout: &'a NodeLayout,
    pub geoid: &'a GeoidLookup,
    pub key: NodeKey,
    /// The node's finest tile.
    pub tile: (TileKey, &'a Tile),
    /// The node mesh's centre.
    pub centre_ecef: DVec3,
    pub edits: &'a EditLayer,
    /// The marks' times count from here.
    pub time_origin_utc_s: f64,
}

/// The patches of a node's refined cells, each kept with the layer's cell it was made from:
/// a node rebuilt after an edit remakes only the cells the edit changed (the layer replaces
/// exactly those), so a crater costs its own cells, not every crater's in the node.
#[derive(Clone, Debug, Default)]
pub struct CellPatches {
    cells: HashMap<CellKey, (Arc<RefinedCell>, Arc<NodePatch>)>,
}

impl CellPatches {
    /// Cells held.
    pub fn len(&self) -> usize {
        self.cells.len()
    }

    pub fn is_empty(&self) -> bool {
        self.cells.is_empty()
    }
}

impl PatchedNode<'_> {
    /// The node's patches, or `None` when no edit touches it; the cells unchanged since
    /// `reuse` last saw them are copied from it, and `reuse` keeps this build's cells.
    pub fn build(&self, reuse: &mut CellPatches) -> Option<NodePatches> {
        let (layout, key, tile, edits) = (self.layout, self.key, self.tile, self.edits);
        if key.level != 0 || tile.0.level != 0 || edits.is_empty() {
            reuse.cells.clear();
            return None;
        }
        if edits.tile_range_m(tile.0.row, tile.0.col) == (0.0, 0.0) {
            reuse.cells.clear();
            return None;
        }
        let n = u64::from(layout.node_cells);
        if n * n > 256 {
            return None;
        }
        let (r0, c0) = layout.finest_origin(key);
        let mut patch = NodePatches::default();
        let mut kept = HashMap::with_capacity(reuse.cells.len());
        for i in 0..n {
            for j in 0..n {
                let (Ok(r), Ok(c)) = (u32::try_from(r0 + i), u32::try_from(c0 + j)) else {
                    continue;
                };
                let Some(shared) = edits.shared_cell((r, c)) else {
                    continue;
                };
                let piece = match reuse.cells.remove(&(r, c)) {
                    Some((made_from, piece)) if Arc::ptr_eq(&made_from, shared) => piece,
                    _ => match self.cell_patch((r, c), (i, j), shared) {
                        Some(piece) => Arc::new(piece),
                        None => continue,
                    },
                };
                for (w, bits) in patch.refined_mask.iter_mut().zip(piece.refined_mask) {
                    *w |= bits;
                }
                kept.insert((r, c), (Arc::clone(shared), Arc::clone(&piece)));
                if !piece.indices.is_empty() {
                    patch.pieces.push(piece);
                }
            }
        }
        reuse.cells = kept;
        (!patch.pieces.is_empty()).then_some(patch)
    }

    /// The patch of refined cell `(r, c)`, the node's cell `(i, j)` (row, column), with its
    /// own vertices (indices from 0).
    fn cell_patch(
        &self,
        (r, c): CellKey,
        (i, j): (u64, u64),
        cell: &RefinedCell,
    ) -> Option<NodePatch> {
        let (layout, geoid, tile, edits) = (self.layout, self.geoid, self.tile, self.edits);
        let (centre_ecef, time_origin_utc_s) = (self.centre_ecef, self.time_origin_utc_s);
        let (r32, c32) = (r, c);
        let (r, c) = (u64::from(r), u64::from(c));
        let n = u64::from(layout.node_cells);
        let (r0, c0) = layout.finest_origin(self.key);
        let tile_cells = layout.pyramid.tile_cells as u64;
        let (tr0, tc0) = (
            u64::from(tile.0.row) * tile_cells,
            u64::from(tile.0.col) * tile_cells,
        );
        let (ti, tj) = (r.wrapping_sub(tr0) as usize, c.wrapping_sub(tc0) as usize);
        if ti >= tile.1.posts_per_side - 1 || tj >= tile.1.posts_per_side - 1 {
            return None;
        }
        let mut patch = NodePatch::default();
        let corners = tile.1.cell_corners(ti, tj);
        let diagonal = Tile::cell_diagonal(ti, tj);
        let bit = (i * n + j) as usize;
        patch.refined_mask[bit / 32] |= 1 << (bit % 32);
        let f = cell.lattice.split;
        let bs = BLOCK.min(f);
        let side = (f + 1) as usize;
        let mut index_of = vec![u32::MAX; side * side];
        let base_index = patch.vertices.len() as u32;
        let height = |u: f64, v: f64| {
            triangulated_height(corners, u, v, diagonal) + cell.delta_m(u, v, diagonal)
        };
        // The cell's corners on the geoid and the ellipsoid's normals there: a post's place
        // is their bilinear blend raised by its height along the blended normal (exact at the
        // corners; inside a cell the ellipsoid's sag and the normals' turn are hundredths of a
        // millimetre), and one frame at the cell's middle turns the posts' normals. The
        // trigonometry is done 5 times a cell instead of twice a post.
        let corner = |v: f64, u: f64| {
            let (lat, lon) = layout.lat_lon_of_finest(r as f64 + v, c as f64 + u);
            let base = Geodetic::new(lat, lon, geoid.undulation_m(lat, lon));
            let frame = cig_geo::EnuFrame::new(base);
            (base.to_ecef(), frame.enu_vector_to_ecef(DVec3::Z))
        };
        let [(b00, n00), (b01, n01), (b10, n10), (b11, n11)] =
            [(0.0, 0.0), (0.0, 1.0), (1.0, 0.0), (1.0, 1.0)].map(|(v, u)| corner(v, u));
        let (lat_mid, lon_mid) = layout.lat_lon_of_finest(r as f64 + 0.5, c as f64 + 0.5);
        let middle = cig_geo::EnuFrame::new(Geodetic::new(lat_mid, lon_mid, 0.0));
        let (north_m, east_m) = cig_geo::metres_per_degree(lat_mid);
        let mut vertex = |a: u32, b: u32, patch: &mut NodePatch| -> u32 {
            let k = b as usize * side + a as usize;
            if index_of[k] == u32::MAX {
                let (u, v) = (f64::from(a) / f64::from(f), f64::from(b) / f64::from(f));
                let h = height(u, v);
                let (row_f, col_f) = (r as f64 + v, c as f64 + u);
                let blend = |p00: DVec3, p01: DVec3, p10: DVec3, p11: DVec3| {
                    (p00 * (1.0 - u) + p01 * u) * (1.0 - v) + (p10 * (1.0 - u) + p11 * u) * v
                };
                let up = blend(n00, n01, n10, n11).normalize();
                let position = (blend(b00, b01, b10, b11) + up * h - centre_ecef)
                    .as_vec3()
                    .to_array();
                // The edits' slope at the post from its neighbours a sub-cell away
                // (one-sided at the cell's edges), for smooth shading across the facets.
                let step = 1.0 / f64::from(f);
                let (ue, uw) = ((u + step).min(1.0), (u - step).max(0.0));
                let (vn, vs) = ((v + step).min(1.0), (v - step).max(0.0));
                let g = &layout.pyramid.grid;
                let change = |u: f64, v: f64| cell.delta_m(u, v, diagonal);
                let dzdx = (change(ue, v) - change(uw, v)) / ((ue - uw) * g.dlon_deg * east_m);
                let dzdy = (change(u, vn) - change(u, vs)) / ((vn - vs) * g.dlat_deg * north_m);
                // Ground the edits moved is bare, disturbed earth: the field's upward part
                // carries how much (1 untouched, 2 fully disturbed, from 1 cm of change);
                // ruts' marks and craters' scorch fade with their age, so they go to
                // the shader with their times.
                let in_window = a >= cell.lattice.origin.0
                    && b >= cell.lattice.origin.1
                    && a < cell.lattice.origin.0 + cell.lattice.posts.0
                    && b < cell.lattice.origin.1 + cell.lattice.posts.1;
                let marks = if in_window {
                    let (lat, lon) = layout.lat_lon_of_finest(row_f, col_f);
                    edits.ground_marks((r32, c32), lat, lon)
                } else {
                    GroundMarks::default()
                };
                let disturbed = (marks.earth_moved_m / 0.01).min(1.0);
                let normal = middle.enu_vector_to_ecef(DVec3::new(-dzdx, -dzdy, 1.0 + disturbed));
                let normal = normal.as_vec3().to_array();
                index_of[k] = patch.vertices.len() as u32;
                patch.marks.push([
                    marks.track,
                    (marks.track_time_utc_s - time_origin_utc_s) as f32,
                    marks.scorch,
                    (marks.scorch_time_utc_s - time_origin_utc_s) as f32,
                ]);
                patch.vertices.push(TerrainVertex {
                    position,
                    // A patch does not morph: the field carries the edits' slope (ECEF).
                    morph_target: normal,
                    grid_uv: [
                        ((col_f - c0 as f64) / n as f64) as f32,
                        ((row_f - r0 as f64) / n as f64) as f32,
                    ],
                    skirt: 0.0,
                });
            }
            index_of[k]
        };
        let (wa0, wb0) = cell.lattice.origin;
        let (wa1, wb1) = (
            wa0 + cell.lattice.posts.0 - 1,
            wb0 + cell.lattice.posts.1 - 1,
        );
        let mut quad = |a0: u32, b0: u32, a1: u32, b1: u32, patch: &mut NodePatch| {
            let sw = vertex(a0, b0, patch);
            let se = vertex(a1, b0, patch);
            let nw = vertex(a0, b1, patch);
            let ne = vertex(a1, b1, patch);
            let tris = match diagonal {
                Diagonal::SouthWestNorthEast => [sw, se, ne, sw, ne, nw],
                Diagonal::NorthWestSouthEast => [sw, se, nw, se, ne, nw],
            };
            patch.indices.extend_from_slice(&tris);
        };
        // Which of the window's posts the edits changed, as counts over the posts south-west
        // of each (a summed-area table), so any square asks in four reads.
        let lattice = &cell.lattice;
        let (na, nb) = (lattice.posts.0 as usize, lattice.posts.1 as usize);
        let mut changed = vec![0u32; (na + 1) * (nb + 1)];
        for b in 0..nb {
            for a in 0..na {
                let here = u32::from(lattice.post_m(a, b) != 0.0);
                changed[(b + 1) * (na + 1) + a + 1] =
                    here + changed[b * (na + 1) + a + 1] + changed[(b + 1) * (na + 1) + a]
                        - changed[b * (na + 1) + a];
            }
        }
        // Whether a post of the square from (a0, b0) to (a1, b1) (sub-cells of the cell,
        // edges included) changed.
        let changes = |a0: u32, b0: u32, a1: u32, b1: u32| -> bool {
            let (x0, x1) = (a0.max(wa0), a1.min(wa1));
            let (y0, y1) = (b0.max(wb0), b1.min(wb1));
            if x0 > x1 || y0 > y1 {
                return false;
            }
            let at = |x: u32, y: u32| changed[(y - wb0) as usize * (na + 1) + (x - wa0) as usize];
            at(x1 + 1, y1 + 1) + at(x0, y0) > at(x0, y1 + 1) + at(x1 + 1, y0)
        };
        // Aligned squares, halved down to single sub-cells where the edits changed a post of
        // them: a square with none is two triangles (an aligned square lies wholly on one side
        // of the cell's diagonal or has its own diagonal on it, so its triangles are on the
        // cell's planes, and the posts of the halved squares along its edges, unchanged, lie
        // on them too).
        let mut squares = vec![(0u32, 0u32, f)];
        while let Some((a0, b0, size)) = squares.pop() {
            let fine = changes(a0, b0, a0 + size, b0 + size);
            if !fine {
                quad(a0, b0, a0 + size, b0 + size, &mut patch);
            } else if size > bs {
                let h = size / 2;
                squares.extend([
                    (a0, b0, h),
                    (a0 + h, b0, h),
                    (a0, b0 + h, h),
                    (a0 + h, b0 + h, h),
                ]);
            } else {
                for b in b0..b0 + size {
                    for a in a0..a0 + size {
                        quad(a, b, a + 1, b + 1, &mut patch);
                    }
                }
            }
        }
        // Skirts along the cell's edges, from the posts made there.
        let edges: [&dyn Fn(u32) -> (u32, u32); 4] =
            [&|t| (t, 0), &|t| (f, t), &|t| (f - t, f), &|t| (0, f - t)];
        for edge in edges {
            let posts: Vec<u32> = (0..=f)
                .filter_map(|t| {
                    let (a, b) = edge(t);
                    let k = index_of[b as usize * side + a as usize];
                    (k != u32::MAX).then_some(k)
                })
                .collect();
            for pair in posts.windows(2) {
                let (top0, top1) = (pair[0], pair[1]);
                let foot = |k: u32, patch: &mut NodePatch| {
                    let mut v = patch.vertices[k as usize];
                    v.skirt = 1.0;
                    patch.vertices.push(v);
                    patch.marks.push(patch.marks[k as usize]);
                    patch.vertices.len() as u32 - 1
                };
                let f0 = foot(top0, &mut patch);
                let f1 = foot(top1, &mut patch);
                patch
                    .indices
                    .extend_from_slice(&[top0, top1, f1, top0, f1, f0]);
            }
        }
        debug_assert!(patch.vertices.len() as u32 >= base_index);
        Some(patch)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use cig_terrain::build::{build_pyramid, BuildError};
    use cig_terrain::database::{GeoidGrid, Manifest, MemoryTileStore, TerrainDatabase};
    use cig_terrain::edits::{EditAuthor, EditShape, GeoPoint, TerrainEdit};
    use cig_terrain::raster::{GeoGrid, Raster};
    use cig_terrain::{Material, PagingConfig, QuerySession, TileCache};
    use std::sync::Arc;

    #[test]
    fn a_patch_lies_on_the_surface_the_queries_answer_on() {
        let (mn, me) = cig_geo::metres_per_degree(36.0);
        let grid = GeoGrid {
            south_lat_deg: 36.0,
            west_lon_deg: -121.0,
            dlat_deg: 30.0 / mn,
            dlon_deg: 30.0 / me,
            rows: 65,
            cols: 65,
        };
        let raster = Raster {
            grid,
            elevation_m: (0..grid.len())
                .map(|k| 100.0 + ((k % 65) as f32 * 0.3).sin() * 4.0 + (k / 65) as f32 * 0.2)
                .collect(),
            material: Some(vec![Material::Grass; grid.len()]),
        };
        let store = Arc::new(MemoryTileStore::new());
        let summary = build_pyramid::<BuildError>(&raster, 64, &mut |t| {
            store.insert(t.key, t.encode());
            Ok(())
        })
        .expect("build");
        let db = Arc::new(
            TerrainDatabase::new(
                Manifest::from_build(&summary, GeoidGrid::zero(), 0, vec![]),
                store as Arc<dyn cig_terrain::TileStore>,
            )
            .expect("db"),
        );
        let cache =
            Arc::new(TileCache::new(Arc::clone(&db), PagingConfig::default()).expect("cache"));
        let (lat, lon) = (36.0 + 300.0 / mn, -121.0 + 310.0 / me);
        cache
            .update_edits(|e| {
                e.apply(TerrainEdit {
                    author: EditAuthor::default(),
                    sequence: 1,
                    time_utc_s: 0.0,
                    shape: EditShape::Crater {
                        centre: GeoPoint {
                            lat_deg: lat,
                            lon_deg: lon,
                        },
                        radius_m: 3.0,
                        depth_m: 1.0,
                        lip_radius_m: 3.75,
                        lip_height_m: 0.25,
                    },
                })
            })
            .expect("crater");
        let layout = NodeLayout::new(*db.layout());
        let geoid = GeoidLookup::new(&db.manifest().geoid);
        let tile_key = TileKey {
            level: 0,
            row: 0,
            col: 0,
        };
        let tile = db.load_tile(tile_key).expect("tile");
        let key = NodeKey {
            level: 0,
            row: 0,
            col: 0,
        };
        let centre = Geodetic::new(36.0, -121.0, 0.0).to_ecef();
        let patch = build_node_patch(
            &layout,
            &geoid,
            key,
            (tile_key, &tile),
            centre,
            &cache.edits(),
            0.0,
        )
        .expect("a patch");
        assert_eq!(patch.marks.len(), patch.vertices.len());
        assert!(patch.refined_mask.iter().any(|w| *w != 0));
        // Every surface vertex is on the queried surface.
        let mut q = QuerySession::new(Arc::clone(&cache));
        let mut lowest = f64::INFINITY;
        for v in patch.vertices.iter().filter(|v| v.skirt == 0.0) {
            let p = Geodetic::from_ecef(centre + DVec3::from_array(v.position.map(f64::from)));
            let hot = q.hot(p.lat_deg, p.lon_deg).expect("hot").height_msl_m;
            assert!((p.alt_m - hot).abs() < 0.01, "{} vs {hot}", p.alt_m);
            lowest = lowest.min(hot);
        }
        let plain = q.hot(lat, lon).expect("hot").height_msl_m;
        assert!(
            lowest <= plain + 0.05,
            "the bowl's bottom is among the posts"
        );
        // Nothing outside node (0, 0) is patched; a node elsewhere has none.
        let far = NodeKey {
            level: 0,
            row: 3,
            col: 3,
        };
        assert!(build_node_patch(
            &layout,
            &geoid,
            far,
            (tile_key, &tile),
            centre,
            &cache.edits(),
            0.0,
        )
        .is_none());
        // Triangles index real vertices.
        assert!(patch
            .indices
            .iter()
            .all(|&k| (k as usize) < patch.vertices.len()));
        // The crater scorches its bowl, not the cell's far corners.
        let scorch_at = |north_m: f64, east_m: f64| {
            let target = Geodetic::new(lat + north_m / mn, lon + east_m / me, 0.0);
            let (k, _) = patch
                .vertices
                .iter()
                .enumerate()
                .map(|(k, v)| {
                    let p =
                        Geodetic::from_ecef(centre + DVec3::from_array(v.position.map(f64::from)));
                    let d = ((p.lat_deg - target.lat_deg) * mn)
                        .hypot((p.lon_deg - target.lon_deg) * me);
                    (k, d)
                })
                .min_by(|a, b| a.1.total_cmp(&b.1))
                .expect("vertices");
            patch.marks[k][2]
        };
        assert!(scorch_at(0.0, 0.0) > 0.99 && scorch_at(0.0, 14.0) == 0.0);
        // A node remade after a second crater in another of its cells remakes that cell
        // alone, and makes what a fresh build makes.
        let mut reuse = CellPatches::default();
        fn node<'a>(
            layout: &'a NodeLayout,
            geoid: &'a GeoidLookup,
            key: NodeKey,
            tile: (TileKey, &'a Tile),
            centre: DVec3,
            edits: &'a EditLayer,
        ) -> PatchedNode<'a> {
            PatchedNode {
                layout,
                geoid,
                key,
                tile,
                centre_ecef: centre,
                edits,
                time_origin_utc_s: 0.0,
            }
        }
        let first = node(
            &layout,
            &geoid,
            key,
            (tile_key, &tile),
            centre,
            &cache.edits(),
        )
        .build(&mut reuse)
        .expect("a patch");
        assert_eq!(first.joined(), patch);
        let cells_before = reuse.len();
        // A rut 0.6 m wide and 0.1 m deep between two (latitude, longitude) points.
        let rut = |sequence: u32, time_utc_s: f64, from: (f64, f64), to: (f64, f64)| {
            let point = |(lat_deg, lon_deg)| GeoPoint { lat_deg, lon_deg };
            TerrainEdit {
                author: EditAuthor::default(),
                sequence,
                time_utc_s,
                shape: EditShape::Rut {
                    from: point(from),
                    to: point(to),
                    width_m: 0.6,
                    depth_m: 0.1,
                },
            }
        };
        cache
            .update_edits(|e| {
                e.apply(rut(
                    2,
                    60.0,
                    (lat + 100.0 / mn, lon),
                    (lat + 100.0 / mn, lon + 20.0 / me),
                ))
            })
            .expect("rut");
        let edits = cache.edits();
        let reused = node(&layout, &geoid, key, (tile_key, &tile), centre, &edits)
            .build(&mut reuse)
            .expect("a patch");
        // Only the rut's cells are new: the crater's pieces are the very ones kept.
        assert!(first
            .pieces
            .iter()
            .all(|p| reused.pieces.iter().any(|q| Arc::ptr_eq(p, q))));
        assert!(reused.pieces.len() > first.pieces.len());
        let reused = reused.joined();
        let fresh = build_node_patch(&layout, &geoid, key, (tile_key, &tile), centre, &edits, 0.0)
            .expect("a patch");
        assert_eq!(reused, fresh);
        assert!(reuse.len() > cells_before, "{} cells", reuse.len());
        // The rut's posts carry its track mark and time.
        assert!(fresh.marks.iter().any(|m| m[0] == 1.0 && m[1] == 60.0));
        // A rut across a cell's diagonal is drawn fine along its band only: far fewer
        // vertices than the window's posts, and still on the queried surface.
        let cell_centre = |r: u32, c: u32| {
            (
                36.0 + (f64::from(r) + 0.5) * grid.dlat_deg,
                -121.0 + (f64::from(c) + 0.5) * grid.dlon_deg,
            )
        };
        let (la, lo) = cell_centre(20, 20);
        cache
            .update_edits(|e| {
                e.apply(rut(
                    3,
                    90.0,
                    (la - 14.0 / mn, lo - 14.0 / me),
                    (la + 14.0 / mn, lo + 14.0 / me),
                ))
            })
            .expect("diagonal rut");
        let edits = cache.edits();
        let rut_cell = edits.cell((20, 20)).expect("refined");
        let window_posts = rut_cell.lattice.posts.0 * rut_cell.lattice.posts.1;
        assert!(
            window_posts > 100 * 100,
            "{window_posts} posts in the window"
        );
        let diagonal_node = NodeKey {
            level: 0,
            row: 20 / layout.node_cells,
            col: 20 / layout.node_cells,
        };
        let patch = build_node_patch(
            &layout,
            &geoid,
            diagonal_node,
            (tile_key, &tile),
            centre,
            &edits,
            0.0,
        )
        .expect("a patch");
        let surface = patch.vertices.iter().filter(|v| v.skirt == 0.0).count();
        assert!(
            (surface as u32) < window_posts / 5,
            "{surface} vertices for a window of {window_posts} posts"
        );
        let mut deepest = 0.0f64;
        for v in patch.vertices.iter().filter(|v| v.skirt == 0.0) {
            let p = Geodetic::from_ecef(centre + DVec3::from_array(v.position.map(f64::from)));
            let hot = q.hot(p.lat_deg, p.lon_deg).expect("hot").height_msl_m;
            assert!((p.alt_m - hot).abs() < 0.01, "{} vs {hot}", p.alt_m);
            let plain = p.alt_m - edits.delta_m(p.lat_deg, p.lon_deg);
            deepest = deepest.max(plain - p.alt_m);
        }
        assert!(deepest > 0.08, "the rut's bottom is drawn: {deepest} m");
    }
}
