//! Appearance effects, detonation seeds, time-master election and lightning.

use cig_dis::codec::{decode_pdu, encode_pdu, DisMessage, DisVersion, EncodeHeader};
use cig_dis::detonation::{classify_result, impact_effect, splitmix64, EventIdentity};
use cig_dis::dis_rs::detonation::model::{Detonation, DetonationDescriptor};
use cig_dis::dis_rs::enumerations::DetonationResult;
use cig_dis::dis_rs::model::{EntityId, EventId, Location, MunitionDescriptor, VectorF32};
use cig_dis::dis_rs::BodyRaw;
use cig_dis::time_sync::{
    LightningStrike, NodeId, TimeMessage, TimeRole, TimeSync, TimeSyncConfig,
};
use cig_dis::{DustCloudSize, EffectsRequested, EntityEffect, ImpactSize, ImpactSurface};
use glam::DVec3;
use proptest::prelude::*;

#[test]
fn appearance_bits_decode_per_kind() {
    let bits = (1 << 5) | (1 << 6) | (1 << 15) | (3 << 7);
    let land = EffectsRequested::from_appearance(bits, 1, 1);
    assert_eq!(
        land,
        EffectsRequested {
            smoke_plume: true,
            engine_smoke: true,
            flaming: true,
            dust_cloud: DustCloudSize::Large
        }
    );
    // Air platforms: bits 7-8 are trailing effects, not dust.
    let air = EffectsRequested::from_appearance(bits, 1, 2);
    assert_eq!(air.dust_cloud, DustCloudSize::None);
    assert!(air.smoke_plume && air.engine_smoke && air.flaming);
    // Munitions share smoke/flame bits.
    assert!(EffectsRequested::from_appearance(1 << 15, 2, 0).flaming);
    // Life forms: bits 5-8 are compliance status, nothing is requested.
    assert_eq!(
        EffectsRequested::from_appearance(bits, 3, 1),
        EffectsRequested::default()
    );
    assert_eq!(
        EffectsRequested::from_appearance(1 << 7, 1, 1).dust_cloud,
        DustCloudSize::Small
    );
    assert_eq!(
        EffectsRequested::from_appearance(2 << 7, 1, 1).dust_cloud,
        DustCloudSize::Medium
    );
}

#[test]
fn appearance_diff_lists_starts_and_stops() {
    let none = EffectsRequested::default();
    let smoke = EffectsRequested::from_appearance(1 << 5, 1, 1);
    let d = none.diff(smoke);
    assert_eq!(d.start, vec![EntityEffect::SmokePlume]);
    assert!(d.stop.is_empty());
    assert!(smoke.diff(smoke).is_empty());
    let small_dust = EffectsRequested::from_appearance((1 << 5) | (1 << 7), 1, 1);
    let large_dust_fire = EffectsRequested::from_appearance((1 << 15) | (3 << 7), 1, 1);
    let d = small_dust.diff(large_dust_fire);
    assert_eq!(
        d.start,
        vec![
            EntityEffect::Flames,
            EntityEffect::DustCloud(DustCloudSize::Large)
        ]
    );
    assert_eq!(
        d.stop,
        vec![
            EntityEffect::SmokePlume,
            EntityEffect::DustCloud(DustCloudSize::Small)
        ]
    );
}

proptest! {
    #[test]
    fn effects_survive_the_appearance_bits(
        smoke in any::<bool>(), engine in any::<bool>(), flame in any::<bool>(),
        dust in 0u8..4, other_bits in any::<u32>(),
    ) {
        let e = EffectsRequested {
            smoke_plume: smoke,
            engine_smoke: engine,
            flaming: flame,
            dust_cloud: [DustCloudSize::None, DustCloudSize::Small, DustCloudSize::Medium, DustCloudSize::Large][usize::from(dust)],
        };
        let bits = e.apply_to_appearance(other_bits);
        prop_assert_eq!(EffectsRequested::from_appearance(bits, 1, 1), e);
        // Unrelated bits are kept.
        let mask = (1u32 << 5) | (1 << 6) | (1 << 15) | (3 << 7);
        prop_assert_eq!(bits & !mask, other_bits & !mask);
    }

    #[test]
    fn distinct_events_get_distinct_seeds(
        a in (any::<u16>(), any::<u16>(), any::<u16>()),
        b in (any::<u16>(), any::<u16>(), any::<u16>()),
    ) {
        let ea = EventIdentity { site: a.0, application: a.1, event_number: a.2 };
        let eb = EventIdentity { site: b.0, application: b.1, event_number: b.2 };
        prop_assert_eq!(ea == eb, ea.effect_seed() == eb.effect_seed());
    }
}

