//! Directional ocean wave spectra tied to the wind, the fetch and the depth, with a swell; the WMO
//! sea state code and whitecap coverage.
//!
//! Algorithms and sources:
//!
//! - **Pierson-Moskowitz** (fully developed sea; Pierson and Moskowitz 1964):
//!   `S(ω) = α g² ω⁻⁵ exp(-5/4 (ωp/ω)⁴)` with `α = 8.1e-3`, `ωp = 0.877 g / U19.5` and
//!   `U19.5 ≈ 1.026 U10`, which gives `Hs = 0.21 U19.5² / g ≈ 0.22 U10² / g` (U10 5, 10, 15,
//!   20 m/s: Hs 0.56, 2.25, 5.05, 8.99 m; Tp 3.7, 7.5, 11.2, 15.0 s).
//! - **JONSWAP** (fetch-limited sea; Hasselmann et al. 1973): the same form times the peak
//!   enhancement `γ^r`, `r = exp(-(ω - ωp)² / (2 σ² ωp²))`, `γ = 3.3`, `σ = 0.07` below the peak
//!   and `0.09` above, with `α = 0.076 (U10² / (F g))^0.22` and `ωp = 22 (g² / (U10 F))^(1/3)`.
//!   As the fetch grows the JONSWAP energy is capped at Pierson-Moskowitz's, and once the
//!   fetch-limited peak would fall below Pierson-Moskowitz's peak frequency the sea is fully
//!   developed and Pierson-Moskowitz is used: Hs and Tp never exceed the fully developed values
//!   and vary continuously with the fetch (the peak's shape switches from γ = 3.3 to 1 there).
//! - **TMA** (finite depth; Bouws et al. 1985): the wind sea is multiplied by Kitaigorodskii's
//!   depth factor `φ(ωh)`, `ωh = ω √(d/g)`: `ωh²/2` below 1, `1 - (2 - ωh)²/2` up to 2, then 1;
//!   the dispersion relation is `ω² = g k tanh(k d)` ([`dispersion_omega_rad_s`]).
//! - **Directional spreading** (Hasselmann et al. 1980, as used by Horvath 2015, "Empirical
//!   directional wave spectra for computer graphics"): `D(θ) = Q(s) |cos(θ/2)|^(2s)` with
//!   `s = 6.97 (ω/ωp)^4.06` up to the peak and `s = 9.77 (ω/ωp)^(-2.33 - 1.45 (ωp U10/g - 1.17))`
//!   above; `Q(s) = Γ(s+1) / (2 √π Γ(s+½))` normalises `∫ D dθ` over `[-π, π]` to 1 (computed
//!   through log-gamma, so it stays finite for any `s`).
//! - **Swell**: a JONSWAP-shaped peak with `γ = 7` at the swell's period, scaled so its own
//!   `Hs` is the one given, spread as `cos^(2s)(θ/2)` with `s = 75` (Goda's value for swell with
//!   a long decay distance). It adds to the wind sea (the two are independent).
//! - **WMO sea state code** (Douglas scale, WMO code table 3700): [`sea_state_hs_range_m`].
//! - **Whitecap coverage**: Monahan and O'Muircheartaigh 1980, `W = 3.84e-6 U10^3.41`
//!   ([`whitecap_fraction_monahan`]), capped at 0.2.
//!
//! Conventions: directions are degrees true (clockwise from north); x is east and y is north; the
//! wind blows *from* `wind_from_deg`, so the wind sea travels toward `wind_from_deg + 180`; a
//! swell's `from_deg` is likewise where it comes from. Spectra are one-sided in frequency
//! (`∫₀^∞ S(ω) dω` is the elevation variance `m0`, `Hs = 4 √m0`).
//!
//! Limits: the spectra are empirical fits for a steady, homogeneous wind over open water; the
//! wind is the 10 m wind (U10); a fetch-limited sea is assumed to have grown for long enough
//! (no duration limit); the depth is uniform and the TMA factor is applied to the wind sea only
//! (the swell keeps its given height); currents, refraction, shoaling and breaking are not
//! modelled; the swell spreading is a fixed constant.

use std::f64::consts::{PI, TAU};

use crate::{checked, SeaError, G_MPS2};

/// Phillips' constant of the Pierson-Moskowitz spectrum.
const PM_ALPHA: f64 = 8.1e-3;
/// Pierson-Moskowitz's peak: `ωp U19.5 / g`.
const PM_PEAK_OMEGA_U_OVER_G: f64 = 0.877;
/// The wind at 19.5 m over the wind at 10 m (neutral log profile).
const U19_5_OVER_U10: f64 = 1.026;
/// JONSWAP's mean peak enhancement.
const JONSWAP_GAMMA: f64 = 3.3;
/// The swell's peak enhancement (a narrow peak).
const SWELL_GAMMA: f64 = 7.0;
/// The swell's spreading exponent `s` (Goda: swell with a long decay distance).
const SWELL_SPREADING_S: f64 = 75.0;
/// `C(γ) = ∫₀^∞ x⁻⁵ exp(-5/4 x⁻⁴) γ^r(x) dx` for γ = 3.3 (numeric, checked by a test); the
/// integral for γ = 1 is exactly 1/5.
const SHAPE_INTEGRAL_GAMMA_3_3: f64 = 0.304_989_721_778;
/// The same integral for [`SWELL_GAMMA`].
const SHAPE_INTEGRAL_GAMMA_7: f64 = 0.445_033_846_983;
/// Monahan and O'Muircheartaigh's coefficient and exponent.
const MONAHAN_COEFFICIENT: f64 = 3.84e-6;
const MONAHAN_EXPONENT: f64 = 3.41;
/// The whitecap fraction's cap (the fit is for winds up to about 20 m/s).
const WHITECAP_FRACTION_CAP: f64 = 0.2;

