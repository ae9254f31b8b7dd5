//! End-to-end runs of `cig render` and `cig bench render` (lavapipe when there is no GPU).

mod common;

use common::{cig, one_line_error, small_db};
use serde_json::Value;
use std::path::Path;

fn render_args(db: &Path, out: &Path) -> Vec<String> {
    [
        "render",
        "--db",
        &db.display().to_string(),
        "--eye",
        "35.99,-121.22,900",
        "--hpr",
        "45,-20,0",
        "--fov",
        "60",
        "--size",
        "128x96",
        "--time",
        "2026-06-21T19:00:00Z",
        "--out",
        &out.display().to_string(),
    ]
    .iter()
    .map(|s| s.to_string())
    .collect()
}

#[test]
fn render_writes_a_png_and_its_statistics() {
    let dir = tempfile::tempdir().expect("tmp");
    let db = small_db(dir.path());
    let out = dir.path().join("frame.png");
    let stats = dir.path().join("stats.json");
    cig()
        .args(render_args(&db, &out))
        .args(["--stats", &stats.display().to_string()])
        .args([
            "--entity",
            "tank,35.995,-121.215,0,30,clamp",
            "--fog",
            "exp2",
            "--visibility",
            "8000",
        ])
        .assert()
        .success();
    let png = std::fs::read(&out).expect("png");
    assert_eq!(&png[1..4], b"PNG");
    let json: Value = serde_json::from_slice(&std::fs::read(&stats).expect("stats")).expect("json");
    for key in [
        "triangles",
        "tiles_resident",
        "draw_calls",
        "cpu_ms",
        "gpu_ms",
        "klod",
        "klod_nominal",
    ] {
        assert!(json[key].is_number(), "{key} in {json}");
    }
    assert!(json["triangles"].as_u64().unwrap_or(0) > 1000);
    assert!(json["draw_calls"].as_u64().unwrap_or(0) > 1);
    // Full detail draws more triangles than the default 1 px.
    let full = dir.path().join("full.json");
    cig()
        .args(render_args(&db, &dir.path().join("full.png")))
        .args([
            "--max-pixel-error",
            "0",
            "--stats",
            &full.display().to_string(),
        ])
        .assert()
        .success();
    let full: Value = serde_json::from_slice(&std::fs::read(&full).expect("stats")).expect("json");
    assert!(full["triangles"].as_u64() > json["triangles"].as_u64());
}

#[test]
fn bad_render_input_gives_one_line_errors() {
    let dir = tempfile::tempdir().expect("tmp");
    let db = small_db(dir.path());
    let out = dir.path().join("frame.png");
    let cases: Vec<(Vec<&str>, &str)> = vec![
        (vec!["--size", "0x10"], "--size"),
        (vec!["--fov", "180"], "field of view"),
        (vec!["--eye", "35.99,-121.22,-2000"], "below the ellipsoid"),
        (vec!["--eye", "95,-121.22,100"], "latitude"),
        (vec!["--time", "yesterday"], "--time"),
        (vec!["--fog", "soup"], "--fog"),
        (vec!["--max-pixel-error", "-1"], "--max-pixel-error"),
        (vec!["--entity", "zeppelin,35.99,-121.21,0"], "no model"),
        (vec!["--ground-fog", "300"], "--ground-fog"),
        (vec!["--ground-fog", "300,0"], "--ground-fog"),
        (vec!["--ground-fog", "1e6,100"], "--ground-fog"),
        (vec!["--sky", "cartoon"], "--sky"),
        (vec!["--exposure-ev", "40"], "--exposure-ev"),
        (vec!["--fixed-exposure-ev", "NaN"], "--fixed-exposure-ev"),
    ];
    for (extra, expect) in cases {
        let mut args = render_args(&db, &out);
        // Later values of the same option win in clap only for repeated flags; rebuild instead.
        for pair in extra.chunks(2) {
            if let Some(i) = args.iter().position(|a| a == pair[0]) {
                args[i + 1] = pair[1].to_string();
            } else {
                args.push(pair[0].to_string());
                args.push(pair[1].to_string());
            }
        }
        let line = one_line_error(&cig().args(&args).assert().failure());
        assert!(line.contains(expect), "{extra:?}: {line}");
    }
    let missing = dir.path().join("nowhere");
    let line = one_line_error(&cig().args(render_args(&missing, &out)).assert().failure());
    assert!(line.contains("nowhere"), "{line}");
    let broken = dir.path().join("broken.glb");
    std::fs::write(&broken, b"glTF garbage").expect("write");
    let mut args = render_args(&db, &out);
    args.extend([
        "--entity".to_string(),
        format!("{},35.99,-121.21,0", broken.display()),
    ]);
    let line = one_line_error(&cig().args(&args).assert().failure());
    assert!(line.contains("broken.glb"), "{line}");
    assert!(!out.exists(), "no frame written after an error");
}

