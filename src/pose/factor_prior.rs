//! Learned priors from the 2-D joints alone, trained on projected training motion with random
//! cameras and random proportions (`sketchbody-lab train-factor-prior`) and
//! embedded from `assets/factor_prior.json`: a regressor of each proportion group's log factor
//! ([`super::figure`]), with its predictive spread, and a regressor of the joints' relative
//! depths, which becomes the pose step's depth hint ([`FactorPrior::depth_hint`],
//! [`super::DepthHint`]) when no image cue gives one.
//!
//! **Inputs.** With `d_b` the 2-D vector of bone `b` and `L_b` its reference length, the figure's
//! 2-D scale is `s₂ = √(Σ|d_b|² / Σ L_b²)` (px per metre) and each bone gives three inputs: the
//! components of `d_b / (s₂ L_b)` (its image direction and relative length) and the log of that
//! relative length (floored at [`MIN_RATIO`]). The 42 inputs are standardised and a small
//! network ([`super::mlp`]: two tanh layers of 128) predicts `ln(s k_g / s₂)` for every group
//! (`s` the true figure scale, `k_g` the group's factor relative to the reference lengths).
//! [`FactorPrior::predict`] returns `ln(s k_g)`, so that the caller can express it relative to
//! any scale estimate (the pose step: the first solve's camera scale, the convention of
//! [`super::figure::estimate_factors`]). A second network of the same shape predicts each
//! joint's depth toward the camera relative to the pelvis, over `s₂` (metres at the figure's
//! 2-D scale). The file also holds the learned bend prior of the knees and elbows
//! ([`super::bend_prior`], [`FactorPrior::bend`]), counted on the same training motion. How the
//! networks are trained and measured: docs/benchmarks.md, "3-D pose".

use std::sync::OnceLock;

use serde::{Deserialize, Serialize};

use super::bend_prior::BendPrior;
use super::depth_hint::DepthHint;
use super::figure::{BONE_GROUP, NUM_GROUPS};
use super::mlp::Mlp;
use crate::error::{Error, Result};
use crate::skeleton::{Joints2, BONES, NUM_BONES, NUM_JOINTS};

/// The embedded prior (`assets/factor_prior.json`).
pub static EMBEDDED_FACTOR_PRIOR: &str = include_str!("../../assets/factor_prior.json");

/// Format tag of the JSON file.
pub const FORMAT: &str = "sketchbody-factor-prior";
/// Format version (2: the network; 1 was a ridge regression, no longer read).
pub const VERSION: u32 = 2;
/// Raw inputs: three per bone (module doc).
pub const NUM_INPUTS: usize = 3 * NUM_BONES;
/// Floor of a bone's relative image length before its log is taken.
pub const MIN_RATIO: f64 = 0.05;
/// Bound of the predicted log factor relative to the 2-D scale (|ln(s k_g / s₂)|), so that
/// absurd input cannot give absurd factors (the caller clamps the factors too).
const MAX_LOG: f64 = 2.0;

/// The learned factor prior, as stored in `assets/factor_prior.json`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FactorPrior {
    /// Format tag, [`FORMAT`].
    pub format: String,
    /// Format version, [`VERSION`].
    pub version: u32,
    /// How it was made: command, data (clips, held-out clips, licences), parameters, fit figures.
    pub provenance: String,
    /// Reference bone lengths the inputs and factors refer to (metres, canonical bone order).
    pub lengths: Vec<f64>,
    /// Mean of each raw input over the training samples.
    pub mean: Vec<f64>,
    /// Spread of each raw input over the training samples (> 0).
    pub scale: Vec<f64>,
    /// The factors' regressor: [`NUM_INPUTS`] standardised inputs to [`NUM_GROUPS`] outputs.
    pub network: Mlp,
    /// The depths' regressor: [`NUM_INPUTS`] standardised inputs to one depth per joint
    /// (canonical order), toward the camera relative to the pelvis, over `s₂`.
    pub depth_network: Mlp,
    /// Predictive spread of each group's log factor (RMS residual on samples not fitted), > 0.
    pub sd: Vec<f64>,
    /// The learned bend prior of the knees and elbows ([`super::bend_prior`]), from the same
    /// training motion; `None` in files written before it (the free-joint step then has none).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub bend: Option<BendPrior>,
}

