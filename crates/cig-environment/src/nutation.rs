//! Nutation in longitude and obliquity, the obliquity of the ecliptic, and
//! Greenwich sidereal time.
//!
//! Algorithm: the IAU 1980 nutation series (63 terms, arguments D, M, M′, F, Ω
//! as cubic polynomials in Julian centuries of TT) and Laskar's polynomial for
//! the mean obliquity, from J. Meeus, *Astronomical Algorithms* (2nd ed.),
//! chapter 22 (Table 22.A, equation 22.3); the same table is used by the NREL
//! SPA (Reda and Andreas, NREL/TP-560-34302, Table A4.3). Greenwich mean
//! sidereal time is Meeus equation 12.4 (IAU 1982), apparent sidereal time adds
//! the equation of the equinoxes `Δψ cos ε`. Limits: the series is good to
//! about 0.01 arcsecond against IAU 2000 over 1900–2100; Laskar's obliquity to
//! 0.01 arcsecond over 1000 years; sidereal time uses UTC for UT1 (an error
//! under 0.9 s of time, 0.004 degree).

/// Multipliers of D, M, M′, F, Ω and coefficients (Δψ: a + b T, Δε: c + d T) in 0.0001".
type NutationTerm = ([i8; 5], f64, f64, f64, f64);

const TERMS: &[NutationTerm] = &[
    ([0, 0, 0, 0, 1], -171_996.0, -174.2, 92025.0, 8.9),
    ([-2, 0, 0, 2, 2], -13187.0, -1.6, 5736.0, -3.1),
    ([0, 0, 0, 2, 2], -2274.0, -0.2, 977.0, -0.5),
    ([0, 0, 0, 0, 2], 2062.0, 0.2, -895.0, 0.5),
    ([0, 1, 0, 0, 0], 1426.0, -3.4, 54.0, -0.1),
    ([0, 0, 1, 0, 0], 712.0, 0.1, -7.0, 0.0),
    ([-2, 1, 0, 2, 2], -517.0, 1.2, 224.0, -0.6),
    ([0, 0, 0, 2, 1], -386.0, -0.4, 200.0, 0.0),
    ([0, 0, 1, 2, 2], -301.0, 0.0, 129.0, -0.1),
    ([-2, -1, 0, 2, 2], 217.0, -0.5, -95.0, 0.3),
    ([-2, 0, 1, 0, 0], -158.0, 0.0, 0.0, 0.0),
    ([-2, 0, 0, 2, 1], 129.0, 0.1, -70.0, 0.0),
    ([0, 0, -1, 2, 2], 123.0, 0.0, -53.0, 0.0),
    ([2, 0, 0, 0, 0], 63.0, 0.0, 0.0, 0.0),
    ([0, 0, 1, 0, 1], 63.0, 0.1, -33.0, 0.0),
    ([2, 0, -1, 2, 2], -59.0, 0.0, 26.0, 0.0),
    ([0, 0, -1, 0, 1], -58.0, -0.1, 32.0, 0.0),
    ([0, 0, 1, 2, 1], -51.0, 0.0, 27.0, 0.0),
    ([-2, 0, 2, 0, 0], 48.0, 0.0, 0.0, 0.0),
    ([0, 0, -2, 2, 1], 46.0, 0.0, -24.0, 0.0),
    ([2, 0, 0, 2, 2], -38.0, 0.0, 16.0, 0.0),
    ([0, 0, 2, 2, 2], -31.0, 0.0, 13.0, 0.0),
    ([0, 0, 2, 0, 0], 29.0, 0.0, 0.0, 0.0),
    ([-2, 0, 1, 2, 2], 29.0, 0.0, -12.0, 0.0),
    ([0, 0, 0, 2, 0], 26.0, 0.0, 0.0, 0.0),
    ([-2, 0, 0, 2, 0], -22.0, 0.0, 0.0, 0.0),
    ([0, 0, -1, 2, 1], 21.0, 0.0, -10.0, 0.0),
    ([0, 2, 0, 0, 0], 17.0, -0.1, 0.0, 0.0),
    ([2, 0, -1, 0, 1], 16.0, 0.0, -8.0, 0.0),
    ([-2, 2, 0, 2, 2], -16.0, 0.1, 7.0, 0.0),
    ([0, 1, 0, 0, 1], -15.0, 0.0, 9.0, 0.0),
    ([-2, 0, 1, 0, 1], -13.0, 0.0, 7.0, 0.0),
    ([0, -1, 0, 0, 1], -12.0, 0.0, 6.0, 0.0),
    ([0, 0, 2, -2, 0], 11.0, 0.0, 0.0, 0.0),
    ([2, 0, -1, 2, 1], -10.0, 0.0, 5.0, 0.0),
    ([2, 0, 1, 2, 2], -8.0, 0.0, 3.0, 0.0),
    ([0, 1, 0, 2, 2], 7.0, 0.0, -3.0, 0.0),
    ([-2, 1, 1, 0, 0], -7.0, 0.0, 0.0, 0.0),
    ([0, -1, 0, 2, 2], -7.0, 0.0, 3.0, 0.0),
    ([2, 0, 0, 2, 1], -7.0, 0.0, 3.0, 0.0),
    ([2, 0, 1, 0, 0], 6.0, 0.0, 0.0, 0.0),
    ([-2, 0, 2, 2, 2], 6.0, 0.0, -3.0, 0.0),
    ([-2, 0, 1, 2, 1], 6.0, 0.0, -3.0, 0.0),
    ([2, 0, -2, 0, 1], -6.0, 0.0, 3.0, 0.0),
    ([2, 0, 0, 0, 1], -6.0, 0.0, 3.0, 0.0),
    ([0, -1, 1, 0, 0], 5.0, 0.0, 0.0, 0.0),
    ([-2, -1, 0, 2, 1], -5.0, 0.0, 3.0, 0.0),
    ([-2, 0, 0, 0, 1], -5.0, 0.0, 3.0, 0.0),
    ([0, 0, 2, 2, 1], -5.0, 0.0, 3.0, 0.0),
    ([-2, 0, 2, 0, 1], 4.0, 0.0, 0.0, 0.0),
    ([-2, 1, 0, 2, 1], 4.0, 0.0, 0.0, 0.0),
    ([0, 0, 1, -2, 0], 4.0, 0.0, 0.0, 0.0),
    ([-1, 0, 1, 0, 0], -4.0, 0.0, 0.0, 0.0),
    ([-2, 1, 0, 0, 0], -4.0, 0.0, 0.0, 0.0),
    ([1, 0, 0, 0, 0], -4.0, 0.0, 0.0, 0.0),
    ([0, 0, 1, 2, 0], 3.0, 0.0, 0.0, 0.0),
    ([0, 0, -2, 2, 2], -3.0, 0.0, 0.0, 0.0),
    ([-1, -1, 1, 0, 0], -3.0, 0.0, 0.0, 0.0),
    ([0, 1, 1, 0, 0], -3.0, 0.0, 0.0, 0.0),
    ([0, -1, 1, 2, 2], -3.0, 0.0, 0.0, 0.0),
    ([2, -1, -1, 2, 2], -3.0, 0.0, 0.0, 0.0),
    ([0, 0, 3, 2, 2], -3.0, 0.0, 0.0, 0.0),
    ([2, -1, 0, 2, 2], -3.0, 0.0, 0.0, 0.0),
];

