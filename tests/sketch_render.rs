//! The sketch renderer through the library: determinism, ground-truth consistency (2-D joints are
//! the camera projection of the 3-D joints), visibility from the depth buffer, bad input.

use std::sync::Arc;

use nalgebra::Vector3;
use sketchbody::body::{BodyModel, Gender};
use sketchbody::render::sketch::{CameraAngles, SketchRenderer, SketchRequest, SketchStyle};
use sketchbody::skeleton::joint;

fn renderer() -> SketchRenderer {
    SketchRenderer::new(Arc::new(BodyModel::embedded().unwrap()), None).unwrap()
}

#[test]
fn same_seed_same_sketch_and_truth_matches_projection() {
    let r = renderer();
    let req = SketchRequest::random(42, 160);
    let a = r.render(&req).unwrap();
    let b = r.render(&req).unwrap();
    assert_eq!(a.pixels, b.pixels);
    assert_eq!(a.truth, b.truth);
    let c = r.render(&SketchRequest::random(43, 160)).unwrap();
    assert_ne!(a.pixels, c.pixels);
    // Rendered on a pool of 1 thread: identical (skinning is parallel but per-vertex).
    let pool = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap();
    let d = pool.install(|| r.render(&req).unwrap());
    assert_eq!(a.pixels, d.pixels);
    let cam = a.truth.camera.to_camera().unwrap();
    for k in 0..15 {
        let p = cam.project(&Vector3::from(a.truth.joints3d[k]));
        let q = a.truth.joints2d[k];
        assert!((p[0] - q[0]).abs() < 1e-9 && (p[1] - q[1]).abs() < 1e-9, "joint {k}: {p:?} vs {q:?}");
        assert!(q[0] >= 0.0 && q[0] < 160.0 && q[1] >= 0.0 && q[1] < 160.0, "joint {k} inside the image");
    }
    assert_eq!(a.rest_vertices.len(), r.model().num_vertices());
    assert!(a.truth.height_m > 1.0 && a.truth.height_m < 2.5, "height {}", a.truth.height_m);
    let ink = a.pixels.iter().filter(|&&p| p < 128).count();
    assert!(ink > 200, "the figure is drawn: {ink} dark pixels");
}

#[test]
fn a_wrist_behind_the_back_is_hidden_and_bad_input_is_rejected() {
    let r = renderer();
    let rest = r.model().space(Gender::Male).synthesize(&[]).unwrap().joints;
    let mut j = rest;
    let v = |p: [f64; 3]| Vector3::from(p);
    let sh = v(rest[joint::R_SHOULDER]);
    let elbow = sh + Vector3::new(0.08, -0.12, -0.22);
    let wrist = elbow + Vector3::new(0.2, 0.0, -0.05);
    j[joint::R_ELBOW] = elbow.into();
    j[joint::R_WRIST] = wrist.into();
    let req = SketchRequest {
        gender: Some(Gender::Male),
        shape_weights: Some(vec![]),
        joints: Some(j),
        camera: Some(CameraAngles::default()),
        style: Some(SketchStyle::default()),
        ..SketchRequest::random(1, 256)
    };
    let s = r.render(&req).unwrap();
    assert!(!s.truth.visible[joint::R_WRIST], "wrist behind the back must be hidden");
    for k in [joint::HEAD, joint::L_WRIST, joint::L_ANKLE, joint::R_ANKLE, joint::L_SHOULDER] {
        assert!(s.truth.visible[k], "joint {k} should be visible");
    }
    assert_eq!(s.truth.pose_source, "given");

    let bad = |req: SketchRequest| r.render(&req).unwrap_err().to_string();
    assert!(bad(SketchRequest { width: 0, ..req.clone() }).contains("0x256"));
    assert!(bad(SketchRequest { width: 5000, ..req.clone() }).contains("4096"));
    let mut nan = j;
    nan[3][1] = f64::NAN;
    assert!(bad(SketchRequest { joints: Some(nan), ..req.clone() }).contains("finite"));
    let mut same = j;
    same[joint::R_ELBOW] = same[joint::R_SHOULDER];
    assert!(bad(SketchRequest { joints: Some(same), ..req.clone() }).contains("coincide"));
    assert!(bad(SketchRequest { shape_weights: Some(vec![0.0; 999]), ..req.clone() }).contains("weight"));
    let style = SketchStyle { margin: 0.9, ..Default::default() };
    assert!(bad(SketchRequest { style: Some(style), ..req.clone() }).contains("style.margin"));
    assert!(bad(SketchRequest { camera: Some(CameraAngles { yaw_deg: 200.0, ..Default::default() }), ..req })
        .contains("yaw"));
}

#[test]
fn art_styles_render_valid_distinct_images_deterministically() {
    use sketchbody::render::sketch::art::{ArtStyle, Build, Fill};
    let r = renderer();
    let req = SketchRequest::random(7, 160);
    let plain = r.render(&req).unwrap();
    let styles: Vec<ArtStyle> = Fill::ALL
        .iter()
        .enumerate()
        .map(|(i, &fill)| ArtStyle {
            fill,
            thick_ink: fill == Fill::Lines,
            masses: i % 2 == 0,
            build: Build::Natural,
            textured_paper: i == 3,
        })
        .chain([
            ArtStyle { fill: Fill::Flat, thick_ink: true, masses: false, build: Build::Chibi, textured_paper: false },
            ArtStyle { fill: Fill::Cel, thick_ink: false, masses: false, build: Build::Heroic, textured_paper: true },
        ])
        .collect();
    let mut seen: Vec<Vec<u8>> = vec![plain.pixels.clone()];
    for s in &styles {
        let a = r.render_art(&req, s).unwrap();
        let b = r.render_art(&req, s).unwrap();
        assert_eq!(a.pixels, b.pixels, "{s:?}: same seed, same image");
        assert_eq!(a.pixels.len(), 160 * 160);
        let dark = a.pixels.iter().filter(|&&p| p < 200).count();
        assert!(dark > 150 && dark < 160 * 160 * 3 / 4, "{s:?}: {dark} dark pixels");
        assert!(seen.iter().all(|o| *o != a.pixels), "{s:?} looks like an earlier style");
        let c = r.render_art(&SketchRequest::random(8, 160), s).unwrap();
        assert_ne!(a.pixels, c.pixels, "{s:?}: another seed, another image");
        if s.build == Build::Natural {
            // Same figure: the art changes the paint, not the pose or the proportions.
            assert_eq!(a.truth.joints2d, plain.truth.joints2d, "{s:?}");
        } else {
            assert_ne!(a.truth.style.proportions, plain.truth.style.proportions, "{s:?}");
        }
        seen.push(a.pixels);
    }
    // The fills darken the figure's inside; lines alone leave it paper.
    let fill = r.render_art(&req, &styles[1]).unwrap();
    let mean = |p: &[u8]| p.iter().map(|&v| v as f64).sum::<f64>() / p.len() as f64;
    assert!(mean(&fill.pixels) < mean(&plain.pixels) - 2.0, "{} vs {}", mean(&fill.pixels), mean(&plain.pixels));
    // The plain renderer is untouched by the art module.
    assert_eq!(r.render(&req).unwrap().pixels, plain.pixels);
}
