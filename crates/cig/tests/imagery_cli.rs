//! End to end through the `cig` binary: imagery is georeferenced exactly in the rendered picture.
//! An image with known marks, imported over a flat database and rendered at nadir, shows each
//! mark at its predicted pixel within 1 px, from an EPSG:4326 source and from a UTM one.

mod common;

use cig_geo::utm::{geodetic_to_utm, UtmZone};
use common::cig;
use std::path::Path;

/// The centre point: the eye is straight above it.
const LAT0: f64 = 36.015_13;
const LON0: f64 = -120.981_47;
/// Marks, (north_m, east_m) from the centre point.
const MARKS: [(f64, f64); 5] = [
    (0.0, 0.0),
    (95.0, 70.0),
    (-80.0, 100.0),
    (60.0, -105.0),
    (-100.0, -40.0),
];
const MARK_RADIUS_M: f64 = 1.6;
/// Source pixel size, metres (on the ground, or UTM grid metres).
const PIXEL_M: f64 = 0.5;
/// Half the side of each image, metres.
const HALF_SIDE_M: f64 = 130.0;
const BACKGROUND: u8 = 60;
/// The eye's height above the ground, metres.
const EYE_HAT_M: f64 = 250.0;
const FRAME_PX: u32 = 320;

/// A flat database (100 m everywhere) of 1 arc-second posts, about 3.3 km on a side, around the
/// centre point.
fn flat_database(dir: &Path) -> std::path::PathBuf {
    let asc = dir.join("flat.asc");
    let (rows, cols) = (109usize, 133usize);
    let mut text = format!(
        "ncols {cols}\nnrows {rows}\nxllcenter -121.0\nyllcenter 36.0\ncellsize {}\nNODATA_value -9999\n",
        1.0 / 3600.0
    );
    let row = vec!["100"; cols].join(" ");
    for _ in 0..rows {
        text.push_str(&row);
        text.push('\n');
    }
    std::fs::write(&asc, text).expect("write grid");
    let db = dir.join("db");
    cig()
        .args(["db", "import", "--out"])
        .arg(&db)
        .arg(&asc)
        .assert()
        .success();
    db
}

/// The ground's height above the ellipsoid at a point, as `cig query hat` answers it.
fn ground_ellipsoid_m(db: &Path, lat: f64, lon: f64) -> f64 {
    let out = cig()
        .args(["query", "hat"])
        .arg(db)
        .args([&lat.to_string(), &lon.to_string(), "--json"])
        .assert()
        .success();
    let json: serde_json::Value = serde_json::from_slice(&out.get_output().stdout).expect("json");
    json["height_ellipsoid_m"].as_f64().expect("height")
}

/// The geographic position of a mark (the offsets are small enough, 110 m, that the local
/// metres per degree place it within millimetres).
fn mark_lat_lon(ground_m: f64, (north_m, east_m): (f64, f64)) -> (f64, f64) {
    let (m_lat, m_lon) = cig_geo::metres_per_degree(LAT0);
    let scale = 1.0 + ground_m / 6_371_000.0;
    (
        LAT0 + north_m / (m_lat * scale),
        LON0 + east_m / (m_lon * scale),
    )
}

