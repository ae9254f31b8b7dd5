//! The pure part of `cig dis listen` and `cig dis send`: PDUs described, arguments parsed,
//! Entity States built.
//!
//! Listening: each datagram is walked PDU by PDU with `cig_dis::decode_datagram` (IEEE
//! 1278.1-2012 §6.2.66 header, bundled PDUs per IEEE 1278.2 §4.1.3) and each PDU described in
//! one line ([`pdu_line`]) or one JSON object ([`pdu_json`]): the header, and for the PDUs an IG
//! uses the fields that matter — Entity State (§7.2.2: ids, type, geodetic position from the
//! ECEF location via `cig-geo`, velocity in ECEF and local east/north/up, local
//! heading/pitch/roll, appearance and the obscurant effects it asks for, dead-reckoning
//! algorithm), Fire and Detonation (§7.3.2-7.3.3, with the impact effect cig would start),
//! Remove Entity, Data Query / Set Data / Data (§7.5.9-7.5.11, with cig's time and lightning
//! datums decoded), Environmental Process (§7.10.5). A datagram that does not decode gives one
//! error line and is counted ([`Listing`]).
//!
//! Sending: [`EntitySender`] builds an Entity State with `cig_dis::OwnedEntityPublisher` (so it
//! is exactly what an IG publishes) from a geodetic position, an east/north/up velocity and a
//! local heading, moving the entity by its velocity with the time since the first PDU (a
//! straight ECEF line: what DR algorithm 2, FPW, predicts).
//!
//! Limits: orientation is set from the heading only (level, no roll); the timestamp is the
//! sender's UTC time past the hour marked relative (no claim of a synchronised clock). Error
//! messages name the `cig dis` option the value came from.

use crate::ToolError;
use cig_dis::codec::{timestamp_from_seconds_past_hour, timestamp_seconds_past_hour};
use cig_dis::dis_rs::enumerations::PduType;
use cig_dis::dis_rs::model::{EntityId, EntityType, EventId, Location, VectorF32};
use cig_dis::remote::{dr_input_from_entity_state, local_heading_pitch_roll_deg};
use cig_dis::{
    DecodedPdu, DisMessage, DisVersion, DrAlgorithm, DustCloudSize, EffectsRequested, EncodeHeader,
    EntityKey, EntityTypeCode, EnvironmentGeometry, EulerAngles, LightningStrike,
    OwnedEntityPublisher, OwnedEntityState, PublisherConfig, TimeMessage,
};
use cig_geo::{EnuFrame, Geodetic};
use glam::{DMat3, DVec3};
use serde_json::{json, Value};
use std::net::SocketAddr;

/// Short name of a dead-reckoning algorithm (SISO-REF-010 UID 44).
pub fn dr_name(algorithm: DrAlgorithm) -> &'static str {
    match algorithm {
        DrAlgorithm::Other => "Other",
        DrAlgorithm::Static => "Static",
        DrAlgorithm::Fpw => "FPW",
        DrAlgorithm::Rpw => "RPW",
        DrAlgorithm::Rvw => "RVW",
        DrAlgorithm::Fvw => "FVW",
        DrAlgorithm::Fpb => "FPB",
        DrAlgorithm::Rpb => "RPB",
        DrAlgorithm::Rvb => "RVB",
        DrAlgorithm::Fvb => "FVB",
    }
}

fn dust_name(size: DustCloudSize) -> &'static str {
    match size {
        DustCloudSize::None => "none",
        DustCloudSize::Small => "small",
        DustCloudSize::Medium => "medium",
        DustCloudSize::Large => "large",
    }
}

fn id_text(id: &EntityId) -> String {
    format!(
        "{}:{}:{}",
        id.simulation_address.site_id, id.simulation_address.application_id, id.entity_id
    )
}

fn event_text(id: &EventId) -> String {
    format!(
        "{}:{}:{}",
        id.simulation_address.site_id, id.simulation_address.application_id, id.event_id
    )
}

fn type_text(t: &EntityType) -> String {
    let c = EntityTypeCode::from_dis(t);
    format!(
        "{}:{}:{}:{}:{}:{}:{}",
        c.kind, c.domain, c.country, c.category, c.subcategory, c.specific, c.extra
    )
}

fn ecef(l: &Location) -> DVec3 {
    DVec3::new(l.x_coordinate, l.y_coordinate, l.z_coordinate)
}

fn vector(v: &VectorF32) -> DVec3 {
    DVec3::new(
        f64::from(v.first_vector_component),
        f64::from(v.second_vector_component),
        f64::from(v.third_vector_component),
    )
}

/// JSON numbers cannot be NaN or infinite: those print as null.
fn num(x: f64) -> Value {
    if x.is_finite() {
        json!(x)
    } else {
        Value::Null
    }
}

