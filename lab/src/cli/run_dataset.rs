//! `sketchbody-lab run-dataset DATASET --out RESULTS [--gender truth|auto|f|m] [--mean-shape] ...`:
//! the pipeline on every sample of a synthetic-sketch dataset with the sample's ground-truth
//! 2-D joints (the user-correction path), writing the results layout `sketchbody-lab eval` reads
//! (docs/dataset.md): `STEM.json` (joints2d, joints3d = the fitted mesh's posed joints,
//! camera_r, gender, scores, fit_height_m / height_m), `STEM_rest.obj`, `STEM_posed.obj`, each
//! atomically, the posed OBJ last. Samples whose `STEM_posed.obj` exists are skipped
//! (resumable). Samples run in parallel (rayon); each fit's seed is the same `--seed`, so
//! results do not depend on the thread count or the order. Ground-truth joints outside the
//! image are marked missing. With `--views side[,back]` each sample is fitted as a turnaround:
//! the dataset's extra views of those labels (the truth's `views` list, e.g. from
//! `VIEWS=side scripts/make-blender-set.sh`) join the front view, each with its true joints (or
//! the detector's with `--detect`); STEM.json then also lists each view's residual, scale and
//! outline support and the run's view warnings.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;
use std::time::Instant;

use rayon::prelude::*;
use serde_json::json;
use sketchbody::body::{BodyModel, Gender};
use sketchbody::detect::figure::{Backend, FigureOptions};
use sketchbody::detect::landmark::LandmarkNet;
use sketchbody::detect::Model;
use sketchbody::export::obj::write_obj;
use sketchbody::fsutil::write_atomic;
use sketchbody::image::load_image;
use sketchbody::pipeline::{run_pipeline_views, FigureJoints, GivenJoints, JointsSource, PipelineOptions, ViewInput};
use sketchbody::pose::{dict_io, Dictionary, PoseEstimate};
use sketchbody::render::sketch::truth::GroundTruth;
use sketchbody::skeleton::{Joints2, Joints3, NUM_JOINTS};
use sketchbody::view::ViewLabel;
use sketchbody_lab::eval::score::dataset_samples;

use sketchbody_cli::fit_args::{score_name, FitArgs};
use sketchbody_cli::run::{catch_interrupt, parse_gender, INTERRUPTED};
use sketchbody_cli::CliError;

/// Arguments of `sketchbody-lab run-dataset`.
#[derive(clap::Args)]
pub struct Args {
    /// Dataset folder (from make-dataset).
    dataset: PathBuf,
    /// Results folder (created when missing).
    #[arg(long)]
    out: PathBuf,
    /// Gender: truth (the sample's, as a user would say), auto (fit both, choose by score), f or m.
    #[arg(long, default_value = "truth")]
    gender: String,
    /// The mean-shape baseline: the gender's mean shape posed the same way (no fit).
    #[arg(long)]
    mean_shape: bool,
    /// Take the 2-D joints from the embedded single-figure detector instead of the ground truth,
    /// as `run` without `--joints` does (measures what detection costs the fit).
    #[arg(long)]
    detect: bool,
    /// Detector backend with --detect: auto (the default of `run`), fmp (the sketch model) or
    /// blazepose.
    #[arg(long, default_value = "auto", value_parser = sketchbody_cli::detect::parse_backend, requires = "detect")]
    detector: Backend,
    /// Give the fit each sample's true rest height (`height_m` of the ground truth), as an
    /// artist with a character sheet would: measures the fit when the size is known.
    #[arg(long, conflicts_with = "height")]
    true_height: bool,
    /// Diagnostic only: skip the pose solver and use the ground-truth 3-D pose and camera of
    /// each sample (shows what the fit reaches when the pose is right; not a pipeline result).
    #[arg(long)]
    oracle_pose: bool,
    #[command(flatten)]
    fit: FitArgs,
    /// Pose dictionary file for the 3-D pose step (default: the embedded one; e.g. one learned
    /// without the dataset's motion, to fit as on motion the pose step has not seen).
    #[arg(long)]
    dictionary: Option<PathBuf>,
    /// Only the first N samples (sorted by name).
    #[arg(long)]
    first: Option<usize>,
    /// Worker threads (default: all cores).
    #[arg(long)]
    threads: Option<usize>,
    /// Fit each sample as a turnaround with the dataset's extra views of these labels
    /// (comma-separated: side, side_left, back); a sample without one of them fails.
    #[arg(long, value_delimiter = ',', value_parser = parse_view_label)]
    views: Vec<ViewLabel>,
    /// Diagnostic (issue 47): also score, as the fit scores its samples, N + 1 shapes along the
    /// line from the fitted gender's mean shape (0) to the true rest mesh's projection onto the
    /// fitted dimensions (1), and the fit's own weights; written as `score_line` and
    /// `score_line_fit` (bone-length factors left at 1 for all of them).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=100))]
    score_line: Option<u32>,
}

