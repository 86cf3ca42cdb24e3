//! `sketchbody run --format glb,fbx,usd --units cm --up z`: the rigged body in the formats
//! named, beside the other outputs, the FBX and USD in the unit and up axis asked for and the GLB
//! unchanged (metres, Y up: the same bytes as without them); an unknown format, unit or axis name
//! fails at argument parsing (exit 2, naming the option and the value) and writes nothing; the
//! rig options of issue 49 reach every format.

use std::path::PathBuf;
use std::process::{Command, Output};

const SKETCH: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../assets/examples/sketch.png");
const JOINTS: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../assets/examples/sketch_joints.json");
/// Small fit settings: the tests check plumbing, not accuracy.
const FAST: [&str; 6] = ["--samples", "24", "--iterations", "2", "--quiet", "--preview-size=128"];

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("skb-cli-formats-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn run(out: &std::path::Path, extra: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_sketchbody"))
        .args(["run", SKETCH, "--joints", JOINTS, "--gender", "m", "--out", out.to_str().unwrap()])
        .args(FAST)
        .args(extra)
        .output()
        .unwrap()
}

fn exists(dir: &std::path::Path, name: &str) -> bool {
    dir.join(name).exists()
}

#[test]
fn each_format_named_is_written_and_an_unknown_one_is_refused() {
    let dir = scratch("all");
    let all = dir.join("all");
    let out = run(&all, &["--format", "glb,fbx,usd", "--units", "cm", "--up", "z"]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let fbx = std::fs::read(all.join("body.fbx")).unwrap();
    assert_eq!(&fbx[..23], b"Kaydara FBX Binary  \x00\x1a\x00");
    assert!(fbx.windows(4).any(|w| w == b"\x89PNG"), "the texture is embedded");
    let usda = std::fs::read_to_string(all.join("body.usda")).unwrap();
    assert!(usda.starts_with("#usda 1.0") && usda.contains("@body_texture.png@"));
    assert!(usda.contains("    metersPerUnit = 0.01\n") && usda.contains("    upAxis = \"Z\"\n"), "cm, Z up");
    // FBX's UnitScaleFactor (centimetres per unit) is the double after its name's P entry.
    let at = fbx.windows(15).position(|w| w == b"UnitScaleFactor").expect("UnitScaleFactor");
    let d = fbx[at..].iter().position(|&b| b == b'D').map(|k| at + k).unwrap();
    assert_eq!(f64::from_le_bytes(fbx[d + 1..d + 9].try_into().unwrap()), 1.0, "centimetres");
    assert!(exists(&all, "body.glb") && exists(&all, "body_texture.png"));
    let report = std::fs::read_to_string(all.join("report.md")).unwrap();
    assert!(report.contains("body.glb, body.fbx, body.usda, body.obj"), "{report}");
    // Only FBX: no GLB.
    let only = dir.join("only");
    let out = run(&only, &["--format", "fbx"]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    assert!(exists(&only, "body.fbx") && !exists(&only, "body.glb") && !exists(&only, "body.usda"));
    // The default: GLB only.
    let default = dir.join("default");
    assert!(run(&default, &[]).status.success());
    assert!(exists(&default, "body.glb") && !exists(&default, "body.fbx") && !exists(&default, "body.usda"));
    assert!(
        std::fs::read(default.join("body.glb")).unwrap() == std::fs::read(all.join("body.glb")).unwrap(),
        "--units and --up leave the GLB in metres, Y up"
    );
    // An unknown name: exit 2 at argument parsing, naming the option, nothing written.
    let bad = dir.join("bad");
    let out = run(&bad, &["--format", "glb,obj"]);
    assert_eq!(out.status.code(), Some(2), "{out:?}");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("--format") && err.contains("obj"), "{err}");
    assert!(!bad.exists(), "nothing written on a bad format");
    for (option, value, choices) in [("--units", "mm", "m or cm"), ("--up", "x", "y or z")] {
        let out = run(&bad, &["--format", "fbx", option, value]);
        assert_eq!(out.status.code(), Some(2), "{out:?}");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains(option) && err.contains(value) && err.contains(choices), "{err}");
        assert!(!bad.exists(), "nothing written on a bad {option}");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// The JSON chunk of a GLB.
fn glb_json(path: &std::path::Path) -> serde_json::Value {
    let b = std::fs::read(path).unwrap();
    let len = u32::from_le_bytes(b[12..16].try_into().unwrap()) as usize;
    serde_json::from_slice(&b[20..20 + len]).unwrap()
}

/// The number of shape weights the run's report lists.
fn reported_weights(dir: &std::path::Path) -> usize {
    let report = std::fs::read_to_string(dir.join("report.md")).unwrap();
    let line = report.lines().find(|l| l.starts_with("- shape weights (m)")).unwrap();
    let list = &line[line.find('[').unwrap() + 1..line.rfind(']').unwrap()];
    list.split(',').filter(|x| !x.trim().is_empty()).count()
}

/// Issue 49's rig options: `--pose-as both --ik-targets --naming unreal` (twist bones and shape
/// keys on by default) in every format, against `--twist-bones false --shape-keys false`
/// (MakeHuman's 53 bones, no keys, the pose as the action `pose`); a bad `--pose-as` fails and
/// writes nothing.
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
