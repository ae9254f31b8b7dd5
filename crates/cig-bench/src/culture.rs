//! `cig bench culture`: the culture of a database drawn with level-of-detail management and at
//! full detail in the same run, and the overload control through a climb over its densest wood.
//!
//! 1. The densest area: every finest tile's culture is read once (one tile at a time) and the
//!    8 x 8-cell block with the most objects is the place looked at.
//! 2. A frame looking over it from 1 km south at 100 m above the terrain, drawn with the detail
//!    control parameter (`N_e`, Table 3's levels, removal below step 1) and with every
//!    resident object at its finest level; triangles and frame times (interleaved, medians)
//!    give `triangles_ratio` and `frame_ratio`.
//! 3. A scripted climb from 50 m to 3000 m above the wood, looking ahead and down, drawn
//!    first without the overload control (its most triangles set the budget: half of that)
//!    and then with it (Table 4: capacity the budget, decrement above 95 %, increment below
//!    80 %): the share of frames over the budget after the first second and how often
//!    `K_LOD` changes direction.
//! 4. The CPU time of each view's culture selection and culling, from the frames' counters.
//! 5. Terrain occlusion: eight eyes 5 m above the ground on a 2 km ring about the densest
//!    block, each looking at it, drawn with and without culling behind ridges: blocks and
//!    objects culled, the pixels that changed (none should), the selection's CPU time.

use crate::report::{date_utc, machine, percentile};
use crate::{require, BenchError, Report, Step};
use cig_geo::Geodetic;
use cig_render::{FrameOptions, FrameStats, Renderer};
use cig_scene::overload::{CounterLimits, OverloadSettings};
use cig_scene::{FovDeg, FrameSnapshot, Hpr, View};
use cig_terrain::culture::CULTURE_BLOCK_CELLS;
use cig_terrain::{PagingConfig, QuerySession, TileCache, TileKey};
use std::path::PathBuf;
use std::sync::Arc;
use std::time::Instant;

/// What `cig bench culture` measures.
#[derive(Clone, Debug)]
pub struct CultureOptions {
    pub db: PathBuf,
    /// Frame size, pixels.
    pub size: (u32, u32),
    /// Horizontal field of view, degrees.
    pub fov: f64,
    /// Frames of the climb (60 Hz).
    pub climb_frames: usize,
    pub paging: PagingConfig,
    pub commit: String,
}

/// The densest block: its centre and its object count.
fn densest_block(db: &cig_terrain::TerrainDatabase) -> Result<(f64, f64, usize), BenchError> {
    densest_block_of(db, |_| true)
}

/// The block holding the most objects of the kinds `counted` accepts: its centre (degrees)
/// and that count. Reads every finest tile once, one at a time.
pub(crate) fn densest_block_of(
    db: &cig_terrain::TerrainDatabase,
    counted: impl Fn(cig_terrain::CultureKind) -> bool,
) -> Result<(f64, f64, usize), BenchError> {
    let layout = *db.layout();
    let (rows, cols) = layout.tiles_at(0);
    let (dlat, dlon) = layout.spacing_deg(0);
    let mut best: Option<(f64, f64, usize)> = None;
    for row in 0..rows {
        for col in 0..cols {
            let key = TileKey { level: 0, row, col };
            let tile = db
                .load_tile(key)
                .step_with(|| format!("reading the culture of tile {key}"))?;
            let Some(culture) = &tile.culture else {
                continue;
            };
            for block in culture.blocks() {
                let count = culture.items[block.start..block.end]
                    .iter()
                    .filter(|item| counted(item.kind))
                    .count();
                if count == 0 || best.is_some_and(|b| b.2 >= count) {
                    continue;
                }
                let (i0, j0) = layout.finest_index_of_post(key, 0, 0);
                let half = CULTURE_BLOCK_CELLS as f64 * 0.5;
                let fi = i0 as f64 + f64::from(block.block_row) * CULTURE_BLOCK_CELLS as f64 + half;
                let fj = j0 as f64 + f64::from(block.block_col) * CULTURE_BLOCK_CELLS as f64 + half;
                best = Some((
                    layout.grid.south_lat_deg + fi * dlat,
                    layout.grid.west_lon_deg + fj * dlon,
                    count,
                ));
            }
        }
    }
    best.ok_or_else(|| BenchError::Scene("the database has no culture of those kinds".into()))
}

