//! Runs the Khronos glTF validator (npm `gltf-validator`, via scripts/validate-gltf.mjs) on the
//! .glb files we export: rest, posed and retargeted poses, with per-corner UVs, and the
//! embedded MakeHuman body. Needs node and
//! npm (the package is installed under the cargo target dir on first use); without them the
//! test prints SKIPPED, or fails when SKB_REQUIRE_SHARED_DATA is set (CI).

use std::path::{Path, PathBuf};
use std::process::Command;

use rand::SeedableRng;
use sketchbody::body::ik::{solve, IkOptions, Pose};
use sketchbody::body::procedural::{capsule_humanoid, random_pose, rest_joints};
use sketchbody::body::rig::{FaceUvs, RiggedMesh};
use sketchbody::body::{BodyModel, Gender};
use sketchbody::export::gltf::write_glb;

const VALIDATOR: &str = "gltf-validator@2.0.0-dev.3.10";

fn skip_or_fail(why: &str) {
    if std::env::var_os("SKB_REQUIRE_SHARED_DATA").is_some() {
        panic!("glTF validation: {why}, but SKB_REQUIRE_SHARED_DATA is set");
    }
    eprintln!("SKIPPED glTF validation: {why}");
}

/// The directory holding node_modules/gltf-validator, installing it there when missing.
fn validator_dir() -> Result<PathBuf, String> {
    let dir = std::env::var_os("SKB_GLTF_VALIDATOR_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| Path::new(env!("CARGO_TARGET_TMPDIR")).join("gltf-validator"));
    if dir.join("node_modules/gltf-validator/package.json").is_file() {
        return Ok(dir);
    }
    std::fs::create_dir_all(&dir).map_err(|e| format!("cannot create {}: {e}", dir.display()))?;
    let out = Command::new("npm")
        .args(["install", "--no-save", "--no-audit", "--no-fund", "--prefix"])
        .arg(&dir)
        .arg(VALIDATOR)
        .output()
        .map_err(|e| format!("npm not runnable: {e}"))?;
    if !out.status.success() {
        return Err(format!("npm install {VALIDATOR} failed: {}", String::from_utf8_lossy(&out.stderr)));
    }
    Ok(dir)
}

#[test]
fn exported_glb_files_have_no_validator_errors() {
    if Command::new("node").arg("--version").output().map(|o| !o.status.success()).unwrap_or(true) {
        return skip_or_fail("node is not installed");
    }
    let dir = match validator_dir() {
        Ok(d) => d,
        Err(e) => return skip_or_fail(&e),
    };
    let rest = rest_joints();
    let mut mesh = capsule_humanoid(&rest, 12, 10);
    // Per-corner UVs: a grid over each capsule, with seams (several UVs per vertex).
    let coords: Vec<[f32; 2]> = (0..mesh.quads.len())
        .flat_map(|f| {
            let u = (f % 10) as f32 / 10.0;
            let v = (f / 10 % 12) as f32 / 12.0;
            [[u, v], [u + 0.1, v], [u + 0.1, v + 1.0 / 12.0], [u, v + 1.0 / 12.0]]
        })
        .collect();
    let quads = (0..mesh.quads.len() as u32).map(|f| [4 * f, 4 * f + 1, 4 * f + 2, 4 * f + 3]).collect();
    mesh.uvs = Some(FaceUvs { coords, quads });
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
    let out = tempdir();
    let mut files = Vec::new();
    let cases = [
        ("rest", Pose::rest(&rest)),
        ("posed", solve(&rest, &random_pose(&rest, &mut rng, 0.0), &IkOptions::default()).unwrap()),
        ("retargeted", solve(&rest, &random_pose(&rest, &mut rng, 0.2), &IkOptions { retarget: true }).unwrap()),
    ];
    for (name, pose) in &cases {
        let path = out.join(format!("{name}.glb"));
        write_glb(&path, &mesh, pose).unwrap();
        files.push(path);
    }
    // The embedded MakeHuman body with its UVs, posed with retargeting.
    let model = BodyModel::embedded().unwrap();
    let body = RiggedMesh::from_model(&model, Gender::Female, &[]).unwrap();
    let pose = solve(&body.joints, &random_pose(&body.joints, &mut rng, 0.1), &IkOptions { retarget: true }).unwrap();
    let path = out.join("makehuman-female.glb");
    write_glb(&path, &body, &pose).unwrap();
    files.push(path);
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("scripts/validate-gltf.mjs");
    let run = Command::new("node").arg(&script).args(&files).env("GLTF_VALIDATOR_DIR", &dir).output().unwrap();
    let text = String::from_utf8_lossy(&run.stdout);
    println!("{text}{}", String::from_utf8_lossy(&run.stderr));
    assert!(run.status.success(), "validator reported errors:\n{text}");
    assert_eq!(text.matches(": 0 errors").count(), files.len(), "{text}");
    std::fs::remove_dir_all(&out).unwrap();
}

fn tempdir() -> PathBuf {
    let d = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("glb-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}