fn geodetic_json(p: DVec3) -> Value {
    if !p.is_finite() {
        return json!({"lat_deg": null, "lon_deg": null, "alt_m": null});
    }
    let g = Geodetic::from_ecef(p);
    json!({"lat_deg": num(g.lat_deg), "lon_deg": num(g.lon_deg), "alt_m": num(g.alt_m)})
}

fn vec_json(v: DVec3) -> Value {
    json!([num(v.x), num(v.y), num(v.z)])
}

/// East/north/up components of an ECEF vector at an ECEF position.
fn enu_of(position_ecef_m: DVec3, v: DVec3) -> Option<DVec3> {
    if !position_ecef_m.is_finite() || position_ecef_m.length() < 1.0 {
        return None;
    }
    Some(EnuFrame::new(Geodetic::from_ecef(position_ecef_m)).ecef_vector_to_enu(v))
}

fn effects_json(e: EffectsRequested) -> Value {
    json!({
        "smoke": e.smoke_plume,
        "engine_smoke": e.engine_smoke,
        "flaming": e.flaming,
        "dust": dust_name(e.dust_cloud),
    })
}

fn header_json(pdu: &DecodedPdu, from: SocketAddr) -> serde_json::Map<String, Value> {
    let h = &pdu.header;
    let (seconds, absolute) = timestamp_seconds_past_hour(h.timestamp);
    let mut m = serde_json::Map::new();
    m.insert("pdu_type".into(), json!(h.pdu_type));
    m.insert(
        "pdu_name".into(),
        json!(PduType::from(h.pdu_type).to_string()),
    );
    m.insert("protocol_version".into(), json!(h.version.octet()));
    m.insert("exercise".into(), json!(h.exercise_id));
    m.insert("protocol_family".into(), json!(h.protocol_family));
    m.insert("length_octets".into(), json!(h.length_octets));
    m.insert("timestamp_raw".into(), json!(h.timestamp));
    m.insert("timestamp_s_past_hour".into(), num(seconds));
    m.insert("timestamp_absolute".into(), json!(absolute));
    m.insert("from".into(), json!(from.to_string()));
    m
}

