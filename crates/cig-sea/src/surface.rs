//! The wave surface, deterministic in (seed, time): FFT cascades with choppy crests plus the
//! host's explicit waves, sampled on the CPU and handed to the renderer as grids.
//!
//! Algorithm (Tessendorf 2001, "Simulating Ocean Water", with the spectrum of
//! [`crate::spectrum`] after Horvath 2015):
//!
//! - **Amplitudes.** Each cascade is a periodic tile of `size²` points over `tile_m²` metres; its
//!   wave vectors are `k = 2π (p, q) / tile_m`. At each `k` a complex Gaussian `ξ` (two standard
//!   normals from a ChaCha8 generator keyed by the seed and the cascade's index, through
//!   Box-Muller) gives `a(k) = ξ √(P(k) Δk²) / 2`, `P` the directional wave-number spectrum
//!   (averaged over the cell for cells within 8 steps of the origin, where it varies fastest),
//!   so that a wave travelling toward `k` has mean variance `P(k) Δk²`. Each cascade's
//!   amplitudes are then scaled by one factor so the cascade holds exactly its expected variance:
//!   the amplitudes keep their Rayleigh spread, but the tile's Hs does not wander with the seed
//!   (the first tile holds few peak waves in a strong wind: unscaled, the measured Hs of sea
//!   state 8 scattered by 9 % (standard deviation over 24 seeds), up to 22 % from the mean).
//! - **Time.** `ĥ(k, t) = a(k) e^(-iωt) + conj(a(-k)) e^(iωt)`, `ω` from the dispersion
//!   relation with the depth; `ĥ(-k) = conj(ĥ(k))`, so the surface is real. The `k = 0` term and
//!   the Nyquist row and column (`p` or `q` = `size/2`) are zero.
//! - **Channels.** Inverse FFTs give the height `h`, the choppy horizontal displacement
//!   `D = λ Σ i k/|k| ĥ e^(ik·x)` (λ the choppiness; this sign moves points toward the crests, as
//!   Gerstner's trochoid does), the slopes `∂h/∂x`, `∂h/∂y` and the displacement's gradient
//!   `∂Dx/∂x`, `∂Dy/∂y`, `∂Dx/∂y` (= `∂Dy/∂x`), whose Jacobian
//!   `J = (1 + ∂Dx/∂x)(1 + ∂Dy/∂y) - (∂Dx/∂y)²` is below 1 where the surface is compressed and
//!   negative where it folds. The gradient is that of the *breaking-scale* displacement: each
//!   wave's share is weighted by `1 / (1 + (k / kb)⁴)`, `kb = 2π / 4 m`, so waves shorter than
//!   a few metres (which break as micro-breakers, without the air entrainment of a whitecap)
//!   barely compress it. Without this filter the Jacobian's spread grows only with the logarithm
//!   of the wind (the Pierson-Moskowitz tail is the same at every wind up to the grid's finest
//!   waves), and no threshold can follow Monahan's `U^3.41`. Two real channels share one complex
//!   FFT (`A + iB`, both Hermitian), so 8 channels cost 4 FFTs of `size²` per cascade; the 2-D
//!   FFT is rows, one transpose, rows (in `f32`). The default configuration updates in about
//!   0.9 ms on one core (release, x86-64 with AVX2).
//! - **Cascades.** The tiles (default 1000, 137 and 19.3 m of 128² points: not multiples of each
//!   other, so their repetitions do not line up) split the wave numbers into bands: cascade `i`
//!   keeps `|k|` in `[kᵢ₋₁, kᵢ)` where `kᵢ` is half its Nyquist wave number `π size / (2 tile)`
//!   (its shortest waves have 4 points each); the first starts at its first harmonic and the
//!   last runs to its Nyquist. Default bands: wavelengths above 31 m, 4.3 to 31 m and 0.3 to
//!   4.3 m; the 20 m/s peak (350 m) is 45 grid points long in the first cascade.
//! - **Explicit waves** (CIGI Wave Control): Gerstner waves added to the sampled height and
//!   displacement ([`WaveComponent`]); they are not in the grids (the renderer adds them). A
//!   wave applies everywhere or only over an area ([`WaveArea`]: a region's rounded rectangle
//!   or an entity's disc, fading out across a band), entities' areas taking precedence over
//!   regions' and regions' over the global waves; the weight scales the wave's height and
//!   displacement at the undisplaced point (its own gradient, over a band of hundreds of
//!   metres, is left out of the slopes).
//! - **Sampling.** A query at a horizontal position finds the undisplaced point `x0` whose
//!   displaced position `x0 + D(x0)` lands on it by Newton's method on the displacement (4
//!   steps, a plain fixed-point step where the surface folds), interpolating each cascade
//!   bilinearly with periodic wrap and summing.
//! - **Statistics** ([`SeaSurface::measure`]) are measured from the simulated surface, see
//!   [`SeaStats`].
//!
//! Whitecaps: a point is whitecap where its (breaking-scale) Jacobian, summed over the
//! cascades and explicit waves, is below [`WHITECAP_JACOBIAN`]. Calibration: the breaking scale
//! (4 m) and the threshold (0.8) are two constants for the default choppiness (1), chosen once
//! so the measured fraction follows Monahan and O'Muircheartaigh within a factor of 2 at 10 and
//! 15 m/s. Measured over 8 seeds and 2 times (the `whitecap_calibration` test): none at 3 m/s
//! (Monahan 0.016 %), 0.04 % at 5 (0.09 %), 1.27 % at 10 (0.99 %), 2.7 % at 15 (3.9 %), 3.8 %
//! at 20 (10.5 %): the fraction grows more slowly than Monahan's above 15 m/s. Another
//! choppiness scales the compression and so the coverage.
//!
//! Limits: linear waves (the choppy displacement only sharpens crests); the normal and the
//! inversion use the breaking-scale gradient, so they ignore the horizontal compression of
//! waves shorter than a few metres (their slopes are in the normal); the spectrum is frozen at
//! construction (new conditions need a new surface); the tiles repeat; waves longer than the
//! largest tile or shorter than the last cascade's Nyquist are absent (the measured Hs is 6 %
//! low at 3 m/s, where the tail beyond 0.3 m matters); bilinear interpolation softens each
//! cascade's shortest waves; the explicit waves are not in the renderer's grids.
//! Determinism: the amplitudes are the same on every machine up to the last bit of `ln`, `sin`
//! and `cos`; the surface at a time is bit-identical between instances on one machine and build,
//! and equal to float rounding across machines (the FFT's SIMD path depends on the processor).

use std::f64::consts::{PI, TAU};
use std::fmt;
use std::sync::Arc;

use rand_chacha::rand_core::{RngCore, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rustfft::num_complex::Complex32;
use rustfft::{Fft, FftPlanner};

use crate::spectrum::{dispersion_omega_rad_s, SeaConditions, SpectrumModel};
use crate::{checked, SeaError};

/// A point is whitecap where the surface's (breaking-scale) Jacobian, summed over the cascades,
/// is below this (the module doc gives the calibration).
pub const WHITECAP_JACOBIAN: f64 = 0.8;

/// The breaking scale: the displacement's gradient (so the Jacobian) keeps waves longer than
/// this, rolling off as `1 / (1 + (k / kb)⁴)`, `kb = 2π / 4 m` (see the module doc).
const BREAKING_WAVELENGTH_M: f64 = 4.0;
/// Newton steps of [`SeaSurface::sample`]'s inversion of the displacement.
const SAMPLE_ITERATIONS: usize = 4;
/// Below this Jacobian the inversion takes a fixed-point step instead of a Newton step.
const NEWTON_MIN_JACOBIAN: f64 = 0.2;
/// Cells within this many steps of the origin average the spectrum over 4×4 points.
const CELL_AVERAGE_RADIUS: isize = 8;
const CELL_AVERAGE_POINTS: u32 = 4;
/// The sum of the explicit waves' `k b` (displacement amplitude times wave number) is kept at
/// or below this, so their crests never loop.
const MAX_GERSTNER_STEEPNESS: f64 = 0.9;
/// Half-width, in `ln f`, of the window over which [`SeaSurface::measure`] smooths the realised
/// periodogram (±10 %).
const PERIODOGRAM_HALF_WIDTH: f64 = 0.1;
/// Mixed into the generator's key so the sea draws differ from other users of the same seed.
const SEED_DOMAIN: u64 = 0x5EA5_0CEA_4E5E_ED00;

/// One FFT cascade: a periodic tile of `size × size` points.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cascade {
    /// The tile's side, metres.
    pub tile_m: f64,
    /// Points along a side: a power of two in `8..=4096`.
    pub size: usize,
}

/// The surface's cascades and choppiness.
#[derive(Clone, Debug, PartialEq)]
pub struct SurfaceConfig {
    /// The cascades, largest tile first (1 to 8 of them); see the module doc for their bands.
    pub cascades: Vec<Cascade>,
    /// The choppy displacement's scale λ (`0..=4`; 1 is Gerstner's trochoid, 0 no displacement).
    pub choppiness: f64,
}

impl Default for SurfaceConfig {
    /// Three cascades of 128²: 1000, 137 and 19.3 m, choppiness 1.
    fn default() -> SurfaceConfig {
        SurfaceConfig {
            cascades: [1000.0, 137.0, 19.3]
                .into_iter()
                .map(|tile_m| Cascade { tile_m, size: 128 })
                .collect(),
            choppiness: 1.0,
        }
    }
}

impl SurfaceConfig {
    /// Checks the configuration.
    ///
    /// # Errors
    /// [`SeaError::OutOfRange`] for no cascade or more than 8, a size that is not a power of two
    /// in `8..=4096`, a tile that is not finite and positive, a cascade whose band would not lie
    /// above the previous one's (each cascade's `size / tile` must exceed the previous one's), or
    /// a choppiness outside `0..=4`.
    pub fn validate(&self) -> Result<(), SeaError> {
        #[expect(clippy::cast_precision_loss, reason = "a count of a few cascades")]
        let count = self.cascades.len() as f64;
        checked("cascade count", count, 1.0, 8.0, "in 1..=8")?;
        checked("choppiness", self.choppiness, 0.0, 4.0, "in 0..=4")?;
        let mut previous_band_top = 0.0;
        for cascade in &self.cascades {
            #[expect(clippy::cast_precision_loss, reason = "sizes are at most 4096")]
            let size = cascade.size as f64;
            if !cascade.size.is_power_of_two() || !(8..=4096).contains(&cascade.size) {
                return Err(SeaError::OutOfRange {
                    name: "cascade size",
                    range: "a power of two in 8..=4096",
                    value: size,
                });
            }
            checked(
                "cascade tile",
                cascade.tile_m,
                1e-3,
                1e6,
                "in 0.001..=1e6 m",
            )?;
            let band_top = band_top_rad_m(cascade);
            if band_top <= previous_band_top {
                return Err(SeaError::OutOfRange {
                    name: "cascade tile",
                    range: "such that size / tile grows from each cascade to the next",
                    value: cascade.tile_m,
                });
            }
            previous_band_top = band_top;
        }
        Ok(())
    }

