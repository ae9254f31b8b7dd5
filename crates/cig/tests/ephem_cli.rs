//! End-to-end runs of `cig ephem`.

mod common;

use common::cig;
use serde_json::Value;

fn ephem_json(args: &[&str]) -> Value {
    let mut all = vec!["ephem"];
    all.extend_from_slice(args);
    common::json_output(&all)
}

fn keys(v: &Value) -> Vec<String> {
    v.as_object().expect("object").keys().cloned().collect()
}

fn is_iso_utc(s: &str) -> bool {
    let b = s.as_bytes();
    b.len() == 20
        && s.ends_with('Z')
        && b[4] == b'-'
        && b[7] == b'-'
        && b[10] == b'T'
        && b[13] == b':'
        && b[16] == b':'
        && s.chars().filter(char::is_ascii_digit).count() == 14
}

#[test]
fn json_has_exactly_the_issue_shape() {
    let v = ephem_json(&[
        "--lat",
        "48.8566",
        "--lon",
        "2.3522",
        "--time",
        "2024-06-21T12:00:00Z",
    ]);
    assert_eq!(
        keys(&v),
        ["sun", "moon", "illuminance_lux", "nvg_irradiance", "events"]
    );
    assert_eq!(
        keys(&v["sun"]),
        ["azimuth_deg", "altitude_deg", "apparent_altitude_deg"]
    );
    assert_eq!(
        keys(&v["moon"]),
        [
            "azimuth_deg",
            "altitude_deg",
            "apparent_altitude_deg",
            "illuminated_fraction",
            "phase_angle_deg"
        ]
    );
    assert_eq!(keys(&v["illuminance_lux"]), ["sun", "moon", "sky", "total"]);
    assert_eq!(
        keys(&v["events"]),
        [
            "sunrise",
            "sunset",
            "civil_dawn",
            "civil_dusk",
            "nautical_dawn",
            "nautical_dusk",
            "astronomical_dawn",
            "astronomical_dusk",
            "moonrise",
            "moonset"
        ]
    );
    for (_, e) in v["events"].as_object().unwrap() {
        assert!(e.is_null() || e.as_str().is_some_and(is_iso_utc), "{e}");
    }
    // Paris at the June solstice: the sun due south-ish and high; USNO sunrise 03:47 UTC,
    // sunset 19:58 UTC; astronomical twilight all night.
    let sun_alt = v["sun"]["altitude_deg"].as_f64().unwrap();
    assert!((sun_alt - 64.5).abs() < 0.2, "{sun_alt}");
    let az = v["sun"]["azimuth_deg"].as_f64().unwrap();
    assert!((170.0..200.0).contains(&az), "{az}");
    assert!(v["sun"]["apparent_altitude_deg"].as_f64().unwrap() > sun_alt);
    assert!(v["events"]["sunrise"]
        .as_str()
        .unwrap()
        .starts_with("2024-06-21T03:47"));
    assert!(v["events"]["sunset"]
        .as_str()
        .unwrap()
        .starts_with("2024-06-21T19:5"));
    assert!(v["events"]["astronomical_dawn"].is_null());
    let total = v["illuminance_lux"]["total"].as_f64().unwrap();
    assert!((9e4..1.3e5).contains(&total), "{total}");
    let f = v["moon"]["illuminated_fraction"].as_f64().unwrap();
    assert!((0.98..=1.0).contains(&f), "full moon on 2024-06-22: {f}");
}

#[test]
fn nvg_irradiance_is_positive_and_richer_than_lux_on_a_moonless_night() {
    // Greenwich, 2024-01-11: new moon at 11:57 UTC. At midnight the sun is near -60 deg and
    // the moon, a few degrees from the sun, far below the horizon; at noon the sun is up.
    let at = |time: &str| ephem_json(&["--lat", "51.4779", "--lon", "0", "--time", time]);
    let night = at("2024-01-11T00:00:00Z");
    let noon = at("2024-01-11T12:00:00Z");
    assert!(night["sun"]["altitude_deg"].as_f64().unwrap() < -18.0);
    assert!(night["moon"]["altitude_deg"].as_f64().unwrap() < -10.0);
    assert!(noon["sun"]["altitude_deg"].as_f64().unwrap() > 10.0);
    let ratio = |v: &Value| {
        let nvg = &v["nvg_irradiance"];
        assert_eq!(
            keys(nvg),
            [
                "sun",
                "moon",
                "sky",
                "night_sky",
                "total",
                "unit",
                "total_w_m2"
            ]
        );
        assert_eq!(nvg["unit"], "lx_A (2856 K-equivalent lux)");
        let total = nvg["total"].as_f64().unwrap();
        assert!(
            total > 0.0 && nvg["total_w_m2"].as_f64().unwrap() > 0.0,
            "{nvg}"
        );
        let parts: f64 = ["sun", "moon", "sky", "night_sky"]
            .iter()
            .map(|k| nvg[*k].as_f64().unwrap())
            .sum();
        assert!((parts - total).abs() <= 1e-12 * total, "{nvg}");
        total / v["illuminance_lux"]["total"].as_f64().unwrap()
    };
    let (night_ratio, noon_ratio) = (ratio(&night), ratio(&noon));
    // Airglow makes the moonless sky several times richer for the tube than its lux; daylight
    // is bluer than illuminant A.
    assert!(
        night_ratio > 2.0 * noon_ratio,
        "{night_ratio} vs {noon_ratio}"
    );
    assert!(
        noon_ratio < 1.0 && night_ratio > 1.0,
        "{night_ratio} vs {noon_ratio}"
    );
}

