//! Published reference values and events at the equator, a mid latitude and
//! above the polar circle. (Meeus's worked examples 7.a, 12.a/b, 22.a, 25.b and
//! 47.a are unit tests beside the code they check.)

use cig_environment::ephemeris::refraction_deg;
use cig_environment::{day_events, ephemeris, DayEvents, Observer, UtcTime};
use proptest::prelude::*;

#[test]
fn nrel_spa_test_case() {
    // Reda and Andreas, NREL/TP-560-34302 (2008), Table A5.1: 2003-10-17 12:30:30 at
    // UTC-7, 39.742476 N, 105.1786 W, 1830.14 m, 820 hPa, 11 °C:
    // topocentric zenith 50.11162°, azimuth 194.34024°.
    let obs = Observer::new(39.742_476, -105.1786, 1830.14).unwrap();
    let t = UtcTime::from_calendar(2003, 10, 17, 19, 30, 30.0).unwrap();
    let e = ephemeris(&obs, t);
    let zenith = 90.0 - (e.sun.altitude_deg + refraction_deg(e.sun.altitude_deg, 820.0, 11.0));
    assert!((zenith - 50.111_62).abs() < 0.0005, "zenith {zenith}");
    assert!(
        (e.sun.azimuth_deg - 194.340_24).abs() < 0.0005,
        "azimuth {}",
        e.sun.azimuth_deg
    );
}

fn iso(t: Option<UtcTime>) -> Option<String> {
    t.map(|t| t.to_iso8601_seconds())
}

/// Asserts each event against a reference time (ISO 8601 UTC) within `tol_s`, or absent.
fn check(events: &DayEvents, expected: [(&str, Option<&str>); 10], tol_s: f64) {
    let ours = [
        events.sunrise,
        events.sunset,
        events.civil_dawn,
        events.civil_dusk,
        events.nautical_dawn,
        events.nautical_dusk,
        events.astronomical_dawn,
        events.astronomical_dusk,
        events.moonrise,
        events.moonset,
    ];
    for ((name, want), got) in expected.iter().zip(ours.iter()) {
        match (want, got) {
            (None, None) => {}
            (Some(w), Some(g)) => {
                let w = parse(w);
                let dt = (w.seconds_since_j2000() - g.seconds_since_j2000()).abs();
                assert!(
                    dt < tol_s,
                    "{name}: {} vs {} ({dt:.0} s)",
                    g.to_iso8601_seconds(),
                    w.to_iso8601_seconds()
                );
            }
            _ => panic!("{name}: expected {want:?}, got {:?}", iso(*got)),
        }
    }
}

fn parse(s: &str) -> UtcTime {
    let n = |a: usize, b: usize| s[a..b].parse::<u32>().expect("reference time");
    UtcTime::from_calendar(
        i32::try_from(n(0, 4)).expect("reference time"),
        n(5, 7),
        n(8, 10),
        n(11, 13),
        n(14, 16),
        f64::from(n(17, 19)),
    )
    .expect("reference time")
}

// Reference times from PyEphem 4.2.1 (pressure 0, the same horizon definitions);
// the Paris sunrise and sunset agree with the USNO's published 03:47 and 19:58 UTC.

#[test]
fn events_at_the_equator() {
    let obs = Observer::new(0.0, -78.5, 0.0).unwrap();
    let e = day_events(
        &obs,
        UtcTime::from_calendar(2024, 3, 20, 17, 0, 0.0).unwrap(),
    );
    check(
        &e,
        [
            ("sunrise", Some("2024-03-20T11:18:00")),
            ("sunset", Some("2024-03-20T23:24:29")),
            ("civil_dawn", Some("2024-03-20T10:57:20")),
            ("civil_dusk", Some("2024-03-20T23:45:09")),
            ("nautical_dawn", Some("2024-03-20T10:33:20")),
            ("nautical_dusk", Some("2024-03-21T00:09:09")),
            ("astronomical_dawn", Some("2024-03-20T10:09:20")),
            ("astronomical_dusk", Some("2024-03-21T00:33:09")),
            ("moonrise", Some("2024-03-20T20:24:29")),
            ("moonset", Some("2024-03-20T08:00:12")),
        ],
        30.0,
    );
}

