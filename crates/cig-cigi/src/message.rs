//! Messages: version and byte-order detection, the packet walk, and the
//! variable-size packets (Image Generator Message, user-defined).
//!
//! Algorithm: see the crate documentation. The walk reads each packet's
//! header, checks the declared size against what remains of the datagram and
//! against the layout's minimum, decodes the packet, and advances by the
//! declared size (so packets a newer minor version made longer still decode).
//! Unknown or untyped IDs are stepped over and recorded as warnings.
//!
//! Limits: a packet whose declared size runs past the datagram, a size
//! smaller than the header, or a typed packet shorter than its layout ends
//! decoding with a [`CigiError`] naming the packet and its offset; packets
//! decoded before it are discarded with the message (a datagram is one
//! frame's worth of state, applied whole or not at all).

use std::fmt;

use thiserror::Error;

use crate::packets::*;
use crate::wire::{ByteOrder, FieldIo, Reader, Writer};
use crate::{v3, v4};

/// Longest Image Generator Message text, in bytes: the 3.3 packet is at most
/// 104 bytes, 4 of header and the text's terminating NUL included.
pub const MAX_IG_MESSAGE_TEXT_BYTES: usize = 99;

/// A CIGI protocol version.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Version {
    /// Major version: 3 or 4.
    pub major: u8,
    /// Minor version (4 bits on the wire).
    pub minor: u8,
}

impl Version {
    /// CIGI 3.3.
    pub const V3_3: Version = Version { major: 3, minor: 3 };
    /// CIGI 4.0.
    pub const V4_0: Version = Version { major: 4, minor: 0 };
}

impl fmt::Display for Version {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}.{}", self.major, self.minor)
    }
}

