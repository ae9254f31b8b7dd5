//! Orthoimagery import: georeferencing of marks (EPSG:4326 with PixelIsArea and PixelIsPoint,
//! strips and tiles, and UTM), mosaic order, nodata and alpha, 16-bit scaling, and bad input
//! refused with the database unchanged.

mod imagery_support;

use cig_geo::utm::{geodetic_to_utm, utm_to_geodetic, UtmZone};
use cig_terrain_io::imagery::{add_imagery, write_imagery, ImageryError};
use cig_terrain_io::store::{write_database_with, BuildInputs};
use imagery_support::*;

const SOUTH: f64 = 35.0;
const WEST: f64 = -120.5;
/// Post spacing of the test databases, degrees.
const D: f64 = 1.0 / 3600.0;
/// Level-0 texel of an image of D / 8 pixels.
const T: f64 = D / 8.0;

/// Marks: pixel (col, row from north) of each 3x3 mark's centre.
const MARKS: [(u32, u32); 4] = [(20, 30), (150, 100), (280, 170), (60, 180)];

fn marked(w: u32, h: u32) -> Samples {
    rgb8(w, h, |c, r| {
        if MARKS
            .iter()
            .any(|&(mc, mr)| c.abs_diff(mc) <= 1 && r.abs_diff(mr) <= 1)
        {
            [255, 255, 255]
        } else {
            [60, 90, 40]
        }
    })
}

/// Centroid (level-0 texel coordinates, row, col) of the bright texels near `around`.
fn centroid(
    manifest: &cig_terrain::Manifest,
    tiles: &std::collections::BTreeMap<cig_terrain::ImageryKey, Vec<u8>>,
    around: (f64, f64),
) -> (f64, f64) {
    let (mut sw, mut sr, mut sc) = (0.0, 0.0, 0.0);
    let (r0, c0) = (around.0.floor() as i64, around.1.floor() as i64);
    for r in r0 - 6..=r0 + 6 {
        for c in c0 - 6..=c0 + 6 {
            let px = texel(manifest, tiles, 0, r as u64, c as u64).expect("texel stored");
            let w = f64::from(px[0]).sub_floor(150.0);
            sw += w;
            sr += w * (r as f64 + 0.5);
            sc += w * (c as f64 + 0.5);
        }
    }
    assert!(sw > 0.0, "no mark found near {around:?}");
    (sr / sw, sc / sw)
}

trait SubFloor {
    fn sub_floor(self, floor: f64) -> f64;
}
impl SubFloor for f64 {
    fn sub_floor(self, floor: f64) -> f64 {
        (self - floor).max(0.0)
    }
}

fn check_geographic(spec: &ImageSpec, name: &str) {
    let dir = tempfile::tempdir().expect("tempdir");
    let db = small_database(dir.path(), "db", SOUTH, WEST, 64);
    let (north, west) = (SOUTH + 450.3 * T, WEST + 100.6 * T);
    let mut spec = spec.clone();
    if spec.geokeys == Some(geokeys_geographic(4326, 2)) {
        // PixelIsPoint: the tie point is pixel (0, 0)'s centre.
        spec.tiepoint = [0.0, 0.0, 0.0, west + 0.5 * T, north - 0.5 * T, 0.0];
    } else {
        spec.tiepoint = [0.0, 0.0, 0.0, west, north, 0.0];
    }
    let image = write_file(dir.path(), name, &write_image(&spec, &marked(300, 200)));
    add_imagery(&db, &[image], &[], &mut |_| {}).expect("imagery");
    let (manifest, tiles) = read_tiles(&db);
    let layout = manifest.imagery.as_ref().expect("imagery").layout;
    assert_eq!(layout.fine_shift, 3);
    for (c, r) in MARKS {
        let lon = west + (f64::from(c) + 0.5) * T;
        let lat = north - (f64::from(r) + 0.5) * T;
        let predicted = layout.texel_coordinates(lat, lon);
        let found = centroid(&manifest, &tiles, predicted);
        let error = (found.0 - predicted.0).hypot(found.1 - predicted.1);
        eprintln!("{name}: mark {c},{r} off by {error:.3} texels");
        assert!(
            error <= 1.0,
            "{name}: mark {c},{r} at {found:?}, predicted {predicted:?}"
        );
    }
}

