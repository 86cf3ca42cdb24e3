//! Drawn proportions as unknowns of the 3-D pose step: per-group bone-length factors (head,
//! torso, shoulders, arms, hips, legs) relative to the dictionary's skeleton.
//!
//! Under a weak-perspective camera every 2-D bone vector is `s · P · (k_g L_b d_b)` (scale `s`,
//! camera rows `P`, group factor `k_g`, reference length `L_b`, unit direction `d_b`), so dividing
//! each 2-D bone vector by its factor and re-chaining from the pelvis ([`BodyFactors::unstylise_2d`])
//! gives exactly the image of the same directions on the reference skeleton. The pose step
//! estimates the factors ([`estimate_factors`]), solves on the unstylised joints, and scales the
//! 3-D bones back ([`BodyFactors::apply`]): foreshortening and proportions are then told apart
//! by the image evidence instead of by the dictionary's fixed bone lengths.
//!
//! **Estimate.** A bone's image length is at most `s k_g L_b` (foreshortening only shortens),
//! so the longest image bone of a group, relative to its reference length, bounds `s k_g`
//! from below, and the bound is tight when one bone of the group lies near the image plane —
//! the common case for the four bones of the arms or of the legs in a drawing. Each group's log
//! factor is the log of that bound over the figure scale (for the single bones and the girdles
//! corrected by the first estimate's foreshortening, [`CORRECTED`]), then shrunk toward 0 by a Gaussian prior whose
//! spread spans realistic to heroic to chibi characters ([`PRIOR_SD`]), and clamped to
//! [[`FACTOR_MIN`], [`FACTOR_MAX`]]. The figure scale is the one the dictionary fit found.
//! With [`crate::pose::PoseOptions::factor_prior`] the prior is the learned one instead
//! ([`super::factor_prior`]: mean and spread predicted from the 2-D joints,
//! [`estimate_factors_with_prior`]), and the bound is combined with it as a Gaussian product.

use nalgebra::{Matrix3, Vector3};

use crate::skeleton::{joint, Joints2, Joints3, BONES, NUM_BONES, NUM_JOINTS, PARENT};

/// Number of proportion groups.
pub const NUM_GROUPS: usize = 6;

/// Group names, in [`BodyFactors::k`] order (also the pose JSON keys).
pub const GROUP_NAMES: [&str; NUM_GROUPS] = ["head", "torso", "shoulders", "arms", "hips", "legs"];

/// Group of each canonical bone ([`crate::skeleton::BONES`] order): neck→head is the head,
/// neck→shoulders the shoulders, the arm bones the arms, pelvis→neck the torso, pelvis→hips the
/// hips, thighs and shins the legs.
pub const BONE_GROUP: [usize; NUM_BONES] = [0, 2, 3, 3, 2, 3, 3, 1, 4, 5, 5, 4, 5, 5];

/// Smallest factor reported (half the reference length).
pub const FACTOR_MIN: f64 = 0.5;
/// Largest factor reported (twice the reference length: a chibi head).
pub const FACTOR_MAX: f64 = 2.0;

/// Prior spread of each log factor (head first): 0.35 for the head (factors 0.7–2.0 within two
/// spreads: small heads of heroic figures to chibi heads), 0.2 for the other groups (0.67–1.5).
pub const PRIOR_SD: [f64; NUM_GROUPS] = [0.35, 0.2, 0.2, 0.2, 0.2, 0.2];

/// Expected spread of a group's log bound about the truth (2-D noise, the remaining
/// foreshortening of the best bone), by group; the girdles (two collinear bones that
/// foreshorten together when the body turns) and single bones are the least certain. Natural
/// log units, in [`PRIOR_SD`]'s group order.
pub const EVIDENCE_SD: [f64; NUM_GROUPS] = [0.12, 0.12, 0.2, 0.06, 0.25, 0.06];

/// Bones of a group are used only when the first estimate's foreshortening (image length over
/// true length, 1 = in the image plane) is at least this.
pub const MIN_FORESHORTENING: f64 = 0.5;

