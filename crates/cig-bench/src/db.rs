//! `cig bench db`: terrain database benchmarks, all figures from one run.
//!
//! HAT and LOS rates are taken on one thread over random points inside a window of the database
//! whose finest tiles are all resident (warm cache). Tile loads are timed through a fresh cache
//! (cold tile cache; the operating system's page cache is as it is). Build and import times
//! come from building the 50 km x 50 km, 30 m demo database and importing a generated
//! 3601 x 3601 SRTM 1-arc-second file in a temporary directory.

use crate::database::{build_database, demo_params, BuildProgress};
use crate::report::{date_utc, machine, median};
use crate::{require, BenchError};
use cig_geo::Geodetic;
use cig_terrain::{PagingConfig, QuerySession, TileCache, TileKey};
use cig_terrain_io::store::open_database;
use rand::{Rng, SeedableRng};
use std::hint::black_box;
use std::path::PathBuf;
use std::sync::Arc;
use std::time::{Duration, Instant};

/// What `cig bench db` measures.
#[derive(Clone, Debug)]
pub struct DbOptions {
    /// The database measured.
    pub db: PathBuf,
    /// Seconds each rate measurement takes.
    pub seconds: f64,
    /// Also time building the demo database and importing an SRTM tile (about 100 MB written
    /// to a temporary directory).
    pub build: bool,
    /// The tile cache's configuration.
    pub paging: PagingConfig,
    /// Cells along a tile side of the databases built.
    pub tile_cells: u32,
    /// The commit the report names.
    pub commit: String,
}

