//! Sea physics for cig's maritime channels (issue 21), without the GPU.
//!
//! - [`spectrum`]: directional ocean wave spectra tied to the wind and the fetch (JONSWAP,
//!   Pierson-Moskowitz when fully developed, TMA in shallow water) with Hasselmann spreading
//!   and a swell; the WMO sea state code and whitecap coverage;
//! - [`surface`]: the wave surface, deterministic in (seed, time): FFT cascades with choppy
//!   (horizontally displaced) crests plus the host's explicit waves (CIGI Wave Control), sampled
//!   on the CPU for height queries and handed to the renderer as grids; its measured statistics;
//! - [`response`]: ships' heave, pitch and roll in the seaway in closed form (the hull's filter
//!   and its natural periods, per wave);
//! - [`motion`]: the hull's particulars, and the same oscillators integrated in time;
//! - [`wake`]: the Kelvin wake and the foam trail;
//! - [`horizon`]: earth curvature with standard terrestrial refraction (hull-down);
//! - [`periscope`]: magnifications, field of view and the stadimeter.
//!
//! Pure: no files, sockets, GPU or terminal. Limits are listed in each module. Source: document
//! 001 (the periscope trainer), with the published models each module names.

pub mod horizon;
pub mod motion;
pub mod periscope;
pub mod response;
pub mod spectrum;
pub mod surface;
pub mod wake;

/// Gravity at the sea surface, m/s² (standard).
pub const G_MPS2: f64 = 9.806_65;

/// Why a sea call refused its input: each message is one line naming the value.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum SeaError {
    /// A value outside its range, or not finite.
    #[error("{name} must be {range}, not {value}")]
    OutOfRange {
        name: &'static str,
        range: &'static str,
        value: f64,
    },
}

/// `value` when finite and inside `lo..=hi`, else [`SeaError::OutOfRange`].
pub(crate) fn checked(
    name: &'static str,
    value: f64,
    lo: f64,
    hi: f64,
    range: &'static str,
) -> Result<f64, SeaError> {
    if value.is_finite() && (lo..=hi).contains(&value) {
        Ok(value)
    } else {
        Err(SeaError::OutOfRange { name, range, value })
    }
}
