//! HOT/HAT and line of sight against terrains whose answers are known.
mod common;

use cig_geo::Geodetic;
use cig_terrain::material::Material;
use cig_terrain::raster::{triangulated_height, Diagonal};
use cig_terrain::{CultureTest, PagingConfig, QueryError, QuerySession, Refraction};
use common::*;
use proptest::prelude::*;

fn bumpy(r: usize, c: usize) -> f32 {
    let (r, c) = (r as f32, c as f32);
    200.0 + 40.0 * (r * 0.21).sin() * (c * 0.17).cos() + 0.37 * r - 0.11 * c
}

#[test]
fn hot_at_every_source_post_is_the_post() {
    let g = grid(150, 170, 30.0);
    let r = raster(g, bumpy);
    let (db, _) = database(&r, 64, 0.0);
    let mut q = QuerySession::new(cache(&db, PagingConfig::default()));
    for row in 0..g.rows {
        for col in 0..g.cols {
            let (lat, lon) = g.post_lat_lon_deg(row, col);
            let s = q.hot(lat, lon).expect("inside");
            assert_eq!(
                s.height_msl_m,
                f64::from(bumpy(row, col)),
                "post {row},{col}"
            );
            assert_eq!(s.level, 0);
        }
    }
}

#[test]
fn hot_between_posts_lies_on_the_drawn_triangle() {
    let g = grid(100, 100, 30.0);
    let r = raster(g, bumpy);
    let (db, _) = database(&r, 32, 0.0);
    let mut q = QuerySession::new(cache(&db, PagingConfig::default()));
    let mut rng = 12345u64;
    let mut next = || {
        rng = rng
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (rng >> 11) as f64 / (1u64 << 53) as f64
    };
    for _ in 0..2000 {
        let (fr, fc) = (next() * 98.999, next() * 98.999);
        let lat = g.south_lat_deg + fr * g.dlat_deg;
        let lon = g.west_lon_deg + fc * g.dlon_deg;
        let (row, col) = (fr.floor() as usize, fc.floor() as usize);
        let (u, v) = (fc - col as f64, fr - row as f64);
        let expected = triangulated_height(
            [
                bumpy(row, col),
                bumpy(row, col + 1),
                bumpy(row + 1, col),
                bumpy(row + 1, col + 1),
            ],
            u,
            v,
            Diagonal::of_cell(row, col),
        );
        let got = q.hot(lat, lon).expect("inside").height_msl_m;
        assert!((got - expected).abs() < 1e-6, "{got} vs {expected}");
    }
}

#[test]
fn normal_of_a_plane_is_its_normal() {
    // Rises 1 m per post eastward (30 m): slope 1/30.
    let g = grid(40, 40, 30.0);
    let r = raster(g, |_, c| c as f32);
    let (db, _) = database(&r, 16, 0.0);
    let mut q = QuerySession::new(cache(&db, PagingConfig::default()));
    let (lat, lon) = g.post_lat_lon_deg(20, 20);
    let s = q
        .hot(lat + 0.3 * g.dlat_deg, lon + 0.6 * g.dlon_deg)
        .expect("inside");
    let (_, east_m_per_deg) = cig_geo::metres_per_degree(s.lat_deg);
    let slope = 1.0 / (g.dlon_deg * east_m_per_deg);
    let len = (1.0 + slope * slope).sqrt();
    assert!((s.normal_enu[0] + slope / len).abs() < 1e-9);
    assert!(s.normal_enu[1].abs() < 1e-9);
    assert!((s.normal_enu[2] - 1.0 / len).abs() < 1e-9);
}

#[test]
fn hat_uses_the_geoid_and_material_comes_from_the_nearest_post() {
    let g = grid(40, 40, 30.0);
    let r = raster(g, |_, _| 100.0);
    let (db, _) = database(&r, 16, -33.0);
    let mut q = QuerySession::new(cache(&db, PagingConfig::default()));
    let (lat, lon) = g.post_lat_lon_deg(10, 13);
    let (hat, s) = q.hat(Geodetic::new(lat, lon, 500.0)).expect("inside");
    assert!((hat - (500.0 - (100.0 - 33.0))).abs() < 1e-9);
    assert_eq!(s.material, Material::ALL[13 % 9]);
}

#[test]
fn queries_outside_or_invalid_are_errors() {
    let g = grid(40, 40, 30.0);
    let (db, _) = database(&raster(g, |_, _| 1.0), 16, 0.0);
    let mut q = QuerySession::new(cache(&db, PagingConfig::default()));
    assert!(matches!(q.hot(10.0, 10.0), Err(QueryError::Outside { .. })));
    assert!(matches!(
        q.hot(f64::NAN, -121.0),
        Err(QueryError::Invalid { .. })
    ));
    assert!(matches!(
        q.los(
            Geodetic::new(f64::INFINITY, 0.0, 0.0),
            Geodetic::new(36.0, -121.0, 0.0)
        ),
        Err(QueryError::Invalid { .. })
    ));
}

