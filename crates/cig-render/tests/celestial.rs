//! The moon and the stars in rendered frames: narrow views aimed by the ephemeris and the star
//! catalogue, checked for place, size, phase and bright-limb orientation, and for stars that
//! show at night and vanish by day. Every check compares pixels within one image (or a night
//! and a noon image), never absolute colours, so a new sky or exposure leaves them valid.

mod common;

use cig_environment::moon_disc;
use cig_environment::stars::{self, star_direction_ecef};
use cig_environment::{ephemeris, Ephemeris, Observer, UtcTime};
use cig_geo::{EnuFrame, Geodetic};
use cig_render::{Image, Renderer};
use cig_scene::{FrameSnapshot, View};
use cig_terrain::TileCache;
use glam::DVec3;
use std::sync::Arc;

/// Over the sea database's centre (36 N 122 W), 50 m up.
fn site() -> Geodetic {
    Geodetic::new(36.0, -122.0, 50.0)
}

fn observer() -> Observer {
    let s = site();
    Observer::new(s.lat_deg, s.lon_deg, s.alt_m).expect("observer")
}

/// The first instant from `start` (steps of `step_s`, at most `steps`) whose ephemeris passes.
fn find_time(
    start: UtcTime,
    step_s: f64,
    steps: u32,
    pass: impl Fn(&Ephemeris) -> bool,
) -> UtcTime {
    let obs = observer();
    (0..steps)
        .map(|i| start.plus_seconds(f64::from(i) * step_s))
        .find(|t| pass(&ephemeris(&obs, *t)))
        .expect("an instant that fits")
}

fn to_enu(dir_ecef: DVec3) -> DVec3 {
    EnuFrame::new(site()).ecef_vector_to_enu(dir_ecef)
}

/// A square view of `size` pixels and `fov_deg` across aimed at `dir_ecef`.
fn aimed(dir_ecef: DVec3, fov_deg: f64, size: u32) -> View {
    let enu = to_enu(dir_ecef);
    let heading = enu.x.atan2(enu.y).to_degrees();
    let pitch = enu.z.clamp(-1.0, 1.0).asin().to_degrees();
    common::view(site(), (heading, pitch, 0.0), fov_deg, (size, size))
}

/// Pixel coordinates (x right, y down; pixel i spans [i, i + 1]) of a direction in a view.
fn project(view: &View, dir_ecef: DVec3) -> (f64, f64) {
    let cam = view.camera();
    let [tl, tr, td, tu] = view.fov.tangents();
    let f = dir_ecef.dot(cam.forward);
    let x_tan = dir_ecef.dot(cam.right) / f;
    let y_tan = dir_ecef.dot(cam.up) / f;
    (
        (x_tan + tl) / (tl + tr) * f64::from(view.width_px),
        (tu - y_tan) / (tu + td) * f64::from(view.height_px),
    )
}

/// The direction of pixel coordinates (x, y) of a view (inverse of [`project`]).
fn unproject(view: &View, x: f64, y: f64) -> DVec3 {
    let cam = view.camera();
    let [tl, tr, td, tu] = view.fov.tangents();
    let x_tan = x / f64::from(view.width_px) * (tl + tr) - tl;
    let y_tan = tu - y / f64::from(view.height_px) * (tu + td);
    (cam.forward + cam.right * x_tan + cam.up * y_tan).normalize()
}

struct Scene {
    cache: Arc<TileCache>,
    renderer: Renderer,
}

fn scene() -> Scene {
    let cache = common::cache(&common::sea());
    let renderer = common::renderer(&cache);
    Scene { cache, renderer }
}

fn render(scene: &mut Scene, time: UtcTime, view: View, stars_visible: bool) -> Image {
    render_with(scene, time, view, |s| s.stars_visible = stars_visible)
}

fn render_with(
    scene: &mut Scene,
    time: UtcTime,
    view: View,
    adjust: impl FnOnce(&mut FrameSnapshot),
) -> Image {
    let mut snapshot = FrameSnapshot::new(time.unix_seconds(), vec![view]);
    adjust(&mut snapshot);
    common::render(&mut scene.renderer, &scene.cache, &snapshot, false).0
}

/// Per pixel, the sum of the three 8-bit channels.
fn brightness(image: &Image) -> Vec<u32> {
    image
        .rgba
        .chunks_exact(4)
        .map(|p| u32::from(p[0]) + u32::from(p[1]) + u32::from(p[2]))
        .collect()
}

