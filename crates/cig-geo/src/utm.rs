//! Universal Transverse Mercator on WGS84.
//!
//! Algorithm: the transverse Mercator projection by Krüger's series in the
//! third flattening `n = f / (2 - f)`, carried to order n⁶, with the exact
//! conformal-latitude step and Newton's method for its inverse, following
//! C. F. F. Karney, "Transverse Mercator with an accuracy of a few
//! nanometres", *J. Geodesy* 85(8), 475–485 (2011) (after L. Krüger,
//! *Konforme Abbildung des Erdellipsoids in der Ebene*, 1912). UTM
//! parameters: scale on the central meridian k0 = 0.9996, false easting
//! 500 000 m, false northing 0 in the north and 10 000 000 m in the south
//! (NGA.SIG.0012, *The Universal Grids and the Transverse Mercator and Polar
//! Stereographic Map Projections*, 2014).
//!
//! Limits: within about 3 900 km (35 degrees at the equator) of the central
//! meridian the error is below 5 nm (Karney 2011); a UTM zone spans ±3
//! degrees, and points a few degrees outside it (as used for overlap and for
//! the Norway/Svalbard zones) are just as accurate. The series degrades far
//! from the central meridian and the projection itself is singular at 90
//! degrees of longitude difference; do not use it there. UTM is defined for
//! 80 S..84 N; the maths here works up to the poles (the UPS grid is not
//! provided). Points are not restricted to their zone: any zone may be asked
//! for any point, as DEM importers need.

use std::sync::LazyLock;

use crate::angle::{atan2_deg, sincos_deg, wrap_deg};
use crate::{GeoError, WGS84_A_M, WGS84_F};

/// Scale factor on the central meridian.
pub const UTM_K0: f64 = 0.9996;
/// False easting, metres.
pub const UTM_FALSE_EASTING_M: f64 = 500_000.0;
/// False northing in the southern hemisphere, metres.
pub const UTM_FALSE_NORTHING_SOUTH_M: f64 = 10_000_000.0;

/// A UTM zone: number `1..=60` and hemisphere.
///
/// The fields are public, so a zone with a number outside `1..=60` can be
/// built; the functions here then still compute with the central meridian
/// `6 number - 183` degrees. Use [`UtmZone::new`] to validate.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct UtmZone {
    /// Zone number, `1..=60`; zone 1 spans 180 W..174 W.
    pub number: u8,
    /// Northern hemisphere (false northing 0) or southern (10 000 km).
    pub north: bool,
}

impl UtmZone {
    /// A validated zone.
    pub fn new(number: u8, north: bool) -> Result<UtmZone, GeoError> {
        if (1..=60).contains(&number) {
            Ok(UtmZone { number, north })
        } else {
            Err(GeoError::InvalidUtmZone(number))
        }
    }

    /// The zone of a WGS84 / UTM EPSG code: 32601..=32660 north,
    /// 32701..=32760 south; anything else is `None`.
    pub fn from_epsg(epsg: u32) -> Option<UtmZone> {
        let (base, north) = match epsg {
            32601..=32660 => (32600, true),
            32701..=32760 => (32700, false),
            _ => return None,
        };
        let number = u8::try_from(epsg - base).ok()?;
        Some(UtmZone { number, north })
    }

    /// The EPSG code of this zone on WGS84 (326zz north, 327zz south).
    pub fn epsg(&self) -> u32 {
        let base = if self.north { 32600 } else { 32700 };
        base + u32::from(self.number)
    }

    /// Longitude of the central meridian, degrees: `6 number - 183`.
    pub fn central_meridian_deg(&self) -> f64 {
        6.0 * f64::from(self.number) - 183.0
    }

