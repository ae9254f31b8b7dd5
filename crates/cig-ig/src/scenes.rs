//! Scenes the commands draw beside the terrain: the fires of `cig render --smoke` (a smoke
//! plume and its flames, stepped to the moment asked for) and the lightning bolt of
//! `--lightning` and of the demo's thunderstorm.
//!
//! Algorithm: each fire starts a smoke and a flame plume in a fresh `cig_effects::EffectSystem`
//! whose air has Pasquill's class from the wind and the sun's elevation (Turner's key), started
//! so that every fire has burnt its own seconds when the system reaches the frame; the bolt is
//! `cig_ig::weather::make_bolt` on the terrain a given distance ahead of the eye, at its
//! brightest, with its flash at the eye. Limits: the air is 15 °C at the ground with no cloud
//! ceiling; at most 2 x the fires' count of plume slots.

use crate::weather::{flash_lux_from, make_bolt, MadeBolt};

use cig_geo::Geodetic;
use cig_scene::View;
use cig_terrain::QuerySession;
use std::sync::Arc;

/// Why a scene could not be made: what was being done, then why (with its causes). One line.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    #[error("{what}: {reason}")]
    Step { what: String, reason: String },
    #[error(transparent)]
    Effects(#[from] cig_effects::EffectsError),
}

impl SceneError {
    fn new(what: &str, error: &dyn std::error::Error) -> SceneError {
        let mut reason = error.to_string();
        let mut cause = error.source();
        while let Some(c) = cause {
            reason.push_str(": ");
            reason.push_str(&c.to_string());
            cause = c.source();
        }
        SceneError::Step {
            what: what.to_string(),
            reason,
        }
    }
}

/// A fire asked for with `--smoke`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FireSpec {
    pub lat_deg: f64,
    pub lon_deg: f64,
    pub heat_w: f64,
    /// How long it has burnt at the frame's time, s.
    pub burning_s: f64,
}

/// Largest heat release `--smoke` takes, MW (a large oil-tank fire).
pub const MAX_HEAT_MW: f64 = 10_000.0;
/// Longest `--smoke` burn simulated, s.
pub const MAX_BURN_S: f64 = 3600.0;
/// Footprint of a `--smoke` fire (a burning vehicle), m.
pub const FIRE_SIZE_M: f64 = 3.0;

/// Starts each fire (a smoke plume and its flames, on the terrain) in a new effect system
/// stepped to the moment the longest has burnt its seconds, in air of Pasquill's class for
/// the wind and the sun at `unix_time_s`, and returns the puffs relative to `origin_ecef_m`.
/// Each fire comes with the text it was given as, which errors name.
///
/// # Errors
/// When the air or a fire is refused, or a fire is off the database.
pub fn fire_puffs(
    session: &mut QuerySession,
    fires: &[(String, FireSpec)],
    wind: cig_effects::Wind,
    unix_time_s: f64,
    origin_ecef_m: glam::DVec3,
) -> Result<Vec<cig_effects::PuffInstance>, SceneError> {
    use cig_effects::{
        Atmosphere, EffectId, EffectSystem, EffectsConfig, PlumeKind, PlumeSource, PlumeSpec,
    };
    let mut puffs = Vec::new();
    let Some((_, first)) = fires.first() else {
        return Ok(puffs);
    };
    let sun = cig_scene::Lighting::at(
        unix_time_s,
        Geodetic::new(first.lat_deg, first.lon_deg, 0.0),
    );
    let atmosphere =
        Atmosphere::from_weather(wind, 288.15, sun.sun_elevation_deg, 0.0, f64::INFINITY)
            .map_err(|e| SceneError::new("--wind", &e))?;
    let mut system = EffectSystem::new(EffectsConfig {
        plume_slots: 2 * fires.len(),
        dust_slots: 0,
        ..Default::default()
    })?;
    system.set_atmosphere(atmosphere)?;
    let end_s = fires.iter().map(|(_, f)| f.burning_s).fold(0.0, f64::max);
    system.advance_to(0.0)?;
    for (i, (text, fire)) in fires.iter().enumerate() {
        let ground = session.hot(fire.lat_deg, fire.lon_deg).map_err(|e| {
            SceneError::new(
                &format!("--smoke \"{text}\": the fire cannot be placed on the terrain"),
                &e,
            )
        })?;
        let position = Geodetic::new(fire.lat_deg, fire.lon_deg, ground.height_ellipsoid_m());
        for (k, kind) in [PlumeKind::Smoke, PlumeKind::Flame].into_iter().enumerate() {
            system
                .start_plume(&PlumeSpec {
                    id: EffectId((2 * i + k) as u64),
                    kind,
                    position,
                    size_m: FIRE_SIZE_M,
                    source: PlumeSource::HeatReleaseW(fire.heat_w),
                    start_time_s: end_s - fire.burning_s,
                    duration_s: MAX_BURN_S * 2.0,
                })
                .map_err(|e| SceneError::new(&format!("--smoke \"{text}\""), &e))?;
        }
    }
    system.advance_to(end_s)?;
    system.snapshot(origin_ecef_m, &mut puffs);
    Ok(puffs)
}

/// The bolt of `--lightning`: `distance_m` ahead of the eye on the terrain (or the ellipsoid
/// off the database), at its brightest, and its flash at the eye.
pub fn lightning_bolt(
    session: &mut QuerySession,
    view: &View,
    seed: u64,
    distance_m: f64,
) -> (cig_scene::BoltDraw, f64, MadeBolt) {
    let frame = cig_geo::EnuFrame::new(view.eye);
    let h = view.orientation.heading_deg.to_radians();
    let ahead = frame.enu_to_geodetic(glam::DVec3::new(
        distance_m * h.sin(),
        distance_m * h.cos(),
        0.0,
    ));
    let ground_m = session
        .hot(ahead.lat_deg, ahead.lon_deg)
        .map_or(0.0, |g| g.height_ellipsoid_m());
    let ground = Geodetic::new(ahead.lat_deg, ahead.lon_deg, ground_m);
    let bolt = make_bolt(ground, 1500.0, seed);
    let flash_lux = flash_lux_from(view.eye.to_ecef(), bolt.centre_ecef_m, 1.0);
    (
        cig_scene::BoltDraw {
            origin_ecef_m: bolt.origin_ecef_m,
            lines: Arc::clone(&bolt.lines),
            intensity: 1.0,
        },
        flash_lux,
        bolt,
    )
}