/// The significant wave height range, metres, of each WMO sea state code 0..=9.
const SEA_STATE_HS_M: [(f64, f64); 10] = [
    (0.0, 0.0),
    (0.0, 0.1),
    (0.1, 0.5),
    (0.5, 1.25),
    (1.25, 2.5),
    (2.5, 4.0),
    (4.0, 6.0),
    (6.0, 9.0),
    (9.0, 14.0),
    (14.0, f64::INFINITY),
];
/// The height [`SeaConditions::for_sea_state`] aims at for code 9 (it has no upper bound).
const SEA_STATE_9_HS_M: f64 = 16.0;

/// A swell: long waves from a distant storm, added to the local wind sea.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Swell {
    /// Significant wave height of the swell alone, metres (`0..=20`).
    pub height_m: f64,
    /// Peak period, seconds (`2..=30`).
    pub period_s: f64,
    /// Direction the swell comes from, degrees true.
    pub from_deg: f64,
}

impl Swell {
    /// A checked swell; `from_deg` is wrapped to `[0, 360)`.
    ///
    /// # Errors
    /// [`SeaError::OutOfRange`] for a height outside `0..=20` m, a period outside `2..=30` s or a
    /// direction that is not finite.
    pub fn new(height_m: f64, period_s: f64, from_deg: f64) -> Result<Swell, SeaError> {
        let swell = Swell {
            height_m,
            period_s,
            from_deg: finite_deg("swell direction", from_deg)?,
        };
        swell.validate()?;
        Ok(swell)
    }

    /// Checks the fields (they are public, so a swell built by hand may be out of range).
    ///
    /// # Errors
    /// As [`Swell::new`].
    pub fn validate(&self) -> Result<(), SeaError> {
        checked("swell height", self.height_m, 0.0, 20.0, "in 0..=20 m")?;
        checked("swell period", self.period_s, 2.0, 30.0, "in 2..=30 s")?;
        finite_deg("swell direction", self.from_deg)?;
        Ok(())
    }
}

/// The sea's driving conditions: the wind, its fetch, the depth and a swell.
#[derive(Clone, Debug, PartialEq)]
pub struct SeaConditions {
    /// Wind speed at 10 m (U10), m/s (`0..=60`).
    pub wind_speed_mps: f64,
    /// Direction the wind blows from, degrees true; the wind sea travels toward `+ 180`.
    pub wind_from_deg: f64,
    /// Fetch, metres; `None` is a fully developed sea (Pierson-Moskowitz).
    pub fetch_m: Option<f64>,
    /// Water depth, metres; `None` is deep water.
    pub depth_m: Option<f64>,
    /// A swell added to the wind sea.
    pub swell: Option<Swell>,
}

impl SeaConditions {
    /// A fully developed wind sea in deep water without swell; `wind_from_deg` is wrapped to
    /// `[0, 360)`.
    ///
    /// # Errors
    /// [`SeaError::OutOfRange`] for a wind outside `0..=60` m/s or a direction that is not finite.
    pub fn new(wind_speed_mps: f64, wind_from_deg: f64) -> Result<SeaConditions, SeaError> {
        Ok(SeaConditions {
            wind_speed_mps: checked("wind speed", wind_speed_mps, 0.0, 60.0, "in 0..=60 m/s")?,
            wind_from_deg: finite_deg("wind direction", wind_from_deg)?,
            fetch_m: None,
            depth_m: None,
            swell: None,
        })
    }

    /// The same conditions with a limited fetch (JONSWAP).
    ///
    /// # Errors
    /// [`SeaError::OutOfRange`] for a fetch that is not finite and positive.
    pub fn with_fetch_m(self, fetch_m: f64) -> Result<SeaConditions, SeaError> {
        Ok(SeaConditions {
            fetch_m: Some(positive("fetch", fetch_m)?),
            ..self
        })
    }

    /// The same conditions in water of finite depth (TMA).
    ///
    /// # Errors
    /// [`SeaError::OutOfRange`] for a depth that is not finite and positive.
    pub fn with_depth_m(self, depth_m: f64) -> Result<SeaConditions, SeaError> {
        Ok(SeaConditions {
            depth_m: Some(positive("depth", depth_m)?),
            ..self
        })
    }

    /// The same conditions with a swell.
    ///
    /// # Errors
    /// [`SeaError::OutOfRange`] for a swell out of range (see [`Swell::new`]).
    pub fn with_swell(self, swell: Swell) -> Result<SeaConditions, SeaError> {
        swell.validate()?;
        Ok(SeaConditions {
            swell: Some(swell),
            ..self
        })
    }

    /// A fully developed deep-water wind sea for a WMO sea state code: the wind whose
    /// Pierson-Moskowitz Hs is the middle of the code's range (code 0: no wind; code 9: 16 m).
    ///
    /// # Errors
    /// [`SeaError::OutOfRange`] for a code above 9 or a direction that is not finite.
    pub fn for_sea_state(code: u8, wind_from_deg: f64) -> Result<SeaConditions, SeaError> {
        let (lo_m, hi_m) = sea_state_hs_range_m(code)?;
        let hs_m = if hi_m.is_finite() {
            0.5 * (lo_m + hi_m)
        } else {
            SEA_STATE_9_HS_M
        };
        SeaConditions::new(pierson_moskowitz_wind_for_hs_mps(hs_m), wind_from_deg)
    }

    /// Checks the fields (they are public, so conditions built by hand may be out of range).
    ///
    /// # Errors
    /// As the constructor and builders.
    pub fn validate(&self) -> Result<(), SeaError> {
        checked(
            "wind speed",
            self.wind_speed_mps,
            0.0,
            60.0,
            "in 0..=60 m/s",
        )?;
        finite_deg("wind direction", self.wind_from_deg)?;
        if let Some(fetch_m) = self.fetch_m {
            positive("fetch", fetch_m)?;
        }
        if let Some(depth_m) = self.depth_m {
            positive("depth", depth_m)?;
        }
        if let Some(swell) = &self.swell {
            swell.validate()?;
        }
        Ok(())
    }

