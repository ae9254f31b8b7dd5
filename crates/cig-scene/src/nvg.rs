//! The night-vision (image intensifier) channel: the goggle's settings and the tube's model,
//! as the renderer's intensifier pass applies it.
//!
//! Algorithm. The scene is drawn with every light source weighted by the photocathode's
//! response (`cig_environment::nvg`: 2856 K-equivalent lux, lx_A) and every material by its
//! NVG-band reflectance ([`nvg_reflectance`]), so a pixel holds `πL` in lx_A (what a white
//! Lambert surface under that many lx_A shows). The tube then:
//!
//! 1. **Photoelectrons.** The photocathode illuminance behind the objective is
//!    `E_pc = πL T / (4 N²)` (f-number `N`, transmission `T`); a photocathode area `a` gives
//!    `S E_pc a / (e f)` photoelectrons a frame (sensitivity `S` in A/lm at 2856 K, frame rate
//!    `f`). With the reference tube (2000 µA/lm, f/1.23, T 0.8, 17.6 µm pixels, 60 Hz) a 30 %
//!    Lambertian scene under 10⁻³ lx gives 2.6 photoelectrons per tube pixel per frame
//!    (`../shared/references/sensors.md`). A display pixel counts the tube pixels its solid
//!    angle covers, so the grain follows the view, not the display's pixels. The count is drawn
//!    from a Poisson law per pixel and frame (temporal: never a fixed pattern).
//! 2. **Microchannel plate.** Each photoelectron's gain varies (excess noise factor
//!    [`Tube::mcp_excess_noise`], about 1.7 for Gen III): the summed signal of `n`
//!    photoelectrons gets a further spread of `sqrt(n (F - 1))`.
//! 3. **Automatic brightness control.** The output is proportional to the input until the
//!    control's range is reached; inside it the gain is set so the view's (trimmed log-) mean
//!    shows at [`OUTPUT_KEY`], followed with the time constant [`Tube::abc_tau_s`]. The gain
//!    tops out where the mean scene `πL` falls below [`Tube::abc_floor_lxa`] (starlight: the
//!    picture then dims and scintillates), and bottoms out above
//!    [`Tube::abc_ceiling_lxa`] (bright-source protection's limit): beyond it the phosphor
//!    saturates. So a quarter moon and a full moon show alike, a flare or a flash washes the
//!    picture out until the control pulls the gain down, and daylight saturates the tube.
//! 4. **Halo.** A point source's photoelectrons bounce off the microchannel plate's face and
//!    land in a disc around it: a halo of nearly constant angular size, 1°48′ ± 7′ across
//!    (Craig et al., SPIE 5800, 2005), growing weakly with intensity (Zacher et al.):
//!    [`halo_diameter_deg`]. It carries [`HALO_FRACTION`] of the source's signal.
//! 5. **Limits of the tube.** Its modulation transfer (a Gaussian point spread whose MTF falls
//!    to 3 % at the limiting resolution: 64 lp/mm over an 18 mm photocathode for a 40° field),
//!    the goggle's circular field with a black surround, and the phosphor's colour: P43
//!    (Gd₂O₂S:Tb, CIE x 0.333 y 0.556, green) or P45 "white phosphor" (x 0.253 y 0.312).
//!
//! Sources: thesis 000 ch. IV.C and V.C.3 (the NPSNET goggles: green tint, random dots and a
//! mask, no bloom); `../shared/references/sensors.md` (tube figures, halo, night
//! illuminance); the open `stoatworks-labs/intensifier` model (Poisson photoelectrons, MCP gain
//! per event, halo, brightness control).
//!
//! Limits: one spectral weighting for the whole tube (no per-pixel spectra); the halo only
//! around light points (a fire's or flare's lit ground does not bloom); the MCP gain spread is
//! a Gaussian of the summed signal, not a per-electron exponential; the control acts on the
//! whole view's mean (no local area control).

use thiserror::Error;

