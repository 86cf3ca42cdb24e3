//! `pipeline::run_pipeline` on the example sketch: gender choice, determinism across thread
//! counts, prompt cancellation, and the specific errors of bad input.

#[path = "common/example.rs"]
mod example;
use example::inputs;

use sketchbody::body::{BodyModel, Gender, ShapeChoice};
use sketchbody::detect::figure::Figure;
use sketchbody::detect::{DetectOptions, Model};
use sketchbody::fit::{BodyPart, FitOptions};
use sketchbody::image::GrayImage;
use sketchbody::pipeline::{run_pipeline, DetectedJoints, GivenJoints, JointsSource, PipelineOptions};
use sketchbody::skeleton::{joint, Joints2};
use sketchbody::Error;

fn fast(gender: Option<Gender>) -> PipelineOptions {
    PipelineOptions {
        fit: FitOptions { samples: 24, max_iterations: 3, ..FitOptions::default() },
        gender,
        ..PipelineOptions::default()
    }
}

#[test]
fn fits_gender_as_a_continuous_weight_and_is_deterministic() {
    let (model, dict, sketch, j) = inputs();
    let mut fractions = Vec::new();
    let blended = PipelineOptions { classify_gender: false, ..fast(None) };
    let r = run_pipeline(&model, &dict, &sketch, &GivenJoints(j), &blended, &mut |f| {
        fractions.push(f);
        true
    })
    .unwrap();
    assert_eq!(r.fits.len(), 1);
    assert!(r.gender_fitted && r.space == ShapeChoice::Blended);
    // The prior's mass on the male end is the gender classifier's probability.
    assert_eq!(r.male_prior, Some(r.gender_evidence.male_probability));
    let best = &r.fits[0];
    assert_eq!(r.score, best.score);
    // The reported gender is the nearer end of the fitted value; the confidence is the
    // posterior mass of that half.
    assert!((0.0..=1.0).contains(&r.gender_value));
    assert_eq!(r.gender, if r.gender_value > 0.5 { Gender::Male } else { Gender::Female });
    assert!((0.5..=1.0).contains(&r.gender_confidence));
    let blend = model.blended().unwrap();
    let range = blend.space().gmm().marginal(r.weights.len()).unwrap().range(sketchbody::fit::PRIOR_RANGE_SD);
    assert!(r.weights.iter().zip(&range).all(|(w, (lo, hi))| (lo..=hi).contains(&w)), "{:?}", r.weights);
    assert!((0.0..=1.0).contains(&r.edge_support));
    // The example drawn as a body: every part in view, the torso and limbs supported (its
    // head is drawn larger than a body's, with hair: the body's skull outline lies inside it).
    let parts = r.part_support.expect("a fitted body");
    assert!(parts.support.iter().all(|s| s.is_some()), "{parts:?}");
    let weak = parts.below(sketchbody::fit::LOW_EVIDENCE_SUPPORT);
    assert!(weak.iter().all(|&p| p == BodyPart::Head), "{parts:?}");
    assert!(r.fits.iter().all(|g| g.score.is_finite() && g.score < 0.0));
    assert_eq!(r.weights, best.fit.as_ref().unwrap().weights);
    assert!(fractions.windows(2).all(|w| w[0] <= w[1]), "{fractions:?}");
    assert_eq!(*fractions.last().unwrap(), 1.0);
    // The posed mesh's joints land near the estimated 3-D joints (IK without retargeting keeps
    // the shape's bone lengths, so only directions match exactly; the pelvis is the root).
    let d = (0..3)
        .map(|k| (r.posed_joints[joint::PELVIS][k] - r.pose.joints[joint::PELVIS][k]).powi(2))
        .sum::<f64>()
        .sqrt();
    assert!(d < 1e-6, "pelvis off by {d}");
    assert_eq!(r.posed_vertices.len(), 13380);
    // Same seed on 1 and 2 threads: the same result.
    let one = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap();
    let r1 = one.install(|| run_pipeline(&model, &dict, &sketch, &GivenJoints(j), &blended, &mut |_| true).unwrap());
    assert_eq!(r1.weights, r.weights);
    assert_eq!(r1.gender, r.gender);
    assert_eq!(r1.posed_vertices, r.posed_vertices);
}

