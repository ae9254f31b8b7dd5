//! Remote entity table: Entity State in, dead-reckoned and smoothed snapshots out.
//!
//! Algorithm: entities are keyed by their Entity ID (site, application, entity) in an ordered
//! map, so snapshots come out in the same order on every machine. A PDU is accepted when its
//! exercise ID matches, its site passes the site filter and it is not from this node's own
//! (site, application). Each accepted Entity State replaces the entity's dead-reckoning input
//! (IEEE 1278.1-2012 Annex E, see [`crate::dead_reckoning`]) stamped with the local receive
//! time; between updates the entity moves by its own DR algorithm.
//!
//! Smoothing (IEEE 1278.1-2012 Annex E.3 asks for it but leaves the method open): when an update
//! arrives at time tᵤ, the pose being displayed at tᵤ (position, velocity, orientation, angular
//! velocity) becomes a constant-velocity "old" track starting exactly there, and for
//! `smoothing_s` seconds the displayed pose is blended from that old track to the new DR track
//! with weight s = 3u² − 2u³, u = (t − tᵤ)/`smoothing_s` (positions interpolated linearly,
//! orientations by quaternion slerp). At tᵤ the weight is 0, so there is no jump; after
//! `smoothing_s` the new track alone is shown. Updates further than `snap_distance_m` from the
//! displayed position snap (a teleport should not slide).
//!
//! Removal: an entity whose last update is older than `timeout_s` (default 12 s = 2.4 × the
//! 5 s heartbeat, IEEE 1278.1-2012 §5.2.6 / Table 4 defaults) is dropped, as is one whose
//! appearance "state" bit (bit 23) says deactivated.
//!
//! Limits: the receive time, not the PDU timestamp, is the DR time base (timestamps of
//! unsynchronised senders are relative); the table holds at most `max_entities` entities and
//! ignores new ones beyond that; no Entity State Update PDU (type 67) handling.

use std::collections::{BTreeMap, BTreeSet};

use cig_geo::Geodetic;
use dis_rs::entity_state::model::EntityState;
use dis_rs::enumerations::{Country, EntityKind, PlatformDomain};
use dis_rs::model::EntityType;
use glam::{DMat3, DQuat, DVec3};

use crate::appearance::{EffectsDiff, EffectsRequested};
use crate::codec::{DecodedPdu, DisMessage, PduHeaderInfo};
use crate::dead_reckoning::{DrAlgorithm, DrInput, DrModel, DrPose, EulerAngles};

/// Entity ID: (site, application, entity).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct EntityKey {
    /// Site number.
    pub site: u16,
    /// Application number.
    pub application: u16,
    /// Entity number.
    pub entity: u16,
}

/// The seven-field DIS entity type, as plain numbers.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Default)]
pub struct EntityTypeCode {
    /// Kind (1 platform, 2 munition, 3 life form, 4 environmental …).
    pub kind: u8,
    /// Domain (for platforms: 1 land, 2 air, 3 surface, 4 subsurface, 5 space).
    pub domain: u8,
    /// Country (SISO-REF-010 UID 29).
    pub country: u16,
    /// Category.
    pub category: u8,
    /// Subcategory.
    pub subcategory: u8,
    /// Specific.
    pub specific: u8,
    /// Extra.
    pub extra: u8,
}

impl EntityTypeCode {
    /// From a `dis-rs` entity type.
    #[must_use]
    pub fn from_dis(t: &EntityType) -> EntityTypeCode {
        EntityTypeCode {
            kind: u8::from(t.kind),
            domain: u8::from(t.domain),
            country: u16::from(t.country),
            category: t.category,
            subcategory: t.subcategory,
            specific: t.specific,
            extra: t.extra,
        }
    }

    /// As a `dis-rs` entity type.
    #[must_use]
    pub fn to_dis(self) -> EntityType {
        EntityType {
            kind: EntityKind::from(self.kind),
            domain: PlatformDomain::from(self.domain),
            country: Country::from(self.country),
            category: self.category,
            subcategory: self.subcategory,
            specific: self.specific,
            extra: self.extra,
        }
    }
}

