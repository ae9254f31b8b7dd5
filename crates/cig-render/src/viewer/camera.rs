//! The viewer's free-flying camera: geodetic position in f64, heading/pitch/roll, speed.
//!
//! Algorithm: each frame the wanted motion (forward/back along the line of sight, right/left
//! along the camera's right axis, up/down along the local vertical) is scaled by the speed and
//! the frame time, taken as a displacement in the local east-north-up frame of the eye
//! (`cig_geo::EnuFrame`, the standard local-tangent-plane rotation) and converted back to
//! geodetic coordinates through ECEF, all in double precision. The line of sight is then
//! re-expressed in the ENU frame of the new position, so the camera keeps looking in the same
//! direction in space while heading and pitch follow the local north and horizon (a camera flying
//! east along a parallel drifts in heading by the convergence of the meridians, as a real
//! aircraft flying a straight line does). Mouse look changes heading and pitch directly; pitch
//! stays within +-89.9 degrees so heading stays defined.
//!
//! Limits: no inertia; the camera itself knows nothing of the terrain (the viewer keeps a free
//! camera on or above the terrain's surface, `EYE_CLEARANCE_M` up); the
//! altitude is held at or above [`cig_scene::view::MIN_EYE_ALTITUDE_M`] so the view stays valid.

use cig_geo::{EnuFrame, Geodetic};
use cig_scene::view::MIN_EYE_ALTITUDE_M;
use cig_scene::Hpr;
use glam::DVec3;

/// Slowest and fastest flying speeds, metres per second.
pub const SPEED_RANGE_MPS: (f64, f64) = (0.1, 100_000.0);
/// Speed factor of one mouse-wheel notch.
pub const SPEED_STEP_PER_NOTCH: f64 = 1.25;
/// Speed factor while the fast key (shift) is held.
pub const FAST_FACTOR: f64 = 5.0;
/// Largest pitch magnitude, degrees.
pub const MAX_PITCH_DEG: f64 = 89.9;

/// Wanted motion of one frame: each axis in -1..=1.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct MoveInput {
    /// +1 forward along the line of sight, -1 back.
    pub forward: f64,
    /// +1 to the right, -1 to the left.
    pub right: f64,
    /// +1 up along the local vertical, -1 down.
    pub up: f64,
    /// Fly [`FAST_FACTOR`] times faster.
    pub fast: bool,
}

/// A free-flying camera.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FlyCamera {
    /// Eyepoint, altitude above the WGS84 ellipsoid.
    pub eye: Geodetic,
    pub orientation: Hpr,
    /// Flying speed without the fast key, metres per second.
    pub speed_mps: f64,
}

impl FlyCamera {
    pub fn new(eye: Geodetic, orientation: Hpr, speed_mps: f64) -> FlyCamera {
        let mut camera = FlyCamera {
            eye,
            orientation,
            speed_mps: SPEED_RANGE_MPS.0,
        };
        camera.set_speed(speed_mps);
        camera.look(0.0, 0.0);
        camera
    }

    /// Sets the speed, clamped to [`SPEED_RANGE_MPS`] (a non-finite value is ignored).
    pub fn set_speed(&mut self, speed_mps: f64) {
        if speed_mps.is_finite() {
            self.speed_mps = speed_mps.clamp(SPEED_RANGE_MPS.0, SPEED_RANGE_MPS.1);
        }
    }

    /// Multiplies the speed by [`SPEED_STEP_PER_NOTCH`] per wheel notch (negative: slower).
    pub fn scale_speed(&mut self, notches: f64) {
        if notches.is_finite() {
            self.set_speed(
                self.speed_mps * SPEED_STEP_PER_NOTCH.powf(notches.clamp(-100.0, 100.0)),
            );
        }
    }

    /// The speed flown with the fast key `fast` held or not.
    pub fn effective_speed_mps(&self, fast: bool) -> f64 {
        if fast {
            self.speed_mps * FAST_FACTOR
        } else {
            self.speed_mps
        }
    }

