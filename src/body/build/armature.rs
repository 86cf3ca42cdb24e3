//! The production rig from MakeHuman's `game_engine` rig (`rigs/standard/rig.game_engine.json`),
//! its weights (`weights.game_engine.json`) and T-pose (`poses/game_engine_fk/t-pose.json`):
//! bone ends on canonical joint cubes are the canonical joints themselves; every other end (a
//! joint cube of the spine, clavicle, head, hand, fingers, foot or toes) is regressed as an
//! affine combination of the 15 canonical joints and the [`NEAREST_VERTICES`] body vertices
//! nearest to it, fitted by least squares over synthesised humans of both genders.

use std::collections::BTreeMap;

use nalgebra::{DMatrix, DVector};

use crate::body::rig::bones::{bone_by_makehuman_name, canonical_joint_of_cube, NUM_RIG_BONES, RIG_BONES};
use crate::body::rig::{PointRegressor, RigData};
use crate::error::{Error, Result};
use crate::skeleton::{joint, Joints3, NUM_JOINTS};

use super::super::model::{VertexWeights, MAX_INFLUENCES};

/// Body vertices offered to each regressed bone end (besides the 15 canonical joints).
pub const NEAREST_VERTICES: usize = 24;
/// Ridge of the regressor fit, relative to the mean diagonal of the normal matrix.
pub const REGRESSOR_RIDGE: f64 = 1e-6;

/// How one bone end is located.
#[derive(Clone, Debug, PartialEq)]
pub enum EndSource {
    /// A canonical joint.
    Joint(usize),
    /// The centre of a MakeHuman joint cube (mean of its vertices), regressed.
    Cube(String),
}

/// The rig file read: per bone (in [`RIG_BONES`] order) head and tail sources and roll.
#[derive(Clone, Debug)]
pub struct RigSpec {
    /// Head, tail of each bone.
    pub ends: Vec<[EndSource; 2]>,
    /// Roll of each bone, radians.
    pub rolls: Vec<f32>,
    /// T-pose Euler XYZ angles of each bone, radians.
    pub tpose: Vec<[f32; 3]>,
}

fn end_source(bone: &str, key: &str, end: &serde_json::Value) -> Result<EndSource> {
    let bad = |m: &str| Error::CorruptData(format!("rig.game_engine.json {bone} {key}: {m}"));
    if bone == "Root" {
        // MakeHuman's root sits on ground helper vertices; ours is between the ankles, dropped
        // to the body's lowest point (crate::body::rig::Armature::rest).
        return Ok(EndSource::Joint(joint::R_ANKLE));
    }
    match end.get("strategy").and_then(|s| s.as_str()) {
        Some("CUBE") => {
            let cube = end.get("cube_name").and_then(|c| c.as_str()).ok_or_else(|| bad("no cube_name"))?;
            Ok(canonical_joint_of_cube(cube).map_or_else(|| EndSource::Cube(cube.to_string()), EndSource::Joint))
        }
        _ => Err(bad("not located by a joint cube")),
    }
}

