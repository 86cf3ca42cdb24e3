//! The single-figure front end (`detect::figure`) and its evaluation (`eval::backends`) on
//! rendered sketches and blank pages: per-limb fusion takes each limb whole from one backend
//! and never lowers the figure's confidence below the per-image choice; a blank page is "no
//! figure" by the calibrated presence and by the hard thresholds; the set scores agree with the
//! metrics computed directly; a calibration cannot be fitted from one-sided outcomes; refusing
//! a fraction of negative pages lowers only the presence intercepts, enough and no more; joints
//! both backends agree on are averaged; with both backends the presence is the surer of the
//! two-backend model and BlazePose's own.

use std::sync::Arc;

use sketchbody::body::BodyModel;
use sketchbody::detect::calibration::{log_odds, presence_features, Calibration};
use sketchbody::detect::figure::{
    gather, presence_log_odds, Backend, EvidenceFeatures, FigureOptions, Fusion, LIMB_GROUPS,
};
use sketchbody::detect::landmark::LandmarkNet;
use sketchbody::detect::Model;
use sketchbody::error::Error;
use sketchbody::image::ImageView;
use sketchbody::pipeline::figure::decide;
use sketchbody::render::sketch::{SketchRenderer, SketchRequest};
use sketchbody_lab::eval::backends::{fit_calibration, gather_sample, refuse_negatives, reliability, score_set};
use sketchbody_lab::eval::metrics::pck;

/// The embedded backends, calibration and a sketch renderer.
fn backends() -> (Model, LandmarkNet, &'static Calibration, SketchRenderer) {
    let renderer = SketchRenderer::new(Arc::new(BodyModel::embedded().unwrap()), None).unwrap();
    (Model::embedded().unwrap(), LandmarkNet::embedded().unwrap(), Calibration::embedded().unwrap(), renderer)
}