#[test]
fn default_automatic_gender_chooses_between_both_gendered_fits() {
    let (model, dict, sketch, j) = inputs();
    let mut fractions = Vec::new();
    let one = PipelineOptions { gender_decision_seeds: 1, ..fast(None) };
    let r = run_pipeline(&model, &dict, &sketch, &GivenJoints(j), &one, &mut |f| {
        fractions.push(f);
        true
    })
    .unwrap();
    assert!(r.gender_fitted && r.male_prior.is_none());
    // The two deciding fits in the spaces' 4 leading dimensions, then the chosen gender's in
    // all 10 of its prior's.
    let dims = |g: &sketchbody::pipeline::GenderFit| g.fit.as_ref().unwrap().weights.len();
    assert_eq!(r.fits.len(), 3);
    assert_eq!(r.fits.iter().map(dims).collect::<Vec<_>>(), [4, 4, 10]);
    assert_eq!(r.space, ShapeChoice::Gendered(r.gender));
    assert_eq!(r.fits[2].space, r.space);
    let chosen = r.chosen_fit().unwrap();
    assert!(std::ptr::eq(chosen, &r.fits[2]));
    assert_eq!((r.score, r.weights.len()), (chosen.score, 10));
    assert_eq!(r.gender_value, r.gender.index() as f64);
    assert!((0.5..=1.0).contains(&r.gender_confidence));
    // The confidence is the combination's probability of the chosen gender.
    let margin = r.fits[1].score - r.fits[0].score;
    let male = sketchbody::fit::MarginCombination::SHIPPED
        .male_probability(sketchbody::fit::GenderClassifier::SHIPPED.log_odds(&r.gender_evidence.features), margin);
    assert_eq!(r.gender, if male > 0.5 { Gender::Male } else { Gender::Female });
    assert!((r.gender_confidence - male.max(1.0 - male)).abs() < 1e-12);
    assert!(fractions.windows(2).all(|w| w[0] <= w[1]), "{fractions:?}");

    // Deciding in the fit's own dimensions with a flat population needs no refit, and decides
    // as before.
    let same = PipelineOptions {
        gender_decision_dims: Some(4),
        fit: FitOptions { dims: Some(4), initial_factor: 1, ..fast(None).fit },
        ..one.clone()
    };
    let r4 = run_pipeline(&model, &dict, &sketch, &GivenJoints(j), &same, &mut |_| true).unwrap();
    assert_eq!(r4.fits.len(), 2);
    assert_eq!((r4.gender, r4.fits[0].score, r4.fits[1].score), (r.gender, r.fits[0].score, r.fits[1].score));
    assert_eq!(r4.chosen_fit().unwrap().space, r4.space);
    assert_eq!(r4.weights.len(), 4);
    // The deciding fits keep a flat population whatever the fit's schedule; a schedule alone
    // makes the chosen gender's refit.
    let scheduled = PipelineOptions { fit: FitOptions { initial_factor: 4, ..same.fit.clone() }, ..same.clone() };
    let rs = run_pipeline(&model, &dict, &sketch, &GivenJoints(j), &scheduled, &mut |_| true).unwrap();
    assert_eq!(rs.fits.len(), 3);
    assert_eq!((rs.gender, rs.fits[0].score, rs.fits[1].score), (r.gender, r.fits[0].score, r.fits[1].score));
    assert!(std::ptr::eq(rs.chosen_fit().unwrap(), &rs.fits[2]));

    // Two deciding seeds: the first pair is the one-seed decision's, the second pair runs with
    // the next fit seed, and the mean of the two margins decides.
    let two = PipelineOptions { gender_decision_seeds: 2, ..one.clone() };
    let r2 = run_pipeline(&model, &dict, &sketch, &GivenJoints(j), &two, &mut |_| true).unwrap();
    assert_eq!(r2.fits.iter().map(dims).collect::<Vec<_>>(), [4, 4, 4, 4, 10]);
    assert_eq!((r2.fits[0].score, r2.fits[1].score), (r.fits[0].score, r.fits[1].score));
    assert_ne!(r2.fits[2].score, r2.fits[0].score, "the second pair has its own seed");
    let margin2 = 0.5 * ((r2.fits[1].score - r2.fits[0].score) + (r2.fits[3].score - r2.fits[2].score));
    let male2 = sketchbody::fit::MarginCombination::SHIPPED
        .male_probability(sketchbody::fit::GenderClassifier::SHIPPED.log_odds(&r2.gender_evidence.features), margin2);
    assert_eq!(r2.gender, if male2 > 0.5 { Gender::Male } else { Gender::Female });
    assert!((r2.gender_confidence - male2.max(1.0 - male2)).abs() < 1e-12);
    assert!(std::ptr::eq(r2.chosen_fit().unwrap(), &r2.fits[4]));
    // Without a refit the body is the last seed's fit of the chosen gender.
    let same2 = PipelineOptions { gender_decision_seeds: 2, ..same.clone() };
    let r42 = run_pipeline(&model, &dict, &sketch, &GivenJoints(j), &same2, &mut |_| true).unwrap();
    assert_eq!(r42.fits.len(), 4);
    let chosen = r42.chosen_fit().unwrap();
    assert!(std::ptr::eq(chosen, &r42.fits[2 + r42.gender.index()]));
    assert_eq!(r42.weights, chosen.fit.as_ref().unwrap().weights);
    let none = PipelineOptions { gender_decision_seeds: 0, ..one.clone() };
    let e = run_pipeline(&model, &dict, &sketch, &GivenJoints(j), &none, &mut |_| true).unwrap_err();
    assert!(matches!(e, Error::OutOfRange { name: "gender decision seeds", .. }), "{e:?}");

    // Cheaper deciding fits (their own samples per iteration) leave the chosen gender's fit as
    // it was: 12 × 3 evaluations each, then the fit's own schedule (8 × 24, 96, 48).
    let evaluations = |g: &sketchbody::pipeline::GenderFit| g.fit.as_ref().unwrap().evaluations;
    let full = PipelineOptions { fit: FitOptions { tolerance: 1e-12, ..one.fit.clone() }, ..one };
    let rf = run_pipeline(&model, &dict, &sketch, &GivenJoints(j), &full, &mut |_| true).unwrap();
    let cheap = PipelineOptions { gender_decision_samples: Some(12), ..full.clone() };
    let rc = run_pipeline(&model, &dict, &sketch, &GivenJoints(j), &cheap, &mut |_| true).unwrap();
    assert_eq!(rf.fits.iter().map(evaluations).collect::<Vec<_>>(), [72, 72, 192 + 96 + 48]);
    assert_eq!(rc.fits.iter().map(evaluations).collect::<Vec<_>>(), [36, 36, 192 + 96 + 48]);
    assert_ne!(rc.fits[0].score, rf.fits[0].score, "the deciding fits are other fits");
    assert_eq!(rc.gender, rf.gender);
    assert_eq!((&rc.weights, rc.fits[2].score), (&rf.weights, rf.fits[2].score), "the same final fit");
    let bad = PipelineOptions { gender_decision_samples: Some(1), ..full.clone() };
    let e = run_pipeline(&model, &dict, &sketch, &GivenJoints(j), &bad, &mut |_| true).unwrap_err();
    assert!(matches!(e, Error::OutOfRange { name: "samples", .. }), "{e:?}");

    // Shorter deciding fits (their own iterations) are the first iterations of the full ones:
    // the same samples, so each best score is the best of those iterations; the chosen
    // gender's fit is as it was. Never longer than the fit's own iterations.
    let iterations = |g: &sketchbody::pipeline::GenderFit| g.fit.as_ref().unwrap().history.len();
    let short = PipelineOptions { gender_decision_iterations: Some(2), ..full.clone() };
    let rsh = run_pipeline(&model, &dict, &sketch, &GivenJoints(j), &short, &mut |_| true).unwrap();
    assert_eq!(rf.fits.iter().map(iterations).collect::<Vec<_>>(), [3, 3, 3]);
    assert_eq!(rsh.fits.iter().map(iterations).collect::<Vec<_>>(), [2, 2, 3]);
    for k in 0..2 {
        let (a, b) = (rf.fits[k].fit.as_ref().unwrap(), rsh.fits[k].fit.as_ref().unwrap());
        assert_eq!(a.history[..2], b.history[..]);
        let best2 = b.history.iter().map(|h| h.best_score).fold(f64::NEG_INFINITY, f64::max);
        assert_eq!(rsh.fits[k].score, best2);
    }
    assert_eq!((&rsh.weights, rsh.fits[2].score), (&rf.weights, rf.fits[2].score), "the same final fit");
    let long = PipelineOptions { gender_decision_iterations: Some(50), ..full.clone() };
    let rl = run_pipeline(&model, &dict, &sketch, &GivenJoints(j), &long, &mut |_| true).unwrap();
    assert_eq!(
        rl.fits.iter().map(|g| g.score).collect::<Vec<_>>(),
        rf.fits.iter().map(|g| g.score).collect::<Vec<_>>()
    );
    let zero = PipelineOptions { gender_decision_iterations: Some(0), ..full };
    let e = run_pipeline(&model, &dict, &sketch, &GivenJoints(j), &zero, &mut |_| true).unwrap_err();
    assert!(matches!(e, Error::OutOfRange { name: "iterations", .. }), "{e:?}");
}

