//! Band radiance of a black body: the Planck integral over a wavelength band.
//!
//! Algorithm: the integral the ship-imagery source writes for the 8-12 um band (source 001,
//! "Thermal Emission"; its shape was lost in the scan and is restored in `INDEX.md`),
//! `L = integral from l1 to l2 of c1L / (l^5 (exp(c2 / (l T)) - 1)) dl`, evaluated without
//! quadrature. With `x = c2 / (l T)` the short-wavelength side `integral from 0 to l` is
//! `c1L (T/c2)^4 F(x)` with `F(x) = integral from x to infinity of t^3 / (e^t - 1) dt`.
//! - For `x >= 2`, Widger and Woodall's series (Bull. Amer. Meteor. Soc. 57:1217, 1976):
//!   `F(x) = sum over n of e^(-n x) (x^3/n + 3 x^2/n^2 + 6 x/n^3 + 6/n^4)`, summed until a
//!   term no longer changes the sum (at most 40 terms at x = 2).
//! - For `x < 2`, where that series converges slowly, the complement
//!   `F(x) = pi^4/15 - integral from 0 to x of t^3 / (e^t - 1) dt` with the integrand's
//!   Bernoulli expansion `t^3 / (e^t - 1) = sum B_k t^(k+2) / k!` integrated term by term
//!   (it converges for `x < 2 pi`; at `x = 2` the terms fall by about `(x / 2 pi)^2` each).
//!
//! The band value is the difference of the two one-sided integrals. Constants are CODATA 2018
//! (exact SI values of h, c and k). Radiances are in W m-2 sr-1; band edges in micrometres.
//! Limits: a black body; emissivity and the atmosphere are applied by the callers.

use crate::ThermalError;

/// Planck constant, J s (exact, SI 2019).
const PLANCK_J_S: f64 = 6.626_070_15e-34;
/// Speed of light, m/s (exact).
const LIGHT_M_S: f64 = 299_792_458.0;
/// Boltzmann constant, J/K (exact, SI 2019).
const BOLTZMANN_J_K: f64 = 1.380_649e-23;
/// First radiation constant for radiance, 2 h c^2, W m^2 sr-1.
pub const C1L_W_M2_SR: f64 = 2.0 * PLANCK_J_S * LIGHT_M_S * LIGHT_M_S;
/// Second radiation constant, h c / k, m K.
pub const C2_M_K: f64 = PLANCK_J_S * LIGHT_M_S / BOLTZMANN_J_K;
/// Stefan-Boltzmann constant, W m-2 K-4 (from the exact constants).
pub const STEFAN_BOLTZMANN: f64 = 5.670_374_419e-8;

/// A wavelength band, micrometres.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Band {
    /// Short edge, micrometres.
    pub lo_um: f64,
    /// Long edge, micrometres.
    pub hi_um: f64,
}

impl Band {
    /// The long-wave infrared window, 8-12 um.
    pub const LWIR: Band = Band {
        lo_um: 8.0,
        hi_um: 12.0,
    };
    /// The mid-wave infrared window, 3-5 um.
    pub const MWIR: Band = Band {
        lo_um: 3.0,
        hi_um: 5.0,
    };

    /// A band with `0 < lo_um < hi_um`, both finite.
    pub fn new(lo_um: f64, hi_um: f64) -> Result<Band, ThermalError> {
        if !(lo_um.is_finite() && hi_um.is_finite() && lo_um > 0.0 && hi_um > lo_um) {
            return Err(ThermalError::InvalidBand { lo_um, hi_um });
        }
        Ok(Band { lo_um, hi_um })
    }

    /// Parses `8-12`, `3-5` or `LO-HI` (micrometres).
    pub fn parse(text: &str) -> Result<Band, ThermalError> {
        let bad = || ThermalError::UnparsableBand(text.to_string());
        let (lo, hi) = text.trim().split_once('-').ok_or_else(bad)?;
        let lo: f64 = lo.trim().parse().map_err(|_| bad())?;
        let hi: f64 = hi.trim().parse().map_err(|_| bad())?;
        Band::new(lo, hi)
    }
}

