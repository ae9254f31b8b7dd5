//! Geodetic (latitude, longitude, ellipsoidal height) <-> ECEF on WGS84.
//!
//! Algorithm: forward by the closed-form ellipsoid formula with the prime
//! vertical radius `N`; reverse by Vermeille's closed-form solution of the
//! quartic for the foot point (H. Vermeille, *J. Geodesy* 76, 451–454, 2002)
//! as modified by Karney in GeographicLib's `Geocentric` (sign choices that
//! avoid cancellation, explicit limits on the equatorial plane inside the
//! evolute, scaling far from the Earth). Limits: errors of a few nanometres
//! everywhere; at the exact centre the answer is the north pole at height
//! `-b`; inside the evolute (within about 43 km of the centre) the nearest
//! surface point is not unique and one valid answer is returned.

use glam::DVec3;
use serde::{Deserialize, Serialize};

use crate::angle::{atan2_deg, sincos_deg};
use crate::{WGS84_A_M, WGS84_E2, WGS84_F};

/// `(1 - f)²` = `1 - e²`.
const E2M: f64 = (1.0 - WGS84_F) * (1.0 - WGS84_F);
/// `e⁴`.
const E4: f64 = WGS84_E2 * WGS84_E2;
/// Beyond this distance from the centre the Earth is treated as a point
/// (GeographicLib's `2 a / epsilon`), which keeps the quartic from overflowing.
const MAX_RADIUS_M: f64 = 2.0 * WGS84_A_M / f64::EPSILON;

/// A position given by geodetic latitude, longitude (degrees) and height
/// above the WGS84 ellipsoid (metres).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Geodetic {
    /// Geodetic latitude, degrees, positive north, in `[-90, 90]`.
    pub lat_deg: f64,
    /// Longitude, degrees, positive east.
    pub lon_deg: f64,
    /// Height above the WGS84 ellipsoid, metres (not above mean sea level:
    /// see [`crate::geoid`]).
    pub alt_m: f64,
}

impl Geodetic {
    /// A geodetic position. No validation: see the field docs for ranges.
    pub const fn new(lat_deg: f64, lon_deg: f64, alt_m: f64) -> Self {
        Self {
            lat_deg,
            lon_deg,
            alt_m,
        }
    }

    /// Earth-centred, Earth-fixed coordinates of this position, metres.
    pub fn to_ecef(&self) -> DVec3 {
        geodetic_to_ecef(*self)
    }

    /// The geodetic position of an ECEF point; see [`ecef_to_geodetic`].
    pub fn from_ecef(p: DVec3) -> Geodetic {
        ecef_to_geodetic(p)
    }
}

/// Geodetic position to Earth-centred, Earth-fixed coordinates, metres.
///
/// `x = (N + h) cos φ cos λ`, `y = (N + h) cos φ sin λ`,
/// `z = (N (1 - e²) + h) sin φ`, `N = a / sqrt(1 - e² sin² φ)`.
/// Exact at the poles and on the equator (the trigonometry is done in
/// degrees with exact quadrant reduction).
pub fn geodetic_to_ecef(g: Geodetic) -> DVec3 {
    LatLonTrig::new(g.lat_deg, g.lon_deg).to_ecef(g.alt_m)
}

/// The sines and cosines of a latitude and a longitude (and the prime vertical
/// radius of the latitude), for converting many positions that share latitudes
/// or longitudes (the posts of a grid) without repeating the trigonometry: the
/// latitude of one value may be combined with the longitude of another
/// ([`LatLonTrig::with_lon_of`]), and the results are the same bits as
/// [`geodetic_to_ecef`] and [`crate::EnuFrame::new`] give.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LatLonTrig {
    pub sin_lat: f64,
    pub cos_lat: f64,
    pub sin_lon: f64,
    pub cos_lon: f64,
    /// Prime vertical radius of curvature `N = a / sqrt(1 - e² sin² φ)`, metres.
    pub prime_vertical_radius_m: f64,
}

