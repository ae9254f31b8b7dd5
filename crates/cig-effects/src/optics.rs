//! Transmittance of a line of sight through obscurant puffs.
//!
//! Algorithm (source 000 chapter II.A, Eq 1-4, after Gardner): `T = exp(-alpha * integral of
//! C dl)` along the path, with each puff a Gaussian blob of concentration
//! `C = M / ((2 pi)^(3/2) sigma^3) exp(-D^2 / 2)`, `D = |p - c| / sigma` (Eq 2-3 with equal
//! sigmas). Along a segment `a + s d`, `0 <= s <= L`, with `s0 = d . (c - a)` and `b` the
//! distance of the centre from the line, the integral is closed-form:
//! `M / (2 pi sigma^2) exp(-b^2 / (2 sigma^2)) * (erf((L - s0) / (sigma sqrt 2)) +
//! erf(s0 / (sigma sqrt 2))) / 2` (`libm::erf`, bit-identical on every machine). Optical depths
//! of all puffs add; `alpha` is a mass extinction coefficient per obscurant kind.
//!
//! Mass extinction coefficients (visible band; Eq 1's wavelength dependence folded into one
//! alpha per kind): smoke 8.7 m^2/g, the specific extinction coefficient of flame-generated soot
//! (Mulholland and Croarkin 2000, 633 nm); dust 0.58 m^2/g, `3 Q_ext / (2 rho_p r)` for mineral
//! grains of radius 2 um, density 2600 kg/m^3 and extinction efficiency 2; flame 0.5 m^2/g
//! (luminous gas carrying little soot: a visual choice, not a measurement).
//!
//! Limits: isotropic puffs (Gardner's ellipsoids have three sigmas); one wavelength band; no
//! scattering into the path (no glare, no multiple scattering). Puffs whose centre is more than 8 sigma from the line are skipped
//! (their share is below e^-32).

use glam::DVec3;

/// Kind of obscurant a puff is made of.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
#[repr(u32)]
pub enum ObscurantKind {
    Smoke = 0,
    Flame = 1,
    Dust = 2,
}

impl ObscurantKind {
    /// Every kind.
    pub const ALL: [ObscurantKind; 3] = [
        ObscurantKind::Smoke,
        ObscurantKind::Flame,
        ObscurantKind::Dust,
    ];

    /// Visible-band mass extinction coefficient, m^2/kg.
    pub fn mass_extinction_m2_per_kg(self) -> f64 {
        match self {
            ObscurantKind::Smoke => 8700.0,
            ObscurantKind::Flame => 500.0,
            ObscurantKind::Dust => 580.0,
        }
    }

    /// snake_case name.
    pub fn name(self) -> &'static str {
        match self {
            ObscurantKind::Smoke => "smoke",
            ObscurantKind::Flame => "flame",
            ObscurantKind::Dust => "dust",
        }
    }
}

/// Puffs further than this many sigmas from a line add nothing to its optical depth.
pub const CUTOFF_SIGMAS: f64 = 8.0;

/// Integral of one Gaussian puff's concentration along the segment `a -> b`, kg/m^2.
///
/// `centre` and the endpoints in one metric frame; `mass_kg` >= 0, `sigma_m` > 0.
pub fn gaussian_path_integral_kg_m2(
    a: DVec3,
    b: DVec3,
    centre: DVec3,
    mass_kg: f64,
    sigma_m: f64,
) -> f64 {
    if sigma_m.is_nan() || sigma_m <= 0.0 || mass_kg.is_nan() || mass_kg <= 0.0 {
        return 0.0;
    }
    let ab = b - a;
    let length = ab.length();
    let ac = centre - a;
    if length.is_nan() || length <= 0.0 {
        return 0.0;
    }
    let d = ab / length;
    let s0 = d.dot(ac);
    let b2 = (ac.length_squared() - s0 * s0).max(0.0);
    let two_sigma2 = 2.0 * sigma_m * sigma_m;
    if b2 > CUTOFF_SIGMAS * CUTOFF_SIGMAS * sigma_m * sigma_m {
        return 0.0;
    }
    let scale = 1.0 / (std::f64::consts::SQRT_2 * sigma_m);
    let along = 0.5 * (libm::erf((length - s0) * scale) + libm::erf(s0 * scale));
    mass_kg / (std::f64::consts::PI * two_sigma2) * libm::exp(-b2 / two_sigma2) * along
}