/// An 8-bit RGB image: grey, with a white disc (anti-aliased by 4 x 4 supersampling) around
/// each of `centres`, in the image's own map units, north-west corner `(west, north)` and pixel
/// size `(dx, dy)`; `metres(dx, dy)` turns a map-unit offset into ground metres near a mark.
fn marked_image(
    w: u32,
    h: u32,
    (west, north): (f64, f64),
    (dx, dy): (f64, f64),
    centres: &[(f64, f64)],
    metres: &dyn Fn(f64, f64) -> (f64, f64),
) -> Vec<u8> {
    let mut cover = vec![0.0f64; (w * h) as usize];
    let reach = 2.5 * MARK_RADIUS_M / PIXEL_M;
    for &(cx, cy) in centres {
        let (col, row) = ((cx - west) / dx, (north - cy) / dy);
        let c0 = (col - reach).floor().max(0.0) as u32;
        let c1 = ((col + reach).ceil() as u32).min(w - 1);
        let r0 = (row - reach).floor().max(0.0) as u32;
        let r1 = ((row + reach).ceil() as u32).min(h - 1);
        for r in r0..=r1 {
            for c in c0..=c1 {
                let mut inside = 0u32;
                for sy in 0..4 {
                    for sx in 0..4 {
                        let x = west + (f64::from(c) + (f64::from(sx) + 0.5) / 4.0) * dx;
                        let y = north - (f64::from(r) + (f64::from(sy) + 0.5) / 4.0) * dy;
                        let (e, n) = metres(x - cx, y - cy);
                        if e.hypot(n) <= MARK_RADIUS_M {
                            inside += 1;
                        }
                    }
                }
                cover[(r * w + c) as usize] += f64::from(inside) / 16.0;
            }
        }
    }
    cover
        .iter()
        .flat_map(|&f| {
            let v =
                (f64::from(BACKGROUND) + f.min(1.0) * f64::from(255 - BACKGROUND)).round() as u8;
            [v, v, v]
        })
        .collect()
}

/// Writes an RGB GeoTIFF (PixelIsArea: the tie point is pixel (0, 0)'s north-west corner).
fn write_geotiff(
    path: &Path,
    w: u32,
    h: u32,
    keys: &[u16],
    scale: [f64; 3],
    tie: [f64; 6],
    data: &[u8],
) {
    use tiff::encoder::{colortype, TiffEncoder};
    use tiff::tags::Tag;
    let file = std::fs::File::create(path).expect("create");
    let mut encoder = TiffEncoder::new(std::io::BufWriter::new(file)).expect("encoder");
    let mut image = encoder.new_image::<colortype::RGB8>(w, h).expect("image");
    let dir = image.encoder();
    dir.write_tag(Tag::GeoKeyDirectoryTag, keys).expect("keys");
    dir.write_tag(Tag::ModelPixelScaleTag, &scale[..])
        .expect("scale");
    dir.write_tag(Tag::ModelTiepointTag, &tie[..])
        .expect("tiepoint");
    image.write_data(data).expect("data");
}

/// Geographic (EPSG:4326, degrees) and projected (UTM, metres) GeoKey directories, PixelIsArea.
const KEYS_4326: [u16; 20] = [
    1, 1, 0, 4, 1024, 0, 1, 2, 1025, 0, 1, 1, 2048, 0, 1, 4326, 2054, 0, 1, 9102,
];
const KEYS_32610: [u16; 20] = [
    1, 1, 0, 4, 1024, 0, 1, 1, 1025, 0, 1, 1, 3072, 0, 1, 32610, 3076, 0, 1, 9001,
];

/// An EPSG:4326 image of 0.5 m pixels (in degrees at the centre's latitude) around the centre.
fn geographic_image(path: &Path, ground_m: f64) {
    let (m_lat, m_lon) = cig_geo::metres_per_degree(LAT0);
    let (dy, dx) = (PIXEL_M / m_lat, PIXEL_M / m_lon);
    let side = (2.0 * HALF_SIDE_M / PIXEL_M) as u32;
    // The grid is offset from the centre by a fraction of a pixel, so nothing lines up by luck.
    let north = LAT0 + HALF_SIDE_M / m_lat + 0.37 * dy;
    let west = LON0 - HALF_SIDE_M / m_lon - 0.29 * dx;
    let centres: Vec<(f64, f64)> = MARKS
        .iter()
        .map(|&m| {
            let (lat, lon) = mark_lat_lon(ground_m, m);
            (lon, lat)
        })
        .collect();
    let data = marked_image(
        side,
        side,
        (west, north),
        (dx, dy),
        &centres,
        &|ddx, ddy| (ddx * m_lon, ddy * m_lat),
    );
    write_geotiff(
        path,
        side,
        side,
        &KEYS_4326,
        [dx, dy, 0.0],
        [0.0, 0.0, 0.0, west, north, 0.0],
        &data,
    );
}