#[test]
fn mean_shape_baseline_is_the_mean_posed() {
    let (model, dict, sketch, j) = inputs();
    let o = PipelineOptions { mean_shape: true, ..fast(Some(Gender::Male)) };
    let r = run_pipeline(&model, &dict, &sketch, &GivenJoints(j), &o, &mut |_| true).unwrap();
    assert!(r.weights.is_empty() && r.score.is_nan() && r.gender == Gender::Male);
    assert_eq!(r.mesh.vertices, model.space(Gender::Male).synthesize(&[]).unwrap().vertices);
    let o = PipelineOptions { mean_shape: true, gender: None, ..fast(None) };
    assert!(matches!(
        run_pipeline(&model, &dict, &sketch, &GivenJoints(j), &o, &mut |_| true),
        Err(Error::OutOfRange { name: "gender", .. })
    ));
}

/// The pipeline hands its own dictionary to the joints source, so the detector's pose-step
/// referee (`pipeline::figure`) judges with the caller's dictionary, not the embedded one.
#[test]
fn the_joints_source_gets_the_callers_dictionary() {
    struct Recording(Joints2, std::sync::Mutex<Vec<String>>);
    impl JointsSource for Recording {
        fn name(&self) -> &str {
            "recording"
        }
        fn joints(&self, _sketch: &GrayImage, _edges: &GrayImage) -> sketchbody::Result<Joints2> {
            Ok(self.0)
        }
        fn figure(
            &self,
            sketch: &GrayImage,
            edges: &GrayImage,
            dict: &sketchbody::pose::Dictionary,
        ) -> sketchbody::Result<(Joints2, Option<Figure>)> {
            self.1.lock().unwrap().push(dict.provenance.clone());
            Ok((self.joints(sketch, edges)?, None))
        }
    }
    let (model, mut dict, sketch, j) = inputs();
    dict.provenance = "the caller's dictionary".into();
    let source = Recording(j, Default::default());
    let o = PipelineOptions { mean_shape: true, ..fast(Some(Gender::Female)) };
    run_pipeline(&model, &dict, &sketch, &source, &o, &mut |_| true).unwrap();
    assert_eq!(*source.1.lock().unwrap(), ["the caller's dictionary"]);
}

