//! Light points: lamps, signal lights, fires and flares drawn as points of a physical luminous
//! intensity and colour, kept where a real light of that intensity would be seen.
//!
//! Algorithm. Every light is a [`LightPoint`]: an ECEF position, an on-axis intensity (cd),
//! a colour (linear sRGB of unit luminance), a spectrum (for its night-vision weighting), a
//! lobe and a blink pattern. Its intensity toward a direction ([`LightPoint::intensity_toward_cd`])
//! is the on-axis intensity times the lobe's factor, or nothing while a flashing light is dark:
//! - [`Lobe::Omni`]: the same everywhere;
//! - [`Lobe::Beam`]: a Gaussian in the angle `a` off the axis with the half width at half
//!   maximum `w`, `max(back_fraction, exp(-ln 2 (a / w)^2))` (headlights, searchlights,
//!   street lamps aimed down);
//! - [`Lobe::Sector`]: full intensity within an azimuth sector about the axis in the plane
//!   normal to `up` (any elevation), falling linearly to nothing over [`SECTOR_CUTOFF_DEG`]
//!   beyond its edge (navigation lights of aircraft and ships: COLREGS Annex I §9(a) asks for
//!   a practical cut-off 1 to 3 degrees outside the sector).
//!
//! A flashing light is on while `(t + phase) mod period < on` (a function of time only, so
//! every channel agrees). Its on-intensity is set from the effective intensity a rule asks for
//! by the Blondel-Rey relation of 14 CFR 25.1401(f), `I_e = I t / (0.2 s + t)` for a flash of
//! `t` seconds, with flashes at least 0.05 s long so a 60 Hz frame catches them.
//!
//! A light reaches the eye with the illuminance of Allard's law, `E = I T / d^2`, where `T` is
//! the frame's fog factor at `d` ([`crate::lighting::Fog::factor`]: the clear air's extinction
//! is already in its visibility, so no other atmospheric term is applied), times the ground fog
//! layer's transmittance ([`FogLayer::transmittance`], heights from the eye's local vertical
//! with the earth's curvature), times the obscurant puffs' (each puff the renderer's Gaussian:
//! centre optical depth `-ln(1 - opacity)` capped at 9.21, `sigma = radius / 2.5`, integrated
//! along the segment eye-light in closed form by `cig_effects::optics::gaussian_path_integral_kg_m2`,
//! source 000 Eq 1-4). [`drawn_lights`] keeps a light only where `E` reaches the observer's
//! threshold: for the eye, the point-source threshold against the scene's background luminance
//! (`cig_environment::stars::threshold_illuminance_lux`, Schaefer 1990 after Hecht: about
//! 1.5e-8 lx against a moonless night's 1e-3 cd/m², 2e-5 lx against an overcast day's
//! 1e3 cd/m²); for an image intensifier, a threshold in 2856 K-equivalent lux
//! (`E * spectrum.nvg_per_lux()`). So a light's range follows its intensity, the visibility
//! and the adaptation level, never a fixed distance ([`allard_range_m`] solves it).
//!
//! Obscurants are found fast: every segment starts at the eye, so each puff is a cone of
//! directions (angular radius `asin(4 sigma / d)`), binned into a 6 x 64 x 64 cube map of
//! directions (a conservative rectangle per face from the cone's two projected angle ranges);
//! a light tests only the puffs of its direction's cell, plus the few that surround the eye or
//! subtend more than 14.5 degrees. Puffs further than 4 sigma from the segment are skipped (at
//! most 0.003 of optical depth); a puff the segment crosses whole takes the full line's column
//! (the error-function terms are within 6e-5 of one). 10,000 lights through 200 puffs cost
//! about 0.9 ms (release, one core).
//!
//! Sources. Entity lights ([`entity_lights`], switched by [`LightSwitches`], which the IG
//! (`cig-ig`) sets from the host, the scenario or the DIS appearance bits that
//! `cig_dis::LightsRequested` decodes):
//! - ground vehicles: halogen low-beam headlamps 15 kcd on axis, 10° half width, aimed 1° down
//!   (ECE R112 / SAE J1383 order of magnitude: 10-20 kcd at the hot spot); tail lamps 5 cd red
//!   (FMVSS 108: at least 2 cd, at most 18 cd on axis), stop lamps 80 cd red (FMVSS 108: at least
//!   80 cd, at most 300 cd); blackout markers 0.002 cd (chosen so the dark-adapted eye sees them
//!   to about 350 m, the short range they are made for) and a 50 cd blackout drive lamp aimed
//!   10° down; a 200 kcd searchlight (3° half width); a 2 cd interior light;
//! - aircraft: position lights red left and green right, 40 cd over 110° sectors from the nose
//!   (14 CFR 25.1385/25.1391: 40 cd within 10° of the nose, less out to 110°: the 40 cd is
//!   held over the whole sector), white tail 20 cd over 140° aft (25.1391/25.1393); red
//!   anti-collision beacons top and bottom, 400 cd effective at 50 flashes a minute, 0.15 s
//!   flashes (25.1401: at least 400 cd effective, 40-100 flashes a minute); white wing-tip
//!   strobes 400 cd effective, 0.05 s flashes; landing lights 200 kcd, 6° half width (order of
//!   magnitude of a 250 W PAR-46 sealed beam);
//! - ships: COLREGS Annex I §8, `I = 3.43e6 T D^2 K^-D` with `T = 2e-7` lx and `K = 0.8`
//!   ([`colregs_intensity_cd`]: 6 NM 94 cd, 3 NM 12 cd), ranges by length from Rule 22
//!   (50 m or more: masthead 6 NM, sidelights 3 NM, sternlight 3 NM; 20-50 m: 5, 2, 2;
//!   12-20 m: 3, 2, 2; under 12 m: 2, 1, 2), sectors from Rule 21 (masthead 225° forward,
//!   sidelights 112.5° from dead ahead, sternlight 135° aft).
//!
//! Street and settlement lights ([`culture_lights`], once per resident culture tile): a street
//! lamp 0.3 m below every power pole's top, a high-pressure sodium semi-cutoff luminaire (150 W,
//! about 16,000 lm): 3000 cd at the nadir falling as a Gaussian of 65° half width, so 1050 cd
//! at 80° and 790 cd at 90° from the nadir, within IES semi-cutoff (at most 20 % and 5 % of the
//! lamp lumens in cd at 80° and 90°), colour of 2000 K; a porch light (2.2 m up on one long
//! side) at a share of the houses hashed from their position (60 %), 60 cd (a 60 W
//! incandescent lamp's 700 lm over 4π, about 56 cd), tungsten 2700 K or white LED 3500 K by
//! hash. They burn while [`street_lights_on`]: a photocontrol turning on at 16 lx (ANSI C136.10:
//! 1.5 fc nominal turn-on).
//!
//! Fires and flares: [`Flare`] falls at its descent rate from its ignition point and burns for
//! its duration (155 mm M485: about 1 Mcd, 120 s, 5 m/s, TM 43-0001-28 / FM 6-40; 81 mm
//! M853A1: about 500 kcd, 60 s, 2.5 m/s, FM 3-22.90). [`fire_light`] gives a fire of heat
//! release `Q` the intensity `Q chi_r K / 4 pi` (radiant fraction `chi_r` 0.3 of sooty
//! hydrocarbon fires, SFPE Handbook; luminous efficacy `K` 0.1 lm/W of a 1500 K grey body,
//! Planck's law against V(λ)), centred at half the flame height of Heskestad's correlation
//! `L = 0.235 Q^(2/5) - 1.02 D` (kW, m), flickering at the puffing frequency
//! `f = 1.5 / sqrt(D)` Hz (Cetegen and Ahmed 1993) as a sum of three sines with phases hashed
//! from its seed. Fires, flares, headlights, searchlights, landing lights and street lamps light
//! the ground ([`local_lights`] picks the strongest near the eye for the renderer).
//!
//! Limits: point sources only (no glare, halo or scattering into the fog around a light); beams
//! are circular cones (a headlamp's vertical cut-off is not modelled); sectors have no vertical
//! fall-off; the tail, stop and position lamps take the Incandescent spectrum (a red filter over
//! tungsten passes the near infrared, so goggles see them brighter than that weighting says);
//! terrain and culture hide lights only through the renderer's depth test; flares do not drift
//! with the wind; every street lamp of a frame switches at the same illuminance.

use crate::lighting::Fog;
use crate::snapshot::FogLayer;
use crate::view::{Hpr, Plane};
use cig_effects::optics::gaussian_path_integral_kg_m2;
use cig_effects::PuffInstance;
use cig_environment::nvg::LightSpectrum;
use cig_environment::stars::{planckian_xy, threshold_illuminance_lux};
use cig_geo::{EnuFrame, Geodetic};
use cig_terrain::culture::{CultureKind, CultureTile};
use cig_terrain::database::GeoidLookup;
use cig_terrain::PyramidLayout;
use glam::DVec3;
use std::f64::consts::{FRAC_PI_4, LN_2, PI, TAU};

/// How a light's intensity varies with direction. `LightPoint::intensity_cd` is the on-axis
/// (or in-sector) intensity.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Lobe {
    /// The same intensity every way.
    Omni,
    /// A beam: `I(a) = I max(back_fraction, exp(-ln 2 (a / half_width)^2))`, `a` the angle off
    /// `axis_ecef` (a Gaussian in angle with `half_width_deg` its half width at half maximum).
    Beam {
        axis_ecef: DVec3,
        half_width_deg: f32,
        back_fraction: f32,
    },
    /// A sector of azimuths about `axis_ecef` in the plane normal to `up_ecef`: full intensity
    /// within `half_angle_deg` of the axis (at any elevation), falling linearly to nothing over
    /// [`SECTOR_CUTOFF_DEG`] beyond.
    Sector {
        axis_ecef: DVec3,
        up_ecef: DVec3,
        half_angle_deg: f32,
    },
}

/// Width of a sector's cut-off beyond its edge, degrees (COLREGS Annex I §9(a): 1 to 3).
pub const SECTOR_CUTOFF_DEG: f64 = 2.0;

impl Lobe {
    /// The share of the on-axis intensity sent toward `dir` (from the light; any length).
    pub fn factor(&self, dir: DVec3) -> f64 {
        match *self {
            Lobe::Omni => 1.0,
            Lobe::Beam {
                axis_ecef,
                half_width_deg,
                back_fraction,
            } => {
                let norm = (dir.length_squared() * axis_ecef.length_squared()).sqrt();
                if norm.is_nan() || norm <= 0.0 {
                    return 1.0;
                }
                let angle = (dir.dot(axis_ecef) / norm).clamp(-1.0, 1.0).acos();
                let x = angle / f64::from(half_width_deg).to_radians();
                (-LN_2 * x * x).exp().max(f64::from(back_fraction))
            }
            Lobe::Sector {
                axis_ecef,
                up_ecef,
                half_angle_deg,
            } => {
                let up = up_ecef.normalize_or_zero();
                let h = dir - up * dir.dot(up);
                let a = axis_ecef - up * axis_ecef.dot(up);
                let (h_len, a_len) = (h.length(), a.length());
                if h_len.is_nan() || h_len <= 1e-9 * dir.length() || a_len.is_nan() || a_len <= 0.0
                {
                    // Straight up or down (or an axis along `up`): no azimuth; lit.
                    return 1.0;
                }
                let norm = h_len * a_len;
                let half = f64::from(half_angle_deg).to_radians();
                let cos_az = (h.dot(a) / norm).clamp(-1.0, 1.0);
                if cos_az >= half.cos() {
                    return 1.0;
                }
                let beyond = cos_az.acos() - half;
                (1.0 - beyond / SECTOR_CUTOFF_DEG.to_radians()).max(0.0)
            }
        }
    }
}

/// How a light flashes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Blink {
    Steady,
    /// On while `(t + phase_s) mod period_s < on_s`.
    Flash {
        period_s: f32,
        on_s: f32,
        phase_s: f32,
    },
}

