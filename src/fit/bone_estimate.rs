//! A deterministic estimate of the renderer's five proportion factors (legs, arms, shoulders,
//! head, torso; [`Proportions`]) from the 2-D joints, the estimated 3-D pose's bone directions
//! and the camera, relative to a reference rest skeleton (the gender's mean).
//!
//! Under a weak-perspective camera the image length of bone `b` is `l_b = s · k_g · L_b · p_b`:
//! `s` the image scale (pixels per metre), `k_g` the factor of the bone's group, `L_b` the
//! reference bone length and `p_b = |diag(ax, ay) P d_b|` its foreshortening (`P` the first two
//! rows of the camera rotation, `d_b` the posed unit direction, `ax, ay` the camera's scales
//! divided by their geometric mean). In logs every usable bone gives one linear observation
//! `ln(l_b / (L_b p_b)) = u + z_g` with `u = ln s` and `z_g = ln k_g`.
//!
//! **Identifiability.** The overall scale `u` cannot be told from a common factor of all bones.
//! The renderer leaves exactly one group at factor 1, the pelvis→hip bones, so they are the
//! reference: with both hips usable and `ridge = 0` the five factors are recovered exactly (the
//! unit tests check it). Hips are short and often badly posed, so by default a ridge
//! `ridge · Σ z_g²` (a Gaussian prior on the log factors, in units of the squared relative error
//! of an unforeshortened bone as long as the reference torso) keeps the system well posed when
//! the hips are missing or foreshortened and shrinks weakly observed groups toward 1.
//!
//! **Robustness.** Each observation is weighted by `(L_b p_b / L_torso)²` (the squared
//! expected image length: relative pixel error falls with length, and foreshortened bones carry
//! the pose's depth error); bones with `p_b <` [`EstimateOptions::min_foreshortening`] or a
//! missing end joint are dropped; groups without a usable bone stay at 1 and are reported as
//! unobserved; the factors are clamped to `exp(±`[`EstimateOptions::max_log`]`)`.

use nalgebra::{Matrix6, Vector3, Vector6};

use crate::body::proportions::Proportions;
use crate::camera::WeakPerspective;
use crate::error::{ensure_finite, Error, Result};
use crate::skeleton::{joint, Joints2, Joints3, BONES, NUM_BONES};

/// Group of each canonical bone in [`Proportions`] order (0 legs, 1 arms, 2 shoulders, 3 head,
/// 4 torso); `None` for the pelvis→hip bones, which the renderer never scales (the reference).
pub const BONE_GROUP: [Option<usize>; NUM_BONES] = [
    Some(3),
    Some(2),
    Some(1),
    Some(1),
    Some(2),
    Some(1),
    Some(1),
    Some(4),
    None,
    Some(0),
    Some(0),
    None,
    Some(0),
    Some(0),
];

/// Options of [`estimate_proportions`], with documented defaults.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EstimateOptions {
    /// Bones whose foreshortening `p_b` (1 = in the image plane) is below this are dropped
    /// (default 0.4: more than about 66° out of the image plane). In 0..1.
    pub min_foreshortening: f64,
    /// Ridge on the log factors (see the module doc; default 0.1, i.e. a relative bone-length
    /// error of about 5% against a prior sd of about 0.16 on each log factor); ≥ 0. With 0 the
    /// hips must be usable.
    pub ridge: f64,
    /// Log factors are clamped to ±this (default 0.4: factors 0.67..1.49, inside the renderer's
    /// accepted 0.5..=2.0 and the SIR's ±0.5). In 0..=0.69.
    pub max_log: f64,
}

impl Default for EstimateOptions {
    fn default() -> Self {
        EstimateOptions { min_foreshortening: 0.4, ridge: 0.1, max_log: 0.4 }
    }
}

