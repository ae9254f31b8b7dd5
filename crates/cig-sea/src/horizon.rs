//! Earth curvature with standard terrestrial refraction: the sea horizon, its dip, and how
//! much of a distant ship hides below it (hull-down).
//!
//! Algorithm: a spherical earth of radius `R` (by default the mean radius 6 371 008.8 m).
//! Terrestrial refraction bends a nearly horizontal ray with a curvature `k / R` (the
//! refraction coefficient `k`, standard 0.13); the usual equivalent is a straight ray over an
//! earth of effective radius `R_e = R / (1 − k)` (Bowditch, *The American Practical
//! Navigator*, table of distance of the horizon: 3.83 √h km with refraction, 3.57 √h km
//! without). On that effective sphere:
//!
//! - the horizon lies at the central angle `θ_h = acos(R_e / (R_e + h))`, computed as
//!   `atan2(√(2 R_e h + h²), R_e)`; its distance is the arc `R_e θ_h` (within 10⁻⁵ of the
//!   tangent length for eyes below 100 m);
//! - the dip of the horizon below the eye's horizontal is the same angle `θ_h` (angles at the
//!   observer are preserved by the effective-radius substitution): 1.80′ at 1 m, 2.54′ at 2 m;
//! - an object at the arc distance `d` beyond the horizon hides its lowest
//!   `R_e (1 / cos(d / R_e − θ_h) − 1)` metres; its top is visible from up to the sum of the
//!   horizon distances of the eye and the top (3.83 (√h_eye + √h_top) km);
//! - for the renderer, a sea-level point at distance `d` lies `d² / (2 R)` below the eye's
//!   tangent plane on the true earth but appears only `d² (1 − k) / (2 R)` below it: the
//!   difference `k d² / (2 R)` ([`refraction_lift_m`]) is what refraction adds to what the eye
//!   sees (parabolic approximation: 10⁻⁴ relative at 100 km, 1 % at 1000 km).
//!
//! Limits: one constant `k` along the ray (no ducting, mirage or looming: `k` is limited to
//! −1..=0.9, where `k → 1` would flatten the earth); a sphere, not the ellipsoid (pass a local
//! radius of curvature with [`Refraction::with_radius_m`] if it matters); the eye and the
//! object stand on a calm sea level (waves and tide are the caller's). Distances are along the
//! earth's surface, in metres.

use crate::{checked, SeaError};

/// Mean earth radius, m (IUGG mean radius R₁ of the WGS84 ellipsoid).
pub const EARTH_MEAN_RADIUS_M: f64 = 6_371_008.8;

/// The standard terrestrial refraction coefficient (0.13: the ray's curvature over the
/// earth's, the value behind the 3.83 √h km horizon of the navigation tables).
pub const STANDARD_REFRACTION_K: f64 = 0.13;

/// Largest eye or object height accepted, m (100 km).
pub const MAX_HEIGHT_M: f64 = 100_000.0;

/// Largest distance accepted, m (1000 km).
pub const MAX_DISTANCE_M: f64 = 1_000_000.0;

/// The refraction coefficient `k` with the earth radius it applies to.
///
/// Build with [`Refraction::new`] (checked) or use [`Refraction::STANDARD`] and
/// [`Refraction::NONE`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Refraction {
    k: f64,
    radius_m: f64,
}

impl Refraction {
    /// Standard terrestrial refraction, `k` = 0.13, on the mean earth radius.
    pub const STANDARD: Refraction = Refraction {
        k: STANDARD_REFRACTION_K,
        radius_m: EARTH_MEAN_RADIUS_M,
    };

    /// No refraction (the geometric horizon), `k` = 0, on the mean earth radius.
    pub const NONE: Refraction = Refraction {
        k: 0.0,
        radius_m: EARTH_MEAN_RADIUS_M,
    };