impl Blink {
    /// Whether the light is lit at `unix_time_s`.
    pub fn is_on(&self, unix_time_s: f64) -> bool {
        match *self {
            Blink::Steady => true,
            Blink::Flash {
                period_s,
                on_s,
                phase_s,
            } => {
                let period = f64::from(period_s);
                if period.is_nan() || period <= 0.0 {
                    return true;
                }
                (unix_time_s + f64::from(phase_s)).rem_euclid(period) < f64::from(on_s)
            }
        }
    }
}

/// One light point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightPoint {
    pub position_ecef_m: DVec3,
    /// On-axis luminous intensity, cd.
    pub intensity_cd: f32,
    /// Linear sRGB of unit luminance (Y = 1).
    pub colour: [f32; 3],
    pub spectrum: LightSpectrum,
    pub lobe: Lobe,
    pub blink: Blink,
    /// Also lights the surfaces around it (flares, fires, headlights, street lamps): a
    /// candidate of [`local_lights`].
    pub lights_ground: bool,
}

/// Why a light cannot be used.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum LightError {
    #[error("light position {0:?} m is not finite")]
    Position([f64; 3]),
    #[error("light intensity {0} cd is negative or not finite")]
    Intensity(f32),
    #[error("light colour {0:?} has a negative or non-finite channel")]
    Colour([f32; 3]),
    #[error("light axis {0:?} is zero or not finite")]
    Axis([f64; 3]),
    #[error("light lobe angle {0} degrees is not in (0, 180]")]
    LobeAngle(f32),
    #[error("beam back fraction {0} is not in 0..=1")]
    BackFraction(f32),
    #[error("flash period {period_s} s, on {on_s} s, phase {phase_s} s: the period must be positive and the on time within it")]
    Flash {
        period_s: f32,
        on_s: f32,
        phase_s: f32,
    },
}

fn check_axis(axis: DVec3) -> Result<(), LightError> {
    if axis.is_finite() && axis.length_squared() > 0.0 {
        Ok(())
    } else {
        Err(LightError::Axis(axis.to_array()))
    }
}

fn check_angle(angle_deg: f32) -> Result<(), LightError> {
    if angle_deg.is_finite() && angle_deg > 0.0 && angle_deg <= 180.0 {
        Ok(())
    } else {
        Err(LightError::LobeAngle(angle_deg))
    }
}

impl LightPoint {
    /// Checks the light's values (one-line reason when something is out of range).
    pub fn validate(&self) -> Result<(), LightError> {
        if !self.position_ecef_m.is_finite() {
            return Err(LightError::Position(self.position_ecef_m.to_array()));
        }
        if !(self.intensity_cd.is_finite() && self.intensity_cd >= 0.0) {
            return Err(LightError::Intensity(self.intensity_cd));
        }
        if !self.colour.iter().all(|c| c.is_finite() && *c >= 0.0) {
            return Err(LightError::Colour(self.colour));
        }
        match self.lobe {
            Lobe::Omni => {}
            Lobe::Beam {
                axis_ecef,
                half_width_deg,
                back_fraction,
            } => {
                check_axis(axis_ecef)?;
                check_angle(half_width_deg)?;
                if !(0.0..=1.0).contains(&back_fraction) {
                    return Err(LightError::BackFraction(back_fraction));
                }
            }
            Lobe::Sector {
                axis_ecef,
                up_ecef,
                half_angle_deg,
            } => {
                check_axis(axis_ecef)?;
                check_axis(up_ecef)?;
                check_angle(half_angle_deg)?;
            }
        }
        if let Blink::Flash {
            period_s,
            on_s,
            phase_s,
        } = self.blink
        {
            let ok = period_s.is_finite()
                && period_s > 0.0
                && on_s.is_finite()
                && (0.0..=period_s).contains(&on_s)
                && phase_s.is_finite();
            if !ok {
                return Err(LightError::Flash {
                    period_s,
                    on_s,
                    phase_s,
                });
            }
        }
        Ok(())
    }

    /// Intensity toward `dir_from_light` (any length; zero means on axis) at `unix_time_s`,
    /// cd: the lobe's share of the on-axis intensity, nothing while a flash is dark.
    pub fn intensity_toward_cd(&self, dir_from_light: DVec3, unix_time_s: f64) -> f64 {
        if !self.blink.is_on(unix_time_s) {
            return 0.0;
        }
        let i = f64::from(self.intensity_cd);
        if dir_from_light == DVec3::ZERO {
            return i;
        }
        i * self.lobe.factor(dir_from_light)
    }
}

/// What lies between the eye and the lights.
#[derive(Clone, Copy, Debug)]
pub struct LightPath<'a> {
    /// The frame's global fog from the visibility (the clear air's extinction included).
    pub fog: &'a Fog,
    pub ground_fog: Option<FogLayer>,
    /// The obscurant puffs (positions relative to `puff_origin_ecef_m`).
    pub puffs: &'a [PuffInstance],
    pub puff_origin_ecef_m: DVec3,
}

/// A light to draw this frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DrawnLight {
    /// Eye-relative ECEF position, m.
    pub rel_m: [f32; 3],
    /// Illuminance at the eye, lux (through lobe, blink, fog, ground fog and obscurants).
    pub illuminance_lux: f32,
    /// `illuminance_lux * spectrum.nvg_per_lux()`: 2856 K-equivalent lux.
    pub nvg_lxa: f32,
    pub colour: [f32; 3],
    pub distance_m: f32,
}

/// Who looks at the lights.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Observer {
    /// The unaided eye adapted to a background of this luminance: a light is kept where its
    /// illuminance reaches the point-source threshold against it (Allard's law).
    Eye { background_cd_per_m2: f64 },
    /// An image intensifier: a light is kept where its NVG-weighted illuminance reaches this.
    Intensifier { threshold_lxa: f64 },
}

impl Observer {
    /// The faintest illuminance (lux) of a light of `spectrum` this observer sees.
    pub fn threshold_lux(&self, spectrum: LightSpectrum) -> f64 {
        match *self {
            Observer::Eye {
                background_cd_per_m2,
            } => threshold_illuminance_lux(background_cd_per_m2),
            Observer::Intensifier { threshold_lxa } => threshold_lxa / spectrum.nvg_per_lux(),
        }
    }
}

/// Mean earth radius, m (the curvature of the ground fog's heights).
const EARTH_RADIUS_M: f64 = 6_371_000.0;

/// Whether `e` falls short of `floor` (NaN falls short).
#[inline]
fn short_of(e: f64, floor: f64) -> bool {
    e.is_nan() || e < floor
}

/// Lights `lights` as the eye at `eye_ecef_m` (altitude `eye_alt_m` above the ellipsoid) sees
/// them at `unix_time_s`: those inside every plane of `frustum` (eye-relative, e.g.
/// [`crate::view::Camera::planes`]; an empty slice culls nothing), lit now, and bright enough
/// through `path` for `observer`, written to `out` (cleared first) in `lights`' order.
#[allow(
    clippy::too_many_arguments,
    reason = "each argument is an independent input of the frame: lights, eye, its altitude, frustum, time, path, observer, output"
)]
pub fn drawn_lights(
    lights: &[LightPoint],
    eye_ecef_m: DVec3,
    eye_alt_m: f64,
    frustum: &[Plane],
    unix_time_s: f64,
    path: &LightPath,
    observer: Observer,
    out: &mut Vec<DrawnLight>,
) {
    out.clear();
    if !eye_ecef_m.is_finite() {
        return;
    }
    let grid = PuffGrid::new(path.puffs, path.puff_origin_ecef_m - eye_ecef_m);
    let eye_threshold_lux = match observer {
        Observer::Eye {
            background_cd_per_m2,
        } => Some(threshold_illuminance_lux(background_cd_per_m2)),
        Observer::Intensifier { .. } => None,
    };
    let up = if path.ground_fog.is_some() {
        EnuFrame::new(Geodetic::from_ecef(eye_ecef_m)).enu_vector_to_ecef(DVec3::Z)
    } else {
        DVec3::Z
    };
    for light in lights {
        let rel = light.position_ecef_m - eye_ecef_m;
        if frustum
            .iter()
            .any(|p| short_of(p.normal.dot(rel), p.offset_m))
        {
            continue;
        }
        let d2 = rel.length_squared();
        if d2.is_nan() || d2 <= 0.0 || d2.is_infinite() {
            continue;
        }
        let d = d2.sqrt();
        let intensity = light.intensity_toward_cd(-rel, unix_time_s);
        if intensity.is_nan() || intensity <= 0.0 {
            continue;
        }
        let floor = eye_threshold_lux.unwrap_or_else(|| observer.threshold_lux(light.spectrum));
        let mut e = intensity / d2;
        if short_of(e, floor) {
            continue;
        }
        e *= path.fog.factor(d);
        if short_of(e, floor) {
            continue;
        }
        if let Some(layer) = path.ground_fog {
            let vertical = rel.dot(up);
            let horizontal2 = (d2 - vertical * vertical).max(0.0);
            let light_alt_m = eye_alt_m + vertical + horizontal2 / (2.0 * EARTH_RADIUS_M);
            if eye_alt_m < layer.top_m || light_alt_m < layer.top_m {
                e *= layer.transmittance(eye_alt_m, light_alt_m, d);
                if short_of(e, floor) {
                    continue;
                }
            }
        }
        e *= grid.transmittance(rel, d);
        if short_of(e, floor) {
            continue;
        }
        out.push(DrawnLight {
            rel_m: rel.as_vec3().to_array(),
            illuminance_lux: e as f32,
            nvg_lxa: (e * light.spectrum.nvg_per_lux()) as f32,
            colour: light.colour,
            distance_m: d as f32,
        });
    }
}

/// The distance (m) at which a light of `intensity_cd` toward the eye falls to `threshold_lux`
/// through `fog` (Allard's law `I T(d) / d^2 = E_t`); 0 where it is never seen.
pub fn allard_range_m(intensity_cd: f64, fog: &Fog, threshold_lux: f64) -> f64 {
    if intensity_cd.is_nan() || intensity_cd <= 0.0 || threshold_lux.is_nan() {
        return 0.0;
    }
    let mut hi = (intensity_cd / threshold_lux.max(1e-300)).sqrt();
    if !hi.is_finite() {
        return f64::INFINITY;
    }
    let mut lo = 0.0;
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if intensity_cd * fog.factor(mid) / (mid * mid) >= threshold_lux {
            lo = mid;
        } else {
            hi = mid;
        }
        if hi - lo <= 1e-9 * hi {
            break;
        }
    }
    lo
}

// ---------------------------------------------------------------------------------------------
// Obscurant puffs binned by direction from the eye.

/// Cells along a cube face's side.
const GRID_N: usize = 64;
/// A puff reaches this many sigmas from its centre (beyond: at most e^-8 of its centre depth).
const PUFF_REACH_SIGMAS: f64 = 4.0;
/// Puffs subtending more than this sine of angular radius (14.5°) are tested by every light.
const WIDE_PUFF_SIN: f64 = 0.25;
/// The renderer's largest centre optical depth (opacity 0.9999).
const MAX_PUFF_TAU: f64 = 9.21;

#[derive(Clone, Copy, Debug)]
struct PuffRel {
    /// Centre relative to the eye, m.
    centre: DVec3,
    sigma_m: f64,
    /// Centre optical depth times `2 pi sigma^2`: the "mass" of unit extinction whose path
    /// integral is the optical depth.
    depth_mass: f64,
    /// Optical depth of a whole line through the centre.
    centre_depth: f64,
    /// `1 / (2 sigma^2)`, 1/m².
    inv_two_sigma2: f64,
    reach_m: f64,
}

/// The puffs, and per cube-map cell of directions from the eye those whose cone meets it.
struct PuffGrid {
    puffs: Vec<PuffRel>,
    /// Tested by every light (around the eye or very wide).
    everywhere: Vec<u32>,
    /// CSR: cell `c`'s puffs are `list[start[c]..start[c + 1]]`.
    start: Vec<u32>,
    list: Vec<u32>,
}

/// The major axis, sign and the other two axes of cube face `face`.
fn face_axes(face: usize) -> (usize, f64, usize, usize) {
    let m = face / 2;
    let s = if face.is_multiple_of(2) { 1.0 } else { -1.0 };
    let (a, b) = match m {
        0 => (1, 2),
        1 => (0, 2),
        _ => (0, 1),
    };
    (m, s, a, b)
}

