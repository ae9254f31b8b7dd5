//! Rain and snow: how a precipitation rate lowers the visibility, how fast the particles fall,
//! and how many there are.
//!
//! Algorithm: the particles follow an exponential size distribution `N(D) = N0 exp(-Λ D)`
//! (m⁻³ mm⁻¹, `D` in mm). Rain: Marshall & Palmer (1948), `N0 = 8000`, `Λ = 4.1 R^-0.21`.
//! Snow: Gunn & Marshall (1958) in melted diameter, `N0 = 3800 R^-0.87`, `Λ = 2.55 R^-0.48`,
//! with the flake's diameter `(ρ_water / ρ_snow)^(1/3)` times the melted one for dry aggregates
//! of bulk density 0.05 g/cm³ (Magono & Nakamura 1965 give 0.01-0.1). The particles are large
//! against the wavelength, so the extinction efficiency is 2 (the geometric-optics limit, as in
//! Atlas 1953) and the extinction coefficient is
//! `σ = 2 ∫ (π/4) D² N(D) dD = π N0 / Λ³` (in mm² m⁻³, times 1e-6 for m⁻¹), i.e.
//! `σ_rain ≈ 0.365 R^0.63 km⁻¹` and `σ_snow ≈ 5.3 R^0.57 km⁻¹` (`R` in mm/h of water):
//! 1 mm/h of rain leaves about 10.7 km of visibility, 1 mm/h of snow about 0.74 km, the
//! tenfold difference Rasmussen et al. (1999, "The estimation of snowfall rate using
//! visibility") describe. The visibility is Koschmieder's `V = 3.912 / σ`, and precipitation
//! in fog or haze adds its extinction to theirs: `V = 3.912 / (3.912 / V_fog + σ)`.
//! Fall speeds: rain at the median volume diameter `D0 = 3.67 / Λ` by Atlas, Srivastava &
//! Sekhon (1973), `v = 9.65 - 10.3 exp(-0.6 D0)` m/s (about 6.5 m/s for a 2 mm drop); snow
//! aggregates at 1 m/s (Locatelli & Hobbs 1974 measure 0.8-1.5 m/s) with a sideways sway.
//! Sleet falls as small ice pellets and is treated as rain of the same rate with a fall speed of
//! 4 m/s; hail is not modelled.
//!
//! Limits: one distribution per kind; visibility in snow varies by a factor of 3-10 with the
//! crystal type, riming and wetness (Rasmussen et al.), and this model takes dry aggregates; no
//! drizzle or fog droplets (give those as fog visibility); the visibility is a daytime one
//! (at night lights are seen further, which Koschmieder does not cover).

use crate::EnvironmentError;
use serde::{Deserialize, Serialize};

/// Koschmieder's constant, `-ln(0.02)`.
pub const KOSCHMIEDER: f64 = 3.912;
/// The largest rate accepted, mm/h (the heaviest recorded rainfall rates are about this).
pub const MAX_RATE_MM_PER_H: f64 = 200.0;
/// Bulk density of a dry snow aggregate over that of water.
const SNOW_DENSITY_RATIO: f64 = 0.05;
/// Snow aggregates' fall speed, m/s.
const SNOW_FALL_SPEED_MPS: f64 = 1.0;
/// Sleet (ice pellets) fall speed, m/s.
const SLEET_FALL_SPEED_MPS: f64 = 4.0;

/// What falls.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PrecipitationKind {
    #[default]
    Rain,
    Snow,
    Sleet,
}

impl PrecipitationKind {
    /// Parses `rain`, `snow`, `sleet`.
    pub fn parse(text: &str) -> Option<PrecipitationKind> {
        match text.trim().to_ascii_lowercase().as_str() {
            "rain" => Some(PrecipitationKind::Rain),
            "snow" => Some(PrecipitationKind::Snow),
            "sleet" => Some(PrecipitationKind::Sleet),
            _ => None,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            PrecipitationKind::Rain => "rain",
            PrecipitationKind::Snow => "snow",
            PrecipitationKind::Sleet => "sleet",
        }
    }
}

/// Precipitation of one kind at one rate.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Precipitation {
    pub kind: PrecipitationKind,
    /// Rate as water, mm/h.
    pub rate_mm_per_h: f64,
}

