//! PDU codec: split a datagram into PDUs, check each PDU header, and decode the bodies cig uses.
//!
//! Algorithm: every DIS PDU starts with the 12-octet PDU header (IEEE 1278.1-2012 §6.2.66;
//! 1278.1a-1998 §5.2.29 for version 6): protocol version, exercise ID, PDU type, protocol
//! family, timestamp (32 bits), PDU length in octets (16 bits), then PDU status + padding (v7)
//! or two padding octets (v6). A datagram may bundle several PDUs back to back (IEEE 1278.2
//! §4.1.3). This module walks the datagram by the declared lengths, rejects headers that are
//! too short, too long for the datagram or of another protocol version than 6 or 7, and hands
//! each PDU slice — cut to exactly its declared length — to the decoder of its type:
//!
//! * Entity State (1), Fire (2), Detonation (3), Remove Entity (12), Data Query (18),
//!   Set Data (19) and Data (20): the `dis-rs` crate (0.13), which implements both versions;
//! * Environmental Process (41): [`crate::environmental`], and Point (43) and Linear (44)
//!   Object State: [`crate::object_state`], written here because `dis-rs` lacks them;
//! * any other type: reported as [`DisMessage::Unsupported`] with its header, never parsed
//!   further (this also keeps the rest of `dis-rs`'s parsers away from untrusted input).
//!
//! Limits: only big-endian DIS as the standard defines it; no PDU-type-specific validation of
//! enumerations beyond what `dis-rs` does (unknown enumeration values decode as "unspecified").
//! Timestamps are passed through raw; [`timestamp_seconds_past_hour`] converts them.

use bytes::BytesMut;
use dis_rs::data::model::Data;
use dis_rs::data_query::model::DataQuery;
use dis_rs::detonation::model::Detonation;
use dis_rs::entity_state::model::EntityState;
use dis_rs::enumerations::{PduType, ProtocolVersion};
use dis_rs::fire::model::Fire;
use dis_rs::model::{Pdu, PduBody, PduHeader, TimeStamp};
use dis_rs::remove_entity::model::RemoveEntity;
use dis_rs::set_data::model::SetData;

use crate::environmental::{self, EnvironmentalProcess};
use crate::object_state::{self, LinearObjectState, PointObjectState};

/// Octets in a PDU header (both versions).
pub const PDU_HEADER_OCTETS: usize = 12;
/// PDU type number of the Environmental Process PDU (SISO-REF-010 UID 4).
pub const PDU_TYPE_ENVIRONMENTAL_PROCESS: u8 = 41;
/// Protocol family of the Environmental Process PDU: Synthetic Environment (SISO-REF-010 UID 5).
pub const PROTOCOL_FAMILY_SYNTHETIC_ENVIRONMENT: u8 = 9;

/// The DIS protocol versions cig reads and writes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum DisVersion {
    /// IEEE 1278.1a-1998 (protocol version 6).
    V6,
    /// IEEE 1278.1-2012 (protocol version 7).
    V7,
}

impl DisVersion {
    /// The protocol version octet.
    #[must_use]
    pub fn octet(self) -> u8 {
        match self {
            DisVersion::V6 => 6,
            DisVersion::V7 => 7,
        }
    }

    /// The version for a protocol version octet, `None` for versions cig does not read.
    #[must_use]
    pub fn from_octet(octet: u8) -> Option<DisVersion> {
        match octet {
            6 => Some(DisVersion::V6),
            7 => Some(DisVersion::V7),
            _ => None,
        }
    }

    fn protocol_version(self) -> ProtocolVersion {
        match self {
            DisVersion::V6 => ProtocolVersion::IEEE1278_1A1998,
            DisVersion::V7 => ProtocolVersion::IEEE1278_12012,
        }
    }
}

