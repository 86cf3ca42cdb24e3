//! The rig, in one home: a rigged mesh in plain arrays ([`RiggedMesh`], posing and skinning's
//! input) and the production rig (issue 17): MakeHuman's `game_engine` skeleton (53 bones: root at the
//! floor, pelvis, a three-bone spine, neck, head, clavicles, arms, hands with fingers, legs,
//! feet and toes) and its skin weights, fitted to each body and driven by the 15 canonical
//! joints; names in three conventions; A- or T-pose rest; origin at the floor or the pelvis.
//!
//! - [`mesh`]: the rigged mesh and its geometry helpers (heights, normals, triangles).
//! - [`bones`]: the bone table (names, parents, drivers).
//! - [`data`]: what the body model stores ([`RigData`]).
//! - [`armature`]: one body's rest armature and poses.
//! - [`ik_targets`]: the optional IK target bones at the hands and feet.
//! - [`shape_keys`]: the fitted body's shape dimensions as shape keys.
//! - [`twist`]: the twist bones an export may add (upper arms, forearms, thighs).
//! - [`scene`]: everything an export writes (rest mesh, armature, pose) for the chosen options.

pub mod armature;
pub mod bones;
pub mod data;
pub mod ik_targets;
pub mod mesh;
pub mod scene;
pub mod shape_keys;
pub mod twist;

pub use armature::{Armature, RigPose};
pub use bones::{RigBone, NUM_RIG_BONES, RIG_BONES};
pub use data::{PointRegressor, RigData};
pub use mesh::{quads_to_triangles, scale_to_height, vertex_normals, y_extent, FaceUvs, RiggedMesh, VertexWeights};
pub use scene::{Clip, Naming, Placement, PoseAs, RestPose, RigOptions, RigScene};
