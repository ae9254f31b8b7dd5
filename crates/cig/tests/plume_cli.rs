//! End-to-end runs of `cig plume` and `cig bench particles`.

mod common;

use common::cig;
use serde_json::Value;

fn plume_json(args: &[&str]) -> Value {
    let out = cig()
        .arg("plume")
        .args(args)
        .arg("--json")
        .assert()
        .success();
    let stdout = &out.get_output().stdout;
    serde_json::from_slice(stdout)
        .unwrap_or_else(|e| panic!("{e}: {}", String::from_utf8_lossy(stdout)))
}

fn num(v: &Value, key: &str) -> f64 {
    v[key]
        .as_f64()
        .unwrap_or_else(|| panic!("{key} missing in {v}"))
}

fn close(a: f64, b: f64, rel: f64) -> bool {
    (a - b).abs() <= rel * b.abs().max(1e-12)
}

/// Buoyancy flux typed out independently: F = g v d^2 (Ts - Ta) / (4 Ts), g = 9.80616.
fn flux(v: f64, d: f64, ts: f64, ta: f64) -> f64 {
    9.80616 * v * d * d * (ts - ta) / (4.0 * ts)
}

#[test]
fn neutral_plume_matches_the_isc3_formulas_and_eq6() {
    // Default stack: 10 m/s, 1 m, 400 K into 293.15 K air.
    let f = flux(10.0, 1.0, 400.0, 293.15);
    assert!(f < 55.0);
    let v = plume_json(&["--class", "D", "--wind", "5", "--x", "1000"]);
    let xf = 49.0 * f.powf(0.625);
    let final_rise = 21.425 * f.powf(0.75) / 5.0;
    assert!(close(num(&v, "final_rise_m"), final_rise, 1e-12), "{v}");
    assert!(close(num(&v, "final_rise_x_m"), xf, 1e-12), "{v}");
    assert!(xf < 1000.0);
    assert!(close(num(&v, "rise_m"), final_rise, 1e-12), "{v}");
    // Eq 6, class D at 1 km: e^4.230 and e^3.414.
    assert!(close(num(&v, "sigma_y_m"), 4.230f64.exp(), 1e-9), "{v}");
    assert!(close(num(&v, "sigma_z_m"), 3.414f64.exp(), 1e-9), "{v}");
    // Before x_f: the transitional rise.
    let v = plume_json(&["--class", "B", "--wind", "3", "--x", "40"]);
    let transitional = 1.6 * f.cbrt() * 40f64.powf(2.0 / 3.0) / 3.0;
    assert!(close(num(&v, "rise_m"), transitional, 1e-12), "{v}");
    // Class B at 0.1 km: exp(I + J ln 0.1 + K ln^2 0.1).
    let l = 0.1f64.ln();
    let sy = (5.058 + 0.9024 * l - 0.0096 * l * l).exp();
    let sz = (4.694 + 1.0629 * l + 0.0136 * l * l).exp();
    let v = plume_json(&["--class", "b", "--wind", "3", "--x", "100"]);
    assert!(
        close(num(&v, "sigma_y_m"), sy, 1e-9) && close(num(&v, "sigma_z_m"), sz, 1e-9),
        "{v}"
    );
}

#[test]
fn large_buoyancy_and_stable_air_use_their_branches() {
    let f = flux(20.0, 5.0, 500.0, 293.15);
    assert!(f >= 55.0);
    let v = plume_json(&[
        "--class",
        "C",
        "--wind",
        "4",
        "--x",
        "5000",
        "--stack-velocity",
        "20",
        "--stack-diameter",
        "5",
        "--stack-temp",
        "500",
    ]);
    assert!(
        close(num(&v, "final_rise_m"), 38.71 * f.powf(0.6) / 4.0, 1e-12),
        "{v}"
    );
    assert!(
        close(num(&v, "final_rise_x_m"), 119.0 * f.powf(0.4), 1e-12),
        "{v}"
    );
    // Stable: s = g / Ta * dtheta/dz; x_f = 2.0715 u / sqrt(s).
    let f = flux(10.0, 1.0, 400.0, 280.0);
    let s = 9.80616 / 280.0 * 0.01;
    let v = plume_json(&[
        "--class",
        "E",
        "--wind",
        "2",
        "--x",
        "2000",
        "--air-temp",
        "280",
        "--stable-dtheta-dz",
        "0.01",
    ]);
    assert!(
        close(num(&v, "final_rise_m"), 2.6 * (f / (2.0 * s)).cbrt(), 1e-12),
        "{v}"
    );
    assert!(
        close(num(&v, "final_rise_x_m"), 2.0715 * 2.0 / s.sqrt(), 1e-12),
        "{v}"
    );
    // ISC3's default gradient for F is 0.035 K/m: higher stability, lower rise.
    let default_f = plume_json(&[
        "--class",
        "F",
        "--wind",
        "2",
        "--x",
        "2000",
        "--air-temp",
        "280",
    ]);
    assert!(num(&default_f, "final_rise_m") < num(&v, "final_rise_m"));
}

