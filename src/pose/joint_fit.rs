//! Free-joint refinement ([`super::PoseOptions::joint_noise`]): the last step of
//! [`super::estimate_pose`], which lets every joint leave the span of the dictionary.
//!
//! A dictionary pose with a few bases cannot reproduce a motion no training clip covers (a
//! high kick keeps 12 px RMS of reprojection error on a 500-px figure at σ = 0). With the
//! camera fixed, this step moves the 15 joints Y (camera frame, Y = R X) to minimise
//!
//! `Σ_visible ‖π(Y_j) − u_j‖² / σ_px² + Σ_j ‖Y_j − Ŷ_j‖² / σ_3d² + Σ_bones (‖Y_c − Y_p‖ − l̂_cp)² / σ_len²`
//!
//! plus, with the plausibility priors ([`Priors`], [`super::plausibility`]) for a standing
//! figure, its linear standing residuals (the ankles under the pelvis only when the estimate's
//! stride in depth is at most [`STANDING_MAX_STRIDE`]), the depth part of the second term then
//! at [`SIGMA_DEPTH_STANDING`]; knees left bent backwards are flipped in depth at the end. With
//! the learned depths ([`Priors::depths`], from the 2-D joints alone), every bone's depth change
//! `Y_c.z − Y_p.z` is also pulled toward theirs at [`Priors::depth_sd`]:
//! `Σ_bones (Y_c.z − Y_p.z − (d_c − d_p) / s)² / σ_d²` (s the camera's scale).
//!
//! with Ŷ and l̂ the estimate's joints and bone lengths, σ_px = `joint_noise` × the camera's
//! scale (so the trade-off does not depend on the image size), σ_3d = [`SIGMA_3D`] and
//! σ_len = [`SIGMA_LEN`]. Under weak perspective the image fixes each bone's in-plane offset
//! and its length fixes |depth|; the prior keeps each depth on the estimate's side and absorbs
//! 2-D noise. Gauss–Newton on the 45 × 45 normal equations with Levenberg damping, at most
//! [`ITERATIONS`] steps from the estimate; then every bone is set back to its exact estimated
//! length along its new direction (rebuilt from the pelvis outward), so Σ‖X_i − X_j‖² — the
//! limb-length constraint of eq. (3) — is exactly the estimate's.

use nalgebra::{SMatrix, SVector, Vector3};

use super::dictionary::{pose_to_vec, vec_to_pose, with_bone_lengths};
use super::plausibility::{
    standing_in_image, standing_residuals, stride_in_depth, unbend_knees, LinearResidual, SIGMA_DEPTH_STANDING,
    STANDING_MAX_STRIDE,
};
use super::problem::Problem;
use super::pursuit::PoseEstimate;
use crate::camera::WeakPerspective;
use crate::skeleton::{BONES, NUM_BONES, NUM_JOINTS};

/// Spread of a joint about the dictionary estimate, metres.
pub const SIGMA_3D: f64 = 0.02;
/// Spread of a bone length about the estimate's during the iterations, metres.
pub const SIGMA_LEN: f64 = 0.003;
/// Most Gauss–Newton steps.
pub const ITERATIONS: usize = 8;

type Joints = [Vector3<f64>; NUM_JOINTS];

/// The weighted least-squares problem of the module doc in the camera frame.
struct JointProblem<'p> {
    prob: &'p Problem<'p>,
    /// The estimate's camera (its scales and translation apply to camera-frame joints).
    cam: &'p WeakPerspective,
    y0: Joints,
    len: [f64; NUM_BONES],
    /// 1/σ² of the image, prior and bone-length terms.
    wp: f64,
    wd: f64,
    wl: f64,
    /// 1/σ² of the prior along the viewing direction (camera z; `wd` unless standing).
    wz: f64,
    /// Plausibility residuals ([`super::plausibility`]).
    linear: Vec<LinearResidual>,
}

