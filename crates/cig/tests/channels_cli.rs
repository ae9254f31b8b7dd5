//! End-to-end runs of a multi-channel IG: channels of one eyepoint continuous across their
//! seams, a slave that never sends, synchronous channels that draw the same host frames and
//! stop together, the display correction's warp and blend, and bad channel input.

mod common;

use common::{cig, free_udp_port, one_line_error, run_host, small_db, start_serve};
use serde_json::Value;
use std::net::UdpSocket;
use std::path::Path;
use std::time::Duration;

/// A frame read back from its PNG.
struct Frame {
    width: u32,
    height: u32,
    rgba: Vec<u8>,
}

impl Frame {
    fn pixel(&self, x: u32, y: u32) -> [u8; 4] {
        let i = ((y * self.width + x) * 4) as usize;
        [
            self.rgba[i],
            self.rgba[i + 1],
            self.rgba[i + 2],
            self.rgba[i + 3],
        ]
    }
}

fn png(path: &Path) -> Frame {
    let (width, height, rgba) = common::read_png_rgba(path);
    Frame {
        width,
        height,
        rgba,
    }
}

/// `cig render` of the small database with the arguments every frame here shares.
fn render(db: &Path, fov: &str, size: &str, out: &Path, extra: &[&str]) {
    cig()
        .args(["render", "--db"])
        .arg(db)
        .args([
            "--eye",
            "36.0,-121.2,700",
            "--hpr",
            "200,-6,0",
            "--time",
            "2026-06-21T19:00:00Z",
            "--fixed-exposure-ev",
            "14",
            "--fov",
            fov,
            "--size",
            size,
            "--out",
        ])
        .arg(out)
        .args(extra)
        .timeout(Duration::from_secs(300))
        .assert()
        .success();
}

/// Mean absolute difference over one column of two images, 0..255.
fn column_difference(a: &Frame, ax: u32, b: &Frame, bx: u32) -> f64 {
    let mut sum = 0.0;
    for y in 0..a.height {
        let (p, q) = (a.pixel(ax, y), b.pixel(bx, y));
        for c in 0..3 {
            sum += f64::from(p[c].abs_diff(q[c]));
        }
    }
    sum / f64::from(a.height * 3)
}

#[test]
fn three_adjacent_channels_match_one_wide_view_at_their_seams() {
    let dir = tempfile::tempdir().expect("tempdir");
    let db = small_db(dir.path());
    // Three channels splitting a 90° view into equal thirds of its tangent (so each has the
    // wide view's pixels), with a tank and a truck on the left seam, smoke across it and a
    // cloud layer.
    let scene = [
        "--entity",
        "tank,35.9945,-121.2002,0,90,clamp",
        "--entity",
        "truck,35.9925,-121.2005,0,0,clamp",
        "--smoke",
        "35.990,-121.2005,8,600",
        "--cloud",
        "1500,300,0.5",
    ];
    let third = 18.434_948_822_922_01_f64; // atan(1/3)
    let (w, h) = (120u32, 90u32);
    let channels = [
        format!("45,{},20,20", -third),
        format!("{third},{third},20,20"),
        format!("{},45,20,20", -third),
    ];
    let mut frames = Vec::new();
    for (i, fov) in channels.iter().enumerate() {
        let out = dir.path().join(format!("channel{i}.png"));
        render(&db, fov, &format!("{w}x{h}"), &out, &scene);
        frames.push(png(&out));
    }
    let wide_out = dir.path().join("wide.png");
    render(
        &db,
        "45,45,20,20",
        &format!("{}x{h}", 3 * w),
        &wide_out,
        &scene,
    );
    let wide = png(&wide_out);
    // Each channel's edge columns are the wide view's columns there.
    let seams = [
        (0, w - 1, w - 1),
        (1, 0, w),
        (1, w - 1, 2 * w - 1),
        (2, 0, 2 * w),
    ];
    for (channel, x, wide_x) in seams {
        let d = column_difference(&frames[channel], x, &wide, wide_x);
        assert!(
            d < 1.5,
            "channel {channel} column {x}: {d:.2} from the wide view's"
        );
    }
    // And the whole channels too (the picture, not only the seams, is the same).
    for (channel, frame) in frames.iter().enumerate() {
        let mut sum = 0.0;
        for x in 0..w {
            sum += column_difference(frame, x, &wide, channel as u32 * w + x);
        }
        let mean = sum / f64::from(w);
        assert!(
            mean < 1.0,
            "channel {channel}: {mean:.2} from the wide view"
        );
    }
    // The test can fail: the centre channel two pixels off its place does not match (about
    // 0.5 in place, 1.9 two pixels off on lavapipe).
    let shifted: f64 = (0..w - 2)
        .map(|x| column_difference(&frames[1], x, &wide, w + x + 2))
        .sum::<f64>()
        / f64::from(w - 2);
    assert!(shifted > 1.0, "{shifted}");
}

