//! Plume dispersion: McMullen's fit of the Pasquill-Gifford sigma curves and the choice of the
//! Pasquill stability class.
//!
//! Algorithm: `sigma = exp(I + J ln x + K (ln x)^2)` with `x` the downwind distance in km and
//! sigma in metres (McMullen 1975, as given by Beychok and by the thesis, source 000 chapter
//! III.A.1, Eq 6), with the rural constants of the thesis's Table 1 for classes A-F. The scan lost
//! the minus signs of Table 1; the signs used here are those listed in `shared/sources/INDEX.md`
//! (Kz: A +0.2770, B +0.0136, C -0.0020, D -0.0316, E -0.0450, F -0.0540; every Ky negative).
//! The "Iz" columns are the vertical sigma; sigma_z is capped at 5000 m (as the EPA models do).
//!
//! The class, unless set, comes from Turner's key to the Pasquill-Gifford categories (Turner
//! 1964, as tabulated in EPA-454/R-99-005 section 6.4.1): a net radiation index from the solar
//! altitude (insolation class 4 above 60 degrees, 3 above 35, 2 above 15, else 1), cloud cover
//! and ceiling (overcast below 7000 ft: 0 day or night; night: -2 with cover <= 4/10, else -1;
//! day with cover > 5/10: minus 2 below a 7000 ft ceiling, minus 1 below 16000 ft or when
//! overcast, never below 1), then the table of class against wind speed in whole knots and the
//! index. Turner's class 7 (G) is reported as F, as the EPA's regulatory models do.
//!
//! Limits: Eq 6 is a fit for rural, open, level terrain and sampling times of about ten minutes;
//! it is used exactly on 0.1-100 km. Below 100 m and beyond 100 km the curve is continued as a
//! power law with the fit's own slope at the end point (d ln sigma / d ln x = J + 2 K ln x), so
//! sigma is monotone, tends to 0 at the source and has no unphysical upturn (class A's sigma_z
//! fit would otherwise grow again below 22 m). "Night" is taken as a sun elevation below 0
//! degrees (Turner counts from one hour before sunset to one hour after sunrise); urban
//! dispersion is not modelled.

use crate::error::{non_negative, EffectsError};
use std::fmt;
use std::str::FromStr;

/// Pasquill stability class: A is the most unstable, D neutral, F the most stable.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum StabilityClass {
    A,
    B,
    C,
    D,
    E,
    F,
}

impl StabilityClass {
    /// Every class, most unstable first.
    pub const ALL: [StabilityClass; 6] = [
        StabilityClass::A,
        StabilityClass::B,
        StabilityClass::C,
        StabilityClass::D,
        StabilityClass::E,
        StabilityClass::F,
    ];

    /// The class letter.
    pub fn letter(self) -> char {
        match self {
            StabilityClass::A => 'A',
            StabilityClass::B => 'B',
            StabilityClass::C => 'C',
            StabilityClass::D => 'D',
            StabilityClass::E => 'E',
            StabilityClass::F => 'F',
        }
    }

    /// Whether the class is stable (E, F): Briggs's stable plume rise applies.
    pub fn is_stable(self) -> bool {
        matches!(self, StabilityClass::E | StabilityClass::F)
    }

    /// The potential temperature gradient the EPA's ISC3 model assumes for the class, K/m:
    /// 0.020 for E, 0.035 for F, 0 (neutral or unstable) otherwise.
    pub fn default_dtheta_dz_k_per_m(self) -> f64 {
        match self {
            StabilityClass::E => 0.020,
            StabilityClass::F => 0.035,
            _ => 0.0,
        }
    }

    /// McMullen's constants for sigma_y (crosswind) and sigma_z (vertical): Table 1 of the thesis
    /// with the signs restored.
    pub fn mcmullen_constants(self) -> (McMullen, McMullen) {
        let (iz, jz, kz, iy, jy, ky) = match self {
            StabilityClass::A => (6.035, 2.1097, 0.2770, 5.357, 0.8828, -0.0076),
            StabilityClass::B => (4.694, 1.0629, 0.0136, 5.058, 0.9024, -0.0096),
            StabilityClass::C => (4.110, 0.9201, -0.0020, 4.651, 0.9181, -0.0076),
            StabilityClass::D => (3.414, 0.7371, -0.0316, 4.230, 0.9222, -0.0087),
            StabilityClass::E => (3.057, 0.6794, -0.0450, 3.922, 0.9222, -0.0064),
            StabilityClass::F => (2.621, 0.6564, -0.0540, 3.533, 0.9181, -0.0070),
        };
        (
            McMullen {
                i: iy,
                j: jy,
                k: ky,
            },
            McMullen {
                i: iz,
                j: jz,
                k: kz,
            },
        )
    }
}

