//! The SIR shape fit end to end on the embedded model: an outline sketch of a known body (its
//! silhouette's Canny edges) must be fitted closer than the mean shape, deterministically on any
//! thread count, and a cancelling progress callback must stop it.

use nalgebra::Matrix3;
use sketchbody::body::{BodyModel, Gender, ShapeChoice};
use sketchbody::camera::WeakPerspective;
use sketchbody::fit::{fit_shape, score_shapes, FitOptions, FitProblem, MatchScore};
use sketchbody::image::{canny, CannyParams, GrayImage};
use sketchbody::raster::Rasterizer;
use sketchbody::skeleton::{Joints2, NUM_JOINTS};
use sketchbody::Error;

fn aed(a: &[[f32; 3]], b: &[[f32; 3]]) -> f64 {
    let sum: f64 =
        a.iter().zip(b).map(|(p, q)| (0..3).map(|c| (p[c] as f64 - q[c] as f64).powi(2)).sum::<f64>().sqrt()).sum();
    sum / a.len() as f64
}

struct Case {
    model: BodyModel,
    truth: sketchbody::body::RestShape,
    camera: WeakPerspective,
    edges: GrayImage,
}

fn case() -> Case {
    let model = BodyModel::embedded().unwrap();
    let space = model.space(Gender::Male);
    // A clearly non-average body: about one standard deviation along every component.
    let sd: Vec<f64> = space.variances().iter().take(space.default_dim()).map(|v| v.sqrt()).collect();
    let truth_w: Vec<f64> = sd.iter().enumerate().map(|(k, s)| if k < 2 { 1.2 * s } else { -0.8 * s }).collect();
    let truth = space.synthesize(&truth_w).unwrap();
    let camera = WeakPerspective { sx: 110.0, sy: 110.0, r: Matrix3::identity(), t: [128.0, 135.0] };
    let mut raster = Rasterizer::new();
    raster.rasterize(&truth.vertices, &model.triangles(), &camera, 256, 256, false).unwrap();
    let drawing: Vec<u8> = raster.mask().iter().map(|&m| if m != 0 { 40 } else { 235 }).collect();
    let edges = canny(&GrayImage::from_vec(256, 256, drawing).unwrap().view(), &CannyParams::default()).unwrap();
    Case { model, truth, camera, edges }
}

/// The fit problem of `c` in the male space without 2-D joints.
fn male_problem(c: &Case) -> FitProblem<'_> {
    FitProblem {
        model: &c.model,
        gender: Gender::Male.into(),
        pose: &c.truth.joints,
        camera: &c.camera,
        edges: &c.edges,
        joints2d: None,
        views: &[],
    }
}

fn options() -> FitOptions {
    // The problem camera, PCA weights only, temperature 2 (the defaults before per-sample
    // cameras); a small budget in the 4 leading dimensions, where `case`'s truth lies.
    FitOptions {
        samples: 64,
        max_iterations: 6,
        raster_max_side: 128,
        seed: 11,
        temperature: 2.0,
        sample_camera: false,
        proportion_sd: 0.0,
        dims: Some(4),
        ..FitOptions::default()
    }
}

#[test]
fn default_dimensions_are_the_gendered_priors_all_and_the_blended_spaces_own() {
    let c = case();
    for (gender, dims) in [(ShapeChoice::Gendered(Gender::Male), 10), (ShapeChoice::Blended, 5)] {
        let problem = FitProblem {
            model: &c.model,
            gender,
            pose: &c.truth.joints,
            camera: &c.camera,
            edges: &c.edges,
            joints2d: None,
            views: &[],
        };
        let o = FitOptions { samples: 8, max_iterations: 1, raster_max_side: 64, ..FitOptions::default() };
        let r = fit_shape(&problem, &o, &mut |_| true).unwrap();
        assert_eq!(r.weights.len(), dims, "{gender:?}");
        let too_many = FitOptions { dims: Some(100), ..o };
        assert!(matches!(fit_shape(&problem, &too_many, &mut |_| true), Err(Error::OutOfRange { .. })));
    }
}

#[test]
fn fit_beats_the_mean_shape_and_is_deterministic() {
    let c = case();
    let problem = male_problem(&c);
    let space = c.model.space(Gender::Male);
    let mean_error = aed(&c.truth.vertices, &space.synthesize(&[]).unwrap().vertices);
    let mut calls = 0;
    let result = fit_shape(&problem, &options(), &mut |f| {
        calls += 1;
        assert!(f > 0.0 && f <= 1.0);
        true
    })
    .unwrap();
    assert_eq!(calls, result.history.len());
    let fitted = aed(&c.truth.vertices, &space.synthesize(&result.weights).unwrap().vertices);
    assert!(fitted < 0.75 * mean_error, "fitted AED {fitted:.4} m vs mean shape {mean_error:.4} m");
    assert!(result.best_score > -1.0, "best mean boundary-to-edge distance {} raster px", -result.best_score);

    let one_thread = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap();
    let again = one_thread.install(|| fit_shape(&problem, &options(), &mut |_| true)).unwrap();
    assert_eq!(again, result, "same seed must give the same fit on 1 thread");
}

