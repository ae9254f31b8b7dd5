//! A real DEM: `elev.tif` of Debian's package r-cran-terra (Luxembourg, EPSG:4326, 95 x 90
//! int16 pixels of 30 arc-seconds, LZW-compressed strips, GDAL_NODATA -32768).
//!
//! The file is found through `CIG_TEST_REAL_DEM`; `scripts/fetch-test-data.sh` downloads it
//! and prints its path. Without the variable the test fails (it is never silently skipped).

use std::path::PathBuf;

use cig_terrain_io::import::{read_source, SourceFormat};

fn real_dem() -> PathBuf {
    match std::env::var_os("CIG_TEST_REAL_DEM") {
        Some(path) if !path.is_empty() => PathBuf::from(path),
        _ => panic!(
            "CIG_TEST_REAL_DEM is not set: run `export CIG_TEST_REAL_DEM=\"$(scripts/fetch-test-data.sh)\"` \
             from the repository root (it downloads Debian's r-cran-terra and extracts elev.tif \
             into .cache/test-data/), then run the tests again"
        ),
    }
}

#[test]
fn real_luxembourg_dem_from_r_cran_terra() {
    let path = real_dem();
    assert!(
        path.is_file(),
        "CIG_TEST_REAL_DEM={} is not a file: run scripts/fetch-test-data.sh",
        path.display()
    );
    let (raster, info) = read_source(&path).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(info.format, SourceFormat::GeoTiff);
    assert_eq!(info.reprojected_from_epsg, None);

    // ModelTiepoint (0, 0) -> (5.741666.., 50.191666..), ModelPixelScale 1/120 degree,
    // PixelIsArea: posts at pixel centres.
    let g = raster.grid;
    assert_eq!((g.rows, g.cols), (90, 95));
    let step = 1.0 / 120.0;
    let close = |a: f64, b: f64| (a - b).abs() < 1e-9;
    assert!(close(g.dlat_deg, step) && close(g.dlon_deg, step), "{g:?}");
    assert!(
        close(g.west_lon_deg, 5.741_666_666_666_666 + step / 2.0),
        "{g:?}"
    );
    assert!(
        close(g.north_lat_deg(), 50.191_666_666_666_66 - step / 2.0),
        "{g:?}"
    );
    assert!(close(g.south_lat_deg, 49.445_833_333_333_33), "{g:?}");
    assert!(close(g.east_lon_deg(), 6.529_166_666_666_667), "{g:?}");

    // Outside the country's border the file holds -32768 (GDAL_NODATA).
    assert_eq!(info.void_posts, 3942);
    assert_eq!(raster.void_count(), 3942);

    // Known values (file row r from the north is raster row 89 - r).
    assert_eq!(raster.elevation_at(88, 31), 529.0);
    assert_eq!(raster.elevation_at(88, 33), 547.0, "the highest post");
    assert_eq!(raster.elevation_at(8, 74), 141.0, "the lowest post");
    assert_eq!(raster.elevation_at(5, 74), 141.0);
    let row_44: Vec<f32> = (40..50).map(|c| raster.elevation_at(44, c)).collect();
    assert_eq!(
        row_44,
        [304.0, 236.0, 213.0, 244.0, 261.0, 292.0, 293.0, 290.0, 294.0, 284.0]
    );
    assert!(raster.elevation_at(0, 0).is_nan());
    assert!(raster.elevation_at(89, 94).is_nan());

    let valid: Vec<f64> = raster
        .elevation_m
        .iter()
        .filter(|h| !h.is_nan())
        .map(|&h| f64::from(h))
        .collect();
    assert_eq!(valid.iter().sum::<f64>(), 1_605_135.0);
    assert_eq!(valid.iter().copied().fold(f64::INFINITY, f64::min), 141.0);
    assert_eq!(
        valid.iter().copied().fold(f64::NEG_INFINITY, f64::max),
        547.0
    );
}
