//! Lightning and precipitation on lavapipe (or any GPU), by comparison within each test (the
//! sky and the exposure may change under them): a bolt's pixels lie where its line projects,
//! a flash brightens the frame, rain adds streaks and snow flakes near the eye, and the
//! particles are a function of the time.

mod common;

use cig_environment::{Precipitation, PrecipitationKind};
use cig_geo::{EnuFrame, Geodetic};
use cig_render::Image;
use cig_scene::{BoltDraw, BoltLine, FrameSnapshot, PrecipitationDraw};
use common::*;
use glam::DVec3;
use std::sync::Arc;

const SIZE: (u32, u32) = (160, 120);
/// 2026-06-22 07:00 UTC: night in California.
const NIGHT_UNIX_S: f64 = MORNING_UNIX_S + 12.0 * 3600.0;

fn eye() -> Geodetic {
    Geodetic::new(36.0, -122.0, 10.0)
}

/// A frame over the sea looking north, level.
fn frame(unix_time_s: f64) -> FrameSnapshot {
    FrameSnapshot::new(unix_time_s, vec![view(eye(), (0.0, 0.0, 0.0), 60.0, SIZE)])
}

fn luminance_sum(image: &Image) -> f64 {
    image
        .rgba
        .chunks_exact(4)
        .map(|p| f64::from(p[0]) + f64::from(p[1]) + f64::from(p[2]))
        .sum()
}

/// Pixels whose colour changed by more than `threshold` (sum of channels), as (x, y).
fn changed(a: &Image, b: &Image, threshold: i32) -> Vec<(u32, u32)> {
    let mut out = Vec::new();
    for (i, (p, q)) in a
        .rgba
        .chunks_exact(4)
        .zip(b.rgba.chunks_exact(4))
        .enumerate()
    {
        let d: i32 = (0..3)
            .map(|c| (i32::from(p[c]) - i32::from(q[c])).abs())
            .sum();
        if d > threshold {
            out.push((i as u32 % a.width, i as u32 / a.width));
        }
    }
    out
}

/// A straight vertical bolt from the sea to 1500 m, `north_m` ahead of the eye.
fn straight_bolt(north_m: f64, intensity: f32) -> BoltDraw {
    let frame = EnuFrame::new(eye());
    let ground = frame.enu_to_geodetic(DVec3::new(0.0, north_m, -10.0));
    let up = EnuFrame::new(ground).enu_vector_to_ecef(DVec3::new(0.0, 0.0, 1500.0));
    BoltDraw {
        origin_ecef_m: ground.to_ecef(),
        lines: Arc::from(vec![BoltLine {
            start_m: [up.x as f32, up.y as f32, up.z as f32],
            end_m: [0.0, 0.0, 0.0],
            brightness: 1.0,
        }]),
        intensity,
    }
}

#[test]
fn a_bolt_is_drawn_where_its_line_projects() {
    let db = sea();
    let cache = cache(&db);
    let mut renderer = renderer(&cache);
    let plain = frame(NIGHT_UNIX_S);
    let mut lit = plain.clone();
    lit.bolts = vec![straight_bolt(5000.0, 1.0)];
    let (before, _) = render(&mut renderer, &cache, &plain, false);
    let (after, stats) = render(&mut renderer, &cache, &lit, false);
    write_png(&after, &out_dir().join("bolt.png"));
    assert_eq!(stats.bolt_lines_drawn, 1);
    let pixels = changed(&before, &after, 60);
    // The line stands straight ahead: the middle column, from the horizon up.
    assert!(pixels.len() >= 30, "{} pixels", pixels.len());
    let centre = SIZE.0 / 2;
    for (x, _) in &pixels {
        assert!(x.abs_diff(centre) <= 3, "a bolt pixel at column {x}");
    }
    // It reaches from the sea up: pixels above and at the horizon row.
    let rows: Vec<u32> = pixels.iter().map(|p| p.1).collect();
    let (top, bottom) = (rows.iter().min().copied(), rows.iter().max().copied());
    assert!(top.is_some_and(|t| t < SIZE.1 / 2 - 10), "{top:?}");
    assert!(bottom.is_some_and(|b| b >= SIZE.1 / 2 - 2), "{bottom:?}");
    // A bolt behind the eye draws nothing.
    let mut behind = plain.clone();
    behind.bolts = vec![straight_bolt(-5000.0, 1.0)];
    let (back, _) = render(&mut renderer, &cache, &behind, false);
    assert!(changed(&before, &back, 10).is_empty());
}

