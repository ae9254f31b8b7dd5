//! Mosaics: adjacent SRTM tiles sharing an edge column, a finer DTED2 over a coarser DTED1
//! (finer posts unchanged), priorities, voids and the size limit.

mod import_support;

use cig_terrain::raster::{triangulated_height, Diagonal, GeoGrid, Raster};
use cig_terrain_io::import::{import_files, mosaic, read_dted_bytes, ImportError, SourceFormat};
use import_support::*;

fn srtm_value(south: i32, west: i32, bump_west_edge: bool) -> impl Fn(usize, usize) -> Option<i16> {
    move |row_from_north, col| {
        let row = 1200 - row_from_north;
        if is_void(row, col) {
            return None;
        }
        let lat = f64::from(south) + row as f64 / 1200.0;
        let lon = f64::from(west) + col as f64 / 1200.0;
        let bump = if bump_west_edge && col == 0 { 1 } else { 0 };
        Some(field_m(lat, lon).round() as i16 + bump)
    }
}

#[test]
fn adjacent_srtm_tiles_share_their_edge_column() {
    let dir = tempfile::tempdir().expect("tempdir");
    let west_tile = srtm_value(35, -122, false);
    // The east tile's west column (the shared edge) differs by 1 m so the winner shows.
    let east_tile = srtm_value(35, -121, true);
    let a = write_file(dir.path(), "N35W122.hgt", &write_hgt(1201, &west_tile));
    let b = write_file(dir.path(), "N35W121.hgt", &write_hgt(1201, &east_tile));

    for (paths, edge_from_west) in [(vec![a.clone(), b.clone()], true), (vec![b, a], false)] {
        let mut calls = Vec::new();
        let area =
            import_files(&paths, &mut |done, total| calls.push((done, total))).expect("import");
        assert_eq!(calls, vec![(1, 2), (2, 2)]);
        assert_eq!(area.sources.len(), 2);
        assert_eq!(area.sources[0].path, paths[0]);
        assert!(area
            .sources
            .iter()
            .all(|s| s.format == SourceFormat::SrtmHgt));

        let g = area.raster.grid;
        assert_eq!((g.rows, g.cols), (1201, 2401));
        assert_eq!(g.south_lat_deg, 35.0);
        assert_eq!(g.west_lon_deg, -122.0);
        assert_eq!(g.dlat_deg, 1.0 / 1200.0);
        assert_close(g.east_lon_deg(), -120.0, 1e-9, "east");
        assert_posts(&area.raster, |row, col| {
            let row_from_north = 1200 - row;
            let west = || west_tile(row_from_north, col).map(f32::from);
            let east = || east_tile(row_from_north, col - 1200).map(f32::from);
            match col {
                c if c < 1200 => west(),
                // The shared edge: the first file's post, or the other's where it is void.
                1200 if edge_from_west => west().or_else(east),
                1200 => east().or_else(west),
                _ => east(),
            }
        });
    }
}

fn dted(spec: &DtedSpec, offset_m: f64) -> (Raster, impl Fn(usize, usize) -> Option<f32> + '_) {
    let value = move |row: usize, col: usize| {
        if is_void(row, col) {
            return None;
        }
        let (lat, lon) = spec.post(row, col);
        Some((field_m(lat, lon) + offset_m).round() as i16)
    };
    let bytes = write_dted(spec, value);
    let (raster, _) = read_dted_bytes(&bytes, "x.dt1").expect("read dted");
    (raster, move |row, col| value(row, col).map(f32::from))
}

