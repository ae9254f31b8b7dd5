//! Dynamic terrain from the command line: `cig db crater`, `cig db edits`, `cig query soil`,
//! and the queries and render seeing the edits; bad input refused in one line, with nothing on
//! disk lost. Over UDP: a CIGI host's Terrain Edit Request makes a crater its HOT sees,
//! `cig serve --edits` keeps it across a restart, and a DIS Detonation makes the same crater
//! on two IGs and on a third started later.

mod common;

use cig_cigi::{
    decode_message, encode_message, ByteOrder, HatHotRequest, IgControl, Message, Packet,
    UserDefined, Version,
};
use cig_ig::terrain_edits::{CraterSize, EditRequestAction, TerrainEditRequest};
use cig_terrain::Material;
use common::{cig, free_udp_port, json_output, one_line_error, small_db, start_serve};
use serde_json::Value;
use std::net::UdpSocket;
use std::path::Path;
use std::time::{Duration, Instant};

#[test]
fn a_crater_made_at_the_command_line_is_seen_by_the_queries_and_survives_export_and_import() {
    let dir = tempfile::tempdir().expect("dir");
    let db = small_db(dir.path());
    let db_s = db.to_str().expect("utf-8 path");
    let (lat, lon) = ("35.995", "-121.215");
    let before = json_output(&["query", "hat", db_s, lat, lon])["height_m"]
        .as_f64()
        .expect("height");
    let crater = json_output(&[
        "db",
        "crater",
        db_s,
        "--at",
        &format!("{lat},{lon}"),
        "--charge-kg",
        "100",
    ]);
    let depth_m = crater["depth_m"].as_f64().expect("depth");
    let radius_m = crater["radius_m"].as_f64().expect("radius");
    // Cube-root scaling: 100 kg in soil, C_D 0.15-0.23, C_R 0.3-0.46.
    assert!(
        (0.6..1.2).contains(&depth_m) && (1.3..2.5).contains(&radius_m),
        "{crater}"
    );
    let after = json_output(&["query", "hat", db_s, lat, lon])["height_m"]
        .as_f64()
        .expect("height");
    assert!(
        ((before - after) - depth_m).abs() < 0.05,
        "{before} -> {after}, {depth_m} deep"
    );
    // From 0.3 m above the bowl's bottom, a level sightline out meets the bowl's wall, not the
    // ground it started under before the crater.
    let bottom = json_output(&["query", "hat", db_s, lat, lon])["height_ellipsoid_m"]
        .as_f64()
        .expect("height");
    let eye = format!("{}", bottom + 0.3);
    let los = json_output(&[
        "query",
        "los",
        db_s,
        lat,
        lon,
        &eye,
        "35.995",
        "-121.2146",
        &eye,
    ]);
    let range_m = los["hit"]["range_m"].as_f64().expect("blocked by the wall");
    assert!(range_m > 0.3 && range_m < 1.3 * radius_m, "{los}");
    // Export, clear, import.
    let file = dir.path().join("exercise.jsonl");
    cig()
        .args(["db", "edits", db_s, "--export"])
        .arg(&file)
        .assert()
        .success();
    cig()
        .args(["db", "edits", db_s, "--clear"])
        .assert()
        .success();
    let cleared = json_output(&["query", "hat", db_s, lat, lon])["height_m"]
        .as_f64()
        .expect("height");
    assert!((cleared - before).abs() < 1e-9);
    cig()
        .args(["db", "edits", db_s, "--import"])
        .arg(&file)
        .assert()
        .success();
    let back = json_output(&["query", "hat", db_s, lat, lon])["height_m"]
        .as_f64()
        .expect("height");
    assert!((back - after).abs() < 1e-9, "{back} vs {after}");
    let listed = json_output(&["db", "edits", db_s]);
    assert_eq!(
        listed["edits"].as_array().map(Vec::len),
        Some(1),
        "{listed}"
    );

    // Bad input: one line, nothing changed.
    let edits_file = db.join("edits.jsonl");
    let kept = std::fs::read(&edits_file).expect("edits");
    for args in [
        vec![
            "db",
            "crater",
            db_s,
            "--at",
            "35.995,-121.215",
            "--charge-kg",
            "-1",
        ],
        vec![
            "db",
            "crater",
            db_s,
            "--at",
            "35.995,-121.215",
            "--charge-kg",
            "NaN",
        ],
        vec![
            "db",
            "crater",
            db_s,
            "--at",
            "37.5,-121.215",
            "--charge-kg",
            "5",
        ],
        vec!["db", "crater", db_s, "--at", "35.995", "--charge-kg", "5"],
        vec![
            "db",
            "crater",
            db_s,
            "--at",
            "35.995,-121.215",
            "--radius-m",
            "2",
        ],
    ] {
        let out = cig().args(&args).assert().failure();
        let line = one_line_error(&out);
        assert!(line.len() > 10, "{line}");
    }
    let text = std::fs::read_to_string(&file).expect("export");
    std::fs::write(&file, &text[..text.len() - 7]).expect("truncate");
    let out = cig()
        .args(["db", "edits", db_s, "--import"])
        .arg(&file)
        .assert()
        .failure();
    assert!(one_line_error(&out).contains("truncated"));
    assert_eq!(std::fs::read(&edits_file).expect("edits"), kept);
}

