//! Lightning: the NPS thesis's recursive branching bolt, made iterative and
//! bounded, and the flash that lifts the scene illuminance.
//!
//! Algorithm (NPS thesis, chapter V.A.4 and appendix F `do_lightning`): from a
//! root node a segment is drawn downward at a random angle to the vertical
//! (the thesis's 225°–315° to the ground plane, i.e. within 45° of straight
//! down) with a random length (the thesis's 0–100 units); at its end a left
//! child and a right child branch each exist with probability `density`; a
//! branch ends when its segment leaves the bounding volume (the thesis's
//! x/z bounds and ground elevation) or when a node has no child. Changes from
//! the thesis, for a frame that never stalls (its recursion froze the scene
//! above 50 % density): an explicit stack instead of recursion, visited
//! depth-first in the recursion's order (left before right), a hard cap on the
//! number of segments (the work is O(cap) whatever the density), the segment
//! that leaves the volume is clipped to its boundary (so every segment lies
//! inside), the geometry is three-dimensional (branch azimuths turn left or right
//! of the parent's by up to 90°), and an optional leader whose left child
//! always exists, so that the bolt reaches the ground. Randomness: ChaCha8 seeded
//! from the caller's seed, trigonometry from `libm`, so the same seed gives the
//! same bolt on every machine.
//!
//! Flash (thesis V.A.4: "set to the maximum amount possible and then linearly
//! decreased"): the envelope rises linearly to 1 over `rise_s` and falls
//! linearly to 0 over `decay_s`; the defaults (20 ms and 250 ms) make a flash a
//! frame or two to full brightness and gone in about 15 frames at 60 Hz.
//! Limits: a visual model only (no return strokes, no electrical effects).

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::EnvironmentError;

/// The largest segment cap accepted.
pub const MAX_SEGMENTS_LIMIT: usize = 100_000;

/// Parameters of one bolt. Positions are metres in a local east-north-up frame.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct BoltParams {
    /// Position of the root node (cloud base).
    pub root_enu_m: [f64; 3],
    /// Angle of the first segment from straight down, degrees (thesis: 0–45).
    pub initial_tilt_deg: f64,
    /// Largest angle of any later segment from straight down, degrees (thesis: 45).
    pub max_tilt_deg: f64,
    /// Shortest segment, metres (> 0).
    pub min_segment_m: f64,
    /// Longest segment, metres (thesis: 100 units).
    pub max_segment_m: f64,
    /// Probability that a node has a left child, and (independently) a right child.
    pub density: f64,
    /// Lower corner of the bounding volume; its up coordinate is the ground elevation.
    pub bounds_min_enu_m: [f64; 3],
    /// Upper corner of the bounding volume.
    pub bounds_max_enu_m: [f64; 3],
    /// Hard cap on the number of segments.
    pub max_segments: usize,
    /// Whether the leader (the chain of left children from the root) always continues.
    pub leader_to_ground: bool,
    /// Random seed.
    pub seed: u64,
}

impl Default for BoltParams {
    fn default() -> Self {
        BoltParams {
            root_enu_m: [0.0, 0.0, 2000.0],
            initial_tilt_deg: 20.0,
            max_tilt_deg: 45.0,
            min_segment_m: 20.0,
            max_segment_m: 100.0,
            density: 0.3,
            bounds_min_enu_m: [-1000.0, -1000.0, 0.0],
            bounds_max_enu_m: [1000.0, 1000.0, 2000.0],
            max_segments: 2000,
            leader_to_ground: true,
            seed: 1,
        }
    }
}

/// One straight piece of a bolt.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct BoltSegment {
    /// Start, metres ENU.
    pub start_enu_m: [f64; 3],
    /// End, metres ENU.
    pub end_enu_m: [f64; 3],
    /// Branching depth: 0 on the leader (or the root branch), +1 per side branch.
    pub generation: u32,
}

/// A generated bolt.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Bolt {
    /// The segments, in generation order (depth first, left before right).
    pub segments: Vec<BoltSegment>,
    /// Whether some segment reached the ground (the volume's lower up bound).
    pub reached_ground: bool,
    /// Whether the segment cap stopped the growth.
    pub truncated: bool,
}

