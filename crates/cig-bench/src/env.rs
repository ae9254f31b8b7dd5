//! `cig bench env`: what the environment costs — the ephemeris and natural illuminance per
//! update, the frame's light and exposure (`Lighting::with_sky`) per view, and the share of
//! the frame the physical sky, aerial perspective and fog take on the GPU.
//!
//! The frame share is a same-run baseline ratio: the same frames along a fixed low pass over
//! the database (every tile resident, meshes built) drawn with the physical sky and fog and
//! with the sky and fog reduced to a flat colour (`SkyModel::Flat`, fog off), interleaved in
//! rounds, medians compared: `share = (physical − flat) / physical`. Each line of
//! [`VARIANTS`] is a named change to the snapshot whose cost is measured against the same flat
//! baseline; `sky_fog_and_clouds` (two cloud layers, one above the eye and one below it) is the
//! issue's budget line, reported as `sky_fog_and_clouds_share_of_frame` with `target_met`
//! (<= 20 %). Limits: the share is a difference of medians of whole frames, so on a shared
//! machine it carries a few percent of noise (it can even come out negative).

use crate::database::{demo_or, BuildProgress};
use crate::report::{date_utc, machine, median};
use crate::{require, BenchError, Report, Step};
use cig_render::{FrameOptions, Renderer};
use cig_scene::lighting::{Fog, FogMode, SkyModel};
use cig_scene::FrameSnapshot;
use cig_terrain::{PagingConfig, QuerySession, TileCache};
use serde_json::json;
use std::hint::black_box;
use std::path::PathBuf;
use std::sync::Arc;
use std::time::Instant;

/// What `cig bench env` measures.
#[derive(Clone, Debug)]
pub struct EnvOptions {
    /// The database flown over; `None`: the demo database "demo-db", built when missing.
    pub db: Option<PathBuf>,
    /// Frame size, pixels.
    pub size: (u32, u32),
    /// Frames along the pass, each drawn every way every round.
    pub frames: usize,
    /// Interleaved rounds.
    pub rounds: usize,
    /// The tile cache's configuration.
    pub paging: PagingConfig,
    /// Cells along a tile side of the demo database, when it is built.
    pub tile_cells: u32,
    /// The commit the report names.
    pub commit: String,
}

/// The measured environment configurations: name, and what it changes in a baseline
/// (flat sky, no fog) snapshot. `sky_fog_and_clouds` is the budget line.
const VARIANTS: &[(&str, SnapshotChange)] = &[
    ("sky_and_fog", physical_sky_and_fog),
    ("sky_fog_and_clouds", physical_sky_fog_and_clouds),
];

/// The variant whose share the 20 % budget is about.
const BUDGET_VARIANT: &str = "sky_fog_and_clouds";

/// A change made to a baseline snapshot.
type SnapshotChange = fn(&mut FrameSnapshot);

/// The physical sky with aerial perspective and the default exponential fog (40 km).
fn physical_sky_and_fog(s: &mut FrameSnapshot) {
    s.sky.model = SkyModel::Physical;
    s.fog = Fog::from_visibility(FogMode::Exponential, 40_000.0);
}

/// The physical sky and fog with two layers placed about the bench's eye (120 m above the
/// ground): a broken cumulus layer seen from below (base 1 200 m above the eye, 800 m thick,
/// 50 % cover) and a thin scattered stratocumulus deck seen from above, between the eye and
/// the ground (top 30 m below the eye, 70 m thick, 40 %).
fn physical_sky_fog_and_clouds(s: &mut FrameSnapshot) {
    use cig_environment::clouds::{CloudKind, CloudLayer};
    physical_sky_and_fog(s);
    let eye_alt_m = s.views.first().map_or(0.0, |v| v.eye.alt_m);
    let mut cumulus = CloudLayer::new(eye_alt_m + 1_200.0, 800.0, 0.5, CloudKind::Cumulus);
    cumulus.seed = 11;
    let mut stratocumulus = CloudLayer::new(eye_alt_m - 100.0, 70.0, 0.4, CloudKind::Stratocumulus);
    stratocumulus.seed = 12;
    s.cloud_layers = vec![cumulus, stratocumulus];
}

