//! Detonation in: ground and building impacts start smoke and flame with a shared seed.
//!
//! Algorithm: the thesis (000, §VI.E.2) starts a node's smoke generator "when a detonation PDU
//! resulting from a ground or building impact is received". The Detonation Result field
//! (SISO-REF-010 UID 62) decides: ground — 3 Ground Impact, 4 Ground Proximate Detonation,
//! 11/12/13 Dirt blast small/medium/large; building — 18/19/20 Building hit small/medium/large,
//! 22 Environment object impact, 23 Environment object proximate detonation. Every other result
//! (entity hits, water, air bursts, duds, kills …) starts nothing here. The size comes from the
//! small/medium/large codes, medium otherwise.
//!
//! The thesis notes that plumes differ between nodes because each draws its own random numbers
//! (§VI.E.2, "dissimilar plume problem"). Here every node seeds the plume from the event
//! identity alone: `seed = splitmix64(site << 32 | application << 16 | event_number)`, where
//! `splitmix64(x)` is Vigna's SplitMix64 output function applied once:
//! `z = x + 0x9E3779B97F4A7C15; z = (z ^ z >> 30) * 0xBF58476D1CE4E5B9;
//! z = (z ^ z >> 27) * 0x94D049BB133111EB; z ^ z >> 31` (wrapping arithmetic). The packing is
//! one-to-one and the mix is a bijection, so distinct events never share a seed, and the value
//! is the same on every machine.
//!
//! Limits: the exercise ID is not part of the seed (event numbers are already unique per
//! application within an exercise); the impact position is the Detonation's world location
//! as sent, not clamped to terrain (the caller owns the terrain).

use dis_rs::detonation::model::Detonation;
use glam::DVec3;

/// Where a detonation hit.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ImpactSurface {
    /// The ground (terrain).
    Ground,
    /// A building or other environment object.
    Building,
}

/// How big the effect is.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum ImpactSize {
    /// Small.
    Small,
    /// Medium (also when the result gives no size).
    Medium,
    /// Large.
    Large,
}

/// A munition's impact on the ground, as the firing simulation reports it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GroundImpact {
    /// The event; the firing entity is object 1 and the munition object 2 of its site and
    /// application.
    pub event: EventIdentity,
    /// Where it burst, ECEF metres.
    pub location_ecef_m: DVec3,
    /// The munition's SISO-REF-010 entity type: kind, domain, country, category,
    /// subcategory, specific, extra.
    pub munition: (u8, u8, u16, u8, u8, u8, u8),
    /// Warhead (SISO-REF-010 UID 60; 1000 high explosive).
    pub warhead: u16,
}

impl GroundImpact {
    /// The Detonation PDU's body: a munition descriptor of one round, coming down at
    /// 300 m/s, result 3 (ground impact).
    #[must_use]
    pub fn message(&self) -> crate::codec::DisMessage {
        use dis_rs::detonation::model::DetonationDescriptor;
        use dis_rs::enumerations::{
            Country, DetonationResult, EntityKind, MunitionDescriptorWarhead, PlatformDomain,
        };
        use dis_rs::model::{
            EntityId, EntityType, EventId, Location, MunitionDescriptor, VectorF32,
        };
        use dis_rs::BodyRaw;
        let (kind, domain, country, category, subcategory, specific, extra) = self.munition;
        let e = self.event;
        let munition = MunitionDescriptor {
            entity_type: EntityType {
                kind: EntityKind::from(kind),
                domain: PlatformDomain::from(domain),
                country: Country::from(country),
                category,
                subcategory,
                specific,
                extra,
            },
            warhead: MunitionDescriptorWarhead::from(self.warhead),
            quantity: 1,
            ..MunitionDescriptor::default()
        };
        let p = self.location_ecef_m;
        let detonation = Detonation::builder()
            .with_source_entity_id(EntityId::new(e.site, e.application, 1))
            .with_target_entity_id(EntityId::new(0, 0, 0))
            .with_exploding_entity_id(EntityId::new(e.site, e.application, 2))
            .with_event_id(EventId::new(e.site, e.application, e.event_number))
            .with_velocity(VectorF32::new(0.0, 0.0, -300.0))
            .with_world_location(Location::new(p.x, p.y, p.z))
            .with_descriptor(DetonationDescriptor::Munition(munition))
            .with_entity_location(VectorF32::new(0.0, 0.0, 0.0))
            .with_detonation_result(DetonationResult::from(3))
            .build();
        crate::codec::DisMessage::Detonation(Box::new(detonation))
    }

