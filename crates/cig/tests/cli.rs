//! End-to-end runs of the `cig` binary.

mod common;

use common::{cig, one_line_error};
use serde_json::Value;
use std::path::{Path, PathBuf};

fn json(out: &[u8]) -> Value {
    serde_json::from_slice(out).unwrap_or_else(|e| panic!("{e}: {}", String::from_utf8_lossy(out)))
}

fn synth(dir: &Path, name: &str, seed: u64, size_km: &str, spacing: &str) -> PathBuf {
    let db = dir.join(name);
    cig()
        .args(["db", "synth", "--out"])
        .arg(&db)
        .args([
            "--origin",
            "35.98,-121.23",
            "--size-km",
            size_km,
            "--spacing-m",
            spacing,
        ])
        .args(["--seed", &seed.to_string()])
        .assert()
        .success();
    db
}

fn files(root: &Path) -> Vec<(PathBuf, Vec<u8>)> {
    let mut out = Vec::new();
    let mut stack = vec![root.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).expect("dir") {
            let p = e.expect("entry").path();
            if p.is_dir() {
                stack.push(p);
            } else {
                out.push((
                    p.strip_prefix(root).expect("prefix").to_path_buf(),
                    std::fs::read(&p).expect("read"),
                ));
            }
        }
    }
    out.sort();
    out
}

#[test]
fn synth_is_deterministic_and_info_describes_it() {
    let dir = tempfile::tempdir().expect("tmp");
    let a = synth(dir.path(), "a", 7, "4", "30");
    let b = synth(dir.path(), "b", 7, "4", "30");
    let c = synth(dir.path(), "c", 8, "4", "30");
    let (fa, fb, fc) = (files(&a), files(&b), files(&c));
    assert!(fa.len() > 2);
    assert_eq!(fa, fb, "same seed, same bytes");
    assert_ne!(fa, fc, "another seed, another world");

    let out = cig()
        .args(["db", "info"])
        .arg(&a)
        .arg("--json")
        .assert()
        .success();
    let info = json(&out.get_output().stdout);
    assert_eq!(info["origin"]["lat"].as_f64(), Some(35.98));
    assert_eq!(info["origin"]["lon"].as_f64(), Some(-121.23));
    assert!((info["spacing_m"].as_f64().expect("spacing") - 30.0).abs() < 0.01);
    assert!(
        (info["extent_deg"]["lat"].as_f64().expect("extent") - 4000.0 / 110_960.0).abs() < 1e-3
    );
    assert_eq!(info["format_version"].as_u64(), Some(1));
    assert!(info["levels"].as_u64().expect("levels") >= 2);
    assert!(info["tiles"].as_u64().expect("tiles") >= 5);
    assert!(info["min_elev_m"].as_f64() < info["max_elev_m"].as_f64());
}

/// `db info --lod-errors`: per level, the level-of-detail nodes' error against the finest
/// posts, at the finest level only its cells' chord sag on the curved earth (under a
/// millimetre at 30 m posts) and growing with each coarser one; without the flag the
/// tiles are not read and the key is absent.
#[test]
fn info_reports_the_level_of_detail_error_of_every_level() {
    let dir = tempfile::tempdir().expect("tmp");
    let db = synth(dir.path(), "db", 5, "6", "30");
    // `db info --lod-errors`, in JSON or as text.
    let info_of = |db: &std::path::Path, as_json: bool| {
        let mut command = cig();
        command.args(["db", "info"]).arg(db).arg("--lod-errors");
        if as_json {
            command.arg("--json");
        }
        command.assert().success().get_output().stdout.clone()
    };
    let info = json(&info_of(&db, true));
    let levels = info["lod_errors"]["levels"].as_array().expect("levels");
    assert_eq!(
        levels.len() as u64,
        info["levels"].as_u64().expect("levels")
    );
    let value = |l: &serde_json::Value, k: &str| l[k].as_f64().expect(k);
    let finest_m = value(&levels[0], "max_m");
    assert!(
        finest_m > 0.0 && finest_m < 0.001,
        "the finest level: {finest_m} m"
    );
    for pair in levels.windows(2) {
        assert!(
            value(&pair[1], "median_m") > value(&pair[0], "median_m"),
            "{pair:?}"
        );
    }
    for l in levels {
        assert!(value(l, "nodes") >= 1.0);
        assert!(
            value(l, "median_m") <= value(l, "p90_m") && value(l, "p90_m") <= value(l, "max_m")
        );
        // 1920 px across 60 degrees: 1662.8 px per unit tangent, and the selection's 5 %.
        let within = value(l, "median_node_refines_within_m");
        assert!(
            (within - value(l, "median_m") * 1662.77 * 1.05).abs() < 1.0,
            "{l}"
        );
    }
    let plain = cig()
        .args(["db", "info"])
        .arg(&db)
        .arg("--json")
        .assert()
        .success();
    assert!(json(&plain.get_output().stdout).get("lod_errors").is_none());
    let text = String::from_utf8_lossy(&info_of(&db, false)).to_string();
    assert!(
        text.contains("lod errors") && text.contains("level 1"),
        "{text}"
    );
    // A freshly built database holds every post's hierarchy error; a tile rewritten in format 1
    // (as an older build wrote it) is counted and named as drawn with regular grids.
    assert_eq!(info["lod_errors"]["tiles_without_post_errors"], 0);
    assert!(text.contains("every tile holds"), "{text}");
    let path = db.join("tiles").join("L0").join("0_0.tile");
    let bytes = std::fs::read(&path).expect("tile file");
    let mut tile = cig_terrain::tile::Tile::decode(&bytes, None).expect("a tile");
    tile.lod_errors = None;
    std::fs::write(&path, tile.encode()).expect("rewrite");
    let info = json(&info_of(&db, true));
    assert_eq!(info["lod_errors"]["tiles_without_post_errors"], 1);
    let text = String::from_utf8_lossy(&info_of(&db, false)).to_string();
    assert!(
        text.contains("1 of ") && text.contains("regular grids"),
        "{text}"
    );
}

