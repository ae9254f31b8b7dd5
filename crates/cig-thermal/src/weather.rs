//! The weather that drives the surface temperatures: air temperature over the day, humidity,
//! wind, cloud, the sun's irradiance and the sky's long-wave irradiance.
//!
//! - Air temperature: the source's 24 hourly air temperatures before the simulated day
//!   (source 001, "Infrared Gray Level Prediction"), as an hourly table in local solar time
//!   (linear between hours, repeating daily), or from a diurnal minimum and maximum: the
//!   minimum at sunrise, the maximum at 14:00 local solar time, half-cosines between them
//!   (the shape of Parton and Logan, Agric. Meteorol. 23:205, 1981, without their
//!   exponential night decay). The host's current value shifts the whole curve
//!   ([`AirTemperature::with_offset_k`]).
//! - Saturation vapour pressure: Magnus form with Alduchov and Eskridge's constants (J. Appl.
//!   Meteor. 35:601, 1996): `e_s = 6.1094 exp(17.625 t / (t + 243.04))` hPa, t in C.
//! - Sky long-wave: Brutsaert's clear-sky emissivity (Water Resour. Res. 11:742, 1975)
//!   `eps = 1.24 (e / T)^(1/7)`, e in hPa, T in K, with Crawford and Duchon's cloud term
//!   `eps = N + (1 - N) eps_clear` (J. Appl. Meteor. 38:474, 1999): cloud radiates as a black
//!   body at the air temperature.
//! - Sun: Meinel's clear-sky direct normal irradiance `S0 0.7^(AM^0.678)` (Meinel and Meinel,
//!   *Applied Solar Energy*, 1976) with Kasten and Young's air mass (Appl. Opt. 28:4735, 1989),
//!   and Haurwitz's clear-sky global irradiance `1098 cos z exp(-0.057 / cos z)` (J. Meteor.
//!   2:154, 1945); the diffuse part is their difference. Cloud: Kasten and Czeplak's global
//!   reduction `1 - 0.75 N^3.4` (Solar Energy 24:177, 1980), the direct beam scaled by `1 - N`.
//! - Convection: McAdams' `h = 5.7 + 3.8 U` W m-2 K-1 (U wind speed, m/s).
//!
//! Limits: one weather for the whole served area; no rain wetting; the sun's beam is not
//! shadowed by terrain relief or by the model itself; the ground seen by a tilted surface is at
//! air temperature with albedo 0.2.

use crate::planck::STEFAN_BOLTZMANN;
use crate::ThermalError;
use cig_environment::UtcTime;

/// Zero Celsius, kelvin.
pub const CELSIUS_0_K: f64 = 273.15;
/// Solar constant, W m-2 (Kopp and Lean 2011).
pub const SOLAR_CONSTANT_W_M2: f64 = 1361.0;
/// Latent heat of vaporisation of water, J/kg (at about 20 C).
pub const LATENT_HEAT_J_KG: f64 = 2.45e6;
/// Specific heat of air at constant pressure, J kg-1 K-1.
pub const AIR_SPECIFIC_HEAT_J_KG_K: f64 = 1005.0;
/// Albedo of the ground a tilted surface sees.
pub const GROUND_ALBEDO: f64 = 0.2;

/// Air temperature through the day.
#[derive(Clone, Debug, PartialEq)]
pub enum AirTemperature {
    /// Minimum at sunrise, maximum at 14:00 local solar time, kelvin.
    Diurnal {
        /// Daily minimum, kelvin.
        min_k: f64,
        /// Daily maximum, kelvin.
        max_k: f64,
        /// Added to the curve (the host's current value), kelvin.
        offset_k: f64,
    },
    /// 24 values at 00:00..23:00 local solar time, kelvin; linear between them.
    Hourly {
        /// The hourly values, kelvin.
        hours_k: [f64; 24],
        /// Added to the table (the host's current value), kelvin.
        offset_k: f64,
    },
}

