//! Export: Wavefront OBJ and binary glTF 2.0 (.glb) with skeleton, skin and poses. Every file
//! is written atomically (temporary file, then rename).

pub mod gltf;
pub mod joints;
pub mod joints2d;
pub mod obj;
pub mod pose3d;
pub mod texture;
