//! Round trips: a known elevation field written by a test-side writer in every supported
//! format, read back with `read_source` (or the byte-level readers), grid and every post checked.

mod import_support;

use cig_terrain_io::import::{
    read_dted_bytes, read_hgt_bytes, read_source, SourceFormat, SourceInfo,
};
use import_support::*;

const TOL_DEG: f64 = 1e-9;

// ---------------------------------------------------------------------------------------------
// GeoTIFF

/// Geographic test image: 45 x 37 pixels of 0.015 x 0.01 degrees, west edge 7.0, north edge
/// 46.5 (PixelIsArea).
const W: u32 = 45;
const H: u32 = 37;
const DLON: f64 = 0.015;
const DLAT: f64 = 0.01;
const WEST_EDGE: f64 = 7.0;
const NORTH_EDGE: f64 = 46.5;

/// North-first heights quantised for `kind` (NaN = void).
fn tiff_values(kind: SampleKind, first_post_lat: f64, first_post_lon: f64) -> Vec<f64> {
    let mut values = Vec::new();
    for r in 0..H as usize {
        for c in 0..W as usize {
            if is_void(r, c) {
                values.push(f64::NAN);
                continue;
            }
            let h = field_m(
                first_post_lat - r as f64 * DLAT,
                first_post_lon + c as f64 * DLON,
            );
            values.push(match kind {
                SampleKind::I16 | SampleKind::I32 => h.round(),
                SampleKind::U16 => h.round() + 1000.0,
                SampleKind::F32 | SampleKind::F64 => (h * 4.0).round() / 4.0,
            });
        }
    }
    values
}

fn nodata_for(kind: SampleKind) -> Option<String> {
    Some(
        match kind {
            SampleKind::I16 => "-32768",
            SampleKind::U16 => "65535",
            SampleKind::I32 => "-99999",
            SampleKind::F32 | SampleKind::F64 => "-9999",
        }
        .to_string(),
    )
}

fn area_spec(kind: SampleKind, layout: Layout, comp: Comp) -> TiffSpec {
    TiffSpec {
        width: W,
        height: H,
        sample: kind,
        layout,
        comp,
        predictor: false,
        geokeys: geokeys_geographic(4326, PIXEL_IS_AREA),
        pixel_scale: Some([DLON, DLAT, 0.0]),
        tiepoint: Some([0.0, 0.0, 0.0, WEST_EDGE, NORTH_EDGE, 0.0]),
        transformation: None,
        nodata: nodata_for(kind),
    }
}

/// Checks grid and posts of a geographic GeoTIFF whose first (north-west) post is at
/// `(north_post, west_post)`.
#[track_caller]
fn check_tiff(
    raster: &cig_terrain::raster::Raster,
    info: &SourceInfo,
    values: &[f64],
    north_post: f64,
    west_post: f64,
) {
    let g = raster.grid;
    assert_eq!((g.rows, g.cols), (H as usize, W as usize));
    assert_close(g.dlat_deg, DLAT, 1e-15, "dlat");
    assert_close(g.dlon_deg, DLON, 1e-15, "dlon");
    assert_close(g.west_lon_deg, west_post, TOL_DEG, "west");
    assert_close(g.north_lat_deg(), north_post, TOL_DEG, "north");
    assert_close(
        g.south_lat_deg,
        north_post - (H - 1) as f64 * DLAT,
        TOL_DEG,
        "south",
    );
    assert_eq!(info.format, SourceFormat::GeoTiff);
    assert_eq!(info.grid, g);
    assert_eq!(info.reprojected_from_epsg, None);
    let voids = values.iter().filter(|v| v.is_nan()).count();
    assert!(voids > 0);
    assert_eq!(info.void_posts, voids);
    assert!(raster.material.is_none());
    assert_posts(raster, |row, col| {
        let v = values[(H as usize - 1 - row) * W as usize + col];
        (!v.is_nan()).then_some(v as f32)
    });
}

