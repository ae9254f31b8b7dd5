//! Lightning in the world: a storm's strike schedule, the bolts lit now and their flash.
//!
//! Algorithm: a storm (centre, radius, cloud base, strikes per minute, seed) strikes as a
//! Poisson process in the shared world time. Time is cut into one-second slots; slot `k`
//! holds `Poisson(rate)` strikes drawn from a ChaCha8 stream seeded by `(seed, k)`, each at a
//! uniform time inside the slot and a uniform place inside the storm's disc, with its own bolt
//! seed and intensity. The schedule is thus a function of (seed, time) alone: every IG of an
//! exercise that shares the world time draws the same bolts at the same instants, whatever its
//! frame rate, and an IG that steps in other frame sizes sees the same strikes. When a strike
//! starts, its bolt is generated once (`cig_environment::lightning`: the NPS thesis's branching
//! bolt, §V.A.4 and appendix F, iterative and capped at [`MAX_BOLT_SEGMENTS`] segments, which
//! takes tens of microseconds, so no frame stalls; the time is measured and kept) and lit
//! along the thesis's flash envelope ("set to the maximum ... then linearly decreased"; rise
//! 20 ms, decay 250 ms: full brightness within 2 frames at 60 Hz, gone in about 16). Strikes
//! other nodes announce over DIS (thesis §VI.E.5) are drawn from the frame they arrive in;
//! strikes this IG schedules are announced when it is in an exercise (with the ground point
//! the bolt reaches); a strike with the seed of one struck in the last 10 s is the same strike
//! (two IGs of one storm announce it both) and is drawn once.
//!
//! The flash's illuminance at the eye is `I / d²` per lit bolt (times its envelope), with the
//! bolt's mean luminous intensity over a frame `I` = [`FLASH_LUMINOUS_INTENSITY_CD`] and `d`
//! the distance to the middle of its channel (at least 300 m: the cloud spreads the light),
//! capped at [`MAX_FLASH_LUX`]: a strike 1 km away lights the ground like an overcast day
//! (100 lux), one 10 km away like a full moon three times over, and at noon a flash changes
//! little — while at night it floods the scene, the night-vision washout of the thesis.
//!
//! Limits: no return strokes or restrikes (one stroke per flash), no intra-cloud lightning
//! (every bolt strikes the ground under its root), the luminous intensity is a visual constant
//! (measured peak intensities of return strokes are far higher but last microseconds), no
//! thunder.

use cig_environment::lightning::FlashEnvelope;
use cig_geo::{EnuFrame, Geodetic};
pub use cig_scene::bolt::{
    flash_lux_from, make_bolt, MadeBolt, FLASH_LUMINOUS_INTENSITY_CD, MAX_BOLT_SEGMENTS,
    MAX_FLASH_LUX,
};
use cig_scene::BoltDraw;
use glam::DVec3;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::sync::Arc;

/// Length of one schedule slot, s.
const SLOT_S: f64 = 1.0;
/// Most strikes one slot holds (a storm of 600 a minute would need more; rates are capped).
const MAX_STRIKES_PER_SLOT: u32 = 32;
/// The largest strike rate accepted, per minute.
pub const MAX_STRIKES_PER_MINUTE: f64 = 600.0;
/// Longest window one step looks back over, s (older strikes are over anyway).
const MAX_WINDOW_S: f64 = 2.0;
/// Bolts lit at once at most (the oldest go first).
const MAX_ACTIVE_BOLTS: usize = 16;

/// A thunderstorm that strikes by itself.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightningStorm {
    pub centre_lat_deg: f64,
    pub centre_lon_deg: f64,
    /// Strikes fall anywhere within this distance of the centre, m.
    pub radius_m: f64,
    /// Height of the cloud base (the bolts' roots) above the ground, m.
    pub cloud_base_m: f64,
    pub strikes_per_minute: f64,
    pub seed: u64,
}

/// One strike of a storm's schedule.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ScheduledStrike {
    /// When it strikes, seconds since 1970 UTC (world time).
    pub time_unix_s: f64,
    /// Where, on the ellipsoid (the ground height is found when it strikes).
    pub lat_deg: f64,
    pub lon_deg: f64,
    pub bolt_seed: u64,
    /// Relative intensity, 0.5..1.
    pub intensity: f32,
}