    /// The band `[lo, hi)` of wave numbers, rad/m, each cascade carries (the last runs to its
    /// Nyquist: `hi` is infinite).
    pub fn bands_rad_m(&self) -> Vec<(f64, f64)> {
        let count = self.cascades.len();
        (0..count)
            .map(|i| {
                let lo = if i == 0 {
                    0.0
                } else {
                    band_top_rad_m(&self.cascades[i - 1])
                };
                let hi = if i + 1 == count {
                    f64::INFINITY
                } else {
                    band_top_rad_m(&self.cascades[i])
                };
                (lo, hi)
            })
            .collect()
    }
}

/// Half a cascade's Nyquist wave number, `π size / (2 tile)`: where the next cascade takes over.
fn band_top_rad_m(cascade: &Cascade) -> f64 {
    #[expect(clippy::cast_precision_loss, reason = "sizes are at most 4096")]
    let size = cascade.size as f64;
    PI * size / (2.0 * cascade.tile_m)
}

/// One of the host's explicit waves (CIGI Wave Control), a Gerstner wave.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WaveComponent {
    /// Trough-to-crest height, metres (`0..=30`).
    pub height_m: f64,
    /// Crest-to-crest length, metres (`0.1..=5000`).
    pub wavelength_m: f64,
    /// Period, seconds (`0.1..=100`); the host may give any period, not only the dispersion's.
    pub period_s: f64,
    /// Direction the wave travels toward, degrees true.
    pub direction_deg: f64,
    /// Phase at the origin at time 0, degrees (0: a crest at the origin).
    pub phase_deg: f64,
    /// Crest shape, `0..=1`: 0 a sinusoid, toward 1 a trochoid with sharper crests and flatter
    /// troughs (the horizontal displacement's amplitude is `leading` times half the height,
    /// reduced if the explicit waves together would loop).
    pub leading: f64,
}

impl WaveComponent {
    /// A checked wave; the directions are wrapped to `[0, 360)`.
    ///
    /// # Errors
    /// [`SeaError::OutOfRange`] for a value outside the ranges of the fields.
    pub fn new(
        height_m: f64,
        wavelength_m: f64,
        period_s: f64,
        direction_deg: f64,
        phase_deg: f64,
        leading: f64,
    ) -> Result<WaveComponent, SeaError> {
        let wave = WaveComponent {
            height_m,
            wavelength_m,
            period_s,
            direction_deg: direction_deg.rem_euclid(360.0),
            phase_deg: phase_deg.rem_euclid(360.0),
            leading,
        };
        // NaN or infinite directions stay NaN through rem_euclid, so validate catches them.
        wave.validate()?;
        Ok(wave)
    }

    /// Checks the fields (they are public, so a wave built by hand may be out of range).
    ///
    /// # Errors
    /// As [`WaveComponent::new`].
    pub fn validate(&self) -> Result<(), SeaError> {
        checked("wave height", self.height_m, 0.0, 30.0, "in 0..=30 m")?;
        checked(
            "wavelength",
            self.wavelength_m,
            0.1,
            5000.0,
            "in 0.1..=5000 m",
        )?;
        checked("wave period", self.period_s, 0.1, 100.0, "in 0.1..=100 s")?;
        let finite = "finite degrees";
        checked(
            "wave direction",
            self.direction_deg,
            f64::MIN,
            f64::MAX,
            finite,
        )?;
        checked("wave phase", self.phase_deg, f64::MIN, f64::MAX, finite)?;
        checked("wave leading", self.leading, 0.0, 1.0, "in 0..=1")?;
        Ok(())
    }
}

/// An explicit wave ready to evaluate: at the undisplaced point `x` (east, north of the sea's
/// origin) and time `t` its phase is `φ = k (d · x) − ω t + phase`, its height `a cos φ` and its
/// horizontal displacement `−b d sin φ` (what [`SeaSurface::sample`] adds and the renderer
/// draws).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GerstnerWave {
    /// Unit vector of travel (east, north).
    pub direction: [f64; 2],
    pub k_rad_m: f64,
    pub omega_rad_s: f64,
    /// Half the trough-to-crest height, metres.
    pub amplitude_m: f64,
    /// Horizontal displacement amplitude `b`, metres.
    pub displacement_m: f64,
    pub phase_rad: f64,
}

/// Which host waves an area holds (CIGI Wave Control's scope), for the precedence between
/// them.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AreaKind {
    /// An environmental region's waves.
    Region,
    /// An entity's surroundings' waves.
    Entity,
}

/// An area of the sea's plane some explicit waves are confined to: a rectangle with rounded
/// corners (a CIGI Environmental Region; an entity's surroundings are a square of side twice
/// the corner radius, a disc), and a band around it over which its waves fade out.
///
/// Weight of a point: 1 inside; across the transition band, `smoothstep` of the distance
/// from the rounded rectangle's edge (1 at the edge, 0 at `transition_m` out, at least
/// [`MIN_AREA_BAND_M`]); 0 beyond.
/// Precedence (as CIGI's regional conditions over its global ones): where entities' areas
/// cover a point by `E` (their weights summed, at most 1) and regions' by `R`, an entity's
/// wave has its area's weight, a region's wave its area's weight times `1 − E`, and a global
/// wave `(1 − E)(1 − R)`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WaveArea {
    /// The centre, metres east and north of the sea's origin.
    pub centre_m: [f64; 2],
    /// Half the rectangle's size along its own x and y axes, metres (`0..=1e7`).
    pub half_size_m: [f64; 2],
    /// The rectangle's x axis turned clockwise from east by this, degrees (finite).
    pub rotation_deg: f64,
    /// The corners' radius, metres (`0..=1e7`; at most the smaller half size counts, unless
    /// the rectangle has no size: a disc).
    pub corner_radius_m: f64,
    /// The transition band's width, metres (`0..=1e7`; under [`MIN_AREA_BAND_M`] taken as
    /// that).
    pub transition_m: f64,
    /// Whose waves the area holds (for the precedence).
    pub kind: AreaKind,
}

impl WaveArea {
    /// Checks the fields.
    ///
    /// # Errors
    /// [`SeaError::OutOfRange`] for a value outside its range.
    pub fn validate(&self) -> Result<(), SeaError> {
        let finite = "finite, within ±1e9 m";
        checked("area centre", self.centre_m[0], -1e9, 1e9, finite)?;
        checked("area centre", self.centre_m[1], -1e9, 1e9, finite)?;
        for half in self.half_size_m {
            checked("area half size", half, 0.0, 1e7, "in 0..=1e7 m")?;
        }
        checked(
            "area rotation",
            self.rotation_deg,
            -1e6,
            1e6,
            "finite degrees",
        )?;
        checked(
            "area corner radius",
            self.corner_radius_m,
            0.0,
            1e7,
            "in 0..=1e7 m",
        )?;
        checked(
            "area transition",
            self.transition_m,
            0.0,
            1e7,
            "in 0..=1e7 m",
        )?;
        Ok(())
    }

    /// The weight of the point (`x_m`, `y_m`) of the sea's plane, `0..=1`.
    pub fn weight(&self, x_m: f64, y_m: f64) -> f64 {
        let (dx, dy) = (x_m - self.centre_m[0], y_m - self.centre_m[1]);
        let (sin, cos) = self.rotation_deg.to_radians().sin_cos();
        // Into the rectangle's axes (its x axis turned clockwise from east).
        let (u, v) = (dx * cos - dy * sin, dx * sin + dy * cos);
        let [hx, hy] = self.half_size_m;
        let radius = if hx > 0.0 || hy > 0.0 {
            self.corner_radius_m.min(hx.min(hy))
        } else {
            self.corner_radius_m
        };
        // Signed distance from the rounded rectangle's edge (negative inside).
        let (qx, qy) = (
            u.abs() - (hx - radius).max(0.0),
            v.abs() - (hy - radius).max(0.0),
        );
        let outside = qx.max(0.0).hypot(qy.max(0.0)) + qx.max(qy).min(0.0);
        let distance = outside - radius;
        let band = self.band_m();
        if distance <= 0.0 {
            1.0
        } else if distance >= band {
            0.0
        } else {
            let t = 1.0 - distance / band;
            t * t * (3.0 - 2.0 * t)
        }
    }

    /// The band the weight falls across, metres: the transition, at least
    /// [`MIN_AREA_BAND_M`] (the sea has no cliff at a hard edge).
    pub fn band_m(&self) -> f64 {
        self.transition_m.max(MIN_AREA_BAND_M)
    }
}

/// An area's waves fade out over at least this, metres, even with no transition asked for:
/// the weight's slope (at most 1.5 over the band) times a wave's amplitude stays a gentle
/// slope of the sea, which line of sight can bound.
pub const MIN_AREA_BAND_M: f64 = 50.0;

/// How much entities' and regions' areas cover a point (see [`WaveArea`]).
#[derive(Clone, Copy, Debug)]
struct AreaPrecedence {
    entities: f64,
    regions: f64,
}

impl AreaPrecedence {
    fn at(areas: &[WaveArea], x_m: f64, y_m: f64) -> AreaPrecedence {
        let mut cover = AreaPrecedence {
            entities: 0.0,
            regions: 0.0,
        };
        for area in areas {
            let w = area.weight(x_m, y_m);
            match area.kind {
                AreaKind::Entity => cover.entities += w,
                AreaKind::Region => cover.regions += w,
            }
        }
        cover.entities = cover.entities.min(1.0);
        cover.regions = cover.regions.min(1.0);
        cover
    }

    /// The weight at (`x_m`, `y_m`) of a wave placed in `area` (`None`: global).
    fn weight(&self, areas: &[WaveArea], area: Option<usize>, x_m: f64, y_m: f64) -> f64 {
        match area.and_then(|i| areas.get(i)) {
            None if area.is_some() => 0.0,
            None => (1.0 - self.entities) * (1.0 - self.regions),
            Some(a) => match a.kind {
                AreaKind::Entity => a.weight(x_m, y_m),
                AreaKind::Region => a.weight(x_m, y_m) * (1.0 - self.entities),
            },
        }
    }
}

/// One travelling linear wave: at the undisplaced point `x` (east, north of the sea's origin)
/// and time `t` its height is `Re(A e^(i (k·x − ω t)))`, `A` its complex amplitude.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LinearWave {
    /// Wave vector (east, north), rad/m: the wave travels toward it.
    pub k_rad_m: [f64; 2],
    pub omega_rad_s: f64,
    /// Complex amplitude `A` (real, imaginary), metres.
    pub amplitude_m: [f64; 2],
}

