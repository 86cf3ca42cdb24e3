//! Rig data from MakeHuman's helpers: the canonical joints as fixed linear combinations of mesh
//! vertices (joint-cube centres), the check of the rig's stored default positions, and skin
//! weights mapped from the `cmu_mb` rig to the 14 canonical bones.

use std::collections::BTreeMap;

use crate::error::{Error, Result};
use crate::skeleton::{Joints3, NUM_BONES, NUM_JOINTS};

use super::super::model::{VertexWeights, MAX_INFLUENCES};

/// The MakeHuman rig whose skin weights are mapped (`rigs/standard/weights.cmu_mb.json`).
pub const SKIN_RIG: &str = "cmu_mb";

/// Joint cubes (`joint-*` vertex groups) whose centres give each canonical joint; the head is
/// the midpoint of the two head cubes (base of the skull and top of the head).
pub const JOINT_CUBES: [&[&str]; NUM_JOINTS] = [
    &["joint-head", "joint-head-2"],
    &["joint-neck"],
    &["joint-r-shoulder"],
    &["joint-r-elbow"],
    &["joint-r-hand"],
    &["joint-l-shoulder"],
    &["joint-l-elbow"],
    &["joint-l-hand"],
    &["joint-pelvis"],
    &["joint-r-upper-leg"],
    &["joint-r-knee"],
    &["joint-r-ankle"],
    &["joint-l-upper-leg"],
    &["joint-l-knee"],
    &["joint-l-ankle"],
];

/// Which canonical bone(s) each `cmu_mb` bone's weight goes to, with shares summing to 1. A
/// bone `b` of ours is the segment ending at joint `BONES[b].1`; hands ride on the forearms, feet
/// and toes on the shins, the neck and head on bone 0, the spine on the torso bone 7; `Hips`
/// (the pelvis block) is split evenly between the two pelvis→hip bones 8 and 11.
pub const CMU_MB_TO_CANONICAL: [(&str, &[(usize, f64)]); 31] = [
    ("Head", &[(0, 1.0)]),
    ("Neck", &[(0, 1.0)]),
    ("Neck1", &[(0, 1.0)]),
    ("RightShoulder", &[(1, 1.0)]),
    ("RightArm", &[(2, 1.0)]),
    ("RightForeArm", &[(3, 1.0)]),
    ("RightHand", &[(3, 1.0)]),
    ("RightFingerBase", &[(3, 1.0)]),
    ("RightHandFinger1", &[(3, 1.0)]),
    ("RThumb", &[(3, 1.0)]),
    ("LeftShoulder", &[(4, 1.0)]),
    ("LeftArm", &[(5, 1.0)]),
    ("LeftForeArm", &[(6, 1.0)]),
    ("LeftHand", &[(6, 1.0)]),
    ("LeftFingerBase", &[(6, 1.0)]),
    ("LeftHandFinger1", &[(6, 1.0)]),
    ("LThumb", &[(6, 1.0)]),
    ("LowerBack", &[(7, 1.0)]),
    ("Spine", &[(7, 1.0)]),
    ("Spine1", &[(7, 1.0)]),
    ("Hips", &[(8, 0.5), (11, 0.5)]),
    ("RHipJoint", &[(8, 1.0)]),
    ("RightUpLeg", &[(9, 1.0)]),
    ("RightLeg", &[(10, 1.0)]),
    ("RightFoot", &[(10, 1.0)]),
    ("RightToeBase", &[(10, 1.0)]),
    ("LHipJoint", &[(11, 1.0)]),
    ("LeftUpLeg", &[(12, 1.0)]),
    ("LeftLeg", &[(13, 1.0)]),
    ("LeftFoot", &[(13, 1.0)]),
    ("LeftToeBase", &[(13, 1.0)]),
];

/// Vertex groups of `mesh_metadata/basemesh_vertex_groups.json`: name → vertex indices.
pub fn vertex_groups(json: &serde_json::Value, num_vertices: usize) -> Result<BTreeMap<String, Vec<usize>>> {
    let bad = |m: String| Error::CorruptData(format!("basemesh_vertex_groups.json: {m}"));
    let obj = json.as_object().ok_or_else(|| bad("not an object".into()))?;
    let mut out = BTreeMap::new();
    for (name, ranges) in obj {
        let mut idx = Vec::new();
        for r in ranges.as_array().ok_or_else(|| bad(format!("{name}: not a list of ranges")))? {
            let a = r.get(0).and_then(|v| v.as_u64()).ok_or_else(|| bad(format!("{name}: bad range")))? as usize;
            let b = r.get(1).and_then(|v| v.as_u64()).ok_or_else(|| bad(format!("{name}: bad range")))? as usize;
            if a > b || b >= num_vertices {
                return Err(bad(format!("{name}: range [{a}, {b}] outside 0..{num_vertices}")));
            }
            idx.extend(a..=b);
        }
        out.insert(name.clone(), idx);
    }
    Ok(out)
}

