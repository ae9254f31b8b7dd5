//! Views: an eyepoint, its orientation, its field of view and its frame size, and the camera
//! maths the renderer and the level-of-detail selection share.
//!
//! Algorithm: the eye's orientation is heading (clockwise from true north), pitch (up positive)
//! and roll (right wing down positive) applied in that order to the local east-north-up frame of
//! the eye (source 001, "Frame Generation": eyepoint, aim, field of view). Everything the GPU
//! sees is relative to the eye: ECEF differences are taken in double precision on the CPU and
//! only then rounded to single precision, so nothing jitters anywhere on the earth. The
//! projection is an off-centre (asymmetric) perspective with reversed Z and an infinite far
//! plane (depth = near / distance along the view axis), which with a 32-bit float depth buffer
//! resolves centimetres at 0.5 m and metres at 200 km.
//!
//! Limits: a view is a pinhole camera; fields of view must be below 180 degrees in each axis.

use cig_geo::{EnuFrame, Geodetic};
use glam::{DMat3, DVec3, Mat4, Vec4};
use serde::{Deserialize, Serialize};

/// Near plane distance, metres: the closest geometry a view draws.
pub const NEAR_PLANE_M: f64 = 0.5;

/// Lowest eye altitude accepted, metres above the ellipsoid.
pub const MIN_EYE_ALTITUDE_M: f64 = -1000.0;

/// The four half-angles of a (possibly asymmetric) frustum, degrees, each measured from the
/// view axis; `left_deg + right_deg` is the horizontal field of view.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct FovDeg {
    pub left_deg: f64,
    pub right_deg: f64,
    pub down_deg: f64,
    pub up_deg: f64,
}

impl FovDeg {
    /// A symmetric frustum from full horizontal and vertical angles.
    pub fn symmetric(horizontal_deg: f64, vertical_deg: f64) -> FovDeg {
        FovDeg {
            left_deg: horizontal_deg / 2.0,
            right_deg: horizontal_deg / 2.0,
            down_deg: vertical_deg / 2.0,
            up_deg: vertical_deg / 2.0,
        }
    }

    /// A symmetric frustum from the horizontal angle, the vertical one following the frame's
    /// aspect ratio (square pixels).
    pub fn from_horizontal(horizontal_deg: f64, width_px: u32, height_px: u32) -> FovDeg {
        let half_tan = (horizontal_deg.to_radians() / 2.0).tan();
        let vertical_deg = 2.0
            * (half_tan * f64::from(height_px) / f64::from(width_px.max(1)))
                .atan()
                .to_degrees();
        FovDeg::symmetric(horizontal_deg, vertical_deg)
    }

    /// Tangents of the half-angles (left, right, down, up).
    pub fn tangents(&self) -> [f64; 4] {
        [
            self.left_deg.to_radians().tan(),
            self.right_deg.to_radians().tan(),
            self.down_deg.to_radians().tan(),
            self.up_deg.to_radians().tan(),
        ]
    }

    /// Pixels per unit of tangent on a `width_px x height_px` frame (the larger of the two
    /// axes): a length `e` seen across at distance `d` covers about `e * this / d` pixels.
    pub fn pixels_per_tangent(&self, width_px: u32, height_px: u32) -> f64 {
        let [tl, tr, td, tu] = self.tangents();
        (f64::from(width_px) / (tl + tr)).max(f64::from(height_px) / (td + tu))
    }
}

/// Orientation of a view or an entity: heading, pitch, roll in degrees.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Hpr {
    pub heading_deg: f64,
    pub pitch_deg: f64,
    pub roll_deg: f64,
}

