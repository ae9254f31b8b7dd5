//! Entity State out: when to publish an owned entity, and the PDU body to publish.
//!
//! Algorithm (IEEE 1278.1-2012 §5.2.5 and Annex E.3, "dead reckoning thresholds"): the
//! publisher keeps the state it last sent and dead-reckons it exactly as every receiver does
//! ([`crate::dead_reckoning::extrapolate`] with the same algorithm). At each call with the
//! entity's true state it sends a new Entity State when
//! 1. nothing was sent yet;
//! 2. the true position is more than `position_threshold_m` (default 1 m) from the
//!    dead-reckoned one;
//! 3. the rotation between the true and the dead-reckoned orientation is more than
//!    `orientation_threshold_deg` (default 3°);
//! 4. the appearance bits changed; or
//! 5. `heartbeat_s` (default 5 s) passed since the last send.
//!
//! The PDU carries the chosen DR algorithm, the world velocity, the acceleration in the axes the
//! algorithm expects (world for DRM 2-5, body for DRM 6-9) and the body angular velocity.
//!
//! Limits: the thresholds are the standard's defaults and apply per entity; the caller supplies
//! monotonic seconds and builds the PDU header (exercise, timestamp) through
//! [`crate::codec::encode_pdu`].

use dis_rs::entity_state::model::{DrParameters, EntityAppearance, EntityMarking, EntityState};
use dis_rs::enumerations::{DeadReckoningAlgorithm, ForceId};
use dis_rs::model::{EntityId, Location, Orientation, VectorF32};
use dis_rs::BodyRaw;
use glam::DVec3;

use crate::dead_reckoning::{
    extrapolate, rotation_angle_between, DrAlgorithm, DrInput, EulerAngles,
};
use crate::remote::{EntityKey, EntityTypeCode};

/// Thresholds and heartbeat.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PublisherConfig {
    /// Position error that forces an update, metres.
    pub position_threshold_m: f64,
    /// Orientation error that forces an update, degrees.
    pub orientation_threshold_deg: f64,
    /// Longest time between updates, seconds.
    pub heartbeat_s: f64,
    /// DR algorithm announced in the PDUs.
    pub algorithm: DrAlgorithm,
}

impl Default for PublisherConfig {
    fn default() -> Self {
        PublisherConfig {
            position_threshold_m: 1.0,
            orientation_threshold_deg: 3.0,
            heartbeat_s: 5.0,
            algorithm: DrAlgorithm::Rvw,
        }
    }
}

/// The true state of an owned entity at one time.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct OwnedEntityState {
    /// Position, ECEF metres.
    pub position_ecef_m: DVec3,
    /// Orientation, DIS Euler angles.
    pub orientation: EulerAngles,
    /// Velocity, ECEF m/s.
    pub velocity_ecef_mps: DVec3,
    /// Acceleration, ECEF m/s² (converted to body axes for DRM 6-9).
    pub acceleration_ecef_mps2: DVec3,
    /// Angular velocity in body axes, rad/s.
    pub angular_velocity_body_radps: DVec3,
    /// Appearance bits.
    pub appearance: u32,
}

/// Why a PDU goes out.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SendReason {
    /// First publication.
    First,
    /// Position threshold exceeded.
    Position,
    /// Orientation threshold exceeded.
    Orientation,
    /// Appearance changed.
    Appearance,
    /// Heartbeat interval elapsed.
    Heartbeat,
}

/// Decides when an owned entity is published and builds its Entity State.
#[derive(Clone, Debug)]
pub struct OwnedEntityPublisher {
    key: EntityKey,
    entity_type: EntityTypeCode,
    force_id: u8,
    marking: String,
    config: PublisherConfig,
    last_sent: Option<(f64, DrInput, u32)>,
}

impl OwnedEntityPublisher {
    /// A publisher for one entity. `marking` is cut to 11 characters.
    #[must_use]
    pub fn new(
        key: EntityKey,
        entity_type: EntityTypeCode,
        force_id: u8,
        marking: &str,
        config: PublisherConfig,
    ) -> OwnedEntityPublisher {
        OwnedEntityPublisher {
            key,
            entity_type,
            force_id,
            marking: marking.chars().filter(char::is_ascii).take(11).collect(),
            config,
            last_sent: None,
        }
    }

