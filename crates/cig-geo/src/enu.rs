//! Local east-north-up (ENU) frame at a geodetic origin.
//!
//! Algorithm: `enu = Rᵀ (p - o)` and `p = o + R enu`, where `o` is the ECEF
//! position of the origin and the columns of `R` are the unit east, north and
//! up vectors at the origin's latitude φ and longitude λ:
//! `e = (-sin λ, cos λ, 0)`, `n = (-sin φ cos λ, -sin φ sin λ, cos φ)`,
//! `u = (cos φ cos λ, cos φ sin λ, sin φ)` (the standard local-tangent-plane
//! rotation, e.g. NIMA TR8350.2 chapter 4 or any geodesy text). Limits: exact
//! to rounding (f64 ECEF resolves about a nanometre); "up" is the ellipsoid
//! normal, not the local vertical of gravity (they differ by the deflection of
//! the vertical, up to about an arcminute). ENU is a flat tangent frame: a
//! point 10 km east of the origin at ENU height 0 is about 7.8 m above the
//! ellipsoid. At the poles "east" follows the origin's longitude.

use glam::{DMat3, DVec3};

use crate::geodetic::{ecef_to_geodetic, geodetic_to_ecef, Geodetic, LatLonTrig};

/// Local east-north-up frame at a geodetic origin.
#[derive(Clone, Copy, Debug)]
pub struct EnuFrame {
    origin: Geodetic,
    origin_ecef: DVec3,
    /// Columns: east, north, up unit vectors in ECEF (ENU -> ECEF rotation).
    enu_to_ecef_rot: DMat3,
    /// The transpose of `enu_to_ecef_rot` (ECEF -> ENU rotation).
    ecef_to_enu_rot: DMat3,
}

impl EnuFrame {
    /// The ENU frame whose origin is `origin` (height included).
    pub fn new(origin: Geodetic) -> Self {
        Self::with_trig(origin, LatLonTrig::new(origin.lat_deg, origin.lon_deg))
    }

    /// [`EnuFrame::new`] with the sines and cosines of the origin's latitude and longitude
    /// already worked out (`trig` must be those of `origin`).
    pub fn with_trig(origin: Geodetic, trig: LatLonTrig) -> Self {
        let LatLonTrig {
            sin_lat,
            cos_lat,
            sin_lon,
            cos_lon,
            ..
        } = trig;
        let east = DVec3::new(-sin_lon, cos_lon, 0.0);
        let north = DVec3::new(-sin_lat * cos_lon, -sin_lat * sin_lon, cos_lat);
        let up = DVec3::new(cos_lat * cos_lon, cos_lat * sin_lon, sin_lat);
        let enu_to_ecef_rot = DMat3::from_cols(east, north, up);
        Self {
            origin,
            origin_ecef: trig.to_ecef(origin.alt_m),
            enu_to_ecef_rot,
            ecef_to_enu_rot: enu_to_ecef_rot.transpose(),
        }
    }

    /// The origin as given to [`EnuFrame::new`].
    pub fn origin(&self) -> Geodetic {
        self.origin
    }

    /// ECEF position of the origin, metres.
    pub fn origin_ecef(&self) -> DVec3 {
        self.origin_ecef
    }

    /// ECEF point (metres) to ENU coordinates (metres) in this frame.
    pub fn ecef_to_enu(&self, p: DVec3) -> DVec3 {
        self.ecef_to_enu_rot * (p - self.origin_ecef)
    }

    /// ENU coordinates (metres) in this frame to an ECEF point (metres).
    pub fn enu_to_ecef(&self, enu: DVec3) -> DVec3 {
        self.origin_ecef + self.enu_to_ecef_rot * enu
    }

    /// Geodetic position to ENU coordinates (metres) in this frame.
    pub fn geodetic_to_enu(&self, g: Geodetic) -> DVec3 {
        self.ecef_to_enu(geodetic_to_ecef(g))
    }

    /// ENU coordinates (metres) in this frame to a geodetic position.
    pub fn enu_to_geodetic(&self, enu: DVec3) -> Geodetic {
        ecef_to_geodetic(self.enu_to_ecef(enu))
    }

    /// Rotates a vector (velocity, direction, offset) from ENU to ECEF axes;
    /// no translation.
    pub fn enu_vector_to_ecef(&self, v: DVec3) -> DVec3 {
        self.enu_to_ecef_rot * v
    }