    /// The direction the wind sea travels toward, degrees true in `[0, 360)`.
    pub fn waves_toward_deg(&self) -> f64 {
        (self.wind_from_deg + 180.0).rem_euclid(360.0)
    }

    /// Whether the wind sea is fully developed (no fetch, or a fetch beyond full development).
    pub fn is_fully_developed(&self) -> bool {
        self.model().wind.is_none_or(|wind| wind.shape.gamma <= 1.0)
    }

    /// The wind sea's peak period, seconds (`None` without wind).
    pub fn wind_sea_peak_period_s(&self) -> Option<f64> {
        self.model().wind.map(|wind| TAU / wind.shape.omega_p_rad_s)
    }

    /// The one-sided frequency spectrum of the elevation, m² s, at `omega_rad_s` (rad/s): the
    /// wind sea plus the swell.
    pub fn omega_spectrum(&self, omega_rad_s: f64) -> f64 {
        self.model().omega_spectrum(omega_rad_s)
    }

    /// The wind sea's directional spreading `D(θ)`, 1/rad, at `omega_rad_s` and at
    /// `theta_rad_relative` from the wind sea's mean direction (`∫ D dθ = 1` over `[-π, π]`);
    /// isotropic `1/(2π)` without wind.
    pub fn spreading(&self, omega_rad_s: f64, theta_rad_relative: f64) -> f64 {
        match self.model().wind {
            Some(wind) => spreading_cos2s(
                wind.spreading_exponent(omega_rad_s, self.wind_speed_mps),
                theta_rad_relative,
            ),
            None => 1.0 / TAU,
        }
    }

    /// The directional elevation spectrum in wave-number space, m⁴, at (`kx_rad_m` east,
    /// `ky_rad_m` north): `S(ω, θ) (dω/dk) / k` with `θ` the direction the waves travel toward,
    /// so that its integral over the plane is the elevation variance. Zero at `k = 0`.
    pub fn wavenumber_spectrum(&self, kx_rad_m: f64, ky_rad_m: f64) -> f64 {
        self.model().wavenumber_spectrum(kx_rad_m, ky_rad_m)
    }

    /// The significant wave height, metres, `4 √m0` with `m0` the numeric integral of
    /// [`SeaConditions::omega_spectrum`] (Simpson's rule in `ln ω` from 0.005 to 200 rad/s).
    pub fn expected_hs_m(&self) -> f64 {
        let model = self.model();
        let (lo, hi) = (0.005_f64.ln(), 200.0_f64.ln());
        let steps = 8000_u32;
        let step = (hi - lo) / f64::from(steps);
        let variance_m2 = (0..=steps)
            .map(|i| {
                let omega = (lo + step * f64::from(i)).exp();
                let weight = if i == 0 || i == steps {
                    1.0
                } else if i % 2 == 1 {
                    4.0
                } else {
                    2.0
                };
                weight * model.omega_spectrum(omega) * omega
            })
            .sum::<f64>()
            * step
            / 3.0;
        4.0 * variance_m2.max(0.0).sqrt()
    }

    /// The spectrum's parameters, computed once for many evaluations.
    pub(crate) fn model(&self) -> SpectrumModel {
        let wind = WindSea::new(self.wind_speed_mps, self.fetch_m);
        let swell = self
            .swell
            .filter(|swell| swell.height_m > 0.0)
            .map(|swell| {
                (
                    swell.height_m * swell.height_m / 16.0,
                    PeakShape::swell(TAU / swell.period_s),
                    bearing_rad(swell.from_deg + 180.0),
                )
            });
        SpectrumModel {
            wind,
            wind_u10_mps: self.wind_speed_mps,
            wind_bearing_rad: bearing_rad(self.waves_toward_deg()),
            swell,
            swell_spreading_norm: spreading_normalisation(SWELL_SPREADING_S),
            depth_m: self.depth_m,
        }
    }
}

/// A unit-variance JONSWAP-shaped peak: its density over ω integrates to 1.
#[derive(Clone, Copy, Debug)]
struct PeakShape {
    omega_p_rad_s: f64,
    /// The peak enhancement γ (1: Pierson-Moskowitz).
    gamma: f64,
    /// `C(γ) = ∫₀^∞ x⁻⁵ exp(-5/4 x⁻⁴) γ^r(x) dx`.
    shape_integral: f64,
}

impl PeakShape {
    fn pierson_moskowitz(omega_p_rad_s: f64) -> PeakShape {
        PeakShape {
            omega_p_rad_s,
            gamma: 1.0,
            shape_integral: 0.2,
        }
    }

    fn jonswap(omega_p_rad_s: f64) -> PeakShape {
        PeakShape {
            omega_p_rad_s,
            gamma: JONSWAP_GAMMA,
            shape_integral: SHAPE_INTEGRAL_GAMMA_3_3,
        }
    }

    fn swell(omega_p_rad_s: f64) -> PeakShape {
        PeakShape {
            omega_p_rad_s,
            gamma: SWELL_GAMMA,
            shape_integral: SHAPE_INTEGRAL_GAMMA_7,
        }
    }

    /// 1/(rad/s): `x⁻⁵ exp(-5/4 x⁻⁴) γ^r / (C(γ) ωp)` with `x = ω/ωp`.
    fn density(&self, omega_rad_s: f64) -> f64 {
        let x = omega_rad_s / self.omega_p_rad_s;
        // Below 0.05 ωp the exponential is below e^-200000: zero (and x⁻⁵ could overflow).
        if x.is_nan() || x < 0.05 {
            return 0.0;
        }
        let x2 = x * x;
        let x4 = x2 * x2;
        let pm = (-1.25 / x4).exp() / (x4 * x);
        let enhancement = if self.gamma <= 1.0 {
            1.0
        } else {
            let sigma = if x <= 1.0 { 0.07 } else { 0.09 };
            let r = (-(x - 1.0) * (x - 1.0) / (2.0 * sigma * sigma)).exp();
            self.gamma.powf(r)
        };
        pm * enhancement / (self.shape_integral * self.omega_p_rad_s)
    }
}