#[test]
fn cancel_returns_promptly() {
    let (model, dict, sketch, j) = inputs();
    let o = PipelineOptions {
        fit: FitOptions { samples: 200, max_iterations: 100, ..FitOptions::default() },
        ..fast(None)
    };
    let mut calls = 0;
    let r = run_pipeline(&model, &dict, &sketch, &GivenJoints(j), &o, &mut |f| {
        calls += 1;
        f <= 0.06
    });
    assert!(matches!(r, Err(Error::Cancelled)), "{r:?}");
    // Stopped after the first fit iteration, not after 2 × 100.
    assert!(calls <= 5, "{calls} progress calls");
    // Cancel before any work.
    let r = run_pipeline(&model, &dict, &sketch, &GivenJoints(j), &o, &mut |_| false);
    assert!(matches!(r, Err(Error::Cancelled)));
}

#[test]
fn bad_input_gives_specific_errors() {
    let (model, dict, sketch, j) = inputs();
    let o = fast(Some(Gender::Female));
    let go =
        |img: &GrayImage, joints: Joints2| run_pipeline(&model, &dict, img, &GivenJoints(joints), &o, &mut |_| true);
    let blank = GrayImage::filled(300, 300, 230).unwrap();
    assert!(matches!(go(&blank, j), Err(Error::BlankImage { width: 300, height: 300, .. })));
    let tiny = GrayImage::filled(31, 200, 0).unwrap();
    assert!(matches!(go(&tiny, j), Err(Error::ImageTooSmall { width: 31, height: 200, min: 32 })));
    let mut outside = j;
    outside.xy[joint::R_ANKLE] = [222.0, -3.0];
    assert!(matches!(go(&sketch, outside), Err(Error::JointOutsideImage { joint: "r_ankle", .. })));
    let mut nan = j;
    nan.xy[joint::NECK] = [f64::NAN, 100.0];
    assert!(matches!(go(&sketch, nan), Err(Error::NonFinite { .. })));
    // The detected-joints options are checked even when the joints are given.
    for w in [-0.1, f64::NAN, f64::INFINITY] {
        let bad = PipelineOptions { depth_hint: w, ..o.clone() };
        let r = run_pipeline(&model, &dict, &sketch, &GivenJoints(j), &bad, &mut |_| true);
        assert!(matches!(r, Err(Error::OutOfRange { name: "depth_hint", .. })), "{w}");
    }
    let bad = PipelineOptions {
        detected: sketchbody::pipeline::DetectedJointsFit { joint_weight_scale: 2.0, ..Default::default() },
        ..o.clone()
    };
    let r = run_pipeline(&model, &dict, &sketch, &GivenJoints(j), &bad, &mut |_| true);
    assert!(matches!(r, Err(Error::OutOfRange { name: "detected.joint_weight_scale", .. })));
    // A joint marked missing may lie anywhere (it is only a guess).
    let mut hidden = outside;
    hidden.visible[joint::R_ANKLE] = false;
    assert!(go(&sketch, hidden).is_ok());
    // Without joints the embedded detector finds them near the drawn ones.
    let detector = Model::embedded().unwrap();
    let detect_options = DetectOptions::default();
    let found = run_pipeline(
        &model,
        &dict,
        &sketch,
        &DetectedJoints { model: &detector, options: &detect_options },
        &o,
        &mut |_| true,
    )
    .unwrap();
    assert_eq!(found.joints_source, "detector");
    let height = (0..15).map(|k| j.xy[k][1]).fold(f64::NEG_INFINITY, f64::max)
        - (0..15).map(|k| j.xy[k][1]).fold(f64::INFINITY, f64::min);
    // PCK@0.2 of the figure height over the joints the detector kept visible.
    let visible: Vec<usize> = (0..15).filter(|&k| found.joints2d.visible[k]).collect();
    let close = visible
        .iter()
        .filter(|&&k| (found.joints2d.xy[k][0] - j.xy[k][0]).hypot(found.joints2d.xy[k][1] - j.xy[k][1]) < 0.2 * height)
        .count();
    assert!(
        visible.len() >= 12 && close * 5 >= visible.len() * 4,
        "{close} of {} visible detected joints within 0.2 figure heights: {:?}",
        visible.len(),
        found.joints2d
    );
    let bad_fit = PipelineOptions { fit: FitOptions { temperature: f64::NAN, ..o.fit.clone() }, ..o.clone() };
    assert!(matches!(
        run_pipeline(&model, &dict, &sketch, &GivenJoints(j), &bad_fit, &mut |_| true),
        Err(Error::NonFinite { .. })
    ));
}

