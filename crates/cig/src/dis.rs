//! `cig dis listen` and `cig dis send`: DIS diagnostic tools on the network edge.
//!
//! `listen` opens a [`crate::net::UdpEndpoint`], walks each datagram PDU by PDU with
//! `cig_dis::decode_datagram` (IEEE 1278.1-2012 §6.2.66 header, bundled PDUs per IEEE 1278.2
//! §4.1.3) and prints one line per PDU: the header, and for the PDUs an IG uses the fields that
//! matter — Entity State (§7.2.2: ids, type, geodetic position from the ECEF location via
//! `cig-geo`, velocity in ECEF and local east/north/up, local heading/pitch/roll, appearance
//! and the obscurant effects it asks for, dead-reckoning algorithm), Fire and Detonation
//! (§7.3.2-7.3.3, with the impact effect cig would start), Remove Entity, Data Query / Set Data
//! / Data (§7.5.9-7.5.11, with cig's time and lightning datums decoded), Environmental Process
//! (§7.10.5). A datagram that does not decode prints one error line and is counted; nothing
//! ends the listener but --count, --timeout-s or a signal.
//!
//! `send` builds an Entity State with `cig_dis::OwnedEntityPublisher` (so it is exactly what
//! an IG publishes) from a geodetic position, an east/north/up velocity and a local heading,
//! and sends it --count times, moving the entity by its velocity between sends (a straight
//! ECEF line: what DR algorithm 2, FPW, predicts).
//!
//! Limits: orientation is set from the heading only (level, no roll); the timestamp is the
//! sender's UTC time past the hour marked relative (no claim of a synchronised clock).

use crate::cli::{DisListenArgs, DisSendArgs};
use crate::net::{BindTarget, Datagram, Delivery, EndpointConfig, UdpEndpoint};
use anyhow::Context;
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
use std::io::Write;
use std::net::{IpAddr, Ipv4Addr, SocketAddr, ToSocketAddrs};
use std::time::{Duration, Instant};

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

fn delivery_of(broadcast: bool, multicast: Option<&str>, option: &str) -> anyhow::Result<Delivery> {
    if let Some(group) = multicast {
        return Ok(Delivery::Multicast(crate::net::parse_multicast_group(
            group, option,
        )?));
    }
    Ok(if broadcast {
        Delivery::Broadcast
    } else {
        Delivery::Unicast
    })
}

fn bind_of(text: &str) -> anyhow::Result<BindTarget> {
    text.parse::<BindTarget>()
        .map_err(|e| anyhow::anyhow!("--bind: {e}"))
}

/// `cig dis listen`.
pub fn listen(args: &DisListenArgs) -> anyhow::Result<()> {
    let bind = bind_of(&args.bind)?;
    let delivery = delivery_of(args.broadcast, args.multicast.as_deref(), "--multicast")?;
    let timeout = match args.timeout_s {
        Some(s) => {
            anyhow::ensure!(
                s.is_finite() && s > 0.0 && s <= 1.0e7,
                "--timeout-s {s} must be a number of seconds above 0"
            );
            Some(Duration::from_secs_f64(s))
        }
        None => None,
    };
    if let Some(0) = args.count {
        return Ok(());
    }
    let endpoint = UdpEndpoint::open(EndpointConfig {
        label: "DIS",
        bind,
        port: args.port,
        delivery,
        destination: None,
        queue_limit: 65_536,
        reuse_port: delivery != Delivery::Unicast,
    })?;
    tracing::info!("DIS: listening on {}", endpoint.local_addr());
    let started = Instant::now();
    let mut printed = 0u64;
    let mut bad = 0u64;
    let stdout = std::io::stdout();
    loop {
        let wait = match timeout {
            Some(t) => match t.checked_sub(started.elapsed()) {
                Some(left) if !left.is_zero() => left.min(Duration::from_millis(250)),
                _ => break,
            },
            None => Duration::from_millis(250),
        };
        let Some(datagram) = endpoint.recv_timeout(wait) else {
            continue;
        };
        let mut out = stdout.lock();
        // `datagram_lines` stops at --count, so everything it returns is printed.
        for line in datagram_lines(&datagram, args, &mut bad, &mut printed) {
            writeln!(out, "{line}").context("writing to standard output")?;
        }
        out.flush().context("writing to standard output")?;
        if args.count.is_some_and(|n| printed >= n) {
            return Ok(());
        }
    }
    let stats = endpoint.stats();
    if let Some(n) = args.count {
        anyhow::bail!(
            "DIS: --timeout-s passed with {printed} of {n} PDUs received on {} ({bad} bad datagrams, {} datagrams in all)",
            endpoint.local_addr(),
            stats.received
        );
    }
    Ok(())
}

