//! The IG's CIGI and DIS behaviour on an analytic terrain: answers compared with the database's
//! own queries, both byte orders and both CIGI versions, attachments, rates, standing requests,
//! reset, clamping, line of sight, views, and two IGs sharing a DIS exercise.

use cig_cigi::{
    decode_message, encode_message, ByteOrder, CelestialSphereControl, EntityControl,
    EntityControl4, EntityPosition, HatHotRequest, IgControl, LosSegmentRequest, Message, Packet,
    PositionRequest, RateControl, Version, ViewControl, ViewDefinition,
};
use cig_effects::EffectsConfig;
use cig_environment::UtcTime;
use cig_geo::Geodetic;
use cig_ig::{IgWorld, Scenario, SessionConfig, WorldConfig};
use cig_scene::lighting::FogMode;
use cig_scene::{FovDeg, Hpr, View};
use cig_terrain::build::build_pyramid;
use cig_terrain::database::{GeoidGrid, Manifest, MemoryTileStore, TerrainDatabase};
use cig_terrain::material::Material;
use cig_terrain::raster::{GeoGrid, Raster};
use cig_terrain::{PagingConfig, QuerySession, TileCache};
use std::sync::Arc;

const SOUTH: f64 = 36.0;
const WEST: f64 = -121.0;
const GEOID_M: f32 = 12.0;

/// 129 x 129 posts, 30 m apart: a plane at 100 m MSL with a 60 m ridge along column 64.
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
        .map(|k| {
            let col = (k % grid.cols) as f32;
            100.0 + 60.0 * (-((col - 64.0) / 3.0).powi(2)).exp()
        })
        .collect();
    let raster = Raster {
        grid,
        elevation_m,
        material: Some(vec![Material::Grass; grid.len()]),
    };
    let store = Arc::new(MemoryTileStore::new());
    let summary = build_pyramid::<cig_terrain::build::BuildError>(&raster, 64, &mut |t| {
        store.insert(t.key, t.encode());
        Ok(())
    })
    .expect("build");
    let mut geoid = GeoidGrid::zero();
    geoid.undulation_m.iter_mut().for_each(|v| *v = GEOID_M);
    let manifest = Manifest::from_build(&summary, geoid, 0, vec!["test".into()]);
    let db = TerrainDatabase::new(manifest, store as Arc<dyn cig_terrain::TileStore>).expect("db");
    let cache = TileCache::new(Arc::new(db), PagingConfig::default()).expect("cache");
    QuerySession::new(Arc::new(cache))
}

/// Longitude of the ridge (column 64) and of a point on the plane (column 20).
fn lon_of_col(col: f64) -> f64 {
    let (_, e) = cig_geo::metres_per_degree(SOUTH);
    WEST + col * 30.0 / e
}
fn lat_of_row(row: f64) -> f64 {
    let (n, _) = cig_geo::metres_per_degree(SOUTH);
    SOUTH + row * 30.0 / n
}