#[test]
fn camera_refit_recovers_the_scale_of_the_body_skeleton() {
    use sketchbody::camera::WeakPerspective;
    use sketchbody::pipeline::refit_camera;
    use sketchbody::pose::PoseEstimate;
    let model = BodyModel::embedded().unwrap();
    let rest = *model.space(Gender::Male).mean_joints();
    let truth = WeakPerspective { sx: 300.0, sy: 310.0, r: nalgebra::Matrix3::identity(), t: [250.0, 260.0] };
    let mut j = Joints2 { xy: [[0.0; 2]; 15], visible: [true; 15] };
    for k in 0..15 {
        j.xy[k] = truth.project(&nalgebra::Vector3::from(rest[k]));
    }
    j.visible[joint::L_WRIST] = false;
    j.xy[joint::L_WRIST] = [0.0, 0.0]; // a wrong guess, ignored
    let wrong = WeakPerspective { sx: 200.0, sy: 180.0, t: [0.0, 0.0], ..truth };
    let est = PoseEstimate {
        joints: rest,
        camera: wrong,
        bases: vec![],
        weights: vec![],
        rms: 0.0,
        length_excess: 0.0,
        base: rest,
        base_parts: None,
        factors: sketchbody::pose::figure::BodyFactors::default(),
        plausible: true,
        alternatives: Vec::new(),
        depth_costs: None,
    };
    let fixed = refit_camera(&est, &rest, &j).unwrap();
    assert!((fixed.camera.sx - 300.0).abs() < 1e-6 && (fixed.camera.sy - 310.0).abs() < 1e-6, "{:?}", fixed.camera);
    assert!((fixed.camera.t[0] - 250.0).abs() < 1e-6 && (fixed.camera.t[1] - 260.0).abs() < 1e-6);
    assert_eq!(fixed.joints, rest);
    let mut few = j;
    few.visible = [false; 15];
    few.visible[0] = true;
    assert!(matches!(refit_camera(&est, &rest, &few), Err(Error::Degenerate(_))));
}

