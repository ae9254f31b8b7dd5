//! UTC instants, the Gregorian calendar, Julian dates and ΔT.
//!
//! Algorithm: an instant is held as seconds since J2000.0 on the UTC scale
//! (2000-01-01T12:00:00 UTC, Julian date 2451545.0), counting every day as
//! 86 400 s, as POSIX time does. Calendar conversion uses the proleptic
//! Gregorian day-count formulas of H. Hinnant, "chrono-Compatible Low-Level
//! Date Algorithms" (`days_from_civil`, `civil_from_days`). ΔT = TT − UT1
//! follows the polynomial expressions of F. Espenak and J. Meeus, *Five
//! Millennium Canon of Solar Eclipses* (NASA TP-2006-214141, section 2.6),
//! for 1900–2150.
//!
//! Limits: leap seconds are not represented (23:59:60 cannot be given) and
//! UTC is used as UT1 (they differ by less than 0.9 s, 0.004 degree of Earth
//! rotation). The supported range is 1900-01-01T00:00:00 to
//! 2100-12-31T23:59:59.999 UTC; the polynomial ΔT is within about a second of
//! the observed values over the 20th century and an extrapolation (uncertain
//! by a minute or more by 2100) after 2005. An error of a minute in ΔT moves
//! the moon by 0.01 degree and the sun by 0.0007 degree.

use crate::EnvironmentError;

/// Seconds per day.
pub const SECONDS_PER_DAY: f64 = 86_400.0;
/// Julian date of J2000.0 (2000-01-01T12:00:00).
pub const J2000_JD: f64 = 2_451_545.0;
/// Unix time of J2000.0 on the UTC scale.
const J2000_UNIX_S: f64 = 946_728_000.0;
/// First supported year.
pub const MIN_YEAR: i32 = 1900;
/// Last supported year.
pub const MAX_YEAR: i32 = 2100;

/// A UTC instant, seconds since J2000.0 (2000-01-01T12:00:00 UTC), 86 400 s a day.
/// Serialised as that number of seconds; deserialising checks the range.
#[derive(Clone, Copy, Debug, PartialEq, PartialOrd, serde::Serialize, serde::Deserialize)]
#[serde(try_from = "f64", into = "f64")]
pub struct UtcTime {
    seconds_since_j2000: f64,
}

impl TryFrom<f64> for UtcTime {
    type Error = EnvironmentError;

    fn try_from(seconds_since_j2000: f64) -> Result<Self, Self::Error> {
        UtcTime::from_seconds_since_j2000(seconds_since_j2000)
    }
}

impl From<UtcTime> for f64 {
    fn from(t: UtcTime) -> f64 {
        t.seconds_since_j2000
    }
}

/// A broken-down UTC calendar time.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CalendarTime {
    /// Gregorian year.
    pub year: i32,
    /// Month, 1..=12.
    pub month: u32,
    /// Day of the month, 1..=31.
    pub day: u32,
    /// Hour, 0..=23.
    pub hour: u32,
    /// Minute, 0..=59.
    pub minute: u32,
    /// Second with fraction, `[0, 60)`.
    pub second: f64,
}

/// Days since 1970-01-01 of a proleptic Gregorian date (Hinnant's `days_from_civil`).
fn days_from_civil(year: i64, month: i64, day: i64) -> i64 {
    let y = if month <= 2 { year - 1 } else { year };
    let era = y.div_euclid(400);
    let yoe = y - era * 400;
    let mp = (month + 9) % 12;
    let doy = (153 * mp + 2) / 5 + day - 1;
    let doe = yoe * 365 + yoe / 4 - yoe / 100 + doy;
    era * 146_097 + doe - 719_468
}

/// Proleptic Gregorian date of a day count since 1970-01-01 (Hinnant's `civil_from_days`).
fn civil_from_days(days: i64) -> (i64, u32, u32) {
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let day = doy - (153 * mp + 2) / 5 + 1;
    let month = if mp < 10 { mp + 3 } else { mp - 9 };
    let year = yoe + era * 400 + i64::from(month <= 2);
    // month is in 1..=12 and day in 1..=31 by construction.
    #[allow(
        clippy::cast_possible_truncation,
        clippy::cast_sign_loss,
        reason = "month and day are small positive numbers by construction"
    )]
    (year, month as u32, day as u32)
}