impl AirTemperature {
    /// A diurnal curve from its minimum and maximum, Celsius.
    pub fn diurnal_c(min_c: f64, max_c: f64) -> Result<AirTemperature, ThermalError> {
        for (name, v) in [("air minimum", min_c), ("air maximum", max_c)] {
            check_air_c(name, v)?;
        }
        if max_c < min_c {
            return Err(ThermalError::OutOfRange {
                name: "air maximum",
                value: max_c,
                expected: "at least the air minimum",
            });
        }
        Ok(AirTemperature::Diurnal {
            min_k: min_c + CELSIUS_0_K,
            max_k: max_c + CELSIUS_0_K,
            offset_k: 0.0,
        })
    }

    /// An hourly table, Celsius, at 00:00..23:00 local solar time.
    pub fn hourly_c(hours_c: &[f64]) -> Result<AirTemperature, ThermalError> {
        let hours: [f64; 24] = hours_c.try_into().map_err(|_| ThermalError::OutOfRange {
            name: "hourly air temperatures",
            value: hours_c.len() as f64,
            expected: "24 values",
        })?;
        for v in hours {
            check_air_c("hourly air temperature", v)?;
        }
        Ok(AirTemperature::Hourly {
            hours_k: hours.map(|c| c + CELSIUS_0_K),
            offset_k: 0.0,
        })
    }

    /// The same curve shifted so that it reads `current_k` at `time` (the host's value).
    pub fn with_current(&self, time: UtcTime, lat_deg: f64, lon_deg: f64, current_k: f64) -> Self {
        let mut base = self.clone();
        base.set_offset(0.0);
        let offset = current_k - base.at(time, lat_deg, lon_deg);
        base.set_offset(offset);
        base
    }

    fn set_offset(&mut self, offset: f64) {
        match self {
            AirTemperature::Diurnal { offset_k, .. } | AirTemperature::Hourly { offset_k, .. } => {
                *offset_k = offset
            }
        }
    }

    /// The mean of the curve over a day, kelvin (the deep-ground default).
    pub fn daily_mean_k(&self) -> f64 {
        match self {
            AirTemperature::Diurnal {
                min_k,
                max_k,
                offset_k,
            } => 0.5 * (min_k + max_k) + offset_k,
            AirTemperature::Hourly { hours_k, offset_k } => {
                hours_k.iter().sum::<f64>() / 24.0 + offset_k
            }
        }
    }

    /// Air temperature at `time` at a place, kelvin.
    pub fn at(&self, time: UtcTime, lat_deg: f64, lon_deg: f64) -> f64 {
        let hour = local_solar_hour(time, lon_deg);
        match self {
            AirTemperature::Hourly { hours_k, offset_k } => {
                let i = hour.floor() as usize % 24;
                let f = hour - hour.floor();
                hours_k[i] * (1.0 - f) + hours_k[(i + 1) % 24] * f + offset_k
            }
            AirTemperature::Diurnal {
                min_k,
                max_k,
                offset_k,
            } => {
                let rise = sunrise_solar_hour(time, lat_deg);
                const PEAK: f64 = 14.0;
                let range = max_k - min_k;
                let shape = if hour >= rise && hour <= PEAK {
                    0.5 * (1.0 - (std::f64::consts::PI * (hour - rise) / (PEAK - rise)).cos())
                } else {
                    let since_peak = (hour - PEAK).rem_euclid(24.0);
                    let night = 24.0 - PEAK + rise;
                    1.0 - 0.5 * (1.0 - (std::f64::consts::PI * since_peak / night).cos())
                };
                min_k + range * shape + offset_k
            }
        }
    }
}

fn check_air_c(name: &'static str, value_c: f64) -> Result<(), ThermalError> {
    if !(value_c.is_finite() && (-90.0..=60.0).contains(&value_c)) {
        return Err(ThermalError::OutOfRange {
            name,
            value: value_c,
            expected: "-90..60 C",
        });
    }
    Ok(())
}

/// Local mean solar time, hours in [0, 24).
pub fn local_solar_hour(time: UtcTime, lon_deg: f64) -> f64 {
    let day_fraction = (time.days_since_j2000() + 0.5).rem_euclid(1.0);
    (day_fraction * 24.0 + lon_deg / 15.0).rem_euclid(24.0)
}

