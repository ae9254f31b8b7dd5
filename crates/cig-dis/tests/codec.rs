//! Codec tests: round trips through dis-rs, hand-built byte vectors from the standard's layouts,
//! the Environmental Process PDU, and garbage that must never panic.

use cig_dis::codec::{
    decode_datagram, decode_header, decode_pdu, encode_pdu, timestamp_from_seconds_past_hour,
    timestamp_seconds_past_hour, DecodeError, DisMessage, DisVersion, EncodeHeader,
};
use cig_dis::dis_rs::data::model::Data;
use cig_dis::dis_rs::data_query::model::DataQuery;
use cig_dis::dis_rs::detonation::model::{Detonation, DetonationDescriptor};
use cig_dis::dis_rs::entity_state::model::{
    DrParameters, EntityAppearance, EntityMarking, EntityState,
};
use cig_dis::dis_rs::enumerations::{
    Country, DeadReckoningAlgorithm, DetonationResult, EntityKind, ForceId, PlatformDomain,
    VariableRecordType,
};
use cig_dis::dis_rs::fire::model::Fire;
use cig_dis::dis_rs::model::{
    EntityId, EntityType, EventId, FixedDatum, Location, MunitionDescriptor, Orientation,
    VariableDatum, VectorF32,
};
use cig_dis::dis_rs::remove_entity::model::RemoveEntity;
use cig_dis::dis_rs::set_data::model::SetData;
use cig_dis::dis_rs::BodyRaw;
use cig_dis::environmental::{
    self, EnvironmentGeometry, EnvironmentRecord, EnvironmentalProcess, GaussianPlume,
    GaussianPuff, RECORD_TYPE_GAUSSIAN_PLUME,
};
use cig_dis::time_sync::{LightningStrike, NodeId, TimeMessage};
use proptest::prelude::*;

fn tank_type() -> EntityType {
    EntityType::default()
        .with_kind(EntityKind::Platform)
        .with_domain(PlatformDomain::Land)
        .with_country(Country::from(225))
        .with_category(1)
        .with_subcategory(1)
        .with_specific(3)
        .with_extra(0)
}

fn sample_entity_state() -> EntityState {
    let t = tank_type();
    EntityState::builder()
        .with_entity_id(EntityId::new(10, 20, 30))
        .with_force_id(ForceId::Friendly)
        .with_entity_type(t)
        .with_alternative_entity_type(t)
        .with_velocity(VectorF32::new(1.5, -2.25, 0.125))
        .with_location(Location::new(4_000_000.5, 300_000.25, 4_900_000.75))
        .with_orientation(Orientation::new(0.5, -0.25, 0.125))
        .with_appearance(EntityAppearance::from_bytes((1 << 5) | (2 << 7), &t))
        .with_dead_reckoning_parameters(
            DrParameters::default()
                .with_algorithm(DeadReckoningAlgorithm::from(4))
                .with_linear_acceleration(VectorF32::new(0.5, 0.0, -0.5))
                .with_angular_velocity(VectorF32::new(0.0, 0.0, 0.1)),
        )
        .with_marking(EntityMarking::new_ascii("CIG01"))
        .build()
}

fn sample_detonation() -> Detonation {
    Detonation::builder()
        .with_source_entity_id(EntityId::new(1, 2, 3))
        .with_target_entity_id(EntityId::new(0, 0, 0))
        .with_exploding_entity_id(EntityId::new(1, 2, 4))
        .with_event_id(EventId::new(1, 2, 77))
        .with_velocity(VectorF32::new(0.0, 0.0, -300.0))
        .with_world_location(Location::new(4_000_000.0, 300_000.0, 4_900_000.0))
        .with_descriptor(DetonationDescriptor::Munition(MunitionDescriptor::default()))
        .with_entity_location(VectorF32::new(0.0, 0.0, 0.0))
        .with_detonation_result(DetonationResult::from(3))
        .build()
}

fn header(version: DisVersion) -> EncodeHeader {
    EncodeHeader {
        version,
        exercise_id: 7,
        timestamp: timestamp_from_seconds_past_hour(1234.5, true),
    }
}