fn read_rgba(path: &Path) -> Vec<u8> {
    common::read_png_rgba(path).2
}

#[test]
fn render_draws_smoke_plumes_from_the_command_line() {
    let dir = tempfile::tempdir().expect("tmp");
    let db = small_db(dir.path());
    let clear = dir.path().join("clear.png");
    cig().args(render_args(&db, &clear)).assert().success();
    let smoky = dir.path().join("smoke.png");
    let stats = dir.path().join("stats.json");
    cig()
        .args(render_args(&db, &smoky))
        .args([
            "--smoke",
            "35.995,-121.215,20,90",
            "--smoke",
            "35.993,-121.21",
            "--wind",
            "4,250",
            "--stats",
            &stats.display().to_string(),
        ])
        .assert()
        .success();
    let json: Value = serde_json::from_slice(&std::fs::read(&stats).expect("stats")).expect("json");
    assert!(json["puffs_drawn"].as_u64().unwrap_or(0) > 500, "{json}");
    assert!(json["puff_gpu_ms"].is_number(), "{json}");
    let (a, b) = (read_rgba(&clear), read_rgba(&smoky));
    assert_eq!(a.len(), b.len());
    let changed = a
        .chunks_exact(4)
        .zip(b.chunks_exact(4))
        .filter(|(p, q)| (0..3).any(|c| p[c].abs_diff(q[c]) > 8))
        .count();
    assert!(changed > 20, "only {changed} pixels show the smoke");
}

#[test]
fn render_draws_cloud_layers_from_the_command_line() {
    let dir = tempfile::tempdir().expect("tmp");
    let db = small_db(dir.path());
    let clear = dir.path().join("clear.png");
    cig().args(render_args(&db, &clear)).assert().success();
    let cloudy = dir.path().join("cloudy.png");
    let stats = dir.path().join("stats.json");
    cig()
        .args(render_args(&db, &cloudy))
        .args([
            "--cloud",
            "1200,400,1,stratus",
            "--cloud",
            "3000,800,0.4,cumulus,10,250",
            "--stats",
            &stats.display().to_string(),
        ])
        .assert()
        .success();
    let json: Value = serde_json::from_slice(&std::fs::read(&stats).expect("stats")).expect("json");
    assert_eq!(json["cloud_layers_drawn"].as_u64(), Some(2), "{json}");
    assert!(json["cloud_gpu_ms"].is_number(), "{json}");
    let (a, b) = (read_rgba(&clear), read_rgba(&cloudy));
    assert_eq!(a.len(), b.len());
    let changed = a
        .chunks_exact(4)
        .zip(b.chunks_exact(4))
        .filter(|(p, q)| (0..3).any(|c| p[c].abs_diff(q[c]) > 8))
        .count();
    // Under an overcast the sky greys and the sunlit ground is in shade: most pixels change.
    assert!(changed > a.len() / 4 / 2, "only {changed} pixels changed");
}

