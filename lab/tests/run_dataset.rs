//! `sketchbody-lab run-dataset` on a tiny rendered dataset: the results layout `eval` reads, the
//! mean-shape baseline, resuming, determinism across thread counts, a given pose dictionary, and
//! its errors.

#[path = "../../tests/common/mod.rs"]
mod common;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("skb-cli-rds-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn skb(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_sketchbody-lab")).args(args).output().unwrap()
}

fn ok(o: &Output) {
    assert!(o.status.success(), "{}\n{}", String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr));
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

#[test]
fn results_are_scored_by_eval_and_deterministic() {
    let dir = scratch("ok");
    let (ds, a, b, m) = (dir.join("ds"), dir.join("a"), dir.join("b"), dir.join("mean"));
    ok(&skb(&["make-dataset", "3", "--seed", "5", "--size", "256", "--out", s(&ds)]));
    let fast = ["--samples", "16", "--iterations", "2"];
    ok(&skb(&[&["run-dataset", s(&ds), "--out", s(&a), "--threads", "2"][..], &fast].concat()));
    ok(&skb(&[&["run-dataset", s(&ds), "--out", s(&b), "--threads", "1"][..], &fast].concat()));
    for stem in ["000000", "000001", "000002"] {
        for f in [format!("{stem}.json"), format!("{stem}_rest.obj"), format!("{stem}_posed.obj")] {
            let (fa, fb) = (std::fs::read(a.join(&f)).unwrap(), std::fs::read(b.join(&f)).unwrap());
            if f.ends_with(".obj") {
                assert_eq!(fa, fb, "{f} differs between 1 and 2 threads");
            } else {
                // Everything but the wall-clock time must be identical.
                let mut ja: serde_json::Value = serde_json::from_slice(&fa).unwrap();
                let mut jb: serde_json::Value = serde_json::from_slice(&fb).unwrap();
                assert!(ja["seconds"].as_f64().is_some_and(|t| t >= 0.0), "{f}: seconds");
                ja["seconds"] = serde_json::Value::Null;
                jb["seconds"] = serde_json::Value::Null;
                assert_eq!(ja, jb, "{f} differs between 1 and 2 threads");
            }
        }
        let truth: serde_json::Value =
            serde_json::from_slice(&std::fs::read(ds.join(format!("{stem}.json"))).unwrap()).unwrap();
        let res: serde_json::Value =
            serde_json::from_slice(&std::fs::read(a.join(format!("{stem}.json"))).unwrap()).unwrap();
        assert_eq!(res["gender"], truth["gender"], "gender comes from the ground truth by default");
        let gender = res["gender"].as_str().unwrap();
        assert!(res["score"].as_f64().is_some_and(|x| x < 0.0) && res["score"] == res["scores"][gender], "{res}");
        assert_eq!(res["joints2d"], truth["joints2d"]);
    }
    // Detected joints instead of the ground truth: results for every sample, near the truth.
    let d = dir.join("det");
    ok(&skb(&[&["run-dataset", s(&ds), "--out", s(&d), "--detect"][..], &fast].concat()));
    let (mut close, mut total) = (0, 0);
    for stem in ["000000", "000001", "000002"] {
        let truth: serde_json::Value =
            serde_json::from_slice(&std::fs::read(ds.join(format!("{stem}.json"))).unwrap()).unwrap();
        let res: serde_json::Value =
            serde_json::from_slice(&std::fs::read(d.join(format!("{stem}.json"))).unwrap()).unwrap();
        let (t, r) = (truth["joints2d"].as_array().unwrap(), res["joints2d"].as_array().unwrap());
        let ys: Vec<f64> = t.iter().map(|p| p[1].as_f64().unwrap()).collect();
        let height =
            ys.iter().cloned().fold(f64::NEG_INFINITY, f64::max) - ys.iter().cloned().fold(f64::INFINITY, f64::min);
        for (p, q) in t.iter().zip(r) {
            let dist = (p[0].as_f64().unwrap() - q[0].as_f64().unwrap())
                .hypot(p[1].as_f64().unwrap() - q[1].as_f64().unwrap());
            total += 1;
            close += (dist < 0.2 * height) as usize;
        }
        assert_ne!(res["joints2d"], truth["joints2d"], "{stem}: joints come from the detector");
    }
    assert!(close * 5 >= total * 4, "{close} of {total} detected joints within 0.2 figure heights");
    let manifest: serde_json::Value = serde_json::from_slice(&std::fs::read(d.join("run.json")).unwrap()).unwrap();
    assert_eq!(manifest["detector"], "auto", "--detect runs the product's default single-figure detector");
    let plain: serde_json::Value = serde_json::from_slice(&std::fs::read(a.join("run.json")).unwrap()).unwrap();
    assert!(plain["detector"].is_null(), "ground-truth joints name no detector");
    assert_eq!(plain["depth_prior"], 0.05, "the pose step's default weight of its learned depths is recorded");
    assert_eq!(plain["initial_factor"], 8, "the fit's population schedule is recorded");
    let bad = skb(&["run-dataset", s(&ds), "--out", s(&dir.join("bad")), "--detector", "fmp"]);
    assert!(!bad.status.success(), "--detector without --detect is refused");
    // Resuming skips finished samples.
    let again = skb(&[&["run-dataset", s(&ds), "--out", s(&a)][..], &fast].concat());
    ok(&again);
    assert!(
        String::from_utf8_lossy(&again.stdout).contains("0 samples run, 3 already done"),
        "{}",
        String::from_utf8_lossy(&again.stdout)
    );
    ok(&skb(&["run-dataset", s(&ds), "--out", s(&m), "--mean-shape"]));
    let e = skb(&["eval", s(&ds), s(&m), "--compare", s(&a)]);
    ok(&e);
    let table = String::from_utf8_lossy(&e.stdout);
    let aed_row = table.lines().find(|l| l.starts_with("| aed_rest |")).unwrap();
    let cells: Vec<&str> = aed_row.split('|').map(str::trim).collect();
    assert_eq!((cells[3], cells[5]), ("3", "3"), "{aed_row}");
    assert!(cells[2].parse::<f64>().unwrap() > 0.0 && cells[4].parse::<f64>().unwrap() > 0.0, "{aed_row}");
    shape_floor_agrees_with_eval(&ds, &table);
    // `--score-line N`: N + 1 scores from the mean shape (t = 0) to the truth's projection
    // (t = 1), and the fit's own weights' score; the truth drawn by the model's own renderer,
    // with its pose, camera and height, scores above the mean shape.
    let line = dir.join("line");
    let extra = ["--oracle-pose", "--true-height", "--score-line", "2"];
    ok(&skb(&[&["run-dataset", s(&ds), "--out", s(&line)][..], &fast, &extra].concat()));
    let mut rising = 0;
    for stem in ["000000", "000001", "000002"] {
        let r: serde_json::Value =
            serde_json::from_slice(&std::fs::read(line.join(format!("{stem}.json"))).unwrap()).unwrap();
        let l = r["score_line"].as_array().unwrap_or_else(|| panic!("{stem}: {r}"));
        let t: Vec<f64> = l.iter().map(|p| p["t"].as_f64().unwrap()).collect();
        assert_eq!(t, [0.0, 0.5, 1.0], "{stem}");
        let sc: Vec<f64> = l.iter().map(|p| p["score"].as_f64().unwrap()).collect();
        assert!(r["score_line_fit"].as_f64().is_some(), "{stem}: {r}");
        rising += (sc[2] > sc[0]) as usize;
    }
    assert!(rising >= 2, "the truth above the mean on {rising} of 3");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `shape-floor`'s mean-shape row is the mean-shape baseline `eval` scored (`eval_table`, the
/// mean-shape results first), and the truth projected onto all 16 dimensions of the model it
/// was rendered from lies far below it; so do its front-view projections (`--axes`).
fn shape_floor_agrees_with_eval(ds: &Path, eval_table: &str) {
    let o = skb(&["shape-floor", s(ds), "--dims", "4,16"]);
    ok(&o);
    let floor = String::from_utf8_lossy(&o.stdout);
    let cell = |table: &str, row: &str, col: usize| -> f64 {
        let line = table.lines().find(|l| l.starts_with(row)).unwrap_or_else(|| panic!("no {row} in {table}"));
        line.split('|').map(str::trim).nth(col).unwrap().parse().unwrap()
    };
    let eval_mean = cell(eval_table, "| aed_rest_centred |", 2);
    assert!((cell(&floor, "| mean shape |", 2) - eval_mean).abs() < 1.5e-4, "{floor} vs eval {eval_mean}");
    let (four, all) = (cell(&floor, "| truth projected, 4 dims |", 2), cell(&floor, "| truth projected, 16 dims |", 2));
    assert!(all <= four && all < 0.5 * eval_mean, "{floor}");
    let bad = skb(&["shape-floor", s(ds), "--dims", "17"]);
    assert!(!bad.status.success() && String::from_utf8_lossy(&bad.stderr).contains("17 > 16"));
    // What a front view could tell (issue 47): the truth's heights and widths, or only the
    // offsets across its front contour (and a side view's), with the prior. On bodies the model drew itself, both
    // recover most of the body; fewer constraints never fit the truth better than all of them;
    // every coordinate without noise is the plain projection.
    let run = |axes: &str, noise: &str| -> String {
        let o = skb(&["shape-floor", s(ds), "--dims", "4,16", "--axes", axes, "--noise-mm", noise]);
        ok(&o);
        String::from_utf8_lossy(&o.stdout).into_owned()
    };
    let at_height = |t: &str, row: &str| cell(t, row, 5);
    let plain = run("xyz", "0");
    assert_eq!(at_height(&plain, "| truth projected, 16 dims |"), at_height(&floor, "| truth projected, 16 dims |"));
    let mean_at_height = at_height(&floor, "| mean shape |");
    for axes in ["xy", "outline", "outline+side"] {
        let t = run(axes, "50");
        let sixteen = at_height(&t, "| truth projected, 16 dims |");
        assert!(sixteen < 0.6 * mean_at_height, "{axes}: {t}");
        assert!(sixteen >= at_height(&floor, "| truth projected, 16 dims |") - 1e-4, "{axes}: {t} vs {floor}");
    }
    let bad = skb(&["shape-floor", s(ds), "--axes", "z"]);
    assert!(!bad.status.success() && String::from_utf8_lossy(&bad.stderr).contains("--axes z"));
}

/// `--dictionary` replaces the embedded pose dictionary: the embedded asset given as a file
/// changes nothing, one learned from other motion changes the pose (and so the body), the
/// manifest names the file, and a missing file is a one-line error naming it.
#[test]
fn a_given_dictionary_replaces_the_embedded_one() {
    let dir = scratch("dict");
    let ds = dir.join("ds");
    ok(&skb(&["make-dataset", "2", "--seed", "9", "--size", "256", "--out", s(&ds)]));
    let fast = ["--samples", "16", "--iterations", "2"];
    let run = |out: &Path, dict: Option<&Path>| {
        let mut args = vec!["run-dataset", s(&ds), "--out", s(out)];
        args.extend(dict.map(|d| ["--dictionary", s(d)]).into_iter().flatten());
        ok(&skb(&[&args[..], &fast].concat()));
    };
    let json = |out: &Path, stem: &str| -> serde_json::Value {
        let mut v: serde_json::Value =
            serde_json::from_slice(&std::fs::read(out.join(format!("{stem}.json"))).unwrap()).unwrap();
        v["seconds"] = serde_json::Value::Null;
        v
    };
    let (plain, same) = (dir.join("plain"), dir.join("same"));
    let asset = Path::new(env!("CARGO_MANIFEST_DIR")).join("../assets/pose_dictionary.skbpd");
    run(&plain, None);
    run(&same, Some(&asset));
    for stem in ["000000", "000001"] {
        assert_eq!(json(&plain, stem), json(&same, stem), "{stem}: the embedded dictionary as a file");
    }
    let manifest: serde_json::Value = serde_json::from_slice(&std::fs::read(same.join("run.json")).unwrap()).unwrap();
    assert_eq!(manifest["dictionary"], s(&asset));
    let missing = dir.join("none.skbpd");
    let o = skb(&["run-dataset", s(&ds), "--out", s(&dir.join("bad")), "--dictionary", s(&missing)]);
    assert_eq!(o.status.code(), Some(1), "{o:?}");
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.trim_end().lines().count() == 1 && err.contains("none.skbpd"), "{err}");
    // A dictionary of walking alone (the DeepMimic walks) poses the same sketches otherwise.
    let Some(data) = common::shared_data("run-dataset --dictionary") else { return };
    let walks = dir.join("walks.skbpd");
    ok(&skb(&[
        "learn-poses",
        "--mocap",
        s(&data.join("mocap/deepmimic")),
        "--exclude",
        "backflip,cartwheel,crawl,dance_a,dance_spin,getup_facedown,getup_faceup,jump,punch,roll,run,sideflip,spin,spinkick,zombie_walk,long_long_zombie",
        "--out",
        s(&walks),
    ]));
    let other = dir.join("other");
    run(&other, Some(&walks));
    let differ = ["000000", "000001"]
        .iter()
        .filter(|stem| json(&plain, stem)["joints3d"] != json(&other, stem)["joints3d"])
        .count();
    assert!(differ > 0, "another dictionary, another 3-D pose");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn errors_are_one_line() {
    let dir = scratch("bad");
    let empty = dir.join("empty");
    std::fs::create_dir_all(&empty).unwrap();
    for (args, expect) in [
        (vec!["run-dataset", s(&empty), "--out", s(&dir.join("r"))], "no samples"),
        (
            vec!["run-dataset", s(&empty), "--out", s(&dir.join("r")), "--gender", "auto", "--mean-shape"],
            "--mean-shape needs",
        ),
        (
            vec!["run-dataset", s(&empty), "--out", s(&dir.join("r")), "--score", "best"],
            "expected paper, filled, chamfer or chamfer2",
        ),
    ] {
        let o = skb(&args);
        assert_eq!(o.status.code(), Some(1), "{o:?}");
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(err.trim_end().lines().count(), 1, "{err}");
        assert!(err.contains(expect), "{expect}: {err}");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn train_gender_fits_the_margin_combination_on_either_classifiers_log_odds() {
    let dir = scratch("gender");
    let ds = dir.join("ds");
    ok(&skb(&["make-dataset", "8", "--seed", "6", "--size", "256", "--out", s(&ds)]));
    let fast = ["--samples", "16", "--iterations", "2"];
    for g in ["f", "m"] {
        ok(&skb(&[&["run-dataset", s(&ds), "--out", s(&dir.join(g)), "--gender", g][..], &fast].concat()));
    }
    let fits = format!("{}={},{}", s(&ds), s(&dir.join("f")), s(&dir.join("m")));
    // The first mean is that of the classifier's log-odds: the given-joints classifier's by
    // default, the detected-joints one's with --detected; the margin's mean is the same.
    let means = |extra: &[&str]| -> Vec<f64> {
        let o = skb(&[&["train-gender", "--fits", &fits][..], extra].concat());
        ok(&o);
        let out = String::from_utf8_lossy(&o.stdout).into_owned();
        assert!(out.contains("trained on 8 samples"), "{out}");
        let line = out.lines().find(|l| l.trim_start().starts_with("means:")).unwrap().to_string();
        line.split(['[', ']', ',']).filter_map(|t| t.trim().parse().ok()).collect()
    };
    let (given, detected) = (means(&[]), means(&["--detected"]));
    assert_eq!(given.len(), 2);
    assert_ne!(given[0], detected[0]);
    assert_eq!(given[1], detected[1]);
    // An automatic-gender run recalibrates the shipped combination's intercept; a run with a
    // given gender has no pair of deciding fits and is refused.
    let auto = dir.join("auto");
    ok(&skb(&[&["run-dataset", s(&ds), "--out", s(&auto), "--gender", "auto"][..], &fast].concat()));
    let o = skb(&["train-gender", "--shipped", "--recalibrate", &format!("{}={}", s(&ds), s(&auto))]);
    ok(&o);
    let out = String::from_utf8_lossy(&o.stdout).into_owned();
    let line = out.lines().find(|l| l.starts_with("recalibrated on 8 sketches: intercept ")).expect(&out);
    let v: Vec<f64> = line.split([' ', '(', ')']).filter_map(|t| t.parse().ok()).collect();
    assert!(v.len() >= 3 && v[1] != v[2] && v[2].is_finite(), "shipped -> recalibrated intercept: {line}");
    assert_eq!(out.matches("accuracy ").count(), 2, "the set before and after: {out}");
    let o = skb(&["train-gender", "--shipped", "--recalibrate", &format!("{}={}", s(&ds), s(&dir.join("f")))]);
    assert!(!o.status.success() && String::from_utf8_lossy(&o.stderr).contains("no score of both gendered fits"));
    // The same fits calibrate the height: every result reports its fitted and its calibrated
    // rest height, within the calibration's bound of each other.
    for g in ["f", "m"] {
        let r: serde_json::Value =
            serde_json::from_slice(&std::fs::read(dir.join(g).join("000000.json")).unwrap()).unwrap();
        let (fit, h) = (r["fit_height_m"].as_f64().unwrap(), r["height_m"].as_f64().unwrap());
        assert!(fit > 1.0 && fit < 2.5 && (h / fit).ln().abs() <= 0.15 + 1e-9, "{fit} {h}");
    }
    let (rf, rm) = (format!("{}={}", s(&ds), s(&dir.join("f"))), format!("{}={}", s(&ds), s(&dir.join("m"))));
    // The same fits train the fit's calibration: the shape map on the samples fitted in their
    // true gender, then the height calibration on the mapped bodies.
    // Two evidence values: 16 samples do not determine the default's fifteen.
    let few = ["--height-evidence", "log_torso_factor,log_hip_width"];
    let o = skb(&[&["calibrate-fit", "--train", &rf, "--train", &rm, "--test", &rf, "--cv", "2"], &few[..]].concat());
    ok(&o);
    let out = String::from_utf8_lossy(&o.stdout).into_owned();
    assert!(out.contains("ShapeCalibration { first_dim: 3, intercept: [["), "{out}");
    let line = out.lines().find(|l| l.starts_with("HeightCalibration { intercept: ")).expect(&out);
    let weights: Vec<f64> = line
        .split("evidence_weights: [")
        .nth(1)
        .expect(line)
        .split([',', ']', ' '])
        .filter_map(|t| t.parse().ok())
        .collect();
    assert_eq!(weights.len(), 15, "{line}");
    let used: Vec<usize> = (0..15).filter(|&k| weights[k] != 0.0).collect();
    assert_eq!(used, vec![4, 6], "only the named evidence is read: {line}");
    assert_eq!(out.lines().filter(|l| l.starts_with("cv 2-fold, first dimension ")).count(), 11, "{out}");
    assert!(out.contains("training: 16 samples (8 fitted in their true gender"), "{out}");
    let numbers = |line: &str| -> Vec<f64> {
        line.split([' ', ',']).filter_map(|t| t.parse().ok()).filter(|x: &f64| x.fract() != 0.0).collect()
    };
    let line = out.lines().find(|l| l.starts_with("test ")).expect(&out);
    let v = numbers(line);
    assert!(v.len() == 4 && v.iter().all(|x| x.is_finite() && *x >= 0.0 && *x < 0.5), "{line}");
    // Without a shape map, least squares over a family holding the identity: the calibrated
    // heights are no worse than the fitted ones.
    let o =
        skb(&[&["calibrate-fit", "--train", &rf, "--train", &rm, "--first-dim", "10", "--cv", "2"], &few[..]].concat());
    ok(&o);
    let out = String::from_utf8_lossy(&o.stdout).into_owned();
    let cv: Vec<&str> = out.lines().filter(|l| l.starts_with("cv 2-fold")).collect();
    assert!(
        cv.len() == 1 && cv[0].starts_with("cv 2-fold, first dimension 10:"),
        "--first-dim: its own line only: {out}"
    );
    let v = numbers(out.lines().find(|l| l.starts_with("training: 16 samples, RMS")).expect(&out));
    assert!(v[1] <= v[0] + 1e-9, "{out}");
    let o = skb(&["calibrate-fit", "--train", &rf, "--train", &rm]);
    assert!(String::from_utf8_lossy(&o.stderr).contains("need more than 18"), "all fifteen values: {o:?}");
    let o = skb(&["calibrate-fit", "--train", &rf, "--height-evidence", "log_tail_factor"]);
    assert!(String::from_utf8_lossy(&o.stderr).contains("unknown height evidence"), "{o:?}");
    let o = skb(&["calibrate-fit", "--shipped", "--test", &rf]);
    ok(&o);
    assert!(String::from_utf8_lossy(&o.stdout).starts_with("test "), "{o:?}");
    let o = skb(&["calibrate-fit", "--train", &format!("{}={}", s(&ds), s(&dir.join("f")))]);
    assert!(!o.status.success(), "one gender does not train the male map: {o:?}");
    let mean = dir.join("mean");
    ok(&skb(&["run-dataset", s(&ds), "--out", s(&mean), "--mean-shape", "--first", "2"]));
    let o = skb(&["calibrate-fit", "--train", &format!("{}={}", s(&ds), s(&mean)), "--train", &rm]);
    assert!(String::from_utf8_lossy(&o.stderr).contains("mean-shape results"), "{o:?}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `fit-landmark-joints` fits the shifts from BlazePose's mapped landmarks to the model's joints
/// on rendered sketches: symmetric pairs, the head moved up the torso (the ears' midpoint sits
/// below the model's head joint), and a report line per set; `--shipped` needs a test set.
#[test]
fn fit_landmark_joints_fits_symmetric_shifts_and_reports_each_set() {
    let dir = scratch("landmarks");
    let ds = dir.join("ds");
    ok(&skb(&["make-dataset", "12", "--seed", "8", "--size", "384", "--out", s(&ds)]));
    let o = skb(&["fit-landmark-joints", "--train", s(&ds), "--test", s(&ds)]);
    ok(&o);
    let out = String::from_utf8_lossy(&o.stdout).into_owned();
    let line = out.lines().find(|l| l.starts_with("JointDefinitions { along_torso: [")).expect(&out);
    let numbers = |key: &str| -> Vec<f64> {
        let rest = line.split(key).nth(1).expect(line);
        rest[..rest.find(']').unwrap()].split(',').map(|t| t.trim().parse().unwrap()).collect()
    };
    let (along, outward) = (numbers("along_torso: ["), numbers("outward: ["));
    assert_eq!((along.len(), outward.len()), (15, 15), "{line}");
    for (r, l) in [(2, 5), (3, 6), (4, 7), (9, 12), (10, 13), (11, 14)] {
        assert_eq!((along[r], outward[r]), (along[l], outward[l]), "pair {r}/{l}: {line}");
    }
    assert_eq!((outward[0], outward[1], outward[8]), (0.0, 0.0, 0.0), "head, neck, pelvis have no side");
    assert!(along[0] > 0.03, "the head moves up the torso: {line}");
    assert!(out.lines().any(|l| l.starts_with("training: ") && l.contains("mapped ->")), "{out}");
    assert_eq!(out.lines().filter(|l| l.starts_with("test ")).count(), 1, "{out}");
    let o = skb(&["fit-landmark-joints", "--shipped"]);
    assert!(String::from_utf8_lossy(&o.stderr).contains("--shipped needs"), "{o:?}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `make-dataset --views side,back` draws each sample's body and pose again from the side and the
/// back (the front camera turned +90° and 180° about the body's vertical), with each view's truth
/// in the sample's JSON; `run-dataset --views side` fits the turnarounds.
#[test]
fn turnarounds_are_drawn_with_their_views_and_fitted() {
    let dir = scratch("views");
    let (ds, out) = (dir.join("ds"), dir.join("out"));
    ok(&skb(&["make-dataset", "2", "--seed", "5", "--size", "256", "--views", "side,back", "--out", s(&ds)]));
    for stem in ["000000", "000001"] {
        let truth: serde_json::Value =
            serde_json::from_slice(&std::fs::read(ds.join(format!("{stem}.json"))).unwrap()).unwrap();
        let r = |c: &serde_json::Value| -> Vec<Vec<f64>> {
            c["r"]
                .as_array()
                .unwrap()
                .iter()
                .map(|row| row.as_array().unwrap().iter().map(|x| x.as_f64().unwrap()).collect())
                .collect()
        };
        let front = r(&truth["camera"]);
        let views = truth["views"].as_array().unwrap();
        assert_eq!(views.len(), 2);
        for (v, (label, yaw)) in views.iter().zip([("side", 90.0f64), ("back", 180.0)]) {
            assert_eq!(v["label"], label);
            assert!(ds.join(v["image"].as_str().unwrap()).is_file(), "{stem}: {v}");
            // R_view = R_front · R_y(yaw).
            let (sn, cs) = yaw.to_radians().sin_cos();
            let turn = [[cs, 0.0, sn], [0.0, 1.0, 0.0], [-sn, 0.0, cs]];
            let view = r(&v["camera"]);
            for i in 0..3 {
                for j in 0..3 {
                    let want: f64 = (0..3).map(|k| front[i][k] * turn[k][j]).sum();
                    assert!((view[i][j] - want).abs() < 1e-9, "{stem} {label}: r[{i}][{j}] {} vs {want}", view[i][j]);
                }
            }
        }
    }
    let fast = ["--samples", "16", "--iterations", "2"];
    ok(&skb(&[&["run-dataset", s(&ds), "--out", s(&out), "--views", "side"][..], &fast].concat()));
    let res: serde_json::Value = serde_json::from_slice(&std::fs::read(out.join("000000.json")).unwrap()).unwrap();
    assert_eq!(res["views"].as_array().map(|v| v.len()), Some(1), "{res}");
    let o = skb(&["make-dataset", "1", "--views", "front", "--out", s(&dir.join("bad"))]);
    assert_eq!(o.status.code(), Some(2), "{o:?}");
}
