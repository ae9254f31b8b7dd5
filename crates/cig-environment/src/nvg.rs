//! Night-vision (image intensifier) weighting of light: what a Gen III photocathode behind a
//! minus-blue filter sees of each natural source and of each kind of lamp, beside its lux.
//!
//! Unit: the **2856 K-equivalent lux** (lx_A), the illuminance of CIE illuminant A (a 2856 K
//! Planckian radiator, the source that image-intensifier tubes are rated with) that gives the
//! same NVG-weighted irradiance `∫R(λ)E(λ)dλ`. A spectrum's `nvg_per_lux` is its lx_A per lux:
//!
//! ```text
//! nvg_per_lux(E) = [∫R E dλ / (683 ∫V E dλ)] / [the same ratio for illuminant A]
//! ```
//!
//! so illuminant A is exactly 1. One lx_A is [`NVG_W_M2_PER_LXA`] W/m² of NVG-weighted
//! irradiance (`∫R E dλ` with the peak-1 response `R`).
//!
//! Algorithm: both integrals by the trapezoidal rule on a 1 nm grid over 380-950 nm, the tables
//! interpolated linearly:
//!
//! - `V(λ)`: the CIE 1931 photopic luminous efficiency function (the 2° observer's ȳ), 380-780 nm
//!   at 5 nm, as tabulated in CIE 015:2004 / ISO 11664-1; `∫V dλ` = 106.86 nm. `K_m` = 683 lm/W.
//! - `R(λ)`: the relative spectral response (peak 1) of a Gen III GaAs photocathode behind a
//!   625 nm minus-blue objective filter (MIL-L-85762A / MIL-STD-3009 Class A NVIS), 550-950 nm
//!   at 10 nm. **An approximation**: no published table could be consulted, so the curve is
//!   shaped from the documented features — the Class A filter's 50 % cut-on at 625 nm (a
//!   logistic edge of 5 nm scale, 10-90 % over 22 nm), a GaAs quantum efficiency that falls
//!   linearly by 15 % per 100 nm above 600 nm, responsivity ∝ quantum efficiency × λ, and the
//!   GaAs band-gap cut-off (1.42 eV, 873 nm) as a logistic edge at 885 nm of 8 nm scale, so the
//!   response is 0.55 at 880 nm, 0.11 at 900 nm and 0.003 at 930 nm (MIL-STD-3009's 625-930 nm
//!   NVIS band). Its peak lies at 660 nm and it stays above 0.87 from 640 to 850 nm, the usual
//!   Gen III filmed-tube shape; the tabulated values are the formula rounded to 3 decimals.
//! - Planck: `λ⁻⁵ / (exp(c₂/λT) − 1)` with `c₂` = 1.438 777 × 10⁻² m·K (CODATA 2018). CIE
//!   015:2004 defines illuminant A with `c₂` = 1.435 × 10⁻² m·K at 2848 K: the same `c₂/T`
//!   within 0.02 %, so 2856 K here is illuminant A (tests: within 0.1 %).
//!
//! Lamps ([`LightSpectrum`]), each a documented model spectrum:
//!
//! - Incandescent 2856 K, Halogen 3200 K, Flame 1500 K (sooty flames radiate as near-grey
//!   bodies), Xenon 6000 K: Planckian.
//! - LedWhite: a phosphor-converted white LED as two Gaussians, the InGaN pump at 450 nm (20 nm
//!   FWHM) and the YAG:Ce phosphor band at 570 nm (120 nm FWHM) with 0.3 of the phosphor's
//!   radiant power in the pump (a neutral-to-cool white): 4 % of the phosphor's peak at
//!   700 nm, 0.2 % at 750 nm, nothing beyond.
//! - LedRed: a Gaussian at 630 nm, 20 nm FWHM (AlInGaP).
//! - Sodium (high-pressure sodium street lamp): the self-reversed, pressure-broadened D band as
//!   two Lorentzians at 583 and 597 nm (12 nm FWHM, 0.45 of the power each; the Lorentz wings
//!   reach the red, de Groot and van Vliet, *The High-Pressure Sodium Lamp*, 1986), the Na lines
//!   at 498.3, 515.4, 568.8 and 615.4 nm (0.02, 0.01, 0.03, 0.03), and the 818.3/819.5 nm
//!   doublet as one 6 nm Gaussian carrying 0.15 of the D band's radiant power (this crate's
//!   reading of published HPS spectra, approximate).
//! - Flare (a magnesium / sodium-nitrate illuminating flare): a 3000 K continuum from the hot
//!   MgO particles carrying 40 % of the lux, the rest a strongly broadened sodium D band (a
//!   Lorentzian at 589 nm, 30 nm FWHM) with the 819 nm doublet at 0.1 of its radiant power
//!   (after H. A. Douda, *Theory of Colored Flame Production*, NAD Crane RDTN 71, 1964, and
//!   *Spectral Observations in Illuminating Flames*, 1965: the D band dominates the visible).
//!
//! Natural sources (constants, recomputed by the tests from these models):
//!
//! - Sunlight outside the atmosphere: a 5772 K Planckian (IAU 2015 Resolution B3 nominal solar
//!   effective temperature). Direct sunlight at the ground ([`SUN_NVG_PER_LUX`]): that through
//!   the clear atmosphere at air mass 1.5 (the ASTM G173 reference), optical depth
//!   `τ(λ) = τ_R + τ_a` with Rayleigh `0.008569 λ⁻⁴(1 + 0.0113 λ⁻² + 0.00013 λ⁻⁴)` (λ in µm,
//!   Hansen and Travis 1974) and Ångström aerosol `0.1 λ⁻¹·³` (as in `clock`).
//! - Moonlight ([`MOON_NVG_PER_LUX`]): that sunlight times the lunar disc reflectance, which
//!   rises linearly from 0.07 at 450 nm to 0.16 at 900 nm (Lane and Irvine 1973, AJ 78:267;
//!   Kieffer and Stone 2005, AJ 129:2887, the ROLO model), through the same atmosphere.
//! - Skylight ([`SUNLIT_SKY_NVG_PER_LUX`], [`MOONLIT_SKY_NVG_PER_LUX`]): the light above the
//!   atmosphere times the single-scattering diffuse weights of Bird and Riordan's SPCTRAL2
//!   (J. Climate Appl. Meteor. 25:87, 1986) at air mass 1.5, `½(1 − T_R)T_a + F_s ω₀(1 − T_a)T_R`
//!   with `T = exp(−τ m)`, `ω₀` = 0.945, `F_s` = 0.82, without the ground-sky multiple
//!   reflection: bluer than sunlight (about a 10 000 K Planckian's weighting).
//! - The moonless night sky ([`NIGHT_SKY_NVG_PER_LUX`] = 4): starlight, zodiacal light and
//!   airglow, whose OH Meinel bands make the sky far richer above 700 nm than its lux suggest
//!   (Vatsia 1972, *Atmospheric Optical Environment*, RADC-TR-72-223; the RCA Electro-Optics
//!   Handbook; Task and Pinkus, AFRL, find no agreed NVG radiance for it). No spectrum is
//!   modelled: 4 is a choice in the middle of the 3-6 that those sources' statements suggest.
//!
//! [`nvg_irradiance`] weights the parts of [`crate::natural_illuminance`]: the USNO sun and moon
//! fits include their skylight, so each is split into direct beam and sky by the clear-sky
//! direct-beam illuminance on horizontal ground, `E_v0 sin h exp(−a_v T_v m)` (CIE S 017
//! 17-29-108; Navvab et al., Energy and Buildings 6:293, 1984; `a_v = 1/(9.9 + 0.043 m)`,
//! rural luminous turbidity `T_v` = 2.5, Kasten-Young air mass, `E_v0` the 128 klx at the top
//! of the atmosphere), as a fraction of the sun's total at that altitude; the moon's light is
//! split by the same fraction at the moon's altitude (the atmosphere does not care which
//! body lights it). The fraction is 0.2 at 5°, 0.5 at 10°, 0.84 at 30° and 0.77 at the zenith
//! (the two fits are independent, hence the slight fall above 30°).
//!
//! Limits: `R(λ)` is a shaped approximation, not a measured tube (real tubes differ with the
//! maker and the photocathode's film; Class B or leaky-green filters are not modelled); fixed
//! air mass 1.5 for the sun's and the moon's spectra (a low sun is redder: about 0.6 lx_A/lux
//! at air mass 5, not modelled); no molecular absorption bands (O₂ A-band, water vapour at 720, 820 and 940 nm),
//! which overstates sunlight's weighting by a few per cent; cloud divides every part alike (as
//! in `illuminance`) and is treated as grey; the night-sky factor is a choice, not a fit; the
//! twilight sky has the daylight sky's factor (no Chappuis-band blueing).