/// Reads the rig and T-pose files, checking every bone of [`RIG_BONES`] is there with the same
/// parent.
pub fn rig_spec(rig: &serde_json::Value, tpose: &serde_json::Value) -> Result<RigSpec> {
    let bones = rig.as_object().ok_or_else(|| Error::CorruptData("rig.game_engine.json: not an object".into()))?;
    if bones.len() != NUM_RIG_BONES {
        return Err(Error::CorruptData(format!(
            "rig.game_engine.json has {} bones, expected {NUM_RIG_BONES}",
            bones.len()
        )));
    }
    let angles = tpose.get("bone_rotations").and_then(|r| r.as_object());
    let angles = angles.ok_or_else(|| Error::CorruptData("t-pose.json: no bone_rotations".into()))?;
    for name in angles.keys() {
        if bone_by_makehuman_name(name).is_none() {
            return Err(Error::CorruptData(format!("t-pose.json: unknown bone {name}")));
        }
    }
    let mut spec = RigSpec { ends: Vec::new(), rolls: Vec::new(), tpose: Vec::new() };
    for b in &RIG_BONES {
        let bone =
            bones.get(b.makehuman).ok_or_else(|| Error::CorruptData(format!("rig has no bone {}", b.makehuman)))?;
        let parent = bone.get("parent").and_then(|p| p.as_str()).unwrap_or("");
        let expected = b.parent.map_or("", |p| RIG_BONES[p].makehuman);
        if parent != expected {
            return Err(Error::CorruptData(format!(
                "rig bone {}: parent {parent:?}, expected {expected:?}",
                b.makehuman
            )));
        }
        let end =
            |k: &str| bone.get(k).ok_or_else(|| Error::CorruptData(format!("rig bone {} has no {k}", b.makehuman)));
        spec.ends
            .push([end_source(b.makehuman, "head", end("head")?)?, end_source(b.makehuman, "tail", end("tail")?)?]);
        spec.rolls.push(bone.get("roll").and_then(|r| r.as_f64()).unwrap_or(0.0) as f32);
        let a = angles.get(b.makehuman).and_then(|a| a.as_array());
        let a: Vec<f32> = a.map_or(vec![0.0; 3], |a| a.iter().map(|x| x.as_f64().unwrap_or(f64::NAN) as f32).collect());
        if a.len() != 3 || a.iter().any(|x| !x.is_finite()) {
            return Err(Error::CorruptData(format!("t-pose.json: bad rotation of {}", b.makehuman)));
        }
        spec.tpose.push([a[0], a[1], a[2]]);
    }
    // The root's tail also sits between the ankles (its direction is set at run time).
    spec.ends[0] = [EndSource::Joint(joint::R_ANKLE), EndSource::Joint(joint::R_ANKLE)];
    Ok(spec)
}

impl RigSpec {
    /// Distinct cube names to regress, sorted.
    pub fn cubes(&self) -> Vec<String> {
        let mut c: Vec<String> = self
            .ends
            .iter()
            .flatten()
            .filter_map(|e| match e {
                EndSource::Cube(n) => Some(n.clone()),
                EndSource::Joint(_) => None,
            })
            .collect();
        c.sort();
        c.dedup();
        c
    }
}

/// Centre of a joint cube (mean of its vertices) on a full mesh in decimetres, in metres.
pub fn cube_centre(groups: &BTreeMap<String, Vec<usize>>, cube: &str, all_dm: &[[f64; 3]]) -> Result<[f64; 3]> {
    let v = groups
        .get(cube)
        .filter(|v| !v.is_empty())
        .ok_or_else(|| Error::CorruptData(format!("no vertex group {cube}")))?;
    let mut p = [0.0; 3];
    for &i in v {
        let q = all_dm.get(i).ok_or_else(|| Error::CorruptData(format!("{cube}: vertex {i} out of range")))?;
        for c in 0..3 {
            p[c] += q[c] * 0.1 / v.len() as f64;
        }
    }
    Ok(p)
}

/// One synthesised human as the regressor fit sees it: body vertices and joints (metres) and
/// the centre of every cube to regress.
pub struct RigSample {
    /// Body vertices, metres.
    pub body: Vec<[f64; 3]>,
    /// Canonical joints, metres.
    pub joints: Joints3,
    /// Cube centres, metres, in [`RigSpec::cubes`] order.
    pub cubes: Vec<[f64; 3]>,
}

