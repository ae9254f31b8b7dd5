//! `cig bench render`: a fixed low-level pass over a database, drawn with the level-of-detail
//! renderer and at full detail in the same run, the same frames with the ground's detail and
//! plain (`ground_detail_over_plain`), and with and without 32 smoke-and-flame plumes in view (the scene of `cig bench particles`: 16 fires of a smoke and a
//! flame plume, 5 columns x 75 puffs each, after 100 s of burning).

use crate::flight::{views_along, Leg};
use crate::particles::{bench_atmosphere, start_fires};
use crate::report::{date_utc, machine, percentile};
use crate::{require, BenchError, Report, Step};
use cig_geo::{EnuFrame, Geodetic};
use cig_render::{FrameOptions, FrameStats, Renderer};
use cig_scene::FrameSnapshot;
use cig_terrain::{PagingConfig, QuerySession, TileCache};
use glam::DVec3;
use rand::{Rng, SeedableRng};
use std::path::PathBuf;
use std::sync::Arc;
use std::time::Instant;

/// What `cig bench render` measures.
#[derive(Clone, Debug)]
pub struct RenderOptions {
    /// The database flown over.
    pub db: PathBuf,
    /// Frame size, pixels.
    pub size: (u32, u32),
    /// Horizontal field of view, degrees.
    pub fov: f64,
    /// Level-of-detail threshold, pixels.
    pub max_pixel_error: f64,
    /// Frames of the 60 Hz pass.
    pub frames: usize,
    /// Frames of the pass drawn both ways for the comparison.
    pub compare_frames: usize,
    /// The tile cache's configuration.
    pub paging: PagingConfig,
    /// The commit the report names.
    pub commit: String,
}

/// The benchmark's pass: south-west to north-east across the middle of the database.
pub(crate) fn pass_leg(db: &cig_terrain::TerrainDatabase, speed_mps: f64, duration_s: f64) -> Leg {
    let g = db.layout().grid;
    let lat = g.south_lat_deg + 0.3 * (g.north_lat_deg() - g.south_lat_deg);
    let lon = g.west_lon_deg + 0.3 * (g.east_lon_deg() - g.west_lon_deg);
    Leg {
        start: Geodetic::new(lat, lon, 0.0),
        heading_deg: 45.0,
        speed_mps,
        duration_s,
        agl_start_m: 120.0,
        agl_end_m: 120.0,
        pitch_deg: -3.0,
    }
}

/// How long the comparison's fires have burnt (every smoke pool full: smoke lives 90 s), s.
const PLUMES_BURNING_S: f64 = 100.0;

fn summary(times_ms: &[f64]) -> serde_json::Value {
    serde_json::json!({
        "median": percentile(times_ms, 0.5),
        "p99": percentile(times_ms, 0.99),
        "max": percentile(times_ms, 1.0),
    })
}

#[derive(Default)]
struct Run {
    frame_ms: Vec<f64>,
    select_ms: Vec<f64>,
    gpu_ms: Vec<f64>,
    triangles: Vec<f64>,
    draw_calls: Vec<f64>,
    puffs: Vec<f64>,
    puff_gpu_ms: Vec<f64>,
    meshes_built: Vec<f64>,
    meshes_deferred: Vec<f64>,
}

impl Run {
    fn append(&mut self, other: Run) {
        self.frame_ms.extend(other.frame_ms);
        self.select_ms.extend(other.select_ms);
        self.gpu_ms.extend(other.gpu_ms);
        self.triangles.extend(other.triangles);
        self.draw_calls.extend(other.draw_calls);
        self.puffs.extend(other.puffs);
        self.puff_gpu_ms.extend(other.puff_gpu_ms);
        self.meshes_built.extend(other.meshes_built);
        self.meshes_deferred.extend(other.meshes_deferred);
    }
}

/// Times each comparison view is drawn both ways.
const COMPARISON_ROUNDS: usize = 2;