fn round_trip(version: DisVersion, message: &DisMessage) -> DisMessage {
    let bytes = encode_pdu(header(version), message).expect("encodes");
    let decoded = decode_pdu(&bytes).expect("decodes");
    assert_eq!(decoded.header.version, version);
    assert_eq!(decoded.header.exercise_id, 7);
    assert_eq!(usize::from(decoded.header.length_octets), bytes.len());
    decoded.message
}

#[test]
fn every_dis_rs_body_round_trips_in_version_7() {
    let messages = vec![
        DisMessage::EntityState(Box::new(sample_entity_state())),
        DisMessage::Detonation(Box::new(sample_detonation())),
        DisMessage::Fire(Box::new(
            Fire::builder()
                .with_firing_entity_id(EntityId::new(1, 2, 3))
                .with_target_entity_id(EntityId::new(4, 5, 6))
                .with_entity_id(EntityId::new(1, 2, 9))
                .with_event_id(EventId::new(1, 2, 77))
                .with_location_in_world(Location::new(1.0, 2.0, 3.0))
                .with_velocity(VectorF32::new(100.0, 0.0, 0.0))
                .with_range(1500.0)
                .build(),
        )),
        DisMessage::RemoveEntity(
            RemoveEntity::builder()
                .with_origination_id(EntityId::new(1, 2, 0))
                .with_receiving_id(EntityId::new(3, 4, 5))
                .with_request_id(99)
                .build(),
        ),
        DisMessage::DataQuery(
            DataQuery::builder()
                .with_origination_id(EntityId::new(1, 2, 0))
                .with_receiving_id(EntityId::new(0xFFFF, 0xFFFF, 0xFFFF))
                .with_request_id(5)
                .with_time_interval(0)
                .with_fixed_datums(vec![VariableRecordType::from(52_370)])
                .with_variable_datums(vec![VariableRecordType::from(52_000)])
                .build(),
        ),
        DisMessage::SetData(
            SetData::builder()
                .with_origination_id(EntityId::new(1, 2, 0))
                .with_receiving_id(EntityId::new(0xFFFF, 0xFFFF, 0xFFFF))
                .with_request_id(6)
                .with_fixed_datums(vec![FixedDatum::new(VariableRecordType::from(52_370), 7)])
                .with_variable_datums(vec![VariableDatum::new(
                    VariableRecordType::from(52_000),
                    vec![1, 2, 3, 4, 5, 6, 7, 8],
                )])
                .build(),
        ),
        DisMessage::Data(
            Data::builder()
                .with_origination_id(EntityId::new(1, 2, 0))
                .with_receiving_id(EntityId::new(3, 4, 0))
                .with_request_id(7)
                .with_fixed_datums(vec![FixedDatum::new(VariableRecordType::from(52_370), 9)])
                .with_variable_datums(vec![VariableDatum::new(
                    VariableRecordType::from(52_000),
                    vec![8, 7, 6, 5, 4, 3, 2, 1],
                )])
                .build(),
        ),
    ];
    for message in &messages {
        assert_eq!(
            without_dr_other_parameters(round_trip(DisVersion::V7, message)),
            without_dr_other_parameters(message.clone())
        );
    }
}

/// dis-rs reads the 15 "other parameters" octets by the DR algorithm (quaternion or local Euler
/// angles) even when they are all zero (type 0, none), so a None record comes back re-typed;
/// the octets on the wire stay zero (checked in `dr_other_parameters_stay_zero_on_the_wire`).
fn without_dr_other_parameters(message: DisMessage) -> DisMessage {
    match message {
        DisMessage::EntityState(mut es) => {
            es.dead_reckoning_parameters.other_parameters = Default::default();
            DisMessage::EntityState(es)
        }
        other => other,
    }
}

#[test]
fn dr_other_parameters_stay_zero_on_the_wire() {
    let message = DisMessage::EntityState(Box::new(sample_entity_state()));
    let bytes = encode_pdu(header(DisVersion::V7), &message).expect("valid in this test");
    // Header 12, id 6, force 1, count 1, types 16, velocity 12, location 24, orientation 12,
    // appearance 4, algorithm 1: the 15 other-parameter octets follow at 89.
    assert_eq!(bytes[88], 4);
    assert_eq!(&bytes[89..104], &[0u8; 15]);
}