fn parse_view_label(s: &str) -> Result<ViewLabel, String> {
    match ViewLabel::parse(s) {
        Ok(ViewLabel::Front) => Err("the front view is the sample's own image".into()),
        Ok(l) => Ok(l),
        Err(e) => Err(e.to_string()),
    }
}

enum GenderMode {
    Truth,
    Auto,
    Fixed(Gender),
}

/// Ground-truth joints of a sample; joints outside the image are marked missing.
fn truth_joints(t: &GroundTruth) -> Joints2 {
    image_joints(&t.joints2d, t.width, t.height)
}

/// `xy` as joints, those outside a `w`×`h` image marked missing.
fn image_joints(xy: &[[f64; 2]], w: usize, h: usize) -> Joints2 {
    let mut j = Joints2 { xy: [[0.0; 2]; NUM_JOINTS], visible: [true; NUM_JOINTS] };
    for k in 0..NUM_JOINTS {
        j.xy[k] = xy[k];
        let [x, y] = j.xy[k];
        j.visible[k] = (0.0..=w as f64).contains(&x) && (0.0..=h as f64).contains(&y);
    }
    j
}

struct Shared<'a> {
    model: &'a BodyModel,
    dict: &'a Dictionary,
    base: PipelineOptions,
    mode: GenderMode,
    /// The sketch model, the landmark network and the figure options when the joints come from
    /// detection.
    detector: Option<(Model, LandmarkNet, FigureOptions)>,
    /// `--true-height`.
    true_height: bool,
    /// `--oracle-pose`.
    oracle_pose: bool,
    /// `--views`.
    views: Vec<ViewLabel>,
    /// `--score-line`.
    score_line: Option<u32>,
}

/// The ground truth's 3-D pose and camera as a pose estimate (for `--oracle-pose`).
fn truth_pose(t: &GroundTruth, stem: &str) -> Result<PoseEstimate, CliError> {
    let joints: Joints3 = t
        .joints3d
        .as_slice()
        .try_into()
        .map_err(|_| CliError(format!("sample {stem}: joints3d must hold {NUM_JOINTS} joints")))?;
    Ok(PoseEstimate {
        joints,
        camera: t.camera.to_camera()?,
        bases: Vec::new(),
        weights: Vec::new(),
        rms: 0.0,
        length_excess: 0.0,
        base: joints,
        base_parts: None,
        factors: sketchbody::pose::figure::BodyFactors::default(),
        plausible: true,
        alternatives: Vec::new(),
        depth_costs: None,
    })
}

/// `--score-line`: the fit's score of `n + 1` shapes from the fitted gender's mean shape to the
/// truth's projection onto the fitted dimensions, under the result's pose, camera, edges and
/// joints, and the score of the fit's own weights. Errors: a blended fit (no single gender's
/// space), the mesh file's, the fit's.
fn score_line(
    model: &sketchbody::body::BodyModel,
    dataset: &Path,
    stem: &str,
    r: &sketchbody::pipeline::PipelineResult,
    fit: &sketchbody::fit::FitOptions,
    n: u32,
) -> Result<(Vec<(f64, f64)>, f64), CliError> {
    let sketchbody::body::ShapeChoice::Gendered(gender) = r.space else {
        return Err(CliError(format!("sample {stem}: --score-line needs a gendered fit")));
    };
    let mp = dataset.join(format!("{stem}.mesh"));
    let bytes = std::fs::read(&mp).map_err(|e| CliError(format!("{}: {e}", mp.display())))?;
    let rest = sketchbody::render::sketch::truth::parse_mesh(&bytes, &mp.display().to_string())?.0;
    let space = model.space(gender);
    let dims = fit.dims.unwrap_or(space.gmm().dims());
    let truth = space.project(&rest, dims)?;
    let problem = sketchbody::fit::FitProblem {
        model,
        gender: r.space,
        pose: &r.pose.joints,
        camera: &r.pose.camera,
        edges: &r.edges,
        joints2d: Some(&r.joints2d),
        views: &[],
    };
    let ts: Vec<f64> = (0..=n).map(|k| k as f64 / n as f64).collect();
    let mut shapes: Vec<Vec<f64>> = ts.iter().map(|t| truth.iter().map(|w| t * w).collect()).collect();
    let fitted = r.chosen_fit().and_then(|g| g.fit.as_ref()).map(|f| f.weights.clone());
    shapes.push(fitted.unwrap_or_else(|| vec![0.0; dims]));
    let scores = sketchbody::fit::score_shapes(&problem, fit, dims, &shapes)
        .map_err(|e| CliError(format!("sample {stem}: score line: {e}")))?;
    Ok((ts.into_iter().zip(scores.iter().copied()).collect(), scores[scores.len() - 1]))
}