/// Whether a group's bound is corrected by the first estimate's foreshortening of its bone. Not
/// for arms and legs: the first estimate explains short drawn limbs by depth, so its
/// foreshortening would cancel the evidence; with four bones one is usually near the image plane.
pub const CORRECTED: [bool; NUM_GROUPS] = [true, true, true, false, true, false];

/// Per-group bone-length factors (multipliers of the dictionary skeleton's bone lengths, bone
/// directions unchanged), in [`GROUP_NAMES`] order; each in [[`FACTOR_MIN`], [`FACTOR_MAX`]].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BodyFactors {
    /// The factors (head, torso, shoulders, arms, hips, legs).
    pub k: [f64; NUM_GROUPS],
}

impl Default for BodyFactors {
    /// All 1: the dictionary's own proportions.
    fn default() -> Self {
        BodyFactors { k: [1.0; NUM_GROUPS] }
    }
}

/// Joints in hierarchy order (every parent before its children), pelvis first.
const ORDER: [usize; NUM_JOINTS] = [
    joint::PELVIS,
    joint::NECK,
    joint::R_HIP,
    joint::L_HIP,
    joint::HEAD,
    joint::R_SHOULDER,
    joint::L_SHOULDER,
    joint::R_KNEE,
    joint::L_KNEE,
    joint::R_ELBOW,
    joint::L_ELBOW,
    joint::R_ANKLE,
    joint::L_ANKLE,
    joint::R_WRIST,
    joint::L_WRIST,
];

/// The bone ending at each joint (`None` for the pelvis).
fn bone_to(j: usize) -> Option<usize> {
    BONES.iter().position(|&(_, c)| c == j)
}

impl BodyFactors {
    /// Factor of each canonical bone.
    pub fn bone_factors(&self) -> [f64; NUM_BONES] {
        BONE_GROUP.map(|g| self.k[g])
    }

    /// The factors with every value clamped into [[`FACTOR_MIN`], [`FACTOR_MAX`]] (non-finite → 1).
    pub fn clamped(&self) -> BodyFactors {
        BodyFactors { k: self.k.map(|k| if k.is_finite() { k.clamp(FACTOR_MIN, FACTOR_MAX) } else { 1.0 }) }
    }

    /// `x` with every bone scaled by its factor, directions kept, the pelvis fixed.
    pub fn apply(&self, x: &Joints3) -> Joints3 {
        let f = self.bone_factors();
        let mut out = *x;
        for &c in &ORDER[1..] {
            let (b, p) = (bone_to(c).unwrap_or(0), PARENT[c].unwrap_or(joint::PELVIS));
            let d = Vector3::from(x[c]) - Vector3::from(x[p]);
            out[c] = (Vector3::from(out[p]) + d * f[b]).into();
        }
        out
    }

    /// The 2-D joints of the same bone directions on the reference skeleton: every 2-D bone
    /// vector divided by its factor, re-chained from the pelvis (module doc). A joint whose
    /// parent is invisible chains from its nearest visible ancestor; joints with no visible
    /// ancestor (a hidden pelvis) keep their positions. Visibility is unchanged.
    pub fn unstylise_2d(&self, j: &Joints2) -> Joints2 {
        let f = self.bone_factors();
        let mut out = *j;
        for &c in &ORDER[1..] {
            let mut a = PARENT[c];
            while let Some(p) = a {
                if j.visible[p] {
                    break;
                }
                a = PARENT[p];
            }
            let (Some(p), Some(b)) = (a, bone_to(c)) else { continue };
            out.xy[c] =
                [out.xy[p][0] + (j.xy[c][0] - j.xy[p][0]) / f[b], out.xy[p][1] + (j.xy[c][1] - j.xy[p][1]) / f[b]];
        }
        out
    }
}

