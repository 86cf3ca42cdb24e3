//! The USD writer read back two ways. An independent minimal `.usda` reader written here (the
//! attributes the writer sets, by name, bracketed values split into numbers and strings)
//! checks the counts, the 53 joints and their paths, weights summing to 1 per vertex, the UV
//! count, the bind transforms against the rest transforms, and the posed body reproduced by
//! composing the animation's local transforms with the inverse bind transforms, for each unit
//! (m, cm: `metersPerUnit`) and up axis (Y, Z: `upAxis`), every position the model frame's
//! turned and scaled as documented. Pixar's own
//! library (`usd-core` in `target/usd-venv`, `scripts/usd-venv.sh`; or `$SKB_USD_PYTHON`) then
//! runs usdchecker's validators (no error) and skins the mesh with UsdSkel (the posed body within
//! 0.1 mm), in centimetres and Z up too, reading `upAxis` and `metersPerUnit` back through
//! `UsdGeom`; without it that part prints SKIPPED, or fails when SKB_REQUIRE_SHARED_DATA is set.
//! Bad input: an unwritable path writes nothing.

mod common;

use std::path::PathBuf;
use std::process::Command;

use nalgebra::{Matrix4, Point3, Quaternion, Translation3, UnitQuaternion, Vector3};
use rand::SeedableRng;
use sketchbody::body::ik::{solve, IkOptions};
use sketchbody::body::procedural::random_pose;
use sketchbody::body::rig::shape_keys::ShapeKey;
use sketchbody::body::rig::RiggedMesh;
use sketchbody::body::rig::{Naming, PoseAs, RigOptions, RigScene};
use sketchbody::body::{BodyModel, Gender};
use sketchbody::export::frame::{ExportFrame, Units, UpAxis};
use sketchbody::pipeline::shape_keys::ShapeOrigin;

#[path = "common/frames.rs"]
mod frames;
use frames::{in_frame, FRAMES};
use sketchbody::export::usd::{usda_string, write_usda};

/// The text after `name = ` up to the end of its bracketed (or single-token) value.
fn value<'t>(text: &'t str, name: &str) -> &'t str {
    let key = format!(" {name} = ");
    let start = text.find(&key).unwrap_or_else(|| panic!("no attribute {name}")) + key.len();
    let rest = &text[start..];
    let mut depth = 0i32;
    for (i, c) in rest.char_indices() {
        match c {
            '[' | '(' => depth += 1,
            ']' | ')' => {
                depth -= 1;
                if depth == 0 {
                    return &rest[..=i];
                }
            }
            '\n' if depth == 0 => return &rest[..i],
            _ => {}
        }
    }
    rest
}

fn numbers(v: &str) -> Vec<f64> {
    v.split(|c: char| !(c.is_ascii_digit() || c == '.' || c == '-' || c == 'e' || c == 'E' || c == '+'))
        .filter(|s| !s.is_empty())
        .map(|s| s.parse::<f64>().unwrap_or_else(|_| panic!("not a number: {s:?}")))
        .collect()
}

fn strings(v: &str) -> Vec<String> {
    v.split('"').skip(1).step_by(2).map(str::to_string).collect()
}

/// USD matrices are rows with the translation in the last: read as nalgebra's columns.
fn matrices(v: &str) -> Vec<Matrix4<f64>> {
    numbers(v).chunks(16).map(Matrix4::from_column_slice).collect()
}

fn scene(gender: Gender, seed: u64, naming: Naming) -> (RiggedMesh, RigScene) {
    let model = BodyModel::embedded().unwrap();
    let mesh = RiggedMesh::from_model(&model, gender, &[]).unwrap();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let pose = solve(&mesh.joints, &random_pose(&mesh.joints, &mut rng, 0.0), &IkOptions::default()).unwrap();
    let options = RigOptions { naming, ..RigOptions::default() };
    let scene = RigScene::build(model.rig(), &mesh, &pose, &options).unwrap();
    (mesh, scene)
}

