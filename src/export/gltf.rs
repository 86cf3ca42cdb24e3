//! Binary glTF 2.0 (.glb), one scene: the rest mesh (normals, UVs, optional base-colour
//! texture) skinned (`JOINTS_0`, `WEIGHTS_0`, inverse bind matrices) to MakeHuman's 53-bone
//! production armature ([`crate::body::rig`]), posed: the nodes carry the body's pose as bone
//! rotations, with a translation on the root only; the same pose is also a one-frame animation
//! clip named "pose" (STEP interpolation, time 0); see [`crate::body::rig::PoseAs`] for the
//! other ways. Shape keys, when the scene has them, are morph targets (`POSITION` displacements,
//! weights 0, names in the mesh's `extras.targetNames`).
//!
//! Nodes 0..53 are the bones in [`crate::body::rig::RIG_BONES`] order, then any twist bones
//! ([`crate::body::rig::twist`]), named in the chosen convention, each placed at its bone's head
//! with its rest frame (local +Y along the bone, MakeHuman's roll); the node after the bones is
//! the mesh. The scene's roots are the root bone (at the floor by default) and the
//! mesh. UVs are written with v flipped (glTF's texture origin is the top-left).
use std::collections::HashMap;
use std::path::Path;

use nalgebra::{UnitQuaternion, Vector3};
use serde_json::{json, Value};