    /// The coefficient `k` (dimensionless, −1..=0.9) on the mean earth radius.
    pub fn new(k: f64) -> Result<Refraction, SeaError> {
        let k = checked("refraction k", k, -1.0, 0.9, "-1..=0.9")?;
        Ok(Refraction {
            k,
            radius_m: EARTH_MEAN_RADIUS_M,
        })
    }

    /// The same coefficient on another earth radius, m (1000..=100 000 km), e.g. the local
    /// radius of curvature of the ellipsoid.
    pub fn with_radius_m(self, radius_m: f64) -> Result<Refraction, SeaError> {
        let radius_m = checked("earth radius_m", radius_m, 1.0e6, 1.0e8, "1e6..=1e8 m")?;
        Ok(Refraction { radius_m, ..self })
    }

    /// The refraction coefficient `k`.
    pub fn k(&self) -> f64 {
        self.k
    }

    /// The true earth radius, m.
    pub fn radius_m(&self) -> f64 {
        self.radius_m
    }

    /// The effective earth radius `R / (1 − k)`, m.
    pub fn effective_radius_m(&self) -> f64 {
        self.radius_m / (1.0 - self.k)
    }
}

impl Default for Refraction {
    /// [`Refraction::STANDARD`].
    fn default() -> Refraction {
        Refraction::STANDARD
    }
}

/// The effective earth radius `R / (1 − k)`, m (7 323 000 m for the standard `k`).
pub fn effective_radius_m(refraction: Refraction) -> f64 {
    refraction.effective_radius_m()
}

fn height(name: &'static str, value: f64) -> Result<f64, SeaError> {
    checked(name, value, 0.0, MAX_HEIGHT_M, "0..=100000 m")
}

fn distance(value: f64) -> Result<f64, SeaError> {
    checked("distance_m", value, 0.0, MAX_DISTANCE_M, "0..=1000000 m")
}

/// The central angle from the foot of an eye `h` metres up to its horizon, radians, on the
/// effective sphere of radius `re`.
fn horizon_angle_rad(h: f64, re: f64) -> f64 {
    (2.0 * re * h + h * h).sqrt().atan2(re)
}

/// Distance to the sea horizon from an eye `eye_height_m` above the sea (0..=100 km), m,
/// along the surface: about 3.83 √h km with standard refraction, 3.57 √h km without.
pub fn horizon_distance_m(eye_height_m: f64, refraction: Refraction) -> Result<f64, SeaError> {
    let h = height("eye_height_m", eye_height_m)?;
    let re = refraction.effective_radius_m();
    Ok(re * horizon_angle_rad(h, re))
}

/// Dip of the sea horizon below the eye's horizontal, degrees: about 0.0300° √h (1.80′ √h)
/// with standard refraction.
pub fn dip_deg(eye_height_m: f64, refraction: Refraction) -> Result<f64, SeaError> {
    let h = height("eye_height_m", eye_height_m)?;
    Ok(horizon_angle_rad(h, refraction.effective_radius_m()).to_degrees())
}

/// The height of an object's base hidden below the sea horizon, m, for an eye
/// `eye_height_m` above the sea and an object `distance_m` away along the surface (0 inside
/// the horizon).
pub fn hidden_height_m(
    eye_height_m: f64,
    distance_m: f64,
    refraction: Refraction,
) -> Result<f64, SeaError> {
    let h = height("eye_height_m", eye_height_m)?;
    let d = distance(distance_m)?;
    let re = refraction.effective_radius_m();
    let beyond = d / re - horizon_angle_rad(h, re);
    if beyond <= 0.0 {
        return Ok(0.0);
    }
    // R_e (1/cos x − 1) written without the cancellation of 1/cos x − 1 for small x.
    let half_sin = (0.5 * beyond).sin();
    Ok(re * 2.0 * half_sin * half_sin / beyond.cos())
}