impl Hpr {
    /// Body axes (forward, right, up) in the local east-north-up frame.
    pub fn axes_enu(&self) -> (DVec3, DVec3, DVec3) {
        let (sh, ch) = self.heading_deg.to_radians().sin_cos();
        let (sp, cp) = self.pitch_deg.to_radians().sin_cos();
        let (sr, cr) = self.roll_deg.to_radians().sin_cos();
        let forward = DVec3::new(sh * cp, ch * cp, sp);
        let right0 = DVec3::new(ch, -sh, 0.0);
        let up0 = right0.cross(forward);
        let right = right0 * cr - up0 * sr;
        let up = up0 * cr + right0 * sr;
        (forward, right, up)
    }
}

/// Why a view cannot be drawn.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum ViewError {
    #[error("frame size {width_px}x{height_px} is empty or larger than 16384 pixels a side")]
    FrameSize { width_px: u32, height_px: u32 },
    #[error("field of view {0} must lie between 0 and 180 degrees in each axis")]
    FieldOfView(String),
    #[error("eye latitude {0} is outside -90..90 degrees")]
    Latitude(f64),
    #[error("eye longitude {0} is outside -180..360 degrees")]
    Longitude(f64),
    #[error("eye altitude {0} m is more than 1 km below the ellipsoid or not finite")]
    Altitude(f64),
    #[error("orientation {0} is not finite")]
    Orientation(String),
}

/// One view: what a display channel shows.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct View {
    /// Eyepoint, altitude above the WGS84 ellipsoid.
    pub eye: Geodetic,
    pub orientation: Hpr,
    pub fov: FovDeg,
    pub width_px: u32,
    pub height_px: u32,
}

/// A frustum plane in eye-relative coordinates: points `p` with `normal · p >= offset_m` are
/// inside.
#[derive(Clone, Copy, Debug)]
pub struct Plane {
    pub normal: DVec3,
    pub offset_m: f64,
}

/// Everything derived from a [`View`] for one frame.
#[derive(Clone, Debug)]
pub struct Camera {
    pub view: View,
    pub eye_ecef: DVec3,
    /// Camera axes in ECEF.
    pub forward: DVec3,
    pub right: DVec3,
    pub up: DVec3,
    /// Local up (ellipsoid normal) at the eye, ECEF.
    pub local_up: DVec3,
    /// Inward planes: left, right, bottom, top, near.
    pub planes: [Plane; 5],
    /// Pixels per unit of tangent at the view axis (the larger of the two axes): a length `e`
    /// seen across at distance `d` covers about `e * pixels_per_tangent / d` pixels.
    pub pixels_per_tangent: f64,
}

impl View {
    /// Checks the view's values (one-line reason when something is out of range).
    pub fn validate(&self) -> Result<(), ViewError> {
        if self.width_px == 0
            || self.height_px == 0
            || self.width_px > 16384
            || self.height_px > 16384
        {
            return Err(ViewError::FrameSize {
                width_px: self.width_px,
                height_px: self.height_px,
            });
        }
        let f = self.fov;
        let ok = |a: f64| a.is_finite() && a > -89.9 && a < 89.9;
        if !(ok(f.left_deg) && ok(f.right_deg) && ok(f.down_deg) && ok(f.up_deg))
            || f.left_deg + f.right_deg <= 0.0
            || f.down_deg + f.up_deg <= 0.0
            || f.left_deg + f.right_deg >= 180.0
            || f.down_deg + f.up_deg >= 180.0
        {
            return Err(ViewError::FieldOfView(format!(
                "(left {}, right {}, down {}, up {})",
                f.left_deg, f.right_deg, f.down_deg, f.up_deg
            )));
        }
        if !(self.eye.lat_deg.is_finite() && (-90.0..=90.0).contains(&self.eye.lat_deg)) {
            return Err(ViewError::Latitude(self.eye.lat_deg));
        }
        if !(self.eye.lon_deg.is_finite() && (-180.0..=360.0).contains(&self.eye.lon_deg)) {
            return Err(ViewError::Longitude(self.eye.lon_deg));
        }
        if !(self.eye.alt_m.is_finite() && self.eye.alt_m >= MIN_EYE_ALTITUDE_M) {
            return Err(ViewError::Altitude(self.eye.alt_m));
        }
        let o = self.orientation;
        if !(o.heading_deg.is_finite() && o.pitch_deg.is_finite() && o.roll_deg.is_finite()) {
            return Err(ViewError::Orientation(format!(
                "({}, {}, {})",
                o.heading_deg, o.pitch_deg, o.roll_deg
            )));
        }
        Ok(())
    }