impl fmt::Display for StabilityClass {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.letter())
    }
}

impl FromStr for StabilityClass {
    type Err = EffectsError;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s.trim().to_ascii_uppercase().as_str() {
            "A" => Ok(StabilityClass::A),
            "B" => Ok(StabilityClass::B),
            "C" => Ok(StabilityClass::C),
            "D" => Ok(StabilityClass::D),
            "E" => Ok(StabilityClass::E),
            "F" => Ok(StabilityClass::F),
            _ => Err(EffectsError::UnknownStabilityClass(s.to_string())),
        }
    }
}

/// The three constants of McMullen's equation (Eq 6).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct McMullen {
    pub i: f64,
    pub j: f64,
    pub k: f64,
}

/// Upper end of the sigma_z values the models use, metres.
pub const SIGMA_Z_CAP_M: f64 = 5000.0;
/// Lower end of the distances on which Eq 6 is used as written, km.
pub const FIT_MIN_KM: f64 = 0.1;
/// Upper end of the distances on which Eq 6 is used as written, km.
pub const FIT_MAX_KM: f64 = 100.0;

impl McMullen {
    /// Eq 6 as written: `exp(I + J ln x + K (ln x)^2)`, `x` in km, metres out. No range checks.
    pub fn eq6_m(self, x_km: f64) -> f64 {
        let l = libm::log(x_km);
        libm::exp(self.i + self.j * l + self.k * l * l)
    }

    /// Eq 6 on 0.1-100 km, continued outside as a power law with the fit's slope at the end
    /// point. `x_km` must be >= 0; 0 gives 0.
    pub fn sigma_m(self, x_km: f64) -> f64 {
        if x_km <= 0.0 {
            return 0.0;
        }
        self.sigma_from_ln_km(libm::log(x_km))
    }

    /// [`Self::sigma_m`] from `ln(x_km)` (one logarithm serves sigma_y and sigma_z).
    pub fn sigma_from_ln_km(self, l: f64) -> f64 {
        // ln 0.1 and ln 100.
        const LN_MIN: f64 = -std::f64::consts::LN_10;
        const LN_MAX: f64 = 2.0 * std::f64::consts::LN_10;
        let e = l.clamp(LN_MIN, LN_MAX);
        // Inside the fit the last term is 0 and this is Eq 6 as written.
        libm::exp(self.i + self.j * e + self.k * e * e + (self.j + 2.0 * self.k * e) * (l - e))
    }
}

/// Crosswind and vertical dispersion of a plume at one downwind distance.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sigmas {
    /// Crosswind standard deviation, metres.
    pub y_m: f64,
    /// Vertical standard deviation, metres (capped at 5000 m).
    pub z_m: f64,
}

/// sigma_y and sigma_z at `downwind_m` metres for a class. Errors on a negative or non-finite
/// distance.
pub fn sigmas(class: StabilityClass, downwind_m: f64) -> Result<Sigmas, EffectsError> {
    let x = non_negative("downwind distance (m)", downwind_m)?;
    Ok(sigmas_unchecked(class, x))
}

/// [`sigmas`] for a distance already known to be finite and >= 0.
pub(crate) fn sigmas_unchecked(class: StabilityClass, downwind_m: f64) -> Sigmas {
    if downwind_m <= 0.0 {
        return Sigmas { y_m: 0.0, z_m: 0.0 };
    }
    let (y, z) = class.mcmullen_constants();
    let l = libm::log(downwind_m / 1000.0);
    Sigmas {
        y_m: y.sigma_from_ln_km(l),
        z_m: z.sigma_from_ln_km(l).min(SIGMA_Z_CAP_M),
    }
}

