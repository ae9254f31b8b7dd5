//! The naked-eye stars: a catalogue of the 904 stars of visual magnitude 4.5 and brighter, their
//! directions in the Earth-fixed (ECEF) frame at any instant, their illuminance and colour, and
//! the eye's threshold for seeing a point source against a bright sky.
//!
//! Algorithm: each star's J2000 direction (ICRS, epoch J2000) is moved by its proper motion
//! (linearly, along the local east and north of the sphere) to the date; the direction is
//! precessed from J2000 to the mean equator and equinox of date with the rigorous rotation
//! `R3(−z) R2(θ) R3(−ζ)` of J. Meeus, *Astronomical Algorithms* (2nd ed., 1998), chapter 21
//! (equations 21.3 for ζ, z, θ from J2000.0), turned to the true equator of date by the nutation
//! rotation `R1(−ε) R3(−Δψ) R1(ε0)` (Meeus chapter 23, nutation from [`crate::nutation`]), and
//! turned with the Earth by the Greenwich apparent sidereal time, `R3(GAST)`: the ECEF frame is
//! the true-of-date equatorial frame rotated by GAST about the pole (polar motion, below 0.5″,
//! is ignored). The three rotations are one matrix per instant ([`celestial_to_ecef`]).
//! Illuminance from magnitude: `E = 10^(−0.4 (m + 13.99))` lux (the zero point of
//! visual magnitudes, 2.54e-6 lux at m = 0; Allen's *Astrophysical Quantities*). Colour from
//! B−V through the effective temperature of F. J. Ballesteros (*EPL* 97, 34008, 2012),
//! `T = 4600 K (1 / (0.92 (B−V) + 1.7) + 1 / (0.92 (B−V) + 0.62))`, and the Planckian locus in
//! CIE 1931 xy (Kim et al.'s cubic spline, US patent 7 024 034) turned to linear sRGB of unit
//! luminance. The eye's threshold illuminance for a point source against a background of
//! luminance B is B. E. Schaefer's fit of Hecht's data (*PASP* 102, 212, 1990, eq. 2):
//! `I = c1 (1 + sqrt(c2 B))²` foot-candles for B in nanolamberts, with (c1, c2) =
//! (10^−9.8, 10^−1.9) at night (B < 1500 nL) and (10^−8.35, 10^−5.9) by day.
//!
//! Source of the table (`data/stars.csv`, built by `data/make_stars.py`): the selection, HR
//! numbers and V magnitudes are the Yale Bright Star Catalogue, 5th revised edition (D. Hoffleit
//! and W. H. Warren Jr., 1991; CDS V/50; public domain), stars with V ≤ 4.5; positions, proper
//! motions and B−V are those of the matched star of the Hipparcos new reduction (F. van Leeuwen,
//! 2007; CDS I/311; public domain), moved from its epoch J1991.25 to J2000.0.
//!
//! Limits: annual aberration (up to 20.5″), parallax and light deflection are left out, so
//! directions are good to about 25″ (0.007°); linear proper motion is good to a few arcseconds
//! over 1900–2100 for these stars. Directions are geometric: atmospheric refraction (0.5° at the
//! horizon) is not applied, like the sun and moon directions the renderer uses. Double stars
//! closer than the catalogue resolves are one entry; variable stars keep the catalogue's V.

use std::sync::OnceLock;

use glam::{DMat3, DVec3};

use crate::nutation::{greenwich_apparent_sidereal_time_deg, nutation};
use crate::time::UtcTime;

/// The brightest visual magnitude in the table is −1.46 (Sirius); the faintest is this.
pub const CATALOGUE_LIMIT_V_MAG: f64 = 4.5;

/// One catalogue star.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Star {
    /// Harvard Revised (Bright Star Catalogue) number.
    pub hr: u16,
    /// Right ascension, ICRS (≈ J2000 mean equator and equinox), epoch J2000.0, degrees.
    pub ra_deg: f64,
    /// Declination, ICRS, epoch J2000.0, degrees.
    pub dec_deg: f64,
    /// Proper motion in right ascension times cos(declination), milliarcseconds per year.
    pub pm_ra_cosdec_mas_per_yr: f64,
    /// Proper motion in declination, milliarcseconds per year.
    pub pm_dec_mas_per_yr: f64,
    /// Visual magnitude V.
    pub v_mag: f64,
    /// Colour index B−V (none for a star without a measured one).
    pub b_minus_v: Option<f64>,
}