/// Number of days in a Gregorian month.
pub fn days_in_month(year: i32, month: u32) -> u32 {
    match month {
        1 | 3 | 5 | 7 | 8 | 10 | 12 => 31,
        4 | 6 | 9 | 11 => 30,
        2 if (year % 4 == 0 && year % 100 != 0) || year % 400 == 0 => 29,
        2 => 28,
        _ => 0,
    }
}

/// Seconds since J2000 of the first supported instant, 1900-01-01T00:00:00 UTC.
fn min_seconds() -> f64 {
    seconds_of(i64::from(MIN_YEAR), 1, 1)
}

/// Seconds since J2000 just past the last supported instant, 2101-01-01T00:00:00 UTC.
fn end_seconds() -> f64 {
    seconds_of(i64::from(MAX_YEAR) + 1, 1, 1)
}

/// Seconds since J2000 of midnight starting a date.
fn seconds_of(year: i64, month: i64, day: i64) -> f64 {
    // Day counts in the supported range are far below 2^53.
    #[allow(
        clippy::cast_precision_loss,
        reason = "day counts of the supported years are exact in f64"
    )]
    let days = days_from_civil(year, month, day) as f64;
    days * SECONDS_PER_DAY - J2000_UNIX_S
}

impl UtcTime {
    /// Parses an ISO 8601 instant: RFC 3339, or ISO 8601 with or without an offset (no offset
    /// means UTC), or a date alone (its midnight UTC).
    ///
    /// # Errors
    /// [`EnvironmentError::InvalidTime`] when the text is not such an instant or falls outside
    /// 1900..=2100.
    pub fn parse_iso8601(text: &str) -> Result<UtcTime, EnvironmentError> {
        use ::time::format_description::well_known::{Iso8601, Rfc3339};
        use ::time::{Date, OffsetDateTime, PrimitiveDateTime, UtcOffset};
        let parsed = OffsetDateTime::parse(text, &Rfc3339)
            .or_else(|_| OffsetDateTime::parse(text, &Iso8601::DEFAULT))
            .or_else(|_| PrimitiveDateTime::parse(text, &Iso8601::DEFAULT).map(|p| p.assume_utc()))
            .or_else(|_| Date::parse(text, &Iso8601::DEFAULT).map(|d| d.midnight().assume_utc()))
            .map_err(|e| {
                EnvironmentError::InvalidTime(format!(
                    "{text:?} is not an ISO 8601 date and time ({e})"
                ))
            })?;
        let utc = parsed
            .checked_to_offset(UtcOffset::UTC)
            .ok_or_else(|| EnvironmentError::InvalidTime(format!("{text:?} is out of range")))?;
        let second = f64::from(utc.second()) + f64::from(utc.nanosecond()) * 1e-9;
        UtcTime::from_calendar(
            utc.year(),
            u32::from(u8::from(utc.month())),
            u32::from(utc.day()),
            u32::from(utc.hour()),
            u32::from(utc.minute()),
            second,
        )
    }

    /// The instant of a UTC calendar time; `second` may carry a fraction.
    ///
    /// # Errors
    /// [`EnvironmentError::InvalidTime`] for a field out of range or a year
    /// outside 1900..=2100.
    pub fn from_calendar(
        year: i32,
        month: u32,
        day: u32,
        hour: u32,
        minute: u32,
        second: f64,
    ) -> Result<UtcTime, EnvironmentError> {
        let bad = |reason: &str| EnvironmentError::InvalidTime(reason.to_string());
        if !(MIN_YEAR..=MAX_YEAR).contains(&year) {
            return Err(bad(&format!(
                "year {year} is outside {MIN_YEAR}..={MAX_YEAR}"
            )));
        }
        if !(1..=12).contains(&month) {
            return Err(bad(&format!("month {month} is outside 1..=12")));
        }
        let last = days_in_month(year, month);
        if day == 0 || day > last {
            return Err(bad(&format!(
                "day {day} is outside 1..={last} for {year}-{month:02}"
            )));
        }
        if hour > 23 || minute > 59 {
            return Err(bad(&format!(
                "time {hour:02}:{minute:02} is not a clock time"
            )));
        }
        if !(0.0..60.0).contains(&second) {
            return Err(bad(&format!("second {second} is outside [0, 60)")));
        }
        let s = seconds_of(i64::from(year), i64::from(month), i64::from(day))
            + f64::from(hour) * 3600.0
            + f64::from(minute) * 60.0
            + second;
        Ok(UtcTime {
            seconds_since_j2000: s,
        })
    }