#[test]
fn soil_answers_sinkage_resistance_and_go_no_go() {
    let dir = tempfile::tempdir().expect("dir");
    let db = small_db(dir.path());
    let db_s = db.to_str().expect("utf-8 path");
    let soil = json_output(&[
        "query",
        "soil",
        db_s,
        "35.995",
        "-121.215",
        "--vehicle-mass-kg",
        "62000",
        "--contact-area-m2",
        "5.8",
    ]);
    for key in ["material", "sinkage_m", "resistance_n", "trafficable"] {
        assert!(soil.get(key).is_some(), "{key}: {soil}");
    }
    let sinkage = soil["sinkage_m"].as_f64().expect("sinkage");
    assert!((0.0..=0.45).contains(&sinkage), "{soil}");
    // Wet soil sinks at least as deep (the same vehicle).
    let wet = json_output(&[
        "query",
        "soil",
        db_s,
        "35.995",
        "-121.215",
        "--vehicle-mass-kg",
        "62000",
        "--contact-area-m2",
        "5.8",
        "--wet",
    ]);
    assert!(
        wet["sinkage_m"].as_f64().expect("wet") >= sinkage - 1e-9 || soil["material"] == "sand"
    );
    for bad in [["-5", "5.8"], ["62000", "0"], ["nan", "1"]] {
        let out = cig()
            .args([
                "query",
                "soil",
                db_s,
                "35.995",
                "-121.215",
                "--vehicle-mass-kg",
            ])
            .arg(bad[0])
            .arg("--contact-area-m2")
            .arg(bad[1])
            .assert()
            .failure();
        one_line_error(&out);
    }
}

/// The test as the CIGI host of one `cig serve`: each message is IG Control and the packets
/// given, in one version and byte order.
struct Host {
    socket: UdpSocket,
    ig: String,
    version: Version,
    order: ByteOrder,
    frame: u32,
    hot_id: u16,
}

impl Host {
    fn new(ig_port: u16, version: Version, order: ByteOrder) -> Host {
        let socket = UdpSocket::bind("127.0.0.1:0").expect("socket");
        socket
            .set_read_timeout(Some(Duration::from_millis(20)))
            .expect("timeout");
        Host {
            socket,
            ig: format!("127.0.0.1:{ig_port}"),
            version,
            order,
            frame: 0,
            hot_id: 0,
        }
    }

    fn send(&mut self, packets: Vec<Packet>) {
        self.frame += 1;
        let mut all = vec![Packet::IgControl(IgControl {
            ig_mode: 1,
            host_frame_number: self.frame,
            ..IgControl::default()
        })];
        all.extend(packets);
        let mut bytes = Vec::new();
        encode_message(&Message::new(self.version, self.order, all), &mut bytes).expect("encode");
        self.socket.send_to(&bytes, &self.ig).expect("send");
    }

    fn request(&mut self, request: TerrainEditRequest) {
        let packet = request
            .to_packet(self.version, self.order)
            .expect("a Terrain Edit Request");
        self.send(vec![Packet::UserDefined(packet)]);
    }

    /// The IG's height of terrain (above mean sea level) and material at a point: an extended
    /// HAT/HOT request of a new id, sent again every 150 ms until it is answered. Everything
    /// sent before is applied before it (the IG applies a host's datagrams in order).
    fn hot(&mut self, lat_deg: f64, lon_deg: f64) -> (f64, Material) {
        self.hot_id += 1;
        let id = self.hot_id;
        let deadline = Instant::now() + Duration::from_secs(20);
        let mut buf = vec![0u8; 65536];
        while Instant::now() < deadline {
            self.send(vec![Packet::HatHotRequest(HatHotRequest {
                hat_hot_id: id,
                request_type: 2,
                lat_deg_or_x_m: lat_deg,
                lon_deg_or_y_m: lon_deg,
                alt_m_or_z_m: 1000.0,
                ..HatHotRequest::default()
            })]);
            let until = Instant::now() + Duration::from_millis(150);
            while Instant::now() < until {
                let Ok((n, _)) = self.socket.recv_from(&mut buf) else {
                    continue;
                };
                let Ok(message) = decode_message(&buf[..n]) else {
                    continue;
                };
                for packet in message.packets {
                    if let Packet::HatHotExtendedResponse(r) = packet {
                        if r.hat_hot_id == id && r.valid {
                            let material = u8::try_from(r.material_code)
                                .ok()
                                .and_then(Material::from_byte)
                                .expect("a terrain material");
                            return (r.hot_m, material);
                        }
                    }
                }
            }
        }
        panic!("no HOT answer from the IG at {} in 20 s", self.ig);
    }
}

