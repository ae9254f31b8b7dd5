//! Sun and moon light, sky light, fog and exposure of a frame, in physical units.
//!
//! Algorithm: the sun's and the moon's directions come from `cig-environment`'s ephemeris
//! (Meeus: truncated VSOP87 and ELP, nutation, aberration, topocentric at the eye), good to 0.01
//! and 0.05 degree from 1900 to 2100; outside those years the light stays at the nearest
//! year's. The light colours come from the physical atmosphere (`cig_environment::atmosphere`,
//! Bruneton 2017 / Hillaire 2020): the sun's colour is the solar illuminance at the top of the
//! atmosphere times the atmosphere's transmittance to the eye (so it reddens and dims as the
//! sun sinks); the moon's is its illuminance at the zenith for its phase and distance
//! (`cig_environment::illuminance`, USNO fits) times the same transmittance relative to the
//! zenith's; the ambient light is the sky irradiance of the sun-lit and moon-lit sky plus the
//! night-sky background (0.002 lux); the fog colour is the sky's radiance toward the horizon,
//! averaged over eight azimuths. The cloud cover's sky-condition divisor dims them all. Light
//! colours are illuminance times [`LIGHTING_UNITS_PER_LUX`]; sky colours are radiance `L` shown
//! as `π L` times the same constant (what a white Lambert surface under illuminance `π L`
//! shows).
//!
//! Exposure ([`exposure_for_illuminance`]) is a pure function of the natural illuminance
//! (sun, moon, sky, with the cloud cover) as this model lights the ground — so the exposure
//! matches the light actually drawn — never of transients such as a lightning flash:
//! a grey card (albedo 0.18) under the natural illuminance `E` is shown at a key value that
//! falls with `log E` (after the log-compressed key of G. Krawczyk, K. Myszkowski, H.-P.
//! Seidel, "Lightness Perception in Tone Reproduction for High Dynamic Range Images", 2005):
//! 0.18 at 10⁵ lux, 0.05 at a full moon's 0.3 lux, 0.003 at a moonless night's 0.002 lux,
//! constant beyond (piecewise log-linear). So noon, dusk and a moonlit night each look right,
//! a moonlit night darker than the day but readable, and a moonless night nearly black (the
//! unaided eye sees little there: that is what goggles are for). The renderer then adapts
//! this exposure to what the view shows, within bounds (`cig_render`'s eye adaptation). Below 10 lux the tone map shifts toward the
//! scotopic blue ([`scotopic_fraction`], wholly at 0.01 lux).
//!
//! Fog follows the classic fixed-function factors of the NPSNET thesis (source 000, Eq 13-16,
//! as restored in INDEX.md): linear `f = (end - z)/(end - start)`, exponential `f = exp(-d z)`,
//! exponential-squared `f = exp(-(d z)^2)`, with the final colour `f * object + (1 - f) * fog`.
//! A visibility `V` in metres sets the parameters through Koschmieder's law (2 % contrast at
//! `V`): `d = 3.912 / V` for exponential, `d = sqrt(3.912) / V` for exponential-squared,
//! `end = V / 0.98` with `start = 0` for linear.
//!
//! Limits: a clear standard atmosphere at three wavelengths; the moon lights the sky as the sun
//! would at the same altitude (its own spectrum is not modelled); the cloud cover dims direct
//! and diffuse light alike (no overcast diffusion of the sun); the exposure here is the natural
//! illuminance's (the adaptation to the view and its time constants are the renderer's).

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
    let frame = EnuFrame::new(eye);
    let enu = ephemeris_at(unix_time_s, eye).map_or([0.0, 0.0, 1.0], |e| e.sun.direction_enu);
    frame.enu_vector_to_ecef(DVec3::from_array(enu)).normalize()
}

/// Light colours per lux of illuminance: the scale between the natural illuminance
/// (`cig_environment::natural_illuminance`, lux) and the frame's light colours. 1.0 is about
/// daylight (10⁵ lux). Pre-exposed values do not depend on it (exposure divides it out); it
/// keeps the un-exposed light colours near 1 by day and well inside f32 range at night.
pub const LIGHTING_UNITS_PER_LUX: f64 = 1.0 / 100_000.0;

/// Reflectance of the grey card the exposure keys on.
pub const EXPOSURE_GREY_ALBEDO: f64 = 0.18;

