//! The FBX writer read back by an independent minimal FBX 7.x binary reader written here from
//! the format's description (node records with end offsets, typed properties, uncompressed or
//! zlib-flagged arrays refused): node counts, the 53 named bones and their hierarchy, weights
//! summing to 1 per vertex, UV and normal counts, the embedded texture, and the posed body
//! reproduced by composing the bones' local transforms (Euler XYZ) with the clusters' bind
//! matrices as a DCC does, for each unit (m, cm) and up axis (Y, Z): the global settings name
//! them and every position is the model frame's turned and scaled as documented. Bad input: an
//! unwritable path writes nothing.

use std::collections::HashMap;
use std::process::Command;

use nalgebra::{Matrix4, Point3, Rotation3, Translation3, Vector3};
use rand::SeedableRng;
use sketchbody::body::ik::{solve, IkOptions};
use sketchbody::body::procedural::random_pose;
use sketchbody::body::rig::shape_keys::ShapeKey;
use sketchbody::body::rig::RiggedMesh;
use sketchbody::body::rig::{PoseAs, RigOptions, RigScene, NUM_RIG_BONES};
use sketchbody::body::{BodyModel, Gender};
use sketchbody::export::fbx::node::{file_bytes, s, Node, Prop};
use sketchbody::export::fbx::{fbx_bytes, write_fbx};
use sketchbody::export::frame::{ExportFrame, Units, UpAxis};
use sketchbody::pipeline::shape_keys::ShapeOrigin;

#[path = "common/frames.rs"]
mod frames;
use frames::{in_frame, metres_to_unit, FRAMES};

#[derive(Debug, Clone)]
enum Value {
    Int(i64),
    Float(f64),
    Bytes(Vec<u8>),
    Ints(Vec<i64>),
    Floats(Vec<f64>),
}

#[derive(Debug)]
struct Rec {
    name: String,
    props: Vec<Value>,
    kids: Vec<Rec>,
}

impl Rec {
    fn kid(&self, name: &str) -> &Rec {
        self.kids.iter().find(|k| k.name == name).unwrap_or_else(|| panic!("{} has no {name}", self.name))
    }
    fn all<'a>(&'a self, name: &'a str) -> impl Iterator<Item = &'a Rec> + 'a {
        self.kids.iter().filter(move |k| k.name == name)
    }
    fn int(&self, i: usize) -> i64 {
        match &self.props[i] {
            Value::Int(v) => *v,
            v => panic!("{}: property {i} is {v:?}", self.name),
        }
    }
    fn text(&self, i: usize) -> String {
        match &self.props[i] {
            Value::Bytes(b) => String::from_utf8_lossy(b).into_owned(),
            v => panic!("{}: property {i} is {v:?}", self.name),
        }
    }
    fn floats(&self) -> Vec<f64> {
        match &self.props[0] {
            Value::Floats(v) => v.clone(),
            v => panic!("{}: {v:?}", self.name),
        }
    }
    fn ints(&self) -> Vec<i64> {
        match &self.props[0] {
            Value::Ints(v) => v.clone(),
            v => panic!("{}: {v:?}", self.name),
        }
    }
    /// A `Properties70` entry's values by name.
    fn p70(&self, name: &str) -> Option<Vec<f64>> {
        let p = self.kids.iter().find(|k| k.name == "Properties70")?.all("P").find(|p| p.text(0) == name)?;
        Some(
            p.props[4..]
                .iter()
                .map(|v| match v {
                    Value::Float(f) => *f,
                    Value::Int(i) => *i as f64,
                    v => panic!("{v:?}"),
                })
                .collect(),
        )
    }
}

struct Reader<'a> {
    data: &'a [u8],
    at: usize,
}

impl Reader<'_> {
    fn take(&mut self, n: usize) -> &[u8] {
        let s = &self.data[self.at..self.at + n];
        self.at += n;
        s
    }
    fn u32(&mut self) -> usize {
        u32::from_le_bytes(self.take(4).try_into().unwrap()) as usize
    }
    fn array(&mut self, width: usize) -> Vec<[u8; 8]> {
        let (count, encoding, len) = (self.u32(), self.u32(), self.u32());
        assert_eq!(encoding, 0, "compressed arrays are not expected");
        assert_eq!(len, count * width);
        self.take(len)
            .chunks_exact(width)
            .map(|c| {
                let mut b = [0u8; 8];
                b[..width].copy_from_slice(c);
                b
            })
            .collect()
    }
    fn value(&mut self) -> Value {
        let code = self.take(1)[0];
        match code {
            b'C' => Value::Int(self.take(1)[0] as i64),
            b'Y' => Value::Int(i16::from_le_bytes(self.take(2).try_into().unwrap()) as i64),
            b'I' => Value::Int(i32::from_le_bytes(self.take(4).try_into().unwrap()) as i64),
            b'L' => Value::Int(i64::from_le_bytes(self.take(8).try_into().unwrap())),
            b'F' => Value::Float(f32::from_le_bytes(self.take(4).try_into().unwrap()) as f64),
            b'D' => Value::Float(f64::from_le_bytes(self.take(8).try_into().unwrap())),
            b'S' | b'R' => {
                let n = self.u32();
                Value::Bytes(self.take(n).to_vec())
            }
            b'i' => Value::Ints(
                self.array(4).iter().map(|b| i32::from_le_bytes(b[..4].try_into().unwrap()) as i64).collect(),
            ),
            b'l' => Value::Ints(self.array(8).iter().map(|b| i64::from_le_bytes(*b)).collect()),
            b'd' => Value::Floats(self.array(8).iter().map(|b| f64::from_le_bytes(*b)).collect()),
            b'f' => Value::Floats(
                self.array(4).iter().map(|b| f32::from_le_bytes(b[..4].try_into().unwrap()) as f64).collect(),
            ),
            c => panic!("unknown property type {:?} at {}", c as char, self.at - 1),
        }
    }
    /// One record, or `None` at a null record.
    fn record(&mut self) -> Option<Rec> {
        let (end, count, props_len) = (self.u32(), self.u32(), self.u32());
        let name_len = self.take(1)[0] as usize;
        if end == 0 {
            assert_eq!((count, props_len, name_len), (0, 0, 0), "null record");
            return None;
        }
        let name = String::from_utf8(self.take(name_len).to_vec()).unwrap();
        let start = self.at;
        let props: Vec<Value> = (0..count).map(|_| self.value()).collect();
        assert_eq!(self.at - start, props_len, "property bytes of {name}");
        let mut kids = Vec::new();
        if self.at < end {
            while let Some(k) = self.record() {
                kids.push(k);
            }
        }
        assert_eq!(self.at, end, "end offset of {name}");
        Some(Rec { name, props, kids })
    }
}