/// A north-south ridge: a triangular profile 300 m high at column 100, flat (0 m) elsewhere.
fn ridge(_: usize, c: usize) -> f32 {
    (300.0 - 10.0 * (c as f32 - 100.0).abs()).max(0.0)
}

#[test]
fn los_across_an_analytic_ridge() {
    let g = grid(120, 200, 30.0);
    let (db, _) = database(&raster(g, ridge), 32, 0.0);
    let mut q = QuerySession::new(cache(&db, PagingConfig::default()));
    let (lat, lon_a) = g.post_lat_lon_deg(60, 20);
    let (_, lon_b) = g.post_lat_lon_deg(60, 180);
    // 10 m above flat ground either side: blocked by the ridge.
    let blocked = q
        .los(
            Geodetic::new(lat, lon_a, 10.0),
            Geodetic::new(lat, lon_b, 10.0),
        )
        .expect("los");
    assert!(!blocked.visible);
    let hit = blocked.hit.expect("hit");
    // The sightline meets the west flank (300 - 10 (100 - c)) where the flank reaches it: the
    // chord sags below 10 m by t (1 - t) L^2 / 2R = 0.39 m there (1.53 km into a 4.8 km chord),
    // so at column 70.96, not 71.
    let col_f = (hit.point.lon_deg - g.west_lon_deg) / g.dlon_deg;
    let flank_m = 300.0 - 10.0 * (100.0 - col_f);
    assert!(
        (hit.point.alt_m - flank_m).abs() < 0.01,
        "hit at {:?}, flank {flank_m}",
        hit.point
    );
    assert!(
        (hit.point.alt_m - 9.61).abs() < 0.03,
        "hit at {:?}",
        hit.point
    );
    let start = Geodetic::new(lat, lon_a, 10.0).to_ecef();
    assert!((hit.range_m - (hit.point.to_ecef() - start).length()).abs() < 0.01);
    // 320 m up on both sides: clears the 300 m crest (the chord sags only ~0.1 m over 4.8 km).
    let clear = q
        .los(
            Geodetic::new(lat, lon_a, 320.0),
            Geodetic::new(lat, lon_b, 320.0),
        )
        .expect("los");
    assert!(clear.visible && clear.hit.is_none());
    // 290 m: blocked near the crest.
    let grazing = q
        .los(
            Geodetic::new(lat, lon_a, 290.0),
            Geodetic::new(lat, lon_b, 290.0),
        )
        .expect("los");
    let hit = grazing.hit.expect("hit");
    let (_, lon_crest) = g.post_lat_lon_deg(60, 99);
    let (_, east_m_per_deg) = cig_geo::metres_per_degree(lat);
    assert!(((hit.point.lon_deg - lon_crest) * east_m_per_deg).abs() < 30.0);
}

#[test]
fn los_starting_underground_hits_at_range_zero() {
    let g = grid(40, 40, 30.0);
    let (db, _) = database(&raster(g, |_, _| 50.0), 16, 0.0);
    let mut q = QuerySession::new(cache(&db, PagingConfig::default()));
    let (lat, lon) = g.post_lat_lon_deg(5, 5);
    let (lat2, lon2) = g.post_lat_lon_deg(30, 30);
    let r = q
        .los(
            Geodetic::new(lat, lon, 10.0),
            Geodetic::new(lat2, lon2, 500.0),
        )
        .expect("los");
    assert_eq!(r.hit.expect("hit").range_m, 0.0);
}

#[test]
fn long_sightlines_drop_below_a_flat_plain_with_earth_curvature() {
    // A flat plain at 0 m, 30 km across: two points 1 m up, 25 km apart, cannot see each other
    // (the chord's middle is ~12 m underground), but two points 60 m up can.
    let g = grid(60, 1000, 30.0);
    let (db, _) = database(&raster(g, |_, _| 0.0), 64, 0.0);
    let mut q = QuerySession::new(cache(&db, PagingConfig::default()));
    let (lat, lon_a) = g.post_lat_lon_deg(30, 50);
    let (_, lon_b) = g.post_lat_lon_deg(30, 50 + 833);
    let low = q
        .los(
            Geodetic::new(lat, lon_a, 1.0),
            Geodetic::new(lat, lon_b, 1.0),
        )
        .expect("los");
    assert!(!low.visible);
    let high = q
        .los(
            Geodetic::new(lat, lon_a, 60.0),
            Geodetic::new(lat, lon_b, 60.0),
        )
        .expect("los");
    assert!(high.visible);
}

