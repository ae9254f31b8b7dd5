//! Point and Linear Object State PDUs (types 43 and 44): the layouts octet by octet against
//! IEEE 1278.1-2012 §7.10.4-7.10.5 and §6.2.52, round trips, hostile input that must be refused
//! without a panic, and Open-DIS for Python (`pip install opendis`) as an independent peer —
//! skipped, with a message, when `python3` or `opendis` is missing.

mod common;

use common::{hex, unhex};

use cig_dis::codec::{DecodeError, DisVersion, EncodeHeader};
use cig_dis::object_state::{
    decode_linear_object_state, decode_linear_object_state_body, decode_point_object_state,
    decode_point_object_state_body, encode_linear_object_state, encode_point_object_state,
    LinearObjectState, LinearSegment, ObjectId, ObjectStateError, ObjectType, PointObjectState,
    SimulationAddress, LINEAR_OBJECT_STATE_FIXED_OCTETS, LINEAR_SEGMENT_OCTETS,
    MAX_LINEAR_SEGMENTS, PDU_TYPE_LINEAR_OBJECT_STATE, PDU_TYPE_POINT_OBJECT_STATE,
    POINT_OBJECT_STATE_OCTETS,
};
use proptest::prelude::*;

const HEADER: EncodeHeader = EncodeHeader {
    version: DisVersion::V7,
    exercise_id: 3,
    timestamp: 0x0102_0305,
};

fn crater() -> PointObjectState {
    PointObjectState {
        object_id: ObjectId {
            site: 0x0A01,
            application: 0x0A02,
            object: 0x0A03,
        },
        referenced_object_id: ObjectId {
            site: 0x0B01,
            application: 0x0B02,
            object: 0x0B03,
        },
        update_number: 0x0C0D,
        force_id: 2,
        modifications: 1,
        object_type: ObjectType::POINT_CRATER_MEDIUM,
        location_ecef_m: [-2_700_000.5, -4_300_000.25, 3_850_000.125],
        orientation_rad: [0.75, -0.125, 0.0625],
        specific_appearance: 0x1122_3344,
        general_appearance: 0x5566,
        requester: SimulationAddress {
            site: 0x0D01,
            application: 0x0D02,
        },
        receiver: SimulationAddress {
            site: 0xFFFF,
            application: 0xFFFF,
        },
    }
}

fn segment(n: u8) -> LinearSegment {
    LinearSegment {
        segment_number: n,
        modifications: 3,
        general_appearance: 0x0064,
        specific_appearance: 0x0A0B_0C00 | u32::from(n),
        location_ecef_m: [4_000_000.0 + f64::from(n), 300_000.5, 4_900_000.25],
        orientation_rad: [1.5, 0.0, -0.25],
        length_m: 25.5,
        width_m: 4.0,
        height_m: 0.75,
        depth_m: 2.5,
    }
}

fn ditch(segments: usize) -> LinearObjectState {
    LinearObjectState {
        object_id: ObjectId {
            site: 5,
            application: 6,
            object: 7,
        },
        referenced_object_id: ObjectId::default(),
        update_number: 9,
        force_id: 1,
        requester: SimulationAddress {
            site: 5,
            application: 6,
        },
        receiver: SimulationAddress {
            site: 0xFFFF,
            application: 0xFFFF,
        },
        object_type: ObjectType::LINEAR_TANK_DITCH,
        segments: (0..segments)
            .map(|i| segment(u8::try_from(i % 256).expect("< 256")))
            .collect(),
    }
}

fn be16(b: &[u8], at: usize) -> u16 {
    u16::from_be_bytes([b[at], b[at + 1]])
}

fn be32(b: &[u8], at: usize) -> u32 {
    u32::from_be_bytes(b[at..at + 4].try_into().expect("4 octets"))
}

fn f32_at(b: &[u8], at: usize) -> f32 {
    f32::from_bits(be32(b, at))
}

fn f64_at(b: &[u8], at: usize) -> f64 {
    f64::from_be_bytes(b[at..at + 8].try_into().expect("8 octets"))
}