/// A node waiting to grow a segment.
struct Node {
    position: [f64; 3],
    azimuth_deg: f64,
    tilt_deg: f64,
    generation: u32,
    leader: bool,
}

fn inside(p: [f64; 3], lo: [f64; 3], hi: [f64; 3]) -> bool {
    (0..3).all(|i| p[i] >= lo[i] && p[i] <= hi[i])
}

/// Check the parameters.
fn validate(p: &BoltParams) -> Result<(), EnvironmentError> {
    let bad = |what: String| Err(EnvironmentError::InvalidSetting(what));
    let finite = p
        .root_enu_m
        .iter()
        .chain(p.bounds_min_enu_m.iter())
        .chain(p.bounds_max_enu_m.iter())
        .chain(
            [
                p.initial_tilt_deg,
                p.max_tilt_deg,
                p.min_segment_m,
                p.max_segment_m,
            ]
            .iter(),
        )
        .all(|v| v.is_finite());
    if !finite {
        return bad("lightning parameters must be finite numbers".into());
    }
    if !(0.0..=1.0).contains(&p.density) {
        return bad(format!("lightning density {} is outside [0, 1]", p.density));
    }
    if !(0.0..90.0).contains(&p.initial_tilt_deg) || !(0.0..90.0).contains(&p.max_tilt_deg) {
        return bad(format!(
            "lightning tilts {} and {} degrees must be in [0, 90)",
            p.initial_tilt_deg, p.max_tilt_deg
        ));
    }
    if !(p.min_segment_m > 0.0 && p.min_segment_m <= p.max_segment_m) {
        return bad(format!(
            "lightning segment lengths {} to {} m need 0 < min <= max",
            p.min_segment_m, p.max_segment_m
        ));
    }
    if (0..3).any(|i| p.bounds_min_enu_m[i] >= p.bounds_max_enu_m[i]) {
        return bad("lightning bounding volume is empty".into());
    }
    if !inside(p.root_enu_m, p.bounds_min_enu_m, p.bounds_max_enu_m) {
        return bad("lightning root is outside its bounding volume".into());
    }
    if p.max_segments == 0 || p.max_segments > MAX_SEGMENTS_LIMIT {
        return bad(format!(
            "lightning segment cap {} is outside 1..={MAX_SEGMENTS_LIMIT}",
            p.max_segments
        ));
    }
    Ok(())
}

