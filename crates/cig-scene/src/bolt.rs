//! One lightning bolt made ready to draw, and the light of its flash.
//!
//! Algorithm: the NPS thesis's branching bolt (§V.A.4, appendix F; `cig_environment::lightning`,
//! iterative, seeded, capped at [`MAX_BOLT_SEGMENTS`] segments so its cost is bounded — tens of
//! microseconds) grown from a root `cloud_base_m` above the strike point inside a 3 km wide
//! box down to the ground, turned from the strike point's east-north-up frame into ECEF
//! offsets (f32) from it, the main channel at brightness 1 and side branches at 0.4 / depth;
//! the generation time is measured. The flash's illuminance at the eye is `I / d²` with the
//! bolt's mean luminous intensity over a frame `I` = [`FLASH_LUMINOUS_INTENSITY_CD`] and `d` the
//! distance to the middle of its channel (at least 300 m: the cloud spreads the light), capped
//! at [`MAX_FLASH_LUX`]: 100 lux at 1 km (an overcast day), 1 lux at 10 km.
//!
//! Limits: one stroke, no return strokes; the luminous intensity is a visual constant (a
//! return stroke's peak is far higher but lasts microseconds).

use crate::BoltLine;
use cig_environment::lightning::{generate_bolt, BoltParams};
use cig_geo::{EnuFrame, Geodetic};
use glam::DVec3;
use std::sync::Arc;

/// Segment cap of every bolt.
pub const MAX_BOLT_SEGMENTS: usize = 2000;
/// Mean luminous intensity of a bolt over a frame, candela.
pub const FLASH_LUMINOUS_INTENSITY_CD: f64 = 1.0e8;
/// Nearest distance the flash's intensity is taken at, m.
const MIN_FLASH_DISTANCE_M: f64 = 300.0;
/// The most a flash adds to the scene's illuminance, lux.
pub const MAX_FLASH_LUX: f64 = 2000.0;
/// Horizontal half-size of a bolt's bounding volume, m.
const BOLT_HALF_WIDTH_M: f64 = 1500.0;

/// A generated bolt ready to draw, and what generating it cost.
#[derive(Clone, Debug)]
pub struct MadeBolt {
    pub origin_ecef_m: DVec3,
    pub lines: Arc<[BoltLine]>,
    /// The middle of the channel, ECEF, m (where the flash's light comes from).
    pub centre_ecef_m: DVec3,
    pub generation_us: f64,
    pub segments: usize,
}

/// Generates the bolt of a strike at `ground` (its root `cloud_base_m` above) with `seed`.
pub fn make_bolt(ground: Geodetic, cloud_base_m: f64, seed: u64) -> MadeBolt {
    let started = std::time::Instant::now();
    let base = if cloud_base_m.is_finite() {
        cloud_base_m.clamp(100.0, 10_000.0)
    } else {
        1500.0
    };
    let params = BoltParams {
        root_enu_m: [0.0, 0.0, base],
        bounds_min_enu_m: [-BOLT_HALF_WIDTH_M, -BOLT_HALF_WIDTH_M, 0.0],
        bounds_max_enu_m: [BOLT_HALF_WIDTH_M, BOLT_HALF_WIDTH_M, base],
        max_segments: MAX_BOLT_SEGMENTS,
        seed,
        ..BoltParams::default()
    };
    let frame = EnuFrame::new(ground);
    let lines: Vec<BoltLine> = match generate_bolt(&params) {
        Ok(bolt) => bolt
            .segments
            .iter()
            .map(|s| {
                let f = |p: [f64; 3]| {
                    let v = frame.enu_vector_to_ecef(DVec3::from_array(p));
                    [v.x as f32, v.y as f32, v.z as f32]
                };
                BoltLine {
                    start_m: f(s.start_enu_m),
                    end_m: f(s.end_enu_m),
                    brightness: if s.generation == 0 {
                        1.0
                    } else {
                        0.4 / s.generation as f32
                    },
                }
            })
            .collect(),
        // The parameters are this module's own and valid (the base is clamped); a failure
        // would draw nothing.
        Err(_) => Vec::new(),
    };
    let origin = ground.to_ecef();
    MadeBolt {
        origin_ecef_m: origin,
        segments: lines.len(),
        lines: lines.into(),
        centre_ecef_m: origin + frame.enu_vector_to_ecef(DVec3::new(0.0, 0.0, base / 2.0)),
        generation_us: started.elapsed().as_secs_f64() * 1e6,
    }
}

/// Illuminance at `eye_ecef_m` from a bolt whose channel's middle is at `centre_ecef_m`, lit
/// at `intensity` (0..1) of its peak, lux.
pub fn flash_lux_from(eye_ecef_m: DVec3, centre_ecef_m: DVec3, intensity: f64) -> f64 {
    let d = (centre_ecef_m - eye_ecef_m)
        .length()
        .max(MIN_FLASH_DISTANCE_M);
    (FLASH_LUMINOUS_INTENSITY_CD * intensity.clamp(0.0, 1.0) / (d * d)).min(MAX_FLASH_LUX)
}