#[test]
fn point_object_state_is_88_octets_at_the_standard_offsets() {
    let b = encode_point_object_state(HEADER, &crater()).expect("valid");
    assert_eq!(b.len(), POINT_OBJECT_STATE_OCTETS);
    assert_eq!(b.len(), 88);
    // Header: version 7, exercise, type 43, family 9, timestamp, length, status, padding.
    assert_eq!(&b[..12], &[7, 3, 43, 9, 1, 2, 3, 5, 0, 88, 0, 0]);
    assert_eq!(
        (be16(&b, 12), be16(&b, 14), be16(&b, 16)),
        (0x0A01, 0x0A02, 0x0A03)
    );
    assert_eq!(
        (be16(&b, 18), be16(&b, 20), be16(&b, 22)),
        (0x0B01, 0x0B02, 0x0B03)
    );
    assert_eq!(be16(&b, 24), 0x0C0D, "update number");
    assert_eq!((b[26], b[27]), (2, 1), "force ID, modifications");
    assert_eq!(
        &b[28..32],
        &[1, 1, 3, 2],
        "domain, kind, category, subcategory"
    );
    assert_eq!(f64_at(&b, 32), -2_700_000.5);
    assert_eq!(f64_at(&b, 40), -4_300_000.25);
    assert_eq!(f64_at(&b, 48), 3_850_000.125);
    assert_eq!(
        (f32_at(&b, 56), f32_at(&b, 60), f32_at(&b, 64)),
        (0.75, -0.125, 0.0625)
    );
    assert_eq!(be32(&b, 68), 0x1122_3344, "specific appearance");
    assert_eq!(be16(&b, 72), 0x5566, "general appearance");
    assert_eq!(be16(&b, 74), 0, "padding");
    assert_eq!((be16(&b, 76), be16(&b, 78)), (0x0D01, 0x0D02), "requester");
    assert_eq!((be16(&b, 80), be16(&b, 82)), (0xFFFF, 0xFFFF), "receiver");
    assert_eq!(be32(&b, 84), 0, "padding");
    assert_eq!(decode_point_object_state(&b), Ok(crater()));
}

#[test]
fn linear_object_state_is_40_plus_64_per_segment_at_the_standard_offsets() {
    let b = encode_linear_object_state(HEADER, &ditch(2)).expect("valid");
    assert_eq!(
        b.len(),
        LINEAR_OBJECT_STATE_FIXED_OCTETS + 2 * LINEAR_SEGMENT_OCTETS
    );
    assert_eq!(b.len(), 168);
    assert_eq!(&b[..12], &[7, 3, 44, 9, 1, 2, 3, 5, 0, 168, 0, 0]);
    assert_eq!((be16(&b, 12), be16(&b, 14), be16(&b, 16)), (5, 6, 7));
    assert_eq!(&b[18..24], &[0; 6], "referenced object ID");
    assert_eq!(be16(&b, 24), 9, "update number");
    assert_eq!((b[26], b[27]), (1, 2), "force ID, number of segments");
    assert_eq!((be16(&b, 28), be16(&b, 30)), (5, 6), "requester");
    assert_eq!((be16(&b, 32), be16(&b, 34)), (0xFFFF, 0xFFFF), "receiver");
    assert_eq!(&b[36..40], &[1, 1, 1, 0], "object type: tank ditch");
    for (i, at) in [40_usize, 104].into_iter().enumerate() {
        let n = u8::try_from(i).expect("small");
        assert_eq!((b[at], b[at + 1]), (n, 3), "segment number, modifications");
        assert_eq!(be16(&b, at + 2), 0x0064, "general appearance");
        assert_eq!(be32(&b, at + 4), 0x0A0B_0C00 | u32::from(n));
        assert_eq!(f64_at(&b, at + 8), 4_000_000.0 + f64::from(n));
        assert_eq!(f64_at(&b, at + 16), 300_000.5);
        assert_eq!(f64_at(&b, at + 24), 4_900_000.25);
        assert_eq!(
            (
                f32_at(&b, at + 32),
                f32_at(&b, at + 36),
                f32_at(&b, at + 40)
            ),
            (1.5, 0.0, -0.25)
        );
        assert_eq!(f32_at(&b, at + 44), 25.5, "length");
        assert_eq!(f32_at(&b, at + 48), 4.0, "width");
        assert_eq!(f32_at(&b, at + 52), 0.75, "height");
        assert_eq!(f32_at(&b, at + 56), 2.5, "depth");
        assert_eq!(be32(&b, at + 60), 0, "padding");
    }
    assert_eq!(decode_linear_object_state(&b), Ok(ditch(2)));
}

