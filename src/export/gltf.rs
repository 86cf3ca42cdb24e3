//! Binary glTF 2.0 (.glb): the rest mesh with normals, UVs, skin weights (`JOINTS_0`,
//! `WEIGHTS_0`) and inverse bind matrices; the 15 canonical joints as nodes; two scenes, "posed"
//! (the default: node rotations and translations from IK) and "rest" (the bind pose).
//!
//! Skeleton: one node per joint, named as in [`JOINT_NAMES`], parented as in `PARENT`, placed at
//! the joint. The node of joint `c` carries the rotation of the bone ending at `c`, so vertices
//! of bone `b = (s, c)` are skinned to joint node `c` and move rigidly with the bone. The pelvis
//! node carries the pelvis frame ([`Pose::root`]) and has no vertices. With IK retargeting the
//! posed joints still land on the targets (node translations) but glTF has no per-bone stretch:
//! vertices follow their bone rigidly from its end joint instead of stretching.
//! UVs are written with v flipped (glTF's origin is the top-left of the texture).

use std::collections::HashMap;
use std::path::Path;

use nalgebra::{UnitQuaternion, Vector3};
use serde_json::{json, Value};

use crate::body::ik::Pose;
use crate::body::rig::{vertex_normals, RiggedMesh};
use crate::error::{Error, Result};
use crate::fsutil::write_atomic;
use crate::skeleton::{joint::PELVIS, Joints3, BONES, JOINT_NAMES, NUM_JOINTS, PARENT};

const ARRAY_BUFFER: u32 = 34962;
const ELEMENT_ARRAY_BUFFER: u32 = 34963;
const FLOAT: u32 = 5126;
const UNSIGNED_BYTE: u32 = 5121;
const UNSIGNED_INT: u32 = 5125;

/// Accumulates the binary chunk and its buffer views / accessors.
#[derive(Default)]
struct Bin {
    data: Vec<u8>,
    views: Vec<Value>,
    accessors: Vec<Value>,
}

impl Bin {
    /// Appends `bytes` as a new buffer view and an accessor over it; returns the accessor index.
    fn add(&mut self, bytes: &[u8], target: Option<u32>, accessor: Value) -> usize {
        while self.data.len() % 4 != 0 {
            self.data.push(0);
        }
        let mut view = json!({"buffer": 0, "byteOffset": self.data.len(), "byteLength": bytes.len()});
        if let Some(t) = target {
            view["target"] = json!(t);
        }
        self.data.extend_from_slice(bytes);
        self.views.push(view);
        let mut acc = accessor;
        acc["bufferView"] = json!(self.views.len() - 1);
        self.accessors.push(acc);
        self.accessors.len() - 1
    }
}

fn f32_bytes(v: impl IntoIterator<Item = f32>) -> Vec<u8> {
    v.into_iter().flat_map(f32::to_le_bytes).collect()
}

fn quat_json(q: &UnitQuaternion<f64>) -> Value {
    let c = q.quaternion().coords.normalize(); // (i, j, k, w): glTF's order
    json!([c[0], c[1], c[2], c[3]])
}

fn vec_json(v: &Vector3<f64>) -> Value {
    json!([v.x, v.y, v.z])
}

/// Nodes of one skeleton (15 joints, then the skinned mesh node) with global rotations `rot`
/// per joint and positions `pos`; node indices start at `base`.
fn skeleton_nodes(
    base: usize,
    pos: &Joints3,
    rot: &[UnitQuaternion<f64>; NUM_JOINTS],
    skin: usize,
    tag: &str,
) -> Vec<Value> {
    let mut nodes = Vec::with_capacity(NUM_JOINTS + 1);
    for j in 0..NUM_JOINTS {
        let (t, r) = match PARENT[j] {
            None => (Vector3::from(pos[j]), rot[j]),
            Some(p) => {
                let inv = rot[p].inverse();
                (inv * (Vector3::from(pos[j]) - Vector3::from(pos[p])), inv * rot[j])
            }
        };
        let children: Vec<usize> = (0..NUM_JOINTS).filter(|&c| PARENT[c] == Some(j)).map(|c| base + c).collect();
        let mut node = json!({"name": JOINT_NAMES[j], "translation": vec_json(&t), "rotation": quat_json(&r)});
        if !children.is_empty() {
            node["children"] = json!(children);
        }
        nodes.push(node);
    }
    nodes.push(json!({"name": format!("body ({tag})"), "mesh": 0, "skin": skin}));
    nodes
}

