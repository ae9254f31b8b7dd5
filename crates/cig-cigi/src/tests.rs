//! Unit tests: round trips of every packet in both versions and byte orders,
//! hand-built byte vectors from the ICD layouts, bad input.

use proptest::prelude::*;

use crate::sample::{Sample, SampleField, SampleSource};
use crate::*;

const ORDERS: [ByteOrder; 2] = [ByteOrder::BigEndian, ByteOrder::LittleEndian];
const VERSIONS: [Version; 2] = [Version::V3_3, Version::V4_0];

/// Every host-to-IG packet type of `version`, with fields the version lacks
/// left at their defaults.
fn host_packets(src: &mut SampleSource, version: Version) -> Vec<Packet> {
    let mut ig = IgControl::sample(src);
    if version.major == 3 {
        ig.entity_substitution_enable = false;
    }
    let mut celestial = CelestialSphereControl::sample(src);
    let mut weather = WeatherControl::sample(src);
    if version.major == 3 {
        celestial.seconds = 0.0;
        weather.top_scud_enable = false;
        weather.top_scud_frequency_pct = 0.0;
        weather.top_transition_band_m = 0.0;
    }
    let mut packets = vec![Packet::IgControl(ig)];
    if version.major == 3 {
        packets.push(Packet::EntityControl(EntityControl::sample(src)));
    } else {
        packets.push(Packet::EntityPosition(EntityPosition::sample(src)));
        packets.push(Packet::EntityControl4(EntityControl4::sample(src)));
        packets.push(Packet::AnimationControl(AnimationControl::sample(src)));
    }
    packets.extend([
        Packet::ConformalClampedEntity(Sample::sample(src)),
        Packet::ComponentControl(Sample::sample(src)),
        Packet::ShortComponentControl(Sample::sample(src)),
        Packet::ArticulatedPart(Sample::sample(src)),
        Packet::ShortArticulatedPart(Sample::sample(src)),
        Packet::RateControl(Sample::sample(src)),
        Packet::CelestialSphereControl(celestial),
        Packet::AtmosphereControl(Sample::sample(src)),
        Packet::EnvironmentalRegionControl(Sample::sample(src)),
        Packet::WeatherControl(weather),
        Packet::MaritimeSurfaceConditionsControl(Sample::sample(src)),
        Packet::WaveControl(Sample::sample(src)),
        Packet::TerrestrialSurfaceConditionsControl(Sample::sample(src)),
        Packet::ViewControl(Sample::sample(src)),
        Packet::SensorControl(Sample::sample(src)),
        Packet::ViewDefinition(Sample::sample(src)),
        Packet::CollisionSegmentDefinition(Sample::sample(src)),
        Packet::CollisionVolumeDefinition(Sample::sample(src)),
        Packet::HatHotRequest(Sample::sample(src)),
        Packet::LosSegmentRequest(Sample::sample(src)),
        Packet::LosVectorRequest(Sample::sample(src)),
        Packet::PositionRequest(Sample::sample(src)),
        Packet::EnvironmentalConditionsRequest(Sample::sample(src)),
        user_defined(src, version),
    ]);
    packets
}

/// Every IG-to-host packet type of `version`.
fn ig_packets(src: &mut SampleSource, version: Version) -> Vec<Packet> {
    let mut sof = StartOfFrame::sample(src);
    if version.major == 3 {
        sof.overframing = false;
        sof.paging = false;
        sof.excessive_variable_length_data = false;
    } else {
        sof.ig_status = 0;
    }
    vec![
        Packet::StartOfFrame(sof),
        Packet::HatHotResponse(Sample::sample(src)),
        Packet::HatHotExtendedResponse(Sample::sample(src)),
        Packet::LosResponse(Sample::sample(src)),
        Packet::LosExtendedResponse(Sample::sample(src)),
        Packet::SensorResponse(Sample::sample(src)),
        Packet::SensorExtendedResponse(Sample::sample(src)),
        Packet::PositionResponse(Sample::sample(src)),
        Packet::WeatherConditionsResponse(Sample::sample(src)),
        Packet::AerosolConcentrationResponse(Sample::sample(src)),
        Packet::MaritimeSurfaceConditionsResponse(Sample::sample(src)),
        Packet::TerrestrialSurfaceConditionsResponse(Sample::sample(src)),
        Packet::CollisionSegmentNotification(Sample::sample(src)),
        Packet::CollisionVolumeNotification(Sample::sample(src)),
        Packet::AnimationStopNotification(Sample::sample(src)),
        Packet::EventNotification(Sample::sample(src)),
        Packet::ImageGeneratorMessage(Sample::sample(src)),
        user_defined(src, version),
    ]
}

