//! Dead reckoning against closed forms and numerical integration, smoothing, timeouts, the
//! remote entity table and the publisher's thresholds.

use std::collections::BTreeSet;
use std::f64::consts::PI;

use cig_dis::codec::{decode_pdu, encode_pdu, DisMessage, DisVersion, EncodeHeader};
use cig_dis::dead_reckoning::{
    dr_matrix, extrapolate, rotation_angle_between, DrAlgorithm, DrInput, EulerAngles,
};
use cig_dis::publisher::{OwnedEntityPublisher, OwnedEntityState, PublisherConfig, SendReason};
use cig_dis::remote::{
    local_heading_pitch_roll_deg, EntityKey, EntityTypeCode, RemoteEntityTable, RemoteTableConfig,
    RemovalReason, TableEvent,
};
use cig_dis::{EffectsRequested, EntityEffect};
use cig_geo::Geodetic;
use glam::{DMat3, DVec3};
use proptest::prelude::*;

const ALL: [DrAlgorithm; 10] = [
    DrAlgorithm::Other,
    DrAlgorithm::Static,
    DrAlgorithm::Fpw,
    DrAlgorithm::Rpw,
    DrAlgorithm::Rvw,
    DrAlgorithm::Fvw,
    DrAlgorithm::Fpb,
    DrAlgorithm::Rpb,
    DrAlgorithm::Rvb,
    DrAlgorithm::Fvb,
];

fn close(a: DVec3, b: DVec3, tol: f64) -> bool {
    (a - b).length() <= tol
}

fn base_input() -> DrInput {
    DrInput {
        position_ecef_m: DVec3::new(4_000_000.0, 300_000.0, 4_900_000.0),
        orientation: EulerAngles {
            psi_rad: 0.3,
            theta_rad: -0.2,
            phi_rad: 0.1,
        },
        velocity_ecef_mps: DVec3::new(10.0, -5.0, 2.0),
        acceleration_mps2: DVec3::new(0.5, 0.25, -1.0),
        angular_velocity_body_radps: DVec3::new(0.01, -0.02, 0.2),
    }
}

#[test]
fn algorithm_codes_round_trip() {
    for a in ALL {
        assert_eq!(DrAlgorithm::from_code(a.code()), a);
    }
    assert_eq!(DrAlgorithm::from_code(200), DrAlgorithm::Other);
}

#[test]
fn static_models_do_not_move() {
    let input = base_input();
    for a in [DrAlgorithm::Static, DrAlgorithm::Other] {
        let pose = extrapolate(a, &input, 30.0);
        assert_eq!(pose.position_ecef_m, input.position_ecef_m);
        assert!(
            rotation_angle_between(pose.body_to_world, input.orientation.body_to_world()) < 1e-12
        );
    }
}

#[test]
fn constant_velocity_world_models_follow_p0_plus_vt() {
    let input = base_input();
    for a in [DrAlgorithm::Fpw, DrAlgorithm::Rpw, DrAlgorithm::Fpb] {
        let pose = extrapolate(a, &input, 7.5);
        assert!(close(
            pose.position_ecef_m,
            input.position_ecef_m + input.velocity_ecef_mps * 7.5,
            1e-6
        ));
    }
}

#[test]
fn constant_acceleration_world_models_follow_the_parabola() {
    let input = base_input();
    let t = 4.0;
    let expected = input.position_ecef_m
        + input.velocity_ecef_mps * t
        + input.acceleration_mps2 * (0.5 * t * t);
    for a in [DrAlgorithm::Fvw, DrAlgorithm::Rvw] {
        let pose = extrapolate(a, &input, t);
        assert!(close(pose.position_ecef_m, expected, 1e-6));
        assert!(close(
            pose.velocity_ecef_mps,
            input.velocity_ecef_mps + input.acceleration_mps2 * t,
            1e-9
        ));
    }
    // The fixed one keeps its orientation, the rotating one turns.
    let fixed = extrapolate(DrAlgorithm::Fvw, &input, t);
    assert!(rotation_angle_between(fixed.body_to_world, input.orientation.body_to_world()) < 1e-12);
    let turned = extrapolate(DrAlgorithm::Rvw, &input, t);
    let w = input.angular_velocity_body_radps.length();
    let angle = rotation_angle_between(turned.body_to_world, input.orientation.body_to_world());
    assert!((angle - w * t).abs() < 1e-9, "{angle} vs {}", w * t);
}