#[test]
fn marks_land_on_their_texels_in_geographic_images() {
    let mut strips = ImageSpec::geographic(300, 200, 0.0, 0.0, T);
    strips.comp = Comp::Lzw;
    check_geographic(&strips, "area-strips.tif");
    let mut tiles = ImageSpec::geographic(300, 200, 0.0, 0.0, T);
    tiles.chunks = Chunks::Tiles(64);
    tiles.comp = Comp::Deflate;
    tiles.geokeys = Some(geokeys_geographic(4326, 2));
    check_geographic(&tiles, "point-tiles.tif");
}

#[test]
fn marks_land_on_their_texels_in_utm_images() {
    let dir = tempfile::tempdir().expect("tempdir");
    let db = small_database(dir.path(), "db", SOUTH, WEST, 64);
    let zone = UtmZone::from_epsg(32610).expect("zone");
    let (ec, nc) = geodetic_to_utm(zone, SOUTH + 32.0 * D, WEST + 32.0 * D);
    let (pixel, w, h) = (3.0, 300u32, 200u32);
    let (west_e, north_n) = (ec - 451.3, nc + 280.7);
    let mut spec = ImageSpec::geographic(w, h, north_n, west_e, pixel);
    spec.geokeys = Some(geokeys_projected(32610, 1));
    spec.chunks = Chunks::Tiles(32);
    let image = write_file(dir.path(), "utm.tif", &write_image(&spec, &marked(w, h)));
    add_imagery(&db, &[image], &[], &mut |_| {}).expect("imagery");
    let (manifest, tiles) = read_tiles(&db);
    let layout = manifest.imagery.as_ref().expect("imagery").layout;
    assert_eq!(layout.fine_shift, 4);
    let texel_m = (manifest.spacing_m[0] / 16.0, manifest.spacing_m[1] / 16.0);
    for (c, r) in MARKS {
        let e = west_e + (f64::from(c) + 0.5) * pixel;
        let n = north_n - (f64::from(r) + 0.5) * pixel;
        let (lat, lon) = utm_to_geodetic(zone, e, n);
        let predicted = layout.texel_coordinates(lat, lon);
        let found = centroid(&manifest, &tiles, predicted);
        let error_m =
            ((found.0 - predicted.0) * texel_m.0).hypot((found.1 - predicted.1) * texel_m.1);
        eprintln!("utm: mark {c},{r} off by {error_m:.3} m");
        assert!(
            error_m <= pixel,
            "mark {c},{r}: {error_m:.2} m off (found {found:?}, predicted {predicted:?})"
        );
    }
}

const RED: [u8; 3] = [200, 30, 30];
const BLUE: [u8; 3] = [30, 30, 200];
const GREEN: [u8; 3] = [30, 200, 30];

fn close(px: Option<[u8; 4]>, want: [u8; 3], what: &str) {
    let px = px.unwrap_or_else(|| panic!("{what}: no opaque texel"));
    assert!(px[3] >= 128, "{what}: transparent");
    for b in 0..3 {
        assert!(
            px[b].abs_diff(want[b]) <= 12,
            "{what}: {px:?}, expected {want:?}"
        );
    }
}

/// A red image of 2T pixels over the whole database (native level 1).
fn coarse_red(dir: &std::path::Path) -> std::path::PathBuf {
    let spec = ImageSpec::geographic(256, 256, SOUTH + 512.0 * T, WEST, 2.0 * T);
    write_file(
        dir,
        "coarse.tif",
        &write_image(&spec, &rgb8(256, 256, |_, _| RED)),
    )
}