/// Peak optical depth of a puff seen through its centre: `alpha M / (2 pi sigma^2)`.
pub fn centre_optical_depth(kind: ObscurantKind, mass_kg: f64, sigma_m: f64) -> f64 {
    if sigma_m.is_nan() || sigma_m <= 0.0 {
        return 0.0;
    }
    kind.mass_extinction_m2_per_kg() * mass_kg / (2.0 * std::f64::consts::PI * sigma_m * sigma_m)
}

/// The answer to "how much of the light gets through".
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Transmittance {
    /// Fraction of the light transmitted, 0-1.
    pub transmittance: f64,
    /// Total optical depth `sum alpha integral C dl`.
    pub optical_depth: f64,
    /// Puffs that added to the optical depth.
    pub puffs_crossed: u32,
}

impl Transmittance {
    /// A clear line.
    pub const CLEAR: Transmittance = Transmittance {
        transmittance: 1.0,
        optical_depth: 0.0,
        puffs_crossed: 0,
    };

    /// Whether less than `threshold` of the light gets through.
    pub fn obscured(&self, threshold: f64) -> bool {
        self.transmittance < threshold
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// Concentration of Eq 2-3 at a point.
    fn concentration(p: DVec3, c: DVec3, m: f64, sigma: f64) -> f64 {
        let d2 = (p - c).length_squared() / (sigma * sigma);
        m / ((2.0 * std::f64::consts::PI).powf(1.5) * sigma.powi(3)) * (-0.5 * d2).exp()
    }

    /// Composite Simpson integration of Eq 2 along the segment.
    fn numeric(a: DVec3, b: DVec3, c: DVec3, m: f64, sigma: f64) -> f64 {
        let n = 20_000;
        let h = 1.0 / n as f64;
        let len = (b - a).length();
        let mut sum = 0.0;
        for i in 0..=n {
            let t = i as f64 * h;
            let w = if i == 0 || i == n {
                1.0
            } else if i % 2 == 1 {
                4.0
            } else {
                2.0
            };
            sum += w * concentration(a + (b - a) * t, c, m, sigma);
        }
        sum * h / 3.0 * len
    }

    #[test]
    fn through_the_centre_of_a_puff_on_an_infinite_line() {
        let c = DVec3::new(10.0, 5.0, 2.0);
        let a = c - DVec3::X * 1000.0;
        let b = c + DVec3::X * 1000.0;
        let v = gaussian_path_integral_kg_m2(a, b, c, 2.0, 3.0);
        assert!((v - 2.0 / (2.0 * std::f64::consts::PI * 9.0)).abs() < 1e-12);
        // Half the line gives half.
        let half = gaussian_path_integral_kg_m2(a, c, c, 2.0, 3.0);
        assert!((half - v / 2.0).abs() < 1e-12);
        assert_eq!(gaussian_path_integral_kg_m2(a, a, c, 2.0, 3.0), 0.0);
        assert_eq!(gaussian_path_integral_kg_m2(a, b, c, 2.0, 0.0), 0.0);
    }

    proptest! {
        #[test]
        fn analytic_integral_agrees_with_numeric_integration(
            ax in -20.0f64..20.0, ay in -20.0f64..20.0, az in -20.0f64..20.0,
            bx in -20.0f64..20.0, by in -20.0f64..20.0, bz in -20.0f64..20.0,
            sigma in 0.5f64..10.0, m in 0.001f64..10.0,
        ) {
            let (a, b) = (DVec3::new(ax, ay, az), DVec3::new(bx, by, bz));
            prop_assume!((b - a).length() > 0.1);
            let c = DVec3::new(1.0, -2.0, 0.5);
            let exact = gaussian_path_integral_kg_m2(a, b, c, m, sigma);
            let approx = numeric(a, b, c, m, sigma);
            // Beyond 8 sigma the analytic form returns 0: at most e^-32 of the peak line integral.
            let cutoff = m / (2.0 * std::f64::consts::PI * sigma * sigma) * (-32.0f64).exp();
            prop_assert!((exact - approx).abs() <= 1e-7 * approx + cutoff,
                "analytic {exact} numeric {approx}");
        }

        #[test]
        fn integral_grows_with_path_length(
            sigma in 0.5f64..10.0, offset in 0.0f64..20.0, l1 in 0.0f64..100.0, dl in 0.0f64..100.0,
        ) {
            let c = DVec3::new(30.0, offset, 0.0);
            let a = DVec3::ZERO;
            let short = gaussian_path_integral_kg_m2(a, DVec3::X * l1, c, 1.0, sigma);
            let long = gaussian_path_integral_kg_m2(a, DVec3::X * (l1 + dl), c, 1.0, sigma);
            prop_assert!(long >= short);
        }
    }
}
