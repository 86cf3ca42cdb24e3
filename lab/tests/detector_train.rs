//! Detector training (`detect::train`): a short run on a few sketches gives a model that scores
//! its training positives above every configuration on its negative pages, mined negatives score
//! exactly w·φ, and training is deterministic.

use std::sync::Arc;

use sketchbody::body::BodyModel;
use sketchbody::render::sketch::SketchRenderer;
use sketchbody_lab::detect::train::examples::{gray_planes, render_negatives};
use sketchbody_lab::detect::train::mine::{mine_image, SearchRange};
use sketchbody_lab::detect::train::{train, TrainOptions, Trained};

fn options() -> TrainOptions {
    TrainOptions {
        seed: 5,
        positives: 10,
        negatives: 3,
        mixtures: 2,
        rounds: 2,
        image_size: 256,
        c: 0.05,
        search: SearchRange { min_cell_px: 3.0, max_cell_px: 8.0 },
        ..TrainOptions::default()
    }
}

fn trained() -> (Trained, TrainOptions) {
    let r = SketchRenderer::new(Arc::new(BodyModel::embedded().unwrap()), None).unwrap();
    let o = options();
    let mut lines = Vec::new();
    let t = train(&r, &o, &mut |l| lines.push(l.to_string())).unwrap();
    assert!(lines.iter().any(|l| l.contains("round 2")), "{lines:?}");
    (t, o)
}

#[test]
fn short_training_separates_positives_from_negatives_and_scores_are_w_dot_phi() {
    let (t, o) = trained();
    assert!(t.counts.0 >= 12, "{:?}", t.counts);
    let st = &t.structure;
    let w: Vec<f64> = {
        // The model's parameters back in w's layout: filters, deformations, biases.
        let mut w = Vec::with_capacity(st.dim());
        for f in &t.model.filters {
            w.extend(f.w.iter().map(|&v| v as f64));
        }
        for d in &t.model.defs {
            w.extend_from_slice(&d.w);
        }
        w.extend_from_slice(&t.model.bias);
        w
    };
    assert_eq!(w.len(), st.dim());
    let pages = render_negatives(o.seed, o.negatives, o.image_size).unwrap();
    let mut best_negative = f64::NEG_INFINITY;
    for (i, px) in pages.iter().enumerate() {
        let im = gray_planes(px, o.image_size, o.image_size);
        let mined = mine_image(&im, i, &t.model, st, o.search, f64::NEG_INFINITY, 3, 20).unwrap();
        assert!(!mined.is_empty());
        for m in &mined {
            let wx = m.x.dot(&w);
            assert!((wx - m.score).abs() <= 1e-3 * (1.0 + m.score.abs()), "w·φ {wx} vs engine score {}", m.score);
        }
        best_negative = best_negative.max(mined[0].score);
    }
    let mut ps = t.positive_scores.clone();
    ps.sort_by(f64::total_cmp);
    let p10 = ps[ps.len() / 10];
    assert!(p10 > best_negative, "10th-percentile positive {p10} vs best negative {best_negative}; positives {ps:?}");
}

#[test]
fn training_is_deterministic_and_rejects_bad_options() {
    let r = SketchRenderer::new(Arc::new(BodyModel::embedded().unwrap()), None).unwrap();
    let o = TrainOptions { positives: 3, negatives: 1, rounds: 1, ..options() };
    let a = train(&r, &o, &mut |_| {}).unwrap();
    let one = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap();
    let b = one.install(|| train(&r, &o, &mut |_| {}).unwrap());
    assert_eq!(a.model, b.model);
    assert_eq!(a.model.to_bytes(), b.model.to_bytes());
    let bad = TrainOptions { mixtures: 0, ..o.clone() };
    assert!(matches!(train(&r, &bad, &mut |_| {}), Err(sketchbody::Error::OutOfRange { name: "mixtures", .. })));
    let bad = TrainOptions { c: f64::NAN, ..o };
    assert!(matches!(train(&r, &bad, &mut |_| {}), Err(sketchbody::Error::OutOfRange { name: "c", .. })));
}
