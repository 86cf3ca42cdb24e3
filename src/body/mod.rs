//! The body (paper §II-C): the shape model (a PCA shape space per gender over MakeHuman's body
//! mesh, and a both-sexes space with gender as a continuous weight built from them at load time, a GMM prior over the PCA weights, the canonical joints as linear functions of the shape,
//! skin weights to the 14 canonical bones), rigged-mesh data, procedural test bodies, inverse
//! kinematics and skinning. [`BodyModel::embedded`] decodes the model compiled into the library;
//! `build` makes it from the MakeHuman data (`sketchbody-lab build-model`).

mod blend;
#[cfg(feature = "model-builder")]
pub mod build;
pub mod decimate;
mod format;
mod gender;
mod gmm;
pub mod ik;
mod model;
pub mod procedural;
pub mod proportions;
mod proxy;
pub mod retarget;
pub mod rig;
pub mod skin;

pub use blend::{BlendedSpace, BLEND_COMPONENTS, BLEND_DEFAULT_DIM, GENDER_LEVELS, LEVEL_WEIGHTS};
/// A tiny valid body model (4 vertices) for crate-level tests (the fuzz seeds).
#[cfg(test)]
pub(crate) use format::tests::tiny_model as tiny_test_model;
pub use format::{SKBM_MAGIC, SKBM_VERSION};
pub use gender::Gender;
pub use gmm::Gmm;
pub use model::{BodyModel, RestShape, ShapeChoice, ShapeSpace, VertexWeights, MAX_INFLUENCES};
pub use proxy::{FitProxy, ProxySpace, PROXY_VERTICES};

/// The committed model asset (`assets/body_model.skbm`, rebuilt by `sketchbody-lab build-model`).
pub(crate) static EMBEDDED_MODEL: &[u8] = include_bytes!("../../assets/body_model.skbm");