/// Pixels brighter than `threshold`: their count and centroid (pixel centres at i + 0.5).
fn bright_region(image: &Image, threshold: u32) -> (usize, f64, f64) {
    let b = brightness(image);
    let (mut n, mut sx, mut sy) = (0usize, 0.0, 0.0);
    for (i, v) in b.iter().enumerate() {
        if *v > threshold {
            n += 1;
            sx += (i as u32 % image.width) as f64 + 0.5;
            sy += (i as u32 / image.width) as f64 + 0.5;
        }
    }
    (n, sx / n.max(1) as f64, sy / n.max(1) as f64)
}

fn median(values: &[u32]) -> u32 {
    let mut v = values.to_vec();
    v.sort_unstable();
    v[v.len() / 2]
}

fn write(image: &Image, name: &str) {
    common::write_png(image, &common::out_dir().join(format!("{name}.png")));
}

const MOON_FOV_DEG: f64 = 2.0;
const MOON_SIZE_PX: u32 = 128;

/// Renders the moon at `time` in a narrow view aimed at it; returns the image, the view, the
/// predicted centre (pixels) and radius (pixels).
fn moon_frame(scene: &mut Scene, time: UtcTime) -> (Image, View, (f64, f64), f64) {
    let moon = cig_render::celestial::moon_view(time.unix_seconds(), site()).expect("moon");
    let view = aimed(moon.direction_ecef, MOON_FOV_DEG, MOON_SIZE_PX);
    let image = render(scene, time, view, true);
    let centre = project(&view, moon.direction_ecef);
    let radius_px = moon.angular_radius_deg.to_radians().tan() * view.camera().pixels_per_tangent;
    (image, view, centre, radius_px)
}

#[test]
fn the_full_moon_is_a_whole_disc_of_its_predicted_size_at_its_predicted_place() {
    let start = UtcTime::from_calendar(2026, 1, 1, 0, 0, 0.0).expect("in range");
    let time = find_time(start, 3600.0, 24 * 90, |e| {
        e.moon_illuminated_fraction > 0.98
            && e.moon.altitude_deg > 35.0
            && e.sun.altitude_deg < -18.0
    });
    let mut scene = scene();
    let (image, view, (cx, cy), radius_px) = moon_frame(&mut scene, time);
    write(&image, "moon-full");
    // The host can switch it off.
    let off = render_with(&mut scene, time, view, |s| s.moon_visible = false);
    let b_off = brightness(&off);
    assert!(
        b_off.iter().max() <= Some(&(median(&b_off) + 3)),
        "moon switched off"
    );
    let b = brightness(&image);
    let peak = *b.iter().max().expect("in range");
    let background = median(&b);
    assert!(
        peak > background + 100,
        "the moon stands out: {peak} vs {background}"
    );
    // Half way between the sky and the disc: the disc's edge.
    let (n, x, y) = bright_region(&image, (peak + background) / 2);
    assert!(
        (x - cx).hypot(y - cy) < 1.0,
        "centroid ({x:.2}, {y:.2}) vs predicted ({cx:.2}, {cy:.2})"
    );
    let measured_radius = (n as f64 / std::f64::consts::PI).sqrt();
    assert!(
        (measured_radius - radius_px).abs() < 0.04 * radius_px,
        "radius {measured_radius:.2} px vs {radius_px:.2} px"
    );
}