/// The affine regressor of one cube (index `c` of the samples' cubes): candidates are the 15
/// joints and the [`NEAREST_VERTICES`] body vertices nearest the cube on `reference`; the weights
/// minimise the squared error over `samples` plus a small ridge, subject to summing to 1.
pub fn fit_regressor(reference: &RigSample, samples: &[RigSample], c: usize) -> Result<PointRegressor> {
    let centre = reference.cubes[c];
    let d2 = |p: &[f64; 3]| (0..3).map(|k| (p[k] - centre[k]).powi(2)).sum::<f64>();
    let mut order: Vec<usize> = (0..reference.body.len()).collect();
    order.sort_by(|&a, &b| d2(&reference.body[a]).total_cmp(&d2(&reference.body[b])).then(a.cmp(&b)));
    let mut candidates: Vec<u32> = (0..NUM_JOINTS as u32).collect();
    candidates.extend(order.iter().take(NEAREST_VERTICES).map(|&v| (v + NUM_JOINTS) as u32));
    let m = candidates.len();
    let point = |s: &RigSample, i: u32| -> [f64; 3] {
        match (i as usize).checked_sub(NUM_JOINTS) {
            None => s.joints[i as usize],
            Some(v) => s.body[v],
        }
    };
    let mut a = DMatrix::<f64>::zeros(3 * samples.len(), m);
    let mut y = DVector::<f64>::zeros(3 * samples.len());
    for (r, s) in samples.iter().enumerate() {
        for (k, &i) in candidates.iter().enumerate() {
            let p = point(s, i);
            for d in 0..3 {
                a[(3 * r + d, k)] = p[d];
            }
        }
        for d in 0..3 {
            y[3 * r + d] = s.cubes[c][d];
        }
    }
    let ata = a.transpose() * &a;
    let lambda = REGRESSOR_RIDGE * ata.trace() / m as f64;
    let mut kkt = DMatrix::<f64>::zeros(m + 1, m + 1);
    kkt.view_mut((0, 0), (m, m)).copy_from(&ata);
    for k in 0..m {
        kkt[(k, k)] += lambda;
        kkt[(k, m)] = 1.0;
        kkt[(m, k)] = 1.0;
    }
    let mut rhs = DVector::<f64>::zeros(m + 1);
    rhs.rows_mut(0, m).copy_from(&(a.transpose() * y));
    rhs[m] = 1.0;
    let w = kkt.lu().solve(&rhs).ok_or_else(|| Error::Degenerate("rig regressor system is singular".into()))?;
    let terms = candidates.iter().enumerate().map(|(k, &i)| (i, w[k] as f32)).filter(|t| t.1 != 0.0).collect();
    Ok(PointRegressor { terms })
}

/// Per cube, the largest distance (metres) between the cube and its regressor over `samples`;
/// and the mean distance over every cube and sample.
pub fn regressor_error(regressors: &[PointRegressor], samples: &[RigSample]) -> (Vec<f64>, f64) {
    let mut worst = vec![0.0f64; regressors.len()];
    let (mut sum, mut n) = (0.0, 0usize);
    for s in samples {
        let body: Vec<[f32; 3]> = s.body.iter().map(|p| p.map(|c| c as f32)).collect();
        for (k, (r, c)) in regressors.iter().zip(&s.cubes).enumerate() {
            let p = r.eval(&s.joints, &body);
            let d = (0..3).map(|k| (p[k] - c[k]).powi(2)).sum::<f64>().sqrt();
            worst[k] = worst[k].max(d);
            sum += d;
            n += 1;
        }
    }
    (worst, sum / n.max(1) as f64)
}