#[test]
fn constant_turn_in_body_axes_is_a_circle() {
    // Level orientation (body axes = ECEF axes), speed v along body x, yaw rate r about body z:
    // the closed form is a circle of radius v / r.
    let (v, r) = (20.0, 0.1);
    let input = DrInput {
        position_ecef_m: DVec3::new(1000.0, 2000.0, 3000.0),
        orientation: EulerAngles::default(),
        velocity_ecef_mps: DVec3::new(v, 0.0, 0.0),
        acceleration_mps2: DVec3::ZERO,
        angular_velocity_body_radps: DVec3::new(0.0, 0.0, r),
    };
    for t in [0.5, 3.0, 10.0, 31.4] {
        let pose = extrapolate(DrAlgorithm::Rpb, &input, t);
        let expected = input.position_ecef_m
            + DVec3::new(v / r * (r * t).sin(), v / r * (1.0 - (r * t).cos()), 0.0);
        assert!(close(pose.position_ecef_m, expected, 1e-9), "t={t}");
        let o = pose.orientation();
        let psi = (r * t + PI).rem_euclid(2.0 * PI) - PI;
        assert!((o.psi_rad - psi).abs() < 1e-9, "psi {} vs {psi}", o.psi_rad);
        assert!(o.theta_rad.abs() < 1e-12 && o.phi_rad.abs() < 1e-12);
        assert!(close(
            pose.velocity_ecef_mps,
            DVec3::new(v * (r * t).cos(), v * (r * t).sin(), 0.0),
            1e-9
        ));
    }
    // World-axis RPW goes straight while turning.
    let straight = extrapolate(DrAlgorithm::Rpw, &input, 10.0);
    assert!(close(
        straight.position_ecef_m,
        input.position_ecef_m + DVec3::new(v * 10.0, 0.0, 0.0),
        1e-9
    ));
}

#[test]
fn fixed_body_models_with_level_orientation_match_world_models() {
    let mut input = base_input();
    input.orientation = EulerAngles::default();
    let t = 6.0;
    let fvb = extrapolate(DrAlgorithm::Fvb, &input, t);
    let fvw = extrapolate(DrAlgorithm::Fvw, &input, t);
    assert!(close(fvb.position_ecef_m, fvw.position_ecef_m, 1e-6));
}

#[test]
fn orientation_update_equals_the_standards_dr_matrix() {
    let input = base_input();
    for t in [0.0, 0.001, 1.0, 9.0] {
        let pose = extrapolate(DrAlgorithm::Rvb, &input, t);
        let world_to_body_0 = input.orientation.body_to_world().transpose();
        let expected = dr_matrix(input.angular_velocity_body_radps, t) * world_to_body_0;
        let got = pose.body_to_world.transpose();
        assert!(rotation_angle_between(expected, got) < 1e-9, "t={t}");
        assert!((expected - got)
            .abs()
            .to_cols_array()
            .iter()
            .all(|d| *d < 1e-9));
    }
}

