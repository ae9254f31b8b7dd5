//! Behaviour of the particle engine: pools, lifetimes, determinism, physics and optics.

use cig_effects::optics::gaussian_path_integral_kg_m2;
use cig_effects::{
    Atmosphere, DustTrailSpec, EffectHandle, EffectId, EffectSystem, EffectsConfig, EffectsError,
    ObscurantKind, PlumeKind, PlumeSource, PlumeSpec, PuffInstance, ServedArea, StabilityClass,
    VehicleUpdate, Wind, STEP_S,
};
use cig_geo::{EnuFrame, Geodetic};
use cig_terrain::Material;
use glam::DVec3;
use rand::{Rng, SeedableRng};

const ORIGIN: Geodetic = Geodetic::new(36.0, -121.0, 100.0);

fn small_config() -> EffectsConfig {
    EffectsConfig {
        plume_slots: 4,
        puffs_per_column: 75,
        dust_slots: 4,
        puffs_per_dust_trail: 50,
        area: None,
    }
}

fn atmosphere(speed: f64, from_deg: f64, class: StabilityClass) -> Atmosphere {
    Atmosphere {
        wind: Wind {
            speed_mps: speed,
            from_deg,
        },
        stability: class,
        air_temperature_k: 290.0,
        dtheta_dz_k_per_m: None,
    }
}

fn plume(id: u64, kind: PlumeKind, start: f64, duration: f64) -> PlumeSpec {
    PlumeSpec {
        id: EffectId(id),
        kind,
        position: ORIGIN,
        size_m: 3.0,
        source: PlumeSource::HeatReleaseW(5.0e6),
        start_time_s: start,
        duration_s: duration,
    }
}

fn vehicle(t: f64, material: Material, speed: f64) -> VehicleUpdate {
    VehicleUpdate {
        time_s: t,
        position: ORIGIN,
        velocity_enu_mps: [0.0, speed, 0.0],
        material,
        roadside_material: None,
    }
}

fn trail(id: u64, start: f64, material: Material, speed: f64) -> DustTrailSpec {
    DustTrailSpec {
        id: EffectId(id),
        start_time_s: start,
        duration_s: None,
        vehicle_length_m: 7.0,
        vehicle: vehicle(start, material, speed),
    }
}

/// ENU of a puff state's centre in the frame at ORIGIN.
fn enu(frame: &EnuFrame, c: [f64; 3]) -> DVec3 {
    frame.ecef_to_enu(DVec3::from_array(c))
}

#[test]
fn pools_are_reused_without_growth_over_a_long_run() {
    let mut sys = EffectSystem::new(small_config()).unwrap();
    sys.set_atmosphere(atmosphere(5.0, 270.0, StabilityClass::C))
        .unwrap();
    sys.advance_to(0.0).unwrap();
    let built = sys.allocated_at_build();
    assert_eq!(sys.stats().allocated_slots, built);
    sys.start_plume(&plume(1, PlumeKind::Smoke, 0.0, 1.0e9))
        .unwrap();
    sys.start_plume(&plume(2, PlumeKind::Flame, 0.0, 1.0e9))
        .unwrap();
    sys.start_dust_trail(&trail(3, 0.0, Material::Sand, 15.0))
        .unwrap();
    let capacity = sys.stats().capacity;
    let mut out: Vec<PuffInstance> = Vec::new();
    // Five minutes at 60 Hz: smoke lives 90 s, so each smoke puff is reused three times.
    for frame in 1..=18_000u32 {
        sys.advance_to(f64::from(frame) / 60.0).unwrap();
        if frame % 600 == 0 {
            sys.snapshot(DVec3::ZERO, &mut out);
            let s = sys.stats();
            assert_eq!(s.allocated_slots, built, "pool grew at frame {frame}");
            assert_eq!(s.active + s.free, capacity);
            assert_eq!(s.starved_total, 0, "a column ran out of puffs");
        }
    }
    let s = sys.stats();
    // Smoke 5 x 75 full, flame 5 x 75 full, dust 50 full.
    assert_eq!(s.active, 2 * 375 + 50);
    // Far more spawns than slots (flame puffs live 2.5 s).
    assert!(s.spawned_total > 10 * s.active as u64, "{s:?}");
    assert_eq!(s.allocated_slots, built);
}

