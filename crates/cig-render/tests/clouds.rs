//! The cloud pass on lavapipe (or any GPU), asserted by comparison within each test (never
//! absolute colours): an overcast greys the sky seen from below, a layer seen from above hides
//! the terrain, the ground is darker under a cloud (chosen with the CPU model) and not in a
//! gap, the clouds drift with the wind, and an eye inside a cloud loses the scene's contrast.

mod common;

use cig_environment::clouds::{CloudField, CloudKind, CloudLayer, CloudOrigin, PlanePoint};
use cig_geo::{EnuFrame, Geodetic};
use cig_render::Image;
use cig_scene::FrameSnapshot;
use common::*;
use glam::DVec3;

const SIZE: (u32, u32) = (96, 72);
const ORIGIN: CloudOrigin = CloudOrigin {
    lat_deg: 36.0,
    lon_deg: -122.0,
};

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

fn mean_luminance(image: &Image) -> f64 {
    let n = (image.width * image.height) as f64;
    image.rgba.chunks_exact(4).map(luminance).sum::<f64>() / n
}

/// Standard deviation of the pixels' luminance over their mean (the image's contrast).
fn contrast(image: &Image) -> f64 {
    let mean = mean_luminance(image);
    let n = (image.width * image.height) as f64;
    let var = image
        .rgba
        .chunks_exact(4)
        .map(|p| (luminance(p) - mean).powi(2))
        .sum::<f64>()
        / n;
    var.sqrt() / mean.max(1e-6)
}

/// Mean saturation, (max - min) / max of the linear channels.
fn saturation(image: &Image) -> f64 {
    let n = (image.width * image.height) as f64;
    image
        .rgba
        .chunks_exact(4)
        .map(|p| {
            let c = [p[0], p[1], p[2]].map(srgb_to_linear);
            let max = c.iter().copied().fold(0.0, f64::max);
            let min = c.iter().copied().fold(1.0, f64::min);
            if max > 1e-4 {
                (max - min) / max
            } else {
                0.0
            }
        })
        .sum::<f64>()
        / n
}

fn with_clouds(snapshot: &FrameSnapshot, layers: &[CloudLayer]) -> FrameSnapshot {
    let mut s = snapshot.clone();
    s.cloud_layers = layers.to_vec();
    s.cloud_origin = ORIGIN;
    s
}

fn overcast(base_m: f64, thickness_m: f64) -> CloudLayer {
    CloudLayer::new(base_m, thickness_m, 1.0, CloudKind::Stratus)
}

#[test]
fn an_overcast_seen_from_below_greys_the_sky() {
    let db = sea();
    let cache = cache(&db);
    let mut renderer = renderer(&cache);
    let v = view(
        Geodetic::new(36.0, -122.0, 20.0),
        (0.0, 60.0, 0.0),
        60.0,
        SIZE,
    );
    let clear = FrameSnapshot::new(MORNING_UNIX_S, vec![v]);
    let (sky, _) = render(&mut renderer, &cache, &clear, false);
    let cloudy = with_clouds(&clear, &[overcast(1500.0, 800.0)]);
    let (grey, stats) = render(&mut renderer, &cache, &cloudy, false);
    write_png(&sky, &out_dir().join("clouds_up_clear.png"));
    write_png(&grey, &out_dir().join("clouds_up_overcast.png"));
    assert_eq!(stats.cloud_layers_drawn, 1);
    let (s0, s1) = (saturation(&sky), saturation(&grey));
    assert!(s1 < 0.6 * s0, "saturation {s0:.3} clear, {s1:.3} overcast");
    assert!(mean_abs_diff(&sky, &grey) > 10.0);
}

/// The hills' ground height (ellipsoid) at their reference point.
fn hills_ground_m() -> (Geodetic, f64) {
    let at = Geodetic::new(36.0159, -121.1854, 0.0);
    let mut q = cig_terrain::QuerySession::new(cache(&hills()));
    let ground = q.hot(at.lat_deg, at.lon_deg).expect("inside the database");
    (at, ground.height_ellipsoid_m())
}

