//! `sketchbody run SKETCH --out DIR [--joints JOINTS.json] [--gender m|f] ...`: the main job.
//! A turnaround adds its other views: `--view side=SIDE.png [--view-joints side=SIDE.json]
//! [--view back=BACK.png ...]` (one body and one pose from every view; SKETCH is the front view),
//! or the whole sheet in one image: `--sheet [--views front,side,back]` (module `sheet`).
//! Edges → 2-D joints → 3-D pose and camera → shape fit, then every output is written into a
//! staging folder and moved into DIR together (`fsutil::StagingDir`): a failed, cancelled or
//! interrupted (Ctrl-C) run leaves no file of its own in DIR.
//!
//! Files: `body.glb` (one scene: the rest mesh on MakeHuman's 53-bone rig, posed, with a
//! one-frame clip and the sketch as its texture; `--format` adds or replaces it with `body.fbx`
//! and `body.usda`, the same rigged body, in the unit and up axis of `--units` and `--up`),
//! `body.obj` (posed mesh), `body_rest.obj`,
//! `body.mtl` + `body_texture.png` (the texture, unless `--no-texture`), `joints2d.json`
//! (sketchbody-joints2d), `pose3d.json` (sketchbody-pose3d: 3-D joints and camera),
//! `overlay.png`, `preview.png` (sketch, body through the camera, blend, front, side),
//! `report.md`; with views also `overlay_LABEL.png`, `preview_LABEL.png` (that view's sketch,
//! the body through its camera, the blend, the body's front and side) and `joints2d_LABEL.json`
//! per view.

use std::fmt::Write as _;
use std::io::Write as _;
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

use sketchbody::body::rig::RigScene;
use sketchbody::body::{BodyModel, Gender};
use sketchbody::detect::figure::{Backend, FigureOptions};
use sketchbody::detect::landmark::LandmarkNet;
use sketchbody::detect::Model;
use sketchbody::export::frame::{ExportFrame, Units, UpAxis};
use sketchbody::export::joints2d::{load_joints2d, write_joints2d_with, LOW_CONFIDENCE_HINT};
use sketchbody::export::obj::{mtl_string, write_obj_with_material};
use sketchbody::export::pose3d::pose3d_json;
use sketchbody::export::texture::{check_texture_size, project_sketch};
use sketchbody::fsutil::{write_atomic, StagingDir};
use sketchbody::image::{encode_png, load_rgb_image, save_png, to_gray};
use sketchbody::pipeline::overlay::overlay;
use sketchbody::pipeline::shape_keys::shape_keys;
use sketchbody::pipeline::{
    run_pipeline_views, FigureJoints, GivenJoints, InterimBody, InterimStage, JointsSource, PipelineOptions,
    PipelineResult, ViewInput,
};
use sketchbody::pose::dict_io;
use sketchbody::render::preview::{compare_layout, compare_preview, SurfaceTexture};
use sketchbody::skeleton::Joints2;
use sketchbody::view::ViewLabel;

use crate::detect::NO_FIGURE_HINT;
use crate::export_formats::{file_list, write_rigged, Format};
use crate::fit_args::{score_name, FitArgs};
use crate::rig_args::RigArgs;
use crate::{release_free_memory, CliError};