use crate::body::rig::RigScene;
use crate::body::rig::{vertex_normals, RiggedMesh};
use crate::error::{Error, Result};
use crate::export::rigged::{bind_transform, check_scene, pose_locals, posed_locals};
use crate::fsutil::write_atomic_parts;

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
        while !self.data.len().is_multiple_of(4) {
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

/// The .glb bytes of `scene` (built by [`RigScene::build`] from `mesh`), with faces and UVs from
/// `mesh` and, when given, `texture_png` (PNG bytes) as the base-colour texture. Errors: the
/// mesh is invalid or its vertex count differs from the scene's; the file would exceed 4 GiB.
pub fn glb_bytes(mesh: &RiggedMesh, scene: &RigScene, texture_png: Option<&[u8]>) -> Result<Vec<u8>> {
    Ok(build_glb(mesh, scene, texture_png)?.parts().concat())
}

fn build_glb(mesh: &RiggedMesh, scene: &RigScene, texture_png: Option<&[u8]>) -> Result<Glb> {
    check_scene(mesh, scene)?;
    let vertices = &scene.rest_vertices;
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
    let normals = vertex_normals(vertices, &mesh.quads);
    let n = source.len();
    let mut bin = Bin::default();
    let pos: Vec<[f32; 3]> = source.iter().map(|&(v, _)| vertices[v as usize]).collect();
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
    let mut joints_bytes = Vec::with_capacity(n * 4);
    let mut weights = Vec::with_capacity(n * 4);
    for &(v, _) in &source {
        let w = &scene.skin[v as usize];
        for k in 0..4 {
            joints_bytes.push(if w.weights[k] > 0.0 { w.bones[k] } else { 0 });
            weights.push(w.weights[k]);
        }
    }
    let a =
        bin.add(&joints_bytes, Some(ARRAY_BUFFER), json!({"componentType": UNSIGNED_BYTE, "count": n, "type": "VEC4"}));
    attributes.insert("JOINTS_0".into(), json!(a));
    let a =
        bin.add(&f32_bytes(weights), Some(ARRAY_BUFFER), json!({"componentType": FLOAT, "count": n, "type": "VEC4"}));
    attributes.insert("WEIGHTS_0".into(), json!(a));
    // Morph targets: each shape key's displacement per glTF vertex (weights 0: the base is
    // the fitted body).
    let mut targets = Vec::with_capacity(scene.shape_keys.len());
    for key in &scene.shape_keys {
        let d: Vec<[f32; 3]> = source.iter().map(|&(v, _)| key.deltas[v as usize]).collect();
        let (mut lo, mut hi) = ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]);
        for p in &d {
            for k in 0..3 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        let a = bin.add(
            &f32_bytes(d.iter().flatten().copied()),
            Some(ARRAY_BUFFER),
            json!({"componentType": FLOAT, "count": n, "type": "VEC3", "min": lo, "max": hi}),
        );
        targets.push(json!({"POSITION": a}));
    }
    let idx: Vec<u8> = tris.iter().flat_map(|i| i.to_le_bytes()).collect();
    let indices = bin.add(
        &idx,
        Some(ELEMENT_ARRAY_BUFFER),
        json!({"componentType": UNSIGNED_INT, "count": tris.len(), "type": "SCALAR"}),
    );
    // Inverse bind matrices: the inverse of each bone's rest transform [F_b | h_b].
    let bones = scene.armature.len();
    let parents = &scene.armature.parents;
    let ibm = f32_bytes((0..bones).flat_map(|b| {
        let m = bind_transform(scene, b).inverse().to_homogeneous();
        m.as_slice().iter().map(|&c| c as f32).collect::<Vec<_>>()
    }));
    let ibm = bin.add(&ibm, None, json!({"componentType": FLOAT, "count": bones, "type": "MAT4"}));

    let locals = posed_locals(scene);
    let mut nodes = Vec::with_capacity(bones + 1);
    for (b, name) in scene.names.iter().enumerate() {
        let children: Vec<usize> = (0..bones).filter(|&c| parents[c] == Some(b)).collect();
        let mut node =
            json!({"name": name, "translation": vec_json(&locals[b].0), "rotation": quat_json(&locals[b].1)});
        if !children.is_empty() {
            node["children"] = json!(children);
        }
        nodes.push(node);
    }
    nodes.push(json!({"name": "body", "mesh": 0, "skin": 0}));
    // The one-frame clip: every bone's rotation and the root's translation at t = 0.
    let mut animations = Vec::new();
    if let Some(clip) = &scene.clip {
        let clip_locals = pose_locals(scene, &clip.pose);
        let time = bin.add(
            &f32_bytes([0.0]),
            None,
            json!({"componentType": FLOAT, "count": 1, "type": "SCALAR", "min": [0.0], "max": [0.0]}),
        );
        let mut samplers = Vec::with_capacity(bones + 1);
        let mut channels = Vec::with_capacity(bones + 1);
        for (b, (_, q)) in clip_locals.iter().enumerate() {
            let c = q.quaternion().coords.normalize();
            let out = bin.add(
                &f32_bytes([c[0], c[1], c[2], c[3]].map(|x| x as f32)),
                None,
                json!({"componentType": FLOAT, "count": 1, "type": "VEC4"}),
            );
            samplers.push(json!({"input": time, "output": out, "interpolation": "STEP"}));
            channels.push(json!({"sampler": samplers.len() - 1, "target": {"node": b, "path": "rotation"}}));
        }
        let t = clip_locals[0].0;
        let out = bin.add(
            &f32_bytes([t.x, t.y, t.z].map(|x| x as f32)),
            None,
            json!({"componentType": FLOAT, "count": 1, "type": "VEC3"}),
        );
        samplers.push(json!({"input": time, "output": out, "interpolation": "STEP"}));
        channels.push(json!({"sampler": samplers.len() - 1, "target": {"node": 0, "path": "translation"}}));
        // IK targets move with the bones they follow: their translations are keyed too.
        for b in (1..bones).filter(|&b| scene.armature.follows[b].is_some()) {
            let t = clip_locals[b].0;
            let out = bin.add(
                &f32_bytes([t.x, t.y, t.z].map(|x| x as f32)),
                None,
                json!({"componentType": FLOAT, "count": 1, "type": "VEC3"}),
            );
            samplers.push(json!({"input": time, "output": out, "interpolation": "STEP"}));
            channels.push(json!({"sampler": samplers.len() - 1, "target": {"node": b, "path": "translation"}}));
        }
        animations.push(json!({"name": clip.name, "samplers": samplers, "channels": channels}));
    }

    let mut material = json!({"name": "skin", "pbrMetallicRoughness": {"baseColorFactor": [0.8, 0.7, 0.65, 1.0], "metallicFactor": 0.0, "roughnessFactor": 0.8}, "doubleSided": true});
    let mut extra = serde_json::Map::new();
    if let Some(png) = texture_png {
        while !bin.data.len().is_multiple_of(4) {
            bin.data.push(0);
        }
        bin.views.push(json!({"buffer": 0, "byteOffset": bin.data.len(), "byteLength": png.len()}));
        bin.data.extend_from_slice(png);
        extra.insert(
            "images".into(),
            json!([{"name": "sketch", "bufferView": bin.views.len() - 1, "mimeType": "image/png"}]),
        );
        extra
            .insert("samplers".into(), json!([{"magFilter": 9729, "minFilter": 9729, "wrapS": 33071, "wrapT": 33071}]));
        extra.insert("textures".into(), json!([{"sampler": 0, "source": 0}]));
        material["pbrMetallicRoughness"]["baseColorFactor"] = json!([1.0, 1.0, 1.0, 1.0]);
        material["pbrMetallicRoughness"]["baseColorTexture"] = json!({"index": 0, "texCoord": 0});
    }
    let mut doc = json!({
        "asset": {"version": "2.0", "generator": format!("sketchbody {}", crate::VERSION)},
        "scene": 0,
        "scenes": [{"name": "body", "nodes": [0, bones]}],
        "nodes": nodes,
        "skins": [{"name": "armature", "inverseBindMatrices": ibm, "skeleton": 0, "joints": (0..bones).collect::<Vec<_>>()}],
        "meshes": [{"name": "body", "primitives": [{"attributes": attributes, "indices": indices, "mode": 4, "material": 0}]}],
        "materials": [material],
        "buffers": [{"byteLength": bin.data.len()}],
        "bufferViews": bin.views,
        "accessors": bin.accessors,
    });
    if !animations.is_empty() {
        doc["animations"] = json!(animations);
    }
    if !targets.is_empty() {
        let names: Vec<&str> = scene.shape_keys.iter().map(|k| k.name.as_str()).collect();
        doc["meshes"][0]["primitives"][0]["targets"] = json!(targets);
        doc["meshes"][0]["weights"] = json!(vec![0.0; targets.len()]);
        doc["meshes"][0]["extras"] = json!({"targetNames": names});
    }
    for (k, v) in extra {
        doc[k] = v;
    }
    let mut text = serde_json::to_vec(&doc).map_err(|e| Error::CorruptData(format!("glTF JSON: {e}")))?;
    while !text.len().is_multiple_of(4) {
        text.push(b' ');
    }
    let mut data = bin.data;
    while !data.len().is_multiple_of(4) {
        data.push(0);
    }
    Glb::new(text, data)
}