macro_rules! packet_enum {
    ($( $(#[$meta:meta])* $variant:ident ),* $(,)?) => {
        /// One typed CIGI packet.
        #[derive(Debug, Clone, PartialEq)]
        pub enum Packet {
            $( $(#[$meta])* $variant($variant), )*
        }

        impl Packet {
            /// The packet's name, as used in errors and warnings.
            #[must_use]
            pub fn name(&self) -> &'static str {
                match self {
                    $( Packet::$variant(_) => stringify!($variant), )*
                }
            }
        }
    };
}

packet_enum! {
    /// IG Control (3.x ID 1, 4.0 ID 0x00).
    IgControl,
    /// Entity Control (3.x ID 2; 3.x only).
    EntityControl,
    /// Entity Position (4.0 ID 0x01; 4.0 only).
    EntityPosition,
    /// Entity Control (4.0 ID 0x25; 4.0 only).
    EntityControl4,
    /// Animation Control (4.0 ID 0x26; 4.0 only).
    AnimationControl,
    /// Conformal Clamped Entity Control (3.x ID 3, 4.0 ID 0x02).
    ConformalClampedEntity,
    /// Component Control (3.x ID 4, 4.0 ID 0x03).
    ComponentControl,
    /// Short Component Control (3.x ID 5, 4.0 ID 0x04).
    ShortComponentControl,
    /// Articulated Part Control (3.x ID 6, 4.0 ID 0x05).
    ArticulatedPart,
    /// Short Articulated Part Control (3.x ID 7, 4.0 ID 0x06).
    ShortArticulatedPart,
    /// Rate Control (3.x ID 8) / Velocity Control (4.0 ID 0x07).
    RateControl,
    /// Celestial Sphere Control (3.x ID 9, 4.0 ID 0x08).
    CelestialSphereControl,
    /// Atmosphere Control (3.x ID 10, 4.0 ID 0x09).
    AtmosphereControl,
    /// Environmental Region Control (3.x ID 11, 4.0 ID 0x0A).
    EnvironmentalRegionControl,
    /// Weather Control (3.x ID 12, 4.0 ID 0x0B).
    WeatherControl,
    /// Maritime Surface Conditions Control (3.x ID 13, 4.0 ID 0x0C).
    MaritimeSurfaceConditionsControl,
    /// Wave Control (3.x ID 14, 4.0 ID 0x0D).
    WaveControl,
    /// Terrestrial Surface Conditions Control (3.x ID 15, 4.0 ID 0x0E).
    TerrestrialSurfaceConditionsControl,
    /// View Control (3.x ID 16, 4.0 ID 0x0F).
    ViewControl,
    /// Sensor Control (3.x ID 17, 4.0 ID 0x10).
    SensorControl,
    /// View Definition (3.x ID 21, 4.0 ID 0x14).
    ViewDefinition,
    /// Collision Detection Segment Definition (3.x ID 22, 4.0 ID 0x15).
    CollisionSegmentDefinition,
    /// Collision Detection Volume Definition (3.x ID 23, 4.0 ID 0x16).
    CollisionVolumeDefinition,
    /// HAT/HOT Request (3.x ID 24, 4.0 ID 0x17).
    HatHotRequest,
    /// Line of Sight Segment Request (3.x ID 25, 4.0 ID 0x18).
    LosSegmentRequest,
    /// Line of Sight Vector Request (3.x ID 26, 4.0 ID 0x19).
    LosVectorRequest,
    /// Position Request (3.x ID 27, 4.0 ID 0x1A).
    PositionRequest,
    /// Environmental Conditions Request (3.x ID 28, 4.0 ID 0x1B).
    EnvironmentalConditionsRequest,
    /// Start of Frame (3.x ID 101, 4.0 ID 0xFFFF).
    StartOfFrame,
    /// HAT/HOT Response (3.x ID 102, 4.0 ID 0x0FFF).
    HatHotResponse,
    /// HAT/HOT Extended Response (3.x ID 103, 4.0 ID 0x0FFE).
    HatHotExtendedResponse,
    /// Line of Sight Response (3.x ID 104, 4.0 ID 0x0FFD).
    LosResponse,
    /// Line of Sight Extended Response (3.x ID 105, 4.0 ID 0x0FFC).
    LosExtendedResponse,
    /// Sensor Response (3.x ID 106, 4.0 ID 0x0FFB).
    SensorResponse,
    /// Sensor Extended Response (3.x ID 107, 4.0 ID 0x0FFA).
    SensorExtendedResponse,
    /// Position Response (3.x ID 108, 4.0 ID 0x0FF9).
    PositionResponse,
    /// Weather Conditions Response (3.x ID 109, 4.0 ID 0x0FF8).
    WeatherConditionsResponse,
    /// Aerosol Concentration Response (3.x ID 110, 4.0 ID 0x0FF7).
    AerosolConcentrationResponse,
    /// Maritime Surface Conditions Response (3.x ID 111, 4.0 ID 0x0FF6).
    MaritimeSurfaceConditionsResponse,
    /// Terrestrial Surface Conditions Response (3.x ID 112, 4.0 ID 0x0FF5).
    TerrestrialSurfaceConditionsResponse,
    /// Collision Detection Segment Notification (3.x ID 113, 4.0 ID 0x0FF4).
    CollisionSegmentNotification,
    /// Collision Detection Volume Notification (3.x ID 114, 4.0 ID 0x0FF3).
    CollisionVolumeNotification,
    /// Animation Stop Notification (3.x ID 115, 4.0 ID 0x0FF2).
    AnimationStopNotification,
    /// Event Notification (3.x ID 116, 4.0 ID 0x0FF1).
    EventNotification,
    /// Image Generator Message (3.x ID 117, 4.0 ID 0x0FF0).
    ImageGeneratorMessage,
    /// User-defined packet (3.x IDs 201-255, 4.0 IDs 0x1000-0xFFFE).
    UserDefined,
}

/// A decoded or to-be-encoded CIGI message (one datagram).
#[derive(Debug, Clone, PartialEq)]
pub struct Message {
    /// Protocol version (from the first packet when decoded).
    pub version: Version,
    /// Byte order of the multi-byte fields.
    pub byte_order: ByteOrder,
    /// The packets in message order; the first is [`Packet::IgControl`] or
    /// [`Packet::StartOfFrame`].
    pub packets: Vec<Packet>,
    /// Packets the decoder stepped over (ignored by the encoder).
    pub warnings: Vec<DecodeWarning>,
}

impl Message {
    /// A message with no warnings.
    #[must_use]
    pub fn new(version: Version, byte_order: ByteOrder, packets: Vec<Packet>) -> Self {
        Self {
            version,
            byte_order,
            packets,
            warnings: Vec::new(),
        }
    }
}

/// A packet the decoder did not decode but could step over.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct DecodeWarning {
    /// Byte offset of the packet in the datagram.
    pub offset: usize,
    /// Its packet ID.
    pub packet_id: u16,
    /// Its declared size in bytes.
    pub size: usize,
    /// Why it was not decoded.
    pub reason: &'static str,
}

impl fmt::Display for DecodeWarning {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "CIGI packet {} ({} bytes) at offset {}: {}",
            self.packet_id, self.size, self.offset, self.reason
        )
    }
}