/// Arguments of `sketchbody run`.
#[derive(clap::Args)]
pub struct Args {
    /// The sketch (PNG or JPEG; colour is converted to gray).
    sketch: PathBuf,
    /// Output folder (created when missing; existing files of the same names are replaced).
    #[arg(long)]
    out: PathBuf,
    /// 2-D joints of the figure (sketchbody-joints2d JSON; the user-correction path). When
    /// omitted, the embedded detector finds them (see --detector).
    #[arg(long)]
    joints: Option<PathBuf>,
    /// Detector backend without --joints: auto (the sketch model and BlazePose, one candidate per
    /// image: on a drawing the sketch model recognises, the one whose proportions the 3-D pose
    /// step finds nearer a body's, else the higher calibrated confidence), fmp (the sketch
    /// model), blazepose.
    #[arg(long, default_value = "auto", value_parser = crate::detect::parse_backend)]
    detector: Backend,
    /// Hard detection thresholds: "no figure" unless a backend passes its own threshold (default:
    /// the best figure whenever the image plausibly holds one).
    #[arg(long)]
    strict_detection: bool,
    /// With both detector backends (auto): each joint the two put within this fraction of the
    /// figure's size of each other becomes their mean (0 = keep the chosen backend's joints).
    #[arg(long, default_value_t = sketchbody::detect::figure::AVERAGE_AGREEMENT, value_parser = crate::detect::parse_fraction)]
    average_agreement: f64,
    /// Shape space: f or m; both are fitted and the better score is kept when omitted.
    #[arg(long)]
    gender: Option<String>,
    /// Skip the fit: the gender's mean shape posed the same way (baseline; needs --gender).
    #[arg(long)]
    mean_shape: bool,
    #[command(flatten)]
    fit: FitArgs,
    #[command(flatten)]
    rig: RigArgs,
    /// Rigged-body files to write, comma-separated: glb (body.glb), fbx (body.fbx, binary FBX
    /// 7.4), usd (body.usda, UsdSkel).
    #[arg(long, value_enum, value_delimiter = ',', default_value = "glb")]
    format: Vec<Format>,
    /// Length unit of body.fbx and body.usda: m (metres) or cm (centimetres). body.glb is always
    /// in metres (glTF's specification).
    #[arg(long, default_value = "m", value_parser = crate::export_formats::parse_units)]
    units: Units,
    /// Up axis of body.fbx and body.usda: y (Y up, the body facing +Z) or z (Z up, the body
    /// facing -Y, as Blender, 3ds Max and Unreal). body.glb is always Y up (glTF's
    /// specification).
    #[arg(long, default_value = "y", value_parser = crate::export_formats::parse_up)]
    up: UpAxis,
    /// No texture: the GLB gets a plain skin colour and the OBJs no material.
    #[arg(long)]
    no_texture: bool,
    /// Side of the texture projected from the sketch, texels (1..=4096).
    #[arg(long, default_value_t = sketchbody::export::texture::DEFAULT_TEXTURE_SIZE, value_parser = crate::ranges::count(1..=4096))]
    texture_size: usize,
    /// Height of the preview's panels, pixels (1..=16384; lowered when the preview would be over
    /// 16384 px wide or a panel over 4096 px).
    #[arg(long, default_value_t = 512, value_parser = crate::ranges::count(1..=16384))]
    preview_size: usize,
    /// No progress bar.
    #[arg(long)]
    quiet: bool,
    /// Another view of the same character in the same pose (a turnaround), as LABEL=IMAGE with
    /// LABEL side (turned +90°: the character's right side, facing image right), side_left
    /// (turned −90°: the character's left side, facing image left) or back; SKETCH is the front
    /// view. Repeat for several views.
    #[arg(long = "view", value_name = "LABEL=IMAGE")]
    views: Vec<String>,
    /// 2-D joints of a view, as LABEL=JOINTS.json (sketchbody-joints2d); a view without them gets
    /// the detector's.
    #[arg(long = "view-joints", value_name = "LABEL=JSON")]
    view_joints: Vec<String>,
    /// SKETCH is a model sheet: its figures side by side (left to right, blank space between
    /// them) are the views of one character in one pose. Each figure's view is the detector's
    /// reading of its facing, or the labels of --views; --joints (the front figure's) and
    /// --view-joints files are in the sheet's pixels.
    #[arg(long, conflicts_with = "views")]
    sheet: bool,
    /// The views of a --sheet's figures in reading order, as front,side,back (labels front, side,
    /// side_left, back).
    #[arg(long = "views", value_name = "LABELS", requires = "sheet")]
    sheet_views: Option<String>,
}

/// One `--view` of the command line with its `--view-joints`.
struct ViewArg {
    label: ViewLabel,
    image: PathBuf,
    joints: Option<PathBuf>,
}

/// Splits `LABEL=PATH` of `flag`. Errors: no `=`, an unknown label, the front label.
fn labelled(flag: &str, text: &str) -> Result<(ViewLabel, PathBuf), CliError> {
    let Some((label, path)) = text.split_once('=') else {
        return Err(CliError(format!(
            "{flag} {text}: a view needs its label, as side=FILE, side_left=FILE or back=FILE (the front view is \
             the main sketch)"
        )));
    };
    let label = ViewLabel::parse(label).map_err(|e| CliError(format!("{flag} {text}: {e}")))?;
    if label == ViewLabel::Front {
        return Err(CliError(format!(
            "{flag} {text}: the front view is the main sketch; extra views are side, side_left or back"
        )));
    }
    if path.is_empty() {
        return Err(CliError(format!("{flag} {text}: no file")));
    }
    Ok((label, PathBuf::from(path)))
}

/// Parses `--view` and `--view-joints`. Errors: a bad `LABEL=PATH`, a label given twice, joints
/// for a view not given.
fn view_args(views: &[String], joints: &[String]) -> Result<Vec<ViewArg>, CliError> {
    let mut out: Vec<ViewArg> = Vec::new();
    for v in views {
        let (label, image) = labelled("--view", v)?;
        if out.iter().any(|o| o.label == label) {
            return Err(CliError(format!("--view: two {} views", label.name())));
        }
        out.push(ViewArg { label, image, joints: None });
    }
    for j in joints {
        let (label, path) = labelled("--view-joints", j)?;
        let Some(view) = out.iter_mut().find(|o| o.label == label) else {
            return Err(CliError(format!("--view-joints {j}: no --view {}=IMAGE to go with it", label.name())));
        };
        if view.joints.replace(path).is_some() {
            return Err(CliError(format!("--view-joints: two joint files for the {} view", label.name())));
        }
    }
    Ok(out)
}

/// The joints source of an image: its given joints, else the detectors on `rgb`.
fn source_for<'a>(
    joints: Option<&(String, Joints2)>,
    rgb: &'a sketchbody::image::RgbImage,
    detectors: Option<(&'a Model, &'a LandmarkNet)>,
    options: &'a FigureOptions,
) -> Result<Box<dyn JointsSource + 'a>, CliError> {
    Ok(match (joints, detectors) {
        (Some((_, j)), _) => Box::new(GivenJoints(*j)),
        (None, Some((model, net))) => Box::new(FigureJoints { model, net, options, colour: Some(rgb.view()) }),
        (None, None) => return Err(CliError("internal: the detector was not loaded".into())),
    })
}

