//! The night-vision channel on lavapipe (or any GPU): the automatic brightness control holds a
//! quarter moon and a full moon alike, starlight scintillates, grass outshines a road on
//! goggles while it is darker to the eye, a flash washes the picture out and the control pulls
//! it back, daylight saturates the tube, and a light's halo keeps its angular size.

mod common;

use cig_geo::Geodetic;
use cig_render::{Adaptation, Image};
use cig_scene::nvg::{NvgView, Phosphor};
use cig_scene::FrameSnapshot;
use cig_terrain::raster::{GeoGrid, Raster};
use cig_terrain::Material;
use common::*;
use std::sync::Arc;

const SIZE: (u32, u32) = (160, 120);
/// 2026-06-29 07:30 UTC: a full moon 25 degrees up over the hills.
const FULL_MOON: (i32, u32, u32, f64) = (2026, 6, 29, 7.5);
/// 2026-06-22 05:00 UTC: a moon a little past first quarter (55 % lit) 33 degrees up.
const QUARTER_MOON: (i32, u32, u32, f64) = (2026, 6, 22, 5.0);
/// 2026-06-15 07:30 UTC: no moon (26 degrees below the horizon), the sun 25 below.
const MOONLESS: (i32, u32, u32, f64) = (2026, 6, 15, 7.5);

fn at((y, m, d, h): (i32, u32, u32, f64)) -> f64 {
    unix(y, m, d, h)
}

fn quiet_goggle() -> NvgView {
    NvgView {
        noise: false,
        ..NvgView::default()
    }
}

/// The hills seen from 30 m up, looking north and down a little, through a goggle.
fn hills_frame(unix_s: f64, nvg: Option<NvgView>) -> FrameSnapshot {
    let eye = hills_point(-400.0, 0.0, 30.0);
    let mut snapshot = FrameSnapshot::new(unix_s, vec![view(eye, (0.0, -8.0, 0.0), 50.0, SIZE)]);
    snapshot.culture = false;
    snapshot.nvg = vec![nvg];
    snapshot
}

/// The RGB of each pixel within `radius_px` of the frame's centre.
fn pixels_within(image: &Image, radius_px: f64) -> impl Iterator<Item = &[u8]> + '_ {
    let (w, h) = (f64::from(image.width), f64::from(image.height));
    image.rgba.chunks(4).enumerate().filter_map(move |(i, px)| {
        let dx = (i as u32 % image.width) as f64 + 0.5 - 0.5 * w;
        let dy = (i as u32 / image.width) as f64 + 0.5 - 0.5 * h;
        (dx * dx + dy * dy < radius_px * radius_px).then_some(&px[..3])
    })
}

/// The green channel's mean (0..255) over the pixels inside the goggle's circle, away from its
/// edge.
fn mean_inside(image: &Image, nvg: &NvgView, fov_deg: f64) -> f64 {
    let ppt = 0.5 * f64::from(image.width) / (0.5 * fov_deg).to_radians().tan();
    let radius_px = 0.9 * ppt * (0.5 * f64::from(nvg.fov_deg)).to_radians().tan();
    let (sum, n) = pixels_within(image, radius_px)
        .fold((0.0, 0.0), |(s, n), px| (s + f64::from(px[1]), n + 1.0));
    sum / f64::max(n, 1.0)
}

/// Share of the pixels inside the circle whose brightest channel is at least `level`.
fn share_at_least(image: &Image, level: u8) -> f64 {
    let (hits, n) =
        pixels_within(image, 0.3 * f64::from(image.width)).fold((0.0, 0.0), |(hits, n), px| {
            let bright = px.iter().max().copied().unwrap_or(0) >= level;
            (hits + f64::from(u8::from(bright)), n + 1.0)
        });
    hits / f64::max(n, 1.0)
}

#[test]
fn the_brightness_control_holds_a_quarter_moon_and_a_full_moon_alike() {
    let db = hills();
    let cache = cache(&db);
    let mut renderer = renderer(&cache);
    let nvg = quiet_goggle();
    let mut means = Vec::new();
    for time in [FULL_MOON, QUARTER_MOON] {
        let snapshot = hills_frame(at(time), Some(nvg));
        let (image, stats) =
            render_adapted(&mut renderer, &cache, &snapshot, false, Adaptation::Settled);
        means.push((mean_inside(&image, &nvg, 50.0), stats.illuminance_lux));
        write_png(&image, &out_dir().join(format!("nvg_moon_{}.png", time.2)));
    }
    let (full, quarter) = (means[0].0, means[1].0);
    assert!(full > 40.0 && quarter > 40.0, "{means:?}");
    assert!(
        (full - quarter).abs() <= 0.25 * full.max(quarter),
        "full moon {full:.1}, quarter moon {quarter:.1}: {means:?}"
    );
    // The scene's light differs by far more than the picture does (nearly three times in
    // the goggle's weighting, where the night sky's airglow adds to both).
    assert!(means[0].1 > 2.5 * means[1].1, "{means:?}");
}