#[test]
fn entity_state_round_trips_in_version_6() {
    let message = DisMessage::EntityState(Box::new(sample_entity_state()));
    let DisMessage::EntityState(back) = round_trip(DisVersion::V6, &message) else {
        panic!("not an entity state");
    };
    let DisMessage::EntityState(sent) = &message else {
        unreachable!()
    };
    assert_eq!(back.entity_id, sent.entity_id);
    assert_eq!(back.entity_type, sent.entity_type);
    assert_eq!(back.entity_location, sent.entity_location);
    assert_eq!(back.entity_orientation, sent.entity_orientation);
    assert_eq!(back.entity_linear_velocity, sent.entity_linear_velocity);
    assert_eq!(
        u32::from(&back.entity_appearance),
        u32::from(&sent.entity_appearance)
    );
    assert_eq!(
        back.dead_reckoning_parameters.linear_acceleration,
        sent.dead_reckoning_parameters.linear_acceleration
    );
    assert_eq!(
        back.dead_reckoning_parameters.angular_velocity,
        sent.dead_reckoning_parameters.angular_velocity
    );
    assert_eq!(
        back.dead_reckoning_parameters.algorithm,
        sent.dead_reckoning_parameters.algorithm
    );
    assert_eq!(back.entity_marking, sent.entity_marking);
}

fn put_f32(out: &mut Vec<u8>, v: f32) {
    out.extend_from_slice(&v.to_be_bytes());
}

fn put_f64(out: &mut Vec<u8>, v: f64) {
    out.extend_from_slice(&v.to_be_bytes());
}

/// An Entity State PDU written field by field from IEEE 1278.1-2012 §7.2.2 (Table 131).
fn hand_built_entity_state(version: u8) -> Vec<u8> {
    let mut b = vec![version, 3, 1, 1];
    b.extend_from_slice(&0x0000_1235_u32.to_be_bytes()); // timestamp
    b.extend_from_slice(&144u16.to_be_bytes()); // length
    b.extend_from_slice(&[0, 0]); // status + padding
    b.extend_from_slice(&[0, 42, 0, 7, 1, 0]); // entity id 42:7:256
    b.extend_from_slice(&[2, 0]); // force opposing, 0 variable parameters
    b.extend_from_slice(&[1, 1, 0, 222, 1, 2, 3, 4]); // entity type 1:1:222:1:2:3:4
    b.extend_from_slice(&[0; 8]); // alternative type
    for v in [10.0_f32, -20.0, 5.0] {
        put_f32(&mut b, v);
    }
    for v in [-2_700_000.0_f64, -4_300_000.0, 3_850_000.0] {
        put_f64(&mut b, v);
    }
    for v in [1.0_f32, 0.1, -0.2] {
        put_f32(&mut b, v);
    }
    b.extend_from_slice(&((1u32 << 15) | (3 << 7)).to_be_bytes()); // flaming, large dust
    b.push(2); // DRM FPW
    b.extend_from_slice(&[0; 15]);
    for v in [0.0_f32, 0.0, 0.0, 0.0, 0.0, 0.25] {
        put_f32(&mut b, v);
    }
    b.push(1); // ASCII
    b.extend_from_slice(b"T72\0\0\0\0\0\0\0\0");
    b.extend_from_slice(&[0; 4]); // capabilities
    assert_eq!(b.len(), 144);
    b
}

