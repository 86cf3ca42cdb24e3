//! `sketchbody run --format glb,fbx,usd`: the rigged body in the formats named, beside the other
//! outputs; an unknown format name fails at argument parsing (exit 2, naming the option) and
//! writes nothing.

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
    let out = run(&all, &["--format", "glb,fbx,usd"]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let fbx = std::fs::read(all.join("body.fbx")).unwrap();
    assert_eq!(&fbx[..23], b"Kaydara FBX Binary  \x00\x1a\x00");
    assert!(fbx.windows(4).any(|w| w == b"\x89PNG"), "the texture is embedded");
    let usda = std::fs::read_to_string(all.join("body.usda")).unwrap();
    assert!(usda.starts_with("#usda 1.0") && usda.contains("@body_texture.png@"));
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
    // An unknown name: exit 2 at argument parsing, naming the option, nothing written.
    let bad = dir.join("bad");
    let out = run(&bad, &["--format", "glb,obj"]);
    assert_eq!(out.status.code(), Some(2), "{out:?}");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("--format") && err.contains("obj"), "{err}");
    assert!(!bad.exists(), "nothing written on a bad format");
    std::fs::remove_dir_all(&dir).unwrap();
}
