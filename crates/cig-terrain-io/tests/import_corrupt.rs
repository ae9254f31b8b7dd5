//! Bad input never crashes: each corrupt file gives the right error variant, with a one-line
//! message that ends with the path; random and mutated bytes never panic any reader.

mod import_support;

use std::path::{Path, PathBuf};

use cig_terrain_io::import::{
    read_asc_str, read_dted_bytes, read_geotiff_bytes, read_hgt_bytes, read_source, ImportError,
};
use import_support::*;
use proptest::prelude::*;

fn small_dted() -> Vec<u8> {
    write_dted(&small_dted_spec(), |row, col| {
        Some((row as i16 - 60) * 10 + col as i16)
    })
}

/// Writes `bytes` as `name`, reads it back and checks the message: one line, path last.
fn read_err(dir: &Path, name: &str, bytes: &[u8]) -> (ImportError, PathBuf) {
    let path = write_file(dir, name, bytes);
    let err = read_source(&path).expect_err("corrupt input must fail");
    let message = err.to_string();
    assert!(!message.contains('\n'), "one line: {message}");
    assert!(
        message.ends_with(&path.display().to_string()),
        "path last: {message}"
    );
    assert_eq!(err.path(), Some(path.as_path()));
    (err, path)
}

#[test]
fn truncated_dted_names_the_record() {
    let dir = tempfile::tempdir().expect("tempdir");
    let bytes = small_dted();
    let record_len = 12 + 2 * 121;
    let cut = 3428 + 17 * record_len + 100;
    let (err, _) = read_err(dir.path(), "n35w122.dt0", &bytes[..cut]);
    match &err {
        ImportError::Truncated {
            expected, found, ..
        } => assert_eq!((*expected, *found), (record_len as u64, 100)),
        other => panic!("wrong variant: {other:?}"),
    }
    assert!(
        err.to_string()
            .starts_with("truncated DTED data record 17 (expected 254 bytes, found 100): "),
        "{err}"
    );
    // Truncated inside the headers.
    let (err, _) = read_err(dir.path(), "short.dt1", &bytes[..1000]);
    assert!(matches!(err, ImportError::Truncated { .. }), "{err}");
    let (err, _) = read_err(dir.path(), "tiny.dt1", b"UHL1");
    assert!(matches!(err, ImportError::Truncated { .. }), "{err}");
}

#[test]
fn bad_dted_checksum_names_the_record() {
    let dir = tempfile::tempdir().expect("tempdir");
    let mut bytes = small_dted();
    let record_len = 12 + 2 * 121;
    bytes[3428 + 5 * record_len + 20] ^= 0x10;
    let (err, _) = read_err(dir.path(), "n35w122.dt0", &bytes);
    assert!(
        matches!(err, ImportError::Checksum { record: 5, .. }),
        "{err:?}"
    );
    assert!(err.to_string().contains("checksum"), "{err}");
}

#[test]
fn dted_with_wrong_magic_or_impossible_header() {
    let dir = tempfile::tempdir().expect("tempdir");
    let (err, _) = read_err(dir.path(), "text.dt2", b"hello, this is not DTED at all");
    assert!(matches!(err, ImportError::BadMagic { .. }), "{err}");

    let mut bytes = small_dted();
    bytes[20..24].copy_from_slice(b"0000"); // longitude interval 0
    let (err, _) = read_err(dir.path(), "zero.dt0", &bytes);
    assert!(matches!(err, ImportError::InvalidHeader { .. }), "{err}");
    assert!(err.to_string().contains("longitude interval"), "{err}");

    let mut bytes = small_dted();
    bytes[47..51].copy_from_slice(b"9999"); // far more lines than the file holds
    let (err, _) = read_err(dir.path(), "huge.dt0", &bytes);
    assert!(matches!(err, ImportError::Truncated { .. }), "{err}");

    let mut bytes = small_dted();
    bytes[12..20].copy_from_slice(b"0357000N"); // 70 minutes
    let (err, _) = read_err(dir.path(), "minutes.dt0", &bytes);
    assert!(matches!(err, ImportError::InvalidHeader { .. }), "{err}");
}