impl Star {
    /// The star's unit direction in the J2000 (ICRS) frame at `julian_years_since_j2000`
    /// (proper motion applied along the sphere's local east and north, then renormalised).
    pub fn direction_j2000(&self, julian_years_since_j2000: f64) -> DVec3 {
        let (sa, ca) = self.ra_deg.to_radians().sin_cos();
        let (sd, cd) = self.dec_deg.to_radians().sin_cos();
        let p = DVec3::new(cd * ca, cd * sa, sd);
        let east = DVec3::new(-sa, ca, 0.0);
        let north = DVec3::new(-sd * ca, -sd * sa, cd);
        let mas = std::f64::consts::PI / (180.0 * 3_600_000.0);
        let dt = julian_years_since_j2000;
        (p + east * (self.pm_ra_cosdec_mas_per_yr * mas * dt)
            + north * (self.pm_dec_mas_per_yr * mas * dt))
            .normalize()
    }

    /// Illuminance the star gives on a surface facing it, outside the atmosphere, lux.
    pub fn illuminance_lux(&self) -> f64 {
        illuminance_lux_from_magnitude(self.v_mag)
    }
}

/// The catalogue, sorted by HR number (parsed once from the embedded table).
pub fn catalogue() -> &'static [Star] {
    static STARS: OnceLock<Vec<Star>> = OnceLock::new();
    STARS.get_or_init(|| parse_table(include_str!("../data/stars.csv")))
}

/// Parses the table's lines `hr,ra,dec,pm_ra,pm_dec,v,b-v`; lines that do not parse are skipped
/// (the embedded table has none: a test checks the count).
fn parse_table(text: &str) -> Vec<Star> {
    let mut stars = Vec::new();
    for line in text.lines() {
        if line.starts_with('#') || line.trim().is_empty() {
            continue;
        }
        let fields: Vec<&str> = line.split(',').collect();
        let [hr, ra, dec, pm_ra, pm_dec, v, bv] = fields.as_slice() else {
            continue;
        };
        let num = |s: &str| s.trim().parse::<f64>().ok();
        let (Some(hr), Some(ra), Some(dec), Some(pm_ra), Some(pm_dec), Some(v)) = (
            hr.trim().parse::<u16>().ok(),
            num(ra),
            num(dec),
            num(pm_ra),
            num(pm_dec),
            num(v),
        ) else {
            continue;
        };
        stars.push(Star {
            hr,
            ra_deg: ra,
            dec_deg: dec,
            pm_ra_cosdec_mas_per_yr: pm_ra,
            pm_dec_mas_per_yr: pm_dec,
            v_mag: v,
            b_minus_v: num(bv),
        });
    }
    stars
}

/// Illuminance of a point source of visual magnitude `v_mag`, lux: `10^(−0.4 (m + 13.99))`.
pub fn illuminance_lux_from_magnitude(v_mag: f64) -> f64 {
    10f64.powf(-0.4 * (v_mag + 13.99))
}

/// Rotation about the x axis of the frame by `angle` (the frame turns; Meeus's R1).
fn r1(angle_rad: f64) -> DMat3 {
    let (s, c) = angle_rad.sin_cos();
    DMat3::from_cols(
        DVec3::new(1.0, 0.0, 0.0),
        DVec3::new(0.0, c, -s),
        DVec3::new(0.0, s, c),
    )
}

/// Rotation about the y axis of the frame by `angle` (R2).
fn r2(angle_rad: f64) -> DMat3 {
    let (s, c) = angle_rad.sin_cos();
    DMat3::from_cols(
        DVec3::new(c, 0.0, s),
        DVec3::new(0.0, 1.0, 0.0),
        DVec3::new(-s, 0.0, c),
    )
}

/// Rotation about the z axis of the frame by `angle` (R3).
fn r3(angle_rad: f64) -> DMat3 {
    let (s, c) = angle_rad.sin_cos();
    DMat3::from_cols(
        DVec3::new(c, -s, 0.0),
        DVec3::new(s, c, 0.0),
        DVec3::new(0.0, 0.0, 1.0),
    )
}

/// Precession matrix from the J2000 mean equator and equinox to the mean equator and equinox
/// of `t` Julian centuries of TT after J2000.0 (Meeus 21.3 with T = 0, rigorous form 21.4).
pub fn precession_from_j2000(t: f64) -> DMat3 {
    let arcsec = |a: f64| (a / 3600.0).to_radians();
    let zeta = arcsec(t * (2306.2181 + t * (0.301_88 + t * 0.017_998)));
    let z = arcsec(t * (2306.2181 + t * (1.094_68 + t * 0.018_203)));
    let theta = arcsec(t * (2004.3109 - t * (0.426_65 + t * 0.041_833)));
    r3(-z) * r2(theta) * r3(-zeta)
}

