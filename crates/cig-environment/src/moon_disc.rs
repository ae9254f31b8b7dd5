//! The moon's disc as seen by an observer: its angular radius, the position angle of its bright
//! limb, its illuminated fraction, and the surface brightness that a renderer paints on it.
//!
//! Algorithm: angular radius `asin(R / d)` for the topocentric distance d and the mean radius
//! R = 1737.4 km. Position angle of the bright limb, J. Meeus, *Astronomical Algorithms* (2nd
//! ed., 1998), equation 48.5: `χ = atan2(cos δ0 sin(α0 − α), sin δ0 cos δ − cos δ0 sin δ
//! cos(α0 − α))`, with (α0, δ0) the sun's and (α, δ) the moon's apparent right ascension and
//! declination, measured from the north point of the disc through east. Illuminated fraction
//! `k = (1 + cos i) / 2` (48.1) with the phase angle i. Surface brightness: the lunar surface is
//! taken as a Lommel–Seeliger scatterer, `L ∝ cos i / (cos i + cos e)` (i, e the angles of
//! incidence and emergence; the law of dark, low-albedo regoliths, which makes the full moon the
//! flat, limb-bright disc it is), scaled so that the disc's total illuminance follows the
//! moon's observed phase law, the one [`crate::illuminance`] uses, `E(α) = E0 10^(−0.00868 α −
//! 2.2e-9 α⁴)`, with E0 the full moon's exo-atmospheric illuminance at mean distance (visual
//! magnitude −12.74, Allen's *Astrophysical Quantities*). The disc-integrated Lommel–Seeliger
//! phase function is `Φ(α) = 1 − sin(α/2) tan(α/2) ln(cot(α/4))`, so the luminance of a surface
//! element lit and seen head-on at phase α is `E(α) / (Ω Φ(α))` times `2 cos i / (cos i + cos e)`
//! (1 everywhere on a full moon), with Ω the disc's solid angle; E and Ω both fall as 1/d², so
//! the luminance does not depend on the distance. Earthshine: the dark side shows the full
//! Earth's light at about 2.5e-4 of the full moon's surface brightness (a crescent's ashen
//! light, about magnitude 12.5 per square arcsecond), scaled by the Earth's illuminated fraction
//! seen from the moon, `(1 − cos α) / 2`.
//!
//! Limits: the moon is a smooth sphere of uniform albedo (no maria, libration or roughness),
//! so the terminator is sharp and the opposition surge is carried only by the phase law; the
//! position angle is geocentric (Meeus): the topocentric one differs by the parallax, up to
//! about a degree.

use glam::DVec3;

use crate::ephemeris::MOON_RADIUS_M;
use crate::stars::illuminance_lux_from_magnitude;

/// Visual magnitude of the full moon at its mean distance (Allen).
pub const FULL_MOON_V_MAG: f64 = -12.74;
/// Mean distance of the moon from the centre of the Earth, metres.
pub const MOON_MEAN_DISTANCE_M: f64 = 384_400_000.0;
/// Earthshine on the dark side, as a fraction of the full moon's surface luminance, when the
/// Earth seen from the moon is full (new moon).
pub const EARTHSHINE_FRACTION: f64 = 2.5e-4;

/// Angular radius of the moon seen from `distance_m`, degrees.
pub fn moon_angular_radius_deg(distance_m: f64) -> f64 {
    if distance_m.is_nan() || distance_m <= MOON_RADIUS_M {
        return 90.0;
    }
    (MOON_RADIUS_M / distance_m).asin().to_degrees()
}

/// Position angle of the moon's bright limb, degrees in `[0, 360)`, from the north point of the
/// disc through east, given the sun's (α0, δ0) and the moon's (α, δ) apparent equatorial
/// coordinates in degrees (Meeus 48.5).
pub fn bright_limb_position_angle_deg(
    sun_ra_deg: f64,
    sun_dec_deg: f64,
    moon_ra_deg: f64,
    moon_dec_deg: f64,
) -> f64 {
    let (s0, c0) = sun_dec_deg.to_radians().sin_cos();
    let (s, c) = moon_dec_deg.to_radians().sin_cos();
    let da = (sun_ra_deg - moon_ra_deg).to_radians();
    (c0 * da.sin())
        .atan2(s0 * c - c0 * s * da.cos())
        .to_degrees()
        .rem_euclid(360.0)
}