/// The JSON description of one decoded PDU.
pub fn pdu_json(pdu: &DecodedPdu, from: SocketAddr) -> Value {
    let mut m = header_json(pdu, from);
    let mut put = |k: &str, v: Value| {
        m.insert(k.to_string(), v);
    };
    match &pdu.message {
        DisMessage::EntityState(es) => {
            let (algorithm, input) = dr_input_from_entity_state(es);
            let code = EntityTypeCode::from_dis(&es.entity_type);
            let appearance = u32::from(&es.entity_appearance);
            let p = input.position_ecef_m;
            put("entity_id", json!(id_text(&es.entity_id)));
            put("force_id", json!(u8::from(es.force_id)));
            put("entity_type", json!(type_text(&es.entity_type)));
            put("marking", json!(es.entity_marking.marking_string));
            put("position", geodetic_json(p));
            put("position_ecef_m", vec_json(p));
            put("velocity_ecef_mps", vec_json(input.velocity_ecef_mps));
            put(
                "velocity_enu_mps",
                match enu_of(p, input.velocity_ecef_mps) {
                    Some(v) => json!({"east": num(v.x), "north": num(v.y), "up": num(v.z)}),
                    None => Value::Null,
                },
            );
            let o = input.orientation;
            let finite = o.psi_rad.is_finite() && o.theta_rad.is_finite() && o.phi_rad.is_finite();
            put(
                "orientation",
                if finite && p.is_finite() && p.length() >= 1.0 {
                    let [h, pi, r] = local_heading_pitch_roll_deg(o.body_to_world(), p);
                    json!({"heading_deg": num(h), "pitch_deg": num(pi), "roll_deg": num(r),
                           "psi_rad": num(o.psi_rad), "theta_rad": num(o.theta_rad), "phi_rad": num(o.phi_rad)})
                } else {
                    json!({"psi_rad": num(o.psi_rad), "theta_rad": num(o.theta_rad), "phi_rad": num(o.phi_rad)})
                },
            );
            put("appearance", json!(format!("0x{appearance:08x}")));
            put(
                "effects",
                effects_json(EffectsRequested::from_appearance(
                    appearance,
                    code.kind,
                    code.domain,
                )),
            );
            put(
                "dead_reckoning",
                json!({"algorithm": algorithm.code(), "name": dr_name(algorithm),
                       "wire_code": u8::from(es.dead_reckoning_parameters.algorithm)}),
            );
        }
        DisMessage::Fire(f) => {
            put("firing_entity_id", json!(id_text(&f.firing_entity_id)));
            put("target_entity_id", json!(id_text(&f.target_entity_id)));
            put("munition_entity_id", json!(id_text(&f.entity_id)));
            put("event_id", json!(event_text(&f.event_id)));
            put("position", geodetic_json(ecef(&f.location_in_world)));
            put("velocity_ecef_mps", vec_json(vector(&f.velocity)));
            put("range_m", num(f64::from(f.range)));
        }
        DisMessage::Detonation(d) => {
            let p = ecef(&d.location_in_world_coordinates);
            put("source_entity_id", json!(id_text(&d.source_entity_id)));
            put("target_entity_id", json!(id_text(&d.target_entity_id)));
            put(
                "exploding_entity_id",
                json!(id_text(&d.exploding_entity_id)),
            );
            put("event_id", json!(event_text(&d.event_id)));
            put("position", geodetic_json(p));
            put("position_ecef_m", vec_json(p));
            put("velocity_ecef_mps", vec_json(vector(&d.velocity)));
            let (descriptor, munition_type) = match &d.descriptor {
                cig_dis::dis_rs::detonation::model::DetonationDescriptor::Munition(m) => {
                    ("munition", type_text(&m.entity_type))
                }
                cig_dis::dis_rs::detonation::model::DetonationDescriptor::Explosion(e) => {
                    ("explosion", type_text(&e.entity_type))
                }
                cig_dis::dis_rs::detonation::model::DetonationDescriptor::Expendable(e) => {
                    ("expendable", type_text(&e.entity_type))
                }
            };
            put("descriptor", json!(descriptor));
            put("munition_type", json!(munition_type));
            put(
                "result",
                json!({"code": u8::from(d.detonation_result), "name": d.detonation_result.to_string()}),
            );
            put(
                "impact_effect",
                match cig_dis::impact_effect(d) {
                    Some(e) => json!({
                        "surface": format!("{:?}", e.surface).to_lowercase(),
                        "size": format!("{:?}", e.size).to_lowercase(),
                        "seed": format!("0x{:016x}", e.effect_seed),
                    }),
                    None => Value::Null,
                },
            );
        }
        DisMessage::RemoveEntity(r) => {
            put("originating_id", json!(id_text(&r.originating_id)));
            put("receiving_id", json!(id_text(&r.receiving_id)));
            put("request_id", json!(r.request_id));
        }
        DisMessage::DataQuery(q) => {
            put("originating_id", json!(id_text(&q.originating_id)));
            put("receiving_id", json!(id_text(&q.receiving_id)));
            put("request_id", json!(q.request_id));
            put("time_interval", json!(q.time_interval));
            put(
                "fixed_datum_ids",
                json!(q
                    .fixed_datum_records
                    .iter()
                    .map(|r| u32::from(*r))
                    .collect::<Vec<_>>()),
            );
            put(
                "variable_datum_ids",
                json!(q
                    .variable_datum_records
                    .iter()
                    .map(|r| u32::from(*r))
                    .collect::<Vec<_>>()),
            );
            put("time_sync", time_json(&pdu.message));
        }
        DisMessage::SetData(s) => {
            put("originating_id", json!(id_text(&s.originating_id)));
            put("receiving_id", json!(id_text(&s.receiving_id)));
            put("request_id", json!(s.request_id));
            put("fixed_datums", fixed_json(&s.fixed_datum_records));
            put("variable_datums", variable_json(&s.variable_datum_records));
            put("time_sync", time_json(&pdu.message));
        }
        DisMessage::Data(d) => {
            put("originating_id", json!(id_text(&d.originating_id)));
            put("receiving_id", json!(id_text(&d.receiving_id)));
            put("request_id", json!(d.request_id));
            put("fixed_datums", fixed_json(&d.fixed_datum_records));
            put("variable_datums", variable_json(&d.variable_datum_records));
            put("time_sync", time_json(&pdu.message));
            put(
                "lightning",
                match LightningStrike::from_message(&pdu.message) {
                    Some(l) => json!({
                        "from": format!("{}:{}", l.from.site, l.from.application),
                        "position": geodetic_json(l.position_ecef_m),
                        "seed": format!("0x{:016x}", l.seed),
                        "intensity": num(f64::from(l.intensity)),
                    }),
                    None => Value::Null,
                },
            );
        }
        DisMessage::PointObjectState(o) => {
            put("object_id", json!(o.object_id.to_string()));
            put("object_type", json!(o.object_type.to_string()));
            put("update_number", json!(o.update_number));
            put(
                "position",
                geodetic_json(DVec3::from_array(o.location_ecef_m)),
            );
            put(
                "specific_appearance",
                json!(format!("0x{:08x}", o.specific_appearance)),
            );
        }
        DisMessage::LinearObjectState(o) => {
            put("object_id", json!(o.object_id.to_string()));
            put("object_type", json!(o.object_type.to_string()));
            put("update_number", json!(o.update_number));
            let segments: Vec<Value> = o
                .segments
                .iter()
                .map(|s| {
                    json!({
                        "position": geodetic_json(DVec3::from_array(s.location_ecef_m)),
                        "length_m": num(f64::from(s.length_m)),
                        "width_m": num(f64::from(s.width_m)),
                        "height_m": num(f64::from(s.height_m)),
                        "depth_m": num(f64::from(s.depth_m)),
                    })
                })
                .collect();
            put("segments", json!(segments));
        }
        DisMessage::EnvironmentalProcess(e) => {
            put("process_id", json!(id_text(&e.process_id)));
            put("environment_type", json!(type_text(&e.environment_type)));
            put("model_type", json!(e.model_type));
            put("is_last", json!(e.is_last));
            put("is_active", json!(e.is_active));
            put("sequence_number", json!(e.sequence_number));
            let records: Vec<Value> = e
                .records
                .iter()
                .map(|r| match &r.geometry {
                    EnvironmentGeometry::GaussianPlume(g) => json!({
                        "index": r.index,
                        "record": "gaussian_plume",
                        "source": geodetic_json(DVec3::from_array(g.source_location_ecef_m)),
                        "length_m": num(f64::from(g.length_m)),
                        "width_m": num(f64::from(g.width_m)),
                        "height_m": num(f64::from(g.height_m)),
                    }),
                    EnvironmentGeometry::GaussianPuff(g) => json!({
                        "index": r.index,
                        "record": "gaussian_puff",
                        "puff": geodetic_json(DVec3::from_array(g.puff_location_ecef_m)),
                        "origin": geodetic_json(DVec3::from_array(g.origination_location_ecef_m)),
                        "sigma_m": g.sigma_m.iter().map(|s| num(f64::from(*s))).collect::<Vec<_>>(),
                    }),
                    EnvironmentGeometry::Unknown { record_type, data } => json!({
                        "index": r.index,
                        "record": "other",
                        "record_type": record_type,
                        "octets": data.len(),
                    }),
                })
                .collect();
            put("records", json!(records));
        }
        DisMessage::Unsupported => {
            put("body", json!("not decoded"));
        }
    }
    Value::Object(m)
}