fn flat(s: &mut FrameSnapshot) {
    s.sky.model = SkyModel::Flat;
    s.fog = Fog::from_visibility(FogMode::Off, 40_000.0);
}

/// Median microseconds per call of `f` over `rounds` rounds of `per_round` calls.
fn time_us(rounds: usize, per_round: usize, mut f: impl FnMut(usize)) -> f64 {
    let mut per_call = Vec::with_capacity(rounds);
    for r in 0..rounds {
        let started = Instant::now();
        for i in 0..per_round {
            f(r * per_round + i);
        }
        per_call.push(started.elapsed().as_secs_f64() * 1e6 / per_round as f64);
    }
    median(&per_call)
}

/// Runs the benchmark; `progress` hears the demo database's build, if it is built.
///
/// # Errors
/// When an option is out of range, there is no GPU or the pass leaves the database.
pub fn run(
    options: &EnvOptions,
    progress: &mut dyn FnMut(BuildProgress<'_>),
) -> Result<Report, BenchError> {
    let size = options.size;
    require((2..=1000).contains(&options.frames), || {
        format!("--frames {} must be between 2 and 1000", options.frames)
    })?;
    require((1..=100).contains(&options.rounds), || {
        format!("--rounds {} must be between 1 and 100", options.rounds)
    })?;
    let time = cig_environment::UtcTime::parse_iso8601("2026-06-21T19:00:00Z")?.unix_seconds();

    // 1. Ephemeris and natural illuminance per update, over a day of instants.
    let observer = cig_environment::Observer::new(36.0, -121.0, 100.0)?;
    let start = cig_environment::UtcTime::from_unix_seconds(time)?;
    let instants: Vec<cig_environment::UtcTime> = (0..1440)
        .map(|m| cig_environment::UtcTime::from_unix_seconds(time + 60.0 * f64::from(m)))
        .collect::<Result<_, _>>()?;
    let ephemeris_us = time_us(9, 1000, |i| {
        let t = instants[i % instants.len()];
        let e = cig_environment::ephemeris(&observer, t);
        black_box(cig_environment::natural_illuminance(&e, 0.0).ok());
    });
    // The frame's light (ephemeris, atmosphere transmittance, sky irradiance, 18 sky
    // radiances), once per view per frame; the atmosphere's tables are built before timing.
    let eye = observer.geodetic();
    let settings = cig_scene::lighting::SkySettings::default();
    let table_started = Instant::now();
    black_box(cig_environment::Atmosphere::earth());
    let tables_ms = table_started.elapsed().as_secs_f64() * 1e3;
    let lighting_us = time_us(5, 100, |i| {
        let t = time + 60.0 * (i % 1440) as f64;
        black_box(cig_scene::Lighting::with_sky(t, eye, 0.0, &settings));
    });
    black_box(start);

    // 2. The frame share, on the GPU.
    let path = demo_or(
        options.db.as_deref(),
        "bench env",
        options.tile_cells,
        progress,
    )?;
    let db = Arc::new(cig_terrain_io::store::open_database(&path)?);
    let gpu = cig_render::Gpu::headless()?;
    let target = cig_render::OffscreenTarget::new(&gpu, size);
    let cache = Arc::new(TileCache::new(Arc::clone(&db), options.paging.clone())?);
    let mut session = QuerySession::new(Arc::clone(&cache));
    // The render benchmark's pass, sampled at `frames` points over 10 s.
    let leg = crate::render::pass_leg(&db, 300.0, 10.0);
    let dt_s = 10.0 / options.frames as f64;
    let views = crate::flight::views_along(&mut session, &leg, dt_s, 60.0, size)
        .step("the benchmark path")?;
    let base: Vec<FrameSnapshot> = views
        .iter()
        .take(options.frames)
        .map(|v| {
            let mut s = FrameSnapshot::new(time, vec![*v]);
            flat(&mut s);
            s
        })
        .collect();
    let mut renderer = Renderer::new(Arc::clone(&gpu), &cache, cig_render::FRAME_FORMAT);
    for s in &base {
        cig_render::load_for_view(&mut renderer, &cache, s, 0, 64)?;
    }
    let frame_options = FrameOptions {
        mesh_budget: usize::MAX,
        key_background: false,
        fade_in_s: 0.0,
        ..FrameOptions::default()
    };
    let draw =
        |renderer: &mut Renderer, frames: &[FrameSnapshot]| -> Result<Vec<f64>, BenchError> {
            let mut ms = Vec::with_capacity(frames.len());
            for s in frames {
                let started = Instant::now();
                renderer.render(&cache, s, 0, target.view(), frame_options)?;
                ms.push(started.elapsed().as_secs_f64() * 1e3);
            }
            Ok(ms)
        };
    let variants: Vec<(&str, Vec<FrameSnapshot>)> = VARIANTS
        .iter()
        .map(|(name, change)| {
            let frames = base
                .iter()
                .map(|s| {
                    let mut s = s.clone();
                    change(&mut s);
                    s
                })
                .collect();
            (*name, frames)
        })
        .collect();
    // Warm every configuration (pipelines, meshes), then interleave the rounds.
    draw(&mut renderer, &base)?;
    for (_, frames) in &variants {
        draw(&mut renderer, frames)?;
    }
    let mut flat_ms = Vec::new();
    let mut variant_ms: Vec<Vec<f64>> = vec![Vec::new(); variants.len()];
    for _ in 0..options.rounds {
        flat_ms.extend(draw(&mut renderer, &base)?);
        for (i, (_, frames)) in variants.iter().enumerate() {
            variant_ms[i].extend(draw(&mut renderer, frames)?);
        }
    }
    let flat_median = median(&flat_ms);
    let mut passes = serde_json::Map::new();
    for (i, (name, _)) in variants.iter().enumerate() {
        let m = median(&variant_ms[i]);
        passes.insert(
            (*name).to_string(),
            json!({
                "frame_ms_median": m,
                "share_of_frame": (m - flat_median) / m,
            }),
        );
    }
    let budget_share = variants
        .iter()
        .position(|(name, _)| *name == BUDGET_VARIANT)
        .and_then(|i| variant_ms.get(i))
        .map(|v| {
            let m = median(v);
            (m - flat_median) / m
        })
        .unwrap_or(f64::NAN);
    let environment_ms = variant_ms
        .iter()
        .map(|v| median(v))
        .fold(flat_median, f64::max);
    let report = json!({
        "machine": machine(),
        "date_utc": date_utc(),
        "commit": options.commit,
        "adapter": gpu.describe(),
        "database": path.display().to_string(),
        "size": [size.0, size.1],
        "frames": base.len(),
        "rounds": options.rounds,
        "ephemeris_us_per_update": ephemeris_us,
        "lighting_us_per_view": lighting_us,
        "atmosphere_tables_ms": tables_ms,
        "flat_frame_ms_median": flat_median,
        "passes": passes,
        "environment_share_of_frame": (environment_ms - flat_median) / environment_ms,
        "sky_fog_and_clouds_share_of_frame": budget_share,
        "target_met": budget_share <= 0.20,
        "targets": {
            "environment_share_of_frame_at_most": 0.20,
            "ephemeris_us_per_update_at_most": 20.0,
        },
    });
    let summary = format!(
        "ephemeris + illuminance {:.2} us per update; light of a view {:.1} us; frame {:.2} ms flat, environment {:.0}% of the frame",
        ephemeris_us,
        lighting_us,
        flat_median,
        100.0 * (environment_ms - flat_median) / environment_ms
    );
    Ok(Report {
        json: report,
        summary,
    })
}