/// The wind sea: its variance and peak.
#[derive(Clone, Copy, Debug)]
struct WindSea {
    variance_m2: f64,
    shape: PeakShape,
}

impl WindSea {
    /// Pierson-Moskowitz, or JONSWAP capped at it; `None` without wind.
    fn new(u10_mps: f64, fetch_m: Option<f64>) -> Option<WindSea> {
        if u10_mps.is_nan() || u10_mps <= 0.0 {
            return None;
        }
        let g = G_MPS2;
        let pm_omega_p = PM_PEAK_OMEGA_U_OVER_G * g / (U19_5_OVER_U10 * u10_mps);
        let pm_variance = PM_ALPHA * g * g / (5.0 * pm_omega_p.powi(4));
        let pm = WindSea {
            variance_m2: pm_variance,
            shape: PeakShape::pierson_moskowitz(pm_omega_p),
        };
        let Some(fetch_m) = fetch_m else {
            return Some(pm);
        };
        let omega_p = 22.0 * (g * g / (u10_mps * fetch_m)).cbrt();
        if omega_p <= pm_omega_p {
            return Some(pm);
        }
        let alpha = 0.076 * (u10_mps * u10_mps / (fetch_m * g)).powf(0.22);
        let variance = alpha * g * g * SHAPE_INTEGRAL_GAMMA_3_3 / omega_p.powi(4);
        Some(WindSea {
            variance_m2: variance.min(pm_variance),
            shape: PeakShape::jonswap(omega_p),
        })
    }

    /// Hasselmann's spreading exponent `s` at `omega_rad_s`.
    fn spreading_exponent(&self, omega_rad_s: f64, u10_mps: f64) -> f64 {
        let omega_p = self.shape.omega_p_rad_s;
        let x = omega_rad_s / omega_p;
        if x.is_nan() || x <= 0.0 {
            0.0
        } else if x <= 1.0 {
            6.97 * x.powf(4.06)
        } else {
            9.77 * x.powf(-2.33 - 1.45 * (omega_p * u10_mps / G_MPS2 - 1.17))
        }
    }
}

/// The parameters of a [`SeaConditions`]'s spectrum.
#[derive(Clone, Debug)]
pub(crate) struct SpectrumModel {
    wind: Option<WindSea>,
    wind_u10_mps: f64,
    wind_bearing_rad: f64,
    /// Variance, peak and travel bearing.
    swell: Option<(f64, PeakShape, f64)>,
    swell_spreading_norm: f64,
    depth_m: Option<f64>,
}

impl SpectrumModel {
    fn wind_sea_omega_spectrum(&self, omega_rad_s: f64) -> f64 {
        let Some(wind) = &self.wind else {
            return 0.0;
        };
        let depth_factor = self.depth_m.map_or(1.0, |depth_m| {
            kitaigorodskii_depth_factor(omega_rad_s * (depth_m / G_MPS2).sqrt())
        });
        wind.variance_m2 * wind.shape.density(omega_rad_s) * depth_factor
    }

    fn swell_omega_spectrum(&self, omega_rad_s: f64) -> f64 {
        self.swell.as_ref().map_or(0.0, |(variance_m2, shape, _)| {
            variance_m2 * shape.density(omega_rad_s)
        })
    }

    pub(crate) fn omega_spectrum(&self, omega_rad_s: f64) -> f64 {
        self.wind_sea_omega_spectrum(omega_rad_s) + self.swell_omega_spectrum(omega_rad_s)
    }

    /// `S(ω, θ)`, m² s/rad, for waves travelling toward `bearing_rad` (clockwise from north).
    fn directional_spectrum(&self, omega_rad_s: f64, bearing_rad: f64) -> f64 {
        let wind = self.wind.as_ref().map_or(0.0, |wind| {
            let s = wind.spreading_exponent(omega_rad_s, self.wind_u10_mps);
            self.wind_sea_omega_spectrum(omega_rad_s)
                * spreading_cos2s(s, bearing_rad - self.wind_bearing_rad)
        });
        let swell = self.swell.as_ref().map_or(0.0, |(_, _, swell_bearing)| {
            let half = 0.5 * (bearing_rad - swell_bearing);
            self.swell_omega_spectrum(omega_rad_s)
                * self.swell_spreading_norm
                * half.cos().abs().powf(2.0 * SWELL_SPREADING_S)
        });
        wind + swell
    }

    pub(crate) fn wavenumber_spectrum(&self, kx_rad_m: f64, ky_rad_m: f64) -> f64 {
        let k = kx_rad_m.hypot(ky_rad_m);
        if !k.is_finite() || k <= 0.0 {
            return 0.0;
        }
        let omega = dispersion_omega_rad_s(k, self.depth_m);
        let bearing = kx_rad_m.atan2(ky_rad_m);
        self.directional_spectrum(omega, bearing) * group_speed_mps(k, self.depth_m) / k
    }

    /// The water depth, metres (`None`: deep).
    pub(crate) fn depth_m(&self) -> Option<f64> {
        self.depth_m
    }
}

/// Kitaigorodskii's depth factor of the TMA spectrum at `ωh = ω √(d/g)`.
fn kitaigorodskii_depth_factor(omega_h: f64) -> f64 {
    if omega_h <= 1.0 {
        0.5 * omega_h * omega_h
    } else if omega_h < 2.0 {
        1.0 - 0.5 * (2.0 - omega_h) * (2.0 - omega_h)
    } else {
        1.0
    }
}