#[test]
fn object_types_follow_siso_ref_010() {
    let t = |o: ObjectType| [o.domain, o.kind, o.category, o.subcategory];
    assert_eq!(t(ObjectType::POINT_CRATER_SMALL), [1, 1, 3, 1]);
    assert_eq!(t(ObjectType::POINT_CRATER_MEDIUM), [1, 1, 3, 2]);
    assert_eq!(t(ObjectType::POINT_CRATER_LARGE), [1, 1, 3, 3]);
    assert_eq!(t(ObjectType::POINT_VEHICLE_DEFILADE_TANK), [1, 2, 1, 4]);
    assert_eq!(
        t(ObjectType::POINT_INFANTRY_FIGHTING_POSITION),
        [1, 2, 2, 0]
    );
    assert_eq!(t(ObjectType::POINT_DISTURBED_EARTH), [1, 3, 3, 0]);
    assert_eq!(t(ObjectType::LINEAR_TANK_DITCH), [1, 1, 1, 0]);
    assert_eq!(t(ObjectType::LINEAR_RUT), [1, 1, 5, 0]);
    assert_eq!(t(ObjectType::LINEAR_TIRE_TRACKS), [1, 3, 2, 0]);
}

#[test]
fn a_linear_object_without_segments_and_one_at_the_limit_round_trip() {
    let none = encode_linear_object_state(HEADER, &ditch(0)).expect("valid");
    assert_eq!(none.len(), 40);
    assert_eq!(decode_linear_object_state(&none), Ok(ditch(0)));
    let full = encode_linear_object_state(HEADER, &ditch(MAX_LINEAR_SEGMENTS)).expect("valid");
    assert_eq!(MAX_LINEAR_SEGMENTS, 127);
    assert_eq!(full.len(), 8168);
    assert_eq!(
        decode_linear_object_state(&full),
        Ok(ditch(MAX_LINEAR_SEGMENTS))
    );
}

#[test]
fn too_many_segments_are_refused_both_ways() {
    for n in [128, 255, 256, 5000] {
        assert_eq!(
            encode_linear_object_state(HEADER, &ditch(n)),
            Err(ObjectStateError::TooManySegments(n))
        );
    }
    // A peer declares 200 segments and sends all of them (40 + 12 800 octets).
    let mut b = encode_linear_object_state(HEADER, &ditch(100)).expect("valid");
    let again = b[40..40 + 100 * 64].to_vec();
    b.extend_from_slice(&again);
    b[27] = 200;
    let len = u16::try_from(b.len()).expect("fits");
    b[8..10].copy_from_slice(&len.to_be_bytes());
    assert_eq!(
        decode_linear_object_state(&b),
        Err(ObjectStateError::TooManySegments(200))
    );
}

#[test]
fn segment_count_must_match_the_declared_length() {
    let good = encode_linear_object_state(HEADER, &ditch(3)).expect("valid");
    // Count says 4, the octets hold 3.
    let mut more = good.clone();
    more[27] = 4;
    assert_eq!(
        decode_linear_object_state(&more),
        Err(ObjectStateError::LengthMismatch {
            pdu_type: PDU_TYPE_LINEAR_OBJECT_STATE,
            declared_octets: 232,
            expected_octets: 296,
        })
    );
    // Count says 2, the octets hold 3.
    let mut fewer = good.clone();
    fewer[27] = 2;
    assert!(matches!(
        decode_linear_object_state(&fewer),
        Err(ObjectStateError::LengthMismatch {
            declared_octets: 232,
            expected_octets: 168,
            ..
        })
    ));
    // The 1998 layout's 56-octet records: never misread as 64-octet ones.
    let mut old = good[..40 + 3 * 56].to_vec();
    old[8..10].copy_from_slice(&208_u16.to_be_bytes());
    assert!(matches!(
        decode_linear_object_state(&old),
        Err(ObjectStateError::LengthMismatch { .. })
    ));
}