fn fixed_json(records: &[cig_dis::dis_rs::model::FixedDatum]) -> Value {
    json!(records
        .iter()
        .map(|r| json!({"id": u32::from(r.datum_id), "value": r.datum_value}))
        .collect::<Vec<_>>())
}

fn variable_json(records: &[cig_dis::dis_rs::model::VariableDatum]) -> Value {
    json!(records
        .iter()
        .map(|r| {
            let shown: String = r
                .datum_value
                .iter()
                .take(64)
                .map(|b| format!("{b:02x}"))
                .collect();
            json!({"id": u32::from(r.datum_id), "octets": r.datum_value.len(), "hex": shown})
        })
        .collect::<Vec<_>>())
}

fn time_json(message: &DisMessage) -> Value {
    let node = |n: cig_dis::NodeId| format!("{}:{}", n.site, n.application);
    match TimeMessage::from_message(message) {
        Some(TimeMessage::Query { from, request_id }) => {
            json!({"kind": "query", "from": node(from), "request_id": request_id})
        }
        Some(TimeMessage::Announce {
            from,
            to,
            request_id,
            world_time_ms,
            rate,
        }) => json!({
            "kind": "announce", "from": node(from), "to": to.map(node),
            "request_id": request_id, "world_time_ms": world_time_ms,
            "world_time_utc": utc_text(world_time_ms), "rate": num(f64::from(rate)),
        }),
        Some(TimeMessage::Set {
            from,
            world_time_ms,
            rate,
        }) => json!({
            "kind": "set", "from": node(from), "world_time_ms": world_time_ms,
            "world_time_utc": utc_text(world_time_ms), "rate": num(f64::from(rate)),
        }),
        None => Value::Null,
    }
}

fn utc_text(ms: i64) -> Option<String> {
    let t = time::OffsetDateTime::from_unix_timestamp_nanos(i128::from(ms) * 1_000_000).ok()?;
    t.format(&time::format_description::well_known::Rfc3339)
        .ok()
}

