//! Dynamic terrain from the command line: `cig db crater`, `cig db edits`, `cig query soil`,
//! and the queries and render seeing the edits; bad input refused in one line, with nothing on
//! disk lost.

mod common;

use common::{cig, json_output, one_line_error, small_db};

#[test]
fn a_crater_made_at_the_command_line_is_seen_by_the_queries_and_survives_export_and_import() {
    let dir = tempfile::tempdir().expect("dir");
    let db = small_db(dir.path());
    let db_s = db.to_str().expect("utf-8 path");
    let (lat, lon) = ("35.995", "-121.215");
    let before = json_output(&["query", "hat", db_s, lat, lon])["height_m"]
        .as_f64()
        .expect("height");
    let crater = json_output(&[
        "db",
        "crater",
        db_s,
        "--at",
        &format!("{lat},{lon}"),
        "--charge-kg",
        "100",
    ]);
    let depth_m = crater["depth_m"].as_f64().expect("depth");
    let radius_m = crater["radius_m"].as_f64().expect("radius");
    // Cube-root scaling: 100 kg in soil, C_D 0.15-0.23, C_R 0.3-0.46.
    assert!(
        (0.6..1.2).contains(&depth_m) && (1.3..2.5).contains(&radius_m),
        "{crater}"
    );
    let after = json_output(&["query", "hat", db_s, lat, lon])["height_m"]
        .as_f64()
        .expect("height");
    assert!(
        ((before - after) - depth_m).abs() < 0.05,
        "{before} -> {after}, {depth_m} deep"
    );
    // From 0.3 m above the bowl's bottom, a level sightline out meets the bowl's wall, not the
    // ground it started under before the crater.
    let bottom = json_output(&["query", "hat", db_s, lat, lon])["height_ellipsoid_m"]
        .as_f64()
        .expect("height");
    let eye = format!("{}", bottom + 0.3);
    let los = json_output(&[
        "query",
        "los",
        db_s,
        lat,
        lon,
        &eye,
        "35.995",
        "-121.2146",
        &eye,
    ]);
    let range_m = los["hit"]["range_m"].as_f64().expect("blocked by the wall");
    assert!(range_m > 0.3 && range_m < 1.3 * radius_m, "{los}");
    // Export, clear, import.
    let file = dir.path().join("exercise.jsonl");
    cig()
        .args(["db", "edits", db_s, "--export"])
        .arg(&file)
        .assert()
        .success();
    cig()
        .args(["db", "edits", db_s, "--clear"])
        .assert()
        .success();
    let cleared = json_output(&["query", "hat", db_s, lat, lon])["height_m"]
        .as_f64()
        .expect("height");
    assert!((cleared - before).abs() < 1e-9);
    cig()
        .args(["db", "edits", db_s, "--import"])
        .arg(&file)
        .assert()
        .success();
    let back = json_output(&["query", "hat", db_s, lat, lon])["height_m"]
        .as_f64()
        .expect("height");
    assert!((back - after).abs() < 1e-9, "{back} vs {after}");
    let listed = json_output(&["db", "edits", db_s]);
    assert_eq!(
        listed["edits"].as_array().map(Vec::len),
        Some(1),
        "{listed}"
    );

    // Bad input: one line, nothing changed.
    let edits_file = db.join("edits.jsonl");
    let kept = std::fs::read(&edits_file).expect("edits");
    for args in [
        vec![
            "db",
            "crater",
            db_s,
            "--at",
            "35.995,-121.215",
            "--charge-kg",
            "-1",
        ],
        vec![
            "db",
            "crater",
            db_s,
            "--at",
            "35.995,-121.215",
            "--charge-kg",
            "NaN",
        ],
        vec![
            "db",
            "crater",
            db_s,
            "--at",
            "37.5,-121.215",
            "--charge-kg",
            "5",
        ],
        vec!["db", "crater", db_s, "--at", "35.995", "--charge-kg", "5"],
        vec![
            "db",
            "crater",
            db_s,
            "--at",
            "35.995,-121.215",
            "--radius-m",
            "2",
        ],
    ] {
        let out = cig().args(&args).assert().failure();
        let line = one_line_error(&out);
        assert!(line.len() > 10, "{line}");
    }
    let text = std::fs::read_to_string(&file).expect("export");
    std::fs::write(&file, &text[..text.len() - 7]).expect("truncate");
    let out = cig()
        .args(["db", "edits", db_s, "--import"])
        .arg(&file)
        .assert()
        .failure();
    assert!(one_line_error(&out).contains("truncated"));
    assert_eq!(std::fs::read(&edits_file).expect("edits"), kept);
}

#[test]
fn soil_answers_sinkage_resistance_and_go_no_go() {
    let dir = tempfile::tempdir().expect("dir");
    let db = small_db(dir.path());
    let db_s = db.to_str().expect("utf-8 path");
    let soil = json_output(&[
        "query",
        "soil",
        db_s,
        "35.995",
        "-121.215",
        "--vehicle-mass-kg",
        "62000",
        "--contact-area-m2",
        "5.8",
    ]);
    for key in ["material", "sinkage_m", "resistance_n", "trafficable"] {
        assert!(soil.get(key).is_some(), "{key}: {soil}");
    }
    let sinkage = soil["sinkage_m"].as_f64().expect("sinkage");
    assert!((0.0..=0.45).contains(&sinkage), "{soil}");
    // Wet soil sinks at least as deep (the same vehicle).
    let wet = json_output(&[
        "query",
        "soil",
        db_s,
        "35.995",
        "-121.215",
        "--vehicle-mass-kg",
        "62000",
        "--contact-area-m2",
        "5.8",
        "--wet",
    ]);
    assert!(
        wet["sinkage_m"].as_f64().expect("wet") >= sinkage - 1e-9 || soil["material"] == "sand"
    );
    for bad in [["-5", "5.8"], ["62000", "0"], ["nan", "1"]] {
        let out = cig()
            .args([
                "query",
                "soil",
                db_s,
                "35.995",
                "-121.215",
                "--vehicle-mass-kg",
            ])
            .arg(bad[0])
            .arg("--contact-area-m2")
            .arg(bad[1])
            .assert()
            .failure();
        one_line_error(&out);
    }
}