#[test]
fn known_height_per_sample_cameras_and_a_given_pose() {
    let (model, dict, sketch, j) = inputs();
    let base = fast(Some(Gender::Female));
    // Uncalibrated, so that the fit's own weights and height are compared.
    let free = PipelineOptions {
        fit: FitOptions { sample_camera: true, ..base.fit.clone() },
        calibrate_fit: false,
        ..base.clone()
    };
    let r = run_pipeline(&model, &dict, &sketch, &GivenJoints(j), &free, &mut |_| true).unwrap();
    // A known height: the same fit (a uniform scale does not change a per-sample camera's image;
    // the proportion estimate sees the refitted camera's axis ratio, equal up to rounding), the
    // mesh scaled about its pelvis to exactly that height.
    let tall = PipelineOptions { fit: FitOptions { height: Some(2.1), ..free.fit.clone() }, ..free.clone() };
    let t = run_pipeline(&model, &dict, &sketch, &GivenJoints(j), &tall, &mut |_| true).unwrap();
    assert_eq!(t.weights.len(), r.weights.len());
    assert!(t.weights.iter().zip(&r.weights).all(|(a, b)| (a - b).abs() < 1e-9), "{:?} vs {:?}", t.weights, r.weights);
    assert!((t.mesh.height() - 2.1).abs() < 1e-5, "{}", t.mesh.height());
    let (tp, rp) = (t.mesh.joints[joint::PELVIS], r.mesh.joints[joint::PELVIS]);
    assert!((0..3).all(|a| (tp[a] - rp[a]).abs() < 1e-6), "{tp:?} vs {rp:?}");
    // The output camera is refitted to the chosen body: a taller body, a smaller image scale.
    let k = t.mesh.height() / r.mesh.height();
    assert!(
        (r.pose.camera.sx / t.pose.camera.sx - k).abs() < 1e-6 * k,
        "{} {} {k}",
        r.pose.camera.sx,
        t.pose.camera.sx
    );
    // The mean-shape baseline takes the height too.
    let mean = PipelineOptions { mean_shape: true, ..tall.clone() };
    assert!(
        (run_pipeline(&model, &dict, &sketch, &GivenJoints(j), &mean, &mut |_| true).unwrap().mesh.height() - 2.1)
            .abs()
            < 1e-5
    );
    let bad = PipelineOptions { fit: FitOptions { height: Some(0.01), ..free.fit.clone() }, ..free.clone() };
    assert!(matches!(
        run_pipeline(&model, &dict, &sketch, &GivenJoints(j), &bad, &mut |_| true),
        Err(Error::OutOfRange { name: "height", .. })
    ));
    // A given pose replaces the solver's.
    let mut given = r.pose.clone();
    given.joints[joint::L_WRIST][2] += 0.2;
    let g = PipelineOptions { given_pose: Some(given.clone()), ..base.clone() };
    let rg = run_pipeline(&model, &dict, &sketch, &GivenJoints(j), &g, &mut |_| true).unwrap();
    assert_eq!(rg.pose.joints, given.joints);
    let mut nan = given;
    nan.joints[3][0] = f64::NAN;
    let g = PipelineOptions { given_pose: Some(nan), ..base };
    assert!(matches!(
        run_pipeline(&model, &dict, &sketch, &GivenJoints(j), &g, &mut |_| true),
        Err(Error::NonFinite { .. })
    ));
}