/// The readable one-line form of a PDU.
pub fn pdu_line(pdu: &DecodedPdu, from: SocketAddr) -> String {
    let h = &pdu.header;
    let name = PduType::from(h.pdu_type).to_string();
    let head = format!(
        "{name} (type {}) v{} exercise {} from {from}",
        h.pdu_type,
        h.version.octet(),
        h.exercise_id
    );
    let where_ = |p: DVec3| {
        if p.is_finite() {
            let g = Geodetic::from_ecef(p);
            format!("{:.6},{:.6} alt {:.1} m", g.lat_deg, g.lon_deg, g.alt_m)
        } else {
            "at a non-finite position".to_string()
        }
    };
    match &pdu.message {
        DisMessage::EntityState(es) => {
            let (algorithm, input) = dr_input_from_entity_state(es);
            let code = EntityTypeCode::from_dis(&es.entity_type);
            let appearance = u32::from(&es.entity_appearance);
            let effects = EffectsRequested::from_appearance(appearance, code.kind, code.domain);
            let v = enu_of(input.position_ecef_m, input.velocity_ecef_mps).unwrap_or(DVec3::NAN);
            let mut flags: Vec<String> = Vec::new();
            if effects.smoke_plume {
                flags.push("smoke".into());
            }
            if effects.engine_smoke {
                flags.push("engine-smoke".into());
            }
            if effects.flaming {
                flags.push("flaming".into());
            }
            if effects.dust_cloud != DustCloudSize::None {
                flags.push(format!("dust-{}", dust_name(effects.dust_cloud)));
            }
            format!(
                "{head}: {} type {} {:?} at {} vel E/N/U {:.2}/{:.2}/{:.2} m/s appearance 0x{appearance:08x} [{}] DR {} {}",
                id_text(&es.entity_id),
                type_text(&es.entity_type),
                es.entity_marking.marking_string,
                where_(input.position_ecef_m),
                v.x,
                v.y,
                v.z,
                flags.join(","),
                algorithm.code(),
                dr_name(algorithm)
            )
        }
        DisMessage::Detonation(d) => format!(
            "{head}: event {} by {} at {} result {} ({})",
            event_text(&d.event_id),
            id_text(&d.source_entity_id),
            where_(ecef(&d.location_in_world_coordinates)),
            u8::from(d.detonation_result),
            d.detonation_result
        ),
        DisMessage::Fire(f) => format!(
            "{head}: event {} by {} at {}",
            event_text(&f.event_id),
            id_text(&f.firing_entity_id),
            where_(ecef(&f.location_in_world))
        ),
        DisMessage::RemoveEntity(r) => format!(
            "{head}: {} asks {} (request {})",
            id_text(&r.originating_id),
            id_text(&r.receiving_id),
            r.request_id
        ),
        DisMessage::PointObjectState(o) => format!(
            "{head}: point object {} type {} at {}",
            o.object_id,
            o.object_type,
            where_(DVec3::from_array(o.location_ecef_m))
        ),
        DisMessage::LinearObjectState(o) => format!(
            "{head}: linear object {} type {} {} segments",
            o.object_id,
            o.object_type,
            o.segments.len()
        ),
        DisMessage::EnvironmentalProcess(e) => format!(
            "{head}: process {} type {} {} records{}",
            id_text(&e.process_id),
            type_text(&e.environment_type),
            e.records.len(),
            if e.is_active { "" } else { " (inactive)" }
        ),
        DisMessage::DataQuery(_) | DisMessage::SetData(_) | DisMessage::Data(_) => {
            let time = time_json(&pdu.message);
            if time.is_null() {
                if LightningStrike::from_message(&pdu.message).is_some() {
                    format!("{head}: lightning strike")
                } else {
                    head
                }
            } else {
                format!("{head}: time {time}")
            }
        }
        DisMessage::Unsupported => format!("{head} (body not decoded)"),
    }
}

/// What `cig dis listen` prints, datagram by datagram: PDUs of the chosen exercise up to
/// `count`, as lines or JSON lines, and one error line per PDU that does not decode.
#[derive(Clone, Debug, Default)]
pub struct Listing {
    /// Only PDUs of this exercise.
    pub exercise: Option<u8>,
    /// Stop after this many PDUs (bad datagrams do not count).
    pub count: Option<u64>,
    /// JSON lines instead of readable ones.
    pub json: bool,
    printed: u64,
    bad: u64,
}

impl Listing {
    /// A listing that has described nothing yet.
    #[must_use]
    pub fn new(exercise: Option<u8>, count: Option<u64>, json: bool) -> Listing {
        Listing {
            exercise,
            count,
            json,
            printed: 0,
            bad: 0,
        }
    }

    /// The lines for one datagram from `from`; stops at `count` PDUs, so every line returned
    /// is to be printed.
    pub fn lines(&mut self, bytes: &[u8], from: SocketAddr) -> Vec<String> {
        let mut lines = Vec::new();
        for result in cig_dis::decode_datagram(bytes) {
            match result {
                Ok(pdu) => {
                    if self.exercise.is_some_and(|e| e != pdu.header.exercise_id) {
                        continue;
                    }
                    if self.done() {
                        break;
                    }
                    self.printed += 1;
                    lines.push(if self.json {
                        pdu_json(&pdu, from).to_string()
                    } else {
                        pdu_line(&pdu, from)
                    });
                }
                Err(e) => {
                    self.bad += 1;
                    lines.push(if self.json {
                        json!({"error": e.to_string(), "from": from.to_string(),
                               "octets": bytes.len()})
                        .to_string()
                    } else {
                        format!("bad datagram from {from} ({} octets): {e}", bytes.len())
                    });
                }
            }
        }
        lines
    }

