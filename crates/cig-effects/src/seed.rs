//! Effect identity and the random generator every effect draws from.
//!
//! Algorithm: an effect is named by a 64-bit [`EffectId`] (for a DIS event: site, application and
//! event number packed as `site << 32 | application << 16 | event`, IEEE 1278.1 section 6.2.33).
//! Its generator is ChaCha8 (Bernstein's ChaCha with 8 rounds, `rand_chacha`) keyed with 32 bytes
//! expanded by SplitMix64 (Steele, Lea and Flood 2014) from the id and the IEEE-754 bits of the
//! start time. Uniform numbers take the top 53 bits of a `u64` (`x >> 11` times 2^-53), so every
//! machine draws the same sequence (source 000 chapter VII.A: the thesis's plumes differed on
//! every node because each drew its own random numbers).
//!
//! Epoch `e > 0` of an effect mixes `e * 0xD1B54A32D192ED03` into the SplitMix64 state.
//!
//! Limits: ChaCha8 is used for reproducibility, not secrecy.

use rand_chacha::rand_core::{RngCore, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Identity of an effect, the same on every IG of an exercise.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct EffectId(pub u64);

impl EffectId {
    /// The id of the effect caused by a DIS event (event id: site, application, event number).
    pub fn from_dis_event(site: u16, application: u16, event_number: u16) -> EffectId {
        EffectId((u64::from(site) << 32) | (u64::from(application) << 16) | u64::from(event_number))
    }
}

fn splitmix64(state: &mut u64) -> u64 {
    *state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
    let mut z = *state;
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// The generator of the effect `id` started at `start_time_s`.
pub fn effect_rng(id: EffectId, start_time_s: f64) -> EffectRng {
    effect_epoch_rng(id, start_time_s, 0)
}

/// The generator of epoch `epoch` of the effect (the particle engine re-keys its generator
/// every epoch, so a late joiner can start at an epoch instead of replaying the whole effect).
pub fn effect_epoch_rng(id: EffectId, start_time_s: f64, epoch: u64) -> EffectRng {
    let mut state =
        id.0 ^ start_time_s.to_bits().rotate_left(29) ^ epoch.wrapping_mul(0xD1B5_4A32_D192_ED03);
    let mut seed = [0u8; 32];
    for chunk in seed.chunks_exact_mut(8) {
        chunk.copy_from_slice(&splitmix64(&mut state).to_le_bytes());
    }
    EffectRng(ChaCha8Rng::from_seed(seed))
}

/// An effect's deterministic generator.
#[derive(Clone, Debug)]
pub struct EffectRng(ChaCha8Rng);

impl EffectRng {
    /// Uniform in `[0, 1)`.
    pub fn unit(&mut self) -> f64 {
        (self.0.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }

    /// Uniform in `[-1, 1)`.
    pub fn signed(&mut self) -> f64 {
        2.0 * self.unit() - 1.0
    }

    /// Approximately standard normal: the sum of three uniforms on [-1, 1) (variance 1), bounded
    /// at 3.
    pub fn normalish(&mut self) -> f64 {
        self.signed() + self.signed() + self.signed()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn same_identity_same_sequence_and_different_identities_differ() {
        let id = EffectId::from_dis_event(1, 2, 3);
        assert_eq!(id.0, (1 << 32) | (2 << 16) | 3);
        let draw = |id, t| {
            let mut r = effect_rng(id, t);
            (0..8).map(|_| r.unit()).collect::<Vec<f64>>()
        };
        assert_eq!(draw(id, 10.0), draw(id, 10.0));
        assert_ne!(draw(id, 10.0), draw(id, 10.5));
        assert_ne!(
            draw(id, 10.0),
            draw(EffectId::from_dis_event(1, 2, 4), 10.0)
        );
        let mut r = effect_rng(id, 0.0);
        let mut sum = 0.0;
        for _ in 0..10_000 {
            let u = r.unit();
            assert!((0.0..1.0).contains(&u));
            sum += u;
        }
        assert!((sum / 10_000.0 - 0.5).abs() < 0.02);
    }
}
