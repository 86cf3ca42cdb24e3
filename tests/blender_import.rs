//! Verification with a real DCC: Blender 3.4's own glTF importer (Debian's `blender`, headless,
//! with `python3-numpy`; scripts/test-all.sh installs both) imports a posed body and must find
//! one mesh, one armature, the documented 53-bone hierarchy, every vertex weighted, the feet on
//! the floor, and an elbow that bends the forearm (rotating `r_elbow` 45° about its X axis moves
//! forearm vertices) and leaves the upper arm (vertices bound wholly to `r_shoulder`) within
//! 5 mm. Without Blender the test prints SKIPPED, or fails when SKB_REQUIRE_SHARED_DATA is set.

use std::path::Path;
use std::process::Command;

use rand::SeedableRng;
use sketchbody::body::ik::{solve, IkOptions};
use sketchbody::body::procedural::random_pose;
use sketchbody::body::rig::shape_keys::ShapeKey;
use sketchbody::body::rig::RiggedMesh;
use sketchbody::body::rig::{Naming, PoseAs, RigOptions, RigScene, RIG_BONES};
use sketchbody::body::{BodyModel, Gender};
use sketchbody::pipeline::shape_keys::ShapeOrigin;
#[path = "common/frames.rs"]
mod frames;
use frames::FRAMES;
use sketchbody::export::gltf::write_glb;

/// True when Blender is missing: prints SKIPPED naming `what`, or panics when
/// SKB_REQUIRE_SHARED_DATA is set.
fn blender_missing(what: &str) -> bool {
    if Command::new("blender").arg("--version").output().map(|o| o.status.success()).unwrap_or(false) {
        return false;
    }
    if std::env::var_os("SKB_REQUIRE_SHARED_DATA").is_some() {
        panic!("Blender is not installed, but SKB_REQUIRE_SHARED_DATA is set");
    }
    eprintln!("SKIPPED {what}: blender is not installed");
    true
}

/// Runs `script` in headless Blender with `args` after `--`.
fn blender(script: &Path, args: &[&Path]) -> std::process::Output {
    Command::new("blender")
        .args(["-b", "--factory-startup", "--python-exit-code", "1", "-P"])
        .arg(script)
        .arg("--")
        .args(args)
        .output()
        .unwrap()
}