use std::sync::OnceLock;

use crate::atmosphere::SUN_ILLUMINANCE_TOA_LUX;
use crate::illuminance::sun_illuminance_lux;
use crate::{EnvironmentError, Ephemeris};

/// The spectrum of a lamp or fire, for its NVG weighting.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum LightSpectrum {
    /// Tungsten filament, about 2856 K (illuminant A).
    Incandescent,
    /// Tungsten-halogen, about 3200 K (vehicle headlights).
    Halogen,
    /// White LED (phosphor-converted): little beyond 700 nm, nothing beyond 750 nm.
    LedWhite,
    /// Red LED (tail lights): a narrow line near 630 nm.
    LedRed,
    /// High-pressure sodium street lamp (strong 819 nm lines).
    Sodium,
    /// A flame or a burning vehicle, about 1500 K.
    Flame,
    /// A magnesium illumination flare.
    Flare,
    /// Xenon strobe, about 6000 K.
    Xenon,
}

impl LightSpectrum {
    /// Every spectrum, in declaration order.
    pub const ALL: [LightSpectrum; 8] = [
        LightSpectrum::Incandescent,
        LightSpectrum::Halogen,
        LightSpectrum::LedWhite,
        LightSpectrum::LedRed,
        LightSpectrum::Sodium,
        LightSpectrum::Flame,
        LightSpectrum::Flare,
        LightSpectrum::Xenon,
    ];

