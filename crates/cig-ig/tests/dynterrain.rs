//! Dynamic terrain in a DIS exercise: a Detonation makes the same crater on every IG, a late
//! joiner gets the earlier edits from the others' re-announcements, and edits survive their
//! Object State PDUs.

use cig_dis::codec::{encode_pdu, DisVersion, EncodeHeader};
use cig_effects::EffectsConfig;
use cig_environment::UtcTime;
use cig_geo::Geodetic;
use cig_ig::terrain_edits::{edit_of_pdu, pdu_of_edit};
use cig_ig::{IgWorld, Scenario, SessionConfig, WorldConfig};
use cig_scene::lighting::FogMode;
use cig_terrain::build::build_pyramid;
use cig_terrain::database::{GeoidGrid, Manifest, MemoryTileStore, TerrainDatabase};
use cig_terrain::edits::{EditAuthor, EditShape, GeoPoint, SpoilSide, TerrainEdit};
use cig_terrain::material::Material;
use cig_terrain::raster::{GeoGrid, Raster};
use cig_terrain::{PagingConfig, QuerySession, TileCache};
use std::sync::Arc;

const SOUTH: f64 = 36.0;
const WEST: f64 = -121.0;

/// 129 x 129 posts 30 m apart, gently sloping, sand in the west half and paved road east.
fn query() -> QuerySession {
    let (n, e) = cig_geo::metres_per_degree(SOUTH);
    let grid = GeoGrid {
        south_lat_deg: SOUTH,
        west_lon_deg: WEST,
        dlat_deg: 30.0 / n,
        dlon_deg: 30.0 / e,
        rows: 129,
        cols: 129,
    };
    let elevation_m = (0..grid.len())
        .map(|k| 100.0 + 0.05 * (k % grid.cols) as f32 + 0.03 * (k / grid.cols) as f32)
        .collect();
    let material = (0..grid.len())
        .map(|k| {
            if k % grid.cols < 64 {
                Material::Sand
            } else {
                Material::PavedRoad
            }
        })
        .collect();
    let raster = Raster {
        grid,
        elevation_m,
        material: Some(material),
    };
    let store = Arc::new(MemoryTileStore::new());
    let summary = build_pyramid::<cig_terrain::build::BuildError>(&raster, 64, &mut |t| {
        store.insert(t.key, t.encode());
        Ok(())
    })
    .expect("build");
    let mut geoid = GeoidGrid::zero();
    geoid.undulation_m.iter_mut().for_each(|v| *v = -30.0);
    let manifest = Manifest::from_build(&summary, geoid, 0, vec!["test".into()]);
    let db = TerrainDatabase::new(manifest, store as Arc<dyn cig_terrain::TileStore>).expect("db");
    let cache = TileCache::new(Arc::new(db), PagingConfig::default()).expect("cache");
    QuerySession::new(Arc::new(cache))
}

fn at(row: f64, col: f64) -> (f64, f64) {
    let (n, e) = cig_geo::metres_per_degree(SOUTH);
    (SOUTH + row * 30.0 / n, WEST + col * 30.0 / e)
}

fn world(application: u16) -> IgWorld {
    world_with(application, "")
}

/// [`world`] with more lines in its `[dis]` section.
fn world_with(application: u16, dis_lines: &str) -> IgWorld {
    let scenario = format!(
        "start_time = \"2026-06-21T12:00:00Z\"\n[dis]\nsite = 1\napplication = {application}\nexercise = 3\n{}{dis_lines}",
        if application == 10 { "time_master = true\n" } else { "" }
    );
    IgWorld::new(
        Scenario::from_toml(&scenario).expect("scenario"),
        WorldConfig {
            session: SessionConfig::default(),
            start: UtcTime::from_calendar(2026, 6, 21, 12, 0, 0.0).expect("time"),
            fog_mode: FogMode::Exponential,
            effects: EffectsConfig::default(),
            join_exercise: true,
        },
    )
    .expect("world")
}

