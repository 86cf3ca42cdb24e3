//! BlazePose's joints moved to the body model's joint definitions.
//!
//! The canonical joints mapped from MediaPipe's landmarks ([`super::joints::to_canonical`]) sit
//! where photo annotators put them, not where the body model's skeleton has its joints: on
//! rendered sketches the ears' midpoint is about a tenth of a torso length below the model's
//! head joint, the hip landmarks above its hip joints, the shoulder landmarks inside and above
//! its shoulder joints. The 3-D pose step and the shape fit read the joints as the model's, so
//! those offsets bend the pose and the body. [`JointDefinitions`] shifts each joint by a fixed
//! fraction of the figure's torso length (pelvis → neck of the mapped joints) along the torso
//! and, for the paired joints, away from the body's axis: the median shift between the mapped
//! joints and the true ones on rendered training sketches, the two sides of each pair averaged
//! (`sketchbody-lab fit-landmark-joints`). Scale-free and rotation-free by construction.

use crate::error::{ensure_finite, Error, Result};
use crate::skeleton::{joint, Joints2, MIRROR, NUM_JOINTS};

/// Left–right joint pairs (right first, [`MIRROR`]'s pairs): shoulders, elbows, wrists, hips,
/// knees, ankles.
fn sides() -> impl Iterator<Item = (usize, usize)> {
    (0..NUM_JOINTS).filter(|&j| MIRROR[j] > j).map(|j| (j, MIRROR[j]))
}

/// Fewest training figures [`JointDefinitions::fit`] accepts.
pub const MIN_FIGURES: usize = 10;

/// Per-joint shifts in torso lengths (module documentation). Plain data; `Send + Sync`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct JointDefinitions {
    /// Shift along the torso's direction (pelvis → neck, "up" the body), torso lengths.
    pub along_torso: [f64; NUM_JOINTS],
    /// Shift away from the body's axis (paired joints; 0 for head, neck and pelvis), torso lengths.
    pub outward: [f64; NUM_JOINTS],
}

/// The figure's frame from its joints: unit torso direction (pelvis → neck), its perpendicular,
/// and the torso length (px); `None` for a torso shorter than 1e-6 px or non-finite joints.
fn frame(j: &Joints2) -> Option<([f64; 2], [f64; 2], f64)> {
    let (neck, pelvis) = (j.xy[joint::NECK], j.xy[joint::PELVIS]);
    let up = [neck[0] - pelvis[0], neck[1] - pelvis[1]];
    let len = up[0].hypot(up[1]);
    if !(len.is_finite() && len > 1e-6) {
        return None;
    }
    let u = [up[0] / len, up[1] / len];
    Some((u, [-u[1], u[0]], len))
}

/// For each joint, the unit direction away from the body's axis (toward the joint's own side of
/// its partner) within `j`, zero for unpaired joints and pairs at one point across.
fn outward_directions(j: &Joints2, across: [f64; 2]) -> [[f64; 2]; NUM_JOINTS] {
    let mut out = [[0.0; 2]; NUM_JOINTS];
    for (r, l) in sides() {
        let d = (j.xy[r][0] - j.xy[l][0]) * across[0] + (j.xy[r][1] - j.xy[l][1]) * across[1];
        if d != 0.0 {
            let s = d.signum();
            out[r] = [s * across[0], s * across[1]];
            out[l] = [-s * across[0], -s * across[1]];
        }
    }
    out
}

/// The median of `v` (not empty).
fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

impl JointDefinitions {
    /// No shift: the mapped landmarks as they are.
    pub const IDENTITY: JointDefinitions =
        JointDefinitions { along_torso: [0.0; NUM_JOINTS], outward: [0.0; NUM_JOINTS] };

    /// The shifts BlazePose's joints take by default ([`super::BlazePoseOptions::definitions`]),
    /// fitted on the first 300 sketches of `make-dataset 1200 --seed 79 --mocap DIR` (the
    /// classifiers' training sketches) by `sketchbody-lab fit-landmark-joints --train DS --first 300`,
    /// on landmarks refined from the heatmap (docs/benchmarks-history.md, "BlazePose's joints on
    /// the body model's definitions", "Landmarks refined from the heatmap").
    pub const SHIPPED: JointDefinitions = JointDefinitions {
        along_torso: [
            0.095903, 0.016533, -0.036644, 0.005798, 0.019818, -0.036644, 0.005798, 0.019818, 0.043058, 0.018922,
            0.007597, -0.049727, 0.018922, 0.007597, -0.049727,
        ],
        outward: [
            0.000000, 0.000000, 0.017159, -0.001757, 0.004279, 0.017159, -0.001757, 0.004279, 0.000000, 0.012913,
            0.006399, -0.000442, 0.012913, 0.006399, -0.000442,
        ],
    };

