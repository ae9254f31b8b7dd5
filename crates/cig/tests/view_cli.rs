//! End-to-end runs of `cig view`: under a virtual X server (Xvfb, Debian package `xvfb`) when
//! `xvfb-run` exists, and without any display.

mod common;

use common::cig;
use std::path::{Path, PathBuf};

fn synth(dir: &Path) -> PathBuf {
    let db = dir.join("db");
    cig()
        .args(["db", "synth", "--out"])
        .arg(&db)
        .args([
            "--origin",
            "35.98,-121.23",
            "--size-km",
            "4",
            "--spacing-m",
            "30",
            "--seed",
            "5",
        ])
        .assert()
        .success();
    db
}

fn xvfb_run() -> Option<PathBuf> {
    let path = std::env::var_os("PATH")?;
    std::env::split_paths(&path)
        .map(|dir| dir.join("xvfb-run"))
        .find(|p| p.is_file())
}

fn assert_no_display_error(stderr: &[u8]) {
    let stderr = String::from_utf8_lossy(stderr);
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert_eq!(stderr.trim_end().lines().count(), 1, "one line: {stderr}");
    assert!(
        stderr.contains("cig view needs a display; use cig render for off-screen frames"),
        "{stderr}"
    );
}

#[test]
fn without_a_display_view_fails_with_one_line() {
    let dir = tempfile::tempdir().expect("tmp");
    let db = synth(dir.path());
    let out = cig()
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY")
        .env_remove("WAYLAND_SOCKET")
        .args(["view", "--db"])
        .arg(&db)
        .args(["--frames", "1"])
        .assert()
        .failure();
    assert_no_display_error(&out.get_output().stderr);

    // A display that does not answer is no display either.
    let out = cig()
        .env("DISPLAY", ":64999")
        .env_remove("WAYLAND_DISPLAY")
        .env_remove("WAYLAND_SOCKET")
        .args(["view", "--db"])
        .arg(&db)
        .assert()
        .failure();
    assert_no_display_error(&out.get_output().stderr);
}

#[test]
fn bad_view_options_are_refused_before_any_window() {
    let dir = tempfile::tempdir().expect("tmp");
    for (flag, value, says) in [
        ("--fov", "180", "--fov"),
        ("--size", "0x10", "--size"),
        ("--max-pixel-error", "9", "--max-pixel-error"),
        ("--frames", "0", "--frames"),
        ("--eye", "35.98,-121.23,-5000", "altitude"),
    ] {
        let db = if flag == "--eye" {
            synth(dir.path())
        } else {
            dir.path().join("missing")
        };
        let out = cig()
            .env_remove("DISPLAY")
            .env_remove("WAYLAND_DISPLAY")
            .args(["view", "--db"])
            .arg(&db)
            .args([flag, value])
            .assert()
            .failure();
        let stderr = String::from_utf8_lossy(&out.get_output().stderr).to_string();
        assert!(stderr.contains(says), "{flag} {value}: {stderr}");
        assert!(!stderr.contains("panicked"), "{stderr}");
        assert_eq!(stderr.trim_end().lines().count(), 1, "{stderr}");
    }
}

#[test]
fn under_xvfb_view_opens_renders_frames_and_saves_a_screenshot() {
    let Some(xvfb_run) = xvfb_run() else {
        eprintln!("SKIPPED: xvfb-run not found (Debian package xvfb); cig view not exercised");
        return;
    };
    let dir = tempfile::tempdir().expect("tmp");
    let db = synth(dir.path());
    let shot = dir.path().join("shot.png");
    let out = assert_cmd::Command::new(xvfb_run)
        .env_remove("CIG_LOG")
        .env_remove("WAYLAND_DISPLAY")
        .args(["-a", "-s", "-screen 0 1024x768x24"])
        .arg(assert_cmd::cargo::cargo_bin("cig"))
        .args(["view", "--db"])
        .arg(&db)
        .args([
            "--eye",
            "35.981,-121.21,900",
            "--hpr",
            "0,-12,0",
            "--size",
            "800x500",
            "--frames",
            "4",
            "--screenshot",
        ])
        .arg(&shot)
        .timeout(std::time::Duration::from_secs(300))
        .assert()
        .success();
    let stderr = String::from_utf8_lossy(&out.get_output().stderr).to_string();
    assert!(stderr.contains("viewed 4 frames"), "{stderr}");

    let decoder = png::Decoder::new(std::io::BufReader::new(
        std::fs::File::open(&shot).expect("screenshot written"),
    ));
    let mut reader = decoder.read_info().expect("png");
    let mut rgba = vec![0; reader.output_buffer_size()];
    let info = reader.next_frame(&mut rgba).expect("frame");
    assert_eq!((info.width, info.height), (800, 500));
    assert_eq!(info.color_type, png::ColorType::Rgba);
    let pixel = |x: u32, y: u32| {
        let i = ((y * info.width + x) * 4) as usize;
        [rgba[i], rgba[i + 1], rgba[i + 2]]
    };
    // The terrain fills the bottom of the frame (below both panel windows) with many colours.
    let mut lower: Vec<[u8; 3]> = (450..500)
        .flat_map(|y| (0..800).map(move |x| (x, y)))
        .map(|(x, y)| pixel(x, y))
        .collect();
    lower.sort_unstable();
    lower.dedup();
    assert!(lower.len() > 200, "{} colours in the terrain", lower.len());
    // The sky, between the two panel windows at the top, is bluer than it is red.
    let [r, _, b] = pixel(445, 3);
    assert!(b > r, "sky {:?}", pixel(445, 3));
    // The operator panel (egui's dark grey window) covers part of the top-left corner.
    let panel_grey = (5..200)
        .flat_map(|y| (5..200).map(move |x| (x, y)))
        .map(|(x, y)| pixel(x, y))
        .filter(|[r, g, b]| r.abs_diff(*g) <= 2 && g.abs_diff(*b) <= 2 && (15..=45).contains(r))
        .count();
    eprintln!(
        "terrain colours {}, sky {:?}, panel pixels {panel_grey}",
        lower.len(),
        pixel(445, 3)
    );
    assert!(panel_grey > 5000, "{panel_grey} panel pixels");
}