/// The PDU header fields, as raw as they came.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PduHeaderInfo {
    /// Protocol version (6 or 7 for anything this module decodes).
    pub version: DisVersion,
    /// Exercise ID.
    pub exercise_id: u8,
    /// PDU type number (SISO-REF-010 UID 4).
    pub pdu_type: u8,
    /// Protocol family number (SISO-REF-010 UID 5).
    pub protocol_family: u8,
    /// Raw timestamp (units of 3600 s / 2^31 past the hour; low bit 1 = absolute).
    pub timestamp: u32,
    /// Declared PDU length in octets, header included.
    pub length_octets: u16,
    /// Octet 10: PDU status in version 7, padding in version 6.
    pub status_octet: u8,
}

/// A decoded PDU body.
#[derive(Clone, Debug, PartialEq)]
pub enum DisMessage {
    /// Entity State PDU (type 1).
    EntityState(Box<EntityState>),
    /// Fire PDU (type 2).
    Fire(Box<Fire>),
    /// Detonation PDU (type 3).
    Detonation(Box<Detonation>),
    /// Remove Entity PDU (type 12).
    RemoveEntity(RemoveEntity),
    /// Data Query PDU (type 18).
    DataQuery(DataQuery),
    /// Set Data PDU (type 19).
    SetData(SetData),
    /// Data PDU (type 20).
    Data(Data),
    /// Environmental Process PDU (type 41).
    EnvironmentalProcess(EnvironmentalProcess),
    /// Point Object State PDU (type 43).
    PointObjectState(Box<PointObjectState>),
    /// Linear Object State PDU (type 44).
    LinearObjectState(Box<LinearObjectState>),
    /// A PDU of another type: header only.
    Unsupported,
}

/// One decoded PDU: its header and body.
#[derive(Clone, Debug, PartialEq)]
pub struct DecodedPdu {
    /// Header fields.
    pub header: PduHeaderInfo,
    /// Body.
    pub message: DisMessage,
}

/// Why a PDU could not be decoded.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum DecodeError {
    /// Fewer octets than a PDU header.
    #[error("DIS PDU: {got} octets, a header needs {PDU_HEADER_OCTETS}")]
    TruncatedHeader {
        /// Octets available.
        got: usize,
    },
    /// Protocol version other than 6 or 7.
    #[error("DIS PDU: protocol version {0} is not read (only 6 and 7)")]
    UnsupportedVersion(u8),
    /// Declared length shorter than the header.
    #[error("DIS PDU type {pdu_type}: declared length {declared} is shorter than the header")]
    LengthBelowHeader {
        /// PDU type number.
        pdu_type: u8,
        /// Declared length.
        declared: u16,
    },
    /// Declared length longer than the octets that arrived.
    #[error(
        "DIS PDU type {pdu_type}: declared length {declared} but only {available} octets arrived"
    )]
    Truncated {
        /// PDU type number.
        pdu_type: u8,
        /// Declared length.
        declared: u16,
        /// Octets available.
        available: usize,
    },
    /// The body does not parse.
    #[error("DIS PDU type {pdu_type}: malformed body: {reason}")]
    Malformed {
        /// PDU type number.
        pdu_type: u8,
        /// What was wrong.
        reason: String,
    },
}

/// Why a PDU could not be encoded.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum EncodeError {
    /// The PDU would be longer than the 16-bit length field allows.
    #[error("DIS PDU: body of {0} octets does not fit the 16-bit length field")]
    TooLong(usize),
    /// `dis-rs` refused to serialise.
    #[error("DIS PDU: dis-rs could not serialise it: {0}")]
    Serialise(String),
    /// [`DisMessage::Unsupported`] carries no body to write.
    #[error("DIS PDU: an unsupported PDU has no body to encode")]
    NoBody,
}

