//! Properties of the built pyramid: coarse levels decimate, bounds are conservative, error
//! bounds hold, materials are majorities.
mod common;

use cig_terrain::pyramid::quadtree_index;
use cig_terrain::raster::{triangulated_height, Diagonal};
use cig_terrain::TileKey;
use common::*;
use proptest::prelude::*;

proptest! {
    #![proptest_config(ProptestConfig::with_cases(24))]

    #[test]
    fn bounds_hold_the_finest_surface_and_errors_bound_the_coarse_one(
        rows in 20usize..90, cols in 20usize..90, seed in 0u32..1000, amp in 1.0f32..500.0
    ) {
        let f = move |r: usize, c: usize| {
            let x = (r as u32).wrapping_mul(73_856_093) ^ (c as u32).wrapping_mul(19_349_663) ^ seed.wrapping_mul(83_492_791);
            (x % 1000) as f32 / 1000.0 * amp + (r as f32 * 0.3).sin() * amp
        };
        let g = grid(rows, cols, 30.0);
        let raster = raster(g, f);
        let (db, _) = database(&raster, 16, 0.0);
        let layout = *db.layout();
        for level in 0..layout.levels {
            for key in layout.keys_at(level) {
                let tile = db.load_tile(key).expect("tile");
                let step = 1usize << level;
                let span = 16 * step;
                let depth = tile.quadtree_depth;
                let leaf = 16 >> depth;
                for r in key.row as usize * span..=((key.row as usize + 1) * span).min(rows - 1) {
                    for c in key.col as usize * span..=((key.col as usize + 1) * span).min(cols - 1) {
                        let h = f(r, c);
                        let (i, j) = (r - key.row as usize * span, c - key.col as usize * span);
                        // Tile posts are the finest posts they sit on (decimation).
                        if i % step == 0 && j % step == 0 {
                            prop_assert_eq!(tile.elevation(i / step, j / step), h);
                        }
                        let (fi, fj) = (i as f64 / step as f64, j as f64 / step as f64);
                        let root = tile.bounds();
                        prop_assert!(root.min_m <= h && h <= root.max_m);
                        // The leaf holding the post bounds it and its own error.
                        let (ci, cj) = ((fi as usize).min(15), (fj as usize).min(15));
                        let lb = tile.nodes[quadtree_index(depth, cj / leaf, ci / leaf)];
                        prop_assert!(lb.min_m <= h && h <= lb.max_m, "leaf {:?} vs {}", lb, h);
                        let coarse = tile.surface_height(fi, fj);
                        prop_assert!((coarse - f64::from(h)).abs() <= f64::from(lb.error_m) + 1e-3,
                            "{:?} level {}: coarse {} fine {} error {}", key, level, coarse, h, lb.error_m);
                    }
                }
            }
        }
    }
}

#[test]
fn top_level_is_one_tile_and_parents_nest() {
    let g = grid(300, 200, 30.0);
    let (db, _) = database(&raster(g, |r, c| (r + c) as f32), 32, 0.0);
    let layout = *db.layout();
    assert_eq!(layout.tiles_at(layout.levels - 1), (1, 1));
    for level in 0..layout.levels - 1 {
        for key in layout.keys_at(level) {
            assert!(
                layout.contains_key(key.parent()),
                "{key} has parent {}",
                key.parent()
            );
        }
    }
    let top = db
        .load_tile(TileKey {
            level: layout.levels - 1,
            row: 0,
            col: 0,
        })
        .expect("top");
    assert_eq!(top.bounds().min_m, 0.0);
    assert_eq!(top.bounds().max_m, 498.0);
}