/// With the height unknown a gendered 10-dimension fit's weights are mapped by the shipped
/// shape calibration (the lower dimensions kept, every weight inside the prior's box) and the
/// body is scaled about its pelvis to the shipped height calibration's height of the mapped
/// body, read with the fitted bone factors and the drawn widths; the fit itself is the same. A given height wins, and the mean shape is never calibrated.
#[test]
fn an_unknown_height_is_calibrated_and_a_known_one_wins() {
    use sketchbody::fit::{FitCalibration, PRIOR_RANGE_SD};
    use sketchbody::pipeline::rest_body;
    let (model, dict, sketch, j) = inputs();
    let run = |o: &PipelineOptions| run_pipeline(&model, &dict, &sketch, &GivenJoints(j), o, &mut |_| true).unwrap();
    let on = fast(Some(Gender::Female));
    assert!(on.calibrate_fit, "the default");
    let off = PipelineOptions { calibrate_fit: false, ..on.clone() };
    let (c, f) = (run(&on), run(&off));
    let fit_weights =
        |r: &sketchbody::pipeline::PipelineResult| r.chosen_fit().unwrap().fit.as_ref().unwrap().weights.clone();
    assert_eq!(fit_weights(&c), fit_weights(&f), "the same fit");
    assert_eq!(f.weights, fit_weights(&f), "uncalibrated: the fit's weights");
    assert!(c.calibrated && !f.calibrated);
    let shipped = FitCalibration::SHIPPED;
    assert_eq!(c.weights.len(), 10);
    assert_eq!(c.weights[..shipped.shape.first_dim], f.weights[..shipped.shape.first_dim], "lower dimensions kept");
    let range = model.space(Gender::Female).gmm().range(PRIOR_RANGE_SD);
    let mapped = shipped.shape.apply(Gender::Female, &f.weights).unwrap().unwrap();
    for k in 0..10 {
        let want = mapped[k].clamp(range[k].0, range[k].1);
        assert!((c.weights[k] - want).abs() < 1e-12, "weight {k}: {} vs {want}", c.weights[k]);
    }
    assert!(c.weights.iter().zip(&f.weights).any(|(a, b)| (a - b).abs() > 1e-3), "the map moves the body");
    let space = sketchbody::body::ShapeChoice::Gendered(Gender::Female);
    let props = c.chosen_fit().unwrap().fit.as_ref().unwrap().proportions;
    let mapped_body = rest_body(&model, space, &c.weights, props.as_ref()).unwrap();
    assert!((c.fit_height - sketchbody::body::rig::y_extent(&mapped_body.vertices)).abs() < 1e-9);
    assert!((f.mesh.height() - f.fit_height).abs() < 1e-6, "uncalibrated: the fitted height");
    let evidence = sketchbody::fit::HeightEvidence::new(props.as_ref(), Some(&c.gender_evidence.features));
    let want = shipped.height.calibrated(c.fit_height, 0.0, &evidence).unwrap();
    let without = shipped.height.calibrated(c.fit_height, 0.0, &sketchbody::fit::HeightEvidence::NONE).unwrap();
    assert!((want / without - 1.0).abs() > 1e-4, "the drawing's evidence moves the height");
    assert!((c.mesh.height() - want).abs() < 1e-5, "{} vs {want}", c.mesh.height());
    assert!((want / c.fit_height - 1.0).abs() > 1e-4, "the example's height moves");
    // A 4-dimension fit is outside the map: only its height is calibrated.
    let four = PipelineOptions { fit: FitOptions { dims: Some(4), ..on.fit.clone() }, ..on.clone() };
    let r4 = run(&four);
    assert_eq!(r4.weights, fit_weights(&r4));
    assert!(r4.calibrated);
    let (cp, mp) = (c.mesh.joints[joint::PELVIS], mapped_body.joints[joint::PELVIS]);
    assert!((0..3).all(|a| (cp[a] - mp[a]).abs() < 1e-6), "scaled about the pelvis: {cp:?} vs {mp:?}");
    // The output camera follows the calibrated body: its posed joints still land on the drawn ones.
    let rms = |r: &sketchbody::pipeline::PipelineResult| {
        let sq: f64 = (0..15)
            .map(|k| {
                let p = r.pose.camera.project(&nalgebra::Vector3::from(r.posed_joints[k]));
                (p[0] - j.xy[k][0]).powi(2) + (p[1] - j.xy[k][1]).powi(2)
            })
            .sum();
        (sq / 15.0).sqrt()
    };
    assert!(rms(&c) < 1.5 * rms(&f) + 2.0, "calibrated {} px, fitted {} px", rms(&c), rms(&f));
    let known = PipelineOptions { fit: FitOptions { height: Some(1.9), ..on.fit.clone() }, ..on.clone() };
    assert!((run(&known).mesh.height() - 1.9).abs() < 1e-5);
    let mean = PipelineOptions { mean_shape: true, ..on };
    let m = run(&mean);
    assert_eq!(m.mesh.vertices, model.space(Gender::Female).synthesize(&[]).unwrap().vertices);
}

/// Mean distance between corresponding vertices of two rest meshes, each centred on its
/// centroid and divided by its own height (a fraction of the height; the eval's centred AED).
fn shape_distance(a: &[[f32; 3]], b: &[[f32; 3]]) -> f64 {
    let normalised = |v: &[[f32; 3]]| {
        let n = v.len() as f64;
        let c: [f64; 3] = std::array::from_fn(|k| v.iter().map(|p| p[k] as f64).sum::<f64>() / n);
        let h = sketchbody::body::rig::y_extent(v);
        v.iter().map(|p| nalgebra::Vector3::from_fn(|k, _| (p[k] as f64 - c[k]) / h)).collect::<Vec<_>>()
    };
    let (a, b) = (normalised(a), normalised(b));
    a.iter().zip(&b).map(|(p, q)| (p - q).norm()).sum::<f64>() / a.len() as f64
}