impl LinearWave {
    /// The height, metres, at (`x_m`, `y_m`) at `t_s`.
    pub fn height_m(&self, x_m: f64, y_m: f64, t_s: f64) -> f64 {
        let phase = self.k_rad_m[0] * x_m + self.k_rad_m[1] * y_m - self.omega_rad_s * t_s;
        let (sin, cos) = phase.sin_cos();
        self.amplitude_m[0] * cos - self.amplitude_m[1] * sin
    }
}

/// One cascade's grids at the current time, for the renderer (textures) and the sampler.
///
/// Layout: row-major, `size × size`; the value at index `j * size + i` is at `x = i tile / size`
/// metres east and `y = j tile / size` metres north of the sea's origin (modulo the tile), the
/// undisplaced position of that surface point. Values are this cascade's share only; the surface
/// is the sum over the cascades.
#[derive(Clone, Debug, PartialEq)]
pub struct CascadeGrid {
    /// The tile's side, metres.
    pub tile_m: f64,
    /// Points along a side.
    pub size: usize,
    /// Height (m), displacement east and north (m), and this cascade's own Jacobian
    /// `(1 + ∂Dx/∂x)(1 + ∂Dy/∂y) - (∂Dx/∂y)²` of its breaking-scale displacement (see the module
    /// doc; for foam, sum the gradients over the cascades instead).
    pub height_displacement: Vec<[f32; 4]>,
    /// The height's slopes `∂h/∂x`, `∂h/∂y` (with respect to the undisplaced position).
    pub slopes: Vec<[f32; 2]>,
    /// The breaking-scale displacement's gradient `∂Dx/∂x`, `∂Dy/∂y`, `∂Dx/∂y` (= `∂Dy/∂x`):
    /// summed over the cascades it gives the surface's Jacobian, whose values below
    /// [`WHITECAP_JACOBIAN`] are whitecaps (the renderer's foam).
    pub displacement_gradient: Vec<[f32; 3]>,
}

impl CascadeGrid {
    fn new(cascade: &Cascade) -> CascadeGrid {
        let points = cascade.size * cascade.size;
        CascadeGrid {
            tile_m: cascade.tile_m,
            size: cascade.size,
            height_displacement: vec![[0.0, 0.0, 0.0, 1.0]; points],
            slopes: vec![[0.0; 2]; points],
            displacement_gradient: vec![[0.0; 3]; points],
        }
    }
}

/// The surface at a horizontal position.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SeaSample {
    /// Elevation above the mean sea level, metres.
    pub height_m: f64,
    /// Unit normal (east, north, up) of the displaced surface.
    pub normal: [f64; 3],
    /// The horizontal displacement (east, north), metres, of the surface point found there
    /// (`undisplaced_m + displacement_m` is the query position, to the inversion's accuracy).
    pub displacement_m: [f64; 2],
    /// The undisplaced position (east, north), metres, of the surface point found there (its
    /// displaced position lands on the query position to better than 1 mm).
    pub undisplaced_m: [f64; 2],
    /// The Jacobian of the breaking-scale displacement there (cascades and explicit waves): 1
    /// undisturbed, below 1 compressed (crests), negative folded; whitecap below
    /// [`WHITECAP_JACOBIAN`].
    pub jacobian: f64,
}

/// Statistics measured from the simulated surface ([`SeaSurface::measure`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SeaStats {
    /// Significant wave height, metres: 4 times the standard deviation of the elevation of the
    /// displaced surface (each point weighted by its area, the Jacobian: what a buoy sees), over
    /// the first cascade's grid points with every cascade and explicit wave summed, the variance
    /// averaged over the times.
    pub hs_m: f64,
    /// Peak period, seconds, from the realised amplitudes: each mode's variance put at its
    /// frequency (and each explicit wave's), the periodogram density per unit frequency smoothed
    /// over ±10 % in frequency, and the energy-weighted mean frequency inside the densest window
    /// inverted. It does not depend on the times.
    pub peak_period_s: f64,
    /// The fraction of the displaced surface's area whose (breaking-scale) Jacobian is below
    /// [`WHITECAP_JACOBIAN`], over the same points, averaged over the times (the calibration is
    /// in the module doc).
    pub whitecap_fraction: f64,
    /// Mean elevation of the displaced surface, metres (slightly negative with choppy crests).
    pub mean_m: f64,
}

/// A wave mode of a cascade: the wave vector `k` (a half-plane representative) and its mirror.
#[derive(Clone, Copy, Debug)]
struct Mode {
    /// Indices of `k` and `-k` in the spectrum buffer, laid out kx-major (`p * size + q`).
    index: usize,
    mirror: usize,
    omega_rad_s: f64,
    /// `a(k)` and `conj(a(-k))`.
    a: Complex32,
    b: Complex32,
    kx_rad_m: f32,
    ky_rad_m: f32,
    /// `kx / |k|`, `ky / |k|`.
    ux: f32,
    uy: f32,
    /// The breaking-scale filter's weight on the displacement's gradient.
    breaking_weight: f32,
}

/// A cascade's modes and FFT.
#[derive(Clone)]
struct CascadeSynth {
    size: usize,
    modes: Vec<Mode>,
    fft: Arc<dyn Fft<f32>>,
}

/// Buffers reused by every update.
#[derive(Clone, Debug, Default)]
struct Workspace {
    spectra: [Vec<Complex32>; 4],
    transposed: Vec<Complex32>,
    scratch: Vec<Complex32>,
}

/// The sea surface: FFT cascades plus explicit waves, deterministic in (seed, time).
#[derive(Clone)]
pub struct SeaSurface {
    conditions: SeaConditions,
    seed: u64,
    config: SurfaceConfig,
    synths: Vec<CascadeSynth>,
    grids: Vec<CascadeGrid>,
    explicit: Vec<WaveComponent>,
    gerstner: Vec<GerstnerWave>,
    /// Where each explicit wave applies: `None` everywhere, else its area in `areas`.
    placed: Vec<Option<usize>>,
    areas: Vec<WaveArea>,
    workspace: Workspace,
    time_s: f64,
}

impl fmt::Debug for SeaSurface {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("SeaSurface")
            .field("conditions", &self.conditions)
            .field("seed", &self.seed)
            .field("config", &self.config)
            .field("explicit", &self.explicit)
            .field("time_s", &self.time_s)
            .finish_non_exhaustive()
    }
}

/// The channels summed at a point, all with respect to the undisplaced position.
#[derive(Clone, Copy, Debug, Default)]
struct Fields {
    h: f64,
    dx: f64,
    dy: f64,
    hx: f64,
    hy: f64,
    dxx: f64,
    dyy: f64,
    dxy: f64,
}

impl Fields {
    fn jacobian(&self) -> f64 {
        (1.0 + self.dxx) * (1.0 + self.dyy) - self.dxy * self.dxy
    }
}

impl SeaSurface {
    /// A surface for `conditions`, its random amplitudes drawn from `seed`, at time 0.
    ///
    /// # Errors
    /// [`SeaError::OutOfRange`] for conditions or a configuration out of range.
    pub fn new(
        conditions: &SeaConditions,
        seed: u64,
        config: SurfaceConfig,
    ) -> Result<SeaSurface, SeaError> {
        SeaSurface::build(conditions, seed, config, TAU / BREAKING_WAVELENGTH_M)
    }

    fn build(
        conditions: &SeaConditions,
        seed: u64,
        config: SurfaceConfig,
        breaking_k_rad_m: f64,
    ) -> Result<SeaSurface, SeaError> {
        conditions.validate()?;
        config.validate()?;
        let model = conditions.model();
        let mut planner = FftPlanner::<f32>::new();
        let synths: Vec<CascadeSynth> = config
            .cascades
            .iter()
            .zip(config.bands_rad_m())
            .enumerate()
            .map(|(index, (cascade, band))| CascadeSynth {
                size: cascade.size,
                modes: cascade_modes(&model, cascade, band, seed, index as u64, breaking_k_rad_m),
                fft: planner.plan_fft_inverse(cascade.size),
            })
            .collect();
        let scratch_len = synths
            .iter()
            .map(|synth| synth.fft.get_inplace_scratch_len())
            .max()
            .unwrap_or(0);
        let workspace = Workspace {
            scratch: vec![Complex32::default(); scratch_len],
            ..Workspace::default()
        };
        let grids = config.cascades.iter().map(CascadeGrid::new).collect();
        let mut surface = SeaSurface {
            conditions: conditions.clone(),
            seed,
            config,
            synths,
            grids,
            explicit: Vec::new(),
            gerstner: Vec::new(),
            placed: Vec::new(),
            areas: Vec::new(),
            workspace,
            time_s: 0.0,
        };
        surface.synthesise();
        Ok(surface)
    }

    /// The conditions the surface was built for.
    pub fn conditions(&self) -> &SeaConditions {
        &self.conditions
    }

    /// The seed of the random amplitudes.
    pub fn seed(&self) -> u64 {
        self.seed
    }

    /// The cascades and choppiness.
    pub fn config(&self) -> &SurfaceConfig {
        &self.config
    }

    /// The time of the grids, seconds.
    pub fn time_s(&self) -> f64 {
        self.time_s
    }

    /// The grids of each cascade at [`SeaSurface::time_s`], largest tile first.
    pub fn grids(&self) -> &[CascadeGrid] {
        &self.grids
    }

    /// The explicit waves.
    pub fn explicit_waves(&self) -> &[WaveComponent] {
        &self.explicit
    }

    /// The explicit waves as evaluated (their crests' displacement limited against looping).
    pub fn gerstner_waves(&self) -> &[GerstnerWave] {
        &self.gerstner
    }

    /// Where each explicit wave applies (as [`SeaSurface::explicit_waves`]): `None`
    /// everywhere, else the index of its area in [`SeaSurface::wave_areas`].
    pub fn explicit_wave_areas(&self) -> &[Option<usize>] {
        &self.placed
    }

    /// The areas the explicit waves are confined to.
    pub fn wave_areas(&self) -> &[WaveArea] {
        &self.areas
    }

    /// The surface as travelling linear waves (the cascades' modes, each `k` and `-k`, then the
    /// explicit waves): where every explicit wave applies in full (as with no areas), the
    /// height of the undisplaced point `x` at time `t` is the sum of their
    /// [`LinearWave::height_m`] (the choppy displacement and the grids' bilinear interpolation
    /// aside); with areas, take [`SeaSurface::spectral_linear_waves`] and
    /// [`SeaSurface::explicit_linear_waves`] with the weights at the place.
    pub fn linear_waves(&self) -> Vec<LinearWave> {
        let mut waves = self.spectral_linear_waves();
        waves.extend(self.explicit_linear_waves(&vec![1.0; self.gerstner.len()]));
        waves
    }

