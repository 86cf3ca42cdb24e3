//! The detector engine with the authors' PARSE model on a few PARSE test images (reference data
//! from `../shared/data`; skipped with a SKIPPED line when it is absent, fails under CI).

#[path = "../../tests/common/mod.rs"]
mod common;

use sketchbody::detect::{detect, DetectOptions, Model, NUM_PARSE_JOINTS};
use sketchbody::image::load_rgb_image;
use sketchbody::skeleton::joint;
use sketchbody_lab::detect::parse_eval::{correct_joints, evaluate_image, read_labels};

/// Five test-split images (im0101..im0305); PCK@0.1 with the ground-truth box must be high.
const IMAGES: [&str; 5] = ["im0102.jpg", "im0103.jpg", "im0104.jpg", "im0105.jpg", "im0108.jpg"];

#[test]
fn parse_model_finds_the_joints_on_parse_images() {
    let Some(data) = common::shared_data("detect_parse") else { return };
    let model = Model::load_json(&data.join("fmp/parse_model.json")).unwrap();
    // The binary format carries the PARSE model without loss.
    assert_eq!(Model::from_bytes(&model.to_bytes()).unwrap(), model);
    let labels = read_labels(&data.join("parse/labels.csv")).unwrap();
    let mut correct = 0;
    for name in IMAGES {
        let l = labels.iter().find(|l| l.image == name).unwrap();
        let img = load_rgb_image(&data.join("parse/images").join(name)).unwrap();
        let (ok, score) = evaluate_image(&img.view(), &model, &l.joints, 0.1).unwrap();
        let n = ok.iter().filter(|&&b| b).count();
        println!("{name}: score {score:?}, {n}/14 joints within 0.1 of the box");
        correct += n;
    }
    let pck = correct as f64 / (IMAGES.len() * NUM_PARSE_JOINTS) as f64;
    println!("PCK@0.1 on {} images: {:.1}%", IMAGES.len(), 100.0 * pck);
    assert!(pck >= 0.70, "PCK@0.1 = {:.1}% < 70%", 100.0 * pck);
}

#[test]
fn detect_api_returns_the_figure_in_image_pixels() {
    let Some(data) = common::shared_data("detect_parse") else { return };
    let model = Model::load_json(&data.join("fmp/parse_model.json")).unwrap();
    let labels = read_labels(&data.join("parse/labels.csv")).unwrap();
    let l = labels.iter().find(|l| l.image == "im0103.jpg").unwrap();
    let img = load_rgb_image(&data.join("parse/images/im0103.jpg")).unwrap();
    let d = detect(&img.view(), &model, &DetectOptions::default()).unwrap();
    let best = d.best();
    // PARSE labels are pixel indices; detections are continuous coordinates (+0.5).
    let pred = best.parse_joints.map(|p| [p[0] - 0.5, p[1] - 0.5]);
    let ok = correct_joints(&pred, &l.joints, 0.2);
    let n = ok.iter().filter(|&&b| b).count();
    assert!(n >= 11, "only {n}/14 joints within 0.2 of the box; score {}", best.score);
    // Canonical joints: head above neck above pelvis above the ankles.
    let y = |j: usize| best.joints.xy[j][1];
    assert!(
        y(joint::HEAD) < y(joint::NECK) && y(joint::NECK) < y(joint::PELVIS) && y(joint::PELVIS) < y(joint::R_ANKLE)
    );
    assert!(best.confidence.iter().all(|&c| c > 0.0 && c < 1.0));
    assert!(d.all.windows(2).all(|w| w[0].score >= w[1].score));
    // A blank image of the same size holds no figure above the model's threshold.
    let blank = vec![255u8; img.width() * img.height()];
    let v = sketchbody::image::ImageView::gray(&blank, img.width(), img.height()).unwrap();
    match detect(&v, &model, &DetectOptions::default()) {
        Err(sketchbody::Error::NoFigure { score, threshold }) => assert!(score < threshold),
        other => panic!("blank image: expected NoFigure, got {:?}", other.map(|d| d.best().score)),
    }
}
