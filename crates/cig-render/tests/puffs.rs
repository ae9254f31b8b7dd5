//! The obscurant pass on lavapipe (or any GPU): a golden plume over terrain, independence of
//! draw order, optical depths that add as one medium (Beer-Lambert, checked pixel by pixel
//! against an independent CPU integration), soft contact with the ground, drift with the wind
//! in rendered frames, and flames that glow at night.

mod common;

use cig_effects::{
    Atmosphere, EffectId, EffectSystem, EffectsConfig, PlumeKind, PlumeSource, PlumeSpec,
    PuffInstance, StabilityClass, Wind,
};
use cig_geo::{EnuFrame, Geodetic};
use cig_render::Image;
use cig_scene::lighting::{Fog, FogMode};
use cig_scene::FrameSnapshot;
use common::*;
use glam::DVec3;

const SIZE: (u32, u32) = (128, 96);
/// 2026-06-22 07:00 UTC: 23:00 in California, the sun 20 degrees below the horizon.
const NIGHT_UNIX_S: f64 = MORNING_UNIX_S + 12.0 * 3600.0;

/// A point on the sea `east_m`, `north_m` from `eye`.
fn sea_point(eye: Geodetic, east_m: f64, north_m: f64) -> Geodetic {
    let g = EnuFrame::new(eye).enu_to_geodetic(DVec3::new(east_m, north_m, 0.0));
    Geodetic::new(g.lat_deg, g.lon_deg, 0.0)
}

/// An effect system with the wind blowing from `from_deg` at 5 m/s, neutral air.
fn effects(from_deg: f64) -> EffectSystem {
    let mut sys = EffectSystem::new(EffectsConfig {
        plume_slots: 4,
        dust_slots: 1,
        ..Default::default()
    })
    .expect("effect system");
    sys.set_atmosphere(Atmosphere {
        wind: Wind {
            speed_mps: 5.0,
            from_deg,
        },
        stability: StabilityClass::D,
        air_temperature_k: 288.0,
        dtheta_dz_k_per_m: None,
    })
    .expect("atmosphere");
    sys.advance_to(0.0).expect("start");
    sys
}

/// Starts a fire at `at`: a smoke plume when `smoke` and flames when `flame` (5 MW, 3 m
/// across).
fn start_fire(sys: &mut EffectSystem, id: u64, at: Geodetic, smoke: bool, flame: bool) {
    start_fire_of(sys, id, at, smoke, flame, 5.0e6);
}

/// As [`start_fire`] with a heat release, W.
fn start_fire_of(
    sys: &mut EffectSystem,
    id: u64,
    at: Geodetic,
    smoke: bool,
    flame: bool,
    heat_w: f64,
) {
    let kinds = [(PlumeKind::Smoke, smoke), (PlumeKind::Flame, flame)];
    for (k, (kind, wanted)) in kinds.into_iter().enumerate() {
        if wanted {
            sys.start_plume(&PlumeSpec {
                id: EffectId(id * 2 + k as u64),
                kind,
                position: at,
                size_m: 3.0,
                source: PlumeSource::HeatReleaseW(heat_w),
                start_time_s: 0.0,
                duration_s: 1.0e5,
            })
            .expect("plume");
        }
    }
}

/// A frame of one view with the effect system's puffs (relative to the eye).
fn frame_with_puffs(unix_time_s: f64, view: cig_scene::View, sys: &EffectSystem) -> FrameSnapshot {
    let mut snapshot = FrameSnapshot::new(unix_time_s, vec![view]);
    snapshot.puff_origin_ecef_m = view.eye.to_ecef();
    sys.snapshot(snapshot.puff_origin_ecef_m, &mut snapshot.puffs);
    snapshot
}