/// Sunrise in local solar hours (from the declination of the day; polar day and night are
/// clamped to 02:00 and 10:00).
fn sunrise_solar_hour(time: UtcTime, lat_deg: f64) -> f64 {
    let day_of_year = time.to_calendar_day_of_year();
    let declination =
        23.44_f64.to_radians() * (2.0 * std::f64::consts::PI * (284.0 + day_of_year) / 365.0).sin();
    let cos_h = -lat_deg.to_radians().tan() * declination.tan();
    let h_deg = cos_h.clamp(-1.0, 1.0).acos().to_degrees();
    (12.0 - h_deg / 15.0).clamp(2.0, 10.0)
}

trait DayOfYear {
    fn to_calendar_day_of_year(&self) -> f64;
}

impl DayOfYear for UtcTime {
    fn to_calendar_day_of_year(&self) -> f64 {
        // Days since J2000 modulo the tropical year, shifted so 1 January is day 1.
        (self.days_since_j2000() + 0.5).rem_euclid(365.2422) + 1.0
    }
}

/// Saturation vapour pressure over water, hPa, at `temp_k`.
pub fn saturation_vapour_pressure_hpa(temp_k: f64) -> f64 {
    let t_c = temp_k - CELSIUS_0_K;
    6.1094 * (17.625 * t_c / (t_c + 243.04)).exp()
}

/// Saturation specific humidity at `temp_k` and sea-level pressure, kg/kg, and its slope
/// per kelvin.
pub fn saturation_specific_humidity(temp_k: f64) -> (f64, f64) {
    const PRESSURE_HPA: f64 = 1013.25;
    let e = saturation_vapour_pressure_hpa(temp_k);
    let t_c = temp_k - CELSIUS_0_K;
    let de_dt = e * 17.625 * 243.04 / ((t_c + 243.04) * (t_c + 243.04));
    let q = 0.622 * e / (PRESSURE_HPA - 0.378 * e);
    let dq_de = 0.622 * PRESSURE_HPA / ((PRESSURE_HPA - 0.378 * e) * (PRESSURE_HPA - 0.378 * e));
    (q, dq_de * de_dt)
}

/// Effective emissivity of the sky for air at `air_k`, relative humidity `rh_pct` and cloud
/// cover `cloud` (0..1): Brutsaert clear sky with Crawford and Duchon's cloud term.
pub fn sky_emissivity(air_k: f64, rh_pct: f64, cloud: f64) -> f64 {
    let e = saturation_vapour_pressure_hpa(air_k) * (rh_pct / 100.0).clamp(0.0, 1.0);
    let clear = (1.24 * (e.max(1e-3) / air_k).powf(1.0 / 7.0)).min(1.0);
    let cloud = cloud.clamp(0.0, 1.0);
    cloud + (1.0 - cloud) * clear
}

/// Downwelling long-wave irradiance from the sky on a horizontal surface, W m-2.
pub fn sky_longwave_w_m2(air_k: f64, rh_pct: f64, cloud: f64) -> f64 {
    sky_emissivity(air_k, rh_pct, cloud) * STEFAN_BOLTZMANN * air_k.powi(4)
}

/// McAdams' convective film coefficient for wind speed `wind_mps`, W m-2 K-1.
pub fn convection_w_m2_k(wind_mps: f64) -> f64 {
    5.7 + 3.8 * wind_mps.max(0.0)
}

/// The sun's irradiance at the ground.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SolarIrradiance {
    /// Direct beam on a surface facing the sun, W m-2.
    pub direct_normal_w_m2: f64,
    /// Diffuse sky irradiance on a horizontal surface, W m-2.
    pub diffuse_horizontal_w_m2: f64,
    /// Global (direct + diffuse) on a horizontal surface, W m-2.
    pub global_horizontal_w_m2: f64,
}