#[test]
fn bad_cloud_values_give_one_line_errors() {
    let dir = tempfile::tempdir().expect("tmp");
    let db = small_db(dir.path());
    let out = dir.path().join("frame.png");
    let cases: Vec<(&str, &str)> = vec![
        ("1200,400", "--cloud"),
        ("1200,400,0.5,cumulus,10", "--cloud"),
        ("1200,400,1.5", "coverage"),
        ("1200,0,0.5", "thickness"),
        ("1e6,400,0.5", "base"),
        ("1200,400,0.5,fog", "not a cloud type"),
        ("1200,400,0.5,stratus,-3,90", "wind speed"),
        ("1200,400,nan", "coverage"),
        ("1200,400,0.5,stratus,5,x", "wind direction"),
    ];
    for (value, expect) in cases {
        let mut args = render_args(&db, &out);
        args.extend(["--cloud".to_string(), value.to_string()]);
        let line = one_line_error(&cig().args(&args).assert().failure());
        assert!(
            line.contains(expect) && line.contains("--cloud"),
            "{value}: {line}"
        );
    }
    let mut args = render_args(&db, &out);
    for _ in 0..5 {
        args.extend(["--cloud".to_string(), "1200,400,0.5".to_string()]);
    }
    let line = one_line_error(&cig().args(&args).assert().failure());
    assert!(line.contains("at most 4"), "{line}");
    assert!(!out.exists(), "no frame written after an error");
}

#[test]
fn bad_smoke_and_wind_values_give_one_line_errors() {
    let dir = tempfile::tempdir().expect("tmp");
    let db = small_db(dir.path());
    let out = dir.path().join("frame.png");
    let cases: Vec<(&str, &str, &str)> = vec![
        ("--smoke", "fire", "--smoke"),
        ("--smoke", "35.99", "--smoke"),
        ("--smoke", "35.99,-121.21,5,60,7", "--smoke"),
        ("--smoke", "95,-121.21", "latitude"),
        ("--smoke", "35.99,-121.21,-5", "heat release"),
        ("--smoke", "35.99,-121.21,nan", "--smoke"),
        ("--smoke", "35.99,-121.21,5,0", "seconds"),
        ("--smoke", "35.99,-121.21,5,1e9", "seconds"),
        ("--smoke", "10,10", "cannot be placed on the terrain"),
        ("--wind", "5", "--wind"),
        ("--wind", "-1,270", "speed"),
        ("--wind", "5,inf", "--wind"),
    ];
    for (option, value, expect) in cases {
        let mut args = render_args(&db, &out);
        args.extend([option.to_string(), value.to_string()]);
        if option == "--wind" {
            args.extend(["--smoke".to_string(), "35.995,-121.215".to_string()]);
        }
        let line = one_line_error(&cig().args(&args).assert().failure());
        assert!(line.contains(expect), "{option} {value}: {line}");
    }
    assert!(!out.exists(), "no frame written after an error");
}

#[test]
fn render_reports_the_exposure_and_its_sky_and_exposure_options_change_the_frame() {
    let dir = tempfile::tempdir().expect("tmp");
    let db = small_db(dir.path());
    let frame = |name: &str, extra: &[&str]| -> (Vec<u8>, Value) {
        let out = dir.path().join(format!("{name}.png"));
        let stats = dir.path().join(format!("{name}.json"));
        cig()
            .args(render_args(&db, &out))
            .args(["--stats", &stats.display().to_string()])
            .args(extra)
            .assert()
            .success();
        let json = serde_json::from_slice(&std::fs::read(&stats).expect("stats")).expect("json");
        (read_rgba(&out), json)
    };
    let mean = |px: &[u8]| px.iter().map(|&v| f64::from(v)).sum::<f64>() / px.len() as f64;
    let (physical, stats) = frame("physical", &[]);
    // Daylight: about 10^5 lux, EV about 15.
    let lux = stats["illuminance_lux"].as_f64().unwrap_or(0.0);
    assert!((5.0e4..1.5e5).contains(&lux), "{stats}");
    let ev = stats["exposure_ev"].as_f64().unwrap_or(0.0);
    assert!((14.0..16.5).contains(&ev), "{stats}");
    let (brighter, _) = frame("brighter", &["--exposure-ev", "1.5"]);
    assert!(mean(&brighter) > mean(&physical) * 1.2);
    let (flat, _) = frame("flat", &["--sky", "flat"]);
    assert_ne!(flat, physical);
    // A fixed exposure for a moonlit night burns the daylight frame out.
    let (burnt, stats) = frame("burnt", &["--fixed-exposure-ev", "-3"]);
    assert!(mean(&burnt) > 240.0, "{}", mean(&burnt));
    assert!(
        (stats["exposure_ev"].as_f64().unwrap_or(0.0) + 3.0).abs() < 1e-6,
        "{stats}"
    );
}