/// Fires of the plume comparison: 16 points on the terrain ahead of the pass's start, from a
/// third of the reach to the reach (4 km, or less where the database ends sooner), within
/// 0.3 of their distance to either side of the track.
fn fire_positions(session: &mut QuerySession, leg: &Leg) -> Result<Vec<Geodetic>, BenchError> {
    let frame = EnuFrame::new(leg.start);
    let (sh, ch) = leg.heading_deg.to_radians().sin_cos();
    let forward = DVec3::new(sh, ch, 0.0);
    let right = DVec3::new(ch, -sh, 0.0);
    let inside = |session: &mut QuerySession, enu: DVec3| {
        let p = frame.enu_to_geodetic(enu);
        session
            .hot(p.lat_deg, p.lon_deg)
            .map(|h| Geodetic::new(p.lat_deg, p.lon_deg, h.height_ellipsoid_m()))
    };
    let mut reach_m = 0.0;
    while reach_m < 4000.0 {
        let ahead = reach_m + 100.0;
        let sides = [-0.3, 0.3].map(|s| forward * ahead + right * (s * ahead));
        if sides.iter().any(|&p| inside(session, p).is_err()) {
            break;
        }
        reach_m = ahead;
    }
    if reach_m < 600.0 {
        return Err(BenchError::Scene(format!(
            "the database ends {reach_m} m ahead of the pass: too close for the plume comparison"
        )));
    }
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(16);
    (0..16)
        .map(|_| {
            let d = rng.gen_range(reach_m / 3.0..reach_m);
            let side = rng.gen_range(-0.3..0.3) * d;
            inside(session, forward * d + right * side).step("a plume of the comparison")
        })
        .collect()
}

fn render_frames(
    renderer: &mut Renderer,
    cache: &TileCache,
    snapshots: &[FrameSnapshot],
    target: &cig_render::OffscreenTarget,
    streaming: bool,
) -> Result<Run, BenchError> {
    let mut run = Run::default();
    for snapshot in snapshots {
        let started = Instant::now();
        let stats: FrameStats = if streaming {
            cache.update(&[snapshot.views[0].eye]);
            renderer.render(cache, snapshot, 0, target.view(), FrameOptions::default())?
        } else {
            renderer.render(
                cache,
                snapshot,
                0,
                target.view(),
                FrameOptions {
                    mesh_budget: usize::MAX,
                    key_background: false,
                    fade_in_s: 0.0,
                    ..FrameOptions::default()
                },
            )?
        };
        run.frame_ms.push(started.elapsed().as_secs_f64() * 1e3);
        run.select_ms.push(stats.cpu_select_ms);
        run.gpu_ms.push(stats.gpu_ms);
        run.triangles.push(stats.triangles as f64);
        run.draw_calls.push(f64::from(stats.draw_calls));
        run.puffs.push(f64::from(stats.puffs_drawn));
        run.puff_gpu_ms.push(stats.puff_gpu_ms);
        run.meshes_built.push(f64::from(stats.meshes_built));
        run.meshes_deferred.push(f64::from(stats.meshes_deferred));
    }
    Ok(run)
}

/// Selections of the comparison frames' views back to back, with no frame drawn in between
/// (so the rasteriser's threads neither share the cores nor evict the caches), times each.
const SELECT_ALONE_ROUNDS: usize = 25;

fn select_alone(renderer: &mut Renderer, cache: &TileCache, sample: &[FrameSnapshot]) -> Vec<f64> {
    let mut times_ms = Vec::with_capacity(SELECT_ALONE_ROUNDS * sample.len());
    for _ in 0..SELECT_ALONE_ROUNDS {
        for s in sample {
            let started = Instant::now();
            let selection = renderer.select(cache, &s.views[0], s.max_pixel_error);
            times_ms.push(started.elapsed().as_secs_f64() * 1e3);
            std::hint::black_box(selection);
        }
    }
    times_ms
}

fn mean(v: &[f64]) -> f64 {
    v.iter().sum::<f64>() / v.len().max(1) as f64
}

