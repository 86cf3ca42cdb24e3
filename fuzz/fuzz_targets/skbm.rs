//! `.skbm` body model parsing. Each input is parsed twice: as given, and with its trailing
//! CRC-32 recomputed, so mutations reach the payload parser and the model validation behind the
//! checksum. A model that parses must round-trip byte for byte.
#![no_main]

use libfuzzer_sys::fuzz_target;
use sketchbody::body::BodyModel;

fuzz_target!(|data: &[u8]| {
    let _ = BodyModel::from_bytes(data);
    if data.len() > 4 {
        let mut fixed = data.to_vec();
        let n = fixed.len();
        let crc = crc32fast::hash(&fixed[..n - 4]);
        fixed[n - 4..].copy_from_slice(&crc.to_le_bytes());
        if let Ok(model) = BodyModel::from_bytes(&fixed) {
            assert_eq!(model.to_bytes(), fixed, "a parsed model re-encodes to the same bytes");
        }
    }
});