/// A 155 mm HE round (SISO-REF-010 2.9.225.2.14.2) bursting `above_m` over the ground.
fn shell(q: &mut QuerySession, event: u16, row: f64, col: f64, above_m: f64) -> Vec<u8> {
    let (lat, lon) = at(row, col);
    let ground = q.hot(lat, lon).expect("hot").height_ellipsoid_m();
    let impact = cig_dis::detonation::GroundImpact {
        event: cig_dis::detonation::EventIdentity {
            site: 7,
            application: 8,
            event_number: event,
        },
        location_ecef_m: Geodetic::new(lat, lon, ground + above_m).to_ecef(),
        munition: (2, 9, 225, 2, 14, 2, 0),
        warhead: 1000,
    };
    impact.pdu(3, 1.0).expect("encode")
}

#[test]
fn a_detonation_makes_the_same_crater_on_every_ig_and_a_late_joiner_gets_it() {
    let (mut qa, mut qb, mut qc) = (query(), query(), query());
    let (mut a, mut b, mut c) = (world(10), world(11), world(12));
    let sand = shell(&mut qa, 41, 60.3, 30.6, 0.0);
    let road = shell(&mut qa, 42, 60.3, 100.4, 0.0);
    let air = shell(&mut qa, 43, 80.0, 30.0, 40.0);
    let (lat, lon) = at(60.3, 30.6);
    let (road_lat, road_lon) = at(60.3, 100.4);
    let before = qa.hot(lat, lon).expect("hot").height_msl_m;
    let before_road = qa.hot(road_lat, road_lon).expect("hot").height_msl_m;
    for frame in 0..60 * 12 {
        if frame == 5 {
            for pdu in [&sand, &road, &air] {
                a.receive_dis(pdu, &mut qa);
            }
        }
        if frame == 9 {
            for pdu in [&sand, &road, &air] {
                b.receive_dis(pdu, &mut qb);
            }
        }
        a.step(1.0 / 60.0, &mut qa);
        b.step(1.0 / 60.0, &mut qb);
        c.step(1.0 / 60.0, &mut qc);
        // C joins after the shots: it hears only A's and B's re-announcements.
        let from_a = a.take_dis_outgoing();
        let from_b = b.take_dis_outgoing();
        for d in from_a.iter().chain(&from_b) {
            if frame > 60 {
                c.receive_dis(d, &mut qc);
            }
        }
        for d in from_a {
            b.receive_dis(&d, &mut qb);
        }
        for d in from_b {
            a.receive_dis(&d, &mut qa);
        }
        let _ = c.take_dis_outgoing();
    }
    let ca = a.exercise().expect("a").counters();
    assert_eq!(ca.craters_made, 2, "sand and road, no air burst: {ca:?}");
    assert!(ca.terrain_edits_sent >= 2, "{ca:?}");
    let hot = |q: &mut QuerySession, lat, lon| q.hot(lat, lon).expect("hot").height_msl_m;
    let (ha, hb, hc) = (
        hot(&mut qa, lat, lon),
        hot(&mut qb, lat, lon),
        hot(&mut qc, lat, lon),
    );
    assert!(
        (ha - hb).abs() < 1e-3 && (ha - hc).abs() < 1e-3,
        "{ha} {hb} {hc}"
    );
    // 155 mm in dry sand: the table's 7 kg, C_D 0.149: about 0.28 m deep.
    let depth = before - ha;
    assert!(depth > 0.2 && depth < 0.45, "{depth}");
    // On the paved road the crater is shallower than in the sand.
    let road_depth = before_road - hot(&mut qa, road_lat, road_lon);
    assert!(
        road_depth > 0.05 && road_depth < 0.6 * depth,
        "{road_depth} vs {depth}"
    );
    let cc = c.exercise().expect("c").counters();
    assert_eq!(cc.terrain_edits_received, 2, "{cc:?}");
    assert_eq!(cc.craters_made, 0);
    assert_eq!(qc.edits().len(), 2);
}