#[test]
fn an_identity_warp_changes_nothing_a_shift_moves_the_picture_and_a_blend_dims_its_edge() {
    let dir = tempfile::tempdir().expect("tempdir");
    let db = small_db(dir.path());
    let grid = |f: &dyn Fn(f64, f64) -> (f64, f64)| {
        let (c, r) = (5, 4);
        let nodes: Vec<String> = (0..r)
            .flat_map(|j| (0..c).map(move |i| (f64::from(i) / 4.0, f64::from(j) / 3.0)))
            .map(|(u, v)| {
                let (x, y) = f(u, v);
                format!("[{x}, {y}]")
            })
            .collect();
        format!(
            "columns = {c}\nrows = {r}\ndisplay = [{}]\n",
            nodes.join(", ")
        )
    };
    let identity = dir.path().join("identity.toml");
    std::fs::write(&identity, grid(&|u, v| (u, v))).expect("write");
    let shift = dir.path().join("shift.toml");
    std::fs::write(&shift, grid(&|u, v| (u + 0.25, v))).expect("write");
    let blend = dir.path().join("blend.toml");
    std::fs::write(&blend, "right = 0.25\ngamma = 2.2\n").expect("write");
    let (w, h) = (96u32, 72u32);
    let size = format!("{w}x{h}");
    let plain_out = dir.path().join("plain.png");
    render(&db, "60", &size, &plain_out, &[]);
    let identity_out = dir.path().join("identity.png");
    render(
        &db,
        "60",
        &size,
        &identity_out,
        &["--warp", identity.to_str().expect("utf-8")],
    );
    let (plain, same) = (png(&plain_out), png(&identity_out));
    assert_eq!(plain.rgba, same.rgba, "the identity warp changed the frame");
    // A quarter of the display to the right: pixel x of the view lands at x + 24 exactly, the
    // first 24 columns are black.
    let shift_out = dir.path().join("shift.png");
    render(
        &db,
        "60",
        &size,
        &shift_out,
        &["--warp", shift.to_str().expect("utf-8")],
    );
    let moved = png(&shift_out);
    for y in 0..h {
        for x in 0..w {
            let got = moved.pixel(x, y);
            let expected = if x < w / 4 {
                [0, 0, 0, 255]
            } else {
                plain.pixel(x - w / 4, y)
            };
            assert_eq!(got, expected, "pixel {x},{y}");
        }
    }
    // The right quarter's ramp: the value times w^(1/2.2), smoothstep weight w, 0 at the edge.
    let blend_out = dir.path().join("blend.png");
    render(
        &db,
        "60",
        &size,
        &blend_out,
        &["--blend", blend.to_str().expect("utf-8")],
    );
    let blended = png(&blend_out);
    for x in 0..w {
        let from_edge = 1.0 - (f64::from(x) + 0.5) / f64::from(w);
        let t = (from_edge / 0.25).clamp(0.0, 1.0);
        let factor = (t * t * (3.0 - 2.0 * t)).powf(1.0 / 2.2);
        for y in (0..h).step_by(7) {
            for c in 0..3 {
                let expected = f64::from(plain.pixel(x, y)[c]) * factor;
                let got = f64::from(blended.pixel(x, y)[c]);
                assert!(
                    (got - expected).abs() <= 1.0,
                    "pixel {x},{y}: {got} for {expected}"
                );
            }
        }
    }
}