/// Global rotation carried by each joint node: the pelvis frame for the pelvis, otherwise the
/// rotation of the bone ending at the joint.
fn joint_rotations(pose: &Pose) -> [UnitQuaternion<f64>; NUM_JOINTS] {
    let mut r = [pose.root; NUM_JOINTS];
    for (b, &(_, c)) in BONES.iter().enumerate() {
        r[c] = pose.rotations[b];
    }
    r
}

/// The .glb bytes of `mesh` (rest pose, with its skin) and `pose` (made by IK from
/// `mesh.joints`). Errors when the mesh is invalid or the pose's rest joints differ from the
/// mesh's.
pub fn glb_bytes(mesh: &RiggedMesh, pose: &Pose) -> Result<Vec<u8>> {
    mesh.validate()?;
    let same_rest = mesh.joints.iter().flatten().zip(pose.rest.iter().flatten()).all(|(a, b)| (a - b).abs() < 1e-9);
    if !same_rest {
        return Err(Error::OutOfRange { name: "pose", detail: "its rest joints are not the mesh's".into() });
    }
    // Split vertices where a vertex has several UVs (glTF attributes are per vertex).
    let mut key_to_new: HashMap<(u32, u32), u32> = HashMap::new();
    let mut source: Vec<(u32, u32)> = Vec::new();
    let mut tris: Vec<u32> = Vec::with_capacity(mesh.quads.len() * 6);
    for (f, q) in mesh.quads.iter().enumerate() {
        let uvq = mesh.uvs.as_ref().map_or([0; 4], |u| u.quads[f]);
        let mut corner = |k: usize| {
            let key = (q[k], uvq[k]);
            *key_to_new.entry(key).or_insert_with(|| {
                source.push(key);
                (source.len() - 1) as u32
            })
        };
        let c: Vec<u32> =
            if q[3] == q[2] { (0..3).map(&mut corner).collect() } else { (0..4).map(&mut corner).collect() };
        tris.extend_from_slice(&[c[0], c[1], c[2]]);
        if c.len() == 4 {
            tris.extend_from_slice(&[c[0], c[2], c[3]]);
        }
    }
    let normals = vertex_normals(&mesh.vertices, &mesh.quads);
    let n = source.len();
    let mut bin = Bin::default();
    let pos: Vec<[f32; 3]> = source.iter().map(|&(v, _)| mesh.vertices[v as usize]).collect();
    let (mut lo, mut hi) = ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]);
    for p in &pos {
        for k in 0..3 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    let mut attributes = serde_json::Map::new();
    let a = bin.add(
        &f32_bytes(pos.iter().flatten().copied()),
        Some(ARRAY_BUFFER),
        json!({"componentType": FLOAT, "count": n, "type": "VEC3", "min": lo, "max": hi}),
    );
    attributes.insert("POSITION".into(), json!(a));
    let a = bin.add(
        &f32_bytes(source.iter().flat_map(|&(v, _)| normals[v as usize])),
        Some(ARRAY_BUFFER),
        json!({"componentType": FLOAT, "count": n, "type": "VEC3"}),
    );
    attributes.insert("NORMAL".into(), json!(a));
    if let Some(uv) = &mesh.uvs {
        let a = bin.add(
            &f32_bytes(source.iter().flat_map(|&(_, t)| {
                let c = uv.coords[t as usize];
                [c[0], 1.0 - c[1]]
            })),
            Some(ARRAY_BUFFER),
            json!({"componentType": FLOAT, "count": n, "type": "VEC2"}),
        );
        attributes.insert("TEXCOORD_0".into(), json!(a));
    }
    // Skin: bone b drives joint node BONES[b].1; merge duplicates, renormalise.
    let mut joints_bytes = Vec::with_capacity(n * 4);
    let mut weights = Vec::with_capacity(n * 4);
    for &(v, _) in &source {
        let mut slots: Vec<(u8, f32)> = Vec::with_capacity(4);
        for (b, w) in mesh.weights[v as usize].influences() {
            let j = BONES[b].1 as u8;
            match slots.iter_mut().find(|s| s.0 == j) {
                Some(s) => s.1 += w,
                None => slots.push((j, w)),
            }
        }
        let sum: f32 = slots.iter().map(|s| s.1).sum();
        slots.resize(4, (0, 0.0));
        for s in &slots {
            joints_bytes.push(s.0);
            weights.push(s.1 / sum);
        }
    }
    let a =
        bin.add(&joints_bytes, Some(ARRAY_BUFFER), json!({"componentType": UNSIGNED_BYTE, "count": n, "type": "VEC4"}));
    attributes.insert("JOINTS_0".into(), json!(a));
    let a =
        bin.add(&f32_bytes(weights), Some(ARRAY_BUFFER), json!({"componentType": FLOAT, "count": n, "type": "VEC4"}));
    attributes.insert("WEIGHTS_0".into(), json!(a));
    let idx: Vec<u8> = tris.iter().flat_map(|i| i.to_le_bytes()).collect();
    let indices = bin.add(
        &idx,
        Some(ELEMENT_ARRAY_BUFFER),
        json!({"componentType": UNSIGNED_INT, "count": tris.len(), "type": "SCALAR"}),
    );
    // Inverse bind matrices: translation by -J_rest (column-major 4x4).
    let ibm = f32_bytes(mesh.joints.iter().flat_map(|j| {
        let t = j.map(|c| -(c as f32));
        [1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, t[0], t[1], t[2], 1.0]
    }));
    let ibm = bin.add(&ibm, None, json!({"componentType": FLOAT, "count": NUM_JOINTS, "type": "MAT4"}));

    let posed_rot = joint_rotations(pose);
    let rest_rot = [UnitQuaternion::identity(); NUM_JOINTS];
    let mut nodes = skeleton_nodes(0, &pose.joints, &posed_rot, 0, "posed");
    nodes.extend(skeleton_nodes(NUM_JOINTS + 1, &mesh.joints, &rest_rot, 1, "rest"));
    let skin = |base: usize, name: &str| json!({"name": name, "inverseBindMatrices": ibm, "skeleton": base + PELVIS, "joints": (base..base + NUM_JOINTS).collect::<Vec<_>>()});
    let doc = json!({
        "asset": {"version": "2.0", "generator": format!("sketchbody {}", crate::VERSION)},
        "scene": 0,
        "scenes": [
            {"name": "posed", "nodes": [PELVIS, NUM_JOINTS]},
            {"name": "rest", "nodes": [NUM_JOINTS + 1 + PELVIS, 2 * NUM_JOINTS + 1]},
        ],
        "nodes": nodes,
        "skins": [skin(0, "posed"), skin(NUM_JOINTS + 1, "rest")],
        "meshes": [{"name": "body", "primitives": [{"attributes": attributes, "indices": indices, "mode": 4, "material": 0}]}],
        "materials": [{"name": "skin", "pbrMetallicRoughness": {"baseColorFactor": [0.8, 0.7, 0.65, 1.0], "metallicFactor": 0.0, "roughnessFactor": 0.8}, "doubleSided": true}],
        "buffers": [{"byteLength": bin.data.len()}],
        "bufferViews": bin.views,
        "accessors": bin.accessors,
    });
    let mut text = serde_json::to_vec(&doc).map_err(|e| Error::CorruptData(format!("glTF JSON: {e}")))?;
    while text.len() % 4 != 0 {
        text.push(b' ');
    }
    let mut data = bin.data;
    while data.len() % 4 != 0 {
        data.push(0);
    }
    let total = 12 + 8 + text.len() + 8 + data.len();
    let total32 = u32::try_from(total)
        .map_err(|_| Error::OutOfRange { name: "glb size", detail: format!("{total} bytes exceeds 4 GiB") })?;
    let mut out = Vec::with_capacity(total);
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&total32.to_le_bytes());
    out.extend_from_slice(&(text.len() as u32).to_le_bytes());
    out.extend_from_slice(b"JSON");
    out.extend_from_slice(&text);
    out.extend_from_slice(&(data.len() as u32).to_le_bytes());
    out.extend_from_slice(b"BIN\0");
    out.extend_from_slice(&data);
    Ok(out)
}