fn edit(shape: EditShape) -> TerrainEdit {
    TerrainEdit {
        author: EditAuthor {
            site: 4,
            application: 9,
        },
        sequence: 300,
        time_utc_s: 1.9e9,
        shape,
    }
}

#[test]
fn edits_survive_their_object_state_pdus() {
    let (lat, lon) = at(40.0, 40.0);
    let p = |dlat_m: f64, dlon_m: f64| {
        let (n, e) = cig_geo::metres_per_degree(lat);
        GeoPoint {
            lat_deg: lat + dlat_m / n,
            lon_deg: lon + dlon_m / e,
        }
    };
    let shapes = [
        EditShape::Crater {
            centre: p(0.0, 0.0),
            radius_m: 2.5,
            depth_m: 0.8,
            lip_radius_m: 3.125,
            lip_height_m: 0.2,
        },
        EditShape::Position {
            centre: p(5.0, 5.0),
            heading_deg: 35.0,
            length_m: 9.0,
            width_m: 4.5,
            depth_m: 2.2,
        },
        EditShape::Rut {
            from: p(0.0, 0.0),
            to: p(30.0, 40.0),
            width_m: 0.6,
            depth_m: 0.12,
        },
        EditShape::Ditch {
            from: p(-20.0, 0.0),
            to: p(-20.0, 80.0),
            width_m: 4.0,
            depth_m: 2.5,
            spoil: SpoilSide::Left,
        },
        EditShape::Berm {
            from: p(10.0, 0.0),
            to: p(-10.0, -50.0),
            width_m: 3.0,
            height_m: 1.8,
        },
    ];
    for shape in shapes {
        let original = edit(shape);
        let message = pdu_of_edit(&original, 70.0).expect("sent");
        // Through the bytes.
        let bytes = encode_pdu(
            EncodeHeader {
                version: DisVersion::V7,
                exercise_id: 1,
                timestamp: 0,
            },
            &message,
        )
        .expect("encode");
        let decoded = cig_dis::decode_pdu(&bytes).expect("decode");
        let back = edit_of_pdu(&decoded.message, 1.9e9).expect("read");
        assert_eq!(back.id(), original.id());
        // The same surface within a centimetre over the footprint.
        for dy in (-60..=60).step_by(3) {
            for dx in (-60..=90).step_by(3) {
                let q = p(f64::from(dy), f64::from(dx));
                let (x, y) = (
                    original.shape.delta_m(q.lat_deg, q.lon_deg),
                    back.shape.delta_m(q.lat_deg, q.lon_deg),
                );
                assert!((x - y).abs() < 0.01, "{:?}: {x} vs {y}", original.shape);
            }
        }
    }
    // A crater named by its Detonation's event keeps that name through its PDU, apart from an
    // object of the same number.
    let mut named = edit(EditShape::Crater {
        centre: p(0.0, 0.0),
        radius_m: 1.0,
        depth_m: 0.3,
        lip_radius_m: 1.25,
        lip_height_m: 0.075,
    });
    named.sequence = cig_ig::terrain_edits::DETONATION_SEQUENCES | 77;
    let back = edit_of_pdu(&pdu_of_edit(&named, 0.0).expect("sent"), 0.0).expect("read");
    assert_eq!(back.sequence, named.sequence);
    named.sequence = 77;
    let back = edit_of_pdu(&pdu_of_edit(&named, 0.0).expect("sent"), 0.0).expect("read");
    assert_eq!(back.sequence, 77);
    // A height patch is not sent; hostile PDUs are refused by the codec.
    let patch = edit(EditShape::HeightPatch {
        south_west: p(0.0, 0.0),
        spacing_m: 1.0,
        cols: 2,
        rows: 2,
        deltas_m: vec![0.0; 4],
    });
    assert!(pdu_of_edit(&patch, 0.0).is_none());
}