fn user_defined(src: &mut SampleSource, version: Version) -> Packet {
    let words = usize::try_from(src.next_u64() % 6).unwrap();
    let (first, span, header) = if version.major == 3 {
        (201u64, 55u64, 2usize)
    } else {
        (0x1000, 0xEFFF, 4)
    };
    let packet_id = u16::try_from(first + src.next_u64() % span).unwrap();
    let data = (0..words * 8 + 8 - header)
        .map(|_| u8::sample_field(src, 0))
        .collect();
    Packet::UserDefined(UserDefined { packet_id, data })
}

fn encode(message: &Message) -> Vec<u8> {
    let mut out = Vec::new();
    encode_message(message, &mut out).unwrap();
    out
}

fn assert_round_trip(packets: Vec<Packet>, version: Version, order: ByteOrder) {
    let message = Message::new(version, order, packets);
    let bytes = encode(&message);
    let decoded = decode_message(&bytes).unwrap();
    assert_eq!(decoded.warnings, vec![]);
    assert_eq!(decoded.version, version);
    assert_eq!(decoded.byte_order, order);
    assert_eq!(decoded.packets.len(), message.packets.len());
    for (got, want) in decoded.packets.iter().zip(&message.packets) {
        assert_eq!(got, want, "{} in CIGI {version} {order:?}", want.name());
    }
    assert_eq!(encode(&decoded), bytes, "re-encoding is byte identical");
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    #[test]
    fn every_packet_round_trips_in_both_versions_and_orders(seed in any::<u64>()) {
        let mut src = SampleSource::new(seed);
        for version in VERSIONS {
            for order in ORDERS {
                assert_round_trip(host_packets(&mut src, version), version, order);
                assert_round_trip(ig_packets(&mut src, version), version, order);
            }
        }
    }

    #[test]
    fn truncated_messages_give_errors_not_panics(seed in any::<u64>(), cut in any::<prop::sample::Index>()) {
        let mut src = SampleSource::new(seed);
        for version in VERSIONS {
            for order in ORDERS {
                let packets = host_packets(&mut src, version);
                let bytes = encode(&Message::new(version, order, packets.clone()));
                let boundaries: Vec<usize> = (1..=packets.len())
                    .map(|k| encode(&Message::new(version, order, packets[..k].to_vec())).len())
                    .collect();
                let len = cut.index(bytes.len());
                match decode_message(&bytes[..len]) {
                    // A cut on a packet boundary is a shorter valid message.
                    Ok(message) => {
                        prop_assert!(boundaries.contains(&len));
                        prop_assert_eq!(&message.packets[..], &packets[..message.packets.len()]);
                    }
                    // Anywhere else a packet is cut short.
                    Err(_) => prop_assert!(!boundaries.contains(&len)),
                }
            }
        }
    }

    #[test]
    fn random_bytes_never_panic(bytes in prop::collection::vec(any::<u8>(), 0..300)) {
        let _ = decode_message(&bytes);
    }

    #[test]
    fn random_bodies_behind_a_valid_first_packet_never_panic(
        seed in any::<u64>(),
        tail in prop::collection::vec(any::<u8>(), 0..300),
        v4 in any::<bool>(),
        little in any::<bool>(),
    ) {
        let version = if v4 { Version::V4_0 } else { Version::V3_3 };
        let order = if little { ByteOrder::LittleEndian } else { ByteOrder::BigEndian };
        let mut src = SampleSource::new(seed);
        let mut bytes = encode(&Message::new(version, order, vec![Packet::IgControl(IgControl::sample(&mut src))]));
        bytes.extend_from_slice(&tail);
        if let Ok(message) = decode_message(&bytes) {
            // Whatever decoded encodes again, except text or user data the
            // encoder refuses; re-encoding is then stable.
            let mut once = Vec::new();
            match encode_message(&message, &mut once) {
                Ok(()) => {
                    let mut twice = Vec::new();
                    encode_message(&decode_message(&once).unwrap(), &mut twice).unwrap();
                    prop_assert_eq!(once, twice);
                }
                Err(e) => prop_assert!(matches!(e, CigiError::FieldOutOfRange { .. }), "{}", e),
            }
        }
    }
}

