//! End-to-end runs of `cig sea`: statistics measured on the simulated surface, the horizon.

mod common;

use common::{cig, json_output, one_line_error, read_png_rgba, small_db};
use std::path::{Path, PathBuf};

fn number(v: &serde_json::Value, key: &str) -> f64 {
    v[key]
        .as_f64()
        .unwrap_or_else(|| panic!("{key} is a number: {v}"))
}

#[test]
fn a_fully_developed_sea_follows_pierson_moskowitz_and_sea_states_fall_in_their_codes() {
    // Pierson-Moskowitz: Hs = 0.21 U19.5^2 / g, U19.5 = 1.026 U10.
    let u10 = 10.0;
    let pm_hs_m = 0.21 * (1.026f64 * u10).powi(2) / 9.806_65;
    let v = json_output(&["sea", "stats", "--wind-mps", "10"]);
    let hs = number(&v, "hs_m");
    assert!((hs / pm_hs_m - 1.0).abs() < 0.15, "{v}");
    let tp = number(&v, "peak_period_s");
    assert!((tp / 7.5 - 1.0).abs() < 0.2, "{v}");
    let whitecaps = number(&v, "whitecap_fraction");
    assert!((0.0..0.2).contains(&whitecaps), "{v}");
    // A fetch of 20 km: a younger, lower sea.
    let young = json_output(&["sea", "stats", "--wind-mps", "10", "--fetch-km", "20"]);
    assert!(number(&young, "hs_m") < 0.8 * hs, "{young}");
    // Sea state 5 (rough): 2.5-4 m.
    let rough = json_output(&["sea", "stats", "--sea-state", "5"]);
    let hs5 = number(&rough, "hs_m");
    assert!((2.5..=4.0).contains(&hs5), "{rough}");
    // The same seed, the same sea; another seed, another realisation.
    let again = json_output(&["sea", "stats", "--wind-mps", "10"]);
    assert_eq!(v, again);
}

#[test]
fn the_horizon_hides_a_hull_below_its_masts() {
    // From 1.5 m with standard refraction a 30 m masthead sinks at about 25.6 km.
    let v = json_output(&["sea", "horizon", "--eye-m", "1.5", "--top-m", "30"]);
    let sinks_m = number(&v, "top_visible_to_m");
    assert!((sinks_m / 25_600.0 - 1.0).abs() < 0.02, "{v}");
    // Without refraction, the geometric horizon: nearer.
    let geometric = json_output(&[
        "sea",
        "horizon",
        "--eye-m",
        "1.5",
        "--top-m",
        "30",
        "--refraction-k",
        "0",
    ]);
    assert!(number(&geometric, "top_visible_to_m") < sinks_m - 500.0);
    // 7.3 m of a ship 15 km away is below the horizon.
    let hidden = json_output(&["sea", "horizon", "--eye-m", "1.5", "--range-m", "15000"]);
    assert!(
        (number(&hidden, "hidden_height_m") / 7.3 - 1.0).abs() < 0.05,
        "{hidden}"
    );
}

#[test]
fn bad_sea_input_gives_one_line_errors() {
    for (args, needle) in [
        (vec!["sea", "stats", "--sea-state", "10"], "--sea-state"),
        (vec!["sea", "stats", "--sea-state", "4.5"], "--sea-state"),
        (vec!["sea", "stats", "--wind-mps", "-3"], "--wind-mps"),
        (vec!["sea", "stats", "--wind-mps", "NaN"], "--wind-mps"),
        (
            vec!["sea", "stats", "--wind-mps", "8", "--fetch-km", "0"],
            "--fetch-km",
        ),
        (vec!["sea", "stats"], "--wind-mps"),
        (vec!["sea", "horizon", "--eye-m", "-2"], "--eye-m"),
        (
            vec!["sea", "horizon", "--eye-m", "2", "--refraction-k", "inf"],
            "--refraction-k",
        ),
    ] {
        let out = cig().args(&args).assert().failure();
        let line = one_line_error(&out);
        assert!(line.contains(needle), "{args:?}: {line}");
    }
}