/// Weather that sets the Pasquill class when it is not given.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PasquillWeather {
    /// Surface (10 m) wind speed, m/s.
    pub wind_speed_mps: f64,
    /// Elevation of the sun's centre above the horizon, degrees (negative at night).
    pub sun_elevation_deg: f64,
    /// Total cloud cover, 0 (clear) to 1 (overcast).
    pub cloud_cover_fraction: f64,
    /// Cloud ceiling above ground, metres (`f64::INFINITY` for no ceiling).
    pub cloud_ceiling_m: f64,
}

const FEET_M: f64 = 0.3048;
const KNOTS_PER_MPS: f64 = 3600.0 / 1852.0;

/// Turner's net radiation index (-2..=4) for the weather.
pub fn net_radiation_index(w: &PasquillWeather) -> Result<i8, EffectsError> {
    non_negative("wind speed (m/s)", w.wind_speed_mps)?;
    crate::error::finite("sun elevation (deg)", w.sun_elevation_deg)?;
    let cover = non_negative("cloud cover (fraction)", w.cloud_cover_fraction)?;
    if cover > 1.0 {
        return Err(EffectsError::OutOfRange {
            name: "cloud cover (fraction)",
            value: cover,
            expected: "between 0 and 1",
        });
    }
    if w.cloud_ceiling_m.is_nan() || w.cloud_ceiling_m < 0.0 {
        return Err(EffectsError::OutOfRange {
            name: "cloud ceiling (m)",
            value: w.cloud_ceiling_m,
            expected: "a number >= 0 (infinity for no ceiling)",
        });
    }
    // Cover in tenths, as observers report it.
    let tenths = libm::round(cover * 10.0);
    let low_ceiling = w.cloud_ceiling_m < 7000.0 * FEET_M;
    if tenths >= 10.0 && low_ceiling {
        return Ok(0);
    }
    if w.sun_elevation_deg < 0.0 {
        return Ok(if tenths <= 4.0 { -2 } else { -1 });
    }
    let insolation: i8 = if w.sun_elevation_deg > 60.0 {
        4
    } else if w.sun_elevation_deg > 35.0 {
        3
    } else if w.sun_elevation_deg > 15.0 {
        2
    } else {
        1
    };
    if tenths <= 5.0 {
        return Ok(insolation);
    }
    let reduction = if tenths >= 10.0 {
        1 // overcast with the ceiling at or above 7000 ft (the low case returned above)
    } else if low_ceiling {
        2
    } else if w.cloud_ceiling_m < 16000.0 * FEET_M {
        1
    } else {
        0
    };
    Ok((insolation - reduction).max(1))
}