#[test]
fn fusion_presence_and_set_scores() {
    let (model, net, cal, renderer) = backends();
    let options = FigureOptions::default();
    let mut samples = Vec::new();
    for seed in [31, 32, 33] {
        let s = renderer.render(&SketchRequest::random(seed, 384)).unwrap();
        let view = ImageView::gray(&s.pixels, 384, 384).unwrap();
        let truth: [[f64; 2]; 15] = s.truth.joints2d.as_slice().try_into().unwrap();
        let e = gather(&view, &model, &net, Backend::Auto, &options).unwrap();
        let (fmp, bp) = (e.sketch.as_ref().unwrap()[0].joints, e.blazepose.as_ref().unwrap().joints);
        let image = decide(&e, cal, &options, None).unwrap();
        let limb = decide(&e, cal, &FigureOptions { fusion: Fusion::PerLimb, ..options.clone() }, None).unwrap();
        assert!(limb.confidence >= image.confidence - 1e-12, "{} < {}", limb.confidence, image.confidence);
        for g in LIMB_GROUPS {
            let from_fmp = g.iter().all(|&j| limb.joints.xy[j] == fmp.xy[j]);
            let from_bp = g.iter().all(|&j| limb.joints.xy[j] == bp.xy[j]);
            assert!(from_fmp || from_bp, "limb {g:?} mixes the backends");
        }
        assert!((image.confidence - image.joint_confidence.iter().sum::<f64>() / 15.0).abs() < 1e-12);
        assert_eq!(image.low_confidence, image.confidence < 0.75);
        assert!(pck(&truth, &image.joints.xy, 0.2).unwrap() >= 0.6, "seed {seed}");
        // BlazePose's depths ride along for the joints it agrees with, whichever backend won.
        let known = image.landmark_depth.iter().flatten().count();
        assert!(image.landmark_depth.iter().flatten().all(|d| d.is_finite()));
        if image.backend == Backend::BlazePose {
            assert_eq!(known, 15, "seed {seed}: BlazePose's own joints all agree with themselves");
        }
        assert!(known >= 8, "seed {seed}: {known} joints with a depth");
        let sketch_only = gather(&view, &model, &net, Backend::Fmp, &options).unwrap();
        let f = decide(&sketch_only, cal, &options, None).unwrap();
        assert!(f.landmark_depth.iter().all(Option::is_none), "no BlazePose, no depth");
        samples.push(gather_sample(&view, Some(truth), &model, &net, &options).unwrap());
    }
    let blank = vec![255u8; 256 * 256];
    let page = ImageView::gray(&blank, 256, 256).unwrap();
    let e = gather(&page, &model, &net, Backend::Auto, &options).unwrap();
    match decide(&e, cal, &options, None) {
        Err(Error::NoFigure { score, threshold }) => assert!(score < threshold && threshold == 0.5, "{score}"),
        other => panic!("blank page: {other:?}"),
    }
    let strict = FigureOptions { strict: true, ..options.clone() };
    assert!(matches!(decide(&e, cal, &strict, None), Err(Error::NoFigure { .. })));
    samples.push(gather_sample(&page, None, &model, &net, &options).unwrap());

    // Set scores: PCK of the decided figures, the blank page as the one "no figure".
    let s = score_set(&samples, cal, &options).unwrap();
    let mut want = 0.0;
    for x in &samples[..3] {
        let f = decide(&x.evidence, cal, &options, None).unwrap();
        want += pck(x.truth.as_ref().unwrap(), &f.joints.xy, 0.2).unwrap() / 3.0;
    }
    assert!((s.pck[1] - want).abs() < 1e-12, "{} vs {want}", s.pck[1]);
    assert_eq!((s.n, s.no_figure), (4, 0.25));
    let table = reliability(&samples, cal, &options, 10).unwrap();
    assert_eq!(table.iter().map(|b| b.n).sum::<usize>(), 3);
    // Every image here holds a figure but the blank page: presence models see one outcome only
    // for pages with BlazePose evidence, so the fit must refuse rather than extrapolate.
    assert!(matches!(fit_calibration(&samples[..3], 1e-2, "test"), Err(Error::OutOfRange { .. })));
    // Refusing negatives: treat the three figures as pages to refuse; at most ⌊(1 − q) · 3⌋ of
    // them may still be answered, and the joint models are untouched.
    for (q, allowed) in [(1.0, 0), (0.6, 1), (0.0, 3)] {
        let mut strict_cal = cal.clone();
        let d = refuse_negatives(&mut strict_cal, &[&samples[..3]], q).unwrap();
        assert!(d <= 0.0, "{d}");
        assert_eq!(strict_cal.joints, cal.joints);
        let answered = samples[..3].iter().filter(|x| decide(&x.evidence, &strict_cal, &options, None).is_ok()).count();
        assert!(answered <= allowed, "q {q}: {answered} answered");
        if q == 0.0 {
            assert_eq!((d, &strict_cal), (0.0, cal), "nothing to refuse, nothing changed");
        }
    }
    assert!(matches!(refuse_negatives(&mut cal.clone(), &[], 1.5), Err(Error::OutOfRange { .. })));
    assert_eq!("blazepose".parse::<Backend>().unwrap(), Backend::BlazePose);
    assert!(matches!("openpose".parse::<Backend>(), Err(Error::OutOfRange { .. })));
}