/// 3.3 IG Control + Entity Control + HAT/HOT Request, big-endian, built byte
/// by byte from the ICD 3.3 packet diagrams.
fn hand_built_v3(big: bool) -> Vec<u8> {
    let u16b = |v: u16| {
        if big {
            v.to_be_bytes()
        } else {
            v.to_le_bytes()
        }
    };
    let u32b = |v: u32| {
        if big {
            v.to_be_bytes()
        } else {
            v.to_le_bytes()
        }
    };
    let f32b = |v: f32| {
        if big {
            v.to_be_bytes()
        } else {
            v.to_le_bytes()
        }
    };
    let f64b = |v: f64| {
        if big {
            v.to_be_bytes()
        } else {
            v.to_le_bytes()
        }
    };
    let mut m = vec![1, 24, 3, 7];
    // IG mode operate (1), timestamp valid (bit 2), minor version 3 (bits 4-7).
    m.extend([0x01 | 0x04 | 0x30, 0]);
    m.extend(u16b(0x8000));
    m.extend(u32b(1000));
    m.extend(u32b(123_456));
    m.extend(u32b(999));
    m.extend([0; 4]);
    // Entity Control: id 42, state active (1) + attach (bit 2), anim play (2)
    // in bits 2-3 of byte 5, alpha 200, type 7, parent 3.
    m.extend([2, 48]);
    m.extend(u16b(42));
    m.extend([0x01 | 0x04, 2 << 2, 200, 0]);
    m.extend(u16b(7));
    m.extend(u16b(3));
    m.extend(f32b(1.5));
    m.extend(f32b(-2.5));
    m.extend(f32b(270.0));
    m.extend(f64b(51.5));
    m.extend(f64b(-0.125));
    m.extend(f64b(1234.5));
    // HAT/HOT Request: id 9, type extended (2), entity coordinates (bit 2),
    // update period 5, entity 42.
    m.extend([24, 32]);
    m.extend(u16b(9));
    m.extend([2 | 0x04, 5]);
    m.extend(u16b(42));
    m.extend(f64b(1.0));
    m.extend(f64b(2.0));
    m.extend(f64b(-3.0));
    m
}

#[test]
fn hand_built_v3_vectors_decode_in_both_orders() {
    for big in [true, false] {
        let message = decode_message(&hand_built_v3(big)).unwrap();
        assert_eq!(message.version, Version::V3_3);
        let order = if big {
            ByteOrder::BigEndian
        } else {
            ByteOrder::LittleEndian
        };
        assert_eq!(message.byte_order, order);
        assert_eq!(
            message.packets,
            vec![
                Packet::IgControl(IgControl {
                    database_number: 7,
                    ig_mode: 1,
                    timestamp_valid: true,
                    host_frame_number: 1000,
                    timestamp_10us: 123_456,
                    last_ig_frame_number: 999,
                    ..IgControl::default()
                }),
                Packet::EntityControl(EntityControl {
                    entity_id: 42,
                    entity_state: 1,
                    attach: true,
                    animation_state: 2,
                    alpha: 200,
                    entity_type: 7,
                    parent_id: 3,
                    roll_deg: 1.5,
                    pitch_deg: -2.5,
                    yaw_deg: 270.0,
                    lat_deg_or_x_m: 51.5,
                    lon_deg_or_y_m: -0.125,
                    alt_m_or_z_m: 1234.5,
                    ..EntityControl::default()
                }),
                Packet::HatHotRequest(HatHotRequest {
                    hat_hot_id: 9,
                    request_type: 2,
                    coordinate_system_entity: true,
                    update_period: 5,
                    entity_id: 42,
                    lat_deg_or_x_m: 1.0,
                    lon_deg_or_y_m: 2.0,
                    alt_m_or_z_m: -3.0,
                }),
            ]
        );
        // And the encoder reproduces the hand-built bytes exactly.
        assert_eq!(encode(&message), hand_built_v3(big));
    }
}

