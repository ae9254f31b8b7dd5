//! Scripted eyepoint paths over a database: straight legs that follow the terrain at a height
//! above it, looking ahead (the demo's flight and the render and environment benchmarks' pass).
//!
//! Algorithm: the eye moves along the leg's heading, straight in the start's local east/north
//! plane; its height is the highest terrain (HOT) within 300 m ahead, smoothed
//! (30 % a frame, never more than 20 m below the highest), plus a height above terrain that
//! changes linearly along the leg. Limits: the leg is straight in the start's tangent plane,
//! fine for tens of kilometres; it ends with an error where it leaves the database.

use crate::BenchError;
use cig_geo::{EnuFrame, Geodetic};
use cig_scene::{FovDeg, Hpr, View};
use cig_terrain::QuerySession;
use glam::DVec3;

/// One leg: start, heading, ground speed, duration, height above terrain, pitch.
#[derive(Clone, Copy, Debug)]
pub struct Leg {
    pub start: Geodetic,
    pub heading_deg: f64,
    pub speed_mps: f64,
    pub duration_s: f64,
    /// Height above terrain at the start and at the end (linear in between).
    pub agl_start_m: f64,
    pub agl_end_m: f64,
    pub pitch_deg: f64,
}

/// Views every `dt_s` along a leg. The height above terrain is kept against the highest
/// terrain within 300 m ahead, smoothed, so the eye never dips into a ridge.
///
/// # Errors
/// When the leg leaves the database.
pub fn views_along(
    session: &mut QuerySession,
    leg: &Leg,
    dt_s: f64,
    fov_deg: f64,
    size: (u32, u32),
) -> Result<Vec<View>, BenchError> {
    let frame = EnuFrame::new(leg.start);
    let (sh, ch) = leg.heading_deg.to_radians().sin_cos();
    let frames = (leg.duration_s / dt_s).round().max(1.0) as usize;
    let mut views = Vec::with_capacity(frames);
    let mut smoothed: Option<f64> = None;
    for i in 0..frames {
        let t = i as f64 * dt_s;
        let along = leg.speed_mps * t;
        let mut ground = |ahead: f64| -> Result<f64, BenchError> {
            let p =
                frame.enu_to_geodetic(DVec3::new(sh * (along + ahead), ch * (along + ahead), 0.0));
            Ok(session.hot(p.lat_deg, p.lon_deg)?.height_ellipsoid_m())
        };
        let mut highest = f64::NEG_INFINITY;
        for ahead in [0.0, 100.0, 200.0, 300.0] {
            // Past the database edge only the points still inside count.
            if let Ok(h) = ground(ahead) {
                highest = highest.max(h);
            }
        }
        if !highest.is_finite() {
            return Err(BenchError::Scene(format!(
                "the flight leaves the database after {t:.1} s"
            )));
        }
        let s = smoothed.map_or(highest, |prev| prev + (highest - prev) * 0.3);
        smoothed = Some(s.max(highest - 20.0));
        let agl =
            leg.agl_start_m + (leg.agl_end_m - leg.agl_start_m) * (t / leg.duration_s).min(1.0);
        let p = frame.enu_to_geodetic(DVec3::new(sh * along, ch * along, 0.0));
        views.push(View {
            eye: Geodetic::new(p.lat_deg, p.lon_deg, smoothed.unwrap_or(highest) + agl),
            orientation: Hpr {
                heading_deg: leg.heading_deg,
                pitch_deg: leg.pitch_deg,
                roll_deg: 0.0,
            },
            fov: FovDeg::from_horizontal(fov_deg, size.0, size.1),
            width_px: size.0,
            height_px: size.1,
        });
    }
    Ok(views)
}
