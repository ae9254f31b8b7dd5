//! `cig bench particles`: cost of one fixed step of the obscurant particle engine.
//!
//! The scene of the issue: 16 fires, each a smoke and a flame plume (32 plumes of 5 columns x
//! 75 puffs), and 200 vehicles driving over sand and dry clay with dust trails of 50 puffs:
//! about 22,000 puffs, all pools full (warmed for 100 s of simulation first). Each timed frame
//! advances the simulation by one 1/60 s step on one thread; the snapshot for the renderer and
//! transmittance queries through the scene (2000 random 2 km sight lines 2 m above the ground,
//! median of 5 rounds) are timed separately. Baseline, interleaved in the
//! same run over the same number of puffs: the least a particle update can do (position +=
//! velocity * dt on a flat array), so the ratio survives a noisy machine.

use crate::report::{date_utc, machine, median, percentile};
use crate::{require, BenchError};
use cig_effects::{
    Atmosphere, DustTrailSpec, EffectId, EffectSystem, EffectsConfig, PlumeKind, PlumeSource,
    PlumeSpec, StabilityClass, VehicleUpdate, Wind,
};
use cig_geo::{EnuFrame, Geodetic};
use cig_terrain::Material;
use glam::DVec3;
use rand::{Rng, SeedableRng};
use std::hint::black_box;
use std::time::Instant;

const TARGET_MS: f64 = 1.0;

/// What `cig bench particles` measures.
#[derive(Clone, Debug)]
pub struct ParticlesOptions {
    /// Frames timed (each one fixed step of 1/60 s).
    pub frames: u32,
    /// Simulation seconds run before timing (100 s fills every pool: smoke lives 90 s).
    pub warm_seconds: u32,
    /// The commit the report names.
    pub commit: String,
}

/// The benchmark's air: 4 m/s from 250 degrees, neutral (class D), 290 K.
pub(crate) fn bench_atmosphere() -> Atmosphere {
    Atmosphere {
        wind: Wind {
            speed_mps: 4.0,
            from_deg: 250.0,
        },
        stability: StabilityClass::D,
        air_temperature_k: 290.0,
        dtheta_dz_k_per_m: None,
    }
}

/// Starts the benchmark's fires at `positions`: each a smoke and a flame plume (3 m across,
/// 5 MW, burning from time 0 for the whole run), effect ids `2 * fire + kind`.
pub(crate) fn start_fires(
    sys: &mut EffectSystem,
    positions: &[Geodetic],
) -> Result<(), BenchError> {
    for (fire, position) in positions.iter().enumerate() {
        for (k, kind) in [PlumeKind::Smoke, PlumeKind::Flame].into_iter().enumerate() {
            sys.start_plume(&PlumeSpec {
                id: EffectId((fire * 2 + k) as u64),
                kind,
                position: *position,
                size_m: 3.0,
                source: PlumeSource::HeatReleaseW(5.0e6),
                start_time_s: 0.0,
                duration_s: 1.0e6,
            })?;
        }
    }
    Ok(())
}