impl LatLonTrig {
    /// Sines and cosines of `lat_deg` and `lon_deg` (exact at multiples of 90 degrees).
    pub fn new(lat_deg: f64, lon_deg: f64) -> LatLonTrig {
        let (sin_lat, cos_lat) = sincos_deg(lat_deg);
        let (sin_lon, cos_lon) = sincos_deg(lon_deg);
        LatLonTrig {
            sin_lat,
            cos_lat,
            sin_lon,
            cos_lon,
            prime_vertical_radius_m: WGS84_A_M / (1.0 - WGS84_E2 * sin_lat * sin_lat).sqrt(),
        }
    }

    /// The latitude of `self` with the longitude of `other`.
    pub fn with_lon_of(self, other: LatLonTrig) -> LatLonTrig {
        LatLonTrig {
            sin_lon: other.sin_lon,
            cos_lon: other.cos_lon,
            ..self
        }
    }

    /// ECEF coordinates (metres) of the position at this latitude and longitude and
    /// `alt_m` above the ellipsoid; see [`geodetic_to_ecef`].
    pub fn to_ecef(&self, alt_m: f64) -> DVec3 {
        let n = self.prime_vertical_radius_m;
        let r = (n + alt_m) * self.cos_lat;
        DVec3::new(
            r * self.cos_lon,
            r * self.sin_lon,
            (n * (1.0 - WGS84_E2) + alt_m) * self.sin_lat,
        )
    }
}

/// Earth-centred, Earth-fixed coordinates (metres) to geodetic position.
///
/// Closed form (Vermeille 2002, with Karney's robustness changes); a few
/// nanometres of error for any finite input, finite output for any finite
/// input (the centre maps to latitude 90, longitude 0, height `-b`). On the
/// z axis the longitude is 0. NaN in gives NaN out.
pub fn ecef_to_geodetic(p: DVec3) -> Geodetic {
    let (x, y, z) = (p.x, p.y, p.z);
    let mut r = x.hypot(y);
    let (mut sin_lon, mut cos_lon) = if r != 0.0 { (y / r, x / r) } else { (0.0, 1.0) };
    // Distance from the centre; becomes the height below.
    let mut h = r.hypot(z);
    let (sin_lat, cos_lat);
    if h > MAX_RADIUS_M {
        // Treat the Earth as a point; `h` is then an adequate height. Halving
        // avoids overflow of the hypotenuses for huge but finite inputs.
        r = (x / 2.0).hypot(y / 2.0);
        (sin_lon, cos_lon) = if r != 0.0 {
            ((y / 2.0) / r, (x / 2.0) / r)
        } else {
            (0.0, 1.0)
        };
        let hh = (z / 2.0).hypot(r);
        sin_lat = (z / 2.0) / hh;
        cos_lat = r / hh;
    } else {
        let pp = (r / WGS84_A_M) * (r / WGS84_A_M);
        let q = E2M * (z / WGS84_A_M) * (z / WGS84_A_M);
        let rr = (pp + q - E4) / 6.0;
        if !(E4 * q == 0.0 && rr <= 0.0) {
            // General case. The equations for s and t are multiplied by r³
            // and r to avoid a division by zero when r = 0.
            let s = E4 * pp * q / 4.0; // r³ s
            let r2 = rr * rr;
            let r3 = rr * r2;
            let disc = s * (2.0 * r3 + s);
            let mut u = rr;
            if disc >= 0.0 {
                let mut t3 = s + r3;
                // Choose the sign of the root that maximises |t3| (no
                // cancellation); u is unchanged by the choice.
                t3 += if t3 < 0.0 { -disc.sqrt() } else { disc.sqrt() };
                let t = t3.cbrt(); // r t
                u += t + if t != 0.0 { r2 / t } else { 0.0 };
            } else {
                // Three real roots (only possible when r < 0); take the one
                // that avoids cancellation.
                let ang = (-disc).sqrt().atan2(-(s + r3));
                u += 2.0 * rr * (ang / 3.0).cos();
            }
            let v = (u * u + E4 * q).sqrt(); // > 0
                                             // u + v > 0, computed without cancellation when u < 0.
            let uv = if u < 0.0 { E4 * q / (v - u) } else { u + v };
            let w = (WGS84_E2 * (uv - q) / (2.0 * v)).max(0.0);
            let k = uv / ((uv + w * w).sqrt() + w);
            let k2 = k + WGS84_E2;
            let d = k * r / k2;
            let hh = (z / k).hypot(r / k2);
            sin_lat = (z / k) / hh;
            cos_lat = (r / k2) / hh;
            h = (1.0 - E2M / k) * d.hypot(z);
        } else {
            // On the equatorial plane inside the evolute (k = 0): the general
            // formulas give 0/0, so take their limits.
            let zz = ((E4 - pp) / E2M).sqrt();
            let xx = pp.sqrt();
            let hh = zz.hypot(xx);
            sin_lat = if z < 0.0 { -zz / hh } else { zz / hh };
            cos_lat = xx / hh;
            h = -WGS84_A_M * E2M * hh / WGS84_E2;
        }
    }
    Geodetic {
        lat_deg: atan2_deg(sin_lat, cos_lat),
        lon_deg: atan2_deg(sin_lon, cos_lon),
        alt_m: h,
    }
}

