//! The FBX scene of a rigged body: header and global settings (the [`ExportFrame`]'s unit and
//! axes), the mesh geometry (polygons, per-vertex normals, per-corner UVs), a `Null` "armature"
//! holding the `LimbNode` bones (MakeHuman's 53, then any twist bones) in their posed local transforms, the skin (one cluster per
//! bone with the bind matrices), the bind pose, and a material with the embedded texture; then
//! the connections. Every position, normal and transform is written in the frame's axes and
//! unit.
use nalgebra::{Matrix4, Vector3};

use super::node::{object_name, p, s, Node, Prop, VERSION};
use super::{anim, blend};
use crate::body::rig::{vertex_normals, RiggedMesh};
use crate::body::rig::{PoseAs, RigScene};
use crate::export::frame::{ExportFrame, UpAxis};
use crate::export::rigged::{bind_transform, posed_locals};

/// The file name the texture is referenced by (beside the .fbx, as the CLI writes it); the
/// same bytes are embedded.
pub const TEXTURE_FILE: &str = "body_texture.png";

const GEOMETRY: i64 = 1000;
const MESH_MODEL: i64 = 1001;
const ARMATURE: i64 = 1002;
const ARMATURE_ATTR: i64 = 1003;
const SKIN: i64 = 1004;
const MATERIAL: i64 = 1005;
const TEXTURE: i64 = 1006;
const VIDEO: i64 = 1007;
const BIND_POSE: i64 = 1008;
const DOCUMENT: i64 = 1009;

fn bone_model(b: usize) -> i64 {
    2000 + b as i64
}
fn bone_attr(b: usize) -> i64 {
    3000 + b as i64
}
fn cluster(b: usize) -> i64 {
    4000 + b as i64
}

fn int_p(name: &str, v: i32) -> Node {
    p(name, "int", "Integer", "", vec![Prop::I32(v)])
}

fn double_p(name: &str, v: f64) -> Node {
    p(name, "double", "Number", "", vec![Prop::F64(v)])
}

fn vec3_p(name: &str, v: [f64; 3]) -> Node {
    p(name, name, "", "A", v.iter().map(|&x| Prop::F64(x)).collect())
}

fn props70(children: Vec<Node>) -> Node {
    Node::new("Properties70", vec![]).with(children)
}

fn matrix(m: &Matrix4<f64>) -> Prop {
    Prop::F64s(m.as_slice().to_vec())
}

fn connect(child: i64, parent: i64) -> Node {
    Node::new("C", vec![s("OO"), Prop::I64(child), Prop::I64(parent)])
}

/// The global settings' axes for `frame`, as (axis index 0 X / 1 Y / 2 Z, sign): up; front,
/// the axis pointing from the scene toward the viewer (the way the character faces); coord,
/// the third axis (up × front, right-handed).
fn axes(frame: &ExportFrame) -> [(i32, i32); 3] {
    match frame.up {
        UpAxis::Y => [(1, 1), (2, 1), (0, 1)],
        UpAxis::Z => [(2, 1), (1, -1), (0, 1)],
    }
}

fn header(frame: &ExportFrame) -> Vec<Node> {
    let [(up, up_sign), (front, front_sign), (coord, coord_sign)] = axes(frame);
    let unit = frame.units.centimetres();
    let creator = format!("sketchbody {}", crate::VERSION);
    vec![
        Node::new("FBXHeaderExtension", vec![]).with(vec![
            Node::new("FBXHeaderVersion", vec![Prop::I32(1003)]),
            Node::new("FBXVersion", vec![Prop::I32(VERSION as i32)]),
            Node::new("Creator", vec![s(&creator)]),
        ]),
        Node::new("Creator", vec![s(&creator)]),
        Node::new("GlobalSettings", vec![]).with(vec![
            Node::new("Version", vec![Prop::I32(1000)]),
            props70(vec![
                int_p("UpAxis", up),
                int_p("UpAxisSign", up_sign),
                int_p("FrontAxis", front),
                int_p("FrontAxisSign", front_sign),
                int_p("CoordAxis", coord),
                int_p("CoordAxisSign", coord_sign),
                int_p("OriginalUpAxis", up),
                int_p("OriginalUpAxisSign", up_sign),
                double_p("UnitScaleFactor", unit),
                double_p("OriginalUnitScaleFactor", unit),
            ]),
        ]),
        Node::new("Documents", vec![]).with(vec![
            Node::new("Count", vec![Prop::I32(1)]),
            Node::new("Document", vec![Prop::I64(DOCUMENT), s("Scene"), s("Scene")])
                .with(vec![props70(vec![]), Node::new("RootNode", vec![Prop::I64(0)])]),
        ]),
        Node::new("References", vec![]),
    ]
}