#[test]
fn triangulated_height_is_exact_at_corners_and_linear_on_edges() {
    let corners = [1.0f32, 5.0, -3.0, 10.0];
    for diagonal in [Diagonal::SouthWestNorthEast, Diagonal::NorthWestSouthEast] {
        let h = |u, v| triangulated_height(corners, u, v, diagonal);
        assert_eq!(h(0.0, 0.0), 1.0);
        assert_eq!(h(1.0, 0.0), 5.0);
        assert_eq!(h(0.0, 1.0), -3.0);
        assert_eq!(h(1.0, 1.0), 10.0);
        assert!((h(0.5, 0.0) - 3.0).abs() < 1e-12);
        assert!((h(1.0, 0.5) - 7.5).abs() < 1e-12);
    }
    // Along its diagonal both triangles agree: the south-west to north-east split passes
    // through the mean of those corners, the other split through the mean of the others.
    let sw_ne = Diagonal::SouthWestNorthEast;
    assert!((triangulated_height(corners, 0.5, 0.5, sw_ne) - 5.5).abs() < 1e-12);
    let nw_se = Diagonal::NorthWestSouthEast;
    assert!((triangulated_height(corners, 0.5, 0.5, nw_se) - 1.0).abs() < 1e-12);
    assert!(
        (triangulated_height(corners, 0.3, 0.7, nw_se) - (0.3 * 5.0 + 0.7 * -3.0)).abs() < 1e-12
    );
    // The checkerboard: neighbours differ, diagonal neighbours agree.
    assert_eq!(Diagonal::of_cell(0, 0), sw_ne);
    assert_eq!(Diagonal::of_cell(0, 1), nw_se);
    assert_eq!(Diagonal::of_cell(1, 0), nw_se);
    assert_eq!(Diagonal::of_cell(7, 3), sw_ne);
}

/// Every built tile holds its posts' hierarchy errors; the even posts' coarser errors are the
/// next level's own, and a post's error never grows towards coarser levels (so the renderer's
/// meshes nest); past the database's edge they are zero.
#[test]
fn tiles_hold_hierarchy_errors_that_nest_across_levels() {
    let (rows, cols) = (150, 110);
    let f = |r: usize, c: usize| {
        let x = (r as u32).wrapping_mul(73_856_093) ^ (c as u32).wrapping_mul(19_349_663);
        (x % 1000) as f32 / 10.0 + (r as f32 * 0.2).sin() * 80.0
    };
    let raster = raster(grid(rows, cols, 30.0), f);
    let (db, _) = database(&raster, 16, 0.0);
    let layout = *db.layout();
    let n = layout.posts_per_side();
    let m = cig_terrain::tile::even_posts_per_side(n);
    // Level errors by global level post, gathered from the tiles.
    let mut own: Vec<std::collections::HashMap<(usize, usize), f32>> = Vec::new();
    let mut coarser: Vec<std::collections::HashMap<(usize, usize), f32>> = Vec::new();
    let mut positive = 0usize;
    for level in 0..layout.levels {
        let (mut o, mut c) = (
            std::collections::HashMap::new(),
            std::collections::HashMap::new(),
        );
        for key in layout.keys_at(level) {
            let tile = db.load_tile(key).expect("tile");
            let errors = tile
                .lod_errors
                .as_ref()
                .expect("format 2 tiles hold errors");
            assert_eq!(errors.own_m.len(), n * n);
            assert_eq!(errors.coarser_m.len(), m * m);
            let (i0, j0) = (key.row as usize * 16, key.col as usize * 16);
            for i in 0..n {
                for j in 0..n {
                    let e = errors.own_m[i * n + j];
                    assert!(e >= 0.0 && e.is_finite());
                    let (fr, fc) = ((i0 + i) << level, (j0 + j) << level);
                    if fr >= rows || fc >= cols {
                        assert_eq!(e, 0.0, "{key}: post ({i}, {j}) past the edge");
                    }
                    positive += usize::from(e > 0.0);
                    o.insert((i0 + i, j0 + j), e);
                }
            }
            for a in 0..m {
                for b in 0..m {
                    c.insert((i0 / 2 + a, j0 / 2 + b), errors.coarser_m[a * m + b]);
                }
            }
        }
        own.push(o);
        coarser.push(c);
    }
    assert!(positive > 1000, "{positive} posts with an error");
    for level in 0..layout.levels as usize - 1 {
        for (&(i, j), &e) in &own[level + 1] {
            if let Some(&fine) = own[level].get(&(2 * i, 2 * j)) {
                assert!(
                    fine >= e,
                    "level {level} ({i}, {j}): {fine} below the coarser {e}"
                );
            }
            if let Some(&stored) = coarser[level].get(&(i, j)) {
                assert_eq!(
                    stored, e,
                    "level {level} holds the next level's error at ({i}, {j})"
                );
            }
        }
    }
}
