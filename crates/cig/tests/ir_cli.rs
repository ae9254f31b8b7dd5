//! End-to-end runs of `cig ir`: the JSON shapes of the issue, physics a trainee's sensor must
//! show, and one-line refusals of bad values.

mod common;

use common::{cig, one_line_error};
use serde_json::Value;

fn json(args: &[&str]) -> Value {
    let mut all = vec!["ir"];
    all.extend_from_slice(args);
    common::json_output(&all)
}

fn keys(v: &Value) -> Vec<&str> {
    v.as_object()
        .expect("object")
        .keys()
        .map(String::as_str)
        .collect()
}

#[test]
fn radiance_has_the_issue_shape_and_value() {
    let v = json(&["radiance", "--band", "8-12", "--temp-k", "300"]);
    assert_eq!(keys(&v), ["band_um", "temp_k", "radiance_w_m2_sr"]);
    assert_eq!(v["band_um"], serde_json::json!([8.0, 12.0]));
    let l = v["radiance_w_m2_sr"].as_f64().expect("number");
    assert!((l - 38.5004).abs() < 5e-5, "{l}");
    let mwir = json(&["radiance", "--band", "3-5", "--temp-k", "1000"]);
    assert!(mwir["radiance_w_m2_sr"].as_f64().expect("n") > 1000.0);
}

fn surface(material: &str, time: &str, extra: &[&str]) -> (f64, f64) {
    let mut args = vec![
        "surface-temp",
        "--material",
        material,
        "--lat",
        "47.5",
        "--lon",
        "-122.3",
        "--time",
        time,
    ];
    args.extend_from_slice(extra);
    let v = json(&args);
    assert_eq!(keys(&v), ["material", "surface_temp_c", "air_temp_c"]);
    assert_eq!(v["material"], material);
    (
        v["surface_temp_c"].as_f64().expect("n"),
        v["air_temp_c"].as_f64().expect("n"),
    )
}

#[test]
fn surface_temperatures_show_the_physics() {
    // Seattle in August: 15:00 local solar time is 23:10 UTC; 04:00 is 12:10 UTC.
    let afternoon = "2026-08-10T23:10:00Z";
    let before_dawn = "2026-08-10T12:10:00Z";
    let weather = ["--air-min-c", "13", "--air-max-c", "27", "--rh", "45"];
    let (road, air) = surface("paved_road", afternoon, &weather);
    let (grass, _) = surface("grass", afternoon, &weather);
    assert!(
        road > grass + 5.0 && road > air,
        "road {road} grass {grass} air {air}"
    );
    let (road_dawn, air_dawn) = surface("paved_road", before_dawn, &weather);
    assert!(road_dawn < air_dawn, "road {road_dawn} air {air_dawn}");
    // Noon walls: south warmer than north.
    let noon = "2026-08-10T20:10:00Z";
    let wall = |facing: &str| {
        let mut w = weather.to_vec();
        w.extend_from_slice(&["--tilt-deg", "90", "--facing-deg", facing]);
        surface("superstructure", noon, &w).0
    };
    assert!(wall("180") > wall("0") + 5.0);
}

#[test]
fn bad_values_get_one_line_naming_them() {
    for (args, needle) in [
        (
            vec!["radiance", "--band", "12-8", "--temp-k", "300"],
            "12-8",
        ),
        (vec!["radiance", "--band", "8-8", "--temp-k", "300"], "8-8"),
        (vec!["radiance", "--band", "8-12", "--temp-k", "0"], "0 K"),
        (vec!["radiance", "--band", "8-12", "--temp-k", "-4"], "-4"),
        (
            vec!["radiance", "--band", "eight", "--temp-k", "300"],
            "eight",
        ),
        (
            vec![
                "surface-temp",
                "--material",
                "lava",
                "--lat",
                "10",
                "--lon",
                "10",
                "--time",
                "2026-01-01T00:00:00Z",
            ],
            "lava",
        ),
        (
            vec![
                "surface-temp",
                "--material",
                "grass",
                "--lat",
                "10",
                "--lon",
                "10",
                "--time",
                "2026-01-01T00:00:00Z",
                "--rh",
                "140",
            ],
            "140",
        ),
        (
            vec![
                "surface-temp",
                "--material",
                "grass",
                "--lat",
                "95",
                "--lon",
                "10",
                "--time",
                "2026-01-01T00:00:00Z",
            ],
            "95",
        ),
        (
            vec![
                "surface-temp",
                "--material",
                "grass",
                "--lat",
                "10",
                "--lon",
                "10",
                "--time",
                "2026-01-01T00:00:00Z",
                "--tilt-deg",
                "200",
            ],
            "200",
        ),
    ] {
        let err = one_line_error(&cig().arg("ir").args(&args).assert().failure());
        assert!(err.contains(needle), "{args:?}: {err}");
    }
}