#[test]
fn seeds_match_the_splitmix64_reference() {
    // SplitMix64's first output for state 0 is the published 0xE220A8397B1DCDAF.
    assert_eq!(splitmix64(0), 0xE220_A839_7B1D_CDAF);
    // Reference values computed independently (Python, arbitrary-precision integers).
    let e = EventIdentity {
        site: 1,
        application: 2,
        event_number: 3,
    };
    assert_eq!(e.effect_seed(), 0xCFCB_AA72_306B_459E);
    let max = EventIdentity {
        site: 0xFFFF,
        application: 0xFFFF,
        event_number: 0xFFFF,
    };
    assert_eq!(max.effect_seed(), 0xC5C3_58AC_47BD_80EC);
}

fn detonation(result: u8, event: u16) -> Detonation {
    Detonation::builder()
        .with_source_entity_id(EntityId::new(3, 4, 5))
        .with_target_entity_id(EntityId::new(0, 0, 0))
        .with_exploding_entity_id(EntityId::new(3, 4, 6))
        .with_event_id(EventId::new(3, 4, event))
        .with_velocity(VectorF32::new(0.0, 0.0, -200.0))
        .with_world_location(Location::new(4_000_000.0, 300_000.0, 4_900_000.0))
        .with_descriptor(DetonationDescriptor::Munition(MunitionDescriptor::default()))
        .with_entity_location(VectorF32::new(0.0, 0.0, 0.0))
        .with_detonation_result(DetonationResult::from(result))
        .build()
}

#[test]
fn ground_and_building_impacts_start_effects_others_do_not() {
    assert_eq!(
        classify_result(3),
        Some((ImpactSurface::Ground, ImpactSize::Medium))
    );
    assert_eq!(
        classify_result(13),
        Some((ImpactSurface::Ground, ImpactSize::Large))
    );
    assert_eq!(
        classify_result(18),
        Some((ImpactSurface::Building, ImpactSize::Small))
    );
    assert_eq!(
        classify_result(20),
        Some((ImpactSurface::Building, ImpactSize::Large))
    );
    for other in [0u8, 1, 2, 5, 6, 14, 17, 24, 25] {
        assert_eq!(classify_result(other), None, "result {other}");
    }
    // Through the wire, on two "nodes": same event, same seed and place.
    let header = EncodeHeader {
        version: DisVersion::V7,
        exercise_id: 1,
        timestamp: 0,
    };
    let bytes = encode_pdu(
        header,
        &DisMessage::Detonation(Box::new(detonation(3, 901))),
    )
    .expect("valid in this test");
    let seeds: Vec<u64> = (0..2)
        .map(|_| {
            let DisMessage::Detonation(d) = decode_pdu(&bytes).expect("valid in this test").message
            else {
                panic!("not a detonation");
            };
            let effect = impact_effect(&d).expect("ground impact");
            assert_eq!(effect.surface, ImpactSurface::Ground);
            assert_eq!(
                effect.position_ecef_m,
                DVec3::new(4_000_000.0, 300_000.0, 4_900_000.0)
            );
            assert_eq!(
                effect.event,
                EventIdentity {
                    site: 3,
                    application: 4,
                    event_number: 901
                }
            );
            effect.effect_seed
        })
        .collect();
    assert_eq!(seeds[0], seeds[1]);
    assert_ne!(
        impact_effect(&detonation(3, 902))
            .expect("valid in this test")
            .effect_seed,
        seeds[0]
    );
    assert!(impact_effect(&detonation(1, 901)).is_none());
}

/// A broadcast network of time-sharing nodes; every message goes through encode and decode.
struct Net {
    nodes: Vec<Option<TimeSync>>,
    now_s: f64,
    log: Vec<(usize, TimeMessage)>,
}

