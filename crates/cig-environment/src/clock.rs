//! The simulation clock (the thesis's passage of time) and the light state it
//! drives.
//!
//! Algorithm: the clock keeps its start instant and the simulated seconds
//! elapsed since it, `elapsed += rate × real_dt` while running (NPS thesis
//! chapter V.A.2 calls the rate "minutes per minute"; here it is simulated
//! seconds per real second, the same ratio). Keeping the elapsed seconds
//! separately from the J2000-based start keeps sub-microsecond resolution for
//! centuries of simulated time, so the sun moves smoothly every frame instead of
//! the thesis's once-a-minute update. Rates are finite and not negative (time
//! does not run backwards here: DIS and CIGI hosts only ever set it forward or
//! jump it); a rate of 0 freezes time like a pause. At the end of the supported
//! range (2100-12-31) the clock stops.
//!
//! The light state: the sun's and the moon's unit direction in the observer's
//! east-north-up frame (geometric, from [`crate::ephemeris`]), their
//! illuminance in lux ([`crate::illuminance`]) and a linear-RGB colour of their
//! direct light, and the night-sky background. The colour is the clear-sky
//! transmittance `exp(−τ(λ) m)` at 680, 550 and 440 nm, normalised to its
//! largest channel, with the Rayleigh optical depth of Hansen and Travis
//! (*Space Sci. Rev.* 16, 527, 1974, eq. 2.29), an Ångström aerosol depth
//! `0.1 λ^−1.3` (λ in µm; a clear continental atmosphere), and the air mass of
//! F. Kasten and A. T. Young (*Applied Optics* 28, 4735, 1989) on the apparent
//! altitude, held at its horizon value below the horizon. Limits: a fixed clear
//! atmosphere (no humidity, no volcanic aerosol); the colour of moonlight is
//! taken as that of sunlight at the same altitude.

use crate::ephemeris::{ephemeris, Observer};
use crate::illuminance::natural_illuminance;
use crate::time::UtcTime;
use crate::EnvironmentError;

/// The largest accepted rate, simulated seconds per real second (one simulated
/// year per real minute).
pub const MAX_RATE: f64 = 525_960.0;

/// A simulation clock: start instant, rate, pause.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SimClock {
    start: UtcTime,
    elapsed_sim_s: f64,
    /// Kahan compensation of the elapsed-time sum (rounding carried between frames).
    elapsed_compensation_s: f64,
    rate: f64,
    paused: bool,
}

fn check_rate(rate: f64) -> Result<f64, EnvironmentError> {
    if !(0.0..=MAX_RATE).contains(&rate) {
        return Err(EnvironmentError::InvalidSetting(format!(
            "clock rate {rate} is outside [0, {MAX_RATE}] simulated seconds per second"
        )));
    }
    Ok(rate)
}

impl SimClock {
    /// A running clock at `start` advancing `rate` simulated seconds per real second.
    ///
    /// # Errors
    /// [`EnvironmentError::InvalidSetting`] for a negative, non-finite or too large rate.
    pub fn new(start: UtcTime, rate: f64) -> Result<SimClock, EnvironmentError> {
        Ok(SimClock {
            start,
            elapsed_sim_s: 0.0,
            elapsed_compensation_s: 0.0,
            rate: check_rate(rate)?,
            paused: false,
        })
    }

    /// Advance by `real_elapsed_s` seconds of real time; returns the new time.
    ///
    /// # Errors
    /// [`EnvironmentError::InvalidSetting`] for a negative or non-finite interval
    /// (the clock is left unchanged).
    pub fn advance(&mut self, real_elapsed_s: f64) -> Result<UtcTime, EnvironmentError> {
        if !(real_elapsed_s >= 0.0 && real_elapsed_s.is_finite()) {
            return Err(EnvironmentError::InvalidSetting(format!(
                "real elapsed time {real_elapsed_s} s is not a non-negative number"
            )));
        }
        if !self.paused {
            // Kahan summation: no drift over millions of frames.
            let y = self.rate * real_elapsed_s - self.elapsed_compensation_s;
            let next = self.elapsed_sim_s + y;
            self.elapsed_compensation_s = (next - self.elapsed_sim_s) - y;
            // Stop at the end of the supported range.
            let end = UtcTime::clamped_from_seconds_since_j2000(f64::MAX).seconds_since_j2000();
            let max_elapsed = end - self.start.seconds_since_j2000();
            if next >= max_elapsed {
                self.elapsed_compensation_s = 0.0;
            }
            self.elapsed_sim_s = next.min(max_elapsed);
        }
        Ok(self.now())
    }

    /// The current simulated instant.
    pub fn now(&self) -> UtcTime {
        UtcTime::clamped_from_seconds_since_j2000(
            self.start.seconds_since_j2000() + self.elapsed_sim_s,
        )
    }