#[test]
fn paper_score_and_cancellation() {
    let c = case();
    let problem = male_problem(&c);
    let paper =
        fit_shape(&problem, &FitOptions { score: MatchScore::Paper, max_iterations: 2, ..options() }, &mut |_| true)
            .unwrap();
    assert!(
        paper.best_score > 0.0 && paper.best_score < 0.5,
        "eq. 7 IoU of a filled mask with thin edges is small: {}",
        paper.best_score
    );
    let cancelled = fit_shape(&problem, &options(), &mut |_| false);
    assert!(matches!(cancelled, Err(Error::Cancelled)));
    let bad = FitOptions { samples: 1, ..options() };
    assert!(matches!(fit_shape(&problem, &bad, &mut |_| true), Err(Error::OutOfRange { .. })));
    let blank = GrayImage::filled(256, 256, 0).unwrap();
    let blank_problem = FitProblem { edges: &blank, ..problem };
    assert!(fit_shape(&blank_problem, &options(), &mut |_| true).is_err());
}

#[test]
fn joint_term_penalises_off_joints_and_is_validated() {
    let c = case();
    let truth_2d: Vec<[f64; 2]> =
        c.truth.joints.iter().map(|p| c.camera.project(&nalgebra::Vector3::from(*p))).collect();
    // 2-D joints 40 image px (20 raster px at side 128) to the right of the body's own.
    let mut shifted = Joints2 { xy: [[0.0; 2]; NUM_JOINTS], visible: [true; NUM_JOINTS] };
    for (k, q) in truth_2d.iter().enumerate() {
        shifted.xy[k] = [q[0] + 40.0, q[1]];
    }
    let base = male_problem(&c);
    let with_joints = FitProblem { joints2d: Some(&shifted), ..base };
    let o = |w: f64| FitOptions { joint_weight: w, max_iterations: 2, ..options() };
    let off = fit_shape(&base, &o(1.0), &mut |_| true).unwrap();
    // No 2-D joints: the weight has no effect.
    assert_eq!(fit_shape(&base, &o(0.0), &mut |_| true).unwrap(), off);
    // Weight 0 with joints: no effect either.
    assert_eq!(fit_shape(&with_joints, &o(0.0), &mut |_| true).unwrap(), off);
    // Weight 1: every score loses about the 20 raster px of joint distance.
    let on = fit_shape(&with_joints, &o(1.0), &mut |_| true).unwrap();
    let drop = off.best_score - on.best_score;
    assert!(drop > 15.0 && drop < 25.0, "penalty {drop} raster px");
    let one_thread = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap();
    assert_eq!(
        one_thread.install(|| fit_shape(&with_joints, &o(1.0), &mut |_| true)).unwrap(),
        on,
        "joint term deterministic on 1 thread"
    );
    assert!(matches!(fit_shape(&base, &o(-0.1), &mut |_| true), Err(Error::OutOfRange { name: "joint weight", .. })));
    assert!(matches!(
        fit_shape(&base, &o(f64::NAN), &mut |_| true),
        Err(Error::NonFinite { name: "joint weight", .. })
    ));
}