/// The Pasquill class for the weather (Turner's key; G reported as F).
pub fn pasquill_class(w: &PasquillWeather) -> Result<StabilityClass, EffectsError> {
    let index = net_radiation_index(w)?;
    let knots = libm::round(w.wind_speed_mps * KNOTS_PER_MPS);
    // Columns: net radiation index 4, 3, 2, 1, 0, -1, -2. Values: 1 = A ... 7 = G.
    const TABLE: [(f64, [u8; 7]); 9] = [
        (1.0, [1, 1, 2, 3, 4, 6, 7]),
        (3.0, [1, 2, 2, 3, 4, 6, 7]),
        (5.0, [1, 2, 3, 4, 4, 5, 6]),
        (6.0, [2, 2, 3, 4, 4, 5, 6]),
        (7.0, [2, 2, 3, 4, 4, 4, 5]),
        (9.0, [2, 3, 3, 4, 4, 4, 5]),
        (10.0, [3, 3, 4, 4, 4, 4, 5]),
        (11.0, [3, 3, 4, 4, 4, 4, 4]),
        (f64::INFINITY, [3, 4, 4, 4, 4, 4, 4]),
    ];
    let row = TABLE
        .iter()
        .find(|(max_knots, _)| knots <= *max_knots)
        .map_or([3, 4, 4, 4, 4, 4, 4], |(_, row)| *row);
    let column = usize::try_from(4 - i32::from(index)).unwrap_or(0).min(6);
    Ok(match row.get(column).copied().unwrap_or(4) {
        1 => StabilityClass::A,
        2 => StabilityClass::B,
        3 => StabilityClass::C,
        4 => StabilityClass::D,
        5 => StabilityClass::E,
        _ => StabilityClass::F,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// Eq 6 evaluated independently (std's exp/ln, the table typed out again from INDEX.md).
    fn reference(class: StabilityClass, x_km: f64) -> (f64, f64) {
        let (iy, jy, ky, iz, jz, kz) = match class {
            StabilityClass::A => (5.357, 0.8828, -0.0076, 6.035, 2.1097, 0.2770),
            StabilityClass::B => (5.058, 0.9024, -0.0096, 4.694, 1.0629, 0.0136),
            StabilityClass::C => (4.651, 0.9181, -0.0076, 4.110, 0.9201, -0.0020),
            StabilityClass::D => (4.230, 0.9222, -0.0087, 3.414, 0.7371, -0.0316),
            StabilityClass::E => (3.922, 0.9222, -0.0064, 3.057, 0.6794, -0.0450),
            StabilityClass::F => (3.533, 0.9181, -0.0070, 2.621, 0.6564, -0.0540),
        };
        let l = x_km.ln();
        (
            (iy + jy * l + ky * l * l).exp(),
            (iz + jz * l + kz * l * l).exp().min(5000.0),
        )
    }

    #[test]
    fn sigmas_match_eq6_for_every_class_at_0_1_1_and_10_km() {
        for class in StabilityClass::ALL {
            for x_km in [0.1, 1.0, 10.0] {
                let s = sigmas(class, x_km * 1000.0).unwrap();
                let (y, z) = reference(class, x_km);
                assert!(
                    (s.y_m - y).abs() <= 1e-9 * y,
                    "{class} {x_km} km y {} vs {y}",
                    s.y_m
                );
                assert!(
                    (s.z_m - z).abs() <= 1e-9 * z,
                    "{class} {x_km} km z {} vs {z}",
                    s.z_m
                );
            }
        }
    }

    #[test]
    fn published_values_class_d_at_1_km_and_the_cap() {
        // INDEX.md: class D at 1 km gives sigma_y = e^4.230 = 68.7 m, sigma_z = e^3.414 = 30.4 m.
        let s = sigmas(StabilityClass::D, 1000.0).unwrap();
        assert!((s.y_m - 68.7).abs() < 0.05, "{}", s.y_m);
        assert!((s.z_m - 30.4).abs() < 0.05, "{}", s.z_m);
        // Class A sigma_z exceeds 5000 m well before 10 km: capped.
        assert!(StabilityClass::A.mcmullen_constants().1.eq6_m(10.0) > 5000.0);
        assert_eq!(sigmas(StabilityClass::A, 10_000.0).unwrap().z_m, 5000.0);
        // Spread falls from unstable to stable at 1 km.
        let at_1km: Vec<Sigmas> = StabilityClass::ALL
            .iter()
            .map(|c| sigmas(*c, 1000.0).unwrap())
            .collect();
        for pair in at_1km.windows(2) {
            assert!(pair[0].y_m > pair[1].y_m && pair[0].z_m > pair[1].z_m);
        }
    }

    #[test]
    fn bad_distances_are_refused_and_zero_is_zero() {
        assert!(sigmas(StabilityClass::D, -1.0).is_err());
        assert!(sigmas(StabilityClass::D, f64::NAN).is_err());
        assert!(sigmas(StabilityClass::D, f64::INFINITY).is_err());
        assert_eq!(
            sigmas(StabilityClass::D, 0.0).unwrap(),
            Sigmas { y_m: 0.0, z_m: 0.0 }
        );
        assert!("G".parse::<StabilityClass>().is_err());
        assert_eq!("d".parse::<StabilityClass>().unwrap(), StabilityClass::D);
    }

    fn weather(wind: f64, sun: f64, cover: f64, ceiling: f64) -> PasquillWeather {
        PasquillWeather {
            wind_speed_mps: wind,
            sun_elevation_deg: sun,
            cloud_cover_fraction: cover,
            cloud_ceiling_m: ceiling,
        }
    }

    #[test]
    fn turner_key_cases() {
        use StabilityClass::*;
        let clear = f64::INFINITY;
        // Strong sun, light wind: A; moderate wind: B; strong wind: C.
        assert_eq!(pasquill_class(&weather(1.0, 70.0, 0.0, clear)).unwrap(), A);
        assert_eq!(pasquill_class(&weather(3.0, 70.0, 0.0, clear)).unwrap(), B);
        assert_eq!(pasquill_class(&weather(7.0, 70.0, 0.0, clear)).unwrap(), C);
        // Slight sun (low elevation), 2 m/s (4 kt): C.
        assert_eq!(pasquill_class(&weather(2.0, 25.0, 0.0, clear)).unwrap(), C);
        // Clear night: light wind F (Turner's G), 2.5 m/s (5 kt): F; 3 m/s (6 kt): F; 4 m/s: E.
        assert_eq!(pasquill_class(&weather(0.5, -10.0, 0.0, clear)).unwrap(), F);
        assert_eq!(pasquill_class(&weather(2.5, -10.0, 0.2, clear)).unwrap(), F);
        assert_eq!(pasquill_class(&weather(4.0, -10.0, 0.2, clear)).unwrap(), E);
        // Cloudy night: 2 m/s (4 kt): E; strong wind: D.
        assert_eq!(pasquill_class(&weather(2.0, -10.0, 0.8, clear)).unwrap(), E);
        assert_eq!(pasquill_class(&weather(8.0, -10.0, 0.8, clear)).unwrap(), D);
        // Low overcast: D day or night.
        assert_eq!(pasquill_class(&weather(1.0, 70.0, 1.0, 500.0)).unwrap(), D);
        assert_eq!(pasquill_class(&weather(1.0, -20.0, 1.0, 500.0)).unwrap(), D);
        // Strong sun under a broken low deck: index 4 - 2 = 2: light wind B.
        assert_eq!(pasquill_class(&weather(1.0, 70.0, 0.7, 1000.0)).unwrap(), B);
        assert_eq!(
            net_radiation_index(&weather(1.0, 70.0, 0.7, 1000.0)).unwrap(),
            2
        );
        assert_eq!(
            net_radiation_index(&weather(1.0, 70.0, 1.0, 3000.0)).unwrap(),
            3
        );
        assert_eq!(
            net_radiation_index(&weather(1.0, 10.0, 0.9, 1000.0)).unwrap(),
            1
        );
        // Bad input is refused.
        assert!(pasquill_class(&weather(-1.0, 10.0, 0.0, clear)).is_err());
        assert!(pasquill_class(&weather(1.0, f64::NAN, 0.0, clear)).is_err());
        assert!(pasquill_class(&weather(1.0, 10.0, 1.5, clear)).is_err());
        assert!(pasquill_class(&weather(1.0, 10.0, 0.5, f64::NAN)).is_err());
    }

    proptest! {
        #[test]
        fn sigma_is_monotone_in_distance(class_index in 0usize..6, x1 in 0.0f64..200_000.0, dx in 0.0f64..50_000.0) {
            let class = StabilityClass::ALL[class_index];
            let a = sigmas(class, x1).unwrap();
            let b = sigmas(class, x1 + dx).unwrap();
            prop_assert!(b.y_m >= a.y_m, "y {} -> {}", a.y_m, b.y_m);
            prop_assert!(b.z_m >= a.z_m, "z {} -> {}", a.z_m, b.z_m);
        }

        #[test]
        fn sigma_is_continuous_at_the_fit_ends(class_index in 0usize..6) {
            let class = StabilityClass::ALL[class_index];
            for end_m in [100.0, 100_000.0] {
                let below = sigmas(class, end_m * (1.0 - 1e-9)).unwrap();
                let above = sigmas(class, end_m * (1.0 + 1e-9)).unwrap();
                prop_assert!((below.y_m - above.y_m).abs() <= 1e-6 * above.y_m);
                prop_assert!((below.z_m - above.z_m).abs() <= 1e-6 * above.z_m);
            }
        }

        #[test]
        fn pasquill_class_never_fails_on_valid_weather(wind in 0.0f64..40.0, sun in -90.0f64..90.0, cover in 0.0f64..=1.0, ceiling in 0.0f64..20_000.0) {
            let class = pasquill_class(&weather(wind, sun, cover, ceiling)).unwrap();
            // Unstable classes only by day, stable only by night.
            if sun < 0.0 { prop_assert!(class >= StabilityClass::D); }
            else { prop_assert!(class <= StabilityClass::D); }
        }
    }
}
