//! Dead reckoning: DIS dead-reckoning models DRM 1-9 (IEEE 1278.1-2012 Annex E).
//!
//! Algorithm (Annex E, E.4-E.8). With P0, V0 the ECEF position and velocity of the last
//! update, t the time since it, ω the body-axis angular velocity (|ω| = w), Ω its
//! skew-symmetric matrix (Ω x = ω × x) and R0 the body-to-world rotation of the update's Euler
//! angles:
//!
//! * DRM 1 Static: nothing moves. (DRM 0 "Other" is treated as Static.)
//! * World-coordinate models, acceleration A0 given in world (ECEF) axes:
//!   FPW (2) P = P0 + V0 t; FVW (5) P = P0 + V0 t + ½ A0 t²; RPW (3) and RVW (4) are FPW and
//!   FVW with the orientation turned.
//! * Body-axis models, acceleration a_b given in body axes and the body velocity
//!   v_b = R0ᵀ V0: P = P0 + R0 (R1 v_b + R2 a_b), with R1 = ∫₀ᵗ e^{Ωτ} dτ and
//!   R2 = ∫₀ᵗ τ e^{Ωτ} dτ. In the standard's notation
//!   R1 = ((wt − sin wt)/w³) ωωᵀ + (sin wt / w) I + ((1 − cos wt)/w²) Ω and
//!   R2 = ((½w²t² − cos wt − wt sin wt + 1)/w⁴) ωωᵀ + ((cos wt + wt sin wt − 1)/w²) I +
//!   ((sin wt − wt cos wt)/w³) Ω. FPB (6) and FVB (9) do not rotate (R1 = t I, R2 = ½t² I);
//!   RPB (7) uses R1 v_b and RVB (8) R1 v_b + R2 a_b.
//! * Orientation of the rotating models (RPW, RVW, RPB, RVB): the standard's DR matrix
//!   \[DR\] = ((1 − cos wt)/w²) ωωᵀ + cos wt I − (sin wt / w) Ω updates the world-to-body matrix,
//!   \[R\]w→b(t) = \[DR\] \[R\]w→b(0); equivalently body-to-world R(t) = R0 e^{Ωt}
//!   (Rodrigues: e^{Ωt} = I + (sin wt / w) Ω + ((1 − cos wt)/w²) Ω²).
//!
//! Here the coefficients are written in the Ω, Ω² basis (Ω² = ωωᵀ − w² I, the same matrices)
//! and replaced by their Taylor series when wt < 1e-3 so that a vanishing ω is exact.
//! Euler angles are the DIS ones: ψ about world z, then θ about the new y, then φ about the new x
//! (body x forward, y right, z down), body-to-world R = Rz(ψ) Ry(θ) Rx(φ).
//!
//! Limits: the body-axis acceleration is taken as the rate of change of the body-frame velocity
//! (the reading that makes R2 exact); no Earth-rotation or gravity terms (the standard has
//! none); angles near θ = ±90° lose ψ/φ separation as every Euler form does.

use glam::{DMat3, DVec3};

/// A DIS dead-reckoning algorithm (SISO-REF-010 UID 44).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum DrAlgorithm {
    /// 0: other; extrapolated as static.
    Other,
    /// 1: static.
    Static,
    /// 2: fixed orientation, constant velocity, world axes.
    Fpw,
    /// 3: rotating, constant velocity, world axes.
    Rpw,
    /// 4: rotating, constant acceleration, world axes.
    Rvw,
    /// 5: fixed orientation, constant acceleration, world axes.
    Fvw,
    /// 6: fixed orientation, constant velocity, body axes.
    Fpb,
    /// 7: rotating, constant velocity, body axes.
    Rpb,
    /// 8: rotating, constant acceleration, body axes.
    Rvb,
    /// 9: fixed orientation, constant acceleration, body axes.
    Fvb,
}

impl DrAlgorithm {
    /// The algorithm for its wire number; numbers above 9 read as [`DrAlgorithm::Other`].
    #[must_use]
    pub fn from_code(code: u8) -> DrAlgorithm {
        match code {
            1 => DrAlgorithm::Static,
            2 => DrAlgorithm::Fpw,
            3 => DrAlgorithm::Rpw,
            4 => DrAlgorithm::Rvw,
            5 => DrAlgorithm::Fvw,
            6 => DrAlgorithm::Fpb,
            7 => DrAlgorithm::Rpb,
            8 => DrAlgorithm::Rvb,
            9 => DrAlgorithm::Fvb,
            _ => DrAlgorithm::Other,
        }
    }