const START_MS: i64 = 1_700_000_000_000;

fn over_the_wire(m: &TimeMessage) -> TimeMessage {
    let bytes = encode_pdu(
        EncodeHeader {
            version: DisVersion::V7,
            exercise_id: 1,
            timestamp: 0,
        },
        &m.to_message(),
    )
    .expect("valid in this test");
    TimeMessage::from_message(&decode_pdu(&bytes).expect("valid in this test").message)
        .expect("a time message")
}

impl Net {
    fn new() -> Net {
        Net {
            nodes: Vec::new(),
            now_s: 0.0,
            log: Vec::new(),
        }
    }

    fn join(&mut self, site: u16, application: u16, start_ms: i64) -> usize {
        let (node, out) = TimeSync::join(
            NodeId { site, application },
            TimeSyncConfig::default(),
            self.now_s,
            start_ms,
            1.0,
        );
        self.nodes.push(Some(node));
        let i = self.nodes.len() - 1;
        self.broadcast(i, out);
        i
    }

    fn leave(&mut self, i: usize) {
        self.nodes[i] = None;
    }

    fn broadcast(&mut self, from: usize, messages: Vec<TimeMessage>) {
        let mut queue: Vec<(usize, TimeMessage)> =
            messages.into_iter().map(|m| (from, m)).collect();
        while let Some((sender, m)) = queue.pop() {
            self.log.push((sender, m));
            let m = over_the_wire(&m);
            for j in 0..self.nodes.len() {
                if j == sender {
                    continue;
                }
                if let Some(node) = self.nodes[j].as_mut() {
                    for reply in node.receive(self.now_s, &m) {
                        queue.push((j, reply));
                    }
                }
            }
        }
    }

    fn run_until(&mut self, t_s: f64) {
        while self.now_s < t_s - 1e-9 {
            self.now_s += 0.1;
            for i in 0..self.nodes.len() {
                let out = match self.nodes[i].as_mut() {
                    Some(node) => node.tick(self.now_s),
                    None => continue,
                };
                self.broadcast(i, out);
            }
        }
    }

    fn node(&self, i: usize) -> &TimeSync {
        self.nodes[i].as_ref().expect("valid in this test")
    }

    fn time(&self, i: usize) -> i64 {
        self.node(i).world_time_ms(self.now_s)
    }
}

#[test]
fn first_node_becomes_master_and_a_newcomer_adopts_its_time() {
    let mut net = Net::new();
    let a = net.join(1, 1, START_MS);
    assert_eq!(net.node(a).role(), TimeRole::Joining);
    net.run_until(2.5);
    assert_eq!(net.node(a).role(), TimeRole::Master);
    net.run_until(60.0);
    // B starts with a wrong clock (noon vs the master's time) and is corrected at once.
    let b = net.join(2, 1, START_MS + 3_600_000);
    let master = NodeId {
        site: 1,
        application: 1,
    };
    assert_eq!(net.node(b).role(), TimeRole::Follower { master });
    assert_eq!(net.time(a), net.time(b));
    assert_eq!(net.time(a), START_MS + 60_000);
    // The answer was addressed to B with B's request ID.
    assert!(net.log.iter().any(|(from, m)| *from == a
        && matches!(m, TimeMessage::Announce { to: Some(to), request_id: 1, .. } if *to == NodeId { site: 2, application: 1 })));
    net.run_until(100.0);
    assert_eq!(net.node(b).role(), TimeRole::Follower { master });
    assert_eq!(net.time(a), net.time(b));
}