#[test]
fn hat_and_los_answer_in_json() {
    let dir = tempfile::tempdir().expect("tmp");
    let db = synth(dir.path(), "db", 3, "6", "30");
    let out = cig()
        .args(["query", "hat"])
        .arg(&db)
        .args(["36.0", "-121.2", "--alt", "2000", "--json"])
        .assert()
        .success();
    let hat = json(&out.get_output().stdout);
    assert_eq!(hat["lat"].as_f64(), Some(36.0));
    assert_eq!(hat["lon"].as_f64(), Some(-121.2));
    let h = hat["height_m"].as_f64().expect("height");
    let n = hat["geoid_undulation_m"].as_f64().expect("geoid");
    assert!(
        (-40.0..-25.0).contains(&n),
        "EGM96 near Hunter Liggett is about -33 m: {n}"
    );
    assert!((hat["hat_m"].as_f64().expect("hat") - (2000.0 - (h + n))).abs() < 1e-6);
    let normal: Vec<f64> = hat["normal"]
        .as_array()
        .expect("normal")
        .iter()
        .filter_map(Value::as_f64)
        .collect();
    assert_eq!(normal.len(), 3);
    assert!((normal.iter().map(|v| v * v).sum::<f64>() - 1.0).abs() < 1e-9);
    assert!(normal[2] > 0.0);
    assert!(hat["material"].is_string());

    // From 3 km up to 3 km up: visible. From underground: blocked at once.
    let out = cig()
        .args(["query", "los"])
        .arg(&db)
        .args([
            "36.0", "-121.2", "3000", "36.03", "-121.17", "3000", "--json",
        ])
        .assert()
        .success();
    let los = json(&out.get_output().stdout);
    assert_eq!(los, serde_json::json!({"visible": true, "hit": null}));
    let out = cig()
        .args(["query", "los"])
        .arg(&db)
        .args([
            "36.0", "-121.2", "-100", "36.03", "-121.17", "3000", "--json",
        ])
        .assert()
        .success();
    let los = json(&out.get_output().stdout);
    assert_eq!(los["visible"], Value::Bool(false));
    assert_eq!(los["hit"]["range_m"].as_f64(), Some(0.0));
    assert!(los["hit"]["material"].is_string());
}

/// Command-line arguments of mixed kinds (strings, paths).
macro_rules! argv {
    ($($arg:expr),* $(,)?) => {
        vec![$(std::ffi::OsString::from(&$arg)),*]
    };
}

/// Runs `cig` with `args`, expects it to fail, and returns its one error line.
fn error_line(args: Vec<std::ffi::OsString>) -> String {
    one_line_error(&cig().args(args).assert().failure())
}

/// `db synth` of a 3 km, 60 m database at `out`, followed by `extra` arguments.
fn synth_args(out: &Path, extra: &[&str]) -> Vec<std::ffi::OsString> {
    let mut args = argv!["db", "synth", "--out", out, "--origin", "35.98,-121.23"];
    args.extend(argv!["--size-km", "3", "--spacing-m", "60"]);
    args.extend(extra.iter().map(std::ffi::OsString::from));
    args
}