/// A prediction of [`FactorPrior::predict`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Prediction {
    /// `ln(s k_g)`: the log of each group's image scale (px per metre of reference length).
    pub log_scale: [f64; NUM_GROUPS],
    /// Predictive spread of each value.
    pub sd: [f64; NUM_GROUPS],
}

/// The 2-D scale `s₂` and the raw inputs of a joint set (module doc); `None` when a joint is
/// invisible or not finite, or the figure has no extent.
pub fn inputs(j: &Joints2, lengths: &[f64; NUM_BONES]) -> Option<(f64, [f64; NUM_INPUTS])> {
    if j.visible.iter().any(|v| !v) || j.xy.iter().flatten().any(|v| !v.is_finite()) {
        return None;
    }
    let d: [[f64; 2]; NUM_BONES] = BONES.map(|(p, c)| [j.xy[c][0] - j.xy[p][0], j.xy[c][1] - j.xy[p][1]]);
    let num: f64 = d.iter().map(|v| v[0] * v[0] + v[1] * v[1]).sum();
    let den: f64 = lengths.iter().map(|l| l * l).sum();
    let s2 = (num / den).sqrt();
    if !(s2 > 0.0) || !s2.is_finite() || lengths.iter().any(|l| !(*l > 0.0)) {
        return None;
    }
    let mut x = [0.0; NUM_INPUTS];
    for b in 0..NUM_BONES {
        let (u, v) = (d[b][0] / (s2 * lengths[b]), d[b][1] / (s2 * lengths[b]));
        x[3 * b] = u;
        x[3 * b + 1] = v;
        x[3 * b + 2] = u.hypot(v).max(MIN_RATIO).ln();
    }
    Some((s2, x))
}

/// A raw input standardised by its training mean and spread, bounded to ±8 spreads.
pub fn standardise(x: f64, mean: f64, scale: f64) -> f64 {
    ((x - mean) / scale).clamp(-8.0, 8.0)
}

/// Summed reference length (metres) of each bone-length group ([`super::figure::BONE_GROUP`]) from
/// the 14 bone lengths `lengths`.
pub fn group_lengths(lengths: &[f64]) -> [f64; NUM_GROUPS] {
    let mut g = [0.0; NUM_GROUPS];
    for (b, l) in lengths.iter().enumerate().take(NUM_BONES) {
        g[BONE_GROUP[b]] += l;
    }
    g
}

impl FactorPrior {
    /// Parses and checks a prior. Errors: [`Error::CorruptData`] for bad JSON, another format
    /// or version, arrays of the wrong size, non-finite values, or spreads / lengths ≤ 0.
    pub fn from_json(text: &str) -> Result<FactorPrior> {
        let p: FactorPrior =
            crate::strict_json::from_str(text).map_err(|e| Error::CorruptData(format!("factor prior: {e}")))?;
        if p.format != FORMAT || p.version != VERSION {
            return Err(Error::CorruptData(format!("factor prior: format {:?} version {}", p.format, p.version)));
        }
        let sizes_ok = p.lengths.len() == NUM_BONES
            && p.mean.len() == NUM_INPUTS
            && p.scale.len() == NUM_INPUTS
            && p.network.inputs() == NUM_INPUTS
            && p.network.outputs() == NUM_GROUPS
            && p.depth_network.inputs() == NUM_INPUTS
            && p.depth_network.outputs() == NUM_JOINTS
            && p.sd.len() == NUM_GROUPS;
        if !sizes_ok {
            return Err(Error::CorruptData("factor prior: arrays of the wrong size".into()));
        }
        p.network.check("factor prior")?;
        p.depth_network.check("factor prior depths")?;
        let finite = p.mean.iter().all(|v| v.is_finite());
        let positive = p.lengths.iter().chain(&p.scale).chain(&p.sd).all(|v| v.is_finite() && *v > 0.0);
        if !finite || !positive {
            return Err(Error::CorruptData("factor prior: non-finite values or non-positive spreads".into()));
        }
        if let Some(b) = &p.bend {
            b.validate()?;
        }
        Ok(p)
    }

