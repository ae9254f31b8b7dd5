//! Geocentric apparent position of the moon.
//!
//! Algorithm: J. Meeus, *Astronomical Algorithms* (2nd ed., 1998), chapter 47:
//! the truncated ELP-2000/82 theory of M. Chapront-Touzé and J. Chapront
//! (*A&A* 124, 50, 1983) — mean arguments L′, D, M, M′, F (47.1–47.5), the
//! eccentricity factor E, the 60 periodic terms of Table 47.A for longitude and
//! distance and the 60 of Table 47.B for latitude, and the additive terms for
//! Venus (A1), Jupiter (A2) and the flattening of the Earth (L′ − F, A3).
//! Nutation in longitude gives the apparent longitude; the true obliquity turns
//! it to right ascension and declination. Limits: about 10″ in longitude and 4″
//! in latitude against the full ELP-2000/82 (Meeus), about 0.003 degree;
//! light-time (about 1.3 s, 0.7″) is left out.

use crate::nutation::Nutation;
use crate::sun::{ecliptic_to_equatorial, ApparentPosition};

/// Multipliers of D, M, M′, F; Σl coefficient (1e-6 degree); Σr coefficient (metres).
type LongitudeDistanceTerm = ([i8; 4], f64, f64);
/// Multipliers of D, M, M′, F; Σb coefficient (1e-6 degree).
type LatitudeTerm = ([i8; 4], f64);

const LONGITUDE_DISTANCE: &[LongitudeDistanceTerm] = &[
    ([0, 0, 1, 0], 6_288_774.0, -20_905_355.0),
    ([2, 0, -1, 0], 1_274_027.0, -3_699_111.0),
    ([2, 0, 0, 0], 658_314.0, -2_955_968.0),
    ([0, 0, 2, 0], 213_618.0, -569_925.0),
    ([0, 1, 0, 0], -185_116.0, 48888.0),
    ([0, 0, 0, 2], -114_332.0, -3149.0),
    ([2, 0, -2, 0], 58793.0, 246_158.0),
    ([2, -1, -1, 0], 57066.0, -152_138.0),
    ([2, 0, 1, 0], 53322.0, -170_733.0),
    ([2, -1, 0, 0], 45758.0, -204_586.0),
    ([0, 1, -1, 0], -40923.0, -129_620.0),
    ([1, 0, 0, 0], -34720.0, 108_743.0),
    ([0, 1, 1, 0], -30383.0, 104_755.0),
    ([2, 0, 0, -2], 15327.0, 10321.0),
    ([0, 0, 1, 2], -12528.0, 0.0),
    ([0, 0, 1, -2], 10980.0, 79661.0),
    ([4, 0, -1, 0], 10675.0, -34782.0),
    ([0, 0, 3, 0], 10034.0, -23210.0),
    ([4, 0, -2, 0], 8548.0, -21636.0),
    ([2, 1, -1, 0], -7888.0, 24208.0),
    ([2, 1, 0, 0], -6766.0, 30824.0),
    ([1, 0, -1, 0], -5163.0, -8379.0),
    ([1, 1, 0, 0], 4987.0, -16675.0),
    ([2, -1, 1, 0], 4036.0, -12831.0),
    ([2, 0, 2, 0], 3994.0, -10445.0),
    ([4, 0, 0, 0], 3861.0, -11650.0),
    ([2, 0, -3, 0], 3665.0, 14403.0),
    ([0, 1, -2, 0], -2689.0, -7003.0),
    ([2, 0, -1, 2], -2602.0, 0.0),
    ([2, -1, -2, 0], 2390.0, 10056.0),
    ([1, 0, 1, 0], -2348.0, 6322.0),
    ([2, -2, 0, 0], 2236.0, -9884.0),
    ([0, 1, 2, 0], -2120.0, 5751.0),
    ([0, 2, 0, 0], -2069.0, 0.0),
    ([2, -2, -1, 0], 2048.0, -4950.0),
    ([2, 0, 1, -2], -1773.0, 4130.0),
    ([2, 0, 0, 2], -1595.0, 0.0),
    ([4, -1, -1, 0], 1215.0, -3958.0),
    ([0, 0, 2, 2], -1110.0, 0.0),
    ([3, 0, -1, 0], -892.0, 3258.0),
    ([2, 1, 1, 0], -810.0, 2616.0),
    ([4, -1, -2, 0], 759.0, -1897.0),
    ([0, 2, -1, 0], -713.0, -2117.0),
    ([2, 2, -1, 0], -700.0, 2354.0),
    ([2, 1, -2, 0], 691.0, 0.0),
    ([2, -1, 0, -2], 596.0, 0.0),
    ([4, 0, 1, 0], 549.0, -1423.0),
    ([0, 0, 4, 0], 537.0, -1117.0),
    ([4, -1, 0, 0], 520.0, -1571.0),
    ([1, 0, -2, 0], -487.0, -1739.0),
    ([2, 1, 0, -2], -399.0, 0.0),
    ([0, 0, 2, -2], -381.0, -4421.0),
    ([1, 1, 1, 0], 351.0, 0.0),
    ([3, 0, -2, 0], -340.0, 0.0),
    ([4, 0, -3, 0], 330.0, 0.0),
    ([2, -1, 2, 0], 327.0, 0.0),
    ([0, 2, 1, 0], -323.0, 1165.0),
    ([1, 1, -1, 0], 299.0, 0.0),
    ([2, 0, 3, 0], 294.0, 0.0),
    ([2, 0, -1, -2], 0.0, 8752.0),
];

