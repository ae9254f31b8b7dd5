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
//! master falls silent. Smoke and fire sources of the scenario are published as Environmental
//! Process PDUs (a Gaussian plume record at the source, every 5 s and a last one at the end),
//! and other nodes' processes start a plume here at their source (stopped by a last update or
//! 12 s of silence). Lightning strikes announced by other nodes (Data PDU, datum 51010) are kept
//! for the renderer's flash (§VI.E.5).
//!
//! Effects run on "effect time": seconds of world time since 2020-01-01T00:00:00Z, the same on
//! every node that shares the world time.
//!
//! Limits: entity types map to models by the scenario's table; a remote process is drawn as a
//! standard 5 MW smoke source at its record's source (the plume record carries no fire size);
//! articulated parts of remote entities are not read.

use crate::scenario::{parse_dis_id, parse_hex_u32, DisSettings, DisTypePattern, Scenario};
use crate::terrain_edits;
use cig_dis::dis_rs::model::EntityId;
use cig_dis::{
    decode_datagram, encode_pdu, impact_effect, DisMessage, DisVersion, EncodeHeader, EntityEffect,
    EntityKey, EntityTypeCode, EnvironmentGeometry, EnvironmentRecord, EnvironmentalProcess,
    GaussianPlume, ImpactSize, ImpactSurface, LightningStrike, NodeId, OwnedEntityPublisher,
    OwnedEntityState, PublisherConfig, RemoteEntitySnapshot, RemoteEntityTable, RemoteTableConfig,
    TableEvent, TimeMessage, TimeSync, TimeSyncConfig,
};
use cig_dynterrain::soil::SoilMoisture;
use cig_effects::{
    DustTrailSpec, EffectHandle, EffectId, EffectSystem, PlumeKind, PlumeSource, PlumeSpec,
    VehicleUpdate,
};
use cig_geo::{EnuFrame, Geodetic};
use cig_terrain::edits::{Applied, TerrainEdit};
use cig_terrain::{Material, QuerySession};
use glam::DVec3;
use std::collections::BTreeMap;
use std::sync::Arc;

use cig_effects::effect_time_s;

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
    pub remote_processes_started: u64,
    pub lightning_strikes: u64,
    pub pdus_sent: u64,
    /// Craters made from Detonations (not counting ones already held).
    pub craters_made: u64,
    /// Terrain edits taken from other nodes' Object State PDUs (new ones only).
    pub terrain_edits_received: u64,
    /// Edits other nodes healed (deactivated Object States) that were held here.
    pub terrain_edits_healed: u64,
    /// Edits refused: Object State PDUs whose edit the database refused (outside it, bad
    /// sizes) or that came beyond `MAX_REMOTE_EDITS_PER_S`, and Detonations' craters refused.
    pub terrain_edits_refused: u64,
    /// Object State PDUs sent (first announcements and re-announcements).
    pub terrain_edits_sent: u64,
}

/// A smoke or fire process this IG owns and publishes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OwnedProcess {
    /// Process number (SITE:APPLICATION:number).
    pub number: u16,
    /// Source position, above the ellipsoid.
    pub position: Geodetic,
    /// Plume extent now: downwind length, width and height, metres.
    pub extent_m: [f64; 3],
    /// Still emitting.
    pub active: bool,
}

/// A process another node publishes, drawn here.
struct RemoteProcess {
    handle: EffectHandle,
    last_heard_s: f64,
}

/// Seconds between Environmental Process updates of an unchanged process.
pub const PROCESS_HEARTBEAT_S: f64 = 5.0;
/// A remote process unheard for this long is stopped (2.4 heartbeats, as for entities).
pub const PROCESS_TIMEOUT_S: f64 = 12.0;

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
    remote_processes: BTreeMap<(u16, u16, u16), RemoteProcess>,
    /// Owned processes: number → (last sent, sequence number, was active).
    process_sent: BTreeMap<u16, (f64, u16, bool)>,
    lightning: Vec<LightningStrike>,
    /// Ground and building impacts started, for the thermal sensors' hot spots: (effect time,
    /// ECEF point, size), the last [`MAX_IMPACTS_KEPT`].
    impacts: Vec<(f64, DVec3, ImpactSize)>,
    outgoing: Vec<Vec<u8>>,
    counters: ExerciseCounters,
    /// Re-announcement of the terrain edits: the next edit's place in the list, the edits
    /// owed (fractional), and when the last tick was.
    edit_cursor: usize,
    edits_owed: f64,
    last_tick_s: Option<f64>,
    /// Other nodes' new edits taken in the current second: (the second, how many).
    edit_second: (f64, u32),
    /// Edits healed here or by other nodes, the newest [`terrain_edits::MAX_HEALS_KEPT`]:
    /// announced again with the edits, their re-announcements as live edits ignored.
    heals: std::collections::VecDeque<TerrainEdit>,
    healed_ids: std::collections::HashSet<cig_terrain::EditId>,
    /// Nodes (site, application) whose ruts came in: they lay their own vehicles' ruts.
    rut_authors: std::collections::HashSet<(u16, u16)>,
}

