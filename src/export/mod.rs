//! Export: Wavefront OBJ, binary glTF 2.0 (.glb), binary FBX 7.4 and UsdSkel .usda with
//! skeleton, skin and poses (FBX and USD in metres or centimetres, Y- or Z-up: [`frame`]).
//! Every file is written atomically (temporary file, then rename).

pub mod fbx;
pub mod frame;
pub mod gltf;
pub mod joints;
pub mod joints2d;
pub mod obj;
pub mod pose3d;
pub mod rigged;
pub mod texture;
pub mod usd;