/// The greatest distance along the surface at which the top of an object `top_height_m`
/// above the sea can be seen from an eye `eye_height_m` above it, m: the sum of both
/// horizon distances.
pub fn max_range_to_see_top_m(
    eye_height_m: f64,
    top_height_m: f64,
    refraction: Refraction,
) -> Result<f64, SeaError> {
    let h = height("eye_height_m", eye_height_m)?;
    let top = height("top_height_m", top_height_m)?;
    let re = refraction.effective_radius_m();
    Ok(re * (horizon_angle_rad(h, re) + horizon_angle_rad(top, re)))
}

/// Whether the top of an object `target_height_m` above the sea and `distance_m` away shows
/// above the sea horizon from an eye `eye_height_m` above the sea.
pub fn visible_top(
    eye_height_m: f64,
    target_height_m: f64,
    distance_m: f64,
    refraction: Refraction,
) -> Result<bool, SeaError> {
    let top = height("target_height_m", target_height_m)?;
    Ok(hidden_height_m(eye_height_m, distance_m, refraction)? < top)
}

/// How far a sea-level point `distance_m` away lies below the eye's tangent plane on the
/// true earth, m: `d² / (2 R)`.
pub fn geometric_drop_m(distance_m: f64, refraction: Refraction) -> Result<f64, SeaError> {
    let d = distance(distance_m)?;
    Ok(d * d / (2.0 * refraction.radius_m))
}

/// How far a sea-level point `distance_m` away appears below the eye's tangent plane
/// through the refracting atmosphere, m: `d² (1 − k) / (2 R)`.
pub fn apparent_drop_m(distance_m: f64, refraction: Refraction) -> Result<f64, SeaError> {
    let d = distance(distance_m)?;
    Ok(d * d / (2.0 * refraction.effective_radius_m()))
}

