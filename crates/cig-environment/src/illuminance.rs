//! Natural illuminance on a horizontal surface at the ground, in lux, from the
//! sun, the moon and the night sky, with a sky-condition factor for cloud.
//!
//! Algorithm: the U.S. Naval Observatory's cubic fits of log10 illuminance in
//! the altitude of the body's centre, x = h / 90°, from D. R. Brown,
//! "Natural illumination charts" (U.S. Navy Bureau of Ships report 374-1,
//! 1952) as tabulated by Bond and Henderson (1963) and used in D. A. Vallado,
//! *Fundamentals of Astrodynamics and Applications* (3rd ed., 2007, section
//! 5.3.4, `SunIll` / `MoonIll`), the same model family as the USNO Circular 171
//! (Janiczek and DeYoung, 1987) that the NPS thesis cites as [USNO87]:
//!
//! - sun, six altitude bands from 20°..90° down to −18°..−12°, each a cubic
//!   `l0 + l1 x + l2 x² + l3 x³` (total of direct sun and skylight, clear sky);
//! - moon, three bands from −0.8° to 90°, times the phase law
//!   `10^(−0.00868 f − 2.2e-9 f⁴)` with f the phase angle in degrees, times the
//!   inverse square of the distance relative to the mean 384 400 km;
//! - night sky (starlight, airglow, zodiacal light): 0.002 lux, the value the same
//!   model uses below astronomical twilight.
//!
//! Sky condition: the USNO model divides every term by a factor of 1 (clear or
//! less than 70 % cover), 2 (thin clouds), 3 (average clouds) or 10 (dark
//! stratus). Here a cloud-cover fraction c in `[0, 1]` maps continuously to the
//! divisor `10^(c²)` (1 at c = 0, 1.8 at 0.5, 3.1 at 0.7, 10 at overcast); this
//! mapping is this crate's choice, not a published fit.
//!
//! Continuity (for rendering without steps): the published bands meet with jumps
//! of up to 1 %; the log values are blended linearly over ±0.5° around each band
//! edge. Below −18° the sun's log illuminance continues along the tangent of
//! the last cubic (0.22 decade per degree); the moon's cubic is faded linearly to
//! zero between −0.8° and −1.3° (about its own diameter).
//!
//! Reference points (tests): zenith sun 1.29e5 lux; sunrise (−0.833°) 450 lux;
//! end of civil twilight (−6°) 3.4 lux; full moon at the zenith at mean distance
//! 0.27 lux (0.22 at 60° altitude); clear moonless night 0.002 lux. Limits: a
//! climatological clear-sky mean (±20 % or more on a real day); the altitude is
//! the geometric altitude of the centre; no terrain shading, no city light.

use crate::EnvironmentError;

/// Night-sky background on a clear moonless night, lux.
pub const NIGHT_SKY_LUX: f64 = 0.002;
/// Mean Earth–moon distance of the moon's reference illuminance, metres.
pub const MOON_MEAN_DISTANCE_M: f64 = 384_400_000.0;

/// A cubic band: lower altitude bound (degrees) and `[l0, l1, l2, l3]`.
type Band = (f64, [f64; 4]);

/// Sun bands, highest first (Vallado `SunIll`, Brown 1952).
const SUN_BANDS: [Band; 6] = [
    (20.0, [3.74, 3.97, -4.07, 1.47]),
    (5.0, [3.05, 13.28, -45.98, 64.33]),
    (-0.8, [2.88, 22.26, -207.64, 1034.30]),
    (-5.0, [2.88, 21.81, -258.11, -858.36]),
    (-12.0, [2.70, 12.17, -431.69, -1899.83]),
    (-18.0, [13.84, 262.72, 1447.42, 2797.93]),
];

/// Moon bands, highest first (Vallado `MoonIll`).
const MOON_BANDS: [Band; 3] = [
    (20.0, [-1.95, 4.06, -4.24, 1.56]),
    (5.0, [-2.58, 12.58, -42.58, 59.06]),
    (-0.8, [-2.79, 24.27, -252.95, 1321.29]),
];

/// Half-width of the blend around band edges, degrees.
const BLEND_DEG: f64 = 0.5;

fn cubic(c: &[f64; 4], h_deg: f64) -> f64 {
    let x = h_deg / 90.0;
    c[0] + x * (c[1] + x * (c[2] + x * c[3]))
}