/// Matrix taking a J2000 (ICRS) direction to the Earth-fixed (ECEF) frame at `time`:
/// precession, nutation, then the Earth's rotation by the apparent sidereal time.
pub fn celestial_to_ecef(time: UtcTime) -> DMat3 {
    let t = time.tt_days_since_j2000() / 36_525.0;
    let nut = nutation(t);
    let eps0 = nut.mean_obliquity_deg.to_radians();
    let eps = nut.true_obliquity_deg().to_radians();
    let nutation_matrix = r1(-eps) * r3(-nut.longitude_deg.to_radians()) * r1(eps0);
    let gast = greenwich_apparent_sidereal_time_deg(time.days_since_j2000(), &nut);
    r3(gast.to_radians()) * nutation_matrix * precession_from_j2000(t)
}

/// Julian years of TT from J2000.0 to `time` (for proper motion).
pub fn julian_years_since_j2000(time: UtcTime) -> f64 {
    time.tt_days_since_j2000() / 365.25
}

/// Unit direction of `star` in the ECEF frame at `time` (seen from the Earth's centre; stars are
/// far enough for every observer to share it).
pub fn star_direction_ecef(star: &Star, time: UtcTime) -> DVec3 {
    celestial_to_ecef(time) * star.direction_j2000(julian_years_since_j2000(time))
}

/// Right ascension and declination (degrees) of a unit vector.
pub fn ra_dec_deg(v: DVec3) -> (f64, f64) {
    let ra = v.y.atan2(v.x).to_degrees().rem_euclid(360.0);
    let dec = v.z.clamp(-1.0, 1.0).asin().to_degrees();
    (ra, dec)
}

/// Mean right ascension and declination of `star` at `time`, referred to the mean equator and
/// equinox of date (proper motion and precession, no nutation), degrees.
pub fn mean_position_of_date(star: &Star, tt_centuries_since_j2000: f64) -> (f64, f64) {
    let dir = star.direction_j2000(tt_centuries_since_j2000 * 100.0);
    ra_dec_deg(precession_from_j2000(tt_centuries_since_j2000) * dir)
}

/// Effective temperature (kelvin) of a star of colour index `b_minus_v` (Ballesteros 2012),
/// for B−V in `[−0.4, 2.0]` (clamped).
pub fn temperature_k_from_b_minus_v(b_minus_v: f64) -> f64 {
    let bv = if b_minus_v.is_finite() {
        b_minus_v.clamp(-0.4, 2.0)
    } else {
        0.6
    };
    4600.0 * (1.0 / (0.92 * bv + 1.7) + 1.0 / (0.92 * bv + 0.62))
}

/// CIE 1931 chromaticity (x, y) of a black body at `temperature_k` in `[1667, 25000]` K
/// (clamped; Kim et al.'s cubic fit of the Planckian locus).
pub fn planckian_xy(temperature_k: f64) -> (f64, f64) {
    let t = temperature_k.clamp(1667.0, 25_000.0);
    let (t1, t2, t3) = (1e3 / t, 1e6 / (t * t), 1e9 / (t * t * t));
    let x = if t <= 4000.0 {
        -0.266_123_9 * t3 - 0.234_358_9 * t2 + 0.877_695_6 * t1 + 0.179_910
    } else {
        -3.025_846_9 * t3 + 2.107_037_9 * t2 + 0.222_634_7 * t1 + 0.240_390
    };
    let y = if t <= 2222.0 {
        -1.106_381_4 * x * x * x - 1.348_110_20 * x * x + 2.185_558_32 * x - 0.202_196_83
    } else if t <= 4000.0 {
        -0.954_947_6 * x * x * x - 1.374_185_93 * x * x + 2.091_370_15 * x - 0.167_488_67
    } else {
        3.081_758_0 * x * x * x - 5.873_386_70 * x * x + 3.751_129_97 * x - 0.370_014_83
    };
    (x, y)
}