/// Parses a whole file into a root record holding the top-level records.
fn parse(data: &[u8]) -> Rec {
    assert_eq!(&data[..23], b"Kaydara FBX Binary  \x00\x1a\x00");
    let version = u32::from_le_bytes(data[23..27].try_into().unwrap());
    assert!((7400..7500).contains(&version), "version {version}");
    let mut r = Reader { data, at: 27 };
    let mut kids = Vec::new();
    while let Some(k) = r.record() {
        kids.push(k);
    }
    assert_eq!(data.len() % 16, 0, "the footer pads the file to 16 bytes");
    assert!(data.len() - r.at >= 160, "footer");
    Rec { name: String::new(), props: Vec::new(), kids }
}

fn name_of(r: &Rec) -> (String, String) {
    let t = r.text(1);
    let (n, class) = t.split_once("\u{0}\u{1}").unwrap_or_else(|| panic!("object name {t:?}"));
    (n.to_string(), class.to_string())
}

fn mat(v: &[f64]) -> Matrix4<f64> {
    Matrix4::from_column_slice(v)
}

fn scene(gender: Gender, seed: u64) -> (RiggedMesh, RigScene) {
    let model = BodyModel::embedded().unwrap();
    let mesh = RiggedMesh::from_model(&model, gender, &[]).unwrap();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let pose = solve(&mesh.joints, &random_pose(&mesh.joints, &mut rng, 0.0), &IkOptions::default()).unwrap();
    let scene = RigScene::build(model.rig(), &mesh, &pose, &RigOptions::default()).unwrap();
    (mesh, scene)
}

#[test]
fn an_independent_reader_finds_the_skinned_posed_body() {
    let (mesh, scene) = scene(Gender::Female, 11);
    for frame in FRAMES {
        check_file(&mesh, &scene, &frame);
    }
}