    /// Simulated seconds per real second.
    pub fn rate(&self) -> f64 {
        self.rate
    }

    /// Change the rate from now on (time stays continuous).
    ///
    /// # Errors
    /// As [`SimClock::new`]; the clock is left unchanged.
    pub fn set_rate(&mut self, rate: f64) -> Result<(), EnvironmentError> {
        self.rate = check_rate(rate)?;
        Ok(())
    }

    /// Stop the passage of time.
    pub fn pause(&mut self) {
        self.paused = true;
    }

    /// Let time pass again.
    pub fn resume(&mut self) {
        self.paused = false;
    }

    /// Whether the clock is paused.
    pub fn is_paused(&self) -> bool {
        self.paused
    }

    /// Jump to a new instant (keeps the rate and the pause state).
    pub fn set_time(&mut self, time: UtcTime) {
        self.start = time;
        self.elapsed_sim_s = 0.0;
        self.elapsed_compensation_s = 0.0;
    }
}

/// The direct light of one body.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BodyLight {
    /// Unit vector from the observer toward the body, east-north-up.
    pub direction_enu: [f64; 3],
    /// Linear RGB colour of the direct light, largest channel 1.
    pub color_linear_rgb: [f64; 3],
    /// Illuminance on horizontal ground from this body, lux (sky condition applied).
    pub illuminance_lux: f64,
    /// Geometric altitude of the body's centre, degrees.
    pub altitude_deg: f64,
}

/// What the renderer needs from the sky at one instant.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightState {
    /// The instant.
    pub time: UtcTime,
    /// Sunlight (its illuminance includes the daylight sky).
    pub sun: BodyLight,
    /// Moonlight.
    pub moon: BodyLight,
    /// Night-sky background, lux.
    pub night_sky_lux: f64,
    /// Total natural illuminance, lux.
    pub total_illuminance_lux: f64,
    /// Moon phase angle, degrees (0 full, 180 new).
    pub moon_phase_angle_deg: f64,
    /// Illuminated fraction of the moon.
    pub moon_illuminated_fraction: f64,
}

impl LightState {
    /// The brighter of sun and moon (the thesis's single light source).
    pub fn key_light(&self) -> &BodyLight {
        if self.moon.illuminance_lux > self.sun.illuminance_lux {
            &self.moon
        } else {
            &self.sun
        }
    }
}

/// Clear-sky transmittance colour at 680, 550 and 440 nm for an apparent
/// altitude, normalised to the largest channel.
pub fn direct_light_color(apparent_altitude_deg: f64) -> [f64; 3] {
    let h = if apparent_altitude_deg.is_finite() {
        apparent_altitude_deg.clamp(0.0, 90.0)
    } else {
        90.0
    };
    // Kasten and Young (1989).
    let air_mass = 1.0 / (h.to_radians().sin() + 0.505_72 * (h + 6.079_95).powf(-1.6364));
    let depth = |lambda_um: f64| {
        let l2 = lambda_um * lambda_um;
        let rayleigh = 0.008_569 / (l2 * l2) * (1.0 + 0.0113 / l2 + 0.000_13 / (l2 * l2));
        let aerosol = 0.1 * lambda_um.powf(-1.3);
        rayleigh + aerosol
    };
    let t = [0.68, 0.55, 0.44].map(|l| (-depth(l) * air_mass).exp());
    let max = t.iter().copied().fold(f64::MIN_POSITIVE, f64::max);
    t.map(|c| c / max)
}