/// Generate a bolt. Work and memory are bounded by `max_segments`.
///
/// # Errors
/// [`EnvironmentError::InvalidSetting`] for non-finite values, a density outside
/// `[0, 1]`, tilts outside `[0, 90)`, bad segment lengths, an empty volume, a root
/// outside it, or a segment cap outside `1..=100 000`.
pub fn generate_bolt(params: &BoltParams) -> Result<Bolt, EnvironmentError> {
    validate(params)?;
    let mut rng = ChaCha8Rng::seed_from_u64(params.seed);
    let lo = params.bounds_min_enu_m;
    let hi = params.bounds_max_enu_m;
    let mut segments = Vec::with_capacity(params.max_segments.min(4096));
    let mut reached_ground = false;
    let mut stack = vec![Node {
        position: params.root_enu_m,
        azimuth_deg: rng.gen_range(0.0..360.0),
        tilt_deg: params.initial_tilt_deg,
        generation: 0,
        leader: params.leader_to_ground,
    }];
    // Every pop either adds a segment or ends a branch without pushing, so the loop
    // runs at most 2 * max_segments + 1 times.
    while let Some(node) = stack.pop() {
        if segments.len() >= params.max_segments {
            stack.push(node);
            break;
        }
        let length = rng.gen_range(params.min_segment_m..=params.max_segment_m);
        let tilt = node.tilt_deg.to_radians();
        let az = node.azimuth_deg.to_radians();
        let horizontal = length * libm::sin(tilt);
        let dir = [
            horizontal * libm::sin(az),
            horizontal * libm::cos(az),
            -length * libm::cos(tilt),
        ];
        let start = node.position;
        // Largest fraction of the segment inside the volume, and the limiting face.
        let mut t_exit = 1.0f64;
        let mut hits_ground = false;
        for i in 0..3 {
            let t = if dir[i] > 0.0 {
                (hi[i] - start[i]) / dir[i]
            } else if dir[i] < 0.0 {
                (lo[i] - start[i]) / dir[i]
            } else {
                f64::INFINITY
            };
            if t < t_exit {
                t_exit = t.max(0.0);
                hits_ground = i == 2 && dir[i] < 0.0;
            } else if t == t_exit && i == 2 && dir[i] < 0.0 {
                hits_ground = true;
            }
        }
        let mut end = [0.0; 3];
        for i in 0..3 {
            end[i] = (start[i] + dir[i] * t_exit).clamp(lo[i], hi[i]);
        }
        if t_exit > 0.0 {
            segments.push(BoltSegment {
                start_enu_m: start,
                end_enu_m: end,
                generation: node.generation,
            });
        }
        if t_exit < 1.0 {
            // Left the volume: this branch ends (the thesis backs out of the recursion).
            reached_ground |= hits_ground;
            continue;
        }
        // Children: right is pushed first so the left (the leader) grows first.
        let left = node.leader || rng.gen_bool(params.density);
        let right = rng.gen_bool(params.density);
        if right {
            stack.push(Node {
                position: end,
                azimuth_deg: node.azimuth_deg + rng.gen_range(0.0..90.0),
                tilt_deg: rng.gen_range(0.0..=params.max_tilt_deg),
                generation: node.generation + 1,
                leader: false,
            });
        }
        if left {
            stack.push(Node {
                position: end,
                azimuth_deg: node.azimuth_deg - rng.gen_range(0.0..90.0),
                tilt_deg: rng.gen_range(0.0..=params.max_tilt_deg),
                generation: if node.leader {
                    node.generation
                } else {
                    node.generation + 1
                },
                leader: node.leader,
            });
        }
    }
    Ok(Bolt {
        segments,
        reached_ground,
        truncated: !stack.is_empty(),
    })
}

/// The brightness envelope of a flash over time.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct FlashEnvelope {
    /// Time from the strike to full brightness, seconds.
    pub rise_s: f64,
    /// Time from full brightness back to none, seconds.
    pub decay_s: f64,
}

impl Default for FlashEnvelope {
    fn default() -> Self {
        FlashEnvelope {
            rise_s: 0.02,
            decay_s: 0.25,
        }
    }
}

impl FlashEnvelope {
    /// Relative flash brightness in `[0, 1]` at `t_s` seconds after the strike
    /// (0 before the strike and after the decay, and for non-finite times).
    pub fn intensity(&self, t_s: f64) -> f64 {
        if !t_s.is_finite() || t_s < 0.0 {
            return 0.0;
        }
        let rise = self.rise_s.max(0.0);
        let decay = self.decay_s.max(0.0);
        if t_s < rise {
            t_s / rise
        } else if t_s < rise + decay {
            1.0 - (t_s - rise) / decay
        } else {
            0.0
        }
    }

    /// Total duration of the flash, seconds.
    pub fn duration_s(&self) -> f64 {
        self.rise_s.max(0.0) + self.decay_s.max(0.0)
    }