/// The dead-reckoning algorithm and input an Entity State carries.
#[must_use]
pub fn dr_input_from_entity_state(es: &EntityState) -> (DrAlgorithm, DrInput) {
    let v = &es.entity_linear_velocity;
    let l = &es.entity_location;
    let o = &es.entity_orientation;
    let dr = &es.dead_reckoning_parameters;
    let a = &dr.linear_acceleration;
    let w = &dr.angular_velocity;
    let vec = |x: f32, y: f32, z: f32| DVec3::new(f64::from(x), f64::from(y), f64::from(z));
    (
        DrAlgorithm::from_code(u8::from(dr.algorithm)),
        DrInput {
            position_ecef_m: DVec3::new(l.x_coordinate, l.y_coordinate, l.z_coordinate),
            orientation: EulerAngles {
                psi_rad: f64::from(o.psi),
                theta_rad: f64::from(o.theta),
                phi_rad: f64::from(o.phi),
            },
            velocity_ecef_mps: vec(
                v.first_vector_component,
                v.second_vector_component,
                v.third_vector_component,
            ),
            acceleration_mps2: vec(
                a.first_vector_component,
                a.second_vector_component,
                a.third_vector_component,
            ),
            angular_velocity_body_radps: vec(
                w.first_vector_component,
                w.second_vector_component,
                w.third_vector_component,
            ),
        },
    )
}

fn finite_input(input: &DrInput) -> bool {
    input.position_ecef_m.is_finite()
        && input.velocity_ecef_mps.is_finite()
        && input.acceleration_mps2.is_finite()
        && input.angular_velocity_body_radps.is_finite()
        && input.orientation.psi_rad.is_finite()
        && input.orientation.theta_rad.is_finite()
        && input.orientation.phi_rad.is_finite()
}

/// Configuration of the remote entity table.
#[derive(Clone, Debug, PartialEq)]
pub struct RemoteTableConfig {
    /// Exercise ID to accept.
    pub exercise_id: u8,
    /// Sites to accept; empty accepts all.
    pub accepted_sites: BTreeSet<u16>,
    /// This node's own (site, application), whose PDUs are ignored.
    pub own_address: Option<(u16, u16)>,
    /// Seconds without an update before an entity is dropped.
    pub timeout_s: f64,
    /// Seconds over which a new update is blended in.
    pub smoothing_s: f64,
    /// Updates further than this from the displayed position snap, metres.
    pub snap_distance_m: f64,
    /// At most this many entities are held.
    pub max_entities: usize,
}

impl Default for RemoteTableConfig {
    fn default() -> Self {
        RemoteTableConfig {
            exercise_id: 1,
            accepted_sites: BTreeSet::new(),
            own_address: None,
            timeout_s: 12.0,
            smoothing_s: 0.75,
            snap_distance_m: 250.0,
            max_entities: 100_000,
        }
    }
}

/// Why an entity left the table.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RemovalReason {
    /// No update within the timeout.
    Timeout,
    /// Its appearance said deactivated.
    Deactivated,
}

/// Something that happened to the table.
#[derive(Clone, Debug, PartialEq)]
pub enum TableEvent {
    /// A new entity appeared.
    Appeared(EntityKey),
    /// Its effects changed (also sent right after [`TableEvent::Appeared`] when it has any).
    EffectsChanged {
        /// The entity.
        key: EntityKey,
        /// What starts and stops.
        diff: EffectsDiff,
    },
    /// The entity left; its effects stop.
    Removed {
        /// The entity.
        key: EntityKey,
        /// Why.
        reason: RemovalReason,
        /// Effects that were active and now stop.
        diff: EffectsDiff,
    },
}

/// Why a PDU was not applied.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Ignored {
    /// Another exercise.
    Exercise,
    /// A site outside the filter.
    Site,
    /// This node's own PDU.
    Own,
    /// Not an Entity State.
    NotEntityState,
    /// Non-finite numbers.
    NotFinite,
    /// The table is full.
    Full,
}

#[derive(Clone, Copy, Debug)]
struct Track {
    model: DrModel,
    start_s: f64,
}

impl Track {
    fn new(algorithm: DrAlgorithm, input: DrInput, start_s: f64) -> Track {
        Track {
            model: DrModel::new(algorithm, input),
            start_s,
        }
    }

    fn pose(&self, now_s: f64) -> DrPose {
        self.model.pose(now_s - self.start_s)
    }
}

