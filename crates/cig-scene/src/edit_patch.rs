//! The drawn form of the terrain's edits in one full-detail node: each refined cell
//! (`cig_terrain::edits::RefinedCell`) as a patch of triangles on its fine posts, which the
//! renderer draws in place of the node's own triangles over that cell.
//!
//! Algorithm: a refined cell of split `f` is cut into blocks of `min(f, 8)` sub-cells a side;
//! blocks that overlap the cell's refined window are drawn at the fine posts (the cell's
//! triangulated height plus the edits' change there), the rest, where nothing changed, as two
//! triangles each. Every triangle is split along the cell's own diagonal, so each lies on the
//! surface the queries answer on (`cig_terrain::query`): drawn and queried are one surface. The
//! T-junctions where fine blocks meet plain ones, and where the patch meets the node's own
//! triangles or a neighbour's patch of another split, are coplanar (no change on those edges,
//! or the edits' T-junction map along shared refined edges). A skirt hangs from the cell's
//! edges (lowered by the shader as the node's skirts are) to close the hair-wide gaps that
//! rasterisation and the node's level-of-detail tolerance leave. The renderer discards the
//! node's own fragments over the patched cells ([`NodePatch::refined_mask`]).
//!
//! Limits: patches are made for nodes drawn from the finest level's data only; a coarser node
//! over an edit draws the unedited ground while the queries answer on the edited one. For
//! craters and positions a few metres across that is a few pixels at the distances where the
//! finest level gives way; a long ditch or a large crater seen from afar is not drawn. Patch
//! vertices do not morph: while a node morphs to its parent, its skirts cover the difference;
//! their morph target field carries their normal instead (ECEF, from the fine posts around),
//! its length one plus how disturbed the ground is (bare earth where the edits moved it by
//! a centimetre or more here or a sub-cell away, which the shader draws as dark soil).

use crate::node::{NodeKey, NodeLayout};
use crate::terrain_mesh::TerrainVertex;
use cig_geo::Geodetic;
use cig_terrain::database::GeoidLookup;
use cig_terrain::edits::EditLayer;
use cig_terrain::raster::{triangulated_height, Diagonal};
use cig_terrain::tile::Tile;
use cig_terrain::TileKey;
use glam::DVec3;

/// Sub-cells a side of a patch's blocks.
const BLOCK: u32 = 8;

/// One node's patches: vertices relative to the node's centre (skirt 0 on the surface, 1 at
/// a skirt's foot), triangles, and which of the node's cells they replace.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct NodePatch {
    pub vertices: Vec<TerrainVertex>,
    pub indices: Vec<u32>,
    /// Bit `row * node_cells + col` set for each patched cell (row and column in the node).
    pub refined_mask: [u32; 8],
}