/// Position angle (degrees from north through east) of the direction from `centre` toward
/// `toward`, both unit vectors in a frame whose z axis is the celestial pole (e.g. ECEF).
pub fn position_angle_deg(centre: DVec3, toward: DVec3) -> f64 {
    let east = DVec3::Z.cross(centre).normalize_or_zero();
    let north = centre.cross(east);
    let d = toward - centre * toward.dot(centre);
    d.dot(east)
        .atan2(d.dot(north))
        .to_degrees()
        .rem_euclid(360.0)
}

/// Illuminated fraction of the disc for a phase angle in degrees (Meeus 48.1).
pub fn illuminated_fraction(phase_angle_deg: f64) -> f64 {
    ((1.0 + phase_angle_deg.to_radians().cos()) / 2.0).clamp(0.0, 1.0)
}

/// The moon's phase law: its illuminance at phase angle `phase_angle_deg` over the full moon's.
pub fn phase_law(phase_angle_deg: f64) -> f64 {
    let a = phase_angle_deg.clamp(0.0, 180.0);
    10f64.powf(-0.008_68 * a - 2.2e-9 * a.powi(4))
}

/// Disc-integrated Lommel–Seeliger phase function, 1 at full, 0 at new.
pub fn lommel_seeliger_phase_function(phase_angle_deg: f64) -> f64 {
    let a = phase_angle_deg.clamp(0.0, 180.0).to_radians();
    if a < 1e-9 {
        return 1.0;
    }
    if a > std::f64::consts::PI - 1e-9 {
        return 0.0;
    }
    let cot_quarter = 1.0 / (a / 4.0).tan();
    (1.0 - (a / 2.0).sin() * (a / 2.0).tan() * cot_quarter.ln()).max(0.0)
}

/// Exo-atmospheric illuminance of the full moon at its mean distance, lux.
pub fn full_moon_illuminance_lux() -> f64 {
    illuminance_lux_from_magnitude(FULL_MOON_V_MAG)
}

/// Solid angle of the moon's disc at its mean distance, steradians.
pub fn mean_disc_solid_angle_sr() -> f64 {
    let r = (MOON_RADIUS_M / MOON_MEAN_DISTANCE_M).asin();
    2.0 * std::f64::consts::PI * (1.0 - r.cos())
}

/// Luminance (cd/m²) of a surface element of the moon lit and seen head-on at phase angle
/// `phase_angle_deg`, the scale of the Lommel–Seeliger law `2 cos i / (cos i + cos e)`
/// (outside the atmosphere). About 5000 cd/m² at full moon.
pub fn moon_surface_luminance_cd_per_m2(phase_angle_deg: f64) -> f64 {
    let phi = lommel_seeliger_phase_function(phase_angle_deg).max(1e-6);
    full_moon_illuminance_lux() * phase_law(phase_angle_deg) / (mean_disc_solid_angle_sr() * phi)
}

