//! Paging: budget, hysteresis, non-blocking service, corrupt-tile fallback.
mod common;

use cig_geo::Geodetic;
use cig_terrain::{PagingConfig, QuerySession, TileKey};
use common::*;

fn plain(r: usize, c: usize) -> f32 {
    100.0 + ((r * 7 + c * 3) % 50) as f32
}

#[test]
fn a_300_m_per_s_flight_never_exceeds_the_budget_and_keeps_its_area_loaded() {
    // 60 km x 60 km at 60 m posts, 32-cell tiles (about 1.9 km).
    let g = grid(1001, 1001, 60.0);
    let (db, _) = database(&raster(g, plain), 32, 0.0);
    let probe = cache(&db, PagingConfig::default());
    let tile_bytes = probe.tile_bytes();
    drop(probe);
    let budget_tiles = 120;
    let config = PagingConfig {
        budget_bytes: tile_bytes * budget_tiles,
        ..PagingConfig::default()
    };
    let c = cache(&db, config);
    let (n_per_deg, e_per_deg) = cig_geo::metres_per_degree(36.27);
    // Diagonal flight from the south-west corner area to the north-east, 300 m/s, 10 Hz.
    let mut lat = g.south_lat_deg + 2_000.0 / n_per_deg;
    let mut lon = g.west_lon_deg + 2_000.0 / e_per_deg;
    let step_m = 30.0;
    let mut max_bytes = 0;
    for frame in 0..1800 {
        lat += step_m * std::f64::consts::FRAC_1_SQRT_2 / n_per_deg;
        lon += step_m * std::f64::consts::FRAC_1_SQRT_2 / e_per_deg;
        let stats = c.update(&[Geodetic::new(lat, lon, 500.0)]);
        max_bytes = max_bytes.max(stats.resident_bytes + stats.in_flight as u64 * tile_bytes);
        assert!(
            stats.resident_bytes + stats.in_flight as u64 * tile_bytes <= tile_bytes * budget_tiles,
            "frame {frame}: {stats:?}"
        );
        if frame % 100 == 99 {
            c.wait_idle();
        }
    }
    c.wait_idle();
    c.update(&[Geodetic::new(lat, lon, 500.0)]);
    let stats = c.stats();
    assert!(stats.evictions > 0, "the flight must page: {stats:?}");
    assert!(max_bytes <= tile_bytes * budget_tiles);
    // The tile under the eyepoint is resident at the finest level.
    let layout = *db.layout();
    let (row_f, col_f) = g.fractional_index(lat, lon);
    let (key, _, _) = layout.locate(0, row_f, col_f);
    assert!(
        c.resident(key).is_some(),
        "finest tile under the eye is resident"
    );
}

#[test]
fn hysteresis_stops_thrash_when_the_eye_dithers_across_a_boundary() {
    let g = grid(401, 401, 60.0);
    let (db, _) = database(&raster(g, plain), 32, 0.0);
    let (n_per_deg, _) = cig_geo::metres_per_degree(36.1);
    // The eye starts exactly on a recentring boundary (centre lattice at 1000 m: 10 500 m is
    // halfway between centres) and dithers +-90 m around it (180 m of travel, less than the
    // 200 m the 1200 m box asks for).
    let base_lat = g.south_lat_deg + 10_500.0 / n_per_deg;
    let lon = g.west_lon_deg + 0.05;
    let run = |config: PagingConfig| {
        let c = cache(&db, config);
        for k in 0..200 {
            let offset = if k % 2 == 0 { 90.0 } else { -90.0 };
            c.update(&[Geodetic::new(base_lat + offset / n_per_deg, lon, 100.0)]);
        }
        c.wait_idle();
        c.stats()
    };
    let npsnet = run(PagingConfig::default());
    assert!(npsnet.active_area_moves <= 1, "{npsnet:?}");
    let no_box = run(PagingConfig {
        hysteresis_box_m: 1_000.0,
        recenter_step_m: 1_000.0,
        ..PagingConfig::default()
    });
    assert!(no_box.active_area_moves >= 150, "{no_box:?}");
}

#[test]
fn update_does_not_wait_for_loads() {
    let g = grid(401, 401, 60.0);
    let (db, _) = database(&raster(g, plain), 32, 0.0);
    let c = cache(&db, PagingConfig::default());
    let stats = c.update(&[Geodetic::new(36.1, -120.9, 100.0)]);
    // The first update only issues requests; loads complete later.
    assert!(stats.in_flight + stats.resident_tiles > 0);
    c.wait_idle();
    let after = c.stats();
    assert_eq!(after.in_flight, 0);
    assert!(after.resident_tiles > 0);
    // While a finer tile is missing, the coarsest level serves the area.
    let top = TileKey {
        level: db.layout().levels - 1,
        row: 0,
        col: 0,
    };
    assert!(c
        .best_resident(TileKey {
            level: 0,
            row: 0,
            col: 0
        })
        .is_some());
    assert!(c.resident(top).is_some());
}

#[test]
fn corrupt_tile_is_logged_once_and_served_from_its_parent() {
    let g = grid(129, 129, 30.0);
    // A smooth surface: the parent level's answer is close to the finest one.
    let smooth = |r: usize, c: usize| 100.0 + r as f32 * 0.5 + c as f32 * 0.25;
    let (db, store) = database(&raster(g, smooth), 32, 0.0);
    let bad = TileKey {
        level: 0,
        row: 1,
        col: 2,
    };
    let mut bytes = db.load_tile(bad).expect("load").encode();
    let mid = bytes.len() / 2;
    bytes[mid] ^= 0xff;
    let original = bytes.clone();
    store.insert(bad, bytes);
    let c = cache(&db, PagingConfig::default());
    let mut q = QuerySession::new(c.clone());
    // A post inside the corrupt tile (rows 32..64, cols 64..96).
    for _ in 0..5 {
        let (lat, lon) = g.post_lat_lon_deg(40, 70);
        let s = q.hot(lat, lon).expect("served from a coarser level");
        assert!(s.level >= 1);
        assert!((s.height_msl_m - f64::from(smooth(40, 70))).abs() < 0.01);
    }
    assert_eq!(c.stats().loads_failed, 1);
    // Neighbours are unaffected, and the bytes on "disk" were not touched.
    let (lat, lon) = g.post_lat_lon_deg(10, 10);
    assert_eq!(q.hot(lat, lon).expect("ok").level, 0);
    assert_eq!(
        cig_terrain::TileStore::read_tile(store.as_ref(), bad).expect("read"),
        original
    );
}

#[test]
fn invalid_paging_configuration_is_refused() {
    let bad = PagingConfig {
        hysteresis_box_m: 500.0,
        ..PagingConfig::default()
    };
    let err = bad.validate().expect_err("box smaller than step");
    assert!(err.to_string().contains("hysteresis_box_m"));
}