/// A host script with an entity, its three channels' views and a HAT request every frame.
fn three_view_script(dir: &Path, frames: u32, rate_hz: u32) -> std::path::PathBuf {
    let script = dir.join("host.toml");
    let mut text = format!(
        "rate_hz = {rate_hz}\nframes = {frames}\ntime = \"2026-06-21T19:00:00Z\"\n\
         [[entities]]\nid = 0\ntype = 1\nalt_m = 900\nspeed_mps = 40\npath = [[35.99, -121.21], [36.01, -121.21]]\n\
         [[hat]]\nid = 1\nlat_deg = 36.0\nlon_deg = -121.2\nalt_m = 1500\ntype = \"hat\"\nevery_frame = true\n"
    );
    for (id, fov) in [(0, "-45, -15"), (1, "-15, 15"), (2, "15, 45")] {
        text.push_str(&format!(
            "[[views]]\nid = {id}\nentity = 0\noffset_m = [20, 0, 0]\nhpr_deg = [0, -5, 0]\nfov_deg = [{fov}, -20, 20]\n"
        ));
    }
    std::fs::write(&script, text).expect("script");
    script
}

#[test]
fn a_slave_answers_nothing_and_publishes_nothing_and_leaves_the_masters_answers_alone() {
    let dir = tempfile::tempdir().expect("tempdir");
    let db = small_db(dir.path());
    let script = three_view_script(dir.path(), 40, 20);
    // The exercise's traffic of an IG with an entity of its own goes to this socket.
    let dis_sink = UdpSocket::bind("127.0.0.1:0").expect("socket");
    dis_sink
        .set_read_timeout(Some(Duration::from_millis(300)))
        .expect("timeout");
    let sink_port = dis_sink.local_addr().expect("address").port();
    let scenario = dir.path().join("exercise.toml");
    std::fs::write(
        &scenario,
        format!(
            "start_time = \"2026-06-21T12:00:00Z\"\n\
             [[entities]]\nid = 1\nmodel = \"tank\"\ndis_id = \"1:3001:7\"\ndis_type = \"1:1:225:1:1:0:0\"\n\
             lat_deg = 35.995\nlon_deg = -121.215\nclamp = \"height_and_attitude\"\nspeed_mps = 12\npath = [[36.0, -121.21]]\n\
             [dis]\nexercise = 3\nsite = 1\napplication = 3001\nport = {}\ndelivery = \"unicast:127.0.0.1:{sink_port}\"\n",
            free_udp_port()
        ),
    )
    .expect("scenario");
    let drain = |sink: &UdpSocket| {
        let mut count = 0;
        let mut buf = [0u8; 2048];
        while sink.recv_from(&mut buf).is_ok() {
            count += 1;
        }
        count
    };
    let serve = |role: &str, port: u16, extra: &[String]| {
        let mut args: Vec<String> = [
            "--db",
            &db.display().to_string(),
            "--scenario",
            &scenario.display().to_string(),
            "--no-render",
            "--role",
            role,
            "--cigi-port",
            &port.to_string(),
            "--frames",
            "240",
            "--json",
        ]
        .iter()
        .map(ToString::to_string)
        .collect();
        args.extend_from_slice(extra);
        start_serve(&args)
    };
    let hat_answers = |out: &std::process::Output| -> Vec<f64> {
        String::from_utf8_lossy(&out.stdout)
            .lines()
            .filter_map(|l| serde_json::from_str::<Value>(l).ok())
            .filter(|v| v["packet"] == "hat_hot" && v["id"] == 1)
            .filter_map(|v| v["height_m"].as_f64())
            .collect()
    };

    // The slave: the host's frames reach it, and it sends nothing back, nor to the exercise.
    let slave_port = free_udp_port();
    let slave = serve("slave", slave_port, &[]);
    let host = run_host(&script, slave_port, free_udp_port());
    let slave_dis = drain(&dis_sink);
    let (status, stdout, stderr) = slave.finish();
    assert!(status.success(), "{stderr}");
    let summary: Value = serde_json::from_slice(&stdout).expect("json");
    assert!(
        summary["cigi"]["datagrams"].as_u64().unwrap_or(0) >= 30,
        "{summary}"
    );
    assert_eq!(summary["cigi"]["messages_sent"], 0, "{summary}");
    assert_eq!(summary["cigi"]["hat_hot_answered"], 0, "{summary}");
    assert!(!host.status.success(), "the host heard the slave");
    assert!(hat_answers(&host).is_empty());
    assert_eq!(slave_dis, 0, "the slave published {slave_dis} datagrams");

    // The master alone answers and publishes (so the checks above can fail) ...
    let master_port = free_udp_port();
    let master = serve("master", master_port, &[]);
    let alone = run_host(&script, master_port, free_udp_port());
    let master_dis = drain(&dis_sink);
    let (status, _, stderr) = master.finish();
    assert!(status.success(), "{stderr}");
    assert!(master_dis > 0, "the master published nothing");
    let alone_answers = hat_answers(&alone);
    assert!(alone_answers.len() >= 30, "{}", alone_answers.len());

    // ... and with a slave fed by its relay, it answers the same.
    let slave_port = free_udp_port();
    let slave = serve("slave", slave_port, &[]);
    let master_port = free_udp_port();
    let master = serve(
        "master",
        master_port,
        &["--relay".into(), format!("127.0.0.1:{slave_port}")],
    );
    let with_slave = run_host(&script, master_port, free_udp_port());
    let (status, stdout, stderr) = master.finish();
    assert!(status.success(), "{stderr}");
    let master_summary: Value = serde_json::from_slice(&stdout).expect("json");
    assert!(
        master_summary["channel"]["relayed"].as_u64().unwrap_or(0) >= 30,
        "{master_summary}"
    );
    let (status, stdout, stderr) = slave.finish();
    assert!(status.success(), "{stderr}");
    let slave_summary: Value = serde_json::from_slice(&stdout).expect("json");
    assert!(
        slave_summary["cigi"]["datagrams"].as_u64().unwrap_or(0) >= 30,
        "{slave_summary}"
    );
    assert_eq!(slave_summary["cigi"]["messages_sent"], 0);
    let answers = hat_answers(&with_slave);
    assert!(answers.len() >= 30);
    let first = alone_answers[0];
    assert!(answers
        .iter()
        .chain(&alone_answers)
        .all(|h| (h - first).abs() < 1e-9));
}