#[test]
fn geotiff_every_sample_type_layout_and_compression_round_trips() {
    let dir = tempfile::tempdir().expect("tempdir");
    let north_post = NORTH_EDGE - DLAT / 2.0;
    let west_post = WEST_EDGE + DLON / 2.0;
    let mut cases = Vec::new();
    for kind in [SampleKind::I16, SampleKind::U16, SampleKind::F32] {
        for layout in [
            Layout::Strips { rows_per_strip: 7 },
            Layout::Tiles { size: 16 },
        ] {
            for comp in [Comp::None, Comp::Lzw, Comp::Deflate] {
                cases.push(area_spec(kind, layout, comp));
            }
        }
    }
    // Wider and narrower samples, and the horizontal predictor.
    cases.push(area_spec(
        SampleKind::I32,
        Layout::Strips { rows_per_strip: 5 },
        Comp::Deflate,
    ));
    cases.push(area_spec(
        SampleKind::F64,
        Layout::Tiles { size: 32 },
        Comp::Lzw,
    ));
    for (kind, comp) in [
        (SampleKind::I16, Comp::Lzw),
        (SampleKind::U16, Comp::Deflate),
    ] {
        let mut spec = area_spec(kind, Layout::Tiles { size: 16 }, comp);
        spec.predictor = true;
        cases.push(spec);
    }
    // Float voids as NaN, without a GDAL_NODATA tag.
    let mut spec = area_spec(
        SampleKind::F32,
        Layout::Strips { rows_per_strip: 37 },
        Comp::Lzw,
    );
    spec.nodata = None;
    cases.push(spec);

    for (i, spec) in cases.iter().enumerate() {
        let values = tiff_values(spec.sample, north_post, west_post);
        let bytes = write_geotiff(spec, &values);
        let path = write_file(dir.path(), &format!("case{i}.tif"), &bytes);
        let (raster, info) =
            read_source(&path).unwrap_or_else(|e| panic!("case {i} {spec:?}: {e}"));
        assert_eq!(info.path, path);
        check_tiff(&raster, &info, &values, north_post, west_post);
    }
}

#[test]
fn geotiff_pixel_is_point_puts_posts_at_the_tie_point() {
    let mut spec = area_spec(
        SampleKind::I16,
        Layout::Strips { rows_per_strip: 8 },
        Comp::None,
    );
    spec.geokeys = geokeys_geographic(4326, PIXEL_IS_POINT);
    let values = tiff_values(SampleKind::I16, NORTH_EDGE, WEST_EDGE);
    let bytes = write_geotiff(&spec, &values);
    let (raster, info) =
        cig_terrain_io::import::read_geotiff_bytes(&bytes, "point.tif").expect("read");
    check_tiff(&raster, &info, &values, NORTH_EDGE, WEST_EDGE);
}

#[test]
fn geotiff_model_transformation_without_rotation() {
    let mut spec = area_spec(SampleKind::F32, Layout::Tiles { size: 16 }, Comp::Deflate);
    spec.pixel_scale = None;
    spec.tiepoint = None;
    #[rustfmt::skip]
    let m = [
        DLON, 0.0, 0.0, WEST_EDGE,
        0.0, -DLAT, 0.0, NORTH_EDGE,
        0.0, 0.0, 0.0, 0.0,
        0.0, 0.0, 0.0, 1.0,
    ];
    spec.transformation = Some(m);
    let north_post = NORTH_EDGE - DLAT / 2.0;
    let west_post = WEST_EDGE + DLON / 2.0;
    let values = tiff_values(SampleKind::F32, north_post, west_post);
    let bytes = write_geotiff(&spec, &values);
    let (raster, info) =
        cig_terrain_io::import::read_geotiff_bytes(&bytes, "transform.tif").expect("read");
    check_tiff(&raster, &info, &values, north_post, west_post);
}

#[test]
fn geotiff_nad83_and_etrs89_are_read_as_wgs84() {
    for epsg in [4269, 4258] {
        let mut spec = area_spec(
            SampleKind::I16,
            Layout::Strips { rows_per_strip: 8 },
            Comp::Lzw,
        );
        spec.geokeys = geokeys_geographic(epsg, PIXEL_IS_AREA);
        let values = tiff_values(
            SampleKind::I16,
            NORTH_EDGE - DLAT / 2.0,
            WEST_EDGE + DLON / 2.0,
        );
        let bytes = write_geotiff(&spec, &values);
        let (raster, info) =
            cig_terrain_io::import::read_geotiff_bytes(&bytes, "nad83.tif").expect("read");
        check_tiff(
            &raster,
            &info,
            &values,
            NORTH_EDGE - DLAT / 2.0,
            WEST_EDGE + DLON / 2.0,
        );
    }
}