/// Linear sRGB colour of unit luminance (Y = 1) of a star of colour index `b_minus_v`; a star
/// without one is given B−V = 0.6 (the sun's, near white). Channels are clamped at zero.
pub fn star_colour_linear_srgb(b_minus_v: Option<f64>) -> [f64; 3] {
    let (x, y) = planckian_xy(temperature_k_from_b_minus_v(b_minus_v.unwrap_or(0.6)));
    let big_x = x / y;
    let big_z = (1.0 - x - y) / y;
    let r = 3.240_454_2 * big_x - 1.537_138_5 - 0.498_531_4 * big_z;
    let g = -0.969_266_0 * big_x + 1.876_010_8 + 0.041_556_0 * big_z;
    let b = 0.055_643_4 * big_x - 0.204_025_9 + 1.057_225_2 * big_z;
    [r.max(0.0), g.max(0.0), b.max(0.0)]
}

/// cd/m² per nanolambert.
const CD_PER_M2_PER_NANOLAMBERT: f64 = 1e-9 * 1e4 / std::f64::consts::PI;
/// Lux per foot-candle.
const LUX_PER_FOOT_CANDLE: f64 = 10.763_910_4;

/// The faintest point-source illuminance (lux) the dark- or light-adapted eye sees against a
/// background of luminance `background_cd_per_m2` (Schaefer 1990 after Hecht).
pub fn threshold_illuminance_lux(background_cd_per_m2: f64) -> f64 {
    let b_nl = background_cd_per_m2.max(0.0) / CD_PER_M2_PER_NANOLAMBERT;
    let (c1, c2) = if b_nl < 1500.0 {
        (10f64.powf(-9.8), 10f64.powf(-1.9))
    } else {
        (10f64.powf(-8.35), 10f64.powf(-5.9))
    };
    c1 * (1.0 + (c2 * b_nl).sqrt()).powi(2) * LUX_PER_FOOT_CANDLE
}

/// The faintest visual magnitude seen against a background of `background_cd_per_m2`.
pub fn limiting_magnitude(background_cd_per_m2: f64) -> f64 {
    -13.99 - 2.5 * threshold_illuminance_lux(background_cd_per_m2).log10()
}

#[cfg(test)]
mod tests {
    use super::*;
    use cig_geo::{EnuFrame, Geodetic};
    use proptest::prelude::*;

    fn star(hr: u16) -> Star {
        *catalogue()
            .iter()
            .find(|s| s.hr == hr)
            .expect("star in the catalogue")
    }

    #[test]
    fn the_table_holds_every_naked_eye_star_to_magnitude_4_5() {
        let stars = catalogue();
        // BSC5 has 904 entries with V <= 4.5 (all parsed), sorted, each once.
        assert_eq!(stars.len(), 904);
        assert!(stars.windows(2).all(|w| w[0].hr < w[1].hr));
        assert!(stars.iter().all(|s| s.v_mag <= CATALOGUE_LIMIT_V_MAG));
        assert!(stars.iter().filter(|s| s.b_minus_v.is_some()).count() > 890);
        // Sirius, J2000: 06h45m08.917s -16°42'58.02" (Hipparcos), V -1.46, B-V 0.00.
        let sirius = star(2491);
        assert!((sirius.ra_deg - (6.0 + 45.0 / 60.0 + 8.917 / 3600.0) * 15.0).abs() < 2e-4);
        assert!((sirius.dec_deg + 16.0 + 42.0 / 60.0 + 58.02 / 3600.0).abs() < 2e-4);
        assert_eq!(sirius.v_mag, -1.46);
        assert!(sirius.b_minus_v.is_some_and(|bv| bv.abs() < 0.05));
        // Polaris: 02h31m49.09s +89°15'50.8".
        let polaris = star(424);
        assert!((polaris.ra_deg - (2.0 + 31.0 / 60.0 + 49.09 / 3600.0) * 15.0).abs() < 5e-3);
        assert!((polaris.dec_deg - (89.0 + 15.0 / 60.0 + 50.8 / 3600.0)).abs() < 2e-4);
        // Bad lines are skipped, not fatal.
        assert_eq!(
            parse_table("# c\n1,2,3\nx,1,2,3,4,5,6\n7,1,2,3,4,5,\n").len(),
            1
        );
    }