#[test]
fn bench_env_reports_the_ephemeris_cost_and_the_sky_share() {
    let dir = tempfile::tempdir().expect("tmp");
    let db = small_db(dir.path());
    let out = cig()
        .args(["bench", "env", "--json", "--db", &db.display().to_string()])
        .args(["--size", "96x64", "--frames", "3", "--rounds", "1"])
        .assert()
        .success();
    let json: Value = serde_json::from_slice(&out.get_output().stdout).expect("json");
    let us = json["ephemeris_us_per_update"].as_f64().unwrap_or(0.0);
    assert!(us > 0.0 && us < 10_000.0, "{json}");
    assert!(
        json["lighting_us_per_view"].as_f64().unwrap_or(0.0) > 0.0,
        "{json}"
    );
    let pass = &json["passes"]["sky_and_fog"];
    assert!(
        pass["frame_ms_median"].as_f64().unwrap_or(0.0) > 0.0,
        "{json}"
    );
    assert!(
        pass["share_of_frame"].as_f64().is_some_and(f64::is_finite),
        "{json}"
    );
    assert!(
        json["flat_frame_ms_median"].as_f64().unwrap_or(0.0) > 0.0,
        "{json}"
    );
    assert_eq!(json["frames"].as_u64(), Some(3));
    let line = one_line_error(
        &cig()
            .args([
                "bench",
                "env",
                "--db",
                &db.display().to_string(),
                "--frames",
                "1",
            ])
            .assert()
            .failure(),
    );
    assert!(line.contains("--frames"), "{line}");
}

#[test]
fn bench_render_reports_both_ways_and_their_ratios() {
    let dir = tempfile::tempdir().expect("tmp");
    let db = small_db(dir.path());
    let out = cig()
        .args([
            "bench",
            "render",
            "--db",
            &db.display().to_string(),
            "--json",
        ])
        .args(["--size", "96x64", "--frames", "12", "--compare-frames", "2"])
        .assert()
        .success();
    let json: Value = serde_json::from_slice(&out.get_output().stdout).expect("json");
    for key in ["triangles_full_over_lod", "frame_time_full_over_lod"] {
        assert!(
            json["ratios"][key].as_f64().unwrap_or(0.0) > 0.0,
            "{key}: {json}"
        );
    }
    assert!(json["pass"]["max_over_median_after_warmup"]
        .as_f64()
        .is_some());
    assert!(json["lod"]["cpu_select_ms"]["median"].as_f64().is_some());
    // Selection is also timed on its own, with no frame drawn between selections.
    let alone = json["lod"]["cpu_select_ms_alone"]["median"].as_f64();
    assert!(alone.is_some_and(|ms| ms > 0.0), "{json}");
    assert!(
        json["full_detail"]["triangles_mean"].as_f64() >= json["lod"]["triangles_mean"].as_f64()
    );
    // The plumes comparison: every one of the 32 plumes' puffs in view, timed both ways.
    let plumes = &json["plumes"];
    assert_eq!(plumes["plumes"].as_u64(), Some(32), "{plumes}");
    assert!(
        plumes["puffs_drawn_mean"].as_f64().unwrap_or(0.0) > 5000.0,
        "{plumes}"
    );
    for key in ["frame_time_with_over_without", "puff_share_of_frame_time"] {
        assert!(
            plumes[key].as_f64().is_some_and(f64::is_finite),
            "{key}: {plumes}"
        );
    }
    assert!(
        plumes["frame_ms_with"]["median"].as_f64() > Some(0.0),
        "{plumes}"
    );
}