fn mix(a: u64, b: u64) -> u64 {
    cig_dis::detonation::splitmix64(a ^ cig_dis::detonation::splitmix64(b))
}

impl LightningStorm {
    /// The strikes of slot `slot` (the second starting at `slot * 1 s` since 1970).
    fn slot_strikes(&self, slot: i64, out: &mut Vec<ScheduledStrike>) {
        let mean = (self.strikes_per_minute / 60.0 * SLOT_S).clamp(0.0, 10.0);
        if mean <= 0.0 {
            return;
        }
        let mut rng = ChaCha8Rng::seed_from_u64(mix(self.seed, slot as u64));
        // Poisson by inversion (Knuth): the count whose cumulative probability passes u.
        let u: f64 = rng.gen();
        let mut p = (-mean).exp();
        let mut cumulative = p;
        let mut count = 0;
        while u > cumulative && count < MAX_STRIKES_PER_SLOT {
            count += 1;
            p *= mean / f64::from(count);
            cumulative += p;
        }
        let centre = EnuFrame::new(Geodetic::new(self.centre_lat_deg, self.centre_lon_deg, 0.0));
        for j in 0..count {
            let t = (slot as f64 + rng.gen::<f64>()) * SLOT_S;
            let r = self.radius_m * rng.gen::<f64>().sqrt();
            let a = rng.gen_range(0.0..std::f64::consts::TAU);
            let at = centre.enu_to_geodetic(DVec3::new(r * a.sin(), r * a.cos(), 0.0));
            out.push(ScheduledStrike {
                time_unix_s: t,
                lat_deg: at.lat_deg,
                lon_deg: at.lon_deg,
                bolt_seed: mix(mix(self.seed, slot as u64), u64::from(j) + 1),
                intensity: rng.gen_range(0.5f32..=1.0),
            });
        }
    }

    /// The strikes with `after_s < time <= until_s` (world time), in time order; the window is
    /// cut to its last 2 s.
    pub fn strikes_between(&self, after_s: f64, until_s: f64) -> Vec<ScheduledStrike> {
        let mut out = Vec::new();
        if !(after_s.is_finite() && until_s.is_finite()) || until_s <= after_s {
            return out;
        }
        let after_s = after_s.max(until_s - MAX_WINDOW_S);
        let first = (after_s / SLOT_S).floor() as i64;
        let last = (until_s / SLOT_S).floor() as i64;
        for slot in first..=last {
            self.slot_strikes(slot, &mut out);
        }
        out.retain(|s| s.time_unix_s > after_s && s.time_unix_s <= until_s);
        out.sort_by(|a, b| a.time_unix_s.total_cmp(&b.time_unix_s));
        out
    }
}

/// A bolt lit now.
#[derive(Clone, Debug)]
struct LitBolt {
    start_unix_s: f64,
    seed: u64,
    intensity: f32,
    bolt: MadeBolt,
}

/// Lightning statistics.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct LightningStats {
    pub bolts_generated: u64,
    /// Generation time of the last bolt and the longest, microseconds.
    pub last_generation_us: f64,
    pub max_generation_us: f64,
    /// Strikes received over DIS and drawn.
    pub strikes_received: u64,
}

/// The world's lightning: the storm's schedule and the bolts lit now.
#[derive(Clone, Debug, Default)]
pub struct Lightning {
    storm: Option<LightningStorm>,
    envelope: FlashEnvelope,
    lit: Vec<LitBolt>,
    last_time_unix_s: Option<f64>,
    stats: LightningStats,
    /// Seeds struck in the last [`RECENT_S`] seconds (an announcement of a strike already
    /// drawn, arriving late, is not drawn again).
    recent: Vec<(f64, u64)>,
}

/// How long a struck seed is remembered, s.
const RECENT_S: f64 = 10.0;
/// Most seeds remembered.
const MAX_RECENT: usize = 256;

impl Lightning {
    pub fn new(storm: Option<LightningStorm>) -> Lightning {
        Lightning {
            storm,
            ..Lightning::default()
        }
    }

    pub fn storm(&self) -> Option<&LightningStorm> {
        self.storm.as_ref()
    }

    /// Sets (or ends) the storm; the schedule goes on from now.
    pub fn set_storm(&mut self, storm: Option<LightningStorm>) {
        self.storm = storm;
    }