/// The example sketch under a cloak to the ground: everything below the shoulders is replaced
/// by a wide trapezoid outline (no body stroke left inside it). The fit still returns a body of
/// plausible size inside the prior's range, nearer the uncloaked figure's than the mean body is,
/// flags it as low-evidence and names the legs as the parts not trusted.
#[test]
fn a_cloak_to_the_ground_gives_a_plausible_body_flagged_low_evidence() {
    let (model, dict, sketch, j) = inputs();
    let (w, h) = (sketch.width(), sketch.height());
    let (ls, rs) = (j.xy[joint::L_SHOULDER], j.xy[joint::R_SHOULDER]);
    let top = ls[1].min(rs[1]);
    let bottom = j.xy[joint::L_ANKLE][1].max(j.xy[joint::R_ANKLE][1]) + 4.0;
    let centre = 0.5 * (ls[0] + rs[0]);
    let half_top = 0.5 * (ls[0] - rs[0]).abs() + 12.0;
    let half_bottom = 2.2 * half_top;
    let half_at = |y: f64| half_top + (half_bottom - half_top) * ((y - top) / (bottom - top)).clamp(0.0, 1.0);
    let mut pixels = sketch.as_bytes().to_vec();
    for y in 0..h {
        for x in 0..w {
            let (fx, fy) = (x as f64, y as f64);
            if fy < top || fy > bottom + 3.0 {
                continue;
            }
            let d = (fx - centre).abs() - half_at(fy);
            if d <= 3.0 {
                // Outline 3 px thick on the sides and the hem, paper inside.
                let edge = d >= 0.0 || fy >= bottom;
                pixels[y * w + x] = if edge { 0 } else { 255 };
            }
        }
    }
    let cloaked = GrayImage::from_vec(w, h, pixels).unwrap();
    let r = run_pipeline(&model, &dict, &cloaked, &GivenJoints(j), &fast(None), &mut |_| true).unwrap();
    assert!(r.low_evidence, "edge support {}", r.edge_support);
    // Never worse than the mean: against the same figure drawn without the cloak, the cloaked
    // body (centred, at a common height) is nearer than the mean body of the figure's gender.
    let clean = run_pipeline(&model, &dict, &sketch, &GivenJoints(j), &fast(None), &mut |_| true).unwrap();
    let mean_options = PipelineOptions { mean_shape: true, ..fast(Some(clean.gender)) };
    let mean = run_pipeline(&model, &dict, &sketch, &GivenJoints(j), &mean_options, &mut |_| true).unwrap();
    let (to_cloaked, to_mean) = (
        shape_distance(&r.mesh.vertices, &clean.mesh.vertices),
        shape_distance(&mean.mesh.vertices, &clean.mesh.vertices),
    );
    assert!(to_cloaked < to_mean, "cloaked {to_cloaked} vs mean {to_mean} (fractions of the height)");
    // Per part: the legs under the cloak are the parts not trusted, and the least supported.
    let parts = r.part_support.expect("a fitted body");
    let weak = parts.below(sketchbody::fit::LOW_EVIDENCE_SUPPORT);
    assert!(weak.contains(&BodyPart::RightLeg) && weak.contains(&BodyPart::LeftLeg), "{parts:?}");
    let leg = |p| parts.of(p).unwrap();
    let legs = leg(BodyPart::RightLeg).max(leg(BodyPart::LeftLeg));
    assert!(
        BodyPart::ALL[..4].iter().all(|&p| parts.of(p).unwrap() > legs),
        "the legs are the least supported: {parts:?}"
    );
    let range = model.blended().unwrap().space().gmm().marginal(r.weights.len()).unwrap();
    let range = range.range(sketchbody::fit::PRIOR_RANGE_SD);
    assert!(r.weights.iter().zip(&range).all(|(w, (lo, hi))| (lo..=hi).contains(&w)), "{:?}", r.weights);
    let height = sketchbody::body::rig::y_extent(&r.mesh.vertices);
    assert!((1.4..2.1).contains(&height), "height {height} m");
}

#[test]
fn detected_joints_fit_the_gendered_space_the_classifier_picks() {
    use sketchbody::detect::figure::FigureOptions;
    use sketchbody::detect::landmark::LandmarkNet;
    use sketchbody::pipeline::{DetectedJointsFit, FigureJoints};
    let (model, dict, sketch, _) = inputs();
    let (detector, net) = (Model::embedded().unwrap(), LandmarkNet::embedded().unwrap());
    let figure_options = FigureOptions::default();
    let source = FigureJoints { model: &detector, net: &net, options: &figure_options, colour: None };
    let r = run_pipeline(&model, &dict, &sketch, &source, &fast(None), &mut |_| true).unwrap();
    assert!(r.detection.is_some() && r.gender_fitted);
    let p = r.gender_evidence.male_probability;
    let picked = if p > 0.5 { Gender::Male } else { Gender::Female };
    assert_eq!((r.gender, r.space, r.fits.len()), (picked, ShapeChoice::Gendered(picked), 1));
    assert_eq!((r.gender_value, r.gender_confidence, r.male_prior), (picked.index() as f64, p.max(1.0 - p), None));
    // Switched off: the both-sexes fit with an even prior, as before.
    let blended = PipelineOptions {
        detected: DetectedJointsFit { classifier_gender: false, ..Default::default() },
        ..fast(None)
    };
    let b = run_pipeline(&model, &dict, &sketch, &source, &blended, &mut |_| true).unwrap();
    assert_eq!((b.space, b.male_prior), (ShapeChoice::Blended, Some(0.5)));
    // A given gender wins over the classifier.
    let given = Gender::ALL.into_iter().find(|&g| g != picked).unwrap();
    let g = run_pipeline(&model, &dict, &sketch, &source, &fast(Some(given)), &mut |_| true).unwrap();
    assert_eq!((g.gender, g.gender_fitted, g.gender_confidence), (given, false, 1.0));
}