/// Renders a 320x180 frame with the sea off the small database's west edge (open ocean), 3 m
/// above mean sea level (the geoid lies about 33 m below the ellipsoid there).
fn render_sea(db: &Path, out: &Path, heading_deg: f64, time: &str, sea: &[&str]) -> PathBuf {
    let mut args: Vec<String> = [
        "render",
        "--db",
        &db.display().to_string(),
        "--eye",
        "35.99,-121.40,-30",
        "--hpr",
        &format!("{heading_deg},-3,0"),
        "--size",
        "320x180",
        "--time",
        time,
        "--out",
        &out.display().to_string(),
    ]
    .iter()
    .map(ToString::to_string)
    .collect();
    args.extend(sea.iter().map(ToString::to_string));
    cig().args(&args).assert().success();
    out.to_path_buf()
}

/// Mean of the sRGB channels over rows `rows` of an RGBA frame.
fn mean_rows(pixels: &[u8], width: u32, rows: std::ops::Range<u32>) -> f64 {
    mean_rect(pixels, width, rows, 0..width)
}

/// Mean of the sRGB channels over rows `rows` and columns `columns` of an RGBA frame.
fn mean_rect(
    pixels: &[u8],
    width: u32,
    rows: std::ops::Range<u32>,
    columns: std::ops::Range<u32>,
) -> f64 {
    let w = width as usize;
    let (c0, c1) = (columns.start as usize, columns.end as usize);
    let mut sum = 0.0;
    let mut n = 0.0;
    for y in rows {
        let row = y as usize * w;
        for px in pixels[(row + c0) * 4..(row + c1) * 4].chunks_exact(4) {
            sum += f64::from(px[0]) + f64::from(px[1]) + f64::from(px[2]);
            n += 3.0;
        }
    }
    sum / n
}

#[test]
fn the_sea_glitters_toward_the_sun_is_darker_away_from_it_and_does_not_shimmer() {
    let dir = tempfile::tempdir().expect("tempdir");
    let db = small_db(dir.path());
    // An evening sun low in the west-north-west (about 295 degrees, 10 degrees up).
    let time = "2026-06-22T02:30:00Z";
    let toward = render_sea(
        &db,
        &dir.path().join("toward.png"),
        295.0,
        time,
        &["--sea-state", "3"],
    );
    let away = render_sea(
        &db,
        &dir.path().join("away.png"),
        115.0,
        time,
        &["--sea-state", "3"],
    );
    let bare = render_sea(&db, &dir.path().join("bare.png"), 295.0, time, &[]);
    let (w, h, toward) = read_png_rgba(&toward);
    let (_, _, away) = read_png_rgba(&away);
    let (_, _, bare) = read_png_rgba(&bare);
    // The lower part of the frame is sea.
    let sea_rows = h * 2 / 3..h;
    // The sun's glitter path: the sea under the sun (the middle tenth of the frame) against
    // the same place looking away from it.
    let path = w * 9 / 20..w * 11 / 20;
    let lit = mean_rect(&toward, w, sea_rows.clone(), path.clone());
    let dark = mean_rect(&away, w, sea_rows.clone(), path);
    assert!(lit > 2.0 * dark, "toward the sun {lit:.1}, away {dark:.1}");
    let lit = mean_rows(&toward, w, sea_rows.clone());
    // Without a sea the ground below the horizon is not drawn like water.
    let none = mean_rows(&bare, w, sea_rows.clone());
    assert!(
        (lit - none).abs() > 20.0,
        "with a sea {lit:.1}, without {none:.1}"
    );
    // A still camera over a calm sea, one frame (1/30 s) apart: the far sea, where the waves
    // are finer than a pixel, changes little (no shimmering noise).
    let calm = |name: &str, time: &str| {
        let path = render_sea(
            &db,
            &dir.path().join(name),
            200.0,
            time,
            &["--sea-state", "2"],
        );
        read_png_rgba(&path).2
    };
    let a = calm("calm0.png", "2026-06-21T20:00:00.000Z");
    let b = calm("calm1.png", "2026-06-21T20:00:00.033Z");
    // The far sea: just below the horizon (3 degrees above the frame's centre).
    let far_rows = (h * 45 / 100) * w..(h * 60 / 100) * w;
    let diff: f64 = a[far_rows.start as usize * 4..far_rows.end as usize * 4]
        .iter()
        .zip(&b[far_rows.start as usize * 4..far_rows.end as usize * 4])
        .map(|(x, y)| f64::from(x.abs_diff(*y)))
        .sum::<f64>()
        / f64::from(far_rows.end - far_rows.start)
        / 4.0;
    assert!(
        diff < 3.0,
        "the far sea changes by {diff:.2} levels a frame"
    );
    let moved: f64 = a
        .iter()
        .zip(&b)
        .map(|(x, y)| f64::from(x.abs_diff(*y)))
        .sum::<f64>();
    assert!(moved > 0.0, "the waves move");
}

