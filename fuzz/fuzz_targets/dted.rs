//! DTED reader on arbitrary bytes: errors are fine, panics are bugs.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let _ = cig_terrain_io::import::read_dted_bytes(data, "fuzz.dt1");
});
