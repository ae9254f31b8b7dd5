//! Terrain edits seen by the queries: HOT, HAT and line of sight answer on the edited surface,
//! the same surface the lattice carries.
mod common;

use cig_geo::Geodetic;
use cig_terrain::edits::{EditAuthor, EditId, EditShape, GeoPoint, SpoilSide, TerrainEdit};
use cig_terrain::raster::{triangulated_height, Diagonal};
use cig_terrain::{PagingConfig, QuerySession};
use common::*;
use proptest::prelude::*;

fn bumpy(r: usize, c: usize) -> f32 {
    50.0 + 3.0 * ((r as f32) * 0.37).sin() + 2.0 * ((c as f32) * 0.23).cos()
}

fn edit(sequence: u32, shape: EditShape) -> TerrainEdit {
    TerrainEdit {
        author: EditAuthor {
            site: 3,
            application: 7,
        },
        sequence,
        time_utc_s: 1.9e9,
        shape,
    }
}

fn crater(lat_deg: f64, lon_deg: f64, radius_m: f64, depth_m: f64) -> EditShape {
    EditShape::Crater {
        centre: GeoPoint { lat_deg, lon_deg },
        radius_m,
        depth_m,
        lip_radius_m: 1.25 * radius_m,
        lip_height_m: 0.25 * depth_m,
    }
}

/// The database's own surface at a point, without edits.
fn base_height(g: &cig_terrain::GeoGrid, lat: f64, lon: f64) -> f64 {
    let row_f = (lat - g.south_lat_deg) / g.dlat_deg;
    let col_f = (lon - g.west_lon_deg) / g.dlon_deg;
    let (r, c) = (row_f as usize, col_f as usize);
    let h = |r: usize, c: usize| bumpy(r, c);
    triangulated_height(
        [h(r, c), h(r, c + 1), h(r + 1, c), h(r + 1, c + 1)],
        col_f - c as f64,
        row_f - r as f64,
        Diagonal::of_cell(r, c),
    )
}

#[test]
fn hot_sees_a_crater_finer_than_the_posts_at_its_centre_and_half_radius() {
    let g = grid(100, 100, 30.0);
    let (db, _) = database(&raster(g, bumpy), 32, 0.0);
    let cache = cache(&db, PagingConfig::default());
    let mut q = QuerySession::new(std::sync::Arc::clone(&cache));
    let (lat, lon) = g.post_lat_lon_deg(40, 40);
    // Off the post, so the crater sits inside cells.
    let (mn, me) = cig_geo::metres_per_degree(lat);
    let (lat, lon) = (lat + 7.3 / mn, lon + 11.1 / me);
    let before = q.hot(lat, lon).expect("hot").height_msl_m;
    for (seq, radius_m, depth_m) in [(1, 0.8, 0.3), (2, 1.5, 0.5), (3, 6.0, 1.5)] {
        let (la, lo) = (lat + f64::from(seq) * 20.0 / mn, lon);
        cache
            .update_edits(|e| e.apply(edit(seq, crater(la, lo, radius_m, depth_m))))
            .expect("crater");
        let shape = crater(la, lo, radius_m, depth_m);
        for (dx, dy) in [(0.0, 0.0), (0.5, 0.0), (0.0, -0.5), (-0.35, 0.35)] {
            let (pa, po) = (la + dy * radius_m / mn, lo + dx * radius_m / me);
            let want = base_height(&g, pa, po) + shape.delta_m(pa, po);
            let got = q.hot(pa, po).expect("hot");
            assert!(
                (got.height_msl_m - want).abs() < 0.05,
                "crater {seq} at ({dx}, {dy}) R: {} vs {want}",
                got.height_msl_m
            );
            // The basic answer and HAT agree with HOT.
            assert_eq!(q.height_msl_m(pa, po).expect("h"), got.height_msl_m);
        }
        // The bowl's wall tilts the normal towards the centre.
        let (pa, po) = (la, lo + 0.7 * radius_m / me);
        let s = q.hot(pa, po).expect("hot");
        assert!(s.normal_enu[0] < -0.05, "{:?}", s.normal_enu);
    }
    // Healing the first crater gives the ground back.
    cache
        .update_edits(|e| {
            e.remove(EditId {
                author: EditAuthor {
                    site: 3,
                    application: 7,
                },
                sequence: 1,
            })
        })
        .expect("heal");
    let (la, lo) = (lat + 20.0 / mn, lon);
    assert!((q.hot(la, lo).expect("hot").height_msl_m - base_height(&g, la, lo)).abs() < 1e-6);
    assert!((q.hot(lat, lon).expect("hot").height_msl_m - before).abs() < 1e-9);
}