/// Reads the header at the start of `bytes` without looking at the body.
///
/// # Errors
/// [`DecodeError::TruncatedHeader`], [`DecodeError::UnsupportedVersion`],
/// [`DecodeError::LengthBelowHeader`] or [`DecodeError::Truncated`].
pub fn decode_header(bytes: &[u8]) -> Result<PduHeaderInfo, DecodeError> {
    let Some(head) = bytes.get(..PDU_HEADER_OCTETS) else {
        return Err(DecodeError::TruncatedHeader { got: bytes.len() });
    };
    let octet = |i: usize| head.get(i).copied().unwrap_or(0);
    let version =
        DisVersion::from_octet(octet(0)).ok_or(DecodeError::UnsupportedVersion(octet(0)))?;
    let pdu_type = octet(2);
    let declared = u16::from_be_bytes([octet(8), octet(9)]);
    if usize::from(declared) < PDU_HEADER_OCTETS {
        return Err(DecodeError::LengthBelowHeader { pdu_type, declared });
    }
    if usize::from(declared) > bytes.len() {
        return Err(DecodeError::Truncated {
            pdu_type,
            declared,
            available: bytes.len(),
        });
    }
    Ok(PduHeaderInfo {
        version,
        exercise_id: octet(1),
        pdu_type,
        protocol_family: octet(3),
        timestamp: u32::from_be_bytes([octet(4), octet(5), octet(6), octet(7)]),
        length_octets: declared,
        status_octet: octet(10),
    })
}

/// Decodes the one PDU at the start of `bytes` (octets after its declared length are ignored).
///
/// # Errors
/// Any [`DecodeError`]; never panics on any input.
pub fn decode_pdu(bytes: &[u8]) -> Result<DecodedPdu, DecodeError> {
    let header = decode_header(bytes)?;
    let pdu = bytes
        .get(..usize::from(header.length_octets))
        .ok_or(DecodeError::Truncated {
            pdu_type: header.pdu_type,
            declared: header.length_octets,
            available: bytes.len(),
        })?;
    let malformed = |reason: String| DecodeError::Malformed {
        pdu_type: header.pdu_type,
        reason,
    };
    let message = match header.pdu_type {
        1 | 2 | 3 | 12 | 18 | 19 | 20 => {
            // dis-rs parses as many PDUs as the slice holds and its parsers for types cig does
            // not use are not hardened, so it gets exactly the octets the body's own fields
            // describe: nothing is left behind to be read as a second PDU.
            let body = pdu.get(PDU_HEADER_OCTETS..).unwrap_or_default();
            let needed = body_octets(header.pdu_type, body)
                .ok_or_else(|| malformed("body shorter than its own fields say".to_string()))?;
            let exact = pdu
                .get(..PDU_HEADER_OCTETS + needed)
                .ok_or_else(|| malformed("body shorter than its own fields say".to_string()))?;
            let mut pdus = dis_rs::parse(exact).map_err(|e| malformed(e.to_string()))?;
            if pdus.is_empty() {
                return Err(malformed("no PDU parsed".to_string()));
            }
            let parsed = pdus.swap_remove(0);
            match parsed.body {
                PduBody::EntityState(body) => DisMessage::EntityState(Box::new(body)),
                PduBody::Fire(body) => DisMessage::Fire(Box::new(body)),
                PduBody::Detonation(body) => DisMessage::Detonation(Box::new(body)),
                PduBody::RemoveEntity(body) => DisMessage::RemoveEntity(body),
                PduBody::DataQuery(body) => DisMessage::DataQuery(body),
                PduBody::SetData(body) => DisMessage::SetData(body),
                PduBody::Data(body) => DisMessage::Data(body),
                _ => return Err(malformed("body of another type".to_string())),
            }
        }
        PDU_TYPE_ENVIRONMENTAL_PROCESS => {
            let body = pdu.get(PDU_HEADER_OCTETS..).unwrap_or_default();
            DisMessage::EnvironmentalProcess(
                environmental::decode_body(body).map_err(|e| malformed(e.to_string()))?,
            )
        }
        object_state::PDU_TYPE_POINT_OBJECT_STATE => {
            let body = pdu.get(PDU_HEADER_OCTETS..).unwrap_or_default();
            DisMessage::PointObjectState(Box::new(
                object_state::decode_point_object_state_body(body)
                    .map_err(|e| malformed(e.to_string()))?,
            ))
        }
        object_state::PDU_TYPE_LINEAR_OBJECT_STATE => {
            let body = pdu.get(PDU_HEADER_OCTETS..).unwrap_or_default();
            DisMessage::LinearObjectState(Box::new(
                object_state::decode_linear_object_state_body(body)
                    .map_err(|e| malformed(e.to_string()))?,
            ))
        }
        _ => DisMessage::Unsupported,
    };
    Ok(DecodedPdu { header, message })
}