/// Solar irradiance for the sun at `altitude_deg` (geometric), `distance_au` and cloud cover.
pub fn solar_irradiance(altitude_deg: f64, distance_au: f64, cloud: f64) -> SolarIrradiance {
    if altitude_deg <= 0.0 {
        return SolarIrradiance {
            direct_normal_w_m2: 0.0,
            diffuse_horizontal_w_m2: 0.0,
            global_horizontal_w_m2: 0.0,
        };
    }
    let cos_z = altitude_deg.to_radians().sin();
    let zenith_deg = 90.0 - altitude_deg;
    // Kasten and Young (1989) air mass.
    let air_mass = 1.0 / (cos_z + 0.505_72 * (96.079_95 - zenith_deg).powf(-1.6364));
    let s0 = SOLAR_CONSTANT_W_M2 / (distance_au * distance_au);
    let dni_clear = s0 * 0.7_f64.powf(air_mass.powf(0.678));
    let ghi_clear = (1098.0 * cos_z * (-0.057 / cos_z).exp()).max(dni_clear * cos_z);
    let cloud = cloud.clamp(0.0, 1.0);
    let ghi = ghi_clear * (1.0 - 0.75 * cloud.powf(3.4));
    let dni = dni_clear * (1.0 - cloud);
    SolarIrradiance {
        direct_normal_w_m2: dni,
        diffuse_horizontal_w_m2: (ghi - dni * cos_z).max(0.0),
        global_horizontal_w_m2: ghi,
    }
}

/// The weather the thermal model is driven by.
#[derive(Clone, Debug, PartialEq)]
pub struct ThermalWeather {
    /// Air temperature over the day.
    pub air: AirTemperature,
    /// Relative humidity, percent 0..100.
    pub relative_humidity_pct: f64,
    /// Wind speed near the surface, m/s.
    pub wind_mps: f64,
    /// Cloud cover fraction, 0..1.
    pub cloud_cover: f64,
    /// Deep-ground temperature at the slabs' base (about 1 m), kelvin; `None` takes the air's
    /// daily mean.
    pub deep_ground_k: Option<f64>,
}

impl ThermalWeather {
    /// Checks every field's range.
    pub fn validate(&self) -> Result<(), ThermalError> {
        let checks: [(&'static str, f64, f64, f64, &'static str); 3] = [
            (
                "relative humidity",
                self.relative_humidity_pct,
                0.0,
                100.0,
                "0..100 %",
            ),
            ("wind speed", self.wind_mps, 0.0, 100.0, "0..100 m/s"),
            ("cloud cover", self.cloud_cover, 0.0, 1.0, "0..1"),
        ];
        for (name, value, lo, hi, expected) in checks {
            if !(value.is_finite() && value >= lo && value <= hi) {
                return Err(ThermalError::OutOfRange {
                    name,
                    value,
                    expected,
                });
            }
        }
        if let Some(t) = self.deep_ground_k {
            if !(t.is_finite() && t > 150.0 && t < 350.0) {
                return Err(ThermalError::OutOfRange {
                    name: "deep-ground temperature (K)",
                    value: t,
                    expected: "150..350 K",
                });
            }
        }
        Ok(())
    }

    /// The deep-ground temperature, kelvin.
    pub fn deep_ground_k(&self) -> f64 {
        self.deep_ground_k
            .unwrap_or_else(|| self.air.daily_mean_k())
    }
}