    /// Turns the line of sight: heading right and pitch up by the given degrees. Heading wraps
    /// into 0..360, pitch is clamped to +-[`MAX_PITCH_DEG`].
    pub fn look(&mut self, heading_change_deg: f64, pitch_change_deg: f64) {
        let o = &mut self.orientation;
        if heading_change_deg.is_finite() && o.heading_deg.is_finite() {
            o.heading_deg = (o.heading_deg + heading_change_deg).rem_euclid(360.0);
        }
        if pitch_change_deg.is_finite() && o.pitch_deg.is_finite() {
            o.pitch_deg = (o.pitch_deg + pitch_change_deg).clamp(-MAX_PITCH_DEG, MAX_PITCH_DEG);
        }
    }

    /// Flies for `dt_s` seconds. Returns the displacement flown, metres.
    pub fn fly(&mut self, input: MoveInput, dt_s: f64) -> f64 {
        if !(dt_s.is_finite() && dt_s > 0.0) {
            return 0.0;
        }
        let axis = |v: f64| {
            if v.is_finite() {
                v.clamp(-1.0, 1.0)
            } else {
                0.0
            }
        };
        let (forward, right, _) = self.orientation.axes_enu();
        let mut direction =
            forward * axis(input.forward) + right * axis(input.right) + DVec3::Z * axis(input.up);
        if direction.length_squared() < 1e-24 {
            return 0.0;
        }
        if direction.length() > 1.0 {
            direction = direction.normalize();
        }
        let step_enu = direction * self.effective_speed_mps(input.fast) * dt_s;
        let here = EnuFrame::new(self.eye);
        let forward_ecef = here.enu_vector_to_ecef(forward);
        let mut eye = here.enu_to_geodetic(step_enu);
        eye.alt_m = eye.alt_m.max(MIN_EYE_ALTITUDE_M + 1.0);
        if !(eye.lat_deg.is_finite() && eye.lon_deg.is_finite() && eye.alt_m.is_finite()) {
            return 0.0;
        }
        // Keep looking the same way in space: re-express the line of sight at the new eye.
        let there = EnuFrame::new(eye);
        let f = there.ecef_vector_to_enu(forward_ecef).normalize();
        if f.is_finite() && f.x.hypot(f.y) > 1e-9 {
            self.orientation.heading_deg = f.x.atan2(f.y).to_degrees().rem_euclid(360.0);
            self.orientation.pitch_deg =
                f.z.clamp(-1.0, 1.0)
                    .asin()
                    .to_degrees()
                    .clamp(-MAX_PITCH_DEG, MAX_PITCH_DEG);
        }
        self.eye = eye;
        step_enu.length()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn camera(heading_deg: f64, pitch_deg: f64) -> FlyCamera {
        FlyCamera::new(
            Geodetic::new(35.98, -121.23, 800.0),
            Hpr {
                heading_deg,
                pitch_deg,
                roll_deg: 0.0,
            },
            100.0,
        )
    }

    fn forward_ecef(c: &FlyCamera) -> DVec3 {
        EnuFrame::new(c.eye).enu_vector_to_ecef(c.orientation.axes_enu().0)
    }

    #[test]
    fn flying_north_level_increases_latitude_by_the_distance_flown() {
        let mut c = camera(0.0, 0.0);
        let before = c.eye;
        let flown = c.fly(
            MoveInput {
                forward: 1.0,
                ..Default::default()
            },
            10.0,
        );
        assert!((flown - 1000.0).abs() < 1e-9);
        let (north_m_per_deg, _) = cig_geo::metres_per_degree(before.lat_deg);
        let moved_north_m = (c.eye.lat_deg - before.lat_deg) * north_m_per_deg;
        assert!((moved_north_m - 1000.0).abs() < 0.5, "{moved_north_m}");
        assert!((c.eye.lon_deg - before.lon_deg).abs() < 1e-9);
        // A straight line leaves the curved earth: 1 km out, the tangent is 1000^2/(2R) higher.
        let rise_m = c.eye.alt_m - before.alt_m;
        assert!((rise_m - 0.0785).abs() < 0.01, "{rise_m}");
    }

    #[test]
    fn up_and_down_follow_the_local_vertical_and_shift_is_faster() {
        let mut c = camera(123.0, -30.0);
        let before = c.eye;
        c.fly(
            MoveInput {
                up: 1.0,
                fast: true,
                ..Default::default()
            },
            1.0,
        );
        assert!((c.eye.alt_m - before.alt_m - 100.0 * FAST_FACTOR).abs() < 1e-6);
        assert!((c.eye.lat_deg - before.lat_deg).abs() < 1e-12);
        assert!((c.orientation.heading_deg - 123.0).abs() < 1e-9);
    }

    #[test]
    fn the_eye_never_goes_below_the_lowest_valid_altitude() {
        let mut c = camera(0.0, -89.0);
        c.set_speed(SPEED_RANGE_MPS.1);
        c.fly(
            MoveInput {
                up: -1.0,
                ..Default::default()
            },
            10.0,
        );
        assert!(c.eye.alt_m >= MIN_EYE_ALTITUDE_M);
    }

    #[test]
    fn look_wraps_heading_and_clamps_pitch() {
        let mut c = camera(350.0, 80.0);
        c.look(20.0, 30.0);
        assert!((c.orientation.heading_deg - 10.0).abs() < 1e-9);
        assert_eq!(c.orientation.pitch_deg, MAX_PITCH_DEG);
        c.look(-20.0, -500.0);
        assert!((c.orientation.heading_deg - 350.0).abs() < 1e-9);
        assert_eq!(c.orientation.pitch_deg, -MAX_PITCH_DEG);
        c.look(f64::NAN, f64::INFINITY);
        assert!(c.orientation.heading_deg.is_finite() && c.orientation.pitch_deg.is_finite());
    }

    #[test]
    fn speed_steps_by_wheel_notches_within_range() {
        let mut c = camera(0.0, 0.0);
        c.scale_speed(2.0);
        assert!((c.speed_mps - 100.0 * 1.25 * 1.25).abs() < 1e-9);
        c.scale_speed(-1000.0);
        assert_eq!(c.speed_mps, SPEED_RANGE_MPS.0);
        c.scale_speed(1000.0);
        assert_eq!(c.speed_mps, SPEED_RANGE_MPS.1);
        c.set_speed(f64::NAN);
        assert_eq!(c.speed_mps, SPEED_RANGE_MPS.1);
    }

    #[test]
    fn flying_east_for_100_km_follows_a_straight_line_in_space() {
        // Many small steps along the line of sight trace the straight line of one big step
        // (the line of sight is kept in space, not in heading): compare with the ECEF line.
        let mut c = camera(90.0, 0.0);
        let start = c.eye.to_ecef();
        let direction = forward_ecef(&c);
        for _ in 0..1000 {
            c.fly(
                MoveInput {
                    forward: 1.0,
                    ..Default::default()
                },
                1.0,
            );
        }
        let expected = start + direction * 100_000.0;
        let error_m = (c.eye.to_ecef() - expected).length();
        assert!(error_m < 0.01, "{error_m} m off the straight line");
        // The heading has turned by the convergence of the meridians (about 0.65 degree).
        assert!(
            c.orientation.heading_deg > 90.3,
            "{}",
            c.orientation.heading_deg
        );
    }

    proptest! {
        #[test]
        fn a_step_moves_by_speed_times_time_and_keeps_the_line_of_sight(
            heading in 0.0..360.0f64,
            pitch in -80.0..80.0f64,
            forward in -1.0..1.0f64,
            right in -1.0..1.0f64,
            up in -1.0..1.0f64,
            dt in 0.001..2.0f64,
            lat in -80.0..80.0f64,
            lon in -180.0..180.0f64,
        ) {
            let mut c = FlyCamera::new(
                Geodetic::new(lat, lon, 2000.0),
                Hpr { heading_deg: heading, pitch_deg: pitch, roll_deg: 0.0 },
                50.0,
            );
            let before_ecef = c.eye.to_ecef();
            let sight_before = forward_ecef(&c);
            let input = MoveInput { forward, right, up, fast: false };
            let flown = c.fly(input, dt);
            let moved = (c.eye.to_ecef() - before_ecef).length();
            prop_assert!((moved - flown).abs() < 1e-6, "moved {moved} flown {flown}");
            prop_assert!(flown <= 50.0 * dt + 1e-9);
            let sight_after = forward_ecef(&c);
            prop_assert!((sight_after - sight_before).length() < 1e-9);
        }
    }
}
