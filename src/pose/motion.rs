//! Motion tables and pose normalisation.
//!
//! A motion table is the CSV of `data/mocap`: a header `head_x,head_y,head_z,...` and one row per
//! frame with the 15 canonical joints in metres (+Y up, facing +Z at heading zero).
//!
//! Normalisation (used for learning and for measurement): the pose is translated so the pelvis
//! is at the origin, rotated about +Y so that its left-pointing axis (left hip minus right hip plus
//! left shoulder minus right shoulder, projected on the ground plane) is +X (the body faces +Z),
//! and scaled uniformly so that its stature proxy [`stature_chain`] equals [`REF_CHAIN`]. Only a
//! uniform scale is applied: proportions are kept, which matters for rigs other than DeepMimic's.

use std::path::Path;

use crate::error::{Error, Result};
use crate::skeleton::{joint, Joints3, JOINT_NAMES, MIRROR, NUM_JOINTS};

/// Stature proxy of a 1.75 m person, metres: head centre to ankle along the body,
/// 1.75 m − 0.12 m (head centre below the vertex) − 0.08 m (ankle above the floor).
pub const REF_CHAIN: f64 = 1.55;

/// Reference stature, metres, that normalised poses represent.
pub const REF_STATURE: f64 = 1.75;

/// Stature proxy of a pose, metres: |head−neck| + |neck−pelvis| + the mean of the two leg
/// chains (hip–knee + knee–ankle).
pub fn stature_chain(x: &Joints3) -> f64 {
    let d = |a: usize, b: usize| dist(&x[a], &x[b]);
    let legs = 0.5
        * (d(joint::R_HIP, joint::R_KNEE)
            + d(joint::R_KNEE, joint::R_ANKLE)
            + d(joint::L_HIP, joint::L_KNEE)
            + d(joint::L_KNEE, joint::L_ANKLE));
    d(joint::HEAD, joint::NECK) + d(joint::NECK, joint::PELVIS) + legs
}