#[test]
fn an_independent_reader_finds_the_skinned_posed_body() {
    let (mesh, scene) = scene(Gender::Female, 4, Naming::Mixamo);
    for frame in FRAMES {
        check_layer(&mesh, &scene, &frame);
    }
}

/// The layer of `scene` in `frame` read back: metadata, skeleton, mesh, pose, material.
fn check_layer(mesh: &RiggedMesh, scene: &RigScene, frame: &ExportFrame) {
    let text = usda_string(mesh, scene, true, frame).unwrap();
    assert!(text.starts_with("#usda 1.0\n"));
    let (up, metres) = match (frame.up, frame.units) {
        (UpAxis::Y, Units::Metres) => ("Y", 1.0),
        (UpAxis::Y, Units::Centimetres) => ("Y", 0.01),
        (UpAxis::Z, Units::Metres) => ("Z", 1.0),
        (UpAxis::Z, Units::Centimetres) => ("Z", 0.01),
    };
    assert_eq!(strings(value(&text, "upAxis")), [up]);
    assert_eq!(numbers(value(&text, "metersPerUnit")), [metres]);
    // The skeleton: 53 joints, paths that nest as the rig, the convention's names kept.
    let nb = scene.armature.len();
    let parents = &scene.armature.parents;
    let joints = strings(value(&text, "uniform token[] joints"));
    assert_eq!(joints.len(), nb);
    for (b, parent) in parents.iter().enumerate() {
        if let Some(p) = *parent {
            assert_eq!(joints[b].rsplit_once('/').unwrap().0, joints[p], "path of joint {b}");
        }
        assert!(joints[b].chars().all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '/'), "{}", joints[b]);
    }
    assert_eq!(strings(value(&text, "uniform token[] jointNames")), scene.names);
    assert!(scene.names[0].contains(':'), "the Mixamo names need escaping in paths");
    let bind = matrices(value(&text, "uniform matrix4d[] bindTransforms"));
    let rest = matrices(value(&text, "uniform matrix4d[] restTransforms"));
    assert_eq!((bind.len(), rest.len()), (nb, nb));
    for (b, parent) in parents.iter().enumerate() {
        let composed = parent.map_or(rest[b], |p| bind[p] * rest[b]);
        assert!((composed - bind[b]).abs().max() < 1e-9, "rest transforms compose to bind transforms at {b}");
    }
    // The mesh.
    let n = mesh.vertices.len();
    let points = numbers(value(&text, "point3f[] points"));
    assert_eq!(points.len(), 3 * n);
    let counts = numbers(value(&text, "int[] faceVertexCounts"));
    let indices = numbers(value(&text, "int[] faceVertexIndices"));
    assert_eq!(counts.len(), mesh.quads.len());
    assert_eq!(counts.iter().sum::<f64>() as usize, indices.len());
    assert_eq!(numbers(value(&text, "normal3f[] normals")).len(), 3 * n);
    let uvs = mesh.uvs.as_ref().unwrap();
    assert_eq!(numbers(value(&text, "texCoord2f[] primvars:st")).len(), 2 * uvs.coords.len(), "UV count");
    assert_eq!(numbers(value(&text, "int[] primvars:st:indices")).len(), indices.len());
    let ji = numbers(value(&text, "int[] primvars:skel:jointIndices"));
    let jw = numbers(value(&text, "float[] primvars:skel:jointWeights"));
    assert_eq!((ji.len(), jw.len()), (4 * n, 4 * n));
    assert!(jw.chunks(4).all(|w| (w.iter().sum::<f64>() - 1.0).abs() < 1e-5), "weights sum to 1 per vertex");
    assert!(ji.iter().all(|&j| j >= 0.0 && (j as usize) < nb));
    assert!(text.contains("asset inputs:file = @body_texture.png@"));
    // The pose: the animation's local transforms composed down the tree, times inverse bind.
    let t = numbers(value(&text, "float3[] translations"));
    let r = numbers(value(&text, "quatf[] rotations"));
    let mut global = vec![Matrix4::identity(); nb];
    for (b, parent) in parents.iter().enumerate() {
        let q = UnitQuaternion::from_quaternion(Quaternion::new(r[4 * b], r[4 * b + 1], r[4 * b + 2], r[4 * b + 3]));
        let local = Translation3::new(t[3 * b], t[3 * b + 1], t[3 * b + 2]).to_homogeneous() * q.to_homogeneous();
        global[b] = parent.map_or(local, |p| global[p] * local);
    }
    let mut worst = 0.0f64;
    let mut rest_worst = 0.0f64;
    for v in 0..n {
        let x = Point3::new(points[3 * v], points[3 * v + 1], points[3 * v + 2]);
        rest_worst = rest_worst.max((x.coords - in_frame(frame, scene.rest_vertices[v])).norm() * metres);
        let mut p = Vector3::zeros();
        for k in 0..4 {
            let b = ji[4 * v + k] as usize;
            p += (global[b] * bind[b].try_inverse().unwrap()).transform_point(&x).coords * jw[4 * v + k];
        }
        worst = worst.max((p - in_frame(frame, scene.posed_vertices[v])).norm() * metres);
    }
    // Points are written as f32: 1e-6 m in metres, 1e-6 cm-units relative in centimetres.
    assert!(rest_worst < 1e-5, "{frame:?}: the USD's rest points differ from the scene's by {rest_worst} m");
    assert!(worst < 1e-5, "{frame:?}: the USD's skinning differs from the scene's by {worst} m");
    let plain = usda_string(mesh, scene, false, frame).unwrap();
    assert!(!plain.contains("UsdUVTexture") && plain.contains("inputs:diffuseColor = "));
}