/// The lines to print for one datagram; counts PDUs printed and bad ones.
fn datagram_lines(
    datagram: &Datagram,
    args: &DisListenArgs,
    bad: &mut u64,
    printed: &mut u64,
) -> Vec<String> {
    let mut lines = Vec::new();
    for result in cig_dis::decode_datagram(&datagram.bytes) {
        match result {
            Ok(pdu) => {
                if args.exercise.is_some_and(|e| e != pdu.header.exercise_id) {
                    continue;
                }
                if args.count.is_some_and(|n| *printed >= n) {
                    break;
                }
                *printed += 1;
                lines.push(if args.json {
                    pdu_json(&pdu, datagram.from).to_string()
                } else {
                    pdu_line(&pdu, datagram.from)
                });
            }
            Err(e) => {
                *bad += 1;
                lines.push(if args.json {
                    json!({"error": e.to_string(), "from": datagram.from.to_string(),
                           "octets": datagram.bytes.len()})
                    .to_string()
                } else {
                    format!(
                        "bad datagram from {} ({} octets): {e}",
                        datagram.from,
                        datagram.bytes.len()
                    )
                });
            }
        }
    }
    lines
}

/// Parses "A:B:C..." into numbers, naming the option on error.
fn parse_fields(
    text: &str,
    option: &str,
    form: &str,
    counts: &[usize],
) -> anyhow::Result<Vec<u64>> {
    let parts: Vec<&str> = text.trim().split(':').collect();
    anyhow::ensure!(
        counts.contains(&parts.len()),
        "{option} {text:?} must be {form}"
    );
    parts
        .iter()
        .map(|p| {
            p.trim().parse::<u64>().map_err(|_| {
                anyhow::anyhow!("{option} {text:?}: {p:?} is not a whole number ({form})")
            })
        })
        .collect()
}

fn fit<T: TryFrom<u64>>(value: u64, option: &str, field: &str) -> anyhow::Result<T> {
    T::try_from(value).map_err(|_| {
        anyhow::anyhow!(
            "{option}: {field} {value} is out of range (at most {})",
            if std::mem::size_of::<T>() == 1 {
                u64::from(u8::MAX)
            } else {
                u64::from(u16::MAX)
            }
        )
    })
}

/// "SITE:APP:ID".
pub fn parse_entity_id(text: &str) -> anyhow::Result<EntityKey> {
    let f = parse_fields(text, "--entity", "SITE:APP:ID", &[3])?;
    Ok(EntityKey {
        site: fit(f[0], "--entity", "site")?,
        application: fit(f[1], "--entity", "application")?,
        entity: fit(f[2], "--entity", "entity")?,
    })
}

