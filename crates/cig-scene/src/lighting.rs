//! Sun direction, light colours, sky gradient and fog of a frame.
//!
//! Algorithm: the sun's direction comes from `cig-environment`'s ephemeris (Meeus: truncated
//! VSOP87, nutation, aberration, topocentric at the eye), good to 0.01 degree from 1900 to 2100;
//! outside those years the light stays at the nearest year's. Sun and sky colours are interpolated in the sun's elevation between day, golden
//! hour, dusk and night palettes. Fog follows the classic fixed-function factors of the NPSNET
//! thesis (source 000, Eq 13-16, as restored in INDEX.md): linear `f = (end - z)/(end - start)`,
//! exponential `f = exp(-d z)`, exponential-squared `f = exp(-(d z)^2)`, with the final colour
//! `f * object + (1 - f) * fog`. A visibility `V` in metres sets the parameters through
//! Koschmieder's law (2 % contrast at `V`): `d = 3.912 / V` for exponential,
//! `d = sqrt(3.912) / V` for exponential-squared, `end = V / 0.98` with `start = 0` for linear.
//!
//! Limits: no atmosphere model — the sky is a gradient and the sun's colour a palette; no moon
//! light (the environment issue brings the physical sky, the moon and exposure).

use cig_geo::{EnuFrame, Geodetic};
use glam::DVec3;
use serde::{Deserialize, Serialize};

/// Koschmieder's constant: `-ln(0.02)`.
pub const KOSCHMIEDER: f64 = 3.912;

/// The fog factor's form.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FogMode {
    Off,
    Linear,
    #[default]
    Exponential,
    ExponentialSquared,
}

impl FogMode {
    /// Parses `off`, `linear`, `exp` / `exponential`, `exp2` / `exponential-squared`.
    pub fn parse(s: &str) -> Option<FogMode> {
        match s.to_ascii_lowercase().as_str() {
            "off" | "none" => Some(FogMode::Off),
            "linear" => Some(FogMode::Linear),
            "exp" | "exponential" => Some(FogMode::Exponential),
            "exp2" | "exponential-squared" | "exponential_squared" => {
                Some(FogMode::ExponentialSquared)
            }
            _ => None,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            FogMode::Off => "off",
            FogMode::Linear => "linear",
            FogMode::Exponential => "exp",
            FogMode::ExponentialSquared => "exp2",
        }
    }
}

/// Fog parameters derived from a mode and a visibility.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Fog {
    pub mode: FogMode,
    /// Density `d` (1/m) for the exponential forms.
    pub density_per_m: f64,
    /// Start and end distances for the linear form, metres.
    pub start_m: f64,
    pub end_m: f64,
}

impl Fog {
    pub fn from_visibility(mode: FogMode, visibility_m: f64) -> Fog {
        let v = visibility_m.max(1.0);
        Fog {
            mode,
            density_per_m: match mode {
                FogMode::ExponentialSquared => KOSCHMIEDER.sqrt() / v,
                _ => KOSCHMIEDER / v,
            },
            start_m: 0.0,
            end_m: v / 0.98,
        }
    }

    /// The fraction of an object's colour that survives at `distance_m`.
    pub fn factor(&self, distance_m: f64) -> f64 {
        let z = distance_m.max(0.0);
        match self.mode {
            FogMode::Off => 1.0,
            FogMode::Linear => ((self.end_m - z) / (self.end_m - self.start_m)).clamp(0.0, 1.0),
            FogMode::Exponential => (-self.density_per_m * z).exp(),
            FogMode::ExponentialSquared => (-(self.density_per_m * z).powi(2)).exp(),
        }
    }
}

/// Unit vector from `eye` towards the sun (ECEF), at `unix_time_s` (UTC), topocentric.
pub fn sun_direction_ecef(unix_time_s: f64, eye: Geodetic) -> DVec3 {
    // The ephemeris covers 1900..=2100; clamp into it rather than fail a frame.
    let lo =
        cig_environment::UtcTime::from_calendar(1900, 1, 1, 0, 0, 0.0).map(|t| t.unix_seconds());
    let hi = cig_environment::UtcTime::from_calendar(2100, 12, 31, 23, 59, 59.0)
        .map(|t| t.unix_seconds());
    let t = match (lo, hi) {
        (Ok(lo), Ok(hi)) => unix_time_s.clamp(lo, hi),
        _ => unix_time_s,
    };
    let lat = eye.lat_deg.clamp(-90.0, 90.0);
    let alt = eye.alt_m.clamp(-1000.0, 1.0e7);
    let (Ok(time), Ok(observer)) = (
        cig_environment::UtcTime::from_unix_seconds(t),
        cig_environment::Observer::new(lat, eye.lon_deg, alt),
    ) else {
        return EnuFrame::new(eye).enu_vector_to_ecef(DVec3::Z);
    };
    let sun = cig_environment::ephemeris(&observer, time).sun;
    EnuFrame::new(eye)
        .enu_vector_to_ecef(DVec3::from_array(sun.direction_enu))
        .normalize()
}