const LATITUDE: &[LatitudeTerm] = &[
    ([0, 0, 0, 1], 5_128_122.0),
    ([0, 0, 1, 1], 280_602.0),
    ([0, 0, 1, -1], 277_693.0),
    ([2, 0, 0, -1], 173_237.0),
    ([2, 0, -1, 1], 55413.0),
    ([2, 0, -1, -1], 46271.0),
    ([2, 0, 0, 1], 32573.0),
    ([0, 0, 2, 1], 17198.0),
    ([2, 0, 1, -1], 9266.0),
    ([0, 0, 2, -1], 8822.0),
    ([2, -1, 0, -1], 8216.0),
    ([2, 0, -2, -1], 4324.0),
    ([2, 0, 1, 1], 4200.0),
    ([2, 1, 0, -1], -3359.0),
    ([2, -1, -1, 1], 2463.0),
    ([2, -1, 0, 1], 2211.0),
    ([2, -1, -1, -1], 2065.0),
    ([0, 1, -1, -1], -1870.0),
    ([4, 0, -1, -1], 1828.0),
    ([0, 1, 0, 1], -1794.0),
    ([0, 0, 0, 3], -1749.0),
    ([0, 1, -1, 1], -1565.0),
    ([1, 0, 0, 1], -1491.0),
    ([0, 1, 1, 1], -1475.0),
    ([0, 1, 1, -1], -1410.0),
    ([0, 1, 0, -1], -1344.0),
    ([1, 0, 0, -1], -1335.0),
    ([0, 0, 3, 1], 1107.0),
    ([4, 0, 0, -1], 1021.0),
    ([4, 0, -1, 1], 833.0),
    ([0, 0, 1, -3], 777.0),
    ([4, 0, -2, 1], 671.0),
    ([2, 0, 0, -3], 607.0),
    ([2, 0, 2, -1], 596.0),
    ([2, -1, 1, -1], 491.0),
    ([2, 0, -2, 1], -451.0),
    ([0, 0, 3, -1], 439.0),
    ([2, 0, 2, 1], 422.0),
    ([2, 0, -3, -1], 421.0),
    ([2, 1, -1, 1], -366.0),
    ([2, 1, 0, 1], -351.0),
    ([4, 0, 0, 1], 331.0),
    ([2, -1, 1, 1], 315.0),
    ([2, -2, 0, -1], 302.0),
    ([0, 0, 1, 3], -283.0),
    ([2, 1, 1, -1], -229.0),
    ([1, 1, 0, -1], 223.0),
    ([1, 1, 0, 1], 223.0),
    ([0, 1, -2, -1], -220.0),
    ([2, 1, -1, -1], -220.0),
    ([1, 0, 1, 1], -185.0),
    ([2, -1, -2, -1], 181.0),
    ([0, 1, 2, 1], -177.0),
    ([4, 0, -2, -1], 176.0),
    ([4, -1, -1, -1], 166.0),
    ([1, 0, 1, -1], -164.0),
    ([4, 0, 1, -1], 132.0),
    ([1, 0, -1, -1], -119.0),
    ([4, -1, 0, -1], 115.0),
    ([2, -2, 0, 1], 107.0),
];

/// `a + b x + c x² + d x³ + e x⁴`.
fn quartic(a: f64, b: f64, c: f64, d: f64, e: f64, x: f64) -> f64 {
    a + x * (b + x * (c + x * (d + x * e)))
}

