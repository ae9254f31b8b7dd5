//! End-to-end runs of `cig serve` and `cig host` over UDP on the loopback: the host's HAT/HOT
//! and LOS answers against the database's own queries (`cig query`), bad datagrams on the IG's
//! port, off-screen frames, and bad command-line input.

mod common;

use common::{cig, free_udp_port, one_line_error, run_host, small_db, start_serve};
use serde_json::Value;
use std::net::UdpSocket;
use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// Runs `cig serve --headless` on a scenario for `frames` frames of `size`, writing them to
/// `out_dir`.
fn serve_headless(
    db: &Path,
    scenario: &Path,
    out_dir: &Path,
    size: &str,
    frames: u32,
    extra: &[&str],
) -> std::process::Output {
    cig()
        .args(["serve", "--db"])
        .arg(db)
        .arg("--scenario")
        .arg(scenario)
        .args(["--headless", "--size", size, "--frames"])
        .arg(frames.to_string())
        .args(extra)
        .arg("--cigi-port")
        .arg(free_udp_port().to_string())
        .arg("--out-dir")
        .arg(out_dir)
        .timeout(Duration::from_secs(300))
        .output()
        .expect("serve")
}

fn query_height_msl(db: &Path, lat: f64, lon: f64) -> f64 {
    let out = cig()
        .args(["query", "hat"])
        .arg(db)
        .args([lat.to_string(), lon.to_string(), "--json".into()])
        .output()
        .expect("cig query");
    assert!(out.status.success());
    let v: Value = serde_json::from_slice(&out.stdout).expect("json");
    v["height_m"].as_f64().expect("height_m")
}

fn lines(bytes: &[u8]) -> Vec<Value> {
    String::from_utf8_lossy(bytes)
        .lines()
        .map(|l| serde_json::from_str(l).unwrap_or_else(|e| panic!("{e}: {l}")))
        .collect()
}

