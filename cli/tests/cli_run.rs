//! `sketchbody run` end to end on the example sketch: every output file, the gender decision,
//! and one-line errors that leave no file behind (no joints, joints outside the image, blank and
//! tiny sketches, an unwritable output folder, Ctrl-C).

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use sketchbody::export::joints2d::load_joints2d;
use sketchbody::image::{save_png, GrayImage};

const SKETCH: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../assets/examples/sketch.png");
const JOINTS: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../assets/examples/sketch_joints.json");
/// Small fit settings: the tests check plumbing, not accuracy.
const FAST: [&str; 6] = ["--samples", "24", "--iterations", "2", "--quiet", "--preview-size=128"];

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("skb-cli-run-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn run(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_sketchbody")).arg("run").args(args).output().unwrap()
}

fn one_line_error(out: &Output, expect: &str) {
    assert_eq!(out.status.code(), Some(1), "{out:?}");
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    assert!(err.contains(expect), "expected {expect:?} in {err}");
}

fn names(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> =
        std::fs::read_dir(dir).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
    v.sort();
    v
}

#[test]
fn run_writes_every_output() {
    let dir = scratch("ok");
    let out_dir = dir.join("out");
    let o = out_dir.to_str().unwrap();
    let out = run(&[SKETCH, "--joints", JOINTS, "--out", o, "--gender", "f", "--depth-prior", "0.2"]
        .iter()
        .chain(&FAST)
        .copied()
        .collect::<Vec<_>>());
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    assert_eq!(
        names(&out_dir),
        [
            "body.glb",
            "body.mtl",
            "body.obj",
            "body_rest.obj",
            "body_texture.png",
            "joints2d.json",
            "overlay.png",
            "pose3d.json",
            "preview.png",
            "report.md"
        ]
    );
    let glb = std::fs::read(out_dir.join("body.glb")).unwrap();
    assert_eq!(&glb[..4], b"glTF");
    let json = String::from_utf8_lossy(&glb[20..20 + u32::from_le_bytes(glb[12..16].try_into().unwrap()) as usize]);
    assert!(json.contains("\"image/png\"") && json.contains("\"r_elbow\""), "textured, project names");
    assert_eq!(load_joints2d(&out_dir.join("joints2d.json")).unwrap(), load_joints2d(Path::new(JOINTS)).unwrap());
    let pose: serde_json::Value = serde_json::from_slice(&std::fs::read(out_dir.join("pose3d.json")).unwrap()).unwrap();
    assert_eq!(pose["format"], "sketchbody-pose3d");
    assert!(pose["camera"]["sx"].as_f64().unwrap() > 100.0);
    let alts = sketchbody::export::pose3d::parse_pose3d(
        &String::from_utf8(std::fs::read(out_dir.join("pose3d.json")).unwrap()).unwrap(),
    )
    .unwrap()
    .alternatives;
    assert!(!alts.is_empty() && alts.len() <= 8 && alts[0].flipped.is_empty(), "{}", alts.len());
    let obj = std::fs::read_to_string(out_dir.join("body.obj")).unwrap();
    assert_eq!(obj.lines().filter(|l| l.starts_with("v ")).count(), 13380);
    assert!(obj.contains("\nmtllib body.mtl\n"));
    assert!(std::fs::read_to_string(out_dir.join("body.mtl")).unwrap().contains("map_Kd body_texture.png"));
    let overlay = image::open(out_dir.join("overlay.png")).unwrap();
    // The sketch's size plus the side-view panel (half its height) on the right.
    assert_eq!((overlay.width(), overlay.height()), (512 + 256, 512));
    let preview = image::open(out_dir.join("preview.png")).unwrap();
    // Sketch, camera view, blend (the 512×512 sketch's aspect, 128 px high), then front and side.
    assert_eq!((preview.width(), preview.height()), (3 * 128 + 256, 128));
    let report = std::fs::read_to_string(out_dir.join("report.md")).unwrap();
    assert!(report.contains("gender: female (given)"), "{report}");
    assert!(report.contains("samples 24 (first iteration 8×)"), "{report}");
    assert!(report.contains("learned depths 0.2\n"), "the pose step ran with --depth-prior: {report}");
    let height = report.lines().find(|l| l.starts_with("- rest height: ")).expect(&report);
    assert!(height.contains(" m, calibrated)"), "given joints, no --height: {height}");
    assert!(report.contains("- shape weights (m) (the fit's, calibrated): ["), "{report}");
    assert!(report.contains("bone factors sd 0.1 centred on their 2-D estimate"), "{report}");
    assert!(
        report.contains("- bone factors estimated from the 2-D joints: legs ")
            && report.contains("- bone factors fitted (applied to the mesh): legs "),
        "{report}"
    );
    // A second run into the existing folder replaces the files and leaves no staging folder.
    let out = run(&[SKETCH, "--joints", JOINTS, "--out", o, "--gender", "f"]
        .iter()
        .chain(&FAST)
        .copied()
        .collect::<Vec<_>>());
    assert!(out.status.success());
    assert_eq!(names(&out_dir).len(), 10);
    // Options: no texture, Unreal names, T-pose, pelvis origin; a bad value is a clear error.
    let plain = dir.join("plain");
    let flags = ["--no-texture", "--naming", "unreal", "--rest-pose", "t", "--origin", "pelvis"];
    let args: Vec<&str> = [SKETCH, "--joints", JOINTS, "--out", plain.to_str().unwrap(), "--gender", "f"]
        .iter()
        .chain(&FAST)
        .chain(&flags)
        .copied()
        .collect();
    let out = run(&args);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    assert_eq!(names(&plain).len(), 8);
    let glb = std::fs::read(plain.join("body.glb")).unwrap();
    assert!(String::from_utf8_lossy(&glb).contains("\"lowerarm_r\""));
    let bad = dir.join("bad");
    let args: Vec<&str> = [SKETCH, "--joints", JOINTS, "--out", bad.to_str().unwrap(), "--naming", "rigify"]
        .iter()
        .chain(&FAST)
        .copied()
        .collect();
    let out = run(&args);
    assert!(!out.status.success() && String::from_utf8_lossy(&out.stderr).contains("bone naming"));
    assert!(!bad.exists(), "nothing written on a bad option");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `run` on the example with its joints and no `--gender` (plus `extra`): the report and stdout.
fn run_without_gender(name: &str, extra: &[&str]) -> (String, String) {
    let dir = scratch(name);
    let o = dir.join("out");
    let mut args = vec![SKETCH, "--joints", JOINTS, "--out", o.to_str().unwrap()];
    args.extend_from_slice(extra);
    args.extend_from_slice(&FAST);
    let out = run(&args);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let report = std::fs::read_to_string(o.join("report.md")).unwrap();
    std::fs::remove_dir_all(&dir).unwrap();
    (report, String::from_utf8_lossy(&out.stdout).into_owned())
}

#[test]
fn without_gender_the_classifier_picks_a_gendered_fit_and_reports_its_confidence() {
    let (report, stdout) = run_without_gender("auto", &[]);
    // The two deciding fits in 4 dimensions, then the chosen gender's in all 10.
    assert!(
        report.contains("- female fit (4 PCA dimensions): best score -")
            && report.contains("- male fit (4 PCA dimensions): best score -")
            && report.contains("male fit (10 PCA dimensions): best score -"),
        "{report}"
    );
    assert!(
        report.contains("chosen by the gender classifier with probability 0.")
            || report.contains("chosen by the gender classifier with probability 1.00"),
        "{report}"
    );
    assert!(report.contains("the gender classifier gives P(male) "), "{report}");
    assert!(report.contains("- evidence: "), "{report}");
    assert!(
        stdout.contains("by the gender classifier, p=")
            && stdout.contains(" m tall, score female (4-D) -")
            && stdout.contains(", male (4-D) -")
            && stdout.contains("male (10-D) -"),
        "{stdout}"
    );
}

#[test]
fn without_the_classifier_the_gender_is_fitted_and_reported_with_its_confidence() {
    let (report, stdout) = run_without_gender("blended", &["--classify-gender", "false"]);
    assert!(report.contains("- blended fit (5 PCA dimensions): best score -"), "{report}");
    assert!(report.contains("- gender: fitted as a continuous shape weight"), "{report}");
    assert!(report.contains("with posterior probability 0.") || report.contains("with posterior probability 1.00"));
    assert!(!report.contains("chosen by the gender classifier"), "{report}");
    assert!(stdout.contains("fitted") && stdout.contains(" p=") && stdout.contains("blended -"), "{stdout}");
}

#[test]
fn bad_input_fails_in_one_line_and_leaves_nothing() {
    let dir = scratch("bad");
    let out_dir = dir.join("out");
    let o = out_dir.to_str().unwrap();
    // No joints on a page without a figure: the detector says so, no folder.
    let stroke = dir.join("stroke.png");
    let mut page = GrayImage::filled(200, 200, 255).unwrap();
    for y in 20..180 {
        page.as_bytes_mut()[y * 200 + 100] = 0;
    }
    save_png(&page.view(), &stroke).unwrap();
    one_line_error(&run(&[stroke.to_str().unwrap(), "--out", o, "--quiet"]), "no figure");
    assert!(!out_dir.exists());
    // A joint outside the image.
    let mut doc: serde_json::Value = serde_json::from_slice(&std::fs::read(JOINTS).unwrap()).unwrap();
    doc["joints"]["l_wrist"] = serde_json::json!([600.0, 250.0]);
    let outside = dir.join("outside.json");
    std::fs::write(&outside, doc.to_string()).unwrap();
    one_line_error(
        &run(&[SKETCH, "--joints", outside.to_str().unwrap(), "--out", o, "--quiet"]),
        "joint l_wrist at (600, 250) px lies outside the 512x512 image",
    );
    // Blank and tiny sketches.
    let blank = dir.join("blank.png");
    save_png(&GrayImage::filled(256, 256, 240).unwrap().view(), &blank).unwrap();
    one_line_error(&run(&[blank.to_str().unwrap(), "--joints", JOINTS, "--out", o, "--quiet"]), "has no edges");
    let tiny = dir.join("tiny.png");
    save_png(&GrayImage::filled(16, 16, 0).unwrap().view(), &tiny).unwrap();
    one_line_error(&run(&[tiny.to_str().unwrap(), "--joints", JOINTS, "--out", o, "--quiet"]), "16x16 is too small");
    assert!(!out_dir.exists());
    // An output path below a file cannot be created.
    let file = dir.join("file.txt");
    std::fs::write(&file, "x").unwrap();
    let under = file.join("out");
    one_line_error(
        &run(&[SKETCH, "--joints", JOINTS, "--out", under.to_str().unwrap(), "--quiet"]),
        "cannot write the output folder",
    );
    // A failure into an existing folder leaves its other files alone and adds nothing.
    std::fs::create_dir_all(&out_dir).unwrap();
    std::fs::write(out_dir.join("keep.txt"), "k").unwrap();
    one_line_error(&run(&[blank.to_str().unwrap(), "--joints", JOINTS, "--out", o, "--quiet"]), "has no edges");
    assert_eq!(names(&out_dir), ["keep.txt"]);
    assert_eq!(names(&dir), ["blank.png", "file.txt", "out", "outside.json", "stroke.png", "tiny.png"]);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn ctrl_c_cancels_promptly_and_leaves_nothing() {
    let dir = scratch("cancel");
    let out_dir = dir.join("out");
    let child = Command::new(env!("CARGO_BIN_EXE_sketchbody"))
        .args([
            "run",
            SKETCH,
            "--joints",
            JOINTS,
            "--out",
            out_dir.to_str().unwrap(),
            "--samples",
            "400",
            "--iterations",
            "50",
            "--quiet",
        ])
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    std::thread::sleep(std::time::Duration::from_millis(700));
    // SAFETY: plain kill(2) on our own child.
    unsafe { libc::kill(child.id() as i32, libc::SIGINT) };
    let out = child.wait_with_output().unwrap();
    one_line_error(&out, "cancelled by the progress callback");
    assert!(!out_dir.exists());
    assert_eq!(names(&dir).len(), 0, "{:?}", names(&dir));
    std::fs::remove_dir_all(&dir).unwrap();
}

/// The example sketch centred on a white `w`×`h` page, with its joints moved along.
fn padded_example(dir: &Path, w: usize, h: usize) -> (PathBuf, PathBuf) {
    let small = sketchbody::image::load_image(Path::new(SKETCH)).unwrap();
    let (sw, sh) = (small.width(), small.height());
    let (ox, oy) = ((w - sw) / 2, (h - sh) / 2);
    let mut page = vec![255u8; w * h];
    for y in 0..sh {
        page[(oy + y) * w + ox..][..sw].copy_from_slice(&small.as_bytes()[y * sw..][..sw]);
    }
    let sketch = dir.join(format!("sketch-{w}x{h}.png"));
    save_png(&GrayImage::from_vec(w, h, page).unwrap().view(), &sketch).unwrap();
    let mut joints = load_joints2d(Path::new(JOINTS)).unwrap();
    for p in &mut joints.xy {
        p[0] += ox as f64;
        p[1] += oy as f64;
    }
    let jpath = dir.join(format!("joints-{w}x{h}.json"));
    sketchbody::export::joints2d::write_joints2d(&jpath, &joints).unwrap();
    (sketch, jpath)
}

/// Issue 52 finding 1: sketches wider than 2:1 or over 4096 px a side, and the largest
/// `--preview-size`, run to the end (they failed after the whole fit: "raster size is out of
/// range: 4144x512 exceeds 4096 px a side", "4097x4097", "4100x820"); the preview is scaled
/// down to fit, the overlay is the sketch (shrunk by a whole factor to at most 2048 px a side)
/// plus its side panel (half the height).
#[test]
fn every_promised_size_runs_to_the_end() {
    let dir = scratch("sizes");
    for (w, h, preview) in [(4144, 512, "16384"), (4097, 4097, "512"), (512, 512, "820")] {
        let (sketch, joints) =
            if w == 512 { (PathBuf::from(SKETCH), PathBuf::from(JOINTS)) } else { padded_example(&dir, w, h) };
        let out = dir.join(format!("out-{w}x{h}"));
        let o = run(&[
            sketch.to_str().unwrap(),
            "--joints",
            joints.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "--samples",
            "16",
            "--iterations",
            "1",
            "--raster-side",
            "64",
            "--texture-size",
            "64",
            "--quiet",
            "--preview-size",
            preview,
        ]);
        assert!(o.status.success(), "{w}x{h}, preview {preview}: {}", String::from_utf8_lossy(&o.stderr));
        let overlay = image::open(out.join("overlay.png")).unwrap();
        // Shrunk by a whole factor to at most 2048 px a side, plus the side panel.
        let n = w.max(h).div_ceil(2048);
        let (sw, sh) = (w.div_ceil(n), h.div_ceil(n));
        assert_eq!((overlay.width() as usize, overlay.height() as usize), (sw + sh.div_ceil(2), sh));
        let p = image::open(out.join("preview.png")).unwrap();
        assert!(p.width() <= 16384 && p.height() <= 4096, "{w}x{h}: preview {}x{}", p.width(), p.height());
        let want_h = if w == 512 {
            820
        } else if w == 4144 {
            506
        } else {
            512
        };
        assert_eq!(p.height(), want_h, "{w}x{h}: as tall as fits");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Writes a turnaround of one body and pose (the synthetic renderer, front yaw 0°, side yaw 90°)
/// with each view's true joints into `dir`: (front.png, front.json, side.png, side.json).
fn turnaround(dir: &Path) -> [PathBuf; 4] {
    use sketchbody::body::{BodyModel, Gender};
    use sketchbody::export::joints2d::write_joints2d;
    use sketchbody::render::sketch::{CameraAngles, SketchRenderer, SketchRequest};
    use sketchbody::skeleton::{Joints2, NUM_JOINTS};
    let renderer = SketchRenderer::new(std::sync::Arc::new(BodyModel::embedded().unwrap()), None).unwrap();
    let files = ["front.png", "front.json", "side.png", "side.json"].map(|f| dir.join(f));
    for (k, yaw_deg) in [0.0, 90.0].into_iter().enumerate() {
        let req = SketchRequest {
            gender: Some(Gender::Female),
            camera: Some(CameraAngles { yaw_deg, pitch_deg: 0.0, roll_deg: 0.0 }),
            ..SketchRequest::random(11, 256)
        };
        let s = renderer.render(&req).unwrap();
        let img = GrayImage::from_vec(s.truth.width, s.truth.height, s.pixels.clone()).unwrap();
        save_png(&img.view(), &files[2 * k]).unwrap();
        let j = Joints2 { xy: std::array::from_fn(|i| s.truth.joints2d[i]), visible: [true; NUM_JOINTS] };
        write_joints2d(&files[2 * k + 1], &j).unwrap();
    }
    files
}

#[test]
fn a_turnaround_writes_each_views_overlay_preview_and_joints() {
    let dir = scratch("views");
    let [front, front_j, side, side_j] = turnaround(&dir);
    let out_dir = dir.join("out");
    let side_arg = format!("side={}", side.display());
    let side_joints_arg = format!("side={}", side_j.display());
    let args = [
        front.to_str().unwrap(),
        "--joints",
        front_j.to_str().unwrap(),
        "--view",
        &side_arg,
        "--view-joints",
        &side_joints_arg,
        "--out",
        out_dir.to_str().unwrap(),
        "--gender",
        "f",
    ];
    let out = run(&args.iter().chain(&FAST).copied().collect::<Vec<_>>());
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let files = names(&out_dir);
    for f in ["overlay_side.png", "preview_side.png", "joints2d_side.json", "preview.png"] {
        assert!(files.contains(&f.to_string()), "{f} missing from {files:?}");
    }
    // The side view's panel row has that view's sketch at the preview's height, like the front's.
    let front_preview = image::open(out_dir.join("preview.png")).unwrap();
    let side_preview = image::open(out_dir.join("preview_side.png")).unwrap();
    assert_eq!(side_preview.height(), front_preview.height());
    assert_eq!(side_preview.height(), 128);
    // Its second panel (the sketches are square: panels 128 px wide) is the body seen through the
    // side view's camera: drawn (not one colour), and not the front view's picture of it.
    let body_panel = |p: &image::DynamicImage| -> Vec<[u8; 3]> {
        let rgb = p.to_rgb8();
        (0..128).flat_map(|y| (128..256).map(move |x| (x, y))).map(|(x, y)| rgb.get_pixel(x, y).0).collect()
    };
    let (side_body, front_body) = (body_panel(&side_preview), body_panel(&front_preview));
    assert!(side_body.iter().any(|p| *p != side_body[0]), "the side view's body panel is empty");
    assert_ne!(side_body, front_body, "the side view's body panel is the front's");
    let report = std::fs::read_to_string(out_dir.join("report.md")).unwrap();
    assert!(report.contains("preview_side.png"), "{report}");
}
