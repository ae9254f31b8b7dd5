//! Topocentric positions of the sun and the moon for an observer on the WGS84
//! ellipsoid, the moon's phase, and atmospheric refraction.
//!
//! Algorithm: the apparent geocentric right ascension, declination and
//! distance of each body ([`crate::sun`], [`crate::moon`]) are turned into an
//! Earth-fixed vector by the Greenwich apparent sidereal time (the body's
//! Earth-fixed longitude is α − GAST); the observer's ECEF position from
//! `cig-geo` is subtracted (this *is* the topocentric parallax correction,
//! exact for any height, equivalent to Meeus chapter 40 and the NREL SPA
//! steps 3.8–3.12), and the difference is rotated to local east-north-up with
//! `cig_geo::EnuFrame`. Altitude is `atan2(up, horizontal)`, azimuth
//! `atan2(east, north)` from true north through east. The moon's phase angle is
//! the topocentric angle sun–moon–observer (Meeus chapter 48 does it
//! geocentrically; [`geocentric_moon_phase_angle_deg`] gives that one), and the
//! illuminated fraction `k = (1 + cos i) / 2` (Meeus 48.1). Refraction: G. G.
//! Sæmundsson's formula (*Sky & Telescope* 72, 70, 1986; Meeus 16.4)
//! `R = 1.02′ / tan(h + 10.3° / (h + 5.11°))` scaled by `(P / 1010 hPa)(283 K / T)`.
//!
//! Limits: "up" is the ellipsoid normal (the deflection of the vertical, up to
//! an arcminute, is ignored); polar motion and diurnal aberration (≤ 0.3″) are
//! left out; UTC is used as UT1. Refraction is a standard-atmosphere mean: near
//! the horizon real refraction varies by several arcminutes with the weather.
//! Below −1° geometric altitude the refraction is tapered linearly to zero at
//! −2°, so the apparent altitude stays continuous and increasing although
//! nothing is seen there.

use cig_geo::{EnuFrame, Geodetic};
use glam::DVec3;

use crate::moon::moon_apparent;
use crate::nutation::{greenwich_apparent_sidereal_time_deg, nutation, Nutation};
use crate::sun::{sun_apparent, ApparentPosition, AU_M};
use crate::time::UtcTime;
use crate::EnvironmentError;

/// Mean radius of the moon, metres (IAU).
pub const MOON_RADIUS_M: f64 = 1_737_400.0;
/// Radius of the sun's photosphere, metres (IAU 2015 nominal).
pub const SUN_RADIUS_M: f64 = 695_700_000.0;
/// Standard pressure of the refraction formula, hPa.
pub const STANDARD_PRESSURE_HPA: f64 = 1010.0;
/// Standard temperature of the refraction formula, degrees Celsius.
pub const STANDARD_TEMPERATURE_C: f64 = 10.0;

/// An observer on or above the WGS84 ellipsoid.
#[derive(Clone, Copy, Debug)]
pub struct Observer {
    geodetic: Geodetic,
    ecef_m: DVec3,
    frame: EnuFrame,
}

impl Observer {
    /// An observer at geodetic latitude and longitude (degrees) and height above
    /// the WGS84 ellipsoid (metres).
    ///
    /// # Errors
    /// [`EnvironmentError::InvalidLocation`] for a latitude outside `[-90, 90]`,
    /// a longitude outside `[-180, 180]`, or a height outside `[-12 000, 100 000]` m
    /// (or any non-finite value).
    pub fn new(lat_deg: f64, lon_deg: f64, alt_m: f64) -> Result<Observer, EnvironmentError> {
        if !(-90.0..=90.0).contains(&lat_deg) {
            return Err(EnvironmentError::InvalidLocation(format!(
                "latitude {lat_deg} is outside [-90, 90] degrees"
            )));
        }
        if !(-180.0..=180.0).contains(&lon_deg) {
            return Err(EnvironmentError::InvalidLocation(format!(
                "longitude {lon_deg} is outside [-180, 180] degrees"
            )));
        }
        if !(-12_000.0..=100_000.0).contains(&alt_m) {
            return Err(EnvironmentError::InvalidLocation(format!(
                "height {alt_m} m is outside [-12000, 100000] m"
            )));
        }
        let geodetic = Geodetic::new(lat_deg, lon_deg, alt_m);
        Ok(Observer {
            geodetic,
            ecef_m: geodetic.to_ecef(),
            frame: EnuFrame::new(geodetic),
        })
    }