#[test]
fn offsets_are_converted_to_utc_and_no_offset_means_utc() {
    let a = ephem_json(&[
        "--lat",
        "10",
        "--lon",
        "-20",
        "--time",
        "2030-01-02T03:04:05Z",
    ]);
    let b = ephem_json(&[
        "--lat",
        "10",
        "--lon",
        "-20",
        "--time",
        "2030-01-02T05:04:05+02:00",
    ]);
    let c = ephem_json(&[
        "--lat",
        "10",
        "--lon",
        "-20",
        "--time",
        "2030-01-02T03:04:05",
    ]);
    assert_eq!(a, b);
    assert_eq!(a, c);
}

#[test]
fn polar_night_gives_null_events_and_cloud_divides_light() {
    let clear = ephem_json(&[
        "--lat",
        "78.22",
        "--lon",
        "15.65",
        "--time",
        "2021-12-21T12:00:00Z",
    ]);
    for e in ["sunrise", "sunset", "civil_dawn", "civil_dusk"] {
        assert!(clear["events"][e].is_null(), "{e}");
    }
    assert!(clear["events"]["nautical_dawn"].is_string());
    let cloudy = ephem_json(&[
        "--lat",
        "78.22",
        "--lon",
        "15.65",
        "--time",
        "2021-12-21T12:00:00Z",
        "--cloud-cover",
        "1",
    ]);
    let ratio = clear["illuminance_lux"]["total"].as_f64().unwrap()
        / cloudy["illuminance_lux"]["total"].as_f64().unwrap();
    assert!((ratio - 10.0).abs() < 1e-9, "{ratio}");
}

#[test]
fn human_output_lists_positions_and_events() {
    let out = cig()
        .args([
            "ephem",
            "--lat",
            "0",
            "--lon",
            "-78.5",
            "--time",
            "2024-03-20T17:00:00Z",
        ])
        .assert()
        .success()
        .get_output()
        .stdout
        .clone();
    let text = String::from_utf8(out).unwrap();
    for word in [
        "sun ",
        "moon ",
        "illuminance",
        "lx_A (2856 K-equivalent lux)",
        "sunrise",
        "2024-03-20T11:18",
        "moonset",
    ] {
        assert!(text.contains(word), "{word} missing from:\n{text}");
    }
}

#[test]
fn bad_values_give_one_line_errors() {
    for (args, needle) in [
        (
            vec![
                "--lat",
                "91",
                "--lon",
                "0",
                "--time",
                "2024-01-01T00:00:00Z",
            ],
            "latitude",
        ),
        (
            vec![
                "--lat",
                "0",
                "--lon",
                "200",
                "--time",
                "2024-01-01T00:00:00Z",
            ],
            "longitude",
        ),
        (
            vec!["--lat", "0", "--lon", "0", "--time", "yesterday"],
            "ISO 8601",
        ),
        (
            vec!["--lat", "0", "--lon", "0", "--time", "2024-02-30T00:00:00Z"],
            "ISO 8601",
        ),
        (
            vec!["--lat", "0", "--lon", "0", "--time", "1899-12-31T23:59:59Z"],
            "1900",
        ),
        (
            vec!["--lat", "0", "--lon", "0", "--time", "2101-01-01T00:00:00Z"],
            "2100",
        ),
        (
            vec![
                "--lat",
                "0",
                "--lon",
                "0",
                "--time",
                "2024-01-01T00:00:00Z",
                "--cloud-cover",
                "-0.5",
            ],
            "cloud cover",
        ),
        (
            vec![
                "--lat",
                "NaN",
                "--lon",
                "0",
                "--time",
                "2024-01-01T00:00:00Z",
            ],
            "latitude",
        ),
    ] {
        let out = cig()
            .arg("ephem")
            .args(&args)
            .assert()
            .failure()
            .get_output()
            .clone();
        let err = String::from_utf8(out.stderr).unwrap();
        assert_eq!(err.trim_end().lines().count(), 1, "{args:?}: {err}");
        assert!(
            err.starts_with("error: ") && err.contains(needle),
            "{args:?}: {err}"
        );
        assert!(out.stdout.is_empty());
    }
}

#[test]
fn date_alone_means_midnight_utc() {
    let a = ephem_json(&["--lat", "-33.9", "--lon", "18.4", "--time", "1955-07-01"]);
    let b = ephem_json(&[
        "--lat",
        "-33.9",
        "--lon",
        "18.4",
        "--time",
        "1955-07-01T00:00:00Z",
    ]);
    assert_eq!(a, b);
}