#[test]
fn a_berm_blocks_a_grazing_sightline_and_a_ditch_opens_a_sunken_one() {
    let g = grid(80, 80, 30.0);
    let (db, _) = database(&raster(g, |_, _| 50.0), 32, 0.0);
    let cache = cache(&db, PagingConfig::default());
    let mut q = QuerySession::new(std::sync::Arc::clone(&cache));
    let (lat, lon) = g.post_lat_lon_deg(40, 20);
    let (mn, me) = cig_geo::metres_per_degree(lat);
    let east = |m: f64| lon + m / me;
    // 1.2 m above a flat field, 600 m east.
    let a = Geodetic::new(lat + 3.0 / mn, east(0.0), 51.2);
    let b = Geodetic::new(lat + 3.0 / mn, east(600.0), 51.2);
    assert!(q.los(a, b).expect("los").visible);
    // A berm 2 m high across the line, 300 m along.
    let berm = EditShape::Berm {
        from: GeoPoint {
            lat_deg: lat - 20.0 / mn,
            lon_deg: east(300.0),
        },
        to: GeoPoint {
            lat_deg: lat + 20.0 / mn,
            lon_deg: east(300.0),
        },
        width_m: 5.0,
        height_m: 2.0,
    };
    cache
        .update_edits(|e| e.apply(edit(1, berm)))
        .expect("berm");
    let r = q.los(a, b).expect("los");
    let hit = r.hit.expect("blocked by the berm");
    assert!((hit.range_m - 300.0).abs() < 3.0, "{}", hit.range_m);
    // Half a metre below the field, 80 m along: blocked at once; a 2 m ditch dug along it
    // opens it.
    let c = Geodetic::new(lat - 100.0 / mn, east(100.0), 49.5);
    let d = Geodetic::new(lat - 100.0 / mn, east(180.0), 49.5);
    assert!(!q.los(c, d).expect("los").visible);
    let ditch = EditShape::Ditch {
        from: GeoPoint {
            lat_deg: lat - 100.0 / mn,
            lon_deg: east(80.0),
        },
        to: GeoPoint {
            lat_deg: lat - 100.0 / mn,
            lon_deg: east(200.0),
        },
        width_m: 4.0,
        depth_m: 2.0,
        spoil: SpoilSide::Left,
    };
    cache
        .update_edits(|e| e.apply(edit(2, ditch)))
        .expect("ditch");
    let r = q.los(c, d).expect("los");
    assert!(r.visible, "{:?}", r.hit);
    // And the ditch's spoil, north of it, blocks a line just above the field there.
    let e1 = Geodetic::new(lat - 95.0 / mn, east(0.0), 50.5);
    let e2 = Geodetic::new(lat - 95.0 / mn, east(300.0), 50.5);
    assert!(!q.los(e1, e2).expect("los").visible);
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(24))]
    /// Over random craters and ruts on bumpy ground, a sightline's hit lies on the surface HOT
    /// answers, and a clear sightline stays above it.
    #[test]
    fn sightlines_and_hot_agree_on_the_edited_surface(
        seed in 0u64..1000,
        n in 1usize..12,
        alt in 0.3f64..3.0,
    ) {
        let g = grid(60, 60, 30.0);
        let (db, _) = database(&raster(g, bumpy), 32, 0.0);
        let cache = cache(&db, PagingConfig::default());
        let mut q = QuerySession::new(std::sync::Arc::clone(&cache));
        let (lat0, lon0) = g.post_lat_lon_deg(30, 30);
        let (mn, me) = cig_geo::metres_per_degree(lat0);
        let mut state = seed.wrapping_mul(6364136223846793005).wrapping_add(1);
        let mut next = || {
            state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        for k in 0..n {
            let (x, y) = (next() * 200.0 - 100.0, next() * 200.0 - 100.0);
            let shape = if k % 3 == 2 {
                EditShape::Rut {
                    from: GeoPoint { lat_deg: lat0 + y / mn, lon_deg: lon0 + x / me },
                    to: GeoPoint { lat_deg: lat0 + (y + 30.0) / mn, lon_deg: lon0 + (x + 20.0) / me },
                    width_m: 0.6,
                    depth_m: 0.3,
                }
            } else {
                crater(lat0 + y / mn, lon0 + x / me, 0.5 + 6.0 * next(), 0.2 + 2.0 * next())
            };
            cache.update_edits(|e| e.apply(edit(k as u32, shape))).expect("edit");
        }
        // Wherever a shape changes the ground, its cells were refined (no cell it reaches
        // is left out).
        for _ in 0..400 {
            let (x, y) = (next() * 240.0 - 120.0, next() * 240.0 - 120.0);
            let (la, lo) = (lat0 + y / mn, lon0 + x / me);
            let edits = q.edits();
            if edits.shape_delta_m(la, lo).abs() > 0.05 {
                prop_assert!(edits.delta_m(la, lo) != 0.0, "unrefined at {x}, {y}");
            }
        }
        let a = (next() * 200.0 - 100.0, next() * 200.0 - 100.0);
        let b = (next() * 200.0 - 100.0, next() * 200.0 - 100.0);
        let at = |p: (f64, f64)| (lat0 + p.1 / mn, lon0 + p.0 / me);
        let (la, lo) = at(a);
        let (lb, lob) = at(b);
        let ha = q.hot(la, lo).expect("hot").height_msl_m + alt;
        let hb = q.hot(lb, lob).expect("hot").height_msl_m + alt;
        let r = q.los(Geodetic::new(la, lo, ha), Geodetic::new(lb, lob, hb)).expect("los");
        if let Some(hit) = r.hit {
            let ground = q.hot(hit.point.lat_deg, hit.point.lon_deg).expect("hot").height_msl_m;
            prop_assert!((hit.point.alt_m - ground).abs() < 0.02, "hit {} ground {}", hit.point.alt_m, ground);
        } else {
            for k in 1..400 {
                let t = f64::from(k) / 400.0;
                let p = Geodetic::from_ecef(
                    Geodetic::new(la, lo, ha).to_ecef() * (1.0 - t) + Geodetic::new(lb, lob, hb).to_ecef() * t,
                );
                let ground = q.hot(p.lat_deg, p.lon_deg).expect("hot").height_msl_m;
                prop_assert!(p.alt_m >= ground - 0.01, "clear line under the ground at {t}: {} < {}", p.alt_m, ground);
            }
        }
    }
}