    /// Scene illuminance during the flash: the base illuminance lifted toward
    /// `peak_lux` by the envelope (never lowered).
    pub fn scene_illuminance_lux(&self, base_lux: f64, peak_lux: f64, t_s: f64) -> f64 {
        base_lux + (peak_lux - base_lux).max(0.0) * self.intensity(t_s)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn same_seed_same_bolt_other_seed_other_bolt() {
        let p = BoltParams::default();
        let a = generate_bolt(&p).unwrap();
        let b = generate_bolt(&p).unwrap();
        assert_eq!(a, b);
        let c = generate_bolt(&BoltParams { seed: 2, ..p }).unwrap();
        assert_ne!(a, c);
        assert!(a.reached_ground, "the leader reaches the ground");
    }

    #[test]
    fn density_one_is_capped_not_stalled() {
        // The thesis's 99.9 % density: a full binary tree until the volume ends it.
        let p = BoltParams {
            density: 1.0,
            max_segments: 5000,
            ..BoltParams::default()
        };
        let bolt = generate_bolt(&p).unwrap();
        assert_eq!(bolt.segments.len(), 5000);
        assert!(bolt.truncated);
        assert!(
            bolt.reached_ground,
            "depth first: the leader is grown first"
        );
    }

    #[test]
    fn zero_density_without_leader_is_one_segment() {
        let p = BoltParams {
            density: 0.0,
            leader_to_ground: false,
            ..BoltParams::default()
        };
        let bolt = generate_bolt(&p).unwrap();
        assert_eq!(bolt.segments.len(), 1);
        assert!(!bolt.truncated);
    }

    #[test]
    fn bad_parameters_are_errors() {
        let d = BoltParams::default();
        for p in [
            BoltParams { density: 1.5, ..d },
            BoltParams {
                density: f64::NAN,
                ..d
            },
            BoltParams {
                max_segments: 0,
                ..d
            },
            BoltParams {
                max_segments: MAX_SEGMENTS_LIMIT + 1,
                ..d
            },
            BoltParams {
                min_segment_m: 0.0,
                ..d
            },
            BoltParams {
                min_segment_m: 200.0,
                ..d
            },
            BoltParams {
                max_tilt_deg: 90.0,
                ..d
            },
            BoltParams {
                root_enu_m: [0.0, 0.0, 5000.0],
                ..d
            },
            BoltParams {
                root_enu_m: [f64::NAN, 0.0, 100.0],
                ..d
            },
            BoltParams {
                bounds_min_enu_m: [1000.0, -1000.0, 0.0],
                ..d
            },
        ] {
            assert!(generate_bolt(&p).is_err(), "{p:?}");
        }
    }

    #[test]
    fn flash_rises_then_decays_within_a_few_hundred_ms() {
        let f = FlashEnvelope::default();
        assert_eq!(f.intensity(-0.01), 0.0);
        assert_eq!(f.intensity(0.0), 0.0);
        assert!((f.intensity(0.01) - 0.5).abs() < 1e-12);
        assert_eq!(f.intensity(0.02), 1.0);
        assert!(f.intensity(0.1) < 1.0 && f.intensity(0.1) > f.intensity(0.2));
        assert_eq!(f.intensity(0.27), 0.0);
        assert_eq!(f.intensity(f64::NAN), 0.0);
        assert!(f.duration_s() <= 0.3);
        assert_eq!(f.scene_illuminance_lux(0.01, 1000.0, 0.02), 1000.0);
        assert_eq!(f.scene_illuminance_lux(0.01, 1000.0, 1.0), 0.01);
        // A flash never darkens a bright scene.
        assert_eq!(f.scene_illuminance_lux(5000.0, 1000.0, 0.02), 5000.0);
    }

    proptest! {
        #[test]
        fn bolts_stay_inside_their_volume_and_under_their_cap(
            seed in any::<u64>(), density in 0.0f64..=1.0, cap in 1usize..3000,
            half in 50.0f64..2000.0, top in 100.0f64..3000.0, leader in any::<bool>()) {
            let p = BoltParams {
                root_enu_m: [0.0, 0.0, top * 0.99],
                bounds_min_enu_m: [-half, -half, 0.0],
                bounds_max_enu_m: [half, half, top],
                density,
                max_segments: cap,
                leader_to_ground: leader,
                seed,
                ..BoltParams::default()
            };
            let bolt = generate_bolt(&p).unwrap();
            prop_assert!(!bolt.segments.is_empty());
            prop_assert!(bolt.segments.len() <= cap);
            for s in &bolt.segments {
                for q in [s.start_enu_m, s.end_enu_m] {
                    prop_assert!(inside(q, p.bounds_min_enu_m, p.bounds_max_enu_m), "{q:?}");
                }
                let len: f64 = (0..3).map(|i| (s.end_enu_m[i] - s.start_enu_m[i]).powi(2)).sum::<f64>().sqrt();
                prop_assert!(len <= p.max_segment_m + 1e-9);
                // Every segment goes down (tilt < 90°).
                prop_assert!(s.end_enu_m[2] < s.start_enu_m[2]);
            }
            prop_assert_eq!(generate_bolt(&p).unwrap(), bolt);
        }
    }
}
