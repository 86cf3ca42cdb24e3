//! Geometric evidence about the drawn figure's gender, and a small calibrated logistic
//! regression on it (issue 21): the probability that the figure is male, fed to the both-sexes
//! fit as the prior's mass on the male end ([`super::FitOptions::male_prior`]).
//!
//! Every feature is a log ratio of lengths measured in the image, so it does not depend on the
//! drawing's size, and none reads renderer artefacts (hair, line style): only the 2-D joints,
//! the outline (the edge map) and the 3-D pose's bone directions.
//!
//! - Joint widths: the shoulder width (r_shoulder–l_shoulder) and the hip width (r_hip–l_hip)
//!   over the torso length (pelvis–neck), each corrected for foreshortening by the same ratio of
//!   the estimated 3-D pose's unit bone directions projected by the camera's rotation (the
//!   estimate of the 3-D length ratio when the directions are right).
//! - Outline widths at chest, waist and hip level: from points on the torso axis (pelvis → neck
//!   at [`LEVELS`]) rays run both ways perpendicular to the axis to the first edge pixel beyond
//!   [`MIN_HALF_WIDTH`] × torso length; the width is the sum of both distances over the torso
//!   length, the median over [`SUB_LEVELS`] rays spread along the axis (robust to a belt or a
//!   crease on one ray).
//!
//! A feature that cannot be measured (a hidden joint, no outline within reach) is missing and
//! adds nothing to the classifier's sum (the training set's mean is imputed).
//!
//! The shipped classifier [`GenderClassifier::SHIPPED`] was trained by
//! `sketchbody-lab train-gender` (command, confusion table and calibration: docs/benchmarks-history.md,
//! "The fully automatic path, as a user meets it").

use crate::camera::WeakPerspective;
use crate::error::{ensure_finite, Result};
use crate::image::GrayImage;
use crate::skeleton::{joint, Joints2, Joints3};

/// Number of features of [`GenderFeatures`].
pub const NUM_GENDER_FEATURES: usize = 10;

/// Names of the features, in order (CSV headers, reports).
pub const GENDER_FEATURE_NAMES: [&str; NUM_GENDER_FEATURES] = [
    "log_shoulder_width",
    "log_hip_width",
    "log_chest_outline",
    "log_waist_outline",
    "log_hip_outline",
    "log_neck_outline",
    "log_upper_arm_outline",
    "log_forearm_outline",
    "log_thigh_outline",
    "log_calf_outline",
];

/// Limb and neck outlines: (from joint, to joint, fraction along the segment) — neck (neck →
/// head), upper arm, forearm, thigh, calf; each limb's width is the mean of the log widths of
/// the body's two sides that can be measured.
const SEGMENTS: [[(usize, usize, f64); 2]; 5] = [
    [(joint::NECK, joint::HEAD, 0.2), (joint::NECK, joint::HEAD, 0.2)],
    [(joint::R_SHOULDER, joint::R_ELBOW, 0.5), (joint::L_SHOULDER, joint::L_ELBOW, 0.5)],
    [(joint::R_ELBOW, joint::R_WRIST, 0.4), (joint::L_ELBOW, joint::L_WRIST, 0.4)],
    [(joint::R_HIP, joint::R_KNEE, 0.35), (joint::L_HIP, joint::L_KNEE, 0.35)],
    [(joint::R_KNEE, joint::R_ANKLE, 0.35), (joint::L_KNEE, joint::L_ANKLE, 0.35)],
];

/// Limb and neck rays ignore edges nearer than this many torso lengths and stop at
/// [`MAX_LIMB_HALF_WIDTH`].
pub const MIN_LIMB_HALF_WIDTH: f64 = 0.02;

/// See [`MIN_LIMB_HALF_WIDTH`].
pub const MAX_LIMB_HALF_WIDTH: f64 = 0.35;

/// Fractions of the way from the pelvis to the neck where the outline is measured: chest, waist,
/// hip (slightly below the pelvis joint, where the hips are widest).
pub const LEVELS: [f64; 3] = [0.72, 0.42, -0.05];

/// Rays per level, spread evenly over ±[`SUB_LEVEL_SPREAD`] × torso length along the axis.
pub const SUB_LEVELS: usize = 7;