/// A figure BlazePose is sure of is not refused because the sketch model disagrees: with both
/// backends the presence log-odds is the higher of the two-backend model's and BlazePose's
/// own, never the sketch model's own (which answers most clutter pages); with one backend its
/// own model decides.
#[test]
fn presence_is_the_surer_of_the_two_backend_model_and_blazeposes_own() {
    let cal = Calibration::embedded().unwrap();
    let both = |sketch: f64, flag: f64, agreement: f64| EvidenceFeatures {
        candidates: Vec::new(),
        presence_fmp: Some(presence_features(Some(sketch), None, None)),
        presence_blazepose: Some(presence_features(None, Some(flag), None)),
        presence_auto: Some(presence_features(Some(sketch), Some(flag), Some(agreement))),
    };
    let model = |w: &[f64], x: &Option<Vec<f64>>| log_odds(w, x.as_ref().unwrap()).unwrap();
    let mut blazepose_decided = 0;
    for (sketch, flag, agreement) in [(-3.0, 0.95, 1.0), (1.0, 0.2, 0.02), (0.5, 0.7, 0.05), (-1.0, 0.1, 0.9)] {
        let f = both(sketch, flag, agreement);
        let (auto, bp) =
            (model(&cal.presence.auto, &f.presence_auto), model(&cal.presence.blazepose, &f.presence_blazepose));
        assert_eq!(presence_log_odds(&f, cal).unwrap(), Some(auto.max(bp)));
        blazepose_decided += usize::from(bp > auto);
    }
    assert!((1..4).contains(&blazepose_decided), "both models must decide somewhere: {blazepose_decided}");
    // A confident sketch model alone keeps its own model; BlazePose alone its own.
    let fmp = EvidenceFeatures { presence_blazepose: None, presence_auto: None, ..both(2.0, 0.0, 0.0) };
    assert_eq!(presence_log_odds(&fmp, cal).unwrap(), Some(model(&cal.presence.fmp, &fmp.presence_fmp)));
    let bp = EvidenceFeatures { presence_fmp: None, presence_auto: None, ..both(0.0, 0.9, 0.0) };
    assert_eq!(presence_log_odds(&bp, cal).unwrap(), Some(model(&cal.presence.blazepose, &bp.presence_blazepose)));
    let none =
        EvidenceFeatures { presence_fmp: None, presence_blazepose: None, presence_auto: None, candidates: Vec::new() };
    assert_eq!(presence_log_odds(&none, cal).unwrap(), None);
}

/// `Auto` per image lets the 3-D pose step referee a drawing the sketch model recognises: a
/// BlazePose candidate with a misplaced wrist and confidences that would win (the sketch
/// model's part confidences lowered) is passed over for the sketch model's figure, whose
/// proportions the body model explains; by confidence
/// alone (`Fusion::Confidence`) the misplaced one wins. When the sketch model's figure is
/// below its own threshold, the confidences decide as before.
#[test]
fn the_pose_step_referees_recognised_drawings() {
    use sketchbody::pipeline::figure::proportion_choice;
    use sketchbody::skeleton::joint;
    let (model, net, cal, renderer) = backends();
    // The choice alone: no averaging of the joints both candidates share.
    let options = FigureOptions { average_agreement: 0.0, ..FigureOptions::default() };
    // The first of a few rendered sketches that the sketch model recognises (most are).
    let mut e = (31..40)
        .map(|seed| {
            let s = renderer.render(&SketchRequest::random(seed, 384)).unwrap();
            gather(&ImageView::gray(&s.pixels, 384, 384).unwrap(), &model, &net, Backend::Auto, &options).unwrap()
        })
        .find(|e| e.sketch.as_ref().is_some_and(|d| d[0].score >= e.sketch_threshold))
        .expect("a recognised sketch");
    e.sketch.as_mut().unwrap()[0].confidence = [0.05; 15];
    let fmp = e.sketch.as_ref().unwrap()[0].clone();
    // BlazePose's figure: the sketch model's joints with the right wrist thrown past the
    // elbow's reach (a forearm three times too long), every confidence near 1.
    let bp = e.blazepose.as_mut().unwrap();
    bp.joints = fmp.joints;
    let (el, wr) = (fmp.joints.xy[joint::R_ELBOW], fmp.joints.xy[joint::R_WRIST]);
    bp.joints.xy[joint::R_WRIST] = [el[0] + 3.0 * (wr[0] - el[0]), el[1] + 3.0 * (wr[1] - el[1])];
    bp.confidence = [0.999; 15];
    bp.score = 1.0;
    let bad = bp.joints;
    assert_eq!(
        proportion_choice(sketchbody::pose::dict_io::embedded_shared().unwrap(), &fmp.joints, &bad).unwrap(),
        Some(0)
    );
    assert_eq!(
        proportion_choice(sketchbody::pose::dict_io::embedded_shared().unwrap(), &bad, &fmp.joints).unwrap(),
        Some(1)
    );
    let by_pose = decide(&e, cal, &options, None).unwrap();
    assert_eq!(by_pose.backend, Backend::Fmp);
    assert_eq!(by_pose.joints, fmp.joints);
    let by_conf = decide(&e, cal, &FigureOptions { fusion: Fusion::Confidence, ..options.clone() }, None).unwrap();
    assert_eq!((by_conf.backend, by_conf.joints), (Backend::BlazePose, bad));
    // Below the sketch model's threshold the confidences decide.
    e.sketch_threshold = fmp.score + 1.0;
    assert_eq!(decide(&e, cal, &options, None).unwrap().backend, Backend::BlazePose);
}