/// Runs the benchmark.
///
/// # Errors
/// When an option is out of range or the effect system refuses the scene.
pub fn run(options: &ParticlesOptions) -> Result<serde_json::Value, BenchError> {
    require((10..=1_000_000).contains(&options.frames), || {
        format!("--frames {} must be between 10 and 1000000", options.frames)
    })?;
    let origin = Geodetic::new(36.0, -121.0, 50.0);
    let frame = EnuFrame::new(origin);
    let mut sys = EffectSystem::new(EffectsConfig::default())?;
    sys.set_atmosphere(bench_atmosphere())?;
    sys.advance_to(0.0)?;
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
    let fires: Vec<Geodetic> = (0..16)
        .map(|_| {
            frame.enu_to_geodetic(DVec3::new(
                rng.gen_range(-5000.0..5000.0),
                rng.gen_range(-5000.0..5000.0),
                0.0,
            ))
        })
        .collect();
    start_fires(&mut sys, &fires)?;
    for vehicle in 0..200u64 {
        let position = frame.enu_to_geodetic(DVec3::new(
            rng.gen_range(-5000.0..5000.0),
            rng.gen_range(-5000.0..5000.0),
            0.0,
        ));
        let heading: f64 = rng.gen_range(0.0..std::f64::consts::TAU);
        let speed = rng.gen_range(8.0..20.0);
        sys.start_dust_trail(&DustTrailSpec {
            id: EffectId(1000 + vehicle),
            start_time_s: 0.0,
            duration_s: None,
            vehicle_length_m: 7.0,
            vehicle: VehicleUpdate {
                time_s: 0.0,
                position,
                velocity_enu_mps: [speed * heading.sin(), speed * heading.cos(), 0.0],
                material: if vehicle % 2 == 0 {
                    Material::Sand
                } else {
                    Material::DryClay
                },
                roadside_material: None,
            },
        })?;
    }
    require(options.warm_seconds <= 3600, || {
        format!(
            "--warm-seconds {} must be at most 3600",
            options.warm_seconds
        )
    })?;
    // Warm: every pool full (smoke lives 90 s).
    let warm_frames = options.warm_seconds * 60;
    for f in 1..=warm_frames {
        sys.advance_to(f64::from(f) / 60.0)?;
    }
    let puffs = sys.stats().active;
    if puffs == 0 {
        return Err(BenchError::Scene("the benchmark scene has no puffs".into()));
    }

    // Baseline data: the same number of puffs as flat position/velocity arrays.
    let mut flat: Vec<[f64; 6]> = (0..puffs)
        .map(|_| {
            [
                rng.gen(),
                rng.gen(),
                rng.gen(),
                rng.gen(),
                rng.gen(),
                rng.gen(),
            ]
        })
        .collect();
    let eye = origin.to_ecef();
    let mut instances = Vec::with_capacity(puffs);
    let (mut update_ms, mut baseline_ms, mut snapshot_ms) = (Vec::new(), Vec::new(), Vec::new());
    for f in 1..=options.frames {
        let t = f64::from(warm_frames + f) / 60.0;
        let started = Instant::now();
        sys.advance_to(t)?;
        update_ms.push(started.elapsed().as_secs_f64() * 1e3);

        let started = Instant::now();
        for p in &mut flat {
            p[0] += p[3] * cig_effects::STEP_S;
            p[1] += p[4] * cig_effects::STEP_S;
            p[2] += p[5] * cig_effects::STEP_S;
        }
        black_box(&flat);
        baseline_ms.push(started.elapsed().as_secs_f64() * 1e3);

        if f % 10 == 0 {
            let started = Instant::now();
            sys.snapshot(eye, &mut instances);
            black_box(&instances);
            snapshot_ms.push(started.elapsed().as_secs_f64() * 1e3);
        }
    }
    let stats = sys.stats();
    if stats.allocated_slots != sys.allocated_at_build() {
        return Err(BenchError::Scene(
            "the puff pools grew during the benchmark".into(),
        ));
    }

    // Transmittance: random 2 km sight lines 2 m above the ground across the scene.
    let lines: Vec<(Geodetic, Geodetic)> = (0..2000)
        .map(|_| {
            let a = DVec3::new(
                rng.gen_range(-5000.0..5000.0),
                rng.gen_range(-5000.0..5000.0),
                2.0,
            );
            let azimuth: f64 = rng.gen_range(0.0..std::f64::consts::TAU);
            let b = a + DVec3::new(azimuth.sin(), azimuth.cos(), 0.0) * 2000.0;
            (frame.enu_to_geodetic(a), frame.enu_to_geodetic(b))
        })
        .collect();
    let mut obscured = 0usize;
    let mut rates = Vec::new();
    for _ in 0..5 {
        obscured = 0;
        let started = Instant::now();
        for (a, b) in &lines {
            if sys.transmittance(*a, *b)?.obscured(0.5) {
                obscured += 1;
            }
        }
        rates.push(lines.len() as f64 / started.elapsed().as_secs_f64());
    }
    let transmittance_per_s = median(&rates);

    let update_median = median(&update_ms);
    let baseline_median = median(&baseline_ms);
    let report = serde_json::json!({
        "machine": machine(),
        "date_utc": date_utc(),
        "commit": options.commit,
        "plumes": 32,
        "puffs_per_plume": 375,
        "dust_trails": 200,
        "puffs_per_dust_trail": 50,
        "puffs_active": puffs,
        "frames": options.frames,
        "warm_seconds": options.warm_seconds,
        "step_s": cig_effects::STEP_S,
        "update_ms_per_frame_median": update_median,
        "update_ms_per_frame_p99": percentile(&update_ms, 0.99),
        "update_ms_per_frame_max": percentile(&update_ms, 1.0),
        "update_ns_per_puff_median": update_median * 1e6 / puffs as f64,
        "target_ms_per_frame": TARGET_MS,
        "meets_target": update_median <= TARGET_MS,
        "baseline_flat_update_ms_median": baseline_median,
        "update_vs_baseline": update_median / baseline_median,
        "snapshot_ms_median": median(&snapshot_ms),
        "snapshot_instances": instances.len(),
        "transmittance_2km_per_s_one_core": transmittance_per_s,
        "transmittance_2km_obscured_fraction": obscured as f64 / lines.len() as f64,
        "pool_starved_spawns": stats.starved_total,
    });
    Ok(report)
}