/// A .glb file's two chunks (JSON and binary, each padded to 4 bytes) and the headers that go
/// before each.
struct Glb {
    text: Vec<u8>,
    data: Vec<u8>,
    header: [u8; 20],
    bin_header: [u8; 8],
}

impl Glb {
    /// Errors: the file would exceed 4 GiB.
    fn new(text: Vec<u8>, data: Vec<u8>) -> Result<Glb> {
        let total = 12 + 8 + text.len() + 8 + data.len();
        let total32 = u32::try_from(total)
            .map_err(|_| Error::OutOfRange { name: "glb size", detail: format!("{total} bytes exceeds 4 GiB") })?;
        let mut header = [0u8; 20];
        header[..4].copy_from_slice(b"glTF");
        header[4..8].copy_from_slice(&2u32.to_le_bytes());
        header[8..12].copy_from_slice(&total32.to_le_bytes());
        header[12..16].copy_from_slice(&(text.len() as u32).to_le_bytes());
        header[16..].copy_from_slice(b"JSON");
        let mut bin_header = [0u8; 8];
        bin_header[..4].copy_from_slice(&(data.len() as u32).to_le_bytes());
        bin_header[4..].copy_from_slice(b"BIN\0");
        Ok(Glb { text, data, header, bin_header })
    }