    /// The configuration.
    #[must_use]
    pub fn config(&self) -> &PublisherConfig {
        &self.config
    }

    fn dr_input(&self, truth: &OwnedEntityState) -> DrInput {
        let acceleration = if self.config.algorithm.body_axes() {
            truth.orientation.body_to_world().transpose() * truth.acceleration_ecef_mps2
        } else {
            truth.acceleration_ecef_mps2
        };
        DrInput {
            position_ecef_m: truth.position_ecef_m,
            orientation: truth.orientation,
            velocity_ecef_mps: truth.velocity_ecef_mps,
            acceleration_mps2: acceleration,
            angular_velocity_body_radps: truth.angular_velocity_body_radps,
        }
    }

    /// Whether a PDU is due at `now_s` for the true state, without changing anything.
    #[must_use]
    pub fn due(&self, now_s: f64, truth: &OwnedEntityState) -> Option<SendReason> {
        let Some((sent_s, input, appearance)) = &self.last_sent else {
            return Some(SendReason::First);
        };
        let predicted = extrapolate(self.config.algorithm, input, now_s - sent_s);
        if predicted.position_ecef_m.distance(truth.position_ecef_m)
            > self.config.position_threshold_m
        {
            return Some(SendReason::Position);
        }
        let angle =
            rotation_angle_between(predicted.body_to_world, truth.orientation.body_to_world());
        if angle.to_degrees() > self.config.orientation_threshold_deg {
            return Some(SendReason::Orientation);
        }
        if *appearance != truth.appearance {
            return Some(SendReason::Appearance);
        }
        if now_s - sent_s >= self.config.heartbeat_s {
            return Some(SendReason::Heartbeat);
        }
        None
    }

    /// Checks the thresholds at `now_s`; when a PDU is due, records it as sent and returns the
    /// reason and the Entity State body.
    pub fn update(
        &mut self,
        now_s: f64,
        truth: &OwnedEntityState,
    ) -> Option<(SendReason, EntityState)> {
        let reason = self.due(now_s, truth)?;
        let body = self.build_entity_state(truth);
        self.last_sent = Some((now_s, self.dr_input(truth), truth.appearance));
        Some((reason, body))
    }

    /// The Entity State body for a true state (what [`OwnedEntityPublisher::update`] sends).
    #[must_use]
    pub fn build_entity_state(&self, truth: &OwnedEntityState) -> EntityState {
        let input = self.dr_input(truth);
        let f = |v: DVec3| {
            #[expect(
                clippy::cast_possible_truncation,
                reason = "the wire format carries single precision"
            )]
            VectorF32::new(v.x as f32, v.y as f32, v.z as f32)
        };
        #[expect(
            clippy::cast_possible_truncation,
            reason = "the wire format carries single precision"
        )]
        let orientation = Orientation::new(
            truth.orientation.psi_rad as f32,
            truth.orientation.theta_rad as f32,
            truth.orientation.phi_rad as f32,
        );
        let entity_type = self.entity_type.to_dis();
        EntityState::builder()
            .with_entity_id(EntityId::new(
                self.key.site,
                self.key.application,
                self.key.entity,
            ))
            .with_force_id(ForceId::from(self.force_id))
            .with_entity_type(entity_type)
            .with_alternative_entity_type(entity_type)
            .with_velocity(f(truth.velocity_ecef_mps))
            .with_location(Location::new(
                truth.position_ecef_m.x,
                truth.position_ecef_m.y,
                truth.position_ecef_m.z,
            ))
            .with_orientation(orientation)
            .with_appearance(EntityAppearance::from_bytes(truth.appearance, &entity_type))
            .with_dead_reckoning_parameters(
                DrParameters::default()
                    .with_algorithm(DeadReckoningAlgorithm::from(self.config.algorithm.code()))
                    .with_linear_acceleration(f(input.acceleration_mps2))
                    .with_angular_velocity(f(input.angular_velocity_body_radps)),
            )
            .with_marking(EntityMarking::new_ascii(self.marking.clone()))
            .build()
    }
}
