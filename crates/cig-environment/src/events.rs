//! Sunrise, sunset, twilights, moonrise and moonset within one local day.
//!
//! Definitions (U.S. Naval Observatory, as in the NPS thesis chapter IV.B.4):
//! sunrise and sunset when the topocentric geometric altitude of the sun's
//! centre is −0.833° (34′ of standard refraction plus a 16′ semidiameter);
//! civil, nautical and astronomical dawn and dusk at −6°, −12° and −18°;
//! moonrise and moonset when the moon's upper limb is on the refracted horizon,
//! taken on the *topocentric centre*: altitude = −34′ − s, with s the moon's
//! topocentric semidiameter at that instant. (This equals Meeus's geocentric
//! `h0 = 0.7275 π − 34′`, chapter 15, with the parallax done exactly.)
//!
//! The local day: local mean time, 00:00 to 24:00 at the observer's meridian,
//! i.e. UTC from `−lon/15` hours on the local mean date containing the instant
//! asked about. An event is the first crossing of its kind in that window
//! (rising for sunrise, dawns and moonrise; setting for sunset, dusks and
//! moonset), or `None` when there is none (polar day or night, a moonless
//! day: the moon rises about 50 minutes later each day, so about once a month
//! one of its events falls outside the local day).
//!
//! Algorithm: the altitudes are sampled every 10 minutes over the day; every
//! change of sign of `altitude − threshold` between samples is refined by the
//! Illinois variant of regula falsi to 0.1 s; a pair of crossings hidden between
//! two samples (the body just grazing the threshold) is found from the vertex
//! of the parabola through three neighbouring samples. Limits: the timing error
//! is the position error divided by the altitude rate: well under a minute up to
//! 60° latitude; at higher latitudes grazing events become ill-conditioned
//! (a 0.003° error can move them by minutes), and a grazing pair of crossings
//! less than about 20 minutes apart whose parabola misses the threshold is not
//! reported.

use crate::ephemeris::{moon_altitude_deg, sun_altitude_deg, Geocentric, Observer};
use crate::time::{UtcTime, SECONDS_PER_DAY};

/// Sun altitude of sunrise and sunset, degrees (centre, geometric).
pub const SUNRISE_ALTITUDE_DEG: f64 = -0.833;
/// Sun altitude ending civil twilight, degrees.
pub const CIVIL_TWILIGHT_ALTITUDE_DEG: f64 = -6.0;
/// Sun altitude ending nautical twilight, degrees.
pub const NAUTICAL_TWILIGHT_ALTITUDE_DEG: f64 = -12.0;
/// Sun altitude ending astronomical twilight, degrees.
pub const ASTRONOMICAL_TWILIGHT_ALTITUDE_DEG: f64 = -18.0;
/// Standard horizontal refraction used for moonrise and moonset, degrees (34′).
pub const HORIZON_REFRACTION_DEG: f64 = 34.0 / 60.0;

/// Sampling step of the event search, seconds.
const STEP_S: f64 = 600.0;
/// Samples per day (plus one to close the day).
const STEPS: usize = 144;

/// Rise, set and twilight times within one local day; `None` where the event
/// does not happen that day.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct DayEvents {
    /// Start of the local mean day (UTC).
    pub day_start: Option<UtcTime>,
    /// Sun's centre rises through −0.833°.
    pub sunrise: Option<UtcTime>,
    /// Sun's centre sets through −0.833°.
    pub sunset: Option<UtcTime>,
    /// Sun rises through −6°.
    pub civil_dawn: Option<UtcTime>,
    /// Sun sets through −6°.
    pub civil_dusk: Option<UtcTime>,
    /// Sun rises through −12°.
    pub nautical_dawn: Option<UtcTime>,
    /// Sun sets through −12°.
    pub nautical_dusk: Option<UtcTime>,
    /// Sun rises through −18°.
    pub astronomical_dawn: Option<UtcTime>,
    /// Sun sets through −18°.
    pub astronomical_dusk: Option<UtcTime>,
    /// Moon's upper limb rises on the refracted horizon.
    pub moonrise: Option<UtcTime>,
    /// Moon's upper limb sets on the refracted horizon.
    pub moonset: Option<UtcTime>,
}