/// Estimates the factors (module doc) from the 2-D joints `j`, the reference bone lengths
/// `lengths` (metres, the dictionary's), and a first estimate made with the reference lengths:
/// its model-frame joints `x`, camera rotation `r` and scales `sx`, `sy` (px per metre).
/// Bones with an invisible end, or foreshortened below [`MIN_FORESHORTENING`] in the first
/// estimate, give no evidence; groups without evidence stay at 1. Always finite and in range.
pub fn estimate_factors(
    j: &Joints2,
    lengths: &[f64; NUM_BONES],
    x: &Joints3,
    r: &Matrix3<f64>,
    sx: f64,
    sy: f64,
) -> BodyFactors {
    estimate_factors_with_prior(j, lengths, x, r, sx, sy, None)
}

/// [`estimate_factors`] with another prior on each group's log factor than 0 ± [`PRIOR_SD`]:
/// `prior[g]` = (mean, spread), e.g. the learned prior's ([`super::factor_prior`]); a group
/// without evidence takes the prior's mean. Non-finite or non-positive entries fall back to
/// the fixed prior. Always finite and in range.
pub fn estimate_factors_with_prior(
    j: &Joints2,
    lengths: &[f64; NUM_BONES],
    x: &Joints3,
    r: &Matrix3<f64>,
    sx: f64,
    sy: f64,
    prior: Option<&[(f64, f64); NUM_GROUPS]>,
) -> BodyFactors {
    let mut best = [f64::NEG_INFINITY; NUM_GROUPS];
    for (b, &(p, c)) in BONES.iter().enumerate() {
        if !j.visible[p] || !j.visible[c] || !(lengths[b] > 0.0) {
            continue;
        }
        let d = r * (Vector3::from(x[c]) - Vector3::from(x[p]));
        let len3 = d.norm();
        if !(len3 > 0.0) {
            continue;
        }
        let fore = (d.x * d.x + d.y * d.y).sqrt() / len3;
        if fore < MIN_FORESHORTENING {
            continue;
        }
        let (du, dv) = ((j.xy[c][0] - j.xy[p][0]) / sx, (j.xy[c][1] - j.xy[p][1]) / sy);
        let image = (du * du + dv * dv).sqrt();
        let g = BONE_GROUP[b];
        let z = (image / (lengths[b] * if CORRECTED[g] { fore } else { 1.0 })).ln();
        if z.is_finite() && z > best[g] {
            best[g] = z;
        }
    }
    let k = std::array::from_fn(|g| {
        let (m, sd) = match prior.map(|p| p[g]) {
            Some((m, sd)) if m.is_finite() && sd.is_finite() && sd > 0.0 => (m, sd),
            _ => (0.0, PRIOR_SD[g]),
        };
        if !best[g].is_finite() {
            return m.exp();
        }
        // Posterior mean of the log factor: evidence best[g] ± EVIDENCE_SD, prior m ± sd.
        let (ve, vp) = (EVIDENCE_SD[g].powi(2), sd * sd);
        ((best[g] * vp + m * ve) / (vp + ve)).exp()
    });
    BodyFactors { k }.clamped()
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Rotation3;

    fn figure() -> Joints3 {
        let mut x = [[0.0; 3]; NUM_JOINTS];
        let set = |x: &mut Joints3, j: usize, p: [f64; 3]| x[j] = p;
        set(&mut x, joint::HEAD, [0.0, 0.75, 0.02]);
        set(&mut x, joint::NECK, [0.0, 0.5, 0.0]);
        set(&mut x, joint::R_SHOULDER, [-0.18, 0.45, 0.0]);
        set(&mut x, joint::R_ELBOW, [-0.25, 0.18, 0.05]);
        set(&mut x, joint::R_WRIST, [-0.28, -0.05, 0.12]);
        set(&mut x, joint::L_SHOULDER, [0.18, 0.45, 0.0]);
        set(&mut x, joint::L_ELBOW, [0.26, 0.2, -0.03]);
        set(&mut x, joint::L_WRIST, [0.3, -0.04, 0.0]);
        set(&mut x, joint::R_HIP, [-0.09, -0.05, 0.0]);
        set(&mut x, joint::R_KNEE, [-0.1, -0.45, 0.06]);
        set(&mut x, joint::R_ANKLE, [-0.1, -0.86, 0.0]);
        set(&mut x, joint::L_HIP, [0.09, -0.05, 0.0]);
        set(&mut x, joint::L_KNEE, [0.11, -0.46, -0.02]);
        set(&mut x, joint::L_ANKLE, [0.12, -0.87, -0.05]);
        x
    }

    fn lengths(x: &Joints3) -> [f64; NUM_BONES] {
        BONES.map(|(p, c)| (Vector3::from(x[c]) - Vector3::from(x[p])).norm())
    }

    fn project(x: &Joints3, r: &Matrix3<f64>, s: f64) -> Joints2 {
        let mut j = Joints2 { xy: [[0.0; 2]; NUM_JOINTS], visible: [true; NUM_JOINTS] };
        for (q, p) in j.xy.iter_mut().zip(x) {
            let y = r * Vector3::from(*p);
            *q = [s * y.x + 250.0, -s * y.y + 300.0];
        }
        j
    }

    #[test]
    fn apply_keeps_directions_and_unstylise_inverts_the_projection() {
        let x = figure();
        let f = BodyFactors { k: [1.6, 0.9, 1.2, 0.8, 1.1, 1.3] };
        let y = f.apply(&x);
        let (lx, ly) = (lengths(&x), lengths(&y));
        for b in 0..NUM_BONES {
            assert!((ly[b] - lx[b] * f.bone_factors()[b]).abs() < 1e-12, "bone {b}");
            let (p, c) = BONES[b];
            let (dx, dy) = (Vector3::from(x[c]) - Vector3::from(x[p]), Vector3::from(y[c]) - Vector3::from(y[p]));
            assert!(dx.normalize().dot(&dy.normalize()) > 1.0 - 1e-12);
        }
        let r = *Rotation3::from_euler_angles(0.1, 0.4, 0.05).matrix();
        let back = f.unstylise_2d(&project(&y, &r, 280.0));
        let plain = project(&x, &r, 280.0);
        for k in 0..NUM_JOINTS {
            assert!((back.xy[k][0] - plain.xy[k][0]).abs() < 1e-9 && (back.xy[k][1] - plain.xy[k][1]).abs() < 1e-9);
        }
        // A hidden elbow: the wrist chains from the shoulder (its offset scaled by the forearm's factor).
        let mut hidden = project(&y, &r, 280.0);
        hidden.visible[joint::R_ELBOW] = false;
        let out = f.unstylise_2d(&hidden);
        assert!(out.xy.iter().flatten().all(|v| v.is_finite()));
    }

    #[test]
    fn estimate_recovers_in_plane_factors_and_stays_in_range() {
        let x = figure();
        let f = BodyFactors { k: [1.5, 1.0, 1.0, 0.8, 1.0, 1.25] };
        let r = Matrix3::identity();
        let j = project(&f.apply(&x), &r, 300.0);
        // The first estimate: reference lengths, true directions.
        let e = estimate_factors(&j, &lengths(&x), &x, &r, 300.0, 300.0);
        for g in [0, 3, 5] {
            assert!((e.k[g] - 1.0).signum() == (f.k[g] - 1.0).signum(), "group {g}: {:?}", e.k);
            assert!((e.k[g].ln() - f.k[g].ln()).abs() < 0.5 * f.k[g].ln().abs() + 1e-9, "group {g}: {:?}", e.k);
        }
        assert!((e.k[1] - 1.0).abs() < 0.02, "{:?}", e.k);
        // Absurd input: factors stay finite and inside the documented range.
        let mut bad = j;
        bad.xy[joint::R_WRIST] = [1e5, -1e5];
        bad.xy[joint::HEAD] = bad.xy[joint::NECK];
        let e = estimate_factors(&bad, &lengths(&x), &x, &r, 300.0, 300.0);
        assert!(e.k.iter().all(|k| k.is_finite() && (FACTOR_MIN..=FACTOR_MAX).contains(k)), "{:?}", e.k);
    }
}