#[test]
fn a_plume_ends_after_its_duration_and_returns_its_puffs() {
    let mut sys = EffectSystem::new(small_config()).unwrap();
    sys.advance_to(0.0).unwrap();
    let smoke = sys
        .start_plume(&plume(1, PlumeKind::Smoke, 0.0, 10.0))
        .unwrap();
    let flame = sys
        .start_plume(&plume(2, PlumeKind::Flame, 0.0, 10.0))
        .unwrap();
    let dust = sys
        .start_dust_trail(&trail(3, 0.0, Material::Sand, 15.0))
        .unwrap();
    sys.advance_to(9.0).unwrap();
    assert!(sys.is_live(smoke) && sys.is_live(flame) && sys.is_live(dust));
    let before = sys.stats().spawned_total;
    sys.stop(dust, 9.0).unwrap();
    sys.advance_to(11.0).unwrap();
    // Emission has stopped: only the flame puffs are still ageing (life 2.5 s).
    let spawned = sys.stats().spawned_total;
    sys.advance_to(12.0).unwrap();
    assert_eq!(
        sys.stats().spawned_total,
        spawned,
        "no spawns after the duration"
    );
    assert!(spawned > before);
    // The flame (life 2.5 s) has ended, smoke (life 90 s) and dust (20 s) have not.
    sys.advance_to(13.0).unwrap();
    assert!(!sys.is_live(flame));
    assert!(sys.is_live(smoke));
    sys.advance_to(9.0 + 20.0 + 0.1).unwrap();
    assert!(!sys.is_live(dust));
    sys.advance_to(10.0 + 90.0 - 0.5).unwrap();
    assert!(sys.is_live(smoke));
    sys.advance_to(10.0 + 90.0 + 0.1).unwrap();
    assert!(!sys.is_live(smoke));
    let s = sys.stats();
    assert_eq!((s.active, s.live_effects), (0, 0));
    assert_eq!(s.free, s.capacity);
    // Stale handles are refused, and the slot is reused by a new effect.
    assert!(matches!(
        sys.stop(smoke, 200.0),
        Err(EffectsError::StaleHandle { .. })
    ));
    let again = sys
        .start_plume(&plume(4, PlumeKind::Smoke, 101.0, 5.0))
        .unwrap();
    assert_ne!(again, smoke);
    assert!(sys.is_live(again));
}

/// A scenario: a fire (smoke and flame), a second smoke plume started later, a dust trail, a
/// wind change. `frames` are the times at which the IG happens to advance.
fn run_scenario(frames: &[f64], seed_offset: u64) -> EffectSystem {
    let mut sys = EffectSystem::new(small_config()).expect("scenario");
    sys.set_atmosphere(atmosphere(4.0, 250.0, StabilityClass::D))
        .expect("scenario");
    let mut started_late = false;
    let mut wind_changed = false;
    sys.advance_to(0.0).expect("scenario");
    sys.start_plume(&plume(10 + seed_offset, PlumeKind::Smoke, 0.0, 60.0))
        .expect("scenario");
    sys.start_plume(&plume(11 + seed_offset, PlumeKind::Flame, 0.0, 60.0))
        .expect("scenario");
    sys.start_dust_trail(&trail(12 + seed_offset, 0.0, Material::DryClay, 12.0))
        .expect("scenario");
    for &t in frames {
        // The scenario's events happen at scenario times; an IG applies them on the first frame
        // at or after them (the late plume is stepped through what it missed).
        if !wind_changed && t >= 8.0 {
            // Applied between grid steps 480 and 481 on every IG.
            sys.advance_to(8.0).expect("scenario");
            sys.set_atmosphere(atmosphere(6.0, 200.0, StabilityClass::C))
                .expect("scenario");
            wind_changed = true;
        }
        if !started_late && t >= 3.3 {
            sys.start_plume(&plume(13 + seed_offset, PlumeKind::Smoke, 3.3, 60.0))
                .expect("scenario");
            started_late = true;
        }
        sys.advance_to(t).expect("scenario");
    }
    sys
}

