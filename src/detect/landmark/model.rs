//! The BlazePose landmark network run by tract-onnx: loading (the embedded asset or bytes of a
//! converted ONNX file), checking its interface, and one inference on a 256×256 crop.

use std::sync::{Arc, OnceLock};

use tract_onnx::prelude::*;

use super::crop::INPUT_SIDE;
use crate::error::{Error, Result};

/// Landmarks the network outputs: the 33 pose landmarks and 6 auxiliary ones (33 = hips' midpoint
/// and 34 = scale point are the ROI alignment points).
pub const NUM_OUTPUT_LANDMARKS: usize = 39;
/// Values per output landmark: x, y (px of the 256² crop), z, visibility logit, presence logit.
pub const LANDMARK_VALUES: usize = 5;

/// MediaPipe's `pose_landmark_full` converted to ONNX (`scripts/convert-blazepose.sh`;
/// provenance and licence in `assets/pose_landmark_full.LICENSE`).
pub static EMBEDDED_ONNX: &[u8] = include_bytes!("../../../assets/pose_landmark_full.onnx");

/// The raw output of one inference.
#[derive(Clone, Debug, PartialEq)]
pub struct RawOutput {
    /// 39 × 5 values (see [`LANDMARK_VALUES`]), crop px for x and y.
    pub landmarks: Vec<[f32; LANDMARK_VALUES]>,
    /// The pose-presence flag in [0, 1] (the network's own sigmoid output).
    pub pose_flag: f32,
}

/// A loaded, optimised landmark network (cheap to share: clones share the plan).
#[derive(Clone)]
pub struct LandmarkNet {
    plan: Arc<TypedRunnableModel>,
}

impl std::fmt::Debug for LandmarkNet {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("LandmarkNet")
    }
}

fn corrupt(e: impl std::fmt::Display) -> Error {
    Error::CorruptData(format!("BlazePose landmark model: {e}"))
}

impl LandmarkNet {
    /// Parses and optimises an ONNX landmark model from its bytes. Errors: `CorruptData` when
    /// the bytes are not ONNX, or the model lacks a 1×256×256×3 input, a 195-value landmark output
    /// or a 1-value pose flag.
    pub fn from_onnx(bytes: &[u8]) -> Result<Self> {
        let shape = [1, INPUT_SIDE, INPUT_SIDE, 3];
        let model = tract_onnx::onnx()
            .model_for_read(&mut &*bytes)
            .map_err(corrupt)?
            .with_input_fact(0, f32::fact(shape).into())
            .map_err(corrupt)?;
        let mut typed = model.into_typed().map_err(corrupt)?;
        let outlets = typed.output_outlets().map_err(corrupt)?.to_vec();
        let size = |o: &OutletId| -> Option<usize> {
            typed.outlet_fact(*o).ok()?.shape.as_concrete().map(|s| s.iter().product())
        };
        let find = |n: usize| outlets.iter().find(|o| size(o) == Some(n)).copied();
        let (Some(lm), Some(flag)) = (find(NUM_OUTPUT_LANDMARKS * LANDMARK_VALUES), find(1)) else {
            return Err(corrupt("no 195-value landmark output or 1-value pose flag output"));
        };
        typed.select_output_outlets(&[lm, flag]).map_err(corrupt)?;
        let plan = typed.into_optimized().map_err(corrupt)?.into_runnable().map_err(corrupt)?;
        Ok(Self { plan })
    }

    /// The embedded model, parsed once per process (later calls clone the shared plan).
    pub fn embedded() -> Result<Self> {
        static NET: OnceLock<std::result::Result<LandmarkNet, String>> = OnceLock::new();
        NET.get_or_init(|| Self::from_onnx(EMBEDDED_ONNX).map_err(|e| e.to_string()))
            .clone()
            .map_err(Error::CorruptData)
    }

    /// Runs the network on a 256×256×3 HWC tensor in [0, 1] ([`super::crop::crop_tensor`]).
    /// Errors: `OutOfRange` for a wrong tensor length, `CorruptData` if inference fails.
    pub fn run(&self, tensor: Vec<f32>) -> Result<RawOutput> {
        let want = INPUT_SIDE * INPUT_SIDE * 3;
        if tensor.len() != want {
            return Err(Error::OutOfRange { name: "tensor", detail: format!("{} values, need {want}", tensor.len()) });
        }
        let input = Tensor::from_shape(&[1, INPUT_SIDE, INPUT_SIDE, 3], &tensor).map_err(corrupt)?;
        let out = self.plan.run(tvec!(input.into())).map_err(corrupt)?;
        let lm = out[0].to_plain_array_view::<f32>().map_err(corrupt)?;
        let flag = out[1].to_plain_array_view::<f32>().map_err(corrupt)?;
        let lm: Vec<f32> = lm.iter().copied().collect();
        if lm.len() != NUM_OUTPUT_LANDMARKS * LANDMARK_VALUES || flag.is_empty() {
            return Err(corrupt(format!("outputs of {} and {} values", lm.len(), flag.len())));
        }
        let landmarks = lm.chunks_exact(LANDMARK_VALUES).map(|c| [c[0], c[1], c[2], c[3], c[4]]).collect();
        Ok(RawOutput { landmarks, pose_flag: flag.iter().next().copied().unwrap_or(0.0) })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn corrupt_and_truncated_models_are_errors() {
        assert!(matches!(LandmarkNet::from_onnx(b"not an onnx file"), Err(Error::CorruptData(_))));
        let half = &EMBEDDED_ONNX[..EMBEDDED_ONNX.len() / 2];
        assert!(matches!(LandmarkNet::from_onnx(half), Err(Error::CorruptData(_))));
        let net = LandmarkNet::embedded().unwrap();
        assert!(matches!(net.run(vec![0.5; 10]), Err(Error::OutOfRange { .. })));
        let out = net.run(vec![1.0; INPUT_SIDE * INPUT_SIDE * 3]).unwrap();
        assert_eq!(out.landmarks.len(), NUM_OUTPUT_LANDMARKS);
        assert!((0.0..=1.0).contains(&out.pose_flag));
    }
}