/// Simpson integration of dP/dt = R0 e^{Ωτ} (v_b + a_b τ), with e^{Ωτ} from the orientation the
/// RVB model reports — independent of the R1/R2 closed forms.
fn integrate_rvb(input: &DrInput, t: f64, steps: usize) -> DVec3 {
    let r0 = input.orientation.body_to_world();
    let v_body = r0.transpose() * input.velocity_ecef_mps;
    let velocity = |tau: f64| {
        let rot = extrapolate(DrAlgorithm::Rpw, input, tau).body_to_world;
        rot * (v_body + input.acceleration_mps2 * tau)
    };
    let h = t / steps as f64;
    let mut sum = velocity(0.0) + velocity(t);
    for i in 1..steps {
        let w = if i % 2 == 1 { 4.0 } else { 2.0 };
        sum += velocity(h * i as f64) * w;
    }
    input.position_ecef_m + sum * (h / 3.0)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    #[test]
    fn rvb_matches_numerical_integration(
        psi in -3.0f64..3.0, theta in -1.4f64..1.4, phi in -3.0f64..3.0,
        v in prop::array::uniform3(-50.0f64..50.0),
        a in prop::array::uniform3(-5.0f64..5.0),
        w in prop::array::uniform3(-0.5f64..0.5),
        t in 0.0f64..8.0,
    ) {
        let input = DrInput {
            position_ecef_m: DVec3::new(4.0e6, 3.0e5, 4.9e6),
            orientation: EulerAngles { psi_rad: psi, theta_rad: theta, phi_rad: phi },
            velocity_ecef_mps: DVec3::from_array(v),
            acceleration_mps2: DVec3::from_array(a),
            angular_velocity_body_radps: DVec3::from_array(w),
        };
        let closed = extrapolate(DrAlgorithm::Rvb, &input, t).position_ecef_m;
        let numeric = integrate_rvb(&input, t, 200);
        prop_assert!(close(closed, numeric, 1e-4), "{closed} vs {numeric}");
    }

    #[test]
    fn every_model_at_time_zero_is_the_update(
        which in 0usize..10,
        psi in -3.0f64..3.0, theta in -1.5f64..1.5, phi in -3.0f64..3.0,
        v in prop::array::uniform3(-300.0f64..300.0),
        a in prop::array::uniform3(-20.0f64..20.0),
        w in prop::array::uniform3(-2.0f64..2.0),
    ) {
        let input = DrInput {
            position_ecef_m: DVec3::new(-2.7e6, -4.3e6, 3.85e6),
            orientation: EulerAngles { psi_rad: psi, theta_rad: theta, phi_rad: phi },
            velocity_ecef_mps: DVec3::from_array(v),
            acceleration_mps2: DVec3::from_array(a),
            angular_velocity_body_radps: DVec3::from_array(w),
        };
        let pose = extrapolate(ALL[which], &input, 0.0);
        prop_assert_eq!(pose.position_ecef_m, input.position_ecef_m);
        prop_assert!(rotation_angle_between(pose.body_to_world, input.orientation.body_to_world()) < 1e-9);
    }

    #[test]
    fn euler_angles_survive_the_matrix(
        psi in -3.1f64..3.1, theta in -1.55f64..1.55, phi in -3.1f64..3.1,
    ) {
        let e = EulerAngles { psi_rad: psi, theta_rad: theta, phi_rad: phi };
        let back = EulerAngles::from_body_to_world(e.body_to_world());
        prop_assert!((back.psi_rad - psi).abs() < 1e-9);
        prop_assert!((back.theta_rad - theta).abs() < 1e-9);
        prop_assert!((back.phi_rad - phi).abs() < 1e-9);
    }

    #[test]
    fn rotations_stay_orthonormal(
        which in 0usize..10,
        w in prop::array::uniform3(-3.0f64..3.0),
        t in 0.0f64..100.0,
    ) {
        let mut input = base_input();
        input.angular_velocity_body_radps = DVec3::from_array(w);
        let m = extrapolate(ALL[which], &input, t).body_to_world;
        let err = (m.transpose() * m - DMat3::IDENTITY).abs().to_cols_array().into_iter().fold(0.0, f64::max);
        prop_assert!(err < 1e-9);
        prop_assert!((m.determinant() - 1.0).abs() < 1e-9);
    }
}

