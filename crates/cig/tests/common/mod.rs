//! Helpers shared by the end-to-end tests of the `cig` binary.
#![allow(dead_code, reason = "each test file uses a different subset")]

use assert_cmd::Command;
use std::io::{BufRead, BufReader};
use std::net::UdpSocket;
use std::path::Path;
use std::process::{Child, Stdio};
use std::time::Duration;

/// The `cig` binary, with the log filter of the caller's environment removed.
pub fn cig() -> Command {
    let mut c = Command::cargo_bin("cig").expect("binary");
    c.env_remove("CIG_LOG");
    c
}

/// Runs `cig ARGS... --json`, asserting success, and parses its standard output.
pub fn json_output(args: &[&str]) -> serde_json::Value {
    let out = cig()
        .args(args)
        .arg("--json")
        .assert()
        .success()
        .get_output()
        .stdout
        .clone();
    serde_json::from_slice(&out)
        .unwrap_or_else(|e| panic!("{e}: {}", String::from_utf8_lossy(&out)))
}

/// The one `error:` line a failed command printed (asserting there is exactly one and no
/// panic). Mesa's Vulkan drivers print their own complaint when there is no Wayland session; it
/// is not cig's error line.
pub fn one_line_error(out: &assert_cmd::assert::Assert) -> String {
    let stderr = String::from_utf8_lossy(&out.get_output().stderr).to_string();
    let lines: Vec<&str> = stderr
        .lines()
        .filter(|l| l.starts_with("error:") && !l.contains("XDG_RUNTIME_DIR"))
        .collect();
    assert_eq!(lines.len(), 1, "one error line: {stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
    lines[0].to_string()
}

/// A 4 km synthetic database near 36 N 121 W with 30 m posts, built with `cig db synth`.
pub fn small_db(dir: &std::path::Path) -> std::path::PathBuf {
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
        ])
        .assert()
        .success();
    db
}

pub fn free_udp_port() -> u16 {
    UdpSocket::bind("127.0.0.1:0")
        .and_then(|s| s.local_addr())
        .map(|a| a.port())
        .expect("a free port")
}

/// A running `cig serve` and what it has written to stderr so far.
pub struct Serving {
    pub child: Child,
    pub stderr: std::sync::Arc<std::sync::Mutex<String>>,
}

impl Serving {
    pub fn kill(mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }

    /// Waits for the end; (status, stdout, stderr).
    pub fn finish(self) -> (std::process::ExitStatus, Vec<u8>, String) {
        let out = self.child.wait_with_output().expect("serve ends");
        // Give the reader thread a moment to take the last lines.
        std::thread::sleep(Duration::from_millis(100));
        let stderr = self.stderr.lock().map(|s| s.clone()).unwrap_or_default();
        (out.status, out.stdout, stderr)
    }
}

/// Starts `cig serve` with `-v` and waits until it says it is serving.
pub fn start_serve(args: &[String]) -> Serving {
    let mut child = std::process::Command::new(assert_cmd::cargo::cargo_bin("cig"))
        .arg("-v")
        .arg("serve")
        .args(args)
        .env_remove("CIG_LOG")
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("cig serve starts");
    let stderr = child.stderr.take().expect("stderr");
    let (tx, rx) = std::sync::mpsc::channel();
    let log = std::sync::Arc::new(std::sync::Mutex::new(String::new()));
    let sink = std::sync::Arc::clone(&log);
    std::thread::spawn(move || {
        let mut ready = Some(tx);
        for line in BufReader::new(stderr).lines().map_while(Result::ok) {
            if let Ok(mut all) = sink.lock() {
                all.push_str(&line);
                all.push('\n');
            }
            if line.contains("serving") {
                if let Some(tx) = ready.take() {
                    let _ = tx.send(());
                }
            }
        }
    });
    rx.recv_timeout(Duration::from_secs(60))
        .expect("cig serve says it is serving within a minute");
    Serving { child, stderr: log }
}

/// Runs `cig host --json` with a script against the IG's port, listening on `host_port`.
pub fn run_host(script: &Path, ig_port: u16, host_port: u16) -> std::process::Output {
    cig()
        .args(["host", "--script"])
        .arg(script)
        .args([
            "--ig".into(),
            format!("127.0.0.1:{ig_port}"),
            "--port".into(),
            host_port.to_string(),
            "--json".into(),
        ])
        .timeout(Duration::from_secs(120))
        .output()
        .expect("cig host")
}

/// An 8-bit RGBA PNG's width, height and pixels (RGB ones get an opaque alpha).
pub fn read_png_rgba(path: &Path) -> (u32, u32, Vec<u8>) {
    let decoder = png::Decoder::new(BufReader::new(
        std::fs::File::open(path).unwrap_or_else(|e| panic!("{}: {e}", path.display())),
    ));
    let mut reader = decoder.read_info().expect("png header");
    let mut buf = vec![0; reader.output_buffer_size()];
    let info = reader.next_frame(&mut buf).expect("png data");
    buf.truncate(info.buffer_size());
    assert_eq!(info.bit_depth, png::BitDepth::Eight, "8-bit PNG");
    let rgba = match info.color_type {
        png::ColorType::Rgba => buf,
        png::ColorType::Rgb => buf
            .chunks_exact(3)
            .flat_map(|p| [p[0], p[1], p[2], 255])
            .collect(),
        other => panic!("unexpected PNG colour type {other:?}"),
    };
    (info.width, info.height, rgba)
}