#[test]
fn a_periscope_sees_48_degrees_over_its_power_draws_its_reticle_and_washes_over() {
    let dir = tempfile::tempdir().expect("tempdir");
    let db = small_db(dir.path());
    let periscope = |name: &str, spec: &str, sea: &str| {
        let out = dir.path().join(format!("{name}.png"));
        let stats = dir.path().join(format!("{name}.json"));
        cig()
            .args(["render", "--db"])
            .arg(&db)
            .args([
                "--eye",
                "35.99,-121.40,500",
                "--hpr",
                "270,0,0",
                "--size",
                "400x200",
                "--time",
                "2026-06-21T20:00:00Z",
                "--periscope",
                spec,
                "--sea-state",
                sea,
                "--out",
            ])
            .arg(&out)
            .arg("--stats")
            .arg(&stats)
            .assert()
            .success();
        let json: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&stats).expect("stats")).expect("json");
        (read_png_rgba(&out), json)
    };
    // 6x: 8 degrees; the head 1.5 m above mean sea level (the geoid about 33 m down here).
    let ((w, h, rgba), json) = periscope("six", "1.5,6", "2");
    let fov = json["fov_deg"][0].as_f64().expect("fov");
    assert!((fov - 8.0).abs() < 1e-9, "{json}");
    let alt = json["eye"][2].as_f64().expect("eye");
    assert!((-40.0..-25.0).contains(&alt), "{json}");
    // The reticle: a black line across the centre, graduated; a major tick every degree.
    let black = |x: u32, y: u32| {
        let i = ((y * w + x) * 4) as usize;
        rgba[i] < 10 && rgba[i + 1] < 10 && rgba[i + 2] < 10
    };
    assert!((0..w).filter(|&x| black(x, h / 2)).count() as f64 > 0.95 * f64::from(w));
    let degree_px =
        (1f64.to_radians().tan() / 4f64.to_radians().tan() * f64::from(w) / 2.0).round() as u32;
    assert!(
        black(w / 2 + degree_px, h / 2 - 5),
        "a major tick 1 degree right"
    );
    // 1.5x: 32 degrees.
    let (_, json) = periscope("low", "1.5,1.5", "2");
    assert!((json["fov_deg"][0].as_f64().expect("fov") - 32.0).abs() < 1e-9);
    // A head 3 m under the mean level of a very rough sea (Hs 4-6 m: the troughs seldom bare
    // it): under water, the view is the sea's inside.
    let ((w, h, rgba), _) = periscope("washed", "-3,6", "6");
    let teal = rgba
        .chunks_exact(4)
        .filter(|p| p[2] > p[0] + 10 && p[1] > p[0] + 10 && p[2] < 90)
        .count();
    assert!(
        teal as f64 > 0.5 * f64::from(w * h),
        "{teal} of {} pixels",
        w * h
    );
    // Bad periscopes.
    for (spec, needle) in [
        ("31,6", "height"),
        ("1,0", "magnification"),
        ("1", "--periscope"),
    ] {
        let out = cig()
            .args(["render", "--db"])
            .arg(&db)
            .args(["--eye", "35.99,-121.40,0", "--periscope", spec, "--out"])
            .arg(dir.path().join("bad.png"))
            .assert()
            .failure();
        let line = one_line_error(&out);
        assert!(line.contains(needle), "{spec}: {line}");
    }
    // Bad refraction and explicit waves.
    for (args, needle) in [
        (vec!["--refraction", "2"], "--refraction"),
        (vec!["--refraction", "NaN"], "--refraction"),
        (
            vec!["--sea-state", "2", "--sea-wave", "40,100,8,0"],
            "wave height",
        ),
        (
            vec!["--sea-state", "2", "--sea-wave", "1,100"],
            "--sea-wave",
        ),
        (
            vec!["--sea-state", "2", "--sea-wave", "1,100,0,0"],
            "wave period",
        ),
        (vec!["--sea-wave", "1,100,8,0"], "--sea-wave"),
        (
            vec!["--sea-state", "2", "--sea-wave", "1,100,8,0@95,0,100,100"],
            "region's centre",
        ),
        (
            vec!["--sea-state", "2", "--sea-wave", "1,100,8,0@35,0,-100,100"],
            "region's sizes",
        ),
        (
            vec!["--sea-state", "2", "--sea-wave", "1,100,8,0@35,0"],
            "region",
        ),
    ] {
        let out = cig()
            .args(["render", "--db"])
            .arg(&db)
            .args(["--eye", "35.99,-121.40,0", "--out"])
            .arg(dir.path().join("bad.png"))
            .args(&args)
            .assert()
            .failure();
        let line = one_line_error(&out);
        assert!(line.contains(needle), "{args:?}: {line}");
    }
}

