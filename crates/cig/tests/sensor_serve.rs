//! The thermal sensor in the IG: a scenario's sensor view drawn by `cig serve --headless`, and a
//! host switching a view to LWIR over UDP with CIGI Sensor Control (3.3 and 4.0).

mod common;

use common::{cig, free_udp_port, read_png_rgba, run_host, small_db, start_serve};
use std::path::Path;
use std::time::Duration;

/// Whether every pixel of a frame is grey (R = G = B): a white sensor display.
fn grey(path: &Path) -> bool {
    let (_, _, rgba) = read_png_rgba(path);
    rgba.chunks(4).all(|p| p[0] == p[1] && p[1] == p[2])
}

fn frames(dir: &Path) -> Vec<std::path::PathBuf> {
    let mut v: Vec<_> = std::fs::read_dir(dir)
        .map(|d| d.filter_map(Result::ok).map(|e| e.path()).collect())
        .unwrap_or_default();
    v.retain(|p| p.extension().is_some_and(|e| e == "png"));
    v.sort();
    v
}

#[test]
fn a_scenario_sensor_view_is_drawn_in_lwir() {
    let dir = tempfile::tempdir().expect("tempdir");
    let db = small_db(dir.path());
    let scenario = dir.path().join("thermal.toml");
    std::fs::write(
        &scenario,
        "start_time = \"2026-06-22T04:00:00Z\"\n\
         [thermal]\nair_min_c = 8\nair_max_c = 26\nhumidity_pct = 40\naerosol = \"rural\"\n\
         [[entities]]\nid = 1\nmodel = \"tank\"\nlat_deg = 36.003\nlon_deg = -121.21\nclamp = \"height\"\nengine = true\n\
         [view]\neye = [36.0, -121.21, 700]\nhpr_deg = [0, -10, 0]\nfov_deg = 50\nsensor = \"lwir\"\n",
    )
    .expect("scenario");
    let out_dir = dir.path().join("frames");
    let out = cig()
        .args(["serve", "--db"])
        .arg(&db)
        .arg("--scenario")
        .arg(&scenario)
        .args([
            "--headless",
            "--size",
            "96x64",
            "--frames",
            "3",
            "--cigi-port",
        ])
        .arg(free_udp_port().to_string())
        .arg("--out-dir")
        .arg(&out_dir)
        .timeout(Duration::from_secs(300))
        .output()
        .expect("serve");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let written = frames(&out_dir);
    assert!(!written.is_empty());
    for f in &written {
        assert!(grey(f), "{} is not a sensor frame", f.display());
    }
    // A bad sensor name in the scenario is one line naming it.
    std::fs::write(
        &scenario,
        "[view]\neye = [36.0, -121.21, 700]\nsensor = \"uv\"\n",
    )
    .expect("scenario");
    let bad = cig()
        .args(["serve", "--db"])
        .arg(&db)
        .arg("--scenario")
        .arg(&scenario)
        .args(["--no-render", "--frames", "1"])
        .assert()
        .failure();
    let line = common::one_line_error(&bad);
    assert!(line.contains("uv"), "{line}");
}

#[test]
fn cigi_sensor_control_turns_a_view_into_lwir_in_both_versions() {
    let dir = tempfile::tempdir().expect("tempdir");
    let db = small_db(dir.path());
    for (version, order) in [("3.3", "little"), ("4.0", "big")] {
        for sensor in [false, true] {
            let ig_port = free_udp_port();
            let host_port = free_udp_port();
            let out_dir = dir.path().join(format!("frames-{version}-{sensor}"));
            let serve = start_serve(&[
                "--db".into(),
                db.display().to_string(),
                "--headless".into(),
                "--size".into(),
                "64x48".into(),
                "--out-dir".into(),
                out_dir.display().to_string(),
                "--cigi-port".into(),
                ig_port.to_string(),
                "--cigi-host".into(),
                format!("127.0.0.1:{host_port}"),
                "--frames".into(),
                "40".into(),
            ]);
            let mut script = format!(
                "version = \"{version}\"\nbyte_order = \"{order}\"\nframes = 60\ntime = \"2026-06-21T20:00:00Z\"\n\
                 [[entities]]\nid = 0\ntype = 1\nclamp = \"height\"\nalt_m = 60.0\nspeed_mps = 0\npath = [[35.99, -121.22]]\n\
                 [view]\nentity = 0\nhpr_deg = [0, -10, 0]\nfov_deg = [-30, 30, -20, 20]\n"
            );
            if sensor {
                script += "[view.sensor]\non = true\nblack_hot = true\nautomatic_gain = true\nnoise = 0.1\n";
            }
            let script_path = dir.path().join(format!("host-{version}-{sensor}.toml"));
            std::fs::write(&script_path, script).expect("script");
            let host = run_host(&script_path, ig_port, host_port);
            assert!(
                host.status.success(),
                "{}",
                String::from_utf8_lossy(&host.stderr)
            );
            let (status, _, stderr) = serve.finish();
            assert!(status.success(), "{stderr}");
            let written = frames(&out_dir);
            let last = written.last().expect("frames written");
            assert_eq!(
                grey(last),
                sensor,
                "{version}: sensor {sensor}, {}",
                last.display()
            );
        }
    }
}

