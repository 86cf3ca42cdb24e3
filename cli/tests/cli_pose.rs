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
    // The ranked depth readings, read by the library's reader and, independently, here: the
    // first is the estimate itself, every one a full joint object, scores ascending after it.
    let text = std::fs::read_to_string(dir.join("out.json")).unwrap();
    let doc = sketchbody::export::pose3d::parse_pose3d(&text).unwrap();
    let alts = v["alternatives"].as_array().unwrap();
    assert!(!alts.is_empty() && alts.len() <= 8, "{}", alts.len());
    assert_eq!(doc.alternatives.len(), alts.len());
    assert_eq!(alts[0]["joints"], v["joints"]);
    assert_eq!(alts[0]["flipped"].as_array().unwrap().len(), 0);
    let names = ["r_upper_arm", "r_forearm", "l_upper_arm", "l_forearm", "r_thigh", "r_shin", "l_thigh", "l_shin"];
    let mut last = f64::NEG_INFINITY;
    for (i, (a, parsed)) in alts.iter().zip(&doc.alternatives).enumerate() {
        let joints = a["joints"].as_object().unwrap();
        assert_eq!(joints.len(), 15);
        for (k, name) in JOINT_NAMES.iter().enumerate() {
            let xyz: Vec<f64> = joints[*name].as_array().unwrap().iter().map(|c| c.as_f64().unwrap()).collect();
            assert_eq!(xyz, parsed.joints[k].to_vec(), "alternative {i} {name}");
        }
        let score = a["score"].as_f64().unwrap();
        assert_eq!(score, parsed.score);
        if i > 0 {
            assert!(score >= last, "alternative {i}: {score} < {last}");
            last = score;
            assert!(!a["flipped"].as_array().unwrap().is_empty());
        }
        let flipped: Vec<&str> = a["flipped"].as_array().unwrap().iter().map(|n| n.as_str().unwrap()).collect();
        assert!(flipped.iter().all(|n| names.contains(n)), "{flipped:?}");
        assert_eq!(flipped, parsed.flipped.iter().map(|l| l.name()).collect::<Vec<_>>());
    }
    assert_eq!(doc.joints, doc.alternatives[0].joints);
    // A file without alternatives (written before they existed) reads as none; a bad limb name
    // is refused.
    let mut old = v.clone();
    old.as_object_mut().unwrap().remove("alternatives");
    assert!(sketchbody::export::pose3d::parse_pose3d(&old.to_string()).unwrap().alternatives.is_empty());
    let mut bad = v.clone();
    bad["alternatives"][0]["flipped"] = serde_json::json!(["tail"]);
    assert!(sketchbody::export::pose3d::parse_pose3d(&bad.to_string()).is_err());
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