fn cell_index(u: f64) -> usize {
    (((u + 1.0) * 0.5 * GRID_N as f64).max(0.0) as usize).min(GRID_N - 1)
}

/// The cube-map cell of unit direction `dir`.
fn cell_of(dir: DVec3) -> usize {
    let abs = dir.abs();
    let m = if abs.x >= abs.y && abs.x >= abs.z {
        0
    } else if abs.y >= abs.z {
        1
    } else {
        2
    };
    let face = 2 * m + usize::from(dir[m] < 0.0);
    let (_, _, a, b) = face_axes(face);
    let major = abs[m].max(1e-300);
    (face * GRID_N + cell_index(dir[a] / major)) * GRID_N + cell_index(dir[b] / major)
}

/// The range of `tan(psi)`, `psi = atan2(p_a, p_m)`, over a cap of angular radius
/// `asin(sin_theta)` about a direction with components `p_a`, `p_m` in that plane, clipped to
/// a face (`|psi| <= 45°`); `None` where the cap misses the face's range.
fn face_range(pa: f64, pm: f64, sin_theta: f64) -> Option<(f64, f64)> {
    let rho = pa.hypot(pm);
    let (lo, hi) = if rho <= sin_theta {
        (-FRAC_PI_4, FRAC_PI_4)
    } else {
        let centre = pa.atan2(pm);
        let delta = (sin_theta / rho).asin();
        (centre - delta, centre + delta)
    };
    let (lo, hi) = (lo.max(-FRAC_PI_4), hi.min(FRAC_PI_4));
    (lo <= hi).then(|| (lo.tan(), hi.tan()))
}

impl PuffGrid {
    fn new(puffs: &[PuffInstance], origin_rel_eye: DVec3) -> PuffGrid {
        let mut rel = Vec::with_capacity(puffs.len());
        for p in puffs {
            let sigma = f64::from(p.radius_m) / cig_effects::system::RADIUS_SIGMAS;
            let opacity = f64::from(p.opacity).min(1.0);
            let tau = (-(1.0 - opacity).max(1e-300).ln()).min(MAX_PUFF_TAU);
            let centre = origin_rel_eye + DVec3::from(p.position_eye_m.map(f64::from));
            if !(sigma.is_finite() && sigma > 0.0 && tau > 0.0 && centre.is_finite()) {
                continue;
            }
            rel.push(PuffRel {
                centre,
                sigma_m: sigma,
                depth_mass: tau * TAU * sigma * sigma,
                centre_depth: tau,
                inv_two_sigma2: 0.5 / (sigma * sigma),
                reach_m: PUFF_REACH_SIGMAS * sigma,
            });
        }
        let cells = 6 * GRID_N * GRID_N;
        let mut everywhere = Vec::new();
        // (puff, face, i0, i1, j0, j1)
        let mut rects: Vec<(u32, usize, usize, usize, usize, usize)> = Vec::new();
        for (k, p) in rel.iter().enumerate() {
            let k = k as u32;
            let d = p.centre.length();
            let sin_theta = p.reach_m / d;
            if d.is_nan() || d <= p.reach_m || sin_theta > WIDE_PUFF_SIN {
                everywhere.push(k);
                continue;
            }
            let c = p.centre / d;
            for face in 0..6 {
                let (m, s, a, b) = face_axes(face);
                let (Some(u), Some(w)) = (
                    face_range(c[a], s * c[m], sin_theta),
                    face_range(c[b], s * c[m], sin_theta),
                ) else {
                    continue;
                };
                const PAD: f64 = 1e-9;
                rects.push((
                    k,
                    face,
                    cell_index(u.0 - PAD),
                    cell_index(u.1 + PAD),
                    cell_index(w.0 - PAD),
                    cell_index(w.1 + PAD),
                ));
            }
        }
        let mut start = vec![0u32; cells + 1];
        let each = |rects: &[(u32, usize, usize, usize, usize, usize)],
                    f: &mut dyn FnMut(usize, u32)| {
            for &(k, face, i0, i1, j0, j1) in rects {
                for i in i0..=i1 {
                    for j in j0..=j1 {
                        f((face * GRID_N + i) * GRID_N + j, k);
                    }
                }
            }
        };
        each(&rects, &mut |cell, _| start[cell + 1] += 1);
        for c in 0..cells {
            start[c + 1] += start[c];
        }
        let mut list = vec![0u32; start[cells] as usize];
        let mut fill: Vec<u32> = start[..cells].to_vec();
        each(&rects, &mut |cell, k| {
            list[fill[cell] as usize] = k;
            fill[cell] += 1;
        });
        PuffGrid {
            puffs: rel,
            everywhere,
            start,
            list,
        }
    }

    /// Transmittance of the segment from the eye to `rel` (`d` its length, > 0).
    fn transmittance(&self, rel: DVec3, d: f64) -> f64 {
        if self.puffs.is_empty() {
            return 1.0;
        }
        let dir = rel / d;
        let cell = cell_of(dir);
        let (from, to) = (self.start[cell] as usize, self.start[cell + 1] as usize);
        let mut depth = 0.0;
        for &k in self.everywhere.iter().chain(&self.list[from..to]) {
            let p = &self.puffs[k as usize];
            let along = p.centre.dot(dir);
            let t = along.clamp(0.0, d);
            let miss2 = (p.centre - dir * t).length_squared();
            if miss2 > p.reach_m * p.reach_m {
                continue;
            }
            if along >= p.reach_m && d - along >= p.reach_m {
                // The segment crosses the whole puff: the full line's column (the erf terms
                // are within 6e-5 of one).
                depth += p.centre_depth * (-miss2 * p.inv_two_sigma2).exp();
                continue;
            }
            depth +=
                gaussian_path_integral_kg_m2(DVec3::ZERO, rel, p.centre, p.depth_mass, p.sigma_m);
        }
        (-depth).exp()
    }
}

// ---------------------------------------------------------------------------------------------
// Lights that light the surfaces near the eye.

/// A light the renderer lights surfaces with.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LocalLight {
    /// Eye-relative ECEF position, m.
    pub rel_m: [f32; 3],
    /// On-axis intensity now (blink and flicker applied), cd.
    pub intensity_cd: f32,
    /// `intensity_cd * spectrum.nvg_per_lux()`: 2856 K-equivalent cd.
    pub nvg_intensity_cd: f32,
    pub colour: [f32; 3],
    /// Unit beam axis, ECEF; zero for an omnidirectional light.
    pub axis: [f32; 3],
    /// Cosine of the beam's half width at half maximum (the fall-off is
    /// `max(back_fraction, exp(-ln 2 (acos(cos a) / acos(cos_half_width))^2))`); -1 for an
    /// omnidirectional light.
    pub cos_half_width: f32,
    /// The beam's floor (1 for an omnidirectional light).
    pub back_fraction: f32,
}

/// The lights that light the ground (`lights_ground`), lit at `unix_time_s`, strongest first by
/// their reach at the eye, `I / (d^2 + 1 m^2)`, at most `max`.
pub fn local_lights(
    lights: &[LightPoint],
    eye_ecef_m: DVec3,
    unix_time_s: f64,
    max: usize,
) -> Vec<LocalLight> {
    let mut ranked: Vec<(f64, usize)> = lights
        .iter()
        .enumerate()
        .filter(|(_, l)| l.lights_ground && l.blink.is_on(unix_time_s))
        .filter_map(|(index, l)| {
            let d2 = (l.position_ecef_m - eye_ecef_m).length_squared();
            let score = f64::from(l.intensity_cd) / (d2 + 1.0);
            (score.is_finite() && score > 0.0).then_some((score, index))
        })
        .collect();
    if ranked.len() > max && max > 0 {
        ranked.select_nth_unstable_by(max - 1, |a, b| b.0.total_cmp(&a.0));
    }
    ranked.truncate(max);
    ranked.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
    ranked
        .into_iter()
        .filter_map(|(_, index)| lights.get(index))
        .map(|l| {
            let (axis, cos_half_width, back_fraction) = match l.lobe {
                Lobe::Beam {
                    axis_ecef,
                    half_width_deg,
                    back_fraction,
                } => (
                    axis_ecef.normalize_or_zero().as_vec3().to_array(),
                    f64::from(half_width_deg).to_radians().cos() as f32,
                    back_fraction,
                ),
                Lobe::Omni | Lobe::Sector { .. } => ([0.0; 3], -1.0, 1.0),
            };
            LocalLight {
                rel_m: (l.position_ecef_m - eye_ecef_m).as_vec3().to_array(),
                intensity_cd: l.intensity_cd,
                nvg_intensity_cd: (f64::from(l.intensity_cd) * l.spectrum.nvg_per_lux()) as f32,
                colour: l.colour,
                axis,
                cos_half_width,
                back_fraction,
            }
        })
        .collect()
}

// ---------------------------------------------------------------------------------------------
// Colours.

/// Linear sRGB of unit luminance of CIE 1931 chromaticity `(x, y)`; out-of-gamut channels are
/// clipped at zero and the luminance restored.
pub fn colour_of_xy(x: f64, y: f64) -> [f32; 3] {
    let y = y.max(1e-6);
    let big_x = x / y;
    let big_z = (1.0 - x - y) / y;
    let r = (3.240_454_2 * big_x - 1.537_138_5 - 0.498_531_4 * big_z).max(0.0);
    let g = (-0.969_266_0 * big_x + 1.876_010_8 + 0.041_556_0 * big_z).max(0.0);
    let b = (0.055_643_4 * big_x - 0.204_025_9 + 1.057_225_2 * big_z).max(0.0);
    let luminance = (0.212_672_9 * r + 0.715_152_2 * g + 0.072_175_0 * b).max(1e-9);
    [
        (r / luminance) as f32,
        (g / luminance) as f32,
        (b / luminance) as f32,
    ]
}

/// Linear sRGB of unit luminance of a Planckian radiator at `temperature_k` (clamped to the
/// 1667-25000 K of Kim et al.'s fit).
pub fn colour_of_temperature_k(temperature_k: f64) -> [f32; 3] {
    let t = if temperature_k.is_nan() {
        6500.0
    } else {
        temperature_k.clamp(1667.0, 25_000.0)
    };
    let (x, y) = planckian_xy(t);
    colour_of_xy(x, y)
}

/// Signal red (aviation red, tail lamps): CIE (0.68, 0.32), clipped into sRGB.
fn signal_red() -> [f32; 3] {
    colour_of_xy(0.68, 0.32)
}

/// Signal green (aviation and navigation green): CIE (0.28, 0.50), a bluish green.
fn signal_green() -> [f32; 3] {
    colour_of_xy(0.28, 0.50)
}

// ---------------------------------------------------------------------------------------------
// Entity lights.

/// Which lights an entity carries.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum EntityLightSet {
    GroundVehicle,
    Aircraft,
    Ship,
    #[default]
    None,
}

/// An entity's light switches (the host's or the DIS appearance's); all off by default.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct LightSwitches {
    pub head: bool,
    pub tail: bool,
    pub brake: bool,
    pub blackout: bool,
    pub blackout_brake: bool,
    pub spot: bool,
    pub landing: bool,
    pub navigation: bool,
    pub anti_collision: bool,
    pub strobe: bool,
    /// A ship's running (navigation) lights.
    pub running: bool,
    pub interior: bool,
}

