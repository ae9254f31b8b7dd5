//! End-to-end runs of `cig sea`: statistics measured on the simulated surface, the horizon.

mod common;

use common::{cig, json_output, one_line_error};

fn number(v: &serde_json::Value, key: &str) -> f64 {
    v[key]
        .as_f64()
        .unwrap_or_else(|| panic!("{key} is a number: {v}"))
}

#[test]
fn a_fully_developed_sea_follows_pierson_moskowitz_and_sea_states_fall_in_their_codes() {
    // Pierson-Moskowitz: Hs = 0.21 U19.5^2 / g, U19.5 = 1.026 U10.
    let u10 = 10.0;
    let pm_hs_m = 0.21 * (1.026f64 * u10).powi(2) / 9.806_65;
    let v = json_output(&["sea", "stats", "--wind-mps", "10"]);
    let hs = number(&v, "hs_m");
    assert!((hs / pm_hs_m - 1.0).abs() < 0.15, "{v}");
    let tp = number(&v, "peak_period_s");
    assert!((tp / 7.5 - 1.0).abs() < 0.2, "{v}");
    let whitecaps = number(&v, "whitecap_fraction");
    assert!((0.0..0.2).contains(&whitecaps), "{v}");
    // A fetch of 20 km: a younger, lower sea.
    let young = json_output(&["sea", "stats", "--wind-mps", "10", "--fetch-km", "20"]);
    assert!(number(&young, "hs_m") < 0.8 * hs, "{young}");
    // Sea state 5 (rough): 2.5-4 m.
    let rough = json_output(&["sea", "stats", "--sea-state", "5"]);
    let hs5 = number(&rough, "hs_m");
    assert!((2.5..=4.0).contains(&hs5), "{rough}");
    // The same seed, the same sea; another seed, another realisation.
    let again = json_output(&["sea", "stats", "--wind-mps", "10"]);
    assert_eq!(v, again);
}

#[test]
fn the_horizon_hides_a_hull_below_its_masts() {
    // From 1.5 m with standard refraction a 30 m masthead sinks at about 25.6 km.
    let v = json_output(&["sea", "horizon", "--eye-m", "1.5", "--top-m", "30"]);
    let sinks_m = number(&v, "top_visible_to_m");
    assert!((sinks_m / 25_600.0 - 1.0).abs() < 0.02, "{v}");
    // Without refraction, the geometric horizon: nearer.
    let geometric = json_output(&[
        "sea",
        "horizon",
        "--eye-m",
        "1.5",
        "--top-m",
        "30",
        "--refraction-k",
        "0",
    ]);
    assert!(number(&geometric, "top_visible_to_m") < sinks_m - 500.0);
    // 7.3 m of a ship 15 km away is below the horizon.
    let hidden = json_output(&["sea", "horizon", "--eye-m", "1.5", "--range-m", "15000"]);
    assert!(
        (number(&hidden, "hidden_height_m") / 7.3 - 1.0).abs() < 0.05,
        "{hidden}"
    );
}

#[test]
fn bad_sea_input_gives_one_line_errors() {
    for (args, needle) in [
        (vec!["sea", "stats", "--sea-state", "10"], "--sea-state"),
        (vec!["sea", "stats", "--sea-state", "4.5"], "--sea-state"),
        (vec!["sea", "stats", "--wind-mps", "-3"], "--wind-mps"),
        (vec!["sea", "stats", "--wind-mps", "NaN"], "--wind-mps"),
        (
            vec!["sea", "stats", "--wind-mps", "8", "--fetch-km", "0"],
            "--fetch-km",
        ),
        (vec!["sea", "stats"], "--wind-mps"),
        (vec!["sea", "horizon", "--eye-m", "-2"], "--eye-m"),
        (
            vec!["sea", "horizon", "--eye-m", "2", "--refraction-k", "inf"],
            "--refraction-k",
        ),
    ] {
        let out = cig().args(&args).assert().failure();
        let line = one_line_error(&out);
        assert!(line.contains(needle), "{args:?}: {line}");
    }
}