#[test]
fn a_quarter_moon_is_half_lit_with_its_bright_limb_toward_the_sun() {
    let start = UtcTime::from_calendar(2026, 3, 1, 0, 0, 0.0).expect("in range");
    let mut scene = scene();
    // First quarter in the evening, last quarter in the morning, and a crescent.
    for (name, lo, hi, waxing) in [
        ("first-quarter", 0.45, 0.55, true),
        ("last-quarter", 0.45, 0.55, false),
        ("crescent", 0.12, 0.3, true),
    ] {
        let time = find_time(start, 1800.0, 48 * 120, |e| {
            (lo..hi).contains(&e.moon_illuminated_fraction)
                && e.moon_waxing == waxing
                && e.moon.altitude_deg > 20.0
                && e.sun.altitude_deg < -12.0
        });
        let (image, view, (cx, cy), radius_px) = moon_frame(&mut scene, time);
        write(&image, &format!("moon-{name}"));
        let b = brightness(&image);
        let peak = *b.iter().max().expect("in range");
        let background = median(&b);
        assert!(peak > background + 60, "{name}: {peak} vs {background}");
        let (n, x, y) = bright_region(&image, background + (peak - background) / 5);
        let disc_area = std::f64::consts::PI * radius_px * radius_px;
        let fraction = n as f64 / disc_area;
        let k = ephemeris(&observer(), time).moon_illuminated_fraction;
        assert!(
            (fraction - k).abs() < 0.12,
            "{name}: {fraction:.3} of the disc lit, illuminated fraction {k:.3}"
        );
        // The lit side's centroid lies from the centre at the bright limb's position angle.
        assert!(
            (x - cx).hypot(y - cy) > 0.2 * radius_px,
            "{name}: centroid at the centre"
        );
        let moon_dir = unproject(&view, cx, cy);
        let lit_dir = unproject(&view, x, y);
        let measured = moon_disc::position_angle_deg(moon_dir, lit_dir);
        let (sun, moon) = cig_environment::ephemeris::geocentric_apparent(time);
        let chi = moon_disc::bright_limb_position_angle_deg(
            sun.right_ascension_deg,
            sun.declination_deg,
            moon.right_ascension_deg,
            moon.declination_deg,
        );
        let diff = (measured - chi + 540.0).rem_euclid(360.0) - 180.0;
        assert!(
            diff.abs() < 15.0,
            "{name}: bright limb at {measured:.1}°, Meeus χ {chi:.1}°"
        );
    }
}

/// The night and noon frames of a narrow view aimed at catalogue star `hr`.
const STAR_FOV_DEG: f64 = 0.15;
const STAR_SIZE_PX: u32 = 64;

fn star_dir(hr: u16, time: UtcTime) -> DVec3 {
    let star = stars::catalogue()
        .iter()
        .find(|s| s.hr == hr)
        .expect("catalogue star");
    star_direction_ecef(star, time)
}

fn altitude_deg(dir_ecef: DVec3) -> f64 {
    to_enu(dir_ecef).z.asin().to_degrees()
}

/// The brightest pixel and the brightness-weighted centroid of the 5 x 5 pixels around it,
/// above the image's median.
fn peak_and_centroid(image: &Image) -> (u32, u32, f64, f64) {
    let b = brightness(image);
    let background = median(&b);
    let (i, peak) = b
        .iter()
        .enumerate()
        .max_by_key(|(_, v)| **v)
        .map(|(i, v)| (i as u32, *v))
        .expect("in range");
    let (px, py) = ((i % image.width) as i64, (i / image.width) as i64);
    let (mut w, mut sx, mut sy) = (0.0, 0.0, 0.0);
    for y in (py - 2).max(0)..=(py + 2).min(i64::from(image.height) - 1) {
        for x in (px - 2).max(0)..=(px + 2).min(i64::from(image.width) - 1) {
            let v =
                f64::from(b[(y * i64::from(image.width) + x) as usize].saturating_sub(background));
            w += v;
            sx += v * (x as f64 + 0.5);
            sy += v * (y as f64 + 0.5);
        }
    }
    (peak, background, sx / w.max(1e-9), sy / w.max(1e-9))
}