    /// The observer's geodetic position.
    pub fn geodetic(&self) -> Geodetic {
        self.geodetic
    }

    /// The observer's local east-north-up frame.
    pub fn enu_frame(&self) -> &EnuFrame {
        &self.frame
    }
}

/// Where a body stands in the observer's sky.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BodyPosition {
    /// Azimuth from true north through east, degrees in `[0, 360)`.
    pub azimuth_deg: f64,
    /// Topocentric geometric altitude of the centre (parallax included, no
    /// refraction), degrees.
    pub altitude_deg: f64,
    /// Altitude with standard refraction (1010 hPa, 10 °C), degrees.
    pub apparent_altitude_deg: f64,
    /// Unit vector from the observer toward the body (geometric), east-north-up.
    pub direction_enu: [f64; 3],
    /// Distance from the observer, metres.
    pub distance_m: f64,
    /// Apparent angular radius seen by the observer, degrees.
    pub semidiameter_deg: f64,
}

/// Sun and moon for one observer and instant.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ephemeris {
    /// The instant.
    pub time: UtcTime,
    /// The sun.
    pub sun: BodyPosition,
    /// The moon.
    pub moon: BodyPosition,
    /// Topocentric phase angle of the moon (angle sun–moon–observer), degrees in
    /// `[0, 180]`: 0 at full moon, 180 at new moon.
    pub moon_phase_angle_deg: f64,
    /// Illuminated fraction of the moon's disc, `[0, 1]`.
    pub moon_illuminated_fraction: f64,
    /// Whether the moon is waxing (its elongation east of the sun is under 180°).
    pub moon_waxing: bool,
}

/// Geocentric inputs shared by everything at one instant.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Geocentric {
    pub(crate) sun: ApparentPosition,
    pub(crate) moon: ApparentPosition,
    pub(crate) gast_deg: f64,
}

impl Geocentric {
    pub(crate) fn at(time: UtcTime) -> Geocentric {
        let t = time.tt_days_since_j2000() / 36_525.0;
        let nut: Nutation = nutation(t);
        Geocentric {
            sun: sun_apparent(t, &nut),
            moon: moon_apparent(t, &nut),
            gast_deg: greenwich_apparent_sidereal_time_deg(time.days_since_j2000(), &nut),
        }
    }

    /// Earth-fixed (ECEF-aligned) position of a body, metres.
    pub(crate) fn earth_fixed_m(&self, body: &ApparentPosition) -> DVec3 {
        let lon = (body.right_ascension_deg - self.gast_deg).to_radians();
        let dec = body.declination_deg.to_radians();
        DVec3::new(dec.cos() * lon.cos(), dec.cos() * lon.sin(), dec.sin()) * body.distance_m
    }
}

/// Atmospheric refraction (degrees) to add to a geometric altitude `altitude_deg`
/// for pressure `pressure_hpa` and temperature `temperature_c` (Sæmundsson,
/// Meeus 16.4 with the pressure-temperature factor). Tapered to zero between −1°
/// and −2°; zero below −2° and for non-finite inputs.
pub fn refraction_deg(altitude_deg: f64, pressure_hpa: f64, temperature_c: f64) -> f64 {
    if !altitude_deg.is_finite() || altitude_deg <= -2.0 || temperature_c <= -273.0 {
        return 0.0;
    }
    let scale = (pressure_hpa / 1010.0) * (283.0 / (273.0 + temperature_c));
    let formula = |h: f64| 1.02 / (h + 10.3 / (h + 5.11)).to_radians().tan() / 60.0;
    let r = if altitude_deg >= -1.0 {
        formula(altitude_deg.min(90.0))
    } else {
        formula(-1.0) * (altitude_deg + 2.0)
    };
    // At 90° the formula gives -0.0000015°; refraction never lifts downward.
    (r * scale).max(0.0)
}