/// log10 illuminance from banded cubics, blended across band edges. `h_deg` must
/// be at or above the lowest band's lower bound minus `BLEND_DEG`.
fn banded_log10(bands: &[Band], h_deg: f64) -> f64 {
    // Find the band containing h (the last band covers everything below).
    let idx = bands
        .iter()
        .position(|(lower, _)| h_deg >= *lower)
        .unwrap_or(bands.len().saturating_sub(1));
    let Some((lower, coeffs)) = bands.get(idx) else {
        return f64::NEG_INFINITY;
    };
    let here = cubic(coeffs, h_deg);
    // Blend with the band above near its lower edge (the upper edge of this band).
    if let Some(prev) = idx.checked_sub(1).and_then(|i| bands.get(i)) {
        let edge = prev.0;
        if h_deg > edge - BLEND_DEG {
            let w = (h_deg - (edge - BLEND_DEG)) / (2.0 * BLEND_DEG);
            return (1.0 - w) * here + w * cubic(&prev.1, h_deg);
        }
    }
    // Blend with the band below near this band's lower edge.
    if let Some(next) = bands.get(idx + 1) {
        if h_deg < lower + BLEND_DEG {
            let w = (h_deg - (lower - BLEND_DEG)) / (2.0 * BLEND_DEG);
            return (1.0 - w) * cubic(&next.1, h_deg) + w * here;
        }
    }
    here
}

/// Clear-sky illuminance from the sun (direct and skylight) on horizontal ground,
/// lux, for the geometric altitude of the sun's centre in degrees.
pub fn sun_illuminance_lux(altitude_deg: f64) -> f64 {
    if altitude_deg.is_nan() {
        return 0.0;
    }
    let h = altitude_deg.clamp(-90.0, 90.0);
    let lowest = -18.0;
    let log = if h >= lowest {
        banded_log10(&SUN_BANDS, h)
    } else {
        // Continue along the tangent of the last cubic at -18° (in degrees).
        let c = SUN_BANDS[5].1;
        let x = lowest / 90.0;
        let slope_per_deg = (c[1] + x * (2.0 * c[2] + 3.0 * x * c[3])) / 90.0;
        cubic(&c, lowest) + slope_per_deg * (h - lowest)
    };
    10f64.powf(log)
}

/// Clear-sky illuminance from the moon on horizontal ground, lux, for the
/// geometric altitude of its centre (degrees), its phase angle (degrees, 0 at
/// full) and its distance from the observer (metres).
pub fn moon_illuminance_lux(altitude_deg: f64, phase_angle_deg: f64, distance_m: f64) -> f64 {
    if !altitude_deg.is_finite()
        || !phase_angle_deg.is_finite()
        || distance_m.is_nan()
        || distance_m <= 0.0
    {
        return 0.0;
    }
    let h = altitude_deg.min(90.0);
    let (fade, h_eval) = if h >= -0.8 {
        (1.0, h)
    } else if h > -1.3 {
        ((h + 1.3) / 0.5, -0.8)
    } else {
        return 0.0;
    };
    let f = phase_angle_deg.clamp(0.0, 180.0);
    let phase_log = -0.008_68 * f - 2.2e-9 * f.powi(4);
    let distance_factor = (MOON_MEAN_DISTANCE_M / distance_m).powi(2);
    fade * 10f64.powf(banded_log10(&MOON_BANDS, h_eval) + phase_log) * distance_factor
}

/// The sky-condition divisor for a cloud-cover fraction in `[0, 1]`: `10^(c²)`.
///
/// # Errors
/// [`EnvironmentError::InvalidSetting`] for a fraction outside `[0, 1]` or NaN.
pub fn sky_condition_divisor(cloud_cover_fraction: f64) -> Result<f64, EnvironmentError> {
    if !(0.0..=1.0).contains(&cloud_cover_fraction) {
        return Err(EnvironmentError::InvalidSetting(format!(
            "cloud cover {cloud_cover_fraction} is outside [0, 1]"
        )));
    }
    Ok(10f64.powf(cloud_cover_fraction * cloud_cover_fraction))
}

/// Natural illuminance at the ground, lux.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Illuminance {
    /// From the sun (direct and skylight).
    pub sun_lux: f64,
    /// From the moon.
    pub moon_lux: f64,
    /// Night-sky background (stars, airglow).
    pub sky_lux: f64,
    /// Sum of the three.
    pub total_lux: f64,
}