/// Why a datagram could not be decoded or a message could not be encoded.
#[derive(Debug, Clone, PartialEq, Eq, Error)]
pub enum CigiError {
    /// The datagram is empty.
    #[error("CIGI message: empty datagram")]
    Empty,
    /// The datagram does not start with IG Control or Start of Frame.
    #[error(
        "CIGI message: does not start with a 24-byte IG Control or Start of Frame packet (first bytes {first_bytes:02x?})"
    )]
    NotAMessageStart {
        /// Up to the first 8 bytes.
        first_bytes: Vec<u8>,
    },
    /// A major version this codec does not speak.
    #[error("CIGI message: unsupported version {version}")]
    UnsupportedVersion {
        /// The version found (or asked for).
        version: Version,
    },
    /// The 3.x byte-swap magic number is neither 0x8000 nor 0x0080.
    #[error("CIGI 3 message: byte-swap magic number is {found:#06x}, expected 0x8000 in either byte order")]
    BadMagic {
        /// The 16-bit value read big-endian.
        found: u16,
    },
    /// A packet header or body runs past the end of the datagram.
    #[error("CIGI {packet} (ID {packet_id}) at offset {offset}: needs {size} bytes, only {available} remain")]
    Truncated {
        /// Packet name ("packet header" when the header itself is cut).
        packet: &'static str,
        /// Packet ID (0 when the header is cut).
        packet_id: u16,
        /// Byte offset of the packet.
        offset: usize,
        /// Declared size.
        size: usize,
        /// Bytes left in the datagram from `offset`.
        available: usize,
    },
    /// A declared packet size smaller than the packet header.
    #[error("CIGI packet ID {packet_id} at offset {offset}: declared size {size} is smaller than its header")]
    InvalidSize {
        /// Packet ID.
        packet_id: u16,
        /// Byte offset of the packet.
        offset: usize,
        /// Declared size.
        size: usize,
    },
    /// A typed packet shorter than its layout.
    #[error("CIGI {packet} at offset {offset}: declared size {size} is smaller than the {needed} bytes of its layout")]
    PacketTooShort {
        /// Packet name.
        packet: &'static str,
        /// Byte offset of the packet.
        offset: usize,
        /// Declared size.
        size: usize,
        /// Size of the layout.
        needed: usize,
    },
    /// Encoding: the packet type does not exist in the message's version.
    #[error("CIGI encode: {packet} does not exist in CIGI {version}")]
    NotInVersion {
        /// Packet name.
        packet: &'static str,
        /// Message version.
        version: Version,
    },
    /// Encoding: the first packet is not IG Control or Start of Frame.
    #[error("CIGI encode: a message must start with IgControl or StartOfFrame, not {packet}")]
    FirstPacket {
        /// Name of the first packet ("nothing" for an empty message).
        packet: &'static str,
    },
    /// Encoding: a field value the wire format cannot carry.
    #[error("CIGI encode: {packet} {field}: {reason}")]
    FieldOutOfRange {
        /// Packet name.
        packet: &'static str,
        /// Field name.
        field: &'static str,
        /// What is wrong.
        reason: String,
    },
}

/// Decoder of the fixed-size packets of one version: `None` for an ID not in
/// its table, `Some(Err(needed))` for a packet shorter than its layout.
type DecodeFixed = fn(u16, &[u8], ByteOrder) -> Option<Result<Packet, usize>>;

/// Wire facts of one major version.
struct Dialect {
    version_major: u8,
    header_bytes: usize,
    ig_message_id: u16,
    ig_message_header_bytes: usize,
    ig_message_id_offset: usize,
    user_first: u16,
    user_last: u16,
    decode_fixed: DecodeFixed,
    encode_fixed: fn(&Packet, ByteOrder, &mut Vec<u8>) -> bool,
    packet_name: fn(u16) -> Option<&'static str>,
    write_header: fn(&mut [u8], u16, usize, ByteOrder),
}

const DIALECT_3: Dialect = Dialect {
    version_major: 3,
    header_bytes: v3::HEADER_BYTES,
    ig_message_id: v3::IG_MESSAGE_ID,
    ig_message_header_bytes: v3::IG_MESSAGE_HEADER_BYTES,
    ig_message_id_offset: 2,
    user_first: v3::USER_DEFINED_FIRST,
    user_last: v3::USER_DEFINED_LAST,
    decode_fixed: v3::decode_fixed,
    encode_fixed: v3::encode_fixed,
    packet_name: v3::packet_name,
    write_header: v3::write_header,
};

