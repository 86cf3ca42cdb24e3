//! Options of the 3-D pose solver and the mapping of the paper's κ to the scale-free form.
//!
//! κ here is relative: the constraint of eq. (3) is
//! `|Σ‖X_i − X_j‖² − Σ l_ij²| ≤ κ · Σ l_ij²`, so κ = 0.05 lets the summed squared bone length
//! deviate by 5 % from the dictionary's. The paper's κ = 8 is in CMU motion-capture units
//! (1 unit = 1/0.45 inch = 56.44 mm) on a CMU-sized skeleton; [`kappa_from_paper`] converts it
//! with this dictionary's Σ l² for a 1.75 m person: κ_rel = 8 · (0.05644 m)² / Σ l² (≈ 0.02).

use crate::error::{ensure_finite, Error, Result};

/// Most bases the solver may choose (also the size of the C API's basis arrays).
pub const MAX_BASES: usize = 32;

/// Length of the CMU motion-capture unit, metres (1/0.45 inch).
pub const CMU_UNIT_M: f64 = 0.0254 / 0.45;

/// The paper's κ, CMU units squared.
pub const PAPER_KAPPA: f64 = 8.0;

/// The paper's α (eq. 4).
pub const PAPER_ALPHA: f64 = 0.8;

/// Largest accepted relative κ.
pub const MAX_KAPPA: f64 = 10.0;

/// Most nearest-neighbour starts ([`PoseOptions::starts`]).
pub const MAX_STARTS: usize = 32;

/// Most limb candidates ([`PoseOptions::limb_candidates`]).
pub const MAX_LIMB_CANDIDATES: usize = 4096;

/// Largest accepted blend temperature ([`PoseOptions::blend`]), px².
pub const MAX_BLEND: f64 = 1.0e6;

/// Largest accepted stopping tolerance, pixels.
pub const MAX_TOLERANCE: f64 = 1.0e4;

/// Converts a κ in CMU units² (the paper's κ = 8) to the relative κ of [`PoseOptions::kappa`],
/// given the dictionary's Σ l² in m².
pub fn kappa_from_paper(kappa_cmu: f64, sum_sq_lengths_m2: f64) -> f64 {
    kappa_cmu * CMU_UNIT_M * CMU_UNIT_M / sum_sq_lengths_m2
}

/// What α of eq. (4) pulls the pursuit's camera rotation toward.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RotationTarget {
    /// The identity, as in the paper's eq. (4): a frontal, level view (pulls yaw, pitch and roll).
    Identity,
    /// The fitted rotation with its pitch removed: writing R = Rz(roll)·Rx(pitch)·Ry(yaw) (the
    /// renderer's camera angles), the target is Rz(roll)·Ry(yaw). Only the pitch — the angle a
    /// weak-perspective view of a nearly planar figure barely observes, and which otherwise tips
    /// the body toward or away from the viewer — is pulled toward 0; the turn of the figure
    /// (yaw) and the in-image tilt (roll) stay free.
    Level,
}

impl RotationTarget {
    /// The name used by the CLI and the pose JSON (`identity`, `level`).
    pub fn name(self) -> &'static str {
        match self {
            RotationTarget::Identity => "identity",
            RotationTarget::Level => "level",
        }
    }

    /// Parses [`RotationTarget::name`]. Errors: [`Error::OutOfRange`] naming the value.
    pub fn parse(s: &str) -> Result<RotationTarget> {
        match s {
            "identity" => Ok(RotationTarget::Identity),
            "level" => Ok(RotationTarget::Level),
            _ => Err(Error::OutOfRange { name: "alpha_target", detail: format!("{s:?} (expected identity or level)") }),
        }
    }
}