/// What refraction lifts a point `distance_m` away, m: the geometric drop minus the apparent
/// drop, `k d² / (2 R)` (negative for `k` < 0). The renderer adds it to the height of what
/// it draws at that distance.
pub fn refraction_lift_m(distance_m: f64, refraction: Refraction) -> Result<f64, SeaError> {
    let d = distance(distance_m)?;
    Ok(refraction.k * d * d / (2.0 * refraction.radius_m))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(got: f64, want: f64, rel: f64) -> bool {
        (got - want).abs() <= rel * want.abs()
    }

    #[test]
    fn horizon_is_3_57_and_3_83_sqrt_h_km() {
        for h in [0.5, 1.0, 2.0, 10.0, 30.0, 100.0] {
            let geo = horizon_distance_m(h, Refraction::NONE).unwrap();
            let std = horizon_distance_m(h, Refraction::STANDARD).unwrap();
            assert!(close(geo, 3570.0 * f64::sqrt(h), 0.02), "{h} m: {geo}");
            assert!(close(std, 3830.0 * f64::sqrt(h), 0.02), "{h} m: {std}");
        }
        assert_eq!(horizon_distance_m(0.0, Refraction::STANDARD).unwrap(), 0.0);
        assert!(close(
            effective_radius_m(Refraction::STANDARD),
            EARTH_MEAN_RADIUS_M / 0.87,
            1e-12
        ));
    }

    #[test]
    fn a_30_m_masthead_touches_the_horizon_at_the_tabulated_ranges() {
        let cases = [
            (0.5, 23_700.0, Refraction::STANDARD),
            (1.0, 24_800.0, Refraction::STANDARD),
            (1.5, 25_600.0, Refraction::STANDARD),
            (2.0, 26_400.0, Refraction::STANDARD),
            (1.0, 23_100.0, Refraction::NONE),
            (2.0, 24_600.0, Refraction::NONE),
        ];
        for (eye, want, r) in cases {
            let got = max_range_to_see_top_m(eye, 30.0, r).unwrap();
            assert!(close(got, want, 0.02), "eye {eye} m, k {}: {got}", r.k());
            // Just inside that range the top shows; just beyond it does not.
            assert!(visible_top(eye, 30.0, got * 0.999, r).unwrap());
            assert!(!visible_top(eye, 30.0, got * 1.001, r).unwrap());
            let hidden = hidden_height_m(eye, got, r).unwrap();
            assert!(close(hidden, 30.0, 1e-6), "hidden {hidden}");
        }
    }

    #[test]
    fn hidden_heights_from_a_1_5_m_eye() {
        for (d_km, want) in [
            (8.0, 0.75),
            (10.0, 1.9),
            (15.0, 7.3),
            (20.0, 16.0),
            (25.0, 28.0),
        ] {
            let got = hidden_height_m(1.5, d_km * 1000.0, Refraction::STANDARD).unwrap();
            assert!(close(got, want, 0.02), "{d_km} km: {got}");
        }
        // Inside the horizon (4.7 km) nothing hides.
        assert_eq!(
            hidden_height_m(1.5, 4000.0, Refraction::STANDARD).unwrap(),
            0.0
        );
    }

    #[test]
    fn dip_of_the_horizon() {
        let arcmin = |h: f64| dip_deg(h, Refraction::STANDARD).unwrap() * 60.0;
        assert!(close(arcmin(1.0), 1.8, 0.02), "{}", arcmin(1.0));
        assert!(close(arcmin(2.0), 2.5, 0.02), "{}", arcmin(2.0));
        // Without refraction the dip is larger: 1.93' at 1 m.
        let geo = dip_deg(1.0, Refraction::NONE).unwrap() * 60.0;
        assert!(close(geo, 1.926, 0.01), "{geo}");
    }

    #[test]
    fn drops_and_refraction_lift() {
        let r = Refraction::STANDARD;
        let d = 20_000.0;
        let geo = geometric_drop_m(d, r).unwrap();
        let app = apparent_drop_m(d, r).unwrap();
        let lift = refraction_lift_m(d, r).unwrap();
        assert!(close(geo, 31.39, 0.001), "{geo}");
        assert!(close(app, geo * 0.87, 1e-12));
        assert!(close(lift, geo - app, 1e-9), "{lift} vs {}", geo - app);
        assert_eq!(refraction_lift_m(d, Refraction::NONE).unwrap(), 0.0);
    }

    #[test]
    fn custom_refraction_and_radius() {
        let r = Refraction::new(0.25)
            .unwrap()
            .with_radius_m(6_378_137.0)
            .unwrap();
        assert_eq!(r.k(), 0.25);
        assert_eq!(r.radius_m(), 6_378_137.0);
        assert!(close(r.effective_radius_m(), 6_378_137.0 / 0.75, 1e-12));
        assert_eq!(Refraction::default(), Refraction::STANDARD);
        // More refraction, farther horizon.
        let far = horizon_distance_m(10.0, r).unwrap();
        let std = horizon_distance_m(10.0, Refraction::STANDARD).unwrap();
        assert!(far > std);
    }

    #[test]
    fn bad_input_is_refused() {
        let r = Refraction::STANDARD;
        for k in [f64::NAN, 1.0, 0.95, -1.5, f64::INFINITY] {
            assert!(Refraction::new(k).is_err(), "{k}");
        }
        assert!(r.with_radius_m(0.0).is_err());
        assert!(r.with_radius_m(f64::NAN).is_err());
        assert!(horizon_distance_m(-1.0, r).is_err());
        assert!(horizon_distance_m(f64::NAN, r).is_err());
        assert!(dip_deg(2.0e5, r).is_err());
        assert!(hidden_height_m(1.0, -5.0, r).is_err());
        assert!(hidden_height_m(1.0, 2.0e6, r).is_err());
        assert!(max_range_to_see_top_m(1.0, f64::INFINITY, r).is_err());
        assert!(visible_top(1.0, -1.0, 100.0, r).is_err());
        assert!(refraction_lift_m(f64::NAN, r).is_err());
        let err = horizon_distance_m(-1.0, r).unwrap_err();
        assert_eq!(err.to_string(), "eye_height_m must be 0..=100000 m, not -1");
    }
}