/// Other nodes' new terrain edits taken a second at most; more are counted refused (the
/// re-announcements bring them again).
pub const MAX_REMOTE_EDITS_PER_S: u32 = 400;

/// At most this many received lightning strikes wait for the renderer.
const MAX_PENDING_STRIKES: usize = 64;

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
        // A master announces its own time at once rather than asking.
        let first = if settings.time_master {
            vec![time.set_time(now_s, start_ms, rate32)]
        } else {
            first
        };
        let mut exercise = Exercise {
            settings: settings.clone(),
            version,
            remote,
            owned,
            time,
            remote_effects: BTreeMap::new(),
            remote_processes: BTreeMap::new(),
            process_sent: BTreeMap::new(),
            lightning: Vec::new(),
            impacts: Vec::new(),
            outgoing: Vec::new(),
            counters: ExerciseCounters::default(),
            edit_cursor: 0,
            edits_owed: 0.0,
            last_tick_s: None,
            edit_second: (f64::NEG_INFINITY, 0),
            heals: std::collections::VecDeque::new(),
            healed_ids: std::collections::HashSet::new(),
            rut_authors: std::collections::HashSet::new(),
        };
        exercise.queue_time(now_s, &first);
        exercise
    }

    /// PDU headers carry the shared world time past the hour, marked absolute (the exercise's
    /// nodes agree on it).
    fn header(&self, now_s: f64) -> EncodeHeader {
        EncodeHeader {
            version: self.version,
            exercise_id: self.settings.exercise,
            timestamp: cig_dis::codec::timestamp_from_seconds_past_hour(
                self.world_time_unix_s(now_s).rem_euclid(3600.0),
                true,
            ),
        }
    }

    /// The world time an event happened: the PDU's absolute timestamp when it is within 30 s
    /// of the world time now (so every node starts its effect at the same instant whatever the
    /// network's delay), else the time it arrived.
    fn event_time_unix_s(&self, now_s: f64, timestamp: u32) -> f64 {
        let now_world = self.world_time_unix_s(now_s);
        let (past_hour_s, absolute) = cig_dis::codec::timestamp_seconds_past_hour(timestamp);
        if !absolute || !past_hour_s.is_finite() {
            return now_world;
        }
        let mut t = (now_world / 3600.0).floor() * 3600.0 + past_hour_s;
        if t - now_world > 1800.0 {
            t -= 3600.0;
        } else if now_world - t > 1800.0 {
            t += 3600.0;
        }
        if (t - now_world).abs() <= 30.0 {
            t
        } else {
            now_world
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

    /// Whether another node's new edit may be taken now: at most [`MAX_REMOTE_EDITS_PER_S`]
    /// a second, so a flood of Object State PDUs cannot stall the frame.
    fn edit_budget(&mut self, now_s: f64) -> bool {
        let second = now_s.floor();
        if self.edit_second.0 != second {
            self.edit_second = (second, 0);
        }
        self.edit_second.1 += 1;
        self.edit_second.1 <= MAX_REMOTE_EDITS_PER_S
    }

    /// The remote ground vehicles whose ruts fall to this node, when the scenario's `[dis]
    /// remote_ruts` asks: every land platform of the exercise at `now_s` whose own node sends
    /// no ruts (a simulation that is not an IG), while this node keeps the exercise's time (one node of the exercise lays them, and
    /// they reach the others as its edits; with no time master, none does).
    pub fn remote_rut_vehicles(&self, now_s: f64) -> Vec<RemoteEntitySnapshot> {
        if !self.settings.remote_ruts || self.time.role() != cig_dis::TimeRole::Master {
            return Vec::new();
        }
        let mut vehicles = self.remote.snapshot_where(now_s, |_| true);
        vehicles.retain(|r| {
            r.entity_type.kind == 1
                && r.entity_type.domain == 1
                && !self.rut_authors.contains(&(r.key.site, r.key.application))
        });
        vehicles
    }

    /// This node's DIS simulation address, as a terrain edit's author.
    pub fn address(&self) -> cig_terrain::edits::EditAuthor {
        cig_terrain::edits::EditAuthor {
            site: self.settings.site,
            application: self.settings.application,
        }
    }

    /// Sends a terrain edit this node made (its first announcement); it is announced again
    /// with the others every [`terrain_edits::REANNOUNCE_S`].
    pub fn announce_edit(&mut self, now_s: f64, edit: &TerrainEdit, query: &mut QuerySession) {
        self.send_edit(now_s, edit, query);
    }

    /// Sends the heal of an edit this node removed (the host's, the operator's); it is
    /// announced again with the edits for as long as it is among the newest heals.
    pub fn announce_heal(&mut self, now_s: f64, edit: &TerrainEdit, query: &mut QuerySession) {
        self.remember_heal(edit.clone());
        self.send_edit_as(now_s, edit, query, true);
    }

    /// Keeps a heal (the newest [`terrain_edits::MAX_HEALS_KEPT`]).
    fn remember_heal(&mut self, edit: TerrainEdit) {
        if self.healed_ids.insert(edit.id()) {
            self.heals.push_back(edit);
            while self.heals.len() > terrain_edits::MAX_HEALS_KEPT {
                if let Some(old) = self.heals.pop_front() {
                    self.healed_ids.remove(&old.id());
                }
            }
        }
    }

    fn send_edit(&mut self, now_s: f64, edit: &TerrainEdit, query: &mut QuerySession) {
        self.send_edit_as(now_s, edit, query, false);
    }

    fn send_edit_as(
        &mut self,
        now_s: f64,
        edit: &TerrainEdit,
        query: &mut QuerySession,
        healed: bool,
    ) {
        let anchor = edit.shape.anchor();
        let height_m = query
            .hot(anchor.lat_deg, anchor.lon_deg)
            .map_or(0.0, |s| s.height_ellipsoid_m());
        let message = if healed {
            terrain_edits::heal_pdu_of_edit(edit, height_m)
        } else {
            terrain_edits::pdu_of_edit(edit, height_m)
        };
        let Some(message) = message else {
            return;
        };
        if let Ok(bytes) = encode_pdu(self.header(now_s), &message) {
            self.outgoing.push(bytes);
            self.counters.terrain_edits_sent += 1;
            self.counters.pdus_sent += 1;
        }
    }

    /// Announces the held terrain edits again, spread evenly over the period, so that a node
    /// that joined late gets them all.
    fn reannounce_edits(&mut self, now_s: f64, query: &mut QuerySession) {
        let dt_s = self
            .last_tick_s
            .map_or(0.0, |t| (now_s - t).clamp(0.0, 1.0));
        self.last_tick_s = Some(now_s);
        let edits = Arc::clone(query.edits());
        // The edits held, then the heals known.
        let total = edits.len() + self.heals.len();
        if total == 0 {
            self.edits_owed = 0.0;
            return;
        }
        self.edits_owed += dt_s * total as f64 / terrain_edits::REANNOUNCE_S;
        let due = (self.edits_owed.floor() as usize).min(total);
        if due == 0 {
            return;
        }
        self.edits_owed -= due as f64;
        if self.edit_cursor >= total {
            self.edit_cursor = 0;
        }
        let all = || {
            edits
                .edits()
                .map(|e| (e, false))
                .chain(self.heals.iter().map(|e| (e, true)))
        };
        let batch: Vec<(TerrainEdit, bool)> = all()
            .chain(all())
            .skip(self.edit_cursor)
            .take(due)
            .map(|(e, healed)| (e.clone(), healed))
            .collect();
        self.edit_cursor = (self.edit_cursor + due) % total;
        for (edit, healed) in &batch {
            self.send_edit_as(now_s, edit, query, *healed);
        }
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
                    let event_s = self.event_time_unix_s(now_s, pdu.header.timestamp);
                    if let Some(crater) =
                        terrain_edits::crater_of_detonation(d, event_s, query, SoilMoisture::Dry)
                    {
                        match query.cache().update_edits(|layer| layer.apply(crater)) {
                            Ok(Applied::Added) => self.counters.craters_made += 1,
                            Ok(Applied::Known) => {}
                            Err(_) => self.counters.terrain_edits_refused += 1,
                        }
                    }
                    if let Some(start) = impact_effect(d) {
                        let at_s =
                            effect_time_s(self.event_time_unix_s(now_s, pdu.header.timestamp));
                        if self.start_impact(at_s, &start, effects) {
                            self.counters.impacts_started += 1;
                        }
                        if self.impacts.len() >= MAX_IMPACTS_KEPT {
                            self.impacts.remove(0);
                        }
                        self.impacts.push((at_s, start.position_ecef_m, start.size));
                    }
                }
                DisMessage::EnvironmentalProcess(process) => {
                    self.counters.environmental_processes += 1;
                    self.receive_process(now_s, process, effects);
                }
                DisMessage::PointObjectState(_) | DisMessage::LinearObjectState(_) => {
                    let time_s = self.event_time_unix_s(now_s, pdu.header.timestamp);
                    let deactivated = terrain_edits::is_deactivated(&pdu.message);
                    let edit = terrain_edits::edit_of_pdu(&pdu.message, time_s);
                    // A node that sends ruts lays its own vehicles' ruts.
                    if let Some(e) = edit.as_ref().filter(|_| !deactivated) {
                        if matches!(e.shape, cig_terrain::edits::EditShape::Rut { .. }) {
                            self.rut_authors
                                .insert((e.author.site, e.author.application));
                        }
                    }
                    match edit {
                        // A heal: the edit goes (if held) and is remembered healed.
                        Some(edit) if deactivated => {
                            let id = edit.id();
                            if !self.healed_ids.contains(&id) {
                                if !self.edit_budget(now_s) {
                                    self.counters.terrain_edits_refused += 1;
                                } else {
                                    if query.edits().contains(id)
                                        && query
                                            .cache()
                                            .update_edits(|layer| layer.remove(id))
                                            .is_ok()
                                    {
                                        self.counters.terrain_edits_healed += 1;
                                    }
                                    self.remember_heal(edit);
                                }
                            }
                        }
                        // A healed edit announced by a node that missed the heal.
                        Some(edit) if self.healed_ids.contains(&edit.id()) => {}
                        // Re-announcements of edits held (every node's, this one's echoed back)
                        // change nothing and cost nothing.
                        Some(edit) if query.edits().contains(edit.id()) => {}
                        Some(edit) if self.edit_budget(now_s) => {
                            match query.cache().update_edits(|layer| layer.apply(edit)) {
                                Ok(Applied::Added) => self.counters.terrain_edits_received += 1,
                                Ok(Applied::Known) => {}
                                Err(_) => self.counters.terrain_edits_refused += 1,
                            }
                        }
                        Some(_) => self.counters.terrain_edits_refused += 1,
                        None => self.counters.ignored += 1,
                    }
                }
                other => {
                    if let Some(strike) = LightningStrike::from_message(other) {
                        self.counters.lightning_strikes += 1;
                        if self.lightning.len() < MAX_PENDING_STRIKES {
                            self.lightning.push(strike);
                        }
                    } else if let Some(t) = TimeMessage::from_message(other) {
                        let replies = self.time.receive(now_s, &t);
                        self.queue_time(now_s, &replies);
                    } else {
                        self.counters.ignored += 1;
                    }
                }
            }
        }
    }

    /// Starts (or keeps alive, or stops) the plume of another node's process.
    fn receive_process(
        &mut self,
        now_s: f64,
        process: &EnvironmentalProcess,
        effects: &mut EffectSystem,
    ) {
        let id = &process.process_id;
        let key = (
            id.simulation_address.site_id,
            id.simulation_address.application_id,
            id.entity_id,
        );
        if (key.0, key.1) == (self.settings.site, self.settings.application) {
            return;
        }
        let t = self.effect_time_s(now_s);
        if process.is_last || !process.is_active {
            if let Some(p) = self.remote_processes.remove(&key) {
                let _ = effects.stop(p.handle, t);
            }
            return;
        }
        if let Some(p) = self.remote_processes.get_mut(&key) {
            p.last_heard_s = now_s;
            return;
        }
        let source = process.records.iter().find_map(|r| match &r.geometry {
            EnvironmentGeometry::GaussianPlume(p) => Some(p.source_location_ecef_m),
            EnvironmentGeometry::GaussianPuff(p) => Some(p.origination_location_ecef_m),
            EnvironmentGeometry::Unknown { .. } => None,
        });
        let Some(source) = source.map(DVec3::from_array).filter(|p| p.is_finite()) else {
            return;
        };
        let seed = (u64::from(key.0) << 32) | (u64::from(key.1) << 16) | u64::from(key.2);
        let spec = PlumeSpec {
            id: EffectId(cig_dis::detonation::splitmix64(seed ^ 0x5052_4f43)),
            kind: PlumeKind::Smoke,
            position: Geodetic::from_ecef(source),
            size_m: 5.0,
            source: PlumeSource::HeatReleaseW(5.0e6),
            start_time_s: t,
            duration_s: 1.0e6,
        };
        if let Ok(handle) = effects.start_plume(&spec) {
            self.counters.remote_processes_started += 1;
            self.remote_processes.insert(
                key,
                RemoteProcess {
                    handle,
                    last_heard_s: now_s,
                },
            );
        }
    }

    /// Publishes this IG's smoke and fire processes: an Environmental Process PDU with a
    /// Gaussian plume record when one starts, every [`PROCESS_HEARTBEAT_S`], and a last one
    /// when it ends.
    pub fn publish_processes(&mut self, now_s: f64, processes: &[OwnedProcess]) {
        for p in processes {
            let (last_s, sequence, was_active) = self
                .process_sent
                .get(&p.number)
                .copied()
                .unwrap_or((f64::NEG_INFINITY, 0, false));
            let ended = was_active && !p.active;
            let due = p.active && now_s - last_s >= PROCESS_HEARTBEAT_S;
            if !(due || ended) {
                continue;
            }
            let [length_m, width_m, height_m] = p.extent_m.map(|v| v as f32);
            let body = EnvironmentalProcess {
                process_id: EntityId::new(self.settings.site, self.settings.application, p.number),
                environment_type: EntityTypeCode {
                    kind: 4,
                    domain: 0,
                    country: 0,
                    category: 1,
                    subcategory: 0,
                    specific: 0,
                    extra: 0,
                }
                .to_dis(),
                model_type: 0,
                is_last: !p.active,
                is_active: p.active,
                sequence_number: sequence,
                records: vec![EnvironmentRecord {
                    index: 0,
                    geometry: EnvironmentGeometry::GaussianPlume(GaussianPlume {
                        source_location_ecef_m: p.position.to_ecef().to_array(),
                        orientation_rad: [0.0; 3],
                        length_m,
                        width_m,
                        height_m,
                        length_rate_mps: 0.0,
                        width_rate_mps: 0.0,
                        height_rate_mps: 0.0,
                        leading_edge_centroid_height_m: height_m / 2.0,
                        leading_edge_velocity_mps: [0.0; 3],
                    }),
                }],
            };
            self.queue(now_s, &DisMessage::EnvironmentalProcess(body));
            self.process_sent
                .insert(p.number, (now_s, sequence.wrapping_add(1), p.active));
        }
    }

    /// Announces a lightning strike this IG made, so other nodes flash too.
    pub fn announce_lightning(
        &mut self,
        now_s: f64,
        position_ecef_m: DVec3,
        seed: u64,
        intensity: f32,
    ) {
        let strike = LightningStrike {
            from: NodeId {
                site: self.settings.site,
                application: self.settings.application,
            },
            position_ecef_m,
            seed,
            intensity,
        };
        self.queue(now_s, &strike.to_message());
    }

    /// Lightning strikes other nodes announced since the last call.
    pub fn take_lightning(&mut self) -> Vec<LightningStrike> {
        std::mem::take(&mut self.lightning)
    }

    fn effect_time_s(&self, now_s: f64) -> f64 {
        effect_time_s(self.world_time_unix_s(now_s))
    }

    /// Starts smoke and flame at an impact, at effect time `t`.
    fn start_impact(
        &mut self,
        t: f64,
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
                let velocity = EnuFrame::new(position).ecef_vector_to_enu(pose.velocity_ecef_mps);
                let handle =
                    start_entity_effect(effects, query, effect, seed, position, velocity, t);
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
        let t_stop = self.effect_time_s(now_s);
        self.remote_processes.retain(|_, p| {
            let alive = now_s - p.last_heard_s <= PROCESS_TIMEOUT_S;
            if !alive {
                let _ = effects.stop(p.handle, t_stop);
            }
            alive
        });
        let t = self.effect_time_s(now_s);
        for (key, slot) in &self.remote_effects {
            let Some(pose) = self.remote.pose(*key, now_s) else {
                continue;
            };
            let position = Geodetic::from_ecef(pose.position_ecef_m);
            let velocity = EnuFrame::new(position).ecef_vector_to_enu(pose.velocity_ecef_mps);
            for (effect, handle) in &slot.handles {
                follow_entity_effect(effects, query, *effect, *handle, position, velocity, t);
            }
        }
        let replies = self.time.tick(now_s);
        self.queue_time(now_s, &replies);
        self.reannounce_edits(now_s, query);
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

    /// Forgets every effect handle (after the effect system was rebuilt by a jump back in time);
    /// remote entities' effects start again with their next Entity State, other nodes'
    /// processes with their next Environmental Process update.
    pub fn forget_effects(&mut self) {
        self.remote_effects.clear();
        self.remote_processes.clear();
        self.remote.forget_effects();
    }

    /// PDUs to send, each one datagram.
    pub fn take_outgoing(&mut self) -> Vec<Vec<u8>> {
        std::mem::take(&mut self.outgoing)
    }

    /// The last ground and building impacts: (effect time, ECEF point, size).
    pub fn recent_impacts(&self) -> &[(f64, DVec3, ImpactSize)] {
        &self.impacts
    }

    /// Remote entities at `now_s` within `radius_m` of any of `eyes_ecef_m`.
    pub fn remote_entities_near(
        &self,
        now_s: f64,
        eyes_ecef_m: &[DVec3],
        radius_m: f64,
    ) -> Vec<RemoteEntitySnapshot> {
        let r2 = radius_m * radius_m;
        self.remote.snapshot_where(now_s, |p| {
            eyes_ecef_m.iter().any(|e| e.distance_squared(p) <= r2)
        })
    }
}