/// A UTM zone 10N (EPSG:32610) image of 0.5 m grid pixels, north-up in the grid (so about 1.2
/// degrees off true north here), around the centre.
fn utm_image(path: &Path, ground_m: f64) {
    let zone = UtmZone::from_epsg(32610).expect("zone");
    let (e0, n0) = geodetic_to_utm(zone, LAT0, LON0);
    let side = (2.0 * HALF_SIDE_M / PIXEL_M) as u32;
    let north = (n0 + HALF_SIDE_M).floor() + 0.21;
    let west = (e0 - HALF_SIDE_M).floor() + 0.33;
    let centres: Vec<(f64, f64)> = MARKS
        .iter()
        .map(|&m| {
            let (lat, lon) = mark_lat_lon(ground_m, m);
            geodetic_to_utm(zone, lat, lon)
        })
        .collect();
    // Grid metres are within 0.1 % of ground metres here, and a disc stays a disc under the
    // grid's rotation.
    let data = marked_image(
        side,
        side,
        (west, north),
        (PIXEL_M, PIXEL_M),
        &centres,
        &|de, dn| (de, dn),
    );
    write_geotiff(
        path,
        side,
        side,
        &KEYS_32610,
        [PIXEL_M, PIXEL_M, 0.0],
        [0.0, 0.0, 0.0, west, north, 0.0],
        &data,
    );
}

/// Grey levels (the mean of R, G and B) of an 8-bit RGB or RGBA PNG.
fn read_grey(path: &Path) -> (u32, u32, Vec<f64>) {
    let decoder = png::Decoder::new(std::io::BufReader::new(
        std::fs::File::open(path).expect("png"),
    ));
    let mut reader = decoder.read_info().expect("png info");
    let mut buf = vec![0; reader.output_buffer_size()];
    let info = reader.next_frame(&mut buf).expect("png frame");
    assert_eq!(info.bit_depth, png::BitDepth::Eight, "8-bit PNG");
    let channels = match info.color_type {
        png::ColorType::Rgb => 3,
        png::ColorType::Rgba => 4,
        other => panic!("unexpected PNG colour type {other:?}"),
    };
    let grey = buf[..info.buffer_size()]
        .chunks_exact(channels)
        .map(|p| (f64::from(p[0]) + f64::from(p[1]) + f64::from(p[2])) / 3.0)
        .collect();
    (info.width, info.height, grey)
}

