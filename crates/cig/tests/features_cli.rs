//! End to end: `cig db import --features FILE` lays roads and lakes on an imported database (the
//! ground levelled across the road, the lake flat at its level, both painted into the imagery),
//! and refuses a broken feature file with one line and nothing written.

mod common;

use common::*;

/// A DEM of 40 x 50 posts 3" apart from 36 N 121 W, rising 7 m a post eastward.
fn sloping_dem(dir: &std::path::Path) -> std::path::PathBuf {
    let asc = dir.join("slope.asc");
    let (rows, cols) = (40usize, 50usize);
    let mut text = format!(
        "ncols {cols}\nnrows {rows}\nxllcenter -121.0\nyllcenter 36.0\ncellsize {}\nNODATA_value -9999\n",
        1.0 / 1200.0
    );
    for _ in 0..rows {
        let line: Vec<String> = (0..cols).map(|c| (200 + 7 * c).to_string()).collect();
        text.push_str(&line.join(" "));
        text.push('\n');
    }
    std::fs::write(&asc, text).expect("write dem");
    asc
}

const ROAD_LON: f64 = -121.0 + 25.3 / 1200.0;

fn features_json(road_width: &str) -> String {
    let (s, n) = (36.0 + 3.0 / 1200.0, 36.0 + 36.0 / 1200.0);
    let (lw, le, ls, ln) = (
        -121.0 + 5.0 / 1200.0,
        -121.0 + 12.0 / 1200.0,
        36.0 + 10.0 / 1200.0,
        36.0 + 16.0 / 1200.0,
    );
    format!(
        r#"{{"type": "FeatureCollection", "features": [
  {{"type": "Feature", "properties": {{"type": "paved_road"{road_width}}},
    "geometry": {{"type": "LineString", "coordinates": [[{ROAD_LON}, {s}], [{ROAD_LON}, {n}]]}}}},
  {{"type": "Feature", "properties": {{"type": "lake", "level_m": 180}},
    "geometry": {{"type": "Polygon", "coordinates": [[[{lw}, {ls}], [{le}, {ls}], [{le}, {ln}], [{lw}, {ln}], [{lw}, {ls}]]]}}}}
]}}"#
    )
}

/// Height above sea level `cig query hat` reports at a point.
fn msl_height(db: &std::path::Path, lat: f64, lon: f64) -> f64 {
    let out = cig()
        .args(["query", "hat"])
        .arg(db)
        .args([lat.to_string(), lon.to_string()])
        .assert()
        .success();
    let text = String::from_utf8_lossy(&out.get_output().stdout).to_string();
    let at = text.find(" m above sea level").expect("a height");
    let head = &text[..at];
    head[head.rfind(' ').expect("space") + 1..]
        .parse()
        .expect("a number")
}

#[test]
fn imported_features_level_the_ground_and_are_painted() {
    let dir = tempfile::tempdir().expect("tmp");
    let dem = sloping_dem(dir.path());
    let features = dir.path().join("features.geojson");
    std::fs::write(&features, features_json(r#", "width_m": 7"#)).expect("write features");
    let db = dir.path().join("db");
    cig()
        .args(["db", "import", "--out"])
        .arg(&db)
        .arg(&dem)
        .arg("--features")
        .arg(&features)
        .assert()
        .success();
    let info = cig()
        .args(["db", "info", "--json"])
        .arg(&db)
        .assert()
        .success();
    let info: serde_json::Value = serde_json::from_slice(&info.get_output().stdout).expect("json");
    let imagery = &info["imagery"];
    assert!(imagery["tiles"].as_u64().expect("tiles") >= 1, "{info}");
    assert!(
        imagery["sources"][0]
            .as_str()
            .expect("source")
            .contains("features"),
        "{info}"
    );
    // Across the road (3 m each side of its centre line) the ground is level, where the
    // slope rises 7 m a post (about 0.56 m over those 6 m) beside it.
    let m_east = cig_geo::metres_per_degree(36.0).1;
    let lat = 36.0 + 20.0 / 1200.0;
    let west = msl_height(&db, lat, ROAD_LON - 3.0 / m_east);
    let east = msl_height(&db, lat, ROAD_LON + 3.0 / m_east);
    assert!(
        (east - west).abs() < 0.05,
        "the road's cross slope: {west:.2} m and {east:.2} m"
    );
    let far_west = msl_height(&db, lat, -121.0 + 15.0 / 1200.0);
    let far_east = msl_height(&db, lat, -121.0 + 16.0 / 1200.0);
    assert!(
        (far_east - far_west - 7.0).abs() < 0.01,
        "away from the road the slope stays: {far_west:.2}, {far_east:.2}"
    );
    // The lake is flat at its level.
    for (r, c) in [(12.0, 7.0), (14.0, 10.0)] {
        let h = msl_height(&db, 36.0 + r / 1200.0, -121.0 + c / 1200.0);
        assert!((h - 180.0).abs() < 0.01, "lake surface {h:.2} m");
    }
}

#[test]
fn a_feature_without_a_width_is_refused_and_nothing_is_written() {
    let dir = tempfile::tempdir().expect("tmp");
    let dem = sloping_dem(dir.path());
    let features = dir.path().join("broken.geojson");
    std::fs::write(&features, features_json("")).expect("write features");
    let db = dir.path().join("db");
    let out = cig()
        .args(["db", "import", "--out"])
        .arg(&db)
        .arg(&dem)
        .arg("--features")
        .arg(&features)
        .assert()
        .failure();
    let line = one_line_error(&out);
    assert!(line.contains("width"), "{line}");
    assert!(line.contains("broken.geojson"), "{line}");
    assert!(!db.exists(), "nothing is written");
}