#[test]
fn demo_flies_to_png_frames_without_a_display_and_in_a_window_with_one() {
    let dir = tempfile::tempdir().expect("tmp");
    let db = dir.path().join("demo-db");
    cig()
        .args(["db", "synth", "--out"])
        .arg(&db)
        .args([
            "--origin",
            "35.98,-121.23",
            "--size-km",
            "50",
            "--spacing-m",
            "150",
        ])
        .assert()
        .success();
    let out = dir.path().join("frames");
    cig()
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY")
        .args([
            "demo",
            "--db",
            &db.display().to_string(),
            "--out",
            &out.display().to_string(),
        ])
        .assert()
        .success();
    let frames = std::fs::read_dir(&out)
        .expect("frames dir")
        .filter(|e| {
            e.as_ref()
                .map(|e| e.file_name().to_string_lossy().starts_with("frame_"))
                .unwrap_or(false)
        })
        .count();
    // 24 of the flight, then the environment: moon, cumulus from below and above, a storm, the
    // valley at night through a thermal sight (grey: a white display) and through night-vision
    // goggles (green in a black circle); then the periscope at sea, 1.5x and 6x.
    assert_eq!(frames, 32);
    let (_, _, thermal) = common::read_png_rgba(&out.join("frame_028.png"));
    assert!(thermal.chunks(4).all(|p| p[0] == p[1] && p[1] == p[2]));
    let (w, h, goggles) = common::read_png_rgba(&out.join("frame_029.png"));
    assert!(
        goggles[..4].iter().take(3).all(|c| *c == 0),
        "the corner is the mask"
    );
    let centre = ((h / 2 * w + w / 2) * 4) as usize;
    let px = &goggles[centre..centre + 3];
    assert!(px[1] > px[0] && px[1] > px[2] && px[1] > 20, "{px:?}");
    // The periscope: the sky above the reticle's line and the sea below it, bluer than grey,
    // and the sea darker than the sky over it.
    for frame in ["frame_030.png", "frame_031.png"] {
        let (w, h, scope) = common::read_png_rgba(&out.join(frame));
        let mean = |rows: std::ops::Range<u32>| {
            let mut sum = [0.0_f64; 3];
            let mut n = 0.0;
            for y in rows {
                for x in (0..w).step_by(7) {
                    let i = ((y * w + x) * 4) as usize;
                    for c in 0..3 {
                        sum[c] += f64::from(scope[i + c]);
                    }
                    n += 1.0;
                }
            }
            sum.map(|s| s / n)
        };
        let sky = mean(h / 20..h / 5);
        let sea = mean(h * 3 / 4..h * 19 / 20);
        assert!(sea[2] > sea[0] + 5.0, "{frame}: sea {sea:?}");
        assert!(
            sea.iter().sum::<f64>() < sky.iter().sum::<f64>(),
            "{frame}: sea {sea:?} against sky {sky:?}"
        );
    }
    let sheet = std::fs::read(out.join("contact-sheet.png")).expect("contact sheet");
    assert_eq!(&sheet[1..4], b"PNG");

    if std::process::Command::new("xvfb-run")
        .arg("--help")
        .output()
        .is_err()
    {
        eprintln!("SKIPPED the window half: xvfb-run is not installed (scripts/setup.sh --test installs xvfb)");
        return;
    }
    let binary = assert_cmd::cargo::cargo_bin("cig");
    let run = std::process::Command::new("xvfb-run")
        .args(["-a", "-s", "-screen 0 1280x800x24"])
        .arg(&binary)
        .args([
            "demo",
            "--db",
            &db.display().to_string(),
            "--exit-after-frames",
            "4",
        ])
        .output()
        .expect("xvfb-run");
    let stdout = String::from_utf8_lossy(&run.stdout);
    assert!(
        run.status.success(),
        "{stdout}\n{}",
        String::from_utf8_lossy(&run.stderr)
    );
    assert!(
        stdout.contains("flying in a window") && stdout.contains("4 frames"),
        "{stdout}"
    );
}