    /// The explicit waves as linear waves, each scaled by its weight (as
    /// [`SeaSurface::explicit_weights_at`] gives them at a place); a weight of 0 leaves the
    /// wave out.
    pub fn explicit_linear_waves(&self, weights: &[f64]) -> Vec<LinearWave> {
        self.gerstner
            .iter()
            .zip(weights)
            .filter(|(_, weight)| **weight > 0.0)
            .map(|(wave, weight)| {
                let [ex, ey] = wave.direction;
                let (sin, cos) = wave.phase_rad.sin_cos();
                let amplitude_m = weight * wave.amplitude_m;
                LinearWave {
                    k_rad_m: [wave.k_rad_m * ex, wave.k_rad_m * ey],
                    omega_rad_s: wave.omega_rad_s,
                    amplitude_m: [amplitude_m * cos, amplitude_m * sin],
                }
            })
            .collect()
    }

    /// How much of each explicit wave applies at the undisplaced point (`x_m`, `y_m`), `0..=1`
    /// (see [`WaveArea`] for the precedence of entities' areas over regions' over the
    /// global waves).
    pub fn explicit_weights_at(&self, x_m: f64, y_m: f64) -> Vec<f64> {
        let precedence = AreaPrecedence::at(&self.areas, x_m, y_m);
        self.placed
            .iter()
            .map(|area| precedence.weight(&self.areas, *area, x_m, y_m))
            .collect()
    }

    /// The cascades' modes as travelling linear waves (each `k` and `-k`), without the
    /// explicit waves.
    pub fn spectral_linear_waves(&self) -> Vec<LinearWave> {
        let mut waves = Vec::new();
        for synth in &self.synths {
            for mode in &synth.modes {
                let (kx, ky) = (f64::from(mode.kx_rad_m), f64::from(mode.ky_rad_m));
                // h = Σ 2 Re(a e^{i(k·x − ωt)}) + 2 Re(b e^{i(k·x + ωt)}); the second is the wave
                // toward −k with amplitude 2 conj(b).
                let (a, b) = (mode.a, mode.b.conj());
                for (k, amplitude) in [([kx, ky], a), ([-kx, -ky], b)] {
                    if amplitude.norm_sqr() > 0.0 {
                        waves.push(LinearWave {
                            k_rad_m: k,
                            omega_rad_s: mode.omega_rad_s,
                            amplitude_m: [
                                2.0 * f64::from(amplitude.re),
                                2.0 * f64::from(amplitude.im),
                            ],
                        });
                    }
                }
            }
        }
        waves
    }

    /// Replaces the explicit waves (CIGI Wave Control), added to what [`SeaSurface::sample`]
    /// returns as Gerstner waves. If their crests together would loop (`Σ k b` above 0.9, `b`
    /// each wave's horizontal displacement amplitude), every `b` is scaled down to keep 0.9.
    ///
    /// # Errors
    /// [`SeaError::OutOfRange`] for a wave out of range (see [`WaveComponent::new`]); the waves
    /// are then left as they were.
    pub fn set_explicit_waves(&mut self, waves: Vec<WaveComponent>) -> Result<(), SeaError> {
        let placed = vec![None; waves.len()];
        self.set_placed_waves(waves, placed, Vec::new())
    }

    /// Replaces the explicit waves as [`SeaSurface::set_explicit_waves`] does, each applying
    /// where `placed` says (`None` everywhere, else only over that one of `areas`).
    ///
    /// # Errors
    /// [`SeaError::OutOfRange`] for a wave or area out of range, an area index past `areas`,
    /// or `placed` not one per wave; the waves are then left as they were.
    pub fn set_placed_waves(
        &mut self,
        waves: Vec<WaveComponent>,
        placed: Vec<Option<usize>>,
        areas: Vec<WaveArea>,
    ) -> Result<(), SeaError> {
        for wave in &waves {
            wave.validate()?;
        }
        for area in &areas {
            area.validate()?;
        }
        if placed.len() != waves.len() || placed.iter().flatten().any(|i| *i >= areas.len()) {
            #[expect(
                clippy::cast_precision_loss,
                reason = "a count of waves, for the message"
            )]
            return Err(SeaError::OutOfRange {
                name: "explicit wave areas",
                range: "one per wave, each naming an area given",
                value: placed.len() as f64,
            });
        }
        let mut gerstner: Vec<GerstnerWave> = waves
            .iter()
            .map(|wave| {
                let bearing = wave.direction_deg.to_radians();
                let amplitude_m = 0.5 * wave.height_m;
                GerstnerWave {
                    direction: [bearing.sin(), bearing.cos()],
                    k_rad_m: TAU / wave.wavelength_m,
                    omega_rad_s: TAU / wave.period_s,
                    amplitude_m,
                    displacement_m: wave.leading * amplitude_m,
                    phase_rad: wave.phase_deg.to_radians(),
                }
            })
            .collect();
        let steepness: f64 = gerstner
            .iter()
            .map(|wave| wave.k_rad_m * wave.displacement_m)
            .sum();
        if steepness > MAX_GERSTNER_STEEPNESS {
            let scale = MAX_GERSTNER_STEEPNESS / steepness;
            for wave in &mut gerstner {
                wave.displacement_m *= scale;
            }
        }
        self.explicit = waves;
        self.gerstner = gerstner;
        self.placed = placed;
        self.areas = areas;
        Ok(())
    }

    /// Computes the grids at `t_s` seconds.
    ///
    /// # Errors
    /// [`SeaError::OutOfRange`] for a time that is not finite or beyond ±1e9 s; the grids are
    /// then left as they were.
    pub fn update(&mut self, t_s: f64) -> Result<(), SeaError> {
        self.time_s = checked("time", t_s, -1e9, 1e9, "finite, within ±1e9 s")?;
        self.synthesise();
        Ok(())
    }

    /// The surface at `x_m` east and `y_m` north of the sea's origin at [`SeaSurface::time_s`]:
    /// the surface point whose displaced position lands there (explicit waves included).
    pub fn sample(&self, x_m: f64, y_m: f64) -> SeaSample {
        let mut x0 = [x_m, y_m];
        for _ in 0..SAMPLE_ITERATIONS {
            let fields = self.fields_at::<false>(x0[0], x0[1]);
            let residual = [x0[0] + fields.dx - x_m, x0[1] + fields.dy - y_m];
            let (a, d, c) = (1.0 + fields.dxx, 1.0 + fields.dyy, fields.dxy);
            let det = a * d - c * c;
            if det > NEWTON_MIN_JACOBIAN {
                x0[0] -= (d * residual[0] - c * residual[1]) / det;
                x0[1] -= (a * residual[1] - c * residual[0]) / det;
            } else {
                x0[0] -= residual[0];
                x0[1] -= residual[1];
            }
        }
        let fields = self.fields_at::<true>(x0[0], x0[1]);
        // The tangents along x0 and y0 are (1 + Dxx, Dxy, hx) and (Dxy, 1 + Dyy, hy).
        let (a, d, c) = (1.0 + fields.dxx, 1.0 + fields.dyy, fields.dxy);
        let jacobian = a * d - c * c;
        let cross = [
            c * fields.hy - fields.hx * d,
            fields.hx * c - a * fields.hy,
            jacobian,
        ];
        // Where the surface folds the cross product points down: keep the upper side.
        let sign = if jacobian < 0.0 { -1.0 } else { 1.0 };
        let length = (cross[0] * cross[0] + cross[1] * cross[1] + cross[2] * cross[2]).sqrt();
        let normal = if length > 0.0 {
            cross.map(|v| sign * v / length)
        } else {
            [0.0, 0.0, 1.0]
        };
        SeaSample {
            height_m: fields.h,
            normal,
            displacement_m: [fields.dx, fields.dy],
            undisplaced_m: x0,
            jacobian,
        }
    }

    /// The height, metres, of the surface point whose undisplaced position is (`x_m`, `y_m`)
    /// (no inversion of the displacement; explicit waves included).
    pub fn height_at_undisplaced(&self, x_m: f64, y_m: f64) -> f64 {
        self.fields_at::<true>(x_m, y_m).h
    }

    /// The displacement (east, north), metres, of the surface point whose undisplaced position
    /// is (`x_m`, `y_m`).
    pub fn displacement_at_undisplaced(&self, x_m: f64, y_m: f64) -> [f64; 2] {
        let fields = self.fields_at::<false>(x_m, y_m);
        [fields.dx, fields.dy]
    }

    /// Measures the surface's statistics (see [`SeaStats`]) at each of `times_s`; the surface is
    /// left at the last time.
    ///
    /// # Errors
    /// [`SeaError::OutOfRange`] for no time or a time out of range (see [`SeaSurface::update`]).
    pub fn measure(&mut self, times_s: &[f64]) -> Result<SeaStats, SeaError> {
        #[expect(clippy::cast_precision_loss, reason = "a count of times")]
        let count = times_s.len() as f64;
        checked("time count", count, 1.0, f64::MAX, "at least 1")?;
        let grid = self.config.cascades[0];
        #[expect(clippy::cast_precision_loss, reason = "sizes are at most 4096")]
        let spacing_m = grid.tile_m / grid.size as f64;
        let (mut variance_sum, mut mean_sum, mut whitecap_sum) = (0.0, 0.0, 0.0);
        for &t_s in times_s {
            self.update(t_s)?;
            let (mut area, mut height, mut height2, mut whitecap) = (0.0, 0.0, 0.0, 0.0);
            for j in 0..grid.size {
                for i in 0..grid.size {
                    #[expect(clippy::cast_precision_loss, reason = "indices below 4096")]
                    let (x_m, y_m) = (i as f64 * spacing_m, j as f64 * spacing_m);
                    let fields = self.fields_at::<true>(x_m, y_m);
                    let jacobian = fields.jacobian();
                    let weight = jacobian.max(0.0);
                    area += weight;
                    height += weight * fields.h;
                    height2 += weight * fields.h * fields.h;
                    if jacobian < WHITECAP_JACOBIAN {
                        whitecap += weight;
                    }
                }
            }
            // The area is about the number of points (the mean Jacobian is 1).
            let area = area.max(f64::MIN_POSITIVE);
            let mean = height / area;
            mean_sum += mean;
            variance_sum += (height2 / area - mean * mean).max(0.0);
            whitecap_sum += whitecap / area;
        }
        Ok(SeaStats {
            hs_m: 4.0 * (variance_sum / count).sqrt(),
            peak_period_s: self.realised_peak_period_s(),
            whitecap_fraction: whitecap_sum / count,
            mean_m: mean_sum / count,
        })
    }

    /// The peak period of the realised amplitudes (see [`SeaStats::peak_period_s`]); 0 for a
    /// flat sea.
    fn realised_peak_period_s(&self) -> f64 {
        // (ln f, variance, variance / f) of every mode and explicit wave.
        let mut lines: Vec<(f64, f64, f64)> = self
            .synths
            .iter()
            .flat_map(|synth| &synth.modes)
            .map(|mode| {
                let variance = 2.0 * f64::from(mode.a.norm_sqr() + mode.b.norm_sqr());
                (mode.omega_rad_s / TAU, variance)
            })
            .chain(self.gerstner.iter().map(|wave| {
                (
                    wave.omega_rad_s / TAU,
                    0.5 * wave.amplitude_m * wave.amplitude_m,
                )
            }))
            .filter(|&(f, variance)| f > 0.0 && variance > 0.0)
            .map(|(f, variance)| (f.ln(), variance, variance / f))
            .collect();
        lines.sort_by(|a, b| a.0.total_cmp(&b.0));
        // A sliding window of ±PERIODOGRAM_HALF_WIDTH around each line: the densest (sum of
        // variance / f) wins; its variance-weighted mean frequency is the peak.
        let (mut start, mut end) = (0, 0);
        let (mut density, mut variance) = (0.0, 0.0);
        let mut best = (0.0, 0.0);
        for &(ln_f, _, _) in &lines {
            while end < lines.len() && lines[end].0 <= ln_f + PERIODOGRAM_HALF_WIDTH {
                variance += lines[end].1;
                density += lines[end].2;
                end += 1;
            }
            while lines[start].0 < ln_f - PERIODOGRAM_HALF_WIDTH {
                variance -= lines[start].1;
                density -= lines[start].2;
                start += 1;
            }
            if density > best.0 {
                best = (density, variance);
            }
        }
        // The mean frequency is Σ v / Σ (v / f); the period is its inverse.
        if best.1 > 0.0 {
            best.0 / best.1
        } else {
            0.0
        }
    }

    /// The channels summed at an undisplaced position: all of them when `ALL`, else only the
    /// displacement and its gradient (what the inversion needs).
    fn fields_at<const ALL: bool>(&self, x_m: f64, y_m: f64) -> Fields {
        let mut sum = Fields::default();
        for grid in &self.grids {
            add_bilinear::<ALL>(grid, x_m, y_m, &mut sum);
        }
        let precedence = AreaPrecedence::at(&self.areas, x_m, y_m);
        for (wave, area) in self.gerstner.iter().zip(&self.placed) {
            let weight = precedence.weight(&self.areas, *area, x_m, y_m);
            if weight <= 0.0 {
                continue;
            }
            let [ex, ey] = wave.direction;
            let phase = wave.k_rad_m * (ex * x_m + ey * y_m) - wave.omega_rad_s * self.time_s
                + wave.phase_rad;
            let (sin, cos) = phase.sin_cos();
            // The weight varies over hundreds of metres: its own gradient is left out.
            let displacement_m = weight * wave.displacement_m;
            let compression = -displacement_m * wave.k_rad_m * cos;
            sum.dx -= displacement_m * ex * sin;
            sum.dy -= displacement_m * ey * sin;
            sum.dxx += compression * ex * ex;
            sum.dyy += compression * ey * ey;
            sum.dxy += compression * ex * ey;
            if ALL {
                let amplitude_m = weight * wave.amplitude_m;
                let slope = -amplitude_m * wave.k_rad_m * sin;
                sum.h += amplitude_m * cos;
                sum.hx += slope * ex;
                sum.hy += slope * ey;
            }
        }
        sum
    }

    /// Recomputes every cascade's grids at `self.time_s`.
    fn synthesise(&mut self) {
        let choppiness = self.config.choppiness;
        #[expect(
            clippy::cast_possible_truncation,
            reason = "the choppiness is at most 4"
        )]
        let lambda = choppiness as f32;
        for (synth, grid) in self.synths.iter().zip(&mut self.grids) {
            synth.synthesise(self.time_s, lambda, &mut self.workspace, grid);
        }
    }
}

