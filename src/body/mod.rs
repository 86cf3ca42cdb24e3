//! The body: rigged mesh data, procedural test bodies, inverse kinematics and skinning.

pub mod ik;
pub mod procedural;
pub mod rig;
pub mod skin;