/// Halogen low-beam headlamp, on axis, cd (ECE R112 / SAE J1383: 10-20 kcd at the hot spot).
pub const HEADLAMP_CD: f32 = 15_000.0;
/// Headlamp beam half width at half maximum, degrees (about 10° horizontally).
pub const HEADLAMP_HALF_WIDTH_DEG: f32 = 10.0;
/// Headlamp aim below the body's forward axis, degrees (low beam: about 1 %).
pub const HEADLAMP_AIM_DOWN_DEG: f64 = 1.0;
/// Tail lamp, cd (FMVSS 108: 2-18 cd on axis).
pub const TAIL_LAMP_CD: f32 = 5.0;
/// Stop lamp, cd (FMVSS 108: 80-300 cd on axis).
pub const STOP_LAMP_CD: f32 = 80.0;
/// Tail and stop lamps' half width, degrees (their photometry spans ±20° H, ±10° V).
pub const SIGNAL_LAMP_HALF_WIDTH_DEG: f32 = 30.0;
/// Blackout marker, cd: seen to about 350 m by the dark-adapted eye (1.5e-8 lx).
pub const BLACKOUT_MARKER_CD: f32 = 0.002;
/// Blackout drive lamp, cd, aimed 10° down with a 15° half width (lights the road ahead
/// to about 0.05 lx at 30 m).
pub const BLACKOUT_DRIVE_CD: f32 = 50.0;
/// Searchlight, cd, 3° half width.
pub const SEARCHLIGHT_CD: f32 = 200_000.0;
/// Aircraft landing light, cd, 6° half width (a 250 W PAR-46's order of magnitude).
pub const LANDING_LIGHT_CD: f32 = 200_000.0;
/// Aircraft forward position lights, cd (14 CFR 25.1391: 40 cd within 10° of the nose).
pub const POSITION_LIGHT_FORWARD_CD: f32 = 40.0;
/// Aircraft rear position light, cd (14 CFR 25.1391: 20 cd).
pub const POSITION_LIGHT_REAR_CD: f32 = 20.0;
/// Anti-collision light's effective intensity, cd (14 CFR 25.1401(f): at least 400 cd).
pub const ANTI_COLLISION_EFFECTIVE_CD: f32 = 400.0;
/// Anti-collision flashes a minute (14 CFR 25.1401(e): 40-100).
pub const ANTI_COLLISION_FLASHES_PER_MIN: f32 = 50.0;
/// Beacon flash length, s.
pub const BEACON_FLASH_S: f32 = 0.15;
/// Strobe flash length, s (a xenon flash lasts about a millisecond; drawn 0.05 s long, at the
/// same effective intensity, so a 60 Hz frame sees each flash).
pub const STROBE_FLASH_S: f32 = 0.05;
/// Blondel-Rey's constant, s (14 CFR 25.1401(f)).
const BLONDEL_REY_S: f32 = 0.2;

/// The on-intensity of a rectangular flash of `on_s` with effective intensity `effective_cd`
/// (Blondel-Rey: `I_e = I t / (0.2 + t)`).
pub fn flash_intensity_cd(effective_cd: f32, on_s: f32) -> f32 {
    effective_cd * (BLONDEL_REY_S + on_s) / on_s.max(1e-6)
}

/// A navigation light's intensity for a range of `range_nm` nautical miles (COLREGS Annex I §8:
/// `I = 3.43e6 T D^2 K^-D`, `T = 2e-7` lx, `K = 0.8`).
pub fn colregs_intensity_cd(range_nm: f64) -> f64 {
    3.43e6 * 2e-7 * range_nm * range_nm * 0.8f64.powf(-range_nm)
}

/// The ranges (NM) of a vessel's masthead light, sidelights and sternlight by its length
/// (COLREGS Rule 22).
fn colregs_ranges_nm(length_m: f64) -> (f64, f64, f64) {
    if length_m >= 50.0 {
        (6.0, 3.0, 3.0)
    } else if length_m >= 20.0 {
        (5.0, 2.0, 2.0)
    } else if length_m >= 12.0 {
        (3.0, 2.0, 2.0)
    } else {
        (2.0, 1.0, 2.0)
    }
}

/// SplitMix64 finaliser.
fn mix64(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// A hash in `[0, 1)`.
fn unit_hash(x: u64) -> f64 {
    (mix64(x) >> 11) as f64 / (1u64 << 53) as f64
}

/// The lights of an entity of `set` with `switches`, its body origin at `position` (altitude
/// above the ellipsoid) turned by `orientation`, appended to `out`.
///
/// Body frame (CIGI's): x forward, y right, z down; the origin lies on the ground (a ship's at
/// its waterline) under the body's centre, as the models' (`crate::models`). `half_extent_m`
/// is the body's half length (x), half width (y; an aircraft's half span) and half height:
/// the body fills `-hx..hx`, `-hy..hy` and `0..2 hz` above the origin. Flashing lights take a
/// phase hashed from `entity_id`, so two aircraft do not flash together.
pub fn entity_lights(
    set: EntityLightSet,
    switches: &LightSwitches,
    entity_id: u32,
    position: Geodetic,
    orientation: Hpr,
    half_extent_m: [f32; 3],
    out: &mut Vec<LightPoint>,
) {
    let o = orientation;
    let turned = o.heading_deg.is_finite() && o.pitch_deg.is_finite() && o.roll_deg.is_finite();
    if set == EntityLightSet::None || !position.to_ecef().is_finite() || !turned {
        return;
    }
    let enu = EnuFrame::new(position);
    let (f, r, u) = orientation.axes_enu();
    let forward = enu.enu_vector_to_ecef(f);
    let right = enu.enu_vector_to_ecef(r);
    let up = enu.enu_vector_to_ecef(u);
    let origin = enu.origin_ecef();
    let [hx, hy, hz] = half_extent_m.map(|v| {
        let v = f64::from(v).abs();
        if v.is_finite() {
            v
        } else {
            0.0
        }
    });
    let at = |x: f64, y: f64, h: f64| origin + forward * x + right * y + up * h;
    // Forward turned `deg` to the right about the body's up.
    let azimuth = |deg: f64| {
        let (s, c) = deg.to_radians().sin_cos();
        forward * c + right * s
    };
    let pitched_down = |deg: f64| {
        let (s, c) = deg.to_radians().sin_cos();
        forward * c - up * s
    };
    let phase = unit_hash(u64::from(entity_id) ^ 0x4C49_4748_5453);
    let light = |position_ecef_m: DVec3,
                 intensity_cd: f32,
                 colour: [f32; 3],
                 spectrum: LightSpectrum,
                 lobe: Lobe,
                 lights_ground: bool| LightPoint {
        position_ecef_m,
        intensity_cd,
        colour,
        spectrum,
        lobe,
        blink: Blink::Steady,
        lights_ground,
    };
    let beam = |axis_ecef: DVec3, half_width_deg: f32| Lobe::Beam {
        axis_ecef,
        half_width_deg,
        back_fraction: 0.0,
    };
    let sector = |axis_ecef: DVec3, half_angle_deg: f32| Lobe::Sector {
        axis_ecef,
        up_ecef: up,
        half_angle_deg,
    };
    let white = colour_of_temperature_k(3200.0);
    let tungsten = colour_of_temperature_k(2856.0);
    let red = signal_red();
    let green = signal_green();
    let s = switches;
    match set {
        EntityLightSet::GroundVehicle => {
            let h = (0.35 * 2.0 * hz).clamp(0.5, 1.2).min(2.0 * hz.max(0.25));
            for side in [-1.0, 1.0] {
                let y = side * 0.75 * hy;
                if s.head {
                    out.push(light(
                        at(hx, y, h),
                        HEADLAMP_CD,
                        white,
                        LightSpectrum::Halogen,
                        beam(pitched_down(HEADLAMP_AIM_DOWN_DEG), HEADLAMP_HALF_WIDTH_DEG),
                        true,
                    ));
                }
                if s.tail {
                    out.push(light(
                        at(-hx, y, h),
                        TAIL_LAMP_CD,
                        red,
                        LightSpectrum::Incandescent,
                        beam(-forward, SIGNAL_LAMP_HALF_WIDTH_DEG),
                        false,
                    ));
                }
                if s.brake {
                    out.push(light(
                        at(-hx, y, h),
                        STOP_LAMP_CD,
                        red,
                        LightSpectrum::Incandescent,
                        beam(-forward, SIGNAL_LAMP_HALF_WIDTH_DEG),
                        false,
                    ));
                }
                if s.blackout {
                    out.push(light(
                        at(hx, 0.85 * y, h),
                        BLACKOUT_MARKER_CD,
                        tungsten,
                        LightSpectrum::Incandescent,
                        beam(forward, 20.0),
                        false,
                    ));
                    out.push(light(
                        at(-hx, 0.85 * y, h),
                        BLACKOUT_MARKER_CD,
                        red,
                        LightSpectrum::Incandescent,
                        beam(-forward, 20.0),
                        false,
                    ));
                }
                if s.blackout_brake {
                    out.push(light(
                        at(-hx, 0.85 * y, h + 0.1),
                        BLACKOUT_MARKER_CD * 4.0,
                        red,
                        LightSpectrum::Incandescent,
                        beam(-forward, 20.0),
                        false,
                    ));
                }
            }
            if s.blackout {
                out.push(light(
                    at(hx, -0.6 * hy, h),
                    BLACKOUT_DRIVE_CD,
                    tungsten,
                    LightSpectrum::Incandescent,
                    beam(pitched_down(10.0), 15.0),
                    true,
                ));
            }
            if s.spot {
                out.push(light(
                    at(0.5 * hx, 0.0, 2.0 * hz),
                    SEARCHLIGHT_CD,
                    white,
                    LightSpectrum::Halogen,
                    beam(pitched_down(2.0), 3.0),
                    true,
                ));
            }
            if s.interior {
                out.push(light(
                    at(0.0, 0.0, hz),
                    2.0,
                    tungsten,
                    LightSpectrum::Incandescent,
                    Lobe::Omni,
                    false,
                ));
            }
        }
        EntityLightSet::Aircraft => {
            if s.navigation {
                out.push(light(
                    at(0.0, -hy, hz),
                    POSITION_LIGHT_FORWARD_CD,
                    red,
                    LightSpectrum::Incandescent,
                    sector(azimuth(-55.0), 55.0),
                    false,
                ));
                out.push(light(
                    at(0.0, hy, hz),
                    POSITION_LIGHT_FORWARD_CD,
                    green,
                    LightSpectrum::Incandescent,
                    sector(azimuth(55.0), 55.0),
                    false,
                ));
                out.push(light(
                    at(-hx, 0.0, hz),
                    POSITION_LIGHT_REAR_CD,
                    tungsten,
                    LightSpectrum::Incandescent,
                    sector(-forward, 70.0),
                    false,
                ));
            }
            let period_s = 60.0 / ANTI_COLLISION_FLASHES_PER_MIN;
            if s.anti_collision {
                for (h, offset) in [(2.0 * hz, 0.0), (0.0, 0.5)] {
                    out.push(LightPoint {
                        blink: Blink::Flash {
                            period_s,
                            on_s: BEACON_FLASH_S,
                            phase_s: ((phase + offset) * f64::from(period_s)) as f32,
                        },
                        ..light(
                            at(0.0, 0.0, h),
                            flash_intensity_cd(ANTI_COLLISION_EFFECTIVE_CD, BEACON_FLASH_S),
                            red,
                            LightSpectrum::Incandescent,
                            Lobe::Omni,
                            false,
                        )
                    });
                }
            }
            if s.strobe {
                for side in [-1.0, 1.0] {
                    out.push(LightPoint {
                        blink: Blink::Flash {
                            period_s,
                            on_s: STROBE_FLASH_S,
                            phase_s: ((phase + 0.25) * f64::from(period_s)) as f32,
                        },
                        ..light(
                            at(0.0, side * hy, hz),
                            flash_intensity_cd(ANTI_COLLISION_EFFECTIVE_CD, STROBE_FLASH_S),
                            colour_of_temperature_k(6000.0),
                            LightSpectrum::Xenon,
                            Lobe::Omni,
                            false,
                        )
                    });
                }
            }
            if s.landing {
                for side in [-1.0, 1.0] {
                    out.push(light(
                        at(0.3 * hx, side * 0.25 * hy, 0.5 * hz),
                        LANDING_LIGHT_CD,
                        white,
                        LightSpectrum::Halogen,
                        beam(pitched_down(3.0), 6.0),
                        true,
                    ));
                }
            }
            if s.spot {
                out.push(light(
                    at(0.6 * hx, 0.0, 0.0),
                    SEARCHLIGHT_CD,
                    white,
                    LightSpectrum::Halogen,
                    beam(pitched_down(15.0), 3.0),
                    true,
                ));
            }
            if s.interior {
                out.push(light(
                    at(0.0, 0.0, hz),
                    5.0,
                    tungsten,
                    LightSpectrum::Incandescent,
                    Lobe::Omni,
                    false,
                ));
            }
        }
        EntityLightSet::Ship => {
            if s.running || s.navigation {
                let (masthead_nm, side_nm, stern_nm) = colregs_ranges_nm(2.0 * hx);
                out.push(light(
                    at(0.3 * hx, 0.0, 2.0 * hz),
                    colregs_intensity_cd(masthead_nm) as f32,
                    tungsten,
                    LightSpectrum::Incandescent,
                    sector(forward, 112.5),
                    false,
                ));
                for (side, colour) in [(-1.0, red), (1.0, green)] {
                    out.push(light(
                        at(0.2 * hx, side * hy, 1.2 * hz),
                        colregs_intensity_cd(side_nm) as f32,
                        colour,
                        LightSpectrum::Incandescent,
                        sector(azimuth(side * 56.25), 56.25),
                        false,
                    ));
                }
                out.push(light(
                    at(-hx, 0.0, hz),
                    colregs_intensity_cd(stern_nm) as f32,
                    tungsten,
                    LightSpectrum::Incandescent,
                    sector(-forward, 67.5),
                    false,
                ));
            }
            if s.spot {
                out.push(light(
                    at(0.5 * hx, 0.0, 2.0 * hz),
                    SEARCHLIGHT_CD,
                    white,
                    LightSpectrum::Halogen,
                    beam(pitched_down(2.0), 3.0),
                    true,
                ));
            }
            if s.interior {
                out.push(light(
                    at(0.0, 0.0, 1.5 * hz),
                    20.0,
                    tungsten,
                    LightSpectrum::Incandescent,
                    Lobe::Omni,
                    false,
                ));
            }
        }
        EntityLightSet::None => {}
    }
}

// ---------------------------------------------------------------------------------------------
// Street and settlement lights.

/// Natural illuminance below which street lamps burn, lux (ANSI C136.10: 1.5 fc nominal
/// turn-on).
pub const STREET_LIGHTS_ON_LUX: f64 = 16.0;

/// Whether street and settlement lights burn under `natural_illuminance_lux` (photocontrol).
pub fn street_lights_on(natural_illuminance_lux: f64) -> bool {
    natural_illuminance_lux < STREET_LIGHTS_ON_LUX
}

/// High-pressure sodium street lamp at the nadir, cd.
pub const STREET_LAMP_CD: f32 = 3000.0;
/// Its Gaussian half width from the nadir, degrees (semi-cutoff: 1050 cd at 80°, 790 cd at
/// 90°).
pub const STREET_LAMP_HALF_WIDTH_DEG: f32 = 65.0;
/// Porch light, cd (60 W incandescent: 700 lm over 4π).
pub const PORCH_LIGHT_CD: f32 = 60.0;

/// Which culture carries lights.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CultureLightRules {
    /// Share of power poles with a street lamp (hashed by position): one in five, the
    /// yard lights of farms and the lamps of junctions (rural roads are not lit end to end).
    pub pole_lamp_share: f64,
    /// Share of houses with a porch light (hashed by position).
    pub house_light_share: f64,
}