    /// 2856 K-equivalent lux per lux of this spectrum, integrated once per process from the
    /// model spectra of the module documentation.
    pub fn nvg_per_lux(self) -> f64 {
        static FACTORS: OnceLock<[f64; 8]> = OnceLock::new();
        let factors = FACTORS.get_or_init(|| {
            LightSpectrum::ALL.map(|s| spectrum_nvg_per_lux(|l| s.spectral_power(l)))
        });
        factors[self as usize]
    }

    /// Relative spectral power of this model spectrum (W/nm, arbitrary scale) at a wavelength.
    pub fn spectral_power(self, wavelength_nm: f64) -> f64 {
        let l = wavelength_nm;
        match self {
            LightSpectrum::Incandescent => planck_relative(l, ILLUMINANT_A_K),
            LightSpectrum::Halogen => planck_relative(l, 3200.0),
            LightSpectrum::Flame => planck_relative(l, 1500.0),
            LightSpectrum::Xenon => planck_relative(l, 6000.0),
            LightSpectrum::LedWhite => 0.3 * gaussian(l, 450.0, 20.0) + gaussian(l, 570.0, 120.0),
            LightSpectrum::LedRed => gaussian(l, 630.0, 20.0),
            LightSpectrum::Sodium => sodium_hps(l),
            LightSpectrum::Flare => flare(l),
        }
    }
}

/// Temperature of CIE illuminant A, kelvin.
pub const ILLUMINANT_A_K: f64 = 2856.0;
/// Maximum luminous efficacy of photopic vision, lm/W.
pub const KM_LM_PER_W: f64 = 683.0;
/// Second radiation constant, nm·K (CODATA 2018: 1.438 776 877 × 10⁻² m·K).
pub const C2_NM_K: f64 = 1.438_776_877e7;
/// Solar effective temperature, kelvin (IAU 2015 Resolution B3).
pub const SUN_EFFECTIVE_TEMPERATURE_K: f64 = 5772.0;

/// NVG-weighted irradiance `∫R E dλ` (W/m², `R` of peak 1) of one 2856 K-equivalent lux.
pub const NVG_W_M2_PER_LXA: f64 = 7.439e-3;
/// lx_A per lux of direct sunlight at the ground (air mass 1.5).
pub const SUN_NVG_PER_LUX: f64 = 0.4102;
/// lx_A per lux of direct moonlight at the ground (air mass 1.5).
pub const MOON_NVG_PER_LUX: f64 = 0.5715;
/// lx_A per lux of the moonless night sky (starlight, zodiacal light, airglow): a choice.
pub const NIGHT_SKY_NVG_PER_LUX: f64 = 4.0;
/// lx_A per lux of the clear sky lit by the sun (and of twilight).
pub const SUNLIT_SKY_NVG_PER_LUX: f64 = 0.2434;
/// lx_A per lux of the clear sky lit by the moon.
pub const MOONLIT_SKY_NVG_PER_LUX: f64 = 0.3371;

/// First wavelength of [`PHOTOPIC_V`], nm.
pub const PHOTOPIC_V_START_NM: f64 = 380.0;
/// Step of [`PHOTOPIC_V`], nm.
pub const PHOTOPIC_V_STEP_NM: f64 = 5.0;
/// CIE 1931 photopic luminous efficiency V(λ) (2° observer ȳ), 380-780 nm at 5 nm (CIE 015:2004).
pub const PHOTOPIC_V: [f64; 81] = [
    0.000_039, 0.000_064, 0.000_120, 0.000_217, 0.000_396, 0.000_640, 0.001_210, 0.002_180,
    0.004_000, 0.007_300, 0.011_600, 0.016_840, 0.023_000, 0.029_800, 0.038_000, 0.048_000,
    0.060_000, 0.073_900, 0.090_980, 0.112_600, 0.139_020, 0.169_300, 0.208_020, 0.258_600,
    0.323_000, 0.407_300, 0.503_000, 0.608_200, 0.710_000, 0.793_200, 0.862_000, 0.914_850,
    0.954_000, 0.980_300, 0.994_950, 1.000_000, 0.995_000, 0.978_600, 0.952_000, 0.915_400,
    0.870_000, 0.816_300, 0.757_000, 0.694_900, 0.631_000, 0.566_800, 0.503_000, 0.441_200,
    0.381_000, 0.321_000, 0.265_000, 0.217_000, 0.175_000, 0.138_200, 0.107_000, 0.081_600,
    0.061_000, 0.044_580, 0.032_000, 0.023_200, 0.017_000, 0.011_920, 0.008_210, 0.005_723,
    0.004_102, 0.002_929, 0.002_091, 0.001_484, 0.001_047, 0.000_740, 0.000_520, 0.000_361,
    0.000_249, 0.000_172, 0.000_120, 0.000_085, 0.000_060, 0.000_042, 0.000_030, 0.000_021,
    0.000_015,
];