/// Half the spread of a level's rays along the torso axis, in torso lengths.
pub const SUB_LEVEL_SPREAD: f64 = 0.06;

/// Edge pixels nearer the axis than this many torso lengths are ignored (interior strokes: a
/// zip, a centre line); no torso is that narrow.
pub const MIN_HALF_WIDTH: f64 = 0.1;

/// Rays stop (no outline found) at this many torso lengths from the axis.
pub const MAX_HALF_WIDTH: f64 = 0.9;

/// Projected / true length of a unit 3-D direction is clamped to at least this when correcting
/// joint widths for foreshortening (a bone pointing at the viewer says nothing about its length).
pub const MIN_FORESHORTENING: f64 = 0.3;

/// The measured features (log ratios, see the module documentation); `None` = missing.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GenderFeatures {
    /// Feature values in the order of [`GENDER_FEATURE_NAMES`].
    pub values: [Option<f64>; NUM_GENDER_FEATURES],
}

/// Logistic regression on standardised [`GenderFeatures`]:
/// `P(male) = σ(intercept + Σ coefficient_i (x_i − mean_i) / scale_i)`, a missing feature
/// contributing 0.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GenderClassifier {
    /// Training-set mean of each feature.
    pub means: [f64; NUM_GENDER_FEATURES],
    /// Training-set standard deviation of each feature (> 0).
    pub scales: [f64; NUM_GENDER_FEATURES],
    /// Weight of each standardised feature.
    pub coefficients: [f64; NUM_GENDER_FEATURES],
    /// Log-odds of male at the mean features.
    pub intercept: f64,
}

/// The evidence of one sketch: its features and the shipped classifier's probability.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GenderEvidence {
    /// The measured features.
    pub features: GenderFeatures,
    /// The classifier's probability that the figure is male (0..=1).
    pub male_probability: f64,
}

impl GenderClassifier {
    /// The classifier the pipeline uses, trained on `make-dataset 1200 --seed 79 --mocap DIR`
    /// (DIR: the DeepMimic clips other than the shape-fit benchmark's six held-out ones) with
    /// ground-truth joints: `run-dataset DS --out R --gender truth --mean-shape`, then
    /// `train-gender --train DS=R --ridge 1`.
    pub const SHIPPED: GenderClassifier = GenderClassifier {
        means: [
            -0.357321, -0.963395, -0.429775, -0.839572, -0.714372, -2.228744, -2.076896, -2.234390, -1.355721,
            -1.868242,
        ],
        scales: [0.157552, 0.082945, 0.316103, 0.204828, 0.318693, 0.386241, 0.247169, 0.209341, 0.233153, 0.285977],
        coefficients: [
            0.623426, 0.406412, 0.013311, 1.569759, -0.338214, 0.074623, -0.199412, -0.183316, -0.604844, -0.327697,
        ],
        intercept: -0.027786,
    };

    /// The classifier for joints from the single-figure detector (whose joints differ from
    /// drawn ones systematically, e.g. BlazePose's hip and shoulder convention), trained like
    /// [`GenderClassifier::SHIPPED`] on the features `run-dataset DS --detect --gender truth
    /// --mean-shape` measures on the first 300 sketches of the same training set
    /// (`train-gender --train DS=R --first 300 --ridge 1`; training accuracy 0.75).
    pub const SHIPPED_DETECTED: GenderClassifier = GenderClassifier {
        means: [
            -0.447276, -1.100977, -0.447643, -0.864722, -0.734098, -2.237932, -2.043577, -2.165987, -1.385822,
            -1.897575,
        ],
        scales: [0.147937, 0.215640, 0.305754, 0.200695, 0.334086, 0.464713, 0.288016, 0.316229, 0.218969, 0.308634],
        coefficients: [
            0.184406, -0.194379, 0.108097, 1.144134, 0.041096, 0.208190, 0.312045, -0.197373, -0.565302, -0.599918,
        ],
        intercept: -0.117362,
    };

    /// `P(male)` for `features` (0..=1; 0.5 when every feature is missing and the intercept
    /// is 0).
    pub fn male_probability(&self, features: &GenderFeatures) -> f64 {
        sigmoid(self.log_odds(features))
    }

