//! The default detector compiled into the library: `assets/detector.skbd`, trained on synthetic
//! concept sketches by `sketchbody train-detector` (command, seed and time in `assets/README.md`).

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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::detect::train::layout::{NUM_PARTS, PART_TO_JOINT};

    #[test]
    fn the_embedded_model_has_the_trained_layout() {
        let m = Model::embedded().unwrap();
        assert_eq!(m.parts.len(), NUM_PARTS);
        assert_eq!(m.part_to_joint, PART_TO_JOINT);
        assert_eq!((m.sbin, m.interval), (4, 10));
        assert!(m.thresh.is_finite());
    }
}