/// The mean temporal standard deviation (green, 0..255) of the pixels of the central square
/// over `frames` frames.
fn temporal_noise(
    renderer: &mut cig_render::Renderer,
    cache: &cig_terrain::TileCache,
    snapshot: &FrameSnapshot,
    frames: usize,
) -> (f64, f64) {
    let mut stack: Vec<Image> = Vec::new();
    for _ in 0..frames {
        let (image, _) = render_adapted(renderer, cache, snapshot, false, Adaptation::Settled);
        stack.push(image);
    }
    let (w, h) = (SIZE.0 as usize, SIZE.1 as usize);
    let mut var_sum = 0.0;
    let mut mean_sum = 0.0;
    let mut n: f64 = 0.0;
    for y in h / 2..h / 2 + 24 {
        for x in w / 2 - 24..w / 2 + 24 {
            let values: Vec<f64> = stack
                .iter()
                .map(|im| f64::from(im.rgba[(y * w + x) * 4 + 1]))
                .collect();
            let mean = values.iter().sum::<f64>() / values.len() as f64;
            let var =
                values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (values.len() - 1) as f64;
            var_sum += var;
            mean_sum += mean;
            n += 1.0;
        }
    }
    ((var_sum / n).sqrt(), mean_sum / n)
}

#[test]
fn overcast_starlight_scintillates_and_a_full_moon_is_smooth() {
    let db = hills();
    let cache = cache(&db);
    let mut renderer = renderer(&cache);
    let nvg = NvgView::default();
    let moon = hills_frame(at(FULL_MOON), Some(nvg));
    let mut overcast = hills_frame(at(MOONLESS), Some(nvg));
    overcast.cloud_cover_fraction = 1.0;
    let (moon_noise, moon_mean) = temporal_noise(&mut renderer, &cache, &moon, 4);
    let (star_noise, star_mean) = temporal_noise(&mut renderer, &cache, &overcast, 4);
    assert!(
        star_noise >= 2.0 * moon_noise,
        "overcast starlight noise {star_noise:.2} (mean {star_mean:.1}), full moon {moon_noise:.2} (mean {moon_mean:.1})"
    );
    // Never a fixed pattern: the full moon's picture still moves a little from frame to frame.
    assert!(moon_noise > 0.2, "{moon_noise}");
}

/// A flat square of grass beside a flat square of paved road.
fn grass_and_road() -> Arc<cig_terrain::TerrainDatabase> {
    let (n, e) = cig_geo::metres_per_degree(36.0);
    let posts = 65;
    let grid = GeoGrid {
        south_lat_deg: 36.0,
        west_lon_deg: -121.0,
        dlat_deg: 30.0 / n,
        dlon_deg: 30.0 / e,
        rows: posts,
        cols: posts,
    };
    let material = (0..posts * posts)
        .map(|i| {
            if i % posts < posts / 2 {
                Material::Grass
            } else {
                Material::PavedRoad
            }
        })
        .collect();
    let raster = Raster {
        grid,
        elevation_m: vec![100.0; posts * posts],
        material: Some(material),
    };
    database_from(&raster, 0.0)
}

#[test]
fn grass_outshines_a_paved_road_on_goggles_but_not_to_the_eye() {
    let db = grass_and_road();
    let cache = cache(&db);
    let mut renderer = renderer(&cache);
    let (n, e) = cig_geo::metres_per_degree(36.0);
    // Above the border between them (grass west, road east), looking straight down.
    let eye = Geodetic::new(36.0 + 960.0 / n, -121.0 + 960.0 / e, 100.0 + 33.0 + 250.0);
    let mut means = Vec::new();
    for nvg in [None, Some(quiet_goggle())] {
        let mut snapshot = FrameSnapshot::new(
            at(FULL_MOON),
            vec![view(eye, (0.0, -90.0, 0.0), 30.0, SIZE)],
        );
        snapshot.culture = false;
        snapshot.nvg = vec![nvg];
        let (image, _) = render(&mut renderer, &cache, &snapshot, false);
        write_png(
            &image,
            &out_dir().join(format!("nvg_grass_road_{}.png", nvg.is_some())),
        );
        // Left and right quarters of the central band: grass and road.
        let band = |x0: u32, x1: u32| {
            let mut sum = 0.0;
            let mut count = 0.0;
            for y in 50..70 {
                for x in x0..x1 {
                    let i = ((y * SIZE.0 + x) * 4) as usize;
                    sum += image.rgba[i..i + 3]
                        .iter()
                        .map(|c| f64::from(*c))
                        .sum::<f64>();
                    count += 3.0;
                }
            }
            sum / count
        };
        means.push((band(50, 70), band(90, 110)));
    }
    let (eye_grass, eye_road) = means[0];
    let (nvg_grass, nvg_road) = means[1];
    assert!(
        eye_grass < eye_road,
        "to the eye: grass {eye_grass:.1}, road {eye_road:.1}"
    );
    assert!(
        nvg_grass > 1.3 * nvg_road,
        "on goggles: grass {nvg_grass:.1}, road {nvg_road:.1}"
    );
}