#[test]
fn finer_images_win_and_nodata_shows_the_coarser_one() {
    let dir = tempfile::tempdir().expect("tempdir");
    let db = small_database(dir.path(), "db", SOUTH, WEST, 64);
    let coarse = coarse_red(dir.path());
    // Blue, 100 x 100 texels at texel rows 300..400, cols 50..150; a nodata hole in the middle.
    let mut spec = ImageSpec::geographic(100, 100, SOUTH + 400.0 * T, WEST + 50.0 * T, T);
    spec.nodata = Some("0".into());
    let samples = rgb8(100, 100, |c, r| {
        if (40..60).contains(&c) && (40..60).contains(&r) {
            [0, 0, 0]
        } else {
            BLUE
        }
    });
    let fine = write_file(dir.path(), "fine.tif", &write_image(&spec, &samples));
    // The fine image first: order on the command line does not matter, pixel size does.
    add_imagery(&db, &[fine, coarse], &[], &mut |_| {}).expect("imagery");
    let (manifest, tiles) = read_tiles(&db);
    let layout = manifest.imagery.as_ref().expect("imagery").layout;
    assert_eq!((layout.fine_shift, layout.levels), (3, 2));
    // Level 0 only where the fine image is; level 1 over everything.
    assert_eq!(
        tiles.len(),
        2,
        "tiles {:?}",
        tiles.keys().collect::<Vec<_>>()
    );
    let at = |row: f64, col: f64| colour_at(&manifest, &tiles, SOUTH + row * T, WEST + col * T);
    close(at(380.5, 60.5), BLUE, "fine image");
    close(
        texel(&manifest, &tiles, 0, 380, 60),
        BLUE,
        "fine image at level 0",
    );
    close(texel(&manifest, &tiles, 0, 350, 100), RED, "nodata hole");
    close(at(100.5, 400.5), RED, "coarse elsewhere");
    close(
        texel(&manifest, &tiles, 0, 280, 200),
        RED,
        "coarse beside the fine",
    );
}

#[test]
fn alpha_is_transparent_and_shows_the_coarser_image() {
    let dir = tempfile::tempdir().expect("tempdir");
    let db = small_database(dir.path(), "db", SOUTH, WEST, 64);
    let mut spec = ImageSpec::geographic(100, 100, SOUTH + 400.0 * T, WEST + 50.0 * T, T);
    spec.bands = 4;
    spec.extra_samples = Some(2);
    spec.chunks = Chunks::Tiles(32);
    let mut v = Vec::new();
    for _r in 0..100 {
        for c in 0..100u32 {
            v.extend_from_slice(&GREEN);
            v.push(if c < 50 { 0 } else { 255 });
        }
    }
    let rgba = write_file(dir.path(), "rgba.tif", &write_image(&spec, &Samples::U8(v)));
    // Alone: the left half is transparent.
    add_imagery(&db, std::slice::from_ref(&rgba), &[], &mut |_| {}).expect("imagery");
    let (manifest, tiles) = read_tiles(&db);
    let left = texel(&manifest, &tiles, 0, 350, 70).expect("tile");
    assert!(left[3] < 128, "left half {left:?}");
    close(texel(&manifest, &tiles, 0, 350, 130), GREEN, "right half");
    // Over the coarse image (replacing the imagery): red shows through the left half.
    let coarse = coarse_red(dir.path());
    add_imagery(&db, &[rgba, coarse], &[], &mut |_| {}).expect("imagery");
    let (manifest, tiles) = read_tiles(&db);
    close(
        texel(&manifest, &tiles, 0, 350, 70),
        RED,
        "left half over red",
    );
    close(
        texel(&manifest, &tiles, 0, 350, 130),
        GREEN,
        "right half over red",
    );
}

