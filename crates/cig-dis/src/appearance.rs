//! Appearance bits that ask for obscurant effects, and the start/stop diff between two updates;
//! appearance bits that switch an entity's lights.
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
//! Lights ([`LightsRequested`]), bit 0 the least significant, from SISO-REF-010 v35
//! (2025-04-27) as bundled with `dis-rs` 0.13 (`enumerations/SISO-REF-010.xml`, from which
//! `dis-rs` generates its typed appearance records; the tests decode every bit through those
//! records): land platforms (UID 31) head 12, tail 13, brake 14, blackout 26, blackout brake
//! 27, spot/search light #1 28, interior (forward) 29; air platforms (UID 32) NVG mode 2 (1 =
//! covert lighting for night-vision goggles), landing 12, navigation 13, anti-collision 14,
//! lower anti-collision 17, upper anti-collision 18, anti-collision day/night 19 (1 = night),
//! blinking 20, formation 24, navigation/position brightness 27 (1 = bright), spot/search
//! light #1 28, interior 29; surface platforms (UID 33) running 12, spot 28, interior 29;
//! subsurface platforms (UID 34) running 12. The XML and `dis-rs` agree on every one of
//! these positions (they cannot disagree: the structs are generated from it).
//!
//! Limits: other kinds (life forms, environmentals, cultural features …) carry no obscurant
//! bits here and request nothing; bits 7-8 of air, surface and munition appearances (trailing
//! effects, wake, vapour trail) are not dust and are ignored. Lights are read for platforms
//! only (space platforms have no light bits); the air bits 2, 17-20 and 27 were added to
//! SISO-REF-010 after IEEE 1278.1a-1998, so older senders leave them 0 (overt, day, dim,
//! not blinking, no separate upper/lower anti-collision light); spot light #1 stands for all
//! spot lights and the interior bit for all interior lights when no further record says more
//! (SISO-REF-010 footnotes).

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

/// Lights an entity's appearance switches on: each field is one appearance bit of its
/// platform domain's layout (module documentation); fields that the domain's layout does not
/// have stay `false`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
pub struct LightsRequested {
    /// Head lights (land, bit 12).
    pub head: bool,
    /// Tail lights (land, bit 13).
    pub tail: bool,
    /// Brake lights (land, bit 14).
    pub brake: bool,
    /// Blackout (convoy) lights (land, bit 26).
    pub blackout: bool,
    /// Blackout brake lights (land, bit 27).
    pub blackout_brake: bool,
    /// Spot / search light (land, air and surface, bit 28).
    pub spot: bool,
    /// Interior lights (land: forward interior; air and surface; bit 29).
    pub interior: bool,
    /// Landing lights (air, bit 12).
    pub landing: bool,
    /// Navigation (position) lights (air, bit 13).
    pub navigation: bool,
    /// Anti-collision lights (air, bit 14).
    pub anti_collision: bool,
    /// Lower anti-collision light (air, bit 17).
    pub lower_anti_collision: bool,
    /// Upper anti-collision light (air, bit 18).
    pub upper_anti_collision: bool,
    /// Anti-collision lights in night (dimmed or red) mode rather than day (air, bit 19).
    pub anti_collision_night: bool,
    /// Some of the aircraft's lights blink (strobes, beacons) (air, bit 20).
    pub blinking: bool,
    /// Formation lights (air, bit 24).
    pub formation: bool,
    /// Navigation / position lights at bright rather than dim (air, bit 27).
    pub navigation_bright: bool,
    /// Covert (NVG, infrared) rather than overt lighting (air, bit 2).
    pub covert: bool,
    /// Running lights (surface and subsurface, bit 12).
    pub running: bool,
}

/// One light field of [`LightsRequested`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum LightBit {
    Head,
    Tail,
    Brake,
    Blackout,
    BlackoutBrake,
    Spot,
    Interior,
    Landing,
    Navigation,
    AntiCollision,
    LowerAntiCollision,
    UpperAntiCollision,
    AntiCollisionNight,
    Blinking,
    Formation,
    NavigationBright,
    Covert,
    Running,
}