#[test]
fn when_the_master_leaves_the_lowest_survivor_takes_over_without_a_time_jump() {
    let mut net = Net::new();
    let a = net.join(1, 1, START_MS);
    net.run_until(3.0);
    let c = net.join(2, 1, START_MS - 50_000);
    let b = net.join(1, 2, START_MS + 50_000);
    net.run_until(20.0);
    assert_eq!(net.node(a).role(), TimeRole::Master);
    let before = net.time(b);
    net.leave(a);
    net.run_until(30.0);
    // Both followers timed out at the same moment and claimed; (1,2) < (2,1) wins.
    assert_eq!(net.node(b).role(), TimeRole::Master);
    assert_eq!(
        net.node(c).role(),
        TimeRole::Follower {
            master: NodeId {
                site: 1,
                application: 2
            }
        }
    );
    assert_eq!(net.time(b), net.time(c));
    assert_eq!(net.time(b) - before, 10_000, "time ran on without a jump");
    // A later newcomer with a lower address adopts the time, then takes the role over.
    let before = net.time(b);
    let d = net.join(0, 9, 0);
    assert_eq!(net.time(d), before);
    net.run_until(31.0);
    assert_eq!(net.node(d).role(), TimeRole::Master);
    let new_master = NodeId {
        site: 0,
        application: 9,
    };
    assert_eq!(
        net.node(b).role(),
        TimeRole::Follower { master: new_master }
    );
    assert_eq!(
        net.node(c).role(),
        TimeRole::Follower { master: new_master }
    );
    assert_eq!(net.time(d), net.time(b));
    assert_eq!(
        net.time(d) - before,
        1_000,
        "the role moved, the time did not jump"
    );
}

#[test]
fn nodes_joining_together_settle_on_the_lowest_address() {
    let mut net = Net::new();
    // All three ask at once; nobody answers; all claim after the join wait.
    let x = net.join(3, 3, START_MS + 1_000);
    let y = net.join(2, 7, START_MS + 2_000);
    let z = net.join(2, 5, START_MS + 3_000);
    net.run_until(10.0);
    let winner = NodeId {
        site: 2,
        application: 5,
    };
    assert_eq!(net.node(z).role(), TimeRole::Master);
    assert_eq!(net.node(x).role(), TimeRole::Follower { master: winner });
    assert_eq!(net.node(y).role(), TimeRole::Follower { master: winner });
    assert_eq!(net.time(x), net.time(z));
    assert_eq!(net.time(y), net.time(z));
    // The first claim (x, ticked first) set the time; the role then moved down to z.
    assert_eq!(net.time(z), START_MS + 1_000 + 10_000);
}

#[test]
fn set_data_sets_the_time_everywhere() {
    let mut net = Net::new();
    let a = net.join(1, 1, START_MS);
    net.run_until(3.0);
    let b = net.join(1, 2, 0);
    net.run_until(5.0);
    // An instructor station (not a time node) sends a Set Data: noon, double speed.
    let instructor = NodeId {
        site: 9,
        application: 9,
    };
    let set = TimeMessage::Set {
        from: instructor,
        world_time_ms: START_MS + 43_200_000,
        rate: 2.0,
    };
    net.nodes.push(None);
    let i = net.nodes.len() - 1;
    net.broadcast(i, vec![set]);
    net.run_until(7.0);
    assert_eq!(net.time(a), START_MS + 43_200_000 + 4_000);
    assert_eq!(net.time(b), net.time(a));
    assert!((net.node(b).rate() - 2.0).abs() < f32::EPSILON);
}

#[test]
fn lightning_round_trips_and_is_not_a_time_message() {
    let strike = LightningStrike {
        from: NodeId {
            site: 4,
            application: 2,
        },
        position_ecef_m: DVec3::new(4_000_100.0, 300_200.0, 4_900_300.0),
        seed: 0xDEAD_BEEF_0123_4567,
        intensity: 0.75,
    };
    let bytes = encode_pdu(
        EncodeHeader {
            version: DisVersion::V7,
            exercise_id: 1,
            timestamp: 0,
        },
        &strike.to_message(),
    )
    .expect("valid in this test");
    let message = decode_pdu(&bytes).expect("valid in this test").message;
    assert_eq!(LightningStrike::from_message(&message), Some(strike));
    assert_eq!(TimeMessage::from_message(&message), None);
    let time = TimeMessage::Announce {
        from: NodeId {
            site: 1,
            application: 1,
        },
        to: None,
        request_id: 0,
        world_time_ms: START_MS,
        rate: 1.0,
    };
    assert_eq!(LightningStrike::from_message(&time.to_message()), None);
    assert_eq!(over_the_wire(&time), time);
}
