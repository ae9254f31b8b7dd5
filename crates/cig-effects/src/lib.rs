//! Obscurants for the IG: smoke and flame plumes, vehicle dust trails, and the transmittance of
//! a line of sight through them.
//!
//! The models are those of the NPSNET environmental-effects thesis (source 000: chapters II.A-B,
//! III.A, V.A.1, VI.E.2-3, VII.A, appendices B-D), with the plume rise in the form of the EPA's
//! ISC3 model and the dispersion from McMullen's fit (Eq 6):
//! - [`briggs`]: buoyancy flux and Briggs plume rise (final, transitional, stable);
//! - [`dispersion`]: sigma_y, sigma_z per Pasquill class and the class from the weather;
//! - [`dust`]: dust strength from speed, soil and road (from the terrain material class);
//! - [`optics`]: Gaussian puffs and `T = exp(-alpha integral C dl)` (Eq 1-4);
//! - [`seed`]: effect identity and its deterministic ChaCha8 generator;
//! - [`system`]: the particle engine (fixed pools, fixed-step stepping), the control API, the
//!   renderer's snapshot and the transmittance query.
//!
//! This crate is pure: no files, sockets, GPU or terminal. Limits are listed in each module.

pub mod briggs;
pub mod dispersion;
pub mod dust;
pub mod error;
pub mod optics;
pub mod seed;
pub mod system;

pub use dispersion::{pasquill_class, sigmas, PasquillWeather, Sigmas, StabilityClass};
pub use dust::{DustSurface, Road, Soil};
pub use error::EffectsError;
pub use optics::{ObscurantKind, Transmittance};
pub use seed::{effect_rng, EffectId};
pub use system::{
    effect_time_s, Atmosphere, DustTrailSpec, EffectHandle, EffectSystem, EffectsConfig, PlumeKind,
    PlumeSource, PlumeSpec, PoolStats, PuffInstance, PuffState, ServedArea, VehicleUpdate, Wind,
    EFFECT_EPOCH_UNIX_S, STEP_S,
};
