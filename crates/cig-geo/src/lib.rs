//! WGS84 geodesy for cig: geodetic / ECEF / local ENU conversions, UTM and
//! the EGM96 geoid. Pure maths: no files, sockets or terminal.
//!
//! Algorithms, sources and limits, by item:
//!
//! - [`geodetic_to_ecef`]: the closed-form ellipsoid formula with the prime
//!   vertical radius `N = a / sqrt(1 - e² sin² φ)` (NIMA TR8350.2, *Department
//!   of Defense World Geodetic System 1984*, 3rd ed., 2000, chapter 4).
//!   Exact to rounding for any input.
//! - [`ecef_to_geodetic`]: Vermeille's closed-form solution of the quartic
//!   (H. Vermeille, "Direct transformation from geocentric coordinates to
//!   geodetic coordinates", *J. Geodesy* 76, 451–454, 2002) with Karney's
//!   changes that keep it accurate and finite everywhere, the centre of the
//!   Earth and the evolute region included (C. F. F. Karney, GeographicLib
//!   class `Geocentric`, <https://geographiclib.sourceforge.io>). Error is a
//!   few nanometres for any point,
//!   far inside the sub-millimetre this crate promises for `|alt| < 1e7 m`.
//!   Inside the evolute (within about 43 km of the centre) the nearest-point
//!   height is not unique; one valid answer is returned, never NaN.
//! - [`EnuFrame`]: the standard rotation between ECEF and local
//!   east-north-up axes (any geodesy text, e.g. TR8350.2). Exact to
//!   rounding; "up" is the ellipsoid normal at the origin, not the plumb line.
//! - [`metres_per_degree`]: meridian radius of curvature
//!   `M = a (1 - e²) / (1 - e² sin² φ)^(3/2)` and parallel radius `N cos φ`
//!   (TR8350.2 chapter 4). These are *local* scales at a latitude: exact
//!   for infinitesimal steps, not lengths of finite arcs.
//! - [`utm`]: Krüger's series to order n⁶ (Karney 2011, nanometre accuracy
//!   within about 35 degrees of the central meridian).
//! - [`geoid`]: EGM96 by degree-360 spherical-harmonic synthesis (slow: about
//!   a millisecond per call; sample it on a coarse grid).
//!
//! Conventions: degrees at every interface, metres for lengths, heights above
//! the WGS84 ellipsoid unless a name says otherwise, ECEF in metres as
//! [`glam::DVec3`] (x towards (0 N, 0 E), z towards the north pole).

#![cfg_attr(not(test), deny(clippy::unwrap_used, clippy::expect_used))]

mod angle;
mod enu;
mod geodetic;
pub mod geoid;
pub mod utm;

pub use enu::EnuFrame;
pub use geodetic::{ecef_to_geodetic, geodetic_to_ecef, metres_per_degree, Geodetic, LatLonTrig};

/// WGS84 semi-major axis (equatorial radius), metres. TR8350.2 chapter 3.
pub const WGS84_A_M: f64 = 6_378_137.0;
/// WGS84 flattening `f = (a - b) / a`. TR8350.2 chapter 3.
pub const WGS84_F: f64 = 1.0 / 298.257_223_563;
/// WGS84 semi-minor axis (polar radius) `b = a (1 - f)`, metres (6 356 752.314 245 m).
pub const WGS84_B_M: f64 = WGS84_A_M * (1.0 - WGS84_F);
/// WGS84 first eccentricity squared `e² = f (2 - f)` (0.006 694 379 990 14).
pub const WGS84_E2: f64 = WGS84_F * (2.0 - WGS84_F);

/// Errors from the fallible helpers of this crate. The core conversions are
/// total functions (NaN in, NaN out) and do not return errors.
#[derive(Clone, Copy, Debug, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum GeoError {
    /// A UTM zone number outside `1..=60`.
    #[error("UTM zone number {0} is outside 1..=60")]
    InvalidUtmZone(u8),
    /// A latitude outside `[-90, 90]` or a non-finite latitude or longitude.
    #[error("invalid geodetic coordinate: lat {lat_deg} deg, lon {lon_deg} deg")]
    InvalidCoordinate {
        /// The latitude given, degrees.
        lat_deg: f64,
        /// The longitude given, degrees.
        lon_deg: f64,
    },
}