/// The altitude (above the ellipsoid) of a point `height_m` above mean sea level at
/// 35.99 N 121.40 W, west of the small database: the geoid's height there from a periscope's
/// stats.
fn altitude_above_sea(db: &Path, dir: &Path, height_m: f64) -> f64 {
    let stats = dir.join("eye.json");
    cig()
        .args(["render", "--db"])
        .arg(db)
        .args([
            "--eye",
            "35.99,-121.40,0",
            "--size",
            "64x32",
            "--periscope",
            &format!("{height_m},6"),
            "--sea-state",
            "0",
            "--out",
        ])
        .arg(dir.join("eye.png"))
        .arg("--stats")
        .arg(&stats)
        .assert()
        .success();
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&stats).expect("stats")).expect("json");
    json["eye"][2].as_f64().expect("eye altitude")
}

/// The rows a ship changes in a frame against the same frame without it: (top, bottom).
fn changed_rows(with: &[u8], without: &[u8], width: u32) -> Option<(u32, u32)> {
    let rows: Vec<u32> = with
        .chunks_exact(width as usize * 4)
        .zip(without.chunks_exact(width as usize * 4))
        .enumerate()
        .filter(|(_, (a, b))| {
            a.iter()
                .zip(*b)
                .enumerate()
                .any(|(i, (x, y))| i % 4 != 3 && x.abs_diff(*y) > 12)
        })
        .map(|(y, _)| y as u32)
        .collect();
    Some((*rows.first()?, *rows.last()?))
}