#[test]
fn a_scripted_host_gets_answers_that_match_the_database_in_both_versions() {
    let dir = tempfile::tempdir().expect("tempdir");
    let db = small_db(dir.path());
    let points = [(35.99, -121.22), (36.005, -121.21), (36.01, -121.195)];
    for (version, order) in [("3.3", "little"), ("4.0", "big")] {
        let ig_port = free_udp_port();
        let host_port = free_udp_port();
        let serve = start_serve(&[
            "--db".into(),
            db.display().to_string(),
            "--no-render".into(),
            "--cigi-port".into(),
            ig_port.to_string(),
            "--cigi-host".into(),
            format!("127.0.0.1:{host_port}"),
        ]);
        let mut script = format!(
            "version = \"{version}\"\nbyte_order = \"{order}\"\nframes = 60\ntime = \"2026-06-21T10:00:00Z\"\n\
             [[entities]]\nid = 0\ntype = 1\nclamp = \"height\"\nalt_m = 2.0\nspeed_mps = 30\npath = [[35.99, -121.22], [36.01, -121.20]]\n\
             [view]\nentity = 0\noffset_m = [0, 0, -3]\n\
             [[hat]]\nid = 100\nentity = 0\ntype = \"hat\"\nevery_frame = true\n\
             [[los]]\nid = 200\nfrom = [35.99, -121.22, 2000]\nto = [36.01, -121.20, 2000]\nextended = true\nevery_frame = true\n"
        );
        for (i, (lat, lon)) in points.iter().enumerate() {
            script += &format!(
                "[[hat]]\nid = {i}\nlat_deg = {lat}\nlon_deg = {lon}\nalt_m = 1500\ntype = \"extended\"\nevery_frame = true\n"
            );
        }
        let script_path = dir.path().join(format!("host-{version}.toml"));
        std::fs::write(&script_path, script).expect("script");
        let out = run_host(&script_path, ig_port, host_port);
        serve.kill();
        assert!(
            out.status.success(),
            "cig host: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        let answers = lines(&out.stdout);
        let summary = answers.last().expect("summary")["summary"].clone();
        assert!(
            summary["start_of_frames"].as_u64().unwrap_or(0) >= 30,
            "{summary}"
        );
        // Answers come in the IG's next frame: at most a few host frames later.
        assert!(
            summary["latency_frames_max"].as_u64().unwrap_or(99) <= 4,
            "{summary}"
        );
        for (i, (lat, lon)) in points.iter().enumerate() {
            let truth = query_height_msl(&db, *lat, *lon);
            let got: Vec<&Value> = answers
                .iter()
                .filter(|a| a["packet"] == "hat_hot_extended" && a["id"] == i)
                .collect();
            assert!(
                got.len() >= 30,
                "{version}: {} answers to request {i}",
                got.len()
            );
            for a in got {
                assert_eq!(a["valid"], true);
                let hot = a["hot_m"].as_f64().expect("hot");
                let hat = a["hat_m"].as_f64().expect("hat");
                assert!(
                    (hot - truth).abs() < 1e-6,
                    "{version} point {i}: {hot} vs {truth}"
                );
                assert!((hat - (1500.0 - truth)).abs() < 1e-6);
            }
        }
        // The clamped entity sits 2 m above the terrain: HAT of its origin is 2 m.
        let below: Vec<f64> = answers
            .iter()
            .filter(|a| a["packet"] == "hat_hot" && a["id"] == 100)
            .filter_map(|a| a["height_m"].as_f64())
            .collect();
        assert!(below.len() >= 20);
        assert!(below.iter().all(|h| (h - 2.0).abs() < 1e-3), "{below:?}");
        // The high sightline sees over everything.
        let los: Vec<&Value> = answers
            .iter()
            .filter(|a| a["packet"] == "los_extended")
            .collect();
        assert!(
            !los.is_empty()
                && los
                    .iter()
                    .all(|a| a["visible"] == true && a["valid"] == true)
        );
    }
}

#[test]
fn garbage_on_the_cigi_port_is_counted_and_the_ig_keeps_serving() {
    let dir = tempfile::tempdir().expect("tempdir");
    let db = small_db(dir.path());
    let ig_port = free_udp_port();
    let started = Instant::now();
    let serve = start_serve(&[
        "--db".into(),
        db.display().to_string(),
        "--no-render".into(),
        "--cigi-port".into(),
        ig_port.to_string(),
        "--frames".into(),
        "90".into(),
        "--json".into(),
    ]);
    let socket = UdpSocket::bind("127.0.0.1:0").expect("socket");
    socket
        .set_read_timeout(Some(Duration::from_secs(5)))
        .expect("timeout");
    let target = format!("127.0.0.1:{ig_port}");
    let garbage: [&[u8]; 5] = [
        b"",
        &[0xFF; 7],
        &[1, 24, 2, 0, 0, 0, 0x80, 0, 0, 0], // truncated IG Control
        &[
            1, 24, 9, 1, 0, 0, 0x80, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0,
        ], // version 9
        &[0x55; 4000],
    ];
    for g in garbage {
        socket.send_to(g, &target).expect("send");
    }
    // A valid CIGI 3.3 IG Control afterwards, built from ICD 3.3 §4.1.1 by hand (little-endian:
    // the magic number 0x8000 reads 00 80): it is answered, to its sender.
    let mut ig_control = vec![
        1,            // packet ID
        24,           // size
        3,            // major version
        1,            // database number
        (3 << 4) | 1, // minor version 3, IG mode operate
        0,            // reserved
        0x00,
        0x80, // byte-swap magic 0x8000, little-endian
    ];
    ig_control.extend_from_slice(&7u32.to_le_bytes()); // host frame number
    ig_control.extend_from_slice(&[0; 12]); // timestamp, last IG frame, reserved
    socket.send_to(&ig_control, &target).expect("send");
    let mut buf = [0u8; 2048];
    let (n, _) = socket
        .recv_from(&mut buf)
        .expect("the IG answers a valid host message");
    assert!(
        n >= 24 && buf[0] == 101,
        "Start of Frame first: {:?}",
        &buf[..n.min(8)]
    );
    let (status, stdout, stderr) = serve.finish();
    assert!(status.success(), "{stderr}");
    let summary: Value = serde_json::from_slice(&stdout).expect("json summary");
    assert_eq!(summary["frames"], 90);
    assert_eq!(summary["cigi"]["bad_datagrams"], 5, "{summary}");
    assert_eq!(summary["cigi"]["problems_noted"], 5, "{summary}");
    assert_eq!(summary["last_host_frame_number"], 7, "{summary}");
    assert!(started.elapsed() < Duration::from_secs(60));
    assert!(!stderr.contains("panicked"), "{stderr}");
    // Bad datagrams are logged, at most once a second per sender.
    let warnings = stderr
        .lines()
        .filter(|l| l.contains("dropped a datagram"))
        .count();
    assert!((1..=3).contains(&warnings), "{stderr}");
}

#[test]
fn serve_draws_off_screen_frames_of_the_scenario() {
    let dir = tempfile::tempdir().expect("tempdir");
    let db = small_db(dir.path());
    let scenario = dir.path().join("scenario.toml");
    std::fs::write(
        &scenario,
        "start_time = \"2026-06-21T12:00:00Z\"\nvisibility_m = 30000\n\
         [[entities]]\nid = 1\nmodel = \"tank\"\nlat_deg = 35.995\nlon_deg = -121.215\nclamp = \"height_and_attitude\"\nspeed_mps = 10\npath = [[36.0, -121.21]]\n\
         [[smoke]]\nid = 1\nlat_deg = 35.9975\nlon_deg = -121.2125\nstart_s = 0\n\
         [view]\nentity = 1\noffset_m = [-40, 0, -15]\nhpr_deg = [0, -15, 0]\nfov_deg = 50\n",
    )
    .expect("scenario");
    let frames = dir.path().join("frames");
    let out = serve_headless(&db, &scenario, &frames, "96x64", 150, &["--json"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let summary: Value = serde_json::from_slice(&out.stdout).expect("json");
    assert_eq!(summary["frames"], 150);
    assert_eq!(summary["cigi"]["entities"], 1);
    // The tank and the scenario's smoke are drawn.
    assert_eq!(summary["last_frame"]["entities_drawn"], 1, "{summary}");
    assert!(
        summary["last_frame"]["puffs_drawn"].as_u64().unwrap_or(0) > 0,
        "{summary}"
    );
    for i in 0..3 {
        let png = frames.join(format!("frame_{i:05}.png"));
        let decoder = png::Decoder::new(std::io::BufReader::new(
            std::fs::File::open(&png).expect("frame written"),
        ));
        let reader = decoder.read_info().expect("a PNG");
        assert_eq!((reader.info().width, reader.info().height), (96, 64));
    }
}

#[test]
fn bad_serve_and_host_input_gives_one_line_errors() {
    let dir = tempfile::tempdir().expect("tempdir");
    let missing_db = dir.path().join("nowhere");
    let bad_scenario = dir.path().join("bad.toml");
    std::fs::write(
        &bad_scenario,
        "[[entities]]\nid = 1\nlat_deg = 95\nlon_deg = 0\n",
    )
    .expect("write");
    let db = small_db(dir.path());
    let cases: Vec<(Vec<String>, &str)> = vec![
        (
            vec![
                "serve".into(),
                "--db".into(),
                db.display().to_string(),
                "--scenario".into(),
                bad_scenario.display().to_string(),
                "--no-render".into(),
            ],
            "entities[0].lat_deg",
        ),
        (
            vec![
                "serve".into(),
                "--db".into(),
                missing_db.display().to_string(),
                "--no-render".into(),
            ],
            "nowhere",
        ),
        (
            vec![
                "serve".into(),
                "--db".into(),
                db.display().to_string(),
                "--size".into(),
                "0x5".into(),
            ],
            "--size",
        ),
        (
            vec![
                "serve".into(),
                "--db".into(),
                db.display().to_string(),
                "--out-dir".into(),
                "x".into(),
            ],
            "--headless",
        ),
        (
            vec![
                "serve".into(),
                "--db".into(),
                db.display().to_string(),
                "--no-render".into(),
                "--cigi-bind".into(),
                "nosuchif0".into(),
                "--frames".into(),
                "1".into(),
            ],
            "nosuchif0",
        ),
        (
            vec![
                "host".into(),
                "--script".into(),
                bad_scenario.display().to_string(),
            ],
            "host script",
        ),
        (
            vec![
                "host".into(),
                "--script".into(),
                dir.path().join("none.toml").display().to_string(),
            ],
            "none.toml",
        ),
    ];
    for (args, needle) in cases {
        let assert = cig()
            .args(&args)
            .timeout(Duration::from_secs(60))
            .assert()
            .failure();
        let line = one_line_error(&assert);
        assert!(line.contains(needle), "{args:?}: {line}");
    }
}

#[test]
fn serve_publishes_its_scenario_entities_and_draws_remote_ones_over_dis() {
    let dir = tempfile::tempdir().expect("tempdir");
    let db = small_db(dir.path());
    let ig_dis_port = free_udp_port();
    let listen_port = free_udp_port();
    let scenario = dir.path().join("exercise.toml");
    std::fs::write(
        &scenario,
        format!(
            "start_time = \"2026-06-21T12:00:00Z\"\n\
             [[models]]\nmodel = \"ship\"\ndis_type = \"1:3\"\n\
             [[entities]]\nid = 1\nmodel = \"tank\"\ndis_id = \"1:3001:7\"\ndis_type = \"1:1:225:1:1:0:0\"\n\
             lat_deg = 35.995\nlon_deg = -121.215\nclamp = \"height_and_attitude\"\nspeed_mps = 12\npath = [[36.0, -121.21]]\n\
             [dis]\nexercise = 3\nsite = 1\napplication = 3001\nport = {ig_dis_port}\ndelivery = \"unicast:127.0.0.1:{listen_port}\"\n"
        ),
    )
    .expect("scenario");
    let listener = Command::new(assert_cmd::cargo::cargo_bin("cig"))
        .args([
            "dis",
            "listen",
            "--port",
            &listen_port.to_string(),
            "--count",
            "2",
        ])
        .args(["--exercise", "3", "--timeout-s", "60", "--json"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("listener");
    let serve = start_serve(&[
        "--db".into(),
        db.display().to_string(),
        "--scenario".into(),
        scenario.display().to_string(),
        "--no-render".into(),
        "--cigi-port".into(),
        free_udp_port().to_string(),
        "--frames".into(),
        "600".into(),
        "--json".into(),
    ]);
    // A ship of another simulator, sent to the IG's DIS port.
    cig()
        .args([
            "dis",
            "send",
            "--port",
            &ig_dis_port.to_string(),
            "--to",
            "127.0.0.1",
        ])
        .args([
            "--entity",
            "2:5:9",
            "--type",
            "1:3:225:6:1",
            "--exercise",
            "3",
        ])
        .args([
            "--lat",
            "36.0",
            "--lon",
            "-121.2",
            "--alt",
            "0",
            "--velocity",
            "5,0,0",
        ])
        .args(["--count", "5", "--interval-s", "0.1"])
        .timeout(Duration::from_secs(60))
        .assert()
        .success();
    let (status, stdout, stderr) = serve.finish();
    assert!(status.success(), "{stderr}");
    let summary: Value = serde_json::from_slice(&stdout).expect("json");
    let dis = &summary["dis"];
    assert_eq!(dis["remote_entities"], 1, "{summary}");
    assert!(
        dis["entity_states_applied"].as_u64().unwrap_or(0) >= 1,
        "{summary}"
    );
    assert!(dis["pdus_sent"].as_u64().unwrap_or(0) >= 1, "{summary}");
    let heard = listener.wait_with_output().expect("listener ends");
    let pdus = lines(&heard.stdout);
    let tank = pdus
        .iter()
        .find(|p| p["entity_id"] == "1:3001:7")
        .unwrap_or_else(|| panic!("the IG's tank was published: {pdus:?}"));
    assert_eq!(tank["entity_type"], "1:1:225:1:1:0:0");
    let lat = tank["position"]["lat_deg"].as_f64().expect("lat");
    let lon = tank["position"]["lon_deg"].as_f64().expect("lon");
    assert!(
        (lat - 35.995).abs() < 0.002 && (lon + 121.215).abs() < 0.002,
        "{tank}"
    );
}

#[test]
fn serve_shows_its_views_in_a_window() {
    if Command::new("xvfb-run").arg("--help").output().is_err() {
        eprintln!("SKIPPED: xvfb-run is not installed (scripts/setup.sh --test installs xvfb)");
        return;
    }
    let dir = tempfile::tempdir().expect("tempdir");
    let db = small_db(dir.path());
    let scenario = dir.path().join("window.toml");
    std::fs::write(
        &scenario,
        "start_time = \"2026-06-21T12:00:00Z\"\n\
         [[entities]]\nid = 1\nmodel = \"truck\"\nlat_deg = 35.995\nlon_deg = -121.215\nclamp = \"height\"\n\
         [view]\nentity = 1\noffset_m = [-30, 0, -10]\nhpr_deg = [0, -10, 0]\n",
    )
    .expect("scenario");
    let run = Command::new("xvfb-run")
        .args(["-a", "-s", "-screen 0 1280x800x24"])
        .arg(assert_cmd::cargo::cargo_bin("cig"))
        .args(["serve", "--db"])
        .arg(&db)
        .arg("--scenario")
        .arg(&scenario)
        .args(["--size", "320x240", "--frames", "5", "--cigi-port"])
        .arg(free_udp_port().to_string())
        .output()
        .expect("xvfb-run");
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "{stderr}");
    assert!(stderr.contains("served 5 frames in a window"), "{stderr}");
}

#[test]
fn a_hosts_line_of_sight_through_the_scenarios_smoke_is_obscured() {
    let dir = tempfile::tempdir().expect("tempdir");
    let db = small_db(dir.path());
    // Bare ground: the synthetic database's trees would stop the line before the smoke.
    let empty = dir.path().join("no-culture.geojson");
    std::fs::write(&empty, r#"{"type": "FeatureCollection", "features": []}"#).expect("write");
    let cleared = std::process::Command::new(env!("CARGO_BIN_EXE_cig"))
        .args(["db", "culture"])
        .arg(&db)
        .arg(&empty)
        .output()
        .expect("cig db culture");
    assert!(
        cleared.status.success(),
        "{}",
        String::from_utf8_lossy(&cleared.stderr)
    );
    let (lat, lon) = (36.0, -121.21);
    let ground = query_height_msl(&db, lat, lon);
    let scenario = dir.path().join("smoke.toml");
    // 60 simulated seconds a second: the plume grows in a second or two.
    std::fs::write(
        &scenario,
        format!(
            "start_time = \"2026-06-21T12:00:00Z\"\ntime_rate = 60\n\
             [[smoke]]\nid = 1\nlat_deg = {lat}\nlon_deg = {lon}\nheat_release_w = 2e6\n\
             [[smoke]]\nid = 2\nlat_deg = 10.0\nlon_deg = 10.0\n"
        ),
    )
    .expect("scenario");
    let ig_port = free_udp_port();
    let host_port = free_udp_port();
    let serve = start_serve(&[
        "--db".into(),
        db.display().to_string(),
        "--scenario".into(),
        scenario.display().to_string(),
        "--no-render".into(),
        "--cigi-port".into(),
        ig_port.to_string(),
        "--cigi-host".into(),
        format!("127.0.0.1:{host_port}"),
    ]);
    let alt = ground + 30.0;
    // Along the plume (the default wind blows from the west) and, as a control, well south of it.
    let script = format!(
        "frames = 180\n\
         [[los]]\nid = 1\nfrom = [{lat}, -121.215, {alt}]\nto = [{lat}, -121.195, {alt}]\nextended = true\nevery_frame = true\n\
         [[los]]\nid = 2\nfrom = [35.985, -121.215, {alt2}]\nto = [35.985, -121.195, {alt2}]\nextended = true\nevery_frame = true\n",
        alt2 = alt + 400.0,
    );
    let script_path = dir.path().join("los.toml");
    std::fs::write(&script_path, script).expect("script");
    let out = run_host(&script_path, ig_port, host_port);
    let stderr = serve.stderr.lock().map(|s| s.clone()).unwrap_or_default();
    serve.kill();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let answers = lines(&out.stdout);
    let through: Vec<&Value> = answers
        .iter()
        .filter(|a| a["packet"] == "los_extended" && a["id"] == 1 && a["valid"] == true)
        .collect();
    // Clear at first (no smoke yet, no terrain in the way), then stopped by the smoke: an
    // alpha below 255 and no range (a terrain hit would give 255 and a range).
    assert!(
        through.first().is_some_and(|a| a["visible"] == true),
        "{through:?}"
    );
    assert!(
        through.iter().any(|a| a["visible"] == false
            && a["range_valid"] == false
            && (1..255).contains(&a["alpha"].as_u64().unwrap_or(0))),
        "the smoke stops the line at some point: {through:?}"
    );
    let control: Vec<&Value> = answers
        .iter()
        .filter(|a| a["packet"] == "los_extended" && a["id"] == 2)
        .collect();
    assert!(!control.is_empty() && control.iter().all(|a| a["visible"] == true));
    // The source far off the database is refused, with a message.
    assert!(stderr.contains("smoke source 2 cannot"), "{stderr}");
}

#[test]
fn serve_warns_once_of_an_eye_below_the_terrain_and_draws_from_its_surface() {
    let dir = tempfile::tempdir().expect("tempdir");
    let db = small_db(dir.path());
    let scenario = dir.path().join("scenario.toml");
    // The view hangs 300 m below a tank standing on the ground (body z is down).
    std::fs::write(
        &scenario,
        "start_time = \"2026-06-21T19:00:00Z\"\n\
         [[entities]]\nid = 1\nmodel = \"tank\"\nlat_deg = 35.995\nlon_deg = -121.215\nclamp = \"height\"\n\
         [view]\nentity = 1\noffset_m = [0, 0, 300]\nhpr_deg = [0, -10, 0]\nfov_deg = 50\n",
    )
    .expect("scenario");
    let frames = dir.path().join("frames");
    let out = serve_headless(&db, &scenario, &frames, "64x48", 5, &[]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    let warnings: Vec<&str> = stderr
        .lines()
        .filter(|l| l.contains("below the terrain"))
        .collect();
    assert_eq!(warnings.len(), 1, "one warning for five frames: {stderr}");
    assert!(warnings[0].contains("height above terrain -"), "{stderr}");
    let png = frames.join("frame_00004.png");
    assert!(png.exists(), "the frames are drawn");
}

/// Runs `cig serve` without rendering while `cig dis send` sends a land vehicle with
/// `appearance`; the most light points any frame's snapshot held.
fn lights_of_a_remote_land_vehicle(dir: &Path, db: &Path, appearance: &str) -> u64 {
    let ig_dis_port = free_udp_port();
    let scenario = dir.join(format!("lights-{appearance}.toml"));
    std::fs::write(
        &scenario,
        format!(
            "start_time = \"2026-06-21T22:00:00Z\"\n\
             [dis]\nexercise = 3\nsite = 1\napplication = 3001\nport = {ig_dis_port}\ndelivery = \"unicast:127.0.0.1:{}\"\n",
            free_udp_port()
        ),
    )
    .expect("scenario");
    let serve = start_serve(&[
        "--db".into(),
        db.display().to_string(),
        "--scenario".into(),
        scenario.display().to_string(),
        "--no-render".into(),
        "--cigi-port".into(),
        free_udp_port().to_string(),
        "--frames".into(),
        "240".into(),
        "--json".into(),
    ]);
    cig()
        .args(["dis", "send", "--port", &ig_dis_port.to_string()])
        .args([
            "--to",
            "127.0.0.1",
            "--entity",
            "2:5:9",
            "--type",
            "1:1:225:1:1",
        ])
        .args([
            "--exercise",
            "3",
            "--lat",
            "36.0",
            "--lon",
            "-121.2",
            "--alt",
            "0",
        ])
        .args([
            "--appearance",
            appearance,
            "--count",
            "5",
            "--interval-s",
            "0.1",
        ])
        .timeout(Duration::from_secs(30))
        .assert()
        .success();
    let (status, stdout, stderr) = serve.finish();
    assert!(status.success(), "{stderr}");
    let summary: Value = serde_json::from_slice(&stdout).expect("json");
    assert_eq!(summary["dis"]["remote_entities"], 1, "{summary}");
    summary["lights_max"].as_u64().expect("lights_max")
}

#[test]
fn a_dis_headlights_bit_lights_a_remote_vehicles_headlamps() {
    let dir = tempfile::tempdir().expect("tempdir");
    let db = small_db(dir.path());
    let dark = lights_of_a_remote_land_vehicle(dir.path(), &db, "0x0");
    // Land platform appearance bit 12: head lights (SISO-REF-010 UID 31).
    let lit = lights_of_a_remote_land_vehicle(dir.path(), &db, "0x1000");
    assert_eq!(dark, 0);
    assert_eq!(lit, 2, "two headlamps");
}