#[test]
fn a_layer_seen_from_above_hides_the_terrain() {
    let db = hills();
    let cache = cache(&db);
    let mut renderer = renderer(&cache);
    let (at, ground_m) = hills_ground_m();
    let eye = Geodetic::new(at.lat_deg, at.lon_deg, ground_m + 1500.0);
    let v = view(eye, (0.0, -80.0, 0.0), 50.0, SIZE);
    let clear = FrameSnapshot::new(MORNING_UNIX_S, vec![v]);
    let (terrain, _) = render(&mut renderer, &cache, &clear, false);
    let cloudy = with_clouds(&clear, &[overcast(ground_m + 600.0, 500.0)]);
    let (hidden, _) = render(&mut renderer, &cache, &cloudy, false);
    write_png(&terrain, &out_dir().join("clouds_down_clear.png"));
    write_png(&hidden, &out_dir().join("clouds_down_overcast.png"));
    let (c0, c1) = (contrast(&terrain), contrast(&hidden));
    assert!(
        c1 < 0.3 * c0,
        "contrast {c0:.3} clear, {c1:.3} over the overcast"
    );
    assert!(mean_abs_diff(&terrain, &hidden) > 10.0);
}

#[test]
fn an_eye_inside_a_cloud_loses_the_scenes_contrast() {
    let db = hills();
    let cache = cache(&db);
    let mut renderer = renderer(&cache);
    let (at, ground_m) = hills_ground_m();
    let eye = Geodetic::new(at.lat_deg, at.lon_deg, ground_m + 400.0);
    let v = view(eye, (0.0, -30.0, 0.0), 60.0, SIZE);
    let clear = FrameSnapshot::new(MORNING_UNIX_S, vec![v]);
    let (outside, _) = render(&mut renderer, &cache, &clear, false);
    // The eye 100 m above the base of a 600 m sheet.
    let cloudy = with_clouds(&clear, &[overcast(ground_m + 300.0, 600.0)]);
    let (inside, _) = render(&mut renderer, &cache, &cloudy, false);
    write_png(&outside, &out_dir().join("clouds_inside_clear.png"));
    write_png(&inside, &out_dir().join("clouds_inside.png"));
    let (c0, c1) = (contrast(&outside), contrast(&inside));
    assert!(
        c1 < 0.2 * c0,
        "contrast {c0:.3} clear, {c1:.3} inside the cloud"
    );
}

/// The sun's direction (east, north, up) at a point.
fn sun_enu(at: Geodetic) -> DVec3 {
    let d = cig_scene::lighting::sun_direction_ecef(MORNING_UNIX_S, at);
    EnuFrame::new(at).ecef_vector_to_enu(d)
}

/// Points of the sea along a line east of the origin where the CPU model's shade is (at the
/// point and 60 m around it) below 0.02 and above 0.999.
fn shaded_and_lit_points(field: &CloudField) -> (Geodetic, Geodetic) {
    let frame = EnuFrame::new(Geodetic::new(ORIGIN.lat_deg, ORIGIN.lon_deg, 0.0));
    let shade_at = |east_m: f64, north_m: f64| {
        let g = frame.enu_to_geodetic(DVec3::new(east_m, north_m, 0.0));
        let (e, n) = ORIGIN.plane_m(g.lat_deg, g.lon_deg);
        let sun = sun_enu(g);
        (
            g,
            field.shade_factor(PlanePoint::new(e, n, 0.0), sun, MORNING_UNIX_S),
        )
    };
    let around = |east_m: f64, north_m: f64, pass: &dyn Fn(f64) -> bool| {
        [
            (0.0, 0.0),
            (60.0, 0.0),
            (-60.0, 0.0),
            (0.0, 60.0),
            (0.0, -60.0),
        ]
        .iter()
        .all(|(de, dn)| pass(shade_at(east_m + de, north_m + dn).1))
    };
    let mut shaded = None;
    let mut lit = None;
    for k in 0..2000 {
        let (e, n) = (f64::from(k) * 29.0 - 20_000.0, 1000.0);
        if shaded.is_none() && around(e, n, &|s| s < 0.02) {
            shaded = Some(shade_at(e, n).0);
        }
        if lit.is_none() && around(e, n, &|s| s > 0.999) {
            lit = Some(shade_at(e, n).0);
        }
    }
    (shaded.expect("a shaded point"), lit.expect("a lit point"))
}

