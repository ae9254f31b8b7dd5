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
    // A head 10 cm up in a very rough sea: under water, the view is the sea's inside.
    let ((w, h, rgba), _) = periscope("washed", "0.1,6", "6");
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
}