/// Renders with `extra` arguments at `time`; returns the PNG's bytes and the statistics.
fn render_with(db: &Path, dir: &Path, name: &str, time: &str, extra: &[&str]) -> (Vec<u8>, Value) {
    let out = dir.join(format!("{name}.png"));
    let stats = dir.join(format!("{name}.json"));
    let mut args = render_args(db, &out);
    if let Some(i) = args.iter().position(|a| a == "--time") {
        args[i + 1] = time.to_string();
    }
    let assert = cig()
        .args(&args)
        .args(["--stats", &stats.display().to_string()])
        .args(extra)
        .assert()
        .success();
    let stderr = String::from_utf8_lossy(&assert.get_output().stderr).to_string();
    if extra.contains(&"--lightning") {
        assert!(stderr.contains("segments generated in"), "{stderr}");
    }
    let json: Value = serde_json::from_slice(&std::fs::read(&stats).expect("stats")).expect("json");
    (std::fs::read(&out).expect("png"), json)
}

#[test]
fn render_draws_rain_snow_and_lightning() {
    let dir = tempfile::tempdir().expect("tmp");
    let db = small_db(dir.path());
    let day = "2026-06-21T19:00:00Z";
    let (clear, clear_stats) = render_with(&db, dir.path(), "clear", day, &[]);
    assert_eq!(clear_stats["precipitation_particles"], 0);
    assert_eq!(clear_stats["bolt_lines_drawn"], 0);
    let (rain, rain_stats) = render_with(&db, dir.path(), "rain", day, &["--rain", "20"]);
    assert!(rain_stats["precipitation_particles"].as_u64().unwrap_or(0) > 1000);
    assert_ne!(rain, clear);
    let (snow, snow_stats) = render_with(&db, dir.path(), "snow", day, &["--snow", "2"]);
    assert!(snow_stats["precipitation_particles"].as_u64().unwrap_or(0) > 1000);
    assert_ne!(snow, rain);
    let night = "2026-06-22T07:00:00Z";
    let (dark, _) = render_with(&db, dir.path(), "night", night, &[]);
    let (bolt, bolt_stats) =
        render_with(&db, dir.path(), "bolt", night, &["--lightning", "7,2000"]);
    assert!(bolt_stats["bolt_lines_drawn"].as_u64().unwrap_or(0) > 10);
    assert_ne!(bolt, dark);
    // The same seed draws the same bolt.
    let (again, _) = render_with(&db, dir.path(), "again", night, &["--lightning", "7,2000"]);
    assert_eq!(again, bolt);
}

#[test]
fn bad_weather_values_give_one_line_errors() {
    let dir = tempfile::tempdir().expect("tmp");
    let db = small_db(dir.path());
    let out = dir.path().join("frame.png");
    let cases: Vec<(Vec<&str>, &str)> = vec![
        (vec!["--rain", "heavy"], "--rain"),
        (vec!["--rain", "-1"], "rain rate -1 mm/h is outside 0..200"),
        (vec!["--snow", "500"], "snow rate 500 mm/h"),
        (vec!["--snow", "nan"], "--snow"),
        (vec!["--rain", "5", "--snow", "1"], "cannot be used with"),
        (vec!["--lightning", "bright"], "--lightning"),
        (vec!["--lightning", "-3"], "seed"),
        (vec!["--lightning", "3,10"], "distance 10 m"),
        (vec!["--lightning", "3,inf"], "--lightning"),
    ];
    for (extra, expect) in cases {
        let mut args = render_args(&db, &out);
        args.extend(extra.iter().map(|s| s.to_string()));
        let line = one_line_error(&cig().args(&args).assert().failure());
        assert!(line.contains(expect), "{extra:?}: {line}");
    }
    assert!(!out.exists(), "no frame written after an error");
}

