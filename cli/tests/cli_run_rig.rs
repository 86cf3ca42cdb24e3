//! `sketchbody run` with issue 49's rig options: `--pose-as both --ik-targets --naming unreal`
//! (twist bones and shape keys on by default) in every format, against `--twist-bones false
//! --shape-keys false` (MakeHuman's 53 bones, no keys, the pose as the action `pose`); a bad
//! `--pose-as` fails and writes nothing.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

const SKETCH: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../assets/examples/sketch.png");
const JOINTS: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../assets/examples/sketch_joints.json");
/// Small fit settings: the tests check plumbing, not accuracy.
const FAST: [&str; 6] = ["--samples", "24", "--iterations", "2", "--quiet", "--preview-size=128"];

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("skb-cli-rig-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn run(out: &Path, extra: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_sketchbody"))
        .args(["run", SKETCH, "--joints", JOINTS, "--gender", "m", "--out", out.to_str().unwrap()])
        .args(FAST)
        .args(extra)
        .output()
        .unwrap()
}

/// The JSON chunk of a GLB.
fn glb_json(path: &Path) -> serde_json::Value {
    let b = std::fs::read(path).unwrap();
    let len = u32::from_le_bytes(b[12..16].try_into().unwrap()) as usize;
    serde_json::from_slice(&b[20..20 + len]).unwrap()
}

/// The number of shape weights the run's report lists.
fn reported_weights(dir: &Path) -> usize {
    let report = std::fs::read_to_string(dir.join("report.md")).unwrap();
    let line = report.lines().find(|l| l.starts_with("- shape weights (m)")).unwrap();
    let list = &line[line.find('[').unwrap() + 1..line.rfind(']').unwrap()];
    list.split(',').filter(|x| !x.trim().is_empty()).count()
}

#[test]
fn rig_options_reach_every_format() {
    let dir = scratch("rig");
    let all = dir.join("all");
    let out = run(&all, &["--format", "glb,fbx,usd", "--pose-as", "both", "--ik-targets", "--naming", "unreal"]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let doc = glb_json(&all.join("body.glb"));
    let joints = doc["skins"][0]["joints"].as_array().unwrap().len();
    assert_eq!(joints, 53 + 6 + 7);
    let names: Vec<&str> = doc["nodes"].as_array().unwrap().iter().filter_map(|n| n["name"].as_str()).collect();
    for name in ["upperarm_twist_01_l", "lowerarm_twist_01_r", "thigh_twist_01_l", "ik_hand_gun", "ik_foot_r"] {
        assert!(names.contains(&name), "{name} in {names:?}");
    }
    let n = reported_weights(&all);
    let keys: Vec<String> = (1..=n).map(|k| format!("shape_{k:02}")).collect();
    assert!(n >= 1);
    assert_eq!(doc["meshes"][0]["extras"]["targetNames"], serde_json::json!(keys));
    assert_eq!(doc["meshes"][0]["primitives"][0]["targets"].as_array().unwrap().len(), n);
    let clips: Vec<&str> = doc["animations"].as_array().unwrap().iter().map(|a| a["name"].as_str().unwrap()).collect();
    assert_eq!(clips, ["a_pose"]);
    let usda = std::fs::read_to_string(all.join("body.usda")).unwrap();
    assert!(usda.contains("def SkelAnimation \"a_pose\"") && !usda.contains("skel:animationSource"));
    assert_eq!(usda.matches("def BlendShape \"shape_").count(), n);
    assert!(usda.contains("upperarm_twist_01_l") && usda.contains("ik_hand_gun"));
    let fbx = std::fs::read(all.join("body.fbx")).unwrap();
    let count = |pat: &[u8]| fbx.windows(pat.len()).filter(|w| *w == pat).count();
    assert_eq!(count(b"BlendShapeChannel"), n);
    assert!(count(b"a_pose") >= 1 && count(b"upperarm_twist_01_l") >= 1 && count(b"ik_foot_root") >= 1);
    // Without twist bones and shape keys, the pose as the action: MakeHuman's 53 bones.
    let plain = dir.join("plain");
    let out = run(&plain, &["--twist-bones", "false", "--shape-keys", "false"]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let doc = glb_json(&plain.join("body.glb"));
    assert_eq!(doc["skins"][0]["joints"].as_array().unwrap().len(), 53);
    assert!(doc["meshes"][0]["primitives"][0].get("targets").is_none());
    assert_eq!(doc["animations"][0]["name"], "pose");
    // A bad --pose-as: an error naming the value, nothing written.
    let bad = dir.join("bad");
    let out = run(&bad, &["--pose-as", "keyed"]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("keyed") && err.contains("rest, action or both"), "{err}");
    assert!(!bad.exists() || std::fs::read_dir(&bad).unwrap().count() == 0, "nothing written on a bad --pose-as");
    std::fs::remove_dir_all(&dir).unwrap();
}