// ---------------------------------------------------------------------------------------------
// SRTM

fn hgt_case(n: usize, south: i32, west: i32, name: &str, bytes_only: bool) {
    let spacing = 1.0 / (n - 1) as f64;
    let value = |row_from_north: usize, col: usize| {
        let row = n - 1 - row_from_north;
        if is_void(row, col) {
            return None;
        }
        let lat = f64::from(south) + row as f64 * spacing;
        let lon = f64::from(west) + col as f64 * spacing;
        Some(field_m(lat, lon).round() as i16)
    };
    let bytes = write_hgt(n, value);
    let (raster, info) = if bytes_only {
        read_hgt_bytes(&bytes, name).expect("read hgt")
    } else {
        let dir = tempfile::tempdir().expect("tempdir");
        let path = write_file(dir.path(), name, &bytes);
        read_source(&path).expect("read hgt")
    };
    let g = raster.grid;
    assert_eq!((g.rows, g.cols), (n, n));
    assert_eq!(g.south_lat_deg, f64::from(south));
    assert_eq!(g.west_lon_deg, f64::from(west));
    assert_close(g.dlat_deg, spacing, 1e-15, "dlat");
    assert_close(g.dlon_deg, spacing, 1e-15, "dlon");
    assert_eq!(info.format, SourceFormat::SrtmHgt);
    assert_eq!(
        info.void_posts,
        (0..n * n).filter(|i| is_void(i / n, i % n)).count()
    );
    assert_posts(&raster, |row, col| value(n - 1 - row, col).map(f32::from));
}

#[test]
fn srtm_3_arc_second_tile_round_trips() {
    hgt_case(1201, 35, -122, "N35W122.hgt", false);
}

#[test]
fn srtm_1_arc_second_tile_with_long_lowercase_name_round_trips() {
    hgt_case(3601, -9, 33, "s09e033.SRTMGL1.hgt", true);
}

// ---------------------------------------------------------------------------------------------
// DTED

fn dted_value(spec: &DtedSpec) -> impl Fn(usize, usize) -> Option<i16> + '_ {
    move |row, col| {
        if is_void(row, col) {
            return None;
        }
        let (lat, lon) = spec.post(row, col);
        // Mirror a quarter of the posts below zero to exercise signed magnitude.
        let sign = if (row + col) % 4 == 0 { -1.0 } else { 1.0 };
        Some((sign * field_m(lat, lon)).round() as i16)
    }
}

fn dted_case(spec: DtedSpec, name: &str) {
    let bytes = write_dted(&spec, dted_value(&spec));
    let dir = tempfile::tempdir().expect("tempdir");
    let path = write_file(dir.path(), name, &bytes);
    let (raster, info) = read_source(&path).expect("read dted");
    let g = raster.grid;
    assert_eq!((g.rows, g.cols), (spec.lat_points, spec.lon_lines));
    assert_close(g.south_lat_deg, spec.south_lat_deg(), 1e-12, "south");
    assert_close(g.west_lon_deg, spec.west_lon_deg(), 1e-12, "west");
    assert_close(g.dlat_deg, spec.dlat_deg(), 1e-15, "dlat");
    assert_close(g.dlon_deg, spec.dlon_deg(), 1e-15, "dlon");
    assert_eq!(info.format, SourceFormat::Dted);
    let value = dted_value(&spec);
    let mut negatives = 0;
    assert_posts(&raster, |row, col| {
        let v = value(row, col);
        negatives += usize::from(v.is_some_and(|v| v < 0));
        v.map(f32::from)
    });
    assert!(negatives > 0, "the field must reach below zero");
    assert_eq!(info.void_posts, raster.void_count());
    assert!(info.void_posts > 0);
}

#[test]
fn dted_level_0_round_trips() {
    dted_case(small_dted_spec(), "n35w122.dt0");
}

#[test]
fn dted_level_1_southern_eastern_round_trips() {
    dted_case(
        DtedSpec {
            origin_lat_arcsec: -12 * 3600,
            origin_lon_arcsec: 45 * 3600,
            lat_interval: 30,
            lon_interval: 30,
            lat_points: 1201,
            lon_lines: 1201,
            level: 1,
        },
        "s12e045.DT1",
    );
}

