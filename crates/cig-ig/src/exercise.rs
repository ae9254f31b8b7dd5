//! The IG in a DIS exercise: remote entities in, owned entities out, detonations and entity
//! appearances turned into smoke, flame and dust, and the shared world time.
//!
//! Algorithm (thesis 000 §VI.E, IEEE 1278.1-2012): each received datagram is walked PDU by PDU
//! (`cig_dis::decode_datagram`); Entity State PDUs of this exercise and accepted sites update
//! the remote entity table, which dead-reckons and smooths them and drops them after 12 s of
//! silence; their appearance bits start and stop smoke plumes, flames and dust trails on them
//! (§VI.E.2-3). Detonation PDUs with a ground or building result start smoke and flame at the
//! impact point, seeded from the event identity, so every IG draws the same plume (§VI.E.2).
//! Owned entities are published with the 1 m / 3° thresholds and a 5 s heartbeat. The
//! simulation world time is shared over Data Query / Data / Set Data with datums 52000 and
//! 52370 (§VI.E.4): a joining node asks, adopts the master's time, and takes over when the
//! master falls silent.
//!
//! Effects run on "effect time": seconds of world time since 2020-01-01T00:00:00Z, the same on
//! every node that shares the world time.
//!
//! Limits: entity types map to models by the scenario's table; Environmental Process PDUs are
//! decoded and counted (their Gaussian plume and puff records are not yet drawn by the
//! renderer); articulated parts of remote entities are not read.

use crate::model_table::ModelTable;
use crate::scenario::{parse_dis_id, parse_hex_u32, DisSettings, DisTypePattern, Scenario};
use cig_dis::{
    decode_datagram, encode_pdu, impact_effect, DisMessage, DisVersion, EncodeHeader, EntityEffect,
    EntityKey, EntityTypeCode, ImpactSize, ImpactSurface, NodeId, OwnedEntityPublisher,
    OwnedEntityState, PublisherConfig, RemoteEntitySnapshot, RemoteEntityTable, RemoteTableConfig,
    TableEvent, TimeMessage, TimeSync, TimeSyncConfig,
};
use cig_effects::{
    DustTrailSpec, EffectHandle, EffectId, EffectSystem, PlumeKind, PlumeSource, PlumeSpec,
    VehicleUpdate,
};
use cig_geo::{EnuFrame, Geodetic};
use cig_terrain::{Material, QuerySession};
use glam::DVec3;
use std::collections::BTreeMap;

/// Effect time is world time minus this (2020-01-01T00:00:00Z), seconds.
pub const EFFECT_EPOCH_UNIX_S: f64 = 1_577_836_800.0;

/// Counters of the exercise's traffic.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ExerciseCounters {
    pub datagrams: u64,
    pub pdus: u64,
    pub bad_pdus: u64,
    pub entity_states_applied: u64,
    pub ignored: u64,
    pub detonations: u64,
    pub impacts_started: u64,
    pub environmental_processes: u64,
    pub pdus_sent: u64,
}

/// An owned entity's publisher and identity.
struct Owned {
    publisher: OwnedEntityPublisher,
    appearance: u32,
}

/// The effects running on a remote entity.
#[derive(Default)]
struct EntityEffects {
    handles: BTreeMap<EntityEffect, EffectHandle>,
}

/// The IG's part in one DIS exercise.
pub struct Exercise {
    settings: DisSettings,
    version: DisVersion,
    remote: RemoteEntityTable,
    owned: BTreeMap<u16, Owned>,
    time: TimeSync,
    remote_effects: BTreeMap<EntityKey, EntityEffects>,
    outgoing: Vec<Vec<u8>>,
    counters: ExerciseCounters,
}

/// What the owned entity is doing now, for publishing.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OwnedTruth {
    pub position: Geodetic,
    pub orientation: cig_scene::Hpr,
    pub velocity_enu_mps: DVec3,
}

/// DIS Euler angles (ψ, θ, φ about ECEF axes) of a local heading, pitch and roll.
fn dis_orientation(position: Geodetic, hpr: cig_scene::Hpr) -> cig_dis::EulerAngles {
    let frame = EnuFrame::new(position);
    let (forward, right, up) = hpr.axes_enu();
    let f = frame.enu_vector_to_ecef(forward);
    let r = frame.enu_vector_to_ecef(right);
    let d = frame.enu_vector_to_ecef(-up);
    cig_dis::EulerAngles::from_body_to_world(glam::DMat3::from_cols(f, r, d))
}