/// Runs the benchmark.
///
/// # Errors
/// When an option is out of range, there is no GPU, the pass leaves the database or no plume
/// of the comparison is in view.
pub fn run(options: &RenderOptions) -> Result<Report, BenchError> {
    let size = options.size;
    require((4..=100_000).contains(&options.frames), || {
        format!("--frames {} must be between 4 and 100000", options.frames)
    })?;
    require(
        options.max_pixel_error.is_finite() && options.max_pixel_error > 0.0,
        || {
            format!(
                "--max-pixel-error {} must be more than 0 (the comparison draws full detail itself)",
                options.max_pixel_error
            )
        },
    )?;
    require(
        options.fov.is_finite() && options.fov > 0.0 && options.fov < 180.0,
        || format!("--fov {} must lie between 0 and 180 degrees", options.fov),
    )?;
    let database = Arc::new(cig_terrain_io::store::open_database(&options.db)?);
    let gpu = cig_render::Gpu::headless()?;
    let target = cig_render::OffscreenTarget::new(&gpu, size);
    let dt_s = 1.0 / 60.0;
    let leg = pass_leg(&database, 300.0, options.frames as f64 * dt_s);
    let time = cig_environment::UtcTime::parse_iso8601("2026-06-21T19:00:00Z")?.unix_seconds();

    // 1. The streaming pass at 300 m/s, 60 Hz: a fresh cache, nothing preloaded.
    let cache = Arc::new(TileCache::new(
        Arc::clone(&database),
        options.paging.clone(),
    )?);
    let mut session = QuerySession::new(Arc::clone(&cache));
    let views =
        views_along(&mut session, &leg, dt_s, options.fov, size).step("the benchmark path")?;
    let snapshots: Vec<FrameSnapshot> = views
        .iter()
        .map(|v| {
            let mut s = FrameSnapshot::new(time, vec![*v]);
            s.max_pixel_error = options.max_pixel_error;
            s
        })
        .collect();
    let mut renderer = Renderer::new(Arc::clone(&gpu), &cache, cig_render::FRAME_FORMAT);
    let streaming = render_frames(&mut renderer, &cache, &snapshots, &target, true)?;
    // The first frames compile pipelines and fill the empty pool; the stall measure skips 10.
    let settled_from = 10.min(streaming.frame_ms.len() / 2);
    let settled = &streaming.frame_ms[settled_from..];
    let stall_ratio = percentile(settled, 1.0) / percentile(settled, 0.5);

    // 2. The same frames (every k-th), everything resident: level of detail against full detail.
    let every = (snapshots.len() / options.compare_frames.max(1)).max(1);
    let sample: Vec<FrameSnapshot> = snapshots.iter().step_by(every).cloned().collect();
    let mut full_sample = sample.clone();
    for s in &mut full_sample {
        s.max_pixel_error = 0.0;
    }
    // Each way has its own renderer (and node pool), so neither evicts the other's meshes.
    let mut full_renderer = Renderer::new(Arc::clone(&gpu), &cache, cig_render::FRAME_FORMAT);
    for (lod_view, full_view) in sample.iter().zip(&full_sample) {
        cig_render::load_for_view(&mut renderer, &cache, lod_view, 0, 64)?;
        cig_render::load_for_view(&mut full_renderer, &cache, full_view, 0, 64)?;
    }
    // Time both ways interleaved view by view, so the machine's slow spells fall on both
    // alike: each view drawn at level of detail and then at full detail, COMPARISON_ROUNDS
    // times over. The views lie far apart along the pass, so each is first drawn once untimed:
    // the timed frame is the steady frame of that view, its node meshes built as consecutive
    // frames of a flight find them (the pass above measures the building). The time ratio is
    // the median of the ratios of those adjacent pairs.
    let mut lod = Run::default();
    let mut full = Run::default();
    let mut pair_ratios = Vec::new();
    for _ in 0..COMPARISON_ROUNDS {
        for (lod_view, full_view) in sample.iter().zip(&full_sample) {
            let steady = |renderer: &mut Renderer, view: &FrameSnapshot| {
                let view = std::slice::from_ref(view);
                render_frames(renderer, &cache, view, &target, false)?;
                render_frames(renderer, &cache, view, &target, false)
            };
            let lod_frame = steady(&mut renderer, lod_view)?;
            let full_frame = steady(&mut full_renderer, full_view)?;
            pair_ratios.push(mean(&full_frame.frame_ms) / mean(&lod_frame.frame_ms).max(1e-6));
            lod.append(lod_frame);
            full.append(full_frame);
        }
    }
    drop(full_renderer);
    let lod_frame = percentile(&lod.frame_ms, 0.5);
    let time_ratio = percentile(&pair_ratios, 0.5);
    let select_alone_ms = select_alone(&mut renderer, &cache, &sample);

    // 3. The same frames with the ground's detail (material noise, smooth borders) and plain
    // (the colour texels alone), interleaved; ratio of the medians.
    let plain_ground: Vec<FrameSnapshot> = sample
        .iter()
        .map(|s| FrameSnapshot {
            ground_detail: false,
            ..s.clone()
        })
        .collect();
    render_frames(&mut renderer, &cache, &plain_ground[..1], &target, false)?;
    let (mut detailed_ground_ms, mut plain_ground_ms) = (Vec::new(), Vec::new());
    for _ in 0..COMPARISON_ROUNDS {
        for (detailed, plain) in sample.iter().zip(&plain_ground) {
            let detailed = std::slice::from_ref(detailed);
            let plain = std::slice::from_ref(plain);
            detailed_ground_ms
                .extend(render_frames(&mut renderer, &cache, detailed, &target, false)?.frame_ms);
            plain_ground_ms
                .extend(render_frames(&mut renderer, &cache, plain, &target, false)?.frame_ms);
        }
    }
    let ground_detail_over_plain =
        percentile(&detailed_ground_ms, 0.5) / percentile(&plain_ground_ms, 0.5).max(1e-6);

    // 4. The same frames with 32 plumes in view, interleaved with frames without them.
    let fires = fire_positions(&mut session, &leg)?;
    let mut effects = cig_effects::EffectSystem::new(cig_effects::EffectsConfig {
        plume_slots: 2 * fires.len(),
        dust_slots: 0,
        ..Default::default()
    })?;
    effects.set_atmosphere(bench_atmosphere())?;
    effects.advance_to(0.0)?;
    start_fires(&mut effects, &fires)?;
    effects.advance_to(PLUMES_BURNING_S)?;
    let smoky: Vec<FrameSnapshot> = sample
        .iter()
        .map(|s| {
            let mut s = s.clone();
            s.puff_origin_ecef_m = s.views[0].eye.to_ecef();
            effects.snapshot(s.puff_origin_ecef_m, &mut s.puffs);
            s
        })
        .collect();
    render_frames(&mut renderer, &cache, &smoky[..1], &target, false)?;
    let mut plain_runs = Vec::new();
    let mut smoky_runs = Vec::new();
    for _ in 0..2 {
        plain_runs.push(render_frames(
            &mut renderer,
            &cache,
            &sample,
            &target,
            false,
        )?);
        smoky_runs.push(render_frames(
            &mut renderer,
            &cache,
            &smoky,
            &target,
            false,
        )?);
    }
    let joined = |runs: &[Run], pick: fn(&Run) -> &Vec<f64>| -> Vec<f64> {
        runs.iter().flat_map(|r| pick(r).iter().copied()).collect()
    };
    let plain_ms = joined(&plain_runs, |r| &r.frame_ms);
    let smoky_ms = joined(&smoky_runs, |r| &r.frame_ms);
    let puffs_drawn = mean(&joined(&smoky_runs, |r| &r.puffs));
    if puffs_drawn <= 0.0 {
        return Err(BenchError::Scene(
            "none of the plumes of the comparison is in view".into(),
        ));
    }
    let (plain_median, smoky_median) = (percentile(&plain_ms, 0.5), percentile(&smoky_ms, 0.5));
    let puff_share = (smoky_median - plain_median) / smoky_median;
    let report = serde_json::json!({
        "machine": machine(),
        "date_utc": date_utc(),
        "commit": options.commit,
        "adapter": gpu.describe(),
        "database": options.db.display().to_string(),
        "size": [size.0, size.1],
        "fov_deg": options.fov,
        "max_pixel_error": options.max_pixel_error,
        "pass": {
            "speed_mps": 300.0,
            "height_above_terrain_m": 120.0,
            "frames": snapshots.len(),
            "frame_ms": summary(&streaming.frame_ms),
            "frame_ms_after_warmup": summary(settled),
            "max_over_median_after_warmup": stall_ratio,
            "cpu_select_ms": summary(&streaming.select_ms),
            "triangles_mean": mean(&streaming.triangles),
            "draw_calls_mean": mean(&streaming.draw_calls),
            // Node meshes built per frame after the warm-up (new nodes, finer data, new
            // tolerance steps) and those left for a later frame by the per-frame budget.
            "meshes_built_after_warmup": summary(&streaming.meshes_built[settled_from..]),
            "meshes_deferred_after_warmup": summary(&streaming.meshes_deferred[settled_from..]),
        },
        "comparison_frames": sample.len(),
        "comparison_rounds": COMPARISON_ROUNDS,
        "lod": {
            "triangles_mean": mean(&lod.triangles),
            "frame_ms": summary(&lod.frame_ms),
            "gpu_ms": summary(&lod.gpu_ms),
            "cpu_select_ms": summary(&lod.select_ms),
            "cpu_select_ms_alone": summary(&select_alone_ms),
            "draw_calls_mean": mean(&lod.draw_calls),
            "meshes_built_mean": mean(&lod.meshes_built),
        },
        "full_detail": {
            "triangles_mean": mean(&full.triangles),
            "frame_ms": summary(&full.frame_ms),
            "gpu_ms": summary(&full.gpu_ms),
            "cpu_select_ms": summary(&full.select_ms),
            "draw_calls_mean": mean(&full.draw_calls),
            "meshes_built_mean": mean(&full.meshes_built),
        },
        "ratios": {
            "triangles_full_over_lod": mean(&full.triangles) / mean(&lod.triangles).max(1.0),
            "frame_time_full_over_lod": time_ratio,
            "frame_time_full_over_lod_pairs": summary(&pair_ratios),
            "ground_detail_over_plain": ground_detail_over_plain,
        },
        "ground_detail": {
            "frames_each_way": detailed_ground_ms.len(),
            "frame_ms_with": summary(&detailed_ground_ms),
            "frame_ms_plain": summary(&plain_ground_ms),
        },
        "plumes": {
            "plumes": 2 * fires.len(),
            "puffs_per_plume": 375,
            "burning_s": PLUMES_BURNING_S,
            "puffs_drawn_mean": puffs_drawn,
            "frames_each_way": plain_ms.len(),
            "frame_ms_without": summary(&plain_ms),
            "frame_ms_with": summary(&smoky_ms),
            "gpu_ms_without": summary(&joined(&plain_runs, |r| &r.gpu_ms)),
            "gpu_ms_with": summary(&joined(&smoky_runs, |r| &r.gpu_ms)),
            "puff_gpu_ms": summary(&joined(&smoky_runs, |r| &r.puff_gpu_ms)),
            "frame_time_with_over_without": smoky_median / plain_median,
            "puff_share_of_frame_time": puff_share,
        },
        "targets": {
            "puff_share_of_frame_time_at_most": 0.25,
            "triangles_full_over_lod_at_least": 20.0,
            "frame_time_full_over_lod_at_least": 5.0,
            "cpu_select_ms_at_most": 0.5,
            "max_over_median_at_most": 2.0,
            "ground_detail_over_plain_at_most": 1.3,
        },
    });
    let summary = format!(
            "pass: {} frames at 300 m/s, median {:.1} ms, max/median after warm-up {:.2}, selection median {:.3} ms\n\
             level of detail: {:.0} triangles, {:.1} ms; full detail: {:.0} triangles, {:.1} ms; ratios {:.1}x triangles, {:.1}x time\n\
             ground detail: {:.1} ms with against {:.1} ms plain, {:.2}x\n\
             plumes: {} plumes, {:.0} puffs drawn, {:.1} ms with against {:.1} ms without: {:.0}% of the frame",
            snapshots.len(),
            percentile(&streaming.frame_ms, 0.5),
            stall_ratio,
            percentile(&streaming.select_ms, 0.5),
            mean(&lod.triangles),
            lod_frame,
            mean(&full.triangles),
            percentile(&full.frame_ms, 0.5),
            mean(&full.triangles) / mean(&lod.triangles).max(1.0),
            time_ratio,
            percentile(&detailed_ground_ms, 0.5),
            percentile(&plain_ground_ms, 0.5),
            ground_detail_over_plain,
            2 * fires.len(),
            puffs_drawn,
            smoky_median,
            plain_median,
            100.0 * puff_share,
    );
    Ok(Report {
        json: report,
        summary,
    })
}