/// Asserts two puff lists are identical, naming the first difference.
fn same_puffs(a: &[cig_effects::PuffState], b: &[cig_effects::PuffState]) {
    let count = |v: &[cig_effects::PuffState], e: u32| v.iter().filter(|p| p.effect == e).count();
    for e in 0..8 {
        assert_eq!(count(a, e), count(b, e), "puffs of effect {e}");
    }
    for (i, (x, y)) in a.iter().zip(b).enumerate() {
        assert_eq!(x, y, "puff {i} differs");
    }
}

#[test]
fn same_seed_and_time_give_identical_puffs_whatever_the_frame_times() {
    let end = 20.0;
    let steady: Vec<f64> = (1..=1200).map(|i| f64::from(i) / 60.0).collect();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(99);
    let mut irregular = Vec::new();
    let mut t: f64 = 0.0;
    while t < end {
        t += rng.gen_range(0.003..0.09);
        irregular.push(t.min(end));
    }
    let a = run_scenario(&steady, 0);
    let b = run_scenario(&irregular, 0);
    let sa = a.puff_states();
    let sb = b.puff_states();
    assert!(sa.len() > 500, "{}", sa.len());
    same_puffs(&sa, &sb);
    // Another identity gives another plume.
    let c = run_scenario(&steady, 100);
    assert_ne!(c.puff_states(), sa);
}

#[test]
fn smoke_drifts_downwind_rises_and_spreads_and_flame_is_turned_45_degrees() {
    let mut sys = EffectSystem::new(small_config()).unwrap();
    // Wind from the west: the plume goes east.
    sys.set_atmosphere(atmosphere(5.0, 270.0, StabilityClass::D))
        .unwrap();
    sys.advance_to(0.0).unwrap();
    sys.start_plume(&plume(1, PlumeKind::Smoke, 0.0, 1000.0))
        .unwrap();
    sys.start_plume(&plume(2, PlumeKind::Flame, 0.0, 1000.0))
        .unwrap();
    // One step: the first puff of each column is at its footprint point.
    sys.advance_to(0.5).unwrap();
    let frame = EnuFrame::new(ORIGIN);
    let states = sys.puff_states();
    let mut smoke_angles = Vec::new();
    let mut flame_angles = Vec::new();
    for s in &states {
        let p = enu(&frame, s.centre_ecef_m);
        let horizontal = (p.x * p.x + p.y * p.y).sqrt();
        if horizontal < 0.5 || s.age_s > 0.05 {
            continue;
        }
        // Angle from downwind (east), folded to [0, 90).
        let a = p.y.atan2(p.x).to_degrees().rem_euclid(90.0);
        match s.kind {
            ObscurantKind::Smoke => smoke_angles.push(a),
            ObscurantKind::Flame => flame_angles.push(a),
            ObscurantKind::Dust => unreachable!(),
        }
    }
    assert!(!smoke_angles.is_empty() && !flame_angles.is_empty());
    for a in smoke_angles {
        assert!(!(10.0..=80.0).contains(&a), "smoke column at {a} degrees");
    }
    for a in flame_angles {
        assert!((25.0..=65.0).contains(&a), "flame column at {a} degrees");
    }
    sys.advance_to(80.0).unwrap();
    let smoke: Vec<_> = sys
        .puff_states()
        .into_iter()
        .filter(|s| s.kind == ObscurantKind::Smoke)
        .collect();
    let young: Vec<_> = smoke.iter().filter(|s| s.age_s < 10.0).collect();
    let old: Vec<_> = smoke.iter().filter(|s| s.age_s > 60.0).collect();
    let mean = |v: &[&cig_effects::PuffState], f: &dyn Fn(&cig_effects::PuffState) -> f64| {
        v.iter().map(|s| f(s)).sum::<f64>() / v.len() as f64
    };
    let east = |s: &cig_effects::PuffState| enu(&frame, s.centre_ecef_m).x;
    let north = |s: &cig_effects::PuffState| enu(&frame, s.centre_ecef_m).y;
    let up = |s: &cig_effects::PuffState| enu(&frame, s.centre_ecef_m).z;
    // Old puffs are about 5 m/s x 70 s downwind, a little north or south, higher and larger.
    let old_east = mean(&old, &east);
    assert!((300.0..400.0).contains(&old_east), "{old_east}");
    assert!(mean(&old, &north).abs() < 30.0);
    assert!(mean(&old, &up) > mean(&young, &up) + 10.0);
    assert!(
        mean(&old, &|s| s.sigma_m) > 2.0 * mean(&young, &|s| s.sigma_m),
        "puffs grow downwind"
    );
    assert!(
        mean(&old, &|s| s.opacity) < mean(&young, &|s| s.opacity),
        "and thin"
    );
    // Flames rise from the fire and stay short.
    let flame_up: Vec<f64> = sys
        .puff_states()
        .iter()
        .filter(|s| s.kind == ObscurantKind::Flame)
        .map(|s| enu(&frame, s.centre_ecef_m).z)
        .collect();
    let top = flame_up.iter().cloned().fold(f64::MIN, f64::max);
    assert!((2.0..40.0).contains(&top), "flame top {top}");
    assert!(flame_up.iter().all(|z| *z >= -1e-6));
}

