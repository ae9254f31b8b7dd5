//! Interoperation with an independent DIS implementation: the Python package `opendis`
//! (PyPI `opendis`, Open-DIS for Python, DIS 7). Python builds Entity State and Detonation PDUs
//! that this crate decodes, and parses the ones this crate encodes. Skipped, with a message,
//! when `python3` or `opendis` is missing (`pip install opendis`).

mod common;

use common::{hex, unhex};

use cig_dis::codec::{decode_pdu, encode_pdu, DisMessage, DisVersion, EncodeHeader};
use cig_dis::detonation::impact_effect;
use cig_dis::dis_rs::detonation::model::{Detonation, DetonationDescriptor};
use cig_dis::dis_rs::enumerations::DetonationResult;
use cig_dis::dis_rs::model::{EntityId, EventId, Location, MunitionDescriptor, VectorF32};
use cig_dis::dis_rs::BodyRaw;
use cig_dis::publisher::{OwnedEntityPublisher, OwnedEntityState, PublisherConfig};
use cig_dis::remote::{dr_input_from_entity_state, EntityKey, EntityTypeCode};
use cig_dis::{DrAlgorithm, EffectsRequested, EulerAngles};
use glam::DVec3;

/// Runs a Python script with opendis; `None` (and a message) when the peer is unavailable.
fn python(script: &str, arg: &str) -> Option<String> {
    common::python("", script, arg)
}

#[test]
fn opendis_entity_state_decodes_here() {
    let script = r"
p = EntityStatePdu()
p.entityID = EntityID(11, 22, 33)
p.forceId = 2
t = p.entityType
t.entityKind, t.domain, t.country, t.category, t.subcategory, t.specific, t.extra = 1, 1, 222, 2, 3, 4, 5
p.entityLinearVelocity = Vector3Float(3.5, -1.25, 0.5)
p.entityLocation = Vector3Double(-2700000.5, -4300000.25, 3850000.125)
p.entityOrientation = EulerAngles(0.75, -0.125, 0.0625)
p.entityAppearance = (1 << 5) | (2 << 7) | (1 << 15)
p.capabilities = 0
p.deadReckoningParameters.deadReckoningAlgorithm = 4
p.deadReckoningParameters.entityLinearAcceleration = Vector3Float(0.5, 0.25, -0.5)
p.deadReckoningParameters.entityAngularVelocity = Vector3Float(0.0, 0.0, 0.2)
p.marking.characterSet = 1
p.marking.setString('PEER1')
print(finish(p, 1, 1).hex())
";
    let Some(out) = python(script, "") else {
        return;
    };
    let pdu = decode_pdu(&unhex(&out)).expect("opendis bytes decode");
    assert_eq!(pdu.header.exercise_id, 4);
    let DisMessage::EntityState(es) = pdu.message else {
        panic!("not an entity state");
    };
    assert_eq!(es.entity_id, EntityId::new(11, 22, 33));
    assert_eq!(
        EntityTypeCode::from_dis(&es.entity_type),
        EntityTypeCode {
            kind: 1,
            domain: 1,
            country: 222,
            category: 2,
            subcategory: 3,
            specific: 4,
            extra: 5
        }
    );
    let (algorithm, input) = dr_input_from_entity_state(&es);
    assert_eq!(algorithm, DrAlgorithm::Rvw);
    assert_eq!(
        input.position_ecef_m,
        DVec3::new(-2_700_000.5, -4_300_000.25, 3_850_000.125)
    );
    assert_eq!(input.velocity_ecef_mps, DVec3::new(3.5, -1.25, 0.5));
    assert_eq!(input.orientation.psi_rad, 0.75);
    assert_eq!(input.acceleration_mps2, DVec3::new(0.5, 0.25, -0.5));
    assert_eq!(
        input.angular_velocity_body_radps,
        DVec3::new(0.0, 0.0, f64::from(0.2_f32))
    );
    let effects = EffectsRequested::from_appearance(u32::from(&es.entity_appearance), 1, 1);
    assert!(effects.smoke_plume && effects.flaming);
    assert_eq!(effects.dust_cloud, cig_dis::DustCloudSize::Medium);
    assert_eq!(es.entity_marking.marking_string, "PEER1");
}

#[test]
fn opendis_detonation_decodes_here() {
    let script = r"
p = DetonationPdu()
p.firingEntityID = EntityID(7, 8, 9)
p.targetEntityID = EntityID(0, 0, 0)
p.explodingEntityID = EntityID(7, 8, 10)
p.eventID.simulationAddress.site = 7
p.eventID.simulationAddress.application = 8
p.eventID.eventNumber = 4321
p.velocity = Vector3Float(0.0, 0.0, -250.0)
p.location = Vector3Double(4000000.0, 300000.0, 4900000.0)
p.detonationResult = 19
print(finish(p, 3, 2).hex())
";
    let Some(out) = python(script, "") else {
        return;
    };
    let pdu = decode_pdu(&unhex(&out)).expect("opendis bytes decode");
    let DisMessage::Detonation(d) = pdu.message else {
        panic!("not a detonation");
    };
    assert_eq!(d.source_entity_id, EntityId::new(7, 8, 9));
    assert_eq!(d.event_id, EventId::new(7, 8, 4321));
    let effect = impact_effect(&d).expect("building hit, medium");
    assert_eq!(effect.surface, cig_dis::ImpactSurface::Building);
    assert_eq!(
        effect.position_ecef_m,
        DVec3::new(4_000_000.0, 300_000.0, 4_900_000.0)
    );
    assert_eq!(effect.event.event_number, 4321);
}