#[test]
fn hand_built_entity_state_decodes_in_both_versions() {
    for version in [6u8, 7] {
        let bytes = hand_built_entity_state(version);
        let pdu = decode_pdu(&bytes).expect("decodes");
        assert_eq!(pdu.header.exercise_id, 3);
        assert_eq!(pdu.header.pdu_type, 1);
        assert_eq!(pdu.header.timestamp, 0x1235);
        let DisMessage::EntityState(es) = pdu.message else {
            panic!("not an entity state");
        };
        assert_eq!(es.entity_id, EntityId::new(42, 7, 256));
        assert_eq!(u8::from(es.entity_type.kind), 1);
        assert_eq!(u16::from(es.entity_type.country), 222);
        assert_eq!(es.entity_type.extra, 4);
        assert_eq!(es.entity_location.x_coordinate, -2_700_000.0);
        assert_eq!(es.entity_location.z_coordinate, 3_850_000.0);
        assert_eq!(es.entity_linear_velocity.second_vector_component, -20.0);
        assert_eq!(es.entity_orientation.theta, 0.1);
        assert_eq!(u32::from(&es.entity_appearance), (1 << 15) | (3 << 7));
        assert_eq!(u8::from(es.dead_reckoning_parameters.algorithm), 2);
        assert_eq!(
            es.dead_reckoning_parameters
                .angular_velocity
                .third_vector_component,
            0.25
        );
        assert_eq!(es.entity_marking.marking_string, "T72");
    }
}

#[test]
fn bundled_datagram_yields_each_pdu() {
    let mut datagram = hand_built_entity_state(7);
    datagram.extend(
        encode_pdu(
            header(DisVersion::V7),
            &DisMessage::Detonation(Box::new(sample_detonation())),
        )
        .expect("valid in this test"),
    );
    let out = decode_datagram(&datagram);
    assert_eq!(out.len(), 2);
    assert!(matches!(
        out[0].as_ref().expect("valid in this test").message,
        DisMessage::EntityState(_)
    ));
    assert!(matches!(
        out[1].as_ref().expect("valid in this test").message,
        DisMessage::Detonation(_)
    ));
}

#[test]
fn bad_headers_are_reported() {
    let good = hand_built_entity_state(7);
    assert_eq!(
        decode_pdu(&good[..5]),
        Err(DecodeError::TruncatedHeader { got: 5 })
    );
    assert_eq!(
        decode_pdu(&good[..100]),
        Err(DecodeError::Truncated {
            pdu_type: 1,
            declared: 144,
            available: 100
        })
    );
    let mut v5 = good.clone();
    v5[0] = 5;
    assert_eq!(decode_pdu(&v5), Err(DecodeError::UnsupportedVersion(5)));
    let mut short = good.clone();
    short[8..10].copy_from_slice(&8u16.to_be_bytes());
    assert_eq!(
        decode_pdu(&short),
        Err(DecodeError::LengthBelowHeader {
            pdu_type: 1,
            declared: 8
        })
    );
    // A declared length that cuts the body short is a malformed body, not a panic.
    let mut cut = good.clone();
    cut[8..10].copy_from_slice(&100u16.to_be_bytes());
    assert!(matches!(
        decode_pdu(&cut),
        Err(DecodeError::Malformed { pdu_type: 1, .. })
    ));
    // Unknown types keep their header.
    let mut other = good;
    other[2] = 200;
    let pdu = decode_pdu(&other).expect("valid in this test");
    assert_eq!(pdu.message, DisMessage::Unsupported);
    assert_eq!(
        decode_header(&other).expect("valid in this test").pdu_type,
        200
    );
}

#[test]
fn timestamps_convert_both_ways() {
    let ts = timestamp_from_seconds_past_hour(1800.0, true);
    assert_eq!(ts, (1u32 << 31) | 1);
    let (s, absolute) = timestamp_seconds_past_hour(ts);
    assert!(absolute);
    assert!((s - 1800.0).abs() < 1e-5);
    assert_eq!(timestamp_from_seconds_past_hour(3600.0, false), 0);
    let (s, absolute) = timestamp_seconds_past_hour(timestamp_from_seconds_past_hour(12.25, false));
    assert!(!absolute);
    assert!((s - 12.25).abs() < 2e-6, "one unit is 1.68 us");
}

fn sample_plume() -> GaussianPlume {
    GaussianPlume {
        source_location_ecef_m: [4_000_000.0, 300_000.0, 4_900_000.0],
        orientation_rad: [0.5, 0.0, -0.25],
        length_m: 250.0,
        width_m: 40.0,
        height_m: 30.0,
        length_rate_mps: 5.0,
        width_rate_mps: 0.5,
        height_rate_mps: 0.25,
        leading_edge_centroid_height_m: 20.0,
        leading_edge_velocity_mps: [3.0, -1.0, 0.5],
    }
}

