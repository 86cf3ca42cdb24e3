//! The default detector compiled into the library: `assets/detector.skbd`, trained on synthetic
//! concept sketches by `sketchbody-lab train-detector` (command, seed and time in `assets/README.md`).

use super::model::Model;
use crate::error::Result;

/// The bytes of the embedded `.skbd` model.
pub(crate) static EMBEDDED_DETECTOR: &[u8] = include_bytes!("../../assets/detector.skbd");

impl Model {
    /// Decodes the embedded default detector (a fresh copy; decode once and share it — the model
    /// is immutable, `Send + Sync`). Errors: `CorruptData` if the embedded bytes are damaged.
    pub fn embedded() -> Result<Model> {
        Model::from_bytes(EMBEDDED_DETECTOR)
    }
}
