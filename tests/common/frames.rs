//! The FBX and USD tests' export frames: every unit and up axis, and where docs/formats.md says
//! a model-frame point lands in each, written out here rather than through the library's
//! conversion (`export::frame`).
#![allow(dead_code)]

use nalgebra::Vector3;
use sketchbody::export::frame::{ExportFrame, Units, UpAxis};

/// Every unit and up axis: m Y, cm Y, m Z, cm Z.
pub const FRAMES: [ExportFrame; 4] = [
    ExportFrame { units: Units::Metres, up: UpAxis::Y },
    ExportFrame { units: Units::Centimetres, up: UpAxis::Y },
    ExportFrame { units: Units::Metres, up: UpAxis::Z },
    ExportFrame { units: Units::Centimetres, up: UpAxis::Z },
];

/// A model-frame point (metres, Y up, facing +Z) in `frame`: Z up is (x, -z, y); centimetres
/// are 100 per metre.
pub fn in_frame(frame: &ExportFrame, p: [f32; 3]) -> Vector3<f64> {
    let (x, y, z) = (p[0] as f64, p[1] as f64, p[2] as f64);
    let turned = match frame.up {
        UpAxis::Y => Vector3::new(x, y, z),
        UpAxis::Z => Vector3::new(x, -z, y),
    };
    turned * metres_to_unit(frame)
}

/// File units per metre in `frame`: 1 or 100.
pub fn metres_to_unit(frame: &ExportFrame) -> f64 {
    if frame.units == Units::Centimetres {
        100.0
    } else {
        1.0
    }
}