/// Land platform light bits (SISO-REF-010 UID 31).
const LAND_LIGHTS: [(LightBit, u32); 7] = [
    (LightBit::Head, 12),
    (LightBit::Tail, 13),
    (LightBit::Brake, 14),
    (LightBit::Blackout, 26),
    (LightBit::BlackoutBrake, 27),
    (LightBit::Spot, 28),
    (LightBit::Interior, 29),
];

/// Air platform light bits (SISO-REF-010 UID 32).
const AIR_LIGHTS: [(LightBit, u32); 12] = [
    (LightBit::Covert, 2),
    (LightBit::Landing, 12),
    (LightBit::Navigation, 13),
    (LightBit::AntiCollision, 14),
    (LightBit::LowerAntiCollision, 17),
    (LightBit::UpperAntiCollision, 18),
    (LightBit::AntiCollisionNight, 19),
    (LightBit::Blinking, 20),
    (LightBit::Formation, 24),
    (LightBit::NavigationBright, 27),
    (LightBit::Spot, 28),
    (LightBit::Interior, 29),
];

/// Surface platform light bits (SISO-REF-010 UID 33).
const SURFACE_LIGHTS: [(LightBit, u32); 3] = [
    (LightBit::Running, 12),
    (LightBit::Spot, 28),
    (LightBit::Interior, 29),
];

/// Subsurface platform light bits (SISO-REF-010 UID 34).
const SUBSURFACE_LIGHTS: [(LightBit, u32); 1] = [(LightBit::Running, 12)];

const DOMAIN_AIR: u8 = 2;
const DOMAIN_SURFACE: u8 = 3;
const DOMAIN_SUBSURFACE: u8 = 4;

/// The light bits of an entity kind and domain (empty where it has none).
fn light_layout(kind: u8, domain: u8) -> &'static [(LightBit, u32)] {
    if kind != KIND_PLATFORM {
        return &[];
    }
    match domain {
        DOMAIN_LAND => &LAND_LIGHTS,
        DOMAIN_AIR => &AIR_LIGHTS,
        DOMAIN_SURFACE => &SURFACE_LIGHTS,
        DOMAIN_SUBSURFACE => &SUBSURFACE_LIGHTS,
        _ => &[],
    }
}

impl LightsRequested {
    fn slot(&mut self, bit: LightBit) -> &mut bool {
        match bit {
            LightBit::Head => &mut self.head,
            LightBit::Tail => &mut self.tail,
            LightBit::Brake => &mut self.brake,
            LightBit::Blackout => &mut self.blackout,
            LightBit::BlackoutBrake => &mut self.blackout_brake,
            LightBit::Spot => &mut self.spot,
            LightBit::Interior => &mut self.interior,
            LightBit::Landing => &mut self.landing,
            LightBit::Navigation => &mut self.navigation,
            LightBit::AntiCollision => &mut self.anti_collision,
            LightBit::LowerAntiCollision => &mut self.lower_anti_collision,
            LightBit::UpperAntiCollision => &mut self.upper_anti_collision,
            LightBit::AntiCollisionNight => &mut self.anti_collision_night,
            LightBit::Blinking => &mut self.blinking,
            LightBit::Formation => &mut self.formation,
            LightBit::NavigationBright => &mut self.navigation_bright,
            LightBit::Covert => &mut self.covert,
            LightBit::Running => &mut self.running,
        }
    }

    /// Decodes the light bits of the appearance field of an entity of the given kind and
    /// domain (SISO-REF-010 layouts, module documentation); nothing for other kinds and
    /// domains.
    #[must_use]
    pub fn from_appearance(appearance: u32, kind: u8, domain: u8) -> LightsRequested {
        let mut out = LightsRequested::default();
        for &(bit, position) in light_layout(kind, domain) {
            *out.slot(bit) = appearance & (1 << position) != 0;
        }
        out
    }