/// (natural illuminance lux, key) anchors of the log-linear exposure key: noon, a full moon,
/// a clear moonless night.
const KEY_ANCHORS: [(f64, f64); 3] = [(1.0e5, 0.18), (0.3, 0.05), (0.002, 0.003)];

/// Incident-light exposure value of an illuminance: `log2(E / 2.5)` (ISO 2720 incident-meter
/// calibration C = 250 with ISO 100).
pub fn exposure_value(illuminance_lux: f64) -> f64 {
    (illuminance_lux.max(1e-9) / 2.5).log2()
}

/// The illuminance an exposure value stands for (the inverse of [`exposure_value`]).
pub fn illuminance_for_exposure_value(ev: f64) -> f64 {
    2.5 * 2f64.powf(ev)
}

/// The display value a grey card shows under natural illuminance `illuminance_lux`
/// (piecewise log-linear between the noon, full-moon and moonless anchors, constant beyond).
pub fn exposure_key(illuminance_lux: f64) -> f64 {
    let log_e = if illuminance_lux.is_finite() {
        illuminance_lux.max(1e-9).log10()
    } else {
        KEY_ANCHORS[0].0.log10()
    };
    let [day, moon, dark] = KEY_ANCHORS;
    let (hi, lo) = if log_e >= moon.0.log10() {
        (day, moon)
    } else {
        (moon, dark)
    };
    let t = ((log_e - lo.0.log10()) / (hi.0.log10() - lo.0.log10())).clamp(0.0, 1.0);
    10f64.powf(lo.1.log10() + t * (hi.1.log10() - lo.1.log10()))
}

/// The frame's exposure (the factor `exposed()` applies to radiance in light units) for a
/// natural illuminance and an exposure compensation in EV.
pub fn exposure_for_illuminance(illuminance_lux: f64, compensation_ev: f64) -> f64 {
    let e = usable_illuminance(illuminance_lux);
    exposure_key(e) / (EXPOSURE_GREY_ALBEDO * e * LIGHTING_UNITS_PER_LUX)
        * 2f64.powf(usable_compensation(compensation_ev))
}

/// log2 of the pre-exposed value a grey card shows under `illuminance_lux` with the
/// compensation: what the eye's adaptation brings a view's mean luminance to.
pub fn shown_grey_log2(illuminance_lux: f64, compensation_ev: f64) -> f64 {
    exposure_key(usable_illuminance(illuminance_lux)).log2() + usable_compensation(compensation_ev)
}

fn usable_illuminance(illuminance_lux: f64) -> f64 {
    if illuminance_lux.is_finite() {
        illuminance_lux.max(1e-6)
    } else {
        KEY_ANCHORS[0].0
    }
}

fn usable_compensation(compensation_ev: f64) -> f64 {
    if compensation_ev.is_finite() {
        compensation_ev.clamp(-10.0, 10.0)
    } else {
        0.0
    }
}

/// How far the tone map shifts toward scotopic (rod) vision: 0 above 10 lux, 1 below 0.01 lux,
/// smooth in log illuminance between (ground lit by 10 lux has about 0.6 cd/m², inside the
/// mesopic range of 0.005-5 cd/m² where the rods take over).
pub fn scotopic_fraction(illuminance_lux: f64) -> f64 {
    let x = ((1.0 - illuminance_lux.max(1e-9).log10()) / 3.0).clamp(0.0, 1.0);
    x * x * (3.0 - 2.0 * x)
}

/// How the sky and the aerial perspective are drawn.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SkyModel {
    /// The physical atmosphere: sky-view table, sun disc, aerial perspective.
    #[default]
    Physical,
    /// A flat sky of the fog colour and the classic fog only (the benchmark's baseline).
    Flat,
}

/// Sky and exposure settings of a frame.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct SkySettings {
    pub model: SkyModel,
    /// Added to the automatic exposure, EV (+1 doubles the picture's brightness).
    pub exposure_compensation_ev: f64,
    /// Expose for this incident-light EV (`log2(E / 2.5)`) instead of the natural illuminance.
    pub fixed_exposure_ev: Option<f64>,
}

impl Default for SkySettings {
    fn default() -> Self {
        SkySettings {
            model: SkyModel::Physical,
            exposure_compensation_ev: 0.0,
            fixed_exposure_ev: None,
        }
    }
}