#[test]
fn dust_trails_follow_the_vehicle_thin_behind_it_and_depend_on_the_ground() {
    let mut sys = EffectSystem::new(small_config()).unwrap();
    sys.set_atmosphere(atmosphere(1.0, 90.0, StabilityClass::D))
        .unwrap();
    sys.advance_to(0.0).unwrap();
    let sand = sys
        .start_dust_trail(&trail(1, 0.0, Material::Sand, 15.0))
        .unwrap();
    let clay = sys
        .start_dust_trail(&trail(2, 0.0, Material::DryClay, 15.0))
        .unwrap();
    let paved = sys
        .start_dust_trail(&trail(3, 0.0, Material::PavedRoad, 15.0))
        .unwrap();
    let parked = sys
        .start_dust_trail(&trail(4, 0.0, Material::Sand, 0.0))
        .unwrap();
    sys.advance_to(15.0).unwrap();
    let states = sys.puff_states();
    let of = |h: EffectHandle| {
        states
            .iter()
            .filter(|s| s.effect == h.slot)
            .cloned()
            .collect::<Vec<_>>()
    };
    assert!(of(paved).is_empty(), "a clean paved road raises no dust");
    assert!(of(parked).is_empty(), "a parked vehicle raises no dust");
    let sand_puffs = of(sand);
    let clay_puffs = of(clay);
    assert!(sand_puffs.len() > 20);
    assert_eq!(sand_puffs.len(), clay_puffs.len());
    // Same ages, bigger and denser puffs on sand.
    for (s, c) in sand_puffs.iter().zip(&clay_puffs) {
        assert!((s.age_s - c.age_s).abs() < 1e-9);
        assert!(s.sigma_m > c.sigma_m && s.mass_kg > c.mass_kg);
    }
    // The vehicle drives north at 15 m/s: the trail lies behind it (south of its position at 15 s),
    // and thins toward the trailing (oldest) edge.
    let frame = EnuFrame::new(ORIGIN);
    let mut by_age = sand_puffs.clone();
    by_age.sort_by(|a, b| a.age_s.total_cmp(&b.age_s));
    for s in &by_age {
        let p = enu(&frame, s.centre_ecef_m);
        assert!(p.y < 15.0 * 15.0, "puff ahead of the vehicle: {p}");
    }
    for pair in by_age.windows(2) {
        assert!(
            pair[1].opacity <= pair[0].opacity,
            "older puffs are thinner"
        );
    }
    let newest = enu(&frame, by_age[0].centre_ecef_m);
    assert!((newest.y - (225.0 - 3.5)).abs() < 10.0, "{newest}");
    // Moving onto pavement stops the trail.
    let mut v = vehicle(15.0, Material::PavedRoad, 15.0);
    v.position = frame.enu_to_geodetic(DVec3::new(0.0, 225.0, 0.0));
    sys.update_vehicle(sand, &v).unwrap();
    let spawned = sys.stats().spawned_total;
    sys.advance_to(15.0 + 1.0).unwrap();
    let after = sys.stats().spawned_total;
    // Only the clay trail kept spawning: one puff per 0.4 s.
    assert!(after - spawned <= 3, "{spawned} -> {after}");
}

