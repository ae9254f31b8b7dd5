//! Geocentric apparent position of the sun.
//!
//! Algorithm: J. Meeus, *Astronomical Algorithms* (2nd ed., 1998), chapter 25
//! "higher accuracy": the Earth's heliocentric coordinates from the truncated
//! VSOP87 series ([`crate::vsop87`]), turned geocentric (Θ = L + 180°, β = −B),
//! reduced to the FK5 frame (equation 32.3), then nutation in longitude
//! ([`crate::nutation`]) and annual aberration −20.4898″ / R are added, and the
//! ecliptic coordinates are rotated to right ascension and declination with the
//! true obliquity (equations 13.3, 13.4). Limits: about 1 arcsecond in longitude
//! over 1900–2100 (Meeus); diurnal aberration (≤ 0.3″) is left out.

use crate::nutation::Nutation;
use crate::vsop87::earth_heliocentric;

/// One astronomical unit, metres (IAU 2012).
pub const AU_M: f64 = 149_597_870_700.0;

/// Apparent geocentric position of a body, referred to the true equator and
/// equinox of date.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ApparentPosition {
    /// Apparent ecliptic longitude, degrees in `[0, 360)`.
    pub longitude_deg: f64,
    /// Ecliptic latitude, degrees.
    pub latitude_deg: f64,
    /// Distance from the centre of the Earth, metres.
    pub distance_m: f64,
    /// Apparent right ascension, degrees in `[0, 360)`.
    pub right_ascension_deg: f64,
    /// Apparent declination, degrees.
    pub declination_deg: f64,
}

/// Ecliptic (λ, β) to equatorial (α, δ), degrees, for obliquity ε (Meeus 13.3, 13.4).
pub fn ecliptic_to_equatorial(
    longitude_deg: f64,
    latitude_deg: f64,
    obliquity_deg: f64,
) -> (f64, f64) {
    let (sl, cl) = longitude_deg.to_radians().sin_cos();
    let (sb, cb) = latitude_deg.to_radians().sin_cos();
    let (se, ce) = obliquity_deg.to_radians().sin_cos();
    let ra = (sl * ce * cb - sb * se).atan2(cl * cb).to_degrees();
    let dec = (sb * ce + cb * se * sl)
        .clamp(-1.0, 1.0)
        .asin()
        .to_degrees();
    (ra.rem_euclid(360.0), dec)
}

/// Apparent geocentric position of the sun at `t` Julian centuries of TT from
/// J2000.0, with the nutation for that instant.
pub fn sun_apparent(t: f64, nutation: &Nutation) -> ApparentPosition {
    let (l, b, r) = earth_heliocentric(t / 10.0);
    let theta = l.to_degrees() + 180.0;
    let beta = -b.to_degrees();
    // FK5 correction (Meeus 32.3).
    let lambda_prime = (theta - 1.397 * t - 0.000_31 * t * t).to_radians();
    let d_theta = -0.090_33 / 3600.0;
    let d_beta = 0.039_16 / 3600.0 * (lambda_prime.cos() - lambda_prime.sin());
    let aberration = -20.4898 / 3600.0 / r;
    let lambda = (theta + d_theta + nutation.longitude_deg + aberration).rem_euclid(360.0);
    let beta = beta + d_beta;
    let (ra, dec) = ecliptic_to_equatorial(lambda, beta, nutation.true_obliquity_deg());
    ApparentPosition {
        longitude_deg: lambda,
        latitude_deg: beta,
        distance_m: r * AU_M,
        right_ascension_deg: ra,
        declination_deg: dec,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::nutation::nutation;

    #[test]
    fn meeus_example_25b_apparent_sun() {
        // 1992 October 13.0 TD: λ = 199°54'21.818" (199.906060), β = +0.62",
        // α = 198.378178, δ = -7.783871, R = 0.99760775.
        let t = (2_448_908.5 - 2_451_545.0) / 36_525.0;
        let sun = sun_apparent(t, &nutation(t));
        assert!((sun.longitude_deg - 199.906_060).abs() < 0.0002, "{sun:?}");
        assert!((sun.latitude_deg * 3600.0 - 0.62).abs() < 0.01, "{sun:?}");
        assert!(
            (sun.right_ascension_deg - 198.378_178).abs() < 0.000_02,
            "{sun:?}"
        );
        assert!(
            (sun.declination_deg - -7.783_871).abs() < 0.000_02,
            "{sun:?}"
        );
        assert!((sun.distance_m / AU_M - 0.997_607_75).abs() < 1e-7);
    }
}
