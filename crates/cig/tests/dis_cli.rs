//! End-to-end tests of `cig dis listen` and `cig dis send` on the loopback, with each other and
//! with an independent DIS implementation: the Python package `opendis` (PyPI `opendis`);
//! and of `cig bench net`'s report. The opendis tests skip, with a message, when
//! `python3 -c "import opendis"` fails.

mod common;

use common::{cig, one_line_error};
use serde_json::Value;
use std::io::{BufRead, BufReader, Read, Write};
use std::net::UdpSocket;
use std::process::{Child, ChildStdout, Command, Stdio};
use std::sync::mpsc;
use std::time::Duration;

/// A running `cig dis listen` and the port it bound (asked for port 0, read off its log).
struct Listener {
    child: Child,
    port: u16,
}

impl Listener {
    fn start(extra: &[&str]) -> Listener {
        Listener::start_on(0, extra)
    }

    fn start_on(port: u16, extra: &[&str]) -> Listener {
        let mut child = Command::new(assert_cmd::cargo::cargo_bin("cig"))
            .args(["-v", "dis", "listen", "--timeout-s", "30", "--port"])
            .arg(port.to_string())
            .args(extra)
            .env_remove("CIG_LOG")
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .expect("cig starts");
        let stderr = child.stderr.take().expect("stderr piped");
        let (tx, rx) = mpsc::channel();
        std::thread::spawn(move || {
            let mut sent = false;
            for line in BufReader::new(stderr).lines().map_while(Result::ok) {
                if !sent {
                    if let Some(rest) = line.split("listening on UDP ").nth(1) {
                        let addr = rest.split_whitespace().next().unwrap_or("").to_string();
                        let port = addr.rsplit(':').next().unwrap_or("").parse::<u16>().ok();
                        let _ = tx.send(port);
                        sent = true;
                    }
                }
                eprintln!("listener: {line}");
            }
        });
        let port = rx
            .recv_timeout(Duration::from_secs(30))
            .expect("the listener logs its address")
            .expect("a port in the log line");
        Listener { child, port }
    }

    /// Waits for the listener to end; its stdout lines and whether it succeeded.
    fn finish(mut self) -> (Vec<String>, bool) {
        let mut out = String::new();
        let mut stdout: ChildStdout = self.child.stdout.take().expect("stdout piped");
        stdout.read_to_string(&mut out).expect("stdout readable");
        let status = self.child.wait().expect("listener ends");
        (out.lines().map(str::to_string).collect(), status.success())
    }
}

fn json_lines(lines: &[String]) -> Vec<Value> {
    lines
        .iter()
        .map(|l| serde_json::from_str(l).unwrap_or_else(|e| panic!("not JSON ({e}): {l}")))
        .collect()
}

fn close(a: f64, b: f64, tolerance: f64) -> bool {
    (a - b).abs() <= tolerance
}

