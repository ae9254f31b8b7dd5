//! Shared simulation world time ("Time Control Monitor") and lightning announcements.
//!
//! Algorithm, after the thesis (000, §VI.E.4): one node, the time master (the thesis's TCM),
//! defines the simulation world time (SWT) for all. Here it is built on standard Data Query /
//! Data / Set Data PDUs (IEEE 1278.1-2012 §7.5.9-7.5.11) with SISO-REF-010 datum IDs:
//!
//! * The time is variable datum **52000 "Time"** holding 8 octets: the SWT as a signed 64-bit
//!   count of milliseconds since 1970-01-01T00:00:00 UTC, big-endian.
//! * The rate is fixed datum **52370 "Time Rate"**: an IEEE 754 single (its bits in the 32-bit
//!   datum value), simulated seconds per real second (1.0 real time, 0.0 frozen).
//! * A newcomer sends a Data Query to all asking for variable datum 52000 and waits
//!   `join_wait_s`. A master answers with a Data PDU (same request ID) carrying both datums,
//!   and also broadcasts that Data PDU (request ID 0) every `heartbeat_s` as its heartbeat.
//!   The newcomer adopts the announced time and follows; if nobody answers it becomes master
//!   with its own starting time — the thesis's "claim and wait" joining.
//! * Followers that hear no heartbeat for `master_timeout_s` (default 12 s, 2.4 heartbeats)
//!   claim mastership with the time they have been extrapolating, so the world time continues
//!   without a jump.
//! * Election is deterministic: the master is the node with the lowest (site, application)
//!   among those alive. Whenever two masters hear each other, the higher one yields and adopts
//!   the lower one's time; followers follow the lowest master they hear; a follower that ranks
//!   before its master (a newcomer, or the survivors after a master left) claims mastership
//!   right after adopting the master's time, so the time itself never jumps — only the role
//!   moves. This also settles the thesis's "several nodes join at nearly the same time" case
//!   instead of leaving the exercise with several masters or none.
//! * A Set Data PDU carrying datum 52000 (e.g. from an instructor station) sets the time on
//!   every node; the master re-announces it at once.
//!
//! Lightning (thesis §VI.E.5: only "a message to the other nodes that lightning is occurring"
//! is needed, each node draws its own flash): a Data PDU to all, request ID 0, with variable
//! datum **51010 "Weather Condition"** whose 44-octet value is: ASCII tag `LGHT`, strike point
//! (3 × f64 ECEF metres), a u64 seed for the bolt shape, an f32 relative intensity and 4 zero
//! octets, all big-endian. Receivers that do not know the tag ignore the datum.
//!
//! Limits: no clock-offset estimation (the network latency of one answer, a few ms, is left in;
//! the thesis accepts differences under a minute); the tag layout is this project's convention
//! on a standard datum, not a SISO record; times are milliseconds.

use dis_rs::data::model::Data;
use dis_rs::data_query::model::DataQuery;
use dis_rs::enumerations::VariableRecordType;
use dis_rs::model::{EntityId, FixedDatum, VariableDatum};
use dis_rs::set_data::model::SetData;
use dis_rs::BodyRaw;
use glam::DVec3;

use crate::codec::DisMessage;

/// Variable datum ID 52000 "Time" (SISO-REF-010 UID 66).
pub const DATUM_TIME: u32 = 52_000;
/// Fixed datum ID 52370 "Time Rate" (SISO-REF-010 UID 66).
pub const DATUM_TIME_RATE: u32 = 52_370;
/// Variable datum ID 51010 "Weather Condition" (SISO-REF-010 UID 66), used for lightning.
pub const DATUM_WEATHER_CONDITION: u32 = 51_010;
/// Tag opening a lightning datum value.
pub const LIGHTNING_TAG: [u8; 4] = *b"LGHT";
/// Site/application/entity value meaning "all" (IEEE 1278.1-2012 §6.1.6).
pub const ALL: u16 = 0xFFFF;

/// A simulation node: (site, application). Ordered by site, then application.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct NodeId {
    /// Site number.
    pub site: u16,
    /// Application number.
    pub application: u16,
}

impl NodeId {
    fn entity_id(self) -> EntityId {
        EntityId::new(self.site, self.application, 0)
    }

    fn from_entity_id(id: &EntityId) -> NodeId {
        NodeId {
            site: id.simulation_address.site_id,
            application: id.simulation_address.application_id,
        }
    }
}

