//! Appearance bits that ask for obscurant effects, and the start/stop diff between two updates.
//!
//! Algorithm: read the 32-bit Entity State appearance field with the bit layouts of
//! SISO-REF-010: for platforms (kind 1: land UID 31, air UID 32, surface UID 33, subsurface
//! UID 34, space UID 35) and munitions (kind 2, UID 36) bit 5 is "smoke emanating" (a plume
//! rising from the entity), bit 6 "engine emitting smoke" and bit 15 "is flaming"; for land
//! platforms only, bits 7-8 are the trailing dust cloud size (0 none, 1 small, 2 medium,
//! 3 large). The thesis (000, §VI.E.2-3) networks smoke, flames and vehicle dust trails exactly
//! through these fields. A diff between the previous and the new request lists the effects to
//! start and to stop (a dust size change is a stop of the old size and a start of the new one).
//!
//! Limits: other kinds (life forms, environmentals, cultural features …) carry no obscurant
//! bits here and request nothing; bits 7-8 of air, surface and munition appearances (trailing
//! effects, wake, vapour trail) are not dust and are ignored.

/// Size of the trailing dust cloud of a land platform (appearance bits 7-8).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Default)]
pub enum DustCloudSize {
    /// No dust cloud.
    #[default]
    None,
    /// Small.
    Small,
    /// Medium.
    Medium,
    /// Large.
    Large,
}

/// Obscurant effects an entity's appearance asks for.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
pub struct EffectsRequested {
    /// A smoke plume rises from the entity (bit 5).
    pub smoke_plume: bool,
    /// The engine emits smoke (bit 6).
    pub engine_smoke: bool,
    /// The entity is on fire (bit 15).
    pub flaming: bool,
    /// Trailing dust cloud (land platforms, bits 7-8).
    pub dust_cloud: DustCloudSize,
}

/// One effect on one entity.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum EntityEffect {
    /// Smoke plume.
    SmokePlume,
    /// Engine smoke.
    EngineSmoke,
    /// Flames.
    Flames,
    /// Trailing dust cloud of the given size (never [`DustCloudSize::None`]).
    DustCloud(DustCloudSize),
}

/// Effects to start and stop after an appearance change, each list in a fixed order.
#[derive(Clone, Debug, PartialEq, Eq, Default)]
pub struct EffectsDiff {
    /// Effects that begin.
    pub start: Vec<EntityEffect>,
    /// Effects that end.
    pub stop: Vec<EntityEffect>,
}

impl EffectsDiff {
    /// Whether nothing changes.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.start.is_empty() && self.stop.is_empty()
    }
}

const BIT_SMOKE: u32 = 1 << 5;
const BIT_ENGINE_SMOKE: u32 = 1 << 6;
const SHIFT_DUST: u32 = 7;
const BIT_FLAMING: u32 = 1 << 15;
const KIND_PLATFORM: u8 = 1;
const KIND_MUNITION: u8 = 2;
const DOMAIN_LAND: u8 = 1;

impl EffectsRequested {
    /// Decodes the appearance field of an entity of the given kind and domain.
    #[must_use]
    pub fn from_appearance(appearance: u32, kind: u8, domain: u8) -> EffectsRequested {
        if kind != KIND_PLATFORM && kind != KIND_MUNITION {
            return EffectsRequested::default();
        }
        let dust_cloud = if kind == KIND_PLATFORM && domain == DOMAIN_LAND {
            match (appearance >> SHIFT_DUST) & 3 {
                1 => DustCloudSize::Small,
                2 => DustCloudSize::Medium,
                3 => DustCloudSize::Large,
                _ => DustCloudSize::None,
            }
        } else {
            DustCloudSize::None
        };
        EffectsRequested {
            smoke_plume: appearance & BIT_SMOKE != 0,
            engine_smoke: appearance & BIT_ENGINE_SMOKE != 0,
            flaming: appearance & BIT_FLAMING != 0,
            dust_cloud,
        }
    }

    /// Sets these effects' bits in `appearance` (other bits kept), for publishing.
    #[must_use]
    pub fn apply_to_appearance(self, appearance: u32) -> u32 {
        let mut out =
            appearance & !(BIT_SMOKE | BIT_ENGINE_SMOKE | BIT_FLAMING | (3 << SHIFT_DUST));
        if self.smoke_plume {
            out |= BIT_SMOKE;
        }
        if self.engine_smoke {
            out |= BIT_ENGINE_SMOKE;
        }
        if self.flaming {
            out |= BIT_FLAMING;
        }
        let dust: u32 = match self.dust_cloud {
            DustCloudSize::None => 0,
            DustCloudSize::Small => 1,
            DustCloudSize::Medium => 2,
            DustCloudSize::Large => 3,
        };
        out | (dust << SHIFT_DUST)
    }

    /// The active effects in a fixed order.
    #[must_use]
    pub fn active(self) -> Vec<EntityEffect> {
        let mut out = Vec::new();
        if self.smoke_plume {
            out.push(EntityEffect::SmokePlume);
        }
        if self.engine_smoke {
            out.push(EntityEffect::EngineSmoke);
        }
        if self.flaming {
            out.push(EntityEffect::Flames);
        }
        if self.dust_cloud != DustCloudSize::None {
            out.push(EntityEffect::DustCloud(self.dust_cloud));
        }
        out
    }

    /// What starts and stops when the request goes from `self` to `next`.
    #[must_use]
    pub fn diff(self, next: EffectsRequested) -> EffectsDiff {
        let before = self.active();
        let after = next.active();
        EffectsDiff {
            start: after
                .iter()
                .copied()
                .filter(|e| !before.contains(e))
                .collect(),
            stop: before
                .iter()
                .copied()
                .filter(|e| !after.contains(e))
                .collect(),
        }
    }
}