/// A loaded view: its label, where it came from (for the report), its colour and gray images
/// and its joints file's joints (in its pixels) when given.
struct LoadedView {
    label: ViewLabel,
    image: String,
    rgb: sketchbody::image::RgbImage,
    gray: sketchbody::image::GrayImage,
    joints: Option<(String, Joints2)>,
}

/// The run's images: the front view and the extra views (`--view` files or a `--sheet`'s figures).
struct Inputs {
    front: LoadedView,
    views: Vec<LoadedView>,
}

/// Loads `--joints` or a view's joints file: its display name and joints.
fn joints_file(p: &std::path::Path) -> Result<(String, Joints2), CliError> {
    Ok((format!("`{}`", p.display()), load_joints2d(p)?))
}

/// The front sketch and the `--view` images with their joint files.
fn load_views(a: &Args) -> Result<Inputs, CliError> {
    let rgb = load_rgb_image(&a.sketch)?;
    let gray = to_gray(&rgb.view())?;
    let joints = a.joints.as_deref().map(joints_file).transpose()?;
    let front = LoadedView { label: ViewLabel::Front, image: format!("`{}`", a.sketch.display()), rgb, gray, joints };
    let views = view_args(&a.views, &a.view_joints)?
        .into_iter()
        .map(|arg| {
            let rgb = load_rgb_image(&arg.image).map_err(|e| CliError(format!("{}: {e}", arg.image.display())))?;
            let gray = to_gray(&rgb.view())?;
            let joints = arg.joints.as_deref().map(joints_file).transpose()?;
            Ok(LoadedView { label: arg.label, image: format!("`{}`", arg.image.display()), rgb, gray, joints })
        })
        .collect::<Result<_, CliError>>()?;
    Ok(Inputs { front, views })
}

/// A `--sheet`'s figures as the front view and the extra views; joint files (in the sheet's
/// pixels) moved into each figure's crop.
fn load_sheet(
    a: &Args,
    detectors: Option<(&Model, &LandmarkNet)>,
    figure_options: &FigureOptions,
    dict: &sketchbody::pose::Dictionary,
) -> Result<Inputs, CliError> {
    let sheet = load_rgb_image(&a.sketch)?;
    let labels = a.sheet_views.as_deref().map(crate::sheet::parse_views).transpose()?;
    let crops = crate::sheet::sheet_views(&a.sketch, &sheet, labels.as_deref(), detectors, figure_options, dict)?;
    let mut files: Vec<(ViewLabel, PathBuf)> = a.joints.iter().map(|p| (ViewLabel::Front, p.clone())).collect();
    for j in &a.view_joints {
        files.push(labelled("--view-joints", j)?);
    }
    let mut front = None;
    let mut views = Vec::new();
    for c in crops {
        let joints = match files.iter().find(|(l, _)| *l == c.label) {
            Some((_, p)) => {
                let (name, j) = joints_file(p)?;
                Some((format!("{name} (sheet pixels)"), c.from_sheet(&j)))
            }
            None => None,
        };
        let image = format!("`{}` ({} figure, {})", a.sketch.display(), c.label.name(), c.span());
        let gray = to_gray(&c.rgb.view())?;
        let v = LoadedView { label: c.label, image, rgb: c.rgb, gray, joints };
        if v.label == ViewLabel::Front {
            front = Some(v);
        } else {
            views.push(v);
        }
    }
    for (l, p) in &files {
        if *l != ViewLabel::Front && !views.iter().any(|v| v.label == *l) {
            return Err(CliError(format!("--view-joints {}: the sheet has no {} view", p.display(), l.name())));
        }
    }
    let front = front.ok_or_else(|| CliError(format!("{}: the sheet has no front view", a.sketch.display())))?;
    Ok(Inputs { front, views })
}

/// Set by Ctrl-C (see [`catch_interrupt`]).
pub static INTERRUPTED: AtomicBool = AtomicBool::new(false);

extern "C" fn on_sigint(_: libc::c_int) {
    INTERRUPTED.store(true, Ordering::SeqCst);
}

/// Makes Ctrl-C cancel the run (through the progress callback) instead of killing it, so the
/// staging folder is cleaned up.
pub fn catch_interrupt() {
    // SAFETY: the handler only stores to an atomic, which is async-signal-safe.
    unsafe {
        libc::signal(libc::SIGINT, on_sigint as extern "C" fn(libc::c_int) as libc::sighandler_t);
    }
}

/// A progress bar on stderr, redrawn at most every 0.1 s.
pub struct Bar {
    start: Instant,
    last: f64,
    quiet: bool,
}

impl Bar {
    /// A bar starting now; `quiet` draws nothing.
    pub fn new(quiet: bool) -> Bar {
        Bar { start: Instant::now(), last: -1.0, quiet }
    }