    pub fn stats(&self) -> LightningStats {
        self.stats
    }

    /// Number of bolts lit now.
    pub fn lit_count(&self) -> usize {
        self.lit.len()
    }

    /// Lights a bolt struck at `ground` at world time `time_unix_s` (a schedule's, a received
    /// or an operator's strike). A bolt with a seed already lit is not lit again.
    pub fn strike(
        &mut self,
        time_unix_s: f64,
        ground: Geodetic,
        cloud_base_m: f64,
        seed: u64,
        intensity: f32,
    ) -> bool {
        if !(time_unix_s.is_finite() && ground.lat_deg.is_finite() && ground.lon_deg.is_finite())
            || self.lit.iter().any(|b| b.seed == seed)
            || self.recent.iter().any(|(_, s)| *s == seed)
        {
            return false;
        }
        if self.recent.len() >= MAX_RECENT {
            self.recent.remove(0);
        }
        self.recent.push((time_unix_s, seed));
        let bolt = make_bolt(ground, cloud_base_m, seed);
        self.stats.bolts_generated += 1;
        self.stats.last_generation_us = bolt.generation_us;
        self.stats.max_generation_us = self.stats.max_generation_us.max(bolt.generation_us);
        if self.lit.len() >= MAX_ACTIVE_BOLTS {
            self.lit.remove(0);
        }
        self.lit.push(LitBolt {
            start_unix_s: time_unix_s,
            seed,
            intensity: if intensity.is_finite() {
                intensity.clamp(0.0, 1.0)
            } else {
                1.0
            },
            bolt,
        });
        true
    }

    /// Advances to world time `now_unix_s`: the storm's strikes since the last step are lit
    /// (their ground height from `ground_height_m`, metres above the ellipsoid) and returned
    /// with their ground points (to announce), and bolts whose flash is over go out. A time
    /// that goes back or jumps ahead starts the schedule again from `now_unix_s`.
    pub fn advance(
        &mut self,
        now_unix_s: f64,
        mut ground_height_m: impl FnMut(f64, f64) -> f64,
    ) -> Vec<(ScheduledStrike, Geodetic)> {
        if !now_unix_s.is_finite() {
            return Vec::new();
        }
        let after = match self.last_time_unix_s {
            Some(t) if now_unix_s >= t && now_unix_s - t <= MAX_WINDOW_S => t,
            _ => now_unix_s,
        };
        self.last_time_unix_s = Some(now_unix_s);
        let mut struck = Vec::new();
        if let Some(storm) = self.storm {
            for s in storm.strikes_between(after, now_unix_s) {
                let h = ground_height_m(s.lat_deg, s.lon_deg);
                let ground =
                    Geodetic::new(s.lat_deg, s.lon_deg, if h.is_finite() { h } else { 0.0 });
                self.strike(
                    s.time_unix_s,
                    ground,
                    storm.cloud_base_m,
                    s.bolt_seed,
                    s.intensity,
                );
                struck.push((s, ground));
            }
        }
        let over = self.envelope.duration_s();
        self.lit
            .retain(|b| now_unix_s - b.start_unix_s <= over && b.start_unix_s <= now_unix_s + 1.0);
        self.recent
            .retain(|(t, _)| (now_unix_s - t).abs() <= RECENT_S);
        struck
    }

    /// The bolts lit at `now_unix_s`, for the snapshot.
    pub fn draws(&self, now_unix_s: f64) -> Vec<BoltDraw> {
        self.lit
            .iter()
            .filter_map(|b| {
                let k = self.envelope.intensity(now_unix_s - b.start_unix_s) as f32 * b.intensity;
                (k > 0.0).then(|| BoltDraw {
                    origin_ecef_m: b.bolt.origin_ecef_m,
                    lines: Arc::clone(&b.bolt.lines),
                    intensity: k,
                })
            })
            .collect()
    }