fn sample_puff() -> GaussianPuff {
    GaussianPuff {
        puff_location_ecef_m: [4_000_010.0, 300_005.0, 4_900_002.0],
        origination_location_ecef_m: [4_000_000.0, 300_000.0, 4_900_000.0],
        sigma_m: [10.0, 8.0, 6.0],
        sigma_rate_mps: [1.0, 0.8, 0.6],
        orientation_rad: [0.1, 0.2, 0.3],
        velocity_mps: [2.0, 1.0, 0.0],
        angular_velocity_radps: [0.0, 0.0, 0.01],
        centroid_height_m: 15.0,
    }
}

fn sample_process() -> EnvironmentalProcess {
    EnvironmentalProcess {
        process_id: EntityId::new(1, 2, 3),
        environment_type: EntityType::default()
            .with_kind(EntityKind::from(4))
            .with_domain(PlatformDomain::from(0))
            .with_category(1),
        model_type: 0,
        is_last: false,
        is_active: true,
        sequence_number: 42,
        records: vec![
            EnvironmentRecord {
                index: 0,
                geometry: EnvironmentGeometry::GaussianPlume(sample_plume()),
            },
            EnvironmentRecord {
                index: 1,
                geometry: EnvironmentGeometry::GaussianPuff(sample_puff()),
            },
            EnvironmentRecord {
                index: 2,
                geometry: EnvironmentGeometry::Unknown {
                    record_type: 655_360,
                    data: vec![9; 24],
                },
            },
        ],
    }
}

#[test]
fn environmental_process_round_trips_in_both_versions() {
    let message = DisMessage::EnvironmentalProcess(sample_process());
    for version in [DisVersion::V6, DisVersion::V7] {
        let bytes = encode_pdu(header(version), &message).expect("valid in this test");
        // 12 header + 20 fixed + (8+76+4) plume + (8+112) puff + (8+24) point.
        assert_eq!(bytes.len(), 12 + 20 + 88 + 120 + 32);
        assert_eq!(bytes[2], 41);
        assert_eq!(bytes[3], 9);
        assert_eq!(round_trip(version, &message), message);
    }
}

/// One plume record written from the layout in the module doc (IEEE 1278.1-2012 §7.10.5,
/// §6.2.31 and SISO-REF-010 record 264), independently of the encoder.
fn hand_built_environmental_process() -> Vec<u8> {
    let mut b = vec![7, 1, 41, 9, 0, 0, 0, 0];
    b.extend_from_slice(&(12u16 + 20 + 88).to_be_bytes());
    b.extend_from_slice(&[0, 0]);
    b.extend_from_slice(&[0, 5, 0, 6, 0, 7]); // process id 5:6:7
    b.extend_from_slice(&[4, 0, 0, 0, 2, 0, 0, 0]); // environment type 4:0:0:2:0:0:0
    b.push(0); // model type
    b.push(0b11); // last + active
    b.extend_from_slice(&1u16.to_be_bytes()); // one record
    b.extend_from_slice(&9u16.to_be_bytes()); // sequence number
    b.extend_from_slice(&RECORD_TYPE_GAUSSIAN_PLUME.to_be_bytes());
    b.extend_from_slice(&608u16.to_be_bytes()); // 76 octets in bits
    b.extend_from_slice(&[3, 0]); // index, padding
    for v in [1.0_f64, 2.0, 3.0] {
        put_f64(&mut b, v);
    }
    for v in [
        0.1_f32, 0.2, 0.3, 100.0, 10.0, 5.0, 1.0, 0.5, 0.25, 4.0, 6.0, 7.0, 8.0,
    ] {
        put_f32(&mut b, v);
    }
    b.extend_from_slice(&[0; 4]); // to the 64-bit boundary
    b
}