    /// The camera of this view (the view must be valid).
    pub fn camera(&self) -> Camera {
        let enu = EnuFrame::new(self.eye);
        let (f, r, u) = self.orientation.axes_enu();
        let forward = enu.enu_vector_to_ecef(f).normalize();
        let right = enu.enu_vector_to_ecef(r).normalize();
        let up = enu.enu_vector_to_ecef(u).normalize();
        let local_up = enu.enu_vector_to_ecef(DVec3::Z);
        let [tl, tr, td, tu] = self.fov.tangents();
        let planes = [
            Plane {
                normal: (right + forward * tl).normalize(),
                offset_m: 0.0,
            },
            Plane {
                normal: (-right + forward * tr).normalize(),
                offset_m: 0.0,
            },
            Plane {
                normal: (up + forward * td).normalize(),
                offset_m: 0.0,
            },
            Plane {
                normal: (-up + forward * tu).normalize(),
                offset_m: 0.0,
            },
            Plane {
                normal: forward,
                offset_m: NEAR_PLANE_M,
            },
        ];
        let pixels_per_tangent = self.fov.pixels_per_tangent(self.width_px, self.height_px);
        Camera {
            view: *self,
            eye_ecef: enu.origin_ecef(),
            forward,
            right,
            up,
            local_up,
            planes,
            pixels_per_tangent,
        }
    }
}

impl Camera {
    /// ECEF -> camera rotation (rows: right, up, -forward), for eye-relative positions.
    pub fn world_to_camera(&self) -> DMat3 {
        DMat3::from_cols(self.right, self.up, -self.forward).transpose()
    }

    /// Reversed-Z, infinite-far, off-centre projection (wgpu clip space, depth 1 at the near
    /// plane falling to 0 at infinity).
    pub fn projection(&self) -> Mat4 {
        let [tl, tr, td, tu] = self.view.fov.tangents();
        let (l, r, b, t) = (-tl, tr, -td, tu);
        let n = NEAR_PLANE_M;
        Mat4::from_cols(
            Vec4::new((2.0 / (r - l)) as f32, 0.0, 0.0, 0.0),
            Vec4::new(0.0, (2.0 / (t - b)) as f32, 0.0, 0.0),
            Vec4::new(
                ((r + l) / (r - l)) as f32,
                ((t + b) / (t - b)) as f32,
                0.0,
                -1.0,
            ),
            Vec4::new(0.0, 0.0, n as f32, 0.0),
        )
    }

    /// View-projection for eye-relative ECEF positions (single precision).
    pub fn view_projection(&self) -> Mat4 {
        let m = self.world_to_camera();
        let rot = Mat4::from_cols(
            m.x_axis.as_vec3().extend(0.0),
            m.y_axis.as_vec3().extend(0.0),
            m.z_axis.as_vec3().extend(0.0),
            Vec4::W,
        );
        self.projection() * rot
    }

    /// True when no point of `points_rel` (eye-relative) can be inside the frustum: all of
    /// them lie outside one plane.
    pub fn culls(&self, points_rel: &[DVec3]) -> bool {
        self.planes.iter().any(|plane| {
            points_rel
                .iter()
                .all(|p| plane.normal.dot(*p) < plane.offset_m)
        })
    }