#[test]
fn the_ground_is_darker_under_a_cloud_and_not_in_a_gap() {
    let db = sea();
    let cache = cache(&db);
    let mut renderer = renderer(&cache);
    let layer = CloudLayer {
        seed: 9,
        ..CloudLayer::new(1200.0, 600.0, 0.5, CloudKind::Cumulus)
    };
    let field = CloudField::new(&[layer]).expect("valid layer");
    let (shaded, lit) = shaded_and_lit_points(&field);
    let mut ratios = Vec::new();
    for (name, point) in [("shaded", shaded), ("lit", lit)] {
        // Looking straight down from 100 m with a narrow view: the pixels see the point.
        let eye = Geodetic::new(point.lat_deg, point.lon_deg, 100.0);
        let v = view(eye, (0.0, -90.0, 0.0), 10.0, SIZE);
        let clear = FrameSnapshot::new(MORNING_UNIX_S, vec![v]);
        let (a, _) = render(&mut renderer, &cache, &clear, false);
        let (b, _) = render(&mut renderer, &cache, &with_clouds(&clear, &[layer]), false);
        write_png(&b, &out_dir().join(format!("clouds_shade_{name}.png")));
        ratios.push(mean_luminance(&b) / mean_luminance(&a));
    }
    assert!(
        ratios[0] < 0.8,
        "under the cloud: {:.3} of the clear luminance",
        ratios[0]
    );
    assert!(
        (ratios[1] - 1.0).abs() < 0.02,
        "in the gap: {:.3} of the clear luminance",
        ratios[1]
    );
}

#[test]
fn clouds_drift_with_the_wind() {
    let db = sea();
    let cache = cache(&db);
    let mut renderer = renderer(&cache);
    let layer = CloudLayer {
        wind_speed_mps: 15.0,
        wind_from_deg: 250.0,
        seed: 4,
        ..CloudLayer::new(1500.0, 600.0, 0.5, CloudKind::Cumulus)
    };
    let (ve, vn) = layer.wind_velocity_mps();
    let dt_s = 40.0;
    let eye = Geodetic::new(36.0, -122.0, 20.0);
    let frame_at = |t_s: f64, east_m: f64, north_m: f64| {
        let g = EnuFrame::new(eye).enu_to_geodetic(DVec3::new(east_m, north_m, 0.0));
        let at = Geodetic::new(g.lat_deg, g.lon_deg, eye.alt_m);
        let v = view(at, (0.0, 89.0, 0.0), 60.0, SIZE);
        with_clouds(&FrameSnapshot::new(t_s, vec![v]), &[layer])
    };
    let t0 = MORNING_UNIX_S;
    let (now, _) = render(&mut renderer, &cache, &frame_at(t0, 0.0, 0.0), false);
    let (later, _) = render(&mut renderer, &cache, &frame_at(t0 + dt_s, 0.0, 0.0), false);
    // What the eye sees dt later is what an eye upwind by wind * dt saw before.
    let (upwind, _) = render(
        &mut renderer,
        &cache,
        &frame_at(t0, -ve * dt_s, -vn * dt_s),
        false,
    );
    write_png(&now, &out_dir().join("clouds_drift_0.png"));
    write_png(&later, &out_dir().join("clouds_drift_1.png"));
    let moved = mean_abs_diff(&now, &later);
    let predicted = mean_abs_diff(&later, &upwind);
    assert!(
        moved > 2.0,
        "the clouds did not change in {dt_s} s ({moved:.2})"
    );
    assert!(
        predicted < 0.25 * moved,
        "frame dt later vs the upwind eye: {predicted:.2}; vs the same eye: {moved:.2}"
    );
}

#[test]
fn invalid_layers_are_left_out_without_harming_the_frame() {
    let db = sea();
    let cache = cache(&db);
    let mut renderer = renderer(&cache);
    let v = view(
        Geodetic::new(36.0, -122.0, 20.0),
        (0.0, 30.0, 0.0),
        60.0,
        SIZE,
    );
    let clear = FrameSnapshot::new(MORNING_UNIX_S, vec![v]);
    let (a, _) = render(&mut renderer, &cache, &clear, false);
    let bad = [
        CloudLayer::new(f64::NAN, 500.0, 1.0, CloudKind::Stratus),
        CloudLayer::new(1000.0, -5.0, 1.0, CloudKind::Stratus),
        CloudLayer::new(1000.0, 500.0, f64::INFINITY, CloudKind::Stratus),
    ];
    let (b, stats) = render(&mut renderer, &cache, &with_clouds(&clear, &bad), false);
    assert_eq!(stats.cloud_layers_drawn, 0);
    assert_eq!(mean_abs_diff(&a, &b), 0.0);
}