/// 4.0 IG Control + Entity Position + HAT/HOT Request and 4.0 Start of Frame +
/// HAT/HOT Response, built byte by byte from the 4.0 layouts.
fn hand_built_v4(big: bool) -> (Vec<u8>, Vec<u8>) {
    let u16b = |v: u16| {
        if big {
            v.to_be_bytes()
        } else {
            v.to_le_bytes()
        }
    };
    let u32b = |v: u32| {
        if big {
            v.to_be_bytes()
        } else {
            v.to_le_bytes()
        }
    };
    let f32b = |v: f32| {
        if big {
            v.to_be_bytes()
        } else {
            v.to_le_bytes()
        }
    };
    let f64b = |v: f64| {
        if big {
            v.to_be_bytes()
        } else {
            v.to_le_bytes()
        }
    };
    let mut host = Vec::new();
    host.extend(u16b(24));
    host.extend(u16b(0x0000));
    // major 4, database 5, entity substitution on, IG mode operate + smoothing
    // (bit 3), minor 0.
    host.extend([4, 5, 1, 0x01 | 0x08]);
    host.extend(u32b(77)); // host frame
    host.extend(u32b(76)); // last IG frame
    host.extend(u32b(5000)); // timestamp
    host.extend([0; 4]);
    // Entity Position: attach (bit 0) + clamp conformal (2 << 1).
    host.extend(u16b(48));
    host.extend(u16b(0x0001));
    host.extend([0x01 | (2 << 1), 0]);
    host.extend(u16b(12)); // entity
    host.extend(u16b(11)); // parent
    host.extend([0; 2]);
    host.extend(f32b(10.0));
    host.extend(f32b(20.0));
    host.extend(f32b(30.0));
    host.extend(f64b(4.0));
    host.extend(f64b(5.0));
    host.extend(f64b(6.0));
    // HAT/HOT Request: id 300, entity 12, type HOT (1), update period 0.
    host.extend(u16b(40));
    host.extend(u16b(0x0017));
    host.extend(u16b(300));
    host.extend(u16b(12));
    host.extend([1, 0, 0, 0]);
    host.extend([0; 4]);
    host.extend(f64b(45.0));
    host.extend(f64b(7.0));
    host.extend(f64b(100.0));

    let mut ig = Vec::new();
    ig.extend(u16b(24));
    ig.extend(u16b(0xFFFF));
    // major 4, database 5, reserved, IG mode operate, minor 0.
    ig.extend([4, 5, 0, 0x01]);
    ig.extend(u32b(78)); // IG frame
    ig.extend(u32b(5100)); // timestamp
    ig.extend(u32b(77)); // last host frame
    ig.extend(u16b(0x0200)); // paging condition (bit 9)
    ig.extend([0; 2]);
    // HAT/HOT Response: valid + HOT (bit 1) + host frame LSN 13.
    ig.extend(u16b(16));
    ig.extend(u16b(0x0FFF));
    ig.extend([0x01 | 0x02 | (13 << 4), 0]);
    ig.extend(u16b(300));
    ig.extend(f64b(87.25));
    (host, ig)
}

#[test]
fn hand_built_v4_vectors_decode_in_both_orders() {
    for big in [true, false] {
        let (host, ig) = hand_built_v4(big);
        let order = if big {
            ByteOrder::BigEndian
        } else {
            ByteOrder::LittleEndian
        };
        let message = decode_message(&host).unwrap();
        assert_eq!(
            (message.version, message.byte_order),
            (Version::V4_0, order)
        );
        assert_eq!(
            message.packets,
            vec![
                Packet::IgControl(IgControl {
                    database_number: 5,
                    ig_mode: 1,
                    smoothing_enable: true,
                    entity_substitution_enable: true,
                    host_frame_number: 77,
                    last_ig_frame_number: 76,
                    timestamp_10us: 5000,
                    ..IgControl::default()
                }),
                Packet::EntityPosition(EntityPosition {
                    entity_id: 12,
                    parent_id: 11,
                    attach: true,
                    ground_ocean_clamp: 2,
                    roll_deg: 10.0,
                    pitch_deg: 20.0,
                    yaw_deg: 30.0,
                    lat_deg_or_x_m: 4.0,
                    lon_deg_or_y_m: 5.0,
                    alt_m_or_z_m: 6.0,
                }),
                Packet::HatHotRequest(HatHotRequest {
                    hat_hot_id: 300,
                    request_type: 1,
                    entity_id: 12,
                    lat_deg_or_x_m: 45.0,
                    lon_deg_or_y_m: 7.0,
                    alt_m_or_z_m: 100.0,
                    ..HatHotRequest::default()
                }),
            ]
        );
        assert_eq!(encode(&message), host);

        let message = decode_message(&ig).unwrap();
        assert_eq!(
            (message.version, message.byte_order),
            (Version::V4_0, order)
        );
        assert_eq!(
            message.packets,
            vec![
                Packet::StartOfFrame(StartOfFrame {
                    database_number: 5,
                    ig_mode: 1,
                    ig_frame_number: 78,
                    timestamp_10us: 5100,
                    last_host_frame_number: 77,
                    paging: true,
                    ..StartOfFrame::default()
                }),
                Packet::HatHotResponse(HatHotResponse {
                    hat_hot_id: 300,
                    valid: true,
                    response_type_hot: true,
                    host_frame_lsn: 13,
                    height_m: 87.25,
                }),
            ]
        );
        assert_eq!(encode(&message), ig);
    }
}

