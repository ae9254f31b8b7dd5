//! Paging: budget, hysteresis, non-blocking service, corrupt-tile fallback.
mod common;

use cig_geo::Geodetic;
use cig_terrain::database::{MemoryTileStore, StoreError, TerrainDatabase, TileStore};
use cig_terrain::{PagingConfig, QuerySession, TileKey};
use common::*;
use std::sync::{Arc, Condvar, Mutex};

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
    // The eye starts exactly on a recentring boundary (centre lattice at 1000 m: 11 500 m is
    // halfway between centres) and dithers +-90 m around it (180 m of travel, less than the
    // 200 m the 1200 m box asks for). Centres 11 000 and 12 000 put the area's south edge
    // either side of the tile boundary at 3840 m (tiles are 1920 m), and the budget holds one
    // active area and little more, so an area that moves must page.
    let base_lat = g.south_lat_deg + 11_500.0 / n_per_deg;
    let lon = g.west_lon_deg + 0.05;
    let run = |hysteresis_box_m: f64| {
        let probe = cache(&db, PagingConfig::default());
        probe.update(&[Geodetic::new(base_lat + 90.0 / n_per_deg, lon, 100.0)]);
        probe.wait_idle();
        let area_tiles = probe.stats().resident_tiles as u64;
        let tile_bytes = probe.tile_bytes();
        drop(probe);
        let c = cache(
            &db,
            PagingConfig {
                hysteresis_box_m,
                budget_bytes: (area_tiles + 2) * tile_bytes,
                ..PagingConfig::default()
            },
        );
        for k in 0..200 {
            let offset = if k % 2 == 0 { 90.0 } else { -90.0 };
            c.update(&[Geodetic::new(base_lat + offset / n_per_deg, lon, 100.0)]);
            c.wait_idle();
        }
        c.stats()
    };
    let npsnet = run(1_200.0);
    assert!(npsnet.active_area_moves <= 1, "{npsnet:?}");
    assert!(npsnet.evictions <= 8, "{npsnet:?}");
    // A box only half a metre larger than the step: every dither moves the area and pages.
    let no_margin = run(1_000.5);
    assert!(no_margin.active_area_moves >= 150, "{no_margin:?}");
    assert!(no_margin.evictions >= 100, "{no_margin:?}");
    assert!(
        no_margin.loads_completed > npsnet.loads_completed + 100,
        "{no_margin:?}"
    );
}

/// A store whose finest tiles wait behind a gate: loads of level 0 block until it opens.
struct GatedStore {
    inner: Arc<MemoryTileStore>,
    open: Mutex<bool>,
    opened: Condvar,
}

impl TileStore for GatedStore {
    fn read_tile(&self, key: TileKey) -> Result<Vec<u8>, StoreError> {
        if key.level == 0 {
            let mut open = self.open.lock().expect("gate");
            while !*open {
                open = self.opened.wait(open).expect("gate");
            }
        }
        self.inner.read_tile(key)
    }

    fn location(&self, key: TileKey) -> String {
        self.inner.location(key)
    }
}