#[test]
fn hand_built_environmental_process_decodes_and_re_encodes_identically() {
    let bytes = hand_built_environmental_process();
    let pdu = decode_pdu(&bytes).expect("valid in this test");
    let DisMessage::EnvironmentalProcess(p) = &pdu.message else {
        panic!("not an environmental process");
    };
    assert_eq!(p.process_id, EntityId::new(5, 6, 7));
    assert_eq!(u8::from(p.environment_type.kind), 4);
    assert_eq!(p.environment_type.category, 2);
    assert!(p.is_last && p.is_active);
    assert_eq!(p.sequence_number, 9);
    assert_eq!(p.records.len(), 1);
    assert_eq!(p.records[0].index, 3);
    let EnvironmentGeometry::GaussianPlume(plume) = p.records[0].geometry else {
        panic!("not a plume");
    };
    assert_eq!(plume.source_location_ecef_m, [1.0, 2.0, 3.0]);
    assert_eq!(plume.orientation_rad, [0.1, 0.2, 0.3]);
    assert_eq!(plume.length_m, 100.0);
    assert_eq!(plume.width_rate_mps, 0.5);
    assert_eq!(plume.height_rate_mps, 0.25);
    assert_eq!(plume.leading_edge_centroid_height_m, 4.0);
    assert_eq!(plume.leading_edge_velocity_mps, [6.0, 7.0, 8.0]);
    let again = encode_pdu(
        EncodeHeader {
            version: DisVersion::V7,
            exercise_id: 1,
            timestamp: 0,
        },
        &pdu.message,
    )
    .expect("valid in this test");
    assert_eq!(again, bytes);
}

#[test]
fn environmental_process_rejects_absurd_record_counts() {
    let mut body = environmental::encode_body(&sample_process());
    body[16..18].copy_from_slice(&5000u16.to_be_bytes());
    assert!(matches!(
        environmental::decode_body(&body),
        Err(environmental::EnvironmentalError::TooManyRecords(5000))
    ));
}

fn finite_f32() -> impl Strategy<Value = f32> {
    -1.0e6_f32..1.0e6
}

fn finite_f64() -> impl Strategy<Value = f64> {
    -1.0e7_f64..1.0e7
}

prop_compose! {
    fn arb_plume()(
        loc in prop::array::uniform3(finite_f64()),
        ori in prop::array::uniform3(finite_f32()),
        dims in prop::array::uniform7(finite_f32()),
        vel in prop::array::uniform3(finite_f32()),
    ) -> GaussianPlume {
        GaussianPlume {
            source_location_ecef_m: loc,
            orientation_rad: ori,
            length_m: dims[0],
            width_m: dims[1],
            height_m: dims[2],
            length_rate_mps: dims[3],
            width_rate_mps: dims[4],
            height_rate_mps: dims[5],
            leading_edge_centroid_height_m: dims[6],
            leading_edge_velocity_mps: vel,
        }
    }
}

prop_compose! {
    fn arb_puff()(
        locs in prop::array::uniform6(finite_f64()),
        f in prop::array::uniform16(finite_f32()),
    ) -> GaussianPuff {
        GaussianPuff {
            puff_location_ecef_m: [locs[0], locs[1], locs[2]],
            origination_location_ecef_m: [locs[3], locs[4], locs[5]],
            sigma_m: [f[0], f[1], f[2]],
            sigma_rate_mps: [f[3], f[4], f[5]],
            orientation_rad: [f[6], f[7], f[8]],
            velocity_mps: [f[9], f[10], f[11]],
            angular_velocity_radps: [f[12], f[13], f[14]],
            centroid_height_m: f[15],
        }
    }
}