    /// Draws `fraction` done; returns `false` once Ctrl-C was pressed.
    pub fn update(&mut self, fraction: f32) -> bool {
        let el = self.start.elapsed().as_secs_f64();
        if !self.quiet && (el - self.last >= 0.1 || fraction >= 1.0) {
            self.last = el;
            let bar: String = (0..30).map(|k| if (k as f32) < fraction * 30.0 { '#' } else { '.' }).collect();
            eprint!("\r[{bar}] {:3.0}% {el:.1} s ", fraction * 100.0);
            let _ = std::io::stderr().flush();
        }
        !INTERRUPTED.load(Ordering::SeqCst)
    }

    /// Ends the bar's line.
    pub fn finish(&self) {
        if !self.quiet && self.last >= 0.0 {
            eprintln!();
        }
    }
}

#[allow(clippy::too_many_arguments)]
fn report(
    a: &Args,
    opts: &PipelineOptions,
    r: &PipelineResult,
    inputs: &Inputs,
    size: (usize, usize),
    firsts: &[(InterimStage, f64)],
    load_s: f64,
    write_s: f64,
) -> String {
    let mut s = String::new();
    let f = &opts.fit;
    let _ = writeln!(s, "# sketchbody run\n");
    let _ = writeln!(s, "- sketch: {} ({}×{} px)", inputs.front.image, size.0, size.1);
    let joints = inputs.front.joints.as_ref().map_or("none", |(name, _)| name.as_str());
    let _ = writeln!(s, "- 2-D joints: {joints} (source: {})", r.joints_source);
    if let Some(f) = &r.detection {
        let _ = writeln!(
            s,
            "- detection: backend {} ({} of 15 joints averaged with the other backend's, where the two agree), confidence {:.2} (expected fraction of joints within 0.2 × the figure's size), presence {:.2}, {}{}",
            f.backend.name(),
            f.averaged.iter().filter(|a| **a).count(),
            f.confidence,
            f.presence,
            sketchbody::export::joints2d::facing_summary(&f.facing),
            if f.low_confidence { format!("; **{LOW_CONFIDENCE_HINT}**") } else { String::new() }
        );
    }
    if !inputs.views.is_empty() {
        let _ = writeln!(s, "- views: {}: one body and one pose fitted to all of them", view_names(r));
        if a.sheet {
            let how = if a.sheet_views.is_some() { "as --views labels them" } else { "by the detector's facing" };
            let _ =
                writeln!(s, "- sheet: {} figures found left to right, their views named {how}", 1 + inputs.views.len());
        }
        for (v, vr) in inputs.views.iter().zip(&r.views) {
            let joints = match (&v.joints, vr.swapped) {
                (Some((name, _)), _) => name.as_str(),
                (None, true) => "detected, left and right swapped (that labelling fits the shared pose better)",
                (None, false) => "detected",
            };
            let _ = writeln!(
                s,
                "- {} view: {} ({}×{} px), 2-D joints {joints} (source: {}), drawn at {:.2}× the front view's size, \
                 joints {:.1}% of the figure's height off the shared pose, {} of the fitted outline in this view within \
                 reach of a stroke",
                vr.label.name(),
                v.image,
                v.gray.width(),
                v.gray.height(),
                vr.joints_source,
                vr.scale_ratio,
                100.0 * vr.residual,
                if vr.edge_support.is_finite() { format!("{:.0}%", 100.0 * vr.edge_support) } else { "-".into() }
            );
        }
        for w in &r.view_warnings {
            let _ = writeln!(s, "- **warning**: {w}");
        }
    }
    let _ = writeln!(s, "- library: sketchbody {}\n", sketchbody::VERSION);
    let _ = writeln!(s, "## Options\n");
    let _ = writeln!(
        s,
        "- Canny: thresholds {}/{}, aperture {}",
        opts.canny.threshold1, opts.canny.threshold2, opts.canny.aperture
    );
    let p = &opts.pose;
    let _ = writeln!(
        s,
        "- pose: κ {}, α {}, ≤ {} bases, tolerance {} px, refine {}, prior {} m, learned depths {}",
        p.kappa, p.alpha, p.max_bases, p.tolerance, p.refine, p.prior, p.depth_prior
    );
    let _ = writeln!(
        s,
        "- fit: score {}, samples {} (first iteration {}×), ≤ {} iterations, transition scale {}, temperature {}, raster side {} px, tolerance {}, dims {}, seed {}, skinning {:?}{}{}{}{}{}{}\n",
        score_name(f.score), f.samples, f.initial_factor, f.max_iterations, f.transition_scale, f.temperature, f.raster_max_side, f.tolerance,
        f.dims.map_or("default".into(), |d| d.to_string()), f.seed, f.skinning,
        if f.retarget { ", retarget" } else { "" },
        if opts.keep_pose_scale { ", solver camera kept" } else { ", camera refitted to the mean skeleton" },
        if f.sample_camera { ", per-sample cameras" } else { "" },
        match (f.proportion_sd > 0.0, f.estimate_proportions) {
            (false, _) => String::new(),
            (true, est) => format!(", bone factors sd {}{}", f.proportion_sd, if est { " centred on their 2-D estimate" } else { "" }),
        },
        f.height.map_or(String::new(), |h| format!(", height {h} m")),
        if opts.mean_shape { " (mean shape: fit skipped)" } else { "" }
    );
    let _ = writeln!(s, "## Results\n");
    let _ = writeln!(
        s,
        "- 3-D pose: {} bases, reprojection RMS {:.3} px, length excess {:+.4}",
        r.pose.bases.len(),
        r.pose.rms,
        r.pose.length_excess
    );
    let factors: Vec<String> = sketchbody::pose::figure::GROUP_NAMES
        .iter()
        .zip(&r.pose.factors.k)
        .map(|(n, k)| format!("{n} {k:.3}"))
        .collect();
    let _ = writeln!(
        s,
        "- drawn proportions (bone factors vs the dictionary skeleton): {}; {}",
        factors.join(", "),
        if r.pose.plausible { "plausible" } else { "LOW PLAUSIBILITY (no plausible body explains the 2-D joints)" }
    );
    let _ = writeln!(
        s,
        "- camera: sx {:.2}, sy {:.2} px/m, t ({:.1}, {:.1}) px",
        r.pose.camera.sx, r.pose.camera.sy, r.pose.camera.t[0], r.pose.camera.t[1]
    );
    for g in &r.fits {
        let it = g.fit.as_ref().map_or(0, |f| f.history.len());
        let ev = g.fit.as_ref().map_or(0, |f| f.evaluations);
        let dims = g.fit.as_ref().map_or(0, |f| f.weights.len());
        let _ = writeln!(
            s,
            "- {} fit ({dims} PCA dimensions): best score {:.5}, {it} iterations, {ev} sample evaluations, {:.2} s",
            g.space.name(),
            g.score,
            g.seconds
        );
    }
    let _ = writeln!(
        s,
        "- rest height: {:.3} m ({})",
        r.mesh.height(),
        match (opts.fit.height, opts.mean_shape, r.calibrated) {
            (Some(_), ..) => "given".to_string(),
            (None, true, _) => "the mean shape's".to_string(),
            (None, false, true) => format!("fitted {:.3} m, calibrated", r.fit_height),
            (None, false, false) if r.detection.is_some() => "fitted; detected joints are not calibrated".to_string(),
            (None, false, false) => "fitted, not calibrated".to_string(),
        }
    );
    let evidence = format!(
        "the gender classifier gives P(male) {:.2} from the sketch's joints and outline",
        r.gender_evidence.male_probability
    );
    if r.gender_fitted && r.male_prior.is_none() {
        let _ = writeln!(
            s,
            "- gender: {} chosen by the gender classifier with probability {:.2} ({evidence}), then that \
             gender's shape space fitted",
            r.gender.name(),
            r.gender_confidence
        );
    } else if r.gender_fitted {
        let _ = writeln!(
            s,
            "- gender: fitted as a continuous shape weight (both-sexes space): value {:.2} (0 female … 1 male), \
             nearer {} with posterior probability {:.2}; prior mass on the male end {:.2} ({evidence})",
            r.gender_value,
            r.gender.name(),
            r.gender_confidence,
            r.male_prior.unwrap_or(0.5)
        );
    } else {
        let _ = writeln!(s, "- gender: {} (given)", r.gender.name());
    }
    if r.edge_support.is_finite() {
        let flag = if r.low_evidence {
            "**low evidence**: the strokes support little of the fitted outline (mostly clothing, or a wrong \
             pose); the body is mostly the prior's"
        } else {
            "ok"
        };
        let _ = writeln!(
            s,
            "- evidence: {:.0}% of the fitted outline within {} raster px of a stroke: {flag}",
            100.0 * r.edge_support,
            sketchbody::fit::EDGE_SUPPORT_RADIUS
        );
    }
    if let Some(parts) = &r.part_support {
        let _ = writeln!(s, "- evidence per part: {}", part_support_line(parts));
        if let Some(line) = not_trusted_line(parts) {
            let _ = writeln!(s, "- {line}");
        }
    }
    let chosen = r.chosen_fit().and_then(|g| g.fit.as_ref());
    let factors = |p: &sketchbody::body::proportions::Proportions| {
        format!(
            "legs {:.3}, arms {:.3}, shoulders {:.3}, head {:.3}, torso {:.3}",
            p.legs, p.arms, p.shoulders, p.head, p.torso
        )
    };
    if let Some(e) = chosen.and_then(|f| f.proportion_estimate.as_ref()) {
        let _ = writeln!(s, "- bone factors estimated from the 2-D joints: {}", factors(e));
    }
    if let Some(p) = chosen.and_then(|f| f.proportions.as_ref()) {
        let _ = writeln!(s, "- bone factors fitted (applied to the mesh): {}", factors(p));
    }
    let w: Vec<String> = r.weights.iter().map(|x| format!("{x:.4}")).collect();
    let mapped =
        if r.calibrated && chosen.is_some_and(|f| f.weights != r.weights) { " (the fit's, calibrated)" } else { "" };
    let _ = writeln!(s, "- shape weights (m){mapped}: [{}]\n", w.join(", "));
    let t = &r.timings;
    let _ = writeln!(s, "## Timings (wall clock, s)\n");
    let _ = writeln!(
        s,
        "load {load_s:.3}, edges {:.3}, joints {:.3}, pose {:.3}, fit {:.3}, posing {:.3}, pipeline {:.3}, writing {write_s:.3}",
        t.edges, t.joints, t.pose, t.fit, t.posing, t.total
    );
    if !firsts.is_empty() {
        let shown: Vec<String> = firsts
            .iter()
            .map(|(stage, at)| match stage {
                InterimStage::MeanShape => format!("the mean body in the pose at {at:.3}"),
                InterimStage::DecidingFit => format!("the deciding fit at {at:.3}"),
            })
            .collect();
        let _ = writeln!(
            s,
            "\nBodies a host could show before the final one (`skb_pipeline_run_progressive`): {}",
            shown.join(", ")
        );
    }
    let tex = if a.no_texture { "" } else { " body.mtl, body_texture.png," };
    let per_view: String = r
        .views
        .iter()
        .map(|v| format!(" overlay_{0}.png, preview_{0}.png, joints2d_{0}.json,", v.label.name()))
        .collect();
    let _ = writeln!(
        s,
        "\n## Files\n\n{}, body.obj, body_rest.obj,{tex} joints2d.json, pose3d.json, overlay.png,{per_view} preview.png, report.md",
        file_list(&a.format)
    );
    s
}