#[test]
fn bad_input_gives_one_line_errors_and_keeps_what_is_on_disk() {
    let dir = tempfile::tempdir().expect("tmp");
    let db = synth(dir.path(), "db", 1, "3", "60");
    // Outside the database.
    let line = error_line(argv!["query", "hat", db, "10.0", "10.0"]);
    assert!(line.contains("10.0000000, 10.0000000 is outside the database"));
    // Not a database.
    let line = error_line(argv!["db", "info", dir.path()]);
    assert!(line.contains("not a cig terrain database"));
    // A missing DEM.
    let missing = dir.path().join("nope.hgt");
    let line = error_line(argv![
        "db",
        "import",
        "--out",
        dir.path().join("x"),
        missing
    ]);
    assert!(line.contains("nope.hgt"));
    // A truncated SRTM file.
    let bad = dir.path().join("N35W122.hgt");
    std::fs::write(&bad, vec![0u8; 1000]).expect("write");
    let line = error_line(argv!["db", "import", "--out", dir.path().join("x"), bad]);
    assert!(line.contains("N35W122.hgt"));
    assert!(!dir.path().join("x").exists());
    // An existing output is not overwritten without --force.
    let before = files(&db);
    assert!(error_line(synth_args(&db, &["--seed", "2"])).contains("--force"));
    assert_eq!(files(&db), before);
    // --force replaces a database, never anything else...
    let precious = dir.path().join("precious");
    std::fs::create_dir(&precious).expect("mkdir");
    std::fs::write(precious.join("important.txt"), "keep me").expect("write");
    let line = error_line(synth_args(&precious, &["--force"]));
    assert!(line.contains("refusing to replace"));
    assert_eq!(
        std::fs::read_to_string(precious.join("important.txt")).expect("kept"),
        "keep me"
    );
    // ...and does replace a database.
    cig()
        .args(synth_args(&db, &["--seed", "9", "--force"]))
        .assert()
        .success();
    assert_ne!(files(&db), before);
    // A sightline that never crosses the database, and one from beyond the sky.
    let line = error_line(argv![
        "query", "los", db, "10", "10", "100", "10.1", "10", "100"
    ]);
    assert!(line.contains("does not cross the database"));
    let line = error_line(argv![
        "query", "los", db, "35.99", "-121.22", "1e15", "35.99", "-121.21", "100"
    ]);
    assert!(line.contains("altitude"));
    let line = error_line(argv![
        "query",
        "los",
        db,
        "35.99",
        "-121.22",
        "100",
        "35.99",
        "-121.21",
        "100",
        "--refraction",
        "2"
    ]);
    assert!(line.contains("--refraction \"2\""), "{line}");
    // Bad command-line values.
    let y = dir.path().join("y");
    let mut args = argv!["db", "synth", "--out", y, "--origin", "95,0"];
    args.extend(argv!["--size-km", "3", "--spacing-m", "60"]);
    assert!(error_line(args).contains("latitude 95"));
    let mut args = argv!["db", "synth", "--out", y, "--origin", "35,-121"];
    args.extend(argv!["--size-km", "-5", "--spacing-m", "60"]);
    assert!(error_line(args).contains("size_km = -5"));
    // A bad configuration file.
    let conf = dir.path().join("cig.toml");
    std::fs::write(&conf, "[paging]\nbudget_bytes = -3\n").expect("write");
    assert!(error_line(argv!["--config", conf, "db", "info", db]).contains("cig.toml"));
    std::fs::write(&conf, "[paging]\nhysteresis_box_m = 10\n").expect("write");
    let line = error_line(argv!["--config", conf, "db", "info", db]);
    assert!(line.contains("hysteresis_box_m"));
    // Bad overload levels name the key.
    let text = "[overload.models]\ncapacity = 100\nbegin_decrement = 50\nbegin_increment = 60\n";
    std::fs::write(&conf, text).expect("write");
    let line = error_line(argv!["--config", conf, "db", "info", db]);
    assert!(
        line.contains("overload.models.begin_increment = 60"),
        "{line}"
    );
    std::fs::write(&conf, "[overload]\nfloor = 1.5\n").expect("write");
    let line = error_line(argv!["--config", conf, "db", "info", db]);
    assert!(line.contains("overload.floor = 1.5"), "{line}");
    std::fs::write(&conf, "[overload]\nflor = 0.5\n").expect("write");
    let line = error_line(argv!["--config", conf, "db", "info", db]);
    assert!(line.contains("flor"), "{line}");
    // An unknown cue-important culture kind is named.
    std::fs::write(&conf, "[culture]\ncue_important = [\"pylon\"]\n").expect("write");
    let line = error_line(argv!["--config", conf, "db", "info", db]);
    assert!(line.contains("\"pylon\" is not a culture kind"), "{line}");
    // Bad render switches.
    for (switch, value) in [("--culture", "maybe"), ("--culture-occlusion", "sometimes")] {
        let mut args = argv!["render", "--db", db, "--eye", "35.99,-121.22,900"];
        args.extend(argv!["--out", dir.path().join("x.png"), switch, value]);
        let line = error_line(args);
        assert!(line.contains(&format!("{switch} \"{value}\"")), "{line}");
    }
    // The configuration's occlusion switch is a boolean.
    std::fs::write(&conf, "[culture]\nocclusion = \"yes\"\n").expect("write");
    let line = error_line(argv!["--config", conf, "db", "info", db]);
    assert!(line.contains("occlusion"), "{line}");
}