#[test]
fn an_eye_below_the_terrain_is_drawn_from_its_surface_with_one_warning() {
    let dir = tempfile::tempdir().expect("tmp");
    let db = small_db(dir.path());
    let render = |name: &str, eye: &str| {
        let out = dir.path().join(format!("{name}.png"));
        let mut args = render_args(&db, &out);
        let at = args.iter().position(|a| a == "--eye").expect("--eye") + 1;
        args[at] = eye.to_string();
        let output = cig().args(&args).output().expect("cig runs");
        assert!(output.status.success(), "{output:?}");
        (
            String::from_utf8_lossy(&output.stderr).to_string(),
            read_rgba(&out),
        )
    };
    // 500 m below the ellipsoid: under the ground anywhere on this database.
    let (warning, below) = render("below", "35.99,-121.22,-500");
    let lines: Vec<&str> = warning
        .lines()
        .filter(|l| l.contains("below the terrain"))
        .collect();
    assert_eq!(lines.len(), 1, "{warning}");
    assert!(
        lines[0].contains("height above terrain -") && lines[0].contains("35.99"),
        "{warning}"
    );
    // The frame is the terrain seen from just above it, not the inside of the hill: the same
    // as an eye placed 1 m above the ground there, and nothing like black.
    let (quiet, above) = render("above", "35.99,-121.22,900");
    assert!(!quiet.contains("below the terrain"), "{quiet}");
    let mean = |px: &[u8]| px.iter().map(|&v| f64::from(v)).sum::<f64>() / px.len() as f64;
    assert!(mean(&below) > 30.0, "{}", mean(&below));
    assert_ne!(below, above);
}

#[test]
fn render_draws_night_vision_lights_and_a_flare() {
    let dir = tempfile::tempdir().expect("tmp");
    let db = small_db(dir.path());
    let night = "2026-06-22T05:00:00Z";
    let (_, plain) = render_with(&db, dir.path(), "night", night, &[]);
    let (goggles, stats) = render_with(
        &db,
        dir.path(),
        "nvg",
        night,
        &[
            "--sensor",
            "nvg",
            "--phosphor",
            "white",
            "--nvg-gain",
            "2",
            "--light",
            "36.0,-121.2,700,5000,sodium",
            "--flare",
            "36.005,-121.19,1000",
        ],
    );
    // The database's street and porch lights, and on goggles the lamp and the flare as well.
    let street = plain["light_points"].as_u64().expect("count");
    assert!(street > 0, "{plain}");
    assert_eq!(stats["light_points"].as_u64(), Some(street + 2), "{stats}");
    assert!(!goggles.is_empty());
    let (_, _, rgba) = common::read_png_rgba(&dir.path().join("nvg.png"));
    assert!(
        rgba[..3].iter().all(|c| *c == 0),
        "the corner is the goggle's mask"
    );
}

#[test]
fn bad_night_vision_and_light_values_give_one_line_errors() {
    let dir = tempfile::tempdir().expect("tmp");
    let db = small_db(dir.path());
    let out = dir.path().join("frame.png");
    let cases: Vec<(&str, &str, &str)> = vec![
        ("--light", "36.0,-121.2,700,-5", "intensity"),
        ("--light", "36.0,-121.2,700,nan", "--light"),
        ("--light", "36.0,-121.2,700,inf", "finite numbers"),
        ("--light", "36.0,-121.2,700,1e12", "intensity"),
        ("--light", "36.0,-121.2,700", "--light"),
        ("--light", "36.0,-121.2,700,100,purple", "unknown colour"),
        ("--light", "10,10,700,100", "outside the database"),
        ("--flare", "10,10,900", "outside the database"),
        ("--flare", "36.0,-121.2,-400", "below the ground"),
        ("--phosphor", "amber", "unknown phosphor"),
        ("--nvg-gain", "0", "--nvg-gain"),
        ("--nvg-gain", "nan", "--nvg-gain"),
        ("--sensor", "goggles", "nvg"),
    ];
    for (option, value, expect) in cases {
        let mut args = render_args(&db, &out);
        args.extend([option.to_string(), value.to_string()]);
        let line = one_line_error(&cig().args(&args).assert().failure());
        assert!(line.contains(expect), "{option} {value}: {line}");
    }
    assert!(!out.exists(), "no frame written after an error");
}