#[test]
fn hgt_of_wrong_size_names_the_size() {
    let dir = tempfile::tempdir().expect("tempdir");
    let (err, _) = read_err(dir.path(), "N35W122.hgt", &[0u8; 1000]);
    assert!(
        matches!(err, ImportError::HgtSize { size: 1000, .. }),
        "{err:?}"
    );
    assert!(err.to_string().contains("1000 bytes"), "{err}");

    let (err, _) = read_err(dir.path(), "tile.hgt", &write_hgt(1201, |_, _| Some(1)));
    assert!(matches!(err, ImportError::HgtName { .. }), "{err:?}");
    let (err, _) = read_err(dir.path(), "N95W122.hgt", &write_hgt(1201, |_, _| Some(1)));
    assert!(matches!(err, ImportError::HgtName { .. }), "{err:?}");
}

#[test]
fn ascii_grid_with_garbage_names_the_line() {
    let dir = tempfile::tempdir().expect("tempdir");
    let text = "ncols 3\nnrows 3\nxllcorner 0\nyllcorner 0\ncellsize 1\nNODATA_value -9999\n\
                1 2 3\n4 five 6\n7 8 9\n";
    let (err, _) = read_err(dir.path(), "bad.asc", text.as_bytes());
    assert!(matches!(err, ImportError::Parse { line: 8, .. }), "{err:?}");
    assert!(err.to_string().contains("\"five\""), "{err}");

    for (text, line) in [
        (
            "ncols 3\nnrows 2\nxllcorner 0\nyllcorner 0\ncellsize 1\n1 2 3\n4 5\n",
            7,
        ),
        (
            "ncols 3\nnrows 1\nxllcorner 0\nyllcorner 0\ncellsize 1\n1 2 3 4\n",
            6,
        ),
        (
            "ncols 3\nnrows 1\nxllcorner 0\nyllcorner 0\ncellsize abc\n1 2 3\n",
            5,
        ),
        (
            "ncols -3\nnrows 1\nxllcorner 0\nyllcorner 0\ncellsize 1\n1 2 3\n",
            1,
        ),
        (
            "ncols 3\nnrows 1\nxllcorner 0\nyllcorner 0\nfoo 1\n1 2 3\n",
            5,
        ),
        ("ncols 3\nnrows 1\nxllcorner 0\ncellsize 1\n1 2 3\n", 5),
    ] {
        let (err, _) = read_err(dir.path(), "bad.asc", text.as_bytes());
        match err {
            ImportError::Parse { line: got, .. } => assert_eq!(got, line, "{text:?}: {err}"),
            other => panic!("{text:?}: {other:?}"),
        }
    }

    let zero = "ncols 3\nnrows 1\nxllcorner 0\nyllcorner 0\ncellsize 0\n1 2 3\n";
    let (err, _) = read_err(dir.path(), "zero.asc", zero.as_bytes());
    assert!(matches!(err, ImportError::InvalidHeader { .. }), "{err:?}");
    // Projected coordinates are not degrees.
    let utm = "ncols 3\nnrows 1\nxllcorner 500000\nyllcorner 4000000\ncellsize 30\n1 2 3\n";
    let (err, _) = read_err(dir.path(), "utm.asc", utm.as_bytes());
    assert!(matches!(err, ImportError::InvalidHeader { .. }), "{err:?}");
}

fn tiff_spec(geokeys: Vec<u16>) -> TiffSpec {
    TiffSpec {
        width: 4,
        height: 3,
        sample: SampleKind::I16,
        layout: Layout::Strips { rows_per_strip: 2 },
        comp: Comp::Lzw,
        predictor: false,
        geokeys,
        pixel_scale: Some([1.0, 1.0, 0.0]),
        tiepoint: Some([0.0, 0.0, 0.0, 10.0, 50.0, 0.0]),
        transformation: None,
        nodata: None,
    }
}