/// Nutation and obliquity at an instant, degrees.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Nutation {
    /// Nutation in longitude Δψ, degrees.
    pub longitude_deg: f64,
    /// Nutation in obliquity Δε, degrees.
    pub obliquity_deg: f64,
    /// Mean obliquity of the ecliptic ε0, degrees.
    pub mean_obliquity_deg: f64,
}

impl Nutation {
    /// True obliquity ε = ε0 + Δε, degrees.
    pub fn true_obliquity_deg(&self) -> f64 {
        self.mean_obliquity_deg + self.obliquity_deg
    }
}

/// `a + b x + c x² + d x³`.
fn cubic(a: f64, b: f64, c: f64, d: f64, x: f64) -> f64 {
    a + x * (b + x * (c + x * d))
}

/// Nutation and mean obliquity at `t` Julian centuries of TT from J2000.0.
pub fn nutation(t: f64) -> Nutation {
    let args = [
        cubic(297.850_36, 445_267.111_48, -0.001_914_2, 1.0 / 189_474.0, t),
        cubic(357.527_72, 35_999.050_34, -0.000_160_3, -1.0 / 300_000.0, t),
        cubic(134.962_98, 477_198.867_398, 0.008_697_2, 1.0 / 56_250.0, t),
        cubic(93.271_91, 483_202.017_538, -0.003_682_5, 1.0 / 327_270.0, t),
        cubic(125.044_52, -1_934.136_261, 0.002_070_8, 1.0 / 450_000.0, t),
    ];
    let mut dpsi = 0.0;
    let mut deps = 0.0;
    for (mult, a, b, c, d) in TERMS {
        let arg: f64 = mult
            .iter()
            .zip(args.iter())
            .map(|(&m, &x)| f64::from(m) * x)
            .sum::<f64>()
            .to_radians();
        dpsi += (a + b * t) * arg.sin();
        deps += (c + d * t) * arg.cos();
    }
    Nutation {
        longitude_deg: dpsi / 36_000_000.0,
        obliquity_deg: deps / 36_000_000.0,
        mean_obliquity_deg: mean_obliquity_deg(t),
    }
}