impl JointProblem<'_> {
    fn image_residual(&self, y: &Vector3<f64>, j: usize) -> [f64; 2] {
        let c = self.cam;
        [c.sx * y.x + c.t[0] - self.prob.uv[j][0], -c.sy * y.y + c.t[1] - self.prob.uv[j][1]]
    }

    fn cost(&self, y: &Joints) -> f64 {
        let image: f64 =
            self.prob.vis.iter().map(|&j| self.image_residual(&y[j], j).iter().map(|r| r * r).sum::<f64>()).sum();
        let prior: f64 = y
            .iter()
            .zip(&self.y0)
            .map(|(a, b)| self.wd * (a - b).xy().norm_squared() + self.wz * (a.z - b.z).powi(2))
            .sum();
        let bones: f64 = BONES.iter().zip(&self.len).map(|(&(p, c), l)| ((y[c] - y[p]).norm() - l).powi(2)).sum();
        let linear: f64 = self.linear.iter().map(|r| r.w * (r.c.dot(&(y[r.a] - y[r.b])) - r.t).powi(2)).sum();
        self.wp * image + prior + self.wl * bones + linear
    }

    /// Gauss–Newton normal equations (JᵀJ, Jᵀr) at `y`.
    fn normal(&self, y: &Joints) -> (SMatrix<f64, 45, 45>, SVector<f64, 45>) {
        let mut h = SMatrix::<f64, 45, 45>::zeros();
        let mut g = SVector::<f64, 45>::zeros();
        for &j in &self.prob.vis {
            let r = self.image_residual(&y[j], j);
            let (sx, sy) = (self.cam.sx, self.cam.sy);
            h[(3 * j, 3 * j)] += self.wp * sx * sx;
            h[(3 * j + 1, 3 * j + 1)] += self.wp * sy * sy;
            g[3 * j] += self.wp * sx * r[0];
            g[3 * j + 1] -= self.wp * sy * r[1];
        }
        for j in 0..NUM_JOINTS {
            for a in 0..3 {
                let w = if a == 2 { self.wz } else { self.wd };
                h[(3 * j + a, 3 * j + a)] += w;
                g[3 * j + a] += w * (y[j][a] - self.y0[j][a]);
            }
        }
        for r in &self.linear {
            let v = r.w * (r.c.dot(&(y[r.a] - y[r.b])) - r.t);
            let cc = r.c * r.c.transpose() * r.w;
            for a in 0..3 {
                g[3 * r.a + a] += v * r.c[a];
                g[3 * r.b + a] -= v * r.c[a];
                for e in 0..3 {
                    h[(3 * r.a + a, 3 * r.a + e)] += cc[(a, e)];
                    h[(3 * r.b + a, 3 * r.b + e)] += cc[(a, e)];
                    h[(3 * r.a + a, 3 * r.b + e)] -= cc[(a, e)];
                    h[(3 * r.b + a, 3 * r.a + e)] -= cc[(a, e)];
                }
            }
        }
        for (&(p, c), l) in BONES.iter().zip(&self.len) {
            let d = y[c] - y[p];
            let n = d.norm();
            if !(n > 0.0) {
                continue;
            }
            let dir = d / n;
            let nn = dir * dir.transpose() * self.wl;
            for a in 0..3 {
                g[3 * c + a] += self.wl * (n - l) * dir[a];
                g[3 * p + a] -= self.wl * (n - l) * dir[a];
                for e in 0..3 {
                    h[(3 * c + a, 3 * c + e)] += nn[(a, e)];
                    h[(3 * p + a, 3 * p + e)] += nn[(a, e)];
                    h[(3 * c + a, 3 * p + e)] -= nn[(a, e)];
                    h[(3 * p + a, 3 * c + e)] -= nn[(a, e)];
                }
            }
        }
        (h, g)
    }
}

/// Which plausibility priors ([`super::plausibility`]) the free-joint step applies.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct Priors {
    /// The standing prior, for figures the 2-D joints show standing on both feet.
    pub standing: bool,
    /// Knees bent backwards are flipped in depth.
    pub knee_limits: bool,
    /// Depths toward the camera of every joint, px at the image's scale (only differences
    /// count; the learned depths, [`super::factor_prior::FactorPrior::depth_hint`]): each bone's
    /// depth change is pulled toward theirs at `depth_sd`. `None` = no pull.
    pub depths: Option<[f64; NUM_JOINTS]>,
    /// Spread of that pull, metres (> 0 to apply it).
    pub depth_sd: f64,
}