    /// The log-odds of male for `features`.
    pub fn log_odds(&self, features: &GenderFeatures) -> f64 {
        let mut z = self.intercept;
        for (k, v) in features.values.iter().enumerate() {
            if let Some(x) = v {
                z += self.coefficients[k] * (x - self.means[k]) / self.scales[k];
            }
        }
        z
    }
}

/// The final gender choice when both gendered spaces are fitted: a logistic regression on the
/// classifier's log-odds ([`GenderClassifier::log_odds`] of [`GenderClassifier::SHIPPED`]) and
/// the score margin (male fit's best score − female fit's, [`super::FitResult::best_score`]),
/// both standardised: `P(male) = σ(intercept + Σ coefficient_i (x_i − mean_i) / scale_i)`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MarginCombination {
    /// Training-set means of (classifier log-odds, score margin).
    pub means: [f64; 2],
    /// Training-set standard deviations (> 0).
    pub scales: [f64; 2],
    /// Weights of the standardised inputs.
    pub coefficients: [f64; 2],
    /// Log-odds of male at the mean inputs.
    pub intercept: f64,
}

impl MarginCombination {
    /// The combination the pipeline uses (with [`crate::pipeline::PipelineOptions::classify_gender`]),
    /// trained on the first 300 sketches of the classifier's training set (`make-dataset 1200
    /// --seed 79`) with the pipeline's own deciding fits (ground-truth joints, 5 iterations,
    /// [`crate::pipeline::PipelineOptions::gender_decision_iterations`]): `run-dataset DS --out R
    /// --first 300 --gender auto`, then `train-gender --fits DS=R,R --ridge 0.1`, its intercept
    /// refitted to the automatic-gender runs of the seed-78 tuning set at fit seeds 1 and 2
    /// (`--recalibrate T78=R1 --recalibrate T78=R2`; docs/benchmarks-history.md, "Five-iteration
    /// deciding fits").
    pub const SHIPPED: MarginCombination = MarginCombination {
        means: [-0.056619, -0.014240],
        scales: [1.767349, 0.314466],
        coefficients: [1.654769, 3.389183],
        intercept: 0.218272,
    };

    /// `P(male)` from the classifier's log-odds and the score margin (male − female). A
    /// non-finite margin (a fit without a finite score) counts as no margin (the mean).
    pub fn male_probability(&self, log_odds: f64, margin: f64) -> f64 {
        sigmoid(self.combined_log_odds(log_odds, margin))
    }

    /// The log-odds of male behind [`MarginCombination::male_probability`].
    pub fn combined_log_odds(&self, log_odds: f64, margin: f64) -> f64 {
        let x = [log_odds, margin];
        let mut z = self.intercept;
        for k in 0..2 {
            if x[k].is_finite() {
                z += self.coefficients[k] * (x[k] - self.means[k]) / self.scales[k];
            }
        }
        z
    }
}

/// The logistic function 1 / (1 + e^−z), without overflow for large |z|.
pub fn sigmoid(z: f64) -> f64 {
    if z >= 0.0 {
        1.0 / (1.0 + (-z).exp())
    } else {
        let e = z.exp();
        e / (1.0 + e)
    }
}

/// Length of a 3-D direction's projection (camera rotation, the camera's own x/y scales
/// normalised away) per unit length, clamped to [`MIN_FORESHORTENING`]..=1.
fn foreshortening(camera: &WeakPerspective, pose: &Joints3, a: usize, b: usize) -> Option<f64> {
    let d = nalgebra::Vector3::from(pose[b]) - nalgebra::Vector3::from(pose[a]);
    let n = d.norm();
    if !(n > 1e-9) {
        return None;
    }
    let c = camera.r * (d / n);
    Some(c.x.hypot(c.y).clamp(MIN_FORESHORTENING, 1.0))
}

