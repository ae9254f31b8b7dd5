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

/// Scene-linear, pre-exposed luminance of each pixel: the sRGB encoding and the tone map's ACES
/// curve (K. Narkowicz's fit, as tonemap.wgsl) undone per channel. Exact up to the 8-bit
/// quantisation for pixels under the curve's clip (display value 1 at 7.2).
fn linear_luminance(image: &Image) -> Vec<f64> {
    let decode = |v: u8| {
        let c = f64::from(v) / 255.0;
        let display = if c <= 0.04045 {
            c / 12.92
        } else {
            ((c + 0.055) / 1.055).powf(2.4)
        };
        // y = x (2.51 x + 0.03) / (x (2.43 x + 0.59) + 0.14), solved for x >= 0.
        let y = display.min(0.999);
        let (a, b, c) = (2.43 * y - 2.51, 0.59 * y - 0.03, 0.14 * y);
        (-b - (b * b - 4.0 * a * c).max(0.0).sqrt()) / (2.0 * a)
    };
    image
        .rgba
        .chunks_exact(4)
        .map(|p| 0.2126 * decode(p[0]) + 0.7152 * decode(p[1]) + 0.0722 * decode(p[2]))
        .collect()
}

/// The incident-light exposure (EV, `cig_scene::lighting::exposure_value`) at which a luminance
/// of `luminance_cd_per_m2` shows as pre-exposed radiance `shown` (a photographer's fixed
/// exposure, so the object is not clipped by the tone map).
fn exposure_ev_showing(luminance_cd_per_m2: f64, shown: f64) -> f64 {
    use cig_scene::lighting::{exposure_for_illuminance, illuminance_for_exposure_value};
    let radiance = luminance_cd_per_m2 * cig_render::celestial::radiance_per_cd_per_m2();
    // The shown value falls monotonically with the EV: bisect.
    let (mut lo, mut hi) = (-10.0, 20.0);
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        let value = radiance * exposure_for_illuminance(illuminance_for_exposure_value(mid), 0.0);
        if value > shown {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

fn write(image: &Image, name: &str) {
    common::write_png(image, &common::out_dir().join(format!("{name}.png")));
}

const MOON_FOV_DEG: f64 = 2.0;
const MOON_SIZE_PX: u32 = 128;

/// The exposure a photographer gives the moon: its brightest surface element (the Lommel–Seeliger
/// limb, up to twice the head-on luminance, times the maria map's 1.15) shown at 0.7, under the
/// tone map's clip, whatever the night's natural light (which would clip the whole disc, the
/// earthshine too: a surface thousands of times brighter than the moonlit ground).
fn moon_exposure_ev(time: UtcTime) -> f64 {
    let e = ephemeris(&observer(), time);
    let limb = if e.moon_phase_angle_deg < 1.0 {
        1.0
    } else {
        2.0
    };
    let peak = moon_disc::moon_surface_luminance_cd_per_m2(e.moon_phase_angle_deg) * limb * 1.15;
    exposure_ev_showing(peak, 0.7)
}

/// Renders the moon at `time` in a narrow view aimed at it at the moon's own fixed exposure;
/// returns the image, the view, the predicted centre (pixels) and radius (pixels).
fn moon_frame(scene: &mut Scene, time: UtcTime) -> (Image, View, (f64, f64), f64) {
    let moon = cig_render::celestial::moon_view(time.unix_seconds(), site()).expect("moon");
    let view = aimed(moon.direction_ecef, MOON_FOV_DEG, MOON_SIZE_PX);
    let ev = moon_exposure_ev(time);
    let image = render_with(scene, time, view, |s| s.sky.fixed_exposure_ev = Some(ev));
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
    let ev = moon_exposure_ev(time);
    let off = render_with(&mut scene, time, view, |s| {
        s.moon_visible = false;
        s.sky.fixed_exposure_ev = Some(ev);
    });
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
        // At the moon's exposure nothing on the disc is clipped.
        assert!(peak < 3 * 250, "{name}: the disc is clipped ({peak})");
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

/// At the renderer's own automatic night exposure (no fixed exposure: the landscape's, thousands
/// of times under the moon's luminance) the disc would clip white without the eye's local
/// adaptation to it (celestial.wgsl's `moon_adapted`): a first-quarter moon must show its lit
/// half brighter than the earthshine, the lit fraction and bright limb of the ephemeris, and
/// shading across the lit half (limb darkening, maria), not a flat clipped white.
#[test]
fn at_the_automatic_night_exposure_the_quarter_moon_shows_its_phase() {
    let start = UtcTime::from_calendar(2026, 3, 1, 0, 0, 0.0).expect("in range");
    let time = find_time(start, 1800.0, 48 * 120, |e| {
        (0.45..0.55).contains(&e.moon_illuminated_fraction)
            && e.moon_waxing
            && e.moon.altitude_deg > 20.0
            && e.sun.altitude_deg < -18.0
    });
    let mut scene = scene();
    let moon = cig_render::celestial::moon_view(time.unix_seconds(), site()).expect("moon");
    let view = aimed(moon.direction_ecef, MOON_FOV_DEG, MOON_SIZE_PX);
    let image = render_with(&mut scene, time, view, |_| {});
    write(&image, "moon-first-quarter-auto-exposure");
    let (cx, cy) = project(&view, moon.direction_ecef);
    let radius_px = moon.angular_radius_deg.to_radians().tan() * view.camera().pixels_per_tangent;
    let b = brightness(&image);
    let peak = *b.iter().max().expect("in range");
    let background = median(&b);
    let (n, x, y) = bright_region(&image, background + (peak - background) / 5);
    let fraction = n as f64 / (std::f64::consts::PI * radius_px * radius_px);
    let k = moon.illuminated_fraction;
    assert!(
        (fraction - k).abs() < 0.15,
        "{fraction:.3} of the disc lit, illuminated fraction {k:.3}"
    );
    let moon_dir = unproject(&view, cx, cy);
    let measured = moon_disc::position_angle_deg(moon_dir, unproject(&view, x, y));
    let (sun, m) = cig_environment::ephemeris::geocentric_apparent(time);
    let chi = moon_disc::bright_limb_position_angle_deg(
        sun.right_ascension_deg,
        sun.declination_deg,
        m.right_ascension_deg,
        m.declination_deg,
    );
    let diff = (measured - chi + 540.0).rem_euclid(360.0) - 180.0;
    assert!(
        diff.abs() < 20.0,
        "bright limb at {measured:.1}°, Meeus χ {chi:.1}°"
    );
    // The disc's pixels (well inside its edge) on the lit side and on the dark side, along the
    // axis from the centre to the lit part's centroid.
    let (ax, ay) = (
        (x - cx) / (x - cx).hypot(y - cy),
        (y - cy) / (x - cx).hypot(y - cy),
    );
    let (mut lit, mut dark) = (Vec::new(), Vec::new());
    for (i, v) in b.iter().enumerate() {
        let px = (i as u32 % image.width) as f64 + 0.5 - cx;
        let py = (i as u32 / image.width) as f64 + 0.5 - cy;
        if px.hypot(py) > 0.85 * radius_px {
            continue;
        }
        let along = px * ax + py * ay;
        if along > 0.3 * radius_px {
            lit.push(*v);
        } else if along < -0.3 * radius_px {
            dark.push(*v);
        }
    }
    let (lit_median, dark_median) = (median(&lit), median(&dark));
    assert!(
        lit_median > dark_median + 150,
        "lit half {lit_median} vs dark half {dark_median}"
    );
    // The earthshine is there, just: over the sky beside the disc.
    assert!(
        dark_median > background,
        "dark half {dark_median} vs sky {background}"
    );
    // Not a flat clipped white: under a quarter of the lit half at the 8-bit clip, and shading
    // across it.
    let clipped = lit.iter().filter(|v| **v >= 3 * 254).count();
    assert!(
        clipped * 4 < lit.len(),
        "{clipped} of {} lit pixels clipped",
        lit.len()
    );
    let mut sorted = lit.clone();
    sorted.sort_unstable();
    let (p10, p90) = (sorted[sorted.len() / 10], sorted[sorted.len() * 9 / 10]);
    eprintln!(
        "auto exposure: lit fraction {fraction:.3} (k {k:.3}), limb {measured:.1}° (χ {chi:.1}°), \
         lit median {lit_median}, dark median {dark_median}, sky {background}, peak {peak}, \
         lit p10 {p10} p90 {p90}, clipped {clipped}/{}",
        lit.len()
    );
    assert!(p90 > p10 + 20, "lit half from {p10} to {p90}: no shading");
}

/// By day the moon stays physical (no local adaptation while the disc is within the display's
/// range): at a noon exposure its disc stands over the blue sky by its own exposed luminance,
/// not by the adapted level (1.0, ten times more) a compressed disc would show.
#[test]
fn the_daytime_moon_is_a_pale_physical_disc() {
    let start = UtcTime::from_calendar(2026, 3, 1, 0, 0, 0.0).expect("in range");
    let time = find_time(start, 1800.0, 48 * 120, |e| {
        (0.4..0.9).contains(&e.moon_illuminated_fraction)
            && e.moon.altitude_deg > 30.0
            && e.sun.altitude_deg > 30.0
    });
    let mut scene = scene();
    let moon = cig_render::celestial::moon_view(time.unix_seconds(), site()).expect("moon");
    let view = aimed(moon.direction_ecef, MOON_FOV_DEG, MOON_SIZE_PX);
    let noon_ev = cig_scene::lighting::exposure_value(1.0e5);
    let image = render_with(&mut scene, time, view, |s| {
        s.sky.fixed_exposure_ev = Some(noon_ev)
    });
    write(&image, "moon-daytime");
    let lum = linear_luminance(&image);
    let mut sorted = lum.clone();
    sorted.sort_by(f64::total_cmp);
    let sky = sorted[sorted.len() / 2];
    let excess = sorted[sorted.len() - 1] - sky;
    use cig_scene::lighting::{exposure_for_illuminance, illuminance_for_exposure_value};
    let exposure = exposure_for_illuminance(illuminance_for_exposure_value(noon_ev), 0.0);
    // An element lit and seen head-on, exposed (the brightest is up to 2.3 times it, less the
    // extinction's 20 %).
    let level = moon_disc::moon_surface_luminance_cd_per_m2(moon.phase_angle_deg)
        * cig_render::celestial::radiance_per_cd_per_m2()
        * exposure;
    assert!(level < 0.5, "the daytime disc is within range: {level:.3}");
    assert!(
        excess > 0.5 * level && excess < 2.5 * level,
        "disc over the sky {excess:.3}, physical level {level:.3}, sky {sky:.3}"
    );
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

/// A fixed exposure at which Sirius, the brightest star, peaks at 0.8 (pre-exposed) in the
/// narrow star views, with its sigma of 0.6 pixel: no star is clipped, so the intensities can
/// be compared on linear values.
fn star_exposure_ev() -> f64 {
    let pixel_rad = 2.0 * (STAR_FOV_DEG / 2.0).to_radians().tan() / f64::from(STAR_SIZE_PX);
    let sigma = 0.6 * pixel_rad;
    let peak_cd =
        stars::illuminance_lux_from_magnitude(-1.46) / (2.0 * std::f64::consts::PI * sigma * sigma);
    exposure_ev_showing(peak_cd, 0.8)
}

#[test]
fn bright_stars_show_at_their_predicted_pixel_at_night_and_vanish_by_day() {
    let mut scene = scene();
    let ev = star_exposure_ev();
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
        let exposed = |s: &mut FrameSnapshot| s.sky.fixed_exposure_ev = Some(ev);
        let image = render_with(&mut scene, night, view, exposed);
        write(&image, &format!("star-{hr}-night"));
        let (peak, background, x, y) = peak_and_centroid(&image);
        let (ex, ey) = project(&view, dir);
        assert!(
            peak > background + 24,
            "HR {hr}: {peak} vs sky {background}"
        );
        assert!(peak < 3 * 250, "HR {hr}: clipped at the star exposure");
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
        // A dimmer star field (the host's intensity): these stars stay far over the dark
        // sky's threshold, so 30 % of the light shows 30 % of the linear radiance.
        let linear_peak = |image: &Image| {
            let l = linear_luminance(image);
            let mut sorted = l.clone();
            sorted.sort_by(f64::total_cmp);
            let sky = sorted[sorted.len() / 2];
            l.iter().fold(0.0f64, |m, v| m.max(*v)) - sky
        };
        let dim = render_with(&mut scene, night, view, |s| {
            exposed(s);
            s.star_intensity = 0.3;
        });
        let ratio = linear_peak(&dim) / linear_peak(&image);
        assert!(
            (ratio - 0.3).abs() < 0.04,
            "HR {hr} at 30 %: {ratio:.3} of the full peak"
        );
        // Switched off, it is gone.
        let off = render_with(&mut scene, night, view, |s| {
            exposed(s);
            s.stars_visible = false;
        });
        let (peak_off, background_off, _, _) = peak_and_centroid(&off);
        assert!(peak_off <= background_off + 3, "HR {hr} off: {peak_off}");
        // By day the sky's brightness hides it (no gate on the sun: the eye's threshold), at
        // the day's own exposure, under which the star, drawn, would stand out of the sky.
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
    // The physics agrees, independently of the shader: Sirius's illuminance at the eye (after
    // the extinction along its air mass) is under Schaefer's threshold against the sky's
    // luminance at its place at dusk, over it after dark.
    let sirius_at_eye_mag = |time: UtcTime| {
        let h = altitude_deg(star_dir(sirius, time));
        let air_mass = 1.0 / (h.to_radians().sin() + 0.50572 * (h + 6.07995).powf(-1.6364));
        -1.46 + cig_render::celestial::extinction_mag_per_air_mass(site().alt_m)[1] * air_mass
    };
    let sky_cd_behind = |time: UtcTime| {
        let e = ephemeris(&observer(), time);
        let view = to_enu(star_dir(sirius, time)).to_array();
        let l = cig_environment::Atmosphere::earth().sky_radiance(
            site().alt_m,
            view,
            e.sun.direction_enu,
        );
        (0.2126 * l[0] + 0.7152 * l[1] + 0.0722 * l[2]) * cig_environment::SUN_ILLUMINANCE_TOA_LUX
    };
    let (dusk_mag, dusk_limit) = (
        sirius_at_eye_mag(dusk),
        stars::limiting_magnitude(sky_cd_behind(dusk)),
    );
    assert!(
        dusk_limit < dusk_mag,
        "dusk: limit {dusk_limit:.2} vs Sirius at {dusk_mag:.2}"
    );
    let (dark_mag, dark_limit) = (
        sirius_at_eye_mag(dark),
        stars::limiting_magnitude(sky_cd_behind(dark)),
    );
    assert!(
        dark_limit > dark_mag + 4.0,
        "dark: limit {dark_limit:.2} vs Sirius at {dark_mag:.2}"
    );
}

/// Isolated points: pixels that are the brightest of their 5 x 5 neighbourhood and brighter by
/// over `margin` (sum of the 8-bit channels) than the brightest pixel of its outer ring (the
/// sky around a point; a star's spread of 0.6 pixel has fallen to 0.4 % there).
fn isolated_points(image: &Image, margin: u32) -> usize {
    let b = brightness(image);
    let (w, h) = (i64::from(image.width), i64::from(image.height));
    let at = |x: i64, y: i64| b[(y * w + x) as usize];
    let mut count = 0;
    for y in 2..h - 2 {
        for x in 2..w - 2 {
            let v = at(x, y);
            let mut ring = 0;
            let mut peak = true;
            for dy in -2i64..=2 {
                for dx in -2i64..=2 {
                    let n = at(x + dx, y + dy);
                    if dx.abs() == 2 || dy.abs() == 2 {
                        ring = ring.max(n);
                    }
                    // Ties go to the first pixel in raster order.
                    let before = dy < 0 || (dy == 0 && dx < 0);
                    if (dx, dy) != (0, 0) && (n > v || (n == v && before)) {
                        peak = false;
                    }
                }
            }
            if peak && v > ring + margin {
                count += 1;
            }
        }
    }
    count
}

#[test]
fn a_wide_view_of_the_moonless_night_sky_is_full_of_stars_and_the_noon_sky_has_none() {
    // 60° across at 640 x 480, looking 60° up to the south, at the frame's own (automatic)
    // exposure: what the dark-adapted eye sees. A moonless winter night with the sun far down.
    let start = UtcTime::from_calendar(2026, 1, 10, 0, 0, 0.0).expect("in range");
    let night = find_time(start, 1800.0, 48 * 40, |e| {
        e.sun.altitude_deg < -24.0 && e.moon.altitude_deg < -10.0
    });
    let view = common::view(site(), (180.0, 60.0, 0.0), 60.0, (640, 480));
    let mut scene = scene();
    let image = render(&mut scene, night, view, true);
    write(&image, "wide-night");
    // The view holds about 6 % of the sphere, so about 55 of the 904 catalogue stars (to
    // magnitude 4.5); each must show as a point over the sky at the night's exposure.
    let stars = isolated_points(&image, 24);
    assert!(stars > 35, "{stars} stars in a moonless 60° view");
    let off = render(&mut scene, night, view, false);
    assert_eq!(isolated_points(&off, 24), 0, "stars switched off");
    // The same view at noon: the sky's brightness hides every star.
    let noon = find_time(start, 1800.0, 48 * 40, |e| e.sun.altitude_deg > 25.0);
    let image = render(&mut scene, noon, view, true);
    write(&image, "wide-noon");
    assert_eq!(isolated_points(&image, 3), 0, "stars at noon");
}

#[test]
fn a_star_fades_out_at_the_eyes_threshold_against_the_sky_behind_it() {
    // Sirius on a moonless night, dimmed by the host's star field intensity to a chosen
    // multiple of Schaefer's threshold against the dark sky (the night-sky background, the sun
    // far down): under the threshold it is not drawn, one magnitude over it, drawn whole.
    let sirius = 2491;
    let start = UtcTime::from_calendar(2026, 1, 10, 0, 0, 0.0).expect("in range");
    let night = find_time(start, 600.0, 6 * 24 * 40, |e| {
        e.sun.altitude_deg < -24.0
            && e.moon.altitude_deg < -10.0
            && altitude_deg(star_dir(sirius, e.time)) > 25.0
    });
    let dir = star_dir(sirius, night);
    let lighting = cig_scene::lighting::Lighting::at(night.unix_seconds(), site());
    let n = lighting.night_sky_colour;
    let sky_cd = f64::from(0.2126 * n[0] + 0.7152 * n[1] + 0.0722 * n[2])
        / cig_render::celestial::radiance_per_cd_per_m2();
    let h = altitude_deg(dir);
    let air_mass = 1.0 / (h.to_radians().sin() + 0.50572 * (h + 6.07995).powf(-1.6364));
    let transmittance = 10f64.powf(
        -0.4 * cig_render::celestial::extinction_mag_per_air_mass(site().alt_m)[1] * air_mass,
    );
    let at_eye_lux = stars::illuminance_lux_from_magnitude(-1.46) * transmittance;
    // The intensity that puts Sirius at the threshold.
    let at_threshold = stars::threshold_illuminance_lux(sky_cd) / at_eye_lux;
    assert!(at_threshold < 0.01, "{at_threshold}");
    // An exposure at which the brightest case's peak would show at 0.8, unclipped.
    let view = aimed(dir, STAR_FOV_DEG, STAR_SIZE_PX);
    let pixel_rad = 2.0 * (STAR_FOV_DEG / 2.0).to_radians().tan() / f64::from(STAR_SIZE_PX);
    let spread_sr = 2.0 * std::f64::consts::PI * (0.6 * pixel_rad).powi(2);
    let (under, half, whole) = (0.6, 1.6, 3.5);
    let ev = exposure_ev_showing(whole * at_threshold * at_eye_lux / spread_sr, 0.8);
    let mut scene = scene();
    let mut peak_at = |multiple: f64| {
        let image = render_with(&mut scene, night, view, |s| {
            s.sky.fixed_exposure_ev = Some(ev);
            s.star_intensity = multiple * at_threshold;
        });
        let l = linear_luminance(&image);
        let mut sorted = l.clone();
        sorted.sort_by(f64::total_cmp);
        let sky = sorted[sorted.len() / 2];
        (l.iter().fold(0.0f64, |m, v| m.max(*v)) - sky, image)
    };
    let (peak_whole, image) = peak_at(whole);
    write(&image, "sirius-threshold-whole");
    // (The view's centre, where the star is, is a pixel corner: the pixels show half the peak.)
    assert!(peak_whole > 0.25, "one magnitude over: {peak_whole:.3}");
    // Drawn in proportion, it would show at 0.6 / 3.5 of that: far over the 8-bit step.
    let (peak_under, _) = peak_at(under);
    assert!(
        peak_under < 0.01 * peak_whole,
        "under the threshold: {peak_under:.4} vs {peak_whole:.3}"
    );
    // Between, partly faded: the ramp gives log2(1.6) * 0.75 = 0.51 of the proportional value.
    let (peak_half, _) = peak_at(half);
    let faded = peak_half / (peak_whole * half / whole);
    assert!((0.25..0.8).contains(&faded), "half-way: {faded:.3}");
}