    /// The instant `seconds` after J2000.0 (UTC scale, 86 400 s a day).
    ///
    /// # Errors
    /// [`EnvironmentError::InvalidTime`] when not finite or outside 1900..=2100.
    pub fn from_seconds_since_j2000(seconds: f64) -> Result<UtcTime, EnvironmentError> {
        if !seconds.is_finite() || seconds < min_seconds() || seconds >= end_seconds() {
            return Err(EnvironmentError::InvalidTime(format!(
                "{seconds} s from J2000 is outside the years {MIN_YEAR}..={MAX_YEAR}"
            )));
        }
        Ok(UtcTime {
            seconds_since_j2000: seconds,
        })
    }

    /// The instant of a Julian date on the UTC scale.
    ///
    /// # Errors
    /// As [`UtcTime::from_seconds_since_j2000`].
    pub fn from_julian_date(jd_utc: f64) -> Result<UtcTime, EnvironmentError> {
        UtcTime::from_seconds_since_j2000((jd_utc - J2000_JD) * SECONDS_PER_DAY)
    }

    /// The instant of a Unix time (seconds since 1970-01-01T00:00:00 UTC).
    ///
    /// # Errors
    /// As [`UtcTime::from_seconds_since_j2000`].
    pub fn from_unix_seconds(unix_s: f64) -> Result<UtcTime, EnvironmentError> {
        UtcTime::from_seconds_since_j2000(unix_s - J2000_UNIX_S)
    }

    /// The supported instant nearest to `seconds` since J2000 (NaN gives J2000).
    pub fn clamped_from_seconds_since_j2000(seconds: f64) -> UtcTime {
        let s = if seconds.is_nan() { 0.0 } else { seconds };
        // The last representable instant before the end of 2100.
        let last = end_seconds() - 1e-3;
        UtcTime {
            seconds_since_j2000: s.clamp(min_seconds(), last),
        }
    }

    /// Seconds since J2000.0, UTC scale.
    pub fn seconds_since_j2000(&self) -> f64 {
        self.seconds_since_j2000
    }

    /// Unix time, seconds.
    pub fn unix_seconds(&self) -> f64 {
        self.seconds_since_j2000 + J2000_UNIX_S
    }

    /// Julian date, UTC scale (used as UT1).
    pub fn julian_date(&self) -> f64 {
        J2000_JD + self.seconds_since_j2000 / SECONDS_PER_DAY
    }

    /// Days since J2000.0 on the UTC (≈ UT1) scale.
    pub fn days_since_j2000(&self) -> f64 {
        self.seconds_since_j2000 / SECONDS_PER_DAY
    }

    /// ΔT = TT − UT1 at this instant, seconds (Espenak–Meeus polynomials).
    pub fn delta_t_s(&self) -> f64 {
        delta_t_s(self.decimal_year())
    }

    /// Julian ephemeris date (TT scale): the Julian date plus ΔT.
    pub fn julian_ephemeris_date(&self) -> f64 {
        self.julian_date() + self.delta_t_s() / SECONDS_PER_DAY
    }

    /// Days since J2000.0 on the TT scale.
    pub fn tt_days_since_j2000(&self) -> f64 {
        (self.seconds_since_j2000 + self.delta_t_s()) / SECONDS_PER_DAY
    }

    /// The year with fraction, for ΔT (mean Gregorian years from 2000.0).
    pub fn decimal_year(&self) -> f64 {
        // 2000-01-01T00:00 is 43 200 s before J2000.
        2000.0 + (self.seconds_since_j2000 + 43_200.0) / (365.2425 * SECONDS_PER_DAY)
    }

    /// This instant plus `seconds` (not range-checked: use the result only for arithmetic
    /// or clamp it).
    pub fn plus_seconds(&self, seconds: f64) -> UtcTime {
        UtcTime {
            seconds_since_j2000: self.seconds_since_j2000 + seconds,
        }
    }