    /// Whether `count` PDUs have been described.
    #[must_use]
    pub fn done(&self) -> bool {
        self.count.is_some_and(|n| self.printed >= n)
    }

    /// PDUs described so far.
    #[must_use]
    pub fn printed(&self) -> u64 {
        self.printed
    }

    /// Undecodable PDUs so far.
    #[must_use]
    pub fn bad(&self) -> u64 {
        self.bad
    }
}

/// Parses "A:B:C..." into numbers, naming the option on error.
fn parse_fields(
    text: &str,
    option: &str,
    form: &str,
    counts: &[usize],
) -> Result<Vec<u64>, ToolError> {
    let parts: Vec<&str> = text.trim().split(':').collect();
    if !counts.contains(&parts.len()) {
        return Err(ToolError::Argument(format!(
            "{option} {text:?} must be {form}"
        )));
    }
    parts
        .iter()
        .map(|p| {
            p.trim().parse::<u64>().map_err(|_| {
                ToolError::Argument(format!(
                    "{option} {text:?}: {p:?} is not a whole number ({form})"
                ))
            })
        })
        .collect()
}

fn fit<T: TryFrom<u64>>(value: u64, option: &str, field: &str) -> Result<T, ToolError> {
    T::try_from(value).map_err(|_| {
        ToolError::Argument(format!(
            "{option}: {field} {value} is out of range (at most {})",
            if std::mem::size_of::<T>() == 1 {
                u64::from(u8::MAX)
            } else {
                u64::from(u16::MAX)
            }
        ))
    })
}

/// "SITE:APP:ID" (`--entity`).
///
/// # Errors
/// When the text is not three whole numbers of 16 bits.
pub fn parse_entity_id(text: &str) -> Result<EntityKey, ToolError> {
    let f = parse_fields(text, "--entity", "SITE:APP:ID", &[3])?;
    Ok(EntityKey {
        site: fit(f[0], "--entity", "site")?,
        application: fit(f[1], "--entity", "application")?,
        entity: fit(f[2], "--entity", "entity")?,
    })
}

/// "K:D:C:CAT:SUB[:SPEC:EXTRA]" (`--type`).
///
/// # Errors
/// When the text is not five or seven whole numbers in their fields' ranges.
pub fn parse_entity_type(text: &str) -> Result<EntityTypeCode, ToolError> {
    let o = "--type";
    let f = parse_fields(
        text,
        o,
        "K:D:C:CAT:SUB or K:D:C:CAT:SUB:SPEC:EXTRA",
        &[5, 7],
    )?;
    Ok(EntityTypeCode {
        kind: fit(f[0], o, "kind")?,
        domain: fit(f[1], o, "domain")?,
        country: fit(f[2], o, "country")?,
        category: fit(f[3], o, "category")?,
        subcategory: fit(f[4], o, "subcategory")?,
        specific: fit(f.get(5).copied().unwrap_or(0), o, "specific")?,
        extra: fit(f.get(6).copied().unwrap_or(0), o, "extra")?,
    })
}

/// "E,N,U" metres per second (`--velocity`).
///
/// # Errors
/// When the text is not three finite speeds within 100 km/s.
pub fn parse_velocity(text: &str) -> Result<DVec3, ToolError> {
    let parts: Vec<&str> = text.split(',').collect();
    if parts.len() != 3 {
        return Err(ToolError::Argument(format!(
            "--velocity {text:?} must be EAST,NORTH,UP in m/s"
        )));
    }
    let mut v = [0.0; 3];
    for (slot, p) in v.iter_mut().zip(&parts) {
        let x: f64 = p.trim().parse().map_err(|_| {
            ToolError::Argument(format!("--velocity {text:?}: {p:?} is not a number"))
        })?;
        if !(x.is_finite() && x.abs() <= 1.0e5) {
            return Err(ToolError::Argument(format!(
                "--velocity {text:?}: {p:?} must be a finite speed within 100 km/s"
            )));
        }
        *slot = x;
    }
    Ok(DVec3::from_array(v))
}

/// "0x8020" or "8020" (`--appearance`).
///
/// # Errors
/// When the text is not a 32-bit hexadecimal number.
pub fn parse_appearance(text: &str) -> Result<u32, ToolError> {
    let t = text.trim();
    let digits = t
        .strip_prefix("0x")
        .or_else(|| t.strip_prefix("0X"))
        .unwrap_or(t);
    u32::from_str_radix(digits, 16).map_err(|_| {
        ToolError::Argument(format!(
            "--appearance {text:?} is not a 32-bit hexadecimal number (e.g. 0x8020)"
        ))
    })
}