/// Luminance of the earthshine on the moon's dark side, cd/m², at phase angle `phase_angle_deg`.
pub fn earthshine_luminance_cd_per_m2(phase_angle_deg: f64) -> f64 {
    let earth_lit = (1.0 - phase_angle_deg.to_radians().cos()) / 2.0;
    moon_surface_luminance_cd_per_m2(0.0) * EARTHSHINE_FRACTION * earth_lit
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ephemeris::geocentric_apparent;
    use crate::time::UtcTime;
    use proptest::prelude::*;

    #[test]
    fn meeus_example_48a_bright_limb_and_illuminated_fraction() {
        // 1992 April 12, 0h TD: sun α0 20.6579°, δ0 +8.6964°; moon α 134.6885°, δ +13.7684°;
        // χ = 285.0°, k = 0.6786 (i = 69.0756°).
        let chi = bright_limb_position_angle_deg(20.6579, 8.6964, 134.6885, 13.7684);
        assert!((chi - 285.0).abs() < 0.05, "{chi}");
        assert!((illuminated_fraction(69.0756) - 0.6786).abs() < 1e-4);
        // The same from this crate's ephemeris at that instant (TD - UT = 59 s in 1992).
        let time = UtcTime::from_julian_date(2_448_724.5 - 59.0 / 86_400.0).unwrap();
        let (sun, moon) = geocentric_apparent(time);
        let chi = bright_limb_position_angle_deg(
            sun.right_ascension_deg,
            sun.declination_deg,
            moon.right_ascension_deg,
            moon.declination_deg,
        );
        assert!((chi - 285.0).abs() < 0.1, "{chi}");
        let k = illuminated_fraction(crate::ephemeris::geocentric_moon_phase_angle_deg(time));
        assert!((k - 0.6786).abs() < 0.001, "{k}");
    }

    #[test]
    fn position_angle_from_vectors_agrees_with_meeus_48_5() {
        let v = |ra: f64, dec: f64| {
            let (sa, ca) = ra.to_radians().sin_cos();
            let (sd, cd) = dec.to_radians().sin_cos();
            DVec3::new(cd * ca, cd * sa, sd)
        };
        for (s, m) in [
            ((20.6579, 8.6964), (134.6885, 13.7684)),
            ((100.0, 23.0), (60.0, 10.0)),
            ((300.0, -20.0), (330.0, -25.0)),
        ] {
            let chi = bright_limb_position_angle_deg(s.0, s.1, m.0, m.1);
            let pa = position_angle_deg(v(m.0, m.1), v(s.0, s.1));
            let diff = (chi - pa + 540.0).rem_euclid(360.0) - 180.0;
            assert!(diff.abs() < 1e-9, "{chi} {pa}");
        }
    }

    #[test]
    fn angular_radius_is_about_a_quarter_degree() {
        // Mean distance: 15.54'; perigee 356 500 km: 16.75'.
        assert!((moon_angular_radius_deg(MOON_MEAN_DISTANCE_M) * 60.0 - 15.54).abs() < 0.01);
        assert!((moon_angular_radius_deg(356_500_000.0) * 60.0 - 16.75).abs() < 0.01);
        assert_eq!(moon_angular_radius_deg(f64::NAN), 90.0);
    }

    #[test]
    fn lommel_seeliger_phase_function_is_the_integral_over_the_disc() {
        // Numerical integral over the disc of 2 cos i / (cos i + cos e), for a sphere seen
        // along -z and lit from a direction at phase angle a, over the full moon's.
        let integral = |a_deg: f64| {
            let a = f64::to_radians(a_deg);
            let sun = DVec3::new(a.sin(), 0.0, a.cos());
            let n = 400;
            let mut sum = 0.0;
            for j in 0..n {
                for i in 0..n {
                    let x = (f64::from(i) + 0.5) / f64::from(n) * 2.0 - 1.0;
                    let y = (f64::from(j) + 0.5) / f64::from(n) * 2.0 - 1.0;
                    let r2 = x * x + y * y;
                    if r2 >= 1.0 {
                        continue;
                    }
                    let normal = DVec3::new(x, y, (1.0 - r2).sqrt());
                    let cos_i = normal.dot(sun);
                    if cos_i > 0.0 {
                        sum += 2.0 * cos_i / (cos_i + normal.z);
                    }
                }
            }
            sum * 4.0 / f64::from(n * n) / std::f64::consts::PI
        };
        for a in [0.0, 30.0, 60.0, 90.0, 120.0, 150.0] {
            let numeric = integral(a);
            let closed = lommel_seeliger_phase_function(a);
            assert!(
                (numeric - closed).abs() < 0.01,
                "{a}: {numeric} vs {closed}"
            );
        }
    }

    #[test]
    fn the_full_moon_is_a_few_thousand_candela_per_square_metre() {
        // Published: 2500-5200 cd/m² (e.g. Allen); exo-atmospheric full moon 0.32 lux.
        let full = moon_surface_luminance_cd_per_m2(0.0);
        assert!((3000.0..6000.0).contains(&full), "{full}");
        assert!((full_moon_illuminance_lux() - 0.316).abs() < 0.01);
        // A quarter moon's lit surface is dimmer than the full moon's (no opposition surge).
        let quarter = moon_surface_luminance_cd_per_m2(90.0);
        assert!(quarter < 0.5 * full && quarter > 0.1 * full, "{quarter}");
        // Earthshine: none at full moon, about 1 cd/m² at new moon.
        assert!(earthshine_luminance_cd_per_m2(0.0) < 1e-9);
        let ashen = earthshine_luminance_cd_per_m2(180.0);
        assert!((0.5..3.0).contains(&ashen), "{ashen}");
    }

    proptest! {
        #[test]
        fn disc_total_follows_the_phase_law(a in 0.0f64..170.0) {
            // Luminance times solid angle times Φ is the phase law's illuminance.
            let e = moon_surface_luminance_cd_per_m2(a) * mean_disc_solid_angle_sr()
                * lommel_seeliger_phase_function(a);
            let expected = full_moon_illuminance_lux() * phase_law(a);
            prop_assert!((e - expected).abs() <= 1e-9 * expected.max(1e-12));
            prop_assert!((0.0..=1.0).contains(&illuminated_fraction(a)));
        }
    }
}