/// Measures [`GenderFeatures`] from the sketch's 2-D joints (pixels), its edge map (non-zero =
/// edge) and the estimated 3-D pose with its camera (only the bone directions and the rotation
/// are used). Errors: a non-finite visible joint ([`Error::NonFinite`]). Without a visible
/// pelvis and neck (no torso axis) every feature is missing.
pub fn gender_features(
    joints2d: &Joints2,
    edges: &GrayImage,
    pose: &Joints3,
    camera: &WeakPerspective,
) -> Result<GenderFeatures> {
    for k in 0..joints2d.xy.len() {
        if joints2d.visible[k] {
            ensure_finite("2-D joint", joints2d.xy[k][0])?;
            ensure_finite("2-D joint", joints2d.xy[k][1])?;
        }
    }
    let mut values = [None; NUM_GENDER_FEATURES];
    let (p, n) = (joint::PELVIS, joint::NECK);
    if !(joints2d.visible[p] && joints2d.visible[n]) {
        return Ok(GenderFeatures { values });
    }
    let (pp, pn) = (joints2d.xy[p], joints2d.xy[n]);
    let axis = [pn[0] - pp[0], pn[1] - pp[1]];
    let torso = axis[0].hypot(axis[1]);
    if !(torso > 4.0) {
        return Ok(GenderFeatures { values });
    }
    let torso_fs = foreshortening(camera, pose, p, n);
    // Joint widths.
    for (slot, (a, b)) in [(joint::R_SHOULDER, joint::L_SHOULDER), (joint::R_HIP, joint::L_HIP)].into_iter().enumerate()
    {
        if !(joints2d.visible[a] && joints2d.visible[b]) {
            continue;
        }
        let w = (joints2d.xy[b][0] - joints2d.xy[a][0]).hypot(joints2d.xy[b][1] - joints2d.xy[a][1]);
        if let (Some(fa), Some(ft)) = (foreshortening(camera, pose, a, b), torso_fs) {
            if w > 0.5 {
                values[slot] = Some((w / torso).ln() - (fa / ft).ln());
            }
        }
    }
    // Outline widths across the torso.
    let torso_range = (MIN_HALF_WIDTH * torso, MAX_HALF_WIDTH * torso);
    for (i, &level) in LEVELS.iter().enumerate() {
        values[2 + i] = outline_width(edges, pp, pn, level, SUB_LEVEL_SPREAD, torso_range).map(|w| (w / torso).ln());
    }
    // Neck and limbs.
    let limb_range = (MIN_LIMB_HALF_WIDTH * torso, MAX_LIMB_HALF_WIDTH * torso);
    for (i, sides) in SEGMENTS.iter().enumerate() {
        let logs: Vec<f64> = sides
            .iter()
            .take(if i == 0 { 1 } else { 2 })
            .filter(|&&(a, b, _)| joints2d.visible[a] && joints2d.visible[b])
            .filter_map(|&(a, b, frac)| {
                let (pa, pb) = (joints2d.xy[a], joints2d.xy[b]);
                let len = (pb[0] - pa[0]).hypot(pb[1] - pa[1]);
                (len > 4.0).then_some(())?;
                // Rays spread over ±15 % of the segment, converted to its own length.
                let spread = 0.15;
                outline_width(edges, pa, pb, frac, spread, limb_range).map(|w| (w / torso).ln())
            })
            .collect();
        if !logs.is_empty() {
            values[5 + i] = Some(logs.iter().sum::<f64>() / logs.len() as f64);
        }
    }
    Ok(GenderFeatures { values })
}

/// Width of the outline across the segment `a → b` at fraction `level` of the way (pixels): the
/// median over [`SUB_LEVELS`] rays pairs spread over ±`spread` × the segment's length, each the
/// sum of the distances to the first edge on either side within `range`; `None` unless more
/// than half the ray pairs find both edges.
fn outline_width(
    edges: &GrayImage,
    a: [f64; 2],
    b: [f64; 2],
    level: f64,
    spread: f64,
    range: (f64, f64),
) -> Option<f64> {
    let axis = [b[0] - a[0], b[1] - a[1]];
    let len = axis[0].hypot(axis[1]);
    if !(len > 1e-9) {
        return None;
    }
    let v = [-axis[1] / len, axis[0] / len];
    let mut widths: Vec<f64> = (0..SUB_LEVELS)
        .filter_map(|s| {
            let off = level + spread * (2.0 * s as f64 / (SUB_LEVELS - 1) as f64 - 1.0);
            let c = [a[0] + off * axis[0], a[1] + off * axis[1]];
            Some(ray_to_edge(edges, c, v, range)? + ray_to_edge(edges, c, [-v[0], -v[1]], range)?)
        })
        .collect();
    if widths.len() * 2 <= SUB_LEVELS {
        return None;
    }
    widths.sort_by(f64::total_cmp);
    Some(widths[widths.len() / 2])
}