/// The light state for an observer at an instant, with a cloud-cover fraction in `[0, 1]`.
///
/// # Errors
/// [`EnvironmentError::InvalidSetting`] for a cloud cover outside `[0, 1]`.
pub fn light_state(
    observer: &Observer,
    time: UtcTime,
    cloud_cover_fraction: f64,
) -> Result<LightState, EnvironmentError> {
    let e = ephemeris(observer, time);
    let lux = natural_illuminance(&e, cloud_cover_fraction)?;
    let body = |p: &crate::BodyPosition, illuminance_lux: f64| BodyLight {
        direction_enu: p.direction_enu,
        color_linear_rgb: direct_light_color(p.apparent_altitude_deg),
        illuminance_lux,
        altitude_deg: p.altitude_deg,
    };
    Ok(LightState {
        time,
        sun: body(&e.sun, lux.sun_lux),
        moon: body(&e.moon, lux.moon_lux),
        night_sky_lux: lux.sky_lux,
        total_illuminance_lux: lux.total_lux,
        moon_phase_angle_deg: e.moon_phase_angle_deg,
        moon_illuminated_fraction: e.moon_illuminated_fraction,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn start() -> UtcTime {
        UtcTime::from_calendar(2024, 6, 21, 12, 0, 0.0).unwrap()
    }

    #[test]
    fn clock_runs_pauses_and_changes_rate() {
        let mut c = SimClock::new(start(), 60.0).unwrap();
        c.advance(1.0).unwrap();
        assert_eq!(
            c.now().seconds_since_j2000() - start().seconds_since_j2000(),
            60.0
        );
        c.pause();
        c.advance(10.0).unwrap();
        assert_eq!(
            c.now().seconds_since_j2000() - start().seconds_since_j2000(),
            60.0
        );
        c.resume();
        c.set_rate(0.0).unwrap();
        c.advance(10.0).unwrap();
        assert_eq!(
            c.now().seconds_since_j2000() - start().seconds_since_j2000(),
            60.0
        );
        c.set_rate(1.0).unwrap();
        c.advance(0.5).unwrap();
        assert_eq!(
            c.now().seconds_since_j2000() - start().seconds_since_j2000(),
            60.5
        );
        assert!(c.set_rate(-1.0).is_err());
        assert!(c.set_rate(f64::NAN).is_err());
        assert!(c.advance(-1.0).is_err());
        assert!(c.advance(f64::INFINITY).is_err());
        assert_eq!(c.rate(), 1.0);
        assert!(SimClock::new(start(), -2.0).is_err());
    }

    #[test]
    fn clock_stops_at_the_end_of_2100() {
        let late = UtcTime::from_calendar(2100, 12, 31, 23, 0, 0.0).unwrap();
        let mut c = SimClock::new(late, MAX_RATE).unwrap();
        let t = c.advance(3600.0).unwrap();
        assert_eq!(t.to_calendar().year, 2100);
    }

    #[test]
    fn sixty_hertz_frames_accumulate_without_drift() {
        // One simulated day at 1 s/s in 1/60 s frames ends within a microsecond of a day.
        let mut c = SimClock::new(start(), 1.0).unwrap();
        for _ in 0..(86_400 * 60) {
            c.advance(1.0 / 60.0).unwrap();
        }
        let dt = c.now().seconds_since_j2000() - start().seconds_since_j2000();
        assert!((dt - 86_400.0).abs() < 1e-6, "{dt}");
    }

    #[test]
    fn light_colour_reddens_toward_the_horizon() {
        let noon = direct_light_color(80.0);
        let low = direct_light_color(2.0);
        assert!(noon[2] > 0.7, "{noon:?}");
        assert!(low[2] < 0.2 * low[0], "{low:?}");
        assert_eq!(low[0], 1.0);
    }

    #[test]
    fn key_light_is_the_sun_by_day_and_the_moon_on_a_moonlit_night() {
        let obs = Observer::new(35.0, -120.0, 0.0).unwrap();
        // 2024-06-21T20:00Z is local noon-ish at 120° W.
        let day = light_state(
            &obs,
            UtcTime::from_calendar(2024, 6, 21, 20, 0, 0.0).unwrap(),
            0.0,
        )
        .unwrap();
        assert!(day.sun.direction_enu[2] > 0.9);
        assert!(std::ptr::eq(day.key_light(), &day.sun));
        // Full moon 2024-06-22 01:08Z; at 2024-06-22T09:00Z (01:00 local) the moon is up.
        let night = light_state(
            &obs,
            UtcTime::from_calendar(2024, 6, 22, 9, 0, 0.0).unwrap(),
            0.0,
        )
        .unwrap();
        assert!(night.moon.altitude_deg > 10.0, "{:?}", night.moon);
        assert!(std::ptr::eq(night.key_light(), &night.moon));
        assert!(night.moon_illuminated_fraction > 0.95);
        let cloudy = light_state(
            &obs,
            UtcTime::from_calendar(2024, 6, 22, 9, 0, 0.0).unwrap(),
            1.0,
        )
        .unwrap();
        assert!((night.total_illuminance_lux / cloudy.total_illuminance_lux - 10.0).abs() < 1e-9);
    }

    proptest! {
        #[test]
        fn light_changes_smoothly_frame_to_frame(s in -3.0e9f64..3.0e9, lat in -70.0f64..70.0, lon in -180.0f64..180.0) {
            // At 60x real time and 60 Hz, a frame is 1 simulated second: the sun moves
            // at most 0.0042° and the illuminance by well under 1 %.
            let obs = Observer::new(lat, lon, 0.0).unwrap();
            let t = UtcTime::from_seconds_since_j2000(s).unwrap();
            let a = light_state(&obs, t, 0.0).unwrap();
            let b = light_state(&obs, t.plus_seconds(1.0), 0.0).unwrap();
            let dot: f64 = a.sun.direction_enu.iter().zip(b.sun.direction_enu.iter()).map(|(x, y)| x * y).sum();
            prop_assert!(dot.clamp(-1.0, 1.0).acos().to_degrees() < 0.0045);
            let ratio = b.total_illuminance_lux / a.total_illuminance_lux;
            prop_assert!((ratio - 1.0).abs() < 0.01, "{ratio}");
        }
    }
}