#[derive(Clone, Debug)]
struct RemoteEntity {
    entity_type: EntityTypeCode,
    current: Track,
    blend_from: Option<Track>,
    received_s: f64,
    effects: EffectsRequested,
    appearance: u32,
    marking: String,
}

/// A remote entity as seen at one time.
#[derive(Clone, Debug, PartialEq)]
pub struct RemoteEntitySnapshot {
    /// Entity ID.
    pub key: EntityKey,
    /// Entity type.
    pub entity_type: EntityTypeCode,
    /// Dead-reckoned, smoothed position, ECEF metres.
    pub position_ecef_m: DVec3,
    /// The same as geodetic latitude, longitude, ellipsoid height.
    pub geodetic: Geodetic,
    /// Orientation, DIS Euler angles (radians, ECEF-referenced).
    pub orientation: EulerAngles,
    /// Heading (degrees from north, clockwise), pitch (degrees, nose up) and roll (degrees,
    /// right side down) in the local east-north-up frame.
    pub heading_pitch_roll_deg: [f64; 3],
    /// Velocity, ECEF m/s.
    pub velocity_ecef_mps: DVec3,
    /// DR algorithm of the last update.
    pub algorithm: DrAlgorithm,
    /// Effects the appearance asks for.
    pub effects: EffectsRequested,
    /// Raw appearance field.
    pub appearance: u32,
    /// Marking text.
    pub marking: String,
    /// Seconds since the last update.
    pub age_s: f64,
}

/// Local heading, pitch and roll (degrees) of a body-to-ECEF rotation at an ECEF position.
#[must_use]
pub fn local_heading_pitch_roll_deg(body_to_world: DMat3, position_ecef_m: DVec3) -> [f64; 3] {
    heading_pitch_roll_at(body_to_world, Geodetic::from_ecef(position_ecef_m))
}

fn heading_pitch_roll_at(body_to_world: DMat3, g: Geodetic) -> [f64; 3] {
    let (lat, lon) = (g.lat_deg.to_radians(), g.lon_deg.to_radians());
    let east = DVec3::new(-lon.sin(), lon.cos(), 0.0);
    let north = DVec3::new(-lat.sin() * lon.cos(), -lat.sin() * lon.sin(), lat.cos());
    let up = DVec3::new(lat.cos() * lon.cos(), lat.cos() * lon.sin(), lat.sin());
    let forward = body_to_world.x_axis;
    let right = body_to_world.y_axis;
    let down = body_to_world.z_axis;
    let heading = forward.dot(east).atan2(forward.dot(north)).to_degrees();
    let pitch = forward.dot(up).clamp(-1.0, 1.0).asin().to_degrees();
    let roll = (-right.dot(up)).atan2(-down.dot(up)).to_degrees();
    [heading.rem_euclid(360.0), pitch, roll]
}

/// The remote entity table.
#[derive(Clone, Debug)]
pub struct RemoteEntityTable {
    config: RemoteTableConfig,
    entities: BTreeMap<EntityKey, RemoteEntity>,
}

const APPEARANCE_DEACTIVATED: u32 = 1 << 23;

fn smoothstep(u: f64) -> f64 {
    let u = u.clamp(0.0, 1.0);
    u * u * (3.0 - 2.0 * u)
}

impl RemoteEntity {
    fn pose(&self, now_s: f64, smoothing_s: f64) -> DrPose {
        let new = self.current.pose(now_s);
        let Some(old_track) = &self.blend_from else {
            return new;
        };
        let u = if smoothing_s > 0.0 {
            (now_s - self.current.start_s) / smoothing_s
        } else {
            1.0
        };
        if u >= 1.0 {
            return new;
        }
        let s = smoothstep(u);
        let old = old_track.pose(now_s);
        let q_old = DQuat::from_mat3(&old.body_to_world).normalize();
        let q_new = DQuat::from_mat3(&new.body_to_world).normalize();
        DrPose {
            position_ecef_m: old.position_ecef_m.lerp(new.position_ecef_m, s),
            body_to_world: DMat3::from_quat(q_old.slerp(q_new, s).normalize()),
            velocity_ecef_mps: old.velocity_ecef_mps.lerp(new.velocity_ecef_mps, s),
        }
    }
}

