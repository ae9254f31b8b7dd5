//! CIGI (Common Image Generator Interface, SISO-STD-013) codec for the image
//! generator side: typed packets of CIGI 3.3 and 4.0, decoded from and
//! encoded to datagrams in either byte order. Pure: no sockets, files or
//! terminal.
//!
//! Algorithm (SISO-STD-013 ICD 3.3 sections 3-4 and ICD 4.0): a CIGI message
//! is one datagram holding a sequence of packets, each starting with its ID
//! and its size in bytes, so a receiver can step over packets it does not
//! know. The first packet is IG Control (host to IG) or Start of Frame (IG to
//! host); it carries the major/minor version and tells the byte order:
//!
//! - CIGI 3.x: packet header is an 8-bit ID and an 8-bit size. The first
//!   packet carries the Byte Swap Magic Number 0x8000 in the sender's byte
//!   order at bytes 6-7; reading 0x0080 means the sender's order is the
//!   other one (ICD 3.3 section 4.1.1 and 4.2.1).
//! - CIGI 4.0: packet header is a 16-bit size followed by a 16-bit ID, both
//!   in the sender's order. IG Control and Start of Frame are 24 bytes long,
//!   so the byte order is read off the first size field (the approach of the
//!   CIGI Class Library 4.0.2).
//!
//! The decoder returns a [`Message`] (version, byte order, typed [`Packet`]s
//! and [`DecodeWarning`]s for packets it skipped); the encoder writes a
//! [`Message`] in its version and byte order. Per-packet layouts live in
//! `v3` and `v4`; `docs/cigi-conformance.md` lists what is supported how far.
//!
//! ```
//! use cig_cigi::{decode_message, encode_message, ByteOrder, HatHotRequest, IgControl, Message, Packet, Version};
//!
//! let message = Message::new(
//!     Version::V3_3,
//!     ByteOrder::LittleEndian,
//!     vec![
//!         Packet::IgControl(IgControl { ig_mode: 1, host_frame_number: 7, ..IgControl::default() }),
//!         Packet::HatHotRequest(HatHotRequest {
//!             hat_hot_id: 1,
//!             lat_deg_or_x_m: 51.0,
//!             lon_deg_or_y_m: -1.0,
//!             ..HatHotRequest::default()
//!         }),
//!     ],
//! );
//! let mut datagram = Vec::new();
//! encode_message(&message, &mut datagram)?;
//! let decoded = decode_message(&datagram)?;
//! assert_eq!(decoded.byte_order, ByteOrder::LittleEndian);
//! assert_eq!(decoded.packets, message.packets);
//! # Ok::<(), cig_cigi::CigiError>(())
//! ```
//!
//! Limits: 3.x messages whose minor version is not 3 are decoded with the 3.3
//! layouts and a warning (3.0-3.2 differ in a few packets). Standard packets
//! this codec does not type (motion tracker, earth reference model,
//! trajectory/acceleration, symbology) are skipped with a warning, like unknown IDs. User-defined packets pass
//! through as raw bytes in the sender's byte order.

macro_rules! codec_table {
    (header = $header:path; $( $variant:ident => $id:literal, $size:literal, $layout:ident; )*) => {
        /// Decodes a fixed-size packet. `None`: the ID is not in this table;
        /// `Some(Err(n))`: the packet is shorter than the `n` bytes its layout
        /// needs.
        pub(crate) fn decode_fixed(
            id: u16,
            bytes: &[u8],
            order: ByteOrder,
        ) -> Option<Result<crate::Packet, usize>> {
            match id {
                $( $id => Some(if bytes.len() < $size {
                    Err($size)
                } else {
                    let mut packet = $variant::default();
                    $layout(&mut crate::wire::Reader::new(bytes, order), &mut packet);
                    Ok(crate::Packet::$variant(packet))
                }), )*
                _ => None,
            }
        }

        /// Appends a fixed-size packet; `false` when the packet type does not
        /// exist in this version.
        pub(crate) fn encode_fixed(
            packet: &crate::Packet,
            order: ByteOrder,
            out: &mut Vec<u8>,
        ) -> bool {
            match packet {
                $( crate::Packet::$variant(fields) => {
                    let start = out.len();
                    out.resize(start + $size, 0);
                    if let Some(bytes) = out.get_mut(start..) {
                        $header(bytes, $id, $size, order);
                        let mut copy = fields.clone();
                        $layout(&mut crate::wire::Writer::new(bytes, order), &mut copy);
                    }
                    true
                } )*
                _ => false,
            }
        }

        /// Name of a fixed-size packet ID of this version.
        pub(crate) fn packet_name(id: u16) -> Option<&'static str> {
            match id {
                $( $id => Some(stringify!($variant)), )*
                _ => None,
            }
        }

        /// (ID, size) of a fixed-size packet in this version.
        #[allow(dead_code, reason = "used by tests and the conformance table")]
        pub(crate) fn id_and_size(packet: &crate::Packet) -> Option<(u16, usize)> {
            match packet {
                $( crate::Packet::$variant(_) => Some(($id, $size)), )*
                _ => None,
            }
        }
    };
}

mod message;
pub mod packets;
#[doc(hidden)]
pub mod sample;
mod v3;
mod v4;
mod wire;

pub use message::{
    decode_message, encode_message, CigiError, DecodeWarning, Message, Packet, Version,
    MAX_IG_MESSAGE_TEXT_BYTES,
};
pub use packets::*;
pub use wire::ByteOrder;

#[cfg(test)]
mod tests;