    /// The standard zone containing a point, with the Norway (32V) and
    /// Svalbard (31X, 33X, 35X, 37X) exceptions; the hemisphere is north for
    /// `lat_deg >= 0`. Longitude 180 belongs to zone 1. Errors on a non-finite
    /// coordinate or a latitude outside `[-90, 90]`.
    pub fn containing(lat_deg: f64, lon_deg: f64) -> Result<UtmZone, GeoError> {
        if !lat_deg.is_finite() || !lon_deg.is_finite() || lat_deg.abs() > 90.0 {
            return Err(GeoError::InvalidCoordinate { lat_deg, lon_deg });
        }
        let lon = wrap_deg(lon_deg);
        let band = ((lon + 180.0) / 6.0).floor().clamp(0.0, 59.0);
        #[allow(
            clippy::cast_possible_truncation,
            clippy::cast_sign_loss,
            reason = "band is a whole number clamped to 0..=59"
        )]
        let mut number = band as u8 + 1;
        if (56.0..64.0).contains(&lat_deg) && (3.0..12.0).contains(&lon) {
            number = 32;
        } else if lat_deg >= 72.0 && (0.0..42.0).contains(&lon) {
            number = match lon {
                l if l < 9.0 => 31,
                l if l < 21.0 => 33,
                l if l < 33.0 => 35,
                _ => 37,
            };
        }
        Ok(UtmZone {
            number,
            north: lat_deg >= 0.0,
        })
    }
}

/// Krüger series coefficients for an ellipsoid.
struct Krueger {
    /// First eccentricity.
    e: f64,
    /// `1 - e²`.
    e2m: f64,
    /// Rectifying radius `A`, metres (Karney 2011).
    rect_radius_m: f64,
    /// Forward (conformal sphere to projection) coefficients α₁..α₆ (Karney 2011).
    alpha: [f64; 6],
    /// Reverse coefficients β₁..β₆ (Karney 2011).
    beta: [f64; 6],
}

impl Krueger {
    fn new(a_m: f64, f: f64) -> Self {
        let n = f / (2.0 - f);
        let (n2, n3) = (n * n, n * n * n);
        let (n4, n5, n6) = (n3 * n, n3 * n2, n3 * n3);
        let e2 = f * (2.0 - f);
        Self {
            e: e2.sqrt(),
            e2m: 1.0 - e2,
            rect_radius_m: a_m / (1.0 + n) * (1.0 + n2 / 4.0 + n4 / 64.0 + n6 / 256.0),
            alpha: [
                n / 2.0 - 2.0 * n2 / 3.0 + 5.0 * n3 / 16.0 + 41.0 * n4 / 180.0 - 127.0 * n5 / 288.0
                    + 7891.0 * n6 / 37800.0,
                13.0 * n2 / 48.0 - 3.0 * n3 / 5.0 + 557.0 * n4 / 1440.0 + 281.0 * n5 / 630.0
                    - 1_983_433.0 * n6 / 1_935_360.0,
                61.0 * n3 / 240.0 - 103.0 * n4 / 140.0
                    + 15061.0 * n5 / 26880.0
                    + 167_603.0 * n6 / 181_440.0,
                49561.0 * n4 / 161_280.0 - 179.0 * n5 / 168.0 + 6_601_661.0 * n6 / 7_257_600.0,
                34729.0 * n5 / 80640.0 - 3_418_889.0 * n6 / 1_995_840.0,
                212_378_941.0 * n6 / 319_334_400.0,
            ],
            beta: [
                n / 2.0 - 2.0 * n2 / 3.0 + 37.0 * n3 / 96.0 - n4 / 360.0 - 81.0 * n5 / 512.0
                    + 96199.0 * n6 / 604_800.0,
                n2 / 48.0 + n3 / 15.0 - 437.0 * n4 / 1440.0 + 46.0 * n5 / 105.0
                    - 1_118_711.0 * n6 / 3_870_720.0,
                17.0 * n3 / 480.0 - 37.0 * n4 / 840.0 - 209.0 * n5 / 4480.0 + 5569.0 * n6 / 90720.0,
                4397.0 * n4 / 161_280.0 - 11.0 * n5 / 504.0 - 830_251.0 * n6 / 7_257_600.0,
                4583.0 * n5 / 161_280.0 - 108_847.0 * n6 / 3_991_680.0,
                20_648_693.0 * n6 / 638_668_800.0,
            ],
        }
    }

    /// `σ = sinh(e atanh(e sin φ))` (Karney 2011).
    fn sigma(&self, sin_lat: f64) -> f64 {
        (self.e * (self.e * sin_lat).atanh()).sinh()
    }

    /// Tangent of the conformal latitude, `τ' = τ sqrt(1 + σ²) - σ sqrt(1 + τ²)`,
    /// from `τ = tan φ`.
    fn taup(&self, tau: f64) -> f64 {
        let tau1 = tau.hypot(1.0);
        let sig = self.sigma(tau / tau1);
        sig.hypot(1.0) * tau - sig * tau1
    }