/// The DIS orientation of a level body heading `heading_deg` at `position`.
fn orientation_for_heading(position: Geodetic, heading_deg: f64) -> EulerAngles {
    let frame = EnuFrame::new(position);
    let h = heading_deg.to_radians();
    let forward = frame.enu_vector_to_ecef(DVec3::new(h.sin(), h.cos(), 0.0));
    let right = frame.enu_vector_to_ecef(DVec3::new(h.cos(), -h.sin(), 0.0));
    let down = frame.enu_vector_to_ecef(DVec3::new(0.0, 0.0, -1.0));
    EulerAngles::from_body_to_world(DMat3::from_cols(forward, right, down))
}

/// What `cig dis send` sends: one entity's Entity State PDUs, as given on the command line
/// (the texts are parsed, and every value checked, by [`EntitySender::new`], in this order).
#[derive(Clone, Debug)]
pub struct SendSpec {
    /// The entity's id, "SITE:APP:ID".
    pub entity: String,
    /// Its type, "K:D:C:CAT:SUB[:SPEC:EXTRA]".
    pub entity_type: String,
    /// Latitude, degrees.
    pub lat_deg: f64,
    /// Longitude, degrees.
    pub lon_deg: f64,
    /// Height above the WGS84 ellipsoid, metres.
    pub alt_m: f64,
    /// Velocity "EAST,NORTH,UP", m/s; `None`: at rest.
    pub velocity: Option<String>,
    /// Heading, degrees clockwise from north; `None`: along the horizontal velocity, or north.
    pub heading_deg: Option<f64>,
    /// Appearance bits, hexadecimal; `None`: 0.
    pub appearance: Option<String>,
    /// Marking text (up to 11 ASCII characters).
    pub marking: String,
    /// Force ID.
    pub force_id: u8,
    /// Exercise ID.
    pub exercise: u8,
    /// Dead-reckoning algorithm 0-9.
    pub dr: u8,
    /// DIS protocol version octet (6 or 7).
    pub version: u8,
    /// PDUs to send.
    pub count: u64,
    /// Seconds between PDUs.
    pub interval_s: f64,
}

/// Builds the Entity States of a [`SendSpec`], checked.
pub struct EntitySender {
    spec: SendSpec,
    key: EntityKey,
    appearance: u32,
    version: DisVersion,
    heading_deg: f64,
    start_ecef_m: DVec3,
    velocity_ecef_mps: DVec3,
    publisher: OwnedEntityPublisher,
}

impl EntitySender {
    /// Checks the spec's ranges.
    ///
    /// # Errors
    /// One line naming the option whose value is out of range.
    pub fn new(spec: SendSpec) -> Result<EntitySender, ToolError> {
        let refuse = |message: String| Err(ToolError::Argument(message));
        let key = parse_entity_id(&spec.entity)?;
        let entity_type = parse_entity_type(&spec.entity_type)?;
        if !(spec.lat_deg.is_finite() && (-90.0..=90.0).contains(&spec.lat_deg)) {
            return refuse(format!(
                "--lat {} must be between -90 and 90 degrees",
                spec.lat_deg
            ));
        }
        if !(spec.lon_deg.is_finite() && (-180.0..=180.0).contains(&spec.lon_deg)) {
            return refuse(format!(
                "--lon {} must be between -180 and 180 degrees",
                spec.lon_deg
            ));
        }
        if !(spec.alt_m.is_finite() && (-20_000.0..=1.0e8).contains(&spec.alt_m)) {
            return refuse(format!(
                "--alt {} must be a height above the ellipsoid between -20000 and 1e8 m",
                spec.alt_m
            ));
        }
        let v = match &spec.velocity {
            Some(text) => parse_velocity(text)?,
            None => DVec3::ZERO,
        };
        let heading_deg = match spec.heading_deg {
            Some(h) if !h.is_finite() => {
                return refuse(format!("--heading-deg {h} is not a number"));
            }
            Some(h) => h,
            None if v.truncate().length() > 0.01 => v.x.atan2(v.y).to_degrees(),
            None => 0.0,
        };
        let appearance = match &spec.appearance {
            Some(text) => parse_appearance(text)?,
            None => 0,
        };
        if spec.dr > 9 {
            return refuse(format!(
                "--dr {} must be a dead-reckoning algorithm 0-9 (2: FPW)",
                spec.dr
            ));
        }
        let Some(version) = DisVersion::from_octet(spec.version) else {
            return refuse(format!("--version {} must be 6 or 7", spec.version));
        };
        if !(1..=1_000_000_000).contains(&spec.count) {
            return refuse(format!(
                "--count {} must be between 1 and 1000000000",
                spec.count
            ));
        }
        if !(spec.interval_s.is_finite() && (0.0..=3600.0).contains(&spec.interval_s)) {
            return refuse(format!(
                "--interval-s {} must be between 0 and 3600 seconds",
                spec.interval_s
            ));
        }
        if !(spec.marking.is_ascii() && spec.marking.len() <= 11) {
            return refuse(format!(
                "--marking {:?} must be at most 11 ASCII characters",
                spec.marking
            ));
        }
        let start = Geodetic::new(spec.lat_deg, spec.lon_deg, spec.alt_m);
        let publisher = OwnedEntityPublisher::new(
            key,
            entity_type,
            spec.force_id,
            &spec.marking,
            PublisherConfig {
                algorithm: DrAlgorithm::from_code(spec.dr),
                ..PublisherConfig::default()
            },
        );
        Ok(EntitySender {
            key,
            appearance,
            version,
            heading_deg,
            start_ecef_m: start.to_ecef(),
            velocity_ecef_mps: EnuFrame::new(start).enu_vector_to_ecef(v),
            publisher,
            spec,
        })
    }