#[test]
fn the_header_length_must_fit_the_buffer_and_the_fields() {
    let b = encode_point_object_state(HEADER, &crater()).expect("valid");
    // Declared longer than what arrived.
    assert!(matches!(
        decode_point_object_state(&b[..80]),
        Err(ObjectStateError::Header(DecodeError::Truncated { .. }))
    ));
    // Declared shorter than the fields.
    let mut short = b.clone();
    short[8..10].copy_from_slice(&80_u16.to_be_bytes());
    assert_eq!(
        decode_point_object_state(&short),
        Err(ObjectStateError::LengthMismatch {
            pdu_type: PDU_TYPE_POINT_OBJECT_STATE,
            declared_octets: 80,
            expected_octets: 88,
        })
    );
    // Declared longer than the fields, with the octets there.
    let mut long = b.clone();
    long.extend_from_slice(&[0; 8]);
    long[8..10].copy_from_slice(&96_u16.to_be_bytes());
    assert!(matches!(
        decode_point_object_state(&long),
        Err(ObjectStateError::LengthMismatch {
            declared_octets: 96,
            ..
        })
    ));
    // Below the header's own size, and no header at all.
    let mut tiny = b.clone();
    tiny[8..10].copy_from_slice(&4_u16.to_be_bytes());
    assert!(matches!(
        decode_point_object_state(&tiny),
        Err(ObjectStateError::Header(
            DecodeError::LengthBelowHeader { .. }
        ))
    ));
    assert!(matches!(
        decode_point_object_state(&[7, 3, 43]),
        Err(ObjectStateError::Header(DecodeError::TruncatedHeader {
            got: 3
        }))
    ));
    // Octets after the declared length (the next PDU of a datagram) are not this PDU's.
    let mut bundled = b.clone();
    bundled.extend_from_slice(&[0xAB; 40]);
    assert_eq!(decode_point_object_state(&bundled), Ok(crater()));
    // Body-level entry points.
    assert!(matches!(
        decode_point_object_state_body(&[]),
        Err(ObjectStateError::LengthMismatch { .. })
    ));
    assert!(matches!(
        decode_linear_object_state_body(&[0; 10]),
        Err(ObjectStateError::Truncated { at: 10, .. })
    ));
}

#[test]
fn wrong_type_family_or_version_is_refused() {
    let point = encode_point_object_state(HEADER, &crater()).expect("valid");
    let linear = encode_linear_object_state(HEADER, &ditch(1)).expect("valid");
    assert_eq!(
        decode_point_object_state(&linear),
        Err(ObjectStateError::WrongPduType {
            expected: 43,
            found: 44
        })
    );
    assert_eq!(
        decode_linear_object_state(&point),
        Err(ObjectStateError::WrongPduType {
            expected: 44,
            found: 43
        })
    );
    let mut family = point.clone();
    family[3] = 1;
    assert_eq!(
        decode_point_object_state(&family),
        Err(ObjectStateError::WrongFamily {
            pdu_type: 43,
            found: 1
        })
    );
    let mut v6 = point.clone();
    v6[0] = 6;
    assert_eq!(
        decode_point_object_state(&v6),
        Err(ObjectStateError::UnsupportedVersion(6))
    );
    let mut v5 = point.clone();
    v5[0] = 5;
    assert_eq!(
        decode_point_object_state(&v5),
        Err(ObjectStateError::Header(DecodeError::UnsupportedVersion(5)))
    );
    let v6_header = EncodeHeader {
        version: DisVersion::V6,
        ..HEADER
    };
    assert_eq!(
        encode_point_object_state(v6_header, &crater()),
        Err(ObjectStateError::UnsupportedVersion(6))
    );
    assert_eq!(
        encode_linear_object_state(v6_header, &ditch(1)),
        Err(ObjectStateError::UnsupportedVersion(6))
    );
}

#[test]
fn non_finite_or_negative_values_are_refused_with_the_field_named() {
    let mut p = crater();
    p.location_ecef_m[1] = f64::NAN;
    let e = encode_point_object_state(HEADER, &p).expect_err("NaN");
    assert_eq!(
        e,
        ObjectStateError::NotFinite {
            field: "location_ecef_m[1]".to_string()
        }
    );
    assert_eq!(
        e.to_string(),
        "Object State PDU: location_ecef_m[1] is not finite"
    );
    let mut p = crater();
    p.orientation_rad[2] = f32::NEG_INFINITY;
    assert_eq!(
        encode_point_object_state(HEADER, &p),
        Err(ObjectStateError::NotFinite {
            field: "orientation_rad[2]".to_string()
        })
    );
    let mut l = ditch(3);
    l.segments[1].width_m = f32::INFINITY;
    assert_eq!(
        encode_linear_object_state(HEADER, &l),
        Err(ObjectStateError::NotFinite {
            field: "segments[1].width_m".to_string()
        })
    );
    let mut l = ditch(3);
    l.segments[2].depth_m = -0.5;
    let e = encode_linear_object_state(HEADER, &l).expect_err("negative");
    assert_eq!(
        e.to_string(),
        "Object State PDU: segments[2].depth_m is negative"
    );

    // The same on the way in: NaN written into valid PDUs by a peer.
    let mut b = encode_point_object_state(HEADER, &crater()).expect("valid");
    b[40..48].copy_from_slice(&f64::NAN.to_be_bytes());
    assert_eq!(
        decode_point_object_state(&b),
        Err(ObjectStateError::NotFinite {
            field: "location_ecef_m[1]".to_string()
        })
    );
    let mut b = encode_linear_object_state(HEADER, &ditch(2)).expect("valid");
    b[104 + 44..104 + 48].copy_from_slice(&f32::NAN.to_be_bytes());
    assert_eq!(
        decode_linear_object_state(&b),
        Err(ObjectStateError::NotFinite {
            field: "segments[1].length_m".to_string()
        })
    );
    let mut b = encode_linear_object_state(HEADER, &ditch(2)).expect("valid");
    b[40 + 52..40 + 56].copy_from_slice(&(-3.0_f32).to_be_bytes());
    assert_eq!(
        decode_linear_object_state(&b),
        Err(ObjectStateError::NegativeSize {
            field: "segments[0].height_m".to_string()
        })
    );
}

