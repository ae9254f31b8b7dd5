//! DIS datagram decoder on arbitrary bytes: errors are fine, panics are bugs. Every PDU that
//! decodes is also re-encoded (when it has a body) and decoded again.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    for pdu in cig_dis::decode_datagram(data).into_iter().flatten() {
        let header = cig_dis::EncodeHeader {
            version: pdu.header.version,
            exercise_id: pdu.header.exercise_id,
            timestamp: pdu.header.timestamp,
        };
        if let Ok(bytes) = cig_dis::encode_pdu(header, &pdu.message) {
            let _ = cig_dis::decode_pdu(&bytes);
        }
    }
});