#[test]
fn finer_dted2_over_coarser_dted1_keeps_the_finer_posts_unchanged() {
    // Coarse: 3" posts over 10' x 10' from N35 W122. Fine: 1" posts, 3' x 3', inside it.
    let coarse_spec = DtedSpec {
        origin_lat_arcsec: 35 * 3600,
        origin_lon_arcsec: -122 * 3600,
        lat_interval: 30,
        lon_interval: 30,
        lat_points: 201,
        lon_lines: 201,
        level: 1,
    };
    let fine_spec = DtedSpec {
        origin_lat_arcsec: 35 * 3600 + 3 * 60 + 1,
        origin_lon_arcsec: -122 * 3600 + 3 * 60 + 2,
        lat_interval: 10,
        lon_interval: 10,
        lat_points: 181,
        lon_lines: 181,
        level: 2,
    };
    // Different fields so the source of each output post shows.
    let (coarse, coarse_value) = dted(&coarse_spec, 7.0);
    let (fine, fine_value) = dted(&fine_spec, 0.0);
    // Coarser first on the command line: the finer still wins and sets the lattice.
    let out = mosaic(&[coarse.clone(), fine.clone()]).expect("mosaic");
    let g = out.grid;
    assert_eq!(g.dlat_deg, fine.grid.dlat_deg);
    assert_eq!(g.dlon_deg, fine.grid.dlon_deg);
    assert_eq!(
        (g.rows, g.cols),
        (601, 601),
        "extent of the coarse tile at 1\" spacing"
    );
    assert_close(g.south_lat_deg, 35.0, 1e-9, "south");
    assert_close(g.west_lon_deg, -122.0, 1e-9, "west");

    // Every fine post: a query at it lands on an output post carrying its value.
    let mut checked = 0;
    let mut filled_from_coarse = 0;
    for row in 0..fine.grid.rows {
        for col in 0..fine.grid.cols {
            let (lat, lon) = fine.grid.post_lat_lon_deg(row, col);
            let (fr, fc) = g.fractional_index(lat, lon);
            let (r, c) = (fr.round(), fc.round());
            assert!((fr - r).abs() < 1e-6 && (fc - c).abs() < 1e-6, "{fr}, {fc}");
            let got = out.elevation_at(r as usize, c as usize);
            match fine_value(row, col) {
                Some(want) => assert_eq!(got, want, "fine post ({row}, {col})"),
                // A fine void is filled from the coarse source (its field is 7 m higher),
                // unless the coarse cell around it has a void too.
                None if got.is_nan() => {}
                None => {
                    let coarse_field = field_m(lat, lon) + 7.0;
                    assert!(
                        (f64::from(got) - coarse_field).abs() < 8.0,
                        "fine void ({row}, {col}) got {got}, coarse field {coarse_field}"
                    );
                    filled_from_coarse += 1;
                }
            }
            checked += 1;
        }
    }
    assert_eq!(checked, 181 * 181);
    assert!(
        filled_from_coarse > 100,
        "fine voids filled from DTED1: {filled_from_coarse}"
    );

    // Outside the fine patch: coarse posts exactly, triangulated surface between them.
    let inside_fine = |lat: f64, lon: f64| fine.grid.contains(lat, lon);
    let mut coarse_posts = 0;
    let mut between = 0;
    for row in 0..g.rows {
        for col in 0..g.cols {
            let (lat, lon) = g.post_lat_lon_deg(row, col);
            if inside_fine(lat, lon) {
                continue;
            }
            let got = out.elevation_at(row, col);
            let (cr, cc) = (row / 3, col / 3);
            let (v, u) = ((row % 3) as f64 / 3.0, (col % 3) as f64 / 3.0);
            if row % 3 == 0 && col % 3 == 0 {
                match coarse_value(cr, cc) {
                    Some(want) => assert_eq!(got, want),
                    None => assert!(got.is_nan()),
                }
                coarse_posts += 1;
            } else {
                let (r1, c1) = ((cr + 1).min(200), (cc + 1).min(200));
                let h = |r, c| coarse_value(r, c).unwrap_or(f32::NAN);
                // On a cell edge the surface is the line between the edge's posts.
                let lerp = |a: f32, b: f32, t: f64| f64::from(a) + t * f64::from(b - a);
                let want = if u == 0.0 {
                    lerp(h(cr, cc), h(r1, cc), v)
                } else if v == 0.0 {
                    lerp(h(cr, cc), h(cr, c1), u)
                } else if u == v {
                    lerp(h(cr, cc), h(r1, c1), u)
                } else {
                    triangulated_height(
                        [h(cr, cc), h(cr, c1), h(r1, cc), h(r1, c1)],
                        u,
                        v,
                        Diagonal::SouthWestNorthEast,
                    )
                };
                if want.is_nan() {
                    assert!(got.is_nan(), "({row}, {col}) next to a void got {got}");
                } else {
                    assert!(
                        (f64::from(got) - want).abs() < 1e-3,
                        "({row}, {col}): {got} vs {want}"
                    );
                }
                between += 1;
            }
        }
    }
    assert!(
        coarse_posts > 30_000 / 9 && between > 30_000,
        "{coarse_posts} {between}"
    );
}