/// Geometric (mean equinox of date) ecliptic longitude and latitude (degrees)
/// and distance (metres) of the moon at `t` Julian centuries of TT from J2000.0.
pub fn moon_geometric(t: f64) -> (f64, f64, f64) {
    let lp = quartic(
        218.316_447_7,
        481_267.881_234_21,
        -0.001_578_6,
        1.0 / 538_841.0,
        -1.0 / 65_194_000.0,
        t,
    );
    let d = quartic(
        297.850_192_1,
        445_267.111_403_4,
        -0.001_881_9,
        1.0 / 545_868.0,
        -1.0 / 113_065_000.0,
        t,
    );
    let m = quartic(
        357.529_109_2,
        35_999.050_290_9,
        -0.000_153_6,
        1.0 / 24_490_000.0,
        0.0,
        t,
    );
    let mp = quartic(
        134.963_396_4,
        477_198.867_505_5,
        0.008_741_4,
        1.0 / 69_699.0,
        -1.0 / 14_712_000.0,
        t,
    );
    let f = quartic(
        93.272_095_0,
        483_202.017_523_3,
        -0.003_653_9,
        -1.0 / 3_526_000.0,
        1.0 / 863_310_000.0,
        t,
    );
    let a1 = 119.75 + 131.849 * t;
    let a2 = 53.09 + 479_264.290 * t;
    let a3 = 313.45 + 481_266.484 * t;
    let e = 1.0 - t * (0.002_516 + t * 0.000_007_4);
    let args = [d, m, mp, f];
    let argument = |mult: &[i8; 4]| -> f64 {
        mult.iter()
            .zip(args.iter())
            .map(|(&k, &x)| f64::from(k) * x)
            .sum::<f64>()
            .rem_euclid(360.0)
            .to_radians()
    };
    let e_factor = |m_mult: i8| match m_mult.unsigned_abs() {
        1 => e,
        2 => e * e,
        _ => 1.0,
    };
    let mut sum_l = 0.0;
    let mut sum_r = 0.0;
    for (mult, cl, cr) in LONGITUDE_DISTANCE {
        let arg = argument(mult);
        let ef = e_factor(mult[1]);
        sum_l += cl * ef * arg.sin();
        sum_r += cr * ef * arg.cos();
    }
    let mut sum_b = 0.0;
    for (mult, cb) in LATITUDE {
        sum_b += cb * e_factor(mult[1]) * argument(mult).sin();
    }
    let rad = f64::to_radians;
    sum_l += 3958.0 * rad(a1).sin() + 1962.0 * rad(lp - f).sin() + 318.0 * rad(a2).sin();
    sum_b += -2235.0 * rad(lp).sin()
        + 382.0 * rad(a3).sin()
        + 175.0 * rad(a1 - f).sin()
        + 175.0 * rad(a1 + f).sin()
        + 127.0 * rad(lp - mp).sin()
        - 115.0 * rad(lp + mp).sin();
    let longitude = (lp + sum_l / 1e6).rem_euclid(360.0);
    let latitude = sum_b / 1e6;
    let distance_m = 385_000_560.0 + sum_r;
    (longitude, latitude, distance_m)
}

/// Apparent geocentric position of the moon at `t` Julian centuries of TT from
/// J2000.0, with the nutation for that instant.
pub fn moon_apparent(t: f64, nutation: &Nutation) -> ApparentPosition {
    let (lon, lat, distance_m) = moon_geometric(t);
    let lambda = (lon + nutation.longitude_deg).rem_euclid(360.0);
    let (ra, dec) = ecliptic_to_equatorial(lambda, lat, nutation.true_obliquity_deg());
    ApparentPosition {
        longitude_deg: lambda,
        latitude_deg: lat,
        distance_m,
        right_ascension_deg: ra,
        declination_deg: dec,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::nutation::nutation;

    #[test]
    fn meeus_example_47a() {
        // 1992 April 12, 0h TD (JDE 2448724.5): λ = 133.162655, β = -3.229126,
        // Δ = 368409.7 km, apparent λ = 133.167265, α = 134.688470, δ = 13.768368.
        let t = (2_448_724.5 - 2_451_545.0) / 36_525.0;
        let (lon, lat, dist) = moon_geometric(t);
        assert!((lon - 133.162_655).abs() < 1e-6, "{lon}");
        assert!((lat - -3.229_126).abs() < 1e-6, "{lat}");
        assert!((dist - 368_409_700.0).abs() < 100.0, "{dist}");
        let moon = moon_apparent(t, &nutation(t));
        assert!((moon.longitude_deg - 133.167_265).abs() < 2e-5, "{moon:?}");
        assert!(
            (moon.right_ascension_deg - 134.688_470).abs() < 5e-5,
            "{moon:?}"
        );
        assert!((moon.declination_deg - 13.768_368).abs() < 5e-5, "{moon:?}");
    }
}
