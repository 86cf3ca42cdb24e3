//! Calibrated confidences for [`super::figure`]: small logistic models that turn each backend's
//! raw evidence (part or landmark confidences, the figure score or pose flag, the two backends'
//! agreement) into probabilities — that a joint is correct at PCK@0.2, and that the image holds
//! a figure at all. The coefficients are fitted by `sketchbody-lab calibrate-detector` on a
//! calibration set disjoint from every benchmark set (`docs/assets.md`, "Detector
//! calibration") and embedded from `assets/detector_calibration.json`.

use std::sync::OnceLock;

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};

/// The embedded calibration (`assets/detector_calibration.json`).
pub static EMBEDDED_CALIBRATION: &str = include_str!("../../assets/detector_calibration.json");

/// Coefficients of one logistic model: `p = σ(w · x)`, `x[0] = 1`.
pub type Coefficients = Vec<f64>;

/// Per-joint correctness models (inputs: [`joint_features`]).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct JointModels {
    /// The sketch model alone.
    pub fmp: Coefficients,
    /// BlazePose alone.
    pub blazepose: Coefficients,
    /// The sketch model's joints when both backends ran (adds the agreement features).
    pub fmp_auto: Coefficients,
    /// BlazePose's joints when both backends ran.
    pub blazepose_auto: Coefficients,
}

/// Figure-presence models (inputs: [`presence_features`]).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PresenceModels {
    /// From the sketch model's score alone.
    pub fmp: Coefficients,
    /// From BlazePose's pose flag alone.
    pub blazepose: Coefficients,
    /// From both and their agreement.
    pub auto: Coefficients,
}

/// A full calibration, as stored in `assets/detector_calibration.json`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Calibration {
    /// Format tag, `sketchbody-detector-calibration`.
    pub format: String,
    /// Format version, 1.
    pub version: u32,
    /// How the coefficients were made (command, sets, date).
    pub provenance: String,
    /// Joint correctness models.
    pub joints: JointModels,
    /// Presence models.
    pub presence: PresenceModels,
}

/// Features of the sketch model alone or BlazePose alone: 1, the joint's raw confidence as a
/// logit, the figure's score (the sketch model's score or BlazePose's pose flag).
pub const ALONE_FEATURES: usize = 3;
/// Features with both backends: those of [`ALONE_FEATURES`], then the distance between the two
/// backends' positions of this joint and the median of that distance over the joints, both as
/// fractions of the figure's size, capped at 1.
pub const AUTO_FEATURES: usize = 5;

/// A raw confidence in (0, 1) as a logit, clamped to ±8 so that saturated values stay finite.
pub fn logit(p: f64) -> f64 {
    let p = p.clamp(3.4e-4, 1.0 - 3.4e-4);
    (p / (1.0 - p)).ln()
}

/// The sketch model's raw score, clamped to [−5, 5] (scores far below the threshold carry no
/// more information, and unbounded inputs would dominate the logistic models).
pub fn clamp_score(s: f64) -> f64 {
    if s.is_nan() {
        -5.0
    } else {
        s.clamp(-5.0, 5.0)
    }
}

/// The features of one joint: `raw` confidence, figure `score` (see [`clamp_score`] for the
/// sketch model), and with both backends `agreement = Some((distance, median))` as fractions of
/// the figure size.
pub fn joint_features(raw: f64, score: f64, agreement: Option<(f64, f64)>) -> Vec<f64> {
    let mut x = vec![1.0, logit(raw), score];
    if let Some((d, m)) = agreement {
        x.push(d.clamp(0.0, 1.0));
        x.push(m.clamp(0.0, 1.0));
    }
    x
}

/// The features of figure presence: 1 and each available evidence (sketch score, pose flag,
/// median agreement), in the order of the model used.
pub fn presence_features(sketch_score: Option<f64>, pose_flag: Option<f64>, median_agreement: Option<f64>) -> Vec<f64> {
    let mut x = vec![1.0];
    x.extend(sketch_score.map(clamp_score));
    x.extend(pose_flag);
    x.extend(median_agreement.map(|m| m.clamp(0.0, 1.0)));
    x
}