#[test]
fn a_tank_driven_across_sand_onto_a_paved_road_leaves_ruts_only_in_the_sand() {
    let mut q = query();
    // From column 40 (sand) east to column 90 (paved road) along row 50, at 10 m/s.
    let (lat, lon) = at(50.0, 40.0);
    let (_, lon_end) = at(50.0, 90.0);
    let scenario = format!(
        "start_time = \"2026-06-21T12:00:00Z\"\n\
         [[entities]]\nid = 1\nmodel = \"tank\"\nlat_deg = {lat}\nlon_deg = {lon}\n\
         clamp = \"height_and_attitude\"\nspeed_mps = 10.0\npath = [[{lat}, {lon_end}]]\n"
    );
    let mut w = IgWorld::new(
        Scenario::from_toml(&scenario).expect("scenario"),
        WorldConfig {
            session: SessionConfig::default(),
            start: UtcTime::from_calendar(2026, 6, 21, 12, 0, 0.0).expect("time"),
            fog_mode: FogMode::Exponential,
            effects: EffectsConfig::default(),
            join_exercise: false,
        },
    )
    .expect("world");
    for _ in 0..60 * 160 {
        w.step(1.0 / 60.0, &mut q);
    }
    let edits = Arc::clone(q.edits());
    let ruts: Vec<&TerrainEdit> = edits.edits().collect();
    assert!(ruts.len() >= 10, "{} ruts", ruts.len());
    let (_, lon_road) = at(50.0, 64.0);
    for r in &ruts {
        let EditShape::Rut {
            from, to, depth_m, ..
        } = &r.shape
        else {
            panic!("{:?}", r.shape);
        };
        // 62 t on 5.8 m2 in dry sand: a rut of some centimetres.
        assert!(*depth_m > 0.02 && *depth_m < 0.3, "{depth_m}");
        assert!(
            from.lon_deg.min(to.lon_deg) < lon_road,
            "a rut on the road: {r:?}"
        );
    }
    // HOT sees the ruts: somewhere under the tracks the ground is lower than before.
    let track = ruts[2].shape.anchor();
    let mut fresh = query();
    let before = fresh
        .hot(track.lat_deg, track.lon_deg)
        .expect("hot")
        .height_msl_m;
    let after = q
        .hot(track.lat_deg, track.lon_deg)
        .expect("hot")
        .height_msl_m;
    assert!(after < before - 0.01, "{before} -> {after}");
}

/// A host message: IG Control and these packets, in `version` and `order`.
fn host_datagram(
    version: cig_cigi::Version,
    order: cig_cigi::ByteOrder,
    packets: Vec<cig_cigi::Packet>,
) -> Vec<u8> {
    let mut all = vec![cig_cigi::Packet::IgControl(cig_cigi::IgControl {
        ig_mode: 1,
        ..cig_cigi::IgControl::default()
    })];
    all.extend(packets);
    let mut bytes = Vec::new();
    cig_cigi::encode_message(&cig_cigi::Message::new(version, order, all), &mut bytes)
        .expect("encode");
    bytes
}