/// The size distribution's `(N0 in m⁻³ mm⁻¹, Λ in mm⁻¹)` in melted (water) diameter.
fn distribution(kind: PrecipitationKind, rate_mm_per_h: f64) -> (f64, f64) {
    let r = rate_mm_per_h;
    match kind {
        PrecipitationKind::Rain | PrecipitationKind::Sleet => (8000.0, 4.1 * r.powf(-0.21)),
        PrecipitationKind::Snow => (3800.0 * r.powf(-0.87), 2.55 * r.powf(-0.48)),
    }
}

/// Geometric diameter over melted diameter.
fn diameter_ratio(kind: PrecipitationKind) -> f64 {
    match kind {
        PrecipitationKind::Snow => (1.0 / SNOW_DENSITY_RATIO).cbrt(),
        PrecipitationKind::Rain | PrecipitationKind::Sleet => 1.0,
    }
}

impl Precipitation {
    /// Checks the rate (finite, 0..=200 mm/h).
    ///
    /// # Errors
    /// [`EnvironmentError::InvalidSetting`] naming the bad rate.
    pub fn new(
        kind: PrecipitationKind,
        rate_mm_per_h: f64,
    ) -> Result<Precipitation, EnvironmentError> {
        if !(rate_mm_per_h.is_finite() && (0.0..=MAX_RATE_MM_PER_H).contains(&rate_mm_per_h)) {
            return Err(EnvironmentError::InvalidSetting(format!(
                "{} rate {rate_mm_per_h} mm/h is outside 0..{MAX_RATE_MM_PER_H}",
                kind.name()
            )));
        }
        Ok(Precipitation {
            kind,
            rate_mm_per_h,
        })
    }

    /// The rate clamped into 0..=200 mm/h (0 for non-finite values), for values from the
    /// network.
    pub fn clamped(kind: PrecipitationKind, rate_mm_per_h: f64) -> Precipitation {
        let rate = if rate_mm_per_h.is_finite() {
            rate_mm_per_h.clamp(0.0, MAX_RATE_MM_PER_H)
        } else {
            0.0
        };
        Precipitation {
            kind,
            rate_mm_per_h: rate,
        }
    }

    /// Extinction coefficient of the falling particles, 1/m (0 without precipitation).
    pub fn extinction_per_m(&self) -> f64 {
        if self.rate_mm_per_h <= 0.0 || !self.rate_mm_per_h.is_finite() {
            return 0.0;
        }
        let (n0, lambda) = distribution(self.kind, self.rate_mm_per_h);
        let k = diameter_ratio(self.kind);
        // 2 * (pi / 4) * k^2 * integral of D^2 N0 exp(-lambda D) dD = pi k^2 N0 / lambda^3.
        std::f64::consts::PI * k * k * n0 / lambda.powi(3) * 1e-6
    }

    /// Meteorological visibility in the precipitation alone, m (infinite without it).
    pub fn visibility_m(&self) -> f64 {
        let sigma = self.extinction_per_m();
        if sigma > 0.0 {
            KOSCHMIEDER / sigma
        } else {
            f64::INFINITY
        }
    }

    /// The visibility of air of visibility `fog_visibility_m` with this precipitation falling
    /// in it: the extinctions add.
    pub fn combined_visibility_m(&self, fog_visibility_m: f64) -> f64 {
        let fog = if fog_visibility_m.is_finite() && fog_visibility_m > 0.0 {
            KOSCHMIEDER / fog_visibility_m
        } else if fog_visibility_m > 0.0 {
            0.0
        } else {
            // No visibility at all stays none.
            return fog_visibility_m.max(0.0);
        };
        let sigma = fog + self.extinction_per_m();
        if sigma > 0.0 {
            KOSCHMIEDER / sigma
        } else {
            f64::INFINITY
        }
    }

    /// Median volume diameter (melted), mm.
    pub fn median_volume_diameter_mm(&self) -> f64 {
        let (_, lambda) = distribution(self.kind, self.rate_mm_per_h.max(1e-3));
        3.67 / lambda
    }

    /// Fall speed of the typical particle, m/s.
    pub fn fall_speed_mps(&self) -> f64 {
        match self.kind {
            PrecipitationKind::Rain => rain_fall_speed_mps(self.median_volume_diameter_mm()),
            PrecipitationKind::Snow => SNOW_FALL_SPEED_MPS,
            PrecipitationKind::Sleet => SLEET_FALL_SPEED_MPS,
        }
    }