    /// The Detonation PDU (DIS 7) of exercise `exercise_id`, stamped `seconds_past_hour`
    /// (absolute time).
    ///
    /// # Errors
    /// When the PDU cannot be encoded.
    pub fn pdu(
        &self,
        exercise_id: u8,
        seconds_past_hour: f64,
    ) -> Result<Vec<u8>, crate::codec::EncodeError> {
        crate::codec::encode_pdu(
            crate::codec::EncodeHeader {
                version: crate::codec::DisVersion::V7,
                exercise_id,
                timestamp: crate::codec::timestamp_from_seconds_past_hour(seconds_past_hour, true),
            },
            &self.message(),
        )
    }
}

/// The identity of a DIS event (Event ID record): unique per firing application.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct EventIdentity {
    /// Site number.
    pub site: u16,
    /// Application number.
    pub application: u16,
    /// Event number.
    pub event_number: u16,
}

impl EventIdentity {
    /// The deterministic 64-bit effect seed of this event (see the module doc).
    #[must_use]
    pub fn effect_seed(self) -> u64 {
        let packed = (u64::from(self.site) << 32)
            | (u64::from(self.application) << 16)
            | u64::from(self.event_number);
        splitmix64(packed)
    }
}

/// SplitMix64's output function applied once to `x` (Steele, Lea, Flood 2014; Vigna's
/// reference constants).
#[must_use]
pub fn splitmix64(x: u64) -> u64 {
    let mut z = x.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// A request to start smoke and flame at an impact point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ImpactEffectStart {
    /// The event that caused it.
    pub event: EventIdentity,
    /// Impact point, ECEF metres.
    pub position_ecef_m: DVec3,
    /// Ground or building.
    pub surface: ImpactSurface,
    /// Effect size.
    pub size: ImpactSize,
    /// Seed for the effect's random draws, equal on every node.
    pub effect_seed: u64,
    /// The raw Detonation Result code.
    pub detonation_result: u8,
}

/// Classifies a Detonation Result code: the surface and size for ground and building impacts.
#[must_use]
pub fn classify_result(code: u8) -> Option<(ImpactSurface, ImpactSize)> {
    use ImpactSize::{Large, Medium, Small};
    use ImpactSurface::{Building, Ground};
    match code {
        3 | 4 | 12 => Some((Ground, Medium)),
        11 => Some((Ground, Small)),
        13 => Some((Ground, Large)),
        18 => Some((Building, Small)),
        19 | 22 | 23 => Some((Building, Medium)),
        20 => Some((Building, Large)),
        _ => None,
    }
}

/// The effect a Detonation asks for, or `None` when its result is not a ground or building
/// impact (or its location is not finite).
#[must_use]
pub fn impact_effect(detonation: &Detonation) -> Option<ImpactEffectStart> {
    let code = u8::from(detonation.detonation_result);
    let (surface, size) = classify_result(code)?;
    let location = &detonation.location_in_world_coordinates;
    let position = DVec3::new(
        location.x_coordinate,
        location.y_coordinate,
        location.z_coordinate,
    );
    if !position.is_finite() {
        return None;
    }
    let event = EventIdentity {
        site: detonation.event_id.simulation_address.site_id,
        application: detonation.event_id.simulation_address.application_id,
        event_number: detonation.event_id.event_id,
    };
    Some(ImpactEffectStart {
        event,
        position_ecef_m: position,
        surface,
        size,
        effect_seed: event.effect_seed(),
        detonation_result: code,
    })
}