/// Start (UTC seconds since J2000) of the local mean day containing `time` at `lon_deg`.
pub fn local_day_start(time: UtcTime, lon_deg: f64) -> UtcTime {
    let offset_s = lon_deg / 15.0 * 3600.0;
    // Local mean time in seconds since J2000 (which is noon); midnights are at 43 200 s
    // offsets from whole days.
    let local = time.seconds_since_j2000() + offset_s + 43_200.0;
    let local_midnight = (local / SECONDS_PER_DAY).floor() * SECONDS_PER_DAY - 43_200.0;
    UtcTime::clamped_from_seconds_since_j2000(local_midnight - offset_s)
}

/// Kind of crossing searched for.
#[derive(Clone, Copy, PartialEq)]
enum Direction {
    Rising,
    Setting,
}

/// Find the first crossing of `f = 0` in direction `dir` over the sampled day.
/// `samples[i]` is `f` at `t0 + i * STEP_S`.
fn first_crossing(
    t0: f64,
    samples: &[f64],
    dir: Direction,
    f: &mut dyn FnMut(f64) -> f64,
) -> Option<f64> {
    let wanted = |a: f64, b: f64| match dir {
        Direction::Rising => a < 0.0 && b >= 0.0,
        Direction::Setting => a >= 0.0 && b < 0.0,
    };
    for i in 0..samples.len().saturating_sub(1) {
        let (a, b) = (*samples.get(i)?, *samples.get(i + 1)?);
        let ta = t0 + STEP_S * idx_f64(i);
        let tb = ta + STEP_S;
        if wanted(a, b) {
            return Some(refine(ta, a, tb, b, f));
        }
        if (a < 0.0) == (b < 0.0) {
            // Look for a hidden pair of crossings: the parabola through the samples
            // around this interval has its vertex inside it.
            if let Some(tv) = hidden_vertex(samples, i, t0) {
                let fv = f(tv);
                if (fv < 0.0) != (a < 0.0) {
                    if wanted(a, fv) {
                        return Some(refine(ta, a, tv, fv, f));
                    }
                    if wanted(fv, b) {
                        return Some(refine(tv, fv, tb, b, f));
                    }
                }
            }
        }
    }
    None
}

/// `i` as f64 (sample indices are tiny).
fn idx_f64(i: usize) -> f64 {
    // At most STEPS + 1 samples.
    #[allow(
        clippy::cast_precision_loss,
        reason = "sample indices are below 200 and exact in f64"
    )]
    let x = i as f64;
    x
}

/// Time of the vertex of the parabola through the samples around interval `i`,
/// when it lies inside `[t_i, t_{i+1}]` and is an extremum toward zero.
fn hidden_vertex(samples: &[f64], i: usize, t0: f64) -> Option<f64> {
    // Use samples i-1, i, i+1 when possible, else i, i+1, i+2.
    let c = if i >= 1 { i } else { i + 1 };
    let (y0, y1, y2) = (
        *samples.get(c.checked_sub(1)?)?,
        *samples.get(c)?,
        *samples.get(c + 1)?,
    );
    let curvature = y0 - 2.0 * y1 + y2;
    if curvature == 0.0 {
        return None;
    }
    // Vertex offset in steps from sample c.
    let x = (y0 - y2) / (2.0 * curvature);
    // The vertex must move toward zero: a minimum of positive values or a maximum
    // of negative ones.
    let toward_zero = (y1 > 0.0 && curvature > 0.0) || (y1 < 0.0 && curvature < 0.0);
    let tv = t0 + STEP_S * (idx_f64(c) + x);
    let ta = t0 + STEP_S * idx_f64(i);
    (toward_zero && tv > ta && tv < ta + STEP_S).then_some(tv)
}

