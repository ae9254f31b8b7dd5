//! `cig bench net`: the per-frame cost of the IG's network side, and its behaviour under a flood.
//!
//! Measures (the targets are issue 6's; each has a baseline measured in the same run, so the
//! ratios survive a noisy machine; rates and times are medians of rounds):
//! * `dis_decode`: Entity State PDUs decoded per second on one core with
//!   `cig_dis::decode_pdu` over 1,024 distinct PDUs (target ≥ 1,000,000/s); baseline: copying
//!   the same bytes into a reused buffer.
//! * `dis_remote_table`: one 60 Hz frame of a [`RemoteEntityTable`] holding 10,000 remote
//!   entities (DR algorithms 1-9 in turn): apply the frame's fresh Entity States (1% of the
//!   entities a frame, 6,000 updates/s), dead-reckon and smooth every entity's pose, expire;
//!   target ≤ 1 ms. The full snapshot (geodetic position, heading/pitch/roll) is timed apart;
//!   baseline: a constant-velocity step of 10,000 flat positions.
//! * `hat_hot`: 100 HAT/HOT requests a frame (half HOT at a point, half HAT of an entity above
//!   the terrain) for 100 entities moving near the database centre, answered through
//!   `cig_terrain::QuerySession`; reported per frame and as a fraction of a 16.7 ms frame.
//! * `cigi_decode`: `cig_cigi::decode_message` of one host message of IG Control + 1,000 Entity
//!   Control packets (3.3 in both byte orders) and 1,000 Entity Position packets (4.0); the
//!   issue's 0.2 ms budget is for decoding and applying; baseline: copying the datagram.
//! * `flood` (with `--flood`): a sender thread floods a loopback [`UdpEndpoint`] with Entity
//!   States of 1,000 entities at `--flood-rate` PDUs/s for `--flood-s` seconds, while a 60 Hz
//!   frame loop drains the queue, decodes, applies to a table and dead-reckons the 1,000
//!   entities; the same loop without the flood (for min(`--flood-s`, 10) s) is the baseline.
//!   Reported: frame work time median/p99 both ways, frames per second both ways (target: the
//!   loaded rate within 10% of the unloaded one), datagrams sent/received/dropped by the queue,
//!   the queue's peak length and the process's VmRSS/VmHWM (from /proc/self/status) before and
//!   after (bounded memory: the queue holds at most its limit).
//!
//! New measures (e.g. applying a CIGI message through the IG session) are appended to
//! [`MEASURES`]; each returns its own JSON object.
//!
//! Limits: the frame loop is the IG's network work only (no rendering); the flood is one
//! sender on the same machine, so on few cores the sender and receive threads compete with the
//! frame loop for CPU — which is the point, but the figures depend on the core count.

use crate::database::{demo_or, open_session, BuildProgress};
use crate::report::{date_utc, machine, median, memory_kb, percentile};
use crate::{require, BenchError, Step};
use cig_cigi::{ByteOrder, EntityControl, EntityPosition, IgControl, Message, Packet, Version};
use cig_dis::codec::timestamp_from_seconds_past_hour;
use cig_dis::{
    DecodedPdu, DisMessage, DisVersion, DrAlgorithm, EncodeHeader, EntityKey, EntityTypeCode,
    EulerAngles, OwnedEntityPublisher, OwnedEntityState, PublisherConfig, RemoteEntityTable,
    RemoteTableConfig,
};
use cig_geo::{EnuFrame, Geodetic};
use cig_net::{EndpointConfig, UdpEndpoint};
use glam::DVec3;
use rand::{Rng, SeedableRng};
use serde_json::{json, Value};
use std::hint::black_box;
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

/// The 60 Hz frame.
const FRAME_S: f64 = 1.0 / 60.0;
/// Rounds each rate is measured in (the median is reported).
const ROUNDS: usize = 5;
const DECODE_TARGET_PER_S: f64 = 1.0e6;
const TABLE_ENTITIES: usize = 10_000;
const TABLE_TARGET_MS: f64 = 1.0;
const HAT_REQUESTS_PER_FRAME: usize = 100;
const CIGI_ENTITIES: usize = 1000;
const CIGI_APPLY_BUDGET_MS: f64 = 0.2;
const FLOOD_ENTITIES: u16 = 1000;
const FLOOD_QUEUE_LIMIT: usize = 4096;

/// What `cig bench net` measures.
#[derive(Clone, Debug)]
pub struct NetOptions {
    /// Seconds each measure may take.
    pub seconds: f64,
    /// The database of the HAT/HOT measures; `None`: the demo database "demo-db", built when
    /// missing.
    pub db: Option<PathBuf>,
    /// Also run the flood.
    pub flood: bool,
    /// Seconds of flood.
    pub flood_s: f64,
    /// PDUs per second of the flood.
    pub flood_rate: u64,
    /// The tile cache's configuration.
    pub paging: cig_terrain::PagingConfig,
    /// Cells along a tile side of the demo database, when it is built.
    pub tile_cells: u32,
    /// The commit the report names.
    pub commit: String,
}