#[test]
fn a_ship_past_the_horizon_shows_its_masts_sinks_hull_first_and_refraction_lifts_it() {
    let dir = tempfile::tempdir().expect("tempdir");
    let db = small_db(dir.path());
    // The eye 1.5 m above a calm sea west of the database.
    let eye_alt_m = altitude_above_sea(&db, dir.path(), 1.5);
    let (eye_m, masthead_m) = (1.5, 40.0);
    let (width, height, fov_deg) = (960_u32, 480_u32, 1.2_f64);
    // Looking west; the destroyer a quarter of a degree right of the centre, broadside on.
    let render = |name: &str, range_m: Option<f64>, refraction: &str| {
        let out = dir.path().join(format!("{name}.png"));
        let mut command = cig();
        command
            .args(["render", "--db"])
            .arg(&db)
            .args([
                "--eye",
                &format!("35.99,-121.40,{eye_alt_m}"),
                "--hpr",
                "270,0,0",
                "--fov",
                &fov_deg.to_string(),
                "--size",
                &format!("{width}x{height}"),
                "--time",
                "2026-06-21T19:00:00Z",
                "--visibility",
                "200000",
                "--sea-state",
                "0",
                "--refraction",
                refraction,
                "--out",
            ])
            .arg(&out);
        if let Some(range_m) = range_m {
            let (north, east) = cig_geo::metres_per_degree(35.99);
            let bearing = 270.25_f64.to_radians();
            let lat = 35.99 + range_m * bearing.cos() / north;
            let lon = -121.40 + range_m * bearing.sin() / east;
            command.args(["--entity", &format!("destroyer,{lat},{lon},0,0")]);
        }
        command.assert().success();
        let (w, _, rgba) = read_png_rgba(&out);
        assert_eq!(w, width);
        rgba
    };
    // Where a point `z_m` above the sea `range_m` away is drawn (row), for refraction `k`.
    let radius_m = 6_371_000.0 / 1.0;
    let row_of = |z_m: f64, range_m: f64, k: f64| {
        let effective_m = radius_m / (1.0 - k);
        let angle = (z_m - eye_m) / range_m - range_m / (2.0 * effective_m);
        let half_v = (fov_deg.to_radians() / 2.0).tan() * f64::from(height) / f64::from(width);
        f64::from(height) / 2.0 - angle.tan() / half_v * f64::from(height) / 2.0
    };
    let hidden_m = |range_m: f64, k: f64| {
        let effective_m = radius_m / (1.0 - k);
        let horizon_m = (2.0 * effective_m * eye_m).sqrt();
        (range_m - horizon_m).max(0.0).powi(2) / (2.0 * effective_m)
    };
    let sinks_at_m = |k: f64| {
        let effective_m = radius_m / (1.0 - k);
        (2.0 * effective_m * eye_m).sqrt() + (2.0 * effective_m * masthead_m).sqrt()
    };
    for (refraction, k) in [("standard", 0.13), ("off", 0.0)] {
        let empty = render(&format!("empty-{refraction}"), None, refraction);
        // 20 km: the masts and the upper works over the horizon, drawn where the earth and
        // the refraction put them.
        let at_20km = render(&format!("20km-{refraction}"), Some(20_000.0), refraction);
        let (top, bottom) = changed_rows(&at_20km, &empty, width).expect("the ship shows at 20 km");
        let (want_top, want_bottom) = (
            row_of(masthead_m, 20_000.0, k),
            row_of(hidden_m(20_000.0, k), 20_000.0, k),
        );
        assert!(
            (f64::from(top) - want_top).abs() < 3.0
                && (f64::from(bottom) - want_bottom).abs() < 3.0,
            "{refraction}: rows {top}-{bottom}, the geometry says {want_top:.1}-{want_bottom:.1}"
        );
        // Where the masthead sinks: seen a little nearer, gone a little farther.
        let sinks_m = sinks_at_m(k);
        let near = render(
            &format!("near-{refraction}"),
            Some(0.95 * sinks_m),
            refraction,
        );
        assert!(
            changed_rows(&near, &empty, width).is_some(),
            "{refraction}: the masthead shows at {:.0} m",
            0.95 * sinks_m
        );
        let far = render(
            &format!("far-{refraction}"),
            Some(1.05 * sinks_m),
            refraction,
        );
        assert_eq!(
            changed_rows(&far, &empty, width),
            None,
            "{refraction}: the ship is gone at {:.0} m",
            1.05 * sinks_m
        );
        if k > 0.0 {
            // 15 km: the masts show, the waterline is hidden (7.3 m down with refraction).
            let at_15km = render("15km", Some(15_000.0), refraction);
            let (top, bottom) =
                changed_rows(&at_15km, &empty, width).expect("the ship shows at 15 km");
            assert!((f64::from(top) - row_of(masthead_m, 15_000.0, k)).abs() < 3.0);
            assert!(
                f64::from(bottom) < row_of(5.0, 15_000.0, k),
                "the hull shows to row {bottom}, below 5 m above the waterline ({:.1})",
                row_of(5.0, 15_000.0, k)
            );
            // Refraction lifts the picture: the masthead higher than the geometric earth's.
            assert!(row_of(masthead_m, 20_000.0, k) < row_of(masthead_m, 20_000.0, 0.0) - 5.0);
        }
    }
}