/// Metres per degree of latitude and of longitude at a latitude:
/// `(north_m_per_deg, east_m_per_deg)`.
///
/// North: the meridian radius of curvature `M = a (1 - e²) / (1 - e² sin² φ)^(3/2)`
/// times π/180. East: the parallel radius `N cos φ` times π/180. Local
/// scales on the ellipsoid surface (height 0); multiply by `(R + h) / R` for
/// a height `h` if that matters. East is 0 at the poles.
pub fn metres_per_degree(lat_deg: f64) -> (f64, f64) {
    let (sin_lat, cos_lat) = sincos_deg(lat_deg);
    let w2 = 1.0 - WGS84_E2 * sin_lat * sin_lat;
    let w = w2.sqrt();
    let n = WGS84_A_M / w;
    let m = WGS84_A_M * (1.0 - WGS84_E2) / (w2 * w);
    let rad = std::f64::consts::PI / 180.0;
    (m * rad, n * cos_lat * rad)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::angle::wrap_deg;
    use crate::WGS84_B_M;
    use proptest::prelude::*;

    fn close(a: f64, b: f64, tol: f64) -> bool {
        (a - b).abs() <= tol
    }

    #[test]
    fn constants() {
        assert!(close(WGS84_B_M, 6_356_752.314_245, 1e-6));
        assert!(close(WGS84_E2, 0.006_694_379_990_14, 1e-14), "{}", WGS84_E2);
    }

    #[test]
    fn known_ecef_values() {
        assert_eq!(
            Geodetic::new(0.0, 0.0, 0.0).to_ecef(),
            DVec3::new(WGS84_A_M, 0.0, 0.0)
        );
        assert_eq!(
            Geodetic::new(0.0, 90.0, 0.0).to_ecef(),
            DVec3::new(0.0, WGS84_A_M, 0.0)
        );
        assert_eq!(
            Geodetic::new(0.0, 180.0, 10.0).to_ecef(),
            DVec3::new(-WGS84_A_M - 10.0, 0.0, 0.0)
        );
        let north = Geodetic::new(90.0, 0.0, 0.0).to_ecef();
        assert_eq!((north.x, north.y), (0.0, 0.0));
        assert!(close(north.z, WGS84_B_M, 1e-8), "{north}");
        let south = Geodetic::new(-90.0, 123.0, 100.0).to_ecef();
        assert_eq!((south.x, south.y), (0.0, 0.0));
        assert!(close(south.z, -WGS84_B_M - 100.0, 1e-8), "{south}");
    }

    #[test]
    fn known_geodetic_values() {
        let g = ecef_to_geodetic(DVec3::new(WGS84_A_M, 0.0, 0.0));
        assert_eq!((g.lat_deg, g.lon_deg), (0.0, 0.0));
        assert!(close(g.alt_m, 0.0, 1e-9));
        let g = ecef_to_geodetic(DVec3::new(0.0, 0.0, WGS84_B_M + 5.0));
        assert_eq!((g.lat_deg, g.lon_deg), (90.0, 0.0));
        assert!(close(g.alt_m, 5.0, 1e-9));
        let g = ecef_to_geodetic(DVec3::new(0.0, 0.0, -WGS84_B_M));
        assert_eq!(g.lat_deg, -90.0);
        assert!(close(g.alt_m, 0.0, 1e-9));
        let g = ecef_to_geodetic(DVec3::new(0.0, -WGS84_A_M - 7.0, 0.0));
        assert_eq!((g.lat_deg, g.lon_deg), (0.0, -90.0));
        assert!(close(g.alt_m, 7.0, 1e-9));
    }

    #[test]
    fn centre_and_evolute_are_finite_and_consistent() {
        let g = ecef_to_geodetic(DVec3::ZERO);
        assert_eq!(g.lat_deg, 90.0);
        assert!(close(g.alt_m, -WGS84_B_M, 1e-6), "{g:?}");
        let points = [
            DVec3::new(1.0, 0.0, 0.0),
            DVec3::new(0.0, 0.0, 1.0),
            DVec3::new(0.0, 0.0, -1.0),
            DVec3::new(-1e-300, 1e-300, 0.0),
            DVec3::new(20_000.0, 0.0, 0.0),
            DVec3::new(20_000.0, 5_000.0, -0.0),
            DVec3::new(20_000.0, 5_000.0, 1e-9),
            DVec3::new(42_000.0, 0.0, -3.0),
            DVec3::new(100.0, -200.0, 40_000.0),
            DVec3::new(3e6, 2e6, -1e6),
        ];
        for p in points {
            let g = ecef_to_geodetic(p);
            assert!(
                g.lat_deg.is_finite() && g.lon_deg.is_finite() && g.alt_m.is_finite(),
                "{p} -> {g:?}"
            );
            let back = g.to_ecef();
            assert!((back - p).length() < 1e-6, "{p} -> {g:?} -> {back}");
        }
    }

    #[test]
    fn huge_and_non_finite_inputs() {
        let g = ecef_to_geodetic(DVec3::new(1e300, 1e300, 1e300));
        assert!(g.lat_deg.is_finite() && g.lon_deg.is_finite() && g.alt_m > 1e300);
        assert!(close(g.lon_deg, 45.0, 1e-12));
        let g = ecef_to_geodetic(DVec3::new(f64::NAN, 0.0, 0.0));
        assert!(g.lat_deg.is_nan() || g.alt_m.is_nan());
    }

    /// Height above the ellipsoid checked against an independent definition:
    /// the foot point `g` at height 0 plus `h` along the normal is `p`.
    #[test]
    fn high_altitude_sub_millimetre() {
        for &alt_m in &[-6.0e6, -1e6, 0.0, 1e5, 3.6e6, 9.99e6, 1e7] {
            for &lat_deg in &[-90.0, -89.999_999, -60.0, -1e-9, 0.0, 33.3, 89.9, 90.0] {
                let g = Geodetic::new(lat_deg, 17.0, alt_m);
                let back = ecef_to_geodetic(g.to_ecef());
                assert!(close(back.alt_m, alt_m, 1e-6), "{g:?} -> {back:?}");
                // 1e-9 deg is 0.1 mm on the surface.
                assert!(close(back.lat_deg, lat_deg, 1e-11), "{g:?} -> {back:?}");
            }
        }
    }

    #[test]
    fn metres_per_degree_known_values() {
        let (n, e) = metres_per_degree(0.0);
        assert!(close(n, 110_574.3, 0.1), "{n}");
        assert!(close(e, 111_319.5, 0.1), "{e}");
        // At 45 degrees M = 6 367 381.8 m and N cos φ = 4 517 590.9 m. The
        // often-quoted 111 132.9 / 78 847 (tables of "length of a degree")
        // are the constant term of the cos 2φ series and a value rounded to
        // the metre, not M and N cos φ at 45 degrees: the arc from 44.5 to
        // 45.5 degrees is 111 131.78 m as well.
        let (n, e) = metres_per_degree(45.0);
        assert!(close(n, 111_131.8, 0.1), "{n}");
        assert!(close(e, 78_846.8, 0.1), "{e}");
        let (n, e) = metres_per_degree(-90.0);
        assert!(close(n, 111_694.0, 0.1), "{n}");
        assert_eq!(e, 0.0);
    }

    #[test]
    fn metres_per_degree_matches_finite_differences() {
        for &lat in &[-80.0, -30.0, 0.0, 12.5, 45.0, 70.0] {
            let (n, e) = metres_per_degree(lat);
            let d = 1e-4;
            let north = (Geodetic::new(lat + d, 5.0, 0.0).to_ecef()
                - Geodetic::new(lat - d, 5.0, 0.0).to_ecef())
            .length()
                / (2.0 * d);
            let east = (Geodetic::new(lat, 5.0 + d, 0.0).to_ecef()
                - Geodetic::new(lat, 5.0 - d, 0.0).to_ecef())
            .length()
                / (2.0 * d);
            assert!(close(n, north, 1e-3), "{lat}: {n} vs {north}");
            assert!(close(e, east, 1e-3), "{lat}: {e} vs {east}");
        }
    }

    proptest! {
        #[test]
        fn geodetic_ecef_round_trip(
            lat_deg in -90.0..=90.0_f64,
            lon_deg in -180.0..=180.0_f64,
            alt_m in -1e4..=1e6_f64,
        ) {
            let g = Geodetic::new(lat_deg, lon_deg, alt_m);
            let back = Geodetic::from_ecef(g.to_ecef());
            prop_assert!(close(back.alt_m, alt_m, 1e-6), "{:?} -> {:?}", g, back);
            prop_assert!(close(back.lat_deg, lat_deg, 1e-9), "{:?} -> {:?}", g, back);
            // Longitude is meaningless at the poles; 180 and -180 are equal.
            if lat_deg.abs() < 90.0 {
                prop_assert!(
                    close(wrap_deg(back.lon_deg - lon_deg), 0.0, 1e-9),
                    "{:?} -> {:?}", g, back
                );
            }
        }

        /// The latitude of one `LatLonTrig` with the longitude of another converts exactly as
        /// the position with that latitude and longitude does (same bits), and the ENU frame
        /// built from it is the frame `EnuFrame::new` builds.
        #[test]
        fn mixed_trig_converts_as_the_position_itself(
            lat_deg in -90.0..=90.0_f64,
            lon_deg in -180.0..=360.0_f64,
            other_lat_deg in -90.0..=90.0_f64,
            other_lon_deg in -180.0..=360.0_f64,
            alt_m in -1e4..=1e6_f64,
        ) {
            let trig = LatLonTrig::new(lat_deg, other_lon_deg)
                .with_lon_of(LatLonTrig::new(other_lat_deg, lon_deg));
            let g = Geodetic::new(lat_deg, lon_deg, alt_m);
            let direct = g.to_ecef();
            let mixed = trig.to_ecef(alt_m);
            prop_assert_eq!(mixed.to_array().map(f64::to_bits), direct.to_array().map(f64::to_bits));
            let a = crate::EnuFrame::new(g);
            let b = crate::EnuFrame::with_trig(g, trig);
            prop_assert_eq!(a.origin_ecef(), b.origin_ecef());
            for v in [DVec3::X, DVec3::Y, DVec3::Z] {
                prop_assert_eq!(a.enu_vector_to_ecef(v), b.enu_vector_to_ecef(v));
            }
        }

        #[test]
        fn ecef_geodetic_round_trip_anywhere(
            x in -2e7..2e7_f64,
            y in -2e7..2e7_f64,
            z in -2e7..2e7_f64,
            scale_exp in -7..=0_i32,
        ) {
            // Scaling by powers of ten reaches deep inside the Earth too.
            let p = DVec3::new(x, y, z) * 10f64.powi(scale_exp);
            let g = ecef_to_geodetic(p);
            prop_assert!(g.lat_deg.abs() <= 90.0 && g.lon_deg.abs() <= 180.0);
            let back = g.to_ecef();
            prop_assert!((back - p).length() < 1e-6, "{} -> {:?} -> {}", p, g, back);
        }
    }
}