    /// The file's bytes in order, as four slices.
    fn parts(&self) -> [&[u8]; 4] {
        [&self.header, &self.text, &self.bin_header, &self.data]
    }
}

/// Writes [`glb_bytes`] to `path` atomically (its chunks one after the other, without the
/// joined copy).
pub fn write_glb(path: &Path, mesh: &RiggedMesh, scene: &RigScene, texture_png: Option<&[u8]>) -> Result<()> {
    write_atomic_parts(path, &build_glb(mesh, scene, texture_png)?.parts())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::body::ik::{solve, IkOptions};
    use crate::body::procedural::random_pose;
    use crate::body::rig::{RigOptions, NUM_RIG_BONES, RIG_BONES};
    use crate::body::{BodyModel, Gender};
    use nalgebra::{Isometry3, Translation3};
    use rand::SeedableRng;

    fn parse(glb: &[u8]) -> Value {
        let jlen = u32::from_le_bytes(glb[12..16].try_into().unwrap()) as usize;
        serde_json::from_slice(&glb[20..20 + jlen]).unwrap()
    }

    /// Reads the JSON chunk back, composes the node transforms and the inverse bind matrices as
    /// a glTF viewer does, and checks the skinned result is the scene's posed vertices.
    #[test]
    fn the_nodes_and_bind_matrices_reproduce_the_posed_body() {
        let model = BodyModel::embedded().unwrap();
        let mesh = RiggedMesh::from_model(&model, Gender::Male, &[]).unwrap();
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
        let pose = solve(&mesh.joints, &random_pose(&mesh.joints, &mut rng, 0.0), &IkOptions::default()).unwrap();
        let scene = RigScene::build(model.rig(), &mesh, &pose, &RigOptions::default()).unwrap();
        let glb = glb_bytes(&mesh, &scene, None).unwrap();
        assert_eq!(&glb[..4], b"glTF");
        assert_eq!(u32::from_le_bytes(glb[8..12].try_into().unwrap()) as usize, glb.len());
        let doc = parse(&glb);
        assert_eq!(doc["scenes"].as_array().unwrap().len(), 1);
        assert_eq!(doc["nodes"].as_array().unwrap().len(), NUM_RIG_BONES + 1);
        assert_eq!(doc["nodes"][9]["name"], "r_elbow");
        let mut global: Vec<nalgebra::Isometry3<f64>> = Vec::new();
        for b in 0..NUM_RIG_BONES {
            let node = &doc["nodes"][b];
            let t: Vec<f64> = serde_json::from_value(node["translation"].clone()).unwrap();
            let r: Vec<f64> = serde_json::from_value(node["rotation"].clone()).unwrap();
            let q = UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(r[3], r[0], r[1], r[2]));
            let local = Isometry3::from_parts(Translation3::new(t[0], t[1], t[2]), q);
            global.push(match RIG_BONES[b].parent {
                None => local,
                Some(p) => global[p] * local,
            });
        }
        let arm = &scene.armature;
        let mut worst = 0.0f64;
        for (i, v) in scene.rest_vertices.iter().enumerate() {
            let x = nalgebra::Point3::new(v[0] as f64, v[1] as f64, v[2] as f64);
            let w = &scene.skin[i];
            let mut p = nalgebra::Vector3::zeros();
            for k in 0..4 {
                let b = w.bones[k] as usize;
                let bind = Isometry3::from_parts(Translation3::from(arm.heads[b]), arm.frames[b]).inverse();
                p += (global[b] * (bind * x)).coords * w.weights[k] as f64;
            }
            let o = scene.posed_vertices[i];
            worst = worst.max((p - nalgebra::Vector3::new(o[0] as f64, o[1] as f64, o[2] as f64)).norm());
        }
        assert!(worst < 1e-5, "glTF skinning differs from the scene's by {worst} m");
        // Feet on the floor, rest and posed.
        let low = |v: &[[f32; 3]]| v.iter().map(|p| p[1]).fold(f32::INFINITY, f32::min);
        assert!(low(&scene.rest_vertices).abs() < 1e-6 && low(&scene.posed_vertices).abs() < 1e-6);
        let other = crate::body::ik::Pose::rest(&random_pose(&mesh.joints, &mut rng, 0.1));
        assert!(RigScene::build(model.rig(), &mesh, &other, &RigOptions::default()).is_err());
    }

    /// The bytes of accessor `a` of `doc` in the binary chunk of `glb`.
    fn accessor_bytes<'g>(glb: &'g [u8], doc: &Value, a: usize) -> &'g [u8] {
        let jlen = u32::from_le_bytes(glb[12..16].try_into().unwrap()) as usize;
        let bin = &glb[20 + jlen + 8..];
        let view = &doc["bufferViews"][doc["accessors"][a]["bufferView"].as_u64().unwrap() as usize];
        let off = view["byteOffset"].as_u64().unwrap() as usize;
        &bin[off..off + view["byteLength"].as_u64().unwrap() as usize]
    }

    /// Little-endian `u32`s / `f32`s of accessor bytes.
    fn u32s(b: &[u8]) -> Vec<u32> {
        b.chunks_exact(4).map(|c| u32::from_le_bytes(c.try_into().unwrap())).collect()
    }

    fn f32s(b: &[u8]) -> Vec<f32> {
        b.chunks_exact(4).map(|c| f32::from_le_bytes(c.try_into().unwrap())).collect()
    }

    /// Reads the binary chunk back as a viewer does: every quad is two triangles (a triangle
    /// one), each index points at the right rest position, and `JOINTS_0` / `WEIGHTS_0` carry each
    /// vertex's skin (bone 0 where the weight is 0, weights summing to 1).
    #[test]
    fn indices_joints_and_weights_read_back() {
        let model = BodyModel::embedded().unwrap();
        let mesh = RiggedMesh::from_model(&model, Gender::Female, &[]).unwrap();
        let pose = crate::body::ik::Pose::rest(&mesh.joints);
        let scene = RigScene::build(model.rig(), &mesh, &pose, &RigOptions::default()).unwrap();
        let glb = glb_bytes(&mesh, &scene, None).unwrap();
        let doc = parse(&glb);
        let prim = &doc["meshes"][0]["primitives"][0];
        let attr = |name: &str| prim["attributes"][name].as_u64().unwrap() as usize;
        let idx = u32s(accessor_bytes(&glb, &doc, prim["indices"].as_u64().unwrap() as usize));
        let tris = mesh.triangles();
        let quads = mesh.quads.iter().filter(|q| q[3] != q[2]).count();
        assert!(quads > 0 && quads < tris.len(), "the body has quads and triangles");
        assert_eq!(tris.len(), quads * 2 + (mesh.quads.len() - quads));
        assert_eq!(idx.len(), 3 * tris.len(), "index count");
        assert_eq!(doc["accessors"][prim["indices"].as_u64().unwrap() as usize]["count"], idx.len());
        let floats = |a: usize| f32s(accessor_bytes(&glb, &doc, a));
        let pos = floats(attr("POSITION"));
        let weights = floats(attr("WEIGHTS_0"));
        let joints = accessor_bytes(&glb, &doc, attr("JOINTS_0"));
        let n = pos.len() / 3;
        assert!(n >= mesh.vertices.len() && weights.len() == 4 * n && joints.len() == 4 * n);
        // glTF vertex -> source vertex, from the triangles in order.
        let mut source = vec![u32::MAX; n];
        for (t, tri) in tris.iter().enumerate() {
            for k in 0..3 {
                let g = idx[3 * t + k] as usize;
                assert!(g < n);
                assert!(source[g] == u32::MAX || source[g] == tri[k], "glTF vertex {g} stands for two vertices");
                source[g] = tri[k];
                let want = scene.rest_vertices[tri[k] as usize];
                assert_eq!(
                    [pos[3 * g], pos[3 * g + 1], pos[3 * g + 2]],
                    want,
                    "position of corner {k} of triangle {t}"
                );
            }
        }
        assert!(source.iter().all(|&s| s != u32::MAX), "every glTF vertex is used");
        let mut multi = 0;
        for (g, &s) in source.iter().enumerate() {
            let skin = &scene.skin[s as usize];
            let w = &weights[4 * g..4 * g + 4];
            assert!((w.iter().sum::<f32>() - 1.0).abs() < 1e-5, "weights of {g} sum to 1");
            for k in 0..4 {
                assert_eq!(w[k], skin.weights[k]);
                let want = if skin.weights[k] > 0.0 { skin.bones[k] } else { 0 };
                assert_eq!(joints[4 * g + k], want, "joint {k} of glTF vertex {g}");
                assert!((joints[4 * g + k] as usize) < NUM_RIG_BONES);
            }
            multi += usize::from(w.iter().filter(|&&x| x > 0.0).count() > 1);
        }
        assert!(multi > n / 10, "blended skin weights are present: {multi} of {n}");
    }

    /// The container as the glTF 2.0 spec lays it out: chunk lengths and every buffer view's
    /// offset multiples of 4, the buffer no longer than its chunk; the node tree is the rig's;
    /// `TEXCOORD_0` is each corner's UV with v flipped (glTF's v runs down); the texture's
    /// bytes are the PNG given; `write_glb` writes exactly these bytes; an unused influence slot
    /// is joint 0; a scene for another vertex count is refused.
    #[test]
    fn layout_tree_uvs_and_texture_read_back() {
        let model = BodyModel::embedded().unwrap();
        let mesh = RiggedMesh::from_model(&model, Gender::Male, &[]).unwrap();
        let pose = crate::body::ik::Pose::rest(&mesh.joints);
        let scene = RigScene::build(model.rig(), &mesh, &pose, &RigOptions::default()).unwrap();
        let png = [0x89, b'P', b'N', b'G', 13, 10, 26]; // 7 bytes: the views after it need padding
        let glb = glb_bytes(&mesh, &scene, Some(&png)).unwrap();
        let jlen = u32::from_le_bytes(glb[12..16].try_into().unwrap()) as usize;
        assert_eq!(&glb[16..20], b"JSON");
        assert_eq!(jlen % 4, 0, "JSON chunk length");
        let blen = u32::from_le_bytes(glb[20 + jlen..24 + jlen].try_into().unwrap()) as usize;
        assert_eq!(&glb[24 + jlen..28 + jlen], b"BIN\0");
        assert_eq!(blen % 4, 0, "BIN chunk length");
        assert_eq!(28 + jlen + blen, glb.len());
        let doc = parse(&glb);
        let buffer_len = doc["buffers"][0]["byteLength"].as_u64().unwrap() as usize;
        assert!(buffer_len <= blen && blen - buffer_len < 4, "buffer {buffer_len} in a chunk of {blen}");
        for (i, v) in doc["bufferViews"].as_array().unwrap().iter().enumerate() {
            let off = v["byteOffset"].as_u64().unwrap() as usize;
            assert_eq!(off % 4, 0, "buffer view {i} offset {off}");
            assert!(off + v["byteLength"].as_u64().unwrap() as usize <= buffer_len);
        }
        // The node tree.
        for b in 0..NUM_RIG_BONES {
            let want: Vec<usize> = (0..NUM_RIG_BONES).filter(|&c| RIG_BONES[c].parent == Some(b)).collect();
            let got: Vec<usize> = match doc["nodes"][b].get("children") {
                Some(c) => serde_json::from_value(c.clone()).unwrap(),
                None => Vec::new(),
            };
            assert_eq!(got, want, "children of node {b}");
        }
        // The texture.
        let image = &doc["images"][0];
        assert_eq!(image["mimeType"], "image/png");
        let view = &doc["bufferViews"][image["bufferView"].as_u64().unwrap() as usize];
        let off = view["byteOffset"].as_u64().unwrap() as usize;
        assert_eq!(&glb[28 + jlen + off..28 + jlen + off + view["byteLength"].as_u64().unwrap() as usize], &png);
        assert_eq!(doc["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"]["index"], 0);
        // UVs per triangle corner, in the writer's triangle order (quads split along 0-2).
        let uvs = mesh.uvs.as_ref().expect("the body model has UVs");
        let prim = &doc["meshes"][0]["primitives"][0];
        let idx = u32s(accessor_bytes(&glb, &doc, prim["indices"].as_u64().unwrap() as usize));
        let tex = f32s(accessor_bytes(&glb, &doc, prim["attributes"]["TEXCOORD_0"].as_u64().unwrap() as usize));
        let mut t = 0;
        for (f, q) in mesh.quads.iter().enumerate() {
            let corners: &[[usize; 3]] = if q[3] == q[2] { &[[0, 1, 2]] } else { &[[0, 1, 2], [0, 2, 3]] };
            for tri in corners {
                for (k, &c) in tri.iter().enumerate() {
                    let g = idx[3 * t + k] as usize;
                    let uv = uvs.coords[uvs.quads[f][c] as usize];
                    assert_eq!([tex[2 * g], tex[2 * g + 1]], [uv[0], 1.0 - uv[1]], "UV of corner {c} of face {f}");
                }
                t += 1;
            }
        }
        assert_eq!(3 * t, idx.len());
        // The file is the bytes.
        let dir = std::env::temp_dir().join(format!("skb-gltf-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("body.glb");
        write_glb(&path, &mesh, &scene, Some(&png)).unwrap();
        assert_eq!(std::fs::read(&path).unwrap(), glb);
        std::fs::remove_dir_all(&dir).unwrap();
        // A scene whose vertex or skin count is not the mesh's.
        let mut short = scene.clone();
        short.rest_vertices.pop();
        assert!(matches!(glb_bytes(&mesh, &short, None), Err(Error::OutOfRange { name: "rig scene", .. })));
        let mut short = scene.clone();
        short.skin.pop();
        assert!(matches!(glb_bytes(&mesh, &short, None), Err(Error::OutOfRange { name: "rig scene", .. })));
        // An unused influence slot (weight 0) is written as joint 0 whatever bone it names
        // (the embedded model already stores 0 there, so name another): the first corner of
        // the first face is glTF vertex 0.
        let mut other = scene.clone();
        let v0 = mesh.quads[0][0] as usize;
        let k = other.skin[v0].weights.iter().position(|&w| w == 0.0).expect("vertex 0 has an unused slot");
        other.skin[v0].bones[k] = 3;
        let glb = glb_bytes(&mesh, &other, None).unwrap();
        let doc = parse(&glb);
        let joints = accessor_bytes(
            &glb,
            &doc,
            doc["meshes"][0]["primitives"][0]["attributes"]["JOINTS_0"].as_u64().unwrap() as usize,
        );
        assert_eq!(joints[k], 0, "unused slot {k} of {:?}", other.skin[v0]);
        let mut bad = scene;
        bad.rest_vertices[7][1] = f32::NAN;
        assert!(matches!(glb_bytes(&mesh, &bad, None), Err(Error::NonFinite { .. })));
    }
}
