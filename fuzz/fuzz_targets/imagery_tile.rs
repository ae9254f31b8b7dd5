//! Imagery tile decoder: any bytes give a tile or an error, never a panic; a decoded tile
//! re-encodes to bytes that decode to the same tile.
#![no_main]
use cig_terrain::imagery::ImageryTile;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok(tile) = ImageryTile::decode(data, None) {
        let again = ImageryTile::decode(&tile.encode(), Some(tile.key)).expect("re-encoded tile");
        assert_eq!(again, tile);
        let _ = tile.to_rgba();
    }
});