#[test]
fn tiff_with_unknown_projection_names_the_epsg_code() {
    let dir = tempfile::tempdir().expect("tempdir");
    let values = vec![1.0; 12];
    let bytes = write_geotiff(&tiff_spec(geokeys_projected(3857, PIXEL_IS_AREA)), &values);
    let (err, _) = read_err(dir.path(), "mercator.tif", &bytes);
    assert!(
        matches!(
            err,
            ImportError::UnsupportedProjection {
                epsg: Some(3857),
                ..
            }
        ),
        "{err:?}"
    );
    assert!(err.to_string().contains("EPSG:3857"), "{err}");

    let bytes = write_geotiff(&tiff_spec(geokeys_geographic(4230, PIXEL_IS_AREA)), &values);
    let (err, _) = read_err(dir.path(), "ed50.tif", &bytes);
    assert!(
        matches!(
            err,
            ImportError::UnsupportedProjection {
                epsg: Some(4230),
                ..
            }
        ),
        "{err:?}"
    );

    // No georeferencing at all.
    let mut spec = tiff_spec(geokeys_geographic(4326, PIXEL_IS_AREA));
    spec.pixel_scale = None;
    let (err, _) = read_err(dir.path(), "nogeo.tif", &write_geotiff(&spec, &values));
    assert!(matches!(err, ImportError::InvalidHeader { .. }), "{err:?}");

    // Zero pixel size.
    let mut spec = tiff_spec(geokeys_geographic(4326, PIXEL_IS_AREA));
    spec.pixel_scale = Some([0.0, 1.0, 0.0]);
    let (err, _) = read_err(dir.path(), "zero.tif", &write_geotiff(&spec, &values));
    assert!(matches!(err, ImportError::InvalidHeader { .. }), "{err:?}");
}

#[test]
fn truncated_and_non_tiff_files_fail_cleanly() {
    let dir = tempfile::tempdir().expect("tempdir");
    let values: Vec<f64> = (0..12).map(f64::from).collect();
    let mut spec = tiff_spec(geokeys_geographic(4326, PIXEL_IS_AREA));
    spec.comp = Comp::None;
    let bytes = write_geotiff(&spec, &values);
    for cut in [3, 8, 20, bytes.len() / 2, bytes.len() - 1] {
        let (err, _) = read_err(dir.path(), "cut.tif", &bytes[..cut]);
        assert!(
            matches!(err, ImportError::Tiff { .. } | ImportError::BadMagic { .. }),
            "cut at {cut}: {err:?}"
        );
    }
    let (err, _) = read_err(dir.path(), "text.tif", b"not a tiff");
    assert!(matches!(err, ImportError::BadMagic { .. }), "{err:?}");
}

#[test]
fn missing_and_unrecognised_files() {
    let dir = tempfile::tempdir().expect("tempdir");
    let missing = dir.path().join("nowhere.dt1");
    let err = read_source(&missing).expect_err("missing");
    assert!(matches!(err, ImportError::Io { .. }), "{err:?}");
    assert!(err.to_string().ends_with(&missing.display().to_string()));

    let (err, _) = read_err(dir.path(), "data.bin", b"\x00\x01\x02 random");
    assert!(matches!(err, ImportError::UnknownFormat { .. }), "{err:?}");
}

// ---------------------------------------------------------------------------------------------
// No panic on random or mutated bytes.

fn valid_inputs() -> Vec<(&'static str, Vec<u8>)> {
    let values: Vec<f64> = (0..12).map(|v| f64::from(v) * 3.0).collect();
    let mut tiled = tiff_spec(geokeys_geographic(4326, PIXEL_IS_AREA));
    tiled.width = 20;
    tiled.height = 18;
    tiled.layout = Layout::Tiles { size: 16 };
    tiled.comp = Comp::Deflate;
    tiled.predictor = true;
    let tiled_values: Vec<f64> = (0..360).map(f64::from).collect();
    let mut utm = tiff_spec(geokeys_projected(32633, PIXEL_IS_POINT));
    utm.pixel_scale = Some([30.0, 30.0, 0.0]);
    utm.tiepoint = Some([0.0, 0.0, 0.0, 400_000.0, 5_000_000.0, 0.0]);
    vec![
        (
            "geotiff",
            write_geotiff(&tiff_spec(geokeys_geographic(4326, PIXEL_IS_AREA)), &values),
        ),
        ("geotiff", write_geotiff(&tiled, &tiled_values)),
        ("geotiff", write_geotiff(&utm, &values)),
        ("dted", small_dted()),
        (
            "asc",
            b"ncols 3\nnrows 2\nxllcorner 1\nyllcorner 2\ncellsize 0.5\nNODATA_value -9999\n\
              1 2 3\n4 -9999 6\n"
                .to_vec(),
        ),
    ]
}