fn srgb_to_linear(v: u8) -> f64 {
    let c = f64::from(v) / 255.0;
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

fn luminance(px: &[u8]) -> f64 {
    0.2126 * srgb_to_linear(px[0]) + 0.7152 * srgb_to_linear(px[1]) + 0.0722 * srgb_to_linear(px[2])
}

/// Largest difference of any channel of any pixel.
fn max_abs_diff(a: &Image, b: &Image) -> u8 {
    a.rgba
        .iter()
        .zip(&b.rgba)
        .map(|(x, y)| x.abs_diff(*y))
        .max()
        .unwrap_or(0)
}

/// Per pixel: summed absolute channel difference between two images.
fn difference(a: &Image, b: &Image) -> Vec<f64> {
    a.rgba
        .chunks_exact(4)
        .zip(b.rgba.chunks_exact(4))
        .map(|(p, q)| (0..3).map(|c| f64::from(p[c].abs_diff(q[c]))).sum())
        .collect()
}

/// Column of the difference-weighted centroid, and the total weight.
fn centroid_x(weights: &[f64], width: u32) -> (f64, f64) {
    let mut sum = 0.0;
    let mut moment = 0.0;
    for (i, w) in weights.iter().enumerate() {
        let x = (i % width as usize) as f64 + 0.5;
        sum += w;
        moment += w * x;
    }
    (moment / sum.max(1e-9), sum)
}

#[test]
fn a_plume_over_terrain_matches_its_golden_image_and_reports_its_puffs() {
    let db = hills();
    let cache = cache(&db);
    let mut renderer = renderer(&cache);
    let mut sys = effects(270.0);
    // A 20 MW fire 200 m ahead; its smoke drifts east into the hillside.
    let fire = hills_point(-1300.0, -1650.0, 0.0);
    start_fire_of(&mut sys, 1, fire, true, true, 20.0e6);
    sys.advance_to(120.0).expect("advance");
    let eye = hills_point(-1500.0, -1700.0, 40.0);
    let snapshot = frame_with_puffs(
        MORNING_UNIX_S,
        view(eye, (20.0, -4.0, 0.0), 60.0, SIZE),
        &sys,
    );
    assert!(snapshot.puffs.len() > 300, "{} puffs", snapshot.puffs.len());
    let (image, stats) = render(&mut renderer, &cache, &snapshot, false);
    assert!(stats.puffs_drawn > 300, "{} puffs drawn", stats.puffs_drawn);
    check_golden("hills_plume", &image);
    // The same view without the plume differs: the smoke is drawn.
    let mut clear = snapshot.clone();
    clear.puffs.clear();
    let (without, stats) = render(&mut renderer, &cache, &clear, false);
    assert_eq!(stats.puffs_drawn, 0);
    let changed = difference(&image, &without)
        .iter()
        .filter(|&&d| d > 6.0)
        .count();
    assert!(changed > 200, "only {changed} pixels show smoke");
}

#[test]
fn the_image_does_not_depend_on_the_order_the_puffs_are_drawn_in() {
    let db = hills();
    let cache = cache(&db);
    let mut renderer = renderer(&cache);
    let mut sys = effects(250.0);
    // Two fires whose smoke crosses (wind from the west-south-west).
    start_fire_of(
        &mut sys,
        1,
        hills_point(-1300.0, -1650.0, 0.0),
        true,
        true,
        20.0e6,
    );
    start_fire_of(
        &mut sys,
        2,
        hills_point(-1250.0, -1600.0, 0.0),
        true,
        false,
        20.0e6,
    );
    sys.advance_to(90.0).expect("advance");
    let eye = hills_point(-1500.0, -1700.0, 40.0);
    let snapshot = frame_with_puffs(
        MORNING_UNIX_S,
        view(eye, (20.0, -4.0, 0.0), 60.0, SIZE),
        &sys,
    );
    let (forward, _) = render(&mut renderer, &cache, &snapshot, false);
    let mut reversed = snapshot.clone();
    reversed.puffs.reverse();
    let (backward, _) = render(&mut renderer, &cache, &reversed, false);
    // Far to near by distance from the eye, as an alpha-blending renderer must sort them.
    let mut sorted = snapshot.clone();
    sorted.puffs.sort_by(|a, b| {
        let d = |p: &PuffInstance| p.position_eye_m.iter().map(|v| v * v).sum::<f32>();
        d(b).total_cmp(&d(a))
    });
    let (far_to_near, _) = render(&mut renderer, &cache, &sorted, false);
    let mut clear = snapshot.clone();
    clear.puffs.clear();
    let (without, _) = render(&mut renderer, &cache, &clear, false);
    assert!(
        max_abs_diff(&forward, &without) > 40,
        "the plume must be visible for this test to mean anything"
    );
    for (name, other) in [("reversed", &backward), ("sorted", &far_to_near)] {
        let diff = max_abs_diff(&forward, other);
        assert!(diff <= 1, "{name} order changes a pixel by {diff} levels");
    }
}

/// A puff of 40 m radius (placed by the caller).
fn sky_puff(opacity: f32, colour: [f32; 3]) -> PuffInstance {
    PuffInstance {
        position_eye_m: [0.0; 3],
        radius_m: 40.0,
        colour_rgb: colour,
        opacity,
        emissive: 0.0,
        temperature_k: 288.0,
        kind: 0,
        effect: 0,
    }
}

/// A view 2 km above the sea looking north and 10 degrees up (only sky behind), with puffs
/// placed at the given east-north-up offsets from the eye.
fn sky_frame(puffs: &[(DVec3, PuffInstance)]) -> FrameSnapshot {
    let eye = Geodetic::new(36.0, -122.0, 2000.0);
    let enu = EnuFrame::new(eye);
    let mut snapshot = FrameSnapshot::new(
        MORNING_UNIX_S,
        vec![view(eye, (0.0, 10.0, 0.0), 40.0, SIZE)],
    );
    snapshot.fog = Fog::from_visibility(FogMode::Off, 40_000.0);
    snapshot.puff_origin_ecef_m = eye.to_ecef();
    snapshot.puffs = puffs
        .iter()
        .map(|(at, p)| {
            let e = enu.enu_vector_to_ecef(*at);
            PuffInstance {
                position_eye_m: [e.x as f32, e.y as f32, e.z as f32],
                ..*p
            }
        })
        .collect();
    snapshot
}

#[test]
fn coincident_puffs_add_optical_depth_like_one_thicker_puff() {
    let db = sea();
    let cache = cache(&db);
    let mut renderer = renderer(&cache);
    let ahead = DVec3::new(0.0, 400.0, 70.0);
    let grey = [0.5, 0.5, 0.5];
    let half = sky_puff(0.5, grey);
    let two = sky_frame(&[(ahead, half), (ahead, half)]);
    // exp(-(tau + tau)) = (1 - 0.5)^2: one puff of opacity 0.75.
    let one = sky_frame(&[(ahead, sky_puff(0.75, grey))]);
    let single = sky_frame(&[(ahead, half)]);
    let (two_image, stats) = render(&mut renderer, &cache, &two, false);
    assert_eq!(stats.puffs_drawn, 2);
    let (one_image, _) = render(&mut renderer, &cache, &one, false);
    let (single_image, _) = render(&mut renderer, &cache, &single, false);
    let diff = max_abs_diff(&two_image, &one_image);
    assert!(
        diff <= 1,
        "two half puffs differ from their sum by {diff} levels"
    );
    assert!(
        max_abs_diff(&two_image, &single_image) > 10,
        "the second puff must add optical depth"
    );
}

#[test]
fn puffs_with_impossible_values_are_left_out_without_harming_the_frame() {
    let db = sea();
    let cache = cache(&db);
    let mut renderer = renderer(&cache);
    let ahead = DVec3::new(0.0, 400.0, 70.0);
    let good = sky_puff(0.6, [0.5, 0.5, 0.5]);
    let clean = sky_frame(&[(ahead, good)]);
    let mut bad = sky_frame(&[(ahead, good)]);
    let template = bad.puffs[0];
    for broken in [
        PuffInstance {
            position_eye_m: [f32::NAN, 0.0, 0.0],
            ..template
        },
        PuffInstance {
            radius_m: -3.0,
            ..template
        },
        PuffInstance {
            radius_m: f32::INFINITY,
            ..template
        },
        PuffInstance {
            opacity: f32::NAN,
            ..template
        },
        PuffInstance {
            opacity: -0.5,
            ..template
        },
    ] {
        bad.puffs.push(broken);
    }
    // A colour or glow out of range is clamped, not propagated into the frame as NaN.
    let mut odd = sky_frame(&[(ahead, good)]);
    odd.puffs[0].colour_rgb = [f32::NAN, 0.5, 7.0];
    odd.puffs[0].emissive = f32::NAN;
    let (clean_image, _) = render(&mut renderer, &cache, &clean, false);
    let (bad_image, stats) = render(&mut renderer, &cache, &bad, false);
    assert_eq!(stats.puffs_drawn, 1);
    assert!(max_abs_diff(&clean_image, &bad_image) <= 1);
    let (odd_image, stats) = render(&mut renderer, &cache, &odd, false);
    assert_eq!(stats.puffs_drawn, 1);
    let mut expected = clean.clone();
    expected.puffs[0].colour_rgb = [0.0, 0.5, 1.0];
    expected.puffs[0].emissive = 0.0;
    let (expected_image, _) = render(&mut renderer, &cache, &expected, false);
    assert!(max_abs_diff(&odd_image, &expected_image) <= 1);
    // Puffs relative to an origin far from the eye land where puffs relative to the eye do.
    let mut shifted = clean.clone();
    let far = glam::DVec3::new(3.0e5, -2.0e5, 1.0e5);
    shifted.puff_origin_ecef_m += far;
    for p in &mut shifted.puffs {
        let moved = DVec3::from(p.position_eye_m.map(f64::from)) - far;
        p.position_eye_m = [moved.x as f32, moved.y as f32, moved.z as f32];
    }
    let (shifted_image, _) = render(&mut renderer, &cache, &shifted, false);
    assert!(max_abs_diff(&clean_image, &shifted_image) <= 2);
}

/// Optical depth along a ray (unit `dir` from the eye) through puffs, the renderer's model
/// integrated independently in f64: Gaussian columns windowed to zero at the radius.
fn expected_optical_depth(puffs: &[PuffInstance], dir: DVec3) -> f64 {
    let edge = (-0.5f64 * 2.5 * 2.5).exp();
    puffs
        .iter()
        .map(|p| {
            let c = DVec3::from(p.position_eye_m.map(f64::from));
            let sigma = f64::from(p.radius_m) / 2.5;
            let s0 = c.dot(dir);
            let b2 = (c.length_squared() - s0 * s0).max(0.0);
            let window = (((-0.5 * b2 / (sigma * sigma)).exp() - edge) / (1.0 - edge)).max(0.0);
            let tau_c = -(1.0 - f64::from(p.opacity).min(0.9999)).ln();
            // The part of the column in front of the eye: Phi(s0 / sigma).
            let in_front = 0.5 * (1.0 + libm::erf(s0 / (sigma * std::f64::consts::SQRT_2)));
            tau_c.min(9.21) * window * in_front
        })
        .sum()
}

#[test]
fn a_plume_is_as_transparent_as_beer_lambert_says_and_no_darker_where_puffs_overlap() {
    let db = sea();
    let cache = cache(&db);
    let mut renderer = renderer(&cache);
    // A smoke plume 1.5 km north of an eye 20 m above the sea, seen against the sky (keyed
    // magenta, linear red 1), its puffs made black so the red channel is the transmittance.
    let eye = Geodetic::new(36.0, -122.0, 20.0);
    let mut sys = effects(270.0);
    start_fire(&mut sys, 1, sea_point(eye, -80.0, 350.0), true, false);
    sys.advance_to(100.0).expect("advance");
    let v = view(eye, (0.0, 5.0, 0.0), 50.0, SIZE);
    let mut snapshot = frame_with_puffs(MORNING_UNIX_S, v, &sys);
    snapshot.fog = Fog::from_visibility(FogMode::Off, 40_000.0);
    for p in &mut snapshot.puffs {
        p.colour_rgb = [0.0; 3];
        p.emissive = 0.0;
    }
    let mut clear = snapshot.clone();
    clear.puffs.clear();
    let (background, _) = render(&mut renderer, &cache, &clear, true);
    let (image, stats) = render(&mut renderer, &cache, &snapshot, true);
    write_png(&image, &out_dir().join("plume_transmittance.png"));
    assert!(stats.puffs_drawn > 200);
    let camera = v.camera();
    let [tl, tr, td, tu] = v.fov.tangents();
    let (mut compared, mut overlapped, mut worst) = (0, 0, 0.0f64);
    for (i, (px, behind)) in image
        .rgba
        .chunks_exact(4)
        .zip(background.rgba.chunks_exact(4))
        .enumerate()
    {
        // Only rays that see the sky (the key colour) behind the plume.
        if !is_key(behind) {
            continue;
        }
        let (x, y) = ((i % SIZE.0 as usize) as f64, (i / SIZE.0 as usize) as f64);
        let x_tan = -tl + (x + 0.5) / f64::from(SIZE.0) * (tl + tr);
        let y_tan = tu - (y + 0.5) / f64::from(SIZE.1) * (td + tu);
        let dir = (camera.forward + camera.right * x_tan + camera.up * y_tan).normalize();
        let tau = expected_optical_depth(&snapshot.puffs, dir);
        let covering = snapshot
            .puffs
            .iter()
            .filter(|p| {
                let c = DVec3::from(p.position_eye_m.map(f64::from));
                let s0 = c.dot(dir);
                c.length_squared() - s0 * s0 < f64::from(p.radius_m).powi(2) && s0 > 0.0
            })
            .count();
        let rendered = srgb_to_linear(px[0]);
        let expected = (-tau).exp();
        let error = rendered - expected;
        worst = worst.max(error.abs());
        // Never darker than the physics (beyond half-float sums and 8-bit steps), never lighter.
        assert!(
            error.abs() < 0.03,
            "pixel ({x}, {y}) under {covering} puffs: transmittance {rendered:.3}, Beer-Lambert {expected:.3}"
        );
        compared += 1;
        if covering >= 3 && tau > 0.1 {
            overlapped += 1;
        }
    }
    assert!(
        overlapped > 100,
        "only {overlapped} pixels with overlapping puffs"
    );
    assert!(compared > 1000, "{compared} pixels compared");
    eprintln!("worst transmittance error {worst:.4} over {compared} pixels");
}

#[test]
fn puffs_fade_softly_into_the_ground_with_no_intersection_line() {
    let db = sea();
    let cache = cache(&db);
    let mut renderer = renderer(&cache);
    if renderer.gpu().info.backend == wgpu::Backend::Gl {
        eprintln!("SKIPPED: wgpu's GL backend cannot sample multisampled depth; its fallback depth-tests puffs (no soft contact)");
        return;
    }
    // A thick white puff of 60 m radius centred on the sea surface, seen from 300 m up looking
    // 35 degrees down at it: a depth test against a billboard through its centre would cut it
    // along a straight line through the middle.
    let eye = Geodetic::new(36.0, -122.0, 300.0);
    let enu = EnuFrame::new(eye);
    let ahead_m = 300.0 / 35f64.to_radians().tan();
    let v = view(eye, (0.0, -35.0, 0.0), 40.0, SIZE);
    let mut snapshot = FrameSnapshot::new(MORNING_UNIX_S, vec![v]);
    snapshot.puff_origin_ecef_m = eye.to_ecef();
    let centre = enu.enu_vector_to_ecef(DVec3::new(0.0, ahead_m, -300.0));
    snapshot.puffs = vec![PuffInstance {
        position_eye_m: [centre.x as f32, centre.y as f32, centre.z as f32],
        radius_m: 60.0,
        ..sky_puff(0.98, [0.9, 0.9, 0.9])
    }];
    let (image, _) = render(&mut renderer, &cache, &snapshot, false);
    let mut clear = snapshot.clone();
    clear.puffs.clear();
    let (without, _) = render(&mut renderer, &cache, &clear, false);
    write_png(&image, &out_dir().join("puff_on_water.png"));
    let d = difference(&image, &without);
    let (w, h) = (SIZE.0 as usize, SIZE.1 as usize);
    let contrast = d.iter().copied().fold(0.0, f64::max);
    assert!(contrast > 150.0, "the puff must stand out ({contrast})");
    // Largest change of the puff's contribution from one row to the next.
    let mut jump = 0.0f64;
    for y in 1..h {
        for x in 0..w {
            jump = jump.max((d[y * w + x] - d[(y - 1) * w + x]).abs());
        }
    }
    // (The filmic tone curve steepens mid-tones against the saturating puff centre: a hard
    // line would still be a step of half the contrast.)
    assert!(
        jump < 0.25 * contrast,
        "a step of {jump} (of {contrast}) between rows: a hard line"
    );
    // The half in front of the centre still shows, fading toward the eye.
    let (_, centre_row) = v
        .camera()
        .project_ecef(eye.to_ecef() + centre)
        .expect("in front");
    let lowest = (0..h)
        .rev()
        .find(|&y| (0..w).any(|x| d[y * w + x] > 0.1 * contrast))
        .expect("puff rows");
    assert!(
        lowest as f64 > centre_row + 3.0,
        "nothing of the puff below its centre row {centre_row:.1} (lowest {lowest})"
    );
}

#[test]
fn smoke_drifts_downwind_in_rendered_frames() {
    let db = sea();
    let cache = cache(&db);
    let mut renderer = renderer(&cache);
    // Wind from the west; looking north from 20 m above the sea, east is to the right.
    let mut sys = effects(270.0);
    let eye = Geodetic::new(36.0, -122.0, 20.0);
    start_fire(&mut sys, 3, sea_point(eye, -60.0, 350.0), true, false);
    let v = view(eye, (0.0, 2.0, 0.0), 60.0, SIZE);
    let clear = FrameSnapshot::new(MORNING_UNIX_S, vec![v]);
    let (without, _) = render(&mut renderer, &cache, &clear, false);
    let mut centroids = Vec::new();
    for t in [20.0, 80.0] {
        sys.advance_to(t).expect("advance");
        // The same sun in both frames: only the smoke changes.
        let snapshot = frame_with_puffs(MORNING_UNIX_S, v, &sys);
        let (image, _) = render(&mut renderer, &cache, &snapshot, false);
        write_png(&image, &out_dir().join(format!("drift_{t}.png")));
        let (x, weight) = centroid_x(&difference(&image, &without), SIZE.0);
        assert!(weight > 500.0, "no smoke in the frame at {t} s");
        centroids.push(x);
    }
    assert!(
        centroids[1] > centroids[0] + 3.0,
        "smoke centroid moved from column {:.1} to {:.1}",
        centroids[0],
        centroids[1]
    );
}

#[test]
fn flames_glow_at_night_and_smoke_does_not() {
    let db = sea();
    let cache = cache(&db);
    let mut renderer = renderer(&cache);
    let mut sys = effects(270.0);
    // Looking north from 5 m above the sea: flames to the left, a smoke plume (drifting east)
    // to the right, 60 m ahead.
    let eye = Geodetic::new(36.0, -122.0, 5.0);
    start_fire(&mut sys, 1, sea_point(eye, -15.0, 60.0), false, true);
    start_fire(&mut sys, 2, sea_point(eye, 8.0, 60.0), true, false);
    sys.advance_to(60.0).expect("advance");
    let v = view(eye, (0.0, 2.0, 0.0), 60.0, SIZE);
    let snapshot = frame_with_puffs(NIGHT_UNIX_S, v, &sys);
    let (image, _) = render(&mut renderer, &cache, &snapshot, false);
    write_png(&image, &out_dir().join("night_fire.png"));
    // The night itself is exposed to be readable: compare with the same frame without puffs.
    let mut clear = snapshot.clone();
    clear.puffs.clear();
    let (background, _) = render(&mut renderer, &cache, &clear, false);
    let half = SIZE.0 as usize / 2;
    let (mut flame_max, mut smoke_max) = (0.0f64, 0.0f64);
    for (i, (px, behind)) in image
        .rgba
        .chunks_exact(4)
        .zip(background.rgba.chunks_exact(4))
        .enumerate()
    {
        // How much brighter the puffs make the pixel.
        let l = luminance(px) - luminance(behind);
        if i % SIZE.0 as usize <= half {
            flame_max = flame_max.max(l);
        } else {
            smoke_max = smoke_max.max(l);
        }
    }
    assert!(
        flame_max > 0.5,
        "the flame is dark at night ({flame_max:.3})"
    );
    assert!(
        smoke_max < 0.05,
        "the smoke glows at night ({smoke_max:.3})"
    );
}