#[test]
fn update_never_waits_and_coarser_levels_serve_while_the_finest_load() {
    let g = grid(401, 401, 60.0);
    let (db, store) = database(&raster(g, plain), 32, 0.0);
    let gated = Arc::new(GatedStore {
        inner: store,
        open: Mutex::new(false),
        opened: Condvar::new(),
    });
    let db = Arc::new(
        TerrainDatabase::new(db.manifest().clone(), gated.clone() as Arc<dyn TileStore>)
            .expect("db"),
    );
    let c = cache(&db, PagingConfig::default());
    let eye = Geodetic::new(36.1, -120.9, 100.0);
    // Every level-0 load blocks, yet updates return.
    let started = std::time::Instant::now();
    for _ in 0..20 {
        c.update(&[eye]);
        std::thread::sleep(std::time::Duration::from_millis(10));
    }
    assert!(started.elapsed() < std::time::Duration::from_secs(5));
    let stats = c.stats();
    assert!(stats.in_flight > 0, "{stats:?}");
    let (row_f, col_f) = g.fractional_index(eye.lat_deg, eye.lon_deg);
    let (key, _, _) = db.layout().locate(0, row_f, col_f);
    assert!(c.resident(key).is_none());
    let served = c.best_resident(key).expect("a coarser level serves");
    assert!(served.key.level >= 1, "{:?}", served.key);
    // Open the gate: the finest tile arrives.
    *gated.open.lock().expect("gate") = true;
    gated.opened.notify_all();
    c.wait_idle();
    c.update(&[eye]);
    assert_eq!(c.best_resident(key).expect("resident").key.level, 0);
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

#[test]
fn prefetch_loads_tiles_beyond_the_area_without_evicting_what_is_in_use() {
    // 60 km x 60 km at 60 m posts, 32-cell tiles; a budget that the active area nearly fills.
    let g = grid(1001, 1001, 60.0);
    let (db, _) = database(&raster(g, plain), 32, 0.0);
    let probe = cache(&db, PagingConfig::default());
    let tile_bytes = probe.tile_bytes();
    drop(probe);
    let config = PagingConfig {
        budget_bytes: tile_bytes * 120,
        ..PagingConfig::default()
    };
    let c = cache(&db, config);
    let eye = Geodetic::new(g.south_lat_deg + 0.02, g.west_lon_deg + 0.02, 500.0);
    c.update(&[eye]);
    c.wait_idle();
    // A level-0 tile in the far corner, well outside the 16 km active area.
    let far = TileKey {
        level: 0,
        row: 30,
        col: 30,
    };
    assert!(c.resident(far).is_none());
    let in_use: Vec<TileKey> = (0..3u32)
        .flat_map(|r| {
            (0..3u32).map(move |col| TileKey {
                level: 0,
                row: r,
                col,
            })
        })
        .filter(|k| c.resident(*k).is_some())
        .collect();
    assert!(!in_use.is_empty());
    let requested = c.prefetch(
        &[
            far,
            far,
            TileKey {
                level: 0,
                row: 9999,
                col: 0,
            },
        ],
        8,
    );
    assert_eq!(
        requested, 1,
        "one new load: duplicates and keys outside the pyramid are skipped"
    );
    c.wait_idle();
    assert!(c.resident(far).is_some(), "prefetched tile arrives");
    for k in &in_use {
        assert!(c.resident(*k).is_some(), "{k} was in use and stays");
    }
    // At most `max` loads per call.
    let many: Vec<TileKey> = (20..30u32)
        .map(|col| TileKey {
            level: 0,
            row: 25,
            col,
        })
        .collect();
    assert!(c.prefetch(&many, 3) <= 3);
    c.wait_idle();
    let s = c.stats();
    assert!(s.resident_bytes <= tile_bytes * 120);
}

/// A reservation of the budget (the renderer's imagery clipmap) leaves the tiles the rest, and
/// gives it back when dropped; no more is granted than leaves room for the minimum of tiles.
#[test]
fn a_reservation_of_the_budget_shrinks_what_the_tiles_may_hold() {
    let g = grid(1001, 1001, 60.0);
    let (db, _) = database(&raster(g, plain), 32, 0.0);
    let probe = cache(&db, PagingConfig::default());
    let tile_bytes = probe.tile_bytes();
    drop(probe);
    let budget_tiles = 120;
    let c = cache(
        &db,
        PagingConfig {
            budget_bytes: tile_bytes * budget_tiles,
            ..PagingConfig::default()
        },
    );
    let eye = Geodetic::new(g.south_lat_deg + 0.2, g.west_lon_deg + 0.2, 500.0);
    let reservation = c.reserve(tile_bytes * 80);
    assert_eq!(reservation.bytes(), tile_bytes * 80);
    assert_eq!(c.tile_budget_bytes(), tile_bytes * 40);
    // Asking for more than leaves the minimum of tiles is granted only up to it.
    let greedy = c.reserve(tile_bytes * 1000);
    assert_eq!(
        greedy.bytes(),
        tile_bytes * (40 - cig_terrain::cache::MIN_BUDGET_TILES)
    );
    drop(greedy);
    for _ in 0..20 {
        let stats = c.update(&[eye]);
        assert!(
            stats.resident_bytes + stats.in_flight as u64 * tile_bytes <= tile_bytes * 40,
            "{stats:?}"
        );
        c.wait_idle();
    }
    drop(reservation);
    assert_eq!(c.tile_budget_bytes(), tile_bytes * budget_tiles);
}