/// Per canonical joint, the (vertex, weight) pairs whose weighted sum is the joint.
pub type JointRegressor = Vec<Vec<(usize, f64)>>;

/// The joint regressor of [`JOINT_CUBES`]: each cube contributes the mean of its vertices.
pub fn joint_regressor(groups: &BTreeMap<String, Vec<usize>>) -> Result<JointRegressor> {
    JOINT_CUBES
        .iter()
        .map(|cubes| {
            let mut terms = Vec::new();
            for cube in cubes.iter() {
                let verts = groups
                    .get(*cube)
                    .filter(|v| !v.is_empty())
                    .ok_or_else(|| Error::CorruptData(format!("no vertex group {cube}")))?;
                let w = 1.0 / (verts.len() * cubes.len()) as f64;
                terms.extend(verts.iter().map(|&v| (v, w)));
            }
            Ok(terms)
        })
        .collect()
}

/// The canonical joints of a mesh given in decimetres (OBJ axes), in metres (model frame; the
/// axes agree, only the unit changes).
pub fn joints_of(reg: &JointRegressor, vertices_dm: &[[f64; 3]]) -> Joints3 {
    let mut j = [[0.0; 3]; NUM_JOINTS];
    for (out, terms) in j.iter_mut().zip(reg) {
        for &(v, w) in terms {
            for c in 0..3 {
                out[c] += w * vertices_dm[v][c] * 0.1;
            }
        }
    }
    j
}

/// Locates one rig end (`CUBE`, `MEAN` or `VERTEX` strategy) on `vertices_dm`, decimetres.
fn rig_end(
    end: &serde_json::Value,
    groups: &BTreeMap<String, Vec<usize>>,
    vertices_dm: &[[f64; 3]],
) -> Result<[f64; 3]> {
    let bad = |m: &str| Error::CorruptData(format!("rig end {end}: {m}"));
    let idx: Vec<usize> = match end.get("strategy").and_then(|s| s.as_str()) {
        Some("CUBE") => {
            let name = end.get("cube_name").and_then(|n| n.as_str()).ok_or_else(|| bad("no cube_name"))?;
            groups.get(name).cloned().ok_or_else(|| bad("unknown cube"))?
        }
        Some("MEAN") => end
            .get("vertex_indices")
            .and_then(|v| v.as_array())
            .ok_or_else(|| bad("no vertex_indices"))?
            .iter()
            .map(|v| v.as_u64().map(|i| i as usize).ok_or_else(|| bad("bad vertex index")))
            .collect::<Result<_>>()?,
        Some("VERTEX") => {
            vec![end.get("vertex_index").and_then(|v| v.as_u64()).ok_or_else(|| bad("no vertex_index"))? as usize]
        }
        _ => return Err(bad("unknown strategy")),
    };
    if idx.is_empty() || idx.iter().any(|&i| i >= vertices_dm.len()) {
        return Err(bad("vertex index out of range"));
    }
    let mut p = [0.0; 3];
    for &i in &idx {
        for c in 0..3 {
            p[c] += vertices_dm[i][c] / idx.len() as f64;
        }
    }
    Ok(p)
}

/// Largest distance, metres, between the rig's stored `default_position`s (Blender metres, Z up:
/// (x, −z, y)·0.1 of OBJ coordinates) and the same ends located on `vertices_dm`, over every
/// bone head and tail of `rig`; and how many ends were compared.
pub fn rig_default_error(
    rig: &serde_json::Value,
    groups: &BTreeMap<String, Vec<usize>>,
    vertices_dm: &[[f64; 3]],
) -> Result<(f64, usize)> {
    let bones = rig.as_object().ok_or_else(|| Error::CorruptData("rig JSON is not an object".into()))?;
    let (mut worst, mut count) = (0.0f64, 0);
    for (name, bone) in bones {
        for key in ["head", "tail"] {
            let end = bone.get(key).ok_or_else(|| Error::CorruptData(format!("rig bone {name} has no {key}")))?;
            let stored = end
                .get("default_position")
                .and_then(|v| v.as_array())
                .filter(|a| a.len() == 3)
                .ok_or_else(|| Error::CorruptData(format!("rig bone {name} {key}: no default_position")))?;
            let s: Vec<f64> = stored.iter().map(|v| v.as_f64().unwrap_or(f64::NAN)).collect();
            let p = rig_end(end, groups, vertices_dm)?;
            let blender = [0.1 * p[0], -0.1 * p[2], 0.1 * p[1]];
            let d = (0..3).map(|c| (blender[c] - s[c]).powi(2)).sum::<f64>().sqrt();
            if !d.is_finite() {
                return Err(Error::CorruptData(format!("rig bone {name} {key}: non-numeric default_position")));
            }
            worst = worst.max(d);
            count += 1;
        }
    }
    Ok((worst, count))
}