/// A dark, nearly opaque puff at an east-north-up offset from the view's eye.
fn with_puff(snapshot: &FrameSnapshot, offset_enu: DVec3, radius_m: f32) -> FrameSnapshot {
    let eye = snapshot.views[0].eye;
    let e = EnuFrame::new(eye).enu_vector_to_ecef(offset_enu);
    let mut s = snapshot.clone();
    s.puff_origin_ecef_m = eye.to_ecef();
    s.puffs = vec![cig_effects::PuffInstance {
        position_eye_m: [e.x as f32, e.y as f32, e.z as f32],
        radius_m,
        colour_rgb: [0.05, 0.05, 0.05],
        opacity: 0.95,
        emissive: 0.0,
        temperature_k: 288.0,
        kind: 0,
        effect: 0,
    }];
    s
}

#[test]
fn puffs_below_the_clouds_are_in_front_of_them_from_below_and_behind_them_from_above() {
    let db = sea();
    let cache = cache(&db);
    let mut renderer = renderer(&cache);
    // From below: the eye at 2 km, an overcast from 2.5 km; the puff 400 m ahead shows.
    let eye = Geodetic::new(36.0, -122.0, 2000.0);
    let below = with_clouds(
        &FrameSnapshot::new(
            MORNING_UNIX_S,
            vec![view(eye, (0.0, 10.0, 0.0), 40.0, SIZE)],
        ),
        &[overcast(2500.0, 500.0)],
    );
    let ahead = DVec3::new(0.0, 400.0, 400.0 * 10f64.to_radians().tan());
    let (clouds_only, _) = render(&mut renderer, &cache, &below, false);
    let (with_smoke, stats) = render(
        &mut renderer,
        &cache,
        &with_puff(&below, ahead, 40.0),
        false,
    );
    write_png(&with_smoke, &out_dir().join("clouds_puff_below.png"));
    assert_eq!((stats.puffs_drawn, stats.cloud_layers_drawn), (1, 1));
    let centre = ((SIZE.1 / 2 * SIZE.0 + SIZE.0 / 2) * 4) as usize;
    let pixel = |image: &Image| luminance(&image.rgba[centre..centre + 4]);
    assert!(
        pixel(&with_smoke) < 0.5 * pixel(&clouds_only),
        "the puff in front of the clouds is hidden: {:.3} against {:.3}",
        pixel(&with_smoke),
        pixel(&clouds_only)
    );
    // From above: the eye at 2 km over an overcast at 1-1.5 km; a puff under it is hidden.
    let above = with_clouds(
        &FrameSnapshot::new(
            MORNING_UNIX_S,
            vec![view(eye, (0.0, -30.0, 0.0), 40.0, SIZE)],
        ),
        &[overcast(1000.0, 500.0)],
    );
    let under = DVec3::new(0.0, 3000.0 * 30f64.to_radians().cos(), -1500.0);
    let (clouds_only, _) = render(&mut renderer, &cache, &above, false);
    let (with_smoke, stats) = render(
        &mut renderer,
        &cache,
        &with_puff(&above, under, 150.0),
        false,
    );
    assert_eq!((stats.puffs_drawn, stats.cloud_layers_drawn), (1, 1));
    let changed = (pixel(&with_smoke) - pixel(&clouds_only)).abs() / pixel(&clouds_only);
    assert!(
        changed < 0.02,
        "the puff under the overcast shows through: {changed:.3}"
    );
    // Without the overcast the same puff is plain to see.
    let mut clear = above.clone();
    clear.cloud_layers.clear();
    let (sea_only, _) = render(&mut renderer, &cache, &clear, false);
    let (smoke_on_sea, _) = render(
        &mut renderer,
        &cache,
        &with_puff(&clear, under, 150.0),
        false,
    );
    let seen = (pixel(&smoke_on_sea) - pixel(&sea_only)).abs() / pixel(&sea_only);
    assert!(seen > 0.1, "the puff is not in view: {seen:.3}");
}