/// Runs the benchmark; `progress` hears the builds' progress.
///
/// # Errors
/// When an option is out of range, the database cannot be read or is too small for 10 km
/// sightlines, or a build fails.
pub fn run(
    options: &DbOptions,
    progress: &mut dyn FnMut(BuildProgress<'_>),
) -> Result<serde_json::Value, BenchError> {
    require(
        options.seconds.is_finite() && options.seconds > 0.0 && options.seconds <= 600.0,
        || format!("--seconds {} must be between 0 and 600", options.seconds),
    )?;
    let budget = Duration::from_secs_f64(options.seconds);
    let db = Arc::new(open_database(&options.db)?);
    let layout = *db.layout();
    let g = layout.grid;
    let cache = Arc::new(TileCache::new(Arc::clone(&db), options.paging.clone())?);
    // Window: the whole database if its finest tiles fit in half the budget, else a centred square.
    let (tile_rows, tile_cols) = layout.tiles_at(0);
    let fit = (options.paging.budget_bytes / 2 / cache.tile_bytes().max(1)).max(1) as f64;
    let side_tiles = fit.sqrt().floor().max(1.0) as u32;
    let (r0, c0) = (
        (tile_rows.saturating_sub(side_tiles)) / 2,
        (tile_cols.saturating_sub(side_tiles)) / 2,
    );
    let (r1, c1) = (
        (r0 + side_tiles).min(tile_rows),
        (c0 + side_tiles).min(tile_cols),
    );
    let span = f64::from(layout.tile_cells);
    let lat_lo = g.south_lat_deg + f64::from(r0) * span * g.dlat_deg;
    let lon_lo = g.west_lon_deg + f64::from(c0) * span * g.dlon_deg;
    let lat_hi = (g.south_lat_deg + f64::from(r1) * span * g.dlat_deg).min(g.north_lat_deg());
    let lon_hi = (g.west_lon_deg + f64::from(c1) * span * g.dlon_deg).min(g.east_lon_deg());

    // Cold tile loads, then warm the window.
    let load_started = Instant::now();
    let mut loaded = 0u64;
    for row in r0..r1 {
        for col in c0..c1 {
            cache.load_now(TileKey { level: 0, row, col })?;
            loaded += 1;
        }
    }
    let tile_loads_per_s = loaded as f64 / load_started.elapsed().as_secs_f64();

    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
    let points: Vec<(f64, f64)> = (0..1 << 20)
        .map(|_| (rng.gen_range(lat_lo..lat_hi), rng.gen_range(lon_lo..lon_hi)))
        .collect();
    let mut q = QuerySession::new(Arc::clone(&cache));
    // HAT: height above terrain only (CIGI's basic response) one by one and in frames of 256
    // (how the IG answers a frame of host requests), then the extended answer
    // (height, normal, material, geoid). Interleaved with a baseline taken in the same run on
    // the same memory: bilinear reads of random cells of the resident tiles with no query logic
    // (what the memory system alone allows), so the ratio survives a noisy machine. Medians of
    // 5 rounds.
    let round = budget / 5;
    let mut resident = Vec::new();
    for row in r0..r1 {
        for col in c0..c1 {
            if let Some(t) = cache.resident(TileKey { level: 0, row, col }) {
                resident.push(t);
            }
        }
    }
    if resident.is_empty() {
        return Err(BenchError::Scene(format!(
            "no tile could be made resident: {}",
            options.db.display()
        )));
    }
    let cells = layout.tile_cells as usize;
    let gather: Vec<(usize, usize, usize, f64, f64)> = (0..points.len())
        .map(|_| {
            (
                rng.gen_range(0..resident.len()),
                rng.gen_range(0..cells),
                rng.gen_range(0..cells),
                rng.gen(),
                rng.gen(),
            )
        })
        .collect();
    let (mut base, mut hat, mut hat_ext, mut hat_batch) =
        (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    let geodetic: Vec<Geodetic> = points
        .iter()
        .map(|&(lat, lon)| Geodetic::new(lat, lon, 1000.0))
        .collect();
    let mut answers = Vec::new();
    for _ in 0..5 {
        base.push(rate(round, gather.len(), || {
            for &(t, i, j, u, v) in &gather {
                black_box(cig_terrain::raster::triangulated_height(
                    resident[t].cell_corners(i, j),
                    u,
                    v,
                    cig_terrain::tile::Tile::cell_diagonal(i, j),
                ));
            }
            Ok(())
        })?);
        hat.push(rate(round, points.len(), || {
            for &(lat, lon) in &points {
                black_box(q.hat_m(Geodetic::new(lat, lon, 1000.0))?);
            }
            Ok(())
        })?);
        hat_batch.push(rate(round, geodetic.len(), || {
            for frame in geodetic.chunks(256) {
                q.hat_batch_m(frame, &mut answers);
                black_box(&answers);
            }
            Ok(())
        })?);
        hat_ext.push(rate(round, points.len(), || {
            for &(lat, lon) in &points {
                black_box(q.hat(Geodetic::new(lat, lon, 1000.0))?);
            }
            Ok(())
        })?);
    }
    let (baseline_per_s, hat_per_s, hat_extended_per_s, hat_batch_per_s) = (
        median(&base),
        median(&hat),
        median(&hat_ext),
        median(&hat_batch),
    );

    // LOS over 10 km: ground to ground (2 m above the terrain at both ends: mostly blocked
    // early), air to ground (500 m above the terrain at one end), and the visible ones of each
    // (the whole way walked; visible ground-hugging sightlines, where the quadtree can skip
    // least, are the worst case).
    let (north_m_per_deg, east_m_per_deg) = cig_geo::metres_per_degree(0.5 * (lat_lo + lat_hi));
    let mut ground = Vec::new();
    let mut air = Vec::new();
    let mut attempts = 0;
    while ground.len() < 4096 && attempts < 1_000_000 {
        attempts += 1;
        let (lat, lon) = (rng.gen_range(lat_lo..lat_hi), rng.gen_range(lon_lo..lon_hi));
        let azimuth: f64 = rng.gen_range(0.0..std::f64::consts::TAU);
        let lat2 = lat + 10_000.0 * azimuth.cos() / north_m_per_deg;
        let lon2 = lon + 10_000.0 * azimuth.sin() / east_m_per_deg;
        if !(lat_lo..lat_hi).contains(&lat2) || !(lon_lo..lon_hi).contains(&lon2) {
            continue;
        }
        let a = q.hat(Geodetic::new(lat, lon, 0.0))?.1.height_ellipsoid_m();
        let b = q
            .hat(Geodetic::new(lat2, lon2, 0.0))?
            .1
            .height_ellipsoid_m();
        ground.push((
            Geodetic::new(lat, lon, a + 2.0),
            Geodetic::new(lat2, lon2, b + 2.0),
        ));
        air.push((
            Geodetic::new(lat, lon, a + 500.0),
            Geodetic::new(lat2, lon2, b + 2.0),
        ));
    }
    if ground.is_empty() {
        return Err(BenchError::Scene(format!(
            "the database is too small for 10 km sightlines: {}",
            options.db.display()
        )));
    }
    let mut visible_fraction =
        |segments: &[(Geodetic, Geodetic)]| -> Result<(f64, Vec<(Geodetic, Geodetic)>), BenchError> {
            let mut visible = Vec::new();
            for (a, b) in segments {
                if q.los(*a, *b)?.visible {
                    visible.push((*a, *b));
                }
            }
            Ok((visible.len() as f64 / segments.len() as f64, visible))
        };
    let (ground_visible, ground_clear) = visible_fraction(&ground)?;
    let (air_visible, clear) = visible_fraction(&air)?;
    let mut los_rate = |segments: &[(Geodetic, Geodetic)]| -> Result<Option<f64>, BenchError> {
        if segments.is_empty() {
            return Ok(None);
        }
        Ok(Some(rate(budget, segments.len(), || {
            for (a, b) in segments {
                black_box(q.los(*a, *b)?);
            }
            Ok(())
        })?))
    };
    let los_ground_per_s = los_rate(&ground)?;
    let los_air_per_s = los_rate(&air)?;
    let los_visible_per_s = los_rate(&clear)?;
    let los_ground_visible_per_s = los_rate(&ground_clear)?;

    let mut report = serde_json::json!({
        "machine": machine(),
        "date_utc": date_utc(),
        "commit": options.commit,
        "database": options.db.display().to_string(),
        "baseline_tile_gather_per_s_one_core": baseline_per_s,
        "hat_per_s_one_core": hat_per_s,
        "hat_vs_baseline": hat_per_s / baseline_per_s,
        "hat_batched_per_s_one_core": hat_batch_per_s,
        "hat_batched_vs_baseline": hat_batch_per_s / baseline_per_s,
        "hat_extended_per_s_one_core": hat_extended_per_s,
        "los_10km_ground_to_ground_per_s_one_core": los_ground_per_s,
        "los_10km_ground_to_ground_visible_fraction": ground_visible,
        "los_10km_air_to_ground_per_s_one_core": los_air_per_s,
        "los_10km_air_to_ground_visible_fraction": air_visible,
        "los_10km_air_to_ground_visible_only_per_s_one_core": los_visible_per_s,
        "los_10km_ground_to_ground_visible_only_per_s_one_core": los_ground_visible_per_s,
        "tile_loads_per_s_cold": tile_loads_per_s,
        "tile_bytes": cache.tile_bytes(),
    });
    if options.build {
        let (synth_s, build_s) = time_demo_build(options.tile_cells, progress)?;
        report["demo_synth_s"] = synth_s.into();
        report["demo_build_s"] = build_s.into();
        report["demo_total_s"] = (synth_s + build_s).into();
        report["srtm1_import_s"] = time_srtm1_import(options.tile_cells, progress)?.into();
    }
    Ok(report)
}

/// Seconds to synthesize and to build (pyramid + write) the demo database.
fn time_demo_build(
    tile_cells: u32,
    progress: &mut dyn FnMut(BuildProgress<'_>),
) -> Result<(f64, f64), BenchError> {
    let dir = tempfile::tempdir()?;
    let started = Instant::now();
    let mut raster = cig_synth::synthesize(&demo_params(), &mut |_, _| {})?;
    let synth_s = started.elapsed().as_secs_f64();
    let started = Instant::now();
    build_database(
        &mut raster,
        vec!["bench".into()],
        &dir.path().join("demo"),
        false,
        tile_cells,
        progress,
    )?;
    Ok((synth_s, started.elapsed().as_secs_f64()))
}

/// Seconds to import a generated 3601 x 3601 SRTM1 tile (read, fill, classify, build, write).
fn time_srtm1_import(
    tile_cells: u32,
    progress: &mut dyn FnMut(BuildProgress<'_>),
) -> Result<f64, BenchError> {
    let dir = tempfile::tempdir()?;
    let hgt = dir.path().join("N35W122.hgt");
    let n = 3601usize;
    let mut bytes = Vec::with_capacity(n * n * 2);
    for r in 0..n {
        for c in 0..n {
            let (x, y) = (c as f64 / 300.0, r as f64 / 300.0);
            let h = 600.0 + 400.0 * x.sin() * y.cos() + 150.0 * (3.1 * x + 1.7 * y).sin();
            bytes.extend_from_slice(&(h as i16).to_be_bytes());
        }
    }
    std::fs::write(&hgt, &bytes)?;
    let started = Instant::now();
    let mut raster = cig_terrain_io::import::import_files(&[hgt], &mut |_, _| {})?.raster;
    build_database(
        &mut raster,
        vec!["bench".into()],
        &dir.path().join("db"),
        false,
        tile_cells,
        progress,
    )?;
    Ok(started.elapsed().as_secs_f64())
}

/// Calls `batch` (which answers `per_batch` queries) until `budget` has passed; answers per second.
fn rate(
    budget: Duration,
    per_batch: usize,
    mut batch: impl FnMut() -> Result<(), BenchError>,
) -> Result<f64, BenchError> {
    let started = Instant::now();
    let mut count = 0u64;
    while started.elapsed() < budget {
        batch()?;
        count += per_batch as u64;
    }
    Ok(count as f64 / started.elapsed().as_secs_f64())
}