#[test]
fn small_angle_series_and_closed_form_both_match_integration() {
    // Just below and above the series threshold (w t = 1e-3), and at w = 0.
    let mut input = base_input();
    let t = 2.0;
    for wt in [0.0, 0.5e-3, 0.999e-3, 1.001e-3, 2e-3] {
        input.angular_velocity_body_radps = DVec3::new(0.3, -0.2, 0.9).normalize() * (wt / t);
        let closed = extrapolate(DrAlgorithm::Rvb, &input, t).position_ecef_m;
        let numeric = integrate_rvb(&input, t, 400);
        assert!(
            close(closed, numeric, 1e-7),
            "wt={wt}: {}",
            (closed - numeric).length()
        );
    }
}

fn tank() -> EntityTypeCode {
    EntityTypeCode {
        kind: 1,
        domain: 1,
        country: 225,
        category: 1,
        subcategory: 1,
        specific: 3,
        extra: 0,
    }
}

fn publisher(key: EntityKey, algorithm: DrAlgorithm) -> OwnedEntityPublisher {
    OwnedEntityPublisher::new(
        key,
        tank(),
        1,
        "CIG",
        PublisherConfig {
            algorithm,
            ..PublisherConfig::default()
        },
    )
}

fn truth_at(t: f64) -> OwnedEntityState {
    OwnedEntityState {
        position_ecef_m: DVec3::new(4_000_000.0, 300_000.0, 4_900_000.0)
            + DVec3::new(8.0, 0.0, 0.0) * t,
        orientation: EulerAngles {
            psi_rad: 0.4,
            theta_rad: 0.0,
            phi_rad: 0.0,
        },
        velocity_ecef_mps: DVec3::new(8.0, 0.0, 0.0),
        acceleration_ecef_mps2: DVec3::ZERO,
        angular_velocity_body_radps: DVec3::ZERO,
        appearance: 0,
    }
}

fn header() -> EncodeHeader {
    EncodeHeader {
        version: DisVersion::V7,
        exercise_id: 1,
        timestamp: 0,
    }
}

/// Publishes through the codec into a table, as two nodes would.
fn deliver(
    table: &mut RemoteEntityTable,
    now_s: f64,
    body: cig_dis::dis_rs::entity_state::model::EntityState,
) -> Vec<TableEvent> {
    let bytes =
        encode_pdu(header(), &DisMessage::EntityState(Box::new(body))).expect("valid in this test");
    let pdu = decode_pdu(&bytes).expect("valid in this test");
    table.apply(now_s, &pdu).expect("valid in this test")
}

const KEY: EntityKey = EntityKey {
    site: 5,
    application: 6,
    entity: 7,
};

#[test]
fn publisher_sends_first_then_only_the_heartbeat_while_dr_is_exact() {
    let mut p = publisher(KEY, DrAlgorithm::Fpw);
    assert_eq!(
        p.update(0.0, &truth_at(0.0)).map(|s| s.0),
        Some(SendReason::First)
    );
    for i in 1..50 {
        let t = f64::from(i) * 0.1;
        assert!(p.update(t, &truth_at(t)).is_none(), "t={t}");
    }
    assert_eq!(
        p.update(5.0, &truth_at(5.0)).map(|s| s.0),
        Some(SendReason::Heartbeat)
    );
    assert!(p.update(5.1, &truth_at(5.1)).is_none());
}

#[test]
fn publisher_position_threshold_is_one_metre() {
    let mut p = publisher(KEY, DrAlgorithm::Fpw);
    // Truth accelerates at 2 m/s² that FPW does not announce: error ½ a t² reaches 1 m at 1 s.
    let accelerating = |t: f64| {
        let mut s = truth_at(t);
        s.position_ecef_m += DVec3::new(0.0, 1.0, 0.0) * t * t;
        s
    };
    assert!(p.update(0.0, &accelerating(0.0)).is_some());
    assert!(p.update(0.99, &accelerating(0.99)).is_none());
    assert_eq!(
        p.update(1.01, &accelerating(1.01)).map(|s| s.0),
        Some(SendReason::Position)
    );
}