#[test]
fn sixteen_bit_images_scale_their_999th_percentile_to_255() {
    let dir = tempfile::tempdir().expect("tempdir");
    let db = small_database(dir.path(), "db", SOUTH, WEST, 64);
    let (w, h) = (200u32, 100u32);
    let mut spec = ImageSpec::geographic(w, h, SOUTH + 400.0 * T, WEST + 50.0 * T, T);
    spec.comp = Comp::Deflate;
    let mut v = Vec::new();
    for r in 0..h {
        for c in 0..w {
            // Ten outliers: 0.05 % of the pixels.
            let s = if r == 0 && c < 10 {
                60000
            } else if c < 100 {
                500
            } else {
                1000
            };
            v.extend_from_slice(&[s, s, s]);
        }
    }
    let image = write_file(dir.path(), "16.tif", &write_image(&spec, &Samples::U16(v)));
    let manifest = add_imagery(&db, &[image], &[], &mut |_| {}).expect("imagery");
    assert!(manifest.imagery.expect("imagery").sources[0].contains("16-bit"));
    let (manifest, tiles) = read_tiles(&db);
    close(
        texel(&manifest, &tiles, 0, 350, 100),
        [128; 3],
        "500 of 1000",
    );
    close(
        texel(&manifest, &tiles, 0, 350, 200),
        [255; 3],
        "1000 of 1000",
    );
}

/// Sets inline LONG tags of the first IFD (width, length, rows per strip…).
fn set_long_tags(bytes: &mut [u8], tags: &[(u16, u32)]) {
    let u16_at = |b: &[u8], at: usize| u16::from_le_bytes([b[at], b[at + 1]]);
    let ifd = u32::from_le_bytes([bytes[4], bytes[5], bytes[6], bytes[7]]) as usize;
    for e in 0..usize::from(u16_at(bytes, ifd)) {
        let at = ifd + 2 + 12 * e;
        if let Some(&(_, value)) = tags.iter().find(|(t, _)| *t == u16_at(bytes, at)) {
            assert_eq!(u16_at(bytes, at + 2), 4, "a LONG tag");
            bytes[at + 8..at + 12].copy_from_slice(&value.to_le_bytes());
        }
    }
}

/// Halves the last strip's byte count: its compressed stream ends early.
fn shorten_last_strip(bytes: &mut [u8]) {
    let u16_at = |b: &[u8], at: usize| u16::from_le_bytes([b[at], b[at + 1]]);
    let u32_at = |b: &[u8], at: usize| u32::from_le_bytes([b[at], b[at + 1], b[at + 2], b[at + 3]]);
    let ifd = u32_at(bytes, 4) as usize;
    for e in 0..usize::from(u16_at(bytes, ifd)) {
        let at = ifd + 2 + 12 * e;
        if u16_at(bytes, at) == 279 {
            let count = u32_at(bytes, at + 4) as usize;
            let last = u32_at(bytes, at + 8) as usize + 4 * (count - 1);
            let half = u32_at(bytes, last) / 2;
            bytes[last..last + 4].copy_from_slice(&half.to_le_bytes());
            return;
        }
    }
    panic!("no StripByteCounts");
}

/// Sets the last strip's offset so its data runs past the end of the file.
fn truncate_last_strip(bytes: &mut [u8]) {
    let u16_at = |b: &[u8], at: usize| u16::from_le_bytes([b[at], b[at + 1]]);
    let u32_at = |b: &[u8], at: usize| u32::from_le_bytes([b[at], b[at + 1], b[at + 2], b[at + 3]]);
    let ifd = u32_at(bytes, 4) as usize;
    let entries = usize::from(u16_at(bytes, ifd));
    for e in 0..entries {
        let at = ifd + 2 + 12 * e;
        if u16_at(bytes, at) == 273 {
            let count = u32_at(bytes, at + 4) as usize;
            assert!(count > 1, "several strips");
            let array = u32_at(bytes, at + 8) as usize;
            let last = array + 4 * (count - 1);
            let offset = (bytes.len() - 10) as u32;
            bytes[last..last + 4].copy_from_slice(&offset.to_le_bytes());
            return;
        }
    }
    panic!("no StripOffsets");
}