    /// Rotates a vector from ECEF to ENU axes; no translation.
    pub fn ecef_vector_to_enu(&self, v: DVec3) -> DVec3 {
        self.ecef_to_enu_rot * v
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{WGS84_A_M, WGS84_B_M};
    use proptest::prelude::*;

    fn origin_strategy() -> impl Strategy<Value = Geodetic> {
        (-90.0..=90.0_f64, -180.0..=180.0_f64, -1e4..=1e6_f64)
            .prop_map(|(lat, lon, alt)| Geodetic::new(lat, lon, alt))
    }

    #[test]
    fn axes_at_known_origins() {
        let f = EnuFrame::new(Geodetic::new(0.0, 0.0, 0.0));
        assert_eq!(f.enu_vector_to_ecef(DVec3::X), DVec3::Y);
        assert_eq!(f.enu_vector_to_ecef(DVec3::Y), DVec3::Z);
        assert_eq!(f.enu_vector_to_ecef(DVec3::Z), DVec3::X);
        assert_eq!(
            f.ecef_to_enu(DVec3::new(WGS84_A_M + 10.0, 0.0, 0.0)),
            DVec3::new(0.0, 0.0, 10.0)
        );
        let f = EnuFrame::new(Geodetic::new(90.0, 0.0, 0.0));
        assert_eq!(f.enu_vector_to_ecef(DVec3::Z), DVec3::Z);
        assert_eq!(f.enu_vector_to_ecef(DVec3::Y), -DVec3::X);
        let enu = f.ecef_to_enu(DVec3::new(0.0, 0.0, WGS84_B_M));
        assert!(enu.length() < 1e-8, "{enu}");
    }

    #[test]
    fn up_offset_changes_only_height() {
        let origin = Geodetic::new(47.3, 8.5, 400.0);
        let f = EnuFrame::new(origin);
        let g = f.enu_to_geodetic(DVec3::new(0.0, 0.0, 1234.5));
        assert!((g.lat_deg - origin.lat_deg).abs() < 1e-12);
        assert!((g.lon_deg - origin.lon_deg).abs() < 1e-12);
        assert!((g.alt_m - 1634.5).abs() < 1e-6);
        // A tangent-plane step east rises above the curved ellipsoid.
        let g = f.enu_to_geodetic(DVec3::new(10_000.0, 0.0, 0.0));
        assert!((g.alt_m - 400.0 - 7.84).abs() < 0.05, "{g:?}");
    }

    proptest! {
        #[test]
        fn origin_maps_to_zero(origin in origin_strategy()) {
            let f = EnuFrame::new(origin);
            prop_assert_eq!(f.origin(), origin);
            prop_assert!(f.geodetic_to_enu(origin).length() < 1e-9);
            prop_assert!(f.ecef_to_enu(origin.to_ecef()).length() < 1e-9);
            prop_assert!((f.enu_to_ecef(DVec3::ZERO) - origin.to_ecef()).length() < 1e-9);
        }

        #[test]
        fn enu_round_trips(
            origin in origin_strategy(),
            e in -1e5..1e5_f64,
            n in -1e5..1e5_f64,
            u in -1e4..1e4_f64,
        ) {
            let f = EnuFrame::new(origin);
            let enu = DVec3::new(e, n, u);
            let back = f.ecef_to_enu(f.enu_to_ecef(enu));
            prop_assert!((back - enu).length() < 1e-6, "{} -> {}", enu, back);
            let back = f.geodetic_to_enu(f.enu_to_geodetic(enu));
            prop_assert!((back - enu).length() < 1e-6, "{} -> {}", enu, back);
            let v = f.ecef_vector_to_enu(f.enu_vector_to_ecef(enu));
            prop_assert!((v - enu).length() < 1e-9, "{} -> {}", enu, v);
            // Vectors rotate without translation and keep their length.
            prop_assert!((f.enu_vector_to_ecef(enu).length() - enu.length()).abs() < 1e-9);
        }

        #[test]
        fn geodetic_enu_round_trip(
            origin in origin_strategy(),
            dlat in -0.5..0.5_f64,
            dlon in -0.5..0.5_f64,
            alt_m in -1e3..1e4_f64,
        ) {
            let f = EnuFrame::new(origin);
            let lat_deg = (origin.lat_deg + dlat).clamp(-89.9, 89.9);
            let g = Geodetic::new(lat_deg, origin.lon_deg + dlon, alt_m);
            let back = f.enu_to_geodetic(f.geodetic_to_enu(g));
            prop_assert!((back.lat_deg - g.lat_deg).abs() < 1e-9, "{:?} -> {:?}", g, back);
            prop_assert!(
                crate::angle::wrap_deg(back.lon_deg - g.lon_deg).abs() < 1e-9,
                "{:?} -> {:?}", g, back
            );
            prop_assert!((back.alt_m - g.alt_m).abs() < 1e-6, "{:?} -> {:?}", g, back);
        }

        /// "Up" is the outward normal of the ellipsoid `x²/a² + y²/a² + z²/b² = 1`
        /// at the foot point, computed independently as the gradient there.
        #[test]
        fn up_is_ellipsoid_normal(origin in origin_strategy()) {
            let f = EnuFrame::new(origin);
            let up = f.enu_vector_to_ecef(DVec3::Z);
            let foot = Geodetic::new(origin.lat_deg, origin.lon_deg, 0.0).to_ecef();
            let normal = DVec3::new(
                foot.x / (WGS84_A_M * WGS84_A_M),
                foot.y / (WGS84_A_M * WGS84_A_M),
                foot.z / (WGS84_B_M * WGS84_B_M),
            )
            .normalize();
            prop_assert!((up - normal).length() < 1e-12, "{} vs {}", up, normal);
            // And the frame is right-handed and orthonormal.
            let east = f.enu_vector_to_ecef(DVec3::X);
            let north = f.enu_vector_to_ecef(DVec3::Y);
            prop_assert!((east.cross(north) - up).length() < 1e-12);
            prop_assert!(east.dot(north).abs() < 1e-12);
            // Moving along up from the origin changes only the height.
            let g = f.enu_to_geodetic(DVec3::new(0.0, 0.0, 500.0));
            prop_assert!((g.alt_m - origin.alt_m - 500.0).abs() < 1e-6);
        }
    }
}