#[test]
fn publisher_orientation_threshold_is_three_degrees() {
    let mut p = publisher(KEY, DrAlgorithm::Fpw);
    // Turning at 10 °/s unannounced: 3° after 0.3 s.
    let turning = |t: f64| {
        let mut s = truth_at(t);
        s.orientation.psi_rad += (10.0 * t).to_radians();
        s
    };
    assert!(p.update(0.0, &turning(0.0)).is_some());
    assert!(p.update(0.29, &turning(0.29)).is_none());
    assert_eq!(
        p.update(0.31, &turning(0.31)).map(|s| s.0),
        Some(SendReason::Orientation)
    );
}

#[test]
fn publisher_sends_on_appearance_change() {
    let mut p = publisher(KEY, DrAlgorithm::Fpw);
    assert!(p.update(0.0, &truth_at(0.0)).is_some());
    let mut smoking = truth_at(1.0);
    smoking.appearance = 1 << 5;
    assert_eq!(
        p.update(1.0, &smoking).map(|s| s.0),
        Some(SendReason::Appearance)
    );
}

#[test]
fn published_turning_entity_is_reproduced_by_a_receiver() {
    // RVB publisher; the receiver's DR must match the publisher's own prediction.
    let mut p = publisher(KEY, DrAlgorithm::Rvb);
    let mut truth = truth_at(0.0);
    truth.angular_velocity_body_radps = DVec3::new(0.0, 0.0, 0.05);
    truth.acceleration_ecef_mps2 = DVec3::new(0.0, 0.3, 0.0);
    truth.appearance = (1 << 6) | (1 << 7);
    let (_, body) = p.update(0.0, &truth).expect("valid in this test");
    let mut table = RemoteEntityTable::new(RemoteTableConfig::default());
    let events = deliver(&mut table, 100.0, body.clone());
    assert_eq!(events[0], TableEvent::Appeared(KEY));
    assert!(matches!(&events[1], TableEvent::EffectsChanged { diff, .. }
        if diff.start == vec![EntityEffect::EngineSmoke, EntityEffect::DustCloud(cig_dis::DustCloudSize::Small)]));
    let received = table.pose(KEY, 103.0).expect("valid in this test");
    let (algorithm, input) = cig_dis::remote::dr_input_from_entity_state(&body);
    let predicted = extrapolate(algorithm, &input, 3.0);
    assert_eq!(algorithm, DrAlgorithm::Rvb);
    assert!(close(
        received.position_ecef_m,
        predicted.position_ecef_m,
        1e-9
    ));
    // And single precision on the wire keeps it within centimetres of the truth's DR.
    let truth_input = DrInput {
        position_ecef_m: truth.position_ecef_m,
        orientation: truth.orientation,
        velocity_ecef_mps: truth.velocity_ecef_mps,
        acceleration_mps2: truth.orientation.body_to_world().transpose()
            * truth.acceleration_ecef_mps2,
        angular_velocity_body_radps: truth.angular_velocity_body_radps,
    };
    let exact = extrapolate(DrAlgorithm::Rvb, &truth_input, 3.0);
    assert!(close(received.position_ecef_m, exact.position_ecef_m, 0.01));
}

fn es_for(
    key: EntityKey,
    position: DVec3,
    velocity: DVec3,
    appearance: u32,
) -> cig_dis::dis_rs::entity_state::model::EntityState {
    let p = publisher(key, DrAlgorithm::Fpw);
    p.build_entity_state(&OwnedEntityState {
        position_ecef_m: position,
        orientation: EulerAngles {
            psi_rad: 0.2,
            theta_rad: 0.1,
            phi_rad: 0.0,
        },
        velocity_ecef_mps: velocity,
        acceleration_ecef_mps2: DVec3::ZERO,
        angular_velocity_body_radps: DVec3::ZERO,
        appearance,
    })
}

