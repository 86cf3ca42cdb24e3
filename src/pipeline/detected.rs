//! How joints from the detector, rather than the user, are treated downstream: BlazePose's
//! relative depths become the pose step's depth hint ([`crate::pose::DepthHint`]), and the shape
//! fit trusts the joints less ([`DetectedJointsFit`]). Given joints use the options as they are.

use crate::detect::figure::Figure;
use crate::error::{Error, Result};
use crate::fit::FitOptions;
use crate::pose::DepthHint;

/// Default [`super::PipelineOptions::depth_hint`]: the weight of BlazePose's relative depths in
/// the pose step, dimensionless. Chosen on `make-dataset 60 --seed 78` with detected joints and
/// automatic gender (docs/benchmarks-history.md, "The fully automatic path, as a user meets it").
pub const DEFAULT_DEPTH_HINT: f64 = 0.1;

/// The shape fit's adjustments for detected joints ([`super::PipelineOptions::detected`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DetectedJointsFit {
    /// Factor on [`FitOptions::joint_weight`], in 0..=1 (default 0.5).
    pub joint_weight_scale: f64,
    /// Search bone-length factors in the fit ([`FitOptions::proportion_sd`]) with detected joints
    /// too (default `false`: the fit keeps the pose step's proportions).
    pub proportions: bool,
    /// The pose step reads BlazePose's own joints and all their depths when they agree with the
    /// chosen figure ([`Figure::landmark_joints`]); the fit keeps the chosen joints.
    pub landmark_pose: bool,
    /// With automatic gender, fit the gendered space the detected-joints gender classifier
    /// ([`crate::fit::GenderClassifier::SHIPPED_DETECTED`]) picks (`P(male) > 0.5`) instead of the
    /// both-sexes space, whose fitted gender value is no better than chance with detected joints.
    /// Default `true`.
    pub classifier_gender: bool,
}

impl Default for DetectedJointsFit {
    /// Chosen on `make-dataset 60 --seed 78` with detected joints and automatic gender, by rest
    /// AED centred (docs/benchmarks-history.md, "The fully automatic path, as a user meets it").
    fn default() -> Self {
        Self { joint_weight_scale: 0.5, proportions: false, landmark_pose: false, classifier_gender: true }
    }
}

impl DetectedJointsFit {
    /// The gender to fit for a detected figure when none was given: the classifier's choice from
    /// its `male_probability` ([`crate::fit::GenderEvidence::male_probability`]) when
    /// [`DetectedJointsFit::classifier_gender`], else `None` (the both-sexes fit).
    pub fn gender(&self, male_probability: f64) -> Option<crate::body::Gender> {
        use crate::body::Gender;
        self.classifier_gender.then_some(if male_probability > 0.5 { Gender::Male } else { Gender::Female })
    }

    /// `fit` adjusted for detected joints. Errors: `OutOfRange` for a scale outside 0..=1.
    pub fn apply(&self, fit: &FitOptions) -> Result<FitOptions> {
        if !(0.0..=1.0).contains(&self.joint_weight_scale) {
            return Err(Error::OutOfRange {
                name: "detected.joint_weight_scale",
                detail: format!("{} not in [0, 1]", self.joint_weight_scale),
            });
        }
        let mut f = fit.clone();
        f.joint_weight *= self.joint_weight_scale;
        if !self.proportions {
            f.proportion_sd = 0.0;
        }
        Ok(f)
    }
}

/// The joints and depth hint of the pose step for a detected figure: BlazePose's own joints with
/// all their depths when `fit.landmark_pose` and they agree, else `joints` with the depths of
/// the agreeing joints ([`depth_hint`]).
pub(crate) fn pose_input(
    figure: &Figure,
    joints: &crate::skeleton::Joints2,
    weight: f64,
    fit: &DetectedJointsFit,
) -> (crate::skeleton::Joints2, Option<DepthHint>) {
    match &figure.landmark_joints {
        Some((j, z)) if fit.landmark_pose => {
            let hint =
                (weight > 0.0).then(|| DepthHint::from_landmark_depth(z, [true; crate::skeleton::NUM_JOINTS], weight));
            (*j, hint)
        }
        _ => (*joints, depth_hint(figure, weight)),
    }
}