/// `Q(s) |cos(θ/2)|^(2s)`, normalised over `[-π, π]`; `s` below 0 counts as 0.
pub(crate) fn spreading_cos2s(s: f64, theta_rad: f64) -> f64 {
    let s = s.max(0.0);
    let c = (0.5 * theta_rad).cos().abs();
    spreading_normalisation(s) * c.powf(2.0 * s)
}

/// `Q(s) = Γ(s+1) / (2 √π Γ(s+½))`, the normalisation of `|cos(θ/2)|^(2s)` over `[-π, π]`
/// (Legendre's duplication formula turns the usual `Γ(s+1)² 2^(2s-1) / (π Γ(2s+1))` into this
/// ratio, computed through log-gamma so it stays finite for large `s`).
fn spreading_normalisation(s: f64) -> f64 {
    (ln_gamma(s + 1.0) - ln_gamma(s + 0.5)).exp() / (2.0 * PI.sqrt())
}

/// `ln Γ(x)` for `x ≥ 0.5` (Lanczos, g = 7, nine terms: relative error about 1e-15).
fn ln_gamma(x: f64) -> f64 {
    const G: f64 = 7.0;
    const COEFFICIENTS: [f64; 9] = [
        0.999_999_999_999_809_9,
        676.520_368_121_885_1,
        -1_259.139_216_722_402_8,
        771.323_428_777_653_1,
        -176.615_029_162_140_6,
        12.507_343_278_686_905,
        -0.138_571_095_265_720_12,
        9.984_369_578_019_572e-6,
        1.505_632_735_149_311_6e-7,
    ];
    let x = x - 1.0;
    let mut sum = COEFFICIENTS[0];
    let mut denominator = x;
    for coefficient in &COEFFICIENTS[1..] {
        denominator += 1.0;
        sum += coefficient / denominator;
    }
    let t = x + G + 0.5;
    0.5 * TAU.ln() + (x + 0.5) * t.ln() - t + sum.ln()
}

/// The angular frequency, rad/s, of a wave of wave number `k_rad_m` (rad/m) in water of depth
/// `depth_m` (`None`: deep): `ω² = g k tanh(k d)`.
pub fn dispersion_omega_rad_s(k_rad_m: f64, depth_m: Option<f64>) -> f64 {
    let k = k_rad_m.max(0.0);
    let depth_factor = depth_m.map_or(1.0, |d| (k * d).tanh());
    (G_MPS2 * k * depth_factor).sqrt()
}

/// The group speed `dω/dk`, m/s, of a wave of wave number `k_rad_m` in water of depth `depth_m`.
pub fn group_speed_mps(k_rad_m: f64, depth_m: Option<f64>) -> f64 {
    let k = k_rad_m.max(0.0);
    let omega = dispersion_omega_rad_s(k, depth_m);
    if omega.is_nan() || omega <= 0.0 {
        // The long-wave limit: √(g d) in shallow water, unbounded in deep water.
        return depth_m.map_or(f64::INFINITY, |d| (G_MPS2 * d).sqrt());
    }
    match depth_m {
        None => 0.5 * omega / k,
        Some(d) => {
            let kd = k * d;
            let sech = 1.0 / kd.cosh();
            G_MPS2 * (kd.tanh() + kd * sech * sech) / (2.0 * omega)
        }
    }
}

/// The wave number, rad/m, of a wave of angular frequency `omega_rad_s` in water of depth
/// `depth_m`: the inverse of [`dispersion_omega_rad_s`] (Eckart's estimate refined by Newton's
/// method to 1e-12 relative).
pub fn dispersion_k_rad_m(omega_rad_s: f64, depth_m: Option<f64>) -> f64 {
    let omega = omega_rad_s.max(0.0);
    let deep_k = omega * omega / G_MPS2;
    let Some(d) = depth_m else {
        return deep_k;
    };
    if deep_k.is_nan() || deep_k <= 0.0 || d.is_nan() || d <= 0.0 {
        return 0.0;
    }
    let mut k = deep_k / (deep_k * d).tanh().sqrt();
    for _ in 0..50 {
        let kd = k * d;
        let tanh = kd.tanh();
        let sech = 1.0 / kd.cosh();
        let f = G_MPS2 * k * tanh - omega * omega;
        let df = G_MPS2 * (tanh + kd * sech * sech);
        let step = f / df;
        k -= step;
        if step.abs() <= 1e-12 * k {
            break;
        }
    }
    k
}

/// The significant wave height, metres, of a fully developed sea in a wind of `u10_mps` at 10 m
/// (Pierson-Moskowitz: `0.2093 U19.5² / g`, about `0.22 U10² / g`); 0 for no wind.
pub fn pierson_moskowitz_hs_m(u10_mps: f64) -> f64 {
    let u = U19_5_OVER_U10 * u10_mps.max(0.0);
    pm_hs_coefficient() * u * u / G_MPS2
}

/// The peak period, seconds, of a fully developed sea in a wind of `u10_mps` at 10 m
/// (Pierson-Moskowitz: `2π U19.5 / (0.877 g)`); 0 for no wind.
pub fn pierson_moskowitz_peak_period_s(u10_mps: f64) -> f64 {
    TAU * U19_5_OVER_U10 * u10_mps.max(0.0) / (PM_PEAK_OMEGA_U_OVER_G * G_MPS2)
}

/// `Hs g / U19.5²` of the Pierson-Moskowitz spectrum: `4 √(α/5) / 0.877²` (about 0.209).
fn pm_hs_coefficient() -> f64 {
    4.0 * (PM_ALPHA / 5.0).sqrt() / (PM_PEAK_OMEGA_U_OVER_G * PM_PEAK_OMEGA_U_OVER_G)
}