/// The estimate of [`estimate_proportions`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ProportionEstimate {
    /// Log factors (legs, arms, shoulders, head, torso), clamped; 0 for unobserved groups.
    pub log_factors: [f64; 5],
    /// Whether each group had at least one usable bone.
    pub observed: [bool; 5],
    /// Fitted image scale `s`, pixels per reference metre (geometric mean of the camera axes).
    pub scale: f64,
    /// Bones used.
    pub bones_used: usize,
}

impl ProportionEstimate {
    /// The factors as renderer proportions (`exp` of the log factors).
    pub fn proportions(&self) -> Proportions {
        super::proportions::proportions_of(&self.log_factors)
    }
}

impl EstimateOptions {
    /// Checks the ranges documented on the fields.
    pub fn validate(&self) -> Result<()> {
        ensure_finite("min foreshortening", self.min_foreshortening)?;
        ensure_finite("proportion ridge", self.ridge)?;
        ensure_finite("proportion max log", self.max_log)?;
        if !(0.0..1.0).contains(&self.min_foreshortening) {
            return Err(Error::OutOfRange {
                name: "min foreshortening",
                detail: format!("{} not in 0..1", self.min_foreshortening),
            });
        }
        if self.ridge < 0.0 {
            return Err(Error::OutOfRange { name: "proportion ridge", detail: format!("{} must be >= 0", self.ridge) });
        }
        if !(0.0..=0.69).contains(&self.max_log) {
            return Err(Error::OutOfRange {
                name: "proportion max log",
                detail: format!("{} not in 0..=0.69", self.max_log),
            });
        }
        Ok(())
    }
}

fn v3(j: &Joints3, k: usize) -> Vector3<f64> {
    Vector3::from(j[k])
}