/// `pi^4 / 15`: `F(0)`, the whole spectrum.
const F_TOTAL: f64 =
    std::f64::consts::PI * std::f64::consts::PI * std::f64::consts::PI * std::f64::consts::PI
        / 15.0;

/// Taylor coefficients `a_k = B_k / k!` of `t / (e^t - 1)`, k = 0..=32, from the recurrence
/// `sum over j = 0..=m of a_j / (m + 1 - j)! = 0` (m >= 1), `a_0 = 1`.
const BERNOULLI_OVER_FACTORIAL: [f64; 33] = bernoulli_over_factorial();

const fn bernoulli_over_factorial() -> [f64; 33] {
    let mut inverse_factorial = [0.0; 35];
    inverse_factorial[0] = 1.0;
    let mut i = 1;
    while i < 35 {
        inverse_factorial[i] = inverse_factorial[i - 1] / i as f64;
        i += 1;
    }
    let mut a = [0.0; 33];
    a[0] = 1.0;
    let mut m = 1;
    while m < 33 {
        let mut sum = 0.0;
        let mut j = 0;
        while j < m {
            sum += a[j] * inverse_factorial[m + 1 - j];
            j += 1;
        }
        a[m] = -sum;
        m += 1;
    }
    a
}

/// `integral from x to infinity of t^3 / (e^t - 1) dt`, for `x >= 0`.
pub fn planck_tail(x: f64) -> f64 {
    if !x.is_finite() {
        return 0.0;
    }
    if x >= 2.0 {
        let (x2, x3) = (x * x, x * x * x);
        let mut sum = 0.0;
        for n in 1..=200 {
            let nf = n as f64;
            let term = (-nf * x).exp()
                * (x3 / nf
                    + 3.0 * x2 / (nf * nf)
                    + 6.0 * x / (nf * nf * nf)
                    + 6.0 / (nf * nf * nf * nf));
            sum += term;
            if term <= sum * 1e-17 {
                break;
            }
        }
        sum
    } else {
        F_TOTAL - planck_head(x)
    }
}

/// `integral from 0 to x of t^3 / (e^t - 1) dt` by the Bernoulli series, for `0 <= x < 2`.
fn planck_head(x: f64) -> f64 {
    let x = x.max(0.0);
    // integral from 0 to x of t^2 (1 - t/2 + sum B_k t^k / k!) dt.
    // Odd k > 1 have B_k = 0, so only even k contribute after the first two terms.
    let x3 = x * x * x;
    let mut head = x3 / 3.0 - x3 * x / 8.0;
    let x2 = x * x;
    let mut power = x3 * x2; // x^(k+3) for k = 2
    for k in (2..BERNOULLI_OVER_FACTORIAL.len()).step_by(2) {
        let term = BERNOULLI_OVER_FACTORIAL[k] * power / (k as f64 + 3.0);
        head += term;
        if term.abs() <= head.abs() * 1e-17 {
            break;
        }
        power *= x2;
    }
    head
}

/// `integral from x_small to x_large of t^3 / (e^t - 1) dt` (`x_small <= x_large`), taken
/// from the heads where both are below 2, so very hot bodies lose no precision to the
/// difference of two nearly equal tails.
fn planck_between(x_small: f64, x_large: f64) -> f64 {
    if x_large < 2.0 {
        planck_head(x_large) - planck_head(x_small)
    } else {
        planck_tail(x_small) - planck_tail(x_large)
    }
}

/// Black-body radiance in `band` at `temp_k`, W m-2 sr-1. `temp_k` must be finite and > 0.
pub fn band_radiance(band: Band, temp_k: f64) -> Result<f64, ThermalError> {
    if !(temp_k.is_finite() && temp_k > 0.0) {
        return Err(ThermalError::InvalidTemperature(temp_k));
    }
    Ok(band_radiance_unchecked(band, temp_k))
}