/// Maps `weights.game_engine.json` (`{"weights": {bone: [[vertex, weight], ...]}}`) to the 53
/// bones for vertices `0..num_body_vertices`: the 4 largest per vertex (ties: lower bone first),
/// renormalised to 1. Errors: an unknown bone, a bad entry, a body vertex with no weight.
pub fn map_rig_weights(json: &serde_json::Value, num_body_vertices: usize) -> Result<Vec<VertexWeights>> {
    let bad = |m: String| Error::CorruptData(format!("weights.game_engine.json: {m}"));
    let table = json.get("weights").and_then(|w| w.as_object()).ok_or_else(|| bad("no weights object".into()))?;
    let mut acc = vec![Vec::<(usize, f64)>::new(); num_body_vertices];
    for (bone, list) in table {
        let b = bone_by_makehuman_name(bone).ok_or_else(|| bad(format!("unknown bone {bone}")))?;
        for pair in list.as_array().ok_or_else(|| bad(format!("{bone}: not a list")))? {
            let v = pair.get(0).and_then(|v| v.as_u64()).ok_or_else(|| bad(format!("{bone}: bad vertex")))? as usize;
            let w = pair.get(1).and_then(|w| w.as_f64()).filter(|w| w.is_finite() && *w >= 0.0);
            let w = w.ok_or_else(|| bad(format!("{bone}: bad weight for vertex {v}")))?;
            if v < num_body_vertices && w > 0.0 {
                match acc[v].iter_mut().find(|e| e.0 == b) {
                    Some(e) => e.1 += w,
                    None => acc[v].push((b, w)),
                }
            }
        }
    }
    acc.iter_mut()
        .enumerate()
        .map(|(v, list)| {
            list.sort_by(|x, y| y.1.total_cmp(&x.1).then(x.0.cmp(&y.0)));
            list.truncate(MAX_INFLUENCES);
            let total: f64 = list.iter().map(|e| e.1).sum();
            if total <= 0.0 {
                return Err(bad(format!("vertex {v} has no weight")));
            }
            let mut out = VertexWeights { bones: [0; MAX_INFLUENCES], weights: [0.0; MAX_INFLUENCES] };
            for (slot, &(b, w)) in list.iter().enumerate() {
                out.bones[slot] = b as u8;
                out.weights[slot] = (w / total) as f32;
            }
            Ok(out)
        })
        .collect()
}

/// The stored rig: regressors per bone end (joint ends exact), rolls, T-pose and skin.
pub fn rig_data(
    spec: &RigSpec,
    cube_regressors: &BTreeMap<String, PointRegressor>,
    skin: Vec<VertexWeights>,
) -> Result<RigData> {
    let end = |e: &EndSource| -> Result<PointRegressor> {
        match e {
            EndSource::Joint(j) => Ok(PointRegressor::joint(*j)),
            EndSource::Cube(c) => {
                cube_regressors.get(c).cloned().ok_or_else(|| Error::CorruptData(format!("no regressor for {c}")))
            }
        }
    };
    let mut rig =
        RigData { heads: Vec::new(), tails: Vec::new(), rolls: spec.rolls.clone(), tpose: spec.tpose.clone(), skin };
    for [h, t] in &spec.ends {
        rig.heads.push(end(h)?);
        rig.tails.push(end(t)?);
    }
    // The root between the ankles (dropped to the floor at run time).
    let mid = PointRegressor { terms: vec![(joint::R_ANKLE as u32, 0.5), (joint::L_ANKLE as u32, 0.5)] };
    rig.heads[0] = mid.clone();
    rig.tails[0] = mid;
    Ok(rig)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rig_weights_keep_four_largest_and_reject_unknown_bones() {
        let json: serde_json::Value = serde_json::from_str(
            r#"{"weights":{"head":[[0,0.5]],"pelvis":[[0,0.2],[1,1.0]],"spine_01":[[0,0.1]],"spine_02":[[0,0.05]],"spine_03":[[0,0.01]]}}"#,
        )
        .unwrap();
        let w = map_rig_weights(&json, 2).unwrap();
        assert_eq!(w[0].bones, [6, 1, 2, 3]);
        assert!((w[0].weights.iter().sum::<f32>() - 1.0).abs() < 1e-6);
        assert_eq!((w[1].bones[0], w[1].weights[0]), (1, 1.0));
        assert!(map_rig_weights(&json, 3).is_err(), "vertex 2 has no weight");
        let unknown: serde_json::Value = serde_json::from_str(r#"{"weights":{"tail":[[0,1.0]]}}"#).unwrap();
        assert!(map_rig_weights(&unknown, 1).is_err());
    }
}