fn world(scenario: &str) -> IgWorld {
    IgWorld::new(
        Scenario::from_toml(scenario).expect("scenario"),
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

fn send(world: &mut IgWorld, version: Version, order: ByteOrder, frame: u32, packets: Vec<Packet>) {
    let mut all = vec![Packet::IgControl(IgControl {
        ig_mode: 1,
        host_frame_number: frame,
        ..IgControl::default()
    })];
    all.extend(packets);
    let mut bytes = Vec::new();
    encode_message(&Message::new(version, order, all), &mut bytes).expect("encode");
    world
        .receive_cigi(&bytes)
        .expect("the IG accepts the message");
}

/// The host puts the IG in reset mode (IG Control with mode 0 alone).
fn reset(world: &mut IgWorld, frame: u32) {
    let mut bytes = Vec::new();
    encode_message(
        &Message::new(
            Version::V3_3,
            ByteOrder::LittleEndian,
            vec![Packet::IgControl(IgControl {
                ig_mode: 0,
                host_frame_number: frame,
                ..IgControl::default()
            })],
        ),
        &mut bytes,
    )
    .expect("encode");
    world.receive_cigi(&bytes).expect("reset");
}

/// One IG frame; returns the IG's message as the host decodes it.
fn frame(world: &mut IgWorld, q: &mut QuerySession) -> Message {
    world.step(1.0 / 60.0, q);
    let message = world.host_message(q, 1234);
    let mut bytes = Vec::new();
    encode_message(&message, &mut bytes).expect("encode");
    decode_message(&bytes).expect("the host decodes the IG's message")
}

fn entity_3(id: u16, lat: f64, lon: f64, alt: f64, yaw: f32) -> Packet {
    Packet::EntityControl(EntityControl {
        entity_id: id,
        entity_state: 1,
        entity_type: 1,
        yaw_deg: yaw,
        lat_deg_or_x_m: lat,
        lon_deg_or_y_m: lon,
        alt_m_or_z_m: alt,
        ..EntityControl::default()
    })
}

#[test]
fn hat_and_hot_answers_match_the_database_in_both_versions_and_byte_orders() {
    for (version, order) in [
        (Version::V3_3, ByteOrder::LittleEndian),
        (Version::V3_3, ByteOrder::BigEndian),
        (Version::V4_0, ByteOrder::LittleEndian),
        (Version::V4_0, ByteOrder::BigEndian),
    ] {
        let mut q = query();
        let mut w = world("");
        let (lat, lon) = (lat_of_row(40.5), lon_of_col(63.3));
        let truth = q.hot(lat, lon).expect("hot");
        let request = |id, kind| {
            Packet::HatHotRequest(HatHotRequest {
                hat_hot_id: id,
                request_type: kind,
                lat_deg_or_x_m: lat,
                lon_deg_or_y_m: lon,
                alt_m_or_z_m: 500.0,
                ..HatHotRequest::default()
            })
        };
        send(
            &mut w,
            version,
            order,
            77,
            vec![request(1, 0), request(2, 1), request(3, 2)],
        );
        let reply = frame(&mut w, &mut q);
        assert_eq!((reply.version, reply.byte_order), (version, order));
        let Some(Packet::StartOfFrame(sof)) = reply.packets.first() else {
            panic!(
                "the IG's message opens with Start of Frame: {:?}",
                reply.packets.first()
            );
        };
        assert_eq!(sof.last_host_frame_number, 77);
        assert_eq!(sof.ig_frame_number, 1);
        assert_eq!(sof.timestamp_10us, 1234);
        let mut seen = 0;
        for p in &reply.packets {
            match p {
                Packet::HatHotResponse(r) if r.hat_hot_id == 1 => {
                    assert!(r.valid && !r.response_type_hot);
                    assert!(
                        (r.height_m - (500.0 - truth.height_msl_m)).abs() < 1e-6,
                        "{r:?}"
                    );
                    assert_eq!(r.host_frame_lsn, 77 & 0xF);
                    seen += 1;
                }
                Packet::HatHotResponse(r) if r.hat_hot_id == 2 => {
                    assert!(r.valid && r.response_type_hot);
                    assert!((r.height_m - truth.height_msl_m).abs() < 1e-6, "{r:?}");
                    seen += 1;
                }
                Packet::HatHotExtendedResponse(r) => {
                    assert!(r.valid);
                    assert!((r.hot_m - truth.height_msl_m).abs() < 1e-6);
                    assert!((r.hat_m - (500.0 - truth.height_msl_m)).abs() < 1e-6);
                    assert_eq!(r.material_code, u32::from(Material::Grass.to_byte()));
                    // West flank of the ridge: the normal leans west.
                    assert!((r.normal_azimuth_deg - 270.0).abs() < 1.0, "{r:?}");
                    assert!(r.normal_elevation_deg < 89.0);
                    seen += 1;
                }
                _ => {}
            }
        }
        assert_eq!(seen, 3, "{version} {order:?}: {:?}", reply.packets);
        // One-shot requests are answered once.
        let next = frame(&mut w, &mut q);
        assert_eq!(next.packets.len(), 1, "{:?}", next.packets);
    }
}

#[test]
fn standing_requests_repeat_at_their_period_and_off_database_points_are_invalid() {
    let mut q = query();
    let mut w = world("");
    send(
        &mut w,
        Version::V3_3,
        ByteOrder::LittleEndian,
        1,
        vec![
            Packet::HatHotRequest(HatHotRequest {
                hat_hot_id: 9,
                request_type: 1,
                update_period: 2,
                lat_deg_or_x_m: lat_of_row(10.0),
                lon_deg_or_y_m: lon_of_col(10.0),
                ..HatHotRequest::default()
            }),
            Packet::HatHotRequest(HatHotRequest {
                hat_hot_id: 10,
                request_type: 1,
                lat_deg_or_x_m: 10.0,
                lon_deg_or_y_m: 10.0,
                ..HatHotRequest::default()
            }),
        ],
    );
    let mut off_database = Vec::new();
    let answered: Vec<usize> = (0..6)
        .map(|_| {
            let reply = frame(&mut w, &mut q);
            off_database.extend(reply.packets.iter().filter_map(|p| match p {
                Packet::HatHotResponse(r) if r.hat_hot_id == 10 => Some(r.valid),
                _ => None,
            }));
            reply
                .packets
                .iter()
                .filter(|p| matches!(p, Packet::HatHotResponse(r) if r.hat_hot_id == 9 && r.valid))
                .count()
        })
        .collect();
    assert_eq!(answered, vec![1, 0, 1, 0, 1, 0]);
    // The point 10 N 10 E is far off the database: one answer, marked invalid.
    assert_eq!(off_database, vec![false]);
    // A request with the same ID and period 0 ends it after one more answer.
    send(
        &mut w,
        Version::V3_3,
        ByteOrder::LittleEndian,
        2,
        vec![Packet::HatHotRequest(HatHotRequest {
            hat_hot_id: 9,
            request_type: 1,
            lat_deg_or_x_m: lat_of_row(10.0),
            lon_deg_or_y_m: lon_of_col(10.0),
            ..HatHotRequest::default()
        })],
    );
    assert_eq!(frame(&mut w, &mut q).packets.len(), 2);
    assert_eq!(frame(&mut w, &mut q).packets.len(), 1);
    assert!(w.session().counters().hat_hot_answered >= 5);
}

#[test]
fn attached_entities_and_views_follow_their_parents_and_position_requests_report_them() {
    let mut q = query();
    let mut w = world("");
    let (lat, lon) = (lat_of_row(64.0), lon_of_col(20.0));
    send(
        &mut w,
        Version::V3_3,
        ByteOrder::BigEndian,
        5,
        vec![
            entity_3(1, lat, lon, 300.0, 90.0),
            Packet::EntityControl(EntityControl {
                entity_id: 2,
                entity_state: 1,
                attach: true,
                parent_id: 1,
                lat_deg_or_x_m: 100.0,
                lon_deg_or_y_m: 0.0,
                alt_m_or_z_m: -10.0,
                yaw_deg: 45.0,
                ..EntityControl::default()
            }),
            Packet::ViewControl(ViewControl {
                view_id: 0,
                entity_id: 2,
                x_offset_enable: true,
                x_offset_m: -5.0,
                yaw_enable: true,
                yaw_deg: -45.0,
                ..ViewControl::default()
            }),
            Packet::ViewDefinition(ViewDefinition {
                view_id: 0,
                left_enable: true,
                right_enable: true,
                top_enable: true,
                bottom_enable: true,
                left_deg: -30.0,
                right_deg: 20.0,
                top_deg: 15.0,
                bottom_deg: -25.0,
                ..ViewDefinition::default()
            }),
            Packet::PositionRequest(PositionRequest {
                object_id: 2,
                object_class: 0,
                coordinate_system: 0,
                ..PositionRequest::default()
            }),
            Packet::PositionRequest(PositionRequest {
                object_id: 2,
                object_class: 0,
                coordinate_system: 1,
                part_id: 1,
                ..PositionRequest::default()
            }),
        ],
    );
    let reply = frame(&mut w, &mut q);
    let responses: Vec<_> = reply
        .packets
        .iter()
        .filter_map(|p| match p {
            Packet::PositionResponse(r) => Some(r.clone()),
            _ => None,
        })
        .collect();
    assert_eq!(responses.len(), 2, "{:?}", reply.packets);
    let geo = responses
        .iter()
        .find(|r| r.coordinate_system == 0)
        .expect("geodetic");
    // 100 m east of the parent (heading 90), 10 m up, heading 135.
    let east = cig_geo::EnuFrame::new(Geodetic::new(lat, lon, 0.0)).geodetic_to_enu(Geodetic::new(
        geo.lat_deg_or_x_m,
        geo.lon_deg_or_y_m,
        0.0,
    ));
    assert!(
        (east.x - 100.0).abs() < 0.01 && east.y.abs() < 0.01,
        "{east:?}"
    );
    assert!((geo.alt_m_or_z_m - 310.0).abs() < 0.01, "{geo:?}");
    assert!((geo.yaw_deg - 135.0).abs() < 1e-3);
    let rel = responses
        .iter()
        .find(|r| r.coordinate_system == 1)
        .expect("relative");
    assert!((rel.lat_deg_or_x_m - 100.0).abs() < 1e-3 && (rel.alt_m_or_z_m + 10.0).abs() < 1e-3);
    // The view: 5 m behind entity 2 along its axis, looking along the parent's heading.
    let fallback = View {
        eye: Geodetic::new(lat, lon, 1000.0),
        orientation: Hpr::default(),
        fov: FovDeg::symmetric(60.0, 45.0),
        width_px: 64,
        height_px: 48,
    };
    let snapshot = w.snapshot(64, 48, &fallback);
    assert_eq!(snapshot.views.len(), 1);
    let view = snapshot.views[0];
    assert!(
        (view.orientation.heading_deg - 90.0).abs() < 1e-6,
        "{view:?}"
    );
    assert_eq!(
        view.fov,
        FovDeg {
            left_deg: 30.0,
            right_deg: 20.0,
            down_deg: 25.0,
            up_deg: 15.0
        }
    );
    // The ellipsoid height of the eye is the MSL altitude plus the geoid.
    assert!((view.eye.alt_m - (310.0 + f64::from(GEOID_M))).abs() < 0.01);
    assert_eq!(snapshot.entities.len(), 2);
}

#[test]
fn rates_move_entities_between_host_updates_and_clamped_entities_sit_on_the_ground() {
    let mut q = query();
    let mut w = world("");
    let (lat, lon) = (lat_of_row(30.0), lon_of_col(30.0));
    send(
        &mut w,
        Version::V4_0,
        ByteOrder::LittleEndian,
        1,
        vec![
            Packet::EntityControl4(EntityControl4 {
                entity_id: 3,
                entity_state: 1,
                entity_type_or_country: 1,
                ..EntityControl4::default()
            }),
            Packet::EntityPosition(EntityPosition {
                entity_id: 3,
                lat_deg_or_x_m: lat,
                lon_deg_or_y_m: lon,
                alt_m_or_z_m: 200.0,
                ..EntityPosition::default()
            }),
            Packet::RateControl(RateControl {
                entity_id: 3,
                x_rate_mps: 10.0,
                yaw_rate_dps: 5.0,
                ..RateControl::default()
            }),
            Packet::EntityPosition(EntityPosition {
                entity_id: 4,
                lat_deg_or_x_m: lat,
                lon_deg_or_y_m: lon_of_col(63.0),
                alt_m_or_z_m: 2.0,
                ground_ocean_clamp: 2,
                yaw_deg: 0.0,
                ..EntityPosition::default()
            }),
        ],
    );
    for _ in 0..60 {
        w.step(1.0 / 60.0, &mut q);
    }
    let pose = w.session().poses()[&3];
    let start = Geodetic::new(lat, lon, 200.0 + f64::from(GEOID_M));
    let moved = cig_geo::EnuFrame::new(start).geodetic_to_enu(pose.position);
    assert!(
        (moved.y - 10.0).abs() < 0.05 && moved.x.abs() < 0.05,
        "{moved:?}"
    );
    assert!((pose.orientation.heading_deg - 5.0).abs() < 0.01);
    let clamped = w.session().poses()[&4];
    let ground = q
        .hot(clamped.position.lat_deg, clamped.position.lon_deg)
        .expect("hot");
    assert!((clamped.position.alt_m - (ground.height_ellipsoid_m() + 2.0)).abs() < 1e-6);
    // On the ridge's west flank facing north, the entity rolls (its right side is higher).
    assert!(clamped.orientation.roll_deg.abs() > 5.0, "{clamped:?}");
}

#[test]
fn line_of_sight_across_the_ridge_is_blocked_and_along_it_is_clear() {
    let mut q = query();
    let mut w = world("");
    let lat = lat_of_row(64.0);
    let los = |id, lon_a, lon_b, alt| {
        Packet::LosSegmentRequest(LosSegmentRequest {
            los_id: id,
            request_type_extended: true,
            source_lat_deg_or_x_m: lat,
            source_lon_deg_or_y_m: lon_a,
            source_alt_m_or_z_m: alt,
            destination_lat_deg_or_x_m: lat,
            destination_lon_deg_or_y_m: lon_b,
            destination_alt_m_or_z_m: alt,
            ..LosSegmentRequest::default()
        })
    };
    send(
        &mut w,
        Version::V3_3,
        ByteOrder::LittleEndian,
        3,
        vec![
            los(1, lon_of_col(40.0), lon_of_col(90.0), 120.0),
            los(2, lon_of_col(40.0), lon_of_col(90.0), 400.0),
        ],
    );
    let reply = frame(&mut w, &mut q);
    let mut by_id = std::collections::BTreeMap::new();
    for p in &reply.packets {
        if let Packet::LosExtendedResponse(r) = p {
            by_id.insert(r.los_id, r.clone());
        }
    }
    let blocked = &by_id[&1];
    assert!(
        blocked.valid && !blocked.visible && blocked.range_valid,
        "{blocked:?}"
    );
    // It meets the ridge's west flank, short of column 64, about (64 - 40) * 30 m away.
    assert!(
        blocked.range_m > 600.0 && blocked.range_m < 24.0 * 30.0,
        "{blocked:?}"
    );
    assert!(blocked.alt_m_or_z_m > 119.0 && blocked.alt_m_or_z_m < 121.0);
    let clear = &by_id[&2];
    assert!(
        clear.valid && clear.visible && !clear.range_valid,
        "{clear:?}"
    );
}

#[test]
fn reset_clears_entities_and_garbage_is_refused_without_harm() {
    let mut q = query();
    let mut w = world("");
    let (lat, lon) = (lat_of_row(30.0), lon_of_col(30.0));
    send(
        &mut w,
        Version::V3_3,
        ByteOrder::LittleEndian,
        1,
        vec![
            entity_3(0, lat, lon, 300.0, 0.0),
            entity_3(7, lat, lon, 300.0, 0.0),
        ],
    );
    frame(&mut w, &mut q);
    assert_eq!(w.session().entities().len(), 2);
    for garbage in [
        &b""[..],
        &[0xFF; 3][..],
        &[1, 24, 3, 0, 0, 0, 0x80, 0][..],
        &[0u8; 70000][..],
    ] {
        assert!(w.receive_cigi(garbage).is_err());
    }
    reset(&mut w, 2);
    let reply = frame(&mut w, &mut q);
    assert_eq!(
        w.session().entities().keys().copied().collect::<Vec<_>>(),
        vec![0]
    );
    let Some(Packet::StartOfFrame(sof)) = reply.packets.first() else {
        panic!("Start of Frame first");
    };
    assert_eq!(sof.ig_mode, 0);
    assert_eq!(w.cigi_rejected(), 4);
}

const DIS_SCENARIO: &str = r#"
start_time = "2026-06-21T12:00:00Z"
[[models]]
model = "tank"
dis_type = "1:1:225:1"
[[entities]]
id = 1
model = "tank"
dis_id = "1:3001:1"
dis_type = "1:1:225:1:1:0:0"
lat_deg = 36.01
lon_deg = -120.99
clamp = "height_and_attitude"
speed_mps = 10
path = [[36.015, -120.99]]
appearance = "0x8000"
[dis]
site = 1
application = 3001
exercise = 4
time_master = true
"#;

#[test]
fn two_igs_share_entities_and_time_over_dis_and_both_draw_the_tanks_smoke() {
    let mut qa = query();
    let mut qb = query();
    let mut a = world(DIS_SCENARIO);
    let b_scenario = DIS_SCENARIO
        .replace(
            "application = 3001\nexercise",
            "application = 3002\nexercise",
        )
        .replace("time_master = true", "time_master = false")
        .replace("2026-06-21T12:00:00Z", "2026-01-01T00:00:00Z")
        .replace("[[entities]]", "[[entities_unused]]");
    // B has no entities of its own.
    let b_scenario: String = b_scenario
        .split("[[entities_unused]]")
        .next()
        .map(|head| {
            format!(
                "{head}{}",
                &b_scenario[b_scenario.find("[dis]").expect("dis")..]
            )
        })
        .expect("split");
    let mut b = world(&b_scenario);
    let fallback = View {
        eye: Geodetic::new(36.0, -121.0, 1000.0),
        orientation: Hpr::default(),
        fov: FovDeg::symmetric(60.0, 45.0),
        width_px: 64,
        height_px: 48,
    };
    for _ in 0..180 {
        a.step(1.0 / 60.0, &mut qa);
        b.step(1.0 / 60.0, &mut qb);
        for d in a.take_dis_outgoing() {
            b.receive_dis(&d, &mut qb);
        }
        for d in b.take_dis_outgoing() {
            a.receive_dis(&d, &mut qa);
        }
    }
    // B adopted A's time (not its own 1 January start).
    assert!(
        (b.unix_time_s() - a.unix_time_s()).abs() < 0.05,
        "{} {}",
        a.unix_time_s(),
        b.unix_time_s()
    );
    // B draws A's tank where A has it, with the table's model.
    let snapshot = b.snapshot(64, 48, &fallback);
    let tank = snapshot
        .entities
        .iter()
        .find(|e| e.model == "tank")
        .expect("remote tank");
    let truth = a.session().poses()[&1].position;
    let gap = (tank.position.to_ecef() - truth.to_ecef()).length();
    assert!(gap < 1.0, "remote tank {gap} m from its owner's");
    // Its smoke appearance bit (0x8000) started the same plume on both... B's plume follows the
    // remote entity; the puffs B computes for it are deterministic.
    assert!(
        b.effects().stats().live_effects >= 1,
        "{:?}",
        b.effects().stats()
    );
    let counters = b.exercise().expect("exercise").counters();
    assert!(
        counters.entity_states_applied >= 1 && counters.bad_pdus == 0,
        "{counters:?}"
    );
}

#[test]
fn a_detonation_starts_the_same_plume_on_every_ig() {
    use cig_dis::codec::{encode_pdu, DisMessage, DisVersion, EncodeHeader};
    use cig_dis::dis_rs::detonation::model::{Detonation, DetonationDescriptor};
    use cig_dis::dis_rs::enumerations::DetonationResult;
    use cig_dis::dis_rs::model::{EntityId, EventId, Location, MunitionDescriptor, VectorF32};
    use cig_dis::dis_rs::BodyRaw;
    let impact = Geodetic::new(lat_of_row(60.0), lon_of_col(30.0), 112.0).to_ecef();
    let detonation = Detonation::builder()
        .with_source_entity_id(EntityId::new(3, 4, 5))
        .with_target_entity_id(EntityId::new(0, 0, 0))
        .with_exploding_entity_id(EntityId::new(3, 4, 6))
        .with_event_id(EventId::new(3, 4, 77))
        .with_velocity(VectorF32::new(0.0, 0.0, -200.0))
        .with_world_location(Location::new(impact.x, impact.y, impact.z))
        .with_descriptor(DetonationDescriptor::Munition(MunitionDescriptor::default()))
        .with_entity_location(VectorF32::new(0.0, 0.0, 0.0))
        .with_detonation_result(DetonationResult::from(3))
        .build();
    // Sent 0.1 s past 12:00:00 world time, stamped absolute.
    let header = |exercise_id| EncodeHeader {
        version: DisVersion::V7,
        exercise_id,
        timestamp: cig_dis::codec::timestamp_from_seconds_past_hour(0.1, true),
    };
    let pdu = encode_pdu(
        header(4),
        &DisMessage::Detonation(Box::new(detonation.clone())),
    )
    .expect("encode");
    let other_exercise =
        encode_pdu(header(5), &DisMessage::Detonation(Box::new(detonation))).expect("encode");
    let scenario =
        "start_time = \"2026-06-21T12:00:00Z\"\n[dis]\nexercise = 4\ntime_master = true\n";
    let run = |delay_frames: usize| {
        let mut q = query();
        let mut w = world(scenario);
        for i in 0..240 {
            if i == delay_frames {
                w.receive_dis(&pdu, &mut q);
                w.receive_dis(&other_exercise, &mut q);
                w.receive_dis(&[0xde, 0xad], &mut q);
            }
            w.step(1.0 / 60.0, &mut q);
        }
        let counters = w.exercise().expect("exercise").counters();
        assert_eq!(counters.impacts_started, 1, "{counters:?}");
        assert_eq!(counters.bad_pdus, 1);
        (w.effects().puff_states(), w.effects().stats().active)
    };
    // Two IGs that get the PDU at different times (network delay) draw the same puffs.
    let (a, active) = run(10);
    let (b, _) = run(40);
    assert!(active > 0, "the impact emits puffs");
    assert_eq!(a, b, "the same event gives the same puffs");
}

#[test]
fn smoke_processes_and_lightning_reach_the_other_ig() {
    let mut qa = query();
    let mut qb = query();
    let a_scenario = format!(
        "start_time = \"2026-06-21T12:00:00Z\"\n\
         [[smoke]]\nid = 5\nlat_deg = {}\nlon_deg = {}\nduration_s = 4\n\
         [dis]\nsite = 1\napplication = 10\nexercise = 2\ntime_master = true\n",
        lat_of_row(50.0),
        lon_of_col(30.0)
    );
    let b_scenario =
        "start_time = \"2026-06-21T12:00:00Z\"\n[dis]\nsite = 1\napplication = 11\nexercise = 2\n";
    let mut a = world(&a_scenario);
    let mut b = world(b_scenario);
    let mut started_at_b = 0;
    let mut strikes = Vec::new();
    for frame in 0..60 * 20 {
        a.step(1.0 / 60.0, &mut qa);
        b.step(1.0 / 60.0, &mut qb);
        if frame == 30 {
            let x = a.exercise_mut().expect("exercise");
            let at = Geodetic::new(lat_of_row(60.0), lon_of_col(60.0), 3000.0).to_ecef();
            x.announce_lightning(0.5, at, 99, 0.8);
        }
        for d in a.take_dis_outgoing() {
            b.receive_dis(&d, &mut qb);
        }
        for d in b.take_dis_outgoing() {
            a.receive_dis(&d, &mut qa);
        }
        strikes.extend(b.take_lightning());
        started_at_b = b
            .exercise()
            .expect("exercise")
            .counters()
            .remote_processes_started;
    }
    let counters = b.exercise().expect("exercise").counters();
    assert_eq!(started_at_b, 1, "{counters:?}");
    assert!(
        counters.environmental_processes >= 2,
        "start and last update: {counters:?}"
    );
    assert_eq!(strikes.len(), 1);
    assert_eq!(strikes[0].seed, 99);
    // After the source's 4 s and the last update, B's copy stops emitting; its puffs age out.
    assert!(b.effects().stats().spawned_total > 0);
}

#[test]
fn reset_brings_back_the_scenario_destroy_takes_children_and_groups_move_together() {
    let mut q = query();
    let scenario = format!(
        "[[entities]]\nid = 5\nmodel = \"tank\"\nlat_deg = {}\nlon_deg = {}\n",
        lat_of_row(20.0),
        lon_of_col(20.0)
    );
    let mut w = world(&scenario);
    let (lat, lon) = (lat_of_row(30.0), lon_of_col(30.0));
    let attached = |id, parent| {
        Packet::EntityControl(EntityControl {
            entity_id: id,
            entity_state: 1,
            attach: true,
            parent_id: parent,
            lat_deg_or_x_m: 5.0,
            ..EntityControl::default()
        })
    };
    let definition = |view_id, group_id| {
        Packet::ViewDefinition(ViewDefinition {
            view_id,
            group_id,
            ..ViewDefinition::default()
        })
    };
    send(
        &mut w,
        Version::V3_3,
        ByteOrder::LittleEndian,
        1,
        vec![
            entity_3(1, lat, lon, 300.0, 0.0),
            attached(2, 1),
            attached(3, 2),
            entity_3(4, lat, lon, 300.0, 0.0),
            definition(1, 7),
            definition(2, 7),
            definition(3, 0),
            Packet::ViewControl(ViewControl {
                group_id: 7,
                entity_id: 4,
                yaw_enable: true,
                yaw_deg: 90.0,
                ..ViewControl::default()
            }),
        ],
    );
    frame(&mut w, &mut q);
    let views = w.session().views();
    assert_eq!(
        (
            views[&1].entity_id,
            views[&2].entity_id,
            views[&3].entity_id
        ),
        (4, 4, 0)
    );
    assert_eq!(views[&2].orientation.heading_deg, 90.0);
    // Destroying entity 1 takes 2 and 3 (attached to it) with it.
    send(
        &mut w,
        Version::V3_3,
        ByteOrder::LittleEndian,
        2,
        vec![Packet::EntityControl(EntityControl {
            entity_id: 1,
            entity_state: 2,
            ..EntityControl::default()
        })],
    );
    frame(&mut w, &mut q);
    assert_eq!(
        w.session().entities().keys().copied().collect::<Vec<_>>(),
        vec![4, 5]
    );
    // A reset keeps the scenario's entity.
    reset(&mut w, 4);
    frame(&mut w, &mut q);
    assert_eq!(
        w.session().entities().keys().copied().collect::<Vec<_>>(),
        vec![5]
    );
}

#[test]
fn a_vector_from_an_entity_is_aimed_in_its_body_axes() {
    let mut q = query();
    let mut w = world("");
    // An entity west of the ridge, facing east (yaw 90), 120 m up: a level vector dead ahead
    // (azimuth 0 in its body axes) hits the ridge; the same vector from a north-facing entity
    // runs along the plain and misses.
    let lat = lat_of_row(64.0);
    send(
        &mut w,
        Version::V3_3,
        ByteOrder::LittleEndian,
        1,
        vec![
            entity_3(1, lat, lon_of_col(40.0), 120.0, 90.0),
            entity_3(2, lat, lon_of_col(40.0), 120.0, 0.0),
        ],
    );
    frame(&mut w, &mut q);
    send(
        &mut w,
        Version::V3_3,
        ByteOrder::LittleEndian,
        2,
        vec![
            Packet::LosVectorRequest(cig_cigi::LosVectorRequest {
                los_id: 1,
                source_coordinate_entity: true,
                entity_id: 1,
                max_range_m: 1500.0,
                ..cig_cigi::LosVectorRequest::default()
            }),
            Packet::LosVectorRequest(cig_cigi::LosVectorRequest {
                los_id: 2,
                source_coordinate_entity: true,
                entity_id: 2,
                max_range_m: 1500.0,
                ..cig_cigi::LosVectorRequest::default()
            }),
        ],
    );
    let reply = frame(&mut w, &mut q);
    let visible: std::collections::BTreeMap<u16, bool> = reply
        .packets
        .iter()
        .filter_map(|p| match p {
            Packet::LosResponse(r) if r.valid => Some((r.los_id, r.visible)),
            _ => None,
        })
        .collect();
    assert_eq!(visible.get(&1), Some(&false), "{:?}", reply.packets);
    assert_eq!(visible.get(&2), Some(&true), "{:?}", reply.packets);
}

#[test]
fn smoke_on_a_clear_line_of_sight_stops_it_at_the_requests_alpha_threshold() {
    let mut q = query();
    let (lat, lon) = (lat_of_row(60.0), lon_of_col(20.0));
    let scenario = format!(
        "start_time = \"2026-06-21T12:00:00Z\"\n[[smoke]]\nid = 1\nlat_deg = {lat}\nlon_deg = {lon}\nheat_release_w = 2e6\n"
    );
    let mut w = world(&scenario);
    for _ in 0..60 * 90 {
        w.step(1.0 / 60.0, &mut q);
    }
    // Along the plume's axis (the wind blows from the west), 30 m above the plain.
    let ground_msl = q.hot(lat, lon).expect("hot").height_msl_m;
    let from = (lat, lon_of_col(13.0), ground_msl + 30.0);
    let to = (lat, lon_of_col(34.0), ground_msl + 30.0);
    let los = |id, threshold| {
        Packet::LosSegmentRequest(LosSegmentRequest {
            los_id: id,
            request_type_extended: true,
            alpha_threshold: threshold,
            source_lat_deg_or_x_m: from.0,
            source_lon_deg_or_y_m: from.1,
            source_alt_m_or_z_m: from.2,
            destination_lat_deg_or_x_m: to.0,
            destination_lon_deg_or_y_m: to.1,
            destination_alt_m_or_z_m: to.2,
            ..LosSegmentRequest::default()
        })
    };
    // The answer is computed after the frame's step: measure the smoke at that very state.
    w.step(1.0 / 60.0, &mut q);
    let geoid = f64::from(GEOID_M);
    let t = w
        .effects()
        .transmittance(
            Geodetic::new(from.0, from.1, from.2 + geoid),
            Geodetic::new(to.0, to.1, to.2 + geoid),
        )
        .expect("transmittance");
    let alpha = (255.0 * (1.0 - t.transmittance)).round() as u8;
    assert!(
        alpha > 50 && alpha < 255,
        "the test line crosses the plume: T = {t:?}"
    );
    send(
        &mut w,
        Version::V3_3,
        ByteOrder::LittleEndian,
        1,
        vec![los(1, alpha), los(2, alpha + 1), los(3, 0)],
    );
    let message = w.host_message(&mut q, 0);
    let answers: std::collections::BTreeMap<u16, (bool, bool, u8)> = message
        .packets
        .iter()
        .filter_map(|p| match p {
            Packet::LosExtendedResponse(r) if r.valid => {
                Some((r.los_id, (r.visible, r.range_valid, r.alpha)))
            }
            _ => None,
        })
        .collect();
    // At the threshold the smoke stops the line (no terrain in the way: no range); one above
    // it, the line is clear; threshold 0 counts any smoke.
    assert_eq!(answers[&1], (false, false, alpha), "{answers:?}");
    assert_eq!(answers[&2], (true, false, 0), "{answers:?}");
    assert_eq!(answers[&3], (false, false, alpha), "{answers:?}");
}

#[test]
fn the_snapshot_carries_the_effects_puffs() {
    let mut q = query();
    let (lat, lon) = (lat_of_row(60.0), lon_of_col(20.0));
    let scenario = format!(
        "start_time = \"2026-06-21T12:00:00Z\"\n[[smoke]]\nid = 1\nlat_deg = {lat}\nlon_deg = {lon}\n"
    );
    let mut w = world(&scenario);
    let fallback = View {
        eye: Geodetic::new(lat_of_row(30.0), lon, 400.0),
        orientation: Hpr::default(),
        fov: FovDeg::symmetric(60.0, 45.0),
        width_px: 64,
        height_px: 48,
    };
    let mut counts = Vec::new();
    for i in 0..180 {
        w.step(1.0 / 60.0, &mut q);
        if i % 30 == 29 {
            counts.push(w.snapshot(64, 48, &fallback).puffs.len());
        }
    }
    assert!(
        counts.last().copied().unwrap_or(0) > 0,
        "{counts:?} {:?}",
        w.effects().stats()
    );
    let s = w.snapshot(64, 48, &fallback);
    assert_eq!(s.puff_origin_ecef_m, fallback.eye.to_ecef());
}

#[test]
fn the_hosts_wind_carries_the_smoke_and_the_operator_can_start_and_stop_plumes() {
    let mut q = query();
    let (lat, lon) = (lat_of_row(60.0), lon_of_col(60.0));
    let mut w = world("start_time = \"2026-06-21T12:00:00Z\"\n");
    // Wind from the east at 8 m/s.
    send(
        &mut w,
        Version::V3_3,
        ByteOrder::LittleEndian,
        1,
        vec![Packet::AtmosphereControl(cig_cigi::AtmosphereControl {
            atmospheric_model_enable: true,
            humidity_pct: 50,
            air_temperature_c: 20.0,
            visibility_range_m: 20_000.0,
            horizontal_wind_speed_mps: 8.0,
            wind_direction_deg: 90.0,
            barometric_pressure_mbar: 1013.0,
            ..cig_cigi::AtmosphereControl::default()
        })],
    );
    let ground = q.hot(lat, lon).expect("hot").height_ellipsoid_m();
    let source = Geodetic::new(lat, lon, ground);
    w.step(1.0 / 60.0, &mut q);
    assert_eq!(
        w.start_operator_plume(source, false, 3.0e6)
            .expect("starts"),
        1
    );
    for _ in 0..60 * 60 {
        w.step(1.0 / 60.0, &mut q);
    }
    let wind = w.effects().atmosphere().wind;
    assert_eq!((wind.speed_mps, wind.from_deg), (8.0, 90.0));
    let frame = cig_geo::EnuFrame::new(source);
    let puffs = w.effects().puff_states();
    let mean_east = puffs
        .iter()
        .map(|p| {
            frame
                .ecef_to_enu(glam::DVec3::from_array(p.centre_ecef_m))
                .x
        })
        .sum::<f64>()
        / puffs.len().max(1) as f64;
    assert!(
        !puffs.is_empty() && mean_east < -50.0,
        "the smoke drifts west: {mean_east} m"
    );
    w.stop_operator_plumes();
    let before = w.effects().stats().spawned_total;
    for _ in 0..60 * 5 {
        w.step(1.0 / 60.0, &mut q);
    }
    assert_eq!(
        w.effects().stats().spawned_total,
        before,
        "a stopped plume emits no more"
    );
}

#[test]
fn a_moving_truck_raises_dust_and_a_stopped_one_does_not() {
    let mut q = query();
    let scenario = format!(
        "start_time = \"2026-06-21T12:00:00Z\"\n\
         [[entities]]\nid = 1\nmodel = \"truck\"\nlat_deg = {}\nlon_deg = {}\nclamp = \"height\"\nspeed_mps = 12\npath = [[{}, {}]]\n\
         [[entities]]\nid = 2\nmodel = \"truck\"\nlat_deg = {}\nlon_deg = {}\nclamp = \"height\"\n\
         [[entities]]\nid = 3\nmodel = \"truck\"\ndust = false\nlat_deg = {}\nlon_deg = {}\nclamp = \"height\"\nspeed_mps = 12\npath = [[{}, {}]]\n",
        lat_of_row(10.0),
        lon_of_col(10.0),
        lat_of_row(100.0),
        lon_of_col(10.0),
        lat_of_row(20.0),
        lon_of_col(40.0),
        lat_of_row(10.0),
        lon_of_col(30.0),
        lat_of_row(100.0),
        lon_of_col(30.0),
    );
    let mut w = world(&scenario);
    for _ in 0..60 * 10 {
        w.step(1.0 / 60.0, &mut q);
    }
    // Only the moving truck that may raise dust does: one live dust trail, emitting.
    let stats = w.effects().stats();
    assert_eq!(stats.live_effects, 1, "{stats:?}");
    let frame = cig_geo::EnuFrame::new(Geodetic::new(lat_of_row(10.0), lon_of_col(10.0), 100.0));
    let puffs = w.effects().puff_states();
    assert!(!puffs.is_empty());
    // The dust lies behind it, along its track (it drives north from column 10).
    let mean = puffs
        .iter()
        .map(|p| frame.ecef_to_enu(glam::DVec3::from_array(p.centre_ecef_m)))
        .fold(glam::DVec3::ZERO, |a, b| a + b)
        / puffs.len() as f64;
    assert!(
        mean.x.abs() < 30.0 && mean.y > 0.0 && mean.y < 12.0 * 10.0,
        "{mean:?}"
    );
}

#[test]
fn a_destroyed_entity_stops_smoking() {
    let mut q = query();
    let scenario = format!(
        "start_time = \"2026-06-21T12:00:00Z\"\n\
         [[entities]]\nid = 1\nmodel = \"tank\"\ndis_type = \"1:1:225:1:1:0:0\"\nappearance = \"0x20\"\ndust = false\nlat_deg = {}\nlon_deg = {}\nclamp = \"height\"\n",
        lat_of_row(30.0),
        lon_of_col(30.0)
    );
    let mut w = world(&scenario);
    for _ in 0..120 {
        w.step(1.0 / 60.0, &mut q);
    }
    assert_eq!(
        w.effects().stats().live_effects,
        1,
        "its appearance (0x20, smoke) smokes"
    );
    send(
        &mut w,
        Version::V3_3,
        ByteOrder::LittleEndian,
        1,
        vec![Packet::EntityControl(EntityControl {
            entity_id: 1,
            entity_state: 2,
            ..EntityControl::default()
        })],
    );
    w.step(1.0 / 60.0, &mut q);
    let spawned = w.effects().stats().spawned_total;
    for _ in 0..600 {
        w.step(1.0 / 60.0, &mut q);
    }
    assert_eq!(
        w.effects().stats().spawned_total,
        spawned,
        "no more smoke once destroyed"
    );
}

#[test]
fn the_hosts_ground_fog_layer_reaches_the_renderer_as_a_layer() {
    let mut q = query();
    let mut w = world("");
    let (lat, lon) = (lat_of_row(30.0), lon_of_col(30.0));
    send(
        &mut w,
        Version::V3_3,
        ByteOrder::LittleEndian,
        1,
        vec![
            entity_3(0, lat, lon, 120.0, 0.0),
            Packet::ViewControl(ViewControl {
                view_id: 0,
                entity_id: 0,
                ..ViewControl::default()
            }),
            Packet::WeatherControl(cig_cigi::WeatherControl {
                layer_id: 0,
                weather_enable: true,
                scope: 0,
                base_elevation_m: 0.0,
                thickness_m: 150.0,
                visibility_range_m: 200.0,
                ..cig_cigi::WeatherControl::default()
            }),
        ],
    );
    frame(&mut w, &mut q);
    let fallback = View {
        eye: Geodetic::new(lat, lon, 1000.0),
        orientation: Hpr::default(),
        fov: FovDeg::symmetric(60.0, 45.0),
        width_px: 64,
        height_px: 48,
    };
    let s = w.snapshot(64, 48, &fallback);
    let layer = s.ground_fog.expect("a ground fog layer");
    assert!(
        (layer.top_m - (150.0 + f64::from(GEOID_M))).abs() < 1e-6,
        "{layer:?}"
    );
    assert_eq!(layer.visibility_m, 200.0);
    // The eye (120 m, inside the layer) keeps the global visibility for the rest of the view.
    assert!(s.fog.density_per_m < 3.912 / 10_000.0, "{:?}", s.fog);
    // The host's Weather Conditions answer at the eye does see the fog.
    assert_eq!(
        w.session().visibility_at_m(Geodetic::new(lat, lon, 120.0)),
        200.0
    );
}

#[test]
fn the_hosts_moon_and_star_switches_reach_the_frame_and_a_bad_intensity_is_clamped_and_told() {
    let mut q = query();
    let mut w = world("");
    let (lat, lon) = (lat_of_row(30.0), lon_of_col(30.0));
    let fallback = View {
        eye: Geodetic::new(lat, lon, 1000.0),
        orientation: Hpr::default(),
        fov: FovDeg::symmetric(60.0, 45.0),
        width_px: 64,
        height_px: 48,
    };
    let before = w.snapshot(64, 48, &fallback);
    assert!(before.stars_visible && before.moon_visible);
    assert_eq!(before.star_intensity, 1.0);
    for (frame_number, (stars, moon, pct)) in [(false, false, 250.0f32), (true, true, 40.0)]
        .into_iter()
        .enumerate()
    {
        send(
            &mut w,
            Version::V3_3,
            ByteOrder::LittleEndian,
            frame_number as u32 + 1,
            vec![Packet::CelestialSphereControl(CelestialSphereControl {
                moon_enable: moon,
                star_field_enable: stars,
                star_field_intensity_pct: pct,
                ..CelestialSphereControl::default()
            })],
        );
        let reply = frame(&mut w, &mut q);
        let snapshot = w.snapshot(64, 48, &fallback);
        assert_eq!(snapshot.stars_visible, stars);
        assert_eq!(snapshot.moon_visible, moon);
        let told = reply.packets.iter().any(|p| {
            matches!(p, Packet::ImageGeneratorMessage(m) if m.text.contains("star field intensity"))
        });
        if pct > 100.0 {
            assert_eq!(snapshot.star_intensity, 1.0);
            assert!(told, "the clamp is reported");
        } else {
            assert!((snapshot.star_intensity - 0.4).abs() < 1e-6);
            assert!(!told);
        }
    }
}

#[test]
fn the_hosts_cloud_layers_reach_the_snapshot_clamped_and_reported() {
    use cig_environment::clouds::CloudKind;
    let mut q = query();
    let scenario = "[[clouds]]\nbase_m = 900\nthickness_m = 300\ncoverage = 0.3\n";
    let mut w = world(scenario);
    let (lat, lon) = (lat_of_row(30.0), lon_of_col(30.0));
    let fallback = View {
        eye: Geodetic::new(lat, lon, 1000.0),
        orientation: Hpr::default(),
        fov: FovDeg::symmetric(60.0, 45.0),
        width_px: 64,
        height_px: 48,
    };
    send(
        &mut w,
        Version::V3_3,
        ByteOrder::LittleEndian,
        1,
        vec![
            entity_3(0, lat, lon, 120.0, 0.0),
            Packet::ViewControl(ViewControl {
                view_id: 0,
                entity_id: 0,
                ..ViewControl::default()
            }),
        ],
    );
    // Before the host sets any cloud, the scenario's layer is drawn.
    frame(&mut w, &mut q);
    let s = w.snapshot(64, 48, &fallback);
    assert_eq!(s.cloud_layers.len(), 1);
    assert!((s.cloud_layers[0].base_m - (900.0 + f64::from(GEOID_M))).abs() < 1e-6);
    assert!((s.cloud_cover_fraction - 0.3).abs() < 1e-12);
    let cloud = |layer_id: u8, cloud_type: u8, coverage_pct: f32| {
        Packet::WeatherControl(cig_cigi::WeatherControl {
            layer_id,
            weather_enable: true,
            scope: 0,
            cloud_type,
            coverage_pct,
            base_elevation_m: 2000.0,
            thickness_m: 800.0,
            horizontal_wind_speed_mps: 12.0,
            wind_direction_deg: 450.0,
            ..cig_cigi::WeatherControl::default()
        })
    };
    send(
        &mut w,
        Version::V3_3,
        ByteOrder::LittleEndian,
        2,
        vec![
            // Stratus at 150 % cover (clamped), cumulus at 40 %, and a layer of no cloud.
            cloud(1, 10, 150.0),
            cloud(2, 7, 40.0),
            cloud(3, 0, 90.0),
        ],
    );
    let message = frame(&mut w, &mut q);
    let s = w.snapshot(64, 48, &fallback);
    assert_eq!(s.cloud_layers.len(), 2, "{:?}", s.cloud_layers);
    let (a, b) = (s.cloud_layers[0], s.cloud_layers[1]);
    assert_eq!((a.kind, b.kind), (CloudKind::Stratus, CloudKind::Cumulus));
    assert_eq!((a.coverage, b.coverage), (1.0, 0.4));
    assert!(
        (a.base_m - (2000.0 + f64::from(GEOID_M))).abs() < 1e-3,
        "{a:?}"
    );
    assert_eq!((a.thickness_m, a.wind_speed_mps), (800.0, 12.0));
    assert_eq!(a.wind_from_deg, 90.0, "the direction wraps into 0..360");
    assert_eq!(s.cloud_cover_fraction, 1.0);
    assert!(s.cloud_layers.iter().all(|l| l.validate().is_ok()));
    let told: Vec<String> = message
        .packets
        .iter()
        .filter_map(|p| match p {
            Packet::ImageGeneratorMessage(m) => Some(m.text.clone()),
            _ => None,
        })
        .collect();
    assert!(
        told.iter()
            .any(|t| t.contains("layer 1") && t.contains("coverage")),
        "{told:?}"
    );
    // The origin of the clouds' pattern stays put while the eye moves.
    let origin = s.cloud_origin;
    send(
        &mut w,
        Version::V3_3,
        ByteOrder::LittleEndian,
        3,
        vec![entity_3(0, lat + 0.6, lon + 0.7, 120.0, 0.0)],
    );
    frame(&mut w, &mut q);
    assert_eq!(w.snapshot(64, 48, &fallback).cloud_origin, origin);
    // The operator's layer wins over the host's; an invalid one is refused.
    let operator = cig_environment::CloudLayer::new(3000.0, 500.0, 0.7, CloudKind::Altocumulus);
    assert!(w
        .set_operator_clouds(Some(vec![cig_environment::CloudLayer {
            coverage: 2.0,
            ..operator
        }]))
        .is_err());
    w.set_operator_clouds(Some(vec![operator])).expect("valid");
    let s = w.snapshot(64, 48, &fallback);
    assert_eq!(s.cloud_layers.len(), 1);
    assert_eq!(s.cloud_layers[0].kind, CloudKind::Altocumulus);
    w.set_operator_clouds(None).expect("back to the host");
    frame(&mut w, &mut q);
    assert_eq!(w.snapshot(64, 48, &fallback).cloud_layers.len(), 2);
}

/// A host's Component Control on a view moves its area-of-interest point (the eye tracker's
/// gaze), and the drawn point follows with a short lag; state 0 brings it back to the centre;
/// a point outside 90 degrees is refused and told to the host.
#[test]
fn a_views_point_of_interest_follows_the_hosts_component_control_with_a_lag() {
    let mut q = query();
    let mut w = world("");
    let (lat, lon) = (lat_of_row(64.0), lon_of_col(20.0));
    let fallback = View {
        eye: Geodetic::new(lat, lon, 1000.0),
        orientation: Hpr::default(),
        fov: FovDeg::symmetric(60.0, 45.0),
        width_px: 64,
        height_px: 48,
    };
    let point = |state: u8, right: f32, up: f32| {
        Packet::ShortComponentControl(cig_cigi::ShortComponentControl {
            component_id: cig_ig::session::POINT_OF_INTEREST_COMPONENT,
            instance_id: 0,
            component_class: 1,
            component_state: state,
            data: [right.to_bits(), up.to_bits()],
        })
    };
    send(
        &mut w,
        Version::V3_3,
        ByteOrder::LittleEndian,
        1,
        vec![
            entity_3(1, lat, lon, 300.0, 0.0),
            Packet::ViewControl(ViewControl {
                view_id: 0,
                entity_id: 1,
                ..ViewControl::default()
            }),
            point(1, 20.0, -10.0),
        ],
    );
    let drawn = |w: &IgWorld| w.snapshot(64, 48, &fallback).points_of_interest_deg[0];
    frame(&mut w, &mut q);
    let first = drawn(&w).expect("a point off the centre");
    assert!(
        first[0] > 0.0 && first[0] < 5.0 && first[1] < 0.0 && first[1] > -2.5,
        "one frame moves it a little of the way: {first:?}"
    );
    for _ in 0..120 {
        frame(&mut w, &mut q);
    }
    let settled = drawn(&w).expect("a point");
    assert!(
        (settled[0] - 20.0).abs() < 0.01 && (settled[1] + 10.0).abs() < 0.01,
        "{settled:?}"
    );
    send(
        &mut w,
        Version::V3_3,
        ByteOrder::LittleEndian,
        2,
        vec![point(1, 120.0, 0.0)],
    );
    frame(&mut w, &mut q);
    assert!(
        (drawn(&w).expect("kept")[0] - 20.0).abs() < 0.01,
        "a point beyond 90 degrees is refused"
    );
    send(
        &mut w,
        Version::V3_3,
        ByteOrder::LittleEndian,
        3,
        vec![point(0, 0.0, 0.0)],
    );
    for _ in 0..120 {
        frame(&mut w, &mut q);
    }
    assert_eq!(drawn(&w), None, "back at the view's centre");
}

/// A host frame with its clock (10 µs ticks) and a HAT request, as bytes.
fn clocked_frame(frame: u32, ticks: u32) -> Vec<u8> {
    let packets = vec![
        Packet::IgControl(IgControl {
            ig_mode: 1,
            host_frame_number: frame,
            timestamp_valid: true,
            timestamp_10us: ticks,
            ..IgControl::default()
        }),
        Packet::HatHotRequest(HatHotRequest {
            hat_hot_id: 5,
            request_type: 0,
            lat_deg_or_x_m: lat_of_row(10.0),
            lon_deg_or_y_m: lon_of_col(20.0),
            alt_m_or_z_m: 500.0,
            ..HatHotRequest::default()
        }),
    ];
    let mut bytes = Vec::new();
    encode_message(
        &Message::new(Version::V3_3, ByteOrder::LittleEndian, packets),
        &mut bytes,
    )
    .expect("encode");
    bytes
}

/// Host frame `frame` at 8 Hz on the host's clock; every eighth one also tells the time of
/// day (19:00:00 plus the host's clock; CIGI 3.3 tells only its minute), as `cig host` does
/// for channels that join late.
fn timed_frame(version: Version, frame: u32) -> Vec<u8> {
    let t_s = f64::from(frame) / 8.0;
    let mut packets = vec![Packet::IgControl(IgControl {
        ig_mode: 1,
        host_frame_number: frame,
        timestamp_valid: true,
        timestamp_10us: (t_s * 1e5).round() as u32,
        ..IgControl::default()
    })];
    if frame.is_multiple_of(8) {
        let c = UtcTime::from_calendar(2026, 6, 21, 19, 0, 0.0)
            .expect("time")
            .plus_seconds(t_s)
            .to_calendar();
        packets.push(Packet::CelestialSphereControl(CelestialSphereControl {
            hour: c.hour as u8,
            minute: c.minute as u8,
            seconds: c.second as f32,
            date_time_valid: true,
            date_mmddyyyy: c.month * 1_000_000 + c.day * 10_000 + c.year as u32,
            ..CelestialSphereControl::default()
        }));
    }
    let mut bytes = Vec::new();
    encode_message(
        &Message::new(version, ByteOrder::LittleEndian, packets),
        &mut bytes,
    )
    .expect("encode");
    bytes
}

#[test]
fn a_channel_that_reads_several_host_frames_at_once_keeps_the_hosts_time_of_day() {
    let mut q = query();
    let expected_s = UtcTime::from_calendar(2026, 6, 21, 19, 0, 0.0)
        .expect("time")
        .unix_seconds();
    for version in [Version::V3_3, Version::V4_0] {
        let mut prompt = world("");
        let mut behind = world("");
        let mut late = world("");
        for frame in 0..24u32 {
            let bytes = timed_frame(version, frame);
            let host_s = f64::from(frame) / 8.0;
            prompt.receive_cigi(&bytes).expect("host frame");
            prompt.step_to_host_clock(0.125, &mut q);
            behind.receive_cigi(&bytes).expect("host frame");
            // The slow channel reads frames 0, 1-9, 10-23: the time told in frames 8 and 16
            // is old by the host frame it steps to.
            if [0, 9, 23].contains(&frame) {
                behind.step_to_host_clock(0.125, &mut q);
                assert!(
                    (behind.unix_time_s() - prompt.unix_time_s()).abs() < 1e-3,
                    "{version:?} frame {frame}: {} s apart",
                    behind.unix_time_s() - prompt.unix_time_s()
                );
            }
            // A channel that restarts at host frame 10 and first hears the time at frame 16.
            if frame >= 10 {
                late.receive_cigi(&bytes).expect("host frame");
                late.step_to_host_clock(0.125, &mut q);
                if frame >= 16 {
                    assert!(
                        (late.unix_time_s() - prompt.unix_time_s()).abs() < 1e-3,
                        "{version:?} frame {frame}: the late one {} s off",
                        late.unix_time_s() - prompt.unix_time_s()
                    );
                }
            }
            // The host's time of day, never pulled back to the minute by a restatement.
            assert!(
                (prompt.unix_time_s() - (expected_s + host_s)).abs() < 1e-3,
                "{version:?} frame {frame}: {} s off",
                prompt.unix_time_s() - (expected_s + host_s)
            );
        }
    }
}

#[test]
fn channels_on_the_hosts_clock_agree_and_a_slave_answers_nothing() {
    let mut q = query();
    let mut master = world("");
    let mut slave = IgWorld::new(
        Scenario::from_toml("").expect("scenario"),
        WorldConfig {
            session: SessionConfig {
                answers_host: false,
                ..SessionConfig::default()
            },
            start: UtcTime::from_calendar(2026, 6, 21, 12, 0, 0.0).expect("time"),
            fog_mode: FogMode::Exponential,
            effects: EffectsConfig::default(),
            join_exercise: true,
        },
    )
    .expect("world");
    // A channel that joins at host frame 200 (a restart) and one there from the start.
    let mut late = world("");
    for frame in 0..400u32 {
        let ticks = frame * 1667;
        let bytes = clocked_frame(frame, ticks);
        master.receive_cigi(&bytes).expect("host frame");
        slave.receive_cigi(&bytes).expect("host frame");
        // The channels' own frame periods differ; the host's clock steps them.
        master.step_to_host_clock(0.016, &mut q);
        slave.step_to_host_clock(0.033, &mut q);
        let answered = master.host_message(&mut q, frame);
        assert!(
            answered.packets.len() >= 2,
            "the master answers the HAT request"
        );
        let silent = slave.host_message(&mut q, frame);
        assert_eq!(
            silent.packets.len(),
            1,
            "a slave's message is its Start of Frame only"
        );
        if frame >= 200 {
            late.receive_cigi(&bytes).expect("host frame");
            late.step_to_host_clock(0.5, &mut q);
            assert!(
                (late.unix_time_s() - master.unix_time_s()).abs() < 1e-6,
                "frame {frame}: {} against {}",
                late.unix_time_s(),
                master.unix_time_s()
            );
        }
        assert!(
            (slave.unix_time_s() - master.unix_time_s()).abs() < 1e-6,
            "frame {frame}"
        );
    }
    assert_eq!(slave.session().counters().hat_hot_answered, 0);
    assert!(master.session().counters().hat_hot_answered >= 399);
    // The host's clock is unwrapped across the 32-bit field's wrap (every 11.9 h of ticks).
    let mut wrapping = world("");
    let first_ticks = u32::MAX - 1000;
    wrapping
        .receive_cigi(&clocked_frame(0, first_ticks))
        .expect("host frame");
    wrapping
        .receive_cigi(&clocked_frame(1, first_ticks.wrapping_add(2000)))
        .expect("host frame");
    let host_s = wrapping.session().host_clock_s().expect("a host clock");
    assert!(
        (host_s - (f64::from(first_ticks) + 2000.0) * 1e-5).abs() < 1e-6,
        "{host_s}"
    );
}
