//! The FBX blend shapes of the scene's shape keys ([`crate::body::rig::shape_keys`]): one
//! `Deformer` `BlendShape` on the body's geometry and per key a `Deformer` `BlendShapeChannel`
//! (`DeformPercent` 0, the base being the fitted body; `FullWeights` 100) holding a `Geometry`
//! `Shape` whose `Indexes` are every vertex, whose `Vertices` are the key's displacements in
//! the file's frame (turned and scaled as positions, no offset) and whose `Normals` (the normals'
//! displacements) are zero: a key keeps the base mesh's normals, as Blender's own FBX exporter
//! writes them; assimp's reader requires the element.
use super::node::{object_name, s, Node, Prop};
use super::scene::flat_points;
use crate::body::rig::RigScene;
use crate::export::frame::ExportFrame;

const BLEND_SHAPE: i64 = 1012;

fn shape(k: usize) -> i64 {
    7000 + k as i64
}

fn channel(k: usize) -> i64 {
    8000 + k as i64
}

fn connect(child: i64, parent: i64) -> Node {
    Node::new("C", vec![s("OO"), Prop::I64(child), Prop::I64(parent)])
}

/// The blend-shape objects of `scene`'s keys on the geometry `geometry`, their connections
/// and the extra object counts per type (`Geometry`, `Deformer`); nothing without keys.
pub fn blend_objects(scene: &RigScene, frame: &ExportFrame, geometry: i64) -> (Vec<Node>, Vec<Node>, [i32; 2]) {
    let keys = &scene.shape_keys;
    if keys.is_empty() {
        return (Vec::new(), Vec::new(), [0, 0]);
    }
    let mut objects = vec![Node::new(
        "Deformer",
        vec![Prop::I64(BLEND_SHAPE), object_name("shape_keys", "Deformer"), s("BlendShape")],
    )
    .with(vec![Node::new("Version", vec![Prop::I32(100)])])];
    let mut links = vec![connect(BLEND_SHAPE, geometry)];
    let n = scene.rest_vertices.len();
    for (k, key) in keys.iter().enumerate() {
        // A displacement turns and scales as a position does (no offset: none is applied).
        let deltas = flat_points(&key.deltas, frame);
        objects.push(
            Node::new("Geometry", vec![Prop::I64(shape(k)), object_name(&key.name, "Geometry"), s("Shape")]).with(
                vec![
                    Node::new("Version", vec![Prop::I32(100)]),
                    Node::new("Indexes", vec![Prop::I32s((0..n as i32).collect())]),
                    Node::new("Vertices", vec![Prop::F64s(deltas)]),
                    Node::new("Normals", vec![Prop::F64s(vec![0.0; 3 * n])]),
                ],
            ),
        );
        objects.push(
            Node::new(
                "Deformer",
                vec![Prop::I64(channel(k)), object_name(&key.name, "SubDeformer"), s("BlendShapeChannel")],
            )
            .with(vec![
                Node::new("Version", vec![Prop::I32(100)]),
                Node::new("DeformPercent", vec![Prop::F64(0.0)]),
                Node::new("FullWeights", vec![Prop::F64s(vec![100.0])]),
            ]),
        );
        links.push(connect(channel(k), BLEND_SHAPE));
        links.push(connect(shape(k), channel(k)));
    }
    let m = keys.len() as i32;
    (objects, links, [m, m + 1])
}
