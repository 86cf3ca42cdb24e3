//! `sketchbody-lab convert-detector` and `eval-detector` end to end: a converted model loads as
//! the same model, a missing input is named in one line, and eval-detector takes the detect
//! command's search flags and reports the figure sizes and scales found.

#[path = "../../tests/common/mod.rs"]
mod common;

use std::path::PathBuf;
use std::process::Command;

use sketchbody::detect::Model;

fn cli() -> Command {
    Command::new(env!("CARGO_BIN_EXE_sketchbody-lab"))
}

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("skb-lab-detector-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

#[test]
fn convert_detector_names_a_missing_input_and_writes_nothing() {
    let dir = scratch("missing");
    let out = cli().arg("convert-detector").arg(dir.join("missing.json")).arg(dir.join("m.skbd")).output().unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8(out.stderr).unwrap();
    assert_eq!(err.trim_end().lines().count(), 1, "one line expected, got {err:?}");
    assert!(err.contains("missing.json") && err.starts_with("sketchbody-lab: "), "{err}");
    assert!(!dir.join("m.skbd").exists());
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn convert_detector_writes_the_same_model() {
    let Some(data) = common::shared_data("lab_detector") else { return };
    let dir = scratch("convert");
    let (json, skbd) = (data.join("fmp/parse_model.json"), dir.join("parse.skbd"));
    let st = cli().arg("convert-detector").arg(&json).arg(&skbd).status().unwrap();
    assert!(st.success());
    assert!(Model::load_any(&json).unwrap() == Model::load_any(&skbd).unwrap());
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn eval_detector_takes_the_search_flags() {
    let dir = scratch("eval");
    // eval-detector takes the same flags and reports the figure sizes and the scales found.
    let res = cli()
        .args([
            "eval-detector",
            "--n",
            "2",
            "--size",
            "256",
            "--levels-per-octave",
            "5",
            "--min-figure",
            "0.4",
            "--by-style",
        ])
        .output()
        .unwrap();
    assert!(res.status.success(), "{}", String::from_utf8_lossy(&res.stderr));
    let text = String::from_utf8(res.stdout).unwrap();
    assert!(text.contains("figures 0.4..1 of the side") && text.contains("5 levels per octave"), "{text}");
    assert!(
        text.contains("drawn figure height / shorter side: min 0.")
            && text.contains("found at (cell × rest height / shorter side)"),
        "{text}"
    );
    // --by-style: one row per rendering choice; "all" holds both sketches with the overall PCK.
    let pck10 = text.split("PCK@0.1 ").nth(1).and_then(|t| t.split_whitespace().next()).unwrap().to_string();
    let all = text.lines().find(|l| l.trim_start().starts_with("all ")).unwrap_or_else(|| panic!("{text}"));
    assert!(all.split_whitespace().nth(1) == Some("2") && all.contains(&format!("{pck10} / ")), "{all} vs {pck10}");
    assert!(text.contains("|yaw| >= 20 deg") && text.contains("cape"), "{text}");
    std::fs::remove_dir_all(&dir).unwrap();
}