/// "K:D:C:CAT:SUB[:SPEC:EXTRA]".
pub fn parse_entity_type(text: &str) -> anyhow::Result<EntityTypeCode> {
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

/// "E,N,U" metres per second.
pub fn parse_velocity(text: &str) -> anyhow::Result<DVec3> {
    let parts: Vec<&str> = text.split(',').collect();
    anyhow::ensure!(
        parts.len() == 3,
        "--velocity {text:?} must be EAST,NORTH,UP in m/s"
    );
    let mut v = [0.0; 3];
    for (slot, p) in v.iter_mut().zip(&parts) {
        let x: f64 = p
            .trim()
            .parse()
            .map_err(|_| anyhow::anyhow!("--velocity {text:?}: {p:?} is not a number"))?;
        anyhow::ensure!(
            x.is_finite() && x.abs() <= 1.0e5,
            "--velocity {text:?}: {p:?} must be a finite speed within 100 km/s"
        );
        *slot = x;
    }
    Ok(DVec3::from_array(v))
}

/// "0x8020" or "8020".
pub fn parse_appearance(text: &str) -> anyhow::Result<u32> {
    let t = text.trim();
    let digits = t
        .strip_prefix("0x")
        .or_else(|| t.strip_prefix("0X"))
        .unwrap_or(t);
    u32::from_str_radix(digits, 16).map_err(|_| {
        anyhow::anyhow!("--appearance {text:?} is not a 32-bit hexadecimal number (e.g. 0x8020)")
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

fn destination_of(args: &DisSendArgs, endpoint: &UdpEndpoint) -> anyhow::Result<SocketAddr> {
    if let Some(host) = &args.to {
        let host = host.trim();
        if let Ok(ip) = host.parse::<IpAddr>() {
            return Ok(SocketAddr::new(ip, args.port));
        }
        let found: Vec<SocketAddr> = (host, args.port)
            .to_socket_addrs()
            .map_err(|e| anyhow::anyhow!("--to {host:?} does not resolve: {e}"))?
            .collect();
        return found
            .iter()
            .find(|a| a.is_ipv4())
            .or(found.first())
            .copied()
            .ok_or_else(|| anyhow::anyhow!("--to {host:?} resolves to no address"));
    }
    Ok(match endpoint.destination() {
        // Broadcast or multicast: the broadcast address or group, at the destination port.
        Some(d) => SocketAddr::new(d.ip(), args.port),
        None => SocketAddr::new(IpAddr::V4(Ipv4Addr::LOCALHOST), args.port),
    })
}

/// `cig dis send`.
pub fn send(args: &DisSendArgs) -> anyhow::Result<()> {
    let key = parse_entity_id(&args.entity)?;
    let entity_type = parse_entity_type(&args.entity_type)?;
    anyhow::ensure!(
        args.lat.is_finite() && (-90.0..=90.0).contains(&args.lat),
        "--lat {} must be between -90 and 90 degrees",
        args.lat
    );
    anyhow::ensure!(
        args.lon.is_finite() && (-180.0..=180.0).contains(&args.lon),
        "--lon {} must be between -180 and 180 degrees",
        args.lon
    );
    anyhow::ensure!(
        args.alt.is_finite() && (-20_000.0..=1.0e8).contains(&args.alt),
        "--alt {} must be a height above the ellipsoid between -20000 and 1e8 m",
        args.alt
    );
    let velocity_enu = match &args.velocity {
        Some(v) => parse_velocity(v)?,
        None => DVec3::ZERO,
    };
    let heading_deg = match args.heading_deg {
        Some(h) => {
            anyhow::ensure!(h.is_finite(), "--heading-deg {h} is not a number");
            h
        }
        None if velocity_enu.truncate().length() > 0.01 => {
            velocity_enu.x.atan2(velocity_enu.y).to_degrees()
        }
        None => 0.0,
    };
    let appearance = match &args.appearance {
        Some(a) => parse_appearance(a)?,
        None => 0,
    };
    anyhow::ensure!(
        args.dr <= 9,
        "--dr {} must be a dead-reckoning algorithm 0-9 (2: FPW)",
        args.dr
    );
    let version = DisVersion::from_octet(args.version)
        .ok_or_else(|| anyhow::anyhow!("--version {} must be 6 or 7", args.version))?;
    anyhow::ensure!(
        (1..=1_000_000_000).contains(&args.count),
        "--count {} must be between 1 and 1000000000",
        args.count
    );
    anyhow::ensure!(
        args.interval_s.is_finite() && (0.0..=3600.0).contains(&args.interval_s),
        "--interval-s {} must be between 0 and 3600 seconds",
        args.interval_s
    );
    anyhow::ensure!(
        args.marking.is_ascii() && args.marking.len() <= 11,
        "--marking {:?} must be at most 11 ASCII characters",
        args.marking
    );
    let bind = bind_of(&args.bind)?;
    let delivery = delivery_of(args.broadcast, args.multicast.as_deref(), "--multicast")?;
    let endpoint = UdpEndpoint::open(EndpointConfig {
        label: "DIS",
        bind,
        port: 0,
        delivery,
        destination: None,
        queue_limit: 16,
        reuse_port: false,
    })?;
    let to = destination_of(args, &endpoint)?;

    let start = Geodetic::new(args.lat, args.lon, args.alt);
    let frame = EnuFrame::new(start);
    let start_ecef = start.to_ecef();
    let velocity_ecef = frame.enu_vector_to_ecef(velocity_enu);
    let publisher = OwnedEntityPublisher::new(
        key,
        entity_type,
        args.force_id,
        &args.marking,
        PublisherConfig {
            algorithm: DrAlgorithm::from_code(args.dr),
            ..PublisherConfig::default()
        },
    );
    let started = Instant::now();
    let mut octets = 0usize;
    for k in 0..args.count {
        let due = Duration::from_secs_f64(args.interval_s * k as f64);
        if let Some(wait) = due.checked_sub(started.elapsed()) {
            std::thread::sleep(wait);
        }
        let elapsed_s = started.elapsed().as_secs_f64();
        let position = start_ecef + velocity_ecef * elapsed_s;
        let here = Geodetic::from_ecef(position);
        let truth = OwnedEntityState {
            position_ecef_m: position,
            orientation: orientation_for_heading(here, heading_deg),
            velocity_ecef_mps: velocity_ecef,
            acceleration_ecef_mps2: DVec3::ZERO,
            angular_velocity_body_radps: DVec3::ZERO,
            appearance,
        };
        let body = publisher.build_entity_state(&truth);
        let utc_s = std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map(|d| d.as_secs_f64())
            .unwrap_or(0.0);
        let bytes = cig_dis::encode_pdu(
            EncodeHeader {
                version,
                exercise_id: args.exercise,
                timestamp: timestamp_from_seconds_past_hour(utc_s % 3600.0, false),
            },
            &DisMessage::EntityState(Box::new(body)),
        )
        .context("DIS: cannot encode the Entity State")?;
        octets = bytes.len();
        endpoint
            .send_to(&bytes, to)
            .with_context(|| format!("DIS: cannot send to {to}"))?;
    }
    println!(
        "sent {} Entity State PDU{} ({octets} octets, DIS {}, exercise {}) for {}:{}:{} to {to}",
        args.count,
        if args.count == 1 { "" } else { "s" },
        version.octet(),
        args.exercise,
        key.site,
        key.application,
        key.entity
    );
    Ok(())
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
