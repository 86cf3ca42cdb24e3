//! The FBX animation of a clip ([`crate::body::rig::Clip`]) written with `--pose-as both`: one
//! `AnimationStack` named after the clip with one `AnimationLayer`, and per bone a translation
//! and a rotation `AnimationCurveNode` (`d|X`, `d|Y`, `d|Z`) on its `Lcl Translation` /
//! `Lcl Rotation`, each channel one `AnimationCurve` with a single constant key at time 0 (the
//! clip's local transform, Euler XYZ degrees, in the file's frame).
use super::node::{object_name, p, s, Node, Prop};
use crate::body::rig::{Clip, RigScene};
use crate::export::frame::ExportFrame;
use crate::export::rigged::pose_locals;

const STACK: i64 = 1010;
const LAYER: i64 = 1011;

fn curve_node(b: usize, k: usize) -> i64 {
    5000 + 2 * b as i64 + k as i64
}

fn curve(b: usize, k: usize, axis: usize) -> i64 {
    10000 + 6 * b as i64 + 3 * k as i64 + axis as i64
}

/// `KeyAttrFlags` of a constant key (FBX's `eInterpolationConstant`, 0x02).
const CONSTANT: i32 = 0x02;

fn connect(kind: &str, child: i64, parent: i64, property: Option<&str>) -> Node {
    let mut props = vec![s(kind), Prop::I64(child), Prop::I64(parent)];
    props.extend(property.map(s));
    Node::new("C", props)
}

/// The objects of `clip` on `scene`'s bones (model ids from `bone_model`), its connections and
/// the object counts per type for the definitions.
pub fn clip_objects(
    scene: &RigScene,
    clip: &Clip,
    frame: &ExportFrame,
    bone_model: impl Fn(usize) -> i64,
) -> (Vec<Node>, Vec<Node>, Vec<(&'static str, i32)>) {
    let props70 = |children: Vec<Node>| Node::new("Properties70", vec![]).with(children);
    let mut objects = vec![
        Node::new("AnimationStack", vec![Prop::I64(STACK), object_name(clip.name, "AnimStack"), s("")])
            .with(vec![props70(vec![])]),
        Node::new("AnimationLayer", vec![Prop::I64(LAYER), object_name("BaseLayer", "AnimLayer"), s("")]),
    ];
    let mut links = vec![connect("OO", LAYER, STACK, None)];
    let locals = pose_locals(scene, &clip.pose);
    for (b, &(t, q)) in locals.iter().enumerate() {
        let (t, q) = match scene.armature.parents[b] {
            None => frame.root_local(t, q),
            Some(_) => frame.child_local(t, q),
        };
        let (rx, ry, rz) = q.euler_angles();
        let channels =
            [("T", "Lcl Translation", [t.x, t.y, t.z]), ("R", "Lcl Rotation", [rx, ry, rz].map(f64::to_degrees))];
        for (k, (name, property, values)) in channels.into_iter().enumerate() {
            let axes = ["d|X", "d|Y", "d|Z"];
            let defaults = (0..3).map(|a| p(axes[a], "Number", "", "A", vec![Prop::F64(values[a])])).collect();
            objects.push(
                Node::new(
                    "AnimationCurveNode",
                    vec![Prop::I64(curve_node(b, k)), object_name(name, "AnimCurveNode"), s("")],
                )
                .with(vec![props70(defaults)]),
            );
            links.push(connect("OO", curve_node(b, k), LAYER, None));
            links.push(connect("OP", curve_node(b, k), bone_model(b), Some(property)));
            for (a, &v) in values.iter().enumerate() {
                objects.push(
                    Node::new("AnimationCurve", vec![Prop::I64(curve(b, k, a)), object_name("", "AnimCurve"), s("")])
                        .with(vec![
                            Node::new("Default", vec![Prop::F64(v)]),
                            Node::new("KeyVer", vec![Prop::I32(4009)]),
                            Node::new("KeyTime", vec![Prop::I64s(vec![0])]),
                            Node::new("KeyValueFloat", vec![Prop::F32s(vec![v as f32])]),
                            Node::new("KeyAttrFlags", vec![Prop::I32s(vec![CONSTANT])]),
                            Node::new("KeyAttrDataFloat", vec![Prop::F32s(vec![0.0; 4])]),
                            Node::new("KeyAttrRefCount", vec![Prop::I32s(vec![1])]),
                        ]),
                );
                links.push(connect("OP", curve(b, k, a), curve_node(b, k), Some(axes[a])));
            }
        }
    }
    let n = locals.len() as i32;
    let counts =
        vec![("AnimationStack", 1), ("AnimationLayer", 1), ("AnimationCurveNode", 2 * n), ("AnimationCurve", 6 * n)];
    (objects, links, counts)
}
