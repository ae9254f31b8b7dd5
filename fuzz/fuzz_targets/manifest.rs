//! Manifest parsing and validation: any text gives a manifest or an error, never a panic, and a
//! valid manifest opens a database.
#![no_main]
use libfuzzer_sys::fuzz_target;
use std::sync::Arc;

fuzz_target!(|data: &[u8]| {
    let Ok(manifest) = serde_json::from_slice::<cig_terrain::Manifest>(data) else {
        return;
    };
    if manifest.validate().is_ok() {
        let store = Arc::new(cig_terrain::database::MemoryTileStore::new());
        let _ = cig_terrain::TerrainDatabase::new(manifest, store);
    }
});