fn arb_geometry() -> impl Strategy<Value = EnvironmentGeometry> {
    prop_oneof![
        arb_plume().prop_map(EnvironmentGeometry::GaussianPlume),
        arb_puff().prop_map(EnvironmentGeometry::GaussianPuff),
        (1u32..1_000_000, prop::collection::vec(any::<u8>(), 0..40)).prop_filter_map(
            "known types are not raw",
            |(record_type, data)| {
                (record_type != RECORD_TYPE_GAUSSIAN_PLUME
                    && record_type != environmental::RECORD_TYPE_GAUSSIAN_PUFF)
                    .then_some(EnvironmentGeometry::Unknown { record_type, data })
            }
        ),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(128))]

    #[test]
    fn environmental_process_round_trips(
        records in prop::collection::vec((any::<u8>(), arb_geometry()), 0..6),
        sequence in any::<u16>(),
        status in 0u8..4,
        site in any::<u16>(),
    ) {
        let process = EnvironmentalProcess {
            process_id: EntityId::new(site, 2, 3),
            environment_type: EntityType::default(),
            model_type: 0,
            is_last: status & 1 != 0,
            is_active: status & 2 != 0,
            sequence_number: sequence,
            records: records
                .into_iter()
                .map(|(index, geometry)| EnvironmentRecord { index, geometry })
                .collect(),
        };
        let body = environmental::encode_body(&process);
        prop_assert_eq!(body.len() % 4, 0);
        prop_assert_eq!(environmental::decode_body(&body).expect("valid in this test"), process);
    }

    #[test]
    fn garbage_never_panics(bytes in prop::collection::vec(any::<u8>(), 0..400)) {
        let _ = decode_datagram(&bytes);
        let _ = environmental::decode_body(&bytes);
    }

    #[test]
    fn garbage_behind_a_plausible_header_never_panics(
        version in 6u8..8,
        pdu_type in prop::sample::select(vec![1u8, 2, 3, 12, 18, 19, 20, 41, 67, 99]),
        body in prop::collection::vec(any::<u8>(), 0..300),
    ) {
        let mut bytes = vec![version, 1, pdu_type, 1, 0, 0, 0, 0];
        let length = u16::try_from(12 + body.len()).expect("valid in this test");
        bytes.extend_from_slice(&length.to_be_bytes());
        bytes.extend_from_slice(&[0, 0]);
        bytes.extend_from_slice(&body);
        let _ = decode_datagram(&bytes);
    }

    #[test]
    fn truncated_and_mutated_valid_pdus_never_panic(
        which in 0usize..3,
        cut in 0usize..400,
        flips in prop::collection::vec((0usize..400, any::<u8>()), 0..6),
        fix_length in any::<bool>(),
    ) {
        let mut bytes = match which {
            0 => hand_built_entity_state(7),
            1 => hand_built_environmental_process(),
            _ => encode_pdu(header(DisVersion::V7), &DisMessage::Detonation(Box::new(sample_detonation()))).expect("valid in this test"),
        };
        for (at, value) in flips {
            if let Some(b) = bytes.get_mut(at) {
                *b = value;
            }
        }
        bytes.truncate(cut);
        if fix_length && bytes.len() >= 12 {
            let length = u16::try_from(bytes.len()).expect("valid in this test");
            bytes[8..10].copy_from_slice(&length.to_be_bytes());
        }
        let _ = decode_datagram(&bytes);
    }
}

#[test]
fn received_non_ascii_markings_re_encode_safely() {
    // A marking octet above 0x7F decodes (lossily) to a 3-octet UTF-8 character; dis-rs's
    // writer would underflow on it. The codec keeps 11 ASCII characters instead.
    let mut bytes = hand_built_entity_state(7);
    bytes[129..140].copy_from_slice(&[
        0xC5, b'A', b'B', b' ', b' ', b' ', b' ', b' ', b' ', b' ', b'Z',
    ]);
    let pdu = decode_pdu(&bytes).expect("decodes");
    let again = encode_pdu(header(DisVersion::V7), &pdu.message).expect("re-encodes");
    let DisMessage::EntityState(es) = decode_pdu(&again).expect("decodes again").message else {
        panic!("not an entity state");
    };
    assert!(es.entity_marking.marking_string.starts_with("AB"));
    assert!(es.entity_marking.marking_string.is_ascii());
}

#[test]
fn oversized_bodies_are_refused() {
    let data = Data::builder()
        .with_origination_id(EntityId::new(1, 2, 0))
        .with_receiving_id(EntityId::new(3, 4, 0))
        .with_request_id(7)
        .with_fixed_datums(vec![])
        .with_variable_datums(vec![VariableDatum::new(
            VariableRecordType::from(52_000),
            vec![0; 70_000],
        )])
        .build();
    assert!(matches!(
        encode_pdu(header(DisVersion::V7), &DisMessage::Data(data)),
        Err(cig_dis::EncodeError::TooLong(_))
    ));
}

