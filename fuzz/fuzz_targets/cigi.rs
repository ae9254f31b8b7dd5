//! CIGI decoder: the first byte picks whether the input is decoded as it is or behind a valid
//! first packet (3.3 or 4.0, either byte order) so the fuzzer reaches the packet walk at once.
//! Whatever decodes must re-encode to bytes that decode and re-encode to the same bytes.
#![no_main]

use cig_cigi::{decode_message, encode_message, ByteOrder, IgControl, Message, Packet, Version};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Some((&selector, rest)) = data.split_first() else {
        return;
    };
    let mut input = Vec::new();
    if selector & 0x80 != 0 {
        let version = if selector & 1 == 0 {
            Version::V3_3
        } else {
            Version::V4_0
        };
        let order = if selector & 2 == 0 {
            ByteOrder::BigEndian
        } else {
            ByteOrder::LittleEndian
        };
        let first = Message::new(
            version,
            order,
            vec![Packet::IgControl(IgControl::default())],
        );
        if encode_message(&first, &mut input).is_err() {
            return;
        }
    }
    input.extend_from_slice(rest);
    let Ok(message) = decode_message(&input) else {
        return;
    };
    let mut once = Vec::new();
    if encode_message(&message, &mut once).is_err() {
        // Text or user data the encoder refuses (too long, not a multiple of 8 bytes).
        return;
    }
    let again = decode_message(&once).expect("re-encoded message decodes");
    let mut twice = Vec::new();
    encode_message(&again, &mut twice).expect("re-encoded message encodes");
    assert_eq!(once, twice);
});
