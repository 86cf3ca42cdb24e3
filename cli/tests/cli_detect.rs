//! `sketchbody detect` end to end: joints JSON and overlay for the example
//! sketch with the PARSE model (reference data), one-line errors for corrupt models and tiny
//! images, and nothing written on failure.

#[path = "../../tests/common/mod.rs"]
mod common;

use std::path::PathBuf;
use std::process::Command;

fn cli() -> Command {
    Command::new(env!("CARGO_BIN_EXE_sketchbody"))
}

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("skb-cli-detect-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn one_line_failure(c: &mut Command) -> String {
    let out = c.output().unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8(out.stderr).unwrap();
    assert_eq!(err.trim_end().lines().count(), 1, "one line expected, got {err:?}");
    err
}

#[test]
fn corrupt_model_is_named_and_nothing_is_written() {
    let dir = scratch("corrupt");
    let model = dir.join("bad.skbd");
    std::fs::write(&model, b"SKBDET\0\0\x01\0\0\0").unwrap();
    let out = dir.join("j.json");
    let sketch = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../assets/examples/sketch.png");
    let err = one_line_failure(cli().arg("detect").arg(&sketch).arg("--model").arg(&model).arg("--out").arg(&out));
    assert!(err.contains("bad.skbd") && err.contains("truncated"), "{err}");
    assert!(!out.exists());
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn detect_finds_the_example_sketch_and_rejects_tiny_images() {
    let Some(data) = common::shared_data("cli_detect") else { return };
    let dir = scratch("ok");
    let skbd = data.join("fmp/parse_model.json");
    let sketch = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../assets/examples/sketch.png");
    let (out, overlay) = (dir.join("j.json"), dir.join("o.png"));
    // Cells of at least 8 px: the figure fills the 512² sketch (and the search stays quick).
    let st = cli()
        .args(["detect", "--min-cell", "8", "--model"])
        .arg(&skbd)
        .arg(&sketch)
        .arg("--out")
        .arg(&out)
        .arg("--overlay")
        .arg(&overlay)
        .status()
        .unwrap();
    assert!(st.success());
    let j: serde_json::Value = serde_json::from_slice(&std::fs::read(&out).unwrap()).unwrap();
    assert_eq!(j["format"], "sketchbody-joints2d");
    let y = |name: &str| j["joints"][name][1].as_f64().unwrap();
    assert!(
        y("head") < y("neck") && y("neck") < y("pelvis") && y("pelvis") < y("l_knee") && y("l_knee") < y("l_ankle")
    );
    // The example figure faces the viewer: its right side is on the image's left.
    let x = |name: &str| j["joints"][name][0].as_f64().unwrap();
    assert!(x("r_wrist") < x("l_wrist") && x("r_ankle") < x("l_ankle"));
    assert!(image::open(&overlay).unwrap().width() == 512);
    // A 20x20 image is rejected with the specific error.
    let tiny = dir.join("tiny.png");
    image::GrayImage::new(20, 20).save(&tiny).unwrap();
    let err =
        one_line_failure(cli().arg("detect").arg(&tiny).arg("--model").arg(&skbd).arg("--out").arg(dir.join("t.json")));
    assert!(err.contains("too small"), "{err}");
    assert!(!dir.join("t.json").exists());
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn detect_defaults_to_the_embedded_model_and_reports_no_figure() {
    let dir = scratch("embedded");
    let sketch = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../assets/examples/sketch.png");
    let (out, overlay) = (dir.join("j.json"), dir.join("o.png"));
    let res = cli()
        .args(["detect", "--min-cell", "4"])
        .arg(&sketch)
        .arg("--out")
        .arg(&out)
        .arg("--overlay")
        .arg(&overlay)
        .output()
        .unwrap();
    assert!(res.status.success(), "{}", String::from_utf8_lossy(&res.stderr));
    let j: serde_json::Value = serde_json::from_slice(&std::fs::read(&out).unwrap()).unwrap();
    assert_eq!(j["format"], "sketchbody-joints2d");
    let y = |name: &str| j["joints"][name][1].as_f64().unwrap();
    assert!(
        y("head") < y("neck") && y("neck") < y("pelvis") && y("pelvis") < y("l_knee") && y("l_knee") < y("l_ankle")
    );
    assert!(j["confidence"]["head"].as_f64().is_some_and(|c| c > 0.0 && c < 1.0));
    assert!(image::open(&overlay).unwrap().width() == 512);
    assert!(["fmp", "blazepose"].contains(&j["detection"]["backend"].as_str().unwrap()), "{}", j["detection"]);
    let c = j["detection"]["confidence"].as_f64().unwrap();
    assert_eq!(j["detection"]["low_confidence"].as_bool(), Some(c < 0.75));
    // On the clean example both backends find every joint: all are their mean, unless asked not.
    let averaged = j["detection"]["averaged_joints"].as_array().unwrap();
    assert_eq!(averaged.len(), 15, "{}", j["detection"]);
    // The example, a faceless outline facing the viewer: not read as seen from behind, the
    // front's labelling (the character's right shoulder on the image's left), and the swapped
    // labelling offered as the less likely alternative.
    use sketchbody::export::joints2d::{parse_alternatives, parse_facing, parse_joints2d};
    let facing = parse_facing(&j).unwrap().expect("a detection reports its facing");
    assert!(facing.facing != sketchbody::detect::facing::Facing::Back, "{:?}", facing);
    assert!((facing.probabilities.iter().sum::<f64>() - 1.0).abs() < 1e-9);
    let x = |name: &str| j["joints"][name][0].as_f64().unwrap();
    assert!(x("r_shoulder") < x("l_shoulder") && x("r_hip") < x("l_hip"));
    let alts = parse_alternatives(&j).unwrap();
    assert_eq!(alts.len(), 1);
    assert!(alts[0].swap == "left_right" && alts[0].score < 0.5, "{:?}", alts[0].score);
    let joints = parse_joints2d(&j).unwrap();
    assert_eq!(alts[0].joints, sketchbody::detect::facing::swap_sides(&joints));
    let out_line = String::from_utf8_lossy(&res.stdout);
    assert!(out_line.contains(&format!("facing {}", facing.facing.name())), "{out_line}");
    let plain = dir.join("plain.json");
    let mut plain_cmd = cli();
    plain_cmd.args(["detect", "--min-cell", "4"]).arg(&sketch).arg("--out").arg(&plain);
    assert!(plain_cmd.args(["--average-agreement", "0"]).status().unwrap().success());
    let p: serde_json::Value = serde_json::from_slice(&std::fs::read(&plain).unwrap()).unwrap();
    assert_eq!(p["detection"]["averaged_joints"].as_array().map(Vec::len), Some(0));
    assert_ne!(p["joints"], j["joints"], "the chosen backend's own joints");
    let bad = cli().arg("detect").arg(&sketch).arg("--out").arg(&plain).arg("--average-agreement=-1").output().unwrap();
    let err = String::from_utf8_lossy(&bad.stderr);
    assert!(!bad.status.success() && err.contains("--average-agreement") && err.contains(">= 0"), "{err}");
    // A blank page holds no figure by default: one line with the hint to give the joints.
    let blank = dir.join("blank.png");
    image::GrayImage::from_pixel(128, 128, image::Luma([255])).save(&blank).unwrap();
    let err = one_line_failure(cli().arg("detect").arg(&blank).arg("--out").arg(dir.join("b0.json")));
    assert!(err.contains("no figure") && err.contains("--joints"), "{err}");
    // Strict, the sketch model alone, an absurd threshold: one line naming the score.
    let strict = ["detect", "--detector", "fmp", "--strict"];
    let err =
        one_line_failure(cli().args(strict).arg("--threshold=1000").arg(&blank).arg("--out").arg(dir.join("b.json")));
    assert!(err.contains("no figure") && err.contains("1000"), "{err}");
    assert!(!dir.join("b.json").exists());
    // The score it names is the best one on that page (what a threshold below it returns).
    let st =
        cli().args(strict).arg("--threshold=-1e9").arg(&blank).arg("--out").arg(dir.join("b2.json")).status().unwrap();
    assert!(st.success());
    let b2: serde_json::Value = serde_json::from_slice(&std::fs::read(dir.join("b2.json")).unwrap()).unwrap();
    let best = b2["detection"]["raw_score"].as_f64().unwrap();
    assert!(err.contains(&format!("score {best:.3} is below the threshold 1000")), "{err} vs best {best}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn levels_per_octave_and_figure_flags_reach_the_search() {
    let dir = scratch("levels");
    let sketch = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../assets/examples/sketch.png");
    let score = |extra: &[&str], name: &str| {
        let out = dir.join(name);
        let res = cli()
            .args(["detect", "--detector", "fmp", "--strict", "--threshold=-1e9"])
            .args(extra)
            .arg(&sketch)
            .arg("--out")
            .arg(&out)
            .output()
            .unwrap();
        assert!(res.status.success(), "{extra:?}: {}", String::from_utf8_lossy(&res.stderr));
        let j: serde_json::Value = serde_json::from_slice(&std::fs::read(&out).unwrap()).unwrap();
        j["detection"]["raw_score"].as_f64().unwrap()
    };
    // Ten levels per octave (the model's own, 0) score a superset of the levels of five.
    let (s5, s10) = (score(&["--levels-per-octave", "5"], "a.json"), score(&["--levels-per-octave", "0"], "b.json"));
    assert!(s10 >= s5, "{s10} vs {s5}");
    // Figures of at most 0.3 of the side miss the page-filling figure.
    let small = score(&["--min-figure", "0.05", "--max-figure", "0.3"], "c.json");
    assert!(small < score(&[], "d.json"), "{small}");
    let err = one_line_failure(
        cli().args(["detect", "--levels-per-octave", "101"]).arg(&sketch).arg("--out").arg(dir.join("e.json")),
    );
    assert!(err.contains("levels_per_octave") && err.contains("101"), "{err}");
    assert!(!dir.join("e.json").exists());
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Issue 52 finding 9: `detect --overlay /dev/full` fails with the joints JSON unwritten (it
/// was written before the overlay failed); an existing JSON keeps its content.
#[test]
fn an_unwritable_overlay_leaves_the_joints_unwritten() {
    let dir = scratch("partial");
    let sketch = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../assets/examples/sketch.png");
    let out = dir.join("j.json");
    let cmd = || {
        let mut c = cli();
        c.args(["detect", "--detector", "fmp", "--min-cell", "8"]).arg(&sketch).arg("--out").arg(&out);
        c.args(["--overlay", "/dev/full"]);
        c
    };
    let err = one_line_failure(&mut cmd());
    assert!(err.contains("/dev/full"), "{err}");
    assert!(!out.exists(), "joints written by a failed command");
    std::fs::write(&out, "old").unwrap();
    one_line_failure(&mut cmd());
    assert_eq!(std::fs::read_to_string(&out).unwrap(), "old");
    assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 1, "no staging file left");
    std::fs::remove_dir_all(&dir).unwrap();
}