#[test]
fn the_drawn_waves_stand_where_the_height_queries_put_them() {
    use cig_sea::spectrum::SeaConditions;
    use cig_sea::surface::{SeaSurface, SurfaceConfig, WaveComponent};
    let dir = tempfile::tempdir().expect("tempdir");
    let db = small_db(dir.path());
    // The eye 0.5 m above the mean sea, looking west (out to sea) along a lone 4 m swell
    // travelling west: the nearest crest hides the horizon.
    let (lat, lon) = (35.99, -121.40);
    let eye_alt_m = altitude_above_sea(&db, dir.path(), 0.5);
    let (width, height, fov_deg) = (200_u32, 400_u32, 4.0_f64);
    let time = "2026-06-21T19:00:00Z";
    let unix_s = 1_782_068_400.0;
    // The same surface on the CPU, in the sea's plane (the database centre's whole degrees).
    let mut surface = SeaSurface::new(
        &SeaConditions::new(0.0, 270.0).expect("calm"),
        1,
        SurfaceConfig::default(),
    )
    .expect("surface");
    surface
        .set_explicit_waves(vec![
            WaveComponent::new(4.0, 300.0, 13.9, 270.0, 0.0, 0.0).expect("wave")
        ])
        .expect("waves");
    surface
        .update(cig_scene::sea::wave_clock_s(unix_s))
        .expect("time");
    let plane = cig_geo::EnuFrame::new(cig_scene::sea::sea_origin(36.0, -121.2));
    let (_, per_deg) = cig_geo::metres_per_degree(lat);
    let height_at = |east_m: f64| {
        let p = plane.geodetic_to_enu(cig_geo::Geodetic::new(lat, lon + east_m / per_deg, 0.0));
        surface.sample(p.x, p.y).height_m
    };
    // The eye 1 m above the mean sea over the trough nearest the place: the next crest
    // ahead stands a metre above it.
    let trough_m = (-150..=150)
        .map(f64::from)
        .min_by(|a, b| height_at(*a).total_cmp(&height_at(*b)))
        .expect("a trough");
    let render_edge = |wave: &str| {
        let out = dir.path().join("swell.png");
        cig()
            .args(["render", "--db"])
            .arg(&db)
            .args([
                "--eye",
                &format!("{lat},{},{}", lon + trough_m / per_deg, eye_alt_m + 0.5),
                "--hpr",
                "270,0,0",
                "--fov",
                &fov_deg.to_string(),
                "--size",
                &format!("{width}x{height}"),
                "--time",
                time,
                "--sea-wind",
                "0",
                "--sea-wave",
                wave,
                "--out",
            ])
            .arg(&out)
            .assert()
            .success();
        let (_, _, rgba) = read_png_rgba(&out);
        // The sea's top edge: the sharpest step in brightness down the middle columns (the
        // sky above it and the sea below change smoothly).
        let brightness = |y: u32| {
            let mut sum = 0.0;
            for x in width / 2 - 10..width / 2 + 10 {
                let i = ((y * width + x) * 4) as usize;
                sum += f64::from(rgba[i]) + f64::from(rgba[i + 1]) + f64::from(rgba[i + 2]);
            }
            sum / 60.0
        };
        let row = (1..height - 1)
            .max_by(|a, b| {
                let step = |y: u32| (brightness(y - 1) - brightness(y + 1)).abs();
                step(*a).total_cmp(&step(*b))
            })
            .expect("rows");
        (
            f64::from(row),
            (row.saturating_sub(6)..row + 6)
                .map(|y| brightness(y).round())
                .collect::<Vec<_>>(),
        )
    };
    // The row of the highest sightline the sea reaches ahead (over the nearest crest).
    let want_row = |height_at: &dyn Fn(f64) -> f64| {
        let mut top = f64::MIN;
        let mut x_m = 2.0;
        while x_m < 3000.0 {
            let h = height_at(trough_m - x_m);
            let angle = (h - 1.0) / x_m - x_m * (1.0 - 0.13) / (2.0 * 6_371_000.0);
            top = top.max(angle);
            x_m += 0.5;
        }
        let half_v = (fov_deg.to_radians() / 2.0).tan() * f64::from(height) / f64::from(width);
        f64::from(height) / 2.0 - top.tan() / half_v * f64::from(height) / 2.0
    };
    let crest_row = want_row(&height_at);
    let (row, rows) = render_edge("4,300,13.9,270");
    assert!(
        (row - crest_row).abs() < 3.0,
        "the sea's top at row {row}, the height queries say {crest_row:.1} (rows: {rows:?})"
    );
    // Without the swell the edge is the horizon, well below the crest.
    let horizon_row = want_row(&|_| 0.0);
    assert!(
        crest_row > f64::from(height) / 2.0 - 30.0 && crest_row < f64::from(height) / 2.0 - 10.0
    );
    assert!(horizon_row > crest_row + 8.0, "{horizon_row} {crest_row}");
    // The swell confined to a region (as a host's regional Wave Control): over the sightline
    // it stands where it did; 30 km north, the sea ahead is calm to the horizon.
    let (row, rows) = render_edge(&format!("4,300,13.9,270@{lat},{lon},8000,8000,0,0,500"));
    assert!(
        (row - crest_row).abs() < 3.0,
        "in its region the swell's top at row {row}, not {crest_row:.1} (rows: {rows:?})"
    );
    let (row, rows) = render_edge(&format!(
        "4,300,13.9,270@{},{lon},8000,8000,0,0,500",
        lat + 0.3
    ));
    assert!(
        (row - horizon_row).abs() < 3.0,
        "outside its region the sea's top at row {row}, the horizon at {horizon_row:.1} (rows: {rows:?})"
    );
}

