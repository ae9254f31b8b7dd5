//! Long-run checks, shortened: a minute of `cig serve` under the soak's load (a host flying
//! at 300 m/s, 200 dead-reckoned DIS entities, smoke, clouds, a storm) with its memory, frame
//! time, descriptors and threads compared between the time after the warm-up and the end. (Alone
//! in its test binary, so no other test's processes share its minute.)

mod common;

use common::{cig, one_line_error, small_db};
use serde_json::Value;
use std::time::Duration;

#[test]
fn a_minute_of_serving_under_load_keeps_memory_frame_time_and_descriptors_flat() {
    let dir = tempfile::tempdir().expect("tempdir");
    let db = small_db(dir.path());
    let out = cig()
        .args(["bench", "soak", "--db"])
        .arg(&db)
        // A minute's first third still pages and grows its plumes: 5 % (the hour's verdict is
        // 2 % after minute 5).
        .args([
            "--minutes",
            "1",
            "--sample-s",
            "2",
            "--rss-growth-max-pct",
            "5",
            "--json",
        ])
        .timeout(Duration::from_secs(240))
        .output()
        .expect("run");
    let stderr = String::from_utf8_lossy(&out.stderr);
    let report: Value =
        serde_json::from_slice(&out.stdout).unwrap_or_else(|e| panic!("{e}: {stderr}"));
    let show = || {
        let mut r = report.clone();
        r["samples"] = Value::Null;
        r.to_string()
    };
    assert!(out.status.success(), "{}\n{stderr}", show());
    assert_eq!(report["passed"], true, "{}", show());
    // The load was there: the host's frames answered, the exercise's entities applied, the
    // plumes live and the frames drawn.
    let serve = &report["serve"];
    assert!(
        serve["hat_hot_answered"].as_u64().unwrap_or(0) > 100,
        "{}",
        show()
    );
    assert_eq!(serve["remote_entities"], 200, "{}", show());
    assert!(
        serve["entity_states_applied"].as_u64().unwrap_or(0) > 2000,
        "{}",
        show()
    );
    assert_eq!(serve["effects_live"], 3, "{}", show());
    assert!(serve["frames"].as_u64().unwrap_or(0) > 100, "{}", show());
    // The figures the verdict reads.
    let growth = report["rss_growth_pct"].as_f64().expect("growth");
    assert!(growth.abs() <= 5.0, "{growth}");
    let ratio = report["frame_time_ratio"].as_f64().expect("ratio");
    assert!(ratio > 0.5 && ratio <= 1.25, "{ratio}");
    assert!(report["fds_leaked"].as_i64().expect("fds") <= 0);
    assert!(report["threads_leaked"].as_i64().expect("threads") <= 0);
    assert_eq!(report["thirds"].as_array().map(Vec::len), Some(3));
    assert!(report["samples"].as_array().map_or(0, Vec::len) >= 25);
}

#[test]
fn bad_soak_and_channel_options_are_refused_with_one_line() {
    let dir = tempfile::tempdir().expect("tempdir");
    let missing = dir.path().join("no-such-db");
    let out = cig()
        .args(["bench", "soak", "--db"])
        .arg(&missing)
        .assert()
        .failure();
    assert!(one_line_error(&out).contains("no-such-db"));
    let out = cig()
        .args(["bench", "soak", "--minutes", "0", "--db"])
        .arg(&missing)
        .assert()
        .failure();
    assert!(one_line_error(&out).contains("--minutes 0"));
    let out = cig()
        .args(["bench", "channels", "--rate-hz", "0", "--db"])
        .arg(&missing)
        .assert()
        .failure();
    assert!(one_line_error(&out).contains("--rate-hz 0"));
}