#[test]
fn every_error_message_is_one_line() {
    let errors = [
        ObjectStateError::Header(DecodeError::TruncatedHeader { got: 3 }),
        ObjectStateError::UnsupportedVersion(6),
        ObjectStateError::WrongPduType {
            expected: 43,
            found: 1,
        },
        ObjectStateError::WrongFamily {
            pdu_type: 43,
            found: 1,
        },
        ObjectStateError::LengthMismatch {
            pdu_type: 44,
            declared_octets: 41,
            expected_octets: 40,
        },
        ObjectStateError::Truncated {
            pdu_type: 44,
            at: 10,
            needed: 2,
        },
        ObjectStateError::TooManySegments(300),
        ObjectStateError::NotFinite {
            field: "x".to_string(),
        },
        ObjectStateError::NegativeSize {
            field: "y".to_string(),
        },
    ];
    for e in errors {
        let s = e.to_string();
        assert!(!s.contains('\n') && !s.is_empty(), "{s:?}");
    }
}

fn finite_f64() -> impl Strategy<Value = f64> {
    prop_oneof![
        -7.0e6..7.0e6_f64,
        any::<f64>().prop_filter("finite", |v| v.is_finite()),
    ]
}

fn finite_f32() -> impl Strategy<Value = f32> {
    prop_oneof![
        -7.0_f32..7.0,
        any::<f32>().prop_filter("finite", |v| v.is_finite()),
    ]
}

fn size_m() -> impl Strategy<Value = f32> {
    prop_oneof![
        0.0_f32..1000.0,
        any::<f32>().prop_filter("finite, not negative", |v| v.is_finite() && *v >= 0.0),
    ]
}

fn object_id() -> impl Strategy<Value = ObjectId> {
    (any::<u16>(), any::<u16>(), any::<u16>()).prop_map(|(site, application, object)| ObjectId {
        site,
        application,
        object,
    })
}

fn address() -> impl Strategy<Value = SimulationAddress> {
    (any::<u16>(), any::<u16>())
        .prop_map(|(site, application)| SimulationAddress { site, application })
}

fn object_type() -> impl Strategy<Value = ObjectType> {
    any::<[u8; 4]>().prop_map(|[domain, kind, category, subcategory]| ObjectType {
        domain,
        kind,
        category,
        subcategory,
    })
}

prop_compose! {
    fn point_state()(
        ids in (object_id(), object_id()),
        update_number in any::<u16>(),
        force_mods in any::<[u8; 2]>(),
        object_type in object_type(),
        location in [finite_f64(), finite_f64(), finite_f64()],
        orientation in [finite_f32(), finite_f32(), finite_f32()],
        appearance in (any::<u32>(), any::<u16>()),
        addresses in (address(), address()),
    ) -> PointObjectState {
        PointObjectState {
            object_id: ids.0,
            referenced_object_id: ids.1,
            update_number,
            force_id: force_mods[0],
            modifications: force_mods[1],
            object_type,
            location_ecef_m: location,
            orientation_rad: orientation,
            specific_appearance: appearance.0,
            general_appearance: appearance.1,
            requester: addresses.0,
            receiver: addresses.1,
        }
    }
}

prop_compose! {
    fn linear_segment()(
        number_mods in any::<[u8; 2]>(),
        appearance in (any::<u16>(), any::<u32>()),
        location in [finite_f64(), finite_f64(), finite_f64()],
        orientation in [finite_f32(), finite_f32(), finite_f32()],
        sizes in [size_m(), size_m(), size_m(), size_m()],
    ) -> LinearSegment {
        LinearSegment {
            segment_number: number_mods[0],
            modifications: number_mods[1],
            general_appearance: appearance.0,
            specific_appearance: appearance.1,
            location_ecef_m: location,
            orientation_rad: orientation,
            length_m: sizes[0],
            width_m: sizes[1],
            height_m: sizes[2],
            depth_m: sizes[3],
        }
    }
}