#[test]
fn the_tracker_holds_a_moving_hot_tank_and_breaks_lock_when_it_leaves_the_frame() {
    let dir = tempfile::tempdir().expect("tempdir");
    let db = small_db(dir.path());
    let scenario = dir.path().join("tanks.toml");
    // No dust trail: on a night field the dust (at the air's temperature, warmer than the
    // cooled ground) is a second warm target the tracker may hold after the tank has gone.
    std::fs::write(
        &scenario,
        "[[models]]\nmodel = \"tank\"\ncigi_type = 1\ndust = false\n",
    )
    .expect("scenario");
    let ig_port = free_udp_port();
    let host_port = free_udp_port();
    let serve = start_serve(&[
        "--db".into(),
        db.display().to_string(),
        "--scenario".into(),
        scenario.display().to_string(),
        "--headless".into(),
        "--size".into(),
        "160x120".into(),
        "--cigi-port".into(),
        ig_port.to_string(),
        "--cigi-host".into(),
        format!("127.0.0.1:{host_port}"),
        "--idle-exit-s".into(),
        "3".into(),
    ]);
    // The observer 250 m above a wood looking down 27.7 degrees at a field 530 m north; a tank
    // (an active CIGI entity: its engine runs) crossing the field west to east at 15 m/s, at
    // night.
    let script = "version = \"3.3\"\nframes = 720\ntime = \"2026-06-22T08:00:00Z\"\n\
         [[entities]]\nid = 0\ntype = 1\nclamp = \"height\"\nalt_m = 250.0\nspeed_mps = 0\npath = [[35.9805, -121.205]]\n\
         [[entities]]\nid = 1\ntype = 1\nclamp = \"height\"\nalt_m = 0.0\nspeed_mps = 15\npath = [[35.9853, -121.20578], [35.9853, -121.1900]]\n\
         [view]\nentity = 0\nhpr_deg = [0, -27.7, 0]\nfov_deg = [-5, 5, -3.75, 3.75]\n\
         [view.sensor]\non = true\ntrack_mode = 3\nextended = true\n";
    let script_path = dir.path().join("track.toml");
    std::fs::write(&script_path, script).expect("script");
    let host = run_host(&script_path, ig_port, host_port);
    let (status, _, stderr) = serve.finish();
    assert!(status.success(), "{stderr}");
    let text = String::from_utf8_lossy(&host.stdout).to_string();
    let tracks: Vec<serde_json::Value> = text
        .lines()
        .filter_map(|l| serde_json::from_str::<serde_json::Value>(l).ok())
        .filter(|v| v["packet"] == "sensor_extended")
        .collect();
    let statuses: Vec<u64> = tracks
        .iter()
        .map(|v| v["status"].as_u64().unwrap_or(9))
        .collect();
    let first_track = statuses
        .iter()
        .position(|s| *s == 1)
        .unwrap_or_else(|| panic!("never tracking: {statuses:?}"));
    // The tracked entity is the tank, at its place.
    let tracked = &tracks[first_track];
    assert_eq!(tracked["entity"], 1, "{tracked}");
    let lat = tracked["track"][0].as_f64().unwrap_or(0.0);
    assert!((lat - 35.9853).abs() < 0.0005, "{tracked}");
    let tracking = statuses.iter().filter(|s| **s == 1).count();
    assert!(tracking >= 20, "tracked {tracking} frames: {statuses:?}");
    // The tank leaves the frame: impending breaklock, then breaklock, then searching again.
    let rest = &statuses[first_track..];
    let lost = rest
        .iter()
        .position(|s| *s == 3)
        .unwrap_or_else(|| panic!("no breaklock: {statuses:?}"));
    assert!(rest[..lost].contains(&2), "{statuses:?}");
    assert!(rest[lost..].contains(&0), "{statuses:?}");
}