/// Illinois regula falsi on a bracket with a sign change, to 0.1 s.
fn refine(
    mut ta: f64,
    mut fa: f64,
    mut tb: f64,
    mut fb: f64,
    f: &mut dyn FnMut(f64) -> f64,
) -> f64 {
    let mut side = 0i8;
    for _ in 0..60 {
        if tb - ta < 0.1 {
            break;
        }
        let denom = fb - fa;
        let mut t = if denom == 0.0 {
            0.5 * (ta + tb)
        } else {
            tb - fb * (tb - ta) / denom
        };
        if !(t > ta && t < tb) {
            t = 0.5 * (ta + tb);
        }
        let ft = f(t);
        if (ft < 0.0) == (fa < 0.0) {
            ta = t;
            fa = ft;
            if side == -1 {
                fb *= 0.5;
            }
            side = -1;
        } else {
            tb = t;
            fb = ft;
            if side == 1 {
                fa *= 0.5;
            }
            side = 1;
        }
    }
    if fa.abs() < fb.abs() {
        ta
    } else {
        tb
    }
}

/// Rise, set and twilight times of the local mean day containing `time`.
pub fn day_events(observer: &Observer, time: UtcTime) -> DayEvents {
    let start = local_day_start(time, observer.geodetic().lon_deg);
    let t0 = start.seconds_since_j2000();
    let at = |s: f64| UtcTime::clamped_from_seconds_since_j2000(s);
    let mut sun_samples = Vec::with_capacity(STEPS + 1);
    let mut moon_samples = Vec::with_capacity(STEPS + 1);
    for i in 0..=STEPS {
        let g = Geocentric::at(at(t0 + STEP_S * idx_f64(i)));
        sun_samples.push(sun_altitude_deg(observer, &g));
        let (alt, sd) = moon_altitude_deg(observer, &g);
        moon_samples.push(alt + HORIZON_REFRACTION_DEG + sd);
    }
    let mut events = DayEvents {
        day_start: Some(start),
        ..DayEvents::default()
    };
    let sun_event = |threshold: f64, dir: Direction| {
        let shifted: Vec<f64> = sun_samples.iter().map(|h| h - threshold).collect();
        let mut f = |s: f64| sun_altitude_deg(observer, &Geocentric::at(at(s))) - threshold;
        first_crossing(t0, &shifted, dir, &mut f).map(at)
    };
    events.sunrise = sun_event(SUNRISE_ALTITUDE_DEG, Direction::Rising);
    events.sunset = sun_event(SUNRISE_ALTITUDE_DEG, Direction::Setting);
    events.civil_dawn = sun_event(CIVIL_TWILIGHT_ALTITUDE_DEG, Direction::Rising);
    events.civil_dusk = sun_event(CIVIL_TWILIGHT_ALTITUDE_DEG, Direction::Setting);
    events.nautical_dawn = sun_event(NAUTICAL_TWILIGHT_ALTITUDE_DEG, Direction::Rising);
    events.nautical_dusk = sun_event(NAUTICAL_TWILIGHT_ALTITUDE_DEG, Direction::Setting);
    events.astronomical_dawn = sun_event(ASTRONOMICAL_TWILIGHT_ALTITUDE_DEG, Direction::Rising);
    events.astronomical_dusk = sun_event(ASTRONOMICAL_TWILIGHT_ALTITUDE_DEG, Direction::Setting);
    let mut moon_f = |s: f64| {
        let (alt, sd) = moon_altitude_deg(observer, &Geocentric::at(at(s)));
        alt + HORIZON_REFRACTION_DEG + sd
    };
    events.moonrise = first_crossing(t0, &moon_samples, Direction::Rising, &mut moon_f).map(at);
    events.moonset = first_crossing(t0, &moon_samples, Direction::Setting, &mut moon_f).map(at);
    events
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn local_day_follows_the_longitude() {
        let t = UtcTime::from_calendar(2024, 6, 21, 3, 0, 0.0).unwrap();
        // At 90° W local mean time is UTC - 6 h: 21:00 on the 20th; the day began at
        // 2024-06-20T06:00Z.
        let start = local_day_start(t, -90.0);
        assert_eq!(start.to_iso8601_seconds(), "2024-06-20T06:00:00Z");
        // At 0° the day is the UTC day.
        assert_eq!(
            local_day_start(t, 0.0).to_iso8601_seconds(),
            "2024-06-21T00:00:00Z"
        );
        // At 150° E local time is 13:00 on the 21st; the day began at 2024-06-20T14:00Z.
        assert_eq!(
            local_day_start(t, 150.0).to_iso8601_seconds(),
            "2024-06-20T14:00:00Z"
        );
    }
}