/// Light, sky and exposure of one frame, in linear RGB (not sRGB), scene-referred: light
/// colours are illuminance × [`LIGHTING_UNITS_PER_LUX`] (1.0 ≈ white paper in full daylight).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lighting {
    /// Towards the sun, ECEF unit vector.
    pub sun_direction: DVec3,
    /// Sun elevation above the eye's horizon (geometric), degrees.
    pub sun_elevation_deg: f64,
    /// Direct sunlight on a surface facing the sun.
    pub sun_colour: [f32; 3],
    /// Skylight on a horizontal surface (sun-lit and moon-lit sky, night-sky background).
    pub ambient_colour: [f32; 3],
    /// The sky straight up and toward the horizon (π L × units).
    pub sky_zenith: [f32; 3],
    pub sky_horizon: [f32; 3],
    /// The classic fog's colour: the horizon sky.
    pub fog_colour: [f32; 3],
    /// Towards the moon, ECEF unit vector.
    pub moon_direction: DVec3,
    pub moon_elevation_deg: f64,
    /// Direct moonlight on a surface facing the moon.
    pub moon_colour: [f32; 3],
    /// Moon phase angle (0 full, 180 new) and illuminated fraction.
    pub moon_phase_angle_deg: f64,
    pub moon_illuminated_fraction: f64,
    /// Solar illuminance at the top of the atmosphere × units (what the sky tables multiply).
    pub sun_toa_colour: [f32; 3],
    /// The moon's illuminance above the atmosphere × units.
    pub moon_toa_colour: [f32; 3],
    /// The night-sky background's radiance (π L × units), in every direction.
    pub night_sky_colour: [f32; 3],
    /// Natural illuminance on horizontal ground (direct sun and moon, sun-lit and moon-lit sky,
    /// night sky, cloud cover applied) as the atmosphere model lights the frame, lux.
    pub natural_illuminance_lux: f64,
    /// The same from `cig_environment::natural_illuminance` (the USNO fits), lux: the model
    /// agrees with it within 10 % by day and is up to 3.5 times brighter in civil twilight.
    pub usno_illuminance_lux: f64,
    /// The illuminance the exposure is set for (the natural one or the fixed EV's), lux.
    pub adapted_illuminance_lux: f64,
    /// The factor `exposed()` applies (see [`exposure_for_illuminance`]).
    pub exposure: f64,
    /// Scotopic blend of the tone map, 0..1.
    pub scotopic_fraction: f64,
}

fn rgb(c: [f64; 3], scale: f64) -> [f32; 3] {
    c.map(|v| (v * scale) as f32)
}

fn luminance(c: [f64; 3]) -> f64 {
    0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]
}

impl Lighting {
    /// The light at `unix_time_s` seen from `eye`, clear sky, automatic exposure.
    pub fn at(unix_time_s: f64, eye: Geodetic) -> Lighting {
        Lighting::with_sky(unix_time_s, eye, 0.0, &SkySettings::default())
    }

    /// The light at `unix_time_s` seen from `eye` under `cloud_cover_fraction` (clamped to
    /// [0, 1]) with the sky settings' exposure.
    pub fn with_sky(
        unix_time_s: f64,
        eye: Geodetic,
        cloud_cover_fraction: f64,
        sky: &SkySettings,
    ) -> Lighting {
        Lighting::weighted(unix_time_s, eye, cloud_cover_fraction, sky, Weighting::Eye)
    }