/// Impacts kept for the thermal sensors' hot spots.
pub const MAX_IMPACTS_KEPT: usize = 32;

/// Starts one appearance effect on an entity at `position` moving at `velocity_enu_mps`, at
/// effect time `t_s`; `seed` is the entity's identity, so every node starts the same effect.
pub fn start_entity_effect(
    effects: &mut EffectSystem,
    query: &mut QuerySession,
    effect: EntityEffect,
    seed: u64,
    position: Geodetic,
    velocity_enu_mps: DVec3,
    t_s: f64,
) -> Option<EffectHandle> {
    match effect {
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
                    start_time_s: t_s,
                    duration_s: 3600.0,
                })
                .ok()
        }
        EntityEffect::DustCloud(size) => {
            let material = query
                .hot(position.lat_deg, position.lon_deg)
                .map_or(Material::DryClay, |s| s.material);
            let length_m = match size {
                cig_dis::DustCloudSize::Large => 10.0,
                cig_dis::DustCloudSize::Medium => 7.0,
                _ => 4.0,
            };
            effects
                .start_dust_trail(&DustTrailSpec {
                    id: EffectId(cig_dis::detonation::splitmix64(seed ^ 4)),
                    start_time_s: t_s,
                    duration_s: None,
                    vehicle_length_m: length_m,
                    vehicle: VehicleUpdate {
                        time_s: t_s,
                        position,
                        velocity_enu_mps: velocity_enu_mps.to_array(),
                        material,
                        roadside_material: None,
                    },
                })
                .ok()
        }
    }
}

/// Moves an entity's effect with it: a plume's source, or a dust trail's vehicle.
pub fn follow_entity_effect(
    effects: &mut EffectSystem,
    query: &mut QuerySession,
    effect: EntityEffect,
    handle: EffectHandle,
    position: Geodetic,
    velocity_enu_mps: DVec3,
    t_s: f64,
) {
    match effect {
        EntityEffect::DustCloud(_) => {
            let material = query
                .hot(position.lat_deg, position.lon_deg)
                .map_or(Material::DryClay, |s| s.material);
            let _ = effects.update_vehicle(
                handle,
                &VehicleUpdate {
                    time_s: t_s,
                    position,
                    velocity_enu_mps: velocity_enu_mps.to_array(),
                    material,
                    roadside_material: None,
                },
            );
        }
        _ => {
            let _ = effects.move_plume(handle, position);
        }
    }
}