/// Writes `scene` as a GLB in `dir`, imports it with Blender's glTF importer
/// (tests/blender/check_glb.py: the bones' parents as the scene has them; `elbow` the bone it
/// turns 45°, `upper_arm` the one it watches) and returns the report and its text after the
/// checks every import passes: one mesh and one armature, the hierarchy as written, no
/// unweighted vertex, the posed and rest feet on the floor.
fn import_glb(
    dir: &Path,
    body: &RiggedMesh,
    scene: &RigScene,
    elbow: &str,
    upper_arm: &str,
) -> (serde_json::Value, String) {
    let glb = dir.join("body.glb");
    write_glb(&glb, body, scene, None).unwrap();
    let parents: serde_json::Map<String, serde_json::Value> = (0..scene.names.len())
        .map(|b| (scene.names[b].clone(), scene.armature.parents[b].map(|p| scene.names[p].clone()).into()))
        .collect();
    let expected = serde_json::json!({"parents": parents, "elbow": elbow, "upper_arm": upper_arm});
    std::fs::write(dir.join("expected.json"), expected.to_string()).unwrap();
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/blender/check_glb.py");
    let out = blender(&script, &[&glb, &dir.join("expected.json"), &dir.join("report.json")]);
    assert!(
        out.status.success(),
        "blender failed:\n{}\n{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    let text = std::fs::read_to_string(dir.join("report.json")).unwrap();
    println!("{text}");
    let r: serde_json::Value = serde_json::from_str(&text).unwrap();
    let f = |k: &str| r[k].as_f64().unwrap();
    assert_eq!((r["meshes"].as_u64(), r["armatures"].as_u64()), (Some(1), Some(1)), "{text}");
    assert_eq!(r["bones"].as_u64(), Some(scene.names.len() as u64), "{text}");
    assert_eq!(r["hierarchy_matches"], true, "{text}");
    assert_eq!(r["unweighted_vertices"].as_u64(), Some(0), "{text}");
    assert!(f("posed_min_z").abs() < 0.005 && f("rest_min_z").abs() < 0.005, "{text}");
    (r, text)
}

#[test]
fn blender_imports_one_rigged_mesh_that_bends_at_the_elbow() {
    if blender_missing("Blender import") {
        return;
    }
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("blender-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let model = BodyModel::embedded().unwrap();
    let body = RiggedMesh::from_model(&model, Gender::Female, &[]).unwrap();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
    let pose = solve(&body.joints, &random_pose(&body.joints, &mut rng, 0.0), &IkOptions::default()).unwrap();
    let scene = RigScene::build(model.rig(), &body, &pose, &RigOptions::default()).unwrap();
    assert_eq!(scene.names.len(), RIG_BONES.len());
    let (r, text) = import_glb(&dir, &body, &scene, "r_elbow", "r_shoulder");
    let f = |k: &str| r[k].as_f64().unwrap();
    assert!(r["forearm_vertices"].as_u64().unwrap() > 100 && f("forearm_mean_move") > 0.02, "{text}");
    assert!(r["upper_arm_vertices"].as_u64().unwrap() > 20 && f("upper_arm_max_move") < 0.005, "{text}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Blender 3.4's FBX importer against its glTF importer on the same posed, textured body, for
/// the FBX in each unit (m, cm) and up axis (Y, Z), Blender's own conversion from the file's
/// global settings bringing it into Blender's metres, Z up: one mesh and one armature, no
/// warning printed, the same 53 bones and parents, every bone's rest and posed head, every
/// vertex's weights and posed world position equal to the glTF import's (vertices matched by
/// rest position) within 0.1 mm, a UV layer, and the embedded texture packed.
#[test]
fn blender_imports_the_fbx_as_it_imports_the_gltf() {
    if blender_missing("Blender FBX import") {
        return;
    }
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("blender-fbx-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let model = BodyModel::embedded().unwrap();
    let body = RiggedMesh::from_model(&model, Gender::Male, &[]).unwrap();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(8);
    let pose = solve(&body.joints, &random_pose(&body.joints, &mut rng, 0.0), &IkOptions::default()).unwrap();
    let scene = RigScene::build(model.rig(), &body, &pose, &RigOptions::default()).unwrap();
    let data = (0..64).flat_map(|i| [(i % 8 * 30) as u8, (i / 8 * 30) as u8, 128]).collect();
    let img = sketchbody::image::RgbImage::from_vec(8, 8, data).unwrap();
    let png = sketchbody::image::encode_png(&img.view()).unwrap();
    let glb = dir.join("body.glb");
    write_glb(&glb, &body, &scene, Some(&png)).unwrap();
    let mut args = vec![glb];
    for (k, frame) in FRAMES.iter().enumerate() {
        let fbx = dir.join(format!("body{k}.fbx"));
        sketchbody::export::fbx::write_fbx(&fbx, &body, &scene, Some(&png), frame).unwrap();
        args.extend([fbx, dir.join(format!("report{k}.json"))]);
    }
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/blender/check_fbx.py");
    let out = blender(&script, &args.iter().map(|p| p.as_path()).collect::<Vec<_>>());
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "blender failed:\n{stdout}\n{}", String::from_utf8_lossy(&out.stderr));
    assert!(!stdout.to_lowercase().contains("warning"), "Blender printed a warning:\n{stdout}");
    for (k, frame) in FRAMES.iter().enumerate() {
        let text = std::fs::read_to_string(dir.join(format!("report{k}.json"))).unwrap();
        println!("{frame:?}: {text}");
        check_fbx_report(&text, body.vertices.len());
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// One FBX import's report (tests/blender/check_fbx.py) against the glTF import's.
fn check_fbx_report(text: &str, vertices: usize) {
    let r: serde_json::Value = serde_json::from_str(text).unwrap();
    let f = |k: &str| r[k].as_f64().unwrap();
    assert_eq!(r["result"], serde_json::json!(["FINISHED"]), "{text}");
    assert_eq!(r["warnings"], serde_json::json!([]), "{text}");
    assert_eq!((r["meshes"].as_u64(), r["armatures"].as_u64()), (Some(1), Some(1)), "{text}");
    assert_eq!(r["bones"].as_u64(), Some(53));
    assert_eq!(r["bones_match"], true, "{text}");
    assert_eq!(r["vertices"].as_u64(), Some(vertices as u64));
    assert_eq!(r["uv_layers"].as_u64(), Some(1));
    assert!(f("rest_gap") < 1e-4 && f("posed_gap") < 1e-4 && f("weight_gap") < 1e-4, "{text}");
    assert!(f("bone_head_gap") < 1e-4 && f("posed_bone_head_gap") < 1e-4, "{text}");
    assert!(f("posed_moved") > 0.05, "the pose moves the body: {text}");
    assert!(r["images"].as_array().unwrap().iter().any(|i| i[1] == 8 && i[2] == 8 && i[3] == true), "{text}");
}

/// The twist bones (issue 49) as Blender 3.4's glTF importer brings them in, with Unreal's
/// names and the sketch's pose as the rest (`PoseAs::Rest`): 59 bones, each twist bone a child
/// of its limb (`upperarm_twist_01_r` of `upperarm_r`, …), no action, the rest mesh already
/// posed (the posed and rest meshes the same), and the elbow still bending the forearm while the
/// upper arm's twist-bone half stays.
#[test]
fn blender_imports_the_twist_bones_with_the_pose_as_rest() {
    if blender_missing("Blender twist-bone import") {
        return;
    }
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("blender-twist-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let model = BodyModel::embedded().unwrap();
    let body = RiggedMesh::from_model(&model, Gender::Male, &[]).unwrap();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
    let pose = solve(&body.joints, &random_pose(&body.joints, &mut rng, 0.0), &IkOptions::default()).unwrap();
    let options =
        RigOptions { naming: Naming::Unreal, twist_bones: true, pose_as: PoseAs::Rest, ..RigOptions::default() };
    let scene = RigScene::build(model.rig(), &body, &pose, &options).unwrap();
    assert_eq!(scene.names.len(), 59);
    let parent = |n: &str| scene.armature.parents[scene.names.iter().position(|x| x == n).unwrap()];
    assert_eq!(parent("lowerarm_twist_01_l").map(|p| scene.names[p].as_str()), Some("lowerarm_l"));
    assert_eq!(parent("thigh_twist_01_r").map(|p| scene.names[p].as_str()), Some("thigh_r"));
    let (r, text) = import_glb(&dir, &body, &scene, "lowerarm_r", "upperarm_twist_01_r");
    let f = |k: &str| r[k].as_f64().unwrap();
    assert_eq!(r["actions"], serde_json::json!([]), "{text}");
    assert!(f("rest_posed_gap") < 1e-4, "the rest mesh is the posed body: {text}");
    // The forearm bone keeps the elbow half of its skin, its twist bone the wrist half.
    assert!(r["forearm_vertices"].as_u64().unwrap() > 50 && f("forearm_mean_move") > 0.02, "{text}");
    assert!(r["upper_arm_vertices"].as_u64().unwrap() > 10 && f("upper_arm_max_move") < 0.005, "{text}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Shape keys (issue 49) as Blender 3.4's glTF and FBX importers bring them in: a basis and one
/// key per shape dimension, every key at 0, each key's displacement of every vertex the one
/// written within 0.1 mm (in Blender's metres, Z up; the FBX in centimetres, Z up, converted by
/// Blender), and the twist bones and IK targets present and parented as written. Then the same
/// body with the pose as the rest (`PoseAs::Rest`): Blender's rest mesh is the posed body of the
/// pose as an action (what the action's glTF shows) within 0.1 mm, its keys the keys carried
/// into that rest.
#[test]
fn blender_imports_the_shape_keys() {
    if blender_missing("Blender shape-key import") {
        return;
    }
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("blender-keys-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let model = BodyModel::embedded().unwrap();
    let body = RiggedMesh::from_model(&model, Gender::Female, &[]).unwrap();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(6);
    let pose = solve(&body.joints, &random_pose(&body.joints, &mut rng, 0.0), &IkOptions::default()).unwrap();
    // Shape keys: the first 4 components of the mean body, one standard deviation each.
    let origin = ShapeOrigin { space: Gender::Female.into(), weights: Vec::new(), proportions: None, scale: 1.0 };
    let keys: Vec<ShapeKey> = origin.keys(&model).unwrap().into_iter().take(4).collect();
    let options = |pose_as| RigOptions {
        naming: Naming::Unreal,
        twist_bones: true,
        ik_targets: true,
        pose_as,
        ..RigOptions::default()
    };
    let action = RigScene::build_with_shape_keys(model.rig(), &body, &pose, &options(PoseAs::Action), &keys).unwrap();
    let rest = RigScene::build_with_shape_keys(model.rig(), &body, &pose, &options(PoseAs::Rest), &keys).unwrap();
    // Blender's world: metres, Z up: (x, y, z) of the model frame is (x, -z, y).
    let z_up = |p: [f32; 3]| [p[0] as f64, -p[2] as f64, p[1] as f64];
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/blender/check_keys.py");
    // (scene written, the rest Blender should find: the action's rest, then its posed body)
    for (label, scene, want_rest) in
        [("action", &action, &action.rest_vertices), ("rest", &rest, &action.posed_vertices)]
    {
        let expected_rest: Vec<[f64; 3]> = want_rest.iter().map(|&p| z_up(p)).collect();
        let key_map: serde_json::Map<String, serde_json::Value> = scene
            .shape_keys
            .iter()
            .map(|k| (k.name.clone(), serde_json::json!(k.deltas.iter().map(|&d| z_up(d)).collect::<Vec<_>>())))
            .collect();
        let expected = dir.join(format!("expected-{label}.json"));
        std::fs::write(&expected, serde_json::json!({"rest": expected_rest, "keys": key_map}).to_string()).unwrap();
        let glb = dir.join(format!("body-{label}.glb"));
        write_glb(&glb, &body, scene, None).unwrap();
        let fbx = dir.join(format!("body-{label}.fbx"));
        sketchbody::export::fbx::write_fbx(&fbx, &body, scene, None, &FRAMES[3]).unwrap();
        for file in [&glb, &fbx] {
            let report = dir.join("report.json");
            let out = blender(&script, &[file, &expected, &report]);
            let stdout = String::from_utf8_lossy(&out.stdout);
            assert!(out.status.success(), "blender failed:\n{stdout}\n{}", String::from_utf8_lossy(&out.stderr));
            let text = std::fs::read_to_string(&report).unwrap();
            println!("{}: {text}", file.display());
            let r: serde_json::Value = serde_json::from_str(&text).unwrap();
            assert_eq!((r["meshes"].as_u64(), r["armatures"].as_u64()), (Some(1), Some(1)), "{text}");
            let names: Vec<&str> = r["keys"].as_array().unwrap().iter().map(|k| k[0].as_str().unwrap()).collect();
            assert_eq!(names, ["Basis", "shape_01", "shape_02", "shape_03", "shape_04"], "{text}");
            assert!(r["keys"].as_array().unwrap().iter().all(|k| k[1].as_f64() == Some(0.0)), "{text}");
            assert!(r["rest_gap"].as_f64().unwrap() < 1e-4, "{label}: Blender's rest mesh: {text}");
            let gaps = r["key_gaps"].as_object().unwrap();
            assert_eq!(gaps.len(), 4, "{text}");
            assert!(gaps.values().all(|g| g.as_f64().unwrap() < 1e-4), "{text}");
            let bones = r["bones"].as_object().unwrap();
            assert_eq!(bones.len(), scene.names.len(), "{text}");
            assert_eq!(bones["upperarm_twist_01_l"], "upperarm_l");
            assert_eq!(bones["ik_hand_r"], "ik_hand_gun");
            assert_eq!(bones["ik_foot_root"], "root");
        }
    }
    std::fs::remove_dir_all(&dir).unwrap();
}