/// Runs one sample and writes its three files. Returns the pipeline's seconds.
fn one(s: &Shared, dataset: &Path, out: &Path, stem: &str) -> Result<f64, CliError> {
    let jp = dataset.join(format!("{stem}.json"));
    let text = std::fs::read_to_string(&jp).map_err(|e| CliError(format!("{}: {e}", jp.display())))?;
    let truth = GroundTruth::from_json(&text, &jp.display().to_string())?;
    let sketch = load_image(&dataset.join(format!("{stem}.png")))?;
    let gender = match s.mode {
        GenderMode::Truth => Some(Gender::parse(&truth.gender)?),
        GenderMode::Auto => None,
        GenderMode::Fixed(g) => Some(g),
    };
    let mut opts = PipelineOptions { gender, ..s.base.clone() };
    if s.true_height {
        opts.fit.height = Some(truth.height_m);
    }
    if s.oracle_pose {
        opts.given_pose = Some(truth_pose(&truth, stem)?);
    }
    let source_of = |j: Joints2| -> Box<dyn JointsSource + '_> {
        match &s.detector {
            Some((model, net, options)) => Box::new(FigureJoints { model, net, options, colour: None }),
            None => Box::new(GivenJoints(j)),
        }
    };
    let source = source_of(truth_joints(&truth));
    let mut view_images = Vec::with_capacity(s.views.len());
    for &label in &s.views {
        let v = truth.views.iter().find(|v| v.label == label.name()).ok_or_else(|| {
            CliError(format!(
                "sample {stem}: no {} view in its truth (render with VIEWS={})",
                label.name(),
                label.name()
            ))
        })?;
        let img = load_image(&dataset.join(&v.image))?;
        let joints = image_joints(&v.joints2d, img.width(), img.height());
        view_images.push((label, img, source_of(joints)));
    }
    let views: Vec<ViewInput> = view_images
        .iter()
        .map(|(label, img, src)| ViewInput { label: *label, sketch: img, source: src.as_ref() })
        .collect();
    let r = run_pipeline_views(
        s.model,
        s.dict,
        &sketch,
        source.as_ref(),
        &views,
        &opts,
        &mut |_| !INTERRUPTED.load(Ordering::SeqCst),
        None,
    )
    .map_err(|e| CliError(format!("sample {stem}: {e}")))?;
    let rm = r.pose.camera.r;
    let finite = |x: f64| json!(if x.is_finite() { Some(x) } else { None });
    let line = match s.score_line {
        Some(n) => Some(score_line(s.model, dataset, stem, &r, &opts.fit, n)?),
        None => None,
    };
    // One score per fitted space: the deciding fit's when the chosen gender was refitted.
    let mut scores = serde_json::Map::new();
    for g in &r.fits {
        scores.entry(g.space.name()).or_insert_with(|| finite(g.score));
    }
    let doc = json!({
        "joints2d": r.joints2d.xy,
        "joints3d": r.posed_joints,
        "camera_r": [[rm[(0, 0)], rm[(0, 1)], rm[(0, 2)]], [rm[(1, 0)], rm[(1, 1)], rm[(1, 2)]], [rm[(2, 0)], rm[(2, 1)], rm[(2, 2)]]],
        "gender": r.gender.name(),
        "gender_fitted": r.gender_fitted,
        "gender_value": r.gender_value,
        "gender_confidence": r.gender_confidence,
        "male_prior": r.male_prior,
        "gender_features": r.gender_evidence.features.values,
        "gender_evidence_male_probability": r.gender_evidence.male_probability,
        "edge_support": if r.edge_support.is_finite() { Some(r.edge_support) } else { None },
        "part_support": r.part_support.map(|p| {
            sketchbody::fit::BodyPart::ALL.iter().map(|&b| (b.name().to_string(), json!(p.of(b)))).collect::<serde_json::Map<_, _>>()
        }),
        "low_evidence": r.low_evidence,
        "scores": scores,
        "fit_iteration_best": r.fits.iter().map(|g| json!({
            "space": g.space.name(),
            "best": g.fit.as_ref().map(|f| f.history.iter().map(|i| finite(i.best_score)).collect::<Vec<_>>()),
        })).collect::<Vec<_>>(),
        "score": finite(r.score),
        "shape_weights": r.weights,
        "fit_shape_weights": r.chosen_fit().and_then(|g| g.fit.as_ref()).map(|f| &f.weights),
        "fit_height_m": r.fit_height,
        "height_m": r.mesh.height(),
        "proportions": r.chosen_fit().and_then(|g| g.fit.as_ref()).and_then(|f| f.proportions),
        "proportion_estimate": r.chosen_fit().and_then(|g| g.fit.as_ref()).and_then(|f| f.proportion_estimate),
        "landmark_depth": r.detection.as_ref().map(|f| f.landmark_depth),
        "pose_joints3d": r.pose.joints,
        "views": r.views.iter().map(|v| json!({
            "label": v.label.name(), "residual": v.residual, "scale_ratio": v.scale_ratio,
            "edge_support": finite(v.edge_support),
            "facing": v.facing.map(|f| json!({"as_labelled_deg": f.as_labelled_deg, "other_side_deg": f.other_side_deg})),
        })).collect::<Vec<_>>(),
        "view_warnings": r.view_warnings,
        "score_line": line.as_ref().map(|(l, _)| l.iter().map(|&(t, v)| json!({"t": t, "score": finite(v)})).collect::<Vec<_>>()),
        "score_line_fit": line.as_ref().map(|(_, f)| finite(*f)),
        "seconds": r.timings.total,
    });
    write_atomic(&out.join(format!("{stem}.json")), doc.to_string().as_bytes())?;
    write_obj(&out.join(format!("{stem}_rest.obj")), &r.mesh.vertices, &r.mesh.quads, None)?;
    write_obj(&out.join(format!("{stem}_posed.obj")), &r.posed_vertices, &r.mesh.quads, None)?;
    Ok(r.timings.total)
}