    /// The flash's illuminance at `eye_ecef_m` at `now_unix_s`, lux.
    pub fn flash_lux(&self, now_unix_s: f64, eye_ecef_m: DVec3) -> f64 {
        let sum: f64 = self
            .lit
            .iter()
            .map(|b| {
                let k =
                    self.envelope.intensity(now_unix_s - b.start_unix_s) * f64::from(b.intensity);
                flash_lux_from(eye_ecef_m, b.bolt.centre_ecef_m, k)
            })
            .sum();
        sum.min(MAX_FLASH_LUX)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn storm(seed: u64) -> LightningStorm {
        LightningStorm {
            centre_lat_deg: 36.0,
            centre_lon_deg: -121.0,
            radius_m: 5000.0,
            cloud_base_m: 1500.0,
            strikes_per_minute: 30.0,
            seed,
        }
    }

    const T0: f64 = 1_782_068_400.0;

    #[test]
    fn the_schedule_has_the_storm_rate_and_stays_in_the_disc() {
        let s = storm(7);
        let strikes = s.strikes_between(T0, T0 + 2.0);
        assert!(strikes.len() < 20);
        let mut n = 0;
        let centre = Geodetic::new(36.0, -121.0, 0.0).to_ecef();
        for k in 0..600 {
            let t = T0 + f64::from(k) * 2.0;
            for x in s.strikes_between(t, t + 2.0) {
                n += 1;
                let d = (Geodetic::new(x.lat_deg, x.lon_deg, 0.0).to_ecef() - centre).length();
                assert!(d <= 5000.0 + 1.0, "{d}");
                assert!(x.time_unix_s > t && x.time_unix_s <= t + 2.0);
                assert!((0.5..=1.0).contains(&x.intensity));
            }
        }
        // 20 minutes at 30 a minute: 600, Poisson standard deviation 24.5.
        assert!((500..700).contains(&n), "{n}");
        assert!(storm(7).strikes_between(T0, T0 + 60.0).len() <= 2 * 32 + 1);
    }

    #[test]
    fn flash_falls_with_distance_and_is_capped() {
        let c = DVec3::new(6.4e6, 0.0, 0.0);
        let near = flash_lux_from(c + DVec3::new(1000.0, 0.0, 0.0), c, 1.0);
        let far = flash_lux_from(c + DVec3::new(10_000.0, 0.0, 0.0), c, 1.0);
        assert!((near - 100.0).abs() < 1e-9);
        assert!((far - 1.0).abs() < 1e-9);
        assert_eq!(flash_lux_from(c, c, 1.0), MAX_FLASH_LUX.min(1e8 / 9e4));
        assert_eq!(flash_lux_from(c, c, 0.0), 0.0);
    }

    #[test]
    fn bolts_are_generated_quickly_and_dedupe_by_seed() {
        let mut l = Lightning::new(None);
        assert!(l.strike(T0, Geodetic::new(36.0, -121.0, 10.0), 1500.0, 5, 1.0));
        assert!(!l.strike(T0, Geodetic::new(36.0, -121.0, 10.0), 1500.0, 5, 1.0));
        assert_eq!(l.lit_count(), 1);
        let d = l.draws(T0 + 0.02);
        assert_eq!(d.len(), 1);
        assert!(!d[0].lines.is_empty() && d[0].lines.len() <= MAX_BOLT_SEGMENTS);
        assert!((d[0].intensity - 1.0).abs() < 1e-6);
        l.advance(T0 + 1.0, |_, _| 0.0);
        assert_eq!(l.lit_count(), 0);
        // A late announcement of the same strike is not drawn again; after 10 s a seed is new.
        assert!(!l.strike(T0 + 1.0, Geodetic::new(36.0, -121.0, 10.0), 1500.0, 5, 1.0));
        l.advance(T0 + 1.5, |_, _| 0.0);
        l.advance(T0 + 3.0, |_, _| 0.0);
        l.advance(T0 + 12.0, |_, _| 0.0);
        assert!(l.strike(T0 + 12.0, Geodetic::new(36.0, -121.0, 10.0), 1500.0, 5, 1.0));
    }

    proptest! {
        #[test]
        fn any_window_split_gives_the_same_strikes(seed in any::<u64>(), cuts in proptest::collection::vec(0.001f64..1.9, 1..40)) {
            let s = storm(seed);
            let mut t = T0;
            let mut pieces = Vec::new();
            for c in &cuts {
                pieces.extend(s.strikes_between(t, t + c));
                t += c;
            }
            // The same span stepped in one-second pieces.
            let mut whole = Vec::new();
            let mut u = T0;
            while u < t {
                let next = (u + 1.0).min(t);
                whole.extend(s.strikes_between(u, next));
                u = next;
            }
            prop_assert_eq!(pieces, whole);
        }
    }
}