const DIALECT_4: Dialect = Dialect {
    version_major: 4,
    header_bytes: v4::HEADER_BYTES,
    ig_message_id: v4::IG_MESSAGE_ID,
    ig_message_header_bytes: v4::IG_MESSAGE_HEADER_BYTES,
    ig_message_id_offset: 4,
    user_first: v4::USER_DEFINED_FIRST,
    user_last: v4::USER_DEFINED_LAST,
    decode_fixed: v4::decode_fixed,
    encode_fixed: v4::encode_fixed,
    packet_name: v4::packet_name,
    write_header: v4::write_header,
};

/// The 24-byte first packet of either version.
const FIRST_PACKET_BYTES: usize = 24;
const MAGIC: u16 = 0x8000;

fn byte(bytes: &[u8], i: usize) -> u8 {
    bytes.get(i).copied().unwrap_or(0)
}

/// Decodes one datagram.
///
/// # Errors
/// [`CigiError`] when the datagram is not a CIGI 3.x/4.0 message or a packet
/// header or body is cut short; see the variants.
pub fn decode_message(bytes: &[u8]) -> Result<Message, CigiError> {
    if bytes.is_empty() {
        return Err(CigiError::Empty);
    }
    let not_a_start = || CigiError::NotAMessageStart {
        first_bytes: bytes.iter().take(8).copied().collect(),
    };
    let first_size_be = u16::from_be_bytes([byte(bytes, 0), byte(bytes, 1)]);
    let first_size_le = u16::from_le_bytes([byte(bytes, 0), byte(bytes, 1)]);
    let first_id_bytes = [byte(bytes, 2), byte(bytes, 3)];
    let v4_start = (first_size_be == 24 || first_size_le == 24)
        && (first_id_bytes == [0, 0] || first_id_bytes == [0xff, 0xff]);
    let v3_start = matches!(byte(bytes, 0), 1 | 101) && byte(bytes, 1) == 24;
    if v4_start && !v3_start {
        if byte(bytes, 4) != 4 {
            return Err(if byte(bytes, 4) == 0 || bytes.len() < 5 {
                not_a_start()
            } else {
                CigiError::UnsupportedVersion {
                    version: Version {
                        major: byte(bytes, 4),
                        minor: byte(bytes, 7) >> 4,
                    },
                }
            });
        }
        if bytes.len() < FIRST_PACKET_BYTES {
            return Err(CigiError::Truncated {
                packet: if first_id_bytes == [0, 0] {
                    "IgControl"
                } else {
                    "StartOfFrame"
                },
                packet_id: u16::from_be_bytes(first_id_bytes),
                offset: 0,
                size: FIRST_PACKET_BYTES,
                available: bytes.len(),
            });
        }
        let order = if first_size_be == 24 {
            ByteOrder::BigEndian
        } else {
            ByteOrder::LittleEndian
        };
        let version = Version {
            major: 4,
            minor: byte(bytes, 7) >> 4,
        };
        return walk(bytes, &DIALECT_4, version, order);
    }
    if !v3_start {
        return Err(not_a_start());
    }
    let is_sof = byte(bytes, 0) == 101;
    if bytes.len() < FIRST_PACKET_BYTES {
        return Err(CigiError::Truncated {
            packet: if is_sof { "StartOfFrame" } else { "IgControl" },
            packet_id: u16::from(byte(bytes, 0)),
            offset: 0,
            size: FIRST_PACKET_BYTES,
            available: bytes.len(),
        });
    }
    let minor = if is_sof {
        byte(bytes, 5)
    } else {
        byte(bytes, 4)
    } >> 4;
    let version = Version {
        major: byte(bytes, 2),
        minor,
    };
    if version.major != 3 {
        return Err(CigiError::UnsupportedVersion { version });
    }
    let magic = u16::from_be_bytes([byte(bytes, 6), byte(bytes, 7)]);
    let order = match magic {
        MAGIC => ByteOrder::BigEndian,
        0x0080 => ByteOrder::LittleEndian,
        found => return Err(CigiError::BadMagic { found }),
    };
    let mut message = walk(bytes, &DIALECT_3, version, order)?;
    if minor != 3 {
        message.warnings.insert(
            0,
            DecodeWarning {
                offset: 0,
                packet_id: u16::from(byte(bytes, 0)),
                size: FIRST_PACKET_BYTES,
                reason: "CIGI 3 minor version is not 3; decoded with the 3.3 layouts",
            },
        );
    }
    Ok(message)
}