/// The output brightness (before the phosphor's saturation curve) the automatic brightness
/// control brings the view's mean to: about 30 % of the phosphor's full output.
pub const OUTPUT_KEY: f32 = 0.35;
/// Share of a point source's signal its halo carries.
pub const HALO_FRACTION: f32 = 0.04;
/// Halo diameter of a point light at the reference intensity, degrees (1°48′).
pub const HALO_DIAMETER_DEG: f32 = 1.8;

/// A setting of the goggle that cannot be used.
#[derive(Debug, Error, PartialEq)]
pub enum NvgError {
    #[error("NVG gain {0} is not a finite number in 0.1..=10")]
    Gain(f32),
    #[error("unknown phosphor {0:?} (p43 or white)")]
    Phosphor(String),
    #[error("NVG field of view {0} degrees is not in 10..=60")]
    FieldOfView(f32),
}

/// The phosphor of the tube's screen.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Phosphor {
    /// P43 green.
    #[default]
    P43,
    /// P45 "white phosphor" (bluish white).
    White,
}

impl Phosphor {
    /// Parses `p43` (or `green`) and `white` (or `p45`).
    pub fn from_name(name: &str) -> Result<Phosphor, NvgError> {
        match name.to_ascii_lowercase().as_str() {
            "p43" | "green" => Ok(Phosphor::P43),
            "white" | "p45" => Ok(Phosphor::White),
            _ => Err(NvgError::Phosphor(name.to_string())),
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            Phosphor::P43 => "p43",
            Phosphor::White => "white",
        }
    }

    /// The phosphor's colour in linear sRGB at full output, the largest channel 1 (from its CIE
    /// chromaticity: P43 x 0.333 y 0.556, P45 x 0.253 y 0.312).
    pub fn colour(self) -> [f32; 3] {
        let (x, y) = match self {
            Phosphor::P43 => (0.333, 0.556),
            Phosphor::White => (0.253, 0.312),
        };
        let big_x = x / y;
        let big_z = (1.0 - x - y) / y;
        let r = 3.2406 * big_x - 1.5372 - 0.4986 * big_z;
        let g = -0.9689 * big_x + 1.8758 + 0.0415 * big_z;
        let b = 0.0557 * big_x - 0.2040 + 1.0570 * big_z;
        let rgb = [r, g, b].map(|c: f64| c.max(0.0));
        let max = rgb.iter().cloned().fold(1e-9, f64::max);
        rgb.map(|c| (c / max) as f32)
    }
}

/// The intensifier tube and its objective.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Tube {
    /// Photocathode luminous sensitivity at 2856 K, µA/lm.
    pub sensitivity_ua_per_lm: f64,
    /// Objective f-number and transmission.
    pub f_number: f64,
    pub transmission: f64,
    /// Side of the area counted as one tube pixel, µm, and the photocathode's diameter, mm,
    /// which spans the goggle's field of view.
    pub pixel_um: f64,
    pub photocathode_mm: f64,
    /// Limiting resolution, line pairs per mm (MTF 3 %).
    pub limiting_lp_per_mm: f64,
    /// Frames a second the phosphor integrates over.
    pub frame_rate_hz: f64,
    /// Excess noise factor of the microchannel plate's gain.
    pub mcp_excess_noise: f64,
    /// Mean scene `πL` (lx_A) below which the control's gain is at its highest.
    pub abc_floor_lxa: f64,
    /// Mean scene `πL` (lx_A) above which the gain is at its lowest and the phosphor saturates.
    pub abc_ceiling_lxa: f64,
    /// Time constant of the automatic brightness control, seconds.
    pub abc_tau_s: f64,
}

impl Default for Tube {
    /// A Gen III tube with a minus-blue filter in a PVS-14-like goggle.
    fn default() -> Tube {
        Tube {
            sensitivity_ua_per_lm: 2000.0,
            f_number: 1.23,
            transmission: 0.8,
            pixel_um: 17.6,
            photocathode_mm: 18.0,
            limiting_lp_per_mm: 64.0,
            frame_rate_hz: 60.0,
            mcp_excess_noise: 1.7,
            abc_floor_lxa: 3e-4,
            abc_ceiling_lxa: 3.0,
            abc_tau_s: 0.1,
        }
    }
}