    /// The UTC calendar time of this instant.
    pub fn to_calendar(&self) -> CalendarTime {
        // Instants made by `plus_seconds` may lie outside the supported range: keep the
        // day count small enough for exact integer arithmetic (NaN becomes 1970).
        let unix = self.unix_seconds();
        let days = (unix / SECONDS_PER_DAY).floor().clamp(-1e9, 1e9);
        let sod = unix - days * SECONDS_PER_DAY;
        // `days` is a whole number of the supported range (|days| < 2^31).
        #[allow(
            clippy::cast_possible_truncation,
            reason = "a whole day count of the supported range"
        )]
        let (year, month, day) = civil_from_days(days as i64);
        let hour = (sod / 3600.0).floor().clamp(0.0, 23.0);
        let minute = ((sod - hour * 3600.0) / 60.0).floor().clamp(0.0, 59.0);
        let second = (sod - hour * 3600.0 - minute * 60.0).clamp(0.0, 59.999_999_999);
        #[allow(
            clippy::cast_possible_truncation,
            clippy::cast_sign_loss,
            reason = "hour and minute are clamped whole numbers; the year is within i32"
        )]
        CalendarTime {
            year: year as i32,
            month,
            day,
            hour: hour as u32,
            minute: minute as u32,
            second,
        }
    }

    /// ISO 8601 text of this instant rounded to the nearest second, `YYYY-MM-DDTHH:MM:SSZ`.
    pub fn to_iso8601_seconds(&self) -> String {
        let rounded = UtcTime {
            seconds_since_j2000: self.seconds_since_j2000.round(),
        };
        let c = rounded.to_calendar();
        // The rounded seconds field is a whole number in 0..=59.
        #[allow(
            clippy::cast_possible_truncation,
            clippy::cast_sign_loss,
            reason = "a rounded seconds field in 0..=59"
        )]
        let s = c.second.round().min(59.0) as u32;
        format!(
            "{:04}-{:02}-{:02}T{:02}:{:02}:{:02}Z",
            c.year, c.month, c.day, c.hour, c.minute, s
        )
    }
}