/// The file of `scene` in `frame` read back: settings, bones, geometry, skin, pose, texture.
fn check_file(mesh: &RiggedMesh, scene: &RigScene, frame: &ExportFrame) {
    let nb = scene.armature.len();
    let parents = &scene.armature.parents;
    let png = b"\x89PNG\r\n\x1a\n-not-really".to_vec();
    let bytes = fbx_bytes(mesh, scene, Some(&png), frame).unwrap();
    let root = parse(&bytes);
    let settings = root.kid("GlobalSettings");
    // Up, front (toward the viewer: the way the character faces) and the third axis, each as
    // (axis index, sign); FBX's unit is centimetres per file unit.
    let (up, front) = match frame.up {
        UpAxis::Y => ([1.0, 1.0], [2.0, 1.0]),
        UpAxis::Z => ([2.0, 1.0], [1.0, -1.0]),
    };
    let g = |name: &str| settings.p70(name).unwrap_or_else(|| panic!("no {name}"))[0];
    assert_eq!([g("UpAxis"), g("UpAxisSign")], up, "{frame:?}");
    assert_eq!([g("FrontAxis"), g("FrontAxisSign")], front, "{frame:?}");
    assert_eq!([g("CoordAxis"), g("CoordAxisSign")], [0.0, 1.0], "{frame:?}");
    assert_eq!([g("OriginalUpAxis"), g("OriginalUpAxisSign")], up, "{frame:?}");
    let cm = if frame.units == Units::Centimetres { 1.0 } else { 100.0 };
    assert_eq!([g("UnitScaleFactor"), g("OriginalUnitScaleFactor")], [cm, cm], "{frame:?}");
    let objects = root.kid("Objects");
    let by_id: HashMap<i64, &Rec> = objects.kids.iter().map(|o| (o.int(0), o)).collect();
    let mut parent: HashMap<i64, i64> = HashMap::new();
    let mut children: HashMap<i64, Vec<i64>> = HashMap::new();
    let mut property_links = Vec::new();
    for c in root.kid("Connections").all("C") {
        match c.text(0).as_str() {
            "OO" => {
                children.entry(c.int(2)).or_default().push(c.int(1));
                // A bone is also linked to its cluster: its parent in the tree is a model.
                if by_id.get(&c.int(2)).is_some_and(|o| o.name == "Model") {
                    assert!(parent.insert(c.int(1), c.int(2)).is_none(), "two parent models");
                }
            }
            "OP" => property_links.push((c.int(1), c.int(2), c.text(3))),
            k => panic!("connection kind {k}"),
        }
    }
    // The bones: 53 LimbNode models named as the scene's, parented as the rig.
    let bones: Vec<&Rec> = objects.all("Model").filter(|m| m.text(2) == "LimbNode").collect();
    assert_eq!(bones.len(), nb);
    let index: HashMap<String, usize> = scene.names.iter().enumerate().map(|(i, n)| (n.clone(), i)).collect();
    let bone_of: HashMap<i64, usize> = bones.iter().map(|m| (m.int(0), index[&name_of(m).0])).collect();
    assert_eq!(bone_of.len(), nb, "distinct bone names");
    for (&id, &b) in &bone_of {
        let up = parent[&id];
        match parents[b] {
            Some(p) => assert_eq!(bone_of.get(&up), Some(&p), "parent of {}", scene.names[b]),
            None => assert_eq!(by_id[&up].text(2), "Null", "the root bone hangs from the armature"),
        }
        let attr = children[&id].iter().filter_map(|c| by_id.get(c)).find(|o| o.name == "NodeAttribute").unwrap();
        assert_eq!(attr.text(2), "LimbNode");
    }
    // The geometry: polygons, normals per vertex, UVs per corner.
    let geom = objects.all("Geometry").next().unwrap();
    let n = mesh.vertices.len();
    let verts = geom.kid("Vertices").floats();
    assert_eq!(verts.len(), 3 * n);
    let polys = geom.kid("PolygonVertexIndex").ints();
    assert_eq!(polys.iter().filter(|&&i| i < 0).count(), mesh.quads.len(), "one polygon per face");
    assert!(polys.iter().all(|&i| (if i < 0 { -i - 1 } else { i }) < n as i64));
    assert_eq!(geom.kid("LayerElementNormal").kid("Normals").floats().len(), 3 * n);
    let uv = geom.kid("LayerElementUV");
    let uvs = mesh.uvs.as_ref().unwrap();
    assert_eq!(uv.kid("UV").floats().len(), 2 * uvs.coords.len(), "UV count");
    let uv_index = uv.kid("UVIndex").ints();
    assert_eq!(uv_index.len(), polys.len());
    let first = mesh.quads[0];
    assert_eq!(uv_index[0] as u32, uvs.quads[0][0]);
    assert_eq!(polys[0] as u32, first[0]);
    // The skin: one skin on the geometry, one cluster per bone, weights summing to 1.
    let skin_id = children[&geom.int(0)].iter().copied().find(|c| by_id[c].text(2) == "Skin").unwrap();
    let clusters = &children[&skin_id];
    assert_eq!(clusters.len(), nb);
    let mut sums = vec![0.0f64; n];
    let mut influences: Vec<Vec<(usize, f64)>> = vec![Vec::new(); n];
    let mut bind: HashMap<usize, Matrix4<f64>> = HashMap::new();
    for c in clusters {
        let cl = by_id[c];
        assert_eq!(cl.text(2), "Cluster");
        let b = bone_of[children[c].iter().find(|k| bone_of.contains_key(k)).unwrap()];
        let link = mat(&cl.kid("TransformLink").floats());
        let transform = mat(&cl.kid("Transform").floats());
        assert!((link * transform - Matrix4::identity()).abs().max() < 1e-9, "Transform is the inverse bind");
        bind.insert(b, link);
        let Some(indexes) = cl.kids.iter().find(|k| k.name == "Indexes") else {
            assert!(cl.kids.iter().all(|k| k.name != "Weights"), "weights without indexes");
            continue;
        };
        assert_eq!(indexes.ints().len(), cl.kid("Weights").floats().len(), "one weight per index");
        for (i, w) in indexes.ints().iter().zip(cl.kid("Weights").floats()) {
            sums[*i as usize] += w;
            influences[*i as usize].push((b, w));
        }
    }
    assert!(sums.iter().all(|s| (s - 1.0).abs() < 1e-5), "weights sum to 1 per vertex");
    // The pose: compose the bones' local transforms (Euler XYZ degrees: Rz Ry Rx) down the tree.
    let mut global = vec![Matrix4::identity(); nb];
    let order: Vec<usize> = (0..nb).collect(); // parents come first
    let model_of: HashMap<usize, &Rec> = bones.iter().map(|m| (bone_of[&m.int(0)], *m)).collect();
    for &b in &order {
        let m = model_of[&b];
        let t = m.p70("Lcl Translation").unwrap();
        let r = m.p70("Lcl Rotation").unwrap();
        let rot = Rotation3::from_axis_angle(&Vector3::z_axis(), r[2].to_radians())
            * Rotation3::from_axis_angle(&Vector3::y_axis(), r[1].to_radians())
            * Rotation3::from_axis_angle(&Vector3::x_axis(), r[0].to_radians());
        let local = Translation3::new(t[0], t[1], t[2]).to_homogeneous() * rot.to_homogeneous();
        global[b] = match parents[b] {
            Some(p) => global[p] * local,
            None => local,
        };
    }
    let mut worst = 0.0f64;
    let mut rest_worst = 0.0f64;
    let unit = metres_to_unit(frame);
    for v in 0..n {
        let x = Point3::new(verts[3 * v], verts[3 * v + 1], verts[3 * v + 2]);
        rest_worst = rest_worst.max((x.coords - in_frame(frame, scene.rest_vertices[v])).norm() / unit);
        let mut p = Vector3::zeros();
        for &(b, w) in &influences[v] {
            p += (global[b] * bind[&b].try_inverse().unwrap()).transform_point(&x).coords * w;
        }
        worst = worst.max((p - in_frame(frame, scene.posed_vertices[v])).norm() / unit);
    }
    assert!(rest_worst < 1e-6, "{frame:?}: the FBX's rest vertices differ from the scene's by {rest_worst} m");
    assert!(worst < 1e-5, "{frame:?}: the FBX's skinning differs from the scene's by {worst} m");
    // Normals turn with the axes and keep unit length.
    let normals = geom.kid("LayerElementNormal").kid("Normals").floats();
    let rest_normals = sketchbody::body::rig::vertex_normals(&scene.rest_vertices, &mesh.quads);
    let turned = |k: usize| in_frame(&ExportFrame { units: Units::Metres, ..*frame }, rest_normals[k]);
    let normal_gap = (0..n)
        .map(|k| (Vector3::new(normals[3 * k], normals[3 * k + 1], normals[3 * k + 2]) - turned(k)).norm())
        .fold(0.0, f64::max);
    assert!(normal_gap < 1e-6, "{frame:?}: normals differ by {normal_gap}");
    // The bind pose lists the mesh, the armature and every bone.
    let pose = objects.all("Pose").next().unwrap();
    assert_eq!(pose.kid("NbPoseNodes").int(0) as usize, nb + 2);
    assert_eq!(pose.all("PoseNode").count(), nb + 2);
    // The texture: material -> texture (DiffuseColor) -> video holding the PNG.
    let (tex, mat_id, prop) = property_links.first().unwrap().clone();
    assert_eq!(
        (by_id[&tex].name.as_str(), by_id[&mat_id].name.as_str(), prop.as_str()),
        ("Texture", "Material", "DiffuseColor")
    );
    let video = by_id[&children[&tex][0]];
    match &video.kid("Content").props[0] {
        Value::Bytes(b) => assert_eq!(b, &png),
        v => panic!("{v:?}"),
    }
    // Without a texture: no texture or video objects.
    let plain = parse(&fbx_bytes(mesh, scene, None, frame).unwrap());
    assert!(plain.kid("Objects").kids.iter().all(|o| o.name != "Texture" && o.name != "Video"));
}