/// Light colours per lux of illuminance: the scale between the natural illuminance
/// (`cig_environment::natural_illuminance`, lux) and the frame's light colours.
pub const LIGHTING_UNITS_PER_LUX: f64 = 1.0 / 100_000.0;

/// Light and sky of one frame, in linear RGB (not sRGB), scene-referred (1.0 = white paper in
/// full daylight).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lighting {
    /// Towards the sun, ECEF unit vector.
    pub sun_direction: DVec3,
    /// Sun elevation above the eye's horizon, degrees.
    pub sun_elevation_deg: f64,
    pub sun_colour: [f32; 3],
    pub ambient_colour: [f32; 3],
    pub sky_zenith: [f32; 3],
    pub sky_horizon: [f32; 3],
    pub fog_colour: [f32; 3],
}

fn lerp3(a: [f32; 3], b: [f32; 3], t: f64) -> [f32; 3] {
    let t = t.clamp(0.0, 1.0) as f32;
    [
        a[0] + (b[0] - a[0]) * t,
        a[1] + (b[1] - a[1]) * t,
        a[2] + (b[2] - a[2]) * t,
    ]
}

/// Palette key: (sun elevation, sun colour, ambient, zenith, horizon).
type PaletteKey = (f64, [f32; 3], [f32; 3], [f32; 3], [f32; 3]);

const PALETTE: [PaletteKey; 5] = [
    (
        -18.0,
        [0.0, 0.0, 0.0],
        [0.004, 0.005, 0.010],
        [0.001, 0.0015, 0.004],
        [0.004, 0.005, 0.010],
    ),
    (
        -6.0,
        [0.0, 0.0, 0.0],
        [0.03, 0.035, 0.06],
        [0.02, 0.03, 0.08],
        [0.12, 0.08, 0.10],
    ),
    (
        0.0,
        [0.55, 0.28, 0.10],
        [0.10, 0.10, 0.14],
        [0.10, 0.16, 0.35],
        [0.70, 0.42, 0.25],
    ),
    (
        10.0,
        [1.00, 0.78, 0.55],
        [0.22, 0.25, 0.32],
        [0.16, 0.32, 0.70],
        [0.62, 0.66, 0.72],
    ),
    (
        40.0,
        [1.00, 0.96, 0.90],
        [0.30, 0.34, 0.42],
        [0.14, 0.30, 0.72],
        [0.62, 0.70, 0.82],
    ),
];

impl Lighting {
    /// The light at `unix_time_s` seen from `eye`.
    pub fn at(unix_time_s: f64, eye: Geodetic) -> Lighting {
        let local_up = EnuFrame::new(eye).enu_vector_to_ecef(DVec3::Z);
        let sun_direction = sun_direction_ecef(unix_time_s, eye);
        let sun_elevation_deg = sun_direction
            .dot(local_up)
            .clamp(-1.0, 1.0)
            .asin()
            .to_degrees();
        let e = sun_elevation_deg;
        let (mut lo, mut hi) = (PALETTE[0], PALETTE[PALETTE.len() - 1]);
        for w in PALETTE.windows(2) {
            if e >= w[0].0 && e <= w[1].0 {
                (lo, hi) = (w[0], w[1]);
            }
        }
        if e < PALETTE[0].0 {
            hi = lo;
        }
        let t = if hi.0 > lo.0 {
            (e - lo.0) / (hi.0 - lo.0)
        } else {
            0.0
        };
        let sky_horizon = lerp3(lo.4, hi.4, t);
        Lighting {
            sun_direction,
            sun_elevation_deg,
            sun_colour: lerp3(lo.1, hi.1, t),
            ambient_colour: lerp3(lo.2, hi.2, t),
            sky_zenith: lerp3(lo.3, hi.3, t),
            sky_horizon,
            fog_colour: sky_horizon,
        }
    }
}