    /// The light as `weighting` sees it: for [`Weighting::Intensifier`] every colour is grey,
    /// in 2856 K-equivalent lux (lx_A) × units instead of lux × units, each source weighted by
    /// its spectrum (`cig_environment::nvg`: sunlight, the sun-lit sky, moonlight, the
    /// moon-lit sky, the night sky's airglow), and the natural and adapted illuminances are in
    /// lx_A (the USNO illuminance stays in lux). The sky-view tables on the GPU keep the
    /// atmosphere's colour; an intensifier view reads their red channel.
    pub fn weighted(
        unix_time_s: f64,
        eye: Geodetic,
        cloud_cover_fraction: f64,
        sky: &SkySettings,
        weighting: Weighting,
    ) -> Lighting {
        use cig_environment::illuminance as lux;
        let frame = EnuFrame::new(eye);
        let cover = if cloud_cover_fraction.is_finite() {
            cloud_cover_fraction.clamp(0.0, 1.0)
        } else {
            0.0
        };
        let divisor = lux::sky_condition_divisor(cover).unwrap_or(1.0);
        let atmosphere = cig_environment::Atmosphere::earth();
        let altitude_m = if eye.alt_m.is_finite() {
            eye.alt_m.clamp(0.0, 99_000.0)
        } else {
            0.0
        };
        let ephemeris = ephemeris_at(unix_time_s, eye);
        let (sun_enu, sun_alt, moon_enu, moon_alt, phase, fraction, moon_zenith_lux, natural) =
            match &ephemeris {
                Some(e) => (
                    e.sun.direction_enu,
                    e.sun.altitude_deg,
                    e.moon.direction_enu,
                    e.moon.altitude_deg,
                    e.moon_phase_angle_deg,
                    e.moon_illuminated_fraction,
                    lux::moon_illuminance_lux(90.0, e.moon_phase_angle_deg, e.moon.distance_m),
                    cig_environment::natural_illuminance(e, cover)
                        .map(|i| i.total_lux)
                        .unwrap_or(lux::NIGHT_SKY_LUX),
                ),
                None => (
                    [0.0, 0.0, 1.0],
                    90.0,
                    [0.0, 0.0, -1.0],
                    -90.0,
                    180.0,
                    0.0,
                    0.0,
                    1e5,
                ),
            };
        let units = LIGHTING_UNITS_PER_LUX / divisor;
        let [sun_k, moon_k, night_k, sun_sky_k, moon_sky_k] = weighting.factors();
        // The sky's light (its tables multiply these) and the direct beams', apart: on goggles
        // they weigh differently.
        let sun_toa = cig_environment::SUN_ILLUMINANCE_TOA_LUX * sun_sky_k;
        let sun_beam_toa = cig_environment::SUN_ILLUMINANCE_TOA_LUX * sun_k;
        // The moon above the atmosphere: its zenith illuminance over the zenith transmittance.
        let zenith_t = luminance(atmosphere.sun_transmittance(0.0, 90.0)).max(1e-6);
        let moon_toa = moon_zenith_lux * moon_sky_k / zenith_t;
        let moon_beam_toa = moon_zenith_lux * moon_k / zenith_t;
        let sun_t = atmosphere.sun_transmittance(altitude_m, sun_alt);
        let moon_t = atmosphere.sun_transmittance(altitude_m, moon_alt);
        let sky_sun = atmosphere.sky_irradiance(altitude_m, sun_alt);
        let sky_moon = atmosphere.sky_irradiance(altitude_m, moon_alt);
        // The night-sky background, slightly blue (airglow and starlight).
        let night = [0.8, 0.9, 1.2].map(|c| c * lux::NIGHT_SKY_LUX * night_k);
        let ambient: [f64; 3] =
            std::array::from_fn(|c| sky_sun[c] * sun_toa + sky_moon[c] * moon_toa + night[c]);
        // Sky radiance toward the zenith and (averaged over azimuth) the horizon, shown as π L.
        let pi = std::f64::consts::PI;
        let sky_at = |view: [f64; 3]| -> [f64; 3] {
            let s = atmosphere.sky_radiance(altitude_m, view, sun_enu);
            let m = if moon_toa > 0.0 && moon_alt > MOON_SKY_LOWEST_DEG {
                atmosphere.sky_radiance(altitude_m, view, moon_enu)
            } else {
                [0.0; 3]
            };
            std::array::from_fn(|c| pi * (s[c] * sun_toa + m[c] * moon_toa) + night[c])
        };
        let zenith = sky_at([0.0, 0.0, 1.0]);
        let mut horizon = [0.0; 3];
        let elevation = 1.5f64.to_radians();
        for k in 0..8 {
            let az = f64::from(k) * pi / 4.0;
            let v = [
                elevation.cos() * az.sin(),
                elevation.cos() * az.cos(),
                elevation.sin(),
            ];
            let l = sky_at(v);
            for c in 0..3 {
                horizon[c] += l[c] / 8.0;
            }
        }
        // The natural illuminance on horizontal ground as this model lights it: direct sun and
        // moon, the sun-lit and moon-lit sky and the night-sky background.
        let sun_lum = luminance(sun_t) * sun_beam_toa * sun_alt.to_radians().sin().max(0.0);
        let moon_lum = luminance(moon_t) * moon_beam_toa * moon_alt.to_radians().sin().max(0.0);
        let modelled = (sun_lum + moon_lum + luminance(ambient)) / divisor;
        let adapted = match sky.fixed_exposure_ev {
            Some(ev) if ev.is_finite() => illuminance_for_exposure_value(ev.clamp(-20.0, 20.0)),
            _ => modelled,
        };
        // On goggles one number (lx_A) is carried grey, at each colour's luminance.
        let rgb = |c: [f64; 3], scale: f64| match weighting {
            Weighting::Eye => rgb(c, scale),
            Weighting::Intensifier => [(luminance(c) * scale) as f32; 3],
        };
        let sky_horizon = rgb(horizon, units);
        let to_ecef = |v: [f64; 3]| frame.enu_vector_to_ecef(DVec3::from_array(v)).normalize();
        Lighting {
            sun_direction: to_ecef(sun_enu),
            sun_elevation_deg: sun_alt,
            sun_colour: rgb(sun_t.map(|t| t * sun_beam_toa), units),
            ambient_colour: rgb(ambient, units),
            sky_zenith: rgb(zenith, units),
            sky_horizon,
            fog_colour: sky_horizon,
            moon_direction: to_ecef(moon_enu),
            moon_elevation_deg: moon_alt,
            moon_colour: rgb(moon_t.map(|t| t * moon_beam_toa), units),
            moon_phase_angle_deg: phase,
            moon_illuminated_fraction: fraction,
            sun_toa_colour: rgb([sun_toa; 3], units),
            moon_toa_colour: rgb([moon_toa; 3], units),
            night_sky_colour: rgb(night, units),
            natural_illuminance_lux: modelled,
            usno_illuminance_lux: natural,
            adapted_illuminance_lux: adapted,
            exposure: exposure_for_illuminance(adapted, sky.exposure_compensation_ev),
            scotopic_fraction: scotopic_fraction(adapted),
        }
    }
}