#[test]
fn refraction_lifts_a_sightline_over_the_curve_of_the_earth() {
    // A flat plain at 0 m, two points 25 km apart: the chord's middle lies D²/8R = 12.3 m
    // under the plain, the standard refracted path's (1 − 0.13) of that, 10.7 m.
    let g = grid(60, 1000, 30.0);
    let (db, _) = database(&raster(g, |_, _| 0.0), 64, 0.0);
    let mut q = QuerySession::new(cache(&db, PagingConfig::default()));
    let (lat, lon_a) = g.post_lat_lon_deg(30, 50);
    let (_, lon_b) = g.post_lat_lon_deg(30, 50 + 833);
    let standard = Refraction {
        k: 0.13,
        earth_radius_m: 6_371_000.0,
    };
    let mut sight = |alt_m: f64, refraction: Refraction| {
        q.los_refracted(
            Geodetic::new(lat, lon_a, alt_m),
            Geodetic::new(lat, lon_b, alt_m),
            CultureTest::LineOfSight,
            refraction,
        )
        .expect("los")
    };
    assert!(!sight(11.5, Refraction::NONE).visible);
    assert!(sight(11.5, standard).visible);
    assert!(!sight(10.0, standard).visible);
    // A hit lies on the bent path, which meets the plain there.
    let hit = sight(9.0, standard).hit.expect("a hit");
    assert!(hit.point.alt_m.abs() < 0.3, "{:?}", hit.point);
    let straight = sight(9.0, Refraction::NONE).hit.expect("a hit");
    assert!(
        hit.range_m > straight.range_m + 500.0,
        "{} {}",
        hit.range_m,
        straight.range_m
    );
    // Values that make no sense bend nothing.
    for (k, r) in [
        (f64::NAN, 6.4e6),
        (1.5, 6.4e6),
        (0.13, 0.0),
        (0.13, f64::INFINITY),
    ] {
        let odd = Refraction {
            k,
            earth_radius_m: r,
        };
        assert_eq!(odd.bow_m(25_000.0), 0.0);
        assert!(!sight(11.5, odd).visible);
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    /// Batched HAT answers are the one-by-one answers, errors included.
    #[test]
    fn batched_hat_equals_single_hat(pts in proptest::collection::vec((-2.0f64..102.0, -2.0f64..102.0, 0.0f64..900.0), 0..100)) {
        let g = grid(100, 100, 30.0);
        let (db, _) = database(&raster(g, bumpy), 32, -20.0);
        let mut q = QuerySession::new(cache(&db, PagingConfig::default()));
        let points: Vec<Geodetic> = pts
            .iter()
            .map(|&(r, c, a)| Geodetic::new(g.south_lat_deg + r * g.dlat_deg, g.west_lon_deg + c * g.dlon_deg, a))
            .collect();
        let mut out = Vec::new();
        q.hat_batch_m(&points, &mut out);
        prop_assert_eq!(out.len(), points.len());
        for (p, batched) in points.iter().zip(&out) {
            prop_assert_eq!(batched, &q.hat_m(*p));
        }
    }

    /// The reported hit lies on the terrain, and the sightline before it is above the terrain.
    #[test]
    fn los_hits_lie_on_the_surface_and_nothing_earlier_is_underground(
        r0 in 5.0f64..95.0, c0 in 5.0f64..95.0, r1 in 5.0f64..95.0, c1 in 5.0f64..95.0,
        a0 in 150.0f64..320.0, a1 in 150.0f64..320.0,
    ) {
        let g = grid(100, 100, 30.0);
        let (db, _) = database(&raster(g, bumpy), 32, 0.0);
        let mut q = QuerySession::new(cache(&db, PagingConfig::default()));
        let from = Geodetic::new(g.south_lat_deg + r0 * g.dlat_deg, g.west_lon_deg + c0 * g.dlon_deg, a0);
        let to = Geodetic::new(g.south_lat_deg + r1 * g.dlat_deg, g.west_lon_deg + c1 * g.dlon_deg, a1);
        let result = q.los(from, to).expect("los");
        let a = from.to_ecef();
        let b = to.to_ecef();
        let len = (b - a).length();
        let end_t = result.hit.map_or(1.0, |h| h.range_m / len.max(1e-9));
        for k in 0..200 {
            let t = end_t * k as f64 / 200.0;
            let p = Geodetic::from_ecef(a + (b - a) * t);
            let ground = q.hot(p.lat_deg, p.lon_deg).expect("inside").height_msl_m;
            if result.hit.is_none() || t < end_t {
                prop_assert!(p.alt_m > ground - 0.01, "underground at t={t}: {} < {ground}", p.alt_m);
            }
        }
        if let Some(hit) = result.hit {
            let ground = q.hot(hit.point.lat_deg, hit.point.lon_deg).expect("inside").height_msl_m;
            if hit.range_m > 0.0 {
                prop_assert!((hit.point.alt_m - ground).abs() < 0.02, "hit {} vs ground {ground}", hit.point.alt_m);
            }
        }
    }
}

/// Sightlines between posts pass exactly through posts on tile and leaf edges; they must never
/// leave the tile they are walking (a panic before this was fixed), and must agree with HOT.
#[test]
fn post_to_post_sightlines_across_tile_edges() {
    let g = grid(100, 100, 30.0);
    let (db, _) = database(&raster(g, bumpy), 32, 0.0);
    let mut q = QuerySession::new(cache(&db, PagingConfig::default()));
    let mut checked = 0;
    for (r0, c0) in [
        (0usize, 0usize),
        (31, 31),
        (32, 0),
        (5, 64),
        (64, 64),
        (99, 99),
        (16, 8),
    ] {
        for (r1, c1) in [
            (0usize, 99usize),
            (99, 0),
            (96, 96),
            (32, 32),
            (64, 0),
            (8, 40),
            (40, 8),
        ] {
            for alt in [180.0, 230.0, 290.0] {
                let (lat0, lon0) = g.post_lat_lon_deg(r0, c0);
                let (lat1, lon1) = g.post_lat_lon_deg(r1, c1);
                let Ok(result) = q.los(
                    Geodetic::new(lat0, lon0, alt),
                    Geodetic::new(lat1, lon1, alt),
                ) else {
                    panic!("los {r0},{c0} -> {r1},{c1} failed");
                };
                if let Some(hit) = result.hit {
                    // A chord along the north edge bows a few centimetres poleward of it (the
                    // great circle does): measure the ground at the nearest point inside.
                    let lat = hit.point.lat_deg.clamp(g.south_lat_deg, g.north_lat_deg());
                    let lon = hit.point.lon_deg.clamp(g.west_lon_deg, g.east_lon_deg());
                    assert!((lat - hit.point.lat_deg).abs() < 1e-5);
                    let ground = q.hot(lat, lon).expect("inside").height_msl_m;
                    assert!(
                        hit.range_m == 0.0 || (hit.point.alt_m - ground).abs() < 0.02,
                        "{r0},{c0} -> {r1},{c1} at {alt}: hit {:?} ground {ground}",
                        hit
                    );
                }
                checked += 1;
            }
        }
    }
    assert_eq!(checked, 147);
}

#[test]
fn sightlines_that_miss_the_database_or_fly_too_high_are_errors() {
    let g = grid(40, 40, 30.0);
    let (db, _) = database(&raster(g, |_, _| 10.0), 16, 0.0);
    let mut q = QuerySession::new(cache(&db, PagingConfig::default()));
    let far = q.los(
        Geodetic::new(10.0, 10.0, 100.0),
        Geodetic::new(10.1, 10.0, 100.0),
    );
    assert!(matches!(far, Err(QueryError::Misses { .. })), "{far:?}");
    let (lat, lon) = g.post_lat_lon_deg(20, 20);
    let high = q.los(
        Geodetic::new(lat, lon, 1e15),
        Geodetic::new(lat, lon, 100.0),
    );
    assert!(matches!(high, Err(QueryError::Altitude { .. })), "{high:?}");
    let deep = q.los(
        Geodetic::new(lat, lon, -7e6),
        Geodetic::new(lat, lon, 100.0),
    );
    assert!(matches!(deep, Err(QueryError::Altitude { .. })), "{deep:?}");
    // From outside into the database is a real question with a real answer.
    let (lat_in, lon_in) = g.post_lat_lon_deg(20, 20);
    let from_outside = q.los(
        Geodetic::new(lat_in, lon_in - 0.05, 5000.0),
        Geodetic::new(lat_in, lon_in, 5.0),
    );
    assert!(from_outside.is_ok());
}

#[test]
fn a_tile_of_another_layout_is_refused_and_served_from_its_parent() {
    let g = grid(129, 129, 30.0);
    let smooth = |r: usize, c: usize| 100.0 + r as f32 * 0.5 + c as f32 * 0.25;
    let (db32, store32) = database(&raster(g, smooth), 32, 0.0);
    let (db16, _) = database(&raster(g, smooth), 16, 0.0);
    let key = cig_terrain::TileKey {
        level: 0,
        row: 0,
        col: 0,
    };
    // Same key, valid checksum, 17 posts per side instead of 33.
    store32.insert(key, db16.load_tile(key).expect("tile").encode());
    assert!(db32.load_tile(key).is_err());
    let mut q = QuerySession::new(cache(&db32, PagingConfig::default()));
    let (lat, lon) = g.post_lat_lon_deg(3, 3);
    let s = q.hot(lat, lon).expect("served");
    assert!(s.level >= 1);
    let (lat2, lon2) = g.post_lat_lon_deg(40, 40);
    q.los(
        Geodetic::new(lat, lon, 300.0),
        Geodetic::new(lat2, lon2, 50.0),
    )
    .expect("los");
}