#[test]
fn dted_level_2_above_50_degrees_has_wider_longitude_interval() {
    dted_case(
        DtedSpec {
            origin_lat_arcsec: 60 * 3600 + 30 * 60,
            origin_lon_arcsec: -(10 * 3600) + 15,
            lat_interval: 10,
            lon_interval: 20,
            lat_points: 301,
            lon_lines: 151,
            level: 2,
        },
        "n60w010.dt2",
    );
}

#[test]
fn dted_bytes_reader_matches_file_reader() {
    let spec = DtedSpec {
        origin_lat_arcsec: 0,
        origin_lon_arcsec: 0,
        lat_interval: 300,
        lon_interval: 300,
        lat_points: 13,
        lon_lines: 9,
        level: 0,
    };
    let bytes = write_dted(&spec, |row, col| Some(-(row as i16) * 100 - col as i16));
    let (raster, _) = read_dted_bytes(&bytes, "tiny.dt0").expect("read");
    assert_eq!(raster.elevation_at(12, 8), -1208.0);
    assert_eq!(raster.elevation_at(0, 0), 0.0);
    assert_eq!(raster.elevation_at(3, 1), -301.0);
}

// ---------------------------------------------------------------------------------------------
// ESRI ASCII grid

fn asc_case(corner: bool) {
    let spec = AscSpec {
        ncols: 23,
        nrows: 17,
        xll: -3.0,
        yll: 51.2,
        corner,
        cellsize: 0.125,
        nodata: -9999.0,
    };
    let half = if corner { 0.0625 } else { 0.0 };
    let (west, south) = (spec.xll + half, spec.yll + half);
    let north = south + (spec.nrows - 1) as f64 * spec.cellsize;
    let mut values = Vec::new();
    for r in 0..spec.nrows {
        for c in 0..spec.ncols {
            let lat = north - r as f64 * spec.cellsize;
            let lon = west + c as f64 * spec.cellsize;
            values.push(if is_void(r, c) {
                f64::NAN
            } else {
                (field_m(lat, lon) * 4.0).round() / 4.0
            });
        }
    }
    let text = write_asc(&spec, &values);
    let dir = tempfile::tempdir().expect("tempdir");
    let path = write_file(dir.path(), "grid.asc", text.as_bytes());
    let (raster, info) = read_source(&path).expect("read asc");
    let g = raster.grid;
    assert_eq!((g.rows, g.cols), (spec.nrows, spec.ncols));
    assert_close(g.west_lon_deg, west, 1e-12, "west");
    assert_close(g.south_lat_deg, south, 1e-12, "south");
    assert_eq!(g.dlat_deg, 0.125);
    assert_eq!(g.dlon_deg, 0.125);
    assert_eq!(info.format, SourceFormat::EsriAscii);
    assert_eq!(
        info.void_posts,
        values.iter().filter(|v| v.is_nan()).count()
    );
    assert_posts(&raster, |row, col| {
        let v = values[(spec.nrows - 1 - row) * spec.ncols + col];
        (!v.is_nan()).then_some(v as f32)
    });
}

#[test]
fn esri_ascii_corner_registration_round_trips() {
    asc_case(true);
}

#[test]
fn esri_ascii_centre_registration_round_trips() {
    asc_case(false);
}

#[test]
fn esri_ascii_with_dx_dy_wrapped_values_and_unknown_extension() {
    let text = "NCOLS 3\nNROWS 2\nXLLCENTER 10\nYLLCENTER 20\nDX 0.5\nDY 0.25\n\
                1 2\n3\n4 5 6\n";
    let dir = tempfile::tempdir().expect("tempdir");
    // No known extension: detected by its first keyword.
    let path = write_file(dir.path(), "grid.txt", text.as_bytes());
    let (raster, info) = read_source(&path).expect("read");
    assert_eq!(info.format, SourceFormat::EsriAscii);
    assert_eq!(raster.grid.dlon_deg, 0.5);
    assert_eq!(raster.grid.dlat_deg, 0.25);
    assert_eq!(raster.elevation_m, vec![4.0, 5.0, 6.0, 1.0, 2.0, 3.0]);
}