#[test]
fn smoothing_blends_without_a_jump_and_then_follows_the_update() {
    let config = RemoteTableConfig {
        smoothing_s: 1.0,
        ..RemoteTableConfig::default()
    };
    let mut table = RemoteEntityTable::new(config);
    let p0 = DVec3::new(4_000_000.0, 300_000.0, 4_900_000.0);
    let v = DVec3::new(10.0, 0.0, 0.0);
    deliver(&mut table, 0.0, es_for(KEY, p0, v, 0));
    // At 2 s the sender reports it is 5 m off the DR track and turned.
    let tu = 2.0;
    let before = table.pose(KEY, tu - 1e-6).expect("valid in this test");
    let mut update = es_for(KEY, p0 + v * tu + DVec3::new(0.0, 5.0, 0.0), v, 0);
    update.entity_orientation.psi = 0.5;
    deliver(&mut table, tu, update);
    let at = table.pose(KEY, tu).expect("valid in this test");
    assert!(
        close(before.position_ecef_m, at.position_ecef_m, 1e-4),
        "jump {}",
        (before.position_ecef_m - at.position_ecef_m).length()
    );
    assert!(rotation_angle_between(before.body_to_world, at.body_to_world) < 1e-5);
    // Small steps through the blend never move more than speed allows plus the blend's share.
    let mut last = at.position_ecef_m;
    for i in 1..=100 {
        let t = tu + f64::from(i) * 0.01;
        let pose = table.pose(KEY, t).expect("valid in this test");
        let step = (pose.position_ecef_m - last).length();
        assert!(step < 10.0 * 0.01 + 0.09, "step {step} at {t}");
        last = pose.position_ecef_m;
    }
    // After the smoothing time the new track alone is shown.
    let after = table.pose(KEY, tu + 1.5).expect("valid in this test");
    assert!(close(
        after.position_ecef_m,
        p0 + v * (tu + 1.5) + DVec3::new(0.0, 5.0, 0.0),
        1e-6
    ));
    assert!((after.orientation().psi_rad - 0.5).abs() < 1e-6);
}

#[test]
fn far_updates_snap() {
    let mut table = RemoteEntityTable::new(RemoteTableConfig::default());
    let p0 = DVec3::new(4_000_000.0, 300_000.0, 4_900_000.0);
    deliver(&mut table, 0.0, es_for(KEY, p0, DVec3::ZERO, 0));
    let far = p0 + DVec3::new(1000.0, 0.0, 0.0);
    deliver(&mut table, 1.0, es_for(KEY, far, DVec3::ZERO, 0));
    assert!(close(
        table
            .pose(KEY, 1.0)
            .expect("valid in this test")
            .position_ecef_m,
        far,
        1e-6
    ));
}

#[test]
fn entities_time_out_after_twelve_seconds() {
    let mut table = RemoteEntityTable::new(RemoteTableConfig::default());
    let p0 = DVec3::new(4_000_000.0, 300_000.0, 4_900_000.0);
    deliver(&mut table, 0.0, es_for(KEY, p0, DVec3::ZERO, 1 << 15));
    assert!(table.expire(11.9).is_empty());
    assert_eq!(table.len(), 1);
    let events = table.expire(12.1);
    assert_eq!(events.len(), 1);
    let TableEvent::Removed { key, reason, diff } = &events[0] else {
        panic!("not a removal");
    };
    assert_eq!((*key, *reason), (KEY, RemovalReason::Timeout));
    assert_eq!(diff.stop, vec![EntityEffect::Flames]);
    assert!(table.is_empty());
}

#[test]
fn deactivated_entities_leave_at_once() {
    let mut table = RemoteEntityTable::new(RemoteTableConfig::default());
    let p0 = DVec3::new(4_000_000.0, 300_000.0, 4_900_000.0);
    deliver(&mut table, 0.0, es_for(KEY, p0, DVec3::ZERO, 0));
    let events = deliver(&mut table, 1.0, es_for(KEY, p0, DVec3::ZERO, 1 << 23));
    assert!(matches!(
        events[0],
        TableEvent::Removed {
            reason: RemovalReason::Deactivated,
            ..
        }
    ));
    assert!(table.is_empty());
}