#[test]
fn byte_order_shows_in_the_magic_number_and_fields() {
    let message = Message::new(
        Version::V3_3,
        ByteOrder::LittleEndian,
        vec![Packet::IgControl(IgControl {
            host_frame_number: 0x0102_0304,
            ..IgControl::default()
        })],
    );
    let bytes = encode(&message);
    assert_eq!(&bytes[0..3], &[1, 24, 3]);
    assert_eq!(bytes[4] >> 4, 3, "minor version 3");
    assert_eq!(&bytes[6..8], &[0x00, 0x80], "0x8000 little-endian");
    assert_eq!(&bytes[8..12], &[4, 3, 2, 1]);
    let big = encode(&Message {
        byte_order: ByteOrder::BigEndian,
        ..message
    });
    assert_eq!(&big[6..8], &[0x80, 0x00]);
    assert_eq!(&big[8..12], &[1, 2, 3, 4]);
}

#[test]
fn unknown_and_untyped_packets_are_skipped_with_warnings() {
    let mut bytes = hand_built_v3(true);
    let after_ig_control = 24;
    // Motion Tracker Control (18, standard but not typed here, 8 bytes) and
    // an unassigned ID 150 (16 bytes), inserted after IG Control.
    let mut extra = vec![18, 8, 0, 0, 0, 0, 0, 0, 150, 16];
    extra.extend([0xAA; 14]);
    bytes.splice(after_ig_control..after_ig_control, extra);
    let message = decode_message(&bytes).unwrap();
    assert_eq!(message.packets.len(), 3, "the typed packets all decode");
    assert_eq!(
        message
            .warnings
            .iter()
            .map(|w| (w.offset, w.packet_id, w.size))
            .collect::<Vec<_>>(),
        vec![(24, 18, 8), (32, 150, 16)]
    );
}

#[test]
fn bad_input_gives_typed_errors() {
    assert_eq!(decode_message(&[]), Err(CigiError::Empty));
    assert!(matches!(
        decode_message(&[9; 30]),
        Err(CigiError::NotAMessageStart { .. })
    ));
    let mut bad_magic = hand_built_v3(true);
    bad_magic[6] = 0x12;
    assert_eq!(
        decode_message(&bad_magic),
        Err(CigiError::BadMagic { found: 0x1200 })
    );
    let mut zero_size = hand_built_v3(true);
    zero_size[25] = 0;
    assert_eq!(
        decode_message(&zero_size),
        Err(CigiError::InvalidSize {
            packet_id: 2,
            offset: 24,
            size: 0
        })
    );
    let mut short_entity = hand_built_v3(true);
    short_entity[25] = 16;
    assert!(matches!(
        decode_message(&short_entity),
        Err(CigiError::PacketTooShort {
            packet: "EntityControl",
            offset: 24,
            size: 16,
            needed: 48
        })
    ));
    let whole = hand_built_v3(true);
    let cut = &whole[..whole.len() - 3];
    assert_eq!(
        decode_message(cut),
        Err(CigiError::Truncated {
            packet: "HatHotRequest",
            packet_id: 24,
            offset: 72,
            size: 32,
            available: 29
        })
    );
    let mut v2 = hand_built_v3(true);
    v2[2] = 2;
    assert!(matches!(
        decode_message(&v2),
        Err(CigiError::UnsupportedVersion { .. })
    ));
}

