//! Tile decoder: any bytes give a tile or an error, never a panic; a decoded tile re-encodes to
//! the same bytes.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok(tile) = cig_terrain::tile::Tile::decode(data, None) {
        assert_eq!(tile.encode(), data);
    }
});