fn walk(
    bytes: &[u8],
    dialect: &Dialect,
    version: Version,
    order: ByteOrder,
) -> Result<Message, CigiError> {
    let mut message = Message::new(version, order, Vec::new());
    let mut offset = 0usize;
    while offset < bytes.len() {
        let rest = bytes.get(offset..).unwrap_or_default();
        if rest.len() < dialect.header_bytes {
            return Err(CigiError::Truncated {
                packet: "packet header",
                packet_id: 0,
                offset,
                size: dialect.header_bytes,
                available: rest.len(),
            });
        }
        let (id, size) = if dialect.version_major == 3 {
            (u16::from(byte(rest, 0)), usize::from(byte(rest, 1)))
        } else {
            let mut reader = Reader::new(rest, order);
            let (mut size, mut id) = (0u16, 0u16);
            reader.u16(0, &mut size);
            reader.u16(2, &mut id);
            (id, usize::from(size))
        };
        let name = (dialect.packet_name)(id).unwrap_or(if id == dialect.ig_message_id {
            "ImageGeneratorMessage"
        } else {
            "unknown packet"
        });
        if size < dialect.header_bytes {
            return Err(CigiError::InvalidSize {
                packet_id: id,
                offset,
                size,
            });
        }
        let Some(packet_bytes) = rest.get(..size) else {
            return Err(CigiError::Truncated {
                packet: name,
                packet_id: id,
                offset,
                size,
                available: rest.len(),
            });
        };
        if id == dialect.ig_message_id {
            message
                .packets
                .push(decode_ig_message(packet_bytes, dialect, order, offset)?);
        } else if (dialect.user_first..=dialect.user_last).contains(&id) {
            message.packets.push(Packet::UserDefined(UserDefined {
                packet_id: id,
                data: packet_bytes
                    .get(dialect.header_bytes..)
                    .unwrap_or_default()
                    .to_vec(),
            }));
        } else {
            match (dialect.decode_fixed)(id, packet_bytes, order) {
                Some(Ok(packet)) => message.packets.push(packet),
                Some(Err(needed)) => {
                    return Err(CigiError::PacketTooShort {
                        packet: name,
                        offset,
                        size,
                        needed,
                    })
                }
                None => message.warnings.push(DecodeWarning {
                    offset,
                    packet_id: id,
                    size,
                    reason: "packet ID not supported by this codec; skipped",
                }),
            }
        }
        offset += size;
    }
    Ok(message)
}

fn decode_ig_message(
    packet_bytes: &[u8],
    dialect: &Dialect,
    order: ByteOrder,
    offset: usize,
) -> Result<Packet, CigiError> {
    if packet_bytes.len() < dialect.ig_message_header_bytes {
        return Err(CigiError::PacketTooShort {
            packet: "ImageGeneratorMessage",
            offset,
            size: packet_bytes.len(),
            needed: dialect.ig_message_header_bytes,
        });
    }
    let mut message_id = 0u16;
    Reader::new(packet_bytes, order).u16(dialect.ig_message_id_offset, &mut message_id);
    let text_bytes = packet_bytes
        .get(dialect.ig_message_header_bytes..)
        .unwrap_or_default();
    let end = text_bytes
        .iter()
        .position(|&b| b == 0)
        .unwrap_or(text_bytes.len());
    let text = String::from_utf8_lossy(text_bytes.get(..end).unwrap_or_default()).into_owned();
    Ok(Packet::ImageGeneratorMessage(ImageGeneratorMessage {
        message_id,
        text,
    }))
}

