//! Thermal infrared physics for cig's sensor channels, without the GPU.
//!
//! - [`planck`]: black-body radiance in a band by converging series (source 001, "Thermal
//!   Emission"), its slope and inverse (brightness temperature);
//! - [`material`]: the thermal materials (the terrain's nine classes and the models'), layered
//!   slabs with surface optics, every property with its source;
//! - [`weather`]: the air temperature history, humidity, sky long-wave, sun and convection that
//!   drive the surfaces;
//! - [`slab`]: one material's RC network (source 001, Figure 4, generalised to N nodes) and its
//!   implicit step;
//! - [`entity_heat`]: engines, exhausts, running gear, crews, burning hulls and hot spots,
//!   warming and cooling with first-order time constants;
//! - [`infrared`]: band transmittance and path radiance of the atmosphere (a LOWTRAN 7 table
//!   generated offline by `tools/lowtran`);
//! - [`table`]: the per-material, per-orientation table (source 001's twelve standard
//!   directions, here 26), spun up over two days and advanced with the clock.
//!
//! Pure: no files, sockets, GPU or terminal. Limits are listed in each module.

pub mod entity_heat;
pub mod infrared;
pub mod material;
pub mod planck;
pub mod slab;
pub mod table;
pub mod weather;

pub use entity_heat::{EntityHeat, EntityThermalInput, HotPart, HotSpot};
pub use infrared::{Aerosol, IrAtmosphere, IrBand, ModelAtmosphere, PathOptics};
pub use material::{material_names, InnerBoundary, Layer, MaterialProperties, ThermalMaterial};
pub use planck::{band_radiance, brightness_temperature_k, Band};
pub use slab::{Slab, SurfaceForcing};
pub use table::{Orientation, Orientations, SurfaceTable};
pub use weather::{AirTemperature, ThermalWeather, CELSIUS_0_K};

/// Why a thermal call refused its input: each message is one line naming the value.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum ThermalError {
    /// A temperature at or below absolute zero, or not finite.
    #[error("temperature {0} K is not above absolute zero")]
    InvalidTemperature(f64),
    /// A band whose edges are not 0 < lo < hi.
    #[error("band {lo_um}-{hi_um} um is empty or inverted: expected 0 < lo < hi")]
    InvalidBand { lo_um: f64, hi_um: f64 },
    /// A band that is not `LO-HI`.
    #[error("band {0:?} is not LO-HI in micrometres (e.g. 8-12)")]
    UnparsableBand(String),
    /// A material name the table does not hold.
    #[error("unknown material {0:?}: expected one of {names}", names = material::material_names())]
    UnknownMaterial(String),
    /// A setting out of its range.
    #[error("{name} = {value} is out of range: expected {expected}")]
    OutOfRange {
        name: &'static str,
        value: f64,
        expected: &'static str,
    },
    /// A band the atmosphere table does not hold.
    #[error("band {0:?} is not one the infrared atmosphere holds: expected 8-12 or 3-5")]
    UnsupportedBand(String),
    /// A name that is not one of a list.
    #[error("unknown {what} {name:?}: expected one of {expected}")]
    UnknownName {
        what: &'static str,
        name: String,
        expected: &'static str,
    },
    /// A latitude or longitude out of range.
    #[error("invalid place: {0}")]
    InvalidPlace(String),
}