    /// `joints` shifted by these definitions in their own frame (module documentation); a
    /// figure without a torso (neck on the pelvis) is returned as it is. Visibility is kept.
    pub fn apply(&self, joints: &Joints2) -> Joints2 {
        let Some((u, across, len)) = frame(joints) else { return *joints };
        let out = outward_directions(joints, across);
        let mut shifted = *joints;
        for k in 0..NUM_JOINTS {
            for a in 0..2 {
                shifted.xy[k][a] += len * (self.along_torso[k] * u[a] + self.outward[k] * out[k][a]);
            }
        }
        shifted
    }

    /// Fits the definitions to `(mapped, truth)` joint pairs of the same figures: per joint the
    /// median shift from the mapped joint to the true one in the mapped joints' frame, the two
    /// sides of each pair averaged (the model's skeleton is symmetric). Figures without a torso
    /// are skipped. Errors: a non-finite joint ([`Error::NonFinite`]); fewer than
    /// [`MIN_FIGURES`] usable figures ([`Error::OutOfRange`]).
    pub fn fit(pairs: &[(Joints2, Joints2)]) -> Result<JointDefinitions> {
        let mut along: Vec<Vec<f64>> = vec![Vec::new(); NUM_JOINTS];
        let mut outward: Vec<Vec<f64>> = vec![Vec::new(); NUM_JOINTS];
        for (mapped, truth) in pairs {
            for p in mapped.xy.iter().chain(&truth.xy) {
                ensure_finite("joint x", p[0])?;
                ensure_finite("joint y", p[1])?;
            }
            let Some((u, across, len)) = frame(mapped) else { continue };
            let out = outward_directions(mapped, across);
            for k in 0..NUM_JOINTS {
                let e = [(truth.xy[k][0] - mapped.xy[k][0]) / len, (truth.xy[k][1] - mapped.xy[k][1]) / len];
                along[k].push(e[0] * u[0] + e[1] * u[1]);
                if out[k] != [0.0; 2] {
                    outward[k].push(e[0] * out[k][0] + e[1] * out[k][1]);
                }
            }
        }
        let usable = along[0].len();
        if usable < MIN_FIGURES {
            return Err(Error::OutOfRange {
                name: "landmark definition set",
                detail: format!("{usable} figures with a torso; need at least {MIN_FIGURES}"),
            });
        }
        let mut d = JointDefinitions::IDENTITY;
        for k in 0..NUM_JOINTS {
            d.along_torso[k] = median(&mut along[k]);
            if !outward[k].is_empty() {
                d.outward[k] = median(&mut outward[k]);
            }
        }
        for (r, l) in sides() {
            for v in [&mut d.along_torso, &mut d.outward] {
                let m = 0.5 * (v[r] + v[l]);
                v[r] = m;
                v[l] = m;
            }
        }
        Ok(d)
    }