#[test]
fn a_corrupt_tile_is_served_from_its_parent_and_left_on_disk() {
    let dir = tempfile::tempdir().expect("tmp");
    let db = synth(dir.path(), "db", 5, "6", "30");
    let tile = db.join("tiles/L0/0_0.tile");
    let mut bytes = std::fs::read(&tile).expect("tile");
    let k = bytes.len() / 3;
    bytes[k] ^= 0x55;
    std::fs::write(&tile, &bytes).expect("write");
    let out = cig()
        .args(["query", "hat"])
        .arg(&db)
        .args(["35.985", "-121.225", "--json"])
        .assert()
        .success();
    let hat = json(&out.get_output().stdout);
    assert!(hat["level"].as_u64().expect("level") >= 1);
    let stderr = String::from_utf8_lossy(&out.get_output().stderr);
    assert_eq!(stderr.matches("checksum mismatch").count(), 1, "{stderr}");
    assert!(stderr.contains("0_0.tile"), "{stderr}");
    assert_eq!(std::fs::read(&tile).expect("tile"), bytes);
}

#[test]
fn import_of_an_esri_grid_keeps_every_post() {
    let dir = tempfile::tempdir().expect("tmp");
    let asc = dir.path().join("area.asc");
    let (rows, cols) = (40usize, 50usize);
    let cell = 1.0 / 1200.0;
    let mut text = format!(
        "ncols {cols}\nnrows {rows}\nxllcenter -121.0\nyllcenter 36.0\ncellsize {cell}\nNODATA_value -9999\n"
    );
    let h = |r: usize, c: usize| 200 + (r * 3 + c * 7) % 41;
    for r in (0..rows).rev() {
        let line: Vec<String> = (0..cols).map(|c| h(r, c).to_string()).collect();
        text.push_str(&line.join(" "));
        text.push('\n');
    }
    std::fs::write(&asc, text).expect("write");
    let db = dir.path().join("db");
    cig()
        .args(["db", "import", "--out"])
        .arg(&db)
        .arg(&asc)
        .assert()
        .success();
    for (r, c) in [(0, 0), (5, 7), (39, 49), (20, 33)] {
        let lat = 36.0 + r as f64 * cell;
        let lon = -121.0 + c as f64 * cell;
        let out = cig()
            .args(["query", "hat"])
            .arg(&db)
            .args([&lat.to_string(), &lon.to_string(), "--json"])
            .assert()
            .success();
        let hat = json(&out.get_output().stdout);
        assert_eq!(
            hat["height_m"].as_f64(),
            Some(h(r, c) as f64),
            "post {r},{c}"
        );
    }
}

#[test]
fn bench_prints_its_figures() {
    let dir = tempfile::tempdir().expect("tmp");
    let db = synth(dir.path(), "db", 2, "12", "60");
    let out = cig()
        .args(["bench", "db"])
        .arg(&db)
        .args(["--json", "--no-build", "--seconds", "0.2"])
        .assert()
        .success();
    let report = json(&out.get_output().stdout);
    for key in [
        "hat_per_s_one_core",
        "hat_extended_per_s_one_core",
        "los_10km_ground_to_ground_per_s_one_core",
        "los_10km_air_to_ground_per_s_one_core",
        "tile_loads_per_s_cold",
    ] {
        assert!(report[key].as_f64().expect(key) > 0.0, "{key}");
    }
}

