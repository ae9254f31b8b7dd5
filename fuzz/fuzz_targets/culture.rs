//! Culture in feature files: any text gives placements or a one-line error, never a panic;
//! placements either bin into a database's finest tiles or are refused with an error.
#![no_main]
use cig_terrain::raster::GeoGrid;
use cig_terrain::PyramidLayout;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let text = String::from_utf8_lossy(data);
    if let Ok(file) = cig_terrain_io::features::parse_feature_file(&text) {
        let placements = cig_terrain_io::culture::placements(&file.culture);
        let layout = PyramidLayout::new(
            GeoGrid {
                south_lat_deg: -1.0,
                west_lon_deg: -1.0,
                dlat_deg: 1.0 / 1200.0,
                dlon_deg: 1.0 / 1200.0,
                rows: 2401,
                cols: 2401,
            },
            128,
        );
        let _ = cig_terrain::culture::bin_placements(&layout, &placements);
    }
});