/// Every PDU kind the codec decodes, in both versions, as mutation seeds.
fn seed_pdus() -> Vec<Vec<u8>> {
    let node = NodeId {
        site: 1,
        application: 2,
    };
    let messages = vec![
        DisMessage::EntityState(Box::new(sample_entity_state())),
        DisMessage::Detonation(Box::new(sample_detonation())),
        DisMessage::Fire(Box::new(Fire::builder().with_range(10.0).build())),
        DisMessage::RemoveEntity(RemoveEntity::builder().with_request_id(3).build()),
        TimeMessage::Query {
            from: node,
            request_id: 1,
        }
        .to_message(),
        TimeMessage::Announce {
            from: node,
            to: None,
            request_id: 0,
            world_time_ms: 1,
            rate: 1.0,
        }
        .to_message(),
        TimeMessage::Set {
            from: node,
            world_time_ms: 2,
            rate: 2.0,
        }
        .to_message(),
        LightningStrike {
            from: node,
            position_ecef_m: glam::DVec3::ONE,
            seed: 5,
            intensity: 1.0,
        }
        .to_message(),
        DisMessage::EnvironmentalProcess(sample_process()),
    ];
    let mut out = Vec::new();
    for version in [DisVersion::V6, DisVersion::V7] {
        for m in &messages {
            out.push(encode_pdu(header(version), m).expect("valid in this test"));
        }
    }
    out
}

/// A deterministic mutation run (xorshift64): byte changes, cuts, length fixes, type and version
/// swaps of valid PDUs, each decoded and, when it decodes, re-encoded and decoded again. This run
/// found two dis-rs faults the codec now fences off (a marking that re-encodes with an
/// underflowing pad, and dis-rs reading leftover body octets as a second PDU of a type whose
/// parser panics). `CIG_DIS_MUTATIONS` (default 300,000) and `CIG_DIS_MUTATION_SEED` make
/// longer runs.
#[test]
fn mutated_pdus_never_panic() {
    let seeds = seed_pdus();
    let env = |name: &str, default: u64| {
        std::env::var(name)
            .ok()
            .and_then(|v| v.parse::<u64>().ok())
            .unwrap_or(default)
    };
    let runs = usize::try_from(env("CIG_DIS_MUTATIONS", 300_000)).unwrap_or(300_000);
    let mut state: u64 = env("CIG_DIS_MUTATION_SEED", 0x9E37_79B9_7F4A_7C15).max(1);
    let mut next = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        state
    };
    let mut decoded = 0usize;
    for i in 0..runs {
        let mut b = seeds[i % seeds.len()].clone();
        for _ in 0..next() % 8 {
            let at = usize::try_from(next()).unwrap_or(0) % b.len();
            b[at] = next().to_le_bytes()[0];
        }
        if next() % 3 == 0 {
            b.truncate(usize::try_from(next()).unwrap_or(0) % (b.len() + 1));
        }
        if next() % 2 == 0 && b.len() >= 12 {
            let length = u16::try_from(b.len()).unwrap_or(u16::MAX);
            b[8..10].copy_from_slice(&length.to_be_bytes());
        }
        if next() % 4 == 0 && b.len() > 2 {
            b[2] =
                [1u8, 2, 3, 12, 18, 19, 20, 41, 26, 0][usize::try_from(next() % 10).unwrap_or(0)];
            b[0] = 6 + u8::from(next() % 2 == 0);
        }
        for pdu in decode_datagram(&b).into_iter().flatten() {
            decoded += 1;
            let h = EncodeHeader {
                version: pdu.header.version,
                exercise_id: 0,
                timestamp: 0,
            };
            if let Ok(bytes) = encode_pdu(h, &pdu.message) {
                let _ = decode_pdu(&bytes);
            }
        }
    }
    assert!(
        decoded > runs / 6,
        "the run must exercise the decoders, {decoded} decoded"
    );
}
