//! End to end: `cig db import --features FILE` stands the file's culture (trees, buildings,
//! walls, poles; beside its roads) on an imported database and `cig db info` counts it; a bad
//! culture feature is refused with one line naming the feature and the file, nothing written.

mod common;

use common::*;
use std::path::{Path, PathBuf};

/// One post, degrees (3 arc seconds).
const POST_DEG: f64 = 1.0 / 1200.0;

/// A DEM of 40 x 50 posts 3" apart from 36 N 121 W (about 3.6 km x 3.7 km), gently sloping.
fn dem(dir: &Path) -> PathBuf {
    let asc = dir.join("area.asc");
    let (rows, cols) = (40usize, 50usize);
    let mut text = format!(
        "ncols {cols}\nnrows {rows}\nxllcenter -121.0\nyllcenter 36.0\ncellsize {POST_DEG}\n\
         NODATA_value -9999\n"
    );
    for r in 0..rows {
        let line: Vec<String> = (0..cols).map(|c| (300 + 2 * c + r).to_string()).collect();
        text.push_str(&line.join(" "));
        text.push('\n');
    }
    std::fs::write(&asc, text).expect("write dem");
    asc
}

/// `[lon, lat]` of a point `east_m`, `north_m` from 36.005 N, 120.995 W (inside the DEM).
fn at(east_m: f64, north_m: f64) -> String {
    let (lat0, lon0) = (36.005, -120.995);
    let (m_north, m_east) = cig_geo::metres_per_degree(lat0);
    format!("[{}, {}]", lon0 + east_m / m_east, lat0 + north_m / m_north)
}

fn ring(points_m: &[(f64, f64)]) -> String {
    let mut pts: Vec<String> = points_m.iter().map(|&(e, n)| at(e, n)).collect();
    pts.push(pts[0].clone());
    format!("[{}]", pts.join(", "))
}

fn feature(props: &str, geometry_type: &str, coordinates: &str) -> String {
    format!(
        r#"{{"type": "Feature", "properties": {props}, "geometry": {{"type": "{geometry_type}", "coordinates": {coordinates}}}}}"#
    )
}

fn collection(features: &[String]) -> String {
    format!(
        "{{\"type\": \"FeatureCollection\", \"features\": [\n{}\n]}}",
        features.join(",\n")
    )
}

/// A road, a 500 m x 400 m conifer stand at 100 a hectare (about 2000 trees), two houses as
/// points, a hall as a footprint, a 130 m wall (7 segments of at most 20 m) and a 400 m power
/// line (9 poles).
fn culture_file() -> String {
    collection(&[
        feature(
            r#"{"type": "paved_road", "width_m": 7}"#,
            "LineString",
            &format!("[{}, {}]", at(0.0, -100.0), at(2000.0, -100.0)),
        ),
        feature(
            r#"{"type": "conifer_tree", "density_per_ha": 100}"#,
            "Polygon",
            &format!(
                "[{}]",
                ring(&[(0.0, 0.0), (500.0, 0.0), (500.0, 400.0), (0.0, 400.0)])
            ),
        ),
        feature(
            r#"{"type": "house", "height_m": 8, "heading_deg": 20}"#,
            "MultiPoint",
            &format!("[{}, {}]", at(800.0, 50.0), at(830.0, 50.0)),
        ),
        feature(
            r#"{"type": "large_building", "height_m": 12}"#,
            "Polygon",
            &format!(
                "[{}]",
                ring(&[(900.0, 0.0), (940.0, 10.0), (935.0, 30.0), (895.0, 20.0)])
            ),
        ),
        feature(
            r#"{"type": "wall", "height_m": 2}"#,
            "LineString",
            &format!("[{}, {}]", at(600.0, 500.0), at(730.0, 500.0)),
        ),
        feature(
            r#"{"type": "power_pole"}"#,
            "LineString",
            &format!("[{}, {}]", at(1000.0, 0.0), at(1000.0, 400.0)),
        ),
    ])
}

fn import(dir: &Path, features: &str) -> (assert_cmd::assert::Assert, PathBuf) {
    let dem = dem(dir);
    let file = dir.join("culture.geojson");
    std::fs::write(&file, features).expect("write features");
    let db = dir.join("db");
    let out = cig()
        .args(["db", "import", "--out"])
        .arg(&db)
        .arg(&dem)
        .arg("--features")
        .arg(&file)
        .assert();
    (out, db)
}

fn info_json(db: &Path) -> serde_json::Value {
    let out = cig()
        .args(["db", "info", "--json"])
        .arg(db)
        .assert()
        .success();
    serde_json::from_slice(&out.get_output().stdout).expect("json")
}