#[test]
fn a_flash_brightens_the_frame_and_fades() {
    let db = sea();
    let cache = cache(&db);
    let mut renderer = renderer(&cache);
    let plain = frame(NIGHT_UNIX_S);
    // Large enough to show at today's fixed exposure and at a night exposure alike.
    let mut flash = plain.clone();
    flash.flash_lux = 20_000.0;
    let mut fading = plain.clone();
    fading.flash_lux = 4_000.0;
    let (dark, _) = render(&mut renderer, &cache, &plain, false);
    let (bright, _) = render(&mut renderer, &cache, &flash, false);
    let (dimmer, _) = render(&mut renderer, &cache, &fading, false);
    let (d, b, m) = (
        luminance_sum(&dark),
        luminance_sum(&bright),
        luminance_sum(&dimmer),
    );
    assert!(b > d * 1.2, "flash {b} vs night {d}");
    assert!(m > d && m <= b, "fading {m} between {d} and {b}");
}

fn rainy(kind: PrecipitationKind, rate: f64, unix_time_s: f64) -> FrameSnapshot {
    let mut s = frame(unix_time_s);
    // Looking down a little so the sea fills most of the frame behind the particles.
    s.views[0].orientation.pitch_deg = -10.0;
    s.precipitation = Some(PrecipitationDraw {
        precipitation: Precipitation::new(kind, rate).expect("rate"),
        wind_en_mps: [2.0, 0.0],
        seed: 3,
    });
    s
}

#[test]
fn rain_adds_streaks_and_snow_adds_flakes_near_the_eye() {
    let db = sea();
    let cache = cache(&db);
    let mut renderer = renderer(&cache);
    let t = MORNING_UNIX_S;
    let mut dry = rainy(PrecipitationKind::Rain, 10.0, t);
    dry.precipitation = None;
    let (clear, none_stats) = render(&mut renderer, &cache, &dry, false);
    assert_eq!(none_stats.precipitation_particles, 0);
    let (rain, rain_stats) = render(
        &mut renderer,
        &cache,
        &rainy(PrecipitationKind::Rain, 10.0, t),
        false,
    );
    let (light, _) = render(
        &mut renderer,
        &cache,
        &rainy(PrecipitationKind::Rain, 1.0, t),
        false,
    );
    let (snow, snow_stats) = render(
        &mut renderer,
        &cache,
        &rainy(PrecipitationKind::Snow, 2.0, t),
        false,
    );
    write_png(&rain, &out_dir().join("rain.png"));
    write_png(&snow, &out_dir().join("snow.png"));
    assert!(rain_stats.precipitation_particles > 1000);
    assert!(snow_stats.precipitation_particles > 1000);
    let rain_px = changed(&clear, &rain, 6).len();
    let light_px = changed(&clear, &light, 6).len();
    let snow_px = changed(&clear, &snow, 6).len();
    let total = (SIZE.0 * SIZE.1) as usize;
    assert!(rain_px > total / 100, "rain changed {rain_px} pixels");
    assert!(light_px < rain_px, "light rain {light_px} vs {rain_px}");
    assert!(snow_px > total / 100, "snow changed {snow_px} pixels");
    // Snow is white flakes: brighter than the sea behind it on the whole.
    assert!(luminance_sum(&snow) > luminance_sum(&clear));
    // The same time draws the same particles; a moment later they have fallen.
    let (again, _) = render(
        &mut renderer,
        &cache,
        &rainy(PrecipitationKind::Rain, 10.0, t),
        false,
    );
    assert_eq!(again.rgba, rain.rgba);
    let (later, _) = render(
        &mut renderer,
        &cache,
        &rainy(PrecipitationKind::Rain, 10.0, t + 0.05),
        false,
    );
    assert!(!changed(&rain, &later, 6).is_empty());
}
