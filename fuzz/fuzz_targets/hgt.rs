//! SRTM reader: the first byte picks a file name (valid or not), the rest is repeated to fill a
//! tile of a valid size (any other size is rejected at once), or used as it is.
#![no_main]

use libfuzzer_sys::fuzz_target;

const NAMES: [&str; 6] = [
    "N35W122.hgt",
    "s09e033.SRTMGL1.hgt",
    "N89E179.hgt",
    "X35W122.hgt",
    "N35W1",
    "",
];

fuzz_target!(|data: &[u8]| {
    let Some((&selector, rest)) = data.split_first() else {
        return;
    };
    let name = NAMES[usize::from(selector) % NAMES.len()];
    if selector & 0x80 != 0 || rest.is_empty() {
        let _ = cig_terrain_io::import::read_hgt_bytes(rest, name);
        return;
    }
    let size = if selector & 0x40 != 0 {
        25_934_402
    } else {
        2_884_802
    };
    let tile: Vec<u8> = rest.iter().copied().cycle().take(size).collect();
    let _ = cig_terrain_io::import::read_hgt_bytes(&tile, name);
});