/// Runs the command.
pub fn run(a: Args) -> Result<(), CliError> {
    let fit = a.fit.options()?;
    let mode = match a.gender.as_str() {
        "truth" => GenderMode::Truth,
        "auto" => GenderMode::Auto,
        g => GenderMode::Fixed(parse_gender(Some(g))?.ok_or_else(|| CliError("--gender: missing".into()))?),
    };
    if a.mean_shape && matches!(mode, GenderMode::Auto) {
        return Err(CliError("--mean-shape needs --gender truth, f or m (there is no score to choose by)".into()));
    }
    let mut stems = dataset_samples(&a.dataset)?;
    if stems.is_empty() {
        return Err(CliError(format!("{}: no samples (STEM.json + STEM.mesh) found", a.dataset.display())));
    }
    stems.truncate(a.first.unwrap_or(usize::MAX));
    std::fs::create_dir_all(&a.out)
        .map_err(|e| CliError(format!("{}: cannot create the results folder: {e}", a.out.display())))?;
    let manifest = json!({
        "format": "sketchbody-run-dataset-1", "dataset": a.dataset.display().to_string(), "samples": stems.len(),
        "gender": a.gender, "dictionary": a.dictionary.as_ref().map(|p| p.display().to_string()), "mean_shape": a.mean_shape, "detector": if a.detect { Some(a.detector.name()) } else { None }, "depth_hint": a.fit.depth_hint, "depth_prior": a.fit.depth_prior, "detected_joint_weight_scale": a.fit.detected_joint_weight_scale, "detected_proportions": a.fit.detected_proportions, "landmark_pose": a.fit.landmark_pose, "detected_classifier_gender": a.fit.detected_classifier_gender, "gender_evidence": a.fit.gender_evidence, "classify_gender": a.fit.classify_gender, "gender_decision_dims": a.fit.gender_decision_dims, "gender_decision_seeds": a.fit.gender_decision_seeds, "gender_decision_samples": a.fit.gender_decision_samples, "gender_decision_iterations": a.fit.gender_decision_iterations, "calibrate_fit": a.fit.calibrate_fit, "male_prior": a.fit.male_prior, "score": score_name(fit.score), "seed": fit.seed, "initial_factor": fit.initial_factor,
        "fit_samples": fit.samples, "iterations": fit.max_iterations, "transition_scale": fit.transition_scale,
        "temperature": fit.temperature, "joint_weight": fit.joint_weight, "sample_camera": fit.sample_camera, "proportion_sd": fit.proportion_sd, "estimate_proportions": fit.estimate_proportions, "height": fit.height, "true_height": a.true_height, "oracle_pose": a.oracle_pose, "views": a.views.iter().map(|v| v.name()).collect::<Vec<_>>(), "keep_pose_scale": a.fit.keep_pose_scale, "raster_side": fit.raster_max_side, "tolerance": fit.tolerance, "version": sketchbody::VERSION,
    });
    write_atomic(&a.out.join("run.json"), manifest.to_string().as_bytes())?;
    let model = BodyModel::embedded()?;
    let dict = match &a.dictionary {
        Some(p) => dict_io::read(p)?,
        None => dict_io::embedded()?,
    };
    let detector = if a.detect {
        let options = FigureOptions { backend: a.detector, ..FigureOptions::default() };
        Some((Model::embedded()?, LandmarkNet::embedded()?, options))
    } else {
        None
    };
    let shared = Shared {
        model: &model,
        dict: &dict,
        base: a.fit.pipeline_options(fit, a.mean_shape),
        mode,
        detector,
        true_height: a.true_height,
        oracle_pose: a.oracle_pose,
        views: a.views.clone(),
        score_line: a.score_line,
    };
    let todo: Vec<&String> = stems.iter().filter(|s| !a.out.join(format!("{s}_posed.obj")).is_file()).collect();
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(a.threads.unwrap_or(0))
        .build()
        .map_err(|e| CliError(format!("thread pool: {e}")))?;
    catch_interrupt();
    let done = AtomicUsize::new(0);
    let failures = Mutex::new(Vec::new());
    let seconds = Mutex::new(Vec::new());
    let t0 = Instant::now();
    let bar = Mutex::new(sketchbody_cli::run::Bar::new(false));
    pool.install(|| {
        todo.par_iter().for_each(|stem| {
            if INTERRUPTED.load(Ordering::SeqCst) {
                return;
            }
            match one(&shared, &a.dataset, &a.out, stem) {
                Ok(s) => seconds.lock().unwrap_or_else(|p| p.into_inner()).push(s),
                Err(CliError(m)) => failures.lock().unwrap_or_else(|p| p.into_inner()).push(m),
            }
            let n = done.fetch_add(1, Ordering::Relaxed) + 1;
            bar.lock().unwrap_or_else(|p| p.into_inner()).update(n as f32 / todo.len().max(1) as f32);
        })
    });
    bar.lock().unwrap_or_else(|p| p.into_inner()).finish();
    let failures = failures.into_inner().unwrap_or_else(|p| p.into_inner());
    for f in &failures {
        eprintln!("sketchbody: {f}");
    }
    if INTERRUPTED.load(Ordering::SeqCst) {
        return Err(CliError(format!(
            "interrupted after {} of {} samples (rerun to resume)",
            done.load(Ordering::Relaxed),
            todo.len()
        )));
    }
    let mut secs = seconds.into_inner().unwrap_or_else(|p| p.into_inner());
    secs.sort_by(f64::total_cmp);
    let median = if secs.is_empty() { f64::NAN } else { secs[secs.len() / 2] };
    println!(
        "{}: {} samples run, {} already done, {} failed; {:.1} s ({} threads), median pipeline {:.2} s per sample",
        a.out.display(),
        todo.len() - failures.len(),
        stems.len() - todo.len(),
        failures.len(),
        t0.elapsed().as_secs_f64(),
        pool.current_num_threads(),
        median
    );
    if failures.is_empty() {
        Ok(())
    } else {
        Err(CliError(format!("{} of {} samples failed (listed above)", failures.len(), todo.len())))
    }
}
