//! Helpers shared by the tests that run the Python `opendis` package as an independent peer.
#![allow(dead_code, reason = "each test file uses a different subset")]

use std::process::Command;

/// What every peer script starts with: the imports, and `finish`, which serialises a PDU with
/// its header set as cig's tests expect (version 7, exercise 4, the length written in).
const BASE_PREAMBLE: &str = r"
import sys, json, struct
from io import BytesIO
from opendis.DataOutputStream import DataOutputStream
from opendis.DataInputStream import DataInputStream
from opendis.PduFactory import createPdu
from opendis.dis7 import *

def finish(pdu, pdu_type, family):
    pdu.pduType = pdu_type
    pdu.protocolFamily = family
    pdu.protocolVersion = 7
    pdu.exerciseID = 4
    pdu.pduStatus = 0
    buf = BytesIO()
    pdu.serialize(DataOutputStream(buf))
    data = bytearray(buf.getvalue())
    data[8:10] = len(data).to_bytes(2, 'big')
    return bytes(data)
";

/// Runs the common preamble, `preamble` and then `script` in Python with opendis, with `arg` as its argument; `None`
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
    let full = format!("{BASE_PREAMBLE}\n{preamble}\n{script}");
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