/// The ephemeris at the eye, the time clamped into 1900..=2100 (None for an eye the ephemeris
/// cannot take).
fn ephemeris_at(unix_time_s: f64, eye: Geodetic) -> Option<cig_environment::Ephemeris> {
    let lo =
        cig_environment::UtcTime::from_calendar(1900, 1, 1, 0, 0, 0.0).map(|t| t.unix_seconds());
    let hi = cig_environment::UtcTime::from_calendar(2100, 12, 31, 23, 59, 59.0)
        .map(|t| t.unix_seconds());
    let t = match (lo, hi) {
        (Ok(lo), Ok(hi)) if unix_time_s.is_finite() => unix_time_s.clamp(lo, hi),
        (Ok(lo), _) => lo,
        _ => return None,
    };
    let lat = eye.lat_deg.clamp(-90.0, 90.0);
    let alt = eye.alt_m.clamp(-1000.0, 1.0e7);
    let time = cig_environment::UtcTime::from_unix_seconds(t).ok()?;
    let observer = cig_environment::Observer::new(lat, eye.lon_deg, alt).ok()?;
    Some(cig_environment::ephemeris(&observer, time))
}

/// Whose spectral weighting the light colours are in.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Weighting {
    /// The eye's (photopic lux).
    #[default]
    Eye,
    /// A Gen III image intensifier's (2856 K-equivalent lux, `cig_environment::nvg`).
    Intensifier,
}

impl Weighting {
    /// Factors on the lux of direct sunlight, direct moonlight, the night sky, the sun-lit
    /// sky and the moon-lit sky.
    pub fn factors(self) -> [f64; 5] {
        use cig_environment::nvg as n;
        match self {
            Weighting::Eye => [1.0; 5],
            Weighting::Intensifier => [
                n::SUN_NVG_PER_LUX,
                n::MOON_NVG_PER_LUX,
                n::NIGHT_SKY_NVG_PER_LUX,
                n::SUNLIT_SKY_NVG_PER_LUX,
                n::MOONLIT_SKY_NVG_PER_LUX,
            ],
        }
    }

    /// Factor on a lightning flash's lux: lightning's spectrum is rich in the near infrared
    /// (the O I 777 nm and N I 868 nm lines; Orville and Henderson, *J. Atmos. Sci.* 41, 1984),
    /// about as an incandescent source per lux.
    pub fn flash_factor(self) -> f64 {
        match self {
            Weighting::Eye => 1.0,
            Weighting::Intensifier => {
                cig_environment::nvg::LightSpectrum::Incandescent.nvg_per_lux()
            }
        }
    }
}

