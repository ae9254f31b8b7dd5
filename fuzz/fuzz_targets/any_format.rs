//! Format detection by magic bytes followed by the matching byte-level reader.
#![no_main]

use cig_terrain_io::import::{self, SourceFormat};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let _ = match import::format_from_magic(data) {
        Some(SourceFormat::GeoTiff) => import::read_geotiff_bytes(data, "fuzz.tif").map(|_| ()),
        Some(SourceFormat::Dted) => import::read_dted_bytes(data, "fuzz.dt2").map(|_| ()),
        Some(SourceFormat::EsriAscii) => {
            import::read_asc_str(&String::from_utf8_lossy(data), "fuzz.asc").map(|_| ())
        }
        Some(SourceFormat::SrtmHgt) | None => {
            import::read_hgt_bytes(data, "N00E000.hgt").map(|_| ())
        }
    };
});
