//! The PARSE model JSON (the paper's detector, `Model::from_json`; also what
//! `skb_detector_new_from_file` and `Model::load_any` read when the file is not binary). A
//! model that parses must survive the binary round trip.
#![no_main]

use libfuzzer_sys::fuzz_target;
use sketchbody::detect::Model;

fuzz_target!(|data: &[u8]| {
    if let Ok(m) = Model::from_json(data) {
        let back = Model::from_bytes(&m.to_bytes()).expect("a validated model re-parses");
        assert_eq!(back, m);
    }
});