/// The wind at 10 m whose fully developed sea has `hs_m` (the inverse of
/// [`pierson_moskowitz_hs_m`]).
fn pierson_moskowitz_wind_for_hs_mps(hs_m: f64) -> f64 {
    (hs_m.max(0.0) * G_MPS2 / pm_hs_coefficient()).sqrt() / U19_5_OVER_U10
}

/// The fraction of the sea surface covered by whitecaps in a wind of `u10_mps` at 10 m
/// (Monahan and O'Muircheartaigh 1980: `3.84e-6 U10^3.41`, capped at 0.2); 0 for no wind.
pub fn whitecap_fraction_monahan(u10_mps: f64) -> f64 {
    if u10_mps > 0.0 {
        (MONAHAN_COEFFICIENT * u10_mps.powf(MONAHAN_EXPONENT)).min(WHITECAP_FRACTION_CAP)
    } else {
        0.0
    }
}

/// The significant wave height range `(lo, hi)`, metres, of a WMO sea state code (Douglas):
/// 0 calm (glassy) 0; 1 calm (rippled) 0-0.1; 2 smooth 0.1-0.5; 3 slight 0.5-1.25; 4 moderate
/// 1.25-2.5; 5 rough 2.5-4; 6 very rough 4-6; 7 high 6-9; 8 very high 9-14; 9 phenomenal over
/// 14 (`hi` is infinite).
///
/// # Errors
/// [`SeaError::OutOfRange`] for a code above 9.
pub fn sea_state_hs_range_m(code: u8) -> Result<(f64, f64), SeaError> {
    SEA_STATE_HS_M
        .get(usize::from(code))
        .copied()
        .ok_or(SeaError::OutOfRange {
            name: "sea state code",
            range: "in 0..=9",
            value: f64::from(code),
        })
}

/// The WMO sea state code of a significant wave height (each range includes its upper bound:
/// 0.5 m is code 2); 0 for a height that is zero, negative or NaN.
pub fn sea_state_for_hs(hs_m: f64) -> u8 {
    if hs_m.is_nan() || hs_m <= 0.0 {
        return 0;
    }
    (1_u8..=9)
        .find(|&code| hs_m <= SEA_STATE_HS_M[usize::from(code)].1)
        .unwrap_or(9)
}

/// A bearing in radians, clockwise from north, of a direction in degrees.
fn bearing_rad(deg: f64) -> f64 {
    deg.rem_euclid(360.0).to_radians()
}

/// `deg` wrapped to `[0, 360)` when finite.
fn finite_deg(name: &'static str, deg: f64) -> Result<f64, SeaError> {
    checked(name, deg, f64::MIN, f64::MAX, "finite degrees")?;
    Ok(deg.rem_euclid(360.0))
}

