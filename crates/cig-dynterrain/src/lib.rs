//! Dynamic-terrain physics for cig (document 002's "track-soil interaction" and "bombing and
//! bomb damage"), without the GPU.
//!
//! - [`soil`]: Bekker–Wong pressure–sinkage, compaction resistance and Mohr–Coulomb /
//!   Janosi–Hanamoto thrust per terrain [`Material`](cig_terrain::Material) and
//!   [`SoilMoisture`](soil::SoilMoisture): ruts and a go/no-go trafficability verdict for a
//!   [`VehicleLoad`](soil::VehicleLoad);
//! - [`crater`]: cube-root (Hopkinson–Cranz) scaling of surface-burst crater radius, depth and
//!   lip per material;
//! - [`munitions`]: the DIS munition entity types (SISO-REF-010) of common rounds and bombs and
//!   the DIS warhead enumeration mapped to an *effective cratering charge*, in kilograms of TNT.
//!
//! Pure: no files, sockets, GPU, terminal or clock. Each module lists its sources, its tables
//! and its limits; values that could not be checked against their source say so where they are
//! defined. Inputs from outside are checked: a bad value is refused with a one-line error that
//! names it ([`SoilError`], [`CraterError`]).

pub mod crater;
pub mod munitions;
pub mod soil;

pub use crater::{CraterCoefficients, CraterDimensions, CraterError};
pub use munitions::{MunitionEntry, MunitionType};
pub use soil::{RunningGear, SoilError, SoilMoisture, SoilProperties, Trafficability, VehicleLoad};

/// Standard gravity, m/s², turning a vehicle's mass into its weight.
pub const G_MPS2: f64 = 9.806_65;