#[test]
fn in_the_thermal_infrared_the_sea_is_colder_at_grazing_angles_where_it_mirrors_the_sky() {
    let dir = tempfile::tempdir().expect("tempdir");
    let db = small_db(dir.path());
    // From about 30 m above a smooth sea at night, LWIR (white hot): looking 30 degrees down
    // the water emits with an emissivity of 0.99 below the eye, less and less toward the
    // horizon, where it reflects the cold sky.
    let out = dir.path().join("lwir.png");
    cig()
        .args(["render", "--db"])
        .arg(&db)
        .args([
            "--eye",
            "35.99,-121.40,0",
            "--hpr",
            "270,-30,0",
            "--fov",
            "60",
            "--size",
            "160x120",
            "--time",
            "2026-06-22T06:00:00Z",
            "--sea-state",
            "1",
            "--sensor",
            "lwir",
            "--out",
        ])
        .arg(&out)
        .assert()
        .success();
    let (w, h, grey) = read_png_rgba(&out);
    // Rows toward the horizon (the frame's top edge lies 6.6 degrees below it), against rows
    // below the eye.
    let grazing = mean_rows(&grey, w, 2..h / 8);
    let steep = mean_rows(&grey, w, h * 3 / 4..h);
    assert!(
        steep > grazing + 40.0,
        "below the eye {steep:.0}, toward the horizon {grazing:.0}"
    );
    // And the grey falls steadily toward the horizon: no band where the sea goes missing.
    let bands: Vec<f64> = (0..8)
        .map(|k| mean_rows(&grey, w, k * h / 8..(k + 1) * h / 8))
        .collect();
    assert!(bands.windows(2).all(|p| p[1] >= p[0] - 3.0), "{bands:?}");
}