    #[test]
    fn meeus_example_21b_precession_with_proper_motion() {
        // θ Persei, J2000.0: α 2h44m11.986s, δ +49°13'42.48", μα +0.03425 s/yr, μδ -0.0895"/yr.
        // At 2028 November 13.19 TD (JDE 2462088.69): α 2h46m11.331s, δ +49°20'54.54".
        let dec0 = 49.0 + 13.0 / 60.0 + 42.48 / 3600.0;
        let theta_per = Star {
            hr: 0,
            ra_deg: (2.0 + 44.0 / 60.0 + 11.986 / 3600.0) * 15.0,
            dec_deg: dec0,
            pm_ra_cosdec_mas_per_yr: 0.03425 * 15_000.0 * dec0.to_radians().cos(),
            pm_dec_mas_per_yr: -89.5,
            v_mag: 4.1,
            b_minus_v: None,
        };
        let t = (2_462_088.69 - 2_451_545.0) / 36_525.0;
        let (ra, dec) = mean_position_of_date(&theta_per, t);
        let ra_expected = (2.0 + 46.0 / 60.0 + 11.331 / 3600.0) * 15.0;
        let dec_expected = 49.0 + 20.0 / 60.0 + 54.54 / 3600.0;
        // Meeus rounds to 0.001 s and 0.01"; linear proper motion along the sphere differs from
        // his linear motion in α, δ by far less than that over 29 years.
        assert!(
            (ra - ra_expected).abs() * 3600.0 * dec.to_radians().cos() < 0.05,
            "{ra} vs {ra_expected}"
        );
        assert!((dec - dec_expected).abs() * 3600.0 < 0.05, "{dec}");
    }

    #[test]
    fn the_matrix_is_a_rotation_and_keeps_the_pole_within_precession_of_the_ecef_z_axis() {
        let time = UtcTime::from_calendar(2050, 3, 1, 12, 0, 0.0).unwrap();
        let m = celestial_to_ecef(time);
        assert!((m.determinant() - 1.0).abs() < 1e-12);
        assert!((m * m.transpose() - DMat3::IDENTITY).abs_diff_eq(DMat3::ZERO, 1e-12));
        // The J2000 pole is θ = 2004.31" * T = 0.2793° from the mean pole of 2050 March 1
        // (T = 0.5016), and nutation moves the true pole by up to 9.2" (0.0026°).
        let pole = m * DVec3::Z;
        let angle = pole.z.clamp(-1.0, 1.0).acos().to_degrees();
        assert!((angle - 0.2793).abs() < 0.003, "{angle}");
    }

    fn altitude_azimuth_deg(dir_ecef: DVec3, site: Geodetic) -> (f64, f64) {
        let enu = EnuFrame::new(site).ecef_vector_to_enu(dir_ecef);
        let alt = enu.z.asin().to_degrees();
        let az = enu.x.atan2(enu.y).to_degrees().rem_euclid(360.0);
        (alt, az)
    }

    #[test]
    fn polaris_stands_at_the_latitude_within_its_polar_distance_all_night() {
        let polaris = star(424);
        for lat in [-10.0, 20.0, 45.0, 70.0] {
            let site = Geodetic::new(lat, 10.0, 0.0);
            let mut lo = f64::MAX;
            let mut hi = f64::MIN;
            for hour in 0..24 {
                let time = UtcTime::from_calendar(2026, 12, 1, hour, 0, 0.0).unwrap();
                let (alt, az) = altitude_azimuth_deg(star_direction_ecef(&polaris, time), site);
                // Polaris is 0.66° from the pole of 2026 (precession has brought it nearer).
                assert!((alt - lat).abs() < 0.7, "{lat}: {alt}");
                if lat > 0.0 {
                    assert!(!(2.0..358.0).contains(&az), "{az}");
                }
                lo = lo.min(alt);
                hi = hi.max(alt);
            }
            // Over a day it swings about ±0.66° (a geodetic latitude, so +0.0 to 0.2° of
            // difference from the astronomical one is absent: the ellipsoid normal is "up").
            assert!((hi - lo) > 1.2 && (hi - lo) < 1.4, "{lo} {hi}");
        }
    }

