//! Fitting the body shape to the sketch (paper §II-C): the SIR of eqs. 5–9 and match scores.

pub mod bone_estimate;
pub mod calibration;
pub mod gender_evidence;
pub mod height_calibration;
pub mod parts;
pub mod proportions;
mod score;
mod sir;
mod transition;

pub use bone_estimate::{estimate_proportions, EstimateOptions, ProportionEstimate};
pub use calibration::{FitCalibration, ShapeCalibration, CALIBRATED_DIMS};
pub use gender_evidence::{
    gender_evidence, gender_features, GenderClassifier, GenderEvidence, GenderFeatures, MarginCombination,
};
pub use height_calibration::{HeightCalibration, HeightEvidence, HEIGHT_EVIDENCE_NAMES, NUM_HEIGHT_EVIDENCE};
pub use parts::{BodyPart, PartSupport};
pub use score::{distance_transform, MatchScore, SketchEvidence, CHAMFER_CAP};
pub use sir::{
    fit_shape, score_shapes, FitOptions, FitProblem, FitResult, FitView, IterationStats, EDGE_SUPPORT_RADIUS,
    LOW_EVIDENCE_SUPPORT, PRIOR_RANGE_SD,
};
pub use transition::Transition;