#[test]
fn imported_culture_is_counted_by_db_info() {
    let dir = tempfile::tempdir().expect("tmp");
    let (out, db) = import(dir.path(), &culture_file());
    out.success();
    let info = info_json(&db);
    let culture = &info["culture"];
    let count = |key: &str| {
        culture[key]
            .as_u64()
            .unwrap_or_else(|| panic!("{key}: {info}"))
    };
    let trees = count("trees");
    assert!(
        (1600..=2400).contains(&trees),
        "about 2000 trees: {culture}"
    );
    assert_eq!(count("buildings"), 3, "{culture}");
    let kind = |name: &str| culture["by_kind"][name].as_u64().expect("a count");
    assert_eq!(kind("conifer_tree"), trees);
    assert_eq!(kind("broadleaf_tree"), 0, "every kind is named: {culture}");
    assert_eq!(kind("house"), 2);
    assert_eq!(kind("large_building"), 1);
    assert_eq!(kind("wall"), 7);
    assert_eq!(kind("power_pole"), 9);
    assert_eq!(count("total"), trees + 3 + 7 + 9);
    assert!(count("tiles") >= 1, "{culture}");
    assert!(
        info["imagery"]["tiles"]
            .as_u64()
            .expect("the road's imagery")
            >= 1,
        "{info}"
    );
    let tiles = std::fs::read_dir(db.join("culture"))
        .expect("culture directory")
        .count() as u64;
    assert_eq!(tiles, count("tiles"));
    let text = cig().args(["db", "info"]).arg(&db).assert().success();
    let text = String::from_utf8_lossy(&text.get_output().stdout).to_string();
    let line = text
        .lines()
        .find(|l| l.starts_with("culture"))
        .unwrap_or_else(|| panic!("a culture line: {text}"));
    assert!(
        line.contains(&format!("{trees} trees")) && line.contains("3 buildings"),
        "{line}"
    );
}

#[test]
fn a_database_without_culture_reports_zeros() {
    let dir = tempfile::tempdir().expect("tmp");
    let dem = dem(dir.path());
    let db = dir.path().join("db");
    cig()
        .args(["db", "import", "--out"])
        .arg(&db)
        .arg(&dem)
        .assert()
        .success();
    let culture = info_json(&db)["culture"].clone();
    assert_eq!(culture["trees"], 0, "{culture}");
    assert_eq!(culture["buildings"], 0, "{culture}");
    assert_eq!(culture["tiles"], 0, "{culture}");
    assert_eq!(culture["by_kind"]["house"], 0, "{culture}");
    let text = cig().args(["db", "info"]).arg(&db).assert().success();
    let text = String::from_utf8_lossy(&text.get_output().stdout).to_string();
    assert!(text.contains("culture       none"), "{text}");
}