    /// Pixel position (x right, y down, from the top-left corner) of an ECEF point, or `None`
    /// when it is behind the near plane.
    pub fn project_ecef(&self, p_ecef: DVec3) -> Option<(f64, f64)> {
        let rel = p_ecef - self.eye_ecef;
        let z = rel.dot(self.forward);
        if z < NEAR_PLANE_M {
            return None;
        }
        let [tl, tr, td, tu] = self.view.fov.tangents();
        let x_tan = rel.dot(self.right) / z;
        let y_tan = rel.dot(self.up) / z;
        let px = (x_tan + tl) / (tl + tr) * f64::from(self.view.width_px);
        let py = (tu - y_tan) / (td + tu) * f64::from(self.view.height_px);
        Some((px, py))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn view() -> View {
        View {
            eye: Geodetic::new(36.0, -121.0, 500.0),
            orientation: Hpr {
                heading_deg: 30.0,
                pitch_deg: -10.0,
                roll_deg: 5.0,
            },
            fov: FovDeg::from_horizontal(60.0, 640, 480),
            width_px: 640,
            height_px: 480,
        }
    }

    #[test]
    fn axes_are_orthonormal_and_heading_zero_looks_north() {
        let (f, r, u) = Hpr::default().axes_enu();
        assert!((f - DVec3::Y).length() < 1e-12);
        assert!((r - DVec3::X).length() < 1e-12);
        assert!((u - DVec3::Z).length() < 1e-12);
        let (f, r, u) = view().orientation.axes_enu();
        assert!(f.dot(r).abs() < 1e-12 && f.dot(u).abs() < 1e-12 && r.dot(u).abs() < 1e-12);
        assert!(
            (r.cross(u) - (-f)).length() < 1e-12,
            "right-handed camera frame"
        );
        // Positive roll puts the right wing down.
        assert!(r.z < 0.0);
    }

    #[test]
    fn projection_matches_project_ecef_and_reverses_depth() {
        let cam = view().camera();
        let vp = cam.view_projection();
        for (dist, off) in [(1.0, 0.2), (100.0, -0.1), (5000.0, 0.3)] {
            let p = cam.eye_ecef + (cam.forward + cam.right * off + cam.up * 0.1) * dist;
            let rel = (p - cam.eye_ecef).as_vec3();
            let clip = vp * rel.extend(1.0);
            let ndc = clip / clip.w;
            let (px, py) = cam.project_ecef(p).expect("in front");
            let px2 = (f64::from(ndc.x) + 1.0) / 2.0 * 640.0;
            let py2 = (1.0 - f64::from(ndc.y)) / 2.0 * 480.0;
            assert!((px - px2).abs() < 0.01 && (py - py2).abs() < 0.01);
            let depth = f64::from(ndc.z);
            assert!((depth - NEAR_PLANE_M / dist).abs() < 1e-6, "reversed z");
        }
    }

    #[test]
    fn frustum_planes_cull_what_is_behind_or_aside() {
        let cam = view().camera();
        assert!(!cam.culls(&[cam.forward * 100.0]));
        assert!(cam.culls(&[-cam.forward * 100.0]));
        assert!(cam.culls(&[cam.right * 100.0 + cam.forward * 10.0]));
        assert!(!cam.culls(&[cam.right * 100.0 + cam.forward * 10.0, cam.forward * 10.0]));
    }

    #[test]
    fn bad_views_are_refused() {
        let mut v = view();
        v.width_px = 0;
        assert!(matches!(v.validate(), Err(ViewError::FrameSize { .. })));
        let mut v = view();
        v.fov = FovDeg::symmetric(180.0, 40.0);
        assert!(matches!(v.validate(), Err(ViewError::FieldOfView(_))));
        let mut v = view();
        v.eye.alt_m = -1500.0;
        assert!(matches!(v.validate(), Err(ViewError::Altitude(_))));
        let mut v = view();
        v.eye.lat_deg = f64::NAN;
        assert!(matches!(v.validate(), Err(ViewError::Latitude(_))));
        assert_eq!(view().validate(), Ok(()));
    }
}