/// Elementary charge, coulombs.
const ELECTRON_C: f64 = 1.602_176_634e-19;

impl Tube {
    /// Photoelectrons a frame from a scene of `πL` = 1 lx_A over a solid angle of one square
    /// degree, for a goggle whose photocathode spans `fov_deg`.
    pub fn photoelectrons_per_lxa_deg2(&self, fov_deg: f64) -> f64 {
        let pc_lux_per_lxa = self.transmission / (4.0 * self.f_number * self.f_number);
        let pixel_m = self.pixel_um * 1e-6;
        let per_tube_pixel = self.sensitivity_ua_per_lm * 1e-6 * pc_lux_per_lxa * pixel_m * pixel_m
            / (ELECTRON_C * self.frame_rate_hz);
        let tube_pixel_deg = fov_deg * self.pixel_um * 1e-3 / self.photocathode_mm;
        per_tube_pixel / (tube_pixel_deg * tube_pixel_deg)
    }

    /// The point spread's standard deviation, degrees: a Gaussian whose MTF
    /// `exp(-2π²σ²f²)` is 3 % at the limiting resolution.
    pub fn blur_sigma_deg(&self, fov_deg: f64) -> f64 {
        let cycles_per_deg = self.limiting_lp_per_mm * self.photocathode_mm / fov_deg;
        let k = (1.0f64 / 0.03).ln() / (2.0 * std::f64::consts::PI * std::f64::consts::PI);
        k.sqrt() / cycles_per_deg
    }
}

/// One night-vision view's settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NvgView {
    /// Manual gain: multiplies the brightness the control holds and its gain limits
    /// (0.1..=10, 1 nominal).
    pub gain: f32,
    pub phosphor: Phosphor,
    /// The goggle's circular field of view, degrees (the black surround outside it).
    pub fov_deg: f32,
    /// Draw the photoelectron noise (off only for tests of the mean).
    pub noise: bool,
    pub tube: Tube,
}

impl Default for NvgView {
    fn default() -> NvgView {
        NvgView {
            gain: 1.0,
            phosphor: Phosphor::P43,
            fov_deg: 40.0,
            noise: true,
            tube: Tube::default(),
        }
    }
}

impl NvgView {
    /// Checks the settings a user gave.
    pub fn validate(&self) -> Result<(), NvgError> {
        if !(self.gain.is_finite() && (0.1..=10.0).contains(&self.gain)) {
            return Err(NvgError::Gain(self.gain));
        }
        if !(self.fov_deg.is_finite() && (10.0..=60.0).contains(&self.fov_deg)) {
            return Err(NvgError::FieldOfView(self.fov_deg));
        }
        Ok(())
    }

    /// The control's gain limits on `πL` (lx_A): output brightness per lx_A, lowest and highest.
    pub fn gain_limits(&self) -> (f64, f64) {
        let key = f64::from(OUTPUT_KEY) * f64::from(self.gain);
        (
            key / self.tube.abc_ceiling_lxa,
            key / self.tube.abc_floor_lxa,
        )
    }
}

/// A light's halo diameter, degrees, for a source giving `nvg_lxa` at the goggle: 1.8° at
/// 10⁻³ lx_A, a twentieth wider per decade brighter, within 1.5..2.4°.
pub fn halo_diameter_deg(nvg_lxa: f64) -> f64 {
    let decades = (nvg_lxa.max(1e-12) / 1e-3).log10();
    (f64::from(HALO_DIAMETER_DEG) * (1.0 + 0.05 * decades)).clamp(1.5, 2.4)
}

