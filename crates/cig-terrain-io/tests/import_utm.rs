//! A UTM GeoTIFF (EPSG:32610) is resampled once onto a geographic lattice that covers its
//! footprint, with values matching the analytic field within interpolation error.

mod import_support;

use cig_geo::utm::{geodetic_to_utm, utm_to_geodetic, UtmZone};
use cig_terrain_io::import::{read_source, SourceFormat};
use import_support::*;

const COLS: u32 = 80;
const ROWS: u32 = 60;
const SPACING_M: f64 = 30.0;
const EAST_EDGE: f64 = 520_000.0;
const NORTH_EDGE: f64 = 4_200_000.0;
const VOID: (usize, usize) = (30, 40); // (file row from north, col)

fn utm_field(e: f64, n: f64) -> f64 {
    let (x, y) = (e - EAST_EDGE, n - NORTH_EDGE);
    200.0 + 0.004 * x + 0.003 * y + 15.0 * (x / 700.0).sin() * (y / 900.0).cos()
}

/// Easting and northing of post (file row from north, col): PixelIsArea, pixel centres.
fn post_en(row: usize, col: usize) -> (f64, f64) {
    (
        EAST_EDGE + (col as f64 + 0.5) * SPACING_M,
        NORTH_EDGE - (row as f64 + 0.5) * SPACING_M,
    )
}

#[test]
fn utm_geotiff_is_resampled_onto_a_covering_geographic_grid() {
    let mut values = Vec::new();
    for r in 0..ROWS as usize {
        for c in 0..COLS as usize {
            let (e, n) = post_en(r, c);
            values.push(if (r, c) == VOID {
                f64::NAN
            } else {
                utm_field(e, n) as f32 as f64
            });
        }
    }
    let spec = TiffSpec {
        width: COLS,
        height: ROWS,
        sample: SampleKind::F32,
        layout: Layout::Tiles { size: 32 },
        comp: Comp::Deflate,
        predictor: false,
        geokeys: geokeys_projected(32610, PIXEL_IS_AREA),
        pixel_scale: Some([SPACING_M, SPACING_M, 0.0]),
        tiepoint: Some([0.0, 0.0, 0.0, EAST_EDGE, NORTH_EDGE, 0.0]),
        transformation: None,
        nodata: Some("-9999".to_string()),
    };
    let dir = tempfile::tempdir().expect("tempdir");
    let path = write_file(dir.path(), "utm10n.tif", &write_geotiff(&spec, &values));
    let (raster, info) = read_source(&path).expect("read UTM GeoTIFF");
    assert_eq!(info.format, SourceFormat::GeoTiff);
    assert_eq!(info.reprojected_from_epsg, Some(32610));
    let zone = UtmZone::from_epsg(32610).expect("zone 10N");
    let g = raster.grid;
    assert_eq!(info.grid, g);

    // Equivalent spacing at the centre latitude.
    let (n_per_deg, e_per_deg) =
        cig_geo::metres_per_degree(0.5 * (g.south_lat_deg + g.north_lat_deg()));
    // (The grid's north edge lies up to a post beyond the footprint's: compare loosely.)
    assert_close(g.dlat_deg, SPACING_M / n_per_deg, 1e-9, "dlat");
    assert_close(g.dlon_deg, SPACING_M / e_per_deg, 1e-9, "dlon");

    // The grid covers the whole footprint.
    let (last_r, last_c) = (ROWS as usize - 1, COLS as usize - 1);
    for (r, c) in [
        (0, 0),
        (0, last_c),
        (last_r, 0),
        (last_r, last_c),
        (last_r / 2, 0),
    ] {
        let (e, n) = post_en(r, c);
        let (lat, lon) = utm_to_geodetic(zone, e, n);
        assert!(
            g.contains(lat, lon),
            "footprint post ({r}, {c}) at {lat}, {lon} outside {g:?}"
        );
    }
    // ... and not much more: about one post beyond the bounding box at most.
    let footprint_lat = (ROWS - 1) as f64 * SPACING_M / n_per_deg;
    assert!(g.north_lat_deg() - g.south_lat_deg < footprint_lat * 1.1);

    let (e_min, n_max) = post_en(0, 0);
    let (e_max, n_min) = post_en(last_r, last_c);
    let (void_e, void_n) = post_en(VOID.0, VOID.1);
    let (mut inside, mut outside, mut near_void_nan) = (0, 0, 0);
    let mut max_error = 0.0f64;
    for row in 0..g.rows {
        for col in 0..g.cols {
            let (lat, lon) = g.post_lat_lon_deg(row, col);
            let (e, n) = geodetic_to_utm(zone, lat, lon);
            let h = raster.elevation_at(row, col);
            let margin = 1e-6;
            let in_footprint = e >= e_min - margin
                && e <= e_max + margin
                && n >= n_min - margin
                && n <= n_max + margin;
            let near_void = (e - void_e).abs() < SPACING_M && (n - void_n).abs() < SPACING_M;
            if !in_footprint {
                assert!(
                    h.is_nan(),
                    "post ({row}, {col}) outside the footprint has {h}"
                );
                outside += 1;
            } else if near_void {
                near_void_nan += usize::from(h.is_nan());
            } else {
                assert!(
                    !h.is_nan(),
                    "post ({row}, {col}) inside the footprint is void"
                );
                let error = (f64::from(h) - utm_field(e, n)).abs();
                max_error = max_error.max(error);
                inside += 1;
            }
        }
    }
    assert!(max_error < 0.02, "interpolation error {max_error} m");
    assert!(inside > 3000, "{inside} posts inside");
    assert!(
        outside > 0,
        "the footprint is rotated against the lattice: corners are outside"
    );
    assert!(near_void_nan > 0, "the source void must show");
    assert_eq!(info.void_posts, raster.void_count());
}