    #[test]
    fn sirius_culminates_due_south_at_its_declination_when_its_hour_angle_is_zero() {
        // At 36 N 121 W, Sirius transits when the local apparent sidereal time equals its
        // apparent right ascension: then it stands due south at 90 - 36 + δ.
        let sirius = star(2491);
        let site = Geodetic::new(36.0, -121.0, 0.0);
        let start = UtcTime::from_calendar(2026, 1, 15, 0, 0, 0.0).unwrap();
        // Search the day for the highest altitude (1 s steps near the top).
        let alt_at = |s: f64| {
            altitude_azimuth_deg(star_direction_ecef(&sirius, start.plus_seconds(s)), site)
        };
        let mut best = (f64::MIN, 0.0);
        for minute in 0..1440 {
            let (alt, _) = alt_at(f64::from(minute) * 60.0);
            if alt > best.0 {
                best = (alt, f64::from(minute) * 60.0);
            }
        }
        let (alt, az) = alt_at(best.1);
        let apparent = celestial_to_ecef(start.plus_seconds(best.1))
            * sirius.direction_j2000(julian_years_since_j2000(start));
        let (_, dec_of_date) = ra_dec_deg(apparent);
        assert!((az - 180.0).abs() < 0.3, "{az}");
        // Geocentric latitude differs from geodetic: use the ellipsoid normal's declination.
        assert!((alt - (90.0 - 36.0 + dec_of_date)).abs() < 0.02, "{alt}");
        // The transit (local mean time ~ 23:35 local sidereal ...): Sirius's RA of date is
        // about 6h46.3m; LST = GMST + longitude, so the UTC of transit is known to a minute.
        let gmst_deg = crate::nutation::greenwich_mean_sidereal_time_deg(
            start.plus_seconds(best.1).days_since_j2000(),
        );
        let lst = (gmst_deg - 121.0).rem_euclid(360.0);
        let (ra_of_date, _) = ra_dec_deg(
            precession_from_j2000(start.tt_days_since_j2000() / 36_525.0)
                * sirius.direction_j2000(26.0),
        );
        assert!((lst - ra_of_date).abs() < 0.3, "{lst} vs {ra_of_date}");
    }

    #[test]
    fn magnitudes_become_lux_and_the_eye_sees_sixth_magnitude_only_on_a_dark_night() {
        // m = 0 gives 2.54e-6 lux; five magnitudes are a factor of 100.
        assert!((illuminance_lux_from_magnitude(0.0) - 2.54e-6).abs() < 0.01e-6);
        let ratio = illuminance_lux_from_magnitude(1.0) / illuminance_lux_from_magnitude(6.0);
        assert!((ratio - 100.0).abs() < 1e-9);
        // A dark sky (21.8 mag/arcsec², about 1.7e-4 cd/m²): about magnitude 6.5 (Schaefer).
        let dark = limiting_magnitude(1.7e-4);
        assert!((6.0..7.0).contains(&dark), "{dark}");
        // Daylight blue sky (~5000 cd/m²): only Venus-like sources (brighter than about -3.5).
        let day = limiting_magnitude(5000.0);
        assert!(day < -3.0, "{day}");
        // Civil twilight (~30 cd/m²): the first-magnitude stars.
        let twilight = limiting_magnitude(30.0);
        assert!((0.0..2.5).contains(&twilight), "{twilight}");
    }

    #[test]
    fn colours_run_from_blue_white_to_orange_with_b_minus_v() {
        let blue = star_colour_linear_srgb(Some(-0.2));
        let sun = star_colour_linear_srgb(Some(0.65));
        let red = star_colour_linear_srgb(Some(1.85));
        assert!(blue[2] > blue[0], "{blue:?}");
        assert!(red[0] > 2.0 * red[2], "{red:?}");
        // The sun (5770 K) is near white: channels within 25 % of each other.
        assert!(
            sun.iter().all(|c| (c - sun[1]).abs() < 0.25 * sun[1]),
            "{sun:?}"
        );
        // Unit luminance.
        for c in [blue, sun, red] {
            let y = 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2];
            assert!((y - 1.0).abs() < 0.05, "{c:?}");
        }
        // Ballesteros: B-V 0.65 gives about 5800 K.
        assert!((temperature_k_from_b_minus_v(0.65) - 5800.0).abs() < 150.0);
    }

    proptest! {
        #[test]
        fn star_directions_are_unit_vectors_and_rotate_once_a_sidereal_day(
            index in 0usize..904, s in -3.0e9f64..3.0e9,
        ) {
            let star = catalogue()[index];
            let time = UtcTime::from_seconds_since_j2000(s).unwrap();
            let d = star_direction_ecef(&star, time);
            prop_assert!((d.length() - 1.0).abs() < 1e-12);
            // One sidereal day (86164.0905 s) later the star is back within 0.01°.
            let later = star_direction_ecef(&star, time.plus_seconds(86_164.090_5));
            prop_assert!(d.angle_between(later).to_degrees() < 0.01);
            // Declination of date is the angle from the ECEF equator, unchanged by rotation.
            let noon = star_direction_ecef(&star, time.plus_seconds(43_200.0));
            prop_assert!((d.z - noon.z).abs() < 1e-6);
        }
    }
}