#[test]
fn per_sample_cameras_ignore_the_problem_cameras_scale() {
    let c = case();
    let truth_2d = Joints2 {
        xy: std::array::from_fn(|k| c.camera.project(&nalgebra::Vector3::from(c.truth.joints[k]))),
        visible: [true; NUM_JOINTS],
    };
    // A camera 20% too small and 15 px off: only its rotation is used with per-sample cameras.
    let wrong = WeakPerspective { sx: 88.0, sy: 88.0, t: [143.0, 150.0], ..c.camera };
    let right = FitProblem {
        model: &c.model,
        gender: Gender::Male.into(),
        pose: &c.truth.joints,
        camera: &c.camera,
        edges: &c.edges,
        joints2d: Some(&truth_2d),
        views: &[],
    };
    let off = FitProblem { camera: &wrong, ..right };
    let o = FitOptions { sample_camera: true, ..options() };
    let fixed_wrong = fit_shape(&off, &options(), &mut |_| true).unwrap();
    let free = fit_shape(&off, &o, &mut |_| true).unwrap();
    let free_right = fit_shape(&right, &o, &mut |_| true).unwrap();
    assert!(free.best_score > -1.5, "per-sample camera: best mean boundary distance {} raster px", -free.best_score);
    assert!(
        free.best_score > fixed_wrong.best_score + 2.0,
        "per-sample {} vs wrong fixed camera {}",
        free.best_score,
        fixed_wrong.best_score
    );
    // The chamfer score does not use the problem camera at all then: the same fit.
    assert_eq!(free, free_right);
    let space = c.model.space(Gender::Male);
    let height = |v: &[[f32; 3]]| {
        let (lo, hi) = v.iter().fold((f32::MAX, f32::MIN), |(lo, hi), p| (lo.min(p[1]), hi.max(p[1])));
        (hi - lo) as f64
    };
    let (h_true, h_fit) = (height(&c.truth.vertices), height(&space.synthesize(&free.weights).unwrap().vertices));
    // The size comes from the shape alone (1.785 m for 1.872 m when this was written).
    assert!((h_fit / h_true - 1.0).abs() < 0.06, "height {h_fit:.3} m vs truth {h_true:.3} m");
    let one_thread = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap();
    assert_eq!(one_thread.install(|| fit_shape(&off, &o, &mut |_| true)).unwrap(), free, "deterministic on 1 thread");
    // Without 2-D joints the problem's camera is used.
    let no_joints = FitProblem { joints2d: None, ..off };
    let o0 = FitOptions { joint_weight: 0.0, ..o.clone() };
    assert_eq!(
        fit_shape(&no_joints, &o0, &mut |_| true).unwrap(),
        fit_shape(&no_joints, &FitOptions { joint_weight: 0.0, ..options() }, &mut |_| true).unwrap()
    );
}

#[test]
fn bone_factors_find_long_legs() {
    use sketchbody::body::proportions::{apply_proportions, Proportions};
    let c = case();
    let props = Proportions { legs: 1.2, ..Proportions::default() };
    let (v, j) = apply_proportions(&c.truth.vertices, &c.truth.joints, c.model.skin_weights(), &props).unwrap();
    let camera = WeakPerspective { sx: 90.0, sy: 90.0, ..c.camera };
    let mut raster = Rasterizer::new();
    raster.rasterize(&v, &c.model.triangles(), &camera, 256, 256, false).unwrap();
    let drawing: Vec<u8> = raster.mask().iter().map(|&m| if m != 0 { 40 } else { 235 }).collect();
    let edges = canny(&GrayImage::from_vec(256, 256, drawing).unwrap().view(), &CannyParams::default()).unwrap();
    let j2 = Joints2 {
        xy: std::array::from_fn(|k| camera.project(&nalgebra::Vector3::from(j[k]))),
        visible: [true; NUM_JOINTS],
    };
    let problem = FitProblem {
        model: &c.model,
        gender: Gender::Male.into(),
        pose: &j,
        camera: &camera,
        edges: &edges,
        joints2d: Some(&j2),
        views: &[],
    };
    let o = FitOptions {
        sample_camera: true,
        proportion_sd: 0.2,
        temperature: 0.1,
        samples: 128,
        max_iterations: 8,
        ..options()
    };
    let r = fit_shape(&problem, &o, &mut |_| true).unwrap();
    let p = r.proportions.expect("factors searched");
    // The long legs pull the leg factor up, more than any other (with the prior at 1 legs
    // 1.047 when written: the PCA shape takes part of the length, and the prior pulls toward 1).
    let others = [p.arms, p.shoulders, p.head, p.torso];
    assert!(p.legs > 1.02 && others.iter().all(|&f| f < p.legs), "{p:?}");
    let plain = fit_shape(&problem, &FitOptions { proportion_sd: 0.0, ..o.clone() }, &mut |_| true).unwrap();
    assert!((p.arms - 1.0).abs() < 0.1 && (p.torso - 1.0).abs() < 0.1, "{p:?}");
    assert_eq!(r.weights.len(), c.model.space(Gender::Male).default_dim());
    let one_thread = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap();
    assert_eq!(one_thread.install(|| fit_shape(&problem, &o, &mut |_| true)).unwrap(), r);
    assert_eq!(plain.proportions, None);
    assert_eq!(plain.proportion_estimate, None);
    // The closed-form estimate from the 2-D bone lengths finds the long legs (relative to the
    // male mean skeleton, so this body's own bone lengths add to the error: 1.121 when
    // written), and centring the prior on it brings the fitted leg factor nearer the truth than
    // the prior at 1 does (1.105 vs 1.047).
    let e = r.proportion_estimate.expect("estimated from the 2-D joints");
    assert!((e.legs - 1.2).abs() < 0.1 && [e.arms, e.shoulders, e.head, e.torso].iter().all(|&f| f < e.legs), "{e:?}");
    let at_one = fit_shape(&problem, &FitOptions { estimate_proportions: false, ..o.clone() }, &mut |_| true).unwrap();
    assert_eq!(at_one.proportion_estimate, None);
    let p1 = at_one.proportions.expect("factors searched");
    assert!((p.legs - 1.2).abs() < (p1.legs - 1.2).abs(), "{p:?} vs {p1:?}");
    assert!(matches!(
        fit_shape(&problem, &FitOptions { proportion_sd: 0.6, ..o.clone() }, &mut |_| true),
        Err(Error::OutOfRange { name: "proportion sd", .. })
    ));
}