#[test]
fn synchronous_channels_draw_the_hosts_frames_and_stop_together_when_it_pauses() {
    let dir = tempfile::tempdir().expect("tempdir");
    let db = small_db(dir.path());
    // 24 host frames, then the host is silent: every channel's last frame is host frame 23.
    let script = three_view_script(dir.path(), 24, 8);
    let ports: Vec<u16> = (0..3).map(|_| free_udp_port()).collect();
    let channel = |view: u16, role: &str, extra: &[String]| {
        let out = dir.path().join(format!("view{view}"));
        let mut args: Vec<String> = [
            "--db",
            &db.display().to_string(),
            "--headless",
            "--size",
            "64x48",
            "--sync",
            "--idle-exit-s",
            "2",
            "--view",
            &view.to_string(),
            "--role",
            role,
            "--cigi-port",
            &ports[usize::from(view)].to_string(),
            "--out-dir",
            &out.display().to_string(),
            "--json",
        ]
        .iter()
        .map(ToString::to_string)
        .collect();
        args.extend_from_slice(extra);
        start_serve(&args)
    };
    let left = channel(0, "slave", &[]);
    let right = channel(2, "slave", &[]);
    let centre = channel(
        1,
        "master",
        &[
            "--relay".into(),
            format!("127.0.0.1:{},127.0.0.1:{}", ports[0], ports[2]),
        ],
    );
    let host = run_host(&script, ports[1], free_udp_port());
    assert!(
        host.status.success(),
        "{}",
        String::from_utf8_lossy(&host.stderr)
    );
    let mut times = Vec::new();
    for (view, serving) in [(1, centre), (0, left), (2, right)] {
        let (status, stdout, stderr) = serving.finish();
        assert!(status.success(), "view {view}: {stderr}");
        let summary: Value = serde_json::from_slice(&stdout).expect("json");
        let c = &summary["channel"];
        assert_eq!(c["host_frame_drawn"], 23, "view {view}: {summary}");
        assert!(c["joined_after_ms"].as_f64().is_some(), "{summary}");
        assert_eq!(c["views_missing"], serde_json::json!([]), "{summary}");
        times.push(summary["sim_time"].as_str().unwrap_or_default().to_string());
        // Frames are named by the host frame they draw; the last is there.
        let last = dir
            .path()
            .join(format!("view{view}"))
            .join("frame_00023.png");
        assert!(last.exists(), "{}", last.display());
    }
    // One world: the same simulation time in every channel.
    assert!(
        times.iter().all(|t| t == &times[0] && !t.is_empty()),
        "{times:?}"
    );
}