#[test]
fn bad_culture_is_refused_with_one_line_and_nothing_written() {
    let point = at(100.0, 100.0);
    let tree = feature(r#"{"type": "bush"}"#, "Point", &point);
    let with = |bad: String| collection(&[tree.clone(), bad]);
    let cases = [
        (
            with(r#"{"type": "Feature", "id": "mill", "properties": {"type": "windmill", "height_m": 12}, "geometry": {"type": "Point", "coordinates": [-120.99, 36.01]}}"#.to_string()),
            vec!["unknown type \"windmill\"", "feature 1, id \"mill\""],
        ),
        (
            with(feature(r#"{"type": "house"}"#, "Point", &point)),
            vec!["house needs its height_m", "(feature 1)"],
        ),
        (
            with(feature(r#"{"type": "conifer_tree"}"#, "Point", "[-120.5, 36.01]")),
            vec![
                "conifer_tree at 36.010000, -120.500000 lies outside the database",
                "(feature 1)",
            ],
        ),
        (
            with(feature(r#"{"type": "shed", "height_m": 4, "width_m": 0}"#, "Point", &point)),
            vec!["width_m 0 is not a positive size", "(feature 1)"],
        ),
        (
            with(feature(r#"{"type": "fence", "height_m": -1.5}"#, "LineString", &format!("[{point}, {}]", at(150.0, 100.0)))),
            vec!["height_m -1.5 is not a positive size", "(feature 1)"],
        ),
        (
            // A comma missing on line 3.
            format!("{{\"type\": \"FeatureCollection\", \"features\": [\n{tree},\n{tree} {tree}]}}"),
            vec!["not GeoJSON", "line 3 column"],
        ),
    ];
    for (k, (text, wanted)) in cases.into_iter().enumerate() {
        let dir = tempfile::tempdir().expect("tmp");
        let (out, db) = import(dir.path(), &text);
        let line = one_line_error(&out.failure());
        for want in wanted {
            assert!(line.contains(want), "case {k}: {line} (wanted {want})");
        }
        assert!(
            line.ends_with(&format!(
                "({})",
                dir.path().join("culture.geojson").display()
            )),
            "case {k}: the file last: {line}"
        );
        assert!(!db.exists(), "case {k}: nothing is written");
        let left: Vec<_> = std::fs::read_dir(dir.path())
            .expect("dir")
            .map(|e| e.expect("entry").file_name())
            .collect();
        assert_eq!(
            left.len(),
            2,
            "case {k}: only the inputs are left: {left:?}"
        );
    }
}

/// Every entry of `dir`, sorted.
fn entries(dir: &Path) -> Vec<std::ffi::OsString> {
    let mut names: Vec<_> = std::fs::read_dir(dir)
        .expect("dir")
        .map(|e| e.expect("entry").file_name())
        .collect();
    names.sort();
    names
}

#[test]
fn db_culture_replaces_the_culture_all_or_nothing() {
    let dir = tempfile::tempdir().expect("tmp");
    let (out, db) = import(dir.path(), &culture_file());
    out.success();
    let before = info_json(&db)["culture"].clone();
    let replace = |name: &str, text: &str| {
        let file = dir.path().join(name);
        std::fs::write(&file, text).expect("write");
        cig().args(["db", "culture"]).arg(&db).arg(&file).assert()
    };
    // A pole outside the database: refused, the database as it was, no staging left.
    let listing = entries(dir.path());
    let out = replace(
        "outside.geojson",
        &collection(&[
            feature(r#"{"type": "bush"}"#, "Point", &at(10.0, 10.0)),
            feature(r#"{"type": "power_pole"}"#, "Point", "[-121.5, 36.01]"),
        ]),
    )
    .failure();
    let line = one_line_error(&out);
    assert!(
        line.contains("power_pole at 36.010000, -121.500000 lies outside the database")
            && line.contains("(feature 1)")
            && line.ends_with("outside.geojson)"),
        "{line}"
    );
    assert_eq!(info_json(&db)["culture"], before);
    let mut expected = listing.clone();
    expected.push("outside.geojson".into());
    expected.sort();
    assert_eq!(entries(dir.path()), expected, "no staging directory left");
    // Three bushes and a shed instead.
    replace(
        "new.geojson",
        &collection(&[
            feature(
                r#"{"type": "bush"}"#,
                "MultiPoint",
                &format!("[{}, {}, {}]", at(5.0, 5.0), at(9.0, 5.0), at(13.0, 5.0)),
            ),
            feature(
                r#"{"type": "shed", "height_m": 4}"#,
                "Point",
                &at(50.0, 50.0),
            ),
        ]),
    )
    .success();
    let culture = info_json(&db)["culture"].clone();
    assert_eq!(culture["trees"], 0, "{culture}");
    assert_eq!(culture["buildings"], 1, "{culture}");
    assert_eq!(culture["by_kind"]["bush"], 3, "{culture}");
    assert_eq!(culture["total"], 4, "{culture}");
    // The imagery painted at import is kept.
    assert!(
        info_json(&db)["imagery"]["tiles"]
            .as_u64()
            .expect("imagery")
            >= 1
    );
    // A file without culture removes it.
    replace(
        "none.geojson",
        r#"{"type": "FeatureCollection", "features": []}"#,
    )
    .success();
    assert_eq!(info_json(&db)["culture"]["total"], 0);
    assert!(!db.join("culture").exists());
}

/// `(lat, lon)` of a point `east_m`, `north_m` from 36.005 N, 120.995 W (as [`at`]).
fn lat_lon(east_m: f64, north_m: f64) -> (f64, f64) {
    let (lat0, lon0) = (36.005, -120.995);
    let (m_north, m_east) = cig_geo::metres_per_degree(lat0);
    (lat0 + north_m / m_north, lon0 + east_m / m_east)
}

/// `cig query los --json` from `from` to `to` (east, north metres), each `above_m` over the
/// terrain there.
fn los_json(db: &Path, from: (f64, f64), to: (f64, f64), above_m: f64) -> serde_json::Value {
    let mut args = Vec::new();
    for (e, n) in [from, to] {
        let (lat, lon) = lat_lon(e, n);
        let out = cig()
            .args(["query", "hat", "--json"])
            .arg(db)
            .args([lat.to_string(), lon.to_string()])
            .assert()
            .success();
        let hat: serde_json::Value =
            serde_json::from_slice(&out.get_output().stdout).expect("json");
        let ground = hat["height_ellipsoid_m"].as_f64().expect("height");
        args.extend([
            lat.to_string(),
            lon.to_string(),
            (ground + above_m).to_string(),
        ]);
    }
    let out = cig()
        .args(["query", "los", "--json"])
        .arg(db)
        .args(&args)
        .assert()
        .success();
    serde_json::from_slice(&out.get_output().stdout).expect("json")
}

#[test]
fn a_line_of_sight_stopped_by_a_house_names_it() {
    // A house 8 m high (8 m wide east-west, 11 m long north-south as typical) 500 m east of
    // the corner, and a line of sight 2 m above the ground from 50 m west of it to 50 m east.
    let dir = tempfile::tempdir().expect("tmp");
    let house = feature(
        r#"{"type": "house", "height_m": 8}"#,
        "Point",
        &at(500.0, 200.0),
    );
    let (out, db) = import(dir.path(), &collection(&[house]));
    out.success();
    let los = los_json(&db, (450.0, 200.0), (550.0, 200.0), 2.0);
    assert_eq!(los["visible"], false, "{los}");
    let hit = &los["hit"];
    let culture = &hit["culture"];
    assert_eq!(culture["kind"], "house", "{los}");
    assert_eq!(culture["height_m"].as_f64(), Some(8.0), "{los}");
    // Its west wall, 4 m west of its centre; the wall faces west.
    let range = hit["range_m"].as_f64().expect("range");
    assert!((range - 46.0).abs() < 0.1, "{los}");
    let normal: Vec<f64> = culture["normal"]
        .as_array()
        .expect("normal")
        .iter()
        .filter_map(serde_json::Value::as_f64)
        .collect();
    assert!((normal[0] + 1.0).abs() < 1e-3, "{los}");
    // The hit's other keys stay: the terrain's material under the house among them.
    for key in ["lat", "lon", "alt_m", "material", "level"] {
        assert!(!hit[key].is_null(), "{key}: {los}");
    }
    // Beside the house: visible, no culture key anywhere.
    let clear = los_json(&db, (450.0, 230.0), (550.0, 230.0), 2.0);
    assert_eq!(clear, serde_json::json!({"visible": true, "hit": null}));
    // A database whose manifest predates the recorded culture bounds answers the same.
    let manifest_path = db.join("manifest.json");
    let mut manifest: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&manifest_path).expect("manifest"))
            .expect("json");
    let culture_section = manifest["culture"].as_object_mut().expect("culture");
    assert!(
        culture_section["max_footprint_radius_m"]
            .as_f64()
            .expect("recorded")
            > 6.0,
        "{culture_section:?}"
    );
    culture_section.remove("max_footprint_radius_m");
    culture_section.remove("max_height_m");
    std::fs::write(&manifest_path, manifest.to_string()).expect("write");
    let old = los_json(&db, (450.0, 200.0), (550.0, 200.0), 2.0);
    assert_eq!(old, los);
}

#[test]
fn culture_rules_scatter_trees_by_material_and_bad_rules_are_named() {
    let dir = tempfile::tempdir().expect("tmp");
    let dem = dem(dir.path());
    let db = dir.path().join("db");
    cig()
        .args(["db", "import", "--culture-rules", "default", "--out"])
        .arg(&db)
        .arg(&dem)
        .assert()
        .success();
    let culture = info_json(&db)["culture"].clone();
    assert!(culture["total"].as_u64().expect("total") > 100, "{culture}");
    assert_eq!(culture["buildings"], 0, "{culture}");
    // Rules of 10 trees a hectare on every material stand about 13 000 trees on the
    // DEM's 1300 ha (stands and clearings either side of the mean).
    let dense = dir.path().join("dense.toml");
    let mut text = String::new();
    for material in ["forest", "grass", "sand", "dry_clay"] {
        text.push_str(&format!("[{material}]\ntrees_per_ha = 10\n"));
    }
    std::fs::write(&dense, text).expect("write");
    let dense_db = dir.path().join("dense");
    cig()
        .args(["db", "import", "--culture-rules"])
        .arg(&dense)
        .arg("--out")
        .arg(&dense_db)
        .arg(&dem)
        .assert()
        .success();
    let culture = info_json(&dense_db)["culture"].clone();
    let trees = culture["trees"].as_u64().expect("trees");
    assert!((6_000..20_000).contains(&trees), "{culture}");
    // A rule out of range names the key and the file; nothing is written.
    let rules = dir.path().join("rules.toml");
    std::fs::write(&rules, "[forest]\ntrees_per_ha = -4\n").expect("write");
    let out = dir.path().join("bad");
    let assert = cig()
        .args(["db", "import", "--culture-rules"])
        .arg(&rules)
        .arg("--out")
        .arg(&out)
        .arg(&dem)
        .assert()
        .failure();
    let line = one_line_error(&assert);
    assert!(
        line.contains("forest.trees_per_ha") && line.contains("rules.toml"),
        "{line}"
    );
    assert!(!out.exists());
}