#[test]
fn encoder_rejects_what_the_wire_cannot_carry() {
    let ig = Packet::IgControl(IgControl::default());
    let mut out = vec![0xEE];
    let e = encode_message(
        &Message::new(
            Version::V3_3,
            ByteOrder::BigEndian,
            vec![
                ig.clone(),
                Packet::EntityPosition(EntityPosition::default()),
            ],
        ),
        &mut out,
    );
    assert_eq!(
        e,
        Err(CigiError::NotInVersion {
            packet: "EntityPosition",
            version: Version::V3_3
        })
    );
    assert_eq!(out, vec![0xEE], "output untouched on error");
    let e = encode_message(
        &Message::new(
            Version::V4_0,
            ByteOrder::BigEndian,
            vec![ig.clone(), Packet::EntityControl(EntityControl::default())],
        ),
        &mut out,
    );
    assert!(matches!(e, Err(CigiError::NotInVersion { .. })));
    let e = encode_message(
        &Message::new(
            Version::V3_3,
            ByteOrder::BigEndian,
            vec![Packet::HatHotRequest(HatHotRequest::default())],
        ),
        &mut out,
    );
    assert_eq!(
        e,
        Err(CigiError::FirstPacket {
            packet: "HatHotRequest"
        })
    );
    let long_text = Packet::ImageGeneratorMessage(ImageGeneratorMessage {
        message_id: 1,
        text: "x".repeat(MAX_IG_MESSAGE_TEXT_BYTES + 1),
    });
    let e = encode_message(
        &Message::new(
            Version::V3_3,
            ByteOrder::BigEndian,
            vec![Packet::StartOfFrame(StartOfFrame::default()), long_text],
        ),
        &mut out,
    );
    assert!(matches!(
        e,
        Err(CigiError::FieldOutOfRange { field: "text", .. })
    ));
    let bad_user = Packet::UserDefined(UserDefined {
        packet_id: 150,
        data: vec![0; 6],
    });
    let e = encode_message(
        &Message::new(Version::V3_3, ByteOrder::BigEndian, vec![ig, bad_user]),
        &mut out,
    );
    assert!(matches!(
        e,
        Err(CigiError::FieldOutOfRange {
            field: "packet_id",
            ..
        })
    ));
}

#[test]
fn ig_message_text_is_nul_terminated_and_padded_to_8() {
    let message = Message::new(
        Version::V3_3,
        ByteOrder::BigEndian,
        vec![
            Packet::StartOfFrame(StartOfFrame::default()),
            Packet::ImageGeneratorMessage(ImageGeneratorMessage {
                message_id: 0x0102,
                text: "hello".into(),
            }),
        ],
    );
    let bytes = encode(&message);
    assert_eq!(
        &bytes[24..],
        &[117, 16, 1, 2, b'h', b'e', b'l', b'l', b'o', 0, 0, 0, 0, 0, 0, 0]
    );
    let v4 = encode(&Message {
        version: Version::V4_0,
        ..message
    });
    assert_eq!(
        &v4[24..],
        &[0, 16, 0x0F, 0xF0, 1, 2, 0, 0, b'h', b'e', b'l', b'l', b'o', 0, 0, 0]
    );
}

#[test]
fn other_cigi_3_minor_versions_decode_with_a_warning() {
    let mut bytes = hand_built_v3(true);
    bytes[4] = (bytes[4] & 0x0f) | (2 << 4);
    let message = decode_message(&bytes).unwrap();
    assert_eq!(message.version, Version { major: 3, minor: 2 });
    assert_eq!(message.packets.len(), 3);
    assert_eq!(message.warnings.len(), 1);
    assert_eq!(message.warnings[0].offset, 0);
}

#[test]
fn v4_unknown_packets_are_skipped_and_cut_packets_are_errors() {
    for big in [true, false] {
        let (mut host, _) = hand_built_v4(big);
        let u16b = |v: u16| {
            if big {
                v.to_be_bytes()
            } else {
                v.to_le_bytes()
            }
        };
        // Acceleration Control (0x13, untyped) of 32 bytes appended.
        let mut wave = Vec::new();
        wave.extend(u16b(32));
        wave.extend(u16b(0x0013));
        wave.extend([0x55; 28]);
        let at = host.len();
        host.extend(&wave);
        let message = decode_message(&host).unwrap();
        assert_eq!(message.packets.len(), 3);
        assert_eq!(
            message
                .warnings
                .iter()
                .map(|w| (w.offset, w.packet_id, w.size))
                .collect::<Vec<_>>(),
            vec![(at, 0x0013, 32)]
        );
        // The same packet claiming 40 bytes runs past the datagram.
        host[at..at + 2].copy_from_slice(&u16b(40));
        assert_eq!(
            decode_message(&host),
            Err(CigiError::Truncated {
                packet: "unknown packet",
                packet_id: 0x0013,
                offset: at,
                size: 40,
                available: 32
            })
        );
    }
}
