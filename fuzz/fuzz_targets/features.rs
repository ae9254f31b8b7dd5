//! Feature files: any text gives features or a one-line error, never a panic; features that
//! parse either validate into a layer or are refused with an error.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let text = String::from_utf8_lossy(data);
    if let Ok(features) = cig_terrain_io::features::parse_features(&text) {
        let _ = cig_terrain::features::FeatureLayer::new(&features);
    }
});