fn read_any(kind: &str, bytes: &[u8]) {
    let result = match kind {
        "geotiff" => read_geotiff_bytes(bytes, "fuzz.tif").map(|_| ()),
        "dted" => read_dted_bytes(bytes, "fuzz.dt1").map(|_| ()),
        "asc" => read_asc_str(&String::from_utf8_lossy(bytes), "fuzz.asc").map(|_| ()),
        _ => read_hgt_bytes(bytes, "N10E010.hgt").map(|_| ()),
    };
    if let Err(err) = result {
        let message = err.to_string();
        assert!(!message.contains('\n'), "{message}");
        // The tiff crate's own panics are caught, but we want to know about them.
        assert!(!message.contains("decoder failed"), "{message}");
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 400, ..ProptestConfig::default() })]

    #[test]
    fn random_bytes_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..4096)) {
        for kind in ["geotiff", "dted", "asc", "hgt"] {
            read_any(kind, &bytes);
        }
        let mut with_magic = b"II*\0".to_vec();
        with_magic.extend_from_slice(&bytes);
        read_any("geotiff", &with_magic);
        let mut with_magic = b"UHL1".to_vec();
        with_magic.extend_from_slice(&bytes);
        read_any("dted", &with_magic);
    }

    #[test]
    fn mutated_files_never_panic(
        which in 0usize..5,
        edits in proptest::collection::vec((any::<prop::sample::Index>(), any::<u8>()), 1..12),
        cut in any::<prop::sample::Index>(),
        truncate in any::<bool>(),
    ) {
        let inputs = valid_inputs();
        let (kind, mut bytes) = inputs[which % inputs.len()].clone();
        for (index, value) in edits {
            let i = index.index(bytes.len());
            bytes[i] = value;
        }
        if truncate {
            bytes.truncate(cut.index(bytes.len() + 1));
        }
        read_any(kind, &bytes);
    }

    #[test]
    fn mutated_ascii_headers_never_panic(
        ncols in "[-+]?[0-9]{0,12}(\\.[0-9]*)?|nan|inf|1e308|",
        nrows in "[-+]?[0-9]{0,12}|99999999999999999999",
        cell in "[-+]?[0-9]{0,5}(\\.[0-9]*)?(e[-+]?[0-9]{1,3})?|nan",
        x in "[-+]?[0-9]{0,4}(\\.[0-9]*)?|inf",
        body in "[-0-9. \\n]{0,200}",
    ) {
        let text = format!(
            "ncols {ncols}\nnrows {nrows}\nxllcorner {x}\nyllcenter -10\ncellsize {cell}\n{body}"
        );
        let _ = read_asc_str(&text, "header.asc");
    }
}

#[test]
fn hgt_mutations_never_panic() {
    // The full-size file is too big for many proptest cases: a few targeted ones.
    let mut bytes = write_hgt(1201, |r, c| Some((r + c) as i16));
    read_any("hgt", &bytes);
    for (i, b) in [(0usize, 0x80u8), (1000, 0xff), (bytes.len() - 1, 0x00)] {
        bytes[i] = b;
        read_any("hgt", &bytes);
    }
    for name in [
        "",
        "N",
        "N35",
        "N35W12",
        "X35W122.hgt",
        "N35Q122.hgt",
        "N3aW122.hgt",
        "é5W122.hgt",
    ] {
        let _ = read_hgt_bytes(&bytes, name);
    }
}