/// Estimates the five proportion factors of the figure whose visible 2-D joints are `joints2d`
/// (pixels) relative to the reference rest skeleton `rest` (metres), given the estimated 3-D
/// pose `pose` (metres, model frame; only its bone directions are used) and the camera (only
/// its rotation and the ratio of its scales are used). See the module doc.
///
/// Errors: non-finite or zero-length bones of `rest` or `pose` ([`Error::NonFinite`],
/// [`Error::DegenerateBone`]); invalid options or camera; [`Error::Degenerate`] when no bone is
/// usable, or with `ridge = 0` when the hips are not usable (the scale is then unidentifiable).
pub fn estimate_proportions(
    rest: &Joints3,
    pose: &Joints3,
    camera: &WeakPerspective,
    joints2d: &Joints2,
    options: &EstimateOptions,
) -> Result<ProportionEstimate> {
    options.validate()?;
    camera.validate()?;
    crate::body::ik::check_joints("rest joint", rest)?;
    crate::body::ik::check_joints("pose joint", pose)?;
    let mean_scale = (camera.sx * camera.sy).sqrt();
    let (ax, ay) = (camera.sx / mean_scale, camera.sy / mean_scale);
    let torso = (v3(rest, joint::NECK) - v3(rest, joint::PELVIS)).norm();
    let mut normal = Matrix6::<f64>::zeros();
    let mut rhs = Vector6::<f64>::zeros();
    let mut observed = [false; 5];
    let mut hips = 0;
    let mut used = 0;
    for (b, &(s, c)) in BONES.iter().enumerate() {
        if !(joints2d.visible[s] && joints2d.visible[c]) {
            continue;
        }
        let (q0, q1) = (joints2d.xy[s], joints2d.xy[c]);
        for v in [q0[0], q0[1], q1[0], q1[1]] {
            ensure_finite("2-D joint", v)?;
        }
        let image_len = ((q1[0] - q0[0]).powi(2) + (q1[1] - q0[1]).powi(2)).sqrt();
        let rest_len = (v3(rest, c) - v3(rest, s)).norm();
        let d = (v3(pose, c) - v3(pose, s)).normalize();
        let rd = camera.r * d;
        let p = (ax * rd.x).hypot(ay * rd.y);
        if p < options.min_foreshortening || image_len <= 0.0 {
            continue;
        }
        let y = (image_len / (rest_len * p)).ln();
        let w = (rest_len * p / torso).powi(2);
        let mut a = Vector6::<f64>::zeros();
        a[0] = 1.0;
        match BONE_GROUP[b] {
            Some(g) => {
                a[1 + g] = 1.0;
                observed[g] = true;
            }
            None => hips += 1,
        }
        normal += w * a * a.transpose();
        rhs += w * y * a;
        used += 1;
    }
    if used == 0 {
        return Err(Error::Degenerate(
            "proportion estimate: no bone with both joints visible and within the foreshortening limit".into(),
        ));
    }
    if options.ridge == 0.0 && hips == 0 {
        return Err(Error::Degenerate(
            "proportion estimate: with ridge 0 the pelvis->hip bones (the reference) must be usable".into(),
        ));
    }
    for g in 0..5 {
        // Unobserved groups are pinned to 0 so the system stays regular.
        normal[(1 + g, 1 + g)] += if observed[g] { options.ridge } else { 1.0 };
    }
    let x = normal
        .lu()
        .solve(&rhs)
        .ok_or_else(|| Error::Degenerate("proportion estimate: singular normal equations".into()))?;
    let mut log_factors = [0.0; 5];
    for g in 0..5 {
        log_factors[g] = if observed[g] { x[1 + g].clamp(-options.max_log, options.max_log) } else { 0.0 };
    }
    Ok(ProportionEstimate { log_factors, observed, scale: x[0].exp(), bones_used: used })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::body::proportions::apply_proportions;
    use crate::body::BodyModel;
    use crate::body::Gender;
    use crate::skeleton::NUM_JOINTS;
    use nalgebra::Rotation3;

    /// Projects `joints` (all visible).
    fn project(camera: &WeakPerspective, joints: &Joints3) -> Joints2 {
        let xy: Vec<[f64; 2]> = joints.iter().map(|j| camera.project(&Vector3::from(*j))).collect();
        Joints2 { xy: xy.try_into().unwrap(), visible: [true; NUM_JOINTS] }
    }

    /// The renderer's proportions applied to the mean skeleton, posed by rotating the whole
    /// body (bone directions of the rest skeleton turned), viewed by a yawed camera.
    fn scene(props: &Proportions) -> (Joints3, Joints3, WeakPerspective) {
        let model = BodyModel::embedded().unwrap();
        let space = model.space(Gender::Female);
        let rest = *space.mean_joints();
        let (_, truth) = apply_proportions(space.mean(), &rest, model.skin_weights(), props).unwrap();
        let r = *Rotation3::from_euler_angles(0.1, 0.5, 0.05).matrix();
        let camera = WeakPerspective { sx: 310.0, sy: 290.0, r, t: [250.0, 260.0] };
        (rest, truth, camera)
    }

    #[test]
    fn recovers_renderer_factors_exactly_without_ridge() {
        let props = Proportions { legs: 1.22, arms: 0.93, shoulders: 1.31, head: 0.8, torso: 1.06 };
        let (rest, truth, camera) = scene(&props);
        let j2 = project(&camera, &truth);
        let o = EstimateOptions { ridge: 0.0, ..EstimateOptions::default() };
        let e = estimate_proportions(&rest, &truth, &camera, &j2, &o).unwrap();
        let p = e.proportions();
        for (got, want) in [(p.legs, 1.22), (p.arms, 0.93), (p.shoulders, 1.31), (p.head, 0.8), (p.torso, 1.06)] {
            assert!((got - want).abs() < 1e-9, "{got} vs {want}");
        }
        assert!((e.scale - (310.0f64 * 290.0).sqrt()).abs() < 1e-6, "{}", e.scale);
        assert_eq!(e.observed, [true; 5]);
        // A pose with the reference's directions gives the same factors (only directions count).
        let e2 = estimate_proportions(&rest, &rest, &camera, &j2, &o).unwrap();
        assert!((e2.log_factors[0] - 1.22f64.ln()).abs() < 1e-9);
    }

    #[test]
    fn missing_and_foreshortened_bones_are_dropped_and_ridge_shrinks() {
        let props = Proportions { legs: 1.2, arms: 1.1, shoulders: 1.0, head: 1.0, torso: 0.95 };
        let (rest, truth, camera) = scene(&props);
        let mut j2 = project(&camera, &truth);
        // Both wrists missing: the forearms drop, the upper arms still give the arms factor.
        j2.visible[joint::R_WRIST] = false;
        j2.visible[joint::L_WRIST] = false;
        // A corrupted head joint far off while the head is pointed along the view axis in the
        // pose: the head bone is dropped as foreshortened and the head group is unobserved.
        j2.xy[joint::HEAD] = [0.0, 0.0];
        let mut pose = truth;
        let toward_viewer = camera.r.transpose() * Vector3::new(0.0, 0.0, 1.0);
        pose[joint::HEAD] = (Vector3::from(pose[joint::NECK]) + 0.2 * toward_viewer).into();
        let o = EstimateOptions { ridge: 0.0, ..EstimateOptions::default() };
        let e = estimate_proportions(&rest, &pose, &camera, &j2, &o).unwrap();
        assert_eq!(e.observed, [true, true, true, false, true]);
        assert_eq!(e.bones_used, NUM_BONES - 3);
        assert_eq!(e.log_factors[3], 0.0);
        assert!((e.log_factors[1] - 1.1f64.ln()).abs() < 1e-9 && (e.log_factors[0] - 1.2f64.ln()).abs() < 1e-9);
        // A ridge shrinks the factors toward 1 but keeps their order.
        let er = estimate_proportions(&rest, &pose, &camera, &j2, &EstimateOptions { ridge: 0.5, ..o }).unwrap();
        assert!(er.log_factors[0] > 0.0 && er.log_factors[0] < e.log_factors[0]);
        assert!(er.log_factors[1] > 0.0 && er.log_factors[1] < e.log_factors[1]);
        // Clamping.
        let big = Proportions { legs: 1.9, ..Proportions::default() };
        let (rest, truth, camera) = scene(&big);
        let e = estimate_proportions(&rest, &truth, &camera, &project(&camera, &truth), &o).unwrap();
        assert_eq!(e.log_factors[0], 0.4);
    }

    #[test]
    fn unidentifiable_and_bad_inputs_are_specific_errors() {
        let (rest, truth, camera) = scene(&Proportions::default());
        let mut j2 = project(&camera, &truth);
        j2.visible[joint::PELVIS] = false;
        let o = EstimateOptions { ridge: 0.0, ..EstimateOptions::default() };
        assert!(matches!(estimate_proportions(&rest, &truth, &camera, &j2, &o), Err(Error::Degenerate(_))));
        // With the default ridge the same input is solvable (scale from the ridge).
        let e = estimate_proportions(&rest, &truth, &camera, &j2, &EstimateOptions::default()).unwrap();
        assert!(e.log_factors.iter().all(|z| z.abs() < 1e-6), "{:?}", e.log_factors);
        j2.visible = [false; NUM_JOINTS];
        assert!(matches!(
            estimate_proportions(&rest, &truth, &camera, &j2, &EstimateOptions::default()),
            Err(Error::Degenerate(_))
        ));
        let mut j2 = project(&camera, &truth);
        j2.xy[3][0] = f64::NAN;
        assert!(matches!(
            estimate_proportions(&rest, &truth, &camera, &j2, &EstimateOptions::default()),
            Err(Error::NonFinite { .. })
        ));
        let bad = EstimateOptions { min_foreshortening: 1.5, ..EstimateOptions::default() };
        assert!(matches!(
            estimate_proportions(&rest, &truth, &camera, &project(&camera, &truth), &bad),
            Err(Error::OutOfRange { .. })
        ));
    }
}
