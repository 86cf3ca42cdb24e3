//! The body: the shape model (paper §II-C: a PCA shape space per gender over MakeHuman's body
//! mesh, a GMM prior over the PCA weights, the canonical joints as linear functions of the shape,
//! skin weights to the 14 canonical bones; [`BodyModel::embedded`] decodes the copy compiled into
//! the library; `build` makes it from the MakeHuman data, `sketchbody build-model`), rigged mesh
//! data, procedural test bodies, inverse kinematics and skinning.

pub mod build;
mod format;
mod gender;
mod gmm;
pub mod ik;
mod model;
pub mod procedural;
pub mod rig;
pub mod skin;

pub use format::{SKBM_MAGIC, SKBM_VERSION};
pub use gender::Gender;
pub use gmm::Gmm;
pub use model::{BodyModel, RestShape, ShapeSpace, VertexWeights, MAX_INFLUENCES};

/// The committed model asset (`assets/body_model.skbm`, rebuilt by `sketchbody build-model`).
pub(crate) static EMBEDDED_MODEL: &[u8] = include_bytes!("../../assets/body_model.skbm");
