//! End-to-end runs of the thermal sensor from the command line: `cig render --sensor`, its
//! options and their refusals, and `cig bench sensor`.

mod common;

use common::{cig, one_line_error, read_png_rgba, small_db};

const EYE: [&str; 8] = [
    "--eye",
    "36.0,-121.21,700",
    "--hpr",
    "0,-10,0",
    "--time",
    "2026-06-21T21:00:00Z",
    "--size",
    "160x90",
];

#[test]
fn lwir_and_mwir_frames_are_grey_green_on_request_and_black_hot_inverts() {
    let dir = tempfile::tempdir().expect("tempdir");
    let db = small_db(dir.path());
    let render = |name: &str, extra: &[&str]| {
        let out = dir.path().join(name);
        cig()
            .arg("render")
            .arg("--db")
            .arg(&db)
            .args(EYE)
            .args(["--noise", "0", "--entity", "tank,36.003,-121.21,0,0,clamp"])
            .args(extra)
            .arg("--out")
            .arg(&out)
            .assert()
            .success();
        read_png_rgba(&out)
    };
    let (_, _, white) = render("lwir.png", &["--sensor", "lwir"]);
    assert!(
        white.chunks(4).all(|p| p[0] == p[1] && p[1] == p[2]),
        "LWIR is grey"
    );
    let spread = white.chunks(4).map(|p| p[0]).max().unwrap_or(0)
        - white.chunks(4).map(|p| p[0]).min().unwrap_or(0);
    assert!(
        spread > 100,
        "the automatic gain spreads the scene: {spread}"
    );
    let (_, _, black) = render(
        "black.png",
        &["--sensor", "lwir", "--polarity", "black-hot"],
    );
    let inverted = white
        .chunks(4)
        .zip(black.chunks(4))
        .filter(|(w, b)| (i32::from(w[0]) + i32::from(b[0]) - 255).abs() <= 2)
        .count();
    assert!(
        inverted * 10 >= white.len() / 4 * 9,
        "black-hot inverts white-hot"
    );
    let (_, _, green) = render("green.png", &["--sensor", "mwir", "--display", "green"]);
    assert!(
        green.chunks(4).all(|p| p[1] >= p[0] && p[1] >= p[2]),
        "a green display"
    );
    let (_, _, manual) = render(
        "manual.png",
        &["--sensor", "lwir", "--gain", "0.2", "--level", "0.5"],
    );
    assert_ne!(manual, white, "the manual window is not the automatic one");
    let (_, _, coupled) = render(
        "ac.png",
        &[
            "--sensor",
            "lwir",
            "--ac-coupling-us",
            "5",
            "--line-dropout",
        ],
    );
    assert_ne!(coupled, white, "AC coupling and dropout change the frame");
}

#[test]
fn bad_sensor_options_get_one_line_naming_them() {
    let dir = tempfile::tempdir().expect("tempdir");
    let db = small_db(dir.path());
    let out = dir.path().join("x.png");
    for (args, needle) in [
        (vec!["--sensor", "uv"], "uv"),
        (vec!["--sensor", "lwir", "--polarity", "hot"], "hot"),
        (
            vec!["--sensor", "lwir", "--gain", "2", "--level", "0.5"],
            "--gain 2",
        ),
        (vec!["--sensor", "lwir", "--gain", "0.5"], "--level"),
        (vec!["--sensor", "lwir", "--noise", "-1"], "--noise -1"),
        (vec!["--sensor", "lwir", "--display", "pink"], "pink"),
        (vec!["--sensor", "lwir", "--air-c", "cold,hot"], "cold"),
        (vec!["--sensor", "lwir", "--air-c", "30,10"], "air maximum"),
        (vec!["--sensor", "lwir", "--rh", "150"], "150"),
        (vec!["--sensor", "lwir", "--engines", "idle"], "idle"),
        (vec!["--sensor", "lwir", "--ac-coupling-us", "-3"], "-3"),
    ] {
        let err = one_line_error(
            &cig()
                .arg("render")
                .arg("--db")
                .arg(&db)
                .args(EYE)
                .args(&args)
                .arg("--out")
                .arg(&out)
                .assert()
                .failure(),
        );
        assert!(err.contains(needle), "{args:?}: {err}");
        assert!(!out.exists(), "{args:?} wrote a frame");
    }
}

#[test]
fn bench_sensor_reports_the_issue_figures() {
    let dir = tempfile::tempdir().expect("tempdir");
    let db = small_db(dir.path());
    let out = cig()
        .args(["bench", "sensor", "--db"])
        .arg(&db)
        .args(["--size", "160x90", "--entities", "10", "--json"])
        .assert()
        .success()
        .get_output()
        .stdout
        .clone();
    let v: serde_json::Value = serde_json::from_slice(&out).expect("JSON");
    for key in [
        "lwir_over_visible",
        "advance_1s_ms",
        "spin_up_s",
        "visible_ms",
        "lwir_ms",
    ] {
        let x = v[key].as_f64().unwrap_or(f64::NAN);
        assert!(x.is_finite() && x > 0.0, "{key}: {x}");
    }
    assert_eq!(v["materials"], 18);
    assert_eq!(v["orientations"], 26);
    assert!(v["entities_drawn"].as_u64().unwrap_or(0) > 0, "{v}");
}