#[test]
fn transmittance_clear_dense_monotone_and_equal_to_numeric_integration() {
    let mut sys = EffectSystem::new(small_config()).unwrap();
    sys.set_atmosphere(atmosphere(3.0, 270.0, StabilityClass::D))
        .unwrap();
    sys.advance_to(0.0).unwrap();
    let frame = EnuFrame::new(ORIGIN);
    let at = |e: f64, n: f64, u: f64| frame.enu_to_geodetic(DVec3::new(e, n, u));
    // No obscurant: everything is visible.
    let t = sys
        .transmittance(at(-500.0, 0.0, 2.0), at(500.0, 10.0, 3.0))
        .unwrap();
    assert_eq!(t.transmittance, 1.0);
    let smoke = PlumeSpec {
        size_m: 6.0,
        source: PlumeSource::HeatReleaseW(10.0e6),
        ..plume(1, PlumeKind::Smoke, 0.0, 600.0)
    };
    sys.start_plume(&smoke).unwrap();
    sys.advance_to(60.0).unwrap();
    // A crosswind sight line 40 m downwind of the source at the plume's height is obscured.
    let states = sys.puff_states();
    let near: Vec<_> = states
        .iter()
        .map(|s| enu(&frame, s.centre_ecef_m))
        .filter(|p| (30.0..50.0).contains(&p.x))
        .collect();
    let z = near.iter().map(|p| p.z).sum::<f64>() / near.len() as f64;
    let through = sys
        .transmittance(at(40.0, -300.0, z), at(40.0, 300.0, z))
        .unwrap();
    assert!(through.transmittance < 0.05, "{through:?}");
    assert!(through.obscured(0.1));
    // Upwind of the fire the air is clear.
    let upwind = sys
        .transmittance(at(-100.0, -300.0, z), at(-100.0, 300.0, z))
        .unwrap();
    assert!(upwind.transmittance > 0.999, "{upwind:?}");
    // Longer paths through the plume never let more light through.
    let mut last = 1.0;
    for end in (0..=30).map(|i| -300.0 + 20.0 * f64::from(i)) {
        let t = sys
            .transmittance(at(40.0, -300.0, z), at(40.0, end, z))
            .unwrap()
            .transmittance;
        // (Geodetic endpoints round-trip through ECEF: nanometre noise, hence the 1e-9.)
        assert!(t <= last * (1.0 + 1e-9), "{t} after {last}");
        last = t;
    }
    // The system's answer is the numeric integral of the summed Gaussian field (Eq 1-2), each
    // puff thinned with age as it is drawn.
    let a = DVec3::new(40.0, -300.0, z);
    let b = DVec3::new(80.0, 300.0, z + 20.0);
    let ecef = |p: DVec3| frame.enu_to_ecef(p);
    let analytic = sys.transmittance_ecef(ecef(a), ecef(b)).optical_depth;
    let n = 60_000;
    let h = 1.0 / f64::from(n);
    let len = (b - a).length();
    let mut sum = 0.0;
    for i in 0..=n {
        let w = if i == 0 || i == n {
            1.0
        } else if i % 2 == 1 {
            4.0
        } else {
            2.0
        };
        let p = ecef(a + (b - a) * (f64::from(i) * h));
        let mut c = 0.0;
        for s in &states {
            let d2 =
                (p - DVec3::from_array(s.centre_ecef_m)).length_squared() / (s.sigma_m * s.sigma_m);
            // Each puff as thin as it is drawn: (1 - e^-tau) fade is its centre opacity on
            // screen, and its optical depth scales to match.
            let centre_tau = ObscurantKind::Smoke.mass_extinction_m2_per_kg() * s.mass_kg
                / (2.0 * std::f64::consts::PI * s.sigma_m * s.sigma_m);
            let drawn_opacity = (1.0 - (-centre_tau).exp()) * s.fade;
            let fraction = -(1.0 - drawn_opacity).ln() / centre_tau;
            c += fraction * s.mass_kg
                / ((2.0 * std::f64::consts::PI).powf(1.5) * s.sigma_m.powi(3))
                * (-0.5 * d2).exp();
        }
        sum += w * c;
    }
    let numeric = ObscurantKind::Smoke.mass_extinction_m2_per_kg() * sum * h / 3.0 * len;
    assert!(
        (analytic - numeric).abs() <= 1e-6 * numeric,
        "analytic {analytic} numeric {numeric}"
    );
    // And one known puff against its closed form.
    let one = gaussian_path_integral_kg_m2(
        DVec3::ZERO,
        DVec3::X * 10.0,
        DVec3::new(5.0, 0.0, 0.0),
        1.0,
        1.0,
    );
    let erf_5_over_sqrt2 = 0.999_999_426_696_856_3;
    let expected = 1.0 / (2.0 * std::f64::consts::PI) * erf_5_over_sqrt2;
    assert!((one - expected).abs() < 1e-15, "{one} vs {expected}");
}