/// [`band_radiance`] for a temperature the caller knows is finite and positive (inner loops).
pub fn band_radiance_unchecked(band: Band, temp_k: f64) -> f64 {
    let x = |wavelength_um: f64| C2_M_K / (wavelength_um * 1e-6 * temp_k);
    let scale = temp_k / C2_M_K;
    let between = planck_between(x(band.hi_um), x(band.lo_um));
    (C1L_W_M2_SR * scale * scale * scale * scale * between).max(0.0)
}

/// `d L / d T` in `band` at `temp_k`, W m-2 sr-1 K-1 (central difference of the exact series).
pub fn band_radiance_slope(band: Band, temp_k: f64) -> f64 {
    let dt = 1e-3 * temp_k.max(1.0);
    (band_radiance_unchecked(band, temp_k + dt) - band_radiance_unchecked(band, temp_k - dt))
        / (2.0 * dt)
}

/// The temperature whose black-body radiance in `band` is `radiance_w_m2_sr` (the brightness
/// temperature), kelvin; `None` for a radiance that is not finite and positive.
pub fn brightness_temperature_k(band: Band, radiance_w_m2_sr: f64) -> Option<f64> {
    if !(radiance_w_m2_sr.is_finite() && radiance_w_m2_sr > 0.0) {
        return None;
    }
    // Bracket, then Newton steps safeguarded by bisection on ln L (monotonic in T).
    let (mut lo, mut hi) = (1.0_f64, 1.0e5_f64);
    if band_radiance_unchecked(band, hi) < radiance_w_m2_sr {
        return None;
    }
    let mut t = 300.0_f64.clamp(lo, hi);
    for _ in 0..200 {
        let l = band_radiance_unchecked(band, t);
        if l < radiance_w_m2_sr {
            lo = t;
        } else {
            hi = t;
        }
        let slope = band_radiance_slope(band, t);
        let mut next = t - (l - radiance_w_m2_sr) / slope;
        if !(next.is_finite() && next > lo && next < hi) {
            next = 0.5 * (lo + hi);
        }
        if (next - t).abs() <= 1e-10 * t {
            return Some(next);
        }
        t = next;
    }
    Some(t)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Composite Gauss-Legendre quadrature of the Planck function over the band in
    /// wavelength: an independent reference for the series.
    fn quadrature(band: Band, temp_k: f64) -> f64 {
        // 5-point Gauss-Legendre nodes and weights on [-1, 1].
        const NODES: [f64; 5] = [
            0.0,
            -0.538_469_310_105_683,
            0.538_469_310_105_683,
            -0.906_179_845_938_664,
            0.906_179_845_938_664,
        ];
        const WEIGHTS: [f64; 5] = [
            0.568_888_888_888_889,
            0.478_628_670_499_366,
            0.478_628_670_499_366,
            0.236_926_885_056_189,
            0.236_926_885_056_189,
        ];
        let planck = |l_um: f64| {
            let l = l_um * 1e-6;
            C1L_W_M2_SR / (l.powi(5) * ((C2_M_K / (l * temp_k)).exp() - 1.0)) * 1e-6
        };
        let panels = 4000;
        let h = (band.hi_um - band.lo_um) / panels as f64;
        let mut sum = 0.0;
        for p in 0..panels {
            let mid = band.lo_um + (p as f64 + 0.5) * h;
            for (x, w) in NODES.iter().zip(WEIGHTS) {
                sum += w * planck(mid + 0.5 * h * x);
            }
        }
        sum * 0.5 * h
    }

    #[test]
    fn lwir_at_300_k_is_the_reference_value() {
        let l = band_radiance(Band::LWIR, 300.0).expect("valid");
        assert!((l - 38.5004).abs() < 1e-4 * 0.5, "{l}");
    }

    #[test]
    fn series_matches_quadrature_from_200_to_1500_k() {
        for band in [Band::LWIR, Band::MWIR, Band::new(0.5, 30.0).expect("band")] {
            let mut t = 200.0;
            while t <= 1500.0 {
                let series = band_radiance(band, t).expect("valid");
                let reference = quadrature(band, t);
                let rel = (series - reference).abs() / reference;
                assert!(
                    rel < 1e-6,
                    "{band:?} at {t} K: {series} vs {reference} ({rel:e})"
                );
                t += 50.0;
            }
        }
    }

    #[test]
    fn whole_spectrum_is_stefan_boltzmann_over_pi() {
        for t in [100.0, 300.0, 1000.0] {
            let l = band_radiance(Band::new(1e-3, 1e7).expect("band"), t).expect("valid");
            let expected = STEFAN_BOLTZMANN * t.powi(4) / std::f64::consts::PI;
            assert!(
                (l - expected).abs() / expected < 1e-8,
                "{t}: {l} vs {expected}"
            );
        }
    }

    #[test]
    fn bernoulli_coefficients_are_the_known_values() {
        let a = BERNOULLI_OVER_FACTORIAL;
        assert!((a[1] + 0.5).abs() < 1e-15);
        assert!((a[2] - 1.0 / 12.0).abs() < 1e-15);
        assert!((a[4] + 1.0 / 720.0).abs() < 1e-16);
        assert!((a[12] + 691.0 / 1_307_674_368_000.0).abs() < 1e-22);
        assert!(a[3].abs() < 1e-15 && a[5].abs() < 1e-15);
    }

    #[test]
    fn the_two_series_agree_where_they_meet() {
        // Both branches a hair either side of x = 2: they differ by the slope (about -1.25)
        // times the step, not by a jump.
        let below = planck_tail(2.0 - 1e-12);
        let above = planck_tail(2.0);
        assert!(
            (below - above - 1.25e-12).abs() < 1e-13,
            "{below} vs {above}"
        );
    }

    #[test]
    fn very_hot_bodies_keep_their_precision() {
        // Rayleigh-Jeans: at x << 1 the band radiance is 2 c k T (1/l1^3 - 1/l2^3) / 3.
        for t in [1.0e7, 1.0e9, 1.0e11] {
            let l = band_radiance(Band::LWIR, t).expect("valid");
            let (l1, l2) = (8e-6_f64, 12e-6_f64);
            let rj =
                2.0 * LIGHT_M_S * BOLTZMANN_J_K * t * (1.0 / l1.powi(3) - 1.0 / l2.powi(3)) / 3.0;
            assert!(
                (l - rj).abs() / rj < 2e-3,
                "{t} K: {l} vs Rayleigh-Jeans {rj}"
            );
        }
    }

    #[test]
    fn slope_at_300_k_in_lwir_is_about_0_63() {
        let s = band_radiance_slope(Band::LWIR, 300.0);
        assert!((s - 0.63).abs() < 0.01, "{s}");
    }

    #[test]
    fn bad_inputs_are_refused() {
        assert!(band_radiance(Band::LWIR, 0.0).is_err());
        assert!(band_radiance(Band::LWIR, -5.0).is_err());
        assert!(band_radiance(Band::LWIR, f64::NAN).is_err());
        assert!(Band::new(12.0, 8.0).is_err());
        assert!(Band::new(8.0, 8.0).is_err());
        assert!(Band::new(0.0, 8.0).is_err());
        assert!(Band::parse("8to12").is_err());
        assert!(Band::parse("12-8").is_err());
        assert_eq!(Band::parse("8-12").expect("band"), Band::LWIR);
    }

    proptest::proptest! {
        #[test]
        fn brightness_temperature_inverts_radiance(t in 150.0f64..2000.0) {
            for band in [Band::LWIR, Band::MWIR] {
                let l = band_radiance(band, t).expect("valid");
                let back = brightness_temperature_k(band, l).expect("inverts");
                proptest::prop_assert!((back - t).abs() < 1e-6 * t, "{} vs {}", back, t);
            }
        }

        #[test]
        fn radiance_rises_with_temperature(t in 100.0f64..3000.0, dt in 0.01f64..100.0) {
            proptest::prop_assert!(band_radiance(Band::LWIR, t + dt).expect("v") > band_radiance(Band::LWIR, t).expect("v"));
        }
    }
}