/// What every measure may use.
struct BenchContext<'a, 'p> {
    /// The options.
    options: &'a NetOptions,
    /// Seconds each rate measurement may take in all.
    seconds: f64,
    /// Hears the demo database's build, if it is built.
    progress: &'a mut (dyn FnMut(BuildProgress<'_>) + 'p),
}

/// A measure: its name in the report and the function that runs it.
type Measure = (
    &'static str,
    fn(&mut BenchContext) -> Result<Value, BenchError>,
);

/// The measures, in report order. Append new ones here.
const MEASURES: &[Measure] = &[
    ("dis_decode", measure_dis_decode),
    ("dis_remote_table", measure_remote_table),
    ("hat_hot", measure_hat_hot),
    ("cigi_decode", measure_cigi_decode),
    ("cigi_apply", measure_cigi_apply),
    ("hat_hot_ig_frame", measure_hat_hot_ig_frame),
];

/// Runs the benchmark; `progress` hears the demo database's build, if it is built.
///
/// # Errors
/// When an option is out of range, a measure's scene cannot be built or the loopback
/// endpoints cannot open.
pub fn run(
    options: &NetOptions,
    progress: &mut dyn FnMut(BuildProgress<'_>),
) -> Result<Value, BenchError> {
    require(
        options.seconds.is_finite() && options.seconds > 0.0 && options.seconds <= 600.0,
        || format!("--seconds {} must be between 0 and 600", options.seconds),
    )?;
    require(
        options.flood_s.is_finite() && options.flood_s > 0.0 && options.flood_s <= 3600.0,
        || format!("--flood-s {} must be between 0 and 3600", options.flood_s),
    )?;
    require((1..=10_000_000).contains(&options.flood_rate), || {
        format!(
            "--flood-rate {} must be between 1 and 10000000 PDUs per second",
            options.flood_rate
        )
    })?;
    let mut context = BenchContext {
        options,
        seconds: options.seconds,
        progress,
    };
    let mut report = serde_json::Map::new();
    report.insert("machine".into(), machine());
    report.insert("date_utc".into(), json!(date_utc()));
    report.insert("commit".into(), json!(options.commit));
    report.insert("seconds_per_measure".into(), json!(options.seconds));
    for (name, measure) in MEASURES {
        tracing::info!("bench net: {name}");
        let value = measure(&mut context).step_with(|| format!("bench net: {name}"))?;
        report.insert((*name).to_string(), value);
    }
    if options.flood {
        tracing::info!("bench net: flood");
        report.insert("flood".into(), measure_flood(&context)?);
    }
    Ok(Value::Object(report))
}

fn ms(d: Duration) -> f64 {
    d.as_secs_f64() * 1e3
}

/// A deterministic scene of `n` entities around (36 N, 121 W): Entity State PDUs (encoded)
/// with DR algorithms 1-9 in turn, as a DIS 7 exercise 1 would carry them.
fn entity_state_pdus(n: usize, seed: u64) -> Result<Vec<Vec<u8>>, BenchError> {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let centre = Geodetic::new(36.0, -121.0, 0.0);
    let frame = EnuFrame::new(centre);
    let mut out = Vec::with_capacity(n);
    for i in 0..n {
        let entity = u16::try_from(i % 60_000 + 1)?;
        let algorithm = DrAlgorithm::from_code(u8::try_from(i % 9 + 1)?);
        let publisher = OwnedEntityPublisher::new(
            EntityKey {
                site: 1,
                application: 1 + u16::try_from(i / 60_000)?,
                entity,
            },
            EntityTypeCode {
                kind: 1,
                domain: 1 + u8::try_from(i % 2)?,
                country: 225,
                category: 1,
                subcategory: 1,
                specific: 0,
                extra: 0,
            },
            1,
            "BENCH",
            PublisherConfig {
                algorithm,
                ..PublisherConfig::default()
            },
        );
        let enu = DVec3::new(
            rng.gen_range(-20_000.0..20_000.0),
            rng.gen_range(-20_000.0..20_000.0),
            rng.gen_range(0.0..3000.0),
        );
        let heading: f64 = rng.gen_range(0.0..std::f64::consts::TAU);
        let speed = rng.gen_range(0.0..250.0);
        let velocity = frame.enu_vector_to_ecef(DVec3::new(
            speed * heading.sin(),
            speed * heading.cos(),
            0.0,
        ));
        let truth = OwnedEntityState {
            position_ecef_m: frame.enu_to_ecef(enu),
            orientation: EulerAngles {
                psi_rad: rng.gen_range(-3.0..3.0),
                theta_rad: rng.gen_range(-0.5..0.5),
                phi_rad: rng.gen_range(-0.5..0.5),
            },
            velocity_ecef_mps: velocity,
            acceleration_ecef_mps2: DVec3::new(0.1, -0.2, 0.05),
            angular_velocity_body_radps: DVec3::new(0.0, 0.01, 0.05),
            appearance: 0,
        };
        let body = publisher.build_entity_state(&truth);
        out.push(cig_dis::encode_pdu(
            EncodeHeader {
                version: DisVersion::V7,
                exercise_id: 1,
                timestamp: timestamp_from_seconds_past_hour(i as f64 * 0.001, false),
            },
            &DisMessage::EntityState(Box::new(body)),
        )?);
    }
    Ok(out)
}

/// Runs `round` (which does `per_call` operations) for `budget`; operations per second.
fn rate(budget: Duration, per_call: usize, mut round: impl FnMut()) -> f64 {
    let started = Instant::now();
    let mut count = 0u64;
    loop {
        round();
        count += per_call as u64;
        let elapsed = started.elapsed();
        if elapsed >= budget {
            return count as f64 / elapsed.as_secs_f64();
        }
    }
}

/// (a) Entity State decoding rate on one core.
fn measure_dis_decode(context: &mut BenchContext) -> Result<Value, BenchError> {
    let pdus = entity_state_pdus(1024, 11)?;
    // Every PDU must decode, or the rate would count failures.
    for p in &pdus {
        cig_dis::decode_pdu(p).step("a benchmark PDU does not decode")?;
    }
    let budget = Duration::from_secs_f64(context.seconds / (2.0 * ROUNDS as f64));
    let (mut decode, mut copy) = (Vec::new(), Vec::new());
    let mut buffer: Vec<u8> = Vec::with_capacity(256);
    for _ in 0..ROUNDS {
        decode.push(rate(budget, pdus.len(), || {
            for p in &pdus {
                let _ = black_box(cig_dis::decode_pdu(black_box(p)));
            }
        }));
        copy.push(rate(budget, pdus.len(), || {
            for p in &pdus {
                buffer.clear();
                buffer.extend_from_slice(black_box(p));
                black_box(&buffer);
            }
        }));
    }
    let decode_per_s = median(&decode);
    let copy_per_s = median(&copy);
    Ok(json!({
        "pdu_octets": pdus.first().map_or(0, Vec::len),
        "distinct_pdus": pdus.len(),
        "decode_per_s_one_core": decode_per_s,
        "decode_ns_per_pdu": 1e9 / decode_per_s,
        "baseline_copy_per_s_one_core": copy_per_s,
        "decode_cost_vs_copy": copy_per_s / decode_per_s,
        "target_per_s": DECODE_TARGET_PER_S,
        "meets_target": decode_per_s >= DECODE_TARGET_PER_S,
    }))
}

fn decoded(pdus: &[Vec<u8>]) -> Result<Vec<DecodedPdu>, BenchError> {
    pdus.iter()
        .map(|p| cig_dis::decode_pdu(p).step("a benchmark PDU does not decode"))
        .collect()
}

fn bench_table_config() -> RemoteTableConfig {
    RemoteTableConfig {
        // Nothing may time out while the benchmark runs: every entity is in every frame.
        timeout_s: 1.0e9,
        ..RemoteTableConfig::default()
    }
}

/// (b) One frame of the remote entity table with 10,000 entities.
fn measure_remote_table(context: &mut BenchContext) -> Result<Value, BenchError> {
    let pdus = decoded(&entity_state_pdus(TABLE_ENTITIES, 12)?)?;
    let fresh_per_frame = TABLE_ENTITIES / 100;
    let mut table = RemoteEntityTable::new(bench_table_config());
    for p in &pdus {
        table
            .apply(0.0, p)
            .map_err(|e| BenchError::Scene(format!("the table refused a benchmark PDU: {e:?}")))?;
    }
    if table.len() != TABLE_ENTITIES {
        return Err(BenchError::Scene(format!(
            "the table holds {}",
            table.len()
        )));
    }
    // Baseline data: the same number of flat positions and velocities.
    let mut flat: Vec<[f64; 6]> = (0..TABLE_ENTITIES)
        .map(|i| [i as f64, 1.0, 2.0, 3.0, 4.0, 5.0])
        .collect();
    let frames = ((context.seconds / 2.0 / FRAME_S).ceil() as usize).clamp(30, 100_000);
    let (mut frame_ms, mut baseline_ms, mut snapshot_ms) = (Vec::new(), Vec::new(), Vec::new());
    let mut next = 0usize;
    let mut checksum = 0.0;
    for f in 1..=frames {
        let now_s = f as f64 * FRAME_S;
        let started = Instant::now();
        for _ in 0..fresh_per_frame {
            let p = &pdus[next % pdus.len()];
            next += 1;
            let _ = black_box(table.apply(now_s, p));
        }
        for (_, pose) in table.poses(now_s) {
            checksum += pose.position_ecef_m.x;
        }
        black_box(table.expire(now_s));
        frame_ms.push(ms(started.elapsed()));

        let started = Instant::now();
        for p in &mut flat {
            p[0] += p[3] * FRAME_S;
            p[1] += p[4] * FRAME_S;
            p[2] += p[5] * FRAME_S;
        }
        black_box(&flat);
        baseline_ms.push(ms(started.elapsed()));

        if f % 10 == 0 {
            let started = Instant::now();
            black_box(table.snapshot(now_s));
            snapshot_ms.push(ms(started.elapsed()));
        }
    }
    black_box(checksum);
    let frame_median = median(&frame_ms);
    let baseline_median = median(&baseline_ms);
    Ok(json!({
        "entities": TABLE_ENTITIES,
        "fresh_updates_per_frame": fresh_per_frame,
        "frames": frames,
        "frame_ms_median": frame_median,
        "frame_ms_p99": percentile(&frame_ms, 0.99),
        "target_ms": TABLE_TARGET_MS,
        "meets_target": frame_median <= TABLE_TARGET_MS,
        "baseline_flat_step_ms_median": baseline_median,
        "frame_vs_baseline": frame_median / baseline_median,
        "snapshot_ms_median": median(&snapshot_ms),
    }))
}

/// The database for the HAT/HOT measure: `--db`, or the demo database (built when missing,
/// as `cig demo` does).
fn database(context: &mut BenchContext) -> Result<PathBuf, BenchError> {
    let options = context.options;
    demo_or(
        options.db.as_deref(),
        "bench net",
        options.tile_cells,
        &mut *context.progress,
    )
}

/// (c) 100 HAT/HOT requests a frame.
fn measure_hat_hot(context: &mut BenchContext) -> Result<Value, BenchError> {
    let path = database(context)?;
    let mut q = open_session(&path, &context.options.paging)?;
    let grid = q.cache().database().layout().grid;
    let moving = MovingEntities::new(&grid);
    let points_at = |t_s: f64| moving.points_at(t_s);
    let ask = |q: &mut cig_terrain::QuerySession, points: &[Geodetic]| -> Result<(), BenchError> {
        for (i, point) in points.iter().enumerate() {
            if i % 2 == 0 {
                black_box(q.hot(point.lat_deg, point.lon_deg)?);
            } else {
                black_box(q.hat_m(*point)?);
            }
        }
        Ok(())
    };
    // The first frame pages the tiles in: timed apart.
    let started = Instant::now();
    ask(&mut q, &points_at(0.0))?;
    let first_frame_ms = ms(started.elapsed());
    let frames = ((context.seconds / FRAME_S).ceil() as usize).clamp(30, 100_000);
    let mut frame_ms = Vec::with_capacity(frames);
    for f in 1..=frames {
        let points = points_at(f as f64 * FRAME_S);
        let started = Instant::now();
        ask(&mut q, &points)?;
        frame_ms.push(ms(started.elapsed()));
    }
    let frame_median = median(&frame_ms);
    let p99 = percentile(&frame_ms, 0.99);
    Ok(json!({
        "database": path.display().to_string(),
        "requests_per_frame": HAT_REQUESTS_PER_FRAME,
        "frames": frames,
        "first_frame_ms": first_frame_ms,
        "frame_ms_median": frame_median,
        "frame_ms_p99": p99,
        "fraction_of_60hz_frame_median": frame_median / (FRAME_S * 1e3),
        "fraction_of_60hz_frame_p99": p99 / (FRAME_S * 1e3),
        "answered_within_the_frame": p99 < FRAME_S * 1e3,
    }))
}

/// [`HAT_REQUESTS_PER_FRAME`] entities flying straight at 10-200 m/s, 500-3,000 m up, within 40%
/// of the database's half-size of its centre (bouncing off that box), as a host's requests
/// follow its entities.
struct MovingEntities {
    frame: EnuFrame,
    east_m: f64,
    north_m: f64,
    entities: Vec<(DVec3, DVec3)>,
}

impl MovingEntities {
    fn new(grid: &cig_terrain::GeoGrid) -> MovingEntities {
        let centre = Geodetic::new(
            0.5 * (grid.south_lat_deg + grid.north_lat_deg()),
            0.5 * (grid.west_lon_deg + grid.east_lon_deg()),
            0.0,
        );
        let frame = EnuFrame::new(centre);
        let span = frame.geodetic_to_enu(Geodetic::new(
            grid.north_lat_deg(),
            grid.east_lon_deg(),
            0.0,
        ));
        let (north_m, east_m) = (span.y.abs() * 0.4, span.x.abs() * 0.4);
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(13);
        let entities = (0..HAT_REQUESTS_PER_FRAME)
            .map(|_| {
                let p = DVec3::new(
                    rng.gen_range(-east_m..=east_m),
                    rng.gen_range(-north_m..=north_m),
                    rng.gen_range(500.0..3000.0),
                );
                let heading: f64 = rng.gen_range(0.0..std::f64::consts::TAU);
                let speed = rng.gen_range(10.0..200.0);
                (
                    p,
                    DVec3::new(speed * heading.sin(), speed * heading.cos(), 0.0),
                )
            })
            .collect();
        MovingEntities {
            frame,
            east_m,
            north_m,
            entities,
        }
    }

    fn points_at(&self, t_s: f64) -> Vec<Geodetic> {
        self.entities
            .iter()
            .map(|(p, v)| {
                // Bounce inside the box so a long run stays on the database.
                let mut e = *p + *v * t_s;
                e.x = fold(e.x, self.east_m);
                e.y = fold(e.y, self.north_m);
                self.frame.enu_to_geodetic(e)
            })
            .collect()
    }
}

/// `x` folded back into [-limit, limit] (a bounce off the box walls).
fn fold(x: f64, limit: f64) -> f64 {
    if limit <= 0.0 {
        return 0.0;
    }
    let period = 4.0 * limit;
    let u = (x + limit).rem_euclid(period);
    if u <= 2.0 * limit {
        u - limit
    } else {
        3.0 * limit - u
    }
}

/// (d) Decoding a host message of 1,000 entity controls.
fn measure_cigi_decode(context: &mut BenchContext) -> Result<Value, BenchError> {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(14);
    let mut cases = serde_json::Map::new();
    let variants = [
        ("v3_3_big_endian", Version::V3_3, ByteOrder::BigEndian),
        ("v3_3_little_endian", Version::V3_3, ByteOrder::LittleEndian),
        ("v4_0_little_endian", Version::V4_0, ByteOrder::LittleEndian),
    ];
    let budget = Duration::from_secs_f64(context.seconds / (2.0 * variants.len() as f64));
    for (name, version, order) in variants {
        let datagram = entity_datagram(version, order, &mut rng)?;
        let check = cig_cigi::decode_message(&datagram)?;
        if !(check.packets.len() == CIGI_ENTITIES + 1 && check.warnings.is_empty()) {
            return Err(BenchError::Scene(
                "the benchmark message does not decode whole".into(),
            ));
        }
        let (decode, copy) = per_call_against_copy(budget, &datagram, || {
            let _ = black_box(cig_cigi::decode_message(black_box(&datagram)));
        });
        cases.insert(
            name.to_string(),
            json!({
                "datagram_octets": datagram.len(),
                "decode_us_median": decode,
                "baseline_copy_us_median": copy,
                "decode_vs_copy": decode / copy,
                "fraction_of_apply_budget": decode / (CIGI_APPLY_BUDGET_MS * 1e3),
            }),
        );
    }
    cases.insert("entity_packets".into(), json!(CIGI_ENTITIES));
    cases.insert("apply_budget_ms".into(), json!(CIGI_APPLY_BUDGET_MS));
    Ok(Value::Object(cases))
}

/// Medians over [`ROUNDS`] rounds of `budget` in all: microseconds per call of `work`, and per
/// copy of `datagram` (the same-run baseline), interleaved.
fn per_call_against_copy(budget: Duration, datagram: &[u8], mut work: impl FnMut()) -> (f64, f64) {
    let (mut work_us, mut copy_us) = (Vec::new(), Vec::new());
    let mut buffer = Vec::with_capacity(datagram.len());
    for _ in 0..ROUNDS {
        work_us.push(1e6 / rate(budget / ROUNDS as u32, 1, &mut work));
        copy_us.push(
            1e6 / rate(budget / ROUNDS as u32, 1, || {
                buffer.clear();
                buffer.extend_from_slice(black_box(datagram));
                black_box(&buffer);
            }),
        );
    }
    (median(&work_us), median(&copy_us))
}

/// A host message of IG Control and [`CIGI_ENTITIES`] entity controls (3.3 Entity Control or
/// 4.0 Entity Position) at random places near 36 N 121 W, encoded.
fn entity_datagram(
    version: Version,
    order: ByteOrder,
    rng: &mut rand_chacha::ChaCha8Rng,
) -> Result<Vec<u8>, BenchError> {
    let mut packets = vec![Packet::IgControl(IgControl {
        ig_mode: 1,
        host_frame_number: 1,
        ..IgControl::default()
    })];
    for i in 0..CIGI_ENTITIES {
        let id = u16::try_from(i + 1)?;
        let (lat, lon, alt) = (
            rng.gen_range(35.0..37.0),
            rng.gen_range(-122.0..-120.0),
            rng.gen_range(0.0..3000.0),
        );
        let (yaw, pitch, roll) = (
            rng.gen_range(0.0..360.0),
            rng.gen_range(-10.0..10.0),
            rng.gen_range(-30.0..30.0),
        );
        packets.push(if version.major == 3 {
            Packet::EntityControl(EntityControl {
                entity_id: id,
                entity_state: 1,
                entity_type: 7,
                alpha: 255,
                yaw_deg: yaw,
                pitch_deg: pitch,
                roll_deg: roll,
                lat_deg_or_x_m: lat,
                lon_deg_or_y_m: lon,
                alt_m_or_z_m: alt,
                ..EntityControl::default()
            })
        } else {
            Packet::EntityPosition(EntityPosition {
                entity_id: id,
                yaw_deg: yaw,
                pitch_deg: pitch,
                roll_deg: roll,
                lat_deg_or_x_m: lat,
                lon_deg_or_y_m: lon,
                alt_m_or_z_m: alt,
                ..EntityPosition::default()
            })
        });
    }
    let mut datagram = Vec::new();
    cig_cigi::encode_message(&Message::new(version, order, packets), &mut datagram)?;
    Ok(datagram)
}

/// An IG world with no scenario, for the CIGI measures.
fn empty_world() -> Result<cig_ig::IgWorld, BenchError> {
    Ok(cig_ig::IgWorld::new(
        cig_ig::Scenario::from_toml("")?,
        cig_ig::WorldConfig {
            session: cig_ig::SessionConfig::default(),
            start: cig_environment::UtcTime::from_calendar(2026, 6, 21, 12, 0, 0.0)?,
            fog_mode: cig_scene::lighting::FogMode::Exponential,
            effects: cig_effects::EffectsConfig::default(),
            join_exercise: false,
        },
    )?)
}

/// (e) Applying a host message of 1,000 entity controls: decoded and applied to the IG's
/// session (entities existing: the steady state), against copying the datagram.
fn measure_cigi_apply(context: &mut BenchContext) -> Result<Value, BenchError> {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(15);
    let mut cases = serde_json::Map::new();
    let variants = [
        ("v3_3_little_endian", Version::V3_3, ByteOrder::LittleEndian),
        ("v4_0_big_endian", Version::V4_0, ByteOrder::BigEndian),
    ];
    let budget = Duration::from_secs_f64(context.seconds / (2.0 * variants.len() as f64));
    for (name, version, order) in variants {
        let datagram = entity_datagram(version, order, &mut rng)?;
        let mut world = empty_world()?;
        let started = Instant::now();
        world.receive_cigi(&datagram)?;
        let create_us = started.elapsed().as_secs_f64() * 1e6;
        if world.session().entities().len() != CIGI_ENTITIES {
            return Err(BenchError::Scene(
                "the benchmark message does not create every entity".into(),
            ));
        }
        let (apply, copy) = per_call_against_copy(budget, &datagram, || {
            let _ = black_box(world.receive_cigi(black_box(&datagram)));
        });
        cases.insert(
            name.to_string(),
            json!({
                "datagram_octets": datagram.len(),
                "first_message_creating_entities_us": create_us,
                "decode_and_apply_us_median": apply,
                "baseline_copy_us_median": copy,
                "apply_vs_copy": apply / copy,
                "fraction_of_budget": apply / (CIGI_APPLY_BUDGET_MS * 1e3),
                "meets_budget": apply <= CIGI_APPLY_BUDGET_MS * 1e3,
            }),
        );
    }
    cases.insert("entity_packets".into(), json!(CIGI_ENTITIES));
    cases.insert("budget_ms".into(), json!(CIGI_APPLY_BUDGET_MS));
    Ok(Value::Object(cases))
}

/// (f) The IG's CIGI frame with 100 HAT/HOT requests (the moving entities of (c)): the host
/// message decoded and applied,
/// the world stepped, the answers computed and the IG's message encoded, every 60 Hz frame;
/// every request is answered in the next frame's message.
fn measure_hat_hot_ig_frame(context: &mut BenchContext) -> Result<Value, BenchError> {
    let path = database(context)?;
    let mut q = open_session(&path, &context.options.paging)?;
    let grid = q.cache().database().layout().grid;
    let moving = MovingEntities::new(&grid);
    let mut world = empty_world()?;
    let frames = ((context.seconds / FRAME_S).ceil() as usize).clamp(30, 100_000);
    let (mut frame_ms, mut answered) = (Vec::with_capacity(frames), Vec::with_capacity(frames));
    let mut datagram = Vec::new();
    let mut reply = Vec::new();
    for f in 0..=frames {
        let mut packets = vec![Packet::IgControl(IgControl {
            ig_mode: 1,
            host_frame_number: f as u32,
            ..IgControl::default()
        })];
        for (i, point) in moving.points_at(f as f64 * FRAME_S).iter().enumerate() {
            packets.push(Packet::HatHotRequest(cig_cigi::HatHotRequest {
                hat_hot_id: i as u16,
                request_type: (i % 3) as u8,
                lat_deg_or_x_m: point.lat_deg,
                lon_deg_or_y_m: point.lon_deg,
                alt_m_or_z_m: point.alt_m,
                ..cig_cigi::HatHotRequest::default()
            }));
        }
        datagram.clear();
        cig_cigi::encode_message(
            &Message::new(Version::V3_3, ByteOrder::LittleEndian, packets),
            &mut datagram,
        )?;
        let started = Instant::now();
        world.receive_cigi(&datagram)?;
        world.step(FRAME_S, &mut q);
        let message = world.host_message(&mut q, f as u32);
        reply.clear();
        cig_cigi::encode_message(&message, &mut reply)?;
        let elapsed = ms(started.elapsed());
        // The first frame pages the tiles in: left out of the statistics.
        if f > 0 {
            frame_ms.push(elapsed);
            answered.push(message.packets.len() - 1);
        }
    }
    let median_ms = median(&frame_ms);
    let p99 = percentile(&frame_ms, 0.99);
    let all_answered = answered.iter().all(|n| *n == HAT_REQUESTS_PER_FRAME);
    Ok(json!({
        "database": path.display().to_string(),
        "requests_per_frame": HAT_REQUESTS_PER_FRAME,
        "frames": frames,
        "ig_cigi_frame_ms_median": median_ms,
        "ig_cigi_frame_ms_p99": p99,
        "fraction_of_60hz_frame_p99": p99 / (FRAME_S * 1e3),
        "every_request_answered_next_frame": all_answered,
    }))
}

#[derive(Default)]
struct LoopResult {
    frame_ms: Vec<f64>,
    frames: usize,
    elapsed_s: f64,
    late_frames: usize,
    datagrams: u64,
    pdus_applied: u64,
    bad_pdus: u64,
}

/// The IG's network work at 60 Hz for `duration`: drain, decode, apply, dead-reckon, expire.
fn frame_loop(
    endpoint: &UdpEndpoint,
    table: &mut RemoteEntityTable,
    epoch: Instant,
    duration: Duration,
) -> LoopResult {
    let mut r = LoopResult::default();
    let mut inbox = Vec::with_capacity(FLOOD_QUEUE_LIMIT);
    let started = Instant::now();
    let period = Duration::from_secs_f64(FRAME_S);
    let mut deadline = started;
    let mut checksum = 0.0;
    while started.elapsed() < duration {
        deadline += period;
        let work = Instant::now();
        let now_s = work.duration_since(epoch).as_secs_f64();
        inbox.clear();
        endpoint.drain(&mut inbox);
        r.datagrams += inbox.len() as u64;
        for d in &inbox {
            match cig_dis::decode_pdu(&d.bytes) {
                Ok(pdu) => {
                    let t = d.received.duration_since(epoch).as_secs_f64();
                    if table.apply(t, &pdu).is_ok() {
                        r.pdus_applied += 1;
                    }
                }
                Err(_) => r.bad_pdus += 1,
            }
        }
        for (_, pose) in table.poses(now_s) {
            checksum += pose.position_ecef_m.x;
        }
        black_box(table.expire(now_s));
        let done = Instant::now();
        r.frame_ms.push(ms(done - work));
        r.frames += 1;
        if done > deadline {
            r.late_frames += 1;
            // A late frame starts the next one at once; the schedule does not try to catch up.
            deadline = done;
        } else {
            std::thread::sleep(deadline - done);
        }
    }
    black_box(checksum);
    r.elapsed_s = started.elapsed().as_secs_f64();
    r
}

fn loop_json(r: &LoopResult) -> Value {
    json!({
        "frames": r.frames,
        "seconds": r.elapsed_s,
        "frames_per_s": r.frames as f64 / r.elapsed_s,
        "late_frames": r.late_frames,
        "frame_work_ms_median": median(&r.frame_ms),
        "frame_work_ms_p99": percentile(&r.frame_ms, 0.99),
        "datagrams_drained": r.datagrams,
        "pdus_applied": r.pdus_applied,
        "bad_pdus": r.bad_pdus,
    })
}

/// (e) The flood.
fn measure_flood(context: &BenchContext) -> Result<Value, BenchError> {
    let options = context.options;
    let (rss_start_kb, hwm_start_kb) = memory_kb();
    let receiver = UdpEndpoint::open(EndpointConfig {
        queue_limit: FLOOD_QUEUE_LIMIT,
        ..EndpointConfig::loopback("DIS", 0)
    })?;
    let sender = UdpEndpoint::open(EndpointConfig {
        destination: Some(receiver.local_addr()),
        queue_limit: 1,
        ..EndpointConfig::loopback("DIS", 0)
    })?;
    let pdus = entity_state_pdus(usize::from(FLOOD_ENTITIES), 15)?;
    let epoch = Instant::now();
    let mut table = RemoteEntityTable::new(bench_table_config());
    for p in decoded(&pdus)? {
        let _ = table.apply(0.0, &p);
    }

    let unloaded_s = options.flood_s.min(10.0);
    let unloaded = frame_loop(
        &receiver,
        &mut table,
        epoch,
        Duration::from_secs_f64(unloaded_s),
    );
    let (rss_unloaded_kb, _) = memory_kb();

    let stop = Arc::new(AtomicBool::new(false));
    let sent = Arc::new(AtomicU64::new(0));
    let send_failed = Arc::new(AtomicU64::new(0));
    let flood_rate = options.flood_rate;
    let thread = {
        let (stop, sent, send_failed) = (
            Arc::clone(&stop),
            Arc::clone(&sent),
            Arc::clone(&send_failed),
        );
        std::thread::Builder::new()
            .name("cig-bench-flood".into())
            .spawn(move || {
                let started = Instant::now();
                let mut k = 0u64;
                while !stop.load(Ordering::Relaxed) {
                    // Send what the schedule owes, then sleep a millisecond.
                    let owed = (started.elapsed().as_secs_f64() * flood_rate as f64) as u64;
                    while k < owed {
                        let p = &pdus[(k % pdus.len() as u64) as usize];
                        if sender.send(p).is_err() {
                            send_failed.fetch_add(1, Ordering::Relaxed);
                        }
                        k += 1;
                    }
                    sent.store(k, Ordering::Relaxed);
                    std::thread::sleep(Duration::from_millis(1));
                }
                sender
            })
            .step("cannot start the flood thread")?
    };
    let loaded = frame_loop(
        &receiver,
        &mut table,
        epoch,
        Duration::from_secs_f64(options.flood_s),
    );
    stop.store(true, Ordering::Relaxed);
    let sender = thread
        .join()
        .map_err(|_| BenchError::Scene("the flood thread panicked".into()))?;
    drop(sender);
    let stats = receiver.stats();
    let (rss_end_kb, hwm_end_kb) = memory_kb();
    let sent = sent.load(Ordering::Relaxed);
    let unloaded_rate = unloaded.frames as f64 / unloaded.elapsed_s;
    let loaded_rate = loaded.frames as f64 / loaded.elapsed_s;
    let rate_ratio = loaded_rate / unloaded_rate;
    let work_ratio = median(&loaded.frame_ms) / median(&unloaded.frame_ms);
    Ok(json!({
        "target_rate_pdus_per_s": flood_rate,
        "seconds": options.flood_s,
        "entities": FLOOD_ENTITIES,
        "queue_limit": FLOOD_QUEUE_LIMIT,
        "unloaded": loop_json(&unloaded),
        "loaded": loop_json(&loaded),
        "frame_rate_ratio_loaded_vs_unloaded": rate_ratio,
        "frame_work_ratio_loaded_vs_unloaded": work_ratio,
        "meets_target": rate_ratio >= 0.9,
        "sent": sent,
        "achieved_send_rate_pdus_per_s": sent as f64 / loaded.elapsed_s,
        "send_errors": send_failed.load(Ordering::Relaxed),
        "received": stats.received,
        "lost_before_the_queue": sent.saturating_sub(stats.received),
        "dropped_queue_full": stats.dropped_queue_full,
        "peak_queue_len": stats.peak_queue_len,
        "memory_kb": {
            "rss_start": rss_start_kb,
            "hwm_start": hwm_start_kb,
            "rss_after_unloaded": rss_unloaded_kb,
            "rss_end": rss_end_kb,
            "hwm_end": hwm_end_kb,
            "queue_bound": (FLOOD_QUEUE_LIMIT * 65_536) / 1024,
        },
    }))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fold_keeps_points_in_the_box_and_is_continuous() {
        for k in -1000..1000 {
            let x = k as f64 * 7.3;
            let y = fold(x, 100.0);
            assert!((-100.0..=100.0).contains(&y), "{x} -> {y}");
            assert!((fold(x + 0.01, 100.0) - y).abs() <= 0.010_001);
        }
        assert_eq!(fold(50.0, 100.0), 50.0);
        assert_eq!(fold(150.0, 100.0), 50.0);
    }

    #[test]
    fn benchmark_pdus_decode_and_fill_a_table() {
        let pdus = decoded(&entity_state_pdus(50, 1).unwrap()).unwrap();
        let mut table = RemoteEntityTable::new(bench_table_config());
        for p in &pdus {
            table.apply(0.0, p).unwrap();
        }
        assert_eq!(table.len(), 50);
    }
}