#[test]
fn config_default_round_trips() {
    let out = cig().args(["config", "default"]).assert().success();
    let text = String::from_utf8_lossy(&out.get_output().stdout).to_string();
    assert!(text.contains("active_area_m = 16000.0"));
    assert!(text.contains("hysteresis_box_m = 1200.0"));
    assert!(text.contains("[overload]"), "{text}");
    assert!(text.contains("begin_decrement"), "{text}");
    let dir = tempfile::tempdir().expect("tmp");
    let conf = dir.path().join("cig.toml");
    std::fs::write(&conf, &text).expect("write");
    let db = synth(dir.path(), "db", 1, "3", "60");
    cig()
        .arg("--config")
        .arg(&conf)
        .args(["db", "info"])
        .arg(&db)
        .assert()
        .success();
}

#[test]
fn a_closed_pipe_ends_the_command_quietly() {
    // The reader goes away before cig writes (exec takes far longer than the drop).
    let mut child = std::process::Command::new(assert_cmd::cargo::cargo_bin("cig"))
        .args(["config", "default"])
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("spawn");
    drop(child.stdout.take());
    let out = child.wait_with_output().expect("wait");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!stderr.contains("panicked"), "{stderr}");
}

/// An RGB GeoTIFF (EPSG:4326, PixelIsArea) of `w` x `h` pixels of `pixel_deg`, its north-west
/// corner at (`north`, `west`), all `rgb`.
fn write_orthoimage(path: &Path, w: u32, h: u32, north: f64, west: f64, pixel_deg: f64) {
    use tiff::encoder::{colortype, TiffEncoder};
    use tiff::tags::Tag;
    let file = std::fs::File::create(path).expect("create");
    let mut encoder = TiffEncoder::new(std::io::BufWriter::new(file)).expect("encoder");
    let mut image = encoder.new_image::<colortype::RGB8>(w, h).expect("image");
    let keys: [u16; 20] = [
        1, 1, 0, 4, 1024, 0, 1, 2, 1025, 0, 1, 1, 2048, 0, 1, 4326, 2054, 0, 1, 9102,
    ];
    let dir = image.encoder();
    dir.write_tag(Tag::GeoKeyDirectoryTag, &keys[..])
        .expect("keys");
    dir.write_tag(Tag::ModelPixelScaleTag, &[pixel_deg, pixel_deg, 0.0][..])
        .expect("scale");
    dir.write_tag(
        Tag::ModelTiepointTag,
        &[0.0, 0.0, 0.0, west, north, 0.0][..],
    )
    .expect("tiepoint");
    let data: Vec<u8> = (0..w * h)
        .flat_map(|i| [40, 120 + (i % 7) as u8, 60])
        .collect();
    image.write_data(&data).expect("data");
}

