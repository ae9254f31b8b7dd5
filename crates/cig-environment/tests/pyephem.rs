//! Comparison with an independent implementation: PyEphem (`pip install ephem`),
//! whose libastro computes the sun with the full VSOP87, the moon with its own
//! lunar theory and its own ΔT. Both sides use geometric topocentric altitudes
//! (PyEphem with `pressure = 0`), so refraction models do not enter.
//!
//! 60 random cases over 1900–2100 (seeded): sun and moon directions (angular
//! separation; azimuth and altitude), the moon's illuminated fraction, and the
//! ten events of the local day for latitudes up to 60°. Skips with a message
//! when python3 or the `ephem` package is missing.

use std::io::Write;
use std::process::{Command, Stdio};

use cig_environment::ephemeris::geocentric_moon_phase_angle_deg;
use cig_environment::{day_events, ephemeris, DayEvents, Observer, UtcTime};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde_json::Value;

struct Case {
    lat: f64,
    lon: f64,
    alt_m: f64,
    time: UtcTime,
}

fn cases() -> Vec<Case> {
    let mut rng = ChaCha8Rng::seed_from_u64(20_240_621);
    let first = UtcTime::from_calendar(1900, 1, 2, 0, 0, 0.0)
        .expect("valid time")
        .seconds_since_j2000();
    let last = UtcTime::from_calendar(2100, 12, 30, 0, 0, 0.0)
        .expect("valid time")
        .seconds_since_j2000();
    let mut out: Vec<Case> = (0..60)
        .map(|_| Case {
            lat: rng.gen_range(-60.0..=60.0),
            lon: rng.gen_range(-180.0..=180.0),
            alt_m: rng.gen_range(0.0..3000.0),
            time: UtcTime::from_seconds_since_j2000(rng.gen_range(first..last))
                .expect("valid time"),
        })
        .collect();
    // Fixed extremes: the polar circles at the solstices.
    for (lat, month) in [(78.0, 6), (78.0, 12), (-70.0, 6)] {
        out.push(Case {
            lat,
            lon: 15.0,
            alt_m: 0.0,
            time: UtcTime::from_calendar(2021, month, 21, 12, 0, 0.0).expect("valid time"),
        });
    }
    out
}

/// Runs the peer; `None` (with a message) when it cannot run.
fn run_peer(input: &str) -> Option<Vec<Value>> {
    let script = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/pyephem_peer.py");
    let child = Command::new("python3")
        .arg(script)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn();
    let mut child = match child {
        Ok(c) => c,
        Err(e) => {
            eprintln!(
                "SKIPPED: python3 is not available ({e}); install python3 and `pip install ephem`"
            );
            return None;
        }
    };
    child
        .stdin
        .take()
        .expect("stdin")
        .write_all(input.as_bytes())
        .expect("write cases");
    let out = child.wait_with_output().expect("peer output");
    if out.status.code() == Some(3) {
        eprintln!(
            "SKIPPED: {}; `pip install ephem` to run this comparison",
            String::from_utf8_lossy(&out.stderr).trim()
        );
        return None;
    }
    assert!(
        out.status.success(),
        "PyEphem peer failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    Some(
        String::from_utf8(out.stdout)
            .expect("utf8")
            .lines()
            .map(|l| serde_json::from_str(l).expect("peer json"))
            .collect(),
    )
}

fn unit(az_deg: f64, alt_deg: f64) -> [f64; 3] {
    let (sa, ca) = az_deg.to_radians().sin_cos();
    let (sh, ch) = alt_deg.to_radians().sin_cos();
    [ch * sa, ch * ca, sh]
}

fn separation_deg(a: [f64; 3], b: [f64; 3]) -> f64 {
    let dot: f64 = a.iter().zip(b.iter()).map(|(x, y)| x * y).sum();
    let cross = [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ];
    let n = cross.iter().map(|c| c * c).sum::<f64>().sqrt();
    n.atan2(dot).to_degrees()
}