impl CascadeSynth {
    /// Fills `grid` at `t_s`: the spectra of the 8 channels packed in pairs, 4 inverse FFTs.
    fn synthesise(&self, t_s: f64, lambda: f32, ws: &mut Workspace, grid: &mut CascadeGrid) {
        if self.modes.is_empty() {
            // A calm cascade: its grids keep their initial zero (Jacobian 1).
            return;
        }
        let n = self.size;
        let points = n * n;
        for spectrum in &mut ws.spectra {
            spectrum.clear();
            spectrum.resize(points, Complex32::default());
        }
        let [s0, s1, s2, s3] = &mut ws.spectra;
        for mode in &self.modes {
            let (sin, cos) = (mode.omega_rad_s * t_s).sin_cos();
            #[expect(clippy::cast_possible_truncation, reason = "to f32 for the FFT")]
            let (sin, cos) = (sin as f32, cos as f32);
            let h = mode.a * Complex32::new(cos, -sin) + mode.b * Complex32::new(cos, sin);
            let ih = Complex32::new(-h.im, h.re);
            let (kx, ky, ux, uy) = (mode.kx_rad_m, mode.ky_rad_m, mode.ux, mode.uy);
            let gradient = h * (-lambda * mode.breaking_weight);
            pack(s0, mode, h, ih * (lambda * ux));
            pack(s1, mode, ih * (lambda * uy), ih * kx);
            pack(s2, mode, ih * ky, gradient * (kx * ux));
            pack(s3, mode, gradient * (ky * uy), gradient * (kx * uy));
        }
        for (channel, spectrum) in ws.spectra.iter_mut().enumerate() {
            // Rows over ky (the buffer is kx-major), transpose, rows over kx: y-major output.
            self.fft.process_with_scratch(spectrum, &mut ws.scratch);
            ws.transposed.resize(points, Complex32::default());
            transpose(spectrum, &mut ws.transposed, n);
            self.fft
                .process_with_scratch(&mut ws.transposed, &mut ws.scratch);
            let values = ws.transposed.iter();
            match channel {
                0 => {
                    for (texel, v) in grid.height_displacement.iter_mut().zip(values) {
                        texel[0] = v.re;
                        texel[1] = v.im;
                    }
                }
                1 => {
                    let texels = grid.height_displacement.iter_mut().zip(&mut grid.slopes);
                    for ((texel, slope), v) in texels.zip(values) {
                        texel[2] = v.re;
                        slope[0] = v.im;
                    }
                }
                2 => {
                    let texels = grid.slopes.iter_mut().zip(&mut grid.displacement_gradient);
                    for ((slope, gradient), v) in texels.zip(values) {
                        slope[1] = v.re;
                        gradient[0] = v.im;
                    }
                }
                _ => {
                    for (gradient, v) in grid.displacement_gradient.iter_mut().zip(values) {
                        gradient[1] = v.re;
                        gradient[2] = v.im;
                    }
                }
            }
        }
        for (texel, g) in grid
            .height_displacement
            .iter_mut()
            .zip(&grid.displacement_gradient)
        {
            texel[3] = (1.0 + g[0]) * (1.0 + g[1]) - g[2] * g[2];
        }
    }
}

/// Writes two Hermitian channels `a`, `b` at `k` as `a + ib` and at `-k` as
/// `conj(a) + i conj(b)`.
fn pack(spectrum: &mut [Complex32], mode: &Mode, a: Complex32, b: Complex32) {
    spectrum[mode.index] = Complex32::new(a.re - b.im, a.im + b.re);
    spectrum[mode.mirror] = Complex32::new(a.re + b.im, b.re - a.im);
}

/// `dst[j][i] = src[i][j]` for `n × n` row-major matrices, in 16 × 16 blocks.
fn transpose(src: &[Complex32], dst: &mut [Complex32], n: usize) {
    const BLOCK: usize = 16;
    for i0 in (0..n).step_by(BLOCK) {
        for j0 in (0..n).step_by(BLOCK) {
            for i in i0..(i0 + BLOCK).min(n) {
                for j in j0..(j0 + BLOCK).min(n) {
                    dst[j * n + i] = src[i * n + j];
                }
            }
        }
    }
}

/// Adds a cascade's channels (all when `ALL`, else the displacement and its gradient),
/// interpolated bilinearly with periodic wrap, to `sum`.
fn add_bilinear<const ALL: bool>(grid: &CascadeGrid, x_m: f64, y_m: f64, sum: &mut Fields) {
    let n = grid.size;
    #[expect(clippy::cast_precision_loss, reason = "sizes are at most 4096")]
    let per_m = n as f64 / grid.tile_m;
    let (i0, fu) = wrapped_floor(x_m * per_m, n);
    let (j0, fv) = wrapped_floor(y_m * per_m, n);
    let (i1, j1) = ((i0 + 1) & (n - 1), (j0 + 1) & (n - 1));
    let corners = [
        (j0 * n + i0, (1.0 - fu) * (1.0 - fv)),
        (j0 * n + i1, fu * (1.0 - fv)),
        (j1 * n + i0, (1.0 - fu) * fv),
        (j1 * n + i1, fu * fv),
    ];
    for (index, weight) in corners {
        let [h, dx, dy, _] = grid.height_displacement[index];
        let [dxx, dyy, dxy] = grid.displacement_gradient[index];
        sum.dx += weight * f64::from(dx);
        sum.dy += weight * f64::from(dy);
        sum.dxx += weight * f64::from(dxx);
        sum.dyy += weight * f64::from(dyy);
        sum.dxy += weight * f64::from(dxy);
        if ALL {
            let [hx, hy] = grid.slopes[index];
            sum.h += weight * f64::from(h);
            sum.hx += weight * f64::from(hx);
            sum.hy += weight * f64::from(hy);
        }
    }
}

/// The grid index below `coordinate`, wrapped into `0..n` (`n` a power of two), and the
/// fraction above it. (A cast, not `floor`, which is a library call on baseline x86-64.)
fn wrapped_floor(coordinate: f64, n: usize) -> (usize, f64) {
    // Positions beyond ±2⁶³ grid steps are not physical; saturating keeps them in range.
    #[expect(
        clippy::cast_possible_truncation,
        reason = "truncation toward zero is the point; saturates at the i64 range"
    )]
    let mut whole = coordinate as i64;
    #[expect(clippy::cast_precision_loss, reason = "exact for the grid's range")]
    let mut below = whole as f64;
    if below > coordinate {
        whole -= 1;
        below -= 1.0;
    }
    #[expect(
        clippy::cast_possible_truncation,
        clippy::cast_sign_loss,
        clippy::cast_possible_wrap,
        reason = "masked into 0..n, n at most 4096"
    )]
    let index = (whole & (n as i64 - 1)) as usize;
    // NaN gives index 0 and a NaN fraction, which propagates to the result.
    (index, coordinate - below)
}

