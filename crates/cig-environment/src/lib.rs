//! The cig environment model: where the sun and the moon are, when they rise
//! and set, how much natural light reaches the ground, the passage of
//! simulated time, and lightning. Pure maths: no GPU, files, sockets or
//! terminal.
//!
//! Algorithms, sources and limits, by module:
//!
//! - [`time`]: UTC instants as seconds since J2000.0, Gregorian calendar
//!   (Hinnant's day-count formulas), ΔT by the Espenak–Meeus polynomials
//!   (NASA TP-2006-214141). 1900–2100; UTC used as UT1 (< 0.9 s).
//! - [`vsop87`], [`nutation`], [`sun`], [`moon`]: J. Meeus, *Astronomical
//!   Algorithms* (2nd ed., 1998) chapters 12, 22, 25 (VSOP87 truncated,
//!   Appendix III) and 47 (ELP-2000/82 truncated). Sun about 1″, moon about
//!   10″ in longitude.
//! - [`ephemeris`]: topocentric azimuth and altitude by subtracting the WGS84
//!   observer (`cig-geo`) from the Earth-fixed body vector, Sæmundsson
//!   refraction, the moon's topocentric phase angle and illuminated fraction.
//!   Checked against Meeus's worked examples, the NREL SPA test case and
//!   PyEphem (tests): sun within 0.01°, moon within 0.05°.
//! - [`events`]: sunrise/sunset (−0.833°), civil/nautical/astronomical
//!   twilight (−6°, −12°, −18°), moonrise/moonset (upper limb on the refracted
//!   horizon) within the local mean day; `None` when an event does not happen.
//! - [`illuminance`]: the USNO/Brown (1952) cubic fits of sun and moon
//!   illuminance in altitude, the moon's phase law and distance, 0.002 lux of
//!   night sky, a cloud-cover divisor.
//! - [`nvg`]: night-vision (Gen III, Class A minus-blue) weighting of light in
//!   2856 K-equivalent lux: the CIE 1931 V(λ) table and a shaped approximation
//!   of the tube's response R(λ), integrated over Planckian, LED, sodium and
//!   flare model spectra and over sunlight, moonlight (ROLO lunar reflectance)
//!   and skylight (Bird–Riordan); the night sky's factor is a documented choice.
//! - [`atmosphere`]: the Bruneton (2017) / Hillaire (2020) clear-sky
//!   atmosphere: transmittance and multiple-scattering tables, sky radiance
//!   and sky irradiance (Rayleigh, Mie, ozone; three wavelengths).
//! - [`clock`]: the simulation clock (start, rate, pause) and the light state
//!   (directions, colours, illuminance) that the renderer reads every frame.
//! - [`clouds`]: cloud layers as a seeded, tileable, rank-equalised fractal value-noise
//!   cover field advected by the wind, shaped by each kind's vertical profile; optical depth,
//!   the sun's transmittance (shade) and the sky's cover fraction. Two-dimensional cover, flat.
//! - [`lightning`]: the NPS thesis's branching bolt (V.A.4, appendix F), made
//!   iterative with a hard segment cap and seeded, and the flash envelope.
//! - [`stars`]: the 904 stars to magnitude 4.5 (Yale Bright Star Catalogue 5 with
//!   Hipparcos positions), precession (Meeus 21), nutation and sidereal rotation to
//!   ECEF, colour from B−V, the eye's threshold against a bright sky (Schaefer 1990).
//! - [`moon_disc`]: the moon's angular radius, bright-limb position angle (Meeus
//!   48.5), illuminated fraction and Lommel–Seeliger surface brightness.
//! - [`precipitation`]: rain and snow extinction from the Marshall-Palmer and Gunn-Marshall
//!   size distributions (geometric optics), visibility by Koschmieder, fall speeds.
//!
//! Conventions: degrees at every interface, metres, UTC; azimuth from true
//! north through east; directions in the observer's east-north-up frame.

#![cfg_attr(not(test), deny(clippy::unwrap_used, clippy::expect_used))]

pub mod atmosphere;
pub mod clock;
pub mod clouds;
pub mod ephemeris;
pub mod events;
pub mod illuminance;
pub mod lightning;
pub mod moon;
pub mod moon_disc;
pub mod nutation;
pub mod nvg;
pub mod precipitation;
pub mod stars;
pub mod sun;
pub mod time;
pub mod vsop87;

pub use atmosphere::{Atmosphere, AtmosphereParams, SUN_ILLUMINANCE_TOA_LUX};
pub use clock::{light_state, BodyLight, LightState, SimClock};
pub use clouds::{
    cloud_cover_fraction, CloudDrift, CloudField, CloudKind, CloudLayer, CloudOrigin,
};
pub use ephemeris::{ephemeris, BodyPosition, Ephemeris, Observer};
pub use events::{day_events, DayEvents};
pub use illuminance::{natural_illuminance, Illuminance};
pub use lightning::{generate_bolt, Bolt, BoltParams, BoltSegment, FlashEnvelope};
pub use nvg::{nvg_irradiance, LightSpectrum, NaturalSpectrum, NvgIrradiance};
pub use precipitation::{Precipitation, PrecipitationKind};
pub use time::{CalendarTime, UtcTime};

/// Errors from the environment model: every one names the bad value.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum EnvironmentError {
    /// A time that is not a valid UTC calendar time in 1900..=2100.
    #[error("invalid time: {0}")]
    InvalidTime(String),
    /// A latitude, longitude or height out of range.
    #[error("invalid location: {0}")]
    InvalidLocation(String),
    /// An environment setting out of range (cloud cover, clock rate, lightning).
    #[error("invalid setting: {0}")]
    InvalidSetting(String),
}