/// Apparent altitude for a geometric altitude, standard atmosphere (1010 hPa, 10 °C).
pub fn apparent_altitude_deg(altitude_deg: f64) -> f64 {
    altitude_deg + refraction_deg(altitude_deg, STANDARD_PRESSURE_HPA, STANDARD_TEMPERATURE_C)
}

/// Azimuth (degrees, `[0, 360)`) and altitude (degrees) of an ENU direction.
fn az_alt(enu: DVec3) -> (f64, f64) {
    let horizontal = enu.x.hypot(enu.y);
    let alt = enu.z.atan2(horizontal).to_degrees();
    let mut az = enu.x.atan2(enu.y).to_degrees().rem_euclid(360.0);
    if az >= 360.0 {
        az = 0.0;
    }
    (az, alt)
}

fn body_position(observer: &Observer, body_ecef_m: DVec3, radius_m: f64) -> BodyPosition {
    let topo = observer
        .frame
        .ecef_vector_to_enu(body_ecef_m - observer.ecef_m);
    let distance_m = topo.length();
    let dir = topo / distance_m;
    let (az, alt) = az_alt(dir);
    BodyPosition {
        azimuth_deg: az,
        altitude_deg: alt,
        apparent_altitude_deg: apparent_altitude_deg(alt),
        direction_enu: dir.to_array(),
        distance_m,
        semidiameter_deg: (radius_m / distance_m).clamp(-1.0, 1.0).asin().to_degrees(),
    }
}

/// The angle at `vertex` between the directions to `a` and `b`, degrees.
fn angle_at_deg(vertex: DVec3, a: DVec3, b: DVec3) -> f64 {
    let u = a - vertex;
    let v = b - vertex;
    u.cross(v).length().atan2(u.dot(v)).to_degrees()
}

/// Topocentric altitude of the moon's centre only (cheaper; for event search).
pub(crate) fn moon_altitude_deg(observer: &Observer, g: &Geocentric) -> (f64, f64) {
    let p = body_position(observer, g.earth_fixed_m(&g.moon), MOON_RADIUS_M);
    (p.altitude_deg, p.semidiameter_deg)
}

/// Topocentric altitude of the sun's centre only (for event search).
pub(crate) fn sun_altitude_deg(observer: &Observer, g: &Geocentric) -> f64 {
    body_position(observer, g.earth_fixed_m(&g.sun), SUN_RADIUS_M).altitude_deg
}

/// Sun and moon positions and the moon's phase for an observer at an instant.
pub fn ephemeris(observer: &Observer, time: UtcTime) -> Ephemeris {
    let g = Geocentric::at(time);
    let sun_ecef = g.earth_fixed_m(&g.sun);
    let moon_ecef = g.earth_fixed_m(&g.moon);
    let sun = body_position(observer, sun_ecef, SUN_RADIUS_M);
    let moon = body_position(observer, moon_ecef, MOON_RADIUS_M);
    let phase = angle_at_deg(moon_ecef, sun_ecef, observer.ecef_m);
    let elongation_east = (g.moon.longitude_deg - g.sun.longitude_deg).rem_euclid(360.0);
    Ephemeris {
        time,
        sun,
        moon,
        moon_phase_angle_deg: phase,
        moon_illuminated_fraction: ((1.0 + phase.to_radians().cos()) / 2.0).clamp(0.0, 1.0),
        moon_waxing: elongation_east < 180.0,
    }
}

/// Geocentric phase angle of the moon (angle sun–moon–centre of the Earth), degrees.
pub fn geocentric_moon_phase_angle_deg(time: UtcTime) -> f64 {
    let g = Geocentric::at(time);
    angle_at_deg(
        g.earth_fixed_m(&g.moon),
        g.earth_fixed_m(&g.sun),
        DVec3::ZERO,
    )
}