/// The modes of one cascade: the half-plane representatives inside its band.
fn cascade_modes(
    model: &SpectrumModel,
    cascade: &Cascade,
    (band_lo, band_hi): (f64, f64),
    seed: u64,
    cascade_index: u64,
    breaking_k_rad_m: f64,
) -> Vec<Mode> {
    let n = cascade.size;
    let dk = TAU / cascade.tile_m;
    let xi = gaussian_field(seed, cascade_index, n);
    #[expect(clippy::cast_possible_wrap, reason = "sizes are at most 4096")]
    let half = (n / 2) as isize;
    let unsigned = |signed: isize| -> usize {
        #[expect(clippy::cast_possible_wrap, reason = "sizes are at most 4096")]
        let index = signed.rem_euclid(n as isize) as usize;
        index
    };
    // The amplitude at signed indices (p, q): ξ √(P Δk²) / 2.
    // The expected variance `P Δk²` at signed indices (p, q) and the amplitude `ξ √(P Δk²) / 2`.
    let variance = |p: isize, q: isize| cell_spectrum(model, p, q, dk) * dk * dk;
    let amplitude = |p: isize, q: isize, variance: f64| -> Complex32 {
        #[expect(clippy::cast_possible_truncation, reason = "to f32 for the FFT")]
        let scale = (0.5 * variance.sqrt()) as f32;
        xi[unsigned(q) * n + unsigned(p)] * scale
    };
    let mut modes = Vec::new();
    let (mut expected, mut realised) = (0.0, 0.0);
    for q in 0..half {
        for p in (1 - half)..half {
            // The half plane: q > 0, or q = 0 and p > 0; the Nyquist row and column are absent.
            if q == 0 && p <= 0 {
                continue;
            }
            #[expect(clippy::cast_precision_loss, reason = "indices below 4096")]
            let (kx, ky) = (p as f64 * dk, q as f64 * dk);
            let k = kx.hypot(ky);
            if !(band_lo..band_hi).contains(&k) {
                continue;
            }
            let (variance_k, variance_minus_k) = (variance(p, q), variance(-p, -q));
            #[expect(clippy::cast_possible_truncation, reason = "to f32 for the FFT")]
            let mode = Mode {
                index: unsigned(p) * n + unsigned(q),
                mirror: unsigned(-p) * n + unsigned(-q),
                omega_rad_s: dispersion_omega_rad_s(k, model.depth_m()),
                a: amplitude(p, q, variance_k),
                b: amplitude(-p, -q, variance_minus_k).conj(),
                kx_rad_m: kx as f32,
                ky_rad_m: ky as f32,
                ux: (kx / k) as f32,
                uy: (ky / k) as f32,
                breaking_weight: (1.0 / (1.0 + (k / breaking_k_rad_m).powi(4))) as f32,
            };
            // A mode's time-averaged share of the variance is 2 (|a|² + |b|²) (k and -k).
            let mode_variance = 2.0 * f64::from(mode.a.norm_sqr() + mode.b.norm_sqr());
            expected += variance_k + variance_minus_k;
            realised += mode_variance;
            // A silent mode (no wind or swell at this k) costs time for nothing.
            if mode_variance > 0.0 {
                modes.push(mode);
            }
        }
    }
    // One factor per cascade: its realised variance is the expected one (see the module doc).
    if realised > 0.0 {
        #[expect(clippy::cast_possible_truncation, reason = "to f32 for the FFT")]
        let scale = (expected / realised).sqrt() as f32;
        for mode in &mut modes {
            mode.a *= scale;
            mode.b *= scale;
        }
    }
    modes
}

/// The directional spectrum at signed indices (p, q), averaged over the cell near the origin.
fn cell_spectrum(model: &SpectrumModel, p: isize, q: isize, dk: f64) -> f64 {
    #[expect(clippy::cast_precision_loss, reason = "indices below 4096")]
    let (pf, qf) = (p as f64, q as f64);
    if p.abs().max(q.abs()) > CELL_AVERAGE_RADIUS {
        return model.wavenumber_spectrum(pf * dk, qf * dk);
    }
    let points = f64::from(CELL_AVERAGE_POINTS);
    let offsets = (0..CELL_AVERAGE_POINTS).map(|i| (f64::from(i) + 0.5) / points - 0.5);
    let mut total = 0.0;
    for du in offsets.clone() {
        for dv in offsets.clone() {
            total += model.wavenumber_spectrum((pf + du) * dk, (qf + dv) * dk);
        }
    }
    total / (points * points)
}