fn send_args(port: u16) -> Vec<String> {
    [
        "dis",
        "send",
        "--port",
        &port.to_string(),
        "--entity",
        "11:22:33",
        "--type",
        "1:1:225:1:1:3:0",
        "--lat",
        "36.25",
        "--lon",
        "-121.5",
        "--alt",
        "412.5",
        "--velocity",
        "12,-5,0.5",
        "--appearance",
        "0x80e0",
        "--exercise",
        "7",
        "--marking",
        "TANK1",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect()
}

#[test]
fn send_and_listen_round_trip_in_json() {
    let listener = Listener::start(&["--json", "--count", "1"]);
    cig().args(send_args(listener.port)).assert().success();
    let (lines, ok) = listener.finish();
    assert!(ok, "{lines:?}");
    let v = json_lines(&lines);
    assert_eq!(v.len(), 1, "{lines:?}");
    let p = &v[0];
    assert_eq!(p["pdu_type"], 1);
    assert_eq!(p["pdu_name"], "Entity State");
    assert_eq!(p["protocol_version"], 7);
    assert_eq!(p["exercise"], 7);
    assert_eq!(p["entity_id"], "11:22:33");
    assert_eq!(p["entity_type"], "1:1:225:1:1:3:0");
    assert_eq!(p["marking"], "TANK1");
    let pos = &p["position"];
    assert!(
        close(pos["lat_deg"].as_f64().unwrap(), 36.25, 1e-7),
        "{pos}"
    );
    assert!(
        close(pos["lon_deg"].as_f64().unwrap(), -121.5, 1e-7),
        "{pos}"
    );
    assert!(close(pos["alt_m"].as_f64().unwrap(), 412.5, 1e-2), "{pos}");
    let v_enu = &p["velocity_enu_mps"];
    assert!(
        close(v_enu["east"].as_f64().unwrap(), 12.0, 1e-4),
        "{v_enu}"
    );
    assert!(
        close(v_enu["north"].as_f64().unwrap(), -5.0, 1e-4),
        "{v_enu}"
    );
    assert!(close(v_enu["up"].as_f64().unwrap(), 0.5, 1e-4), "{v_enu}");
    // Heading follows the horizontal velocity by default: atan2(12, -5).
    let heading = p["orientation"]["heading_deg"].as_f64().unwrap();
    assert!(
        close(heading, 12f64.atan2(-5.0).to_degrees(), 1e-3),
        "{heading}"
    );
    assert_eq!(p["appearance"], "0x000080e0");
    // Land platform: bit 5 smoke, 6 engine smoke, 7-8 dust (1: small), 15 flaming.
    assert_eq!(p["effects"]["smoke"], true);
    assert_eq!(p["effects"]["engine_smoke"], true);
    assert_eq!(p["effects"]["flaming"], true);
    assert_eq!(p["effects"]["dust"], "small");
    assert_eq!(p["dead_reckoning"]["algorithm"], 2);
    assert_eq!(p["dead_reckoning"]["name"], "FPW");
}

/// Two IGs on one machine share the DIS port: a broadcast (or multicast) Entity State reaches
/// both listeners.
#[test]
fn broadcast_and_multicast_reach_every_listener_sharing_the_port() {
    for mode in [vec!["--broadcast"], vec!["--multicast", "239.7.7.7"]] {
        let mut extra = vec!["--json", "--count", "1"];
        extra.extend(&mode);
        let first = Listener::start(&extra);
        let second = Listener::start_on(first.port, &extra);
        assert_eq!(first.port, second.port);
        let sent = cig().args(send_args(first.port)).args(&mode).assert();
        if !sent.get_output().status.success() {
            eprintln!(
                "SKIPPED {mode:?}: the kernel refuses it on the loopback: {}",
                String::from_utf8_lossy(&sent.get_output().stderr)
            );
            continue;
        }
        for listener in [first, second] {
            let (lines, ok) = listener.finish();
            assert!(ok, "{mode:?}: {lines:?}");
            let v = json_lines(&lines);
            assert_eq!(v[0]["entity_id"], "11:22:33", "{mode:?}");
        }
    }
}

#[test]
fn listen_prints_readable_lines_filters_exercises_and_survives_garbage() {
    let listener = Listener::start(&["--count", "2", "--exercise", "7"]);
    let garbage = UdpSocket::bind("127.0.0.1:0").unwrap();
    let to = format!("127.0.0.1:{}", listener.port);
    garbage.send_to(b"\x07\x01\x01\x01garbage", &to).unwrap();
    garbage.send_to(&[0xff; 40], &to).unwrap();
    let mut args = send_args(listener.port);
    // Another exercise first: filtered out.
    let at = args.iter().position(|a| a == "7").unwrap();
    args[at] = "8".into();
    cig().args(&args).assert().success();
    cig()
        .args(send_args(listener.port))
        .args([
            "--dr",
            "4",
            "--version",
            "6",
            "--count",
            "2",
            "--interval-s",
            "0.05",
        ])
        .assert()
        .success();
    let (lines, ok) = listener.finish();
    assert!(ok, "{lines:?}");
    let bad: Vec<&String> = lines
        .iter()
        .filter(|l| l.starts_with("bad datagram"))
        .collect();
    let good: Vec<&String> = lines
        .iter()
        .filter(|l| l.starts_with("Entity State"))
        .collect();
    assert_eq!(bad.len(), 2, "{lines:?}");
    assert_eq!(good.len(), 2, "{lines:?}");
    for l in good {
        assert!(l.contains("v6 exercise 7"), "{l}");
        assert!(
            l.contains("11:22:33") && l.contains("1:1:225:1:1:3:0"),
            "{l}"
        );
        assert!(l.contains("DR 4 RVW"), "{l}");
        assert!(l.contains("smoke,engine-smoke,flaming,dust-small"), "{l}");
    }
}

#[test]
fn bad_datagrams_are_json_error_lines() {
    let listener = Listener::start(&["--json", "--count", "1"]);
    let s = UdpSocket::bind("127.0.0.1:0").unwrap();
    let to = format!("127.0.0.1:{}", listener.port);
    // Truncated header, wrong version, declared length beyond the datagram.
    s.send_to(&[7, 1, 1], &to).unwrap();
    s.send_to(&[5, 1, 1, 1, 0, 0, 0, 0, 0, 12, 0, 0], &to)
        .unwrap();
    s.send_to(&[7, 1, 1, 1, 0, 0, 0, 0, 0, 200, 0, 0], &to)
        .unwrap();
    cig().args(send_args(listener.port)).assert().success();
    let (lines, ok) = listener.finish();
    assert!(ok);
    let v = json_lines(&lines);
    assert_eq!(v.len(), 4, "{lines:?}");
    for e in &v[..3] {
        assert!(e["error"].is_string(), "{e}");
    }
    assert!(
        v[0]["error"].as_str().unwrap().contains("header"),
        "{}",
        v[0]
    );
    assert!(
        v[1]["error"].as_str().unwrap().contains("version 5"),
        "{}",
        v[1]
    );
    assert_eq!(v[3]["entity_id"], "11:22:33");
}

#[test]
fn listen_times_out_with_a_one_line_error_when_count_is_not_reached() {
    let out = cig()
        .args([
            "dis",
            "listen",
            "--port",
            "0",
            "--count",
            "1",
            "--timeout-s",
            "0.3",
        ])
        .assert()
        .failure();
    let line = one_line_error(&out);
    assert!(line.contains("0 of 1 PDUs"), "{line}");
}

#[test]
fn bad_cli_values_are_one_line_errors_naming_the_option() {
    let base = |extra: &[&str]| {
        let mut a: Vec<String> = send_args(9).into_iter().collect();
        for pair in extra.chunks(2) {
            if let Some(i) = a.iter().position(|x| x == pair[0]) {
                a[i + 1] = pair[1].to_string();
            } else {
                a.extend(pair.iter().map(|s| s.to_string()));
            }
        }
        a
    };
    let cases: Vec<(Vec<String>, &str)> = vec![
        (base(&["--entity", "1:2"]), "--entity"),
        (base(&["--entity", "1:2:99999"]), "--entity"),
        (base(&["--type", "1:1:225"]), "--type"),
        (base(&["--type", "1:1:225:1:1:3"]), "--type"),
        (base(&["--lat", "91"]), "--lat"),
        (base(&["--lon", "-181"]), "--lon"),
        (base(&["--lat", "north"]), "--lat"),
        (base(&["--alt", "NaN"]), "--alt"),
        (base(&["--velocity", "1,2"]), "--velocity"),
        (base(&["--velocity", "1,x,2"]), "--velocity"),
        (base(&["--appearance", "smoke"]), "--appearance"),
        (base(&["--dr", "12"]), "--dr"),
        (base(&["--version", "5"]), "--version"),
        (base(&["--count", "0"]), "--count"),
        (base(&["--interval-s", "-1"]), "--interval-s"),
        (base(&["--exercise", "300"]), "--exercise"),
        (base(&["--multicast", "10.0.0.1"]), "--multicast"),
        (base(&["--multicast", "group"]), "--multicast"),
        (base(&["--bind", "no such thing"]), "--bind"),
        (base(&["--marking", "MUCH TOO LONG"]), "--marking"),
        (base(&["--heading-deg", "inf"]), "--heading-deg"),
    ];
    for (args, option) in cases {
        let out = cig().args(&args).assert().failure();
        let line = one_line_error(&out);
        assert!(line.contains(option), "{option}: {line}");
    }
    let out = cig()
        .args(["dis", "listen", "--port", "0", "--bind", "nosuchif0"])
        .assert()
        .failure();
    let line = one_line_error(&out);
    assert!(line.contains("nosuchif0"), "{line}");
    let out = cig()
        .args(["dis", "listen", "--port", "0", "--timeout-s", "-2"])
        .assert()
        .failure();
    assert!(one_line_error(&out).contains("--timeout-s"));
}

// ---------------------------------------------------------------------------------------------
// Interoperation with opendis.

const PREAMBLE: &str = r"
import sys, json, math, socket
from io import BytesIO
from opendis.DataOutputStream import DataOutputStream
from opendis.PduFactory import createPdu
from opendis.dis7 import *

def finish(pdu, pdu_type, family):
    pdu.pduType = pdu_type
    pdu.protocolFamily = family
    pdu.protocolVersion = 7
    pdu.exerciseID = 4
    pdu.pduStatus = 0
    buf = BytesIO()
    pdu.serialize(DataOutputStream(buf))
    data = bytearray(buf.getvalue())
    data[8:10] = len(data).to_bytes(2, 'big')
    return bytes(data)

# WGS84 geodetic to ECEF and the local east/north/up axes, written here independently of cig.
A = 6378137.0
F = 1.0 / 298.257223563
E2 = F * (2.0 - F)
def ecef(lat, lon, h):
    p, l = math.radians(lat), math.radians(lon)
    n = A / math.sqrt(1.0 - E2 * math.sin(p) ** 2)
    return ((n + h) * math.cos(p) * math.cos(l), (n + h) * math.cos(p) * math.sin(l),
            (n * (1.0 - E2) + h) * math.sin(p))
def enu_axes(lat, lon):
    p, l = math.radians(lat), math.radians(lon)
    e = (-math.sin(l), math.cos(l), 0.0)
    n = (-math.sin(p) * math.cos(l), -math.sin(p) * math.sin(l), math.cos(p))
    u = (math.cos(p) * math.cos(l), math.cos(p) * math.sin(l), math.sin(p))
    return e, n, u
";

fn python_available() -> bool {
    let ok = Command::new("python3")
        .args(["-c", "import opendis"])
        .output()
        .map(|o| o.status.success())
        .unwrap_or(false);
    if !ok {
        eprintln!(
            "SKIPPED: python3 with the `opendis` package (pip install opendis) is not available"
        );
    }
    ok
}

/// Writes the script to a temporary file and starts python on it.
fn python(script: &str, args: &[&str]) -> (Child, tempfile::NamedTempFile) {
    let mut file = tempfile::Builder::new()
        .suffix(".py")
        .tempfile()
        .expect("temp file");
    write!(file, "{PREAMBLE}\n{script}").expect("script written");
    let child = Command::new("python3")
        .arg(file.path())
        .args(args)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("python3 starts");
    (child, file)
}

fn python_output(child: Child) -> String {
    let out = child.wait_with_output().expect("python ends");
    assert!(
        out.status.success(),
        "python failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout).expect("utf-8")
}

#[test]
fn opendis_entity_state_and_detonation_are_decoded_by_listen() {
    if !python_available() {
        return;
    }
    let listener = Listener::start(&["--json", "--count", "2"]);
    let script = r"
port = int(sys.argv[1])
lat, lon, h = 35.75, -120.875, 1234.5
p = EntityStatePdu()
p.entityID = EntityID(41, 42, 43)
t = p.entityType
t.entityKind, t.domain, t.country, t.category, t.subcategory, t.specific, t.extra = 1, 2, 225, 1, 5, 6, 7
x, y, z = ecef(lat, lon, h)
p.entityLocation = Vector3Double(x, y, z)
e, n, u = enu_axes(lat, lon)
v = [30.0 * e[i] + 40.0 * n[i] - 2.0 * u[i] for i in range(3)]
p.entityLinearVelocity = Vector3Float(v[0], v[1], v[2])
p.entityAppearance = (1 << 6)
p.capabilities = 0
p.deadReckoningParameters.deadReckoningAlgorithm = 3
p.marking.characterSet = 1
p.marking.setString('PEER')
es = finish(p, 1, 1)
d = DetonationPdu()
d.firingEntityID = EntityID(41, 42, 43)
d.targetEntityID = EntityID(0, 0, 0)
d.explodingEntityID = EntityID(41, 42, 44)
d.eventID.simulationAddress.site = 41
d.eventID.simulationAddress.application = 42
d.eventID.eventNumber = 977
dx, dy, dz = ecef(35.7, -120.8, 200.0)
d.location = Vector3Double(dx, dy, dz)
d.velocity = Vector3Float(0.0, 0.0, -300.0)
d.detonationResult = 5
det = finish(d, 3, 2)
s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
s.sendto(es, ('127.0.0.1', port))
s.sendto(det, ('127.0.0.1', port))
print('sent')
";
    let port = listener.port.to_string();
    let (child, _file) = python(script, &[&port]);
    assert_eq!(python_output(child).trim(), "sent");
    let (lines, ok) = listener.finish();
    assert!(ok, "{lines:?}");
    let v = json_lines(&lines);
    assert_eq!(v.len(), 2, "{lines:?}");
    let es = &v[0];
    assert_eq!(es["pdu_name"], "Entity State");
    assert_eq!(es["exercise"], 4);
    assert_eq!(es["entity_id"], "41:42:43");
    assert_eq!(es["entity_type"], "1:2:225:1:5:6:7");
    assert_eq!(es["marking"], "PEER");
    assert!(close(
        es["position"]["lat_deg"].as_f64().unwrap(),
        35.75,
        1e-9
    ));
    assert!(close(
        es["position"]["lon_deg"].as_f64().unwrap(),
        -120.875,
        1e-9
    ));
    assert!(close(
        es["position"]["alt_m"].as_f64().unwrap(),
        1234.5,
        1e-4
    ));
    let venu = &es["velocity_enu_mps"];
    assert!(close(venu["east"].as_f64().unwrap(), 30.0, 1e-4), "{venu}");
    assert!(close(venu["north"].as_f64().unwrap(), 40.0, 1e-4), "{venu}");
    assert!(close(venu["up"].as_f64().unwrap(), -2.0, 1e-4), "{venu}");
    assert_eq!(es["effects"]["engine_smoke"], true);
    assert_eq!(es["effects"]["smoke"], false);
    assert_eq!(es["dead_reckoning"]["name"], "RPW");
    let det = &v[1];
    assert_eq!(det["pdu_name"], "Detonation");
    assert_eq!(det["event_id"], "41:42:977");
    assert_eq!(det["source_entity_id"], "41:42:43");
    assert_eq!(det["exploding_entity_id"], "41:42:44");
    assert_eq!(det["result"]["code"], 5);
    assert!(close(
        det["position"]["lat_deg"].as_f64().unwrap(),
        35.7,
        1e-9
    ));
    assert!(close(
        det["position"]["lon_deg"].as_f64().unwrap(),
        -120.8,
        1e-9
    ));
    assert!(close(
        det["position"]["alt_m"].as_f64().unwrap(),
        200.0,
        1e-4
    ));
}

#[test]
fn cig_dis_send_is_parsed_by_opendis() {
    if !python_available() {
        return;
    }
    let script = r"
s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
s.bind(('127.0.0.1', 0))
s.settimeout(30)
print(s.getsockname()[1], flush=True)
data, _ = s.recvfrom(65536)
p = createPdu(data)
lat, lon, h = 36.25, -121.5, 412.5
want = ecef(lat, lon, h)
e, n, u = enu_axes(lat, lon)
vel = [12.0 * e[i] - 5.0 * n[i] + 0.5 * u[i] for i in range(3)]
got_v = [p.entityLinearVelocity.x, p.entityLinearVelocity.y, p.entityLinearVelocity.z]
print(json.dumps({
    'version': p.protocolVersion, 'type': p.pduType, 'exercise': p.exerciseID,
    'length': p.length, 'octets': len(data),
    'id': [p.entityID.siteID, p.entityID.applicationID, p.entityID.entityID],
    'etype': [p.entityType.entityKind, p.entityType.domain, p.entityType.country,
              p.entityType.category, p.entityType.subcategory, p.entityType.specific,
              p.entityType.extra],
    'position_error_m': max(abs(a - b) for a, b in zip(
        [p.entityLocation.x, p.entityLocation.y, p.entityLocation.z], want)),
    'velocity_error_mps': max(abs(a - b) for a, b in zip(got_v, vel)),
    'appearance': p.entityAppearance,
    'drm': p.deadReckoningParameters.deadReckoningAlgorithm,
    'marking': p.marking.charactersString().rstrip(' ').rstrip('\x00'),
}))
";
    let (mut child, _file) = python(script, &[]);
    let mut first = String::new();
    BufReader::new(child.stdout.as_mut().expect("stdout"))
        .read_line(&mut first)
        .expect("python prints its port");
    let port: u16 = first.trim().parse().expect("a port number");
    cig().args(send_args(port)).assert().success();
    let out: Value = serde_json::from_str(python_output(child).trim()).expect("JSON from python");
    assert_eq!(out["version"], 7);
    assert_eq!(out["type"], 1);
    assert_eq!(out["exercise"], 7);
    assert_eq!(out["length"], out["octets"]);
    assert_eq!(out["id"], serde_json::json!([11, 22, 33]));
    assert_eq!(out["etype"], serde_json::json!([1, 1, 225, 1, 1, 3, 0]));
    assert!(out["position_error_m"].as_f64().unwrap() < 1e-3, "{out}");
    assert!(out["velocity_error_mps"].as_f64().unwrap() < 1e-4, "{out}");
    assert_eq!(out["appearance"], 0x80e0);
    assert_eq!(out["drm"], 2);
    assert_eq!(out["marking"], "TANK1");
}

/// A datagram bundling a time announcement (Data), an Environmental Process with a Gaussian
/// plume, a lightning strike and a Remove Entity: listen prints each PDU's own fields.
#[test]
fn listen_describes_data_environmental_and_remove_pdus() {
    use cig_dis::dis_rs::model::{EntityId, EntityType};
    use cig_dis::dis_rs::remove_entity::model::RemoveEntity;
    use cig_dis::dis_rs::BodyRaw;
    use cig_dis::{
        encode_pdu, DisMessage, DisVersion, EncodeHeader, EnvironmentGeometry, EnvironmentRecord,
        EnvironmentalProcess, GaussianPlume, LightningStrike, NodeId, TimeMessage,
    };
    let header = EncodeHeader {
        version: DisVersion::V7,
        exercise_id: 3,
        timestamp: 0,
    };
    let source = cig_geo::Geodetic::new(36.0, -121.0, 150.0).to_ecef();
    let messages = [
        TimeMessage::Announce {
            from: NodeId {
                site: 5,
                application: 6,
            },
            to: None,
            request_id: 0,
            world_time_ms: 1_718_971_200_000,
            rate: 1.0,
        }
        .to_message(),
        DisMessage::EnvironmentalProcess(EnvironmentalProcess {
            process_id: EntityId::new(5, 6, 700),
            environment_type: EntityType::default(),
            model_type: 0,
            is_last: false,
            is_active: true,
            sequence_number: 9,
            records: vec![EnvironmentRecord {
                index: 1,
                geometry: EnvironmentGeometry::GaussianPlume(GaussianPlume {
                    source_location_ecef_m: source.to_array(),
                    orientation_rad: [0.0; 3],
                    length_m: 250.0,
                    width_m: 40.0,
                    height_m: 30.0,
                    length_rate_mps: 5.0,
                    width_rate_mps: 0.5,
                    height_rate_mps: 0.25,
                    leading_edge_centroid_height_m: 20.0,
                    leading_edge_velocity_mps: [3.0, -1.0, 0.5],
                }),
            }],
        }),
        LightningStrike {
            from: NodeId {
                site: 5,
                application: 6,
            },
            position_ecef_m: source,
            seed: 0xfeed,
            intensity: 0.5,
        }
        .to_message(),
        DisMessage::RemoveEntity(
            RemoveEntity::builder()
                .with_origination_id(EntityId::new(5, 6, 0))
                .with_receiving_id(EntityId::new(1, 2, 3))
                .with_request_id(44)
                .build(),
        ),
    ];
    let mut datagram = Vec::new();
    for m in &messages {
        datagram.extend(encode_pdu(header, m).expect("encodes"));
    }
    let listener = Listener::start(&["--json", "--count", "4"]);
    UdpSocket::bind("127.0.0.1:0")
        .unwrap()
        .send_to(&datagram, ("127.0.0.1", listener.port))
        .unwrap();
    let (lines, ok) = listener.finish();
    assert!(ok, "{lines:?}");
    let v = json_lines(&lines);
    assert_eq!(v.len(), 4, "{lines:?}");
    assert_eq!(v[0]["pdu_name"], "Data");
    assert_eq!(v[0]["time_sync"]["kind"], "announce");
    assert_eq!(v[0]["time_sync"]["from"], "5:6");
    assert_eq!(v[0]["time_sync"]["world_time_utc"], "2024-06-21T12:00:00Z");
    assert_eq!(v[1]["pdu_name"], "Environmental Process");
    assert_eq!(v[1]["process_id"], "5:6:700");
    assert_eq!(v[1]["sequence_number"], 9);
    let record = &v[1]["records"][0];
    assert_eq!(record["record"], "gaussian_plume");
    assert!(close(
        record["source"]["lat_deg"].as_f64().unwrap(),
        36.0,
        1e-9
    ));
    assert!(close(
        record["source"]["alt_m"].as_f64().unwrap(),
        150.0,
        1e-4
    ));
    assert_eq!(record["length_m"], 250.0);
    assert_eq!(v[2]["lightning"]["seed"], "0x000000000000feed");
    assert!(close(
        v[2]["lightning"]["position"]["lon_deg"].as_f64().unwrap(),
        -121.0,
        1e-9
    ));
    assert_eq!(v[3]["pdu_name"], "Remove Entity");
    assert_eq!(v[3]["receiving_id"], "1:2:3");
    assert_eq!(v[3]["request_id"], 44);
}

/// The benchmark's report has every measure with sane figures (no timing assertions).
#[test]
fn bench_net_reports_every_measure_and_the_flood() {
    let dir = tempfile::tempdir().unwrap();
    let db = dir.path().join("db");
    cig()
        .args([
            "db",
            "synth",
            "--origin",
            "36,-121",
            "--size-km",
            "3",
            "--spacing-m",
            "30",
        ])
        .arg("--out")
        .arg(&db)
        .assert()
        .success();
    let out = cig()
        .args([
            "bench",
            "net",
            "--json",
            "--seconds",
            "0.5",
            "--flood",
            "--flood-s",
            "1",
        ])
        .arg("--db")
        .arg(&db)
        .assert()
        .success();
    let v: Value = serde_json::from_slice(&out.get_output().stdout).expect("one JSON report");
    for key in ["machine", "date_utc", "commit"] {
        assert!(!v[key].is_null(), "{key}");
    }
    let positive = |x: &Value, what: &str| {
        let f = x
            .as_f64()
            .unwrap_or_else(|| panic!("{what} is not a number: {x}"));
        assert!(f.is_finite() && f > 0.0, "{what} = {f}");
    };
    let d = &v["dis_decode"];
    positive(&d["decode_per_s_one_core"], "decode rate");
    positive(&d["decode_cost_vs_copy"], "decode ratio");
    assert!(d["meets_target"].is_boolean());
    let t = &v["dis_remote_table"];
    assert_eq!(t["entities"], 10_000);
    positive(&t["frame_ms_median"], "table frame");
    positive(&t["snapshot_ms_median"], "snapshot");
    let h = &v["hat_hot"];
    assert_eq!(h["requests_per_frame"], 100);
    positive(&h["frame_ms_median"], "hat frame");
    positive(&h["fraction_of_60hz_frame_median"], "hat fraction");
    let c = &v["cigi_decode"];
    for case in [
        "v3_3_big_endian",
        "v3_3_little_endian",
        "v4_0_little_endian",
    ] {
        positive(&c[case]["decode_us_median"], case);
        assert!(
            c[case]["datagram_octets"].as_u64().unwrap() > 48_000,
            "{case}"
        );
    }
    let f = &v["flood"];
    positive(&f["unloaded"]["frames_per_s"], "unloaded rate");
    positive(&f["loaded"]["frames_per_s"], "loaded rate");
    positive(&f["frame_rate_ratio_loaded_vs_unloaded"], "rate ratio");
    let sent = f["sent"].as_u64().unwrap();
    let received = f["received"].as_u64().unwrap();
    assert!(sent > 1000, "the flood sent {sent}");
    assert!(received <= sent && received > 0, "{received} of {sent}");
    assert!(f["loaded"]["pdus_applied"].as_u64().unwrap() > 0);
    assert_eq!(f["loaded"]["bad_pdus"], 0);
    assert!(f["peak_queue_len"].as_u64().unwrap() <= f["queue_limit"].as_u64().unwrap());
    assert!(f["dropped_queue_full"].is_u64());
    positive(&f["memory_kb"]["rss_end"], "RSS");
    positive(&f["memory_kb"]["hwm_end"], "HWM");
}

#[test]
fn bench_net_refuses_bad_durations() {
    for (option, value) in [
        ("--seconds", "0"),
        ("--flood-s", "-1"),
        ("--flood-rate", "0"),
    ] {
        let out = cig()
            .args(["bench", "net", "--flood", option, value])
            .assert()
            .failure();
        assert!(one_line_error(&out).contains(option), "{option}");
    }
}