    /// Particles per cubic metre larger than `min_diameter_mm` (melted), the ones an eye can
    /// see as streaks or flakes: `N0 / Λ · exp(-Λ D_min)`.
    pub fn number_density_per_m3(&self, min_diameter_mm: f64) -> f64 {
        if self.rate_mm_per_h <= 0.0 || !self.rate_mm_per_h.is_finite() {
            return 0.0;
        }
        let (n0, lambda) = distribution(self.kind, self.rate_mm_per_h);
        n0 / lambda * (-lambda * min_diameter_mm.max(0.0)).exp()
    }
}

impl Precipitation {
    /// Liquid water content of the falling particles, g/m³: `π ρ_w N0 / Λ⁴`
    /// (Marshall-Palmer rain: `0.089 R^0.84`).
    pub fn liquid_water_content_g_per_m3(&self) -> f64 {
        if self.rate_mm_per_h <= 0.0 || !self.rate_mm_per_h.is_finite() {
            return 0.0;
        }
        let (n0, lambda) = distribution(self.kind, self.rate_mm_per_h);
        // mm³ per m³ of water times 1e-3 g/mm³.
        std::f64::consts::PI * n0 / lambda.powi(4) * 1e-3
    }

    /// The rate whose liquid water content is `lwc_g_per_m3` (bisection on the monotone
    /// relation), unclamped above 200 mm/h up to 10 000 mm/h; 0 for non-positive or non-finite
    /// contents.
    pub fn rate_for_water_content(kind: PrecipitationKind, lwc_g_per_m3: f64) -> f64 {
        if !(lwc_g_per_m3.is_finite() && lwc_g_per_m3 > 0.0) {
            return 0.0;
        }
        let lwc = |r: f64| {
            Precipitation {
                kind,
                rate_mm_per_h: r,
            }
            .liquid_water_content_g_per_m3()
        };
        let (mut lo, mut hi) = (0.0f64, 10_000.0f64);
        if lwc(hi) <= lwc_g_per_m3 {
            return hi;
        }
        for _ in 0..100 {
            let mid = 0.5 * (lo + hi);
            if lwc(mid) < lwc_g_per_m3 {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        0.5 * (lo + hi)
    }
}

/// Terminal fall speed of a raindrop of diameter `d_mm` at sea level (Atlas, Srivastava &
/// Sekhon 1973), m/s (0 for drops under 0.1 mm).
pub fn rain_fall_speed_mps(d_mm: f64) -> f64 {
    (9.65 - 10.3 * (-0.6 * d_mm).exp()).max(0.0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// The extinction by numerical integration of the distribution (independent of the closed
    /// form): midpoint rule over 0..60/Λ mm.
    fn integrated_extinction(p: &Precipitation) -> f64 {
        let (n0, lambda) = distribution(p.kind, p.rate_mm_per_h);
        let k = diameter_ratio(p.kind);
        let steps = 30_000;
        let dd = 60.0 / lambda / steps as f64;
        let mut sum = 0.0;
        for i in 0..steps {
            let d = (i as f64 + 0.5) * dd;
            let geometric = k * d;
            sum += 2.0
                * std::f64::consts::FRAC_PI_4
                * geometric
                * geometric
                * n0
                * (-lambda * d).exp()
                * dd;
        }
        sum * 1e-6
    }

    #[test]
    fn closed_form_matches_the_integrated_distribution() {
        for kind in [PrecipitationKind::Rain, PrecipitationKind::Snow] {
            for rate in [0.1, 1.0, 10.0, 100.0] {
                let p = Precipitation::new(kind, rate).unwrap();
                let a = p.extinction_per_m();
                let b = integrated_extinction(&p);
                assert!((a - b).abs() < 1e-3 * a, "{kind:?} {rate}: {a} vs {b}");
            }
        }
    }

    #[test]
    fn reference_points() {
        // Marshall-Palmer in the geometric limit: 0.365 R^0.63 per km.
        let rain = |r| Precipitation::new(PrecipitationKind::Rain, r).unwrap();
        for r in [1.0, 4.0, 25.0] {
            let per_km = rain(r).extinction_per_m() * 1000.0;
            let want = 0.3647 * f64::powf(r, 0.63);
            assert!((per_km - want).abs() < 0.002 * want, "{r}: {per_km}");
        }
        assert!((rain(1.0).visibility_m() - 10_700.0).abs() < 100.0);
        // Heavy rain (25 mm/h): about 1.4 km.
        assert!((rain(25.0).visibility_m() - 1_410.0).abs() < 30.0);
        // Snow at 1 mm/h water: under a kilometre (the NWS's "moderate" to "heavy" snow), a
        // tenth or less of rain's at the same water rate.
        let snow = Precipitation::new(PrecipitationKind::Snow, 1.0).unwrap();
        assert!((600.0..900.0).contains(&snow.visibility_m()));
        assert!(snow.visibility_m() < rain(1.0).visibility_m() / 10.0);
        // A 2 mm drop falls at about 6.5 m/s (Gunn & Kinzer 1949 measured 6.49 m/s).
        assert!((rain_fall_speed_mps(2.0) - 6.49).abs() < 0.1);
        assert!((rain(10.0).fall_speed_mps() - 5.3).abs() < 0.3);
        assert_eq!(snow.fall_speed_mps(), 1.0);
    }

    #[test]
    fn water_content_is_marshall_palmers_and_inverts() {
        for r in [0.5, 5.0, 50.0] {
            let p = Precipitation::new(PrecipitationKind::Rain, r).unwrap();
            let w = p.liquid_water_content_g_per_m3();
            let want = 0.089 * f64::powf(r, 0.84);
            assert!((w - want).abs() < 0.005 * want, "{r}: {w} vs {want}");
            for kind in [PrecipitationKind::Rain, PrecipitationKind::Snow] {
                let p = Precipitation::new(kind, r).unwrap();
                let back =
                    Precipitation::rate_for_water_content(kind, p.liquid_water_content_g_per_m3());
                assert!((back - r).abs() < 1e-6 * r, "{kind:?} {r}: {back}");
            }
        }
        assert_eq!(
            Precipitation::rate_for_water_content(PrecipitationKind::Rain, f64::NAN),
            0.0
        );
        assert_eq!(
            Precipitation::rate_for_water_content(PrecipitationKind::Rain, 1e9),
            10_000.0
        );
    }

    #[test]
    fn extinctions_add_and_nothing_falls_at_zero() {
        let none = Precipitation::new(PrecipitationKind::Rain, 0.0).unwrap();
        assert_eq!(none.extinction_per_m(), 0.0);
        assert_eq!(none.visibility_m(), f64::INFINITY);
        assert!((none.combined_visibility_m(5000.0) - 5000.0).abs() < 1e-9);
        assert_eq!(none.number_density_per_m3(0.5), 0.0);
        let rain = Precipitation::new(PrecipitationKind::Rain, 10.0).unwrap();
        let v = rain.combined_visibility_m(5000.0);
        let want = KOSCHMIEDER / (KOSCHMIEDER / 5000.0 + KOSCHMIEDER / rain.visibility_m());
        assert!((v - want).abs() < 1e-9);
        assert!(v < 5000.0 && v < rain.visibility_m());
        assert_eq!(
            rain.combined_visibility_m(f64::INFINITY),
            rain.visibility_m()
        );
    }

    #[test]
    fn bad_rates_are_errors_and_network_rates_are_clamped() {
        for r in [-1.0, 201.0, f64::NAN, f64::INFINITY] {
            let e = Precipitation::new(PrecipitationKind::Snow, r).unwrap_err();
            assert!(e.to_string().contains("snow rate"), "{e}");
        }
        assert_eq!(
            Precipitation::clamped(PrecipitationKind::Rain, 1e9).rate_mm_per_h,
            MAX_RATE_MM_PER_H
        );
        assert_eq!(
            Precipitation::clamped(PrecipitationKind::Rain, f64::NAN).rate_mm_per_h,
            0.0
        );
        assert_eq!(
            PrecipitationKind::parse(" Snow"),
            Some(PrecipitationKind::Snow)
        );
        assert_eq!(PrecipitationKind::parse("hail"), None);
    }

    proptest! {
        #[test]
        fn visibility_falls_monotonically_with_the_rate(
            a in 0.01f64..200.0, b in 0.01f64..200.0, fog in 10.0f64..1e5, snow in any::<bool>()) {
            let kind = if snow { PrecipitationKind::Snow } else { PrecipitationKind::Rain };
            let (lo, hi) = if a < b { (a, b) } else { (b, a) };
            prop_assume!(hi - lo > 1e-6);
            let p = |r| Precipitation::new(kind, r).unwrap();
            prop_assert!(p(hi).visibility_m() < p(lo).visibility_m());
            prop_assert!(p(hi).combined_visibility_m(fog) < p(lo).combined_visibility_m(fog));
            prop_assert!(p(lo).combined_visibility_m(fog) < fog);
            prop_assert!(p(hi).number_density_per_m3(0.5) > p(lo).number_density_per_m3(0.5) * 0.999 || snow);
        }
    }
}