#[test]
fn bad_channel_input_gives_one_line_errors() {
    let dir = tempfile::tempdir().expect("tempdir");
    let db = small_db(dir.path());
    let broken = [
        (
            "grid.toml",
            "columns = 2\nrows = 2\ndisplay = [[0, 0], [1, 0], [0, 1]]\n",
            "4 display positions",
        ),
        (
            "nan.toml",
            "columns = 2\nrows = 2\ndisplay = [[0, 0], [1, 0], [0, 1], [1, 9]]\n",
            "node 3",
        ),
        ("syntax.toml", "columns = 2\nrows = \n", "warp file"),
        (
            "field.toml",
            "columns = 2\nrows = 2\nshape = 1\ndisplay = []\n",
            "warp file",
        ),
    ];
    let db_arg = db.display().to_string();
    // `cig render` refuses the display correction `flag` of file `path`: its one error line.
    let refused = |flag: &str, path: &Path| {
        let assert = cig()
            .args(["render", "--db", &db_arg, "--eye", "36.0,-121.2,700"])
            .args(["--size", "32x24", "--out"])
            .arg(dir.path().join("x.png"))
            .arg(flag)
            .arg(path)
            .timeout(Duration::from_secs(60))
            .assert()
            .failure();
        one_line_error(&assert)
    };
    for (name, text, needle) in broken {
        let path = dir.path().join(name);
        std::fs::write(&path, text).expect("write");
        let line = refused("--warp", &path);
        assert!(
            line.contains(needle) && line.contains(name),
            "{name}: {line}"
        );
    }
    let blend = dir.path().join("blend.toml");
    std::fs::write(&blend, "left = 0.7\n").expect("write");
    assert!(refused("--blend", &blend).contains("blend left"));
    let cases: Vec<(Vec<&str>, &str)> = vec![
        (vec!["--view", "1,2,1"], "--view 1 is given twice"),
        (vec!["--role", "slave", "--relay", "127.0.0.1:9"], "--relay"),
        (vec!["--role", "boss"], "boss"),
        (vec!["--view", "70000"], "70000"),
        (
            vec!["--lock-port", "9"],
            "--lock-port and --lock need --sync",
        ),
        (
            vec!["--sync", "--role", "slave", "--lock-port", "9"],
            "--lock-port is the master's",
        ),
        (
            vec!["--sync", "--lock", "127.0.0.1:9"],
            "--lock is a slave's",
        ),
        (
            vec!["--sync", "--lock-port", "9", "--lock-timeout-ms", "0"],
            "--lock-timeout-ms 0",
        ),
        (
            vec!["--sync", "--role", "slave", "--lock", "nowhere.invalid:9"],
            "--lock",
        ),
    ];
    for (extra, needle) in cases {
        let assert = cig()
            .args(["serve", "--db", &db_arg, "--no-render", "--frames", "1"])
            .args(["--cigi-port", &free_udp_port().to_string()])
            .args(&extra)
            .timeout(Duration::from_secs(60))
            .assert()
            .failure();
        let line = one_line_error(&assert);
        assert!(line.contains(needle), "{extra:?}: {line}");
    }
    // A second master on the first one's port is refused.
    let port = free_udp_port();
    let first = start_serve(&[
        "--db".into(),
        db_arg.clone(),
        "--no-render".into(),
        "--cigi-port".into(),
        port.to_string(),
        "--frames".into(),
        "600".into(),
    ]);
    let assert = cig()
        .args(["serve", "--db", &db_arg, "--no-render", "--frames", "1"])
        .args(["--cigi-port", &port.to_string()])
        .timeout(Duration::from_secs(60))
        .assert()
        .failure();
    let line = one_line_error(&assert);
    assert!(line.contains("one master per host port"), "{line}");
    first.kill();
}

#[test]
fn three_channel_processes_are_measured_and_a_killed_slave_rejoins() {
    let dir = tempfile::tempdir().expect("tempdir");
    let db = small_db(dir.path());
    let out = cig()
        .args(["bench", "channels", "--db"])
        .arg(&db)
        .args([
            "--size",
            "64x48",
            "--warmup-s",
            "3",
            "--seconds",
            "3",
            "--json",
        ])
        .timeout(Duration::from_secs(240))
        .output()
        .expect("run");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    let report: Value = serde_json::from_slice(&out.stdout).expect("json");
    assert!(
        report["frame_spread_instants"].as_u64().unwrap_or(0) > 10,
        "{report}"
    );
    // Frame-locked, the channels are never more than one host frame apart, unless the lock
    // dropped a slave starved of the CPU for longer than its timeout (beyond the killed one).
    let spread = report["frame_spread_max"].as_u64().expect("spread");
    if report["lock"]["timeouts"] == 1 {
        assert!(spread <= 1, "{report}");
    }
    let rejoin = report["restart"]["rejoin_s"].as_f64();
    assert!(rejoin.is_some_and(|s| s > 0.0 && s < 10.0), "{report}");
    let ratio = report["slave_cost"]["slave_over_master"]
        .as_f64()
        .unwrap_or(0.0);
    assert!(ratio > 0.3 && ratio < 3.0, "{report}");
    for channel in report["channels"].as_array().expect("channels") {
        assert!(
            channel["frames_measured"].as_u64().unwrap_or(0) >= 5,
            "{report}"
        );
    }
}

