//! `sketchbody run --format glb,fbx,usd --units cm --up z`: the rigged body in the formats
//! named, beside the other outputs, the FBX and USD in the unit and up axis asked for and the GLB
//! unchanged (metres, Y up: the same bytes as without them); an unknown format, unit or axis name
//! fails at argument parsing (exit 2, naming the option and the value) and writes nothing.

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