/// Natural illuminance from the ephemeris and the cloud cover fraction.
///
/// # Errors
/// [`EnvironmentError::InvalidSetting`] for a cloud cover outside `[0, 1]`.
pub fn natural_illuminance(
    ephemeris: &crate::Ephemeris,
    cloud_cover_fraction: f64,
) -> Result<Illuminance, EnvironmentError> {
    let divisor = sky_condition_divisor(cloud_cover_fraction)?;
    let sun = sun_illuminance_lux(ephemeris.sun.altitude_deg) / divisor;
    let moon = moon_illuminance_lux(
        ephemeris.moon.altitude_deg,
        ephemeris.moon_phase_angle_deg,
        ephemeris.moon.distance_m,
    ) / divisor;
    let sky = NIGHT_SKY_LUX / divisor;
    Ok(Illuminance {
        sun_lux: sun,
        moon_lux: moon,
        sky_lux: sky,
        total_lux: sun + moon + sky,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn published_reference_points() {
        let zenith = sun_illuminance_lux(90.0);
        assert!((1.1e5..1.4e5).contains(&zenith), "zenith {zenith}");
        let sunrise = sun_illuminance_lux(-0.833);
        assert!((400.0..750.0).contains(&sunrise), "sunrise {sunrise}");
        let civil = sun_illuminance_lux(-6.0);
        assert!((3.2..3.6).contains(&civil), "civil {civil}");
        let full_zenith = moon_illuminance_lux(90.0, 0.0, MOON_MEAN_DISTANCE_M);
        assert!(
            (0.25..0.4).contains(&full_zenith),
            "full moon {full_zenith}"
        );
        // A full moon high (70°) near perigee (357 000 km), phase angle 2°.
        let perigee = moon_illuminance_lux(70.0, 2.0, 357_000_000.0);
        assert!(
            (0.25..0.4).contains(&perigee),
            "perigee full moon {perigee}"
        );
        let night = sun_illuminance_lux(-30.0) + NIGHT_SKY_LUX;
        assert!((0.0019..0.0022).contains(&night), "moonless {night}");
        // Nautical twilight end about 0.008 lux, astronomical below 0.001 (Bond and Henderson).
        let nautical = sun_illuminance_lux(-12.0);
        assert!((0.005..0.012).contains(&nautical), "nautical {nautical}");
        assert!(sun_illuminance_lux(-18.0) < 0.001);
    }

    #[test]
    fn phase_law_and_cloud_divisor() {
        let full = moon_illuminance_lux(45.0, 0.0, MOON_MEAN_DISTANCE_M);
        let quarter = moon_illuminance_lux(45.0, 90.0, MOON_MEAN_DISTANCE_M);
        // 10^(-0.00868*90 - 2.2e-9*90^4) = 10^-0.9255 = 0.1187.
        assert!((quarter / full - 0.1187).abs() < 0.0005);
        assert_eq!(moon_illuminance_lux(-2.0, 0.0, MOON_MEAN_DISTANCE_M), 0.0);
        assert_eq!(sky_condition_divisor(0.0).unwrap(), 1.0);
        assert!((sky_condition_divisor(1.0).unwrap() - 10.0).abs() < 1e-12);
        assert!(sky_condition_divisor(1.5).is_err());
        assert!(sky_condition_divisor(f64::NAN).is_err());
    }

    proptest! {
        #[test]
        fn sun_illuminance_is_continuous_and_rising(h in -89.0f64..89.9) {
            let a = sun_illuminance_lux(h);
            let b = sun_illuminance_lux(h + 0.001);
            prop_assert!(b > a, "{h}: {a} -> {b}");
            // No jump: the steepest band rises 0.47 decade per degree, 0.11 % per millidegree.
            prop_assert!(b / a < 1.0015, "{h}: {a} -> {b}");
        }

        #[test]
        fn moon_illuminance_is_continuous_and_bounded(h in -1.5f64..89.9, f in 0.0f64..180.0) {
            let a = moon_illuminance_lux(h, f, MOON_MEAN_DISTANCE_M);
            let b = moon_illuminance_lux(h + 0.001, f, MOON_MEAN_DISTANCE_M);
            prop_assert!((0.0..0.4).contains(&a));
            prop_assert!((b - a).abs() <= 0.001 * b.max(1e-6) + 5e-6, "{h}: {a} -> {b}");
        }
    }
}