    /// Wire number.
    #[must_use]
    pub fn code(self) -> u8 {
        match self {
            DrAlgorithm::Other => 0,
            DrAlgorithm::Static => 1,
            DrAlgorithm::Fpw => 2,
            DrAlgorithm::Rpw => 3,
            DrAlgorithm::Rvw => 4,
            DrAlgorithm::Fvw => 5,
            DrAlgorithm::Fpb => 6,
            DrAlgorithm::Rpb => 7,
            DrAlgorithm::Rvb => 8,
            DrAlgorithm::Fvb => 9,
        }
    }

    /// Whether the orientation turns with the angular velocity.
    #[must_use]
    pub fn rotates(self) -> bool {
        matches!(
            self,
            DrAlgorithm::Rpw | DrAlgorithm::Rvw | DrAlgorithm::Rpb | DrAlgorithm::Rvb
        )
    }

    /// Whether the acceleration field is in body axes.
    #[must_use]
    pub fn body_axes(self) -> bool {
        matches!(
            self,
            DrAlgorithm::Fpb | DrAlgorithm::Rpb | DrAlgorithm::Rvb | DrAlgorithm::Fvb
        )
    }
}

/// DIS Euler angles (Tait-Bryan ψ, θ, φ relative to the ECEF axes), radians.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct EulerAngles {
    /// ψ, rotation about the world z axis, radians.
    pub psi_rad: f64,
    /// θ, rotation about the once-turned y axis, radians.
    pub theta_rad: f64,
    /// φ, rotation about the twice-turned x axis, radians.
    pub phi_rad: f64,
}

impl EulerAngles {
    /// Body-to-world rotation R = Rz(ψ) Ry(θ) Rx(φ) (columns are the body axes in ECEF).
    #[must_use]
    pub fn body_to_world(self) -> DMat3 {
        DMat3::from_rotation_z(self.psi_rad)
            * DMat3::from_rotation_y(self.theta_rad)
            * DMat3::from_rotation_x(self.phi_rad)
    }

    /// The Euler angles of a body-to-world rotation (θ in [−90°, 90°], ψ and φ in (−180°, 180°]).
    #[must_use]
    pub fn from_body_to_world(m: DMat3) -> EulerAngles {
        // m.col(c).{x,y,z} is row x/y/z of column c.
        let sin_theta = (-m.x_axis.z).clamp(-1.0, 1.0);
        let theta = sin_theta.asin();
        if sin_theta.abs() < 1.0 - 1e-12 {
            EulerAngles {
                psi_rad: m.x_axis.y.atan2(m.x_axis.x),
                theta_rad: theta,
                phi_rad: m.y_axis.z.atan2(m.z_axis.z),
            }
        } else {
            // Gimbal lock: put the whole turn in ψ.
            EulerAngles {
                psi_rad: (-m.y_axis.x).atan2(m.y_axis.y),
                theta_rad: theta,
                phi_rad: 0.0,
            }
        }
    }
}

/// The state an Entity State PDU carries for dead reckoning.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct DrInput {
    /// Position, ECEF metres.
    pub position_ecef_m: DVec3,
    /// Orientation.
    pub orientation: EulerAngles,
    /// Linear velocity in world (ECEF) axes, m/s (the Entity State velocity field).
    pub velocity_ecef_mps: DVec3,
    /// Linear acceleration, m/s²: world axes for DRM 2-5, body axes for DRM 6-9.
    pub acceleration_mps2: DVec3,
    /// Angular velocity in body axes, rad/s.
    pub angular_velocity_body_radps: DVec3,
}

/// A dead-reckoned pose.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DrPose {
    /// Position, ECEF metres.
    pub position_ecef_m: DVec3,
    /// Body-to-world rotation.
    pub body_to_world: DMat3,
    /// Velocity, ECEF m/s.
    pub velocity_ecef_mps: DVec3,
}

impl DrPose {
    /// The orientation as DIS Euler angles.
    #[must_use]
    pub fn orientation(&self) -> EulerAngles {
        EulerAngles::from_body_to_world(self.body_to_world)
    }
}