#[test]
fn bad_images_are_refused_and_the_database_is_unchanged() {
    let dir = tempfile::tempdir().expect("tempdir");
    let db = small_database(dir.path(), "db", SOUTH, WEST, 64);
    let good_spec = ImageSpec::geographic(100, 100, SOUTH + 400.0 * T, WEST + 50.0 * T, T);
    let good = write_file(
        dir.path(),
        "good.tif",
        &write_image(&good_spec, &rgb8(100, 100, |_, _| BLUE)),
    );
    // A database that has imagery already: a failure keeps it.
    add_imagery(&db, std::slice::from_ref(&good), &[], &mut |_| {}).expect("imagery");
    let before = snapshot(&db);

    let mut cases: Vec<(std::path::PathBuf, &str)> = Vec::new();
    cases.push((
        write_file(dir.path(), "garbage.tif", b"hello, world"),
        "not a TIFF",
    ));
    let mut bytes = write_image(&good_spec, &rgb8(100, 100, |_, _| BLUE));
    let half = bytes.len() / 2;
    cases.push((write_file(dir.path(), "cut.tif", &bytes[..half]), "corrupt"));
    truncate_last_strip(&mut bytes);
    cases.push((
        write_file(dir.path(), "strip.tif", &bytes),
        "corrupt or truncated",
    ));
    let mut lzw_spec = good_spec.clone();
    lzw_spec.comp = Comp::Lzw;
    let mut lzw = write_image(&lzw_spec, &rgb8(100, 100, |c, r| [c as u8, r as u8, 7]));
    shorten_last_strip(&mut lzw);
    cases.push((
        write_file(dir.path(), "strip-lzw.tif", &lzw),
        "corrupt or truncated",
    ));
    // One strip of 30,000 x 30,000 pixels declared: refused before anything is decoded.
    let mut one_strip = good_spec.clone();
    one_strip.chunks = Chunks::Strips(100);
    let mut huge = write_image(&one_strip, &rgb8(100, 100, |_, _| BLUE));
    set_long_tags(&mut huge, &[(256, 30_000), (257, 30_000), (278, 30_000)]);
    cases.push((write_file(dir.path(), "huge.tif", &huge), "image too large"));
    let mut float = good_spec.clone();
    float.chunks = Chunks::Strips(100);
    cases.push((
        write_file(
            dir.path(),
            "float.tif",
            &write_image(&float, &Samples::F32(vec![0.5; 100 * 100 * 3])),
        ),
        "unsupported",
    ));
    let mut cmyk = good_spec.clone();
    cmyk.bands = 4;
    cmyk.photometric = 5;
    cases.push((
        write_file(
            dir.path(),
            "cmyk.tif",
            &write_image(&cmyk, &Samples::U8(vec![9; 100 * 100 * 4])),
        ),
        "unsupported",
    ));
    let mut bare = good_spec.clone();
    bare.geokeys = None;
    cases.push((
        write_file(
            dir.path(),
            "bare.tif",
            &write_image(&bare, &rgb8(100, 100, |_, _| BLUE)),
        ),
        "GeoKeyDirectoryTag",
    ));
    let mut mercator = good_spec.clone();
    mercator.geokeys = Some(geokeys_projected(3857, 1));
    cases.push((
        write_file(
            dir.path(),
            "mercator.tif",
            &write_image(&mercator, &rgb8(100, 100, |_, _| BLUE)),
        ),
        "EPSG:3857",
    ));
    let far = ImageSpec::geographic(100, 100, 10.0, 10.0, T);
    cases.push((
        write_file(
            dir.path(),
            "far.tif",
            &write_image(&far, &rgb8(100, 100, |_, _| BLUE)),
        ),
        "does not overlap",
    ));
    for (path, reason) in &cases {
        // The good image first: the failure comes after work was done.
        let result = add_imagery(&db, &[good.clone(), path.clone()], &[], &mut |_| {});
        let Err(error) = result else {
            panic!("{} was accepted", path.display());
        };
        let message = error.to_string();
        eprintln!("{message}");
        assert!(!message.contains('\n'), "one line: {message}");
        assert!(
            message.contains(reason) && message.ends_with(&path.display().to_string()),
            "{message}"
        );
        assert_eq!(
            snapshot(&db),
            before,
            "database changed by {}",
            path.display()
        );
    }
    let leftovers: Vec<_> = std::fs::read_dir(dir.path())
        .expect("dir")
        .filter_map(|e| e.ok())
        .filter(|e| e.file_name().to_string_lossy().starts_with('.'))
        .collect();
    assert!(leftovers.is_empty(), "staging left behind: {leftovers:?}");
    let missing = add_imagery(&dir.path().join("nope"), &[good], &[], &mut |_| {});
    assert!(
        matches!(missing, Err(ImageryError::Database(_))),
        "{missing:?}"
    );
}

