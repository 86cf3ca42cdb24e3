//! Joints JSON: the 2-D `sketchbody-joints2d` files (`run --joints`, `pose`, the C API's and the
//! Python package's reader) and the 3-D joints files, from the same bytes. Parsed joints must be
//! complete; 2-D joints that are finite must round-trip through the writer's document.
#![no_main]

use libfuzzer_sys::fuzz_target;
use sketchbody::export::{joints, joints2d};

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else { return };
    let _ = joints::parse_joints3_json(text);
    if let Ok(j) = joints2d::parse_joints2d_text(text) {
        if let Ok(doc) = joints2d::joints2d_json(&j) {
            let back = joints2d::parse_joints2d_text(&doc.to_string()).expect("a written document parses");
            assert_eq!(back.visible, j.visible);
            assert_eq!(back.xy, j.xy);
        }
    }
});