/// The octets a body of a type cig hands to dis-rs occupies according to its own count and
/// length fields (IEEE 1278.1-2012 §7.2.2, 7.3.2, 7.3.3, 7.5.3, 7.5.9-7.5.11); `None` when those
/// fields point past the end of `body`.
fn body_octets(pdu_type: u8, body: &[u8]) -> Option<usize> {
    let u8_at = |i: usize| body.get(i).copied().map(usize::from);
    let u32_at = |i: usize| -> Option<usize> {
        let b: [u8; 4] = body.get(i..i + 4)?.try_into().ok()?;
        usize::try_from(u32::from_be_bytes(b)).ok()
    };
    let needed = match pdu_type {
        1 => 132 + 16 * u8_at(7)?,
        2 => 84,
        3 => 92 + 16 * u8_at(89)?,
        12 => 16,
        18 => {
            let fixed = u32_at(20)?;
            let variable = u32_at(24)?;
            fixed
                .checked_add(variable)?
                .checked_mul(4)?
                .checked_add(28)?
        }
        19 | 20 => {
            let fixed = u32_at(20)?;
            let variable = u32_at(24)?;
            let mut at = fixed.checked_mul(8)?.checked_add(28)?;
            for _ in 0..variable {
                if at > body.len() {
                    return None;
                }
                let value_octets = u32_at(at + 4)? / 8;
                at = at
                    .checked_add(8)?
                    .checked_add(value_octets.div_ceil(8) * 8)?;
            }
            at
        }
        _ => return None,
    };
    (needed <= body.len()).then_some(needed)
}

/// Decodes every PDU bundled in a datagram, in order. A PDU that fails is reported and the walk
/// goes on after its declared length; a header that cannot be read ends the walk.
#[must_use]
pub fn decode_datagram(datagram: &[u8]) -> Vec<Result<DecodedPdu, DecodeError>> {
    let mut out = Vec::new();
    let mut rest = datagram;
    while !rest.is_empty() {
        match decode_header(rest) {
            Ok(header) => {
                out.push(decode_pdu(rest));
                rest = rest
                    .get(usize::from(header.length_octets)..)
                    .unwrap_or_default();
            }
            Err(e) => {
                out.push(Err(e));
                break;
            }
        }
    }
    out
}

/// What to put in the header of a PDU to encode.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct EncodeHeader {
    /// Protocol version.
    pub version: DisVersion,
    /// Exercise ID.
    pub exercise_id: u8,
    /// Raw timestamp (see [`timestamp_from_seconds_past_hour`]).
    pub timestamp: u32,
}