#[test]
fn snapshot_is_eye_relative_reuses_its_buffer_and_flames_glow() {
    let mut sys = EffectSystem::new(small_config()).unwrap();
    sys.advance_to(0.0).unwrap();
    sys.start_plume(&plume(1, PlumeKind::Flame, 0.0, 100.0))
        .unwrap();
    sys.start_plume(&plume(2, PlumeKind::Smoke, 0.0, 100.0))
        .unwrap();
    sys.advance_to(10.0).unwrap();
    let eye = ORIGIN.to_ecef();
    let mut out = Vec::with_capacity(4096);
    sys.snapshot(eye, &mut out);
    let capacity = out.capacity();
    assert!(!out.is_empty());
    assert!(out.len() <= sys.stats().active);
    assert_eq!(bytemuck::bytes_of(&out[0]).len(), 48);
    for p in &out {
        let d = (p.position_eye_m[0].powi(2)
            + p.position_eye_m[1].powi(2)
            + p.position_eye_m[2].powi(2))
        .sqrt();
        assert!(d < 2000.0, "puff {d} m from the source");
        assert!(p.opacity > 0.0 && p.opacity <= 1.0 && p.radius_m > 0.0);
    }
    let flames: Vec<_> = out
        .iter()
        .filter(|p| p.kind == ObscurantKind::Flame as u32)
        .collect();
    assert!(flames
        .iter()
        .any(|p| p.emissive > 0.5 && p.temperature_k > 1000.0));
    assert!(out
        .iter()
        .filter(|p| p.kind == ObscurantKind::Smoke as u32)
        .all(|p| p.emissive == 0.0));
    assert_ne!(
        flames[0].effect,
        out.iter().find(|p| p.kind == 0).unwrap().effect
    );
    sys.advance_to(10.5).unwrap();
    sys.snapshot(eye, &mut out);
    assert_eq!(out.capacity(), capacity);
}