fn skew(w: DVec3) -> DMat3 {
    DMat3::from_cols(
        DVec3::new(0.0, w.z, -w.y),
        DVec3::new(-w.z, 0.0, w.x),
        DVec3::new(w.y, -w.x, 0.0),
    )
}

/// Coefficients of I, Ω, Ω² in a matrix series.
#[derive(Clone, Copy, Debug)]
struct Coefficients {
    identity: f64,
    omega: f64,
    omega_squared: f64,
}

/// Below this w·t the closed forms lose digits; Taylor series are used instead.
const SMALL_ANGLE_RAD: f64 = 1e-3;

/// The three series at once (one sin/cos):
/// e^{Ωt} = I + (sin wt / w) Ω + ((1 − cos wt)/w²) Ω²;
/// R1 = ∫₀ᵗ e^{Ωτ} dτ = t I + ((1 − cos wt)/w²) Ω + ((wt − sin wt)/w³) Ω²;
/// R2 = ∫₀ᵗ τ e^{Ωτ} dτ = ½t² I + ((sin wt − wt cos wt)/w³) Ω +
/// ((½w²t² + 1 − cos wt − wt sin wt)/w⁴) Ω².
fn series(w: f64, t: f64) -> [Coefficients; 3] {
    let wt = w * t;
    let (rot, r1, r2);
    if wt.abs() < SMALL_ANGLE_RAD {
        let w2 = w * w;
        rot = (
            t - w2 * t.powi(3) / 6.0,
            t * t / 2.0 - w2 * t.powi(4) / 24.0,
        );
        r1 = (
            t * t / 2.0 - w2 * t.powi(4) / 24.0,
            t.powi(3) / 6.0 - w2 * t.powi(5) / 120.0,
        );
        r2 = (
            t.powi(3) / 3.0 - w2 * t.powi(5) / 30.0,
            t.powi(4) / 8.0 - w2 * t.powi(6) / 144.0,
        );
    } else {
        let (sin, cos) = wt.sin_cos();
        let w2 = w * w;
        let w3 = w2 * w;
        rot = (sin / w, (1.0 - cos) / w2);
        r1 = ((1.0 - cos) / w2, (wt - sin) / w3);
        r2 = (
            (sin - wt * cos) / w3,
            (0.5 * wt * wt + 1.0 - cos - wt * sin) / (w2 * w2),
        );
    }
    [
        Coefficients {
            identity: 1.0,
            omega: rot.0,
            omega_squared: rot.1,
        },
        Coefficients {
            identity: t,
            omega: r1.0,
            omega_squared: r1.1,
        },
        Coefficients {
            identity: t * t / 2.0,
            omega: r2.0,
            omega_squared: r2.1,
        },
    ]
}

/// The standard's DR matrix for the world-to-body update over `t_s` seconds:
/// \[DR\] = ((1 − cos wt)/w²) ωωᵀ + cos wt I − (sin wt / w) Ω (equal to e^{−Ωt}).
#[must_use]
pub fn dr_matrix(angular_velocity_body_radps: DVec3, t_s: f64) -> DMat3 {
    let w = angular_velocity_body_radps.length();
    let omega = skew(angular_velocity_body_radps);
    let [c, _, _] = series(w, t_s);
    // e^{-Ωt}: flip the sign of the odd term.
    DMat3::IDENTITY + omega * (-c.omega) + omega * omega * c.omega_squared
}

/// Dead-reckons `input` forward by `t_s` seconds with `algorithm`.
#[must_use]
pub fn extrapolate(algorithm: DrAlgorithm, input: &DrInput, t_s: f64) -> DrPose {
    DrModel::new(algorithm, *input).pose(t_s)
}

/// One update's dead-reckoning model with the per-update work done once, for extrapolating
/// the same update every frame: R0, R0 Ω, R0 Ω², and the body velocity and acceleration with
/// their ω× and ω×ω× images taken to world axes, so that each pose is one sin/cos and a few
/// scaled vector sums (P = P0 + R0 (R1 v_b + R2 a_b) expands over the I, Ω, Ω² terms).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DrModel {
    /// The algorithm.
    pub algorithm: DrAlgorithm,
    /// The update.
    pub input: DrInput,
    omega_rad_s: f64,
    r0: DMat3,
    r0_omega: DMat3,
    r0_omega2: DMat3,
    /// R0 v_b, R0 Ω v_b, R0 Ω² v_b.
    velocity_terms: [DVec3; 3],
    /// R0 a_b, R0 Ω a_b, R0 Ω² a_b (body-axis acceleration models).
    acceleration_terms: [DVec3; 3],
}