/// A time-sharing message, independent of the PDU that carries it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum TimeMessage {
    /// "What is the time?" (Data Query for datum 52000).
    Query {
        /// Asking node.
        from: NodeId,
        /// Request ID the answer repeats.
        request_id: u32,
    },
    /// "The time is …" (Data with datums 52000 and 52370): a heartbeat (request ID 0, to all) or
    /// an answer.
    Announce {
        /// Announcing node (a master).
        from: NodeId,
        /// Addressee; `None` for all.
        to: Option<NodeId>,
        /// Request ID answered, 0 for a heartbeat.
        request_id: u32,
        /// Simulation world time, ms since the Unix epoch (UTC).
        world_time_ms: i64,
        /// Simulated seconds per real second.
        rate: f32,
    },
    /// "Set the time to …" (Set Data with datums 52000 and 52370).
    Set {
        /// Sending node.
        from: NodeId,
        /// Simulation world time, ms since the Unix epoch (UTC).
        world_time_ms: i64,
        /// Simulated seconds per real second.
        rate: f32,
    },
}

fn all_id() -> EntityId {
    EntityId::new(ALL, ALL, ALL)
}

fn time_datum(world_time_ms: i64) -> VariableDatum {
    VariableDatum::new(
        VariableRecordType::from(DATUM_TIME),
        world_time_ms.to_be_bytes().to_vec(),
    )
}

fn rate_datum(rate: f32) -> FixedDatum {
    FixedDatum::new(VariableRecordType::from(DATUM_TIME_RATE), rate.to_bits())
}

fn read_time(fixed: &[FixedDatum], variable: &[VariableDatum]) -> Option<(i64, f32)> {
    let time = variable.iter().find_map(|d| {
        if u32::from(d.datum_id) != DATUM_TIME {
            return None;
        }
        let bytes: [u8; 8] = d.datum_value.get(..8)?.try_into().ok()?;
        Some(i64::from_be_bytes(bytes))
    })?;
    let rate = fixed
        .iter()
        .find(|d| u32::from(d.datum_id) == DATUM_TIME_RATE)
        .map_or(1.0, |d| f32::from_bits(d.datum_value));
    let rate = if rate.is_finite() && rate >= 0.0 {
        rate
    } else {
        1.0
    };
    Some((time, rate))
}

impl TimeMessage {
    /// The PDU body that carries this message.
    #[must_use]
    pub fn to_message(&self) -> DisMessage {
        match *self {
            TimeMessage::Query { from, request_id } => DisMessage::DataQuery(
                DataQuery::builder()
                    .with_origination_id(from.entity_id())
                    .with_receiving_id(all_id())
                    .with_request_id(request_id)
                    .with_time_interval(0)
                    .with_fixed_datums(vec![])
                    .with_variable_datums(vec![VariableRecordType::from(DATUM_TIME)])
                    .build(),
            ),
            TimeMessage::Announce {
                from,
                to,
                request_id,
                world_time_ms,
                rate,
            } => DisMessage::Data(
                Data::builder()
                    .with_origination_id(from.entity_id())
                    .with_receiving_id(to.map_or_else(all_id, NodeId::entity_id))
                    .with_request_id(request_id)
                    .with_fixed_datums(vec![rate_datum(rate)])
                    .with_variable_datums(vec![time_datum(world_time_ms)])
                    .build(),
            ),
            TimeMessage::Set {
                from,
                world_time_ms,
                rate,
            } => DisMessage::SetData(
                SetData::builder()
                    .with_origination_id(from.entity_id())
                    .with_receiving_id(all_id())
                    .with_request_id(0)
                    .with_fixed_datums(vec![rate_datum(rate)])
                    .with_variable_datums(vec![time_datum(world_time_ms)])
                    .build(),
            ),
        }
    }

    /// The time message a PDU body carries, if any.
    #[must_use]
    pub fn from_message(message: &DisMessage) -> Option<TimeMessage> {
        match message {
            DisMessage::DataQuery(q) => q
                .variable_datum_records
                .iter()
                .any(|d| u32::from(*d) == DATUM_TIME)
                .then(|| TimeMessage::Query {
                    from: NodeId::from_entity_id(&q.originating_id),
                    request_id: q.request_id,
                }),
            DisMessage::Data(d) => {
                let (world_time_ms, rate) =
                    read_time(&d.fixed_datum_records, &d.variable_datum_records)?;
                let to = NodeId::from_entity_id(&d.receiving_id);
                Some(TimeMessage::Announce {
                    from: NodeId::from_entity_id(&d.originating_id),
                    to: (to.site != ALL || to.application != ALL).then_some(to),
                    request_id: d.request_id,
                    world_time_ms,
                    rate,
                })
            }
            DisMessage::SetData(d) => {
                let (world_time_ms, rate) =
                    read_time(&d.fixed_datum_records, &d.variable_datum_records)?;
                Some(TimeMessage::Set {
                    from: NodeId::from_entity_id(&d.originating_id),
                    world_time_ms,
                    rate,
                })
            }
            _ => None,
        }
    }
}