#[test]
fn exercise_site_and_own_filters() {
    let p0 = DVec3::new(4_000_000.0, 300_000.0, 4_900_000.0);
    let config = RemoteTableConfig {
        exercise_id: 1,
        accepted_sites: BTreeSet::from([5]),
        own_address: Some((5, 99)),
        ..RemoteTableConfig::default()
    };
    let mut table = RemoteEntityTable::new(config);
    let send = |table: &mut RemoteEntityTable, exercise: u8, key: EntityKey| {
        let bytes = encode_pdu(
            EncodeHeader {
                version: DisVersion::V7,
                exercise_id: exercise,
                timestamp: 0,
            },
            &DisMessage::EntityState(Box::new(es_for(key, p0, DVec3::ZERO, 0))),
        )
        .expect("valid in this test");
        table.apply(0.0, &decode_pdu(&bytes).expect("valid in this test"))
    };
    use cig_dis::remote::Ignored;
    assert_eq!(send(&mut table, 2, KEY), Err(Ignored::Exercise));
    assert_eq!(
        send(&mut table, 1, EntityKey { site: 6, ..KEY }),
        Err(Ignored::Site)
    );
    assert_eq!(
        send(
            &mut table,
            1,
            EntityKey {
                application: 99,
                ..KEY
            }
        ),
        Err(Ignored::Own)
    );
    assert!(send(&mut table, 1, KEY).is_ok());
    assert_eq!(table.len(), 1);
}

#[test]
fn snapshot_is_ordered_and_complete() {
    let mut table = RemoteEntityTable::new(RemoteTableConfig::default());
    let origin = Geodetic::new(52.0, 5.0, 100.0).to_ecef();
    for entity in [9u16, 2, 5] {
        let key = EntityKey { entity, ..KEY };
        deliver(
            &mut table,
            0.0,
            es_for(key, origin, DVec3::new(1.0, 0.0, 0.0), 1 << 5),
        );
    }
    let snap = table.snapshot(2.0);
    let ids: Vec<u16> = snap.iter().map(|s| s.key.entity).collect();
    assert_eq!(ids, vec![2, 5, 9]);
    let s = &snap[0];
    assert_eq!(s.entity_type, tank());
    assert!(close(
        s.position_ecef_m,
        origin + DVec3::new(2.0, 0.0, 0.0),
        1e-6
    ));
    assert!((s.geodetic.lat_deg - 52.0).abs() < 1e-3);
    assert!(s.effects.smoke_plume);
    assert_eq!(
        s.effects,
        EffectsRequested {
            smoke_plume: true,
            ..EffectsRequested::default()
        }
    );
    assert_eq!(s.marking, "CIG");
    assert!((s.age_s - 2.0).abs() < 1e-12);
}

#[test]
fn local_heading_pitch_roll_reads_north_and_east() {
    let g = Geodetic::new(30.0, 40.0, 0.0);
    let p = g.to_ecef();
    let (lat, lon) = (30f64.to_radians(), 40f64.to_radians());
    let east = DVec3::new(-lon.sin(), lon.cos(), 0.0);
    let north = DVec3::new(-lat.sin() * lon.cos(), -lat.sin() * lon.sin(), lat.cos());
    let up = east.cross(north);
    let facing_north = DMat3::from_cols(north, east, -up);
    let hpr = local_heading_pitch_roll_deg(facing_north, p);
    assert!(hpr[0].abs() < 1e-9 || (hpr[0] - 360.0).abs() < 1e-9);
    assert!(hpr[1].abs() < 1e-9 && hpr[2].abs() < 1e-9);
    let facing_east = DMat3::from_cols(east, -north, -up);
    let hpr = local_heading_pitch_roll_deg(facing_east, p);
    assert!((hpr[0] - 90.0).abs() < 1e-9);
    // Nose 10° up while facing east.
    let (s, c) = 10f64.to_radians().sin_cos();
    let nose_up = DMat3::from_cols(east * c + up * s, -north, -(up * c - east * s));
    let hpr = local_heading_pitch_roll_deg(nose_up, p);
    assert!((hpr[1] - 10.0).abs() < 1e-9 && hpr[2].abs() < 1e-9);
}