#[test]
fn a_ship_under_way_draws_its_wake_astern_and_round_its_turn() {
    let dir = tempfile::tempdir().expect("tempdir");
    let db = small_db(dir.path());
    // Looking down from 200 m at a destroyer heading north 300 m ahead (north) of the eye.
    let render = |name: &str, entity: &str| {
        let out = dir.path().join(format!("{name}.png"));
        cig()
            .args(["render", "--db"])
            .arg(&db)
            .args([
                "--eye",
                "35.99,-121.40,170",
                "--hpr",
                "0,-50,0",
                "--fov",
                "60",
                "--size",
                "240x180",
                "--time",
                "2026-06-21T19:00:00Z",
                "--sea-state",
                "2",
                "--entity",
                entity,
                "--out",
            ])
            .arg(&out)
            .assert()
            .success();
        read_png_rgba(&out)
    };
    let ship = "destroyer,35.9927,-121.40,0,0";
    let (w, h, still) = render("still", ship);
    let (_, _, under_way) = render("under-way", &format!("{ship},speed=10"));
    // Astern of the ship (below it in the frame, toward the eye): white water under way.
    let astern = |rgba: &[u8]| mean_rect(rgba, w, h * 3 / 4..h, w / 2 - 6..w / 2 + 6);
    let beside = |rgba: &[u8]| mean_rect(rgba, w, h * 3 / 4..h, 10..30);
    assert!(
        astern(&under_way) > astern(&still) + 40.0,
        "astern: {:.0} under way, {:.0} still",
        astern(&under_way),
        astern(&still)
    );
    // Away from the track the sea is the same.
    assert!((beside(&under_way) - beside(&still)).abs() < 3.0);
    // Turning to starboard at 3 degrees a second it came from the south-east: its white water
    // bends away to the right of the frame, off the straight course's line astern.
    let (_, _, turning) = render("turning", &format!("{ship},speed=10,turn=3"));
    let right =
        |rgba: &[u8]| mean_rect(rgba, w, h * 58 / 100..h * 66 / 100, w * 7 / 10..w * 8 / 10);
    assert!(
        right(&turning) > right(&under_way) + 40.0,
        "right of the line: {:.0} turning, {:.0} straight",
        right(&turning),
        right(&under_way)
    );
    assert!(
        astern(&turning) < astern(&under_way) - 40.0,
        "on the straight line astern: {:.0} turning, {:.0} straight",
        astern(&turning),
        astern(&under_way)
    );
}

#[test]
fn straight_down_over_a_calm_sea_the_haze_has_no_cone_at_the_nadir() {
    // From 3 km, straight down, the morning sun low in the east: the haze between the eye
    // and the sea is lit from all around, so it is the same in every direction round the
    // nadir (it once took the horizon sky of each ray's azimuth: a cone, brighter toward and
    // away from the sun, darker to the sides, seamed at the nadir).
    let dir = tempfile::tempdir().expect("tempdir");
    let db = small_db(dir.path());
    let out = dir.path().join("nadir.png");
    cig()
        .args(["render", "--db"])
        .arg(&db)
        .args([
            "--eye",
            "35.99,-121.44,3000",
            "--hpr",
            "0,-89.9,0",
            "--fov",
            "60",
            "--size",
            "160x90",
            "--time",
            "2026-06-21T16:00:00Z",
            "--sea-wind",
            "0",
            "--out",
        ])
        .arg(&out)
        .assert()
        .success();
    let (w, h, rgba) = read_png_rgba(&out);
    let brightness = |x: u32, y: u32| {
        let i = ((y * w + x) * 4) as usize;
        u32::from(rgba[i]) + u32::from(rgba[i + 1]) + u32::from(rgba[i + 2])
    };
    // Close round the nadir (a degree or two) every direction agrees; further out the haze
    // may brighten smoothly toward one side (the path's own light), but a cone would differ
    // by as much at any radius.
    for radius in [1.5_f64, 3.0] {
        let ring: Vec<u32> = (0..16)
            .map(|k| {
                let a = std::f64::consts::TAU * f64::from(k) / 16.0;
                let x = (f64::from(w / 2) + radius * a.cos()).round() as u32;
                let y = (f64::from(h / 2) - radius * a.sin()).round() as u32;
                brightness(x, y)
            })
            .collect();
        let (lo, hi) = (
            ring.iter().copied().min().unwrap_or(0),
            ring.iter().copied().max().unwrap_or(0),
        );
        assert!(
            hi - lo <= 9 && lo > 100,
            "{radius} px round the nadir: {ring:?}"
        );
    }
}