/// Options of [`super::estimate_pose`]. Plain data; validated by [`PoseOptions::validate`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PoseOptions {
    /// Relative limb-length tolerance κ ≥ 0 (0 = equality, Ramakrishna et al.), ≤ [`MAX_KAPPA`].
    pub kappa: f64,
    /// Pull of the camera rotation toward [`PoseOptions::alpha_target`] in eq. (4), in [0, 1]
    /// (0 = none). Acts in the pursuit's camera steps (the refinement starts from them).
    pub alpha: f64,
    /// What α pulls toward (the paper: [`RotationTarget::Identity`]).
    pub alpha_target: RotationTarget,
    /// One scale for both image axes (sx = sy, a camera with square pixels) in the camera fit
    /// and the refinement; `false` = eq. (1)'s independent sx and sy.
    pub equal_scales: bool,
    /// Most bases to choose, 0..=[`MAX_BASES`] (0 = the mean pose with a fitted camera).
    pub max_bases: usize,
    /// Stop adding bases once the reprojection RMS is at most this many pixels (≥ 0).
    pub tolerance: f64,
    /// Run the joint Levenberg–Marquardt refinement after the pursuit.
    pub refine: bool,
    /// Weight prior, metres in [0, 1]: adds residuals `s̄ · prior · w_k / σ_k` (s̄ the figure's
    /// px per metre, σ_k the basis spread) — a Gaussian prior on the weights with the 2-D
    /// error taken as `prior` metres at the figure's scale. 0 = the paper's eq. (3) exactly.
    pub prior: f64,
    /// Nearest-neighbour starts, 0..=[`MAX_STARTS`]: run the pursuit from each of this many
    /// exemplar poses that best explain the 2-D joints and keep the result with the lowest
    /// objective; 0 = from the mean pose μ (the paper). Ignored for a dictionary without
    /// exemplars.
    pub starts: usize,
    /// Limb recomposition of exemplar starts, 0..=[`MAX_LIMB_CANDIDATES`]: each limb of a
    /// start may come from any of this many exemplars that best explain the whole figure
    /// (affine-camera ranking); 0 = starts are whole exemplars. Used only when `starts` > 0.
    pub limb_candidates: usize,
    /// Blend temperature τ, px² per visible joint, in [0, [`MAX_BLEND`]]: the hypotheses of
    /// the exemplar starts are averaged with weights exp(−Δobjective / (τ V))
    /// ([`super::blend`]); 0 = return the single best. Used only when `starts` > 1.
    pub blend: f64,
    /// Free-joint refinement ([`super::joint_fit`]), metres in [0, 1]: the expected error of a
    /// 2-D joint, as a length at the figure's scale (a 1.75 m person). The last step then lets
    /// every joint leave the dictionary's span, trading the 2-D fit against staying near the
    /// dictionary pose, with the bone lengths kept. 0 = off (the pose of eq. 3 as solved).
    pub joint_noise: f64,
    /// Estimate the drawn proportions (per-group bone-length factors, [`super::figure`]) with
    /// the pose: a second solve on the 2-D joints unstylised by factors estimated from the
    /// first (about twice the time). `false` = the dictionary's proportions (factors 1).
    pub proportions: bool,
    /// The standing prior of the free-joint step ([`super::plausibility`]): for a figure the
    /// 2-D joints show standing on both feet, an upright torso, the head over the neck and both
    /// ankles under the pelvis at one height. Needs `joint_noise` > 0.
    pub standing_prior: bool,
    /// Knee limits of the free-joint step ([`super::plausibility::unbend_knees`]): knees bent
    /// backwards are flipped in depth. Needs `joint_noise` > 0.
    pub knee_limits: bool,
    /// The learned factor prior ([`super::factor_prior`], `assets/factor_prior.json`): the
    /// factors' prior is predicted from the 2-D joints instead of 0 ± a fixed spread. Needs
    /// `proportions`; `false` = the fixed prior ([`super::figure::PRIOR_SD`]).
    pub factor_prior: bool,
    /// Weight of the learned joints' depths ([`super::factor_prior::FactorPrior::depth_hint`]),
    /// in [0, [`MAX_DEPTH_PRIOR`]]: px² of depth residual per px² of reprojection residual where
    /// the solver chooses between readings ([`super::depth_hint`]), used when the caller gives no
    /// image cue's depths; 0 = off.
    pub depth_prior: f64,
    /// Spread, metres, of the free-joint step's pull of every bone's depth change (camera
    /// frame) toward the learned depths' ([`super::joint_fit::Priors::depths`]), in
    /// [0, 1]; 0 = off. Applies where the learned depths do ([`PoseOptions::depth_prior`] > 0,
    /// not for a figure the standing prior takes as standing), with or without an image cue.
    pub learned_depth_sd: f64,
    /// Relative spread of each bone's length in the free-joint step ([`super::joint_fit`]), in
    /// [0, 1]: the lengths are unknowns, log-normal about the estimate's, the left and right
    /// limbs' pulled equal; 0 = the estimate's lengths kept exactly. Needs `joint_noise` > 0.
    pub bone_length_sd: f64,
    /// Spread, metres, of the free-joint step's pull of the knees', ankles', elbows' and
    /// wrists' depths (camera frame) toward the estimate's, in [0, 1] (the other joints':
    /// [`super::joint_fit::SIGMA_3D`]); 0 = that of the other joints. Not for a figure the
    /// standing prior takes as standing (every depth is then freer).
    pub limb_depth_sd: f64,
    /// Weight of the learned bend prior of the knees and elbows in the free-joint step
    /// ([`super::bend_prior`], from `assets/factor_prior.json`), in [0, [`MAX_BEND_PRIOR`]]:
    /// 1 = its learned costs (−2 ln p); 0 = off. The default 0.5 was chosen on the validation
    /// clips (docs/benchmarks-history.md, "Uncertain bone lengths and a learned bend prior").
    pub bend_prior: f64,
    /// Straight limbs ([`super::straighten`]): the last step straightens the arms and legs
    /// drawn straight that are bent at most [`super::straighten::MAX_BEND_DEG`] in depth (the
    /// drawn proportions of the two bones absorb what the bend did). Off by default: it trades
    /// limb-direction error on held-out motion for straight limbs.
    pub straight_limbs: bool,
}