/// Apparent geocentric sun and moon (true equator and equinox of date) at an instant.
pub fn geocentric_apparent(time: UtcTime) -> (ApparentPosition, ApparentPosition) {
    let g = Geocentric::at(time);
    (g.sun, g.moon)
}

/// The sun's distance from the Earth's centre in astronomical units at an instant.
pub fn sun_distance_au(time: UtcTime) -> f64 {
    Geocentric::at(time).sun.distance_m / AU_M
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn refraction_matches_meeus_16() {
        // Sæmundsson at the geometric horizon-crossing altitude -0.5667° gives about 34';
        // at 10° about 5.4'; at 45° about 1'.
        let r = refraction_deg(-0.5667, 1010.0, 10.0) * 60.0;
        assert!((r - 34.4).abs() < 0.3, "{r}");
        let r = refraction_deg(10.0, 1010.0, 10.0) * 60.0;
        assert!((r - 5.4).abs() < 0.05, "{r}");
        let r = refraction_deg(45.0, 1010.0, 10.0) * 60.0;
        assert!((r - 1.0).abs() < 0.05, "{r}");
        assert_eq!(refraction_deg(-3.0, 1010.0, 10.0), 0.0);
        assert_eq!(refraction_deg(f64::NAN, 1010.0, 10.0), 0.0);
    }

    #[test]
    fn observer_rejects_bad_places() {
        assert!(Observer::new(90.5, 0.0, 0.0).is_err());
        assert!(Observer::new(f64::NAN, 0.0, 0.0).is_err());
        assert!(Observer::new(0.0, 181.0, 0.0).is_err());
        assert!(Observer::new(0.0, 0.0, f64::INFINITY).is_err());
        assert!(Observer::new(-90.0, -180.0, 0.0).is_ok());
    }

    proptest! {
        #[test]
        fn bennett_inverts_saemundsson(h in 0.0f64..89.0) {
            // Bennett's formula (Meeus 16.3) gives refraction from the apparent altitude;
            // the two agree to about 0.1' (Meeus).
            let apparent = apparent_altitude_deg(h);
            let bennett = 1.0 / (apparent + 7.31 / (apparent + 4.4)).to_radians().tan() / 60.0;
            prop_assert!(((apparent - h) - bennett).abs() * 60.0 < 0.1);
        }

        #[test]
        fn apparent_altitude_is_continuous_and_increasing(h in -10.0f64..89.9) {
            let a = apparent_altitude_deg(h);
            let b = apparent_altitude_deg(h + 0.01);
            prop_assert!(b > a);
            prop_assert!(b - a < 0.02);
        }

        #[test]
        fn positions_are_in_range(lat in -90.0f64..=90.0, lon in -180.0f64..=180.0,
                                  s in -3.15e9f64..3.15e9) {
            let obs = Observer::new(lat, lon, 0.0).unwrap();
            let t = UtcTime::from_seconds_since_j2000(s).unwrap();
            let e = ephemeris(&obs, t);
            for b in [e.sun, e.moon] {
                prop_assert!((0.0..360.0).contains(&b.azimuth_deg));
                prop_assert!((-90.0..=90.0).contains(&b.altitude_deg));
                prop_assert!(b.apparent_altitude_deg >= b.altitude_deg);
                let n = b.direction_enu.iter().map(|c| c * c).sum::<f64>();
                prop_assert!((n - 1.0).abs() < 1e-12);
            }
            prop_assert!((0.0..=1.0).contains(&e.moon_illuminated_fraction));
            prop_assert!((0.0..=180.0).contains(&e.moon_phase_angle_deg));
            // Sun 0.98-1.02 AU away, moon 356 000-407 000 km from the centre of the Earth.
            prop_assert!((0.98..1.02).contains(&(e.sun.distance_m / AU_M)));
            prop_assert!((349e6..414e6).contains(&e.moon.distance_m), "{}", e.moon.distance_m);
        }
    }
}