    /// Geodetic τ from conformal τ' by Newton's method (Karney 2011), as in
    /// GeographicLib `Math::tauf`; converges in two or three steps.
    fn tau_from_taup(&self, taup: f64) -> f64 {
        const MAX_ITERATIONS: usize = 8;
        let tol = f64::EPSILON.sqrt() / 10.0;
        let tau_max = 2.0 / f64::EPSILON.sqrt();
        let mut tau = if taup.abs() > 70.0 {
            taup * (self.e * self.e.atanh()).exp()
        } else {
            taup / self.e2m
        };
        if tau.is_nan() || tau.abs() >= tau_max {
            // ±inf, NaN, or so close to a pole that the initial guess (the
            // asymptote τ = τ' exp(e atanh e)) is already exact to rounding.
            return tau;
        }
        let stol = tol * taup.abs().max(1.0);
        for _ in 0..MAX_ITERATIONS {
            let taupa = self.taup(tau);
            let dtau = (taup - taupa) * (1.0 + self.e2m * tau * tau)
                / (self.e2m * tau.hypot(1.0) * taupa.hypot(1.0));
            tau += dtau;
            if dtau.is_nan() || dtau.abs() < stol {
                break;
            }
        }
        tau
    }

    /// Transverse Mercator with unit scale: `(x, y)` in metres for a
    /// latitude and a longitude difference from the central meridian.
    fn forward(&self, lat_deg: f64, dlon_deg: f64) -> (f64, f64) {
        let (sin_lat, cos_lat) = sincos_deg(lat_deg);
        let (sin_dlon, cos_dlon) = sincos_deg(dlon_deg);
        // ξ' = atan2(τ', cos λ), η' = asinh(sin λ / sqrt(τ'² + cos² λ)),
        // multiplied through by cos φ >= 0, which leaves them unchanged and
        // needs no special case at the poles (cos φ = 0, where τ = tan φ
        // would be infinite): τ' cos φ = sin φ sqrt(1 + σ²) - σ.
        let sig = self.sigma(sin_lat);
        let taup_cos = sin_lat * sig.hypot(1.0) - sig;
        let xip = taup_cos.atan2(cos_lat * cos_dlon);
        let etap = (cos_lat * sin_dlon / taup_cos.hypot(cos_lat * cos_dlon)).asinh();
        let (dxi, deta) = clenshaw_sin(&self.alpha, xip, etap);
        let (xi, eta) = (xip + dxi, etap + deta);
        (self.rect_radius_m * eta, self.rect_radius_m * xi)
    }

    /// Inverse of [`Krueger::forward`]: `(lat_deg, dlon_deg)`.
    fn reverse(&self, x_m: f64, y_m: f64) -> (f64, f64) {
        let xi = y_m / self.rect_radius_m;
        let eta = x_m / self.rect_radius_m;
        let (dxi, deta) = clenshaw_sin(&self.beta, xi, eta);
        let (xip, etap) = (xi - dxi, eta - deta);
        let (sin_xip, cos_xip) = xip.sin_cos();
        let sinh_etap = etap.sinh();
        // Conformal latitude tangent and longitude from ξ', η'.
        let r = sinh_etap.hypot(cos_xip);
        let taup = sin_xip / r; // ±inf exactly at a pole
        let lat_deg = atan2_deg(self.tau_from_taup(taup), 1.0);
        let dlon_deg = atan2_deg(sinh_etap, cos_xip);
        (lat_deg, dlon_deg)
    }
}

/// `Σ c_j sin(2 j ζ)` for j = 1..=6 and complex `ζ = ξ + i η`, returned as
/// `(re, im)` = `(Σ c_j sin 2jξ cosh 2jη, Σ c_j cos 2jξ sinh 2jη)`, Krüger's
/// sums. Clenshaw summation (C. W. Clenshaw, "A note on the summation of
/// Chebyshev series", *Math. Tables Aids Comput.* 9, 118–120, 1955) in complex
/// arithmetic, as Karney 2011 recommends: one sin/cos and one sinh/cosh
/// instead of six each.
fn clenshaw_sin(c: &[f64; 6], xi: f64, eta: f64) -> (f64, f64) {
    let (s2, c2) = (2.0 * xi).sin_cos();
    let (sh2, ch2) = ((2.0 * eta).sinh(), (2.0 * eta).cosh());
    // a = 2 cos 2ζ.
    let (ar, ai) = (2.0 * c2 * ch2, -2.0 * s2 * sh2);
    // y_k = c_k + a y_(k+1) - y_(k+2), from k = 6 down to 1.
    let (mut y0r, mut y0i, mut y1r, mut y1i) = (0.0, 0.0, 0.0, 0.0);
    for &ck in c.iter().rev() {
        let yr = ck + ar * y0r - ai * y0i - y1r;
        let yi = ar * y0i + ai * y0r - y1i;
        (y1r, y1i, y0r, y0i) = (y0r, y0i, yr, yi);
    }
    // Sum = sin 2ζ · y_1.
    let (sr, si) = (s2 * ch2, c2 * sh2);
    (sr * y0r - si * y0i, sr * y0i + si * y0r)
}