/// Distance from `c` along unit `dir` to the first edge pixel between `range.0` and `range.1`
/// pixels (half-pixel steps); `None` when there is none or the ray
/// leaves the image first.
fn ray_to_edge(edges: &GrayImage, c: [f64; 2], dir: [f64; 2], range: (f64, f64)) -> Option<f64> {
    let (w, h) = (edges.width() as i64, edges.height() as i64);
    let data = edges.as_bytes();
    let mut d = range.0;
    while d <= range.1 {
        let (x, y) = ((c[0] + d * dir[0]).round() as i64, (c[1] + d * dir[1]).round() as i64);
        if x < 0 || y < 0 || x >= w || y >= h {
            return None;
        }
        if data[(y * w + x) as usize] != 0 {
            return Some(d);
        }
        d += 0.5;
    }
    None
}

/// The sketch's [`GenderEvidence`] under `classifier` ([`GenderClassifier::SHIPPED`] for given
/// joints, [`GenderClassifier::SHIPPED_DETECTED`] for the detector's).
pub fn gender_evidence(
    joints2d: &Joints2,
    edges: &GrayImage,
    pose: &Joints3,
    camera: &WeakPerspective,
    classifier: &GenderClassifier,
) -> Result<GenderEvidence> {
    let features = gender_features(joints2d, edges, pose, camera)?;
    Ok(GenderEvidence { features, male_probability: classifier.male_probability(&features) })
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Matrix3;

    const CX: f64 = 128.0;
    const PELVIS_Y: f64 = 150.0;
    const TORSO: f64 = 100.0;

    /// Widths (pixels) of a drawn T-pose figure: shoulder and hip joint widths, then the chest,
    /// waist, hip, neck, upper-arm, forearm, thigh and calf outlines.
    type Widths = [f64; 10];

    fn put(e: &mut GrayImage, x: f64, y: f64) {
        let (x, y) = (x.round() as usize, y.round() as usize);
        let w = e.width();
        e.as_bytes_mut()[y * w + x] = 255;
    }

    /// A frontal T-pose: torso vertical (pelvis (128, 150), neck 100 px above), arms out
    /// horizontally, legs straight down; each outline drawn as two strokes parallel to its
    /// segment around the level where it is measured. Pose: the 2-D joints in metres, camera
    /// without rotation.
    fn figure(w: &Widths) -> (Joints2, GrayImage, Joints3, WeakPerspective) {
        let mut xy = [[0.0; 2]; 15];
        let ny = PELVIS_Y - TORSO;
        xy[joint::HEAD] = [CX, ny - 30.0];
        xy[joint::NECK] = [CX, ny];
        xy[joint::PELVIS] = [CX, PELVIS_Y];
        for (s, sign) in [(0, -1.0), (1, 1.0)] {
            let sx = CX + sign * w[0] / 2.0;
            let (sh, el, wr) = if s == 0 {
                (joint::R_SHOULDER, joint::R_ELBOW, joint::R_WRIST)
            } else {
                (joint::L_SHOULDER, joint::L_ELBOW, joint::L_WRIST)
            };
            xy[sh] = [sx, ny + 5.0];
            xy[el] = [sx + sign * 30.0, ny + 5.0];
            xy[wr] = [sx + sign * 55.0, ny + 5.0];
            let hx = CX + sign * w[1] / 2.0;
            let (hip, kn, an) = if s == 0 {
                (joint::R_HIP, joint::R_KNEE, joint::R_ANKLE)
            } else {
                (joint::L_HIP, joint::L_KNEE, joint::L_ANKLE)
            };
            xy[hip] = [hx, PELVIS_Y];
            xy[kn] = [hx, PELVIS_Y + 45.0];
            xy[an] = [hx, PELVIS_Y + 90.0];
        }
        let mut e = GrayImage::filled(256, 256, 0).unwrap();
        // Torso levels: vertical strokes at ±width/2 over the level's rays.
        for (i, &level) in LEVELS.iter().enumerate() {
            let y0 = PELVIS_Y - level * TORSO;
            for k in -8..=8 {
                put(&mut e, CX - w[2 + i] / 2.0, y0 + k as f64);
                put(&mut e, CX + w[2 + i] / 2.0, y0 + k as f64);
            }
        }
        // Neck and limbs: strokes parallel to each segment at ±width/2, over ±20 % of it.
        for (i, sides) in SEGMENTS.iter().enumerate() {
            for &(a, b, frac) in sides {
                let (pa, pb) = (xy[a], xy[b]);
                let d = [pb[0] - pa[0], pb[1] - pa[1]];
                let len = d[0].hypot(d[1]);
                let v = [-d[1] / len, d[0] / len];
                for k in -20..=20 {
                    let t = frac + 0.01 * k as f64;
                    let c = [pa[0] + t * d[0], pa[1] + t * d[1]];
                    for side in [-1.0, 1.0] {
                        put(&mut e, c[0] + side * v[0] * w[5 + i] / 2.0, c[1] + side * v[1] * w[5 + i] / 2.0);
                    }
                }
            }
        }
        let visible = [true; 15];
        let pose: Joints3 = std::array::from_fn(|k| [(xy[k][0] - CX) / 100.0, (PELVIS_Y - xy[k][1]) / 100.0, 0.0]);
        let camera = WeakPerspective { sx: 100.0, sy: 100.0, r: Matrix3::identity(), t: [CX, PELVIS_Y] };
        (Joints2 { xy, visible }, e, pose, camera)
    }

    /// Drawn widths whose features sit `k` training standard deviations from the shipped
    /// classifier's means, each toward the male side of its coefficient (k < 0: female side).
    fn widths_at(k: f64) -> Widths {
        let c = GenderClassifier::SHIPPED;
        std::array::from_fn(|i| TORSO * (c.means[i] + k * c.scales[i] * c.coefficients[i].signum()).exp())
    }

    #[test]
    fn features_are_the_drawn_widths_over_the_torso_length() {
        let w = widths_at(0.0);
        let (j, e, pose, cam) = figure(&w);
        let f = gender_features(&j, &e, &pose, &cam).unwrap();
        for (i, v) in f.values.iter().enumerate() {
            let got = v.unwrap_or_else(|| panic!("{} missing", GENDER_FEATURE_NAMES[i]));
            // Within the pixel grid's rounding of both strokes.
            let px = got.exp() * TORSO;
            assert!((px - w[i]).abs() < 1.5, "{}: {px} px vs {} px", GENDER_FEATURE_NAMES[i], w[i]);
        }
    }

    #[test]
    fn classifier_is_sure_on_clear_figures_and_unsure_on_an_ambiguous_one() {
        let p = |k: f64| {
            let (j, e, pose, cam) = figure(&widths_at(k));
            gender_evidence(&j, &e, &pose, &cam, &GenderClassifier::SHIPPED).unwrap().male_probability
        };
        let (female, middle, male) = (p(-1.5), p(0.0), p(1.5));
        assert!(male > 0.9, "male fixture: P(male) {male}");
        assert!(female < 0.1, "female fixture: P(male) {female}");
        assert!((middle - 0.5).abs() < 0.1, "ambiguous fixture: P(male) {middle}");
    }

    /// The shipped models are the trained ones: their log-odds at fixed inputs (every feature
    /// −1, widths e⁻¹ of the torso; classifier log-odds 1 and margin 1) are those of the
    /// published coefficients, so a changed digit or sign of any mean, scale, coefficient or
    /// intercept shows. The logistic function is exact at 0, symmetric and finite far out.
    #[test]
    fn the_shipped_models_give_their_trained_log_odds() {
        let f = GenderFeatures { values: [Some(-1.0); NUM_GENDER_FEATURES] };
        for (c, want) in
            [(GenderClassifier::SHIPPED, -7.330641313161677), (GenderClassifier::SHIPPED_DETECTED, -3.679819382736251)]
        {
            assert!((c.log_odds(&f) - want).abs() < 1e-9, "{} vs {want}", c.log_odds(&f));
            assert!((c.male_probability(&f) - 1.0 / (1.0 + want.exp().recip())).abs() < 1e-12);
        }
        let m = MarginCombination::SHIPPED;
        assert!((m.combined_log_odds(1.0, 1.0) - 12.138638889441653).abs() < 1e-9, "{}", m.combined_log_odds(1.0, 1.0));
        assert_eq!(m.combined_log_odds(m.means[0], f64::NAN), m.intercept);
        assert_eq!(sigmoid(0.0), 0.5);
        for z in [0.3f64, 2.0, 30.0] {
            let p = 1.0 / (1.0 + (-z).exp());
            assert!((sigmoid(z) - p).abs() < 1e-15 && (sigmoid(-z) - (1.0 - p)).abs() < 1e-15, "{z}");
        }
        assert_eq!((sigmoid(800.0), sigmoid(-800.0)), (1.0, 0.0));
    }

    /// Across a slanted segment the outline width is measured along its normal: two edge bands
    /// 20 px either side of a segment 30° from the horizontal give a width of about 40 px (the
    /// bands' near sides); a segment across the bands, whose rays run along them, gives none.
    #[test]
    fn outline_width_is_measured_across_a_slanted_segment() {
        let (a, angle) = ([60.0, 200.0], 30f64.to_radians());
        let b = [a[0] + 150.0 * angle.cos(), a[1] - 150.0 * angle.sin()];
        let n = [angle.sin(), angle.cos()];
        let mut e = GrayImage::filled(256, 256, 0).unwrap();
        let w = e.width();
        for y in 0..256 {
            for x in 0..256 {
                let d = ((x as f64 - a[0]) * n[0] + (y as f64 - a[1]) * n[1]).abs();
                if (d - 20.0).abs() < 1.0 {
                    e.as_bytes_mut()[y * w + x] = 255;
                }
            }
        }
        let width = outline_width(&e, a, b, 0.5, 0.15, (2.0, 60.0)).expect("both bands found");
        assert!((36.0..=41.0).contains(&width), "{width}");
        // Along the segment (rays in the bands' direction from its line) there is no outline.
        let along = outline_width(&e, a, [a[0] + n[0], a[1] + n[1]], 0.0, 0.0, (2.0, 60.0));
        assert_eq!(along, None);
    }

    /// A segment of 4 px or less is too short to measure across: the neck outline with the head
    /// exactly 4 px above the neck is missing, at 4.5 px it is the drawn width.
    #[test]
    fn segments_of_four_pixels_or_less_are_not_measured() {
        let w = widths_at(0.0);
        let (mut j, e, pose, cam) = figure(&w);
        let neck = j.xy[joint::NECK];
        j.xy[joint::HEAD] = [neck[0], neck[1] - 4.0];
        assert_eq!(gender_features(&j, &e, &pose, &cam).unwrap().values[5], None);
        j.xy[joint::HEAD] = [neck[0], neck[1] - 4.5];
        let got = gender_features(&j, &e, &pose, &cam).unwrap().values[5].expect("neck measured");
        assert!((got.exp() * TORSO - w[5]).abs() < 1.5, "{} px vs {} px", got.exp() * TORSO, w[5]);
    }

    #[test]
    fn missing_evidence_adds_nothing() {
        let (mut j, e, pose, cam) = figure(&widths_at(1.5));
        j.visible[joint::PELVIS] = false;
        let ev = gender_evidence(&j, &e, &pose, &cam, &GenderClassifier::SHIPPED).unwrap();
        assert!(ev.features.values.iter().all(Option::is_none));
        let c = GenderClassifier::SHIPPED;
        assert!((ev.male_probability - 1.0 / (1.0 + (-c.intercept).exp())).abs() < 1e-12);
        let blank = GrayImage::filled(256, 256, 0).unwrap();
        let (j, _, pose, cam) = figure(&widths_at(0.0));
        let f = gender_features(&j, &blank, &pose, &cam).unwrap();
        assert!(f.values[0].is_some() && f.values[2..].iter().all(Option::is_none));
        let mut bad = j;
        bad.xy[3][0] = f64::NAN;
        assert!(gender_features(&bad, &blank, &pose, &cam).is_err());
    }
}
