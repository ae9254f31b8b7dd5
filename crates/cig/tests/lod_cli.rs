//! End-to-end runs of `cig lod ne` and `cig render --klod`.

mod common;

use common::{cig, one_line_error};
use serde_json::Value;

fn ne_json(args: &[&str]) -> Value {
    let out = cig()
        .args(["lod", "ne"])
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

#[test]
fn the_studys_worked_example_gives_klod_1467_and_the_square_law_steps() {
    // Source 004 §4.8.2: a 40-degree channel of 1024 elements, K_LOD = 1 / tan(0.039) = 1467.
    let base = [
        "--radius-m",
        "10",
        "--range-m",
        "1000",
        "--fov-deg",
        "40",
        "--width-px",
        "1024",
    ];
    let v = ne_json(&base);
    let klod = num(&v, "klod");
    assert!((klod - 1467.0).abs() < 0.5, "{v}");
    // Eq 16 typed out: N_e = K_LOD r_c / R_s.
    assert!((num(&v, "ne") - klod * 10.0 / 1000.0).abs() < 1e-9, "{v}");
    // 14.67 reaches Table 3's step 3 (13.5) and not step 4 (24).
    assert_eq!(v["step"].as_u64(), Some(3), "{v}");
    // Each step's table value 1.5 s^2 is reached exactly at the range K r / (1.5 s^2).
    for s in 1..=8u64 {
        let range = klod * 10.0 / (1.5 * (s * s) as f64) * (1.0 - 1e-9);
        let range = format!("{range}");
        let mut args = base.to_vec();
        args[3] = &range;
        let v = ne_json(&args);
        assert_eq!(v["step"].as_u64(), Some(s), "{v}");
    }
    // Below step 1: step 0; far nearer than step 8: step 8.
    let mut args = base.to_vec();
    args[3] = "20000";
    assert_eq!(ne_json(&args)["step"].as_u64(), Some(0));
    args[3] = "10";
    assert_eq!(ne_json(&args)["step"].as_u64(), Some(8));
    // --klod overrides the computed constant.
    let mut args = base.to_vec();
    args.extend(["--klod", "2400"]);
    let v = ne_json(&args);
    assert_eq!(num(&v, "klod"), 2400.0);
    assert!((num(&v, "ne") - 24.0).abs() < 1e-9, "{v}");
    assert_eq!(v["step"].as_u64(), Some(4), "{v}");
    // Plain text without --json.
    let out = cig().args(["lod", "ne"]).args(base).assert().success();
    let text = String::from_utf8_lossy(&out.get_output().stdout).to_string();
    assert!(
        text.contains("K_LOD 1466.8") && text.contains("N_e 14.668") && text.contains("step 3"),
        "{text}"
    );
}

#[test]
fn bad_lod_input_gives_one_line_errors_naming_the_option() {
    let good = [
        ("--radius-m", "10"),
        ("--range-m", "1000"),
        ("--fov-deg", "40"),
        ("--width-px", "1024"),
    ];
    let cases = [
        ("--radius-m", "0"),
        ("--radius-m", "-3"),
        ("--radius-m", "NaN"),
        ("--range-m", "0"),
        ("--range-m", "inf"),
        ("--fov-deg", "0"),
        ("--fov-deg", "180"),
        ("--fov-deg", "-40"),
        ("--width-px", "0"),
        ("--width-px", "-1024"),
        ("--width-px", "10.5"),
        ("--klod", "0"),
        ("--klod", "-1467"),
    ];
    for (option, value) in cases {
        let mut args = vec!["lod".to_string(), "ne".to_string()];
        for (o, v) in good {
            args.push(o.to_string());
            args.push(if o == option { value } else { v }.to_string());
        }
        if option == "--klod" {
            args.push(option.to_string());
            args.push(value.to_string());
        }
        let line = one_line_error(&cig().args(&args).assert().failure());
        assert!(line.contains(option), "{option} {value}: {line}");
    }
}

#[test]
fn render_refuses_a_bad_klod_in_one_line() {
    let dir = tempfile::tempdir().expect("tmp");
    let out = dir.path().join("frame.png");
    for bad in ["0", "-5", "inf", "NaN"] {
        let assert = cig()
            .args(["render", "--db"])
            .arg(dir.path().join("db"))
            .args(["--eye", "35.99,-121.22,500", "--out"])
            .arg(&out)
            .args(["--klod", bad])
            .assert()
            .failure();
        let line = one_line_error(&assert);
        assert!(line.contains("--klod"), "{bad}: {line}");
    }
    assert!(!out.exists());
}