/// First wavelength of [`NVG_RESPONSE`], nm.
pub const NVG_RESPONSE_START_NM: f64 = 550.0;
/// Step of [`NVG_RESPONSE`], nm.
pub const NVG_RESPONSE_STEP_NM: f64 = 10.0;
/// Relative spectral response (peak 1) of a Gen III photocathode behind a 625 nm minus-blue
/// (Class A) filter, 550-950 nm at 10 nm: the shaped approximation of the module documentation.
pub const NVG_RESPONSE: [f64; 41] = [
    0.0, 0.0, 0.0, 0.0, 0.001, 0.007, 0.047, 0.270, 0.733, 0.955, // 550-640
    0.995, 1.000, 0.999, 0.997, 0.995, 0.992, 0.988, 0.984, 0.979, 0.974, // 650-740
    0.969, 0.963, 0.956, 0.949, 0.941, 0.933, 0.925, 0.915, 0.905, 0.893, // 750-840
    0.874, 0.837, 0.748, 0.554, 0.292, 0.110, 0.034, 0.010, 0.003, 0.001, // 850-940
    0.0,   // 950
];

/// Integration grid: 1 nm steps over 380..=950 nm.
const GRID_START_NM: f64 = 380.0;
const GRID_POINTS: usize = 571;

/// Linear interpolation in a table starting at `start_nm` with `step_nm`; 0 outside it.
fn table_at(table: &[f64], start_nm: f64, step_nm: f64, wavelength_nm: f64) -> f64 {
    let x = (wavelength_nm - start_nm) / step_nm;
    let last = table.len().saturating_sub(1) as f64;
    if !x.is_finite() || x < 0.0 || x > last {
        return 0.0;
    }
    let i = x.floor();
    let frac = x - i;
    let i = i as usize;
    let a = table.get(i).copied().unwrap_or(0.0);
    let b = table.get(i + 1).copied().unwrap_or(a);
    a + (b - a) * frac
}

/// CIE 1931 photopic V(λ) at a wavelength (linear between the 5 nm values, 0 outside 380-780).
pub fn photopic_v(wavelength_nm: f64) -> f64 {
    table_at(
        &PHOTOPIC_V,
        PHOTOPIC_V_START_NM,
        PHOTOPIC_V_STEP_NM,
        wavelength_nm,
    )
}

/// The NVG relative response R(λ) at a wavelength (linear between the 10 nm values, 0
/// outside 550-950 nm).
pub fn nvg_response(wavelength_nm: f64) -> f64 {
    table_at(
        &NVG_RESPONSE,
        NVG_RESPONSE_START_NM,
        NVG_RESPONSE_STEP_NM,
        wavelength_nm,
    )
}

/// Trapezoidal integral of `f` over the 1 nm grid, in (units of f) × nm.
fn integrate(f: impl Fn(f64) -> f64) -> f64 {
    let mut sum = 0.0;
    for i in 0..GRID_POINTS {
        let w = if i == 0 || i + 1 == GRID_POINTS {
            0.5
        } else {
            1.0
        };
        sum += w * f(GRID_START_NM + i as f64);
    }
    sum
}

/// ∫V dλ over the grid, nm (106.86 nm for the CIE 1931 table).
pub fn photopic_v_integral_nm() -> f64 {
    integrate(photopic_v)
}

/// Planck's spectral radiance up to a constant factor (W/nm, arbitrary scale), for a
/// wavelength in nm and a temperature in kelvin; 0 for non-positive inputs.
pub fn planck_relative(wavelength_nm: f64, temperature_k: f64) -> f64 {
    if wavelength_nm <= 0.0 || temperature_k <= 0.0 {
        return 0.0;
    }
    // Scaled by 500^5 so the numbers stay near 1 in the visible.
    let x = C2_NM_K / (wavelength_nm * temperature_k);
    (500.0 / wavelength_nm).powi(5) / x.exp_m1()
}

/// A Gaussian line of unit area, FWHM `fwhm_nm`, per nm.
fn gaussian(wavelength_nm: f64, center_nm: f64, fwhm_nm: f64) -> f64 {
    let sigma = fwhm_nm / (8.0 * std::f64::consts::LN_2).sqrt();
    let z = (wavelength_nm - center_nm) / sigma;
    (-0.5 * z * z).exp() / (sigma * (2.0 * std::f64::consts::PI).sqrt())
}

/// A Lorentzian line of unit area, FWHM `fwhm_nm`, per nm.
fn lorentzian(wavelength_nm: f64, center_nm: f64, fwhm_nm: f64) -> f64 {
    let g = 0.5 * fwhm_nm;
    let d = wavelength_nm - center_nm;
    g / (std::f64::consts::PI * (d * d + g * g))
}

/// High-pressure sodium: the self-reversed D band, minor Na lines, the 819 nm doublet.
fn sodium_hps(l: f64) -> f64 {
    let d_band = 0.45 * lorentzian(l, 583.0, 12.0) + 0.45 * lorentzian(l, 597.0, 12.0);
    d_band
        + 0.02 * gaussian(l, 498.3, 3.0)
        + 0.01 * gaussian(l, 515.4, 3.0)
        + 0.03 * gaussian(l, 568.8, 3.0)
        + 0.03 * gaussian(l, 615.4, 3.0)
        + 0.15 * 0.9 * gaussian(l, 819.0, 6.0)
}

/// Magnesium / sodium-nitrate flare: 3000 K continuum with 40 % of the lux, broadened D band
/// and the 819 nm doublet.
fn flare(l: f64) -> f64 {
    static NORMS: OnceLock<(f64, f64)> = OnceLock::new();
    let (continuum_lm, band_lm) = *NORMS.get_or_init(|| {
        (
            integrate(|x| photopic_v(x) * planck_relative(x, 3000.0)),
            integrate(|x| photopic_v(x) * flare_band(x)),
        )
    });
    0.4 * planck_relative(l, 3000.0) / continuum_lm + 0.6 * flare_band(l) / band_lm
}

