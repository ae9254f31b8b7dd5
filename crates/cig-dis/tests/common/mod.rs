//! Helpers shared by the tests that run the Python `opendis` package as an independent peer.
#![allow(dead_code, reason = "each test file uses a different subset")]

use std::process::Command;

/// Runs `preamble` then `script` in Python with opendis, with `arg` as its argument; `None`
/// (and a message) when the peer is unavailable.
pub fn python(preamble: &str, script: &str, arg: &str) -> Option<String> {
    let probe = Command::new("python3")
        .args(["-c", "import opendis"])
        .output();
    match probe {
        Ok(out) if out.status.success() => {}
        _ => {
            eprintln!("SKIPPED: python3 with the `opendis` package (pip install opendis) is not available");
            return None;
        }
    }
    let full = format!("{preamble}\n{script}");
    let out = Command::new("python3")
        .args(["-c", &full, arg])
        .output()
        .expect("python3 runs");
    assert!(
        out.status.success(),
        "python failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    Some(
        String::from_utf8(out.stdout)
            .expect("utf-8")
            .trim()
            .to_string(),
    )
}

pub fn hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}

pub fn unhex(s: &str) -> Vec<u8> {
    (0..s.len())
        .step_by(2)
        .map(|i| u8::from_str_radix(&s[i..i + 2], 16).expect("hex"))
        .collect()
}