fn frame(
    renderer: &mut Renderer,
    cache: &TileCache,
    snapshot: &FrameSnapshot,
    target: &cig_render::OffscreenTarget,
    preload: bool,
) -> Result<(FrameStats, f64), BenchError> {
    cache.update(&[snapshot.views[0].eye]);
    if preload {
        cache.wait_idle();
        cig_render::load_for_view(renderer, cache, snapshot, 0, 64)?;
    }
    let started = Instant::now();
    let stats = renderer.render(
        cache,
        snapshot,
        0,
        target.view(),
        FrameOptions {
            mesh_budget: if preload { usize::MAX } else { 64 },
            key_background: false,
            fade_in_s: 0.0,
            ..FrameOptions::default()
        },
    )?;
    Ok((stats, started.elapsed().as_secs_f64() * 1e3))
}

/// Runs the benchmark.
///
/// # Errors
/// When an option is out of range, there is no GPU, or the database has no culture.
pub fn run(options: &CultureOptions) -> Result<Report, BenchError> {
    require((60..=100_000).contains(&options.climb_frames), || {
        format!(
            "--climb-frames {} must be between 60 and 100000",
            options.climb_frames
        )
    })?;
    require(
        options.fov.is_finite() && options.fov > 0.0 && options.fov < 180.0,
        || format!("--fov {} must lie between 0 and 180 degrees", options.fov),
    )?;
    let size = options.size;
    let database = Arc::new(cig_terrain_io::store::open_database(&options.db)?);
    let manifest_culture = database.manifest().culture.clone().ok_or_else(|| {
        BenchError::Scene(format!(
            "the database has no culture: {}",
            options.db.display()
        ))
    })?;
    let started = Instant::now();
    let (lat, lon, densest_objects) = densest_block(&database)?;
    let densest_search_s = started.elapsed().as_secs_f64();
    let gpu = cig_render::Gpu::headless()?;
    let target = cig_render::OffscreenTarget::new(&gpu, size);
    let time = cig_environment::UtcTime::parse_iso8601("2026-06-21T19:00:00Z")?.unix_seconds();
    let cache = Arc::new(TileCache::new(
        Arc::clone(&database),
        options.paging.clone(),
    )?);
    let mut session = QuerySession::new(Arc::clone(&cache));
    let ground = crate::ground_m;
    let view = |eye: Geodetic, pitch_deg: f64| View {
        eye,
        orientation: Hpr {
            heading_deg: 0.0,
            pitch_deg,
            roll_deg: 0.0,
        },
        fov: FovDeg::from_horizontal(options.fov, size.0, size.1),
        width_px: size.0,
        height_px: size.1,
    };
    let snapshot = |view: View, managed: bool| {
        let mut s = FrameSnapshot::new(time, vec![view]);
        s.culture_managed = managed;
        s
    };

    // 2. Over the densest area: managed against full detail, interleaved.
    let (m_lat, _) = cig_geo::metres_per_degree(lat);
    let eye_lat = lat - 1000.0 / m_lat;
    let eye = Geodetic::new(eye_lat, lon, ground(&mut session, eye_lat, lon)? + 100.0);
    let dense_view = view(eye, -6.0);
    let mut renderer = Renderer::new(Arc::clone(&gpu), &cache, cig_render::FRAME_FORMAT);
    renderer.set_overload(None).step("the overload control")?;
    let managed_snapshot = snapshot(dense_view, true);
    let full_snapshot = snapshot(dense_view, false);
    // Warm both (pipelines, node meshes, culture blocks).
    frame(&mut renderer, &cache, &managed_snapshot, &target, true)?;
    frame(&mut renderer, &cache, &full_snapshot, &target, true)?;
    let (mut managed_ms, mut full_ms, mut pair_ratios) = (Vec::new(), Vec::new(), Vec::new());
    let (mut managed_stats, mut full_stats) = (FrameStats::default(), FrameStats::default());
    for _ in 0..3 {
        let (m, m_ms) = frame(&mut renderer, &cache, &managed_snapshot, &target, true)?;
        let (f, f_ms) = frame(&mut renderer, &cache, &full_snapshot, &target, true)?;
        managed_ms.push(m_ms);
        full_ms.push(f_ms);
        pair_ratios.push(f_ms / m_ms.max(1e-6));
        (managed_stats, full_stats) = (m, f);
    }
    let triangles_ratio = full_stats.triangles as f64 / managed_stats.triangles.max(1) as f64;
    let culture_triangles_ratio =
        full_stats.culture_triangles as f64 / managed_stats.culture_triangles.max(1) as f64;
    let frame_ratio = percentile(&pair_ratios, 0.5);

    // 3. The climb, first without the overload control, then with it.
    let climb_views: Vec<View> = (0..options.climb_frames)
        .map(|k| {
            let t = k as f64 / (options.climb_frames - 1) as f64;
            let agl = 50.0 + (3000.0 - 50.0) * t;
            (t, agl)
        })
        .map(|(t, agl)| {
            // Over the wood, moving north a little as it climbs, looking ahead and down more
            // steeply as it rises.
            let north = -300.0 + 600.0 * t;
            let p_lat = lat + north / m_lat;
            (p_lat, agl)
        })
        .map(|(p_lat, agl)| {
            let g = ground(&mut session, p_lat, lon).unwrap_or(eye.alt_m - 100.0);
            let pitch = -(8.0 + 22.0 * ((agl - 50.0) / 2950.0));
            view(Geodetic::new(p_lat, lon, g + agl), pitch)
        })
        .collect();
    let climb = |renderer: &mut Renderer| -> Result<Vec<FrameStats>, BenchError> {
        let mut out = Vec::with_capacity(climb_views.len());
        for v in &climb_views {
            out.push(frame(renderer, &cache, &snapshot(*v, true), &target, false)?.0);
        }
        Ok(out)
    };
    let unmanaged_climb = climb(&mut renderer)?;
    let most_triangles = unmanaged_climb
        .iter()
        .map(|s| s.triangles)
        .max()
        .unwrap_or(0) as f64;
    let budget = (0.5 * most_triangles).max(1.0);
    renderer
        .set_overload(Some(OverloadSettings {
            triangles: Some(CounterLimits {
                capacity: budget,
                begin_decrement: 0.95 * budget,
                begin_increment: 0.8 * budget,
            }),
            models: None,
            gpu_ms: None,
            ..OverloadSettings::default()
        }))
        .step("the overload control")?;
    let managed_climb = climb(&mut renderer)?;
    let first_second = 60.min(managed_climb.len());
    let after = &managed_climb[first_second..];
    let over = after.iter().filter(|s| s.triangles as f64 > budget).count();
    let frames_over_budget_fraction = over as f64 / after.len().max(1) as f64;
    let mut direction_changes = 0;
    let mut last_direction = 0i8;
    for pair in managed_climb.windows(2) {
        let delta = pair[1].klod - pair[0].klod;
        let direction = if delta > 1e-9 {
            1
        } else if delta < -1e-9 {
            -1
        } else {
            0
        };
        if direction != 0 {
            if last_direction != 0 && direction != last_direction {
                direction_changes += 1;
            }
            last_direction = direction;
        }
    }
    let klod_min = managed_climb
        .iter()
        .map(|s| s.klod)
        .fold(f64::INFINITY, f64::min);

    // 4. Culture selection and culling per view (the first climb frames build the tiles'
    // blocks: reported apart).
    let cpu: Vec<f64> = managed_climb.iter().map(|s| s.culture_cpu_ms).collect();

    // 5. Terrain occlusion: eight eyes 5 m above the ground on a 2 km ring about the densest
    // block, each looking at it, drawn with and without the horizon.
    renderer.set_overload(None).step("the overload control")?;
    let (_, m_lon) = cig_geo::metres_per_degree(lat);
    let mut rows = Vec::new();
    let (mut cpu_on, mut cpu_off) = (Vec::new(), Vec::new());
    let (mut occluded_total, mut culled_total, mut changed_max) = (0u64, 0i64, 0usize);
    for k in 0..8 {
        let bearing_deg = f64::from(k) * 45.0;
        let (s, c) = bearing_deg.to_radians().sin_cos();
        let (p_lat, p_lon) = (lat + 2000.0 * c / m_lat, lon + 2000.0 * s / m_lon);
        let eye = Geodetic::new(p_lat, p_lon, ground(&mut session, p_lat, p_lon)? + 5.0);
        let mut v = view(eye, 0.0);
        v.orientation.heading_deg = (bearing_deg + 180.0) % 360.0;
        let shot = snapshot(v, true);
        cache.update(&[eye]);
        cache.wait_idle();
        cig_render::load_for_view(&mut renderer, &cache, &shot, 0, 64)?;
        let draw = |renderer: &mut Renderer, occlusion: bool| {
            renderer.culture_occlusion = occlusion;
            // The second frame: the first builds the blocks of newly resident tiles.
            cig_render::render_image(renderer, &cache, &shot, 0)?;
            cig_render::render_image(renderer, &cache, &shot, 0)
        };
        let (on_image, on) = draw(&mut renderer, true)?;
        let (off_image, off) = draw(&mut renderer, false)?;
        let changed = on_image.pixels_differing(&off_image, 2);
        occluded_total += u64::from(on.culture_blocks_occluded);
        culled_total += i64::from(off.culture_drawn) - i64::from(on.culture_drawn);
        changed_max = changed_max.max(changed);
        cpu_on.push(on.culture_cpu_ms);
        cpu_off.push(off.culture_cpu_ms);
        rows.push(serde_json::json!({
            "heading_deg": v.orientation.heading_deg,
            "blocks_occluded": on.culture_blocks_occluded,
            "culture_drawn": on.culture_drawn,
            "culture_drawn_without": off.culture_drawn,
            "culture_cpu_ms": on.culture_cpu_ms,
            "culture_cpu_ms_without": off.culture_cpu_ms,
            "pixels_changed": changed,
        }));
    }
    renderer.culture_occlusion = true;
    let report = serde_json::json!({
        "machine": machine(),
        "date_utc": date_utc(),
        "commit": options.commit,
        "adapter": gpu.describe(),
        "database": options.db.display().to_string(),
        "size": [size.0, size.1],
        "fov_deg": options.fov,
        "culture": {
            "trees": manifest_culture.trees(),
            "buildings": manifest_culture.buildings(),
            "objects": manifest_culture.total(),
            "densest_block_objects": densest_objects,
            "densest_search_s": densest_search_s,
        },
        "dense_frame": {
            "eye": [eye.lat_deg, eye.lon_deg, eye.alt_m],
            "managed": {
                "triangles": managed_stats.triangles,
                "culture_triangles": managed_stats.culture_triangles,
                "culture_drawn": managed_stats.culture_drawn,
                "frame_ms_median": percentile(&managed_ms, 0.5),
                "culture_cpu_ms": managed_stats.culture_cpu_ms,
            },
            "full_detail": {
                "triangles": full_stats.triangles,
                "culture_triangles": full_stats.culture_triangles,
                "culture_drawn": full_stats.culture_drawn,
                "frame_ms_median": percentile(&full_ms, 0.5),
            },
        },
        "triangles_ratio": triangles_ratio,
        "culture_triangles_ratio": culture_triangles_ratio,
        "frame_ratio": frame_ratio,
        "climb": {
            "frames": options.climb_frames,
            "from_agl_m": 50.0,
            "to_agl_m": 3000.0,
            "unmanaged_most_triangles": most_triangles,
            "triangle_budget": budget,
            "klod_nominal": managed_climb.first().map_or(0.0, |s| s.klod_nominal),
            "klod_min": klod_min,
        },
        "frames_over_budget_fraction": frames_over_budget_fraction,
        "klod_direction_changes": direction_changes,
        "culture_cpu_ms_per_view": {
            "median": percentile(&cpu, 0.5),
            "p99": percentile(&cpu, 0.99),
            "max": percentile(&cpu, 1.0),
        },
        "occlusion": {
            "views": rows.len(),
            "ring_m": 2000.0,
            "eye_agl_m": 5.0,
            "blocks_occluded": occluded_total,
            "objects_culled": culled_total,
            "pixels_changed_max": changed_max,
            "culture_cpu_ms_median": percentile(&cpu_on, 0.5),
            "culture_cpu_ms_median_without": percentile(&cpu_off, 0.5),
            "per_view": rows,
        },
    });
    let summary = format!(
        "culture: {} trees, {} buildings; densest block {} objects\n\
         dense frame: {} triangles managed, {} full detail (triangles_ratio {:.1}, culture {:.1}); \
         frame_ratio {:.2}\n\
         climb 50 -> 3000 m: budget {:.0} triangles, {:.1} % of frames over after 1 s, \
         K_LOD changed direction {} times (lowest {:.0})\n\
         culture selection per view: median {:.3} ms, p99 {:.3} ms\n\
         terrain occlusion from 8 low eyes: {} blocks, {} objects culled, at most {} pixels \
         changed; selection median {:.3} ms ({:.3} ms without)",
        manifest_culture.trees(),
        manifest_culture.buildings(),
        densest_objects,
        managed_stats.triangles,
        full_stats.triangles,
        triangles_ratio,
        culture_triangles_ratio,
        frame_ratio,
        budget,
        100.0 * frames_over_budget_fraction,
        direction_changes,
        klod_min,
        percentile(&cpu, 0.5),
        percentile(&cpu, 0.99),
        occluded_total,
        culled_total,
        changed_max,
        percentile(&cpu_on, 0.5),
        percentile(&cpu_off, 0.5),
    );
    Ok(Report {
        json: report,
        summary,
    })
}