#[test]
fn bad_input_is_refused_with_a_message() {
    let area = ServedArea {
        south_deg: 35.5,
        north_deg: 36.5,
        west_deg: -121.5,
        east_deg: -120.5,
    };
    let mut sys = EffectSystem::new(EffectsConfig {
        area: Some(area),
        ..small_config()
    })
    .unwrap();
    let good = plume(1, PlumeKind::Smoke, 0.0, 10.0);
    let far = PlumeSpec {
        position: Geodetic::new(48.0, 2.0, 0.0),
        ..good
    };
    let e = sys.start_plume(&far).unwrap_err();
    assert!(matches!(e, EffectsError::OutsideArea { .. }));
    assert!(e.to_string().contains("outside the served area"), "{e}");
    for bad in [
        PlumeSpec {
            size_m: -1.0,
            ..good
        },
        PlumeSpec {
            size_m: f64::NAN,
            ..good
        },
        PlumeSpec {
            duration_s: -5.0,
            ..good
        },
        PlumeSpec {
            duration_s: f64::INFINITY,
            ..good
        },
        PlumeSpec {
            start_time_s: f64::NAN,
            ..good
        },
        PlumeSpec {
            source: PlumeSource::HeatReleaseW(-1.0),
            ..good
        },
        PlumeSpec {
            source: PlumeSource::BuoyancyFluxM4S3(f64::NAN),
            ..good
        },
        PlumeSpec {
            position: Geodetic::new(f64::NAN, 0.0, 0.0),
            ..good
        },
    ] {
        let e = sys.start_plume(&bad).unwrap_err();
        assert!(matches!(e, EffectsError::OutOfRange { .. }), "{e}");
    }
    let mut t = trail(2, 0.0, Material::Sand, 10.0);
    t.vehicle.velocity_enu_mps[0] = f64::INFINITY;
    assert!(sys.start_dust_trail(&t).is_err());
    let t = DustTrailSpec {
        duration_s: Some(-1.0),
        ..trail(2, 0.0, Material::Sand, 10.0)
    };
    assert!(sys.start_dust_trail(&t).is_err());
    assert!(sys.advance_to(f64::NAN).is_err());
    let mut a = Atmosphere::default();
    a.wind.speed_mps = -2.0;
    assert!(sys.set_atmosphere(a).is_err());
    let calm_night = Wind {
        speed_mps: 1.0,
        from_deg: 0.0,
    };
    let night = Atmosphere::from_weather(calm_night, 285.0, -20.0, 0.0, f64::INFINITY).unwrap();
    assert_eq!(night.stability, StabilityClass::F);
    assert!(Atmosphere::from_weather(calm_night, -1.0, -20.0, 0.0, f64::INFINITY).is_err());
    assert!(Atmosphere::from_weather(calm_night, 285.0, f64::NAN, 0.0, f64::INFINITY).is_err());
    assert!("H".parse::<StabilityClass>().is_err());
    assert!("quicksand".parse::<cig_effects::Soil>().is_err());
    // Slots run out with a message, never a panic.
    for i in 0..4 {
        sys.start_plume(&plume(10 + i, PlumeKind::Smoke, 0.0, 10.0))
            .unwrap();
    }
    let e = sys.start_plume(&good).unwrap_err();
    assert!(matches!(e, EffectsError::NoFreeSlot { .. }), "{e}");
    // A plume handle is not a dust trail.
    let mut sys = EffectSystem::new(small_config()).unwrap();
    let h = sys.start_plume(&good).unwrap();
    assert!(matches!(
        sys.update_vehicle(h, &vehicle(0.0, Material::Sand, 1.0)),
        Err(EffectsError::NotADustTrail { .. })
    ));
    assert!(EffectSystem::new(EffectsConfig {
        puffs_per_column: 0,
        ..small_config()
    })
    .is_err());
}