impl RemoteEntityTable {
    /// An empty table.
    #[must_use]
    pub fn new(config: RemoteTableConfig) -> RemoteEntityTable {
        RemoteEntityTable {
            config,
            entities: BTreeMap::new(),
        }
    }

    /// The configuration.
    #[must_use]
    pub fn config(&self) -> &RemoteTableConfig {
        &self.config
    }

    /// Number of entities held.
    #[must_use]
    pub fn len(&self) -> usize {
        self.entities.len()
    }

    /// Whether the table is empty.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.entities.is_empty()
    }

    /// Whether a PDU with this header and originator passes the exercise, site and own filters.
    ///
    /// # Errors
    /// The [`Ignored`] reason.
    pub fn accepts(
        &self,
        header: &PduHeaderInfo,
        site: u16,
        application: u16,
    ) -> Result<(), Ignored> {
        if header.exercise_id != self.config.exercise_id {
            return Err(Ignored::Exercise);
        }
        if !self.config.accepted_sites.is_empty() && !self.config.accepted_sites.contains(&site) {
            return Err(Ignored::Site);
        }
        if self.config.own_address == Some((site, application)) {
            return Err(Ignored::Own);
        }
        Ok(())
    }

    /// Applies a decoded PDU received at `now_s` (local monotonic seconds).
    ///
    /// # Errors
    /// Why it was ignored; the table is unchanged then.
    pub fn apply(&mut self, now_s: f64, pdu: &DecodedPdu) -> Result<Vec<TableEvent>, Ignored> {
        match &pdu.message {
            DisMessage::EntityState(es) => self.apply_entity_state(now_s, &pdu.header, es),
            _ => Err(Ignored::NotEntityState),
        }
    }

    /// Applies an Entity State received at `now_s`.
    ///
    /// # Errors
    /// Why it was ignored; the table is unchanged then.
    pub fn apply_entity_state(
        &mut self,
        now_s: f64,
        header: &PduHeaderInfo,
        es: &EntityState,
    ) -> Result<Vec<TableEvent>, Ignored> {
        let id = &es.entity_id;
        let key = EntityKey {
            site: id.simulation_address.site_id,
            application: id.simulation_address.application_id,
            entity: id.entity_id,
        };
        self.accepts(header, key.site, key.application)?;
        let (algorithm, input) = dr_input_from_entity_state(es);
        if !finite_input(&input) || !now_s.is_finite() {
            return Err(Ignored::NotFinite);
        }
        let entity_type = EntityTypeCode::from_dis(&es.entity_type);
        let appearance = u32::from(&es.entity_appearance);
        let effects =
            EffectsRequested::from_appearance(appearance, entity_type.kind, entity_type.domain);
        let mut events = Vec::new();
        if appearance & APPEARANCE_DEACTIVATED != 0 {
            if let Some(old) = self.entities.remove(&key) {
                events.push(TableEvent::Removed {
                    key,
                    reason: RemovalReason::Deactivated,
                    diff: old.effects.diff(EffectsRequested::default()),
                });
            }
            return Ok(events);
        }
        let new_track = Track::new(algorithm, input, now_s);
        let smoothing_s = self.config.smoothing_s;
        let snap_distance_m = self.config.snap_distance_m;
        if let Some(entity) = self.entities.get_mut(&key) {
            let shown = entity.pose(now_s, smoothing_s);
            let jump_m = shown
                .position_ecef_m
                .distance(new_track.pose(now_s).position_ecef_m);
            entity.blend_from = if smoothing_s > 0.0 && jump_m <= snap_distance_m {
                let angular = if entity.current.model.algorithm.rotates() {
                    entity.current.model.input.angular_velocity_body_radps
                } else {
                    DVec3::ZERO
                };
                Some(Track::new(
                    DrAlgorithm::Rpw,
                    DrInput {
                        position_ecef_m: shown.position_ecef_m,
                        orientation: EulerAngles::from_body_to_world(shown.body_to_world),
                        velocity_ecef_mps: shown.velocity_ecef_mps,
                        acceleration_mps2: DVec3::ZERO,
                        angular_velocity_body_radps: angular,
                    },
                    now_s,
                ))
            } else {
                None
            };
            entity.current = new_track;
            entity.received_s = now_s;
            entity.entity_type = entity_type;
            entity.appearance = appearance;
            entity.marking.clone_from(&es.entity_marking.marking_string);
            let diff = entity.effects.diff(effects);
            entity.effects = effects;
            if !diff.is_empty() {
                events.push(TableEvent::EffectsChanged { key, diff });
            }
        } else {
            if self.entities.len() >= self.config.max_entities {
                return Err(Ignored::Full);
            }
            self.entities.insert(
                key,
                RemoteEntity {
                    entity_type,
                    current: new_track,
                    blend_from: None,
                    received_s: now_s,
                    effects,
                    appearance,
                    marking: es.entity_marking.marking_string.clone(),
                },
            );
            events.push(TableEvent::Appeared(key));
            let diff = EffectsRequested::default().diff(effects);
            if !diff.is_empty() {
                events.push(TableEvent::EffectsChanged { key, diff });
            }
        }
        Ok(events)
    }

    /// Drops entities not updated within the timeout; returns what left, in key order.
    pub fn expire(&mut self, now_s: f64) -> Vec<TableEvent> {
        let timeout_s = self.config.timeout_s;
        let stale: Vec<EntityKey> = self
            .entities
            .iter()
            .filter(|(_, e)| now_s - e.received_s > timeout_s)
            .map(|(k, _)| *k)
            .collect();
        stale
            .into_iter()
            .filter_map(|key| {
                self.entities.remove(&key).map(|old| TableEvent::Removed {
                    key,
                    reason: RemovalReason::Timeout,
                    diff: old.effects.diff(EffectsRequested::default()),
                })
            })
            .collect()
    }

    /// The pose of one entity at `now_s`.
    #[must_use]
    pub fn pose(&self, key: EntityKey, now_s: f64) -> Option<DrPose> {
        self.entities
            .get(&key)
            .map(|e| e.pose(now_s, self.config.smoothing_s))
    }

    /// Every entity's pose at `now_s` in key order, without the geodetic extras (the fast path
    /// for a renderer that works in ECEF).
    pub fn poses(&self, now_s: f64) -> impl Iterator<Item = (EntityKey, DrPose)> + '_ {
        self.entities
            .iter()
            .map(move |(k, e)| (*k, e.pose(now_s, self.config.smoothing_s)))
    }

    /// Forgets which effects each entity's appearance asked for (after the caller's effects
    /// were rebuilt): the next update of each entity reports its effects as starting again.
    pub fn forget_effects(&mut self) {
        for e in self.entities.values_mut() {
            e.effects = EffectsRequested::default();
        }
    }

    /// A plain snapshot of every entity at `now_s`, in key order.
    #[must_use]
    pub fn snapshot(&self, now_s: f64) -> Vec<RemoteEntitySnapshot> {
        self.snapshot_where(now_s, |_| true)
    }

    /// A plain snapshot at `now_s` of the entities whose dead-reckoned ECEF position `keep`
    /// accepts (e.g. those near an eyepoint), in key order; the geodetic conversion, the most
    /// expensive part, is done only for those.
    #[must_use]
    pub fn snapshot_where(
        &self,
        now_s: f64,
        keep: impl Fn(DVec3) -> bool,
    ) -> Vec<RemoteEntitySnapshot> {
        self.entities
            .iter()
            .filter_map(|(key, e)| {
                let pose = e.pose(now_s, self.config.smoothing_s);
                if !keep(pose.position_ecef_m) {
                    return None;
                }
                let geodetic = Geodetic::from_ecef(pose.position_ecef_m);
                Some(RemoteEntitySnapshot {
                    key: *key,
                    entity_type: e.entity_type,
                    position_ecef_m: pose.position_ecef_m,
                    geodetic,
                    orientation: EulerAngles::from_body_to_world(pose.body_to_world),
                    heading_pitch_roll_deg: heading_pitch_roll_at(pose.body_to_world, geodetic),
                    velocity_ecef_mps: pose.velocity_ecef_mps,
                    algorithm: e.current.model.algorithm,
                    effects: e.effects,
                    appearance: e.appearance,
                    marking: e.marking.clone(),
                    age_s: now_s - e.received_s,
                })
            })
            .collect()
    }
}
