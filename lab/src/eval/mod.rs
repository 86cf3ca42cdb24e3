//! Evaluation (paper §III): scores a results folder against a synthetic-sketch dataset with AED
//! (eq. 10, rest and posed), MPJPE and PA-MPJPE (mm) and PCK@0.1/0.2. The results-folder layout
//! is in `docs/dataset.md`.

pub mod backends;
pub mod by_style;
pub mod detector;
pub mod facing;
pub mod metrics;
pub mod score;

pub use score::{load_estimate, score_dataset, score_sample, Estimate, SampleScore, Summary};