impl Default for CultureLightRules {
    fn default() -> Self {
        CultureLightRules {
            pole_lamp_share: 0.2,
            house_light_share: 0.6,
        }
    }
}

/// The street and settlement lights of one resident culture tile, appended to `out`: a
/// function of the tile alone, so made once when the tile becomes resident and kept with it
/// (drawn while [`street_lights_on`]). Heights: the items' bases (above mean sea level, set on
/// load) plus the geoid's undulation.
pub fn culture_lights(
    layout: &PyramidLayout,
    geoid: &GeoidLookup,
    culture: &CultureTile,
    rules: &CultureLightRules,
    out: &mut Vec<LightPoint>,
) {
    let (dlat, dlon) = layout.spacing_deg(0);
    let (row0, col0) = layout.finest_index_of_post(culture.key, 0, 0);
    let south = layout.grid.south_lat_deg + row0 as f64 * dlat;
    let west = layout.grid.west_lon_deg + col0 as f64 * dlon;
    let sodium = colour_of_temperature_k(2000.0);
    for item in &culture.items {
        if !matches!(item.kind, CultureKind::PowerPole | CultureKind::House) {
            continue;
        }
        let key = ((u64::from(item.fi.to_bits()) << 32) | u64::from(item.fj.to_bits()))
            ^ mix64((u64::from(culture.key.row) << 32) | u64::from(culture.key.col));
        let lat = south + f64::from(item.fi) * dlat;
        let lon = west + f64::from(item.fj) * dlon;
        let base = Geodetic::new(
            lat,
            lon,
            f64::from(item.base_m) + geoid.undulation_m(lat, lon),
        );
        if !base.to_ecef().is_finite() {
            continue;
        }
        let enu = EnuFrame::new(base);
        let up = enu.enu_vector_to_ecef(DVec3::Z);
        let height = f64::from(item.height_m).max(0.0);
        match item.kind {
            CultureKind::PowerPole => {
                if unit_hash(key ^ 0x504F_4C45) >= rules.pole_lamp_share {
                    continue;
                }
                out.push(LightPoint {
                    position_ecef_m: enu.enu_to_ecef(DVec3::new(0.0, 0.0, (height - 0.3).max(0.0))),
                    intensity_cd: STREET_LAMP_CD,
                    colour: sodium,
                    spectrum: LightSpectrum::Sodium,
                    lobe: Lobe::Beam {
                        axis_ecef: -up,
                        half_width_deg: STREET_LAMP_HALF_WIDTH_DEG,
                        back_fraction: 0.005,
                    },
                    blink: Blink::Steady,
                    lights_ground: true,
                });
            }
            _ => {
                let pick = unit_hash(key ^ 0x48_4F55_5345);
                if pick >= rules.house_light_share {
                    continue;
                }
                // The outward normal of one long side (the length runs along the heading).
                let side = if unit_hash(key ^ 0x5349_4445) < 0.5 {
                    -1.0
                } else {
                    1.0
                };
                let normal_heading = item.heading_deg().to_radians() + side * 0.5 * PI;
                let normal_enu = DVec3::new(normal_heading.sin(), normal_heading.cos(), 0.0);
                let offset = normal_enu * (0.5 * f64::from(item.width_m) + 0.1)
                    + DVec3::Z * 2.2f64.min(0.8 * height);
                let led = unit_hash(key ^ 0x4C_4544) < 0.5;
                out.push(LightPoint {
                    position_ecef_m: enu.enu_to_ecef(offset),
                    intensity_cd: PORCH_LIGHT_CD,
                    colour: colour_of_temperature_k(if led { 3500.0 } else { 2700.0 }),
                    spectrum: if led {
                        LightSpectrum::LedWhite
                    } else {
                        LightSpectrum::Incandescent
                    },
                    lobe: Lobe::Beam {
                        axis_ecef: enu.enu_vector_to_ecef(normal_enu),
                        half_width_deg: 70.0,
                        back_fraction: 0.02,
                    },
                    blink: Blink::Steady,
                    lights_ground: false,
                });
            }
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Flares and fires.

/// An illumination flare: ignites at `start`, falls at `descent_mps` under its parachute and
/// burns for `burn_s`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Flare {
    /// Where it ignites (altitude above the ellipsoid).
    pub start: Geodetic,
    pub ignition_unix_s: f64,
    pub burn_s: f32,
    pub intensity_cd: f32,
    pub descent_mps: f32,
}

impl Flare {
    /// A 155 mm M485 illuminating projectile's candle: about 1 Mcd for 120 s, falling 5 m/s
    /// (TM 43-0001-28 / FM 6-40; burst about 600 m up, out near the ground).
    pub fn artillery_155mm(start: Geodetic, ignition_unix_s: f64) -> Flare {
        Flare {
            start,
            ignition_unix_s,
            burn_s: 120.0,
            intensity_cd: 1_000_000.0,
            descent_mps: 5.0,
        }
    }

    /// An 81 mm M853A1 illuminating mortar round's candle: about 500 kcd for 60 s, falling
    /// about 2.5 m/s (FM 3-22.90).
    pub fn mortar_81mm(start: Geodetic, ignition_unix_s: f64) -> Flare {
        Flare {
            start,
            ignition_unix_s,
            burn_s: 60.0,
            intensity_cd: 500_000.0,
            descent_mps: 2.5,
        }
    }

    /// Where the flare is at `unix_time_s` (at its start before ignition, where it went out
    /// after).
    pub fn position_at(&self, unix_time_s: f64) -> Geodetic {
        let t = (unix_time_s - self.ignition_unix_s).clamp(0.0, f64::from(self.burn_s).max(0.0));
        let mut p = self.start;
        p.alt_m -= f64::from(self.descent_mps) * t;
        p
    }

    /// The flare's light at `unix_time_s`: `None` before ignition, after its burn time, or once
    /// it is at or below `terrain_alt_below_m` (the surface under it, above the ellipsoid).
    pub fn light_at(
        &self,
        unix_time_s: f64,
        terrain_alt_below_m: Option<f64>,
    ) -> Option<LightPoint> {
        let t = unix_time_s - self.ignition_unix_s;
        if t.is_nan() || t < 0.0 || t > f64::from(self.burn_s) {
            return None;
        }
        let p = self.position_at(unix_time_s);
        if terrain_alt_below_m.is_some_and(|ground| p.alt_m <= ground) {
            return None;
        }
        let position_ecef_m = p.to_ecef();
        position_ecef_m.is_finite().then_some(LightPoint {
            position_ecef_m,
            intensity_cd: self.intensity_cd.max(0.0),
            // The sodium yellow of a magnesium-sodium nitrate candle.
            colour: colour_of_xy(0.50, 0.44),
            spectrum: LightSpectrum::Flare,
            lobe: Lobe::Omni,
            blink: Blink::Steady,
            lights_ground: true,
        })
    }
}

/// A lamp's colour and spectrum by name: `white` (a white LED, 5000 K), `warm` (a tungsten
/// lamp, 2856 K), `red` and `green` (signal lamps: LEDs, CIE x,y 0.69,0.30 and 0.17,0.70),
/// `amber` (filtered tungsten, 0.58,0.41), `blue` (a blue LED, 0.14,0.08) or `sodium` (a
/// high-pressure sodium street lamp, 2000 K). The names of the command line and the scenario.
pub fn named_lamp(name: &str) -> Option<([f32; 3], LightSpectrum)> {
    Some(match name.to_ascii_lowercase().as_str() {
        "white" => (colour_of_temperature_k(5000.0), LightSpectrum::LedWhite),
        "warm" => (colour_of_temperature_k(2856.0), LightSpectrum::Incandescent),
        "red" => (colour_of_xy(0.69, 0.30), LightSpectrum::LedRed),
        "green" => (colour_of_xy(0.17, 0.70), LightSpectrum::LedWhite),
        "amber" => (colour_of_xy(0.58, 0.41), LightSpectrum::Incandescent),
        "blue" => (colour_of_xy(0.14, 0.08), LightSpectrum::LedWhite),
        "sodium" => (colour_of_temperature_k(2000.0), LightSpectrum::Sodium),
        _ => return None,
    })
}

/// The lamp names [`named_lamp`] knows, for messages.
pub const LAMP_NAMES: &str = "white, warm, red, green, amber, blue or sodium";

/// An all-round lamp of `intensity_cd` at `position` named as [`named_lamp`] knows it,
/// checked ([`LightPoint::validate`]).
pub fn omni_lamp(
    position: Geodetic,
    intensity_cd: f32,
    (colour, spectrum): ([f32; 3], LightSpectrum),
) -> Result<LightPoint, LightError> {
    let light = LightPoint {
        position_ecef_m: position.to_ecef(),
        intensity_cd,
        colour,
        spectrum,
        lobe: Lobe::Omni,
        blink: Blink::Steady,
        lights_ground: false,
    };
    light.validate()?;
    Ok(light)
}

/// Radiant fraction of a sooty hydrocarbon fire's heat release (SFPE Handbook: 0.3-0.4).
const FIRE_RADIANT_FRACTION: f64 = 0.3;
/// Luminous efficacy of a 1500 K grey body, lm/W (Planck's law against V(λ)).
const FIRE_LUMENS_PER_WATT: f64 = 0.1;

/// A fire's mean intensity, cd, from its heat release (MW): `Q chi_r K / 4 pi`.
pub fn fire_intensity_cd(heat_release_mw: f64) -> f64 {
    heat_release_mw.max(0.0) * 1e6 * FIRE_RADIANT_FRACTION * FIRE_LUMENS_PER_WATT / (4.0 * PI)
}

/// The light of a fire of `heat_release_mw` and base `diameter_m` burning at `position` (its
/// base) at `unix_time_s`: at half Heskestad's flame height, flickering at `1.5 / sqrt(D)` Hz
/// with phases from `seed` (a function of seed and time only). A burning car: about 4 MW, 2 m.
pub fn fire_light(
    position: Geodetic,
    heat_release_mw: f32,
    diameter_m: f32,
    seed: u64,
    unix_time_s: f64,
) -> LightPoint {
    let q_kw = f64::from(heat_release_mw).max(0.0) * 1000.0;
    let d = f64::from(diameter_m).max(0.1);
    let flame_height_m = (0.235 * q_kw.powf(0.4) - 1.02 * d).max(1.0);
    let frequency_hz = 1.5 / d.sqrt();
    let mut flicker = 1.0;
    for (k, (ratio, amplitude)) in [(1.0, 0.2), (2.13, 0.1), (3.71, 0.06)]
        .into_iter()
        .enumerate()
    {
        let phase = unit_hash(seed ^ (0x4649_5245 + k as u64));
        // Cycles taken modulo one before the sine, so the sines keep their precision.
        let cycles = (frequency_hz * ratio * unix_time_s + phase).rem_euclid(1.0);
        flicker += amplitude * (TAU * cycles).sin();
    }
    let mut p = position;
    p.alt_m += 0.5 * flame_height_m;
    LightPoint {
        position_ecef_m: p.to_ecef(),
        intensity_cd: (fire_intensity_cd(f64::from(heat_release_mw)) * flicker) as f32,
        colour: colour_of_temperature_k(1800.0),
        spectrum: LightSpectrum::Flame,
        lobe: Lobe::Omni,
        blink: Blink::Steady,
        lights_ground: true,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lighting::FogMode;
    use crate::view::{FovDeg, View};
    use cig_terrain::culture::CultureItem;
    use cig_terrain::database::GeoidGrid;
    use cig_terrain::raster::GeoGrid;
    use cig_terrain::TileKey;
    use proptest::prelude::*;

    /// A moonless night's sky background, cd/m².
    const NIGHT_CD_PER_M2: f64 = 1e-3;
    const T0: f64 = 1_700_000_000.0;

    fn eye() -> Geodetic {
        Geodetic::new(45.0, 7.0, 200.0)
    }

    fn enu_point(e: f64, n: f64, u: f64) -> DVec3 {
        EnuFrame::new(eye()).enu_to_ecef(DVec3::new(e, n, u))
    }

    fn omni(position_ecef_m: DVec3, intensity_cd: f32) -> LightPoint {
        LightPoint {
            position_ecef_m,
            intensity_cd,
            colour: [1.0; 3],
            spectrum: LightSpectrum::Incandescent,
            lobe: Lobe::Omni,
            blink: Blink::Steady,
            lights_ground: false,
        }
    }

    fn fog(visibility_m: f64) -> Fog {
        Fog::from_visibility(FogMode::Exponential, visibility_m)
    }

    fn clear_path(fog: &Fog) -> LightPath<'_> {
        LightPath {
            fog,
            ground_fog: None,
            puffs: &[],
            puff_origin_ecef_m: DVec3::ZERO,
        }
    }

    fn night() -> Observer {
        Observer::Eye {
            background_cd_per_m2: NIGHT_CD_PER_M2,
        }
    }

    /// What `drawn_lights` makes of `lights` seen from `eye()` with no frustum.
    fn drawn(lights: &[LightPoint], path: &LightPath, observer: Observer) -> Vec<DrawnLight> {
        let mut out = vec![DrawnLight {
            rel_m: [9.0; 3],
            illuminance_lux: 9.0,
            nvg_lxa: 9.0,
            colour: [9.0; 3],
            distance_m: 9.0,
        }];
        drawn_lights(
            lights,
            eye().to_ecef(),
            eye().alt_m,
            &[],
            T0,
            path,
            observer,
            &mut out,
        );
        out
    }

    fn puff(centre_rel_origin: DVec3, radius_m: f32, opacity: f32) -> PuffInstance {
        PuffInstance {
            position_eye_m: centre_rel_origin.as_vec3().to_array(),
            radius_m,
            colour_rgb: [0.1; 3],
            opacity,
            emissive: 0.0,
            temperature_k: 290.0,
            kind: 0,
            effect: 0,
        }
    }

    #[test]
    fn allard_keeps_a_1000_cd_light_at_5_km_in_clear_air_and_drops_it_in_2_km_visibility() {
        let light = [omni(enu_point(5000.0, 0.0, 0.0), 1000.0)];
        let clear = fog(40_000.0);
        let kept = drawn(&light, &clear_path(&clear), night());
        assert_eq!(kept.len(), 1);
        let expected = 1000.0 / 25e6 * clear.factor(5000.0);
        assert!((f64::from(kept[0].illuminance_lux) / expected - 1.0).abs() < 1e-4);
        assert!((kept[0].distance_m - 5000.0).abs() < 0.01);
        let rel = DVec3::from(kept[0].rel_m.map(f64::from));
        assert!((rel - (light[0].position_ecef_m - eye().to_ecef())).length() < 0.01);
        let thick = fog(2000.0);
        assert!(drawn(&light, &clear_path(&thick), night()).is_empty());
        // In daylight even clear air hides it: the threshold rises with the background.
        let day = Observer::Eye {
            background_cd_per_m2: 5000.0,
        };
        assert!(drawn(&light, &clear_path(&clear), day).is_empty());
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(64))]

        #[test]
        fn the_range_a_light_is_dropped_at_grows_with_its_intensity(
            intensity in 1.0f64..1e5,
            more in 1.05f64..100.0,
            visibility in 300.0f64..60_000.0,
        ) {
            let fog = fog(visibility);
            let threshold = threshold_illuminance_lux(NIGHT_CD_PER_M2);
            let near = allard_range_m(intensity, &fog, threshold);
            let far = allard_range_m(intensity * more, &fog, threshold);
            prop_assert!(near > 0.0 && far > near);
            // drawn_lights keeps it just inside that range and drops it just beyond.
            let path = clear_path(&fog);
            let at = |d: f64| [omni(enu_point(0.0, d, 0.0), intensity as f32)];
            prop_assert_eq!(drawn(&at(near * 0.99), &path, night()).len(), 1);
            prop_assert!(drawn(&at(near * 1.01), &path, night()).is_empty());
        }

        #[test]
        fn the_direction_grid_finds_every_puff_a_segment_meets(
            seed in 0u64..1000,
            count in 1usize..60,
        ) {
            // Puffs and lights all around the eye; the grid's answer is the brute force's.
            let mut s = seed;
            let mut next = || { s = mix64(s); (s >> 11) as f64 / (1u64 << 53) as f64 };
            let origin = DVec3::new(10.0, -20.0, 5.0);
            let puffs: Vec<PuffInstance> = (0..count)
                .map(|_| {
                    let c = DVec3::new(next() - 0.5, next() - 0.5, next() - 0.5) * 800.0;
                    puff(c - origin, (2.0 + 60.0 * next()) as f32, (0.2 + 0.79 * next()) as f32)
                })
                .collect();
            let grid = PuffGrid::new(&puffs, origin);
            prop_assert_eq!(grid.puffs.len(), count);
            let mut dimmed = 0;
            for k in 0..300 {
                let rel = if k % 3 == 0 {
                    // Aimed through (or near) a puff, ending before or beyond it.
                    let p = grid.puffs[k % count];
                    let jitter = DVec3::new(next() - 0.5, next() - 0.5, next() - 0.5) * p.reach_m;
                    (p.centre + jitter) * (0.8 + next())
                } else {
                    DVec3::new(next() - 0.5, next() - 0.5, next() - 0.5) * 1200.0
                };
                let d = rel.length();
                let dir = rel / d;
                // Every puff within its reach of the segment, and every puff at all.
                let (mut reached, mut all) = (0.0, 0.0);
                for p in &grid.puffs {
                    let depth = gaussian_path_integral_kg_m2(DVec3::ZERO, rel, p.centre, p.depth_mass, p.sigma_m);
                    let t = p.centre.dot(dir).clamp(0.0, d);
                    if (p.centre - dir * t).length() <= p.reach_m {
                        reached += depth;
                    }
                    all += depth;
                }
                let fast = grid.transmittance(rel, d);
                prop_assert!((fast.ln() + reached).abs() <= 1e-4 * reached + 1e-12, "{} {}", fast, reached);
                // Beyond 4 sigma a puff adds at most 9.21 e^-8 = 0.003 of depth.
                prop_assert!(all - reached <= 0.0032 * count as f64);
                if reached > 0.01 {
                    dimmed += 1;
                }
            }
            prop_assert!(dimmed > 0, "some segments cross puffs");
        }
    }

    #[test]
    fn a_beam_is_brighter_on_axis_than_30_degrees_off_and_keeps_its_back_fraction() {
        let axis = DVec3::new(0.0, 1.0, 0.0);
        let light = LightPoint {
            lobe: Lobe::Beam {
                axis_ecef: axis * 3.0,
                half_width_deg: 10.0,
                back_fraction: 0.01,
            },
            ..omni(DVec3::ZERO, 10_000.0)
        };
        let on = light.intensity_toward_cd(axis, T0);
        let (s, c) = 30f64.to_radians().sin_cos();
        let off = light.intensity_toward_cd(DVec3::new(s, c, 0.0), T0);
        let half = light.intensity_toward_cd(
            DVec3::new(10f64.to_radians().sin(), 10f64.to_radians().cos(), 0.0),
            T0,
        );
        assert!((on - 10_000.0).abs() < 1e-6);
        assert!(off < 0.05 * on && off >= 99.99);
        assert!(
            (half - 5000.0).abs() < 1.0,
            "half maximum at the half width: {half}"
        );
        assert!((light.intensity_toward_cd(-axis, T0) - 100.0).abs() < 1e-3);
    }

    #[test]
    fn a_strobe_is_lit_during_its_on_time_only() {
        let strobe = LightPoint {
            blink: Blink::Flash {
                period_s: 1.25,
                on_s: 0.0625,
                phase_s: 0.25,
            },
            ..omni(enu_point(0.0, 300.0, 0.0), 2000.0)
        };
        // On while (t + 0.25) mod 1.25 < 0.0625: from 1.0 to 1.0625 s past each multiple of
        // 1.25 s (times that f32 and f64 hold exactly).
        let base = 1250.0 * 1_000_000.0;
        let dir = DVec3::X;
        for k in 0..5 {
            let t0 = base + 1.25 * f64::from(k);
            assert!(strobe.intensity_toward_cd(dir, t0 + 1.01) > 0.0);
            assert!(strobe.intensity_toward_cd(dir, t0 + 1.05) > 0.0);
            assert_eq!(strobe.intensity_toward_cd(dir, t0 + 1.07), 0.0);
            assert_eq!(strobe.intensity_toward_cd(dir, t0 + 0.5), 0.0);
        }
        let fog = fog(40_000.0);
        let seen = |t: f64| {
            let mut out = Vec::new();
            drawn_lights(
                &[strobe],
                eye().to_ecef(),
                eye().alt_m,
                &[],
                t,
                &clear_path(&fog),
                night(),
                &mut out,
            );
            out.len()
        };
        assert_eq!(seen(base + 1.02), 1);
        assert_eq!(seen(base + 0.2), 0);
    }

    #[test]
    fn puffs_between_the_eye_and_a_light_dim_it_and_puffs_beside_the_line_do_not() {
        let light = [omni(enu_point(0.0, 2000.0, 0.0), 1000.0)];
        let fog = fog(40_000.0);
        let clear = drawn(&light, &clear_path(&fog), night())[0].illuminance_lux;
        let origin = enu_point(50.0, 0.0, 0.0);
        let on_line = puff(enu_point(0.0, 1000.0, 0.0) - origin, 25.0, 0.9);
        let beside = puff(enu_point(300.0, 1000.0, 0.0) - origin, 25.0, 0.9);
        let path = |puffs| LightPath {
            fog: &fog,
            ground_fog: None,
            puffs,
            puff_origin_ecef_m: origin,
        };
        let through = drawn(&light, &path(std::slice::from_ref(&on_line)), night());
        let dimmed = through[0].illuminance_lux;
        // The full column through the centre: optical depth -ln(1 - 0.9).
        assert!((dimmed / clear - 0.1).abs() < 0.01, "{dimmed} {clear}");
        let aside = drawn(&light, &path(std::slice::from_ref(&beside)), night());
        assert_eq!(aside[0].illuminance_lux, clear);
        // A puff behind the light does not dim it either.
        let behind = puff(enu_point(0.0, 2500.0, 0.0) - origin, 25.0, 0.9);
        let back = drawn(&light, &path(std::slice::from_ref(&behind)), night());
        assert_eq!(back[0].illuminance_lux, clear);
        // A thick enough cloud hides a faint light altogether.
        let faint = [omni(enu_point(0.0, 2000.0, 0.0), 0.2)];
        assert_eq!(drawn(&faint, &path(&[]), night()).len(), 1);
        let thick = puff(enu_point(0.0, 1000.0, 0.0) - origin, 25.0, 0.9999);
        assert!(drawn(&faint, &path(&[thick, thick]), night()).is_empty());
    }

    #[test]
    fn a_ground_fog_layer_dims_a_light_inside_it_and_not_one_above_it() {
        let fog = fog(40_000.0);
        let layer = FogLayer {
            top_m: 150.0,
            visibility_m: 500.0,
        };
        let path = LightPath {
            ground_fog: Some(layer),
            ..clear_path(&fog)
        };
        // The eye at 200 m; one light 100 m lower, in the layer, one 100 m higher.
        let low = omni(enu_point(0.0, 1000.0, -100.0), 5000.0);
        let high = omni(enu_point(0.0, 1000.0, 100.0), 5000.0);
        let open = drawn(&[low, high], &clear_path(&fog), night());
        let fogged = drawn(&[low, high], &path, night());
        assert_eq!(fogged.len(), 2);
        assert!(fogged[0].illuminance_lux < 0.5 * open[0].illuminance_lux);
        assert!((fogged[1].illuminance_lux / open[1].illuminance_lux - 1.0).abs() < 1e-6);
    }

    #[test]
    fn the_frustum_culls_lights_outside_it() {
        let view = View {
            eye: eye(),
            orientation: Hpr::default(),
            fov: FovDeg::symmetric(60.0, 40.0),
            width_px: 1280,
            height_px: 720,
        };
        let camera = view.camera();
        let ahead = omni(enu_point(0.0, 1000.0, 0.0), 1000.0);
        let behind = omni(enu_point(0.0, -1000.0, 0.0), 1000.0);
        let aside = omni(enu_point(1000.0, 100.0, 0.0), 1000.0);
        let fog = fog(40_000.0);
        let mut out = Vec::new();
        drawn_lights(
            &[behind, ahead, aside],
            eye().to_ecef(),
            eye().alt_m,
            &camera.planes,
            T0,
            &clear_path(&fog),
            night(),
            &mut out,
        );
        assert_eq!(out.len(), 1);
        assert!((out[0].distance_m - 1000.0).abs() < 0.01);
    }

    #[test]
    fn an_intensifier_weights_each_light_by_its_spectrum() {
        let fog = fog(40_000.0);
        let at = enu_point(0.0, 1000.0, 0.0);
        let flame = LightPoint {
            spectrum: LightSpectrum::Flame,
            ..omni(at, 100.0)
        };
        let led = LightPoint {
            spectrum: LightSpectrum::LedWhite,
            ..omni(at, 100.0)
        };
        let seen = drawn(&[flame, led], &clear_path(&fog), night());
        assert_eq!(seen.len(), 2);
        for (d, l) in seen.iter().zip([flame, led]) {
            let expected = f64::from(d.illuminance_lux) * l.spectrum.nvg_per_lux();
            assert!((f64::from(d.nvg_lxa) / expected - 1.0).abs() < 1e-5);
        }
        // A threshold between the two weighted illuminances keeps only the brighter one.
        let (a, b) = (f64::from(seen[0].nvg_lxa), f64::from(seen[1].nvg_lxa));
        let observer = Observer::Intensifier {
            threshold_lxa: (a * b).sqrt(),
        };
        let kept = drawn(&[flame, led], &clear_path(&fog), observer);
        assert_eq!(kept.len(), 1);
        assert_eq!(kept[0].nvg_lxa, seen[usize::from(b > a)].nvg_lxa);
    }

    #[test]
    fn a_flare_falls_at_its_descent_rate_and_is_gone_after_its_burn_or_on_the_ground() {
        let start = Geodetic::new(45.0, 7.0, 800.0);
        let flare = Flare::artillery_155mm(start, T0);
        assert!(flare.light_at(T0 - 1.0, None).is_none());
        for t in [0.0, 10.0, 60.0, 119.0] {
            let light = flare.light_at(T0 + t, None).expect("burning");
            let p = Geodetic::from_ecef(light.position_ecef_m);
            assert!(
                (p.alt_m - (800.0 - 5.0 * t)).abs() < 1e-3,
                "{t}: {}",
                p.alt_m
            );
            assert!((p.lat_deg - 45.0).abs() < 1e-9 && (p.lon_deg - 7.0).abs() < 1e-9);
            assert!(light.lights_ground && light.intensity_cd == 1_000_000.0);
            assert!(light.validate().is_ok());
        }
        assert!(flare.light_at(T0 + 121.0, None).is_none());
        // Ground at 400 m: reached after 80 s.
        assert!(flare.light_at(T0 + 79.0, Some(400.0)).is_some());
        assert!(flare.light_at(T0 + 81.0, Some(400.0)).is_none());
        let mortar = Flare::mortar_81mm(start, T0);
        assert!(mortar.light_at(T0 + 59.0, None).is_some());
        assert!(mortar.light_at(T0 + 61.0, None).is_none());
    }

    #[test]
    fn a_fire_flickers_deterministically_about_its_mean_intensity() {
        let base = Geodetic::new(45.0, 7.0, 100.0);
        let samples: Vec<f64> = (0..2000)
            .map(|k| {
                let l = fire_light(base, 4.0, 2.0, 7, T0 + 0.01 * f64::from(k));
                f64::from(l.intensity_cd)
            })
            .collect();
        let mean = samples.iter().sum::<f64>() / samples.len() as f64;
        let expected = fire_intensity_cd(4.0);
        assert!(
            expected > 1000.0 && expected < 100_000.0,
            "thousands of cd: {expected}"
        );
        assert!((mean / expected - 1.0).abs() < 0.1, "{mean} {expected}");
        let (lo, hi) = samples
            .iter()
            .fold((f64::MAX, f64::MIN), |(a, b), &v| (a.min(v), b.max(v)));
        assert!(hi / lo > 1.3, "it flickers: {lo}..{hi}");
        let again = fire_light(base, 4.0, 2.0, 7, T0 + 0.37);
        assert_eq!(again, fire_light(base, 4.0, 2.0, 7, T0 + 0.37));
        assert_ne!(again, fire_light(base, 4.0, 2.0, 8, T0 + 0.37));
        let p = Geodetic::from_ecef(again.position_ecef_m);
        assert!(p.alt_m > 101.0, "above its base, in the flame: {}", p.alt_m);
        assert!(again.lights_ground && again.spectrum == LightSpectrum::Flame);
    }

    #[test]
    fn street_lights_burn_at_night_and_not_by_day() {
        assert!(street_lights_on(0.01));
        assert!(street_lights_on(3.0));
        assert!(!street_lights_on(1e4));
        assert!(!street_lights_on(100.0));
    }

    fn item(kind: CultureKind, fi: f32, fj: f32, height_m: f32) -> CultureItem {
        CultureItem {
            kind,
            variant: 0,
            heading: 16384,
            fi,
            fj,
            height_m,
            width_m: 8.0,
            length_m: 10.0,
            base_m: 300.0,
            sink_m: 0.0,
        }
    }

    #[test]
    fn culture_lights_put_a_sodium_lamp_on_lit_poles_and_a_light_on_some_houses() {
        let grid = GeoGrid {
            south_lat_deg: 45.0,
            west_lon_deg: 7.0,
            dlat_deg: 1.0 / 3600.0,
            dlon_deg: 1.0 / 3600.0,
            rows: 257,
            cols: 257,
        };
        let layout = PyramidLayout::new(grid, 64);
        let geoid = GeoidLookup::new(&GeoidGrid::zero());
        let key = TileKey {
            level: 0,
            row: 1,
            col: 2,
        };
        let mut items = vec![item(CultureKind::PowerPole, 10.5, 20.5, 10.0)];
        items.push(item(CultureKind::ConiferTree, 11.5, 20.5, 15.0));
        for k in 0..1000 {
            items.push(item(
                CultureKind::House,
                0.06 * (k / 32) as f32,
                0.06 * (k % 32) as f32,
                7.0,
            ));
        }
        let tile = CultureTile { key, items };
        // Every pole lit (the default lights one in five).
        let rules = CultureLightRules {
            pole_lamp_share: 1.0,
            ..CultureLightRules::default()
        };
        let mut lights = Vec::new();
        culture_lights(&layout, &geoid, &tile, &rules, &mut lights);
        let lamps: Vec<&LightPoint> = lights
            .iter()
            .filter(|l| l.spectrum == LightSpectrum::Sodium)
            .collect();
        assert_eq!(lamps.len(), 1);
        let p = Geodetic::from_ecef(lamps[0].position_ecef_m);
        assert!(
            (p.alt_m - 309.7).abs() < 1e-3,
            "at the pole's top: {}",
            p.alt_m
        );
        assert!((p.lat_deg - (45.0 + (64.0 + 10.5) / 3600.0)).abs() < 1e-9);
        assert!((p.lon_deg - (7.0 + (128.0 + 20.5) / 3600.0)).abs() < 1e-9);
        // Its beam points down: brighter toward the ground than toward the horizon.
        let down = -EnuFrame::new(p).enu_vector_to_ecef(DVec3::Z);
        let level = EnuFrame::new(p).enu_vector_to_ecef(DVec3::X);
        let lamp = lamps[0];
        assert!(lamp.intensity_toward_cd(down, T0) > 3.0 * lamp.intensity_toward_cd(level, T0));
        let houses = lights.len() - 1;
        assert!(
            (500..=700).contains(&houses),
            "about 60 % of houses: {houses}"
        );
        assert!(lights.iter().all(|l| l.validate().is_ok()));
        let mut again = Vec::new();
        culture_lights(&layout, &geoid, &tile, &rules, &mut again);
        assert_eq!(lights, again);
        let none = CultureLightRules {
            pole_lamp_share: 0.0,
            house_light_share: 0.0,
        };
        again.clear();
        culture_lights(&layout, &geoid, &tile, &none, &mut again);
        assert!(again.is_empty());
    }

    #[test]
    fn entity_lights_follow_the_switches_and_the_heading() {
        let at = Geodetic::new(45.0, 7.0, 300.0);
        let east = Hpr {
            heading_deg: 90.0,
            ..Hpr::default()
        };
        let size = [2.5, 1.2, 1.0];
        let mut out = Vec::new();
        entity_lights(
            EntityLightSet::GroundVehicle,
            &LightSwitches::default(),
            1,
            at,
            east,
            size,
            &mut out,
        );
        assert!(out.is_empty(), "all switched off");
        let head = LightSwitches {
            head: true,
            ..LightSwitches::default()
        };
        entity_lights(
            EntityLightSet::GroundVehicle,
            &head,
            1,
            at,
            east,
            size,
            &mut out,
        );
        assert_eq!(out.len(), 2);
        let frame = EnuFrame::new(at);
        let east_ecef = frame.enu_vector_to_ecef(DVec3::X);
        for l in &out {
            let Lobe::Beam { axis_ecef, .. } = l.lobe else {
                panic!("a headlight is a beam");
            };
            assert!(axis_ecef.normalize().dot(east_ecef) > 0.999, "points east");
            let enu = frame.ecef_to_enu(l.position_ecef_m);
            assert!((enu.x - 2.5).abs() < 1e-6, "at the front: {enu}");
            assert!(l.lights_ground && l.validate().is_ok());
        }
        // Seen from ahead it is bright, from behind dark.
        let ahead = out[0].intensity_toward_cd(east_ecef, T0);
        assert!(ahead > 10_000.0 && out[0].intensity_toward_cd(-east_ecef, T0) < 1.0);

        let all = LightSwitches {
            head: true,
            tail: true,
            brake: true,
            blackout: true,
            blackout_brake: true,
            spot: true,
            interior: true,
            ..LightSwitches::default()
        };
        out.clear();
        entity_lights(
            EntityLightSet::GroundVehicle,
            &all,
            1,
            at,
            east,
            size,
            &mut out,
        );
        let reds = out
            .iter()
            .filter(|l| l.colour[0] > 3.0 * l.colour[1])
            .count();
        assert_eq!(
            reds, 8,
            "tail, stop, blackout and blackout stop markers, two each"
        );
        assert!(out.iter().all(|l| l.validate().is_ok()));

        // An aircraft's navigation lights: red seen from its left, green from its right.
        let nav = LightSwitches {
            navigation: true,
            anti_collision: true,
            ..LightSwitches::default()
        };
        out.clear();
        entity_lights(
            EntityLightSet::Aircraft,
            &nav,
            9,
            at,
            east,
            [20.0, 17.0, 3.0],
            &mut out,
        );
        assert_eq!(out.len(), 5);
        let north = frame.enu_vector_to_ecef(DVec3::Y);
        let south = -north;
        let (red, green) = (&out[0], &out[1]);
        assert!(red.intensity_toward_cd(north, T0) > 39.0);
        assert_eq!(red.intensity_toward_cd(south, T0), 0.0);
        assert!(green.intensity_toward_cd(south, T0) > 39.0);
        assert_eq!(green.intensity_toward_cd(north, T0), 0.0);
        // The beacons flash 50 times a minute.
        let beacon = out[3];
        let lit = (0..1200)
            .filter(|k| beacon.intensity_toward_cd(north, T0 + 0.01 * f64::from(*k)) > 0.0)
            .count();
        assert!((140..=160).contains(&lit), "0.15 s of each 1.2 s: {lit}");
    }

    #[test]
    fn a_ships_sidelights_show_their_sectors() {
        let at = Geodetic::new(45.0, 7.0, 0.0);
        let north = Hpr::default();
        let running = LightSwitches {
            running: true,
            ..LightSwitches::default()
        };
        let mut out = Vec::new();
        entity_lights(
            EntityLightSet::Ship,
            &running,
            3,
            at,
            north,
            [60.0, 10.0, 15.0],
            &mut out,
        );
        assert_eq!(out.len(), 4);
        let frame = EnuFrame::new(at);
        let dir = |az_deg: f64| {
            let (s, c) = az_deg.to_radians().sin_cos();
            frame.enu_vector_to_ecef(DVec3::new(s, c, 0.0))
        };
        let (masthead, port, starboard, stern) = (out[0], out[1], out[2], out[3]);
        assert!(
            (masthead.intensity_cd - 94.0).abs() < 1.0,
            "6 NM: {}",
            masthead.intensity_cd
        );
        assert!(
            (port.intensity_cd - 12.0).abs() < 0.5,
            "3 NM: {}",
            port.intensity_cd
        );
        // Port (red) from dead ahead to 22.5° abaft the port beam.
        assert!(port.intensity_toward_cd(dir(-1.0), T0) > 11.0);
        assert!(port.intensity_toward_cd(dir(-111.0), T0) > 11.0);
        assert_eq!(port.intensity_toward_cd(dir(-116.0), T0), 0.0);
        assert_eq!(port.intensity_toward_cd(dir(20.0), T0), 0.0);
        assert!(starboard.intensity_toward_cd(dir(90.0), T0) > 11.0);
        assert_eq!(starboard.intensity_toward_cd(dir(-90.0), T0), 0.0);
        assert!(masthead.intensity_toward_cd(dir(110.0), T0) > 90.0);
        assert_eq!(masthead.intensity_toward_cd(dir(180.0), T0), 0.0);
        assert!(stern.intensity_toward_cd(dir(180.0), T0) > 11.0);
        assert_eq!(stern.intensity_toward_cd(dir(90.0), T0), 0.0);
        assert!((colregs_intensity_cd(3.0) - 12.0).abs() < 0.5);
    }

    #[test]
    fn local_lights_are_the_strongest_ground_lights_near_the_eye() {
        let e = eye().to_ecef();
        let lights = [
            LightPoint {
                lights_ground: true,
                ..omni(enu_point(0.0, 100.0, 0.0), 1000.0)
            },
            LightPoint {
                lights_ground: true,
                ..omni(enu_point(0.0, 10.0, 0.0), 1000.0)
            },
            // Bright but not a ground light.
            omni(enu_point(0.0, 5.0, 0.0), 1e6),
            LightPoint {
                lights_ground: true,
                lobe: Lobe::Beam {
                    axis_ecef: DVec3::X,
                    half_width_deg: 10.0,
                    back_fraction: 0.0,
                },
                ..omni(enu_point(0.0, 1000.0, 0.0), 1e6)
            },
            // Dark now.
            LightPoint {
                lights_ground: true,
                blink: Blink::Flash {
                    period_s: 1.0,
                    on_s: 0.1,
                    phase_s: 0.5,
                },
                ..omni(enu_point(0.0, 1.0, 0.0), 1e6)
            },
        ];
        let local = local_lights(&lights, e, T0, 2);
        assert_eq!(local.len(), 2);
        assert!(
            (local[0].rel_m[0].powi(2) + local[0].rel_m[1].powi(2) + local[0].rel_m[2].powi(2)
                - 100.0)
                .abs()
                < 0.1
        );
        assert_eq!(local[0].cos_half_width, -1.0);
        assert_eq!(local[1].intensity_cd, 1e6);
        assert!((local[1].cos_half_width - 10f32.to_radians().cos()).abs() < 1e-6);
        assert_eq!(local[1].axis, [1.0, 0.0, 0.0]);
        assert_eq!(local_lights(&lights, e, T0, 10).len(), 3);
        assert!(local_lights(&lights, e, T0, 0).is_empty());
    }

    #[test]
    fn validate_rejects_bad_lights() {
        let good = omni(DVec3::new(6.4e6, 0.0, 0.0), 10.0);
        assert!(good.validate().is_ok());
        let with = |f: &dyn Fn(&mut LightPoint)| {
            let mut l = good;
            f(&mut l);
            l.validate()
        };
        assert!(matches!(
            with(&|l| l.intensity_cd = -1.0),
            Err(LightError::Intensity(_))
        ));
        assert!(matches!(
            with(&|l| l.intensity_cd = f32::NAN),
            Err(LightError::Intensity(_))
        ));
        assert!(matches!(
            with(&|l| l.intensity_cd = f32::INFINITY),
            Err(LightError::Intensity(_))
        ));
        assert!(matches!(
            with(&|l| l.position_ecef_m.x = f64::NAN),
            Err(LightError::Position(_))
        ));
        assert!(matches!(
            with(&|l| l.colour[1] = -0.5),
            Err(LightError::Colour(_))
        ));
        let beam = |axis: DVec3, w: f32, b: f32| Lobe::Beam {
            axis_ecef: axis,
            half_width_deg: w,
            back_fraction: b,
        };
        assert!(matches!(
            with(&|l| l.lobe = beam(DVec3::ZERO, 10.0, 0.0)),
            Err(LightError::Axis(_))
        ));
        assert!(matches!(
            with(&|l| l.lobe = beam(DVec3::X, 0.0, 0.0)),
            Err(LightError::LobeAngle(_))
        ));
        assert!(matches!(
            with(&|l| l.lobe = beam(DVec3::X, 5.0, 1.5)),
            Err(LightError::BackFraction(_))
        ));
        let flash = |p: f32, on: f32| Blink::Flash {
            period_s: p,
            on_s: on,
            phase_s: 0.0,
        };
        assert!(matches!(
            with(&|l| l.blink = flash(0.0, 0.0)),
            Err(LightError::Flash { .. })
        ));
        assert!(matches!(
            with(&|l| l.blink = flash(1.0, 2.0)),
            Err(LightError::Flash { .. })
        ));
        assert!(with(&|l| l.blink = flash(1.0, 0.5)).is_ok());
        // A bad light costs nothing but itself in drawn_lights.
        let fog = fog(40_000.0);
        let mut nan = omni(enu_point(0.0, 500.0, 0.0), 100.0);
        nan.position_ecef_m.y = f64::NAN;
        let kept = drawn(
            &[nan, omni(enu_point(0.0, 500.0, 0.0), 100.0)],
            &clear_path(&fog),
            night(),
        );
        assert_eq!(kept.len(), 1);
    }

    /// `cargo test -p cig-scene --release lights -- --ignored --nocapture`
    #[test]
    #[ignore = "a timing, not a check: run in release by hand"]
    fn drawn_lights_cost_for_10k_lights_and_200_puffs() {
        let mut s = 42u64;
        let mut next = || {
            s = mix64(s);
            (s >> 11) as f64 / (1u64 << 53) as f64
        };
        let lights: Vec<LightPoint> = (0..10_000)
            .map(|_| {
                let az = (next() - 0.5) * 1.6;
                let d = 100.0 + 20_000.0 * next() * next();
                omni(
                    enu_point(d * az.sin(), d * az.cos(), -150.0 + 10.0 * next()),
                    (20.0 + 3000.0 * next()) as f32,
                )
            })
            .collect();
        let origin = eye().to_ecef();
        let puffs: Vec<PuffInstance> = (0..200)
            .map(|k| {
                let plume = f64::from(k / 50);
                let along = f64::from(k % 50) * 12.0;
                let c = enu_point(
                    -600.0 + 400.0 * plume + along * 0.3,
                    1500.0 + 500.0 * plume,
                    -150.0 + along,
                );
                puff(c - origin, 10.0 + 0.3 * along as f32, 0.5)
            })
            .collect();
        let view = View {
            eye: eye(),
            orientation: Hpr::default(),
            fov: FovDeg::symmetric(90.0, 60.0),
            width_px: 1920,
            height_px: 1080,
        };
        let camera = view.camera();
        let fog = fog(20_000.0);
        let path = LightPath {
            fog: &fog,
            ground_fog: Some(FogLayer {
                top_m: 80.0,
                visibility_m: 3000.0,
            }),
            puffs: &puffs,
            puff_origin_ecef_m: origin,
        };
        let mut out = Vec::new();
        let runs = 100;
        // The fastest of the runs and their median (the machine may be shared).
        let mut time = |path: &LightPath, what: &str| {
            let mut each: Vec<f64> = (0..runs)
                .map(|k| {
                    let start = std::time::Instant::now();
                    drawn_lights(
                        &lights,
                        origin,
                        eye().alt_m,
                        &camera.planes,
                        T0 + f64::from(k),
                        path,
                        night(),
                        &mut out,
                    );
                    start.elapsed().as_secs_f64() * 1e3
                })
                .collect();
            assert!(!out.is_empty());
            each.sort_by(f64::total_cmp);
            println!(
                "drawn_lights, {what}: {} lights, {} kept: {:.3} ms fastest, {:.3} ms median",
                lights.len(),
                out.len(),
                each[0],
                each[each.len() / 2]
            );
        };
        time(&clear_path(&fog), "fog only");
        time(&LightPath { puffs: &[], ..path }, "fog and ground fog");
        time(&path, "fog, ground fog and 200 puffs");
    }
}