#[test]
fn an_unwritable_path_or_a_mismatched_scene_writes_nothing() {
    let (mesh, scene) = scene(Gender::Male, 2);
    let dir = std::env::temp_dir().join(format!("skb-fbx-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let missing = dir.join("no-such-folder").join("body.fbx");
    let frame = ExportFrame { units: Units::Centimetres, up: UpAxis::Z };
    let e = write_fbx(&missing, &mesh, &scene, None, &frame).unwrap_err();
    assert!(matches!(e, sketchbody::Error::Io { .. }), "{e:?}");
    let mut short = scene.clone();
    short.skin.pop();
    let path = dir.join("body.fbx");
    assert!(matches!(write_fbx(&path, &mesh, &short, None, &frame), Err(sketchbody::Error::OutOfRange { .. })));
    assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 0, "nothing written");
    write_fbx(&path, &mesh, &scene, None, &frame).unwrap();
    assert_eq!(std::fs::read(&path).unwrap(), fbx_bytes(&mesh, &scene, None, &frame).unwrap());
    // An unknown unit or axis name is refused by name before anything is written.
    let e = Units::parse("mm").unwrap_err().to_string();
    assert!(e.contains("units") && e.contains("\"mm\"") && e.contains("m or cm"), "{e}");
    let e = UpAxis::parse("x").unwrap_err().to_string();
    assert!(e.contains("up axis") && e.contains("\"x\"") && e.contains("y or z"), "{e}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// True (after printing SKIPPED) when assimp is not installed; panics instead when
/// SKB_REQUIRE_SHARED_DATA is set.
fn assimp_missing() -> bool {
    if Command::new("assimp").arg("version").output().map(|o| o.status.success()).unwrap_or(false) {
        return false;
    }
    if std::env::var_os("SKB_REQUIRE_SHARED_DATA").is_some() {
        panic!("assimp is not installed (assimp-utils), but SKB_REQUIRE_SHARED_DATA is set");
    }
    eprintln!("SKIPPED assimp FBX check: assimp is not installed");
    true
}

/// A second, independent reader: assimp (`assimp info`, Debian's assimp-utils) loads the FBX
/// and finds one mesh with every vertex, the 53 bones, the material and the embedded texture;
/// then, for each unit and up axis, `assimp export` to assimp's JSON (assimp applies no unit or
/// axis conversion of its own): the mesh's rest vertices span the body's box in the file's frame
/// (each axis's lowest and highest value, so a turned or mirrored axis or a wrong unit shows)
/// and the bones' node transforms, composed down assimp's node tree, put every bone's posed head
/// where the scene's posed head lands in that frame, within 0.1 mm. Without assimp the test
/// prints SKIPPED, or fails when SKB_REQUIRE_SHARED_DATA is set.
#[test]
fn assimp_reads_the_fbx() {
    if assimp_missing() {
        return;
    }
    let (mesh, scene) = scene(Gender::Female, 6);
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("assimp-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let data = (0..16).flat_map(|i| [(i % 4 * 60) as u8, (i / 4 * 60) as u8, 90]).collect();
    let img = sketchbody::image::RgbImage::from_vec(4, 4, data).unwrap();
    let png = sketchbody::image::encode_png(&img.view()).unwrap();
    let path = dir.join("body.fbx");
    write_fbx(&path, &mesh, &scene, Some(&png), &FRAMES[0]).unwrap();
    let out = Command::new("assimp").arg("info").arg(&path).output().unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    println!("{text}");
    assert!(out.status.success(), "assimp failed:\n{text}\n{}", String::from_utf8_lossy(&out.stderr));
    let field = |name: &str| -> u64 {
        let line = text.lines().find(|l| l.trim_start().starts_with(name)).unwrap_or_else(|| panic!("no {name}"));
        line.split(':').nth(1).unwrap().split_whitespace().next().unwrap().parse().unwrap()
    };
    assert_eq!(field("Meshes:"), 1);
    assert_eq!(field("Faces:"), mesh.triangles().len() as u64, "assimp triangulates");
    assert_eq!(field("Bones:"), NUM_RIG_BONES as u64);
    assert_eq!(field("Textures (embed.):"), 1);
    let heads = posed_heads(&scene);
    for frame in FRAMES {
        write_fbx(&path, &mesh, &scene, None, &frame).unwrap();
        let json = dir.join("body.json");
        let out = Command::new("assimp").arg("export").arg(&path).arg(&json).arg("-fassjson").output().unwrap();
        assert!(out.status.success(), "assimp export failed: {}", String::from_utf8_lossy(&out.stderr));
        let doc: serde_json::Value = serde_json::from_slice(&std::fs::read(&json).unwrap()).unwrap();
        let unit = metres_to_unit(&frame);
        // The rest mesh's box along each axis.
        let v: Vec<f64> =
            doc["meshes"][0]["vertices"].as_array().unwrap().iter().map(|x| x.as_f64().unwrap()).collect();
        assert!(v.len() >= 3 * mesh.vertices.len(), "{frame:?}: {} coordinates", v.len());
        for k in 0..3 {
            let span =
                |it: &mut dyn Iterator<Item = f64>| it.fold((f64::MAX, f64::MIN), |(a, b), x| (a.min(x), b.max(x)));
            let got = span(&mut v.iter().skip(k).step_by(3).copied());
            let want = span(&mut scene.rest_vertices.iter().map(|&p| in_frame(&frame, p)[k]));
            let gap = (got.0 - want.0).abs().max((got.1 - want.1).abs()) / unit;
            assert!(gap < 1e-4, "{frame:?}: axis {k} spans {got:?} in assimp, {want:?} expected");
        }
        // The posed bone heads from assimp's node tree (row-major matrices, translation in the
        // fourth column).
        let mut found = HashMap::new();
        node_heads(&doc["rootnode"], &Matrix4::identity(), &mut found);
        let mut worst = 0.0f64;
        for (b, name) in scene.names.iter().enumerate() {
            let got = found.get(name).unwrap_or_else(|| panic!("{frame:?}: assimp has no node {name}"));
            let want = in_frame(&frame, heads[b].map(|c| c as f32));
            worst = worst.max((got - want).norm() / unit);
        }
        println!("assimp {frame:?}: posed bone heads within {worst:.2e} m");
        assert!(worst < 1e-4, "{frame:?}: assimp's posed bone heads differ by {worst} m");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// assimp on the issue-49 options: twist bones, IK targets and three shape keys, the pose as an
/// action (Z up, centimetres): assimp finds a bone per cluster (66, the IK targets' empty), every
/// bone's node, the IK targets included, at the scene's posed head within 0.1 mm, and the three
/// blend shapes as animation meshes (through its glTF export: each target's displacement of
/// every vertex the key's within 0.1 mm).
#[test]
fn assimp_reads_twist_bones_ik_targets_and_shape_keys() {
    if assimp_missing() {
        return;
    }
    let model = BodyModel::embedded().unwrap();
    let mesh = RiggedMesh::from_model(&model, Gender::Male, &[]).unwrap();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(14);
    let pose = solve(&mesh.joints, &random_pose(&mesh.joints, &mut rng, 0.0), &IkOptions::default()).unwrap();
    let options = RigOptions { twist_bones: true, ik_targets: true, ..RigOptions::default() };
    let keys = mean_keys(&model, Gender::Male, 3);
    let scene = RigScene::build_with_shape_keys(model.rig(), &mesh, &pose, &options, &keys).unwrap();
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("assimp-rig-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("body.fbx");
    let frame = FRAMES[3];
    write_fbx(&path, &mesh, &scene, None, &frame).unwrap();
    let out = Command::new("assimp").arg("info").arg(&path).output().unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    println!("{text}");
    assert!(out.status.success(), "assimp failed:\n{text}\n{}", String::from_utf8_lossy(&out.stderr));
    let json = dir.join("body.json");
    let out = Command::new("assimp").arg("export").arg(&path).arg(&json).arg("-fassjson").output().unwrap();
    assert!(out.status.success(), "assimp export failed: {}", String::from_utf8_lossy(&out.stderr));
    let doc: serde_json::Value = serde_json::from_slice(&std::fs::read(&json).unwrap()).unwrap();
    assert_eq!(doc["meshes"][0]["bones"].as_array().unwrap().len(), scene.names.len());
    // The blend shapes as assimp's glTF exporter writes the animation meshes it read: each
    // target's displacement of each vertex (matched to the scene's by its rest position).
    let gltf = dir.join("body.gltf");
    let out = Command::new("assimp").arg("export").arg(&path).arg(&gltf).arg("-fgltf2").output().unwrap();
    assert!(out.status.success(), "assimp glTF export failed: {}", String::from_utf8_lossy(&out.stderr));
    let g: serde_json::Value = serde_json::from_slice(&std::fs::read(&gltf).unwrap()).unwrap();
    let bin = std::fs::read(dir.join(g["buffers"][0]["uri"].as_str().unwrap())).unwrap();
    let vec3s = |accessor: &serde_json::Value| -> Vec<Vector3<f64>> {
        let a = &g["accessors"][accessor.as_u64().unwrap() as usize];
        let view = &g["bufferViews"][a["bufferView"].as_u64().unwrap() as usize];
        let start = view["byteOffset"].as_u64().unwrap_or(0) as usize + a["byteOffset"].as_u64().unwrap_or(0) as usize;
        let f = |i: usize| f32::from_le_bytes(bin[start + 4 * i..start + 4 * i + 4].try_into().unwrap()) as f64;
        (0..a["count"].as_u64().unwrap() as usize).map(|i| Vector3::new(f(3 * i), f(3 * i + 1), f(3 * i + 2))).collect()
    };
    let primitive = &g["meshes"][0]["primitives"][0];
    let targets = primitive["targets"].as_array().expect("assimp read the blend shapes");
    assert_eq!(targets.len(), keys.len());
    let unit = metres_to_unit(&frame);
    let rest: Vec<Vector3<f64>> = scene.rest_vertices.iter().map(|&p| in_frame(&frame, p)).collect();
    let cell = |p: &Vector3<f64>| [p.x, p.y, p.z].map(|c| (c / (1e-3 * unit)).round() as i64);
    let mut by_cell: HashMap<[i64; 3], Vec<usize>> = HashMap::new();
    for (i, p) in rest.iter().enumerate() {
        by_cell.entry(cell(p)).or_default().push(i);
    }
    let points = vec3s(&primitive["attributes"]["POSITION"]);
    let matched: Vec<Vec<usize>> = points
        .iter()
        .map(|p| {
            let near = by_cell.get(&cell(p)).cloned().unwrap_or_default();
            let near: Vec<usize> = near.into_iter().filter(|&i| (rest[i] - p).norm() < 1e-4 * unit).collect();
            if near.is_empty() {
                (0..rest.len()).filter(|&i| (rest[i] - p).norm() < 1e-4 * unit).collect()
            } else {
                near
            }
        })
        .collect();
    assert!(matched.iter().all(|m| !m.is_empty()), "every assimp vertex is a rest vertex");
    for (target, key) in targets.iter().zip(&scene.shape_keys) {
        let d = vec3s(&target["POSITION"]);
        let gap = d
            .iter()
            .zip(&matched)
            .map(|(d, m)| m.iter().map(|&i| (d - in_frame(&frame, key.deltas[i])).norm()).fold(f64::INFINITY, f64::min))
            .fold(0.0, f64::max)
            / unit;
        println!("assimp: {} within {gap:.2e} m", key.name);
        assert!(gap < 1e-4, "assimp's {} differs by {gap} m", key.name);
    }
    let mut found = HashMap::new();
    node_heads(&doc["rootnode"], &Matrix4::identity(), &mut found);
    let heads = posed_heads(&scene);
    let mut worst = 0.0f64;
    for (b, name) in scene.names.iter().enumerate() {
        let got = found.get(name).unwrap_or_else(|| panic!("assimp has no node {name}"));
        worst = worst.max((got - in_frame(&frame, heads[b].map(|c| c as f32))).norm() / unit);
    }
    println!("assimp: {} bone nodes, posed heads within {worst:.2e} m", scene.names.len());
    assert!(worst < 1e-4, "assimp's posed bone heads differ by {worst} m");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Each node's global translation (`transformation`: 16 row-major numbers) by name, composed
/// from `parent`.
fn node_heads(node: &serde_json::Value, parent: &Matrix4<f64>, out: &mut HashMap<String, Vector3<f64>>) {
    let m: Vec<f64> = node["transformation"].as_array().unwrap().iter().map(|x| x.as_f64().unwrap()).collect();
    let global = parent * Matrix4::from_row_slice(&m);
    out.insert(
        node["name"].as_str().unwrap().to_string(),
        Vector3::new(global[(0, 3)], global[(1, 3)], global[(2, 3)]),
    );
    for child in node["children"].as_array().into_iter().flatten() {
        node_heads(child, &global, out);
    }
}

/// The scene's posed bone heads (metres, model frame), composed from the bones' posed local
/// transforms.
fn posed_heads(scene: &RigScene) -> Vec<[f64; 3]> {
    let locals = sketchbody::export::rigged::posed_locals(scene);
    let mut global: Vec<Matrix4<f64>> = Vec::with_capacity(locals.len());
    for (b, (t, q)) in locals.iter().enumerate() {
        let local = Translation3::from(*t).to_homogeneous() * q.to_homogeneous();
        let g = scene.armature.parents[b].map_or(local, |p| global[p] * local);
        global.push(g);
    }
    global.iter().map(|g| [g[(0, 3)], g[(1, 3)], g[(2, 3)]]).collect()
}

/// The layout by hand: a record's end offset, property count and length, the null record
/// closing a nested list, an empty record closed by a null record, and a file length that is
/// a multiple of 16 ending in the closing magic.
#[test]
fn records_and_footer_lay_out_as_documented() {
    let leaf = Node::new("B", vec![Prop::I32(7), s("xy")]);
    let file = file_bytes(&[Node::new("A", vec![]).with(vec![leaf]), Node::new("E", vec![])]).unwrap();
    assert_eq!(&file[..23], b"Kaydara FBX Binary  \x00\x1a\x00");
    assert_eq!(u32::from_le_bytes(file[23..27].try_into().unwrap()), 7400);
    let u = |at: usize| u32::from_le_bytes(file[at..at + 4].try_into().unwrap()) as usize;
    // A at 27: header 13 + name 1; B at 41: header 13 + name 1 + I (5) + S (1 + 4 + 2).
    assert_eq!((u(27 + 4), u(27 + 8), file[27 + 12], file[27 + 13]), (0, 0, 1, b'A'));
    let b = 41;
    assert_eq!((u(b + 4), u(b + 8), file[b + 13]), (2, 12, b'B'));
    assert_eq!(u(b), b + 14 + 12, "B's end offset");
    assert_eq!(&file[b + 14..b + 15], b"I");
    assert_eq!(u(27), u(b) + 13, "A ends after B and its null record");
    assert!(file[u(b)..u(b) + 13].iter().all(|&x| x == 0));
    let e = u(27);
    assert_eq!(u(e), e + 14 + 13, "an empty record is closed by a null record");
    assert_eq!(file.len() % 16, 0);
    assert_eq!(&file[file.len() - 16..file.len() - 12], &[0xf8, 0x5a, 0x8c, 0x6a]);
    assert_eq!(u(file.len() - 140), 7400);
}

/// Shape keys of the mean body: the first `n` principal components of its space, one standard
/// deviation each (model frame), as the library makes them.
fn mean_keys(model: &BodyModel, gender: Gender, n: usize) -> Vec<ShapeKey> {
    let origin = ShapeOrigin { space: gender.into(), weights: Vec::new(), proportions: None, scale: 1.0 };
    origin.keys(model).unwrap().into_iter().take(n).collect()
}

/// The rig options of issue 49 read back by the independent reader: twist bones, IK targets and
/// shape keys with the pose as the rest, in every unit and up axis (the bones, skin, bind pose
/// and body as [`check_file`] reads them; no animation stack); each blend shape's channel and
/// shape geometry holding the key's displacements in the file's frame; and with the pose as
/// both, the animation stack `a_pose` whose single keys, composed down the tree, stand every
/// bone at its A-pose bind transform (the pose as an action's).
#[test]
fn twist_bones_ik_targets_shape_keys_and_the_pose_as_rest_read_back() {
    let model = BodyModel::embedded().unwrap();
    let mesh = RiggedMesh::from_model(&model, Gender::Female, &[]).unwrap();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(12);
    let pose = solve(&mesh.joints, &random_pose(&mesh.joints, &mut rng, 0.0), &IkOptions::default()).unwrap();
    let keys = mean_keys(&model, Gender::Female, 3);
    let options = |pose_as| RigOptions { twist_bones: true, ik_targets: true, pose_as, ..RigOptions::default() };
    let rest = RigScene::build_with_shape_keys(model.rig(), &mesh, &pose, &options(PoseAs::Rest), &keys).unwrap();
    assert_eq!(rest.armature.len(), NUM_RIG_BONES + 6 + 7);
    for frame in FRAMES {
        check_file(&mesh, &rest, &frame);
        let root = parse(&fbx_bytes(&mesh, &rest, None, &frame).unwrap());
        let objects = root.kid("Objects");
        assert!(objects.all("AnimationStack").next().is_none(), "the pose as rest has no animation");
        let shapes: Vec<&Rec> = objects.all("Geometry").filter(|g| g.text(2) == "Shape").collect();
        assert_eq!(shapes.len(), keys.len());
        let channels: Vec<&Rec> = objects.all("Deformer").filter(|d| d.text(2) == "BlendShapeChannel").collect();
        assert_eq!(channels.len(), keys.len());
        assert!(channels.iter().all(|c| matches!(c.kid("DeformPercent").props[0], Value::Float(x) if x == 0.0)));
        let unit = metres_to_unit(&frame);
        for (shape, key) in shapes.iter().zip(&rest.shape_keys) {
            assert_eq!(name_of(shape).0, key.name);
            let idx = shape.kid("Indexes").ints();
            let v = shape.kid("Vertices").floats();
            assert_eq!((idx.len(), v.len()), (mesh.vertices.len(), 3 * mesh.vertices.len()));
            let gap = idx
                .iter()
                .map(|&i| {
                    let i = i as usize;
                    let got = Vector3::new(v[3 * i], v[3 * i + 1], v[3 * i + 2]);
                    let d = key.deltas[i];
                    // A displacement turns and scales as a point from the origin does.
                    (got - in_frame(&frame, d)).norm() / unit
                })
                .fold(0.0, f64::max);
            assert!(gap < 1e-6, "{frame:?}: {} differs by {gap} m", key.name);
        }
    }
    // The pose as both: the clip back to the A-pose.
    let both = RigScene::build(model.rig(), &mesh, &pose, &options(PoseAs::Both)).unwrap();
    let frame = FRAMES[3];
    let root = parse(&fbx_bytes(&mesh, &both, None, &frame).unwrap());
    let objects = root.kid("Objects");
    let stack = objects.all("AnimationStack").next().expect("an animation stack");
    assert_eq!(name_of(stack).0, "a_pose");
    let by_id: HashMap<i64, &Rec> = objects.kids.iter().map(|o| (o.int(0), o)).collect();
    let bones: HashMap<i64, usize> = objects
        .all("Model")
        .filter(|m| m.text(2) == "LimbNode")
        .map(|m| (m.int(0), both.names.iter().position(|n| *n == name_of(m).0).unwrap()))
        .collect();
    // Each bone's T and R curve nodes, each axis's single key.
    let nb = both.armature.len();
    let mut keyed = vec![[[f64::NAN; 3]; 2]; nb];
    let mut curve_of: HashMap<i64, (usize, usize)> = HashMap::new();
    for c in root.kid("Connections").all("C").filter(|c| c.text(0) == "OP") {
        let (child, parent, prop) = (c.int(1), c.int(2), c.text(3));
        if let (Some(&b), "Lcl Translation" | "Lcl Rotation") = (bones.get(&parent), prop.as_str()) {
            curve_of.insert(child, (b, usize::from(prop == "Lcl Rotation")));
        }
    }
    assert_eq!(curve_of.len(), 2 * nb, "a T and an R curve node per bone");
    for c in root.kid("Connections").all("C").filter(|c| c.text(0) == "OP") {
        if let Some(&(b, k)) = curve_of.get(&c.int(2)) {
            let axis = ["d|X", "d|Y", "d|Z"].iter().position(|a| *a == c.text(3)).unwrap();
            let curve = by_id[&c.int(1)];
            assert_eq!(curve.kid("KeyTime").ints(), [0]);
            keyed[b][k][axis] = curve.kid("KeyValueFloat").floats()[0];
        }
    }
    let mut global = vec![Matrix4::identity(); nb];
    for b in 0..nb {
        let [t, r] = keyed[b];
        let rot = Rotation3::from_axis_angle(&Vector3::z_axis(), r[2].to_radians())
            * Rotation3::from_axis_angle(&Vector3::y_axis(), r[1].to_radians())
            * Rotation3::from_axis_angle(&Vector3::x_axis(), r[0].to_radians());
        let local = Translation3::new(t[0], t[1], t[2]).to_homogeneous() * rot.to_homogeneous();
        global[b] = both.armature.parents[b].map_or(local, |p| global[p] * local);
    }
    // The clip stands every bone where the A-pose rest (the pose as an action's bind pose) has
    // it. (Skinning the posed rest by it does not give the A-pose mesh back exactly: linear
    // blend skinning's blend of inverses is not the inverse of its blend.)
    let action = RigScene::build(model.rig(), &mesh, &pose, &options(PoseAs::Action)).unwrap();
    let unit = metres_to_unit(&frame);
    let (mut worst_t, mut worst_r) = (0.0f64, 0.0f64);
    for (b, g) in global.iter().enumerate() {
        let want = frame_bind(&action, b, &frame);
        let dt = (g.fixed_view::<3, 1>(0, 3) - want.fixed_view::<3, 1>(0, 3)).norm() / unit;
        let dr = (g.fixed_view::<3, 3>(0, 0) - want.fixed_view::<3, 3>(0, 0)).abs().max();
        worst_t = worst_t.max(dt);
        worst_r = worst_r.max(dr);
    }
    assert!(worst_t < 1e-4 && worst_r < 1e-5, "the a_pose clip's bones: {worst_t} m, rotation {worst_r}");
}

/// Bone `b`'s bind matrix in `frame`.
fn frame_bind(scene: &RigScene, b: usize, frame: &ExportFrame) -> Matrix4<f64> {
    frame.global(&sketchbody::export::rigged::bind_transform(scene, b)).to_homogeneous()
}