/// ΔT = TT − UT1 in seconds for a decimal year, by the Espenak–Meeus polynomials
/// (NASA TP-2006-214141). Years before 1900 use the 1900 expression and years
/// after 2150 the 2050–2150 one; both are outside this crate's supported range.
pub fn delta_t_s(year: f64) -> f64 {
    if year < 1920.0 {
        let t = year - 1900.0;
        -2.79 + t * (1.494_119 + t * (-0.059_893_9 + t * (0.006_196_6 - 0.000_197 * t)))
    } else if year < 1941.0 {
        let t = year - 1920.0;
        21.20 + t * (0.844_93 + t * (-0.076_100 + 0.002_093_6 * t))
    } else if year < 1961.0 {
        let t = year - 1950.0;
        29.07 + 0.407 * t - t * t / 233.0 + t * t * t / 2547.0
    } else if year < 1986.0 {
        let t = year - 1975.0;
        45.45 + 1.067 * t - t * t / 260.0 - t * t * t / 718.0
    } else if year < 2005.0 {
        let t = year - 2000.0;
        63.86
            + t * (0.3345
                + t * (-0.060_374 + t * (0.001_727_5 + t * (0.000_651_814 + 0.000_023_735_99 * t))))
    } else if year < 2050.0 {
        let t = year - 2000.0;
        62.92 + 0.32217 * t + 0.005_589 * t * t
    } else {
        let u = (year - 1820.0) / 100.0;
        -20.0 + 32.0 * u * u - 0.5628 * (2150.0 - year)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn j2000_is_jd_2451545() {
        let t = UtcTime::from_calendar(2000, 1, 1, 12, 0, 0.0).unwrap();
        assert_eq!(t.seconds_since_j2000(), 0.0);
        assert_eq!(t.julian_date(), 2_451_545.0);
        // Meeus Example 7.a: 1957 October 4.81 is JD 2436116.31.
        let sputnik = UtcTime::from_calendar(1957, 10, 4, 19, 26, 24.0).unwrap();
        assert!((sputnik.julian_date() - 2_436_116.31).abs() < 1e-9);
        // Unix epoch.
        let unix0 = UtcTime::from_calendar(1970, 1, 1, 0, 0, 0.0).unwrap();
        assert_eq!(unix0.unix_seconds(), 0.0);
    }

    #[test]
    fn range_and_fields_are_checked() {
        assert!(UtcTime::from_calendar(1899, 12, 31, 23, 59, 59.0).is_err());
        assert!(UtcTime::from_calendar(2101, 1, 1, 0, 0, 0.0).is_err());
        assert!(UtcTime::from_calendar(2100, 12, 31, 23, 59, 59.5).is_ok());
        assert!(UtcTime::from_calendar(1900, 2, 29, 0, 0, 0.0).is_err());
        assert!(UtcTime::from_calendar(2000, 2, 29, 0, 0, 0.0).is_ok());
        assert!(UtcTime::from_calendar(2000, 13, 1, 0, 0, 0.0).is_err());
        assert!(UtcTime::from_calendar(2000, 1, 1, 24, 0, 0.0).is_err());
        assert!(UtcTime::from_calendar(2000, 1, 1, 0, 0, 60.0).is_err());
        assert!(UtcTime::from_calendar(2000, 1, 1, 0, 0, f64::NAN).is_err());
        assert!(UtcTime::from_seconds_since_j2000(f64::INFINITY).is_err());
        assert!(UtcTime::from_julian_date(2_415_020.5).is_ok()); // 1900-01-01T00:00
        assert!(UtcTime::from_julian_date(2_415_020.4).is_err());
    }

    #[test]
    fn delta_t_matches_published_values() {
        // Espenak & Meeus tabulate about 63.8 s for 2000.0, 64.7 s for 2005, 23.6 s
        // (1930), 29.1 s (1950), 45.5 s (1975), and the polynomials join at 2050.
        assert!((delta_t_s(2000.0) - 63.86).abs() < 0.01);
        assert!((delta_t_s(2005.0) - 64.69).abs() < 0.1);
        assert!((delta_t_s(1930.0) - 24.0).abs() < 0.5);
        assert!((delta_t_s(1950.0) - 29.07).abs() < 0.01);
        assert!((delta_t_s(1975.0) - 45.45).abs() < 0.01);
        assert!((delta_t_s(2_049.999_999) - delta_t_s(2050.0)).abs() < 0.1);
    }

    #[test]
    fn iso_text_rounds_to_the_second() {
        let t = UtcTime::from_calendar(2024, 12, 31, 23, 59, 59.6).unwrap();
        assert_eq!(t.to_iso8601_seconds(), "2025-01-01T00:00:00Z");
        let t = UtcTime::from_calendar(1903, 3, 4, 5, 6, 7.2).unwrap();
        assert_eq!(t.to_iso8601_seconds(), "1903-03-04T05:06:07Z");
    }

    #[test]
    fn odd_instants_never_panic() {
        let t = UtcTime::from_calendar(2000, 1, 1, 0, 0, 0.0).unwrap();
        for s in [f64::NAN, f64::INFINITY, -f64::INFINITY, 1e300, -1e300] {
            let odd = t.plus_seconds(s);
            let _ = odd.to_calendar();
            let _ = odd.to_iso8601_seconds();
            let _ = odd.delta_t_s();
        }
        let json = serde_json::to_string(&t).unwrap();
        assert_eq!(serde_json::from_str::<UtcTime>(&json).unwrap(), t);
        assert!(serde_json::from_str::<UtcTime>("1e300").is_err());
    }

    proptest! {
        #[test]
        fn calendar_round_trip(year in 1900i32..=2100, month in 1u32..=12, day in 1u32..=31,
                               hour in 0u32..24, minute in 0u32..60, second in 0.0f64..59.999) {
            prop_assume!(day <= days_in_month(year, month));
            let t = UtcTime::from_calendar(year, month, day, hour, minute, second).unwrap();
            let c = t.to_calendar();
            prop_assert_eq!((c.year, c.month, c.day, c.hour, c.minute), (year, month, day, hour, minute));
            prop_assert!((c.second - second).abs() < 1e-5);
            let back = UtcTime::from_julian_date(t.julian_date()).unwrap();
            prop_assert!((back.seconds_since_j2000() - t.seconds_since_j2000()).abs() < 1e-4);
        }
    }
}