/// `front+side+back`: the views of a turnaround result.
fn view_names(r: &PipelineResult) -> String {
    std::iter::once("front").chain(r.views.iter().map(|v| v.label.name())).collect::<Vec<_>>().join("+")
}

/// Parses `--gender`.
pub fn parse_gender(g: Option<&str>) -> Result<Option<Gender>, CliError> {
    g.map(Gender::parse).transpose().map_err(CliError::from)
}

/// Runs the command.
pub fn run(a: Args) -> Result<(), CliError> {
    let t_all = Instant::now();
    let opts = PipelineOptions {
        gender: parse_gender(a.gender.as_deref())?,
        ..a.fit.pipeline_options(a.fit.options()?, a.mean_shape)
    };
    let rig_options = a.rig.options()?;
    let figure_options = FigureOptions {
        backend: a.detector,
        strict: a.strict_detection,
        average_agreement: a.average_agreement,
        ..FigureOptions::default()
    };
    let dict = dict_io::embedded()?;
    // A sheet is labelled by the detector's facing unless --views names its views.
    let sheet_detection = a.sheet && a.sheet_views.is_none();
    let mut detector = None;
    let mut net = None;
    if sheet_detection {
        detector = Some(Model::embedded()?);
        net = Some(LandmarkNet::embedded_deferred());
    }
    let inputs = if a.sheet {
        load_sheet(&a, detector.as_ref().zip(net.as_ref()), &figure_options, &dict)?
    } else {
        load_views(&a)?
    };
    if inputs.front.joints.is_none() || inputs.views.iter().any(|v| v.joints.is_none()) {
        if detector.is_none() {
            detector = Some(Model::embedded()?);
        }
        if net.is_none() {
            net = Some(LandmarkNet::embedded_deferred());
        }
    }
    let detectors = detector.as_ref().zip(net.as_ref());
    let (sketch_rgb, sketch) = (&inputs.front.rgb, &inputs.front.gray);
    let source = source_for(inputs.front.joints.as_ref(), sketch_rgb, detectors, &figure_options)?;
    let view_sources: Vec<Box<dyn JointsSource + '_>> = inputs
        .views
        .iter()
        .map(|v| source_for(v.joints.as_ref(), &v.rgb, detectors, &figure_options))
        .collect::<Result<_, _>>()?;
    let view_inputs: Vec<ViewInput> = inputs
        .views
        .iter()
        .zip(&view_sources)
        .map(|(v, s)| ViewInput { label: v.label, sketch: &v.gray, source: s.as_ref() })
        .collect();
    // Fail on output sizes that cannot be drawn, and on an unwritable output folder, before
    // the work.
    for rgb in std::iter::once(sketch_rgb).chain(inputs.views.iter().map(|v| &v.rgb)) {
        compare_layout(rgb.width(), rgb.height(), a.preview_size)?;
    }
    check_texture_size(a.texture_size)?;
    let staging = StagingDir::new(&a.out).map_err(|e| CliError(format!("cannot write the output folder: {e}")))?;
    let model = BodyModel::embedded()?;
    let load_s = t_all.elapsed().as_secs_f64();
    catch_interrupt();
    let mut bar = Bar::new(a.quiet);
    let t_run = Instant::now();
    let mut firsts: Vec<(InterimStage, f64)> = Vec::new();
    let mut note = |b: &InterimBody| firsts.push((b.stage, t_run.elapsed().as_secs_f64()));
    let result = run_pipeline_views(
        &model,
        &dict,
        sketch,
        source.as_ref(),
        &view_inputs,
        &opts,
        &mut |f| bar.update(f),
        Some(&mut note),
    );
    bar.finish();
    let r = result.map_err(|e| match (&e, &a.joints) {
        (sketchbody::Error::JointOutsideImage { .. }, Some(p)) => CliError(format!("{}: {e}", p.display())),
        (sketchbody::Error::NoFigure { .. }, None) => {
            CliError(format!("{}: {e}; {}", a.sketch.display(), NO_FIGURE_HINT))
        }
        _ => CliError(format!("{}: {e}", a.sketch.display())),
    })?;
    release_free_memory();
    let t_write = Instant::now();
    let tris = r.mesh.triangles();
    let textured = r.mesh.uvs.is_some() && !a.no_texture;
    let mtl = textured.then_some("body.mtl");
    // Two independent halves of about equal cost, written on two threads: the overlays, the
    // OBJs and the JSON files; the texture, the previews and the rigged exports (which embed
    // the texture).
    let overlays_and_meshes = || -> Result<(), CliError> {
        let over = overlay(sketch, &r.joints2d, &r.pose.joints, &r.posed_vertices, &tris, &r.pose.camera)?;
        save_png(&over.view(), &staging.path("overlay.png"))?;
        let uvs = r.mesh.uvs.as_ref();
        write_obj_with_material(&staging.path("body.obj"), &r.posed_vertices, &r.mesh.quads, uvs, mtl)?;
        write_obj_with_material(&staging.path("body_rest.obj"), &r.mesh.vertices, &r.mesh.quads, uvs, mtl)?;
        write_joints2d_with(&staging.path("joints2d.json"), &r.joints2d, r.detection.as_ref())?;
        let mut pose_bytes =
            serde_json::to_vec_pretty(&pose3d_json(&r.pose, &dict, &opts.pose)).map_err(|e| CliError(e.to_string()))?;
        pose_bytes.push(b'\n');
        write_atomic(&staging.path("pose3d.json"), &pose_bytes)?;
        for (v, vr) in inputs.views.iter().zip(&r.views) {
            let name = vr.label.name();
            let over = overlay(&v.gray, &vr.joints2d, &r.pose.joints, &r.posed_vertices, &tris, &vr.camera)?;
            save_png(&over.view(), &staging.path(&format!("overlay_{name}.png")))?;
            let panel = compare_preview(&v.rgb, &r.posed_vertices, &tris, None, &vr.camera, a.preview_size)?;
            save_png(&panel.view(), &staging.path(&format!("preview_{name}.png")))?;
            write_joints2d_with(&staging.path(&format!("joints2d_{name}.json")), &vr.joints2d, None)?;
        }
        Ok(())
    };
    let textured_and_rigged = || -> Result<(), CliError> {
        let texture_img = match (&r.mesh.uvs, textured) {
            (Some(uvs), true) => Some((
                project_sketch(sketch_rgb, &r.posed_vertices, &r.mesh.quads, uvs, &r.pose.camera, a.texture_size)?.0,
                uvs,
            )),
            _ => None,
        };
        let surface =
            texture_img.as_ref().map(|(img, uvs)| SurfaceTexture::for_quads(img, &r.mesh.quads, uvs)).transpose()?;
        let views =
            compare_preview(sketch_rgb, &r.posed_vertices, &tris, surface.as_ref(), &r.pose.camera, a.preview_size)?;
        save_png(&views.view(), &staging.path("preview.png"))?;
        let keys = if a.rig.shape_keys() { shape_keys(&model, &r)? } else { Vec::new() };
        let scene = RigScene::build_with_shape_keys(model.rig(), &r.mesh, &r.ik_pose, &rig_options, &keys)?;
        let texture = texture_img.as_ref().map(|(img, _)| encode_png(&img.view())).transpose()?;
        let frame = ExportFrame { units: a.units, up: a.up };
        write_rigged(&a.format, |name| staging.path(name), &r.mesh, &scene, texture.as_deref(), &frame)?;
        if let Some(png) = &texture {
            write_atomic(&staging.path("body_texture.png"), png)?;
            write_atomic(&staging.path("body.mtl"), mtl_string("body_texture.png").as_bytes())?;
        }
        Ok(())
    };
    let (first, second) = std::thread::scope(|s| {
        let first = s.spawn(overlays_and_meshes);
        let second = textured_and_rigged();
        (first.join().unwrap_or_else(|panic| std::panic::resume_unwind(panic)), second)
    });
    first?;
    second?;
    let text = report(
        &a,
        &opts,
        &r,
        &inputs,
        (sketch.width(), sketch.height()),
        &firsts,
        load_s,
        t_write.elapsed().as_secs_f64(),
    );
    write_atomic(&staging.path("report.md"), text.as_bytes())?;
    staging.commit()?;
    // Fits in different dimensions (the gender decision's and the refit) carry their dimensions.
    let dims = |g: &sketchbody::pipeline::GenderFit| g.fit.as_ref().map(|f| f.weights.len());
    let mixed = r.fits.windows(2).any(|w| dims(&w[0]) != dims(&w[1]));
    let scores: Vec<String> = r
        .fits
        .iter()
        .map(|g| match dims(g).filter(|_| mixed) {
            Some(d) => format!("{} ({d}-D) {:.4}", g.space.name(), g.score),
            None => format!("{} {:.4}", g.space.name(), g.score),
        })
        .collect();
    let gender = if r.gender_fitted {
        match r.male_prior {
            Some(prior) => format!(
                "gender {:.2} fitted, {} p={:.2} (prior {prior:.2})",
                r.gender_value,
                r.gender.name(),
                r.gender_confidence
            ),
            None => format!("{} by the gender classifier, p={:.2}", r.gender.name(), r.gender_confidence),
        }
    } else {
        format!("{} given", r.gender.name())
    };
    println!(
        "{}: {gender}, {:.2} m tall, score {}{}{}, {:.2} s",
        a.out.display(),
        r.mesh.height(),
        scores.join(", "),
        if r.low_evidence { ", LOW EVIDENCE" } else { "" },
        if r.views.is_empty() { String::new() } else { format!(", views {}", view_names(&r)) },
        t_all.elapsed().as_secs_f64()
    );
    for w in &r.view_warnings {
        eprintln!("sketchbody: warning: {w}");
    }
    if let Some(f) = r.detection.as_ref().filter(|f| f.low_confidence) {
        eprintln!("sketchbody: detection confidence {:.2} ({}): {LOW_CONFIDENCE_HINT}", f.confidence, f.backend.name());
    }
    Ok(())
}