/// Maps the `cmu_mb` weights (`{"weights": {bone: [[vertex, weight], ...]}}`) to the canonical
/// bones for vertices `0..num_body_vertices`: sums shares per canonical bone, keeps the 4 largest
/// (ties: lower bone first), renormalises to sum 1.
pub fn map_skin_weights(json: &serde_json::Value, num_body_vertices: usize) -> Result<Vec<VertexWeights>> {
    let bad = |m: String| Error::CorruptData(format!("weights.{SKIN_RIG}.json: {m}"));
    let table = json.get("weights").and_then(|w| w.as_object()).ok_or_else(|| bad("no weights object".into()))?;
    let mut acc = vec![[0.0f64; NUM_BONES]; num_body_vertices];
    for (bone, list) in table {
        let shares = CMU_MB_TO_CANONICAL
            .iter()
            .find(|(n, _)| n == bone)
            .map(|(_, s)| *s)
            .ok_or_else(|| bad(format!("bone {bone} has no canonical mapping")))?;
        for pair in list.as_array().ok_or_else(|| bad(format!("{bone}: not a list")))? {
            let v = pair.get(0).and_then(|v| v.as_u64()).ok_or_else(|| bad(format!("{bone}: bad vertex")))? as usize;
            let w = pair.get(1).and_then(|w| w.as_f64()).filter(|w| w.is_finite() && *w >= 0.0);
            let w = w.ok_or_else(|| bad(format!("{bone}: bad weight for vertex {v}")))?;
            if v < num_body_vertices {
                for &(b, share) in shares {
                    acc[v][b] += share * w;
                }
            }
        }
    }
    acc.iter()
        .enumerate()
        .map(|(v, a)| {
            let mut order: Vec<usize> = (0..NUM_BONES).collect();
            order.sort_by(|&x, &y| a[y].total_cmp(&a[x]).then(x.cmp(&y)));
            let kept = &order[..MAX_INFLUENCES];
            let total: f64 = kept.iter().map(|&b| a[b]).sum();
            if total <= 0.0 {
                return Err(bad(format!("vertex {v} has no weight")));
            }
            let mut out = VertexWeights { bones: [0; MAX_INFLUENCES], weights: [0.0; MAX_INFLUENCES] };
            for (slot, &b) in kept.iter().enumerate() {
                if a[b] > 0.0 {
                    out.bones[slot] = b as u8;
                    out.weights[slot] = (a[b] / total) as f32;
                }
            }
            Ok(out)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn skin_weights_keep_four_largest_and_renormalise() {
        let json: serde_json::Value = serde_json::from_str(
            r#"{"weights":{"Head":[[0,0.5]],"Hips":[[0,0.2],[1,1.0]],"RightArm":[[0,0.1]],"LeftArm":[[0,0.05]],"Spine":[[0,0.01]]}}"#,
        )
        .unwrap();
        let w = map_skin_weights(&json, 2).unwrap();
        // vertex 0: bone0 0.5, bone8 0.1, bone11 0.1, bone2 0.1, bone5 0.05, bone7 0.01 -> top 4
        assert_eq!(w[0].bones, [0, 2, 8, 11]);
        let s: f32 = w[0].weights.iter().sum();
        assert!((s - 1.0).abs() < 1e-6 && (w[0].weights[0] - 0.5 / 0.8).abs() < 1e-6, "{:?}", w[0]);
        assert_eq!(w[1].bones[..2], [8, 11]);
        assert_eq!(w[1].weights, [0.5, 0.5, 0.0, 0.0]);
        assert!(map_skin_weights(&json, 3).is_err(), "vertex 2 has no weight");
        let unknown: serde_json::Value = serde_json::from_str(r#"{"weights":{"Tail":[[0,1.0]]}}"#).unwrap();
        assert!(map_skin_weights(&unknown, 1).is_err());
    }

    #[test]
    fn every_cmu_mb_share_list_sums_to_one() {
        for (name, shares) in CMU_MB_TO_CANONICAL {
            let s: f64 = shares.iter().map(|s| s.1).sum();
            assert!((s - 1.0).abs() < 1e-12 && shares.iter().all(|s| s.0 < NUM_BONES), "{name}");
        }
    }
}