#[test]
fn a_flash_washes_the_goggles_out_and_the_control_pulls_them_back() {
    let db = hills();
    let cache = cache(&db);
    let mut renderer = renderer(&cache);
    let nvg = quiet_goggle();
    let tau_s = nvg.tube.abc_tau_s;
    let dt = 1.0 / 60.0;
    let mut snapshot = hills_frame(at(QUARTER_MOON), Some(nvg));
    let step = |renderer: &mut cig_render::Renderer, snapshot: &FrameSnapshot, adaptation| {
        render_adapted(renderer, &cache, snapshot, false, adaptation).0
    };
    let before = step(&mut renderer, &snapshot, Adaptation::Settled);
    let before_mean = mean_inside(&before, &nvg, 50.0);
    // A lightning flash of 5 lux for 0.2 s (two time constants).
    snapshot.flash_lux = 5.0;
    let first = step(&mut renderer, &snapshot, Adaptation::Step(dt as f32));
    let washed = share_at_least(&first, 235);
    for _ in 1..12 {
        step(&mut renderer, &snapshot, Adaptation::Step(dt as f32));
    }
    snapshot.flash_lux = 0.0;
    let after = step(&mut renderer, &snapshot, Adaptation::Step(dt as f32));
    let after_mean = mean_inside(&after, &nvg, 50.0);
    // Five time constants later the picture is back.
    let frames = (5.0 * tau_s / dt).ceil() as usize;
    let mut last = after;
    for _ in 0..frames {
        last = step(&mut renderer, &snapshot, Adaptation::Step(dt as f32));
    }
    let recovered = mean_inside(&last, &nvg, 50.0);
    write_png(&first, &out_dir().join("nvg_flash.png"));
    assert!(
        washed > 0.8,
        "{washed:.2} of the pixels near saturation in the flash"
    );
    assert!(
        after_mean < 0.7 * before_mean,
        "just after the flash {after_mean:.1}, before {before_mean:.1}"
    );
    assert!(
        (recovered - before_mean).abs() < 0.15 * before_mean,
        "{:.2} s after the flash {recovered:.1}, before {before_mean:.1}",
        frames as f64 * dt
    );
}

#[test]
fn daylight_saturates_the_goggles() {
    let db = hills();
    let cache = cache(&db);
    let mut renderer = renderer(&cache);
    let nvg = NvgView {
        phosphor: Phosphor::White,
        ..quiet_goggle()
    };
    let snapshot = hills_frame(MORNING_UNIX_S + 4.0 * 3600.0, Some(nvg));
    let (image, _) = render_adapted(&mut renderer, &cache, &snapshot, false, Adaptation::Settled);
    write_png(&image, &out_dir().join("nvg_noon.png"));
    let saturated = share_at_least(&image, 235);
    assert!(
        saturated > 0.9,
        "{saturated:.2} of the pixels saturated at noon"
    );
}

/// A lamp of `candela` at `agl_m` above the hills `north_m` north of their reference.
fn lamp(north_m: f64, agl_m: f64, candela: f32) -> cig_scene::lights::LightPoint {
    cig_scene::lights::omni_lamp(
        hills_point(north_m, 0.0, agl_m),
        candela,
        cig_scene::lights::named_lamp("warm").expect("warm"),
    )
    .expect("lamp")
}

/// The run of pixels, along the row through the frame's brightest pixels (the light), brighter
/// by 8 levels than the background a quarter of the width to the side (the halo is a flat
/// disc well above it; its core is far brighter still).
fn bright_run(image: &Image) -> usize {
    let green = |x: u32, y: u32| u16::from(image.rgba[((y * image.width + x) * 4 + 1) as usize]);
    // The centroid of the brightest pixels (a saturated disc has many).
    let max = (0..image.height)
        .flat_map(|y| (0..image.width).map(move |x| (x, y)))
        .map(|(x, y)| green(x, y))
        .max()
        .unwrap_or(0);
    let (mut sx, mut sy, mut n) = (0u64, 0u64, 0u64);
    for y in 0..image.height {
        for x in 0..image.width {
            if green(x, y) + 2 >= max {
                (sx, sy, n) = (sx + u64::from(x), sy + u64::from(y), n + 1);
            }
        }
    }
    let (bx, by) = ((sx / n.max(1)) as u32, (sy / n.max(1)) as u32);
    let side = if bx > image.width / 2 {
        bx - image.width / 4
    } else {
        bx + image.width / 4
    };
    let half = green(side, by) + 8;
    let right = (bx..image.width)
        .take_while(|x| green(*x, by) > half)
        .count();
    let left = (0..bx).rev().take_while(|x| green(*x, by) > half).count();
    left + right
}