/// Largest [`PoseOptions::depth_prior`].
pub const MAX_DEPTH_PRIOR: f64 = 10.0;

/// Largest [`PoseOptions::bend_prior`].
pub const MAX_BEND_PRIOR: f64 = 10.0;

impl Default for PoseOptions {
    /// The library default (docs/benchmarks.md, "3-D pose"): κ = 0.05, α = 0.8 (the paper's)
    /// toward the level target (the pitch pulled to 0; the paper's identity target pulls the
    /// yaw too), equal scales, up to 4 bases, 0.5 px, refined, prior 0.1 m,
    /// 12 exemplar starts recomposed from 64 limb candidates, blended at τ = 30 px² per joint,
    /// then the free-joint refinement at 0.014 m (4 px on a 500-px figure), with the proportions
    /// estimated under the learned factor prior and the learned depths weighted 0.05 (and pulling
    /// the free-joint step's bone depths at 0.05 m); in the free-joint step each bone's length
    /// uncertain at 5 %, the limb joints' depths at 0.08 m and the learned bend prior at weight 0.5.
    fn default() -> Self {
        PoseOptions {
            kappa: 0.05,
            alpha: 0.8,
            alpha_target: RotationTarget::Level,
            equal_scales: true,
            max_bases: 4,
            tolerance: 0.5,
            refine: true,
            prior: 0.1,
            starts: 12,
            limb_candidates: 64,
            blend: 30.0,
            joint_noise: 0.014,
            proportions: true,
            standing_prior: true,
            knee_limits: true,
            factor_prior: true,
            depth_prior: 0.05,
            learned_depth_sd: 0.05,
            bone_length_sd: 0.05,
            limb_depth_sd: 0.08,
            bend_prior: 0.5,
            straight_limbs: false,
        }
    }
}