/// Renders the database at nadir from `EYE_HAT_M` above the centre and checks every mark.
fn check_marks(db: &Path, ground_m: f64, name: &str) {
    let frame = std::path::PathBuf::from(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("imagery_cli_{name}.png"));
    let eye = format!("{LAT0},{LON0},{}", ground_m + EYE_HAT_M);
    let size = format!("{FRAME_PX}x{FRAME_PX}");
    cig()
        .args(["render", "--db"])
        .arg(db)
        .args([
            "--eye", &eye, "--hpr", "0,-90,0", "--fov", "60", "--size", &size,
        ])
        .args(["--time", "2024-06-21T20:00:00Z", "--out"])
        .arg(&frame)
        .assert()
        .success();
    let (w, h, grey) = read_grey(&frame);
    assert_eq!((w, h), (FRAME_PX, FRAME_PX));
    let mut sorted = grey.clone();
    sorted.sort_by(f64::total_cmp);
    let background = sorted[sorted.len() / 2];
    let brightest = sorted[sorted.len() - 1];
    eprintln!(
        "{name}: frame {} (background {background:.1}, brightest {brightest:.1})",
        frame.display()
    );
    assert!(
        brightest > background + 30.0,
        "{name}: no marks in the frame"
    );

    let half = f64::from(FRAME_PX) / 2.0;
    let px_per_m = half / (EYE_HAT_M * 30f64.to_radians().tan());
    let mut misses = Vec::new();
    for &(north_m, east_m) in &MARKS {
        // Frame coordinates: pixel (i, j) covers [i, i + 1) x [j, j + 1), its centre at + 0.5;
        // the optical axis is at (160, 160), the corner the four middle pixels share.
        let want = (half + east_m * px_per_m, half - north_m * px_per_m);
        // The ground's shading varies across the frame (this flat database is classified as
        // water, and the sun glints on it): the background under a mark is the plane fitted to
        // the ring of pixels around its window.
        let reach = 6i64;
        let (ci, cj) = (want.0.floor() as i64, want.1.floor() as i64);
        assert!(
            ci - reach >= 0
                && cj - reach >= 0
                && ci + reach < i64::from(w)
                && cj + reach < i64::from(h),
            "{name}: mark window off the frame"
        );
        let at = |i: i64, j: i64| grey[(j as usize) * w as usize + i as usize];
        let (mut ring_n, mut ring_v, mut ring_xv, mut ring_xx, mut ring_yv, mut ring_yy) =
            (0.0, 0.0, 0.0, 0.0, 0.0, 0.0);
        for j in -reach..=reach {
            for i in -reach..=reach {
                if i.abs() == reach || j.abs() == reach {
                    let v = at(ci + i, cj + j);
                    let (x, y) = (i as f64, j as f64);
                    ring_n += 1.0;
                    ring_v += v;
                    ring_xv += x * v;
                    ring_xx += x * x;
                    ring_yv += y * v;
                    ring_yy += y * y;
                }
            }
        }
        // The ring is symmetric about (ci, cj): the least-squares plane's terms separate.
        let plane = |i: i64, j: i64| {
            ring_v / ring_n + ring_xv / ring_xx * i as f64 + ring_yv / ring_yy * j as f64
        };
        let (mut sum, mut sx, mut sy) = (0.0, 0.0, 0.0);
        for j in 1 - reach..reach {
            for i in 1 - reach..reach {
                let v = at(ci + i, cj + j) - plane(i, j);
                if v > 2.0 {
                    sum += v;
                    sx += v * ((ci + i) as f64 + 0.5);
                    sy += v * ((cj + j) as f64 + 0.5);
                }
            }
        }
        assert!(
            sum > 50.0,
            "{name}: no mark near ({:.2}, {:.2}) for {north_m} m north, {east_m} m east",
            want.0,
            want.1
        );
        let got = (sx / sum, sy / sum);
        let miss = (got.0 - want.0, got.1 - want.1);
        eprintln!(
            "{name}: mark {north_m:>6.1} m N {east_m:>6.1} m E: predicted ({:.2}, {:.2}), found ({:.2}, {:.2}), miss ({:+.2}, {:+.2}) px = {:.2} px",
            want.0,
            want.1,
            got.0,
            got.1,
            miss.0,
            miss.1,
            miss.0.hypot(miss.1)
        );
        misses.push(((north_m, east_m), miss));
    }
    let n = misses.len() as f64;
    let mean = misses
        .iter()
        .fold((0.0, 0.0), |a, (_, m)| (a.0 + m.0 / n, a.1 + m.1 / n));
    eprintln!("{name}: mean miss ({:+.2}, {:+.2}) px", mean.0, mean.1);
    for ((north_m, east_m), miss) in misses {
        assert!(
            miss.0.hypot(miss.1) <= 1.0,
            "{name}: the mark {north_m} m north, {east_m} m east is {:.2} px off ({:+.2}, {:+.2})",
            miss.0.hypot(miss.1),
            miss.0,
            miss.1
        );
    }
}

#[test]
fn marks_of_geographic_and_utm_imagery_land_on_their_predicted_pixels() {
    let dir = tempfile::tempdir().expect("tmp");
    let db = flat_database(dir.path());
    let ground_m = ground_ellipsoid_m(&db, LAT0, LON0);
    eprintln!("ground at the centre: {ground_m:.3} m above the ellipsoid");

    let geographic = dir.path().join("geographic.tif");
    geographic_image(&geographic, ground_m);
    cig()
        .args(["db", "imagery"])
        .arg(&db)
        .arg(&geographic)
        .assert()
        .success();
    check_marks(&db, ground_m, "epsg4326");

    // The UTM image replaces the geographic one.
    let utm = dir.path().join("utm.tif");
    utm_image(&utm, ground_m);
    cig()
        .args(["db", "imagery"])
        .arg(&db)
        .arg(&utm)
        .assert()
        .success();
    check_marks(&db, ground_m, "utm10n");
}