#[test]
fn a_hosts_crater_requests_make_craters_every_ig_of_the_exercise_sees_and_heal_here() {
    use cig_cigi::{ByteOrder, Packet, UserDefined, Version};
    use cig_ig::terrain_edits::{CraterSize, EditRequestAction, TerrainEditRequest};
    let (mut qa, mut qb) = (query(), query());
    let (mut a, mut b) = (world(20), world(21));
    let (lat, lon) = at(60.3, 30.6);
    let (lat2, lon2) = at(70.2, 20.4);
    let hot = |q: &mut QuerySession, lat, lon| q.hot(lat, lon).expect("hot").height_msl_m;
    let (before, before2) = (hot(&mut qa, lat, lon), hot(&mut qa, lat2, lon2));
    let request = |request_id, action| TerrainEditRequest { request_id, action };
    let crater = |id, lat_deg, lon_deg, size| {
        request(
            id,
            EditRequestAction::Crater {
                lat_deg,
                lon_deg,
                size,
            },
        )
    };
    let packet = |r: TerrainEditRequest, version, order| {
        Packet::UserDefined(r.to_packet(version, order).expect("packet"))
    };
    let first = host_datagram(
        Version::V4_0,
        ByteOrder::BigEndian,
        vec![
            packet(
                crater(1, lat, lon, CraterSize::Charge { charge_kg: 100.0 }),
                Version::V4_0,
                ByteOrder::BigEndian,
            ),
            // Outside the database: refused.
            packet(
                crater(2, 37.5, lon, CraterSize::Charge { charge_kg: 5.0 }),
                Version::V4_0,
                ByteOrder::BigEndian,
            ),
            // Too short: malformed.
            Packet::UserDefined(UserDefined {
                packet_id: 0x10DC,
                data: vec![0; 28],
            }),
            // Another user packet: passed over.
            Packet::UserDefined(UserDefined {
                packet_id: 0x1234,
                data: vec![0; 4],
            }),
        ],
    );
    let second = host_datagram(
        Version::V3_3,
        ByteOrder::LittleEndian,
        vec![packet(
            crater(
                3,
                lat2,
                lon2,
                CraterSize::Explicit {
                    radius_m: 3.0,
                    depth_m: 1.25,
                },
            ),
            Version::V3_3,
            ByteOrder::LittleEndian,
        )],
    );
    for frame in 0..60 * 2 {
        if frame == 5 {
            a.receive_cigi(&first).expect("host message");
        }
        if frame == 6 {
            a.receive_cigi(&second).expect("host message");
            // The same request again: one crater.
            a.receive_cigi(&second).expect("host message");
        }
        a.step(1.0 / 60.0, &mut qa);
        b.step(1.0 / 60.0, &mut qb);
        for d in a.take_dis_outgoing() {
            b.receive_dis(&d, &mut qb);
        }
        let _ = b.take_dis_outgoing();
    }
    let counters = a.session().edit_requests().counters();
    assert_eq!(
        (
            counters.received,
            counters.craters_made,
            counters.refused,
            counters.malformed
        ),
        (5, 2, 2, 1),
        "{counters:?}"
    );
    assert_eq!(a.session().counters().user_defined_packets, 6);
    // 100 kg in dry sand: C_D 0.149, about 0.69 m deep (HOT within 5 cm of the shape: the
    // bowl is drawn on fine posts).
    let depth = before - hot(&mut qa, lat, lon);
    let dims = cig_dynterrain::crater::dimensions(
        Material::Sand,
        cig_dynterrain::soil::SoilMoisture::Dry,
        100.0,
    )
    .expect("charge")
    .expect("a crater");
    assert!((depth - dims.depth_m).abs() < 0.05, "{depth} vs {dims:?}");
    let depth2 = before2 - hot(&mut qa, lat2, lon2);
    assert!((depth2 - 1.25).abs() < 0.05, "{depth2}");
    // B got both from A's Object State PDUs: the same ground to the millimetre.
    for (lat, lon) in [(lat, lon), (lat2, lon2)] {
        let (ha, hb) = (hot(&mut qa, lat, lon), hot(&mut qb, lat, lon));
        assert!((ha - hb).abs() < 1e-3, "{ha} vs {hb}");
    }
    assert_eq!(
        b.exercise().expect("b").counters().terrain_edits_received,
        2
    );
    // Healing request 1 puts A's ground back, and B's: the heal goes out as the crater's
    // Object State deactivated.
    a.receive_cigi(&host_datagram(
        Version::V3_3,
        ByteOrder::BigEndian,
        vec![
            packet(
                request(1, EditRequestAction::Heal),
                Version::V3_3,
                ByteOrder::BigEndian,
            ),
            packet(
                request(99, EditRequestAction::Heal),
                Version::V3_3,
                ByteOrder::BigEndian,
            ),
        ],
    ))
    .expect("host message");
    a.step(1.0 / 60.0, &mut qa);
    assert!((hot(&mut qa, lat, lon) - before).abs() < 1e-9);
    let counters = a.session().edit_requests().counters();
    assert_eq!((counters.healed, counters.refused), (1, 3), "{counters:?}");
    // Both ways for 12 s (B re-announcing the crater it held until the heal came changes
    // nothing on A), then a third IG joins and gets the second crater but not the healed one.
    let mut qc = query();
    let mut c = world(22);
    for frame in 0..60 * 24 {
        a.step(1.0 / 60.0, &mut qa);
        b.step(1.0 / 60.0, &mut qb);
        let late = frame >= 60 * 12;
        if late {
            c.step(1.0 / 60.0, &mut qc);
        }
        let (from_a, from_b) = (a.take_dis_outgoing(), b.take_dis_outgoing());
        let from_c = if late {
            c.take_dis_outgoing()
        } else {
            Vec::new()
        };
        for d in &from_a {
            b.receive_dis(d, &mut qb);
            if late {
                c.receive_dis(d, &mut qc);
            }
        }
        for d in &from_b {
            a.receive_dis(d, &mut qa);
            if late {
                c.receive_dis(d, &mut qc);
            }
        }
        for d in &from_c {
            a.receive_dis(d, &mut qa);
            b.receive_dis(d, &mut qb);
        }
    }
    assert_eq!(b.exercise().expect("b").counters().terrain_edits_healed, 1);
    for q in [&mut qa, &mut qb, &mut qc] {
        assert!(
            (hot(q, lat, lon) - before).abs() < 1e-9,
            "healed everywhere"
        );
        assert!(
            (before2 - hot(q, lat2, lon2) - 1.25).abs() < 0.05,
            "the other stays"
        );
    }
}