impl PoseOptions {
    /// Checks every field: finite and within its documented range.
    pub fn validate(&self) -> Result<()> {
        ensure_finite("kappa", self.kappa)?;
        ensure_finite("alpha", self.alpha)?;
        ensure_finite("tolerance", self.tolerance)?;
        ensure_finite("prior", self.prior)?;
        ensure_finite("blend", self.blend)?;
        ensure_finite("joint_noise", self.joint_noise)?;
        ensure_finite("depth_prior", self.depth_prior)?;
        ensure_finite("learned_depth_sd", self.learned_depth_sd)?;
        ensure_finite("bone_length_sd", self.bone_length_sd)?;
        ensure_finite("limb_depth_sd", self.limb_depth_sd)?;
        ensure_finite("bend_prior", self.bend_prior)?;
        let range = |name: &'static str, detail: String| Err(Error::OutOfRange { name, detail });
        if !(0.0..=MAX_KAPPA).contains(&self.kappa) {
            return range("kappa", format!("{} is not in [0, {MAX_KAPPA}]", self.kappa));
        }
        if !(0.0..=1.0).contains(&self.alpha) {
            return range("alpha", format!("{} is not in [0, 1]", self.alpha));
        }
        if self.max_bases > MAX_BASES {
            return range("max_bases", format!("{} is not in [0, {MAX_BASES}]", self.max_bases));
        }
        if !(0.0..=MAX_TOLERANCE).contains(&self.tolerance) {
            return range("tolerance", format!("{} px is not in [0, {MAX_TOLERANCE}]", self.tolerance));
        }
        if self.starts > MAX_STARTS {
            return range("starts", format!("{} is not in [0, {MAX_STARTS}]", self.starts));
        }
        if self.limb_candidates > MAX_LIMB_CANDIDATES {
            return range("limb_candidates", format!("{} is not in [0, {MAX_LIMB_CANDIDATES}]", self.limb_candidates));
        }
        if !(0.0..=MAX_BLEND).contains(&self.blend) {
            return range("blend", format!("{} px² is not in [0, {MAX_BLEND}]", self.blend));
        }
        if !(0.0..=1.0).contains(&self.prior) {
            return range("prior", format!("{} m is not in [0, 1]", self.prior));
        }
        if !(0.0..=1.0).contains(&self.joint_noise) {
            return range("joint_noise", format!("{} m is not in [0, 1]", self.joint_noise));
        }
        if !(0.0..=MAX_DEPTH_PRIOR).contains(&self.depth_prior) {
            return range("depth_prior", format!("{} is not in [0, {MAX_DEPTH_PRIOR}]", self.depth_prior));
        }
        if !(0.0..=1.0).contains(&self.learned_depth_sd) {
            return range("learned_depth_sd", format!("{} m is not in [0, 1]", self.learned_depth_sd));
        }
        if !(0.0..=1.0).contains(&self.bone_length_sd) {
            return range("bone_length_sd", format!("{} is not in [0, 1]", self.bone_length_sd));
        }
        if !(0.0..=1.0).contains(&self.limb_depth_sd) {
            return range("limb_depth_sd", format!("{} m is not in [0, 1]", self.limb_depth_sd));
        }
        if !(0.0..=MAX_BEND_PRIOR).contains(&self.bend_prior) {
            return range("bend_prior", format!("{} is not in [0, {MAX_BEND_PRIOR}]", self.bend_prior));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn validation_names_the_bad_option() {
        PoseOptions::default().validate().unwrap();
        let bad = [
            PoseOptions { kappa: f64::NAN, ..Default::default() },
            PoseOptions { kappa: -0.1, ..Default::default() },
            PoseOptions { alpha: 1.5, ..Default::default() },
            PoseOptions { max_bases: 33, ..Default::default() },
            PoseOptions { tolerance: f64::INFINITY, ..Default::default() },
            PoseOptions { prior: -1.0, ..Default::default() },
            PoseOptions { starts: 33, ..Default::default() },
            PoseOptions { limb_candidates: 5000, ..Default::default() },
            PoseOptions { blend: -1.0, ..Default::default() },
            PoseOptions { blend: f64::NAN, ..Default::default() },
            PoseOptions { joint_noise: -0.01, ..Default::default() },
            PoseOptions { joint_noise: f64::INFINITY, ..Default::default() },
            PoseOptions { depth_prior: -0.1, ..Default::default() },
            PoseOptions { depth_prior: f64::NAN, ..Default::default() },
            PoseOptions { depth_prior: 11.0, ..Default::default() },
            PoseOptions { learned_depth_sd: -0.01, ..Default::default() },
            PoseOptions { learned_depth_sd: f64::NAN, ..Default::default() },
            PoseOptions { bone_length_sd: -0.01, ..Default::default() },
            PoseOptions { bone_length_sd: f64::NAN, ..Default::default() },
            PoseOptions { limb_depth_sd: 1.5, ..Default::default() },
            PoseOptions { limb_depth_sd: f64::INFINITY, ..Default::default() },
            PoseOptions { bend_prior: -1.0, ..Default::default() },
            PoseOptions { bend_prior: 11.0, ..Default::default() },
        ];
        for o in bad {
            assert!(o.validate().is_err(), "{o:?}");
        }
        assert_eq!(RotationTarget::parse("level").unwrap(), RotationTarget::Level);
        assert_eq!(RotationTarget::parse(RotationTarget::Identity.name()).unwrap(), RotationTarget::Identity);
        assert!(matches!(RotationTarget::parse("frontal"), Err(Error::OutOfRange { name: "alpha_target", .. })));
        // CMU: 8 unit² on a skeleton with Σ l² = 436 unit² is 1.8 %.
        let k = kappa_from_paper(8.0, 436.0 * CMU_UNIT_M * CMU_UNIT_M);
        assert!((k - 8.0 / 436.0).abs() < 1e-12);
    }
}