#[test]
fn events_at_a_mid_latitude_midsummer() {
    // Paris on the June solstice: astronomical twilight lasts all night (None).
    let obs = Observer::new(48.8566, 2.3522, 0.0).unwrap();
    let e = day_events(
        &obs,
        UtcTime::from_calendar(2024, 6, 21, 12, 0, 0.0).unwrap(),
    );
    check(
        &e,
        [
            ("sunrise", Some("2024-06-21T03:47:03")),
            ("sunset", Some("2024-06-21T19:57:57")),
            ("civil_dawn", Some("2024-06-21T03:04:23")),
            ("civil_dusk", Some("2024-06-21T20:40:37")),
            ("nautical_dawn", Some("2024-06-21T02:03:38")),
            ("nautical_dusk", Some("2024-06-21T21:41:21")),
            ("astronomical_dawn", None),
            ("astronomical_dusk", None),
            ("moonrise", Some("2024-06-21T20:14:26")),
            ("moonset", Some("2024-06-21T02:32:09")),
        ],
        30.0,
    );
}

#[test]
fn events_above_the_polar_circle() {
    // Longyearbyen, 78.22 N: polar day at the June solstice, polar night in December
    // with only nautical and astronomical twilight around noon.
    let obs = Observer::new(78.22, 15.65, 0.0).unwrap();
    let june = day_events(
        &obs,
        UtcTime::from_calendar(2021, 6, 21, 12, 0, 0.0).unwrap(),
    );
    check(
        &june,
        [
            ("sunrise", None),
            ("sunset", None),
            ("civil_dawn", None),
            ("civil_dusk", None),
            ("nautical_dawn", None),
            ("nautical_dusk", None),
            ("astronomical_dawn", None),
            ("astronomical_dusk", None),
            ("moonrise", None),
            ("moonset", None),
        ],
        60.0,
    );
    let e = ephemeris(
        &obs,
        UtcTime::from_calendar(2021, 6, 21, 23, 0, 0.0).unwrap(),
    );
    assert!(e.sun.altitude_deg > 0.0, "midnight sun");
    let december = day_events(
        &obs,
        UtcTime::from_calendar(2021, 12, 21, 12, 0, 0.0).unwrap(),
    );
    check(
        &december,
        [
            ("sunrise", None),
            ("sunset", None),
            ("civil_dawn", None),
            ("civil_dusk", None),
            ("nautical_dawn", Some("2021-12-21T09:58:16")),
            ("nautical_dusk", Some("2021-12-21T11:52:47")),
            ("astronomical_dawn", Some("2021-12-21T06:37:06")),
            ("astronomical_dusk", Some("2021-12-21T15:13:57")),
            ("moonrise", None),
            ("moonset", None),
        ],
        60.0,
    );
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(24))]
    #[test]
    fn solar_events_are_ordered(lat in -45.0f64..45.0, lon in -180.0f64..180.0,
                                s in -3.1e9f64..3.1e9) {
        // Below 45° latitude every solar event happens every day, in this order.
        let obs = Observer::new(lat, lon, 0.0).unwrap();
        let e = day_events(&obs, UtcTime::from_seconds_since_j2000(s).unwrap());
        let seq = [e.astronomical_dawn, e.nautical_dawn, e.civil_dawn, e.sunrise,
                   e.sunset, e.civil_dusk, e.nautical_dusk, e.astronomical_dusk];
        let times: Vec<f64> = seq.iter().map(|t| t.expect("every event exists").seconds_since_j2000()).collect();
        for w in times.windows(2) {
            prop_assert!(w[0] < w[1], "{:?}", seq.map(iso));
        }
        let start = e.day_start.unwrap().seconds_since_j2000();
        prop_assert!(times[0] >= start && times[7] < start + 86_400.0);
        // At each event the sun stands at its threshold.
        let sunrise = e.sunrise.unwrap();
        let alt = ephemeris(&obs, sunrise).sun.altitude_deg;
        prop_assert!((alt - -0.833).abs() < 0.001, "{alt}");
    }

    #[test]
    fn moonrise_puts_the_upper_limb_on_the_refracted_horizon(lat in -60.0f64..60.0,
                                lon in -180.0f64..180.0, s in -3.1e9f64..3.1e9) {
        let obs = Observer::new(lat, lon, 0.0).unwrap();
        let e = day_events(&obs, UtcTime::from_seconds_since_j2000(s).unwrap());
        for t in [e.moonrise, e.moonset].into_iter().flatten() {
            let m = ephemeris(&obs, t).moon;
            let upper_limb = m.altitude_deg + m.semidiameter_deg;
            prop_assert!((upper_limb - -34.0 / 60.0).abs() < 0.002, "{upper_limb}");
        }
    }
}