fn flare_band(l: f64) -> f64 {
    lorentzian(l, 589.0, 30.0) + 0.1 * gaussian(l, 819.0, 6.0)
}

/// NVG-weighted irradiance per lux of a spectrum: `∫R E dλ / (683 ∫V E dλ)`, W/m² per lux
/// (`R` of peak 1). `spectral_power` gives the spectrum at a wavelength in nm, any scale. NaN
/// when the spectrum has no light in 380-780 nm.
pub fn nvg_weighted_w_m2_per_lux(spectral_power: impl Fn(f64) -> f64) -> f64 {
    let mut nvg = 0.0;
    let mut lum = 0.0;
    for i in 0..GRID_POINTS {
        let l = GRID_START_NM + i as f64;
        let w = if i == 0 || i + 1 == GRID_POINTS {
            0.5
        } else {
            1.0
        };
        let e = spectral_power(l);
        nvg += w * nvg_response(l) * e;
        lum += w * photopic_v(l) * e;
    }
    if lum > 0.0 {
        nvg / (KM_LM_PER_W * lum)
    } else {
        f64::NAN
    }
}

/// NVG-weighted irradiance per lux of a Planckian radiator at `temperature_k`, W/m² per lux
/// (`∫R E dλ / ∫683 V E dλ`). Temperatures are clamped to 500..=100 000 K; NaN gives NaN.
pub fn nvg_irradiance_per_lux_blackbody(temperature_k: f64) -> f64 {
    if temperature_k.is_nan() {
        return f64::NAN;
    }
    let t = temperature_k.clamp(500.0, 100_000.0);
    nvg_weighted_w_m2_per_lux(|l| planck_relative(l, t))
}

/// NVG-weighted W/m² per lux of illuminant A, computed once (the value of [`NVG_W_M2_PER_LXA`]).
pub fn nvg_w_m2_per_lxa() -> f64 {
    static A: OnceLock<f64> = OnceLock::new();
    *A.get_or_init(|| nvg_irradiance_per_lux_blackbody(ILLUMINANT_A_K))
}

/// lx_A per lux of any spectrum (`spectral_power` at a wavelength in nm, any scale).
pub fn spectrum_nvg_per_lux(spectral_power: impl Fn(f64) -> f64) -> f64 {
    nvg_weighted_w_m2_per_lux(spectral_power) / nvg_w_m2_per_lxa()
}

/// lx_A per lux of a Planckian radiator (1 at 2856 K; decreasing with temperature).
pub fn blackbody_nvg_per_lux(temperature_k: f64) -> f64 {
    nvg_irradiance_per_lux_blackbody(temperature_k) / nvg_w_m2_per_lxa()
}

/// Reference air mass of the natural spectra (ASTM G173).
const REFERENCE_AIR_MASS: f64 = 1.5;

/// Rayleigh (Hansen and Travis 1974) and Ångström aerosol optical depths at sea level.
fn optical_depths(wavelength_nm: f64) -> (f64, f64) {
    let l = wavelength_nm / 1000.0;
    let l2 = l * l;
    let rayleigh = 0.008_569 / (l2 * l2) * (1.0 + 0.0113 / l2 + 0.000_13 / (l2 * l2));
    let aerosol = 0.1 * l.powf(-1.3);
    (rayleigh, aerosol)
}

fn sunlight_toa(l: f64) -> f64 {
    planck_relative(l, SUN_EFFECTIVE_TEMPERATURE_K)
}

fn direct_transmittance(l: f64) -> f64 {
    let (r, a) = optical_depths(l);
    (-(r + a) * REFERENCE_AIR_MASS).exp()
}

/// Single-scattering diffuse weight (Bird and Riordan 1986, without the ground term).
fn diffuse_weight(l: f64) -> f64 {
    let (r, a) = optical_depths(l);
    let t_r = (-r * REFERENCE_AIR_MASS).exp();
    let t_a = (-a * REFERENCE_AIR_MASS).exp();
    0.5 * (1.0 - t_r) * t_a + 0.82 * 0.945 * (1.0 - t_a) * t_r
}

/// Lunar disc reflectance, linear from 0.07 at 450 nm to 0.16 at 900 nm.
fn lunar_reflectance(l: f64) -> f64 {
    0.07 + 0.0002 * (l - 450.0)
}

/// The natural sources' model spectra (module documentation), whose weightings are the
/// constants [`SUN_NVG_PER_LUX`], [`MOON_NVG_PER_LUX`], [`SUNLIT_SKY_NVG_PER_LUX`] and
/// [`MOONLIT_SKY_NVG_PER_LUX`]. The moonless night sky has no model spectrum.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum NaturalSpectrum {
    /// Direct sunlight at the ground, air mass 1.5.
    DirectSun,
    /// Direct moonlight at the ground, air mass 1.5.
    DirectMoon,
    /// Skylight of a sun-lit clear sky.
    SunlitSky,
    /// Skylight of a moon-lit clear sky.
    MoonlitSky,
}