/// `head 97%, torso 99%, right_arm -, …`: each part's supported share of the fitted outline
/// (`-`: the part has no outline in view).
fn part_support_line(parts: &sketchbody::fit::PartSupport) -> String {
    sketchbody::fit::BodyPart::ALL
        .iter()
        .map(|&p| match parts.of(p) {
            Some(v) => format!("{} {:.0}%", p.name(), 100.0 * v),
            None => format!("{} -", p.name()),
        })
        .collect::<Vec<_>>()
        .join(", ")
}

/// `**not trusted**: right_leg, left_leg (…)` naming the parts in view whose support is below
/// [`sketchbody::fit::LOW_EVIDENCE_SUPPORT`]; `None` when every part in view is supported.
fn not_trusted_line(parts: &sketchbody::fit::PartSupport) -> Option<String> {
    let weak = parts.below(sketchbody::fit::LOW_EVIDENCE_SUPPORT);
    if weak.is_empty() {
        return None;
    }
    let names: Vec<&str> = weak.iter().map(|p| p.name()).collect();
    Some(format!(
        "**not trusted**: {} (the strokes support under {:.0}% of the fitted outline there: clothing, hair, or a shape no \
         body has; the body there is the prior's reading)",
        names.join(", "),
        100.0 * sketchbody::fit::LOW_EVIDENCE_SUPPORT
    ))
}

