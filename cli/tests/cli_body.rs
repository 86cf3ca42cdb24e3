//! `sketchbody body`: builds, poses and exports the embedded body; rejects bad input with one
//! line and no output file.

use std::path::{Path, PathBuf};
use std::process::Command;

use rand::SeedableRng;
use sketchbody::body::procedural::random_pose;
use sketchbody::body::rig::RiggedMesh;
use sketchbody::body::{BodyModel, Gender};
use sketchbody::export::joints::write_joints3_json;

fn dir() -> PathBuf {
    let d = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("cli-body-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn run(args: &[&str]) -> (bool, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_sketchbody")).arg("body").args(args).output().unwrap();
    (out.status.success(), String::from_utf8_lossy(&out.stderr).into_owned())
}

#[test]
fn body_command_writes_posed_glb_obj_and_preview() {
    let d = dir();
    let model = BodyModel::embedded().unwrap();
    let mesh = RiggedMesh::from_model(&model, Gender::Male, &[0.05, -0.02]).unwrap();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(8);
    let pose = d.join("pose.json");
    write_joints3_json(&pose, &random_pose(&mesh.joints, &mut rng, 0.1)).unwrap();
    let (glb, obj, png) = (d.join("b.glb"), d.join("b.obj"), d.join("b.png"));
    let s = |p: &Path| p.to_str().unwrap().to_owned();
    let (ok, err) = run(&[
        "--gender",
        "m",
        "--weights",
        "0.05,-0.02",
        "--pose",
        &s(&pose),
        "--retarget",
        "--out",
        &s(&glb),
        "--preview",
        &s(&png),
        "--preview-size",
        "128",
    ]);
    assert!(ok, "{err}");
    let (ok, err) = run(&["--gender", "female", "--dqs", "--pose", &s(&pose), "--out", &s(&obj)]);
    assert!(ok, "{err}");
    assert_eq!(&std::fs::read(&glb).unwrap()[..4], b"glTF");
    assert!(std::fs::read_to_string(&obj).unwrap().lines().filter(|l| l.starts_with("f ")).count() == 13378);
    assert_eq!(&std::fs::read(&png).unwrap()[1..4], b"PNG");

    let mut coincident = mesh.joints;
    coincident[3] = coincident[4];
    let bad_pose = d.join("bad.json");
    write_joints3_json(&bad_pose, &coincident).unwrap();
    let missing = d.join("never.glb");
    for (args, needle) in [
        (vec!["--gender", "x", "--out", &s(&missing)], "gender"),
        (vec!["--gender", "f", "--weights", "NaN", "--out", &s(&missing)], "finite"),
        (vec!["--gender", "f", "--pose", &s(&bad_pose), "--out", &s(&missing)], "r_elbow"),
        (vec!["--gender", "f", "--out", &s(&d.join("never.stl"))], ".glb or .obj"),
        (vec!["--gender", "f", "--out", &s(&missing), "--preview", &s(&png), "--preview-size", "0"], "empty"),
    ] {
        let (ok, err) = run(&args);
        assert!(!ok && err.contains(needle), "{args:?}: {err}");
        assert_eq!(err.lines().count(), 1, "{err}");
    }
    assert!(!missing.exists());
    std::fs::remove_dir_all(&d).unwrap();
}

/// Issue 52 finding 9: an output that cannot be written (`--preview /dev/full`, a device)
/// fails the command with none of its outputs written: no new file, an old one unchanged.
#[test]
fn an_unwritable_preview_leaves_the_mesh_unwritten() {
    let d = dir().join("partial");
    std::fs::create_dir_all(&d).unwrap();
    let obj = d.join("o.obj");
    let args = ["--gender", "f", "--out", obj.to_str().unwrap(), "--preview", "/dev/full", "--preview-size", "16"];
    let (ok, err) = run(&args);
    assert!(!ok && err.contains("/dev/full") && err.contains("not a regular file"), "{err}");
    assert!(!obj.exists(), "o.obj written by a failed command");
    std::fs::write(&obj, "old").unwrap();
    let (ok, err) = run(&args);
    assert!(!ok, "{err}");
    assert_eq!(std::fs::read_to_string(&obj).unwrap(), "old");
    let left: Vec<_> = std::fs::read_dir(&d).unwrap().flatten().map(|e| e.file_name()).collect();
    assert_eq!(left, ["o.obj"], "no staging file left");
    std::fs::remove_dir_all(&d).unwrap();
}