    /// The checked spec.
    #[must_use]
    pub fn spec(&self) -> &SendSpec {
        &self.spec
    }

    /// The encoded Entity State `elapsed_s` after the first, stamped with `utc_s` (seconds
    /// since 1970).
    ///
    /// # Errors
    /// When the PDU cannot be encoded.
    pub fn pdu(&self, elapsed_s: f64, utc_s: f64) -> Result<Vec<u8>, ToolError> {
        let position = self.start_ecef_m + self.velocity_ecef_mps * elapsed_s;
        let here = Geodetic::from_ecef(position);
        let truth = OwnedEntityState {
            position_ecef_m: position,
            orientation: orientation_for_heading(here, self.heading_deg),
            velocity_ecef_mps: self.velocity_ecef_mps,
            acceleration_ecef_mps2: DVec3::ZERO,
            angular_velocity_body_radps: DVec3::ZERO,
            appearance: self.appearance,
        };
        let body = self.publisher.build_entity_state(&truth);
        cig_dis::encode_pdu(
            EncodeHeader {
                version: self.version,
                exercise_id: self.spec.exercise,
                timestamp: timestamp_from_seconds_past_hour(utc_s % 3600.0, false),
            },
            &DisMessage::EntityState(Box::new(body)),
        )
        .map_err(|e| ToolError::Encode(e.to_string()))
    }

    /// The line that reports the sending: PDUs, octets of the last, version, exercise, entity
    /// and destination.
    #[must_use]
    pub fn summary(&self, octets: usize, to: SocketAddr) -> String {
        let (s, key) = (&self.spec, self.key);
        format!(
            "sent {} Entity State PDU{} ({octets} octets, DIS {}, exercise {}) for {}:{}:{} to {to}",
            s.count,
            if s.count == 1 { "" } else { "s" },
            self.version.octet(),
            s.exercise,
            key.site,
            key.application,
            key.entity
        )
    }
}
#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn entity_ids_and_types_parse_and_refuse_with_the_option_named() {
        assert_eq!(
            parse_entity_id("1:2:3").unwrap(),
            EntityKey {
                site: 1,
                application: 2,
                entity: 3
            }
        );
        let t = parse_entity_type("1:1:225:1:1").unwrap();
        assert_eq!((t.kind, t.country, t.specific, t.extra), (1, 225, 0, 0));
        let t = parse_entity_type("1:2:225:1:1:3:4").unwrap();
        assert_eq!((t.domain, t.specific, t.extra), (2, 3, 4));
        for bad in ["1:2", "1:2:x", "1:2:70000", "1:2:3:4"] {
            let e = parse_entity_id(bad).unwrap_err().to_string();
            assert!(e.starts_with("--entity"), "{e}");
        }
        for bad in ["1:1:225:1", "256:1:225:1:1", "1:1:225:1:1:3", "a:b:c:d:e"] {
            let e = parse_entity_type(bad).unwrap_err().to_string();
            assert!(e.starts_with("--type"), "{e}");
        }
    }

    #[test]
    fn velocity_and_appearance_parse() {
        assert_eq!(
            parse_velocity("1.5,-2,0").unwrap(),
            DVec3::new(1.5, -2.0, 0.0)
        );
        assert!(parse_velocity("1,2").is_err());
        assert!(parse_velocity("1,nan,2").is_err());
        assert_eq!(parse_appearance("0x8020").unwrap(), 0x8020);
        assert_eq!(parse_appearance("FF").unwrap(), 0xff);
        assert!(parse_appearance("0x1_0000_0000").is_err());
        assert!(parse_appearance("smoke").is_err());
    }

    /// A level body heading east at the equator and prime meridian: forward is ECEF +Y.
    #[test]
    fn heading_east_points_the_body_east() {
        let e = orientation_for_heading(Geodetic::new(0.0, 0.0, 0.0), 90.0);
        let m = e.body_to_world();
        assert!((m.x_axis - DVec3::Y).length() < 1e-12, "{m:?}");
        let [h, p, r] = local_heading_pitch_roll_deg(m, Geodetic::new(0.0, 0.0, 0.0).to_ecef());
        assert!((h - 90.0).abs() < 1e-9 && p.abs() < 1e-9 && r.abs() < 1e-9);
    }
}