#[test]
fn fixed_steps_do_not_depend_on_the_step_grid_origin_or_rewinds() {
    // Stepping starts at 100 s in one system and at 0 s in the other; a plume started at 100.25 s
    // is the same in both once they reach 130 s. Asking for an earlier time changes nothing.
    let mut a = EffectSystem::new(small_config()).unwrap();
    let mut b = EffectSystem::new(small_config()).unwrap();
    a.advance_to(0.0).unwrap();
    a.advance_to(100.0).unwrap();
    b.advance_to(100.0).unwrap();
    let spec = plume(5, PlumeKind::Flame, 100.25, 100.0);
    a.start_plume(&spec).unwrap();
    b.start_plume(&spec).unwrap();
    a.advance_to(130.0).unwrap();
    for t in [110.0, 120.0, 129.99, 130.0] {
        b.advance_to(t).unwrap();
    }
    let before = b.puff_states();
    b.advance_to(125.0).unwrap();
    assert_eq!(b.puff_states(), before);
    assert_eq!(a.puff_states(), before);
    assert!((a.time_s().unwrap() - 130.0).abs() < 1e-9);
    assert!((STEP_S - 1.0 / 60.0).abs() < 1e-15);
}

#[test]
fn an_ig_that_joins_late_or_jumps_in_time_draws_the_same_effects() {
    // IG A steps every frame from the start; IG B joins at 400 s and starts the same effects
    // (started at 0 s and 130.5 s); IG C jumps through time in big strides. All three agree.
    let specs = [
        plume(1, PlumeKind::Smoke, 0.0, 1000.0),
        plume(2, PlumeKind::Flame, 0.0, 1000.0),
        plume(3, PlumeKind::Smoke, 130.5, 1000.0),
    ];
    let dust = trail(4, 0.0, Material::Sand, 10.0);
    let build = || {
        let mut s = EffectSystem::new(small_config()).unwrap();
        s.set_atmosphere(atmosphere(4.0, 300.0, StabilityClass::B))
            .unwrap();
        s
    };
    let mut a = build();
    a.advance_to(0.0).unwrap();
    a.start_plume(&specs[0]).unwrap();
    a.start_plume(&specs[1]).unwrap();
    a.start_dust_trail(&dust).unwrap();
    for f in 1..=24_000u32 {
        let t = f64::from(f) / 60.0;
        if (t - 130.5).abs() < 0.5 / 60.0 {
            a.start_plume(&specs[2]).unwrap();
        }
        a.advance_to(t).unwrap();
    }
    let mut b = build();
    b.advance_to(400.0).unwrap();
    for s in &specs {
        b.start_plume(s).unwrap();
    }
    b.start_dust_trail(&dust).unwrap();
    let mut c = build();
    c.advance_to(0.0).unwrap();
    c.start_plume(&specs[0]).unwrap();
    c.start_plume(&specs[1]).unwrap();
    c.start_dust_trail(&dust).unwrap();
    c.advance_to(130.0).unwrap();
    c.start_plume(&specs[2]).unwrap();
    c.advance_to(400.0).unwrap();
    let sa = a.puff_states();
    assert!(sa.len() > 700, "{}", sa.len());
    same_puffs(&b.puff_states(), &sa);
    same_puffs(&c.puff_states(), &sa);
    // Absurd times are refused, not ground through.
    assert!(b.advance_to(1.0e12).is_err());
}

#[test]
fn the_system_can_be_shared_between_threads() {
    fn shareable<T: Send + Sync>() {}
    shareable::<EffectSystem>();
    shareable::<PuffInstance>();
}
