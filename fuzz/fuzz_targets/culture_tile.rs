//! Culture tile decoder: any bytes give a tile or an error, never a panic; a decoded tile
//! re-encodes to bytes that decode to the same tile.
#![no_main]
use cig_terrain::culture::CultureTile;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok(tile) = CultureTile::decode(data, None, 128) {
        let again = CultureTile::decode(&tile.encode(), Some(tile.key), 128).expect("re-encoded");
        assert_eq!(again, tile);
        let _ = tile.blocks();
    }
});