#[cfg(test)]
mod part_lines {
    use super::*;
    use sketchbody::fit::PartSupport;

    /// The per-part line lists every part, `-` for one out of view; the not-trusted line names
    /// only the parts in view under the threshold, and is absent when there are none.
    #[test]
    fn the_report_names_the_parts_not_trusted() {
        let parts = PartSupport::from_counts(&[(9, 10), (8, 10), (0, 0), (4, 10), (1, 10), (6, 10)]);
        assert_eq!(
            part_support_line(&parts),
            "head 90%, torso 80%, right_arm -, left_arm 40%, right_leg 10%, left_leg 60%"
        );
        let line = not_trusted_line(&parts).unwrap();
        assert!(line.starts_with("**not trusted**: left_arm, right_leg ("), "{line}");
        let fine = PartSupport::from_counts(&[(9, 10), (8, 10), (0, 0), (5, 10), (7, 10), (6, 10)]);
        assert_eq!(not_trusted_line(&fine), None);
    }
}

#[cfg(test)]
mod view_flags {
    use super::{view_args, ViewLabel};

    #[test]
    fn views_need_a_known_label_once_and_joints_need_their_view() {
        let s = |v: &[&str]| v.iter().map(|x| x.to_string()).collect::<Vec<_>>();
        let ok = view_args(&s(&["side=s.png", "BACK=b.png", "side_left=l.png"]), &s(&["side=s.json"]))
            .unwrap_or_else(|e| panic!("{}", e.0));
        assert_eq!(
            ok.iter().map(|v| v.label).collect::<Vec<_>>(),
            [ViewLabel::Side, ViewLabel::Back, ViewLabel::SideLeft]
        );
        assert_eq!(ok[0].joints.as_deref(), Some(std::path::Path::new("s.json")));
        assert!(ok[1].joints.is_none());
        let err = |v: &[&str], j: &[&str]| view_args(&s(v), &s(j)).err().expect("an error").0;
        assert!(err(&["s.png"], &[]).contains("needs its label"));
        assert!(err(&["front=f.png"], &[]).contains("main sketch"));
        assert!(err(&["three-quarter=t.png"], &[]).contains("not front, side, side_left or back"));
        assert!(err(&["side=a.png", "side=b.png"], &[]).contains("two side views"));
        assert!(err(&["side=a.png"], &["back=b.json"]).contains("no --view back"));
        assert!(err(&["side="], &[]).contains("no file"));
    }
}