/// The pose step's depth hint from a detected figure's landmark depths with `weight`
/// ([`super::PipelineOptions::depth_hint`]); `None` when the weight is 0 or the figure has no depth.
pub(crate) fn depth_hint(figure: &Figure, weight: f64) -> Option<DepthHint> {
    if !(weight > 0.0) || figure.landmark_depth.iter().all(Option::is_none) {
        return None;
    }
    let z = figure.landmark_depth.map(|d| d.unwrap_or(0.0));
    let known = figure.landmark_depth.map(|d| d.is_some());
    Some(DepthHint::from_landmark_depth(&z, known, weight))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::skeleton::NUM_JOINTS;

    #[test]
    fn detected_joints_lower_the_joint_weight_and_keep_the_pose_proportions() {
        let fit = FitOptions { joint_weight: 2.0, proportion_sd: 0.1, ..FitOptions::default() };
        let d = DetectedJointsFit::default().apply(&fit).unwrap();
        assert_eq!((d.joint_weight, d.proportion_sd), (1.0, 0.0));
        assert_eq!(FitOptions { joint_weight: 2.0, proportion_sd: 0.1, ..d.clone() }, fit, "nothing else changes");
        let keep =
            DetectedJointsFit { joint_weight_scale: 1.0, proportions: true, ..Default::default() }.apply(&fit).unwrap();
        assert_eq!(keep, fit);
        for bad in [-0.1, 1.5, f64::NAN] {
            let e = DetectedJointsFit { joint_weight_scale: bad, ..Default::default() }.apply(&fit);
            assert!(matches!(e, Err(Error::OutOfRange { .. })), "{bad}");
        }
    }

    fn figure(joint_confidence: [f64; NUM_JOINTS]) -> Figure {
        Figure {
            backend: crate::detect::figure::Backend::BlazePose,
            joints: crate::skeleton::Joints2 { xy: [[0.0; 2]; NUM_JOINTS], visible: [true; NUM_JOINTS] },
            joint_confidence,
            confidence: 1.0,
            presence: 1.0,
            low_confidence: false,
            raw_score: 1.0,
            others: Vec::new(),
            averaged: [false; NUM_JOINTS],
            landmark_depth: [None; NUM_JOINTS],
            landmark_joints: None,
            facing: crate::detect::facing::estimate(
                &crate::skeleton::Joints2 { xy: [[0.0; 2]; NUM_JOINTS], visible: [true; NUM_JOINTS] },
                [0.25; 4],
                false,
            ),
        }
    }

    #[test]
    fn the_classifier_picks_the_gender_only_when_asked() {
        use crate::body::Gender;
        let on = DetectedJointsFit::default();
        assert!(on.classifier_gender, "the default");
        assert_eq!(on.gender(0.7), Some(Gender::Male));
        assert_eq!(on.gender(0.3), Some(Gender::Female));
        assert_eq!(on.gender(0.5), Some(Gender::Female), "a tie is not male");
        let off = DetectedJointsFit { classifier_gender: false, ..on };
        assert_eq!(off.gender(0.9), None, "the both-sexes fit");
    }

    #[test]
    fn a_figure_gives_a_hint_only_with_depths_and_a_weight() {
        let mut f = figure([1.0; NUM_JOINTS]);
        assert!(depth_hint(&f, 0.1).is_none(), "no depths");
        f.landmark_depth[3] = Some(-10.0);
        assert!(depth_hint(&f, 0.0).is_none(), "zero weight");
        let h = depth_hint(&f, 0.1).unwrap();
        assert_eq!(h.known.iter().filter(|k| **k).count(), 1);
        assert!(h.depth[3] > 0.0, "smaller landmark depth = nearer = larger hint depth");
        assert_eq!(h.weight, 0.1);
        // The pose step's input: the chosen joints with the agreeing depths, or with
        // `landmark_pose` BlazePose's own joints with all their depths.
        let chosen = f.joints;
        let mut theirs = chosen;
        theirs.xy[4] = [7.0, 9.0];
        f.landmark_joints = Some((theirs, [-2.0; NUM_JOINTS]));
        let off = DetectedJointsFit::default();
        let (j, h) = pose_input(&f, &chosen, 0.1, &off);
        assert_eq!(j, chosen);
        assert_eq!(h.unwrap().known.iter().filter(|k| **k).count(), 1);
        let on = DetectedJointsFit { landmark_pose: true, ..off };
        let (j, h) = pose_input(&f, &chosen, 0.1, &on);
        assert_eq!(j, theirs);
        assert!(h.unwrap().known.iter().all(|k| *k));
        assert!(pose_input(&f, &chosen, 0.0, &on).1.is_none(), "zero weight: no hint");
        f.landmark_joints = None;
        assert_eq!(pose_input(&f, &chosen, 0.1, &on).0, chosen, "no agreeing BlazePose figure");
    }
}
