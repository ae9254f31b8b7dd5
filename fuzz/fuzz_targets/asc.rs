//! ESRI ASCII grid reader on arbitrary text: errors are fine, panics are bugs.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let text = String::from_utf8_lossy(data);
    let _ = cig_terrain_io::import::read_asc_str(&text, "fuzz.asc");
});