/// Timing of the time-sharing protocol.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TimeSyncConfig {
    /// Seconds between master heartbeats.
    pub heartbeat_s: f64,
    /// Seconds without a heartbeat after which the master counts as gone.
    pub master_timeout_s: f64,
    /// Seconds a newcomer waits for an answer before it becomes master.
    pub join_wait_s: f64,
}

impl Default for TimeSyncConfig {
    fn default() -> Self {
        TimeSyncConfig {
            heartbeat_s: 5.0,
            master_timeout_s: 12.0,
            join_wait_s: 2.0,
        }
    }
}

/// A node's role.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TimeRole {
    /// Asked for the time and is waiting for an answer.
    Joining,
    /// Defines the time.
    Master,
    /// Follows a master.
    Follower {
        /// The master.
        master: NodeId,
    },
}

/// The time-sharing state machine of one node. Times `now_s` are local monotonic seconds.
#[derive(Clone, Debug)]
pub struct TimeSync {
    me: NodeId,
    config: TimeSyncConfig,
    role: TimeRole,
    base_local_s: f64,
    base_world_ms: f64,
    rate: f32,
    joined_s: f64,
    last_master_heard_s: f64,
    last_heartbeat_s: Option<f64>,
}

impl TimeSync {
    /// A node joining at `now_s` with its own starting time; returns it and the Query to send.
    #[must_use]
    pub fn join(
        me: NodeId,
        config: TimeSyncConfig,
        now_s: f64,
        start_world_time_ms: i64,
        rate: f32,
    ) -> (TimeSync, Vec<TimeMessage>) {
        #[expect(
            clippy::cast_precision_loss,
            reason = "ms since 1970 fit f64 exactly until year 287,396"
        )]
        let base_world_ms = start_world_time_ms as f64;
        let node = TimeSync {
            me,
            config,
            role: TimeRole::Joining,
            base_local_s: now_s,
            base_world_ms,
            rate,
            joined_s: now_s,
            last_master_heard_s: now_s,
            last_heartbeat_s: None,
        };
        (
            node,
            vec![TimeMessage::Query {
                from: me,
                request_id: 1,
            }],
        )
    }

    /// This node.
    #[must_use]
    pub fn node(&self) -> NodeId {
        self.me
    }

    /// Current role.
    #[must_use]
    pub fn role(&self) -> TimeRole {
        self.role
    }

    /// Current rate.
    #[must_use]
    pub fn rate(&self) -> f32 {
        self.rate
    }

    /// Simulation world time at `now_s`, ms since the Unix epoch (UTC).
    #[must_use]
    pub fn world_time_ms(&self, now_s: f64) -> i64 {
        let ms = self.base_world_ms + (now_s - self.base_local_s) * 1000.0 * f64::from(self.rate);
        #[expect(
            clippy::cast_possible_truncation,
            reason = "rounded ms; saturates on overflow"
        )]
        let out = ms.round() as i64;
        out
    }

    fn adopt(&mut self, now_s: f64, world_time_ms: i64, rate: f32) {
        #[expect(clippy::cast_precision_loss, reason = "ms since 1970 fit f64 exactly")]
        let base = world_time_ms as f64;
        self.base_local_s = now_s;
        self.base_world_ms = base;
        self.rate = rate;
    }

    fn announce(&mut self, now_s: f64, to: Option<NodeId>, request_id: u32) -> TimeMessage {
        if to.is_none() {
            self.last_heartbeat_s = Some(now_s);
        }
        TimeMessage::Announce {
            from: self.me,
            to,
            request_id,
            world_time_ms: self.world_time_ms(now_s),
            rate: self.rate,
        }
    }

    fn become_master(&mut self, now_s: f64) -> Vec<TimeMessage> {
        self.role = TimeRole::Master;
        vec![self.announce(now_s, None, 0)]
    }

    /// Advances time to `now_s`: join timeout, master timeout, heartbeats. Returns what to send.
    pub fn tick(&mut self, now_s: f64) -> Vec<TimeMessage> {
        match self.role {
            TimeRole::Joining if now_s - self.joined_s >= self.config.join_wait_s => {
                self.become_master(now_s)
            }
            TimeRole::Follower { master }
                if self.me < master
                    || now_s - self.last_master_heard_s > self.config.master_timeout_s =>
            {
                // Either the master is gone, or this node ranks before it: claim, carrying on
                // the time adopted from it.
                self.become_master(now_s)
            }
            TimeRole::Master => {
                let due = self
                    .last_heartbeat_s
                    .is_none_or(|t| now_s - t >= self.config.heartbeat_s);
                if due {
                    vec![self.announce(now_s, None, 0)]
                } else {
                    vec![]
                }
            }
            _ => vec![],
        }
    }

    /// Handles a received message at `now_s` (own messages are ignored). Returns what to send.
    pub fn receive(&mut self, now_s: f64, message: &TimeMessage) -> Vec<TimeMessage> {
        match *message {
            TimeMessage::Query { from, request_id } => {
                if from == self.me || self.role != TimeRole::Master {
                    return vec![];
                }
                vec![self.announce(now_s, Some(from), request_id)]
            }
            TimeMessage::Announce {
                from,
                to,
                world_time_ms,
                rate,
                ..
            } => {
                if from == self.me
                    || to.is_some_and(|t| t != self.me) && self.role != TimeRole::Joining
                {
                    return vec![];
                }
                let follow = match self.role {
                    TimeRole::Joining => true,
                    TimeRole::Master => from < self.me,
                    TimeRole::Follower { master } => {
                        from <= master
                            || now_s - self.last_master_heard_s > self.config.master_timeout_s
                    }
                };
                if follow {
                    self.adopt(now_s, world_time_ms, rate);
                    self.role = TimeRole::Follower { master: from };
                    self.last_master_heard_s = now_s;
                    vec![]
                } else if self.role == TimeRole::Master {
                    // A higher master: announce at once so it yields.
                    vec![self.announce(now_s, None, 0)]
                } else {
                    vec![]
                }
            }
            TimeMessage::Set {
                from,
                world_time_ms,
                rate,
            } => {
                if from == self.me {
                    return vec![];
                }
                self.adopt(now_s, world_time_ms, rate);
                if self.role == TimeRole::Master {
                    vec![self.announce(now_s, None, 0)]
                } else {
                    vec![]
                }
            }
        }
    }

    /// A Set message to send when this node's operator sets the time; this node adopts it too.
    pub fn set_time(&mut self, now_s: f64, world_time_ms: i64, rate: f32) -> TimeMessage {
        self.adopt(now_s, world_time_ms, rate);
        TimeMessage::Set {
            from: self.me,
            world_time_ms,
            rate,
        }
    }
}