fn crater(request_id: u16, lat_deg: f64, lon_deg: f64, size: CraterSize) -> TerrainEditRequest {
    TerrainEditRequest {
        request_id,
        action: EditRequestAction::Crater {
            lat_deg,
            lon_deg,
            size,
        },
    }
}

/// `cig serve` over `db` on `cigi_port`, answering only (no drawing), ending `idle_exit_s`
/// after its host's last message with its counters as JSON.
fn serve_args(db: &Path, cigi_port: u16, idle_exit_s: u32, extra: &[&str]) -> Vec<String> {
    let mut args: Vec<String> = vec![
        "--db".into(),
        db.display().to_string(),
        "--no-render".into(),
        "--cigi-port".into(),
        cigi_port.to_string(),
        "--idle-exit-s".into(),
        idle_exit_s.to_string(),
        "--json".into(),
    ];
    args.extend(extra.iter().map(|s| s.to_string()));
    args
}

fn finish(serve: common::Serving) -> (Value, String) {
    let (status, stdout, stderr) = serve.finish();
    assert!(status.success(), "{stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
    let summary = serde_json::from_slice(&stdout)
        .unwrap_or_else(|e| panic!("{e}: {}", String::from_utf8_lossy(&stdout)));
    (summary, stderr)
}

#[test]
fn a_cigi_hosts_terrain_edit_request_makes_a_crater_its_hot_sees_and_heals_it() {
    let started = Instant::now();
    let dir = tempfile::tempdir().expect("dir");
    let db = small_db(dir.path());
    let (lat, lon) = (35.995, -121.215);
    let port = free_udp_port();
    let serve = start_serve(&serve_args(&db, port, 3, &[]));
    let mut host = Host::new(port, Version::V3_3, ByteOrder::LittleEndian);
    let (before, material) = host.hot(lat, lon);
    host.request(crater(7, lat, lon, CraterSize::Charge { charge_kg: 100.0 }));
    // A malformed request (kind 9) and another user-defined packet: counted, nothing made.
    let mut bad = crater(8, lat, lon, CraterSize::Charge { charge_kg: 1.0 })
        .to_packet(Version::V3_3, ByteOrder::LittleEndian)
        .expect("packet");
    bad.data[0] = 9;
    host.send(vec![
        Packet::UserDefined(bad),
        Packet::UserDefined(UserDefined {
            packet_id: 201,
            data: vec![0; 6],
        }),
    ]);
    let (after, _) = host.hot(lat, lon);
    // The crater `cig db crater` makes of the same charge in the same ground (dry soil).
    let dims = cig_dynterrain::crater::dimensions(
        material,
        cig_dynterrain::soil::SoilMoisture::Dry,
        100.0,
    )
    .expect("charge")
    .expect("a crater");
    assert!(
        ((before - after) - dims.depth_m).abs() < 0.05,
        "{before} -> {after} in {material}: {dims:?}"
    );
    host.request(TerrainEditRequest {
        request_id: 7,
        action: EditRequestAction::Heal,
    });
    let (healed, _) = host.hot(lat, lon);
    assert!((healed - before).abs() < 1e-6, "{before} -> {healed}");
    let (summary, stderr) = finish(serve);
    let requests = &summary["cigi"]["terrain_edit_requests"];
    assert_eq!(
        (
            &requests["received"],
            &requests["craters_made"],
            &requests["healed"],
            &requests["refused"],
            &requests["malformed"]
        ),
        (&3.into(), &1.into(), &1.into(), &0.into(), &1.into()),
        "{summary}"
    );
    assert_eq!(summary["cigi"]["user_defined_packets"], 4, "{summary}");
    assert_eq!(
        stderr.matches("unknown kind 9").count(),
        1,
        "logged once: {stderr}"
    );
    // The database itself is not changed: its own query answers the ground of before.
    let db_s = db.to_str().expect("utf-8 path");
    let kept = json_output(&["query", "hat", db_s, &lat.to_string(), &lon.to_string()]);
    assert!((kept["height_m"].as_f64().expect("height") - before).abs() < 1e-6);
    eprintln!("took {:.1} s", started.elapsed().as_secs_f64());
}

#[test]
fn serve_edits_keeps_a_hosts_crater_across_a_restart() {
    let started = Instant::now();
    let dir = tempfile::tempdir().expect("dir");
    let db = small_db(dir.path());
    let journal = dir.path().join("exercise-edits.jsonl");
    let journal_s = journal.to_str().expect("utf-8 path");
    let (lat, lon) = (36.005, -121.205);
    let port = free_udp_port();
    let serve = start_serve(&serve_args(&db, port, 3, &["--edits", journal_s]));
    let mut host = Host::new(port, Version::V4_0, ByteOrder::BigEndian);
    let (before, _) = host.hot(lat, lon);
    host.request(crater(
        3,
        lat,
        lon,
        CraterSize::Explicit {
            radius_m: 2.5,
            depth_m: 1.0,
        },
    ));
    let (after, _) = host.hot(lat, lon);
    assert!(((before - after) - 1.0).abs() < 0.05, "{before} -> {after}");
    let (summary, _) = finish(serve);
    assert_eq!(
        summary["cigi"]["terrain_edit_requests"]["craters_made"], 1,
        "{summary}"
    );
    // The journal: its header and the crater, this IG's (site 0, application 1, outside any
    // exercise), numbered in the hosts' requests' space.
    let edits_in = |path: &Path| -> Vec<Value> {
        let text = std::fs::read_to_string(path).expect("journal");
        let lines: Vec<Value> = text
            .lines()
            .map(|l| serde_json::from_str(l).unwrap_or_else(|e| panic!("{e}: {l}")))
            .collect();
        assert_eq!(lines[0]["format"], "cig-terrain-edits", "{text}");
        lines[1..].to_vec()
    };
    let edits = edits_in(&journal);
    assert_eq!(edits.len(), 1, "{edits:?}");
    let edit = &edits[0];
    assert_eq!(edit["shape"]["kind"], "crater", "{edit}");
    assert_eq!(edit["shape"]["radius_m"], 2.5, "{edit}");
    assert_eq!(edit["shape"]["depth_m"], 1.0, "{edit}");
    assert_eq!(edit["author"]["site"], 0, "{edit}");
    assert_eq!(edit["author"]["application"], 1, "{edit}");
    assert_eq!(edit["sequence"], 0x8000_0003u32, "{edit}");
    // Restarted on the same journal: the crater is there before any request.
    let port = free_udp_port();
    let serve = start_serve(&serve_args(&db, port, 3, &["--edits", journal_s]));
    let mut host = Host::new(port, Version::V4_0, ByteOrder::BigEndian);
    let (again, _) = host.hot(lat, lon);
    assert!((again - after).abs() < 1e-6, "{after} then {again}");
    finish(serve);
    assert_eq!(edits_in(&journal).len(), 1, "not written again");
    // The journal is an edit file of the database: `cig db edits` takes it.
    let db_s = db.to_str().expect("utf-8 path");
    cig()
        .args(["db", "edits", db_s, "--import", journal_s])
        .assert()
        .success();
    let listed = json_output(&["db", "edits", db_s]);
    assert_eq!(listed["edits"][0]["sequence"], 0x8000_0003u32, "{listed}");
    // Healed by the host: the journal records the heal, and the terrain state it keeps is the
    // healed ground.
    let port = free_udp_port();
    let serve = start_serve(&serve_args(&db, port, 3, &["--edits", journal_s]));
    let mut host = Host::new(port, Version::V4_0, ByteOrder::BigEndian);
    host.request(TerrainEditRequest {
        request_id: 3,
        action: EditRequestAction::Heal,
    });
    let (healed, _) = host.hot(lat, lon);
    assert!((healed - before).abs() < 1e-6, "{before} -> {healed}");
    finish(serve);
    let lines = edits_in(&journal);
    assert_eq!(lines.len(), 2, "{lines:?}");
    assert_eq!(lines[1]["healed"]["sequence"], 0x8000_0003u32, "{lines:?}");
    // Importing adds a file's edits to the database's: cleared first, the healed journal
    // brings none.
    cig()
        .args(["db", "edits", db_s, "--clear"])
        .assert()
        .success();
    cig()
        .args(["db", "edits", db_s, "--import", journal_s])
        .assert()
        .success();
    let listed = json_output(&["db", "edits", db_s]);
    assert_eq!(
        listed["edits"].as_array().map(Vec::len),
        Some(0),
        "{listed}"
    );
    eprintln!("took {:.1} s", started.elapsed().as_secs_f64());
}

/// A 155 mm HE round (SISO-REF-010 munition 2.9.225.2.14.2, warhead 1000) bursting on the
/// ground at a point of `height_ellipsoid_m`, event 1:2:`event` of exercise 3.
fn ground_burst(lat_deg: f64, lon_deg: f64, height_ellipsoid_m: f64, event: u16) -> Vec<u8> {
    let impact = cig_dis::detonation::GroundImpact {
        event: cig_dis::detonation::EventIdentity {
            site: 1,
            application: 2,
            event_number: event,
        },
        location_ecef_m: cig_geo::Geodetic::new(lat_deg, lon_deg, height_ellipsoid_m).to_ecef(),
        munition: (2, 9, 225, 2, 14, 2, 0),
        warhead: 1000,
    };
    impact.pdu(3, 1.0).expect("encode")
}

/// Asks `host` for HOT at a point until it is below `level` (within `wait`); the answer.
fn hot_once_below(host: &mut Host, lat: f64, lon: f64, level: f64, wait: Duration) -> f64 {
    let deadline = Instant::now() + wait;
    loop {
        let (h, _) = host.hot(lat, lon);
        if h < level || Instant::now() > deadline {
            return h;
        }
        std::thread::sleep(Duration::from_millis(100));
    }
}

#[test]
fn a_detonation_makes_the_same_crater_on_two_igs_and_a_third_started_later_gets_it() {
    let started = Instant::now();
    let dir = tempfile::tempdir().expect("dir");
    let db = small_db(dir.path());
    let db_s = db.to_str().expect("utf-8 path");
    let (lat, lon) = (35.99, -121.22);
    let ground = json_output(&["query", "hat", db_s, &lat.to_string(), &lon.to_string()]);
    let before = ground["height_m"].as_f64().expect("height");
    let height_ellipsoid_m = ground["height_ellipsoid_m"].as_f64().expect("height");
    // A and B send to C's DIS port; C, started later, hears their re-announcements.
    let (dis_a, dis_b, dis_c) = (free_udp_port(), free_udp_port(), free_udp_port());
    let ig = |name: &str, application: u16, dis_port: u16, to_port: u16| {
        let scenario = dir.path().join(format!("{name}.toml"));
        std::fs::write(
            &scenario,
            format!(
                "[dis]\nexercise = 3\nsite = 1\napplication = {application}\nport = {dis_port}\n\
                 delivery = \"unicast:127.0.0.1:{to_port}\"\n"
            ),
        )
        .expect("scenario");
        let cigi_port = free_udp_port();
        let scenario_s = scenario.display().to_string();
        // Killed at the end; the idle exit only ends one a failed test left behind.
        let serve = start_serve(&serve_args(
            &db,
            cigi_port,
            60,
            &["--scenario", &scenario_s],
        ));
        (
            serve,
            Host::new(cigi_port, Version::V3_3, ByteOrder::BigEndian),
        )
    };
    let (a, mut host_a) = ig("a", 11, dis_a, dis_c);
    let (b, mut host_b) = ig("b", 12, dis_b, dis_c);
    let burst = ground_burst(lat, lon, height_ellipsoid_m, 77);
    let sender = UdpSocket::bind("127.0.0.1:0").expect("socket");
    for port in [dis_a, dis_b] {
        sender
            .send_to(&burst, format!("127.0.0.1:{port}"))
            .expect("send");
    }
    let wait = Duration::from_secs(10);
    let hot_a = hot_once_below(&mut host_a, lat, lon, before - 0.1, wait);
    let hot_b = hot_once_below(&mut host_b, lat, lon, before - 0.1, wait);
    // 155 mm: the munition table's 7 kg, a crater some decimetres deep.
    let depth = before - hot_a;
    assert!(depth > 0.1 && depth < 0.6, "{before} -> {hot_a}");
    assert!((hot_a - hot_b).abs() < 1e-3, "A {hot_a}, B {hot_b}");
    let late = Instant::now();
    let (c, mut host_c) = ig("c", 13, dis_c, dis_a);
    // Every held edit is announced again within 10 s.
    let hot_c = hot_once_below(&mut host_c, lat, lon, before - 0.1, Duration::from_secs(25));
    eprintln!(
        "C had the crater {:.1} s after starting",
        late.elapsed().as_secs_f64()
    );
    assert!((hot_c - hot_a).abs() < 1e-3, "A {hot_a}, C {hot_c}");
    for serve in [a, b, c] {
        serve.kill();
    }
    eprintln!("took {:.1} s", started.elapsed().as_secs_f64());
}