/// The patches of a finest-level node `key` over `tile` (its finest tile), or `None` when no
/// edit touches it. `centre_ecef` is the node mesh's centre.
pub fn build_node_patch(
    layout: &NodeLayout,
    geoid: &GeoidLookup,
    key: NodeKey,
    tile: (TileKey, &Tile),
    centre_ecef: DVec3,
    edits: &EditLayer,
) -> Option<NodePatch> {
    if key.level != 0 || tile.0.level != 0 || edits.is_empty() {
        return None;
    }
    let tile_cells = layout.pyramid.tile_cells as u64;
    if edits.tile_range_m(tile.0.row, tile.0.col) == (0.0, 0.0) {
        return None;
    }
    let n = u64::from(layout.node_cells);
    if n * n > 256 {
        return None;
    }
    let (r0, c0) = layout.finest_origin(key);
    let (tr0, tc0) = (
        u64::from(tile.0.row) * tile_cells,
        u64::from(tile.0.col) * tile_cells,
    );
    let mut patch = NodePatch::default();
    for i in 0..n {
        for j in 0..n {
            let (r, c) = (r0 + i, c0 + j);
            let (Ok(r32), Ok(c32)) = (u32::try_from(r), u32::try_from(c)) else {
                continue;
            };
            let Some(cell) = edits.cell((r32, c32)) else {
                continue;
            };
            let (ti, tj) = (r.wrapping_sub(tr0) as usize, c.wrapping_sub(tc0) as usize);
            if ti >= tile.1.posts_per_side - 1 || tj >= tile.1.posts_per_side - 1 {
                continue;
            }
            let corners = tile.1.cell_corners(ti, tj);
            let diagonal = Tile::cell_diagonal(ti, tj);
            let bit = (i * n + j) as usize;
            patch.refined_mask[bit / 32] |= 1 << (bit % 32);
            let f = cell.split;
            let bs = BLOCK.min(f);
            let m = f / bs;
            let side = (f + 1) as usize;
            let mut index_of = vec![u32::MAX; side * side];
            let base_index = patch.vertices.len() as u32;
            let height = |u: f64, v: f64| {
                triangulated_height(corners, u, v, diagonal) + cell.delta_m(u, v, diagonal)
            };
            let mut vertex = |a: u32, b: u32, patch: &mut NodePatch| -> u32 {
                let k = b as usize * side + a as usize;
                if index_of[k] == u32::MAX {
                    let (u, v) = (f64::from(a) / f64::from(f), f64::from(b) / f64::from(f));
                    let h = height(u, v);
                    let (row_f, col_f) = (r as f64 + v, c as f64 + u);
                    let (lat, lon) = layout.lat_lon_of_finest(row_f, col_f);
                    let here = Geodetic::new(lat, lon, h + geoid.undulation_m(lat, lon));
                    let position = (here.to_ecef() - centre_ecef).as_vec3().to_array();
                    // The surface's normal at the post from its neighbours a sub-cell away
                    // (one-sided at the cell's edges), for smooth shading across the facets.
                    let step = 1.0 / f64::from(f);
                    let (ue, uw) = ((u + step).min(1.0), (u - step).max(0.0));
                    let (vn, vs) = ((v + step).min(1.0), (v - step).max(0.0));
                    let (north_m, east_m) = cig_geo::metres_per_degree(lat);
                    let g = &layout.pyramid.grid;
                    let dzdx = (height(ue, v) - height(uw, v)) / ((ue - uw) * g.dlon_deg * east_m);
                    let dzdy = (height(u, vn) - height(u, vs)) / ((vn - vs) * g.dlat_deg * north_m);
                    // Ground the edits moved is bare, disturbed earth: the normal's length
                    // carries how much (1 untouched, 2 fully disturbed, from 1 cm of change).
                    let moved = [(u, v), (ue, v), (uw, v), (u, vn), (u, vs)]
                        .iter()
                        .map(|&(x, y)| cell.delta_m(x, y, diagonal).abs())
                        .fold(0.0, f64::max);
                    let disturbed = (moved / 0.01).min(1.0);
                    let normal = cig_geo::EnuFrame::new(here)
                        .enu_vector_to_ecef(DVec3::new(-dzdx, -dzdy, 1.0).normalize())
                        * (1.0 + disturbed);
                    let normal = normal.as_vec3().to_array();
                    index_of[k] = patch.vertices.len() as u32;
                    patch.vertices.push(TerrainVertex {
                        position,
                        // A patch does not morph: the field carries its normal (ECEF).
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
            let (wa0, wb0) = cell.origin;
            let (wa1, wb1) = (wa0 + cell.posts.0 - 1, wb0 + cell.posts.1 - 1);
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
            for q in 0..m {
                for p in 0..m {
                    let (a0, b0) = (p * bs, q * bs);
                    let fine = a0 < wa1 && a0 + bs > wa0 && b0 < wb1 && b0 + bs > wb0;
                    if fine {
                        for b in b0..b0 + bs {
                            for a in a0..a0 + bs {
                                quad(a, b, a + 1, b + 1, &mut patch);
                            }
                        }
                    } else {
                        quad(a0, b0, a0 + bs, b0 + bs, &mut patch);
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
        }
    }
    (!patch.indices.is_empty()).then_some(patch)
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
        )
        .expect("a patch");
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
            &cache.edits()
        )
        .is_none());
        // Triangles index real vertices.
        assert!(patch
            .indices
            .iter()
            .all(|&k| (k as usize) < patch.vertices.len()));
    }
}
