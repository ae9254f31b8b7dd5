//! Errors of the effects crate: one enum, each message one line naming the value and the reason.

use thiserror::Error;

/// Why an effects call refused its input.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum EffectsError {
    /// A number that must be finite and inside a range was not.
    #[error("{name} = {value} is out of range: {expected}")]
    OutOfRange {
        name: &'static str,
        value: f64,
        expected: &'static str,
    },
    /// A Pasquill stability class name that is not A-F.
    #[error("unknown stability class {0:?}: expected one of A, B, C, D, E, F")]
    UnknownStabilityClass(String),
    /// A soil type name that is not none, dry_clay or light_sand.
    #[error("unknown soil type {0:?}: expected none, dry_clay or light_sand")]
    UnknownSoil(String),
    /// A road type name that is not paved, clay or sand.
    #[error("unknown road type {0:?}: expected paved, clay or sand")]
    UnknownRoad(String),
    /// An effect started (or moved) outside the area the system serves.
    #[error("effect position {lat_deg:.6}, {lon_deg:.6} is outside the served area (lat {south_deg:.6}..{north_deg:.6}, lon {west_deg:.6}..{east_deg:.6})")]
    OutsideArea {
        lat_deg: f64,
        lon_deg: f64,
        south_deg: f64,
        north_deg: f64,
        west_deg: f64,
        east_deg: f64,
    },
    /// Every effect slot of the requested kind is in use.
    #[error("no free {kind} effect slot: all {capacity} are in use")]
    NoFreeSlot { kind: &'static str, capacity: usize },
    /// A handle of an effect that has ended (or was never issued).
    #[error("effect handle {slot}/{generation} does not name a live effect")]
    StaleHandle { slot: u32, generation: u32 },
    /// A plume move sent to an effect that is not a plume.
    #[error("effect handle {slot}/{generation} is not a plume")]
    NotAPlume { slot: u32, generation: u32 },
    /// A vehicle update sent to an effect that is not a dust trail.
    #[error("effect handle {slot}/{generation} is not a dust trail")]
    NotADustTrail { slot: u32, generation: u32 },
}

/// Checks that `value` is finite and `>= 0`.
pub(crate) fn non_negative(name: &'static str, value: f64) -> Result<f64, EffectsError> {
    if value.is_finite() && value >= 0.0 {
        Ok(value)
    } else {
        Err(EffectsError::OutOfRange {
            name,
            value,
            expected: "a finite number >= 0",
        })
    }
}

/// Checks that `value` is finite and `> 0`.
pub(crate) fn positive(name: &'static str, value: f64) -> Result<f64, EffectsError> {
    if value.is_finite() && value > 0.0 {
        Ok(value)
    } else {
        Err(EffectsError::OutOfRange {
            name,
            value,
            expected: "a finite number > 0",
        })
    }
}

/// Checks that `value` is finite.
pub(crate) fn finite(name: &'static str, value: f64) -> Result<f64, EffectsError> {
    if value.is_finite() {
        Ok(value)
    } else {
        Err(EffectsError::OutOfRange {
            name,
            value,
            expected: "a finite number",
        })
    }
}