impl DrModel {
    /// Prepares a model.
    #[must_use]
    pub fn new(algorithm: DrAlgorithm, input: DrInput) -> DrModel {
        let r0 = input.orientation.body_to_world();
        let w = input.angular_velocity_body_radps;
        let omega = skew(w);
        let v_body = r0.transpose() * input.velocity_ecef_mps;
        let a_body = input.acceleration_mps2;
        let images = |v: DVec3| {
            let wv = w.cross(v);
            [r0 * v, r0 * wv, r0 * w.cross(wv)]
        };
        DrModel {
            algorithm,
            input,
            omega_rad_s: w.length(),
            r0,
            r0_omega: r0 * omega,
            r0_omega2: r0 * omega * omega,
            velocity_terms: images(v_body),
            acceleration_terms: images(a_body),
        }
    }

    /// The pose `t_s` seconds after the update (non-finite times read as 0).
    #[must_use]
    pub fn pose(&self, t_s: f64) -> DrPose {
        let t = if t_s.is_finite() { t_s } else { 0.0 };
        let p0 = self.input.position_ecef_m;
        let v0 = self.input.velocity_ecef_mps;
        let a = self.input.acceleration_mps2;
        // Only the rotating and the body-axis turning models need the series (and its sin/cos).
        let [rot, r1, r2] = if self.algorithm.rotates() {
            series(self.omega_rad_s, t)
        } else {
            [Coefficients {
                identity: 1.0,
                omega: 0.0,
                omega_squared: 0.0,
            }; 3]
        };
        let apply = |c: Coefficients, terms: &[DVec3; 3]| {
            terms[0] * c.identity + terms[1] * c.omega + terms[2] * c.omega_squared
        };
        let turned = if self.algorithm.rotates() {
            self.r0 + self.r0_omega * rot.omega + self.r0_omega2 * rot.omega_squared
        } else {
            self.r0
        };
        let (position, velocity) = match self.algorithm {
            DrAlgorithm::Other | DrAlgorithm::Static => (p0, DVec3::ZERO),
            DrAlgorithm::Fpw | DrAlgorithm::Rpw | DrAlgorithm::Fpb => (p0 + v0 * t, v0),
            DrAlgorithm::Fvw | DrAlgorithm::Rvw => (p0 + v0 * t + a * (0.5 * t * t), v0 + a * t),
            DrAlgorithm::Fvb => {
                let a_world = self.acceleration_terms[0];
                (p0 + v0 * t + a_world * (0.5 * t * t), v0 + a_world * t)
            }
            DrAlgorithm::Rpb => (
                p0 + apply(r1, &self.velocity_terms),
                apply(rot, &self.velocity_terms),
            ),
            DrAlgorithm::Rvb => (
                p0 + apply(r1, &self.velocity_terms) + apply(r2, &self.acceleration_terms),
                apply(rot, &self.velocity_terms) + apply(rot, &self.acceleration_terms) * t,
            ),
        };
        DrPose {
            position_ecef_m: position,
            body_to_world: turned,
            velocity_ecef_mps: velocity,
        }
    }
}

/// Angle of the rotation taking `a` to `b`, radians in [0, π], from
/// atan2(|vee(M − Mᵀ)| / 2, (tr M − 1) / 2) with M = aᵀ b (accurate near 0 and π/2).
#[must_use]
pub fn rotation_angle_between(a: DMat3, b: DMat3) -> f64 {
    let m = a.transpose() * b;
    let trace = m.x_axis.x + m.y_axis.y + m.z_axis.z;
    // vee(M - Mᵀ) = 2 sin(angle) · axis.
    let vee = DVec3::new(
        m.y_axis.z - m.z_axis.y,
        m.z_axis.x - m.x_axis.z,
        m.x_axis.y - m.y_axis.x,
    );
    (vee.length() / 2.0).atan2((trace - 1.0) / 2.0)
}
