//! `.skbpd` pose dictionary parsing, as given and with the trailing FNV-1a checksum recomputed
//! (so mutations reach the payload). A dictionary that parses must serialise back to the input.
#![no_main]

use libfuzzer_sys::fuzz_target;
use sketchbody::pose::dict_io;

fuzz_target!(|data: &[u8]| {
    let _ = dict_io::from_bytes(data);
    if data.len() > 16 {
        let mut fixed = data.to_vec();
        let n = fixed.len();
        let sum = dict_io::fnv1a64(&fixed[..n - 8]);
        fixed[n - 8..].copy_from_slice(&sum.to_le_bytes());
        if let Ok(d) = dict_io::from_bytes(&fixed) {
            assert_eq!(dict_io::to_bytes(&d), fixed, "a parsed dictionary re-encodes to the same bytes");
        }
    }
});