#[test]
fn import_with_bad_imagery_writes_nothing() {
    let dir = tempfile::tempdir().expect("tempdir");
    let grid = cig_terrain::GeoGrid {
        south_lat_deg: SOUTH,
        west_lon_deg: WEST,
        dlat_deg: D,
        dlon_deg: D,
        rows: 65,
        cols: 65,
    };
    let mut raster = cig_terrain::Raster {
        grid,
        elevation_m: vec![10.0; 65 * 65],
        material: None,
    };
    cig_terrain::build::prepare_raster(&mut raster).expect("prepare");
    let inputs = BuildInputs {
        sources: vec![],
        void_posts_filled: 0,
        tile_cells: 64,
    };
    let bad = write_file(dir.path(), "bad.tif", b"II*\0garbage");
    let out = dir.path().join("db");
    let result = write_database_with::<ImageryError>(
        &out,
        &raster,
        &inputs,
        false,
        &mut |_, _| {},
        &mut |staging, manifest| {
            manifest.imagery = Some(write_imagery(
                staging,
                manifest,
                std::slice::from_ref(&bad),
                &[],
                &mut |_| {},
            )?);
            Ok(())
        },
    );
    assert!(result.is_err());
    assert_eq!(
        std::fs::read_dir(dir.path()).expect("dir").count(),
        1,
        "only bad.tif"
    );
}

/// Yellow boxes (level-0 texel rows and columns, half-open) painted at level 0 and above.
struct Boxes(Vec<(u64, u64, u64, u64)>);

const YELLOW: [u8; 3] = [230, 230, 20];

impl cig_terrain_io::imagery::OverlayLayer for Boxes {
    fn native_level(&self, _: &cig_terrain::ImageryLayout) -> u8 {
        0
    }
    fn touches(&self, (s, w, n, e): (f64, f64, f64, f64)) -> bool {
        self.0.iter().any(|&(r0, r1, c0, c1)| {
            let (bs, bn) = (SOUTH + r0 as f64 * T, SOUTH + r1 as f64 * T);
            let (bw, be) = (WEST + c0 as f64 * T, WEST + c1 as f64 * T);
            bs < n && s < bn && bw < e && w < be
        })
    }
    fn paint(
        &self,
        layout: &cig_terrain::ImageryLayout,
        key: cig_terrain::ImageryKey,
        rgba: &mut [u8],
    ) {
        let n = layout.tile_texels as u64;
        let s = 1u64 << key.level;
        for i in 0..n {
            for j in 0..n {
                // The level-0 texel under this texel's centre.
                let r = (u64::from(key.row) * n + i) * s + s / 2;
                let c = (u64::from(key.col) * n + j) * s + s / 2;
                if self
                    .0
                    .iter()
                    .any(|&(r0, r1, c0, c1)| (r0..r1).contains(&r) && (c0..c1).contains(&c))
                {
                    let at = ((i * n + j) * 4) as usize;
                    rgba[at..at + 4].copy_from_slice(&[YELLOW[0], YELLOW[1], YELLOW[2], 255]);
                }
            }
        }
    }
    fn describe(&self) -> String {
        "test boxes".into()
    }
}