/// Writes [`glb_bytes`] to `path` atomically.
pub fn write_glb(path: &Path, mesh: &RiggedMesh, pose: &Pose) -> Result<()> {
    write_atomic(path, &glb_bytes(mesh, pose)?)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::body::ik::{solve, IkOptions};
    use crate::body::procedural::{capsule_humanoid, random_pose, rest_joints};
    use crate::body::skin::{skin, SkinMethod};
    use rand::SeedableRng;

    /// Reads the JSON chunk back and applies the posed scene's node transforms to the skin,
    /// checking that glTF's skinning reproduces our LBS for single-bone vertices.
    #[test]
    fn posed_scene_reproduces_our_skinning() {
        let rest = rest_joints();
        let mesh = capsule_humanoid(&rest, 8, 6);
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
        let pose = solve(&rest, &random_pose(&rest, &mut rng, 0.0), &IkOptions::default()).unwrap();
        let glb = glb_bytes(&mesh, &pose).unwrap();
        assert_eq!(&glb[..4], b"glTF");
        assert_eq!(u32::from_le_bytes(glb[8..12].try_into().unwrap()) as usize, glb.len());
        let jlen = u32::from_le_bytes(glb[12..16].try_into().unwrap()) as usize;
        let doc: Value = serde_json::from_slice(&glb[20..20 + jlen]).unwrap();
        // Global transforms of the posed joint nodes.
        let mut global = vec![(UnitQuaternion::identity(), Vector3::zeros()); NUM_JOINTS];
        let order = [8, 1, 0, 2, 3, 4, 5, 6, 7, 9, 10, 11, 12, 13, 14];
        for &j in &order {
            let node = &doc["nodes"][j];
            let t: Vec<f64> = serde_json::from_value(node["translation"].clone()).unwrap();
            let r: Vec<f64> = serde_json::from_value(node["rotation"].clone()).unwrap();
            let q = UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(r[3], r[0], r[1], r[2]));
            let t = Vector3::new(t[0], t[1], t[2]);
            global[j] = match PARENT[j] {
                None => (q, t),
                Some(p) => (global[p].0 * q, global[p].1 + global[p].0 * t),
            };
        }
        let ours = skin(&mesh.vertices, &mesh.weights, &pose, SkinMethod::Linear).unwrap();
        for (i, w) in mesh.weights.iter().enumerate() {
            let x = Vector3::new(mesh.vertices[i][0] as f64, mesh.vertices[i][1] as f64, mesh.vertices[i][2] as f64);
            let mut p = Vector3::zeros();
            for (b, wt) in w.influences() {
                let c = BONES[b].1;
                p += (global[c].1 + global[c].0 * (x - Vector3::from(rest[c]))) * wt as f64;
            }
            let e = (p - Vector3::new(ours[i][0] as f64, ours[i][1] as f64, ours[i][2] as f64)).norm();
            assert!(e < 1e-5, "vertex {i} off by {e}");
        }
        let other = Pose::rest(&random_pose(&rest, &mut rng, 0.1));
        assert!(glb_bytes(&mesh, &other).is_err());
    }
}