fn dist(a: &[f64; 3], b: &[f64; 3]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

/// Normalises a pose (see the module doc). Returns `None` when the pose has no usable heading
/// (its left-right axis is vertical within 1e-3 of its length) or a zero stature proxy.
pub fn normalize_pose(x: &Joints3) -> Option<Joints3> {
    let p = x[joint::PELVIS];
    let across: Vec<f64> = (0..3)
        .map(|k| x[joint::L_HIP][k] - x[joint::R_HIP][k] + x[joint::L_SHOULDER][k] - x[joint::R_SHOULDER][k])
        .collect();
    let full = (across[0].powi(2) + across[1].powi(2) + across[2].powi(2)).sqrt();
    let h = (across[0].powi(2) + across[2].powi(2)).sqrt();
    if !(h > 1e-3 * full) {
        return None;
    }
    let chain = stature_chain(x);
    if !(chain > 1e-9) || !chain.is_finite() {
        return None;
    }
    let (c, s) = (across[0] / h, across[2] / h);
    let k = REF_CHAIN / chain;
    let mut out = [[0.0; 3]; NUM_JOINTS];
    for (o, q) in out.iter_mut().zip(x.iter()) {
        let (dx, dy, dz) = (q[0] - p[0], q[1] - p[1], q[2] - p[2]);
        *o = [k * (c * dx + s * dz), k * dy, k * (-s * dx + c * dz)];
    }
    Some(out)
}

/// The left/right mirror of a pose about the YZ plane (joints swapped with [`MIRROR`], x negated).
pub fn mirror_pose(x: &Joints3) -> Joints3 {
    let mut out = [[0.0; 3]; NUM_JOINTS];
    for j in 0..NUM_JOINTS {
        let q = x[MIRROR[j]];
        out[j] = [-q[0], q[1], q[2]];
    }
    out
}

/// Parses a motion table (see the module doc). Every row must have 45 finite numbers.
pub fn parse_motion_csv(text: &str, what: &str) -> Result<Vec<Joints3>> {
    let mut lines = text.lines().filter(|l| !l.trim().is_empty());
    let header = lines.next().ok_or_else(|| Error::CorruptData(format!("{what}: empty motion table")))?;
    let cols: Vec<&str> = header.split(',').map(str::trim).collect();
    let expected: Vec<String> = JOINT_NAMES.iter().flat_map(|n| ["x", "y", "z"].map(|a| format!("{n}_{a}"))).collect();
    if cols != expected {
        return Err(Error::CorruptData(format!("{what}: header is not the 45 canonical joint columns")));
    }
    let mut frames = Vec::new();
    for (i, line) in lines.enumerate() {
        let mut f = [[0.0; 3]; NUM_JOINTS];
        let mut n = 0;
        for (k, field) in line.split(',').enumerate() {
            let v: f64 = field.trim().parse().map_err(|_| {
                Error::CorruptData(format!("{what}: row {}: field {} ({field:?}) is not a number", i + 2, k + 1))
            })?;
            if !v.is_finite() || k >= 3 * NUM_JOINTS {
                return Err(Error::CorruptData(format!("{what}: row {}: bad or extra field {}", i + 2, k + 1)));
            }
            f[k / 3][k % 3] = v;
            n += 1;
        }
        if n != 3 * NUM_JOINTS {
            return Err(Error::CorruptData(format!("{what}: row {} has {n} fields, expected 45", i + 2)));
        }
        frames.push(f);
    }
    if frames.is_empty() {
        return Err(Error::CorruptData(format!("{what}: no frames")));
    }
    Ok(frames)
}

/// Reads a motion table from a file.
pub fn read_motion_csv(path: &Path) -> Result<Vec<Joints3>> {
    let text = std::fs::read_to_string(path).map_err(|source| Error::Io { path: path.to_path_buf(), source })?;
    parse_motion_csv(&text, &path.display().to_string())
}

/// Sum of squared bone lengths of a pose, m².
pub fn sum_sq_bones(x: &Joints3) -> f64 {
    crate::skeleton::BONES.iter().map(|&(a, b)| dist(&x[a], &x[b]).powi(2)).sum()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> Joints3 {
        let mut x = [[0.0; 3]; NUM_JOINTS];
        for (j, q) in x.iter_mut().enumerate() {
            *q = [0.1 * j as f64 - 0.3 * (j % 3) as f64, 0.07 * j as f64, 0.05 * (j % 4) as f64];
        }
        x[joint::L_HIP] = [0.2, 0.0, 0.0];
        x[joint::R_HIP] = [-0.2, 0.0, 0.0];
        x[joint::PELVIS] = [0.0, 0.0, 0.0];
        x
    }

    #[test]
    fn normalisation_is_invariant_to_heading_translation_and_scale() {
        let x = sample();
        let n0 = normalize_pose(&x).unwrap();
        let (c, s) = (0.3f64.cos(), 0.3f64.sin());
        let mut y = x;
        for q in y.iter_mut() {
            *q = [2.0 * (c * q[0] + s * q[2]) + 5.0, 2.0 * q[1] - 1.0, 2.0 * (-s * q[0] + c * q[2]) + 0.5];
        }
        let n1 = normalize_pose(&y).unwrap();
        for j in 0..NUM_JOINTS {
            for k in 0..3 {
                assert!((n0[j][k] - n1[j][k]).abs() < 1e-12, "joint {j} axis {k}");
            }
        }
        assert!((stature_chain(&n0) - REF_CHAIN).abs() < 1e-12);
        assert_eq!(n0[joint::PELVIS], [0.0; 3]);
        // Left of the body is +X after normalisation.
        assert!(n0[joint::L_HIP][0] > 0.0 && n0[joint::L_HIP][2].abs() < 1e-12 + n0[joint::L_HIP][0]);
        assert_eq!(mirror_pose(&mirror_pose(&n0)), n0);
    }

    #[test]
    fn csv_rejects_bad_rows() {
        let header: Vec<String> =
            JOINT_NAMES.iter().flat_map(|n| ["x", "y", "z"].map(|a| format!("{n}_{a}"))).collect();
        let row = vec!["0.5"; 45].join(",");
        let ok = format!("{}\n{row}\n", header.join(","));
        assert_eq!(parse_motion_csv(&ok, "t").unwrap().len(), 1);
        let short = format!("{}\n{}\n", header.join(","), vec!["0.5"; 44].join(","));
        assert!(parse_motion_csv(&short, "t").is_err());
        let nan = format!("{}\n{}\n", header.join(","), row.replacen("0.5", "nan", 1));
        assert!(parse_motion_csv(&nan, "t").is_err());
        assert!(parse_motion_csv("a,b\n1,2\n", "t").is_err());
    }
}
