//! `render-sketch`, `make-dataset` and `eval` end to end: files beside the image, specific
//! errors, thread-count independence, resuming, no half-written samples, and a perfect result
//! set scoring zero error.

use std::path::{Path, PathBuf};
use std::process::Command;

fn cli(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_sketchbody-lab")).args(args).output().unwrap()
}

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("skb-cli-sketch-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn fails(args: &[&str]) -> String {
    let out = cli(args);
    assert_eq!(out.status.code(), Some(1), "{args:?} should fail: {}", String::from_utf8_lossy(&out.stderr));
    String::from_utf8_lossy(&out.stderr).into_owned()
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

#[test]
fn render_sketch_writes_image_truth_and_meshes_and_rejects_bad_input() {
    let d = scratch("one");
    let out = d.join("a.png");
    let r = cli(&["render-sketch", "--out", s(&out), "--seed", "3", "--gender", "f", "--size", "96x128", "--obj"]);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    for f in ["a.png", "a.json", "a.mesh", "a_rest.obj", "a_posed.obj"] {
        assert!(d.join(f).is_file(), "{f} missing");
    }
    let img = image::open(&out).unwrap();
    assert_eq!((img.width(), img.height()), (96, 128));
    let truth: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(d.join("a.json")).unwrap()).unwrap();
    assert_eq!(truth["gender"], "female");
    assert_eq!(truth["joints2d"].as_array().unwrap().len(), 15);

    assert!(fails(&["render-sketch", "--out", s(&out), "--gender", "x"]).contains("gender"));
    assert!(fails(&["render-sketch", "--out", s(&out), "--size", "0"]).contains("--size"));
    assert!(fails(&["render-sketch", "--out", s(&out), "--size", "5000"]).contains("--size"));
    assert!(fails(&["render-sketch", "--out", s(&d.join("a.jpg"))]).contains(".png"));
    assert!(fails(&["render-sketch", "--out", s(&d.join("no/such/dir/a.png"))]).contains("does not exist"));
    std::fs::remove_dir_all(&d).unwrap();
}

fn files(dir: &Path) -> Vec<(String, Vec<u8>)> {
    let mut v: Vec<(String, Vec<u8>)> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.file_name().unwrap() != "dataset.json")
        .map(|p| (p.file_name().unwrap().to_string_lossy().into_owned(), std::fs::read(&p).unwrap()))
        .collect();
    v.sort();
    v
}

#[test]
fn make_dataset_is_thread_independent_resumable_and_scores_itself_perfectly() {
    let (a, b) = (scratch("ds1"), scratch("ds2"));
    let run = |dir: &Path, threads: &str| {
        cli(&["make-dataset", "4", "--seed", "9", "--out", s(dir), "--size", "96", "--threads", threads])
    };
    assert!(run(&a, "1").status.success());
    assert!(run(&b, "2").status.success());
    let fa = files(&a);
    assert_eq!(fa.len(), 12, "4 samples x (png, json, mesh)");
    assert_eq!(fa, files(&b), "1 and 2 threads give identical files");
    assert!(!fa.iter().any(|(n, _)| n.contains(".tmp")), "no temporary files left");

    // Resume: remove one file of sample 2; only that sample is redone, identically.
    std::fs::remove_file(a.join("000002.png")).unwrap();
    let r = run(&a, "2");
    let text = String::from_utf8_lossy(&r.stdout);
    assert!(text.contains("1 samples written, 3 already complete"), "{text}");
    assert_eq!(files(&a), fa);

    // A perfect result set: the ground truth itself.
    let res = scratch("res");
    for i in 0..4 {
        let stem = format!("{i:06}");
        let t: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(a.join(format!("{stem}.json"))).unwrap()).unwrap();
        let est =
            serde_json::json!({"joints2d": t["joints2d"], "joints3d": t["joints3d"], "camera_r": t["camera"]["r"]});
        std::fs::write(res.join(format!("{stem}.json")), est.to_string()).unwrap();
        let (rest, posed) =
            sketchbody::render::sketch::truth::parse_mesh(&std::fs::read(a.join(format!("{stem}.mesh"))).unwrap(), "t")
                .unwrap();
        let faces = sketchbody::body::BodyModel::embedded().unwrap().faces().to_vec();
        sketchbody::export::obj::write_obj(&res.join(format!("{stem}_rest.obj")), &rest, &faces, None).unwrap();
        if i < 2 {
            sketchbody::export::obj::write_obj(&res.join(format!("{stem}_posed.obj")), &posed, &faces, None).unwrap();
        }
    }
    let r = cli(&["eval", s(&a), s(&res)]);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let text = String::from_utf8_lossy(&r.stdout);
    assert!(text.contains("| aed_rest | 0.0000 | 4 |") && text.contains("| aed_rest_centred | 0.0000 | 4 |"), "{text}");
    assert!(
        text.contains("| aed_rest_at_height | 0.0000 | 4 |") && text.contains("| height_ratio | 1.000 | 4 |"),
        "{text}"
    );
    assert!(text.contains("| aed_posed | 0.0000 | 2 |"), "{text}");
    assert!(text.contains("| mpjpe_mm | 0.0 | 4 |") && text.contains("| pck@0.1 | 1.000 | 4 |"), "{text}");
    let csv = std::fs::read_to_string(res.join("eval.csv")).unwrap();
    assert_eq!(csv.lines().count(), 5);
    // Compare against a folder holding only 2-D joints shifted by 30 px.
    let other = scratch("other");
    for i in 0..4 {
        let stem = format!("{i:06}");
        let t: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(a.join(format!("{stem}.json"))).unwrap()).unwrap();
        let j: Vec<[f64; 2]> = serde_json::from_value(t["joints2d"].clone()).unwrap();
        let shifted: Vec<[f64; 2]> = j.iter().map(|p| [p[0] + 30.0, p[1]]).collect();
        std::fs::write(other.join(format!("{stem}.json")), serde_json::json!({"joints2d": shifted}).to_string())
            .unwrap();
    }
    let r = cli(&["eval", s(&a), s(&res), "--compare", s(&other)]);
    let text = String::from_utf8_lossy(&r.stdout);
    assert!(r.status.success() && text.contains("| aed_rest | 0.0000 | 4 | - | 0 |"), "{text}");

    // Errors: unwritable output folder, missing results folder.
    let file = a.join("000000.png");
    assert!(fails(&["make-dataset", "2", "--out", s(&file.join("sub"))]).contains("cannot create the output folder"));
    assert!(fails(&["eval", s(&a), s(&a.join("nope"))]).contains("not found"));
    for d in [a, b, res, other] {
        std::fs::remove_dir_all(d).unwrap();
    }
}