/// NVG-band (0.6-0.9 µm, Gen III weighted) reflectance of each thermal material
/// (`cig_thermal::ThermalMaterial::ALL` order: the nine terrain classes, then the models'
/// materials). Green vegetation reflects strongly past the red edge (0.70 µm): grass 0.05 at
/// 0.65 µm and 0.48-0.50 at 0.80-0.86 µm (JHU/ASTER spectral library, in
/// `../shared/references/sensors.md`), weighted over the band about 0.35; a forest canopy
/// with its shadows about 0.30; bare soil and sand rise slowly (brown sandy soil 0.21-0.28);
/// asphalt 0.08-0.12; water absorbs (0.02); snow 0.85. Military paints are made to match
/// foliage in the near infrared (CARC green about 0.35-0.45); glass 0.08 (seen by
/// reflection), rubber 0.05, camouflage clothing 0.35, skin 0.45, building walls (concrete,
/// brick) 0.30-0.35.
pub const NVG_REFLECTANCE: [f32; 18] = [
    0.02, // water
    0.32, // sand
    0.30, // dry clay
    0.36, // grass
    0.30, // forest
    0.25, // rock
    0.85, // snow
    0.10, // paved road
    0.22, // dirt road
    0.30, // hull paint (grey)
    0.32, // superstructure
    0.38, // vehicle armour (CARC)
    0.08, // glass
    0.05, // rubber tracks
    0.35, // clothing
    0.45, // skin
    0.42, // canopy foliage
    0.32, // building wall
];

/// NVG reflectance of a thermal material.
pub fn nvg_reflectance(material: cig_thermal::ThermalMaterial) -> f32 {
    NVG_REFLECTANCE
        .get(material.index())
        .copied()
        .unwrap_or(0.3)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reference_photoelectron_count() {
        // 30 % Lambertian under 1e-3 lx_A: πL = 3e-4 lx_A; 2.6 photoelectrons per 17.6 µm tube
        // pixel per frame (sensors.md).
        let tube = Tube::default();
        let tube_pixel_deg = 40.0 * 17.6e-3 / 18.0;
        let n = tube.photoelectrons_per_lxa_deg2(40.0) * 3e-4 * tube_pixel_deg * tube_pixel_deg;
        assert!((n - 2.6).abs() < 0.15, "{n}");
        // A narrower goggle field puts the same photocathode on fewer degrees: more per degree.
        assert!(
            tube.photoelectrons_per_lxa_deg2(20.0) > 3.9 * tube.photoelectrons_per_lxa_deg2(40.0)
        );
    }

    #[test]
    fn blur_is_about_a_minute_of_arc() {
        let sigma_deg = Tube::default().blur_sigma_deg(40.0);
        // 28.8 cycles a degree limiting: sigma about 0.015 degree.
        assert!((0.010..0.020).contains(&sigma_deg), "{sigma_deg}");
    }

    #[test]
    fn halo_grows_slowly_with_intensity() {
        assert!((halo_diameter_deg(1e-3) - 1.8).abs() < 1e-6);
        let a = halo_diameter_deg(1e-5);
        let b = halo_diameter_deg(1e-1);
        assert!(a < 1.8 && b > 1.8 && b < 2.1 && a > 1.5);
    }

    #[test]
    fn phosphors_are_green_and_white() {
        let g = Phosphor::P43.colour();
        assert!(g[1] == 1.0 && g[0] < 0.4 && g[2] < 0.2, "{g:?}");
        let w = Phosphor::White.colour();
        assert!(w.iter().all(|c| *c > 0.25), "{w:?}");
        assert_eq!(Phosphor::from_name("P43"), Ok(Phosphor::P43));
        assert!(Phosphor::from_name("amber").is_err());
    }

    #[test]
    fn settings_are_checked() {
        let mut v = NvgView::default();
        assert!(v.validate().is_ok());
        v.gain = f32::NAN;
        assert!(v.validate().is_err());
        v.gain = 20.0;
        assert!(v.validate().is_err());
        let (lo, hi) = NvgView::default().gain_limits();
        assert!(hi / lo > 1e3);
    }

    #[test]
    fn vegetation_outshines_roads_on_goggles() {
        use cig_thermal::ThermalMaterial as M;
        assert!(nvg_reflectance(M::Grass) > 3.0 * nvg_reflectance(M::PavedRoad));
        assert!(nvg_reflectance(M::Water) < 0.05);
    }
}