/// Appends the encoded `message` to `out`.
///
/// # Errors
/// [`CigiError::FirstPacket`] when the message does not start with IG Control
/// or Start of Frame, [`CigiError::NotInVersion`] for a packet type the
/// version lacks, [`CigiError::FieldOutOfRange`] for text or user data the
/// wire format cannot carry, [`CigiError::UnsupportedVersion`] for a major
/// version other than 3 or 4. On error `out` is left as it was.
pub fn encode_message(message: &Message, out: &mut Vec<u8>) -> Result<(), CigiError> {
    let dialect = match message.version.major {
        3 => &DIALECT_3,
        4 => &DIALECT_4,
        _ => {
            return Err(CigiError::UnsupportedVersion {
                version: message.version,
            })
        }
    };
    match message.packets.first() {
        Some(Packet::IgControl(_) | Packet::StartOfFrame(_)) => {}
        Some(other) => {
            return Err(CigiError::FirstPacket {
                packet: other.name(),
            })
        }
        None => return Err(CigiError::FirstPacket { packet: "nothing" }),
    }
    let start = out.len();
    let result = message
        .packets
        .iter()
        .try_for_each(|packet| encode_packet(packet, message, dialect, out));
    if result.is_err() {
        out.truncate(start);
    }
    result
}

fn encode_packet(
    packet: &Packet,
    message: &Message,
    dialect: &Dialect,
    out: &mut Vec<u8>,
) -> Result<(), CigiError> {
    let order = message.byte_order;
    let start = out.len();
    match packet {
        Packet::ImageGeneratorMessage(m) => {
            if m.text.len() > MAX_IG_MESSAGE_TEXT_BYTES || m.text.bytes().any(|b| b == 0) {
                return Err(CigiError::FieldOutOfRange {
                    packet: "ImageGeneratorMessage",
                    field: "text",
                    reason: format!(
                        "{} bytes; at most {MAX_IG_MESSAGE_TEXT_BYTES} bytes without NUL",
                        m.text.len()
                    ),
                });
            }
            let size = (dialect.ig_message_header_bytes + m.text.len() + 1).div_ceil(8) * 8;
            out.resize(start + size, 0);
            if let Some(bytes) = out.get_mut(start..) {
                (dialect.write_header)(bytes, dialect.ig_message_id, size, order);
                let mut message_id = m.message_id;
                Writer::new(bytes, order).u16(dialect.ig_message_id_offset, &mut message_id);
                if let Some(text) = bytes.get_mut(
                    dialect.ig_message_header_bytes..dialect.ig_message_header_bytes + m.text.len(),
                ) {
                    text.copy_from_slice(m.text.as_bytes());
                }
            }
            Ok(())
        }
        Packet::UserDefined(u) => {
            let size = dialect.header_bytes + u.data.len();
            let max = if dialect.version_major == 3 {
                255
            } else {
                65535
            };
            if !(dialect.user_first..=dialect.user_last).contains(&u.packet_id) {
                return Err(CigiError::FieldOutOfRange {
                    packet: "UserDefined",
                    field: "packet_id",
                    reason: format!(
                        "{} is outside the user-defined range {}..={}",
                        u.packet_id, dialect.user_first, dialect.user_last
                    ),
                });
            }
            if size > max || !size.is_multiple_of(8) {
                return Err(CigiError::FieldOutOfRange {
                    packet: "UserDefined",
                    field: "data",
                    reason: format!(
                        "packet would be {size} bytes; it must be a multiple of 8 and at most {max}"
                    ),
                });
            }
            out.resize(start + dialect.header_bytes, 0);
            if let Some(bytes) = out.get_mut(start..) {
                (dialect.write_header)(bytes, u.packet_id, size, order);
            }
            out.extend_from_slice(&u.data);
            Ok(())
        }
        other => {
            if !(dialect.encode_fixed)(other, order, out) {
                return Err(CigiError::NotInVersion {
                    packet: other.name(),
                    version: message.version,
                });
            }
            if let Some(bytes) = out.get_mut(start..) {
                write_version_fields(other, bytes, message.version, order);
            }
            Ok(())
        }
    }
}

/// Major/minor version and, in 3.x, the byte-swap magic number of IG Control
/// and Start of Frame.
fn write_version_fields(packet: &Packet, bytes: &mut [u8], version: Version, order: ByteOrder) {
    let is_sof = match packet {
        Packet::IgControl(_) => false,
        Packet::StartOfFrame(_) => true,
        _ => return,
    };
    let mut w = Writer::new(bytes, order);
    let mut major = version.major;
    let mut minor = version.minor;
    if version.major == 3 {
        w.u8(2, &mut major);
        w.bits(if is_sof { 5 } else { 4 }, 4, 4, &mut minor);
        let mut magic = MAGIC;
        w.u16(6, &mut magic);
    } else {
        w.u8(4, &mut major);
        w.bits(7, 4, 4, &mut minor);
    }
}