/// A lightning strike announcement.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightningStrike {
    /// Announcing node.
    pub from: NodeId,
    /// Strike point (root of the bolt at the ground), ECEF metres.
    pub position_ecef_m: DVec3,
    /// Seed for the bolt's shape, so every node draws the same bolt.
    pub seed: u64,
    /// Relative intensity, 0..1.
    pub intensity: f32,
}

impl LightningStrike {
    /// The Data PDU body that announces it.
    #[must_use]
    pub fn to_message(&self) -> DisMessage {
        let mut value = Vec::with_capacity(44);
        value.extend_from_slice(&LIGHTNING_TAG);
        for c in self.position_ecef_m.to_array() {
            value.extend_from_slice(&c.to_be_bytes());
        }
        value.extend_from_slice(&self.seed.to_be_bytes());
        value.extend_from_slice(&self.intensity.to_be_bytes());
        value.extend_from_slice(&[0; 4]);
        DisMessage::Data(
            Data::builder()
                .with_origination_id(self.from.entity_id())
                .with_receiving_id(all_id())
                .with_request_id(0)
                .with_fixed_datums(vec![])
                .with_variable_datums(vec![VariableDatum::new(
                    VariableRecordType::from(DATUM_WEATHER_CONDITION),
                    value,
                )])
                .build(),
        )
    }

    /// The strike a PDU body announces, if any.
    #[must_use]
    pub fn from_message(message: &DisMessage) -> Option<LightningStrike> {
        let DisMessage::Data(d) = message else {
            return None;
        };
        d.variable_datum_records.iter().find_map(|datum| {
            if u32::from(datum.datum_id) != DATUM_WEATHER_CONDITION {
                return None;
            }
            let v = &datum.datum_value;
            if v.get(..4)? != LIGHTNING_TAG {
                return None;
            }
            let f64_at = |i: usize| -> Option<f64> {
                Some(f64::from_be_bytes(v.get(i..i + 8)?.try_into().ok()?))
            };
            let position = DVec3::new(f64_at(4)?, f64_at(12)?, f64_at(20)?);
            let seed = u64::from_be_bytes(v.get(28..36)?.try_into().ok()?);
            let intensity = f32::from_be_bytes(v.get(36..40)?.try_into().ok()?);
            (position.is_finite() && intensity.is_finite()).then_some(LightningStrike {
                from: NodeId::from_entity_id(&d.originating_id),
                position_ecef_m: position,
                seed,
                intensity,
            })
        })
    }
}