fn definitions(bones: usize, textured: bool, animation: &[(&'static str, i32)], shapes: [i32; 2]) -> Node {
    let n = bones as i32;
    let mut types =
        vec![("GlobalSettings", 1), ("Model", n + 2), ("NodeAttribute", n + 1), ("Geometry", 1 + shapes[0])];
    types.extend([("Material", 1), ("Deformer", n + 1 + shapes[1]), ("Pose", 1)]);
    if textured {
        types.extend([("Texture", 1), ("Video", 1)]);
    }
    types.extend_from_slice(animation);
    let mut children = vec![
        Node::new("Version", vec![Prop::I32(100)]),
        Node::new("Count", vec![Prop::I32(types.iter().map(|t| t.1).sum())]),
    ];
    children.extend(
        types
            .iter()
            .map(|&(t, c)| Node::new("ObjectType", vec![s(t)]).with(vec![Node::new("Count", vec![Prop::I32(c)])])),
    );
    Node::new("Definitions", vec![]).with(children)
}

/// `points` (model frame, metres) in `frame`, flattened x, y, z: an FBX `Vertices` array.
pub(super) fn flat_points(points: &[[f32; 3]], frame: &ExportFrame) -> Vec<f64> {
    points
        .iter()
        .flat_map(|p| {
            let q = frame.point(Vector3::new(p[0] as f64, p[1] as f64, p[2] as f64));
            [q.x, q.y, q.z]
        })
        .collect()
}

/// The mesh geometry: polygons (a quad whose last two corners agree is a triangle), normals per
/// vertex, UVs per polygon corner (v up, FBX's convention), one material for all; positions
/// and normals in `frame`.
fn geometry(mesh: &RiggedMesh, scene: &RigScene, frame: &ExportFrame) -> Node {
    let vertices = flat_points(&scene.rest_vertices, frame);
    let mut polygon = Vec::with_capacity(mesh.quads.len() * 4);
    let mut uv_index = Vec::with_capacity(mesh.quads.len() * 4);
    for (f, q) in mesh.quads.iter().enumerate() {
        let n = if q[3] == q[2] { 3 } else { 4 };
        for k in 0..n {
            let v = q[k] as i32;
            polygon.push(if k == n - 1 { -v - 1 } else { v });
            if let Some(uv) = &mesh.uvs {
                uv_index.push(uv.quads[f][k] as i32);
            }
        }
    }
    let normals: Vec<f64> = vertex_normals(&scene.rest_vertices, &mesh.quads)
        .iter()
        .flat_map(|&n| frame.direction_f32(n))
        .map(|c| c as f64)
        .collect();
    let element = |name: &'static str, children: Vec<Node>| Node::new(name, vec![Prop::I32(0)]).with(children);
    let mapping = |how: &str, reference: &str| {
        vec![
            Node::new("MappingInformationType", vec![s(how)]),
            Node::new("ReferenceInformationType", vec![s(reference)]),
        ]
    };
    let mut layers = vec![Node::new("Version", vec![Prop::I32(101)]), Node::new("Name", vec![s("")])];
    layers.extend(mapping("ByVertice", "Direct"));
    layers.push(Node::new("Normals", vec![Prop::F64s(normals)]));
    let mut children = vec![
        props70(vec![]),
        Node::new("GeometryVersion", vec![Prop::I32(124)]),
        Node::new("Vertices", vec![Prop::F64s(vertices)]),
        Node::new("PolygonVertexIndex", vec![Prop::I32s(polygon)]),
        element("LayerElementNormal", layers),
    ];
    let mut layer = vec![Node::new("Version", vec![Prop::I32(100)])];
    let layer_element = |t: &str| {
        Node::new("LayerElement", vec![])
            .with(vec![Node::new("Type", vec![s(t)]), Node::new("TypedIndex", vec![Prop::I32(0)])])
    };
    layer.push(layer_element("LayerElementNormal"));
    if let Some(uv) = &mesh.uvs {
        let coords: Vec<f64> = uv.coords.iter().flatten().map(|&c| c as f64).collect();
        let mut e = vec![Node::new("Version", vec![Prop::I32(101)]), Node::new("Name", vec![s("UVMap")])];
        e.extend(mapping("ByPolygonVertex", "IndexToDirect"));
        e.push(Node::new("UV", vec![Prop::F64s(coords)]));
        e.push(Node::new("UVIndex", vec![Prop::I32s(uv_index)]));
        children.push(element("LayerElementUV", e));
        layer.push(layer_element("LayerElementUV"));
    }
    let mut e = vec![Node::new("Version", vec![Prop::I32(101)]), Node::new("Name", vec![s("")])];
    e.extend(mapping("AllSame", "IndexToDirect"));
    e.push(Node::new("Materials", vec![Prop::I32s(vec![0])]));
    children.push(element("LayerElementMaterial", e));
    layer.push(layer_element("LayerElementMaterial"));
    children.push(Node::new("Layer", vec![Prop::I32(0)]).with(layer));
    Node::new("Geometry", vec![Prop::I64(GEOMETRY), object_name("body", "Geometry"), s("Mesh")]).with(children)
}

fn model(id: i64, name: &str, kind: &str, props: Vec<Node>) -> Node {
    Node::new("Model", vec![Prop::I64(id), object_name(name, "Model"), s(kind)]).with(vec![
        Node::new("Version", vec![Prop::I32(232)]),
        props70(props),
        Node::new("Shading", vec![Prop::Bool(true)]),
        Node::new("Culling", vec![s("CullingOff")]),
    ])
}

/// The armature: a `Null` and the bones as `LimbNode` models whose local transforms are the
/// posed ones (Euler XYZ degrees) in `frame`, each with its skeleton attribute.
fn skeleton(scene: &RigScene, frame: &ExportFrame) -> Vec<Node> {
    let attr = |id: i64, name: &str, kind: &str, flags: &str| {
        Node::new("NodeAttribute", vec![Prop::I64(id), object_name(name, "NodeAttribute"), s(kind)])
            .with(vec![Node::new("TypeFlags", vec![s(flags)])])
    };
    let mut nodes = vec![model(ARMATURE, "armature", "Null", vec![]), attr(ARMATURE_ATTR, "armature", "Null", "Null")];
    for (b, &(t, q)) in posed_locals(scene).iter().enumerate() {
        let (t, q) = match scene.armature.parents[b] {
            None => frame.root_local(t, q),
            Some(_) => frame.child_local(t, q),
        };
        let (rx, ry, rz) = q.euler_angles();
        let props = vec![
            vec3_p("Lcl Translation", [t.x, t.y, t.z]),
            vec3_p("Lcl Rotation", [rx.to_degrees(), ry.to_degrees(), rz.to_degrees()]),
        ];
        nodes.push(model(bone_model(b), &scene.names[b], "LimbNode", props));
        nodes.push(attr(bone_attr(b), &scene.names[b], "LimbNode", "Skeleton"));
    }
    nodes
}

/// The skin deformer and one cluster per bone: its vertices and weights (absent for a bone that
/// moves none), `TransformLink` the bone's bind matrix, `Transform` its inverse (the mesh sits
/// at the origin unrotated); in `frame`.
fn skin(scene: &RigScene, frame: &ExportFrame) -> Vec<Node> {
    let mut per_bone: Vec<(Vec<i32>, Vec<f64>)> = vec![(Vec::new(), Vec::new()); scene.armature.len()];
    for (v, w) in scene.skin.iter().enumerate() {
        for k in 0..w.bones.len() {
            if w.weights[k] > 0.0 {
                let entry = &mut per_bone[w.bones[k] as usize];
                entry.0.push(v as i32);
                entry.1.push(w.weights[k] as f64);
            }
        }
    }
    let mut nodes = vec![Node::new("Deformer", vec![Prop::I64(SKIN), object_name("armature", "Deformer"), s("Skin")])
        .with(vec![
            Node::new("Version", vec![Prop::I32(101)]),
            Node::new("Link_DeformAcuracy", vec![Prop::F64(50.0)]),
        ])];
    for (b, (indexes, weights)) in per_bone.into_iter().enumerate() {
        let bind = frame.global(&bind_transform(scene, b));
        let mut children = vec![Node::new("Version", vec![Prop::I32(100)]), Node::new("UserData", vec![s(""), s("")])];
        if !indexes.is_empty() {
            children.push(Node::new("Indexes", vec![Prop::I32s(indexes)]));
            children.push(Node::new("Weights", vec![Prop::F64s(weights)]));
        }
        children.push(Node::new("Transform", vec![matrix(&bind.inverse().to_homogeneous())]));
        children.push(Node::new("TransformLink", vec![matrix(&bind.to_homogeneous())]));
        nodes.push(
            Node::new(
                "Deformer",
                vec![Prop::I64(cluster(b)), object_name(&scene.names[b], "SubDeformer"), s("Cluster")],
            )
            .with(children),
        );
    }
    nodes
}

/// The bind pose: the mesh and the armature at the identity, each bone at its bind matrix (in
/// `frame`).
fn bind_pose(scene: &RigScene, frame: &ExportFrame) -> Node {
    let entry = |id: i64, m: Matrix4<f64>| {
        Node::new("PoseNode", vec![])
            .with(vec![Node::new("Node", vec![Prop::I64(id)]), Node::new("Matrix", vec![matrix(&m)])])
    };
    let mut children = vec![
        Node::new("Type", vec![s("BindPose")]),
        Node::new("Version", vec![Prop::I32(100)]),
        Node::new("NbPoseNodes", vec![Prop::I32(scene.armature.len() as i32 + 2)]),
        entry(MESH_MODEL, Matrix4::identity()),
        entry(ARMATURE, Matrix4::identity()),
    ];
    children.extend(
        (0..scene.armature.len())
            .map(|b| entry(bone_model(b), frame.global(&bind_transform(scene, b)).to_homogeneous())),
    );
    Node::new("Pose", vec![Prop::I64(BIND_POSE), object_name("BindPose", "Pose"), s("BindPose")]).with(children)
}

/// The material (a skin colour, or white under the texture) and, with `texture_png`, the
/// texture and its embedded image.
fn material(texture_png: Option<&[u8]>) -> Vec<Node> {
    let colour = if texture_png.is_some() { [1.0, 1.0, 1.0] } else { [0.8, 0.7, 0.65] };
    let mut nodes = vec![Node::new("Material", vec![Prop::I64(MATERIAL), object_name("skin", "Material"), s("")])
        .with(vec![
            Node::new("Version", vec![Prop::I32(102)]),
            Node::new("ShadingModel", vec![s("phong")]),
            Node::new("MultiLayer", vec![Prop::I32(0)]),
            props70(vec![
                p("DiffuseColor", "Color", "", "A", colour.iter().map(|&c| Prop::F64(c)).collect()),
                p("DiffuseFactor", "Number", "", "A", vec![Prop::F64(1.0)]),
            ]),
        ])];
    if let Some(png) = texture_png {
        nodes.push(Node::new("Texture", vec![Prop::I64(TEXTURE), object_name("sketch", "Texture"), s("")]).with(vec![
            Node::new("Type", vec![s("TextureVideoClip")]),
            Node::new("Version", vec![Prop::I32(202)]),
            Node::new("TextureName", vec![object_name("sketch", "Texture")]),
            Node::new("Media", vec![object_name("sketch", "Video")]),
            Node::new("FileName", vec![s(TEXTURE_FILE)]),
            Node::new("RelativeFilename", vec![s(TEXTURE_FILE)]),
        ]));
        nodes.push(Node::new("Video", vec![Prop::I64(VIDEO), object_name("sketch", "Video"), s("Clip")]).with(vec![
            Node::new("Type", vec![s("Clip")]),
            props70(vec![p("Path", "KString", "XRefUrl", "", vec![s(TEXTURE_FILE)])]),
            Node::new("UseMipMap", vec![Prop::I32(0)]),
            Node::new("Filename", vec![s(TEXTURE_FILE)]),
            Node::new("RelativeFilename", vec![s(TEXTURE_FILE)]),
            Node::new("Content", vec![Prop::Raw(png.to_vec())]),
        ]));
    }
    nodes
}

fn connections(parents: &[Option<usize>], textured: bool) -> Node {
    let mut c = vec![connect(MESH_MODEL, 0), connect(ARMATURE, 0), connect(ARMATURE_ATTR, ARMATURE)];
    for (b, parent) in parents.iter().enumerate() {
        c.push(connect(bone_model(b), parent.map_or(ARMATURE, bone_model)));
        c.push(connect(bone_attr(b), bone_model(b)));
    }
    c.extend([connect(GEOMETRY, MESH_MODEL), connect(MATERIAL, MESH_MODEL), connect(SKIN, GEOMETRY)]);
    for b in 0..parents.len() {
        c.push(connect(cluster(b), SKIN));
        c.push(connect(bone_model(b), cluster(b)));
    }
    if textured {
        c.push(Node::new("C", vec![s("OP"), Prop::I64(TEXTURE), Prop::I64(MATERIAL), s("DiffuseColor")]));
        c.push(connect(VIDEO, TEXTURE));
    }
    Node::new("Connections", vec![]).with(c)
}

/// The top-level records of the file, in `frame`'s unit and axes.
pub fn document(mesh: &RiggedMesh, scene: &RigScene, texture_png: Option<&[u8]>, frame: &ExportFrame) -> Vec<Node> {
    let mut objects = vec![geometry(mesh, scene, frame), model(MESH_MODEL, "body", "Mesh", vec![])];
    objects.extend(skeleton(scene, frame));
    objects.extend(skin(scene, frame));
    objects.push(bind_pose(scene, frame));
    objects.extend(material(texture_png));
    let mut links = connections(&scene.armature.parents, texture_png.is_some());
    // The pose as rest: the bones stand at rest; with `Both`, the clip is an animation stack.
    let mut counts = Vec::new();
    if let Some(clip) = scene.clip.as_ref().filter(|_| scene.pose_as == PoseAs::Both) {
        let (anim, anim_links, anim_counts) = anim::clip_objects(scene, clip, frame, bone_model);
        objects.extend(anim);
        links.children.extend(anim_links);
        counts = anim_counts;
    }
    let (shapes, shape_links, shape_counts) = blend::blend_objects(scene, frame, GEOMETRY);
    objects.extend(shapes);
    links.children.extend(shape_links);
    let mut nodes = header(frame);
    nodes.push(definitions(scene.armature.len(), texture_png.is_some(), &counts, shape_counts));
    nodes.push(Node::new("Objects", vec![]).with(objects));
    nodes.push(links);
    nodes
}

#[cfg(test)]
mod tests {
    use std::collections::{BTreeMap, HashSet};

    use super::*;
    use crate::body::ik::{solve, IkOptions};
    use crate::body::procedural::random_pose;
    use crate::body::rig::{RigOptions, NUM_RIG_BONES};
    use crate::body::{BodyModel, Gender};
    use rand::SeedableRng;

    fn text(p: &Prop) -> &str {
        match p {
            Prop::Str(b) => std::str::from_utf8(b).unwrap(),
            other => panic!("not a string: {other:?}"),
        }
    }

    fn id(p: &Prop) -> i64 {
        match p {
            Prop::I64(v) => *v,
            other => panic!("not an id: {other:?}"),
        }
    }

    /// The `Definitions` count every object of the document by type (and all of them, with the
    /// global settings), the object ids are unique, and every connection joins a written object
    /// to another or to the root (0); with and without the texture.
    #[test]
    fn definitions_and_connections_match_the_objects() {
        let model = BodyModel::embedded().unwrap();
        let mesh = RiggedMesh::from_model(&model, Gender::Female, &[]).unwrap();
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        let pose = solve(&mesh.joints, &random_pose(&mesh.joints, &mut rng, 0.0), &IkOptions::default()).unwrap();
        let scene = RigScene::build(model.rig(), &mesh, &pose, &RigOptions::default()).unwrap();
        for png in [None, Some(&b"\x89PNG"[..])] {
            let doc = document(&mesh, &scene, png, &crate::export::frame::ExportFrame::default());
            let top = |name: &str| doc.iter().find(|n| n.name == name).unwrap_or_else(|| panic!("no {name}"));
            let objects = &top("Objects").children;
            let mut counted: BTreeMap<&str, i32> = BTreeMap::from([("GlobalSettings", 1)]);
            top("GlobalSettings");
            for o in objects {
                *counted.entry(o.name).or_default() += 1;
            }
            let (mut declared, mut total) = (BTreeMap::new(), None);
            for c in &top("Definitions").children {
                match c.name {
                    "Count" => total = Some(c.props[0].clone()),
                    "ObjectType" => {
                        assert_eq!(c.children[0].name, "Count");
                        declared.insert(text(&c.props[0]), c.children[0].props[0].clone());
                    }
                    _ => {}
                }
            }
            let counted_props: BTreeMap<&str, Prop> = counted.iter().map(|(&k, &v)| (k, Prop::I32(v))).collect();
            assert_eq!(declared, counted_props, "textured: {}", png.is_some());
            assert_eq!(total, Some(Prop::I32(counted.values().sum())));
            assert_eq!(counted["Model"], NUM_RIG_BONES as i32 + 2);
            let ids: Vec<i64> = objects.iter().map(|o| id(&o.props[0])).collect();
            let known: HashSet<i64> = ids.iter().copied().collect();
            assert_eq!(known.len(), ids.len(), "object ids are unique");
            for c in &top("Connections").children {
                let (child, parent) = (id(&c.props[1]), id(&c.props[2]));
                assert!(known.contains(&child) && (parent == 0 || known.contains(&parent)), "{c:?}");
            }
        }
    }
}