fn usd_python() -> Option<PathBuf> {
    let p = std::env::var_os("SKB_USD_PYTHON")
        .map(PathBuf::from)
        .unwrap_or_else(|| common::repo_root().join("target/usd-venv/bin/python"));
    let ok = Command::new(&p)
        .args(["-c", "from pxr import Usd, UsdSkel, UsdValidation"])
        .output()
        .map(|o| o.status.success())
        .unwrap_or(false);
    ok.then_some(p)
}

#[test]
fn usd_core_validates_and_skins_the_layer() {
    let Some(python) = usd_python() else {
        if std::env::var_os("SKB_REQUIRE_SHARED_DATA").is_some() {
            panic!("usd-core is not installed (scripts/usd-venv.sh), but SKB_REQUIRE_SHARED_DATA is set");
        }
        eprintln!("SKIPPED usd-core checks: no target/usd-venv (scripts/usd-venv.sh)");
        return;
    };
    let (mesh, scene) = scene(Gender::Male, 9, Naming::Unreal);
    for frame in [FRAMES[0], FRAMES[3]] {
        check_with_usd_core(&python, &mesh, &scene, &frame);
    }
    // Twist bones, IK targets and shape keys; the pose as an action and as the rest.
    for pose_as in [PoseAs::Action, PoseAs::Rest] {
        let (mesh, scene) = rich_scene(pose_as);
        check_with_usd_core(&python, &mesh, &scene, &FRAMES[3]);
    }
}