/// Where both backends answer, each chosen joint that the other backend puts within
/// `average_agreement` of the figure's size becomes the two joints' mean, the others stay the
/// chosen backend's; 0 turns it off, one backend alone averages nothing, and a negative or
/// non-finite fraction is refused.
#[test]
fn agreeing_joints_are_averaged() {
    use sketchbody::detect::figure::AVERAGE_AGREEMENT;
    use sketchbody::pipeline::figure::detect_figure;
    use sketchbody::skeleton::{joint, NUM_JOINTS};
    let (model, net, cal, renderer) = backends();
    let options = FigureOptions::default();
    assert_eq!(options.average_agreement, AVERAGE_AGREEMENT);
    let s = renderer.render(&SketchRequest::random(31, 384)).unwrap();
    let image = ImageView::gray(&s.pixels, 384, 384).unwrap();
    let mut e = gather(&image, &model, &net, Backend::Auto, &options).unwrap();
    let fmp = e.sketch.as_ref().expect("the sketch model's figure")[0].joints;
    // BlazePose's figure: the sketch model's joints, each moved 4 px to the right, the right
    // wrist moved by half the figure's height instead.
    let bp = e.blazepose.as_mut().expect("BlazePose's figure");
    bp.joints = fmp;
    for p in bp.joints.xy.iter_mut() {
        p[0] += 4.0;
    }
    let size = fmp.xy.iter().map(|p| p[1]).fold(f64::NEG_INFINITY, f64::max)
        - fmp.xy.iter().map(|p| p[1]).fold(f64::INFINITY, f64::min);
    bp.joints.xy[joint::R_WRIST][1] += 0.5 * size;
    let blaze = bp.joints;
    let f = decide(&e, cal, &options, None).unwrap();
    let chosen = if f.backend == Backend::Fmp { fmp } else { blaze };
    for j in 0..NUM_JOINTS {
        if j == joint::R_WRIST {
            assert!(!f.averaged[j], "a joint the backends disagree on is not averaged");
            assert_eq!(f.joints.xy[j], chosen.xy[j]);
        } else {
            assert!(f.averaged[j], "joint {j}: the backends agree within 4 px");
            assert!((f.joints.xy[j][0] - (fmp.xy[j][0] + 2.0)).abs() < 1e-9, "the mean of both");
            assert_eq!(f.joints.xy[j][1], fmp.xy[j][1]);
        }
    }
    let off = decide(&e, cal, &FigureOptions { average_agreement: 0.0, ..options.clone() }, None).unwrap();
    assert_eq!(off.averaged, [false; NUM_JOINTS]);
    assert_eq!(off.joints, if off.backend == Backend::Fmp { fmp } else { blaze });
    let mut one = e.clone();
    one.blazepose = None;
    let alone = decide(&one, cal, &options, None).unwrap();
    assert_eq!((alone.backend, alone.joints), (Backend::Fmp, fmp));
    assert_eq!(alone.averaged, [false; NUM_JOINTS], "one backend: nothing to average");
    for bad in [-0.1, f64::NAN, f64::INFINITY] {
        let o = FigureOptions { average_agreement: bad, ..options.clone() };
        assert!(matches!(detect_figure(&image, &model, &net, &o, None), Err(Error::OutOfRange { .. })), "{bad}");
    }
}
