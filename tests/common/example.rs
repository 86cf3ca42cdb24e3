//! The bundled example's inputs for the pipeline tests: the body model, the embedded pose
//! dictionary, the sketch and its 2-D joints.
#![allow(dead_code)]

use std::path::Path;

use sketchbody::body::BodyModel;
use sketchbody::export::joints2d::load_joints2d;
use sketchbody::image::{load_image, GrayImage};
use sketchbody::pose::dict_io;
use sketchbody::skeleton::Joints2;

/// The embedded body model and dictionary, `assets/examples/sketch.png` and its joints.
pub fn inputs() -> (BodyModel, sketchbody::pose::Dictionary, GrayImage, Joints2) {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    (
        BodyModel::embedded().unwrap(),
        dict_io::embedded().unwrap(),
        load_image(&root.join("assets/examples/sketch.png")).unwrap(),
        load_joints2d(&root.join("assets/examples/sketch_joints.json")).unwrap(),
    )
}