/// usd-core on the layer of `scene` in `frame`: validators, UsdSkel's skinning, and UsdGeom's
/// reading of `upAxis` and `metersPerUnit`; the posed points compared in `frame`.
fn check_with_usd_core(python: &std::path::Path, mesh: &RiggedMesh, scene: &RigScene, frame: &ExportFrame) {
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("usd-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let data = (0..16).flat_map(|i| [(i % 4 * 60) as u8, (i / 4 * 60) as u8, 90]).collect();
    let img = sketchbody::image::RgbImage::from_vec(4, 4, data).unwrap();
    std::fs::write(dir.join("body_texture.png"), sketchbody::image::encode_png(&img.view()).unwrap()).unwrap();
    let usda = dir.join("body.usda");
    write_usda(&usda, mesh, scene, true, frame).unwrap();
    let posed: Vec<[f64; 3]> = scene.posed_vertices.iter().map(|&p| in_frame(frame, p).into()).collect();
    let keys: Vec<Vec<[f64; 3]>> =
        scene.shape_keys.iter().map(|k| k.deltas.iter().map(|&d| in_frame(frame, d).into()).collect()).collect();
    let expected = serde_json::json!({"posed": posed, "keys": keys});
    std::fs::write(dir.join("expected.json"), expected.to_string()).unwrap();
    let script = common::repo_root().join("tests/usd/check_usd.py");
    let out = Command::new(python).arg(&script).arg(&usda).arg(dir.join("expected.json")).output().unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "check_usd.py failed:\n{stdout}\n{}", String::from_utf8_lossy(&out.stderr));
    println!("{stdout}");
    let r: serde_json::Value = serde_json::from_str(stdout.trim()).unwrap();
    assert!(r["validators"].as_u64().unwrap() >= 20, "{stdout}");
    assert_eq!(r["errors"], serde_json::json!([]), "{stdout}");
    assert_eq!((r["bindings"].as_u64(), r["targets"].as_u64()), (Some(1), Some(1)), "{stdout}");
    assert_eq!(r["joints"].as_array().unwrap().len(), scene.armature.len());
    let animated = scene.pose_as == PoseAs::Action;
    assert_eq!((r["has_animation"].as_bool(), r["skinned"].as_bool()), (Some(animated), Some(true)), "{stdout}");
    assert_eq!(r["blend_shapes"].as_u64(), Some(scene.shape_keys.len() as u64), "{stdout}");
    assert!(r["blend_gap"].as_f64().unwrap() < 1e-5, "{stdout}");
    assert_eq!(r["points"].as_u64(), Some(mesh.vertices.len() as u64));
    // metersPerUnit converts the gap to metres: within 0.1 mm in either unit.
    let (up, metres) = match frame.units {
        Units::Metres => (frame.up, 1.0),
        Units::Centimetres => (frame.up, 0.01),
    };
    let gap = r["posed_gap"].as_f64().unwrap() * metres;
    assert!(gap < 1e-4, "{frame:?}: UsdSkel's posed body differs by {gap} m: {stdout}");
    let up = if up == UpAxis::Z { "Z" } else { "Y" };
    assert_eq!(r["up_axis"].as_str(), Some(up), "{stdout}");
    assert_eq!(r["meters_per_unit"].as_f64(), Some(metres), "{stdout}");
    // The SkelRoot's extent as usd-core reads it: the posed body's size along each of the
    // layer's axes (the height along the up axis), in its unit.
    let size: Vec<f64> = r["extent_size"].as_array().unwrap().iter().map(|v| v.as_f64().unwrap()).collect();
    for k in 0..3 {
        let (lo, hi) =
            posed.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| (lo.min(p[k]), hi.max(p[k])));
        assert!((size[k] - (hi - lo)).abs() * metres < 1e-5, "{frame:?}: extent {size:?} along axis {k}");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn an_unwritable_path_or_a_mismatched_scene_writes_nothing() {
    let (mesh, scene) = scene(Gender::Male, 2, Naming::Project);
    let dir = std::env::temp_dir().join(format!("skb-usd-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let frame = ExportFrame { units: Units::Centimetres, up: UpAxis::Z };
    let e = write_usda(&dir.join("missing").join("body.usda"), &mesh, &scene, false, &frame).unwrap_err();
    assert!(matches!(e, sketchbody::Error::Io { .. }), "{e:?}");
    let mut short = scene.clone();
    short.rest_vertices.pop();
    assert!(matches!(
        write_usda(&dir.join("body.usda"), &mesh, &short, false, &frame),
        Err(sketchbody::Error::OutOfRange { .. })
    ));
    assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 0, "nothing written");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Shape keys of the mean body: the first `n` principal components of its space, one standard
/// deviation each (model frame), as the library makes them.
fn mean_keys(model: &BodyModel, gender: Gender, n: usize) -> Vec<ShapeKey> {
    let origin = ShapeOrigin { space: gender.into(), weights: Vec::new(), proportions: None, scale: 1.0 };
    origin.keys(model).unwrap().into_iter().take(n).collect()
}

/// A scene with twist bones, IK targets and three shape keys (Mixamo names: paths escaped), the
/// pose as `pose_as`.
fn rich_scene(pose_as: PoseAs) -> (RiggedMesh, RigScene) {
    let model = BodyModel::embedded().unwrap();
    let mesh = RiggedMesh::from_model(&model, Gender::Male, &[]).unwrap();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(13);
    let pose = solve(&mesh.joints, &random_pose(&mesh.joints, &mut rng, 0.0), &IkOptions::default()).unwrap();
    let options =
        RigOptions { naming: Naming::Mixamo, twist_bones: true, ik_targets: true, pose_as, ..RigOptions::default() };
    let keys = mean_keys(&model, Gender::Male, 3);
    let scene = RigScene::build_with_shape_keys(model.rig(), &mesh, &pose, &options, &keys).unwrap();
    (mesh, scene)
}

/// Twist bones, IK targets and shape keys read back by the independent reader: the skeleton,
/// skin and pose as [`check_layer`] reads them in every unit and up axis, the blend shapes
/// named and targeted on the mesh, listed at weight 0 by the animation, each `BlendShape`'s
/// offsets the key's displacements in the layer's frame; with the pose as the rest no animation
/// and the points the posed body; with both, an `a_pose` animation not bound to the skeleton.
#[test]
fn twist_bones_ik_targets_and_shape_keys_read_back() {
    let (mesh, scene) = rich_scene(PoseAs::Action);
    for frame in FRAMES {
        check_layer(&mesh, &scene, &frame);
        let text = usda_string(&mesh, &scene, false, &frame).unwrap();
        let names: Vec<String> = scene.shape_keys.iter().map(|k| k.name.clone()).collect();
        assert_eq!(strings(value(&text, "uniform token[] skel:blendShapes")), names);
        assert_eq!(strings(value(&text, "uniform token[] blendShapes")), names);
        assert_eq!(numbers(value(&text, "float[] blendShapeWeights")), [0.0, 0.0, 0.0]);
        let targets = value(&text, "rel skel:blendShapeTargets");
        let offsets: Vec<Vec<f64>> =
            text.split(" offsets = ").skip(1).map(|rest| numbers(value(&format!(" x = {rest}"), "x"))).collect();
        assert_eq!(offsets.len(), 3);
        let metres = 1.0 / frames::metres_to_unit(&frame);
        for (k, key) in scene.shape_keys.iter().enumerate() {
            assert!(targets.contains(&format!("</body/mesh/{}>", key.name)), "{targets}");
            assert!(text.contains(&format!("def BlendShape \"{}\"", key.name)));
            assert_eq!(offsets[k].len(), 3 * mesh.vertices.len());
            let gap = key
                .deltas
                .iter()
                .enumerate()
                .map(|(i, &d)| {
                    (Vector3::new(offsets[k][3 * i], offsets[k][3 * i + 1], offsets[k][3 * i + 2])
                        - in_frame(&frame, d))
                    .norm()
                })
                .fold(0.0, f64::max);
            assert!(gap * metres < 1e-6, "{frame:?}: {} differs by {gap}", key.name);
        }
    }
    let (mesh, rest) = rich_scene(PoseAs::Rest);
    let text = usda_string(&mesh, &rest, false, &FRAMES[0]).unwrap();
    assert!(!text.contains("SkelAnimation") && !text.contains("skel:animationSource"));
    let points = numbers(value(&text, "point3f[] points"));
    let gap = rest
        .posed_vertices
        .iter()
        .enumerate()
        .map(|(i, p)| (0..3).map(|c| (points[3 * i + c] - p[c] as f64).abs()).fold(0.0, f64::max))
        .fold(0.0, f64::max);
    assert!(gap < 1e-6, "the rest points are the posed body: {gap}");
    let (mesh, both) = rich_scene(PoseAs::Both);
    let text = usda_string(&mesh, &both, false, &FRAMES[0]).unwrap();
    assert!(text.contains("def SkelAnimation \"a_pose\"") && !text.contains("skel:animationSource"));
}