impl NaturalSpectrum {
    /// Relative spectral power (W/nm, arbitrary scale) at a wavelength.
    pub fn spectral_power(self, wavelength_nm: f64) -> f64 {
        let l = wavelength_nm;
        match self {
            NaturalSpectrum::DirectSun => sunlight_toa(l) * direct_transmittance(l),
            NaturalSpectrum::DirectMoon => {
                sunlight_toa(l) * lunar_reflectance(l) * direct_transmittance(l)
            }
            NaturalSpectrum::SunlitSky => sunlight_toa(l) * diffuse_weight(l),
            NaturalSpectrum::MoonlitSky => {
                sunlight_toa(l) * lunar_reflectance(l) * diffuse_weight(l)
            }
        }
    }

    /// lx_A per lux of this spectrum, integrated (about 10 µs; the constants hold the values).
    pub fn nvg_per_lux(self) -> f64 {
        spectrum_nvg_per_lux(|l| self.spectral_power(l))
    }
}

/// Fraction of the clear-sky illuminance of a body at `altitude_deg` (geometric, degrees)
/// that arrives as the direct beam, in `[0, 1]`: `E_v0 sin h exp(−a_v T_v m)` over the USNO
/// total of the sun at that altitude; 0 with the body below the horizon.
pub fn direct_beam_fraction(altitude_deg: f64) -> f64 {
    if !altitude_deg.is_finite() || altitude_deg <= 0.0 {
        return 0.0;
    }
    let h = altitude_deg.min(90.0);
    let air_mass = 1.0 / (h.to_radians().sin() + 0.505_72 * (h + 6.079_95).powf(-1.6364));
    let a_v = 1.0 / (9.9 + 0.043 * air_mass);
    const LUMINOUS_TURBIDITY: f64 = 2.5;
    let direct_lux = SUN_ILLUMINANCE_TOA_LUX
        * h.to_radians().sin()
        * (-a_v * LUMINOUS_TURBIDITY * air_mass).exp();
    let total_lux = sun_illuminance_lux(h);
    if total_lux > 0.0 {
        (direct_lux / total_lux).clamp(0.0, 1.0)
    } else {
        0.0
    }
}

/// Natural NVG-weighted irradiance at the ground, in 2856 K-equivalent lux (lx_A) per part.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct NvgIrradiance {
    /// Direct sunlight, lx_A.
    pub sun_lxa: f64,
    /// Direct moonlight, lx_A.
    pub moon_lxa: f64,
    /// Skylight of the sun- and moon-lit sky (and twilight), lx_A.
    pub sky_lxa: f64,
    /// The moonless night sky (starlight, airglow), lx_A.
    pub night_sky_lxa: f64,
    /// Sum of the four, lx_A.
    pub total_lxa: f64,
    /// `total_lxa` as NVG-weighted irradiance `∫R E dλ` (R of peak 1), W/m².
    pub total_w_m2: f64,
}