/// A ground vehicle of a simulation that is not an IG (it sends no ruts) leaves ruts: the
/// exercise's time master lays them and sends them, the other IG takes them and lays none.
#[test]
fn a_remote_vehicle_of_a_simulation_leaves_the_same_ruts_on_every_ig() {
    use cig_dis::publisher::{OwnedEntityPublisher, OwnedEntityState, PublisherConfig};
    use cig_dis::remote::{EntityKey, EntityTypeCode};
    let (mut qa, mut qb) = (query(), query());
    // A keeps the exercise's time (application 10) and lays the remote vehicles' ruts, B
    // follows (and would lay none if it kept the time: remote_ruts is off there).
    let (mut a, mut b) = (world_with(10, "remote_ruts = true\n"), world(11));
    let mut truck = OwnedEntityPublisher::new(
        EntityKey {
            site: 5,
            application: 5,
            entity: 1,
        },
        EntityTypeCode {
            kind: 1,
            domain: 1,
            country: 222,
            category: 6,
            subcategory: 1,
            specific: 0,
            extra: 0,
        },
        1,
        "TRUCK",
        PublisherConfig::default(),
    );
    let (lat0, lon0) = at(50.0, 10.0);
    let (_, lon1) = at(50.0, 11.0);
    let (_, east_m) = cig_geo::metres_per_degree(lat0);
    let dlon_per_s = 8.0 / ((lon1 - lon0) * east_m) * (lon1 - lon0);
    let dt = 1.0 / 60.0;
    for frame in 0..60 * 40 {
        let t = frame as f64 * dt;
        let lon = lon0 + dlon_per_s * t;
        let ground = qa.hot(lat0, lon).expect("hot").height_ellipsoid_m();
        let here = Geodetic::new(lat0, lon, ground);
        let east = cig_geo::EnuFrame::new(here).enu_vector_to_ecef(glam::DVec3::X);
        let state = OwnedEntityState {
            position_ecef_m: here.to_ecef(),
            velocity_ecef_mps: east * 8.0,
            ..OwnedEntityState::default()
        };
        if let Some((_, body)) = truck.update(t, &state) {
            let pdu = encode_pdu(
                EncodeHeader {
                    version: DisVersion::V7,
                    exercise_id: 3,
                    timestamp: cig_dis::codec::timestamp_from_seconds_past_hour(t, true),
                },
                &cig_dis::codec::DisMessage::EntityState(Box::new(body)),
            )
            .expect("encode");
            a.receive_dis(&pdu, &mut qa);
            b.receive_dis(&pdu, &mut qb);
        }
        a.step(dt, &mut qa);
        b.step(dt, &mut qb);
        let (from_a, from_b) = (a.take_dis_outgoing(), b.take_dis_outgoing());
        for d in &from_a {
            b.receive_dis(d, &mut qb);
        }
        for d in &from_b {
            a.receive_dis(d, &mut qa);
        }
    }
    let ruts = |q: &mut QuerySession| -> Vec<TerrainEdit> {
        q.edits()
            .edits()
            .filter(|e| matches!(e.shape, EditShape::Rut { .. }))
            .cloned()
            .collect()
    };
    let (on_a, on_b) = (ruts(&mut qa), ruts(&mut qb));
    // 300 m of sand in 8 m pieces, two wheel lines.
    assert!(on_a.len() >= 40, "{} ruts", on_a.len());
    assert!(on_a
        .iter()
        .all(|r| (r.author.site, r.author.application) == (1, 10)));
    // B has A's ruts (as carried by the PDUs: the same to a micrometre) and laid none.
    assert_eq!(
        on_a.iter().map(TerrainEdit::id).collect::<Vec<_>>(),
        on_b.iter().map(TerrainEdit::id).collect::<Vec<_>>()
    );
    for r in &on_a[4..] {
        let at = r.shape.anchor();
        let (ha, hb) = (
            qa.hot(at.lat_deg, at.lon_deg).expect("hot").height_msl_m,
            qb.hot(at.lat_deg, at.lon_deg).expect("hot").height_msl_m,
        );
        assert!((ha - hb).abs() < 1e-3, "{ha} vs {hb}");
    }
    let track = on_a[6].shape.anchor();
    let mut fresh = query();
    let plain = fresh
        .hot(track.lat_deg, track.lon_deg)
        .expect("hot")
        .height_msl_m;
    let rutted = qb
        .hot(track.lat_deg, track.lon_deg)
        .expect("hot")
        .height_msl_m;
    assert!(rutted < plain - 0.01, "{plain} -> {rutted}");
}