    /// The embedded prior, parsed once per process.
    pub fn embedded() -> Result<&'static FactorPrior> {
        static PRIOR: OnceLock<std::result::Result<FactorPrior, String>> = OnceLock::new();
        PRIOR
            .get_or_init(|| FactorPrior::from_json(EMBEDDED_FACTOR_PRIOR).map_err(|e| e.to_string()))
            .as_ref()
            .map_err(|e| Error::CorruptData(e.clone()))
    }

    /// Reads and checks a prior file. Errors: [`Error::Io`], and those of [`Self::from_json`].
    pub fn read(path: &std::path::Path) -> Result<FactorPrior> {
        let text = std::fs::read_to_string(path).map_err(|source| Error::Io { path: path.to_path_buf(), source })?;
        FactorPrior::from_json(&text)
    }

    /// The prior as JSON (one line per array).
    pub fn to_json(&self) -> String {
        serde_json::to_string(self).unwrap_or_default()
    }

    fn lengths_array(&self) -> [f64; NUM_BONES] {
        std::array::from_fn(|b| self.lengths[b])
    }

    /// `s₂` and the standardised inputs of the 2-D joints `j` (`None` as for [`inputs`]).
    fn standardised_inputs(&self, j: &Joints2) -> Option<(f64, Vec<f64>)> {
        let (s2, x) = inputs(j, &self.lengths_array())?;
        Some((s2, (0..NUM_INPUTS).map(|i| standardise(x[i], self.mean[i], self.scale[i])).collect()))
    }

    /// `ln(s₂)` and `ln(s k_g / s₂)` by group (the network's output, bounded).
    pub(crate) fn regress(&self, j: &Joints2) -> Option<(f64, [f64; NUM_GROUPS])> {
        let (s2, z) = self.standardised_inputs(j)?;
        let y = self.network.forward(&z)?;
        let out = std::array::from_fn(|g| if y[g].is_finite() { y[g].clamp(-MAX_LOG, MAX_LOG) } else { 0.0 });
        Some((s2.ln(), out))
    }

    /// The depth hint of the 2-D joints `j` with `weight` ([`DepthHint::weight`]): each joint's
    /// predicted depth toward the camera, px at the image's scale (the network's output times
    /// `s₂`). `None` when a joint is invisible or not finite, the figure has no extent, or the
    /// weight is not finite and > 0.
    pub fn depth_hint(&self, j: &Joints2, weight: f64) -> Option<DepthHint> {
        if !(weight.is_finite() && weight > 0.0) {
            return None;
        }
        let (s2, z) = self.standardised_inputs(j)?;
        let y = self.depth_network.forward(&z)?;
        let depth: [f64; NUM_JOINTS] = std::array::from_fn(|k| s2 * y[k]);
        depth.iter().all(|v| v.is_finite()).then_some(DepthHint { depth, known: [true; NUM_JOINTS], weight })
    }

    /// Predicts each group's image scale `ln(s k_g)` from the 2-D joints `j`, for factors
    /// relative to the reference lengths `lengths` (those of the dictionary in use; the
    /// prediction is converted from the prior's own [`FactorPrior::lengths`] group by group).
    /// `None` when a joint is invisible or not finite, or the figure has no extent (the caller
    /// then falls back to the fixed prior). Always finite otherwise.
    pub fn predict(&self, j: &Joints2, lengths: &[f64; NUM_BONES]) -> Option<Prediction> {
        let (ls2, u) = self.regress(j)?;
        let (own, theirs) = (group_lengths(&self.lengths), group_lengths(lengths));
        let log_scale = std::array::from_fn(|g| {
            let conv = if theirs[g] > 0.0 && own[g] > 0.0 { (own[g] / theirs[g]).ln() } else { 0.0 };
            ls2 + u[g] + conv
        });
        let sd = std::array::from_fn(|g| self.sd[g]);
        if !log_scale.iter().all(|v: &f64| v.is_finite()) {
            return None;
        }
        Some(Prediction { log_scale, sd })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::error::Error;

    #[test]
    fn the_embedded_prior_loads_and_corrupt_files_are_rejected() {
        let p = FactorPrior::embedded().unwrap();
        assert!(p.provenance.contains("train-factor-prior"));
        let mut bad = p.clone();
        bad.network.layers[1].weights.pop();
        assert!(
            matches!(FactorPrior::from_json(&bad.to_json()), Err(Error::CorruptData(m)) if m.contains("wrong size"))
        );
        let mut bad = p.clone();
        bad.sd[0] = 0.0;
        assert!(
            matches!(FactorPrior::from_json(&bad.to_json()), Err(Error::CorruptData(m)) if m.contains("non-positive"))
        );
        let mut bad = p.clone();
        bad.version = 9;
        assert!(
            matches!(FactorPrior::from_json(&bad.to_json()), Err(Error::CorruptData(m)) if m.contains("version 9"))
        );
        let text = p.to_json();
        assert!(matches!(FactorPrior::from_json(&text[..text.len() / 2]), Err(Error::CorruptData(_))));
        assert_eq!(&FactorPrior::from_json(&text).unwrap(), p);
        // The bend prior: present in the embedded file, checked when present, optional.
        assert!(p.bend.is_some());
        let mut bad = p.clone();
        if let Some(b) = bad.bend.as_mut() {
            b.knee.pop();
        }
        assert!(matches!(FactorPrior::from_json(&bad.to_json()), Err(Error::CorruptData(m)) if m.contains("bend")));
        let mut bad = p.clone();
        if let Some(b) = bad.bend.as_mut() {
            b.elbow[3] = -1.0;
        }
        assert!(matches!(FactorPrior::from_json(&bad.to_json()), Err(Error::CorruptData(m)) if m.contains("bend")));
        let without = FactorPrior { bend: None, ..p.clone() };
        assert!(!without.to_json().contains("\"bend\""));
        assert_eq!(FactorPrior::from_json(&without.to_json()).unwrap(), without);
    }

    /// Every array and network of the wrong size is refused ("wrong size"), each on its own;
    /// so are lengths and spreads ≤ 0.
    #[test]
    fn every_array_of_the_wrong_size_is_rejected() {
        let p = FactorPrior::embedded().unwrap();
        let faults: [fn(&mut FactorPrior); 9] = [
            |p| {
                p.lengths.pop();
            },
            |p| {
                p.mean.pop();
            },
            |p| {
                p.scale.pop();
            },
            |p| {
                p.sd.pop();
            },
            |p| p.network.layers[0].inputs -= 1,
            |p| p.network.layers.last_mut().unwrap().outputs -= 1,
            |p| p.depth_network.layers[0].inputs -= 1,
            |p| p.depth_network.layers.last_mut().unwrap().outputs -= 1,
            |p| std::mem::swap(&mut p.network, &mut p.depth_network),
        ];
        for (i, fault) in faults.iter().enumerate() {
            let mut bad = p.clone();
            fault(&mut bad);
            let r = FactorPrior::from_json(&bad.to_json());
            assert!(matches!(&r, Err(Error::CorruptData(m)) if m.contains("wrong size")), "fault {i}: {r:?}");
        }
        let faults: [fn(&mut FactorPrior); 3] = [|p| p.lengths[2] = 0.0, |p| p.scale[5] = -1.0, |p| p.sd[1] = 0.0];
        for (i, fault) in faults.iter().enumerate() {
            let mut bad = p.clone();
            fault(&mut bad);
            let r = FactorPrior::from_json(&bad.to_json());
            assert!(matches!(&r, Err(Error::CorruptData(m)) if m.contains("non-positive")), "fault {i}: {r:?}");
        }
    }

    /// A prediction is converted to the caller's reference lengths group by group: doubling
    /// every length lowers each group's log scale by ln 2; a group of no length is not
    /// converted.
    #[test]
    fn predictions_convert_to_the_callers_reference_lengths() {
        let p = FactorPrior::embedded().unwrap();
        let own: [f64; NUM_BONES] = std::array::from_fn(|b| p.lengths[b]);
        let j = Joints2 {
            xy: std::array::from_fn(|i| [(i * 37 % 11) as f64 * 20.0, (i * 13 % 7) as f64 * 30.0]),
            visible: [true; NUM_JOINTS],
        };
        let base = p.predict(&j, &own).unwrap();
        let doubled = p.predict(&j, &own.map(|l| 2.0 * l)).unwrap();
        for g in 0..NUM_GROUPS {
            assert!((doubled.log_scale[g] - (base.log_scale[g] - 2f64.ln())).abs() < 1e-12, "group {g}");
        }
        assert_eq!(doubled.sd, base.sd);
        let mut headless = own;
        headless[0] = 0.0; // bone 0 is the head group's only bone
        let h = p.predict(&j, &headless).unwrap();
        assert_eq!(h.log_scale, base.log_scale);
    }

    #[test]
    fn predictions_are_finite_or_none_on_bad_input() {
        let p = FactorPrior::embedded().unwrap();
        let lengths: [f64; NUM_BONES] = std::array::from_fn(|b| p.lengths[b]);
        let mut j =
            Joints2 { xy: [[0.0; 2]; crate::skeleton::NUM_JOINTS], visible: [true; crate::skeleton::NUM_JOINTS] };
        assert!(p.predict(&j, &lengths).is_none(), "all joints at one point");
        for (i, q) in j.xy.iter_mut().enumerate() {
            *q = [(i * 37 % 11) as f64 * 1e7, (i * 13 % 7) as f64 * -3.0];
        }
        let e = p.predict(&j, &lengths).unwrap();
        assert!(e.log_scale.iter().chain(&e.sd).all(|v| v.is_finite()));
        let h = p.depth_hint(&j, 0.05).unwrap();
        assert!(h.depth.iter().all(|v| v.is_finite()) && h.weight == 0.05);
        assert!(p.depth_hint(&j, 0.0).is_none() && p.depth_hint(&j, f64::NAN).is_none());
        j.visible[3] = false;
        assert!(p.predict(&j, &lengths).is_none());
        assert!(p.depth_hint(&j, 0.05).is_none());
        j.visible[3] = true;
        j.xy[4][0] = f64::NAN;
        assert!(p.predict(&j, &lengths).is_none());
        assert!(p.depth_hint(&j, 0.05).is_none());
    }

    /// The embedded depth network orders the limbs in depth: on dictionary poses seen by
    /// near-frontal cameras (the views where the image says least about depth), the limbs that
    /// point more than 5 cm toward or away from the viewer get the sign of their depth change
    /// right far more often than chance, and the hint's depths are px at the image's scale.
    #[test]
    fn the_depth_hint_orders_limbs_in_depth() {
        use nalgebra::{Rotation3, Vector3};
        use rand::{Rng, SeedableRng};
        let p = FactorPrior::embedded().unwrap();
        let d = crate::pose::dict_io::embedded().unwrap();
        let limbs = crate::skeleton::LIMB_BONES.map(|b| BONES[b]);
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
        let (mut right, mut total, mut scale_err) = (0, 0, 0.0f64);
        for c in d.exemplars.column_iter().step_by(97) {
            let x = crate::pose::dictionary::vec_to_pose(c.as_slice());
            let yaw: f64 = rng.random_range(-30.0..=30.0);
            let r = Rotation3::from_axis_angle(&Vector3::y_axis(), yaw.to_radians());
            let s = 300.0;
            let cam: Vec<Vector3<f64>> = x.iter().map(|q| r * Vector3::from(*q)).collect();
            let j = Joints2 {
                xy: std::array::from_fn(|k| [s * cam[k].x + 250.0, -s * cam[k].y + 300.0]),
                visible: [true; NUM_JOINTS],
            };
            let h = p.depth_hint(&j, 1.0).unwrap();
            for &(a, b) in &limbs {
                let truth = cam[b].z - cam[a].z;
                if truth.abs() > 0.05 {
                    total += 1;
                    right += usize::from((h.depth[b] - h.depth[a]).signum() == truth.signum());
                    scale_err = scale_err.max(((h.depth[b] - h.depth[a]) / (s * truth)).abs());
                }
            }
        }
        assert!(total > 100, "{total} limbs");
        assert!(right as f64 > 0.85 * total as f64, "{right} of {total}");
        assert!(scale_err < 10.0, "depths not in image px: ratio {scale_err}");
    }
}