impl Exercise {
    /// Joins the exercise at local monotonic time `now_s`, with `world_time_unix_s` as this
    /// node's own idea of the time (used if no master answers, or at once for a time master).
    pub fn join(
        settings: &DisSettings,
        scenario: &Scenario,
        now_s: f64,
        world_time_unix_s: f64,
        rate: f64,
    ) -> Exercise {
        let version = if settings.version == 6 {
            DisVersion::V6
        } else {
            DisVersion::V7
        };
        let remote = RemoteEntityTable::new(RemoteTableConfig {
            exercise_id: settings.exercise,
            accepted_sites: settings.accepted_sites.iter().copied().collect(),
            own_address: Some((settings.site, settings.application)),
            ..RemoteTableConfig::default()
        });
        let mut owned = BTreeMap::new();
        for e in &scenario.entities {
            let (Some(id), Some(t)) = (
                e.dis_id.as_deref().and_then(parse_dis_id),
                e.dis_type
                    .as_deref()
                    .and_then(DisTypePattern::parse)
                    .and_then(|p| p.exact()),
            ) else {
                continue;
            };
            let key = EntityKey {
                site: id.0,
                application: id.1,
                entity: id.2,
            };
            owned.insert(
                e.id,
                Owned {
                    publisher: OwnedEntityPublisher::new(
                        key,
                        t,
                        1,
                        &format!("CIG{}", e.id),
                        PublisherConfig::default(),
                    ),
                    appearance: e.appearance.as_deref().and_then(parse_hex_u32).unwrap_or(0),
                },
            );
        }
        let me = NodeId {
            site: settings.site,
            application: settings.application,
        };
        #[expect(
            clippy::cast_possible_truncation,
            reason = "ms since 1970 fit i64; the rate is a small factor"
        )]
        let (start_ms, rate32) = ((world_time_unix_s * 1000.0).round() as i64, rate as f32);
        let (mut time, first) =
            TimeSync::join(me, TimeSyncConfig::default(), now_s, start_ms, rate32);
        let mut exercise = Exercise {
            settings: settings.clone(),
            version,
            remote,
            owned,
            time: time.clone(),
            remote_effects: BTreeMap::new(),
            outgoing: Vec::new(),
            counters: ExerciseCounters::default(),
        };
        if settings.time_master {
            // A master announces its own time at once rather than asking.
            let set = time.set_time(now_s, start_ms, rate32);
            exercise.time = time;
            exercise.queue_time(now_s, &[set]);
        } else {
            exercise.time = time;
            exercise.queue_time(now_s, &first);
        }
        exercise
    }

    fn header(&self, now_s: f64) -> EncodeHeader {
        EncodeHeader {
            version: self.version,
            exercise_id: self.settings.exercise,
            timestamp: cig_dis::codec::timestamp_from_seconds_past_hour(
                now_s.rem_euclid(3600.0),
                false,
            ),
        }
    }

    fn queue(&mut self, now_s: f64, message: &DisMessage) {
        match encode_pdu(self.header(now_s), message) {
            Ok(bytes) => {
                self.outgoing.push(bytes);
                self.counters.pdus_sent += 1;
            }
            Err(e) => tracing::warn!("DIS: a PDU of this IG cannot be encoded: {e}"),
        }
    }

    fn queue_time(&mut self, now_s: f64, messages: &[TimeMessage]) {
        for m in messages {
            self.queue(now_s, &m.to_message());
        }
    }

    pub fn counters(&self) -> ExerciseCounters {
        self.counters
    }
    pub fn settings(&self) -> &DisSettings {
        &self.settings
    }
    pub fn remote_len(&self) -> usize {
        self.remote.len()
    }
    pub fn time_role(&self) -> cig_dis::TimeRole {
        self.time.role()
    }

    /// The shared world time at `now_s`, seconds since 1970 UTC.
    pub fn world_time_unix_s(&self, now_s: f64) -> f64 {
        self.time.world_time_ms(now_s) as f64 / 1000.0
    }

    /// The shared clock rate.
    pub fn rate(&self) -> f64 {
        f64::from(self.time.rate())
    }

    /// Sets the exercise's world time (this node becomes its master).
    pub fn set_time(&mut self, now_s: f64, world_time_unix_s: f64, rate: f64) {
        #[expect(clippy::cast_possible_truncation, reason = "ms since 1970 fit i64")]
        let ms = (world_time_unix_s * 1000.0).round() as i64;
        #[expect(clippy::cast_possible_truncation, reason = "a small factor")]
        let set = self.time.set_time(now_s, ms, rate as f32);
        self.queue_time(now_s, &[set]);
    }

    /// Handles one received datagram at `now_s`.
    pub fn receive(
        &mut self,
        now_s: f64,
        datagram: &[u8],
        effects: &mut EffectSystem,
        query: &mut QuerySession,
    ) {
        self.counters.datagrams += 1;
        for result in decode_datagram(datagram) {
            self.counters.pdus += 1;
            let pdu = match result {
                Ok(pdu) => pdu,
                Err(_) => {
                    self.counters.bad_pdus += 1;
                    continue;
                }
            };
            if pdu.header.exercise_id != self.settings.exercise {
                self.counters.ignored += 1;
                continue;
            }
            match &pdu.message {
                DisMessage::EntityState(_) => match self.remote.apply(now_s, &pdu) {
                    Ok(events) => {
                        self.counters.entity_states_applied += 1;
                        self.handle_events(now_s, events, effects, query);
                    }
                    Err(_) => self.counters.ignored += 1,
                },
                DisMessage::Detonation(d) => {
                    self.counters.detonations += 1;
                    if let Some(start) = impact_effect(d) {
                        if self.start_impact(now_s, &start, effects) {
                            self.counters.impacts_started += 1;
                        }
                    }
                }
                DisMessage::EnvironmentalProcess(_) => self.counters.environmental_processes += 1,
                other => {
                    if let Some(t) = TimeMessage::from_message(other) {
                        let replies = self.time.receive(now_s, &t);
                        self.queue_time(now_s, &replies);
                    } else {
                        self.counters.ignored += 1;
                    }
                }
            }
        }
    }

    fn effect_time_s(&self, now_s: f64) -> f64 {
        self.world_time_unix_s(now_s) - EFFECT_EPOCH_UNIX_S
    }

    fn start_impact(
        &mut self,
        now_s: f64,
        start: &cig_dis::ImpactEffectStart,
        effects: &mut EffectSystem,
    ) -> bool {
        let position = Geodetic::from_ecef(start.position_ecef_m);
        let (size_m, heat_w, duration_s) = match start.size {
            ImpactSize::Small => (2.0, 2.0e6, 60.0),
            ImpactSize::Medium => (4.0, 8.0e6, 120.0),
            ImpactSize::Large => (8.0, 3.0e7, 300.0),
        };
        let factor = match start.surface {
            ImpactSurface::Ground => 1.0,
            ImpactSurface::Building => 1.5,
        };
        let t = self.effect_time_s(now_s);
        let mut ok = true;
        for (kind, salt, d) in [
            (PlumeKind::Smoke, 0u64, duration_s * factor),
            (PlumeKind::Flame, 1u64, duration_s * factor / 4.0),
        ] {
            let spec = PlumeSpec {
                id: EffectId(start.effect_seed ^ salt),
                kind,
                position,
                size_m: size_m * factor,
                source: PlumeSource::HeatReleaseW(heat_w * factor),
                start_time_s: t,
                duration_s: d,
            };
            ok &= effects.start_plume(&spec).is_ok();
        }
        ok
    }

    fn handle_events(
        &mut self,
        now_s: f64,
        events: Vec<TableEvent>,
        effects: &mut EffectSystem,
        query: &mut QuerySession,
    ) {
        for event in events {
            let (key, diff) = match event {
                TableEvent::Appeared(_) => continue,
                TableEvent::EffectsChanged { key, diff } => (key, diff),
                TableEvent::Removed { key, diff, .. } => (key, diff),
            };
            let t = self.effect_time_s(now_s);
            let snapshot = self.remote.pose(key, now_s);
            let slot = self.remote_effects.entry(key).or_default();
            for effect in diff.stop {
                if let Some(h) = slot.handles.remove(&effect) {
                    let _ = effects.stop(h, t);
                }
            }
            let Some(pose) = snapshot else { continue };
            let position = Geodetic::from_ecef(pose.position_ecef_m);
            let seed = (u64::from(key.site) << 32)
                | (u64::from(key.application) << 16)
                | u64::from(key.entity);
            for effect in diff.start {
                let handle = match effect {
                    EntityEffect::SmokePlume | EntityEffect::EngineSmoke | EntityEffect::Flames => {
                        let (kind, heat_w, salt) = match effect {
                            EntityEffect::Flames => (PlumeKind::Flame, 5.0e6, 3),
                            EntityEffect::EngineSmoke => (PlumeKind::Smoke, 2.0e5, 2),
                            _ => (PlumeKind::Smoke, 5.0e6, 1),
                        };
                        effects
                            .start_plume(&PlumeSpec {
                                id: EffectId(cig_dis::detonation::splitmix64(seed ^ salt)),
                                kind,
                                position,
                                size_m: 3.0,
                                source: PlumeSource::HeatReleaseW(heat_w),
                                start_time_s: t,
                                duration_s: 3600.0,
                            })
                            .ok()
                    }
                    EntityEffect::DustCloud(size) => {
                        let material = query
                            .hot(position.lat_deg, position.lon_deg)
                            .map_or(Material::DryClay, |s| s.material);
                        let velocity =
                            EnuFrame::new(position).ecef_vector_to_enu(pose.velocity_ecef_mps);
                        let length_m = match size {
                            cig_dis::DustCloudSize::Large => 10.0,
                            cig_dis::DustCloudSize::Medium => 7.0,
                            _ => 4.0,
                        };
                        effects
                            .start_dust_trail(&DustTrailSpec {
                                id: EffectId(cig_dis::detonation::splitmix64(seed ^ 4)),
                                start_time_s: t,
                                duration_s: None,
                                vehicle_length_m: length_m,
                                vehicle: VehicleUpdate {
                                    time_s: t,
                                    position,
                                    velocity_enu_mps: velocity.to_array(),
                                    material,
                                    roadside_material: None,
                                },
                            })
                            .ok()
                    }
                };
                if let Some(h) = handle {
                    slot.handles.insert(effect, h);
                }
            }
            if slot.handles.is_empty() {
                self.remote_effects.remove(&key);
            }
        }
    }

    /// Advances to `now_s`: timeouts, effects following their entities, time heartbeats and the
    /// owned entities' updates. `owned` gives the truth of each owned entity (by CIGI id).
    pub fn tick(
        &mut self,
        now_s: f64,
        owned: &BTreeMap<u16, OwnedTruth>,
        effects: &mut EffectSystem,
        query: &mut QuerySession,
    ) {
        let events = self.remote.expire(now_s);
        self.handle_events(now_s, events, effects, query);
        let t = self.effect_time_s(now_s);
        for (key, slot) in &self.remote_effects {
            let Some(pose) = self.remote.pose(*key, now_s) else {
                continue;
            };
            let position = Geodetic::from_ecef(pose.position_ecef_m);
            for (effect, handle) in &slot.handles {
                match effect {
                    EntityEffect::DustCloud(_) => {
                        let velocity =
                            EnuFrame::new(position).ecef_vector_to_enu(pose.velocity_ecef_mps);
                        let material = query
                            .hot(position.lat_deg, position.lon_deg)
                            .map_or(Material::DryClay, |s| s.material);
                        let _ = effects.update_vehicle(
                            *handle,
                            &VehicleUpdate {
                                time_s: t,
                                position,
                                velocity_enu_mps: velocity.to_array(),
                                material,
                                roadside_material: None,
                            },
                        );
                    }
                    _ => {
                        let _ = effects.move_plume(*handle, position);
                    }
                }
            }
        }
        let replies = self.time.tick(now_s);
        self.queue_time(now_s, &replies);
        let ids: Vec<u16> = self.owned.keys().copied().collect();
        for id in ids {
            let Some(truth) = owned.get(&id) else {
                continue;
            };
            let Some(o) = self.owned.get_mut(&id) else {
                continue;
            };
            let frame = EnuFrame::new(truth.position);
            let state = OwnedEntityState {
                position_ecef_m: truth.position.to_ecef(),
                orientation: dis_orientation(truth.position, truth.orientation),
                velocity_ecef_mps: frame.enu_vector_to_ecef(truth.velocity_enu_mps),
                appearance: o.appearance,
                ..OwnedEntityState::default()
            };
            if let Some((_, body)) = o.publisher.update(now_s, &state) {
                self.queue(now_s, &DisMessage::EntityState(Box::new(body)));
            }
        }
    }

    /// PDUs to send, each one datagram.
    pub fn take_outgoing(&mut self) -> Vec<Vec<u8>> {
        std::mem::take(&mut self.outgoing)
    }

    /// Remote entities at `now_s`.
    pub fn remote_entities(&self, now_s: f64) -> Vec<RemoteEntitySnapshot> {
        self.remote.snapshot(now_s)
    }

    /// The model for a remote entity.
    pub fn model_for(models: &ModelTable, t: &EntityTypeCode) -> String {
        models.model_for_dis(t).to_string()
    }
}