/// However many vehicles move, at most `MAX_RUTS_PER_S` ruts are laid a second, the vehicles
/// listed first served first.
#[test]
fn ruts_are_laid_within_a_budget_per_second() {
    use cig_dynterrain::soil::{RunningGear, SoilMoisture, VehicleLoad};
    use cig_ig::terrain_edits::{RutTracker, RutVehicle, MAX_RUTS_PER_S};
    let mut q = query();
    let load = VehicleLoad::new(62_000.0, 5.8, RunningGear::Tracked).expect("load");
    let fleet = |step_cols: f64| -> Vec<RutVehicle> {
        (0..30u32)
            .map(|k| {
                let (lat, lon) = at(10.0 + 3.0 * f64::from(k), 5.0 + step_cols);
                RutVehicle {
                    id: u64::from(k),
                    position: Geodetic::new(lat, lon, 0.0),
                    load,
                }
            })
            .collect()
    };
    let mut tracker = RutTracker::default();
    let author = EditAuthor {
        site: 1,
        application: 1,
    };
    let t0 = 1.8e9;
    assert!(tracker
        .advance(&fleet(0.0), author, t0, SoilMoisture::Dry, &mut q)
        .is_empty());
    // Every vehicle 9 m on (0.3 of a 30 m cell) within the same second.
    let ruts = tracker.advance(&fleet(0.3), author, t0 + 0.5, SoilMoisture::Dry, &mut q);
    assert_eq!(ruts.len(), MAX_RUTS_PER_S as usize);
    assert_eq!(tracker.dropped, 30 - u64::from(MAX_RUTS_PER_S) / 2);
    // The first ten vehicles (rows 10 to 37) got theirs.
    let (last_served, _) = at(38.5, 0.0);
    assert!(ruts.iter().all(|r| r.shape.anchor().lat_deg < last_served));
    // The next second, a new budget.
    let more = tracker.advance(&fleet(0.6), author, t0 + 1.2, SoilMoisture::Dry, &mut q);
    assert_eq!(more.len(), MAX_RUTS_PER_S as usize);
}