/// The clothing-robust chamfer: a silhouette well inside a closed outline (a body under a coat)
/// costs at most the inside cap, one crossing the outline the full distance.
#[test]
fn inside_cap_limits_the_pull_of_an_outline_around_the_silhouette() {
    use sketchbody::fit::{MatchScore, SketchEvidence, CHAMFER_CAP};
    let (w, h) = (64, 64);
    let mut edges = vec![0u8; w * h];
    for i in 8..56 {
        for (x, y) in [(i, 8), (i, 55), (8, i), (55, i)] {
            edges[y * w + x] = 255;
        }
    }
    let edges = GrayImage::from_vec(w, h, edges).unwrap();
    let square = |lo: usize, hi: usize| -> Vec<u8> {
        (0..w * h).map(|i| ((lo..hi).contains(&(i % w)) && (lo..hi).contains(&(i / w))) as u8).collect()
    };
    let plain = SketchEvidence::new(&edges, w, h, &[[32.0, 32.0]]).unwrap();
    let robust = SketchEvidence::new(&edges, w, h, &[[32.0, 32.0]]).unwrap().with_inside_cap(4.0);
    let inner = square(24, 40); // boundary 16 px inside the outline
    let outer = square(0, 64); // boundary on the image border, outside the outline
    assert_eq!(plain.score(&inner, MatchScore::Chamfer), -(CHAMFER_CAP as f64));
    assert_eq!(robust.score(&inner, MatchScore::Chamfer), -4.0);
    assert!(robust.score(&outer, MatchScore::Chamfer) < -4.0);
    assert_eq!(robust.score(&outer, MatchScore::Chamfer), plain.score(&outer, MatchScore::Chamfer));
    assert_eq!(robust.edge_support(&inner, Some([0, 0, w - 1, h - 1]), 2.0), 0.0);
    assert_eq!(robust.edge_support(&square(9, 55), Some([0, 0, w - 1, h - 1]), 2.0), 1.0);
}

#[test]
fn the_population_starts_wide_and_halves_down_to_the_samples() {
    let c = case();
    let problem = male_problem(&c);
    let o = |initial_factor: usize| FitOptions {
        samples: 8,
        initial_factor,
        max_iterations: 4,
        tolerance: 1e-12,
        raster_max_side: 64,
        ..FitOptions::default()
    };
    let run = |f: usize| fit_shape(&problem, &o(f), &mut |_| true);
    assert_eq!(run(4).unwrap().evaluations, 32 + 16 + 8 + 8, "4 × 8, halved each iteration down to 8");
    assert_eq!(run(1).unwrap().evaluations, 4 * 8, "a flat population");
    assert_ne!(run(4).unwrap().weights, run(1).unwrap().weights, "the schedule changes the search");
    for bad in [0, 65] {
        assert!(matches!(run(bad), Err(Error::OutOfRange { name: "initial factor", .. })), "{bad}");
    }
}

/// `score_shapes` scores shapes as the fit scores its samples: the body the outline was drawn
/// from above the mean shape, the same shape the same score twice; a shape of another length or
/// with a non-finite weight is an error.
#[test]
fn score_shapes_ranks_the_drawn_body_above_the_mean() {
    let c = case();
    let space = c.model.space(Gender::Male);
    let dims = space.default_dim();
    let truth = space.project(&c.truth.vertices, dims).unwrap();
    let (p, o) = (male_problem(&c), options());
    let s = score_shapes(&p, &o, dims, &[vec![0.0; dims], truth.clone(), truth.clone()]).unwrap();
    assert!(s[1] > s[0], "the drawn body {} against the mean {}", s[1], s[0]);
    assert_eq!(s[1], s[2]);
    assert!(matches!(score_shapes(&p, &o, dims, &[vec![0.0; dims + 1]]), Err(Error::OutOfRange { .. })));
    let mut nan = truth;
    nan[0] = f64::NAN;
    assert!(matches!(score_shapes(&p, &o, dims, &[nan]), Err(Error::NonFinite { .. })));
}