fn flat(grid: GeoGrid, value: f32) -> Raster {
    Raster {
        grid,
        elevation_m: vec![value; grid.rows * grid.cols],
        material: None,
    }
}

#[test]
fn a_void_is_filled_from_the_next_source() {
    let grid = GeoGrid {
        south_lat_deg: 10.0,
        west_lon_deg: 20.0,
        dlat_deg: 0.5,
        dlon_deg: 0.5,
        rows: 3,
        cols: 3,
    };
    let mut first = flat(grid, 1.0);
    first.elevation_m[4] = f32::NAN;
    let second = flat(
        GeoGrid {
            west_lon_deg: 20.5,
            ..grid
        },
        2.0,
    );
    let out = mosaic(&[first, second]).expect("mosaic");
    assert_eq!((out.grid.rows, out.grid.cols), (3, 4));
    assert_eq!(
        out.elevation_at(1, 1),
        2.0,
        "the first source's void, from the second"
    );
    assert_eq!(out.elevation_at(1, 2), 1.0);
    assert_eq!(out.elevation_at(1, 3), 2.0);
}

#[test]
fn disjoint_sources_leave_a_void_gap() {
    let grid = GeoGrid {
        south_lat_deg: 0.0,
        west_lon_deg: 0.0,
        dlat_deg: 1.0,
        dlon_deg: 1.0,
        rows: 2,
        cols: 2,
    };
    let east = GeoGrid {
        west_lon_deg: 3.0,
        ..grid
    };
    let out = mosaic(&[flat(grid, 5.0), flat(east, 6.0)]).expect("mosaic");
    assert_eq!((out.grid.rows, out.grid.cols), (2, 5));
    assert_eq!(out.elevation_at(0, 1), 5.0);
    assert!(out.elevation_at(0, 2).is_nan());
    assert_eq!(out.elevation_at(1, 3), 6.0);
}

#[test]
fn single_source_is_returned_unchanged() {
    let grid = GeoGrid {
        south_lat_deg: 1.0,
        west_lon_deg: 2.0,
        dlat_deg: 0.1,
        dlon_deg: 0.2,
        rows: 2,
        cols: 3,
    };
    let mut raster = flat(grid, 3.0);
    raster.material = Some(vec![cig_terrain::material::Material::Rock; 6]);
    assert_eq!(
        mosaic(std::slice::from_ref(&raster)).expect("mosaic"),
        raster
    );
}

#[test]
fn a_mosaic_above_400_million_posts_is_refused() {
    let small = |south, west| GeoGrid {
        south_lat_deg: south,
        west_lon_deg: west,
        dlat_deg: 1.0 / 3600.0,
        dlon_deg: 1.0 / 3600.0,
        rows: 2,
        cols: 2,
    };
    let err = mosaic(&[
        flat(small(-60.0, -170.0), 0.0),
        flat(small(60.0, 170.0), 0.0),
    ])
    .expect_err("too large");
    assert!(matches!(err, ImportError::MosaicTooLarge { .. }), "{err}");
    assert!(err.to_string().contains("400000000"), "{err}");
    assert!(matches!(mosaic(&[]), Err(ImportError::NoInput)));
    assert!(matches!(
        import_files(&[], &mut |_, _| {}),
        Err(ImportError::NoInput)
    ));
}
