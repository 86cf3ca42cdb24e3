//! Export: Wavefront OBJ, binary glTF 2.0 (.glb) and binary FBX 7.4 with skeleton, skin and poses. Every file
//! is written atomically (temporary file, then rename).

pub mod fbx;
pub mod gltf;
pub mod joints;
pub mod joints2d;
pub mod obj;
pub mod pose3d;
pub mod rigged;
pub mod texture;
pub mod usd;