#[test]
fn imagery_is_draped_reported_and_refused_without_damage() {
    let dir = tempfile::tempdir().expect("tmp");
    let db = synth(dir.path(), "db", 3, "2", "60");
    let info = json(
        &cig()
            .args(["db", "info"])
            .arg(&db)
            .arg("--json")
            .assert()
            .success()
            .get_output()
            .stdout,
    );
    let (south, west) = (
        info["extent_deg"]["south"].as_f64().expect("south"),
        info["extent_deg"]["west"].as_f64().expect("west"),
    );
    // 7.5 m pixels over the south-west kilometre.
    let pixel = 7.5 / 111_000.0;
    let image = dir.path().join("ortho.tif");
    write_orthoimage(&image, 130, 120, south + 120.0 * pixel, west, pixel);
    cig()
        .args(["db", "imagery"])
        .arg(&db)
        .arg(&image)
        .assert()
        .success();
    let info = json(
        &cig()
            .args(["db", "info"])
            .arg(&db)
            .arg("--json")
            .assert()
            .success()
            .get_output()
            .stdout,
    );
    let imagery = &info["imagery"];
    assert!(imagery["tiles"].as_u64().expect("tiles") >= 1, "{info}");
    assert!(imagery["texel_m_north_east"][0].as_f64().expect("texel") <= 7.5 * 1.01);
    assert!(imagery["sources"][0]
        .as_str()
        .expect("source")
        .contains("ortho.tif"));
    let text = cig().args(["db", "info"]).arg(&db).assert().success();
    let text = String::from_utf8_lossy(&text.get_output().stdout).to_string();
    assert!(text.contains("imagery       "), "{text}");

    // A bad image: one line naming it, the database unchanged.
    let before = files(&db);
    let bad = dir.path().join("bad.tif");
    std::fs::write(&bad, b"II*\0nonsense").expect("write");
    let line = error_line(argv!["db", "imagery", db, image, bad]);
    assert!(line.contains("bad.tif"), "{line}");
    assert_eq!(files(&db), before, "database changed");
    let line = error_line(argv!["db", "imagery", dir.path().join("none"), image]);
    assert!(line.contains("none"), "{line}");

    // Import with imagery: all of it, or nothing.
    let asc = dir.path().join("area.asc");
    let cell = 1.0 / 1200.0;
    let mut grid = format!(
        "ncols 20\nnrows 20\nxllcenter {west}\nyllcenter {south}\ncellsize {cell}\nNODATA_value -9999\n"
    );
    for _ in 0..20 {
        grid.push_str(&vec!["100"; 20].join(" "));
        grid.push('\n');
    }
    std::fs::write(&asc, grid).expect("write");
    let out = dir.path().join("imported");
    let line = error_line(argv!["db", "import", "--out", out, asc, "--imagery", bad]);
    assert!(line.contains("bad.tif"), "{line}");
    assert!(!out.exists());
    cig()
        .args(["db", "import", "--out"])
        .arg(&out)
        .arg(&asc)
        .arg("--imagery")
        .arg(&image)
        .assert()
        .success();
    let info = json(
        &cig()
            .args(["db", "info"])
            .arg(&out)
            .arg("--json")
            .assert()
            .success()
            .get_output()
            .stdout,
    );
    assert!(
        info["imagery"]["tiles"].as_u64().expect("tiles") >= 1,
        "{info}"
    );
}

#[test]
fn bench_imagery_reports_time_and_memory() {
    let dir = tempfile::tempdir().expect("tmp");
    let out = cig()
        .args(["bench", "imagery", "--json", "--size", "300", "--scratch"])
        .arg(dir.path())
        .assert()
        .success();
    let report = json(&out.get_output().stdout);
    assert!(report["import_s"].as_f64().expect("import_s") > 0.0);
    assert!(report["import_mb_per_s"].as_f64().expect("rate") > 0.0);
    assert!(report["imagery"]["tiles"].as_u64().expect("tiles") >= 4);
    assert!(report["peak_rss_mb"].as_f64().is_some() || !cfg!(target_os = "linux"));
}

#[test]
fn synth_sea_side_makes_a_coast_and_a_bad_side_is_one_line() {
    let dir = tempfile::tempdir().expect("tmp");
    let db = dir.path().join("coast");
    cig()
        .args(synth_args(&db, &["--sea-side", "west"]))
        .assert()
        .success();
    let info = json(
        &cig()
            .args(["db", "info"])
            .arg(&db)
            .arg("--json")
            .assert()
            .success()
            .get_output()
            .stdout,
    );
    let materials = &info["materials"];
    let total: u64 = materials
        .as_object()
        .expect("materials")
        .values()
        .filter_map(Value::as_u64)
        .sum();
    let water = materials["water"].as_u64().expect("water") as f64 / total as f64;
    assert!((0.2..0.45).contains(&water), "water {water}: {info}");
    // The sea is stored as its surface, at mean sea level: nothing lies below 0 m.
    assert_eq!(info["min_elev_m"].as_f64(), Some(0.0), "{info}");
    assert!(
        info["sources"].to_string().contains("sea_side=west"),
        "{info}"
    );
    let hat = |lon: &str| {
        json(
            &cig()
                .args(["query", "hat"])
                .arg(&db)
                .args(["35.993", lon, "--json"])
                .assert()
                .success()
                .get_output()
                .stdout,
        )
    };
    let west = hat("-121.2295");
    assert_eq!(west["material"].as_str(), Some("water"), "{west}");
    assert_eq!(west["height_m"].as_f64(), Some(0.0), "{west}");
    let east = hat("-121.204");
    assert_ne!(east["material"].as_str(), Some("water"), "{east}");
    assert!(east["height_m"].as_f64().expect("height") > 0.0, "{east}");

    // A side that is none: one line naming the flag and the sides, and nothing written.
    let bad = dir.path().join("bad");
    let line = error_line(synth_args(&bad, &["--sea-side", "up"]));
    assert!(line.contains("--sea-side"), "{line}");
    assert!(line.contains("\"up\""), "{line}");
    assert!(line.contains("west, east, north or south"), "{line}");
    assert!(!bad.exists());
}