/// Refines `est` for `prob` with 2-D joint noise `noise_m` metres (> 0; see the module doc) and
/// the plausibility `priors`. The camera, bases and weights are kept; the base pose is
/// redefined so that joints = base + Σ B w still holds, and the RMS is that of the new joints.
/// Returns `est` unchanged when no step lowers the cost and no knee is flipped.
pub fn fit_joints(prob: &Problem, est: &PoseEstimate, noise_m: f64, priors: &Priors) -> PoseEstimate {
    let cam = &est.camera;
    let y0: Joints = std::array::from_fn(|j| cam.r * Vector3::from(est.joints[j]));
    let sigma_px = noise_m * 0.5 * (cam.sx + cam.sy);
    let standing = priors.standing && standing_in_image(&prob.uv, &std::array::from_fn(|j| prob.vis.contains(&j)));
    let jp = JointProblem {
        prob,
        cam,
        y0,
        len: std::array::from_fn(|b| (y0[BONES[b].1] - y0[BONES[b].0]).norm()),
        wp: 1.0 / (sigma_px * sigma_px),
        wd: 1.0 / (SIGMA_3D * SIGMA_3D),
        wl: 1.0 / (SIGMA_LEN * SIGMA_LEN),
        wz: if standing { 1.0 / (SIGMA_DEPTH_STANDING * SIGMA_DEPTH_STANDING) } else { 1.0 / (SIGMA_3D * SIGMA_3D) },
        linear: {
            let mut v = if standing {
                standing_residuals(&cam.r, stride_in_depth(&y0, &cam.r) <= STANDING_MAX_STRIDE)
            } else {
                Vec::new()
            };
            if let Some(d) = priors.depths.filter(|_| priors.depth_sd > 0.0) {
                let s = 0.5 * (cam.sx + cam.sy);
                let w = 1.0 / (priors.depth_sd * priors.depth_sd);
                for &(p, c) in BONES.iter() {
                    v.push(LinearResidual { a: c, b: p, c: Vector3::z(), w, t: (d[c] - d[p]) / s });
                }
            }
            v
        },
    };
    let mut y = y0;
    let mut f = jp.cost(&y);
    let f0 = f;
    let mut lambda = 1e-6;
    'outer: for _ in 0..ITERATIONS {
        let (h, g) = jp.normal(&y);
        loop {
            let mut hd = h;
            for i in 0..45 {
                hd[(i, i)] *= 1.0 + lambda;
            }
            let step = hd.cholesky().map(|c| -c.solve(&g));
            if let Some(step) = step.filter(|s| s.iter().all(|v| v.is_finite())) {
                let cand: Joints =
                    std::array::from_fn(|j| y[j] + Vector3::new(step[3 * j], step[3 * j + 1], step[3 * j + 2]));
                let fc = jp.cost(&cand);
                if fc < f {
                    let converged = f - fc <= 1e-6 * f;
                    (y, f) = (cand, fc);
                    lambda = (lambda * 0.1).max(1e-9);
                    if converged {
                        break 'outer;
                    }
                    break;
                }
            }
            lambda *= 10.0;
            if lambda > 1e6 {
                break 'outer;
            }
        }
    }
    let flipped = if priors.knee_limits { unbend_knees(&mut y) } else { 0 };
    if !(f < f0) && flipped == 0 {
        return est.clone();
    }
    let rt = cam.r.transpose();
    let x = pose_to_vec(&std::array::from_fn(|j| (rt * y[j]).into()));
    let x = with_bone_lengths(&x, &jp.len);
    let xs: Joints = std::array::from_fn(|j| Vector3::new(x[3 * j], x[3 * j + 1], x[3 * j + 2]));
    let mut base = x.clone();
    for (&b, &w) in est.bases.iter().zip(&est.weights) {
        base.axpy(-w, &prob.dict.bases.column(b), 1.0);
    }
    PoseEstimate {
        joints: vec_to_pose(x.as_slice()),
        rms: prob.rms(cam, &xs),
        base: vec_to_pose(base.as_slice()),
        ..est.clone()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pose::dictionary::{tests::synthetic_clips, Dictionary, LearnParams};
    use crate::pose::pursuit::finish;
    use crate::skeleton::Joints2;
    use nalgebra::Rotation3;

    fn v(x: &[f64; 3]) -> Vector3<f64> {
        Vector3::from(*x)
    }

    #[test]
    fn moves_joints_onto_the_image_and_keeps_bone_lengths() {
        let d = Dictionary::learn(&synthetic_clips(), &LearnParams::default(), "t".into()).unwrap();
        let r = *Rotation3::from_euler_angles(0.1, 0.5, 0.0).matrix();
        let cam = WeakPerspective { sx: 280.0, sy: 280.0, r, t: [250.0, 260.0] };
        // The truth: the mean pose with the right forearm turned 0.5 rad about the viewing
        // direction (an in-image bend, so its depth is not ambiguous); the "estimate": the mean
        // pose (no bases, the true camera).
        let view = r.transpose() * Vector3::z();
        let bend = |angle: f64| {
            let mut x = vec_to_pose(d.mean.as_slice());
            let fore = Rotation3::new(view * angle) * (v(&x[4]) - v(&x[3]));
            x[4] = (v(&x[3]) + fore).into();
            x
        };
        let truth = bend(0.5);
        let mut j = Joints2 { xy: [[0.0; 2]; NUM_JOINTS], visible: [true; NUM_JOINTS] };
        for p in 0..NUM_JOINTS {
            j.xy[p] = cam.project(&v(&truth[p]));
        }
        let prob = Problem::new(&d, &j, 0.0).unwrap().with_base(pose_to_vec(&bend(0.0)));
        let est = finish(&prob, cam, vec![], vec![]);
        let out = fit_joints(&prob, &est, 0.002, &Priors::default());
        assert!(out.rms < 0.25 * est.rms, "rms {} -> {}", est.rms, out.rms);
        let err = |x: &crate::skeleton::Joints3| (v(&x[4]) - v(&truth[4])).norm();
        assert!(err(&out.joints) < 0.3 * err(&est.joints), "wrist error {} -> {}", err(&est.joints), err(&out.joints));
        for &(p, c) in BONES.iter() {
            let l = |x: &crate::skeleton::Joints3| (v(&x[c]) - v(&x[p])).norm();
            assert!((l(&out.joints) - l(&est.joints)).abs() < 1e-12);
        }
        assert_eq!(out.camera, est.camera);
        assert!((out.length_excess - est.length_excess).abs() < 1e-12);
        // joints = base + Σ B w with the redefined base (no bases here: base = joints).
        assert_eq!(out.base, out.joints);
        // An estimate that already explains the image is left as it is.
        let exact = PoseEstimate { joints: truth, ..est.clone() };
        let again = fit_joints(&prob, &exact, 0.002, &Priors::default());
        assert_eq!(again.joints, exact.joints);
    }

    /// The learned depths pull each bone's depth change toward theirs: a forearm the depths put
    /// 0.1 m nearer the viewer (relative to the elbow) than the estimate comes out nearer,
    /// the image barely moves and the bone lengths are kept; without the pull nothing moves.
    #[test]
    fn the_learned_depths_pull_the_bones_depths() {
        use crate::skeleton::joint::{R_ELBOW, R_WRIST};
        let d = Dictionary::learn(&synthetic_clips(), &LearnParams::default(), "t".into()).unwrap();
        let r = *Rotation3::from_euler_angles(0.0, 0.3, 0.0).matrix();
        let cam = WeakPerspective { sx: 280.0, sy: 280.0, r, t: [250.0, 260.0] };
        let x = vec_to_pose(d.mean.as_slice());
        let j = Joints2 { xy: std::array::from_fn(|p| cam.project(&v(&x[p]))), visible: [true; NUM_JOINTS] };
        let prob = Problem::new(&d, &j, 0.0).unwrap().with_base(pose_to_vec(&x));
        let est = finish(&prob, cam, vec![], vec![]);
        let s = 280.0;
        let mut depths: [f64; NUM_JOINTS] = std::array::from_fn(|p| s * (r * v(&x[p])).z);
        depths[R_WRIST] += 0.1 * s;
        let forearm_z = |y: &crate::skeleton::Joints3| (r * (v(&y[R_WRIST]) - v(&y[R_ELBOW]))).z;
        let pulled = Priors { depths: Some(depths), depth_sd: 0.05, ..Priors::default() };
        let out = fit_joints(&prob, &est, 0.014, &pulled);
        let moved = forearm_z(&out.joints) - forearm_z(&est.joints);
        assert!(moved > 0.01, "forearm depth change {moved} m");
        assert!(out.rms < 3.0, "rms {}", out.rms);
        for &(p, c) in BONES.iter() {
            let l = |y: &crate::skeleton::Joints3| (v(&y[c]) - v(&y[p])).norm();
            assert!((l(&out.joints) - l(&est.joints)).abs() < 1e-12);
        }
        let off = Priors { depths: Some(depths), depth_sd: 0.0, ..Priors::default() };
        assert_eq!(fit_joints(&prob, &est, 0.014, &off).joints, est.joints);
    }
}