#[test]
fn the_class_is_derived_from_the_weather_when_not_given() {
    // Clear night, 2 m/s (4 knots): Turner's class 6, F.
    let v = plume_json(&["--wind", "2", "--x", "500", "--sun-elevation-deg", "-10"]);
    assert_eq!(v["class"], "F", "{v}");
    // High sun, light wind: A.
    let v = plume_json(&["--wind", "1", "--x", "500", "--sun-elevation-deg", "70"]);
    assert_eq!(v["class"], "A", "{v}");
    // Low overcast: D.
    let v = plume_json(&[
        "--wind",
        "1",
        "--x",
        "500",
        "--sun-elevation-deg",
        "70",
        "--cloud-cover",
        "1",
        "--ceiling-m",
        "300",
    ]);
    assert_eq!(v["class"], "D", "{v}");
}

#[test]
fn human_output_names_the_numbers() {
    let out = cig()
        .args(["plume", "--class", "D", "--wind", "5", "--x", "100"])
        .assert()
        .success();
    let text = String::from_utf8_lossy(&out.get_output().stdout).to_string();
    assert!(
        text.contains("class D") && text.contains("transitional") && text.contains("final rise"),
        "{text}"
    );
}

fn one_line_error(args: &[&str]) -> String {
    let out = cig().args(args).assert().failure();
    let stderr = String::from_utf8_lossy(&out.get_output().stderr).to_string();
    let lines: Vec<&str> = stderr.lines().filter(|l| l.starts_with("error:")).collect();
    assert_eq!(lines.len(), 1, "one error line: {stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
    lines[0].to_string()
}

#[test]
fn bad_values_give_one_line_errors() {
    // The base command with one flag replaced or added.
    let with = |extra: &[&str]| {
        let mut pairs = vec![("--class", "D"), ("--wind", "5"), ("--x", "100")];
        for flag_value in extra.chunks(2) {
            let (flag, value) = (flag_value[0], flag_value[1]);
            pairs.retain(|(f, _)| *f != flag);
            pairs.push((flag, value));
        }
        let mut v = vec!["plume"];
        for (f, value) in pairs {
            v.push(f);
            v.push(value);
        }
        one_line_error(&v)
    };
    assert!(with(&["--wind", "-1"]).contains("wind"));
    assert!(with(&["--wind", "0"]).contains("wind"));
    assert!(with(&["--wind", "inf"]).contains("wind"));
    assert!(with(&["--x", "-5"]).contains("downwind"));
    assert!(with(&["--x", "nan"]).contains("downwind"));
    assert!(with(&["--class", "Q"]).contains("stability class"));
    assert!(with(&["--stack-temp", "0"]).contains("stack exit temperature"));
    assert!(with(&["--stack-diameter", "-2"]).contains("stack diameter"));
    assert!(with(&["--air-temp", "nan"]).contains("air temperature"));
    assert!(with(&["--stable-dtheta-dz", "0.02"]).contains("E and F"));
    let e = one_line_error(&[
        "plume",
        "--class",
        "F",
        "--wind",
        "5",
        "--x",
        "100",
        "--stable-dtheta-dz",
        "-0.02",
    ]);
    assert!(e.contains("potential temperature gradient"), "{e}");
    assert!(one_line_error(&["plume", "--wind", "5", "--x", "100"]).contains("--class"));
    let e = one_line_error(&[
        "plume",
        "--wind",
        "5",
        "--x",
        "100",
        "--sun-elevation-deg",
        "30",
        "--cloud-cover",
        "2",
    ]);
    assert!(e.contains("cloud cover"), "{e}");
}

#[test]
fn bench_particles_reports_the_issue_scene() {
    let out = cig()
        .args([
            "bench",
            "particles",
            "--json",
            "--frames",
            "10",
            "--warm-seconds",
            "3",
        ])
        .assert()
        .success();
    let v: Value = serde_json::from_slice(&out.get_output().stdout).expect("json");
    for key in [
        "update_ms_per_frame_median",
        "update_ms_per_frame_p99",
        "update_ms_per_frame_max",
        "update_ns_per_puff_median",
        "update_vs_baseline",
        "snapshot_ms_median",
    ] {
        assert!(num(&v, key) > 0.0, "{key} in {v}");
    }
    assert!(num(&v, "update_ms_per_frame_max") >= num(&v, "update_ms_per_frame_median"));
    assert_eq!(v["plumes"], 32);
    assert_eq!(v["dust_trails"], 200);
    assert_eq!(v["pool_starved_spawns"], 0);
    // After 3 s only part of each pool is in use; every count is positive.
    assert!(v["puffs_active"].as_u64().expect("count") > 1000);
    assert!(v["machine"]["cores"].as_u64().expect("cores") >= 1);
    assert!(one_line_error(&["bench", "particles", "--frames", "1"]).contains("--frames"));
}