/// Colour of a lightning flash's light (bluish white, unit luminance-weighted).
pub const FLASH_COLOUR: [f32; 3] = [0.86, 0.92, 1.0];
/// Fraction of the flash's illuminance the sky and the fog show as their colour (the cloud base
/// and the rain lit from within).
const FLASH_SKY_FRACTION: f32 = 0.5;

impl Lighting {
    /// The light of the frame with a lightning flash of `flash_lux` (at the eye) added: its
    /// bluish-white light joins the ambient light and lights the sky and the fog (half of it),
    /// so terrain, models and sky brighten together. Non-finite or negative values add nothing.
    pub fn with_flash(self, flash_lux: f64) -> Lighting {
        if !(flash_lux.is_finite() && flash_lux > 0.0) {
            return self;
        }
        let e = (flash_lux * LIGHTING_UNITS_PER_LUX) as f32;
        let add = |c: [f32; 3], k: f32| {
            [
                c[0] + FLASH_COLOUR[0] * e * k,
                c[1] + FLASH_COLOUR[1] * e * k,
                c[2] + FLASH_COLOUR[2] * e * k,
            ]
        };
        Lighting {
            ambient_colour: add(self.ambient_colour, 1.0),
            sky_zenith: add(self.sky_zenith, FLASH_SKY_FRACTION),
            sky_horizon: add(self.sky_horizon, FLASH_SKY_FRACTION),
            fog_colour: add(self.fog_colour, FLASH_SKY_FRACTION),
            ..self
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn unix(y: i32, m: u32, d: u32, h: f64) -> f64 {
        cig_environment::UtcTime::from_calendar(y, m, d, 0, 0, 0.0)
            .expect("a date in range")
            .unix_seconds()
            + h * 3600.0
    }

    #[test]
    fn sun_is_high_at_local_noon_in_june_and_down_at_midnight() {
        let site = Geodetic::new(36.0, -121.0, 0.0);
        // Local solar noon near 20:04 UTC at 121 W; declination +23.4 on 21 June.
        let noon = Lighting::at(unix(2026, 6, 21, 20.07), site);
        assert!(
            (noon.sun_elevation_deg - (90.0 - 36.0 + 23.44)).abs() < 0.3,
            "{}",
            noon.sun_elevation_deg
        );
        let midnight = Lighting::at(unix(2026, 6, 21, 8.07), site);
        assert!(midnight.sun_elevation_deg < -25.0);
        assert!(noon.sky_zenith[2] > midnight.sky_zenith[2] * 10.0);
    }

    #[test]
    fn fog_meets_two_percent_contrast_at_the_visibility_in_every_mode() {
        for mode in [
            FogMode::Linear,
            FogMode::Exponential,
            FogMode::ExponentialSquared,
        ] {
            let fog = Fog::from_visibility(mode, 5000.0);
            assert!((fog.factor(5000.0) - 0.02).abs() < 1e-3, "{mode:?}");
            assert!((fog.factor(0.0) - 1.0).abs() < 1e-12);
            assert!(fog.factor(2000.0) > fog.factor(3000.0));
        }
        assert_eq!(Fog::from_visibility(FogMode::Off, 10.0).factor(1e6), 1.0);
    }

    #[test]
    fn a_flash_brightens_ambient_and_sky_and_nothing_else() {
        let base = Lighting::at(unix(2026, 6, 21, 8.07), Geodetic::new(36.0, -121.0, 0.0));
        let lit = base.with_flash(100.0);
        let units = (100.0 * LIGHTING_UNITS_PER_LUX) as f32;
        for (i, flash) in FLASH_COLOUR.iter().enumerate() {
            assert!((lit.ambient_colour[i] - base.ambient_colour[i] - flash * units).abs() < 1e-7);
            assert!(lit.sky_zenith[i] > base.sky_zenith[i]);
            assert!(lit.fog_colour[i] > base.fog_colour[i]);
        }
        assert_eq!(lit.sun_colour, base.sun_colour);
        assert_eq!(base.with_flash(0.0), base);
        assert_eq!(base.with_flash(f64::NAN), base);
        assert_eq!(base.with_flash(-5.0), base);
    }
}