static WGS84_KRUEGER: LazyLock<Krueger> = LazyLock::new(|| Krueger::new(WGS84_A_M, WGS84_F));

/// Transverse Mercator by Krüger's series to order n⁶ (Karney 2011,
/// "Transverse Mercator with an accuracy of a few nanometres"); k0 = 0.9996,
/// false easting 500 km, false northing 10 000 km in the south.
///
/// Returns `(easting_m, northing_m)`. The longitude is taken relative to the
/// zone's central meridian (wrapped to ±180); see the module docs for the
/// accuracy away from it.
pub fn geodetic_to_utm(zone: UtmZone, lat_deg: f64, lon_deg: f64) -> (f64, f64) {
    let dlon_deg = wrap_deg(lon_deg - zone.central_meridian_deg());
    let (x, y) = WGS84_KRUEGER.forward(lat_deg, dlon_deg);
    let false_northing = if zone.north {
        0.0
    } else {
        UTM_FALSE_NORTHING_SOUTH_M
    };
    (
        UTM_FALSE_EASTING_M + UTM_K0 * x,
        false_northing + UTM_K0 * y,
    )
}

/// Inverse of [`geodetic_to_utm`]: `(lat_deg, lon_deg)` with the longitude in
/// `[-180, 180)`.
pub fn utm_to_geodetic(zone: UtmZone, easting_m: f64, northing_m: f64) -> (f64, f64) {
    let false_northing = if zone.north {
        0.0
    } else {
        UTM_FALSE_NORTHING_SOUTH_M
    };
    let x = (easting_m - UTM_FALSE_EASTING_M) / UTM_K0;
    let y = (northing_m - false_northing) / UTM_K0;
    let (lat_deg, dlon_deg) = WGS84_KRUEGER.reverse(x, y);
    (lat_deg, wrap_deg(zone.central_meridian_deg() + dlon_deg))
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn zone(number: u8, north: bool) -> UtmZone {
        UtmZone { number, north }
    }

    #[test]
    fn central_meridian_on_the_equator() {
        // Documented in every UTM text: (0 N, 3 E) is the origin of zone 31.
        let (e, n) = geodetic_to_utm(zone(31, true), 0.0, 3.0);
        assert_eq!((e, n), (500_000.0, 0.0));
        let (e, n) = geodetic_to_utm(zone(31, false), 0.0, 3.0);
        assert_eq!((e, n), (500_000.0, 10_000_000.0));
        let (lat, lon) = utm_to_geodetic(zone(31, true), 500_000.0, 0.0);
        assert_eq!((lat, lon), (0.0, 3.0));
    }

    #[test]
    fn meridian_arc_to_the_pole() {
        // The WGS84 quarter meridian (equator to pole along a meridian) is
        // Q = A π / 2 = 10 001 965.729 m (e.g. GeographicLib's
        // `Ellipsoid::QuarterMeridian`); at the pole y = k0 Q.
        let (e, n) = geodetic_to_utm(zone(31, true), 90.0, 3.0);
        assert!((e - 500_000.0).abs() < 1e-9);
        assert!((n - 0.9996 * 10_001_965.729_3).abs() < 1e-3, "{n}");
        let (lat, _) = utm_to_geodetic(zone(31, true), 500_000.0, n);
        assert!((lat - 90.0).abs() < 1e-12, "{lat}");
        let (_, n) = geodetic_to_utm(zone(31, false), -90.0, 40.0);
        assert!(
            (n - (10_000_000.0 - 0.9996 * 10_001_965.729_3)).abs() < 1e-3,
            "{n}"
        );
    }

    #[test]
    fn geographiclib_reference_points() {
        // GeographicLib GeoConvert documentation (C. F. F. Karney,
        // https://geographiclib.sourceforge.io/C++/doc/GeoConvert.1.html):
        // "33.3 44.4" is "38n 444140.54 3684706.36" (given to 1 cm).
        let (e, n) = geodetic_to_utm(zone(38, true), 33.3, 44.4);
        assert!((e - 444_140.54).abs() < 0.005, "{e}");
        assert!((n - 3_684_706.36).abs() < 0.005, "{n}");
        // GeoConvert -u -s -p 9 (GeographicLib's own order-6 Krüger series):
        // Perth airport "-31.93980 115.96650" -> "50s 402314.322464520 6465770.872261507";
        // "47.6514 106.8216" -> "48n 636793.955125689 5279163.338930206".
        let (e, n) = geodetic_to_utm(zone(50, false), -31.9398, 115.9665);
        assert!((e - 402_314.322_464_520).abs() < 1e-6, "{e}");
        assert!((n - 6_465_770.872_261_507).abs() < 1e-6, "{n}");
        let (e, n) = geodetic_to_utm(zone(48, true), 47.6514, 106.8216);
        assert!((e - 636_793.955_125_689).abs() < 1e-6, "{e}");
        assert!((n - 5_279_163.338_930_206).abs() < 1e-6, "{n}");
        // And the reverse: "38n 444140.54 3684706.36" | GeoConvert -p 9 gives
        // "33.30000003988349 44.39999994689769".
        let (lat, lon) = utm_to_geodetic(zone(38, true), 444_140.54, 3_684_706.36);
        assert!((lat - 33.300_000_039_883_49).abs() < 1e-11, "{lat}");
        assert!((lon - 44.399_999_946_897_69).abs() < 1e-11, "{lon}");
    }

    #[test]
    fn snyder_clarke_1866_example() {
        // J. P. Snyder, Map Projections: A Working Manual, USGS Professional
        // Paper 1395 (1987), p. 269, transverse Mercator example: Clarke 1866
        // (a = 6 378 206.4 m, e² = 0.006 768 66), φ = 40.5 N, λ = 73.5 W,
        // central meridian 75 W, k0 = 0.9996 -> x = 127 106.5 m,
        // y = 4 484 124.4 m (printed to 0.1 m). A different ellipsoid checks
        // the coefficients' dependence on n, not just WGS84's numbers.
        let a = 6_378_206.4;
        let f = 1.0 - (1.0_f64 - 0.006_768_66).sqrt();
        let k = Krueger::new(a, f);
        let (x, y) = k.forward(40.5, 1.5);
        assert!((0.9996 * x - 127_106.5).abs() < 0.06, "{}", 0.9996 * x);
        assert!((0.9996 * y - 4_484_124.4).abs() < 0.06, "{}", 0.9996 * y);
        let (lat, dlon) = k.reverse(x, y);
        assert!((lat - 40.5).abs() < 1e-12 && (dlon - 1.5).abs() < 1e-12);
    }

    #[test]
    fn clenshaw_matches_direct_sum() {
        let c = [0.3, -0.2, 0.1, 0.05, -0.02, 0.01];
        for &(xi, eta) in &[
            (0.0, 0.0),
            (0.7, 0.1),
            (-1.2, -0.4),
            (1.55, 0.05),
            (0.3, 1.1),
        ] {
            let (mut re, mut im) = (0.0, 0.0);
            for (j, cj) in c.iter().enumerate() {
                let k = 2.0 * (j as f64 + 1.0);
                re += cj * (k * xi).sin() * (k * eta).cosh();
                im += cj * (k * xi).cos() * (k * eta).sinh();
            }
            let (r2, i2) = clenshaw_sin(&c, xi, eta);
            let tol = 1e-13 * (1.0 + re.abs() + im.abs());
            assert!(
                (r2 - re).abs() < tol && (i2 - im).abs() < tol,
                "{xi} {eta}: {r2} vs {re}, {i2} vs {im}"
            );
        }
    }

    #[test]
    fn epsg_codes() {
        assert_eq!(UtmZone::from_epsg(32601), Some(zone(1, true)));
        assert_eq!(UtmZone::from_epsg(32660), Some(zone(60, true)));
        assert_eq!(UtmZone::from_epsg(32701), Some(zone(1, false)));
        assert_eq!(UtmZone::from_epsg(32760), Some(zone(60, false)));
        for bad in [0, 4326, 32600, 32661, 32700, 32761, 25832, u32::MAX] {
            assert_eq!(UtmZone::from_epsg(bad), None, "{bad}");
        }
        for code in (32601..=32660).chain(32701..=32760) {
            let z = UtmZone::from_epsg(code);
            assert_eq!(z.map(|z| z.epsg()), Some(code));
        }
        assert_eq!(zone(1, true).central_meridian_deg(), -177.0);
        assert_eq!(zone(31, false).central_meridian_deg(), 3.0);
        assert_eq!(zone(60, true).central_meridian_deg(), 177.0);
        assert_eq!(UtmZone::new(0, true), Err(GeoError::InvalidUtmZone(0)));
        assert_eq!(UtmZone::new(61, true), Err(GeoError::InvalidUtmZone(61)));
        assert_eq!(UtmZone::new(60, false), Ok(zone(60, false)));
    }

    #[test]
    fn containing_zone() {
        let c = |lat, lon| UtmZone::containing(lat, lon);
        assert_eq!(c(0.0, 3.0), Ok(zone(31, true)));
        assert_eq!(c(-0.1, 3.0), Ok(zone(31, false)));
        assert_eq!(c(10.0, -180.0), Ok(zone(1, true)));
        assert_eq!(c(10.0, 180.0), Ok(zone(1, true)));
        assert_eq!(c(10.0, 179.999), Ok(zone(60, true)));
        assert_eq!(c(10.0, -174.0), Ok(zone(2, true)));
        assert_eq!(c(60.0, 5.0), Ok(zone(32, true))); // Norway
        assert_eq!(c(60.0, 2.0), Ok(zone(31, true)));
        assert_eq!(c(78.0, 8.0), Ok(zone(31, true))); // Svalbard
        assert_eq!(c(78.0, 9.0), Ok(zone(33, true)));
        assert_eq!(c(78.0, 32.0), Ok(zone(35, true)));
        assert_eq!(c(78.0, 40.0), Ok(zone(37, true)));
        assert_eq!(c(78.0, 42.0), Ok(zone(38, true)));
        assert!(c(91.0, 0.0).is_err());
        assert!(c(f64::NAN, 0.0).is_err());
        assert!(c(0.0, f64::INFINITY).is_err());
    }

    proptest! {
        #[test]
        fn utm_round_trip(
            number in 1u8..=60,
            lat_deg in -84.0..=84.0_f64,
            dlon_deg in -6.0..=6.0_f64,
        ) {
            let z = zone(number, lat_deg >= 0.0);
            let lon_deg = wrap_deg(z.central_meridian_deg() + dlon_deg);
            let (e, n) = geodetic_to_utm(z, lat_deg, lon_deg);
            let (lat2, lon2) = utm_to_geodetic(z, e, n);
            let msg = format!("{lat_deg} {lon_deg} -> {e} {n} -> {lat2} {lon2}");
            prop_assert!((lat2 - lat_deg).abs() < 1e-9, "{}", msg);
            prop_assert!(wrap_deg(lon2 - lon_deg).abs() < 1e-9, "{}", msg);
            // Either hemisphere's false northing must invert too.
            let other = zone(number, lat_deg < 0.0);
            let (e, n) = geodetic_to_utm(other, lat_deg, lon_deg);
            let (lat3, _) = utm_to_geodetic(other, e, n);
            prop_assert!((lat3 - lat_deg).abs() < 1e-9);
        }

        #[test]
        fn utm_grid_round_trip(
            number in 1u8..=60,
            easting_m in 160_000.0..840_000.0_f64,
            // Distance from the equator: 84 N is about 9 330 km, 80 S 8 880 km.
            y_m in -8_880_000.0..9_330_000.0_f64,
        ) {
            let north = y_m >= 0.0;
            let northing_m = if north { y_m } else { y_m + UTM_FALSE_NORTHING_SOUTH_M };
            let z = zone(number, north);
            let (lat, lon) = utm_to_geodetic(z, easting_m, northing_m);
            let (e, n) = geodetic_to_utm(z, lat, lon);
            prop_assert!((e - easting_m).abs() < 1e-6 && (n - northing_m).abs() < 1e-6,
                "{} {} -> {} {} -> {} {}", easting_m, northing_m, lat, lon, e, n);
        }
    }
}
