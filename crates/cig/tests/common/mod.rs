//! Helpers shared by the end-to-end tests of the `cig` binary.
#![allow(dead_code, reason = "each test file uses a different subset")]

use assert_cmd::Command;

/// The `cig` binary, with the log filter of the caller's environment removed.
pub fn cig() -> Command {
    let mut c = Command::cargo_bin("cig").expect("binary");
    c.env_remove("CIG_LOG");
    c
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