/// Encodes one PDU (header and body) into a new buffer.
///
/// # Errors
/// [`EncodeError`] when the body is too long, cannot be written, or is
/// [`DisMessage::Unsupported`].
pub fn encode_pdu(header: EncodeHeader, message: &DisMessage) -> Result<Vec<u8>, EncodeError> {
    let body: PduBody = match message {
        DisMessage::EntityState(b) => {
            // dis-rs pads the marking with `11 - len` octets and underflows (a panic, or a
            // multi-GB allocation in release builds) on longer strings, which a received
            // non-ASCII marking becomes after its lossy UTF-8 decoding: keep 11 ASCII chars.
            let mut body = (**b).clone();
            body.entity_marking.marking_string = body
                .entity_marking
                .marking_string
                .chars()
                .filter(char::is_ascii)
                .take(11)
                .collect();
            PduBody::EntityState(body)
        }
        DisMessage::Fire(b) => PduBody::Fire((**b).clone()),
        DisMessage::Detonation(b) => PduBody::Detonation((**b).clone()),
        DisMessage::RemoveEntity(b) => PduBody::RemoveEntity(b.clone()),
        DisMessage::DataQuery(b) => PduBody::DataQuery(b.clone()),
        DisMessage::SetData(b) => PduBody::SetData(b.clone()),
        DisMessage::Data(b) => PduBody::Data(b.clone()),
        DisMessage::EnvironmentalProcess(process) => {
            let body = environmental::encode_body(process);
            return wrap_raw_body(
                header,
                PDU_TYPE_ENVIRONMENTAL_PROCESS,
                PROTOCOL_FAMILY_SYNTHETIC_ENVIRONMENT,
                &body,
            );
        }
        DisMessage::PointObjectState(pdu) => {
            let body = object_state::encode_point_object_state_body(pdu)
                .map_err(|e| EncodeError::Serialise(e.to_string()))?;
            return wrap_raw_body(
                header,
                object_state::PDU_TYPE_POINT_OBJECT_STATE,
                PROTOCOL_FAMILY_SYNTHETIC_ENVIRONMENT,
                &body,
            );
        }
        DisMessage::LinearObjectState(pdu) => {
            let body = object_state::encode_linear_object_state_body(pdu)
                .map_err(|e| EncodeError::Serialise(e.to_string()))?;
            return wrap_raw_body(
                header,
                object_state::PDU_TYPE_LINEAR_OBJECT_STATE,
                PROTOCOL_FAMILY_SYNTHETIC_ENVIRONMENT,
                &body,
            );
        }
        DisMessage::Unsupported => return Err(EncodeError::NoBody),
    };
    let dis_header = PduHeader::new(
        header.version.protocol_version(),
        header.exercise_id,
        PduType::Other,
    );
    let pdu = Pdu::finalize_from_parts(dis_header, body, TimeStamp::new(header.timestamp));
    let length = usize::from(pdu.pdu_length());
    let mut buf = BytesMut::with_capacity(length);
    pdu.serialize(&mut buf)
        .map_err(|e| EncodeError::Serialise(e.to_string()))?;
    // dis-rs computes lengths in 16 bits; a body beyond that wraps the header's length field.
    if buf.len() != length {
        return Err(EncodeError::TooLong(buf.len()));
    }
    Ok(buf.to_vec())
}

/// Prefixes a hand-written body with a PDU header.
fn wrap_raw_body(
    header: EncodeHeader,
    pdu_type: u8,
    protocol_family: u8,
    body: &[u8],
) -> Result<Vec<u8>, EncodeError> {
    let total = PDU_HEADER_OCTETS + body.len();
    let length = u16::try_from(total).map_err(|_| EncodeError::TooLong(body.len()))?;
    let mut out = Vec::with_capacity(total);
    out.push(header.version.octet());
    out.push(header.exercise_id);
    out.push(pdu_type);
    out.push(protocol_family);
    out.extend_from_slice(&header.timestamp.to_be_bytes());
    out.extend_from_slice(&length.to_be_bytes());
    out.extend_from_slice(&[0, 0]);
    out.extend_from_slice(body);
    Ok(out)
}

/// Timestamp units per hour (IEEE 1278.1-2012 §6.2.88: the 31 high bits count 3600 s / 2^31).
const TIMESTAMP_UNITS_PER_HOUR: f64 = 2_147_483_648.0;

/// A DIS timestamp for `seconds_past_hour` (wrapped into [0, 3600)), absolute (low bit 1, the
/// sender's clock is UTC-synchronised) or relative (low bit 0).
#[must_use]
pub fn timestamp_from_seconds_past_hour(seconds_past_hour: f64, absolute: bool) -> u32 {
    let wrapped = if seconds_past_hour.is_finite() {
        seconds_past_hour.rem_euclid(3600.0)
    } else {
        0.0
    };
    let units = (wrapped / 3600.0 * TIMESTAMP_UNITS_PER_HOUR).floor();
    #[expect(
        clippy::cast_possible_truncation,
        clippy::cast_sign_loss,
        reason = "units is in [0, 2^31) by construction"
    )]
    let units = (units as u64).min((1 << 31) - 1) as u32;
    (units << 1) | u32::from(absolute)
}

/// Seconds past the hour and the absolute flag of a DIS timestamp.
#[must_use]
pub fn timestamp_seconds_past_hour(timestamp: u32) -> (f64, bool) {
    let units = f64::from(timestamp >> 1);
    (
        units / TIMESTAMP_UNITS_PER_HOUR * 3600.0,
        timestamp & 1 == 1,
    )
}
