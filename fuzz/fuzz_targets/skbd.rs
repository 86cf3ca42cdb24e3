//! `.skbd` detector model parsing, as given and with the header's payload length and CRC-32
//! recomputed (so mutations reach the payload parser and the model validation). A model that
//! parses must re-encode to the same bytes.
#![no_main]

use libfuzzer_sys::fuzz_target;
use sketchbody::detect::Model;

/// Header: magic (8), version (4), payload length (8), payload CRC-32 (4).
const HEADER_LEN: usize = 24;

fuzz_target!(|data: &[u8]| {
    let _ = Model::from_bytes(data);
    if data.len() >= HEADER_LEN {
        let mut fixed = data.to_vec();
        let payload_len = (fixed.len() - HEADER_LEN) as u64;
        let crc = crc32fast::hash(&fixed[HEADER_LEN..]);
        fixed[12..20].copy_from_slice(&payload_len.to_le_bytes());
        fixed[20..24].copy_from_slice(&crc.to_le_bytes());
        if let Ok(m) = Model::from_bytes(&fixed) {
            assert_eq!(m.to_bytes(), fixed, "a parsed detector re-encodes to the same bytes");
        }
    }
});