    /// Errors: a non-finite shift ([`Error::NonFinite`]) or one beyond a torso length
    /// ([`Error::OutOfRange`]).
    pub fn validate(&self) -> Result<()> {
        for v in self.along_torso.iter().chain(&self.outward) {
            ensure_finite("joint definition shift", *v)?;
            if v.abs() > 1.0 {
                return Err(Error::OutOfRange {
                    name: "joint definition shift",
                    detail: format!("{v} torso lengths; at most 1"),
                });
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A front-view figure (its right on the image's left), torso 100 px, rotated by `angle`
    /// radians and scaled by `scale` about the origin.
    fn figure(angle: f64, scale: f64) -> Joints2 {
        let base: [[f64; 2]; NUM_JOINTS] = [
            [0.0, -140.0],
            [0.0, -100.0],
            [-40.0, -95.0],
            [-50.0, -50.0],
            [-55.0, -5.0],
            [40.0, -95.0],
            [50.0, -50.0],
            [55.0, -5.0],
            [0.0, 0.0],
            [-20.0, 5.0],
            [-22.0, 90.0],
            [-24.0, 175.0],
            [20.0, 5.0],
            [22.0, 90.0],
            [24.0, 175.0],
        ];
        let (c, s) = (angle.cos(), angle.sin());
        let xy = base.map(|p| [scale * (c * p[0] - s * p[1]) + 300.0, scale * (s * p[0] + c * p[1]) + 250.0]);
        Joints2 { xy, visible: [true; NUM_JOINTS] }
    }

    fn known() -> JointDefinitions {
        let mut d = JointDefinitions::IDENTITY;
        d.along_torso[joint::HEAD] = 0.1;
        d.along_torso[joint::PELVIS] = 0.05;
        for (r, l) in sides() {
            d.along_torso[r] = -0.02;
            d.along_torso[l] = -0.02;
            d.outward[r] = 0.03;
            d.outward[l] = 0.03;
        }
        d
    }

    #[test]
    fn apply_moves_joints_in_the_figures_own_frame() {
        let d = known();
        let j = figure(0.0, 1.0);
        let s = d.apply(&j);
        // Up is −y in the image; the torso is 100 px: the head goes 10 px up.
        assert!((s.xy[joint::HEAD][1] - (j.xy[joint::HEAD][1] - 10.0)).abs() < 1e-9);
        assert!((s.xy[joint::HEAD][0] - j.xy[joint::HEAD][0]).abs() < 1e-9);
        // Shoulders move 3 px outward: the right one (image left) to −x, the left one to +x.
        assert!((s.xy[joint::R_SHOULDER][0] - (j.xy[joint::R_SHOULDER][0] - 3.0)).abs() < 1e-9);
        assert!((s.xy[joint::L_SHOULDER][0] - (j.xy[joint::L_SHOULDER][0] + 3.0)).abs() < 1e-9);
        // The same shift, rotated and scaled with the figure.
        let (a, k) = (0.7, 2.5);
        let (jr, sr) = (figure(a, k), d.apply(&figure(a, k)));
        for n in 0..NUM_JOINTS {
            let moved = [s.xy[n][0] - j.xy[n][0], s.xy[n][1] - j.xy[n][1]];
            let want = [k * (a.cos() * moved[0] - a.sin() * moved[1]), k * (a.sin() * moved[0] + a.cos() * moved[1])];
            let got = [sr.xy[n][0] - jr.xy[n][0], sr.xy[n][1] - jr.xy[n][1]];
            assert!((got[0] - want[0]).abs() < 1e-9 && (got[1] - want[1]).abs() < 1e-9, "{n}");
        }
        assert_eq!(JointDefinitions::IDENTITY.apply(&j), j);
        let mut flat = j;
        flat.xy[joint::NECK] = flat.xy[joint::PELVIS];
        assert_eq!(d.apply(&flat), flat, "no torso, no frame: unchanged");
    }

    #[test]
    fn fit_recovers_known_definitions_and_averages_the_sides() {
        let d = known();
        let pairs: Vec<(Joints2, Joints2)> = (0..15)
            .map(|i| {
                let mapped = figure(0.1 * i as f64 - 0.7, 0.8 + 0.05 * i as f64);
                (mapped, d.apply(&mapped))
            })
            .collect();
        let got = JointDefinitions::fit(&pairs).unwrap();
        for k in 0..NUM_JOINTS {
            assert!((got.along_torso[k] - d.along_torso[k]).abs() < 1e-9, "{k}: {got:?}");
            assert!((got.outward[k] - d.outward[k]).abs() < 1e-9, "{k}: {got:?}");
        }
        // One side shifted alone: the fit gives both sides half of it.
        let mut lopsided = JointDefinitions::IDENTITY;
        lopsided.along_torso[joint::R_HIP] = 0.04;
        let pairs: Vec<(Joints2, Joints2)> = (0..12)
            .map(|i| {
                let m = figure(0.05 * i as f64, 1.0);
                (m, lopsided.apply(&m))
            })
            .collect();
        let got = JointDefinitions::fit(&pairs).unwrap();
        assert!((got.along_torso[joint::R_HIP] - 0.02).abs() < 1e-9);
        assert!((got.along_torso[joint::L_HIP] - 0.02).abs() < 1e-9);
        assert!(got.validate().is_ok() && JointDefinitions::SHIPPED.validate().is_ok());
    }

    #[test]
    fn bad_input_is_an_error() {
        let j = figure(0.0, 1.0);
        let few: Vec<(Joints2, Joints2)> = (0..MIN_FIGURES - 1).map(|_| (j, j)).collect();
        assert!(matches!(JointDefinitions::fit(&few), Err(Error::OutOfRange { .. })));
        let mut flat = j;
        flat.xy[joint::NECK] = flat.xy[joint::PELVIS];
        let no_torso: Vec<(Joints2, Joints2)> = (0..20).map(|_| (flat, j)).collect();
        assert!(matches!(JointDefinitions::fit(&no_torso), Err(Error::OutOfRange { .. })), "skipped");
        let mut nan = j;
        nan.xy[3][0] = f64::NAN;
        assert!(matches!(JointDefinitions::fit(&[(j, nan)]), Err(Error::NonFinite { .. })));
        let mut far = JointDefinitions::IDENTITY;
        far.outward[2] = 1.5;
        assert!(matches!(far.validate(), Err(Error::OutOfRange { .. })));
        far.outward[2] = f64::INFINITY;
        assert!(matches!(far.validate(), Err(Error::NonFinite { .. })));
    }
}