#[test]
fn overlays_paint_over_imagery_and_make_their_own_tiles() {
    let dir = tempfile::tempdir().expect("tempdir");
    let db = small_database(dir.path(), "db", SOUTH, WEST, 64);
    let spec = ImageSpec::geographic(100, 100, SOUTH + 400.0 * T, WEST + 50.0 * T, T);
    let fine = write_file(
        dir.path(),
        "fine.tif",
        &write_image(&spec, &rgb8(100, 100, |_, _| BLUE)),
    );
    let boxes = Boxes(vec![(100, 120, 300, 320), (350, 360, 60, 70)]);
    let manifest = add_imagery(&db, &[fine], &[&boxes], &mut |_| {}).expect("imagery");
    assert!(manifest.imagery.expect("imagery").sources[1].contains("test boxes"));
    let (manifest, tiles) = read_tiles(&db);
    let keys: Vec<_> = tiles.keys().map(|k| (k.level, k.row, k.col)).collect();
    assert_eq!(keys, vec![(0, 0, 1), (0, 1, 0), (1, 0, 0)]);
    close(texel(&manifest, &tiles, 0, 110, 310), YELLOW, "box alone");
    close(
        texel(&manifest, &tiles, 0, 355, 65),
        YELLOW,
        "box over the image",
    );
    close(
        texel(&manifest, &tiles, 0, 380, 100),
        BLUE,
        "image beside the box",
    );
    close(
        texel(&manifest, &tiles, 1, 55, 155),
        YELLOW,
        "box at level 1",
    );
}

/// A database keeps the features it was built with (`features.geojson`), and new imagery
/// added to it is painted with them again: the road still shows over the new image.
#[test]
fn new_imagery_is_painted_with_the_databases_own_features() {
    use cig_terrain::features::{Feature, LineKind};
    let dir = tempfile::tempdir().expect("tempdir");
    let db = small_database(dir.path(), "db", SOUTH, WEST, 64);
    let road_lat = SOUTH + 30.0 * D;
    cig_terrain_io::features::write_features(
        &db.join(cig_terrain_io::features::DATABASE_FEATURES_FILE),
        &[Feature::Line {
            kind: LineKind::DirtRoad,
            width_m: 6.0,
            points_deg: vec![(road_lat, WEST + 2.0 * D), (road_lat, WEST + 60.0 * D)],
        }],
    )
    .expect("features");
    let spec = ImageSpec::geographic(512, 512, SOUTH + 64.0 * D, WEST, D / 8.0);
    let image = write_file(
        dir.path(),
        "blue.tif",
        &write_image(&spec, &rgb8(512, 512, |_, _| BLUE)),
    );
    let manifest = add_imagery(&db, &[image], &[], &mut |_| {}).expect("imagery");
    let sources = manifest.imagery.expect("imagery").sources;
    assert!(
        sources.iter().any(|s| s.contains("features")),
        "{sources:?}"
    );
    let (manifest, tiles) = read_tiles(&db);
    // Texels of dirt (tan: red well above blue) and of the image, at the finest level with any.
    let finest = tiles.keys().map(|k| k.level).min().expect("tiles");
    eprintln!(
        "levels {:?}, finest {finest}",
        manifest.imagery.as_ref().map(|i| i.layout.levels)
    );
    let (mut tan, mut blue) = (0, 0);
    for (key, rgba) in &tiles {
        if key.level != finest {
            continue;
        }
        for px in rgba.chunks_exact(4) {
            if px[3] == 255 && px[0] > px[2] + 40 {
                tan += 1;
            } else if px[3] == 255 && px[2] > px[0] + 100 {
                blue += 1;
            }
        }
    }
    assert!(
        tan > 100 && blue > 10 * tan,
        "road texels {tan}, image texels {blue}"
    );
    assert!(
        db.join(cig_terrain_io::features::DATABASE_FEATURES_FILE)
            .exists(),
        "the features stay with the database"
    );
}