prop_compose! {
    fn linear_state()(
        ids in (object_id(), object_id()),
        update_number in any::<u16>(),
        force_id in any::<u8>(),
        addresses in (address(), address()),
        object_type in object_type(),
        segments in prop::collection::vec(linear_segment(), 0..12),
    ) -> LinearObjectState {
        LinearObjectState {
            object_id: ids.0,
            referenced_object_id: ids.1,
            update_number,
            force_id,
            requester: addresses.0,
            receiver: addresses.1,
            object_type,
            segments,
        }
    }
}

fn header() -> impl Strategy<Value = EncodeHeader> {
    (any::<u8>(), any::<u32>()).prop_map(|(exercise_id, timestamp)| EncodeHeader {
        version: DisVersion::V7,
        exercise_id,
        timestamp,
    })
}

/// A version 7 Synthetic Environment header of `pdu_type` in front of `body`, length correct.
fn framed(pdu_type: u8, body: &[u8]) -> Vec<u8> {
    let len = u16::try_from(12 + body.len()).expect("small");
    let mut b = vec![7, 1, pdu_type, 9, 0, 0, 0, 0];
    b.extend_from_slice(&len.to_be_bytes());
    b.extend_from_slice(&[0, 0]);
    b.extend_from_slice(body);
    b
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(128))]

    #[test]
    fn point_object_state_round_trips(h in header(), p in point_state()) {
        let b = encode_point_object_state(h, &p).expect("valid values encode");
        prop_assert_eq!(b.len(), 88);
        prop_assert_eq!(decode_point_object_state(&b), Ok(p));
    }

    #[test]
    fn linear_object_state_round_trips(h in header(), l in linear_state()) {
        let b = encode_linear_object_state(h, &l).expect("valid values encode");
        prop_assert_eq!(b.len(), 40 + 64 * l.segments.len());
        prop_assert_eq!(decode_linear_object_state(&b), Ok(l));
    }

    #[test]
    fn decoding_arbitrary_octets_never_panics(bytes in prop::collection::vec(any::<u8>(), 0..700)) {
        let _ = decode_point_object_state(&bytes);
        let _ = decode_linear_object_state(&bytes);
        let _ = decode_point_object_state_body(&bytes);
        let _ = decode_linear_object_state_body(&bytes);
    }

    #[test]
    fn decoding_arbitrary_bodies_behind_a_good_header_never_panics(
        body in prop::collection::vec(any::<u8>(), 0..700),
        count in any::<u8>(),
    ) {
        let _ = decode_point_object_state(&framed(43, &body));
        let mut body = body;
        if body.len() > 15 {
            body[15] = count;
        }
        if let Ok(l) = decode_linear_object_state(&framed(44, &body)) {
            prop_assert_eq!(body.len(), 28 + 64 * l.segments.len());
            prop_assert!(l.validate().is_ok());
        }
    }

    #[test]
    fn random_segments_of_the_right_size_decode_or_name_a_bad_value(
        count in 0_usize..6,
        seed in prop::collection::vec(any::<u8>(), 28 + 5 * 64),
    ) {
        let mut body = seed[..28 + count * 64].to_vec();
        body[15] = u8::try_from(count).expect("small");
        match decode_linear_object_state(&framed(44, &body)) {
            Ok(l) => prop_assert_eq!(l.segments.len(), count),
            Err(ObjectStateError::NotFinite { field } | ObjectStateError::NegativeSize { field }) => {
                prop_assert!(field.starts_with("segments["), "{}", field);
            }
            Err(e) => prop_assert!(false, "unexpected error {}", e),
        }
    }

    #[test]
    fn every_truncation_of_a_valid_pdu_is_refused(
        p in point_state(),
        l in linear_state(),
        cut in any::<prop::sample::Index>(),
    ) {
        let point = encode_point_object_state(HEADER, &p).expect("valid");
        let at = cut.index(point.len());
        prop_assert!(decode_point_object_state(&point[..at]).is_err());
        let linear = encode_linear_object_state(HEADER, &l).expect("valid");
        let at = cut.index(linear.len());
        prop_assert!(decode_linear_object_state(&linear[..at]).is_err());
        // Also with the length field rewritten to match the cut (a lying sender).
        if at >= 12 {
            let mut lying = linear[..at].to_vec();
            lying[8..10].copy_from_slice(&u16::try_from(at).expect("small").to_be_bytes());
            prop_assert!(decode_linear_object_state(&lying).is_err());
        }
    }

    #[test]
    fn mutated_valid_pdus_never_panic(
        p in point_state(),
        l in linear_state(),
        flips in prop::collection::vec((any::<prop::sample::Index>(), any::<u8>()), 1..8),
    ) {
        let mut point = encode_point_object_state(HEADER, &p).expect("valid");
        let mut linear = encode_linear_object_state(HEADER, &l).expect("valid");
        for (i, v) in &flips {
            let n = point.len();
            point[i.index(n)] ^= v;
            let n = linear.len();
            linear[i.index(n)] ^= v;
        }
        if let Ok(p) = decode_point_object_state(&point) {
            prop_assert!(p.validate().is_ok());
        }
        if let Ok(l) = decode_linear_object_state(&linear) {
            prop_assert!(l.validate().is_ok());
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Open-DIS for Python as a peer. Its DIS 7 layouts agree with the standard for both PDUs in
// size and field positions: the Point Object State PDU's 64-bit appearance is one opaque
// `double` there (packed here from specific u32, general u16, pad u16), and its Linear Segment
// Parameter is the 64-octet record with float sizes. Its `LinearObjectStatePdu()` constructor
// raises NameError (opendis 1.0 assigns an undefined `numberOfSegments`), so the scripts build
// and parse that PDU through `__new__`.

const PREAMBLE: &str = r"

def linear_pdu():
    p = LinearObjectStatePdu.__new__(LinearObjectStatePdu)
    SyntheticEnvironmentFamilyPdu.__init__(p)
    p.objectID = EntityID()
    p.referencedObjectID = EntityID()
    p.updateNumber = 0
    p.forceID = 0
    p.requesterID = SimulationAddress()
    p.receivingID = SimulationAddress()
    p.objectType = ObjectType()
    p.linearSegmentParameters = []
    return p
";

/// Runs a Python script with opendis; `None` (and a message) when the peer is unavailable.
fn python(script: &str, arg: &str) -> Option<String> {
    common::python(PREAMBLE, script, arg)
}

#[test]
fn opendis_point_object_state_decodes_here() {
    let script = r"
p = PointObjectStatePdu()
p.objectID = EntityID(11, 22, 33)
p.referencedObjectID = EntityID(11, 22, 1)
p.updateNumber = 7
p.forceID = 2
p.modifications = 1
p.objectType = ObjectType(1, 1, 3, 2)
p.objectLocation = Vector3Double(-2700000.5, -4300000.25, 3850000.125)
p.objectOrientation = EulerAngles(0.75, -0.125, 0.0625)
p.objectAppearance = struct.unpack('>d', struct.pack('>IHH', 0x00010203, 0x0432, 0))[0]
p.requesterID = SimulationAddress(11, 22)
p.receivingID = SimulationAddress(65535, 65535)
print(finish(p, 43, 9).hex())
";
    let Some(out) = python(script, "") else {
        return;
    };
    let bytes = unhex(&out);
    assert_eq!(bytes.len(), 88, "opendis writes the 88-octet PDU");
    let p = decode_point_object_state(&bytes).expect("opendis bytes decode");
    assert_eq!(
        p,
        PointObjectState {
            object_id: ObjectId {
                site: 11,
                application: 22,
                object: 33
            },
            referenced_object_id: ObjectId {
                site: 11,
                application: 22,
                object: 1
            },
            update_number: 7,
            force_id: 2,
            modifications: 1,
            object_type: ObjectType::POINT_CRATER_MEDIUM,
            location_ecef_m: [-2_700_000.5, -4_300_000.25, 3_850_000.125],
            orientation_rad: [0.75, -0.125, 0.0625],
            specific_appearance: 0x0001_0203,
            general_appearance: 0x0432,
            requester: SimulationAddress {
                site: 11,
                application: 22
            },
            receiver: SimulationAddress {
                site: 65535,
                application: 65535
            },
        }
    );
}

#[test]
fn opendis_linear_object_state_decodes_here() {
    let script = r"
p = linear_pdu()
p.objectID = EntityID(5, 6, 7)
p.updateNumber = 9
p.forceID = 1
p.requesterID = SimulationAddress(5, 6)
p.receivingID = SimulationAddress(65535, 65535)
p.objectType = ObjectType(1, 1, 5, 0)
for i in range(3):
    p.linearSegmentParameters.append(LinearSegmentParameter(
        segmentNumber=i, segmentModification=3, generalSegmentAppearance=100,
        specificSegmentAppearance=0x0A0B0C00 | i,
        segmentLocation=Vector3Double(4000000.0 + i, 300000.5, 4900000.25),
        segmentOrientation=EulerAngles(1.5, 0.0, -0.25),
        segmentLength=25.5, segmentWidth=4.0, segmentHeight=0.75, segmentDepth=2.5))
print(finish(p, 44, 9).hex())
";
    let Some(out) = python(script, "") else {
        return;
    };
    let bytes = unhex(&out);
    assert_eq!(bytes.len(), 40 + 3 * 64, "opendis writes 64-octet segments");
    let l = decode_linear_object_state(&bytes).expect("opendis bytes decode");
    let mut expected = ditch(3);
    expected.object_type = ObjectType::LINEAR_RUT;
    assert_eq!(l, expected);
}

#[test]
fn our_object_states_parse_in_opendis() {
    let header = EncodeHeader {
        version: DisVersion::V7,
        exercise_id: 9,
        timestamp: 12345,
    };
    let point = encode_point_object_state(header, &crater()).expect("valid");
    let linear = encode_linear_object_state(header, &ditch(2)).expect("valid");
    let script = r"
out = []
for h in sys.argv[1].split(','):
    data = bytes.fromhex(h)
    if data[2] == 43:
        p = createPdu(data)
        spec, gen, pad = struct.unpack('>IHH', struct.pack('>d', p.objectAppearance))
        out.append([p.pduType, p.protocolFamily, p.exerciseID, p.timestamp, p.length,
            [p.objectID.siteID, p.objectID.applicationID, p.objectID.entityID],
            [p.referencedObjectID.siteID, p.referencedObjectID.applicationID, p.referencedObjectID.entityID],
            p.updateNumber, p.forceID, p.modifications,
            [p.objectType.domain, p.objectType.objectKind, p.objectType.category, p.objectType.subcategory],
            [p.objectLocation.x, p.objectLocation.y, p.objectLocation.z],
            [p.objectOrientation.psi, p.objectOrientation.theta, p.objectOrientation.phi],
            spec, gen, pad,
            [p.requesterID.site, p.requesterID.application],
            [p.receivingID.site, p.receivingID.application], p.pad2])
    else:
        p = linear_pdu()
        p.parse(DataInputStream(BytesIO(data)))
        segs = [[s.segmentNumber, s.segmentModification, s.generalSegmentAppearance,
                 s.specificSegmentAppearance,
                 [s.segmentLocation.x, s.segmentLocation.y, s.segmentLocation.z],
                 [s.segmentOrientation.psi, s.segmentOrientation.theta, s.segmentOrientation.phi],
                 s.segmentLength, s.segmentWidth, s.segmentHeight, s.segmentDepth, s.padding]
                for s in p.linearSegmentParameters]
        out.append([p.pduType, p.protocolFamily, p.exerciseID, p.timestamp, p.length,
            [p.objectID.siteID, p.objectID.applicationID, p.objectID.entityID],
            p.updateNumber, p.forceID, len(p.linearSegmentParameters),
            [p.requesterID.site, p.requesterID.application],
            [p.receivingID.site, p.receivingID.application],
            [p.objectType.domain, p.objectType.objectKind, p.objectType.category, p.objectType.subcategory],
            segs])
print(json.dumps(out))
";
    let arg = format!("{},{}", hex(&point), hex(&linear));
    let Some(out) = python(script, &arg) else {
        return;
    };
    let expected_point = format!(
        "[43, 9, 9, 12345, 88, [{}, {}, {}], [{}, {}, {}], {}, 2, 1, [1, 1, 3, 2], \
         [-2700000.5, -4300000.25, 3850000.125], [0.75, -0.125, 0.0625], {}, {}, 0, \
         [{}, {}], [65535, 65535], 0]",
        0x0A01, 0x0A02, 0x0A03, 0x0B01, 0x0B02, 0x0B03, 0x0C0D, 0x1122_3344, 0x5566, 0x0D01, 0x0D02,
    );
    let seg = |n: u32| {
        format!(
            "[{n}, 3, 100, {}, [{}.0, 300000.5, 4900000.25], [1.5, 0.0, -0.25], \
             25.5, 4.0, 0.75, 2.5, 0]",
            0x0A0B_0C00 | n,
            4_000_000 + n
        )
    };
    let expected_linear = format!(
        "[44, 9, 9, 12345, 168, [5, 6, 7], 9, 1, 2, [5, 6], [65535, 65535], [1, 1, 1, 0], [{}, {}]]",
        seg(0),
        seg(1)
    );
    assert_eq!(out, format!("[{expected_point}, {expected_linear}]"));
}