impl Default for ThermalWeather {
    /// A temperate clear day: 10..24 C, 50 % humidity, 3 m/s wind, no cloud.
    fn default() -> Self {
        ThermalWeather {
            air: AirTemperature::Diurnal {
                min_k: CELSIUS_0_K + 10.0,
                max_k: CELSIUS_0_K + 24.0,
                offset_k: 0.0,
            },
            relative_humidity_pct: 50.0,
            wind_mps: 3.0,
            cloud_cover: 0.0,
            deep_ground_k: None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn t(iso: &str) -> UtcTime {
        UtcTime::parse_iso8601(iso).expect("time")
    }

    #[test]
    fn diurnal_curve_has_its_minimum_near_sunrise_and_maximum_at_14() {
        let air = AirTemperature::diurnal_c(10.0, 24.0).expect("valid");
        // Longitude 0: local solar time = UTC.
        let max = air.at(t("2026-06-21T14:00:00Z"), 45.0, 0.0);
        assert!((max - (24.0 + CELSIUS_0_K)).abs() < 1e-9);
        let mut lowest = (f64::MAX, 0);
        for minute in 0..1440 {
            let v = air.at(
                t("2026-06-21T00:00:00Z").plus_seconds(minute as f64 * 60.0),
                45.0,
                0.0,
            );
            assert!((10.0 + CELSIUS_0_K - 1e-9..=24.0 + CELSIUS_0_K + 1e-9).contains(&v));
            if v < lowest.0 {
                lowest = (v, minute);
            }
        }
        // June sunrise at 45 N is about 04:20 local solar time.
        assert!((240..=290).contains(&lowest.1), "{}", lowest.1);
    }

    #[test]
    fn host_value_shifts_the_curve() {
        let air = AirTemperature::diurnal_c(10.0, 24.0).expect("valid");
        let now = t("2026-06-21T12:00:00Z");
        let shifted = air.with_current(now, 45.0, 0.0, CELSIUS_0_K + 30.0);
        assert!((shifted.at(now, 45.0, 0.0) - (CELSIUS_0_K + 30.0)).abs() < 1e-9);
        let later = now.plus_seconds(3600.0);
        let d = shifted.at(later, 45.0, 0.0) - air.at(later, 45.0, 0.0);
        assert!((d - (30.0 - (air.at(now, 45.0, 0.0) - CELSIUS_0_K))).abs() < 1e-9);
    }

    #[test]
    fn hourly_table_interpolates_and_repeats() {
        let hours: Vec<f64> = (0..24).map(|h| h as f64).collect();
        let air = AirTemperature::hourly_c(&hours).expect("valid");
        let v = air.at(t("2026-01-05T06:30:00Z"), 0.0, 0.0) - CELSIUS_0_K;
        assert!((v - 6.5).abs() < 1e-6, "{v}");
        let wrap = air.at(t("2026-01-05T23:30:00Z"), 0.0, 0.0) - CELSIUS_0_K;
        assert!((wrap - 11.5).abs() < 1e-6, "{wrap}");
        assert!(AirTemperature::hourly_c(&hours[..23]).is_err());
    }

    #[test]
    fn sky_is_colder_than_air_when_clear_and_near_it_when_overcast() {
        let air = 300.0;
        let clear = (sky_longwave_w_m2(air, 30.0, 0.0) / STEFAN_BOLTZMANN).powf(0.25);
        // The reference's worked cases: Brunt 275.7 K, Idso 288.3 K, Swinbank 286.8 K.
        assert!((274.0..290.0).contains(&clear), "{clear}");
        let overcast = (sky_longwave_w_m2(air, 80.0, 1.0) / STEFAN_BOLTZMANN).powf(0.25);
        assert!(overcast > 297.0, "{overcast}");
    }

    #[test]
    fn solar_irradiance_is_plausible() {
        let high = solar_irradiance(90.0, 1.0, 0.0);
        assert!(
            (850.0..1000.0).contains(&high.direct_normal_w_m2),
            "{high:?}"
        );
        assert!(
            (950.0..1100.0).contains(&high.global_horizontal_w_m2),
            "{high:?}"
        );
        assert!(
            (30.0..200.0).contains(&high.diffuse_horizontal_w_m2),
            "{high:?}"
        );
        let low = solar_irradiance(5.0, 1.0, 0.0);
        assert!(low.direct_normal_w_m2 < high.direct_normal_w_m2 / 2.0);
        assert_eq!(solar_irradiance(-1.0, 1.0, 0.0).global_horizontal_w_m2, 0.0);
        let cloudy = solar_irradiance(60.0, 1.0, 1.0);
        assert_eq!(cloudy.direct_normal_w_m2, 0.0);
        assert!(cloudy.diffuse_horizontal_w_m2 > 100.0, "{cloudy:?}");
    }

    #[test]
    fn weather_out_of_range_is_refused_naming_the_value() {
        let w = ThermalWeather {
            relative_humidity_pct: 120.0,
            ..ThermalWeather::default()
        };
        let e = w.validate().expect_err("bad");
        assert!(e.to_string().contains("120"), "{e}");
        assert!(AirTemperature::diurnal_c(20.0, 10.0).is_err());
        assert!(AirTemperature::diurnal_c(f64::NAN, 10.0).is_err());
    }
}