/// `n²` complex Gaussians `ξr + iξi` (standard normals, so `E|ξ|² = 2`), row-major over the
/// unsigned (ky, kx) indices, from ChaCha8 keyed by the seed and the cascade's index.
fn gaussian_field(seed: u64, cascade_index: u64, n: usize) -> Vec<Complex32> {
    let mut key = [0_u8; 32];
    key[..8].copy_from_slice(&seed.to_le_bytes());
    key[8..16].copy_from_slice(&cascade_index.to_le_bytes());
    key[16..24].copy_from_slice(&SEED_DOMAIN.to_le_bytes());
    let mut rng = ChaCha8Rng::from_seed(key);
    let mut unit = move || {
        #[expect(clippy::cast_precision_loss, reason = "53 bits fit an f64 exactly")]
        let bits = (rng.next_u64() >> 11) as f64;
        bits * (1.0 / 9_007_199_254_740_992.0)
    };
    (0..n * n)
        .map(|_| {
            // Box-Muller: u1 in (0, 1] keeps the logarithm finite.
            let u1 = 1.0 - unit();
            let u2 = unit();
            let radius = (-2.0 * u1.ln()).sqrt();
            let (sin, cos) = (TAU * u2).sin_cos();
            #[expect(clippy::cast_possible_truncation, reason = "to f32 for the FFT")]
            let xi = Complex32::new((radius * cos) as f32, (radius * sin) as f32);
            xi
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::spectrum::{
        pierson_moskowitz_hs_m, pierson_moskowitz_peak_period_s, sea_state_hs_range_m,
        whitecap_fraction_monahan, Swell,
    };
    use proptest::prelude::*;

    fn surface(u10_mps: f64, seed: u64) -> SeaSurface {
        let sea = SeaConditions::new(u10_mps, 30.0).unwrap();
        SeaSurface::new(&sea, seed, SurfaceConfig::default()).unwrap()
    }

    fn stats(u10_mps: f64, seed: u64) -> SeaStats {
        let stats = surface(u10_mps, seed).measure(&[0.0, 7.0]).unwrap();
        println!(
            "{u10_mps} m/s: Hs {:.3} m (PM {:.3}), Tp {:.2} s (PM {:.2}), whitecaps {:.5} \
             (Monahan {:.5}), mean {:.4} m",
            stats.hs_m,
            pierson_moskowitz_hs_m(u10_mps),
            stats.peak_period_s,
            pierson_moskowitz_peak_period_s(u10_mps),
            stats.whitecap_fraction,
            whitecap_fraction_monahan(u10_mps),
            stats.mean_m,
        );
        stats
    }

    fn ratio(measured: f64, expected: f64) -> f64 {
        measured / expected
    }

    #[test]
    fn an_area_weighs_one_inside_fading_across_its_band_and_none_beyond() {
        // 200 x 100 m turned 90° clockwise from east (its x axis runs south), corners 10 m,
        // a 50 m band, centred 1 km east.
        let area = WaveArea {
            centre_m: [1000.0, 0.0],
            half_size_m: [100.0, 50.0],
            rotation_deg: 90.0,
            corner_radius_m: 10.0,
            transition_m: 50.0,
            kind: AreaKind::Region,
        };
        assert_eq!(area.weight(1000.0, 0.0), 1.0);
        assert_eq!(area.weight(1000.0, -99.0), 1.0);
        assert_eq!(area.weight(1049.0, 0.0), 1.0);
        // 25 m out across the band: half.
        assert!((area.weight(1075.0, 0.0) - 0.5).abs() < 1e-9);
        assert!((area.weight(1000.0, 125.0) - 0.5).abs() < 1e-9);
        assert_eq!(area.weight(1100.0, 0.0), 0.0);
        // The rounded corner: a point diagonally past the corner's circle.
        let corner = (1050.0 - 10.0, 100.0 - 10.0);
        let out = 10.0 + 25.0;
        let d = out / 2.0_f64.sqrt();
        assert!((area.weight(corner.0 + d, corner.1 + d) - 0.5).abs() < 1e-9);
        // Across the band the weight falls steadily.
        let mut last = 1.0;
        for i in 0..=60 {
            let w = area.weight(1050.0 + f64::from(i), 0.0);
            assert!(w <= last && (0.0..=1.0).contains(&w));
            last = w;
        }
        // An entity's disc: 100 m round, 50 m band.
        let disc = WaveArea {
            centre_m: [0.0, 0.0],
            half_size_m: [0.0, 0.0],
            rotation_deg: 0.0,
            corner_radius_m: 100.0,
            transition_m: 50.0,
            kind: AreaKind::Entity,
        };
        assert_eq!(disc.weight(60.0, 79.0), 1.0);
        assert!((disc.weight(-125.0 * 0.6, 125.0 * 0.8) - 0.5).abs() < 1e-9);
        assert_eq!(disc.weight(150.0, 1.0), 0.0);
        // A hard edge asked for is softened over the least band.
        let hard = WaveArea {
            transition_m: 0.0,
            ..disc
        };
        assert_eq!(hard.weight(99.0, 0.0), 1.0);
        assert!((hard.weight(100.0 + MIN_AREA_BAND_M / 2.0, 0.0) - 0.5).abs() < 1e-9);
        assert_eq!(hard.weight(100.0 + MIN_AREA_BAND_M, 0.0), 0.0);
        assert!(WaveArea {
            transition_m: f64::NAN,
            ..disc
        }
        .validate()
        .is_err());
    }

    #[test]
    fn placed_waves_apply_in_their_areas_entities_over_regions_over_global() {
        let calm = SeaConditions::new(0.0, 0.0).unwrap();
        let mut surface = SeaSurface::new(&calm, 1, SurfaceConfig::default()).unwrap();
        let wave = |height| WaveComponent::new(height, 100.0, 8.0, 90.0, 0.0, 0.0).unwrap();
        let region = WaveArea {
            centre_m: [5000.0, 0.0],
            half_size_m: [1000.0, 1000.0],
            rotation_deg: 0.0,
            corner_radius_m: 0.0,
            transition_m: 500.0,
            kind: AreaKind::Region,
        };
        let entity = WaveArea {
            centre_m: [5000.0, 0.0],
            half_size_m: [0.0, 0.0],
            rotation_deg: 0.0,
            corner_radius_m: 200.0,
            transition_m: 100.0,
            kind: AreaKind::Entity,
        };
        surface
            .set_placed_waves(
                vec![wave(1.0), wave(3.0), wave(0.4)],
                vec![None, Some(0), Some(1)],
                vec![region, entity],
            )
            .unwrap();
        // The largest height over a period at a point.
        let mut crest = |x: f64, y: f64| {
            (0..40)
                .map(|i| {
                    surface.update(f64::from(i) * 0.2).unwrap();
                    surface.sample(x, y).height_m
                })
                .fold(f64::MIN, f64::max)
        };
        let open_sea = crest(0.0, 0.0);
        let in_region = crest(5000.0, 800.0);
        let by_the_entity = crest(5000.0, 50.0);
        let in_the_band = crest(5000.0, 1250.0);
        assert!((open_sea - 0.5).abs() < 0.02, "global alone: {open_sea}");
        assert!(
            (in_region - 1.5).abs() < 0.05,
            "the region's alone: {in_region}"
        );
        assert!(
            (by_the_entity - 0.2).abs() < 0.02,
            "the entity's alone: {by_the_entity}"
        );
        // Half way across the region's band: half the region's wave, half the global one.
        assert!((in_the_band - 1.0).abs() < 0.05, "{in_the_band}");
        assert_eq!(
            surface.explicit_weights_at(5000.0, 50.0),
            vec![0.0, 0.0, 1.0]
        );
        // The wrong number of places, or a place naming no area, is refused.
        assert!(surface
            .set_placed_waves(vec![wave(1.0)], vec![], vec![])
            .is_err());
        assert!(surface
            .set_placed_waves(vec![wave(1.0)], vec![Some(0)], vec![])
            .is_err());
        assert_eq!(surface.explicit_waves().len(), 3);
    }

    #[test]
    fn the_measured_sea_follows_pierson_moskowitz_and_monahan() {
        let calm = stats(3.0, 11);
        assert!(calm.whitecap_fraction < 1e-4, "{calm:?}");
        let mut last_whitecaps = calm.whitecap_fraction;
        for u10 in [5.0, 10.0, 15.0] {
            let stats = stats(u10, 11);
            let hs = ratio(stats.hs_m, pierson_moskowitz_hs_m(u10));
            assert!((0.85..1.15).contains(&hs), "{u10} m/s: Hs {hs} of PM");
            let tp = ratio(stats.peak_period_s, pierson_moskowitz_peak_period_s(u10));
            assert!((0.85..1.15).contains(&tp), "{u10} m/s: Tp {tp} of PM");
            assert!(stats.whitecap_fraction > last_whitecaps, "{u10} m/s");
            last_whitecaps = stats.whitecap_fraction;
            if u10 >= 10.0 {
                let whitecaps = ratio(stats.whitecap_fraction, whitecap_fraction_monahan(u10));
                assert!(
                    (0.5..2.0).contains(&whitecaps),
                    "{u10} m/s: {whitecaps} of Monahan"
                );
            }
            // Choppy crests lower the mean level a little.
            assert!(stats.mean_m < 0.0 && stats.mean_m > -0.05 * stats.hs_m);
        }
    }

    #[test]
    fn sea_state_codes_give_their_heights() {
        for code in 2..=8 {
            let sea = SeaConditions::for_sea_state(code, 200.0).unwrap();
            let mut surface =
                SeaSurface::new(&sea, u64::from(code), SurfaceConfig::default()).unwrap();
            let hs_m = surface.measure(&[3.0]).unwrap().hs_m;
            let (lo, hi) = sea_state_hs_range_m(code).unwrap();
            assert!(hs_m > lo && hs_m < hi, "code {code}: {hs_m} m");
        }
    }

    #[test]
    fn the_surface_is_deterministic_in_seed_and_time() {
        let mut a = surface(12.0, 42);
        let mut b = surface(12.0, 42);
        a.update(12.5).unwrap();
        b.update(3.0).unwrap();
        assert_ne!(a.grids(), b.grids());
        b.update(12.5).unwrap();
        assert_eq!(a.grids(), b.grids());
        assert_eq!(a.time_s(), 12.5);
        let mut c = surface(12.0, 43);
        c.update(12.5).unwrap();
        assert_ne!(a.grids(), c.grids());
        assert_eq!(a.sample(10.0, -20.0), b.sample(10.0, -20.0));
        assert_ne!(a.sample(10.0, -20.0), c.sample(10.0, -20.0));
    }

    #[test]
    fn the_grids_are_laid_out_as_documented() {
        let mut surface = surface(9.0, 5);
        surface.update(4.0).unwrap();
        for grid in surface.grids() {
            let points = grid.size * grid.size;
            assert_eq!(grid.height_displacement.len(), points);
            assert_eq!(grid.slopes.len(), points);
            assert_eq!(grid.displacement_gradient.len(), points);
            let finite = grid
                .height_displacement
                .iter()
                .flatten()
                .all(|v| v.is_finite());
            assert!(finite);
            // Each cascade is zero-mean and its Jacobian is the documented combination.
            let mean: f64 = grid
                .height_displacement
                .iter()
                .map(|t| f64::from(t[0]))
                .sum::<f64>();
            assert!(mean.abs() / (points as f64) < 1e-5);
            let (t, g) = (grid.height_displacement[77], grid.displacement_gradient[77]);
            assert_eq!(t[3], (1.0 + g[0]) * (1.0 + g[1]) - g[2] * g[2]);
        }
        // The slope channel is the derivative of the height channel (central differences on
        // the largest tile, index j * size + i at x = i tile / size east).
        let grid = &surface.grids()[0];
        let n = grid.size;
        let step_m = grid.tile_m / n as f64;
        let (i, j) = (40, 70);
        let h = |i: usize, j: usize| f64::from(grid.height_displacement[j * n + i][0]);
        let east = (h(i + 1, j) - h(i - 1, j)) / (2.0 * step_m);
        let north = (h(i, j + 1) - h(i, j - 1)) / (2.0 * step_m);
        let [sx, sy] = grid.slopes[j * n + i];
        let scale = f64::from(sx.abs() + sy.abs()) + 1e-3;
        assert!((east - f64::from(sx)).abs() < 0.3 * scale, "{east} {sx}");
        assert!((north - f64::from(sy)).abs() < 0.3 * scale, "{north} {sy}");
    }

    #[test]
    fn the_waves_travel_downwind() {
        // Wind from the west: the crests move east. The height at a point east of another one
        // repeats the western point's height a little later.
        let sea = SeaConditions::new(10.0, 270.0).unwrap();
        let mut surface = SeaSurface::new(&sea, 9, SurfaceConfig::default()).unwrap();
        let (dt_s, shift_m) = (1.0, 10.0);
        let (mut downwind, mut upwind) = (0.0, 0.0);
        for step in 0..40 {
            let t = f64::from(step) * 0.5;
            surface.update(t).unwrap();
            let west = (0..20)
                .map(|i| surface.height_at_undisplaced(f64::from(i) * 37.0, 5.0))
                .collect::<Vec<_>>();
            surface.update(t + dt_s).unwrap();
            for (i, h) in west.iter().enumerate() {
                let x = i as f64 * 37.0;
                downwind += h * surface.height_at_undisplaced(x + shift_m, 5.0);
                upwind += h * surface.height_at_undisplaced(x - shift_m, 5.0);
            }
        }
        assert!(downwind > 2.0 * upwind.abs(), "{downwind} {upwind}");
    }

    #[test]
    fn crests_are_compressed_and_choppiness_zero_is_flat_horizontally() {
        let surface = surface(14.0, 8);
        let (mut correlation, mut jacobian_sum) = (0.0, 0.0);
        for i in 0..2000 {
            let (x, y) = (f64::from(i) * 3.1, f64::from(i % 37) * 11.0);
            let sample = surface.sample(x, y);
            correlation += sample.height_m * (sample.jacobian - 1.0);
            jacobian_sum += sample.jacobian;
        }
        assert!(correlation < 0.0, "{correlation}");
        assert!((jacobian_sum / 2000.0 - 1.0).abs() < 0.05);
        let sea = SeaConditions::new(14.0, 0.0).unwrap();
        let config = SurfaceConfig {
            choppiness: 0.0,
            ..SurfaceConfig::default()
        };
        let flat = SeaSurface::new(&sea, 8, config).unwrap();
        let sample = flat.sample(12.0, 34.0);
        assert!(sample.displacement_m.iter().all(|d| d.abs() < 1e-6));
        assert!((sample.jacobian - 1.0).abs() < 1e-6);
        // Only the FFT's rounding (the displacement channels share FFTs with others) moves it.
        assert!((sample.height_m - flat.height_at_undisplaced(12.0, 34.0)).abs() < 1e-6);
    }

    #[test]
    fn sample_inverts_the_displacement() {
        let mut surface = surface(15.0, 3);
        surface.update(21.0).unwrap();
        let mut worst_m: f64 = 0.0;
        for i in 0..400 {
            let (x, y) = (f64::from(i) * 7.3 - 1000.0, f64::from(i % 23) * 13.9 + 5e4);
            let sample = surface.sample(x, y);
            let x0 = sample.undisplaced_m;
            let again = surface.height_at_undisplaced(x0[0], x0[1]);
            assert!(
                (again - sample.height_m).abs() < 1e-6,
                "{x} {y}: {again} {sample:?}"
            );
            let [dx, dy] = surface.displacement_at_undisplaced(x0[0], x0[1]);
            worst_m = worst_m.max((x0[0] + dx - x).hypot(x0[1] + dy - y));
            let [nx, ny, nz] = sample.normal;
            assert!(((nx * nx + ny * ny + nz * nz).sqrt() - 1.0).abs() < 1e-9);
            assert!(nz > 0.5);
        }
        assert!(worst_m < 1e-3, "{worst_m}");
    }

    #[test]
    fn an_explicit_wave_alone_has_its_height_and_period() {
        let calm = SeaConditions::new(0.0, 0.0).unwrap();
        let mut surface = SeaSurface::new(&calm, 1, SurfaceConfig::default()).unwrap();
        let (height_m, period_s) = (6.0, 6.2);
        let wave = WaveComponent::new(height_m, 60.0, period_s, 30.0, 40.0, 0.7).unwrap();
        surface.set_explicit_waves(vec![wave]).unwrap();
        assert_eq!(surface.explicit_waves(), &[wave]);
        let (mut lo, mut hi) = (f64::MAX, f64::MIN);
        let mut crossings = Vec::new();
        let mut last = None;
        let steps = 3000;
        for step in 0..=steps {
            let t = f64::from(step) * 3.0 * period_s / f64::from(steps);
            surface.update(t).unwrap();
            let h = surface.sample(13.0, -7.0).height_m;
            lo = lo.min(h);
            hi = hi.max(h);
            if let Some((t0, h0)) = last {
                if h0 < 0.0 && h >= 0.0 {
                    crossings.push(t0 + (t - t0) * h0 / (h0 - h));
                }
            }
            last = Some((t, h));
        }
        assert!(((hi - lo) / height_m - 1.0).abs() < 0.01, "{lo} {hi}");
        let periods = (crossings.len() - 1) as f64;
        let measured = (crossings[crossings.len() - 1] - crossings[0]) / periods;
        assert!((measured / period_s - 1.0).abs() < 0.01, "{measured}");
        // The crests are sharper than the troughs: the crest is higher above the mean level.
        let stats = surface.measure(&[0.0]).unwrap();
        assert!((stats.peak_period_s / period_s - 1.0).abs() < 1e-9);
        assert!(hi - stats.mean_m > stats.mean_m - lo);
    }

    #[test]
    fn explicit_waves_never_loop() {
        let calm = SeaConditions::new(0.0, 0.0).unwrap();
        let mut surface = SeaSurface::new(&calm, 1, SurfaceConfig::default()).unwrap();
        // Two steep trochoids along the same line would loop if not held back.
        let waves = vec![
            WaveComponent::new(10.0, 40.0, 5.0, 90.0, 0.0, 1.0).unwrap(),
            WaveComponent::new(6.0, 25.0, 4.0, 90.0, 0.0, 1.0).unwrap(),
        ];
        surface.set_explicit_waves(waves).unwrap();
        for i in 0..500 {
            let x0 = f64::from(i) * 0.2;
            assert!(surface.fields_at::<true>(x0, 0.0).jacobian() > 0.0);
        }
    }

    #[test]
    fn the_bands_partition_the_wave_numbers() {
        let config = SurfaceConfig::default();
        let bands = config.bands_rad_m();
        assert_eq!(bands[0].0, 0.0);
        assert!(bands[bands.len() - 1].1.is_infinite());
        for pair in bands.windows(2) {
            assert_eq!(pair[0].1, pair[1].0);
            assert!(pair[0].0 < pair[0].1);
        }
        // The 20 m/s peak (350 m) is in the first band, several grid steps long; ripples of
        // 0.3 m reach the last cascade's Nyquist.
        let peak_k = TAU / 350.0;
        assert!(peak_k < bands[0].1);
        let first = config.cascades[0];
        assert!(350.0 / (first.tile_m / first.size as f64) > 8.0);
        let last = config.cascades[config.cascades.len() - 1];
        assert!(2.0 * last.tile_m / last.size as f64 <= 0.31);
        // No tile is a whole multiple of another.
        for a in &config.cascades {
            for b in &config.cascades {
                let r = a.tile_m.max(b.tile_m) / a.tile_m.min(b.tile_m);
                assert!(r == 1.0 || (r - r.round()).abs() > 0.05, "{r}");
            }
        }
    }

    #[test]
    fn bad_inputs_are_refused() {
        let sea = SeaConditions::new(8.0, 0.0).unwrap();
        let with = |cascades: Vec<Cascade>, choppiness: f64| SurfaceConfig {
            cascades,
            choppiness,
        };
        let cascade = |tile_m: f64, size: usize| Cascade { tile_m, size };
        for config in [
            with(vec![], 1.0),
            with(vec![cascade(100.0, 100)], 1.0),
            with(vec![cascade(100.0, 4)], 1.0),
            with(vec![cascade(100.0, 8192)], 1.0),
            with(vec![cascade(f64::NAN, 64)], 1.0),
            with(vec![cascade(-5.0, 64)], 1.0),
            with(vec![cascade(100.0, 64), cascade(200.0, 64)], 1.0),
            with(vec![cascade(100.0, 64)], f64::NAN),
            with(vec![cascade(100.0, 64)], -1.0),
        ] {
            assert!(
                SeaSurface::new(&sea, 1, config.clone()).is_err(),
                "{config:?}"
            );
        }
        let bad_sea = SeaConditions {
            wind_speed_mps: f64::NAN,
            ..sea.clone()
        };
        assert!(SeaSurface::new(&bad_sea, 1, SurfaceConfig::default()).is_err());
        let mut surface = SeaSurface::new(&sea, 1, with(vec![cascade(50.0, 16)], 1.0)).unwrap();
        surface.update(2.0).unwrap();
        let grids = surface.grids().to_vec();
        assert!(surface.update(f64::NAN).is_err());
        assert!(surface.update(f64::INFINITY).is_err());
        assert_eq!(surface.time_s(), 2.0);
        assert_eq!(surface.grids(), &grids[..]);
        assert!(surface.measure(&[]).is_err());
        assert!(surface.measure(&[1.0, f64::NAN]).is_err());
        assert!(WaveComponent::new(-1.0, 10.0, 3.0, 0.0, 0.0, 0.5).is_err());
        assert!(WaveComponent::new(1.0, 0.0, 3.0, 0.0, 0.0, 0.5).is_err());
        assert!(WaveComponent::new(1.0, 10.0, f64::NAN, 0.0, 0.0, 0.5).is_err());
        assert!(WaveComponent::new(1.0, 10.0, 3.0, f64::INFINITY, 0.0, 0.5).is_err());
        assert!(WaveComponent::new(1.0, 10.0, 3.0, 0.0, 0.0, 1.5).is_err());
        let good = WaveComponent::new(1.0, 10.0, 3.0, -90.0, 370.0, 0.5).unwrap();
        assert_eq!((good.direction_deg, good.phase_deg), (270.0, 10.0));
        let bad = WaveComponent {
            leading: -0.1,
            ..good
        };
        surface.set_explicit_waves(vec![good]).unwrap();
        assert!(surface.set_explicit_waves(vec![good, bad]).is_err());
        assert_eq!(surface.explicit_waves(), &[good]);
    }

    /// Prints the scatter of the measured Hs over seeds and directions (run with `--ignored`).
    #[test]
    #[ignore = "statistics over seeds, prints only"]
    fn hs_scatter_over_seeds() {
        for code in [6_u8, 8] {
            let ratios: Vec<f64> = (0..24_u32)
                .map(|seed| {
                    let sea = SeaConditions::for_sea_state(code, f64::from(seed) * 37.0).unwrap();
                    let config = SurfaceConfig::default();
                    let mut surface = SeaSurface::new(&sea, u64::from(seed), config).unwrap();
                    surface.measure(&[3.0]).unwrap().hs_m / sea.expected_hs_m()
                })
                .collect();
            let mean = ratios.iter().sum::<f64>() / ratios.len() as f64;
            let variance =
                ratios.iter().map(|r| (r - mean).powi(2)).sum::<f64>() / ratios.len() as f64;
            println!(
                "code {code}: Hs / expected {mean:.3} ± {:.3}",
                variance.sqrt()
            );
        }
    }

    /// Prints the whitecap fraction against Monahan's for thresholds around
    /// [`WHITECAP_JACOBIAN`], averaged over 8 seeds and 2 times (run with `--ignored`).
    #[test]
    #[ignore = "calibration, prints only"]
    fn whitecap_calibration() {
        let thresholds = [0.76, 0.78, 0.8, 0.82, 0.84];
        for u10 in [3.0, 5.0, 10.0, 15.0, 20.0] {
            let mut fractions = [0.0; 5];
            for seed in 0..8_u32 {
                let sea = SeaConditions::new(u10, f64::from(seed) * 41.0).unwrap();
                let config = SurfaceConfig::default();
                let mut surface = SeaSurface::new(&sea, u64::from(seed), config).unwrap();
                for t in [0.0, 20.0] {
                    surface.update(t).unwrap();
                    let grid = surface.config.cascades[0];
                    let step_m = grid.tile_m / grid.size as f64;
                    let mut area = 0.0;
                    let mut covered = [0.0; 5];
                    for j in 0..grid.size {
                        for i in 0..grid.size {
                            let (x, y) = (i as f64 * step_m, j as f64 * step_m);
                            let jacobian = surface.fields_at::<true>(x, y).jacobian();
                            area += jacobian.max(0.0);
                            for (threshold, covered) in thresholds.iter().zip(&mut covered) {
                                if jacobian < *threshold {
                                    *covered += jacobian.max(0.0);
                                }
                            }
                        }
                    }
                    for (fraction, covered) in fractions.iter_mut().zip(covered) {
                        *fraction += covered / area / 16.0;
                    }
                }
            }
            let monahan = whitecap_fraction_monahan(u10);
            let row: Vec<String> = fractions
                .iter()
                .map(|f| format!("{f:.5} ({:.2})", f / monahan))
                .collect();
            println!("{u10} m/s, J < {thresholds:?}: {row:?}, Monahan {monahan:.5}");
        }
    }

    #[test]
    fn a_fetch_limited_sea_in_shallow_water_with_swell_has_its_height() {
        let swell = Swell::new(1.5, 11.0, 250.0).unwrap();
        let sea = SeaConditions::new(8.0, 10.0)
            .and_then(|sea| sea.with_fetch_m(50_000.0))
            .and_then(|sea| sea.with_depth_m(20.0))
            .and_then(|sea| sea.with_swell(swell))
            .unwrap();
        let mut surface = SeaSurface::new(&sea, 4, SurfaceConfig::default()).unwrap();
        let stats = surface.measure(&[2.0]).unwrap();
        let hs = stats.hs_m / sea.expected_hs_m();
        assert!(
            (0.85..1.15).contains(&hs),
            "{stats:?} {}",
            sea.expected_hs_m()
        );
        // The swell (11 s) is the peak.
        assert!((stats.peak_period_s / 11.0 - 1.0).abs() < 0.15, "{stats:?}");
    }

    /// Prints the cost of the default configuration (run with `--release --ignored`).
    #[test]
    #[ignore = "timing, prints only"]
    fn cost_of_the_default_configuration() {
        let mut surface = surface(15.0, 1);
        let start = std::time::Instant::now();
        let updates = 200;
        for i in 0..updates {
            surface.update(f64::from(i) * 0.02).unwrap();
        }
        println!("update: {:?}", start.elapsed() / updates);
        let start = std::time::Instant::now();
        let mut sum = 0.0;
        for i in 0..1000 {
            sum += surface
                .sample(f64::from(i) * 1.37, f64::from(i) * -0.71)
                .height_m;
        }
        println!("1000 samples: {:?} ({sum})", start.elapsed());
    }

    #[test]
    fn the_surface_can_move_between_threads() {
        fn send_sync<T: Send + Sync>() {}
        send_sync::<SeaSurface>();
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(64))]
        #[test]
        fn samples_are_finite_anywhere(x in -1e7..1e7_f64, y in -1e7..1e7_f64, t in 0.0..1e5_f64) {
            let sea = SeaConditions::new(18.0, 123.0).unwrap();
            let config = SurfaceConfig {
                cascades: vec![Cascade { tile_m: 300.0, size: 16 }, Cascade { tile_m: 40.0, size: 16 }],
                choppiness: 1.5,
            };
            let mut surface = SeaSurface::new(&sea, 77, config).unwrap();
            surface.update(t).unwrap();
            let sample = surface.sample(x, y);
            prop_assert!(sample.height_m.is_finite() && sample.height_m.abs() < 30.0);
            prop_assert!(sample.normal.iter().all(|v| v.is_finite()));
            prop_assert!(sample.normal[2] > 0.0);
            prop_assert!(sample.displacement_m.iter().all(|v| v.is_finite()));
        }
    }
}
