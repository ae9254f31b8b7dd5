//! Exact-where-possible angle helpers in degrees.
//!
//! Algorithm: reduce the argument to within 45 degrees of a multiple of 90
//! degrees before calling the radian trigonometric functions, so that the
//! quadrant angles come out exact (`sin 90 = 1`, `cos 90 = 0`, `atan2(1, 0) =
//! 90`). Source: C. F. F. Karney, GeographicLib, `Math::sincosd` and
//! `Math::atan2d` (<https://geographiclib.sourceforge.io>). Limits: non-finite
//! inputs give NaN; otherwise the error is within an ulp or two of the
//! correctly rounded result.

/// `(sin x, cos x)` for `x` in degrees, exact at multiples of 90 degrees.
pub(crate) fn sincos_deg(x_deg: f64) -> (f64, f64) {
    // `%` keeps the sign of the dividend and is exact.
    let r = x_deg % 360.0;
    let q = (r / 90.0).round();
    let rad = (r - 90.0 * q).to_radians();
    let (s, c) = rad.sin_cos();
    // `q` is in -4..=4 here (or NaN, which gives quadrant 0 and NaN results).
    #[allow(
        clippy::cast_possible_truncation,
        reason = "q is a small whole number in -4..=4 (or NaN, which maps to 0)"
    )]
    let quadrant = (q as i64).rem_euclid(4);
    let (s, c) = match quadrant {
        0 => (s, c),
        1 => (c, -s),
        2 => (-s, -c),
        _ => (-c, s),
    };
    // Adding 0.0 turns a negative zero into a positive one.
    (s + 0.0, c + 0.0)
}

/// `atan2(y, x)` in degrees, in `[-180, 180]`, exact at multiples of 90 degrees.
pub(crate) fn atan2_deg(y: f64, x: f64) -> f64 {
    let (mut y, mut x) = (y, x);
    let mut q = 0;
    if y.abs() > x.abs() {
        std::mem::swap(&mut x, &mut y);
        q = 2;
    }
    if x.is_sign_negative() {
        x = -x;
        q += 1;
    }
    // Here x >= |y|, so the angle is within [-45, 45] degrees.
    let ang = y.atan2(x).to_degrees();
    match q {
        1 => 180.0_f64.copysign(y) - ang,
        2 => 90.0 - ang,
        3 => -90.0 + ang,
        _ => ang,
    }
}

/// Wraps an angle in degrees into `[-180, 180)`, exactly (no rounding: `%`
/// is exact and the final shift by 360 obeys Sterbenz's lemma).
pub(crate) fn wrap_deg(x_deg: f64) -> f64 {
    let r = x_deg % 360.0;
    if r >= 180.0 {
        r - 360.0
    } else if r < -180.0 {
        r + 360.0
    } else {
        r
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sincos_exact_at_quadrants() {
        assert_eq!(sincos_deg(0.0), (0.0, 1.0));
        assert_eq!(sincos_deg(90.0), (1.0, 0.0));
        assert_eq!(sincos_deg(-90.0), (-1.0, 0.0));
        assert_eq!(sincos_deg(180.0), (0.0, -1.0));
        assert_eq!(sincos_deg(-180.0), (0.0, -1.0));
        assert_eq!(sincos_deg(270.0), (-1.0, 0.0));
        assert_eq!(sincos_deg(720.0), (0.0, 1.0));
        let (s, c) = sincos_deg(30.0);
        assert!((s - 0.5).abs() < 2e-16 && (c - 0.75_f64.sqrt()).abs() < 2e-16);
        let (s, c) = sincos_deg(f64::NAN);
        assert!(s.is_nan() && c.is_nan());
    }

    #[test]
    fn atan2_exact_at_quadrants() {
        assert_eq!(atan2_deg(1.0, 0.0), 90.0);
        assert_eq!(atan2_deg(-1.0, 0.0), -90.0);
        assert_eq!(atan2_deg(0.0, -1.0), 180.0);
        assert_eq!(atan2_deg(-0.0, -1.0), -180.0);
        assert_eq!(atan2_deg(0.0, 1.0), 0.0);
        assert_eq!(atan2_deg(1.0, 1.0), 45.0);
        assert!((atan2_deg(1.0, -1.0) - 135.0).abs() < 1e-13);
        assert!((atan2_deg(-1.0, -1.0) + 135.0).abs() < 1e-13);
        for i in -179..=179 {
            let a = f64::from(i);
            let (s, c) = sincos_deg(a);
            assert!((atan2_deg(s, c) - a).abs() < 1e-12, "{a}");
        }
    }

    #[test]
    fn wrapping() {
        assert_eq!(wrap_deg(180.0), -180.0);
        assert_eq!(wrap_deg(-180.0), -180.0);
        assert_eq!(wrap_deg(540.0), -180.0);
        assert_eq!(wrap_deg(-540.0), -180.0);
        assert_eq!(wrap_deg(190.0), -170.0);
        assert_eq!(wrap_deg(-190.0), 170.0);
        assert_eq!(wrap_deg(-1e-300), -1e-300);
        assert_eq!(wrap_deg(359.0), -1.0);
        assert_eq!(wrap_deg(-359.0), 1.0);
        assert_eq!(wrap_deg(1e-12), 1e-12);
        assert!(wrap_deg(f64::NAN).is_nan());
    }
}