/// Mean obliquity of the ecliptic, degrees, Laskar's polynomial (Meeus 22.3)
/// at `t` Julian centuries of TT from J2000.0.
pub fn mean_obliquity_deg(t: f64) -> f64 {
    let u = t / 100.0;
    let coeffs = [
        84_381.448, -4680.93, -1.55, 1999.25, -51.38, -249.67, -39.05, 7.12, 27.87, 5.79, 2.45,
    ];
    let arcsec = coeffs.iter().rev().fold(0.0, |acc, c| acc * u + c);
    arcsec / 3600.0
}

/// Greenwich mean sidereal time, degrees in `[0, 360)`, for `days_ut` days of
/// UT1 since J2000.0 (Meeus 12.4).
pub fn greenwich_mean_sidereal_time_deg(days_ut: f64) -> f64 {
    let t = days_ut / 36_525.0;
    // 360.985 647 366 29 d = 360 d + 0.985 647 366 29 d, and 360 d is 360 frac(d) modulo 360.
    let theta = 280.460_618_37
        + 360.0 * days_ut.fract()
        + 0.985_647_366_29 * days_ut
        + t * t * (0.000_387_933 - t / 38_710_000.0);
    theta.rem_euclid(360.0)
}

/// Greenwich apparent sidereal time, degrees in `[0, 360)`: mean sidereal time
/// plus the equation of the equinoxes `Δψ cos ε`.
pub fn greenwich_apparent_sidereal_time_deg(days_ut: f64, nutation: &Nutation) -> f64 {
    (greenwich_mean_sidereal_time_deg(days_ut)
        + nutation.longitude_deg * nutation.true_obliquity_deg().to_radians().cos())
    .rem_euclid(360.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn meeus_example_22a() {
        // 1987 April 10, 0h TD (JDE 2446895.5): Δψ = -3.788", Δε = +9.443",
        // ε0 = 23°26'27.407", ε = 23°26'36.850".
        let t = (2_446_895.5 - 2_451_545.0) / 36_525.0;
        let n = nutation(t);
        assert!((n.longitude_deg * 3600.0 - -3.788).abs() < 0.01, "{n:?}");
        assert!((n.obliquity_deg * 3600.0 - 9.443).abs() < 0.01, "{n:?}");
        let eps0 = 23.0 + 26.0 / 60.0 + 27.407 / 3600.0;
        assert!((n.mean_obliquity_deg - eps0).abs() * 3600.0 < 0.002);
        let eps = 23.0 + 26.0 / 60.0 + 36.850 / 3600.0;
        assert!((n.true_obliquity_deg() - eps).abs() * 3600.0 < 0.01);
    }

    #[test]
    fn meeus_example_12a_and_12b_sidereal_time() {
        // 1987 April 10, 0h UT: GMST 13h10m46.3668s; GAST 13h10m46.1351s (Δψ -3.788", ε 23°26'36.87").
        let days = 2_446_895.5 - 2_451_545.0;
        let gmst = greenwich_mean_sidereal_time_deg(days);
        let expected = (13.0 + 10.0 / 60.0 + 46.3668 / 3600.0) * 15.0;
        assert!(
            (gmst - expected).abs() * 240.0 < 0.001,
            "{gmst} vs {expected}"
        );
        let n = nutation((2_446_895.5 - 2_451_545.0) / 36_525.0);
        let gast = greenwich_apparent_sidereal_time_deg(days, &n);
        let expected = (13.0 + 10.0 / 60.0 + 46.1351 / 3600.0) * 15.0;
        assert!(
            (gast - expected).abs() * 240.0 < 0.002,
            "{gast} vs {expected}"
        );
        // 1987 April 10, 19h21m00s UT: GMST 8h34m57.0896s.
        let days = 2_446_896.306_25 - 2_451_545.0;
        let gmst = greenwich_mean_sidereal_time_deg(days);
        let expected = (8.0 + 34.0 / 60.0 + 57.0896 / 3600.0) * 15.0;
        assert!(
            (gmst - expected).abs() * 240.0 < 0.001,
            "{gmst} vs {expected}"
        );
    }
}