/// Natural NVG-weighted irradiance from the ephemeris and the cloud-cover fraction: each part
/// of [`crate::natural_illuminance`] split into direct beam and sky and weighted by its
/// source's lx_A per lux.
///
/// # Errors
/// [`EnvironmentError::InvalidSetting`] for a cloud cover outside `[0, 1]`.
pub fn nvg_irradiance(
    ephemeris: &Ephemeris,
    cloud_cover_fraction: f64,
) -> Result<NvgIrradiance, EnvironmentError> {
    let lux = crate::natural_illuminance(ephemeris, cloud_cover_fraction)?;
    let sun_direct = direct_beam_fraction(ephemeris.sun.altitude_deg);
    let moon_direct = direct_beam_fraction(ephemeris.moon.altitude_deg);
    let sun_lxa = lux.sun_lux * sun_direct * SUN_NVG_PER_LUX;
    let moon_lxa = lux.moon_lux * moon_direct * MOON_NVG_PER_LUX;
    let sky_lxa = lux.sun_lux * (1.0 - sun_direct) * SUNLIT_SKY_NVG_PER_LUX
        + lux.moon_lux * (1.0 - moon_direct) * MOONLIT_SKY_NVG_PER_LUX;
    let night_sky_lxa = lux.sky_lux * NIGHT_SKY_NVG_PER_LUX;
    let total_lxa = sun_lxa + moon_lxa + sky_lxa + night_sky_lxa;
    Ok(NvgIrradiance {
        sun_lxa,
        moon_lxa,
        sky_lxa,
        night_sky_lxa,
        total_lxa,
        total_w_m2: total_lxa * NVG_W_M2_PER_LXA,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{ephemeris, Observer, UtcTime};
    use proptest::prelude::*;

    fn natural(s: NaturalSpectrum) -> f64 {
        s.nvg_per_lux()
    }

    fn close(a: f64, b: f64, rel: f64) -> bool {
        (a - b).abs() <= rel * b.abs()
    }

    #[test]
    fn illuminant_a_is_exactly_one() {
        assert!((blackbody_nvg_per_lux(ILLUMINANT_A_K) - 1.0).abs() < 1e-12);
        assert!((LightSpectrum::Incandescent.nvg_per_lux() - 1.0).abs() < 1e-12);
        // CIE 015:2004's own formula for illuminant A (2848 K with c2 = 1.435e-2 m K).
        let cie_a = |l: f64| {
            (560.0 / l).powi(5) * (1.435e7_f64 / (2848.0 * 560.0)).exp_m1()
                / (1.435e7 / (2848.0 * l)).exp_m1()
        };
        let a = spectrum_nvg_per_lux(cie_a);
        assert!((a - 1.0).abs() < 1e-3, "{a}");
        // The published constant is the computed one.
        assert!(close(nvg_w_m2_per_lxa(), NVG_W_M2_PER_LXA, 1e-3));
        // Scale does not matter.
        let b = spectrum_nvg_per_lux(|l| 1e-9 * planck_relative(l, ILLUMINANT_A_K));
        assert!((b - 1.0).abs() < 1e-12);
    }

    #[test]
    fn tables_are_the_cie_values_and_the_documented_response() {
        // ∫V dλ of the CIE 1931 table is 106.857 nm (1 nm table); at 5 nm with the
        // trapezoid the same to 0.01 nm.
        let v = photopic_v_integral_nm();
        assert!((v - 106.857).abs() < 0.01, "{v}");
        assert_eq!(photopic_v(555.0), 1.0);
        assert!((photopic_v(557.5) - 0.9975).abs() < 1e-12);
        assert_eq!(photopic_v(379.0), 0.0);
        assert_eq!(photopic_v(f64::NAN), 0.0);
        // R: peak 1, Class A cut-on at 625 nm, GaAs cut-off by 930 nm.
        let peak = NVG_RESPONSE.iter().copied().fold(0.0, f64::max);
        assert_eq!(peak, 1.0);
        assert!(nvg_response(600.0) < 0.01);
        assert!((0.3..0.7).contains(&nvg_response(625.0)));
        assert!(nvg_response(930.0) < 0.01);
        for l in (640..=850).step_by(10) {
            assert!(nvg_response(f64::from(l)) > 0.85, "{l}");
        }
    }

    #[test]
    fn lamps_order_from_red_to_blue() {
        let f = LightSpectrum::nvg_per_lux;
        assert!(f(LightSpectrum::Flame) > f(LightSpectrum::Incandescent));
        assert!(f(LightSpectrum::Incandescent) > f(LightSpectrum::Halogen));
        assert!(f(LightSpectrum::Halogen) > f(LightSpectrum::Xenon));
        assert!(f(LightSpectrum::Xenon) > f(LightSpectrum::LedWhite));
        assert!(f(LightSpectrum::LedWhite) < 0.1);
        // A 1500 K flame: several times illuminant A per lux.
        assert!((5.0..10.0).contains(&f(LightSpectrum::Flame)));
        // The red LED sits on the filter's edge: much more than white, less than A.
        assert!((0.3..0.7).contains(&f(LightSpectrum::LedRed)));
        // Sodium's visible D band is invisible to the tube; its 819 nm lines are not.
        let sodium = f(LightSpectrum::Sodium);
        assert!((0.02..0.15).contains(&sodium), "{sodium}");
        let without_819 =
            spectrum_nvg_per_lux(|l| sodium_hps(l) - 0.15 * 0.9 * gaussian(l, 819.0, 6.0));
        assert!(without_819 < 0.5 * sodium, "{without_819} vs {sodium}");
        // The flare: between its 3000 K continuum and its D band.
        let flare = f(LightSpectrum::Flare);
        assert!(
            flare < blackbody_nvg_per_lux(3000.0) && flare > 0.2,
            "{flare}"
        );
        for s in LightSpectrum::ALL {
            assert!(f(s).is_finite() && f(s) > 0.0, "{s:?}");
        }
    }

    #[test]
    fn natural_constants_are_their_models() {
        assert!(close(
            natural(NaturalSpectrum::DirectSun),
            SUN_NVG_PER_LUX,
            1e-3
        ));
        assert!(close(
            natural(NaturalSpectrum::DirectMoon),
            MOON_NVG_PER_LUX,
            1e-3
        ));
        assert!(close(
            natural(NaturalSpectrum::SunlitSky),
            SUNLIT_SKY_NVG_PER_LUX,
            1e-3
        ));
        assert!(close(
            natural(NaturalSpectrum::MoonlitSky),
            MOONLIT_SKY_NVG_PER_LUX,
            1e-3
        ));
        // Moonlight is redder than sunlight, the night sky far richer; skylight bluer.
        let sun = natural(NaturalSpectrum::DirectSun);
        let moon = natural(NaturalSpectrum::DirectMoon);
        assert!(NIGHT_SKY_NVG_PER_LUX > moon);
        assert!(moon > sun);
        assert!(natural(NaturalSpectrum::SunlitSky) < sun);
        assert!(natural(NaturalSpectrum::MoonlitSky) < moon);
        // The sun above the atmosphere is close to a 5772 K Planckian; the clear sky's
        // weighting is that of a Planckian of about 10 000 K.
        let sky_like = blackbody_nvg_per_lux(10_000.0);
        assert!((SUNLIT_SKY_NVG_PER_LUX / sky_like - 1.0).abs() < 0.15);
    }

    #[test]
    fn direct_beam_fraction_rises_with_altitude() {
        assert_eq!(direct_beam_fraction(-5.0), 0.0);
        assert_eq!(direct_beam_fraction(0.0), 0.0);
        assert_eq!(direct_beam_fraction(f64::NAN), 0.0);
        // Rising while the air mass falls fast ...
        let mut last = 0.0;
        for h in [1.0, 2.0, 5.0, 10.0, 20.0, 30.0] {
            let f = direct_beam_fraction(h);
            assert!(f > last, "{h}: {f}");
            last = f;
        }
        // ... then flat within the two fits' disagreement: 0.84 at 30°, 0.77 at the zenith.
        for h in [30.0, 45.0, 60.0, 75.0, 90.0] {
            let f = direct_beam_fraction(h);
            assert!((0.75..0.86).contains(&f), "{h}: {f}");
        }
        assert!(direct_beam_fraction(5.0) < 0.25 && direct_beam_fraction(20.0) > 0.7);
    }

    fn at(lat: f64, lon: f64, y: i32, mo: u32, d: u32, h: u32) -> Ephemeris {
        let obs = Observer::new(lat, lon, 0.0).unwrap();
        ephemeris(&obs, UtcTime::from_calendar(y, mo, d, h, 0, 0.0).unwrap())
    }

    #[test]
    fn a_full_moon_night_gives_a_tenth_of_a_2856_k_lux() {
        // Full moon 2024-12-15 09:02 UTC, near +25° declination: at 08:00 UTC it stands
        // near 75° over 35° N 120° W.
        let e = at(35.0, -120.0, 2024, 12, 15, 8);
        assert!(
            e.moon.altitude_deg > 60.0 && e.sun.altitude_deg < -18.0,
            "{e:?}"
        );
        let lux = crate::natural_illuminance(&e, 0.0).unwrap();
        let n = nvg_irradiance(&e, 0.0).unwrap();
        // Documented band: a high full moon's 0.2-0.3 lux at 0.34-0.57 lx_A per lux plus
        // 0.008 lx_A of night sky.
        assert!((0.2..0.3).contains(&lux.moon_lux), "{lux:?}");
        assert!((0.075..0.18).contains(&n.total_lxa), "{n:?}");
        assert!(
            n.moon_lxa > n.sky_lxa && n.sky_lxa > n.night_sky_lxa,
            "{n:?}"
        );
        assert!(n.sun_lxa == 0.0);
        let per_lux = (n.moon_lxa + n.sky_lxa) / lux.moon_lux;
        assert!(per_lux > MOONLIT_SKY_NVG_PER_LUX && per_lux < MOON_NVG_PER_LUX);
        let sum = n.sun_lxa + n.moon_lxa + n.sky_lxa + n.night_sky_lxa;
        assert!((sum - n.total_lxa).abs() < 1e-15);
        assert!((n.total_w_m2 - n.total_lxa * NVG_W_M2_PER_LXA).abs() < 1e-18);
    }

    #[test]
    fn moonless_night_is_richer_than_noon_and_cloud_divides() {
        // Greenwich, new moon 2024-01-11 11:57 UTC: midnight moonless, noon sunlit.
        let night = at(51.4779, 0.0, 2024, 1, 11, 0);
        let noon = at(51.4779, 0.0, 2024, 1, 11, 12);
        assert!(night.moon.altitude_deg < -10.0 && night.sun.altitude_deg < -18.0);
        let ratio = |e: &Ephemeris| {
            nvg_irradiance(e, 0.0).unwrap().total_lxa
                / crate::natural_illuminance(e, 0.0).unwrap().total_lux
        };
        let (r_night, r_noon) = (ratio(&night), ratio(&noon));
        assert!(
            r_night > 3.0 && r_night <= NIGHT_SKY_NVG_PER_LUX,
            "{r_night}"
        );
        assert!(
            r_noon > SUNLIT_SKY_NVG_PER_LUX && r_noon < SUN_NVG_PER_LUX,
            "{r_noon}"
        );
        let clear = nvg_irradiance(&noon, 0.0).unwrap();
        let overcast = nvg_irradiance(&noon, 1.0).unwrap();
        assert!((clear.total_lxa / overcast.total_lxa - 10.0).abs() < 1e-9);
        assert!(nvg_irradiance(&noon, 1.5).is_err());
        assert!(nvg_irradiance(&noon, f64::NAN).is_err());
        // Twilight (sun below the horizon): all skylight, no direct beam.
        let dusk = at(51.4779, 0.0, 2024, 1, 11, 17);
        assert!(
            (-12.0..-1.0).contains(&dusk.sun.altitude_deg),
            "{}",
            dusk.sun.altitude_deg
        );
        let n = nvg_irradiance(&dusk, 0.0).unwrap();
        assert!(n.sun_lxa == 0.0 && n.sky_lxa > n.night_sky_lxa, "{n:?}");
    }

    proptest! {
        #[test]
        fn blackbody_weighting_falls_with_temperature(t in 1000.0f64..10_000.0) {
            let a = blackbody_nvg_per_lux(t);
            let b = blackbody_nvg_per_lux(t + 10.0);
            prop_assert!(b < a, "{t}: {a} -> {b}");
            prop_assert!(a.is_finite() && a > 0.0);
        }
    }
}