#[test]
fn a_window_shows_the_channels_warp_and_blend() {
    if std::process::Command::new("xvfb-run")
        .arg("--help")
        .output()
        .is_err()
    {
        eprintln!("SKIPPED: xvfb-run is not installed (scripts/setup.sh --test installs xvfb)");
        return;
    }
    let dir = tempfile::tempdir().expect("tempdir");
    let db = small_db(dir.path());
    // A warp that moves the view a quarter of the display to the right, and a right ramp.
    let (c, r) = (5, 4);
    let nodes: Vec<String> = (0..r)
        .flat_map(|j| (0..c).map(move |i| (f64::from(i) / 4.0 + 0.25, f64::from(j) / 3.0)))
        .map(|(x, y)| format!("[{x}, {y}]"))
        .collect();
    let shift = dir.path().join("shift.toml");
    std::fs::write(
        &shift,
        format!(
            "columns = {c}\nrows = {r}\ndisplay = [{}]\n",
            nodes.join(", ")
        ),
    )
    .expect("write");
    let blend = dir.path().join("blend.toml");
    std::fs::write(&blend, "right = 0.25\ngamma = 2.2\n").expect("write");
    let screenshot = |name: &str, extra: &[&std::ffi::OsStr]| {
        let out = dir.path().join(name);
        let run = std::process::Command::new("xvfb-run")
            .args(["-a", "-s", "-screen 0 1280x800x24"])
            .arg(assert_cmd::cargo::cargo_bin("cig"))
            .args(["view", "--db"])
            .arg(&db)
            .args(["--size", "800x500", "--frames", "3", "--screenshot"])
            .arg(&out)
            .args(extra)
            .output()
            .expect("xvfb-run");
        assert!(
            run.status.success(),
            "{}",
            String::from_utf8_lossy(&run.stderr)
        );
        png(&out)
    };
    let plain = screenshot("plain.png", &[]);
    let shifted = screenshot("shift.png", &["--warp".as_ref(), shift.as_os_str()]);
    let blended = screenshot("blend.png", &["--blend".as_ref(), blend.as_os_str()]);
    assert_eq!((plain.width, plain.height), (800, 500));
    // Below the panels (their bottom rows stay clear): the scene moved by 200 pixels, black
    // where no warp cell reaches; the blend black at the right edge, untouched left of its
    // ramp. (Each run is a window of its own, its clock a moment later: a level or two apart.)
    let near = |a: [u8; 4], b: [u8; 4]| a.iter().zip(b).all(|(p, q)| p.abs_diff(q) <= 3);
    for y in [466, 480, 495] {
        for x in (0..600).step_by(25) {
            let (moved, was) = (shifted.pixel(x + 200, y), plain.pixel(x, y));
            assert!(near(moved, was), "{x},{y}: {moved:?} {was:?}");
        }
        assert_eq!(shifted.pixel(100, y), [0, 0, 0, 255]);
        let edge = blended.pixel(799, y);
        assert!(edge[..3].iter().all(|v| *v <= 2), "{edge:?}");
        assert!(plain.pixel(799, y)[..3].iter().any(|v| *v > 20));
        assert!(near(blended.pixel(400, y), plain.pixel(400, y)));
    }
    // The shift is exact to the pixel: one pixel off, the scene's edges no longer agree.
    let difference_at = |dx: u32| -> u32 {
        (0..599)
            .map(|x| {
                let (a, b) = (shifted.pixel(x + dx, 480), plain.pixel(x, 480));
                a.iter()
                    .zip(b)
                    .map(|(p, q)| u32::from(p.abs_diff(q)))
                    .sum::<u32>()
            })
            .sum()
    };
    let (on, off) = (difference_at(200), difference_at(201));
    assert!(off > 4 * on.max(1), "{off} against {on}");
}