/// `value` when finite and positive.
fn positive(name: &'static str, value: f64) -> Result<f64, SeaError> {
    checked(
        name,
        value,
        f64::MIN_POSITIVE,
        f64::MAX,
        "finite and positive metres",
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn rel(a: f64, b: f64) -> f64 {
        (a - b).abs() / b.abs()
    }

    #[test]
    fn pierson_moskowitz_matches_the_published_heights_and_periods() {
        for (u10, hs, tp) in [
            (5.0, 0.56, 3.7),
            (10.0, 2.25, 7.5),
            (15.0, 5.07, 11.2),
            (20.0, 9.0, 15.0),
        ] {
            assert!(rel(pierson_moskowitz_hs_m(u10), hs) < 0.03, "{u10}");
            assert!(
                rel(pierson_moskowitz_peak_period_s(u10), tp) < 0.03,
                "{u10}"
            );
            let sea = SeaConditions::new(u10, 0.0).unwrap();
            assert!(rel(sea.expected_hs_m(), hs) < 0.03, "{u10}");
            assert!(rel(sea.expected_hs_m(), pierson_moskowitz_hs_m(u10)) < 1e-4);
            assert!(rel(sea.wind_sea_peak_period_s().unwrap(), tp) < 0.03);
            assert!(sea.is_fully_developed());
        }
    }

    #[test]
    fn the_shape_integrals_are_right() {
        for shape in [
            PeakShape::pierson_moskowitz(1.0),
            PeakShape::jonswap(1.0),
            PeakShape::swell(1.0),
        ] {
            // The density integrates to 1 only if C(γ) is right.
            let steps = 20_000;
            let (lo, hi) = (0.05_f64.ln(), 200.0_f64.ln());
            let h = (hi - lo) / f64::from(steps);
            let total: f64 = (0..steps)
                .map(|i| {
                    let w = (lo + h * (f64::from(i) + 0.5)).exp();
                    shape.density(w) * w * h
                })
                .sum();
            assert!((total - 1.0).abs() < 1e-6, "{shape:?}: {total}");
        }
    }

    #[test]
    fn jonswap_grows_with_fetch_and_stays_below_pierson_moskowitz() {
        let u10 = 12.0;
        let pm_hs = pierson_moskowitz_hs_m(u10);
        let pm_tp = pierson_moskowitz_peak_period_s(u10);
        let mut last_hs = 0.0;
        let mut last_tp = 0.0;
        for fetch_km in [1.0, 5.0, 20.0, 80.0, 200.0, 400.0, 800.0, 2000.0, 10_000.0] {
            let sea = SeaConditions::new(u10, 90.0)
                .unwrap()
                .with_fetch_m(fetch_km * 1000.0)
                .unwrap();
            let hs = sea.expected_hs_m();
            let tp = sea.wind_sea_peak_period_s().unwrap();
            assert!(
                hs >= last_hs * (1.0 - 1e-6),
                "{fetch_km} km: {hs} after {last_hs}"
            );
            assert!(
                tp >= last_tp * (1.0 - 1e-9),
                "{fetch_km} km: {tp} after {last_tp}"
            );
            assert!(hs <= pm_hs * 1.0001, "{fetch_km} km: {hs} above {pm_hs}");
            assert!(tp <= pm_tp * 1.0001, "{fetch_km} km: {tp} above {pm_tp}");
            last_hs = hs;
            last_tp = tp;
        }
        // A short fetch: 10 m/s over 10 km is a young sea (about 0.6 m, 3 s).
        let young = SeaConditions::new(10.0, 0.0)
            .unwrap()
            .with_fetch_m(10_000.0)
            .unwrap();
        assert!(!young.is_fully_developed());
        assert!((0.45..0.75).contains(&young.expected_hs_m()));
        assert!((2.5..3.3).contains(&young.wind_sea_peak_period_s().unwrap()));
        // Beyond full development: Pierson-Moskowitz exactly.
        let far = SeaConditions::new(u10, 0.0)
            .unwrap()
            .with_fetch_m(1e8)
            .unwrap();
        assert!(far.is_fully_developed());
        assert!(rel(far.expected_hs_m(), pm_hs) < 1e-4);
    }

    #[test]
    fn shallow_water_lowers_the_sea_and_shortens_the_waves() {
        let deep = SeaConditions::new(15.0, 0.0).unwrap();
        let shallow = deep.clone().with_depth_m(10.0).unwrap();
        assert!(shallow.expected_hs_m() < 0.9 * deep.expected_hs_m());
        // ω² = g k tanh(k d), inverted.
        for depth in [None, Some(2.0), Some(10.0), Some(500.0)] {
            for k in [0.001, 0.05, 0.3, 2.0, 30.0] {
                let omega = dispersion_omega_rad_s(k, depth);
                assert!(rel(dispersion_k_rad_m(omega, depth), k) < 1e-9);
                // The group speed is dω/dk (central difference).
                let h = k * 1e-5;
                let numeric = (dispersion_omega_rad_s(k + h, depth)
                    - dispersion_omega_rad_s(k - h, depth))
                    / (2.0 * h);
                assert!(rel(group_speed_mps(k, depth), numeric) < 1e-6);
            }
        }
        // Long waves in 10 m: c → √(g d).
        let c = group_speed_mps(1e-6, Some(10.0));
        assert!(rel(c, (G_MPS2 * 10.0).sqrt()) < 1e-6);
        assert!(dispersion_k_rad_m(1.0, Some(10.0)) > dispersion_k_rad_m(1.0, None));
    }

    #[test]
    fn spreading_integrates_to_one() {
        let sea = SeaConditions::new(10.0, 0.0).unwrap();
        let omega_p = TAU / sea.wind_sea_peak_period_s().unwrap();
        for ratio in [0.3, 0.7, 1.0, 1.5, 3.0, 8.0] {
            let steps = 3600;
            let h = TAU / f64::from(steps);
            let total: f64 = (0..steps)
                .map(|i| sea.spreading(ratio * omega_p, -PI + h * (f64::from(i) + 0.5)) * h)
                .sum();
            // The midpoint rule loses a little where a small s makes the ends steep.
            assert!((total - 1.0).abs() < 1e-4, "{ratio}: {total}");
        }
        // Narrowest at the peak, symmetric, largest along the wind.
        let at_peak = sea.spreading(omega_p, 0.3);
        assert_eq!(at_peak, sea.spreading(omega_p, -0.3));
        assert!(sea.spreading(omega_p, 0.0) > at_peak);
        assert!(sea.spreading(omega_p, 0.0) > sea.spreading(3.0 * omega_p, 0.0));
        // No wind: isotropic.
        let calm = SeaConditions::new(0.0, 0.0).unwrap();
        assert_eq!(calm.spreading(1.0, 2.0), 1.0 / TAU);
    }

    /// `∫∫ P(kx, ky) dkx dky` in polar form, log-spaced in k.
    fn wavenumber_variance(sea: &SeaConditions) -> f64 {
        let (lo, hi) = (1e-5_f64.ln(), 2000.0_f64.ln());
        let (k_steps, theta_steps) = (1600, 720);
        let du = (hi - lo) / f64::from(k_steps);
        let dtheta = TAU / f64::from(theta_steps);
        let mut total = 0.0;
        for i in 0..k_steps {
            let k = (lo + du * (f64::from(i) + 0.5)).exp();
            for j in 0..theta_steps {
                let theta = dtheta * (f64::from(j) + 0.5);
                // dkx dky = k dk dθ = k² du dθ.
                total += sea.wavenumber_spectrum(k * theta.cos(), k * theta.sin()) * k * k;
            }
        }
        total * du * dtheta
    }

    #[test]
    fn the_wavenumber_spectrum_holds_the_same_variance() {
        let swell = Swell::new(2.0, 12.0, 300.0).unwrap();
        for sea in [
            SeaConditions::new(10.0, 45.0).unwrap(),
            SeaConditions::new(7.0, 200.0)
                .unwrap()
                .with_fetch_m(30_000.0)
                .unwrap()
                .with_depth_m(15.0)
                .unwrap()
                .with_swell(swell)
                .unwrap(),
        ] {
            let m0 = (sea.expected_hs_m() / 4.0).powi(2);
            let variance = wavenumber_variance(&sea);
            assert!(rel(variance, m0) < 2e-3, "{variance} vs {m0}");
        }
        // The swell alone keeps its height.
        let swell_only = SeaConditions::new(0.0, 0.0)
            .unwrap()
            .with_swell(swell)
            .unwrap();
        assert!(rel(swell_only.expected_hs_m(), 2.0) < 1e-4);
    }

    #[test]
    fn the_wavenumber_spectrum_points_downwind() {
        // Wind from the north: waves travel south (negative ky).
        let sea = SeaConditions::new(10.0, 0.0).unwrap();
        let k = 0.1;
        assert!(sea.wavenumber_spectrum(0.0, -k) > 10.0 * sea.wavenumber_spectrum(0.0, k));
        assert!(sea.wavenumber_spectrum(0.0, -k) > sea.wavenumber_spectrum(k, 0.0));
        assert_eq!(sea.wavenumber_spectrum(0.0, 0.0), 0.0);
        // Wind from 270 (west): waves travel east.
        let sea = SeaConditions::new(10.0, 270.0).unwrap();
        assert!(sea.wavenumber_spectrum(k, 0.0) > 10.0 * sea.wavenumber_spectrum(-k, 0.0));
        assert_eq!(sea.waves_toward_deg(), 90.0);
    }

    #[test]
    fn sea_state_codes_round_trip() {
        for code in 0..=9_u8 {
            let (lo, hi) = sea_state_hs_range_m(code).unwrap();
            let sea = SeaConditions::for_sea_state(code, 10.0).unwrap();
            let hs = sea.expected_hs_m();
            if code == 0 {
                assert_eq!(sea.wind_speed_mps, 0.0);
                assert_eq!(hs, 0.0);
            } else {
                assert!(hs > lo && hs < hi, "{code}: {hs}");
            }
            assert_eq!(sea_state_for_hs(hs), code);
            assert!(sea.wind_speed_mps <= 30.0);
        }
        assert_eq!(sea_state_for_hs(0.5), 2);
        assert_eq!(sea_state_for_hs(0.51), 3);
        assert_eq!(sea_state_for_hs(30.0), 9);
        assert_eq!(sea_state_for_hs(f64::NAN), 0);
        assert_eq!(sea_state_for_hs(-1.0), 0);
    }

    #[test]
    fn whitecaps_follow_monahan() {
        assert!(rel(whitecap_fraction_monahan(10.0), 0.00987) < 0.01);
        assert!(rel(whitecap_fraction_monahan(15.0), 0.0393) < 0.01);
        assert_eq!(whitecap_fraction_monahan(0.0), 0.0);
        assert_eq!(whitecap_fraction_monahan(-3.0), 0.0);
        assert_eq!(whitecap_fraction_monahan(60.0), WHITECAP_FRACTION_CAP);
    }

    #[test]
    fn bad_inputs_are_refused() {
        assert!(SeaConditions::new(f64::NAN, 0.0).is_err());
        assert!(SeaConditions::new(-1.0, 0.0).is_err());
        assert!(SeaConditions::new(61.0, 0.0).is_err());
        assert!(SeaConditions::new(10.0, f64::INFINITY).is_err());
        let sea = SeaConditions::new(10.0, -90.0).unwrap();
        assert_eq!(sea.wind_from_deg, 270.0);
        assert!(sea.clone().with_fetch_m(0.0).is_err());
        assert!(sea.clone().with_fetch_m(f64::NAN).is_err());
        assert!(sea.clone().with_depth_m(-5.0).is_err());
        assert!(sea.clone().with_depth_m(f64::INFINITY).is_err());
        assert!(Swell::new(21.0, 10.0, 0.0).is_err());
        assert!(Swell::new(1.0, 1.0, 0.0).is_err());
        assert!(Swell::new(1.0, f64::NAN, 0.0).is_err());
        let bad_swell = Swell {
            height_m: -1.0,
            period_s: 10.0,
            from_deg: 0.0,
        };
        assert!(sea.clone().with_swell(bad_swell).is_err());
        assert!(SeaConditions::for_sea_state(10, 0.0).is_err());
        assert!(sea_state_hs_range_m(10).is_err());
        let hand_made = SeaConditions {
            fetch_m: Some(-1.0),
            ..sea
        };
        assert!(hand_made.validate().is_err());
        let message = SeaConditions::new(f64::NAN, 0.0).unwrap_err().to_string();
        assert!(message.contains("wind speed"), "{message}");
    }

    #[test]
    fn ln_gamma_is_accurate() {
        // Γ(n) = (n-1)!, Γ(½) = √π.
        assert!((ln_gamma(5.0) - 24.0_f64.ln()).abs() < 1e-12);
        assert!((ln_gamma(0.5) - PI.sqrt().ln()).abs() < 1e-12);
        assert!((ln_gamma(1.0)).abs() < 1e-12);
        assert!((spreading_normalisation(0.0) - 1.0 / TAU).abs() < 1e-14);
        // Large s: Q(s) → √(s/(4π)).
        let s = 1e6;
        assert!(rel(spreading_normalisation(s), (s / (4.0 * PI)).sqrt()) < 1e-5);
    }

    proptest! {
        #[test]
        fn spreading_is_non_negative_and_normalised(s in 0.0..400.0_f64, theta in -PI..PI) {
            prop_assert!(spreading_cos2s(s, theta) >= 0.0);
            prop_assert!(spreading_cos2s(s, theta) <= spreading_cos2s(s, 0.0));
            let steps = 4000;
            let h = TAU / f64::from(steps);
            let total: f64 = (0..steps)
                .map(|i| spreading_cos2s(s, -PI + h * (f64::from(i) + 0.5)) * h)
                .sum();
            prop_assert!((total - 1.0).abs() < 1e-4, "s {}: {}", s, total);
        }

        #[test]
        fn the_spectrum_is_finite_and_non_negative(
            u10 in 0.0..60.0_f64,
            omega in 0.0..50.0_f64,
            fetch in 1.0..1e7_f64,
            depth in 0.5..5000.0_f64,
        ) {
            let sea = SeaConditions::new(u10, 33.0).unwrap()
                .with_fetch_m(fetch).unwrap()
                .with_depth_m(depth).unwrap();
            let s = sea.omega_spectrum(omega);
            prop_assert!(s.is_finite() && s >= 0.0);
            let p = sea.wavenumber_spectrum(omega * 0.1, -omega * 0.05);
            prop_assert!(p.is_finite() && p >= 0.0);
        }
    }
}