/// w · x, the model's log-odds. Errors: `CorruptData` when the lengths differ (a calibration
/// for other features).
pub fn log_odds(w: &[f64], x: &[f64]) -> Result<f64> {
    if w.len() != x.len() {
        return Err(Error::CorruptData(format!(
            "calibration model of {} coefficients for {} features",
            w.len(),
            x.len()
        )));
    }
    Ok(w.iter().zip(x).map(|(a, b)| a * b).sum())
}

/// σ(w · x). Errors: as [`log_odds`].
pub fn predict(w: &[f64], x: &[f64]) -> Result<f64> {
    Ok(sigmoid(log_odds(w, x)?))
}

/// σ(z) = 1 / (1 + e^(−z)).
pub fn sigmoid(z: f64) -> f64 {
    1.0 / (1.0 + (-z).exp())
}

impl Calibration {
    /// Parses a calibration JSON. Errors: `CorruptData` for bad JSON, another format or version,
    /// or models of the wrong length.
    pub fn from_json(text: &str) -> Result<Self> {
        let c: Calibration =
            crate::strict_json::from_str(text).map_err(|e| Error::CorruptData(format!("detector calibration: {e}")))?;
        if c.format != "sketchbody-detector-calibration" || c.version != 1 {
            return Err(Error::CorruptData(format!(
                "detector calibration: format {:?} version {}",
                c.format, c.version
            )));
        }
        let j = &c.joints;
        let p = &c.presence;
        let lens = [
            (j.fmp.len(), ALONE_FEATURES),
            (j.blazepose.len(), ALONE_FEATURES),
            (j.fmp_auto.len(), AUTO_FEATURES),
            (j.blazepose_auto.len(), AUTO_FEATURES),
            (p.fmp.len(), 2),
            (p.blazepose.len(), 2),
            (p.auto.len(), 4),
        ];
        if lens.iter().any(|&(a, b)| a != b)
            || [&j.fmp, &j.blazepose, &j.fmp_auto, &j.blazepose_auto, &p.fmp, &p.blazepose, &p.auto]
                .iter()
                .any(|w| w.iter().any(|v| !v.is_finite()))
        {
            return Err(Error::CorruptData("detector calibration: models of the wrong size or non-finite".into()));
        }
        Ok(c)
    }

    /// The embedded calibration, parsed once per process.
    pub fn embedded() -> Result<&'static Calibration> {
        static CAL: OnceLock<std::result::Result<Calibration, String>> = OnceLock::new();
        CAL.get_or_init(|| Calibration::from_json(EMBEDDED_CALIBRATION).map_err(|e| e.to_string()))
            .as_ref()
            .map_err(|e| Error::CorruptData(e.clone()))
    }

    /// The calibration as pretty JSON.
    pub fn to_json(&self) -> String {
        serde_json::to_string_pretty(self).unwrap_or_default()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn features_are_bounded_and_the_embedded_calibration_loads() {
        assert!(predict(&[0.5, 2.0, -1.5], &[1.0]).is_err(), "a row of the wrong length");
        assert!(logit(0.0).is_finite() && logit(1.0).is_finite() && logit(0.5) == 0.0);
        assert_eq!(clamp_score(f64::NAN), -5.0);
        assert_eq!(joint_features(0.5, 9.0, Some((3.0, -1.0))), vec![1.0, 0.0, 9.0, 1.0, 0.0]);
        assert_eq!(presence_features(Some(-20.0), Some(0.9), None), vec![1.0, -5.0, 0.9]);
        let c = Calibration::embedded().unwrap();
        assert_eq!(Calibration::from_json(&c.to_json()).unwrap(), *c);
        assert!(Calibration::from_json("{}").is_err());
        let mut bad = c.clone();
        bad.joints.fmp.pop();
        assert!(Calibration::from_json(&bad.to_json()).is_err());
    }
}