#[test]
fn a_halo_keeps_its_angular_size_at_any_field_of_view() {
    let db = hills();
    let cache = cache(&db);
    let mut renderer = renderer(&cache);
    let nvg = quiet_goggle();
    // A 1000 cd lamp 300 m ahead, at the eye's height, on a moonless night.
    let eye = hills_point(-300.0, 0.0, 40.0);
    let light = lamp(0.0, 40.0, 1000.0);
    let d = (light.position_ecef_m - eye.to_ecef()).length();
    let nvg_lxa = 1000.0 / (d * d) * cig_environment::LightSpectrum::Incandescent.nvg_per_lux();
    let expected_deg = cig_scene::nvg::halo_diameter_deg(nvg_lxa);
    for fov_deg in [20.0, 36.0] {
        let pitch = (cig_geo::EnuFrame::new(eye)
            .geodetic_to_enu(cig_geo::Geodetic::from_ecef(light.position_ecef_m)))
        .z
        .atan2(d)
        .to_degrees();
        let mut snapshot = FrameSnapshot::new(
            at(MOONLESS),
            vec![view(eye, (0.0, pitch, 0.0), fov_deg, (320, 240))],
        );
        snapshot.culture = false;
        snapshot.nvg = vec![Some(nvg)];
        snapshot.lights = vec![light];
        let (image, stats) =
            render_adapted(&mut renderer, &cache, &snapshot, false, Adaptation::Settled);
        write_png(&image, &out_dir().join(format!("nvg_halo_{fov_deg}.png")));
        assert_eq!(stats.light_points, 1);
        let ppt = 160.0 / (0.5 * fov_deg).to_radians().tan();
        let run = bright_run(&image) as f64;
        let measured_deg = 2.0 * (0.5 * run / ppt).atan().to_degrees();
        assert!(
            (measured_deg - expected_deg).abs() <= 0.2 * expected_deg,
            "at {fov_deg} degrees: halo {measured_deg:.2} degrees ({run} px), model {expected_deg:.2}"
        );
    }
}

#[test]
fn a_1000_cd_light_is_seen_at_night_through_clear_air_and_lost_in_haze() {
    let db = hills();
    let cache = cache(&db);
    let mut renderer = renderer(&cache);
    // The lamp 5 km north of the eye, 300 m up (against the sky), on a moonless night.
    let eye = hills_point(-3800.0, 0.0, 40.0);
    let light = lamp(1200.0, 300.0, 1000.0);
    let rel = cig_geo::EnuFrame::new(eye)
        .geodetic_to_enu(cig_geo::Geodetic::from_ecef(light.position_ecef_m));
    let pitch = rel.z.atan2(rel.y).to_degrees();
    let mut pictures = Vec::new();
    for visibility_m in [40_000.0, 2_000.0] {
        let mut snapshot =
            FrameSnapshot::new(at(MOONLESS), vec![view(eye, (0.0, pitch, 0.0), 30.0, SIZE)]);
        snapshot.culture = false;
        snapshot.fog =
            cig_scene::Fog::from_visibility(cig_scene::FogMode::Exponential, visibility_m);
        snapshot.lights = vec![light];
        let (image, stats) =
            render_adapted(&mut renderer, &cache, &snapshot, false, Adaptation::Settled);
        let centre = ((SIZE.1 / 2 * SIZE.0 + SIZE.0 / 2) * 4) as usize;
        let peak = (0..9)
            .map(|k| {
                let (dx, dy) = (k % 3, k / 3);
                let i = centre + ((dy * SIZE.0 as usize + dx) * 4) - (SIZE.0 as usize + 1) * 4;
                image.rgba[i..i + 3]
                    .iter()
                    .map(|c| u32::from(*c))
                    .sum::<u32>()
            })
            .max()
            .unwrap_or(0);
        pictures.push((stats.light_points, peak));
    }
    let (clear_count, clear_peak) = pictures[0];
    let (hazy_count, hazy_peak) = pictures[1];
    assert_eq!(clear_count, 1, "{pictures:?}");
    assert!(
        clear_peak > 150,
        "the lamp shows {clear_peak} (r+g+b) in clear air"
    );
    assert_eq!(hazy_count, 0, "{pictures:?}");
    assert!(hazy_peak < 60, "{pictures:?}");
}