/// Colour of a lightning flash's light (bluish white, unit luminance-weighted).
pub const FLASH_COLOUR: [f32; 3] = [0.86, 0.92, 1.0];
/// Fraction of the flash's illuminance the sky and the fog show as their colour (the cloud base
/// and the rain lit from within).
const FLASH_SKY_FRACTION: f32 = 0.5;

/// The moon's lowest elevation (degrees) at which its light in the sky is drawn: below it, the
/// twilight it leaves is under the night sky's own light.
const MOON_SKY_LOWEST_DEG: f64 = -10.0;

impl Lighting {
    /// Whether the moon's light in the sky is worth drawing: it has light, stands above
    /// [`MOON_SKY_LOWEST_DEG`] (as the sky colours above assume) and the sun is below the
    /// horizon. With the sun up, the moon's sky is under 10⁻⁶ of the sun's, far below what a
    /// half float or a display level resolves.
    pub fn moon_lights_the_sky(&self) -> bool {
        self.moon_toa_colour.iter().sum::<f32>() > 0.0
            && self.moon_elevation_deg > MOON_SKY_LOWEST_DEG
            && self.sun_elevation_deg < 0.0
    }

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
    fn the_moon_lights_the_sky_only_at_night_and_while_it_is_up() {
        let eye = Geodetic::new(36.0159, -121.1854, 0.0);
        // 2026-06-22 05:00 UTC: the moon 33 degrees up, the sun 16 down; 11:00: the moon 35 down.
        let moonlit = Lighting::at(unix(2026, 6, 22, 5.0), eye);
        let moonless = Lighting::at(unix(2026, 6, 22, 11.0), eye);
        // 2026-06-22 00:00 UTC: the moon up by day.
        let daylit = Lighting::at(unix(2026, 6, 22, 0.0), eye);
        assert!(moonlit.moon_elevation_deg > 30.0 && moonlit.sun_elevation_deg < -10.0);
        assert!(moonlit.moon_lights_the_sky());
        assert!(moonless.moon_elevation_deg < -30.0 && moonless.sun_elevation_deg < -10.0);
        assert!(!moonless.moon_lights_the_sky());
        assert!(daylit.moon_elevation_deg > 10.0 && daylit.sun_elevation_deg > 10.0);
        assert!(!daylit.moon_lights_the_sky());
        // The moon's light above the atmosphere is there in all three.
        for l in [&moonlit, &moonless, &daylit] {
            assert!(l.moon_toa_colour.iter().all(|c| *c > 0.0));
        }
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

    fn lum(c: [f32; 3]) -> f64 {
        0.2126 * f64::from(c[0]) + 0.7152 * f64::from(c[1]) + 0.0722 * f64::from(c[2])
    }

    #[test]
    fn the_sun_is_white_and_bright_at_noon_and_red_and_dim_at_sunset() {
        let site = Geodetic::new(36.0, -121.0, 0.0);
        let noon = Lighting::at(unix(2026, 6, 21, 20.07), site);
        let sun_lux = lum(noon.sun_colour) / LIGHTING_UNITS_PER_LUX;
        assert!((80_000.0..125_000.0).contains(&sun_lux), "{sun_lux}");
        let sky_lux = lum(noon.ambient_colour) / LIGHTING_UNITS_PER_LUX;
        assert!((8_000.0..30_000.0).contains(&sky_lux), "{sky_lux}");
        assert!(noon.ambient_colour[2] > noon.ambient_colour[0]);
        // Sunset at 36 N, 121 W on 21 June: about 03:30 UTC the next day; a sun 1-2 degrees up.
        let mut low = noon;
        for minutes in 0..240 {
            let l = Lighting::at(unix(2026, 6, 22, 2.0 + f64::from(minutes) / 60.0), site);
            if l.sun_elevation_deg < 2.0 {
                low = l;
                break;
            }
        }
        assert!(low.sun_elevation_deg > 0.0 && low.sun_elevation_deg < 2.0);
        assert!(
            low.sun_colour[0] > 2.0 * low.sun_colour[2],
            "{:?}",
            low.sun_colour
        );
        assert!(lum(low.sun_colour) < 0.3 * lum(noon.sun_colour));
        // Fog (the horizon sky) is lighter at noon than at night.
        let midnight = Lighting::at(unix(2026, 6, 21, 8.07), site);
        assert!(lum(noon.fog_colour) > 1000.0 * lum(midnight.fog_colour));
        assert_eq!(midnight.sun_colour, [0.0; 3]);
    }

    #[test]
    fn the_full_moon_lights_the_night() {
        // Full moon 2024-06-22 01:08 UTC; local midnight at 121 W is about 08:00 UTC.
        let site = Geodetic::new(36.0, -121.0, 0.0);
        let night = Lighting::at(unix(2024, 6, 22, 8.0), site);
        assert!(night.sun_elevation_deg < -18.0);
        assert!(
            night.moon_elevation_deg > 15.0,
            "{}",
            night.moon_elevation_deg
        );
        let moon_lux = lum(night.moon_colour) / LIGHTING_UNITS_PER_LUX;
        assert!((0.05..0.5).contains(&moon_lux), "{moon_lux}");
        assert!(lum(night.moon_colour) > lum(night.ambient_colour));
        assert!((0.05..0.6).contains(&night.natural_illuminance_lux));
        // The key light by day is the sun: the moon adds next to nothing.
        let day = Lighting::at(unix(2024, 6, 21, 20.0), site);
        assert!(lum(day.moon_colour) < 1e-4 * lum(day.sun_colour));
    }

    #[test]
    fn exposure_orders_noon_dusk_moonlight_and_a_moonless_night() {
        let shown = |lux: f64| {
            EXPOSURE_GREY_ALBEDO * lux * LIGHTING_UNITS_PER_LUX * exposure_for_illuminance(lux, 0.0)
        };
        let (noon, dusk, moon, dark) = (shown(1.1e5), shown(3.4), shown(0.3), shown(0.002));
        assert!(
            noon > dusk && dusk > moon && moon > dark,
            "{noon} {dusk} {moon} {dark}"
        );
        assert!((0.15..0.25).contains(&noon), "{noon}");
        // A moonlit night is readable: a grey card shows at least a tenth of its noon value.
        assert!(moon > 0.2 * noon && moon > 0.03, "{moon}");
        // Compensation doubles per EV.
        let e = exposure_for_illuminance(1000.0, 1.0) / exposure_for_illuminance(1000.0, 0.0);
        assert!((e - 2.0).abs() < 1e-9);
        assert!(scotopic_fraction(1e4) == 0.0 && scotopic_fraction(1e-4) == 1.0);
        assert!(exposure_for_illuminance(f64::NAN, f64::NAN).is_finite());
        assert!((exposure_value(2.5 * 8.0) - 3.0).abs() < 1e-12);
    }

    #[test]
    fn the_view_key_is_where_a_grey_card_shows() {
        for lux in [1.0e5, 3.4, 0.3, 0.002] {
            for compensation_ev in [0.0, 1.5, -2.0] {
                let shown = EXPOSURE_GREY_ALBEDO
                    * lux
                    * LIGHTING_UNITS_PER_LUX
                    * exposure_for_illuminance(lux, compensation_ev);
                let key = shown_grey_log2(lux, compensation_ev);
                assert!(
                    (shown.log2() - key).abs() < 1e-9,
                    "{lux} lux: {shown} against 2^{key}"
                );
            }
        }
        assert!(shown_grey_log2(f64::NAN, f64::INFINITY).is_finite());
    }

    #[test]
    fn a_fixed_exposure_ignores_the_natural_light() {
        let site = Geodetic::new(36.0, -121.0, 0.0);
        let sky = SkySettings {
            fixed_exposure_ev: Some(exposure_value(1000.0)),
            ..SkySettings::default()
        };
        let noon = Lighting::with_sky(unix(2026, 6, 21, 20.07), site, 0.0, &sky);
        let night = Lighting::with_sky(unix(2026, 6, 21, 8.07), site, 0.0, &sky);
        assert!((noon.exposure / night.exposure - 1.0).abs() < 1e-9);
        assert!((noon.adapted_illuminance_lux - 1000.0).abs() < 1e-6);
        // Cloud cover dims the natural light and so raises the automatic exposure.
        let clear = Lighting::at(unix(2026, 6, 21, 20.07), site);
        let cloudy =
            Lighting::with_sky(unix(2026, 6, 21, 20.07), site, 1.0, &SkySettings::default());
        assert!(cloudy.natural_illuminance_lux < clear.natural_illuminance_lux / 5.0);
        assert!(cloudy.exposure > clear.exposure);
        assert!(lum(cloudy.sun_colour) < lum(clear.sun_colour) / 5.0);
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