#[test]
fn our_entity_state_and_detonation_parse_in_opendis() {
    let publisher = OwnedEntityPublisher::new(
        EntityKey {
            site: 31,
            application: 32,
            entity: 33,
        },
        EntityTypeCode {
            kind: 1,
            domain: 2,
            country: 225,
            category: 1,
            subcategory: 2,
            specific: 3,
            extra: 0,
        },
        1,
        "CIGOUT",
        PublisherConfig {
            algorithm: DrAlgorithm::Rvb,
            ..PublisherConfig::default()
        },
    );
    let es = publisher.build_entity_state(&OwnedEntityState {
        position_ecef_m: DVec3::new(4_000_000.25, 300_000.5, 4_900_000.75),
        orientation: EulerAngles {
            psi_rad: 0.5,
            theta_rad: 0.25,
            phi_rad: -0.125,
        },
        velocity_ecef_mps: DVec3::new(100.0, 50.0, -10.0),
        acceleration_ecef_mps2: DVec3::ZERO,
        angular_velocity_body_radps: DVec3::new(0.0, 0.0, 0.125),
        appearance: 1 << 15,
    });
    let header = EncodeHeader {
        version: DisVersion::V7,
        exercise_id: 9,
        timestamp: 12345,
    };
    let es_bytes =
        encode_pdu(header, &DisMessage::EntityState(Box::new(es))).expect("valid in this test");
    let detonation = Detonation::builder()
        .with_source_entity_id(EntityId::new(31, 32, 33))
        .with_target_entity_id(EntityId::new(0, 0, 0))
        .with_exploding_entity_id(EntityId::new(31, 32, 34))
        .with_event_id(EventId::new(31, 32, 555))
        .with_velocity(VectorF32::new(0.0, 0.0, -100.0))
        .with_world_location(Location::new(1.5, 2.5, 3.5))
        .with_descriptor(DetonationDescriptor::Munition(MunitionDescriptor::default()))
        .with_entity_location(VectorF32::new(0.0, 0.0, 0.0))
        .with_detonation_result(DetonationResult::from(3))
        .build();
    let det_bytes = encode_pdu(header, &DisMessage::Detonation(Box::new(detonation)))
        .expect("valid in this test");
    let script = r"
out = []
for h in sys.argv[1].split(','):
    p = createPdu(bytes.fromhex(h))
    d = {'type': p.pduType, 'exercise': p.exerciseID, 'length': p.length, 'timestamp': p.timestamp}
    if p.pduType == 1:
        d.update(id=[p.entityID.siteID, p.entityID.applicationID, p.entityID.entityID],
                 kind=[p.entityType.entityKind, p.entityType.domain, p.entityType.country],
                 loc=[p.entityLocation.x, p.entityLocation.y, p.entityLocation.z],
                 vel=[p.entityLinearVelocity.x, p.entityLinearVelocity.y, p.entityLinearVelocity.z],
                 ori=[p.entityOrientation.psi, p.entityOrientation.theta, p.entityOrientation.phi],
                 app=p.entityAppearance, drm=p.deadReckoningParameters.deadReckoningAlgorithm,
                 w=p.deadReckoningParameters.entityAngularVelocity.z,
                 marking=p.marking.charactersString().rstrip(' '))  # dis-rs pads with spaces
    else:
        d.update(event=p.eventID.eventNumber, result=p.detonationResult,
                 loc=[p.location.x, p.location.y, p.location.z])
    out.append(d)
print(json.dumps(out))
";
    let arg = format!("{},{}", hex(&es_bytes), hex(&det_bytes));
    let Some(out) = python(script, &arg) else {
        return;
    };
    let expected_es = format!(
        "{{\"type\": 1, \"exercise\": 9, \"length\": {}, \"timestamp\": 12345, \"id\": [31, 32, 33], \"kind\": [1, 2, 225], \"loc\": [4000000.25, 300000.5, 4900000.75], \"vel\": [100.0, 50.0, -10.0], \"ori\": [0.5, 0.25, -0.125], \"app\": 32768, \"drm\": 8, \"w\": 0.125, \"marking\": \"CIGOUT\"}}",
        es_bytes.len()
    );
    let expected_det = format!(
        "{{\"type\": 3, \"exercise\": 9, \"length\": {}, \"timestamp\": 12345, \"event\": 555, \"result\": 3, \"loc\": [1.5, 2.5, 3.5]}}",
        det_bytes.len()
    );
    assert_eq!(out, format!("[{expected_es}, {expected_det}]"));
}