#[test]
fn bright_stars_show_at_their_predicted_pixel_at_night_and_vanish_by_day() {
    let mut scene = scene();
    // Sirius, Capella, Rigel, Procyon, Arcturus: winter nights and summer days.
    for hr in [2491u16, 1708, 1713, 2943, 5340] {
        let night = find_time(
            UtcTime::from_calendar(2026, 1, 10, 0, 0, 0.0).expect("in range"),
            600.0,
            6 * 24 * 3,
            |e| e.sun.altitude_deg < -18.0 && altitude_deg(star_dir(hr, e.time)) > 25.0,
        );
        let dir = star_dir(hr, night);
        let view = aimed(dir, STAR_FOV_DEG, STAR_SIZE_PX);
        let image = render(&mut scene, night, view, true);
        write(&image, &format!("star-{hr}-night"));
        let (peak, background, x, y) = peak_and_centroid(&image);
        let (ex, ey) = project(&view, dir);
        assert!(
            peak > background + 24,
            "HR {hr}: {peak} vs sky {background}"
        );
        assert!(
            (x - ex).hypot(y - ey) < 1.0,
            "HR {hr}: at ({x:.2}, {y:.2}), predicted ({ex:.2}, {ey:.2})"
        );
        // Only the star: the pixels 4 or more away are sky.
        let b = brightness(&image);
        let far_bright = b
            .iter()
            .enumerate()
            .filter(|(i, v)| {
                let (px, py) = (
                    (*i as u32 % image.width) as f64 + 0.5,
                    (*i as u32 / image.width) as f64 + 0.5,
                );
                (px - ex).hypot(py - ey) > 4.0 && **v > background + 6
            })
            .count();
        assert_eq!(far_bright, 0, "HR {hr}: a lone point");
        // A dimmer star field (the host's intensity) shows it dimmer, or not at all once it
        // falls under the eye's threshold.
        let dim = render_with(&mut scene, night, view, |s| s.star_intensity = 0.3);
        let (peak_dim, background_dim, _, _) = peak_and_centroid(&dim);
        assert!(
            peak_dim.saturating_sub(background_dim) + 8 < peak - background,
            "HR {hr} at 30 %: {peak_dim} vs {peak}"
        );
        // Switched off, it is gone.
        let off = render(&mut scene, night, view, false);
        let (peak_off, background_off, _, _) = peak_and_centroid(&off);
        assert!(peak_off <= background_off + 3, "HR {hr} off: {peak_off}");
        // By day the sky's brightness hides it (no gate on the sun: the eye's threshold).
        let noon = find_time(
            UtcTime::from_calendar(2026, 6, 1, 0, 0, 0.0).expect("in range"),
            600.0,
            6 * 24 * 20,
            |e| e.sun.altitude_deg > 30.0 && altitude_deg(star_dir(hr, e.time)) > 25.0,
        );
        let dir = star_dir(hr, noon);
        let view = aimed(dir, STAR_FOV_DEG, STAR_SIZE_PX);
        let image = render(&mut scene, noon, view, true);
        write(&image, &format!("star-{hr}-noon"));
        let (peak, background, _, _) = peak_and_centroid(&image);
        assert!(
            peak <= background + 3,
            "HR {hr} at noon: {peak} vs sky {background}"
        );
    }
}

#[test]
fn sirius_comes_out_after_sunset_with_no_gate_on_the_sun() {
    // The same star, the same narrow view: hidden while the sun is still a few degrees up (the
    // sky's brightness is over the eye's threshold), seen once the sky is dark.
    let sirius = 2491;
    let start = UtcTime::from_calendar(2026, 3, 1, 0, 0, 0.0).expect("in range");
    let dusk = find_time(start, 300.0, 12 * 24 * 10, |e| {
        (2.0..5.0).contains(&e.sun.altitude_deg) && altitude_deg(star_dir(sirius, e.time)) > 20.0
    });
    let dark = find_time(dusk, 300.0, 12 * 24, |e| {
        e.sun.altitude_deg < -18.0 && altitude_deg(star_dir(sirius, e.time)) > 20.0
    });
    let mut scene = scene();
    let mut peaks = Vec::new();
    for (name, time) in [("dusk", dusk), ("dark", dark)] {
        let view = aimed(star_dir(sirius, time), STAR_FOV_DEG, STAR_SIZE_PX);
        let image = render(&mut scene, time, view, true);
        write(&image, &format!("sirius-{name}"));
        let (peak, background, _, _) = peak_and_centroid(&image);
        peaks.push(peak.saturating_sub(background));
    }
    assert!(
        peaks[0] <= 3,
        "Sirius at dusk, sun up: {} above the sky",
        peaks[0]
    );
    assert!(
        peaks[1] > 24,
        "Sirius after dark: {} above the sky",
        peaks[1]
    );
    // The catalogue's physics agrees: only in the dark is its magnitude under the limit.
    let z = cig_scene::lighting::Lighting::at(dark.unix_seconds(), site()).sky_zenith;
    let sky_cd = f64::from(0.2126 * z[0] + 0.7152 * z[1] + 0.0722 * z[2])
        / cig_render::celestial::radiance_per_cd_per_m2();
    assert!(stars::limiting_magnitude(sky_cd) > -1.46);
}