fn event_list(e: &DayEvents) -> [(&'static str, Option<UtcTime>, bool); 10] {
    [
        ("sunrise", e.sunrise, false),
        ("sunset", e.sunset, false),
        ("civil_dawn", e.civil_dawn, false),
        ("civil_dusk", e.civil_dusk, false),
        ("nautical_dawn", e.nautical_dawn, false),
        ("nautical_dusk", e.nautical_dusk, false),
        ("astronomical_dawn", e.astronomical_dawn, false),
        ("astronomical_dusk", e.astronomical_dusk, false),
        ("moonrise", e.moonrise, true),
        ("moonset", e.moonset, true),
    ]
}

#[test]
fn agrees_with_pyephem() {
    let cases = cases();
    let mut input = String::new();
    let mut ours = Vec::new();
    for c in &cases {
        let obs = Observer::new(c.lat, c.lon, c.alt_m).unwrap();
        let e = ephemeris(&obs, c.time);
        let ev = day_events(&obs, c.time);
        let day_start = ev.day_start.unwrap();
        input.push_str(
            &serde_json::json!({
                "lat": c.lat, "lon": c.lon, "alt_m": c.alt_m,
                "jd": c.time.julian_date(), "day_start_jd": day_start.julian_date(),
            })
            .to_string(),
        );
        input.push('\n');
        ours.push((obs, e, ev));
    }
    let Some(theirs) = run_peer(&input) else {
        return;
    };
    assert_eq!(theirs.len(), cases.len());
    let (mut max_sun, mut max_moon, mut max_frac, mut max_event_s) =
        (0.0f64, 0.0f64, 0.0f64, 0.0f64);
    let mut events_compared = 0;
    let mut events_none_both = 0;
    for ((c, (obs, e, ev)), p) in cases.iter().zip(ours.iter()).zip(theirs.iter()) {
        let f = |k: &str| p[k].as_f64().unwrap_or(f64::NAN);
        let sun_sep = separation_deg(e.sun.direction_enu, unit(f("sun_az"), f("sun_alt")));
        let moon_sep = separation_deg(e.moon.direction_enu, unit(f("moon_az"), f("moon_alt")));
        let frac = (e.moon_illuminated_fraction - f("moon_fraction_topocentric")).abs();
        let geocentric = (1.0 + geocentric_moon_phase_angle_deg(c.time).to_radians().cos()) / 2.0;
        let frac_geo = (geocentric - f("moon_fraction_geocentric")).abs();
        let ctx = format!(
            "lat {} lon {} at {}",
            c.lat,
            c.lon,
            c.time.to_iso8601_seconds()
        );
        assert!(sun_sep < 0.01, "sun {sun_sep} deg apart, {ctx}");
        assert!(
            (e.sun.altitude_deg - f("sun_alt")).abs() < 0.01,
            "sun altitude, {ctx}"
        );
        assert!(moon_sep < 0.05, "moon {moon_sep} deg apart, {ctx}");
        assert!(
            (e.moon.altitude_deg - f("moon_alt")).abs() < 0.05,
            "moon altitude, {ctx}"
        );
        assert!(
            frac < 0.005,
            "illuminated fraction {} vs {}, {ctx}",
            e.moon_illuminated_fraction,
            f("moon_fraction_topocentric")
        );
        assert!(
            frac_geo < 0.005,
            "geocentric illuminated fraction {geocentric} vs {}, {ctx}",
            f("moon_fraction_geocentric")
        );
        max_sun = max_sun.max(sun_sep);
        max_moon = max_moon.max(moon_sep);
        max_frac = max_frac.max(frac).max(frac_geo);
        if c.lat.abs() > 60.0 {
            // Above 60° only the existence of the events is compared (polar day/night).
            for (name, mine, _) in event_list(ev) {
                if name.starts_with("moon") {
                    continue;
                }
                let other = p["events"][name].as_f64();
                assert_eq!(mine.is_some(), other.is_some(), "{name} existence, {ctx}");
            }
            continue;
        }
        for (name, mine, is_moon) in event_list(ev) {
            let other = p["events"][name]
                .as_f64()
                .map(|jd| UtcTime::from_julian_date(jd).unwrap());
            match (mine, other) {
                (Some(a), Some(b)) => {
                    let dt = (a.seconds_since_j2000() - b.seconds_since_j2000()).abs();
                    assert!(
                        dt < 60.0,
                        "{name}: ours {} theirs {} ({dt:.1} s), {ctx}",
                        a.to_iso8601_seconds(),
                        b.to_iso8601_seconds()
                    );
                    max_event_s = max_event_s.max(dt);
                    events_compared += 1;
                }
                (None, None) => events_none_both += 1,
                (a, b) => {
                    // Only acceptable when the event sits within a minute of a day boundary
                    // (the two sides may put it on either side).
                    let t = a.or(b).unwrap();
                    let start = ev.day_start.unwrap().seconds_since_j2000();
                    let s = t.seconds_since_j2000();
                    let near_edge = (s - start).abs() < 60.0 || (s - start - 86_400.0).abs() < 60.0;
                    assert!(
                        near_edge,
                        "{name}: ours {a:?} theirs {b:?}, {ctx} (moon: {is_moon})"
                    );
                }
            }
        }
        let _ = obs;
    }
    eprintln!(
        "PyEphem: {} cases; max sun separation {max_sun:.5} deg, moon {max_moon:.5} deg, \
         illuminated fraction {max_frac:.5}; {events_compared} events compared, max {max_event_s:.1} s; \
         {events_none_both} absent on both sides",
        cases.len()
    );
    assert!(
        events_compared > 300,
        "too few events compared: {events_compared}"
    );
}