    /// Sets these lights' bits in `appearance` for an entity of the given kind and domain
    /// (other bits kept; fields the domain's layout lacks are not written), for publishing.
    #[must_use]
    pub fn apply_to_appearance(self, appearance: u32, kind: u8, domain: u8) -> u32 {
        let mut lights = self;
        let mut out = appearance;
        for &(bit, position) in light_layout(kind, domain) {
            out &= !(1 << position);
            if *lights.slot(bit) {
                out |= 1 << position;
            }
        }
        out
    }

    /// Whether any light that emits is on (the mode bits — day/night, bright, covert,
    /// blinking — alone light nothing).
    #[must_use]
    pub fn any_on(self) -> bool {
        self.head
            || self.tail
            || self.brake
            || self.blackout
            || self.blackout_brake
            || self.spot
            || self.interior
            || self.landing
            || self.navigation
            || self.anti_collision
            || self.lower_anti_collision
            || self.upper_anti_collision
            || self.formation
            || self.running
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use dis_rs::entity_state::model::EntityAppearance;
    use dis_rs::enumerations::{EntityKind, PlatformDomain};
    use dis_rs::model::EntityType;
    use proptest::prelude::*;

    /// The lights `dis-rs` decodes from `bits` (its records generated from SISO-REF-010),
    /// in this module's shape: the independent peer of [`LightsRequested::from_appearance`].
    fn peer(bits: u32, kind: u8, domain: u8) -> LightsRequested {
        let entity_type = EntityType::default()
            .with_kind(EntityKind::from(kind))
            .with_domain(PlatformDomain::from(domain));
        let mut l = LightsRequested::default();
        match EntityAppearance::from_bytes(bits, &entity_type) {
            EntityAppearance::LandPlatform(a) => {
                l.head = a.head_lights_on;
                l.tail = a.tail_lights_on;
                l.brake = a.brake_lights_on;
                l.blackout = a.blackout_lights_on;
                l.blackout_brake = a.blackout_brake_lights_on;
                l.spot = a.spot_search_light_1_on;
                l.interior = a.interior_lights_forward_on;
            }
            EntityAppearance::AirPlatform(a) => {
                l.covert = u8::from(a.nvg_mode) == 1;
                l.landing = a.landing_lights_on;
                l.navigation = a.navigation_lights_on;
                l.anti_collision = a.anticollision_lights_on;
                l.lower_anti_collision = a.lower_anticollision_light_on;
                l.upper_anti_collision = a.upper_anticollision_light_on;
                l.anti_collision_night = u8::from(a.anticollision_light_day_night) == 1;
                l.blinking = a.is_blinking;
                l.formation = a.formation_lights_on;
                l.navigation_bright = u8::from(a.navigation_position_brightness) == 1;
                l.spot = a.spot_search_light_1_on;
                l.interior = a.interior_lights_on;
            }
            EntityAppearance::SurfacePlatform(a) => {
                l.running = a.running_lights_on;
                l.spot = a.spot_lights_on;
                l.interior = a.interior_lights_on;
            }
            EntityAppearance::SubsurfacePlatform(a) => {
                l.running = a.running_lights_on;
            }
            _ => {}
        }
        l
    }

    #[test]
    fn each_land_light_is_its_own_bit_as_dis_rs_reads_it() {
        type Field = fn(&mut LightsRequested) -> &mut bool;
        let fields: [(Field, u32); 7] = [
            (|l| &mut l.head, 12),
            (|l| &mut l.tail, 13),
            (|l| &mut l.brake, 14),
            (|l| &mut l.blackout, 26),
            (|l| &mut l.blackout_brake, 27),
            (|l| &mut l.spot, 28),
            (|l| &mut l.interior, 29),
        ];
        for (field, position) in fields {
            let mut l = LightsRequested::default();
            *field(&mut l) = true;
            let bits = l.apply_to_appearance(0, 1, 1);
            assert_eq!(bits, 1 << position, "{l:?}");
            assert_eq!(peer(bits, 1, 1), l);
            assert_eq!(LightsRequested::from_appearance(bits, 1, 1), l);
        }
    }

    #[test]
    fn air_and_surface_layouts_match_dis_rs() {
        let air = LightsRequested {
            landing: true,
            anti_collision: true,
            upper_anti_collision: true,
            anti_collision_night: true,
            blinking: true,
            navigation_bright: true,
            covert: true,
            ..LightsRequested::default()
        };
        let bits = air.apply_to_appearance(0, 1, 2);
        assert_eq!(
            bits,
            (1 << 2) | (1 << 12) | (1 << 14) | (1 << 18) | (1 << 19) | (1 << 20) | (1 << 27)
        );
        assert_eq!(peer(bits, 1, 2), air);
        // The same bits on a land platform mean other lights: 12 head, 14 brake, 27 blackout
        // brake; 2, 18, 19 and 20 are not lights there.
        let as_land = LightsRequested::from_appearance(bits, 1, 1);
        assert_eq!(
            as_land,
            LightsRequested {
                head: true,
                brake: true,
                blackout_brake: true,
                ..LightsRequested::default()
            }
        );
        let ship = LightsRequested {
            running: true,
            spot: true,
            ..LightsRequested::default()
        };
        let bits = ship.apply_to_appearance(0, 1, 3);
        assert_eq!(bits, (1 << 12) | (1 << 28));
        assert_eq!(peer(bits, 1, 3), ship);
        // Fields a layout lacks are not written: a ship has no head lights.
        let odd = LightsRequested {
            head: true,
            ..LightsRequested::default()
        };
        assert_eq!(odd.apply_to_appearance(0, 1, 3), 0);
        // Non-platforms and space platforms have no light bits.
        assert_eq!(
            LightsRequested::from_appearance(u32::MAX, 3, 1),
            LightsRequested::default()
        );
        assert_eq!(
            LightsRequested::from_appearance(u32::MAX, 1, 5),
            LightsRequested::default()
        );
        assert!(LightsRequested::from_appearance(u32::MAX, 1, 1).any_on());
        assert!(!LightsRequested {
            covert: true,
            blinking: true,
            ..LightsRequested::default()
        }
        .any_on());
    }

    #[test]
    fn dis_rs_encoded_lights_decode_here() {
        // dis-rs writes a land appearance from its typed record; this module reads it.
        let entity_type = EntityType::default()
            .with_kind(EntityKind::Platform)
            .with_domain(PlatformDomain::Land);
        let EntityAppearance::LandPlatform(mut land) =
            EntityAppearance::from_bytes(0, &entity_type)
        else {
            panic!("land platform appearance expected");
        };
        land.head_lights_on = true;
        land.blackout_brake_lights_on = true;
        let bits = u32::from(land);
        assert_eq!(
            LightsRequested::from_appearance(bits, 1, 1),
            LightsRequested {
                head: true,
                blackout_brake: true,
                ..LightsRequested::default()
            }
        );
    }

    proptest! {
        #[test]
        fn every_appearance_decodes_as_dis_rs_decodes_it(bits in any::<u32>(), domain in 0u8..7) {
            prop_assert_eq!(LightsRequested::from_appearance(bits, 1, domain), peer(bits, 1, domain));
        }

        #[test]
        fn lights_survive_the_appearance_bits(bits in any::<u32>(), other_bits in any::<u32>(), domain in 1u8..5) {
            let lights = LightsRequested::from_appearance(bits, 1, domain);
            let out = lights.apply_to_appearance(other_bits, 1, domain);
            prop_assert_eq!(LightsRequested::from_appearance(out, 1, domain), lights);
            prop_assert_eq!(peer(out, 1, domain), lights);
            // Unrelated bits are kept; the light bits are exactly the source's.
            let mask = LightsRequested::from_appearance(u32::MAX, 1, domain)
                .apply_to_appearance(0, 1, domain);
            prop_assert_eq!(out & !mask, other_bits & !mask);
            prop_assert_eq!(out & mask, bits & mask);
        }
    }
}
