//! `sketchbody pose` end to end: JSON in, JSON out, and one-line errors for bad input.

use std::path::PathBuf;
use std::process::Command;

use sketchbody::pose::dict_io;
use sketchbody::skeleton::JOINT_NAMES;

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("skb-cli-pose-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// The mean pose seen from the front, as a joints2d document.
fn joints_doc() -> serde_json::Value {
    let d = dict_io::embedded().unwrap();
    let mut joints = serde_json::Map::new();
    for (k, name) in JOINT_NAMES.iter().enumerate() {
        joints.insert(
            name.to_string(),
            serde_json::json!([256.0 + 280.0 * d.mean[3 * k], 300.0 - 280.0 * d.mean[3 * k + 1]]),
        );
    }
    serde_json::json!({"format": "sketchbody-joints2d", "version": 1, "joints": joints, "missing": ["l_wrist"]})
}

fn run_with(input: &serde_json::Value, dir: &std::path::Path, extra: &[&str]) -> std::process::Output {
    let (inp, out) = (dir.join("in.json"), dir.join("out.json"));
    std::fs::write(&inp, serde_json::to_vec(input).unwrap()).unwrap();
    Command::new(env!("CARGO_BIN_EXE_sketchbody"))
        .arg("pose")
        .arg(&inp)
        .arg("--out")
        .arg(&out)
        .args(extra)
        .output()
        .unwrap()
}

fn run(input: &serde_json::Value, dir: &std::path::Path) -> std::process::Output {
    run_with(input, dir, &[])
}

#[test]
fn pose_writes_joints_camera_and_bases() {
    let dir = scratch("ok");
    // From the mean pose (the paper's start), without the free-joint refinement (which trades a
    // pixel for the standing prior), the mean pose's own view fits exactly.
    let out = run_with(&joints_doc(), &dir, &["--starts", "0", "--joint-noise", "0"]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let v: serde_json::Value = serde_json::from_slice(&std::fs::read(dir.join("out.json")).unwrap()).unwrap();
    assert_eq!(v["format"], "sketchbody-pose3d");
    assert_eq!(v["joints"].as_object().unwrap().len(), 15);
    assert_eq!(v["camera"]["r"].as_array().unwrap().len(), 3);
    let rms0 = v["reprojection_rms_px"].as_f64().unwrap();
    assert!(rms0 < 1e-3, "rms from the mean pose {rms0}");
    assert!(v["bases"].is_array());
    assert!(v["base_exemplars"].is_null());
    assert_eq!(v["options"]["starts"], 0);
    // With the refinement on, the standing prior may move the joints by about a pixel, no more.
    let out = run_with(&joints_doc(), &dir, &["--starts", "0"]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let v: serde_json::Value = serde_json::from_slice(&std::fs::read(dir.join("out.json")).unwrap()).unwrap();
    let rms_refined = v["reprojection_rms_px"].as_f64().unwrap();
    assert!(rms_refined < 2.0, "rms with the refinement {rms_refined}");
    // The default starts from training exemplars (torso and four limbs recorded); the weight
    // prior toward them leaves a few pixels on this synthetic average figure.
    let out = run(&joints_doc(), &dir);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let v: serde_json::Value = serde_json::from_slice(&std::fs::read(dir.join("out.json")).unwrap()).unwrap();
    assert_eq!(v["base_exemplars"].as_array().map(|a| a.len()), Some(5));
    let rms = v["reprojection_rms_px"].as_f64().unwrap();
    assert!(rms < 8.0, "rms {rms}");
}

#[test]
fn pose_rejects_bad_joints_in_one_line_and_writes_nothing() {
    let dir = scratch("bad");
    let mut doc = joints_doc();
    doc["joints"].as_object_mut().unwrap().remove("head");
    let mut coincident = joints_doc();
    coincident["joints"]["r_elbow"] = coincident["joints"]["r_shoulder"].clone();
    let mut unknown = joints_doc();
    unknown["joints"]["tail"] = serde_json::json!([1.0, 2.0]);
    for (bad, expect) in [(doc, "head is missing"), (coincident, "coincide"), (unknown, "unknown joint")] {
        let out = run(&bad, &dir);
        assert!(!out.status.success());
        let err = String::from_utf8(out.stderr).unwrap();
        assert_eq!(err.trim_end().lines().count(), 1, "{err}");
        assert!(err.contains(expect), "{err}");
        assert!(!dir.join("out.json").exists());
    }
}

#[test]
fn an_out_of_range_depth_prior_is_refused_before_any_work() {
    let dir = scratch("depth_prior");
    let out = run_with(&joints_doc(), &dir, &["--depth-prior", "11"]);
    assert_eq!(out.status.code(), Some(2), "a parse error");
    assert!(String::from_utf8_lossy(&out.stderr).contains("--depth-prior"));
    assert!(!dir.join("out.json").exists());
}
