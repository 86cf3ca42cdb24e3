//! Shape fitting by sampling importance resampling (paper §II-C, eqs. 5–9).
//!
//! Iteration 1 draws `samples` shapes from the GMM prior (eq. 8); later iterations draw each
//! sample's successor from `N(y; y_prev, Σ) · P(y | θ)` (eq. 9, sampled exactly, see
//! [`Transition`]). Every sample is posed to the estimated 3-D joints (IK + skinning), projected
//! with the estimated camera and rasterised, and weighted by its match score (eqs. 6–7); the
//! population is then resampled (systematic resampling). The fit stops when the weighted mean
//! moves less than `tolerance` standard deviations in every component, or after
//! `max_iterations`. The result is `Y* = Σ w Y` of the last iteration (and the best sample).
//! Samples are evaluated on the model's fit proxy ([`BodyModel::fit_proxy`]: a decimated body
//! whose vertices are a subset of the body's, 1300 of 13380), drawing only its viewer-facing
//! triangles and scoring only the silhouette's bounding box — several times faster than the
//! full mesh for a silhouette within about a pixel of it.
//!
//! Σ is `diag(s² λ_k)` with `λ_k` the PCA variances: the paper's `Σ = I` in whitened weights is
//! `s = 1`; the default `s = 0.3` explores less per step. Determinism: each sample's random
//! stream is derived from (seed, iteration, index), so results do not depend on thread count.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

use super::bone_estimate::{estimate_proportions, EstimateOptions};
use super::parts::{nearest_part, BodyPart, PartSupport};
use super::proportions::{apply_in_place, proportions_of, FactorPrior};
use super::score::{MatchScore, SketchEvidence};
use super::transition::Transition;
use crate::body::ik::{self, IkOptions};
use crate::body::proportions::Proportions;
use crate::body::rig::{scale_to_height, y_extent};
use crate::body::skin::{skin_into, SkinMethod};
use crate::body::{BodyModel, FitProxy, ProxySpace, ShapeChoice, ShapeSpace};
use crate::camera::WeakPerspective;
use crate::error::{ensure_finite, Error, Result};
use crate::image::GrayImage;
use crate::raster::{Facing, Rasterizer};
use crate::skeleton::{Joints2, Joints3, BONES, NUM_JOINTS};

/// Options of [`fit_shape`], with documented defaults ([`FitOptions::default`]); the
/// measurements behind each default are in docs/benchmarks-history.md, "How the fit's defaults
/// were chosen". Plain data.
#[derive(Clone, Debug, PartialEq)]
pub struct FitOptions {
    /// Samples per iteration, S (default 200), from the iteration where
    /// [`initial_factor`](Self::initial_factor)'s schedule reaches it.
    pub samples: usize,
    /// The first iteration draws `initial_factor × samples` prior samples, and each resampling
    /// halves the population until it is `samples` (default 8: 1600, 800, 400, then 200; 1 = a
    /// flat population). A wide first look at the prior steadies the posterior mean. In 1..=64;
    /// the first population is capped at 100000 (or `samples` if larger).
    pub initial_factor: usize,
    /// Most iterations, T (default 8).
    pub max_iterations: usize,
    /// PCA dimensions searched. Default: for a gendered space every dimension its prior covers
    /// (10 in the shipped model), for the both-sexes space its own default dimension (5).
    pub dims: Option<usize>,
    /// Transition step `s` in standard deviations: Σ = diag(s² λ_k) (default 0.3).
    pub transition_scale: f64,
    /// The match score (default [`MatchScore::Chamfer`], the most accurate of the scores on
    /// outline sketches).
    pub score: MatchScore,
    /// For the non-paper scores, sample likelihood = exp(score / temperature) (for the chamfer
    /// score the unit is raster pixels of mean boundary distance). Default 2.0: sharper
    /// likelihoods overfit silhouettes that compensate pose error, flatter ones ignore the
    /// sketch. Finite, > 0.
    pub temperature: f64,
    /// Longest raster side in pixels; the sketch is scored at this resolution (default 256).
    pub raster_max_side: usize,
    /// Convergence: stop when Y* moves less than this many standard deviations (default 0.02).
    pub tolerance: f64,
    /// Seed of every random step (default 1).
    pub seed: u64,
    /// Skinning method (default linear blend skinning, as the paper).
    pub skinning: SkinMethod,
    /// Stretch bones so joints land exactly on the estimated 3-D joints (default off: bone
    /// lengths come from the shape, as in the paper).
    pub retarget: bool,
    /// Weight of the 2-D joint term (used when [`FitProblem::joints2d`] is given): the score
    /// of a sample loses `joint_weight ×` the mean distance, in raster pixels, between its own
    /// posed rig joints projected by the camera and the visible estimated 2-D joints
    /// (default 1.0; 0 turns it off). Must be finite and ≥ 0.
    pub joint_weight: f64,
    /// Give every sample its own camera: when [`FitProblem::joints2d`] is given, each sample's
    /// camera scales and translation are refitted in closed form
    /// ([`WeakPerspective::refit_scale`]) to its own posed rig joints vs the visible 2-D joints
    /// before it is rasterised and scored, so the body's size comes from its shape (proportions
    /// and the prior's correlations) rather than from [`FitProblem::camera`]'s scale (only its
    /// rotation is used). Without 2-D joints the problem's camera is used. Default on: the size
    /// then follows the shape.
    pub sample_camera: bool,
    /// The character's known rest height, metres (`None`: unknown, the default). With a
    /// problem camera (not [`sample_camera`](Self::sample_camera)) every sample's rest body is
    /// scaled uniformly about its pelvis to this height before it is posed, so the fit searches
    /// proportions at the known size (the proxy's height is corrected by the full/proxy height
    /// ratio of the mean shape); with per-sample cameras a uniform scale does not change a
    /// sample's image, so the fit is the same and only the caller's output is scaled
    /// (`pipeline::run_pipeline` scales the fitted mesh to it). In 0.1..=10 m.
    pub height: Option<f64>,
    /// Search bone-length factors (legs, arms, shoulders, head, torso) with this prior standard
    /// deviation of each log factor (see [`super::proportions`]); 0 searches PCA weights only.
    /// Default 0.1. Finite, in 0..=0.5.
    pub proportion_sd: f64,
    /// Centre the bone factors' prior on the closed-form estimate of
    /// [`super::bone_estimate::estimate_proportions`] (bone lengths of the visible 2-D joints
    /// against the gender's mean skeleton, given the problem pose's bone directions and
    /// camera, default [`EstimateOptions`]) instead of 1. Needs [`FitProblem::joints2d`] and
    /// `proportion_sd > 0`; when the estimate is degenerate (no usable bone) the prior stays at 1.
    /// Default on: drawn proportions then start near the sketch's own.
    pub estimate_proportions: bool,
    /// Clothing-robust chamfer ([`SketchEvidence::with_inside_cap`]): silhouette boundary
    /// pixels inside the sketch's outer outline cost their distance to the nearest stroke capped
    /// at this many raster pixels, those outside it the full capped distance, so outline
    /// strokes that may be clothing (coats, capes, skirts) do not pull the body outward while a
    /// body crossing the outline is still penalised. [`super::CHAMFER_CAP`] (12) turns it off.
    /// Only the chamfer scores use it. Default 4.0. Finite, > 0.
    pub inside_cap: f64,
    /// Blended space only: the prior's mass on the male end (a per-sketch
    /// [`crate::body::LEVEL_WEIGHTS`], [`crate::body::BlendedSpace::prior_with_male_mass`]),
    /// e.g. [`super::GenderClassifier`]'s probability. `None` (default): the space's own prior,
    /// 0.5 on each end. Ignored for a gendered space. In 0..=1.
    pub male_prior: Option<f64>,
}

/// Every PCA weight the fit returns or scores lies within this many standard deviations of some
/// component mean of its prior ([`crate::body::Gmm::range`]): the prior's documented range.
pub const PRIOR_RANGE_SD: f64 = 3.0;

/// A fitted silhouette with less than this fraction of its boundary within
/// [`EDGE_SUPPORT_RADIUS`] raster pixels of a stroke is reported as low-evidence
/// ([`FitResult::low_evidence`]): the body is mostly the prior's, not the sketch's (e.g. under a
/// cloak to the ground).
pub const LOW_EVIDENCE_SUPPORT: f64 = 0.5;

/// Radius of [`FitResult::edge_support`], raster pixels.
pub const EDGE_SUPPORT_RADIUS: f64 = 2.0;

impl Default for FitOptions {
    fn default() -> Self {
        Self {
            samples: 200,
            initial_factor: 8,
            max_iterations: 8,
            dims: None,
            transition_scale: 0.3,
            score: MatchScore::Chamfer,
            temperature: 2.0,
            raster_max_side: 256,
            tolerance: 0.02,
            seed: 1,
            skinning: SkinMethod::Linear,
            retarget: false,
            joint_weight: 1.0,
            sample_camera: true,
            height: None,
            proportion_sd: 0.1,
            estimate_proportions: true,
            inside_cap: 4.0,
            male_prior: None,
        }
    }
}

/// What the fit works on: the model, a shape space (a gender's, or the blended one with gender as
/// weight 0), the estimated 3-D pose (metres, model frame),
/// the estimated camera (image pixels) and the sketch's edge map (non-zero = edge).
pub struct FitProblem<'a> {
    /// The body model the shape space belongs to.
    pub model: &'a BodyModel,
    /// Which shape space is searched (a gender's, or the blended one).
    pub gender: ShapeChoice,
    /// The estimated 3-D joints the samples are posed to (metres, model frame).
    pub pose: &'a Joints3,
    /// The estimated camera mapping the posed body to image pixels.
    pub camera: &'a WeakPerspective,
    /// The sketch's edge map (non-zero = edge), image pixels.
    pub edges: &'a GrayImage,
    /// The sketch's 2-D joints (image pixels), for the joint term of
    /// [`FitOptions::joint_weight`]; `None` turns the term off.
    pub joints2d: Option<&'a Joints2>,
    /// A turnaround's other views of the same posed body (empty: one view). A sample's score is
    /// the mean of every view's score (its outline match less its joint term), so
    /// [`FitOptions::temperature`] and the calibrations trained on one-view fits mean the same
    /// for a turnaround (docs/benchmarks.md, "Model sheets").
    pub views: &'a [FitView<'a>],
}

/// One extra view of a turnaround in a [`FitProblem`]: the same posed body seen through its own
/// camera in its own image.
#[derive(Clone, Copy)]
pub struct FitView<'a> {
    /// The view's camera (image pixels of `edges`); its rotation is used as is, its scales and
    /// translation refitted per sample like the front's ([`FitOptions::sample_camera`]).
    pub camera: &'a WeakPerspective,
    /// The view's edge map (non-zero = edge), image pixels.
    pub edges: &'a GrayImage,
    /// The view's 2-D joints (image pixels), for its joint term; `None` turns it off.
    pub joints2d: Option<&'a Joints2>,
}

/// Per-iteration figures.
#[derive(Clone, Debug, PartialEq)]
pub struct IterationStats {
    /// Best score of the iteration's samples.
    pub best_score: f64,
    /// Weighted-mean score of the iteration's samples.
    pub mean_score: f64,
    /// Effective sample size 1 / Σ w² before resampling.
    pub effective_samples: f64,
}

/// The fit's result. Weights are PCA weights of the problem's shape space (first `dims`), each
/// within the prior's range ([`PRIOR_RANGE_SD`]).
#[derive(Clone, Debug, PartialEq)]
pub struct FitResult {
    /// Y* = Σ w Y over the last iteration (blended space: over the samples on the more probable
    /// side of gender value 0.5, weights renormalised).
    pub weights: Vec<f64>,
    /// Bone-length factors of Y* (`exp` of the weighted mean log factors); `None` unless
    /// [`FitOptions::proportion_sd`] > 0.
    pub proportions: Option<Proportions>,
    /// The closed-form estimate the factors' prior was centred on (`None` unless
    /// [`FitOptions::estimate_proportions`] was used and the estimate was not degenerate).
    pub proportion_estimate: Option<Proportions>,
    /// The best-scoring sample seen (PCA weights).
    pub best_weights: Vec<f64>,
    /// Score of [`FitResult::best_weights`].
    pub best_score: f64,
    /// One entry per iteration, in order.
    pub history: Vec<IterationStats>,
    /// Samples evaluated (synthesis + posing + skinning + raster + score).
    pub evaluations: usize,
    /// Blended space only: the posterior mean of the gender value over the last iteration's
    /// weighted samples ([`crate::body::BlendedSpace::gender_value`]: 0 female mean … 1 male
    /// mean), clamped to 0..=1.
    pub gender_value: Option<f64>,
    /// Blended space only: the posterior probability (last iteration's weights) that the gender
    /// value is above 0.5, i.e. of the male-leaning half.
    pub male_probability: Option<f64>,
    /// Fraction of Y*'s silhouette boundary within [`EDGE_SUPPORT_RADIUS`] raster pixels of a
    /// stroke (0..=1).
    pub edge_support: f64,
    /// Per body part, the share of Y*'s silhouette boundary within [`EDGE_SUPPORT_RADIUS`]
    /// raster pixels of a stroke (each boundary pixel belongs to the part of its nearest
    /// projected bone); all `None` when Y* cannot be drawn.
    pub part_support: PartSupport,
    /// [`FitResult::edge_support`] of Y* in each of [`FitProblem::views`], in order (empty for
    /// one view; 0 where Y* cannot be drawn).
    pub view_support: Vec<f64>,
}

impl FitResult {
    /// `true` when [`FitResult::edge_support`] is below [`LOW_EVIDENCE_SUPPORT`]: the sketch
    /// supports little of the fitted outline (mostly clothing, or a wrong pose).
    pub fn low_evidence(&self) -> bool {
        self.edge_support < LOW_EVIDENCE_SUPPORT
    }
}

/// Splits 64-bit seeds (SplitMix64 finaliser).
fn mix(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58476d1ce4e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d049bb133111eb);
    z ^ (z >> 31)
}

fn sample_rng(seed: u64, iteration: usize, index: usize) -> ChaCha8Rng {
    ChaCha8Rng::seed_from_u64(mix(mix(seed ^ 0x5eed) ^ (iteration as u64) << 32 ^ index as u64))
}

impl FitOptions {
    /// Checks every field: positive finite scale, temperature and tolerance; samples in
    /// 2..=100000, iterations in 1..=1000, raster side in 16..=4096.
    pub fn validate(&self) -> Result<()> {
        let positive = |name: &'static str, v: f64| -> Result<()> {
            ensure_finite(name, v)?;
            if v > 0.0 {
                Ok(())
            } else {
                Err(Error::OutOfRange { name, detail: format!("{v} must be > 0") })
            }
        };
        positive("transition scale", self.transition_scale)?;
        positive("temperature", self.temperature)?;
        positive("tolerance", self.tolerance)?;
        positive("inside cap", self.inside_cap)?;
        ensure_finite("joint weight", self.joint_weight)?;
        if self.joint_weight < 0.0 {
            return Err(Error::OutOfRange {
                name: "joint weight",
                detail: format!("{} must be >= 0", self.joint_weight),
            });
        }
        if let Some(h) = self.height {
            ensure_finite("height", h)?;
            if !(0.1..=10.0).contains(&h) {
                return Err(Error::OutOfRange { name: "height", detail: format!("{h} m not in 0.1..=10") });
            }
        }
        if let Some(p) = self.male_prior {
            ensure_finite("male prior", p)?;
            if !(0.0..=1.0).contains(&p) {
                return Err(Error::OutOfRange { name: "male prior", detail: format!("{p} not in 0..=1") });
            }
        }
        ensure_finite("proportion sd", self.proportion_sd)?;
        if !(0.0..=0.5).contains(&self.proportion_sd) {
            return Err(Error::OutOfRange {
                name: "proportion sd",
                detail: format!("{} not in 0..=0.5", self.proportion_sd),
            });
        }
        if !(2..=100_000).contains(&self.samples) {
            return Err(Error::OutOfRange { name: "samples", detail: format!("{} not in 2..=100000", self.samples) });
        }
        if !(1..=64).contains(&self.initial_factor) {
            return Err(Error::OutOfRange {
                name: "initial factor",
                detail: format!("{} not in 1..=64", self.initial_factor),
            });
        }
        if !(1..=1000).contains(&self.max_iterations) {
            return Err(Error::OutOfRange {
                name: "iterations",
                detail: format!("{} not in 1..=1000", self.max_iterations),
            });
        }
        if !(16..=4096).contains(&self.raster_max_side) {
            return Err(Error::OutOfRange {
                name: "raster size",
                detail: format!("{} not in 16..=4096", self.raster_max_side),
            });
        }
        Ok(())
    }
}

/// Everything fixed during one fit. Samples are evaluated on the model's fit proxy (a
/// decimated body, [`BodyModel::fit_proxy`]), drawing its viewer-facing triangles only.
struct Evaluator<'a> {
    problem: &'a FitProblem<'a>,
    options: &'a FitOptions,
    proxy: &'a FitProxy,
    space: &'a ShapeSpace,
    proxy_space: &'a ProxySpace,
    /// The main (front) view.
    front: ViewEvidence,
    /// [`FitProblem::views`], in order.
    views: Vec<ViewEvidence>,
    /// Full-mesh / proxy height of the mean shape (for [`FitOptions::height`]).
    height_correction: f64,
    /// PCA dimensions searched; a sample's entries after them are its log bone factors.
    dims: usize,
}

/// One view at raster resolution: its camera, its sketch evidence and its joints.
struct ViewEvidence {
    raster_camera: WeakPerspective,
    evidence: SketchEvidence,
    /// Visible 2-D joints in raster pixels (index, position), empty when the term is off.
    joints_px: Vec<(usize, [f64; 2])>,
}

impl ViewEvidence {
    /// The view of `camera`, `edges` and `joints2d` at the raster size of `options`, its figure
    /// region seeded by the projected `pose`.
    fn new(
        pose: &Joints3,
        camera: &WeakPerspective,
        edges: &GrayImage,
        joints2d: Option<&Joints2>,
        options: &FitOptions,
    ) -> Result<ViewEvidence> {
        let (iw, ih) = (edges.width(), edges.height());
        let f = (options.raster_max_side as f64 / iw.max(ih) as f64).min(1.0);
        let (rw, rh) = (((iw as f64 * f).round() as usize).max(1), ((ih as f64 * f).round() as usize).max(1));
        let raster_camera = camera.scaled_image(f);
        let skeleton_px: Vec<[f64; 2]> = BONES
            .iter()
            .flat_map(|&(a, b)| {
                let (pa, pb) = (pose[a], pose[b]);
                (0..=8).map(move |i| {
                    let t = i as f64 / 8.0;
                    nalgebra::Vector3::new(
                        pa[0] + t * (pb[0] - pa[0]),
                        pa[1] + t * (pb[1] - pa[1]),
                        pa[2] + t * (pb[2] - pa[2]),
                    )
                })
            })
            .map(|p| raster_camera.project(&p))
            .collect();
        Ok(ViewEvidence {
            raster_camera,
            evidence: SketchEvidence::new(edges, rw, rh, &skeleton_px)?.with_inside_cap(options.inside_cap),
            joints_px: joints_in_raster(joints2d, f)?,
        })
    }
}

/// Per-thread scratch.
#[derive(Default)]
struct Scratch {
    raster: Rasterizer,
    rest: Vec<[f32; 3]>,
    posed: Vec<[f32; 3]>,
    /// The last drawn shape's posed joints projected into the raster, pixels.
    joints_px: [[f64; 2]; NUM_JOINTS],
}

impl<'a> Evaluator<'a> {
    /// The evaluator of `problem` under `options`, searching the first `dims` dimensions of its
    /// shape space. Errors: the model's, a view's camera, the sketch evidence's.
    fn new(problem: &'a FitProblem<'a>, options: &'a FitOptions, dims: usize) -> Result<Evaluator<'a>> {
        let space = problem.model.shape_space(problem.gender)?;
        let proxy = problem.model.fit_proxy()?;
        let proxy_space = proxy.shape_space(problem.model, problem.gender)?;
        let mut views = Vec::with_capacity(problem.views.len());
        for v in problem.views {
            v.camera.validate()?;
            views.push(ViewEvidence::new(problem.pose, v.camera, v.edges, v.joints2d, options)?);
        }
        Ok(Evaluator {
            problem,
            options,
            proxy,
            space,
            proxy_space,
            front: ViewEvidence::new(problem.pose, problem.camera, problem.edges, problem.joints2d, options)?,
            views,
            height_correction: {
                let mut proxy_mean = Vec::new();
                proxy_space.synthesize_into(space, &[], &mut proxy_mean)?;
                y_extent(space.mean()) / y_extent(&proxy_mean)
            },
            dims,
        })
    }

    /// Score of one shape (higher is better); a shape that cannot be posed or lands outside the
    /// image scores −∞.
    fn score(&self, y: &[f64], s: &mut Scratch) -> Result<f64> {
        Ok(self.draw_and_score(y, s)?.unwrap_or(f64::NEG_INFINITY))
    }

    /// Score, edge support and per-part support of one shape; `None` when it cannot be posed or
    /// lands outside the image.
    fn evaluate(&self, y: &[f64], s: &mut Scratch) -> Result<Option<(f64, f64, PartSupport)>> {
        Ok(self.draw_and_score(y, s)?.map(|score| {
            let (mask, bounds) = (s.raster.mask(), s.raster.covered_bounds());
            let support = self.front.evidence.edge_support(mask, bounds, EDGE_SUPPORT_RADIUS);
            let joints = &s.joints_px;
            let counts = self.front.evidence.edge_support_counts(
                mask,
                bounds,
                EDGE_SUPPORT_RADIUS,
                BodyPart::ALL.len(),
                |x, y| {
                    let part = nearest_part(joints, [x as f64 + 0.5, y as f64 + 0.5])?;
                    BodyPart::ALL.iter().position(|&p| p == part)
                },
            );
            (score, support, PartSupport::from_counts(&counts))
        }))
    }

    /// [`FitResult::view_support`] of one shape (0 for a view it cannot be drawn in).
    fn view_support(&self, y: &[f64], s: &mut Scratch) -> Result<Vec<f64>> {
        if self.views.is_empty() {
            return Ok(Vec::new());
        }
        let Some(pose) = self.pose_sample(y, s)? else { return Ok(vec![0.0; self.views.len()]) };
        let mut out = Vec::with_capacity(self.views.len());
        for v in &self.views {
            out.push(match self.score_view(v, &pose, s)? {
                Some(_) => v.evidence.edge_support(s.raster.mask(), s.raster.covered_bounds(), EDGE_SUPPORT_RADIUS),
                None => 0.0,
            });
        }
        Ok(out)
    }

    /// Draws one shape's silhouette in every view and scores it (the mean over the views); the
    /// front view is drawn last, so `s.raster` and `s.joints_px` hold its silhouette and joints.
    /// `None` when it cannot be posed or lands outside an image. The edge support is left to
    /// [`Evaluator::evaluate`]: only the fit's result needs it, and it costs a tenth of a sample.
    fn draw_and_score(&self, y: &[f64], s: &mut Scratch) -> Result<Option<f64>> {
        let Some(pose) = self.pose_sample(y, s)? else { return Ok(None) };
        let mut views = 0.0;
        for v in &self.views {
            match self.score_view(v, &pose, s)? {
                Some(score) => views += score,
                None => return Ok(None),
            }
        }
        let front = self.score_view(&self.front, &pose, s)?;
        Ok(if self.views.is_empty() { front } else { front.map(|f| (f + views) / (1 + self.views.len()) as f64) })
    }

    /// Synthesises, sizes and poses one shape into `s.posed`; returns its IK pose, `None` when
    /// it cannot be posed.
    fn pose_sample(&self, y: &[f64], s: &mut Scratch) -> Result<Option<ik::Pose>> {
        let mut joints = self.proxy_space.synthesize_into(self.space, &y[..self.dims], &mut s.rest)?;
        if y.len() > self.dims {
            match apply_in_place(&mut s.rest, &mut joints, self.proxy.skin_weights(), &proportions_of(&y[self.dims..]))
            {
                Ok(()) => {}
                Err(Error::NonFinite { .. }) => return Err(Error::NonFinite { name: "shape", value: f64::NAN }),
                Err(_) => return Ok(None),
            }
        }
        if let (Some(h), false) = (self.options.height, self.options.sample_camera) {
            scale_to_height(&mut s.rest, &mut joints, h / self.height_correction)?;
        }
        let pose = match ik::solve(&joints, self.problem.pose, &IkOptions { retarget: self.options.retarget }) {
            Ok(p) => p,
            Err(Error::NonFinite { .. }) => return Err(Error::NonFinite { name: "pose", value: f64::NAN }),
            Err(_) => return Ok(None),
        };
        skin_into(&s.rest, self.proxy.skin_weights(), &pose, self.options.skinning, &mut s.posed)?;
        Ok(Some(pose))
    }

    /// Draws the posed shape in `s.posed` (IK pose `pose`) in view `v` into `s.raster` and
    /// scores it; `None` when the camera cannot be fitted or the body lands outside the image.
    fn score_view(&self, v: &ViewEvidence, pose: &ik::Pose, s: &mut Scratch) -> Result<Option<f64>> {
        let camera = if self.options.sample_camera && !v.joints_px.is_empty() {
            match v.raster_camera.refit_scale(&pose.joints, &v.joints_px) {
                Ok(c) => c,
                Err(Error::Degenerate(_)) => return Ok(None),
                Err(e) => return Err(e),
            }
        } else {
            v.raster_camera
        };
        let (w, h) = (v.evidence.width(), v.evidence.height());
        match s.raster.rasterize_mask(&s.posed, self.proxy.triangles(), &camera, w, h, Facing::Front) {
            Ok(_) => {
                for (px, j) in s.joints_px.iter_mut().zip(&pose.joints) {
                    *px = camera.project(&nalgebra::Vector3::from(*j));
                }
                let (mask, bounds) = (s.raster.mask(), s.raster.covered_bounds());
                Ok(Some(
                    v.evidence.score_in(mask, bounds, self.options.score)
                        - self.joint_penalty(v, &pose.joints, &camera),
                ))
            }
            Err(Error::MeshOutsideImage { .. }) | Err(Error::OutOfRange { name: "projected vertex", .. }) => Ok(None),
            Err(e) => Err(e),
        }
    }
}

impl Evaluator<'_> {
    /// `joint_weight ×` mean raster-pixel distance between the projected posed joints and the
    /// visible 2-D joints (0 when the term is off).
    fn joint_penalty(&self, v: &ViewEvidence, posed: &Joints3, camera: &WeakPerspective) -> f64 {
        if v.joints_px.is_empty() || self.options.joint_weight == 0.0 {
            return 0.0;
        }
        let total: f64 = v
            .joints_px
            .iter()
            .map(|&(k, q)| {
                let p = camera.project(&nalgebra::Vector3::from(posed[k]));
                ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2)).sqrt()
            })
            .sum();
        self.options.joint_weight * total / v.joints_px.len() as f64
    }
}

/// The fit's score (higher is better; −∞ for a shape that cannot be posed or lands outside the
/// image) of each of `shapes` under `problem` and `options`, as [`fit_shape`] scores its samples:
/// each shape is its first `dims` PCA weights, optionally followed by the natural logs of its
/// five bone-length factors. A diagnostic (e.g. the score along the line from the mean shape to
/// a known body). Errors: `options`' and the camera's checks, a shape with another length
/// (`OutOfRange`), a non-finite weight.
pub fn score_shapes(
    problem: &FitProblem<'_>,
    options: &FitOptions,
    dims: usize,
    shapes: &[Vec<f64>],
) -> Result<Vec<f64>> {
    options.validate()?;
    problem.camera.validate()?;
    crate::body::ik::check_joints("pose", problem.pose)?;
    let evaluator = Evaluator::new(problem, options, dims)?;
    evaluator.space.check_weights(&vec![0.0; dims])?;
    let mut scratch = Scratch::default();
    shapes
        .iter()
        .map(|y| {
            if y.len() != dims && y.len() != dims + super::proportions::NUM_FACTORS {
                return Err(Error::OutOfRange {
                    name: "scored shape",
                    detail: format!(
                        "{} values, expected {dims} or {}",
                        y.len(),
                        dims + super::proportions::NUM_FACTORS
                    ),
                });
            }
            for &v in y {
                ensure_finite("scored shape", v)?;
            }
            evaluator.score(y, &mut scratch)
        })
        .collect()
}

/// Fits the shape (see the module documentation). `progress(fraction)` is called after every
/// iteration from the calling thread; returning `false` cancels with [`Error::Cancelled`].
pub fn fit_shape(
    problem: &FitProblem<'_>,
    options: &FitOptions,
    progress: &mut dyn FnMut(f32) -> bool,
) -> Result<FitResult> {
    options.validate()?;
    problem.camera.validate()?;
    crate::body::ik::check_joints("pose", problem.pose)?;
    let space = problem.model.shape_space(problem.gender)?;
    let reweighted = match (problem.gender, options.male_prior) {
        (ShapeChoice::Blended, Some(p)) => Some(problem.model.blended()?.prior_with_male_mass(p)?),
        _ => None,
    };
    let prior_full = reweighted.as_ref().unwrap_or(space.gmm());
    let dims = options.dims.unwrap_or(match problem.gender {
        ShapeChoice::Gendered(_) => prior_full.dims(),
        ShapeChoice::Blended => space.default_dim(),
    });
    if dims == 0 || dims > prior_full.dims() {
        return Err(Error::OutOfRange {
            name: "fit dimensions",
            detail: format!("{dims} not in 1..={}", prior_full.dims()),
        });
    }
    let prior = prior_full.marginal(dims)?;
    let range = prior.range(PRIOR_RANGE_SD);
    let clamp = |y: &mut Vec<f64>| y.iter_mut().zip(&range).for_each(|(v, &(lo, hi))| *v = v.clamp(lo, hi));
    let sigma: Vec<f64> = space.variances()[..dims].iter().map(|l| options.transition_scale.powi(2) * l).collect();
    let transition = Transition::new(&prior, &sigma)?;

    let evaluator = Evaluator::new(problem, options, dims)?;
    let estimate = match (options.estimate_proportions && options.proportion_sd > 0.0, problem.joints2d) {
        (true, Some(j2)) => match estimate_proportions(
            space.mean_joints(),
            problem.pose,
            problem.camera,
            j2,
            &EstimateOptions::default(),
        ) {
            Ok(e) => Some(e),
            Err(Error::Degenerate(_)) => None,
            Err(e) => return Err(e),
        },
        _ => None,
    };
    let factors = (options.proportion_sd > 0.0).then(|| {
        let prior = FactorPrior::new(options.proportion_sd, options.transition_scale);
        estimate.map_or(prior, |e| prior.centred(e.log_factors))
    });

    let mut stds: Vec<f64> = space.variances()[..dims].iter().map(|l| l.sqrt()).collect();
    if let Some(f) = &factors {
        stds.extend([f.sd(); super::proportions::NUM_FACTORS]);
    }
    let state_dims = stds.len();
    let first_population = (options.samples * options.initial_factor).min(100_000).max(options.samples);
    let mut population: Vec<Vec<f64>> = (0..first_population)
        .map(|i| {
            let rng = &mut sample_rng(options.seed, 0, i);
            let mut y = prior.sample(rng);
            clamp(&mut y);
            if let Some(f) = &factors {
                f.extend_initial(&mut y, rng);
            }
            y
        })
        .collect();
    let mut history = Vec::new();
    let mut best = (f64::NEG_INFINITY, population[0].clone());
    let mut previous_mean: Option<Vec<f64>> = None;
    let mut weighted_mean = vec![0.0; state_dims];
    let mut evaluations = 0;
    let mut last_weights = vec![1.0 / options.samples as f64; options.samples];
    for t in 0..options.max_iterations {
        if t > 0 {
            population = population
                .par_iter()
                .enumerate()
                .map(|(i, y)| {
                    let rng = &mut sample_rng(options.seed, t, i);
                    let mut next = transition.sample(&y[..dims], rng);
                    clamp(&mut next);
                    if let Some(f) = &factors {
                        f.extend_successor(&y[dims..], &mut next, rng);
                    }
                    next
                })
                .collect();
        }
        let scores: Vec<f64> =
            population.par_iter().map_init(Scratch::default, |s, y| evaluator.score(y, s)).collect::<Result<_>>()?;
        evaluations += scores.len();
        let weights = importance_weights(&scores, options)?;
        last_weights.clone_from(&weights);
        for (y, &s) in population.iter().zip(&scores) {
            if s > best.0 {
                best = (s, y.clone());
            }
        }
        weighted_mean = (0..state_dims).map(|k| population.iter().zip(&weights).map(|(y, w)| w * y[k]).sum()).collect();
        let finite: Vec<f64> = scores.iter().copied().filter(|s| s.is_finite()).collect();
        history.push(IterationStats {
            best_score: finite.iter().cloned().fold(f64::NEG_INFINITY, f64::max),
            mean_score: scores.iter().zip(&weights).filter(|(s, _)| s.is_finite()).map(|(s, w)| s * w).sum(),
            effective_samples: 1.0 / weights.iter().map(|w| w * w).sum::<f64>(),
        });
        if !progress((t + 1) as f32 / options.max_iterations as f32) {
            return Err(Error::Cancelled);
        }
        let converged = previous_mean.as_ref().is_some_and(|p| {
            p.iter().zip(&weighted_mean).zip(&stds).all(|((a, b), s)| (a - b).abs() < options.tolerance * s)
        });
        if converged || t + 1 == options.max_iterations {
            break;
        }
        previous_mean = Some(weighted_mean.clone());
        let next = (population.len() / 2).max(options.samples);
        population = systematic_resample(&population, &weights, next, &mut sample_rng(options.seed, t, usize::MAX));
    }
    let (gender_value, male_probability) = match problem.gender {
        ShapeChoice::Blended => {
            let blend = problem.model.blended()?;
            let t: Vec<f64> = population.iter().map(|y| blend.gender_value(&y[..dims])).collect();
            let mean_t: f64 = t.iter().zip(&last_weights).map(|(t, w)| t * w).sum();
            let male: f64 = t.iter().zip(&last_weights).filter(|(t, _)| **t > 0.5).map(|(_, w)| w).sum();
            (Some(mean_t.clamp(0.0, 1.0)), Some(male.clamp(0.0, 1.0)))
        }
        ShapeChoice::Gendered(_) => (None, None),
    };
    // Blended space: Y* is the posterior mean over the samples on the more probable side of
    // gender 0.5. When a sketch does not settle the gender the posterior is bimodal, and the
    // mean of both modes is neither body (tuning set: rest AED centred 0.0231 vs 0.0243).
    if let (ShapeChoice::Blended, Some(male)) = (problem.gender, male_probability) {
        let blend = problem.model.blended()?;
        let side = |y: &[f64]| (blend.gender_value(&y[..dims]) > 0.5) == (male > 0.5);
        let total: f64 = population.iter().zip(&last_weights).filter(|(y, _)| side(y)).map(|(_, w)| w).sum();
        if total > 0.0 {
            weighted_mean = (0..state_dims)
                .map(|k| {
                    population.iter().zip(&last_weights).filter(|(y, _)| side(y)).map(|(y, w)| w * y[k]).sum::<f64>()
                        / total
                })
                .collect();
        }
    }
    clamp(&mut weighted_mean);
    let view_support = evaluator.view_support(&weighted_mean, &mut Scratch::default())?;
    let (edge_support, part_support) = evaluator
        .evaluate(&weighted_mean, &mut Scratch::default())?
        .map_or((0.0, PartSupport::from_counts(&[])), |(_, support, parts)| (support, parts));
    let proportions = factors.map(|_| proportions_of(&weighted_mean[dims..]));
    weighted_mean.truncate(dims);
    best.1.truncate(dims);
    let proportion_estimate = estimate.map(|e| e.proportions());
    Ok(FitResult {
        weights: weighted_mean,
        proportions,
        proportion_estimate,
        best_weights: best.1,
        best_score: best.0,
        history,
        evaluations,
        gender_value,
        male_probability,
        edge_support,
        part_support,
        view_support,
    })
}

/// The visible 2-D joints scaled to the raster (factor `f`); non-finite positions are an error.
fn joints_in_raster(joints: Option<&Joints2>, f: f64) -> Result<Vec<(usize, [f64; 2])>> {
    let Some(j) = joints else { return Ok(Vec::new()) };
    let mut out = Vec::new();
    for k in 0..j.xy.len() {
        if j.visible[k] {
            ensure_finite("2-D joint", j.xy[k][0])?;
            ensure_finite("2-D joint", j.xy[k][1])?;
            out.push((k, [j.xy[k][0] * f, j.xy[k][1] * f]));
        }
    }
    Ok(out)
}

/// Normalised importance weights (eqs. 6–7): the paper's score is used as the likelihood
/// itself; other scores through exp(score / temperature). All-hopeless populations are an error.
fn importance_weights(scores: &[f64], options: &FitOptions) -> Result<Vec<f64>> {
    let max = scores.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
    if !max.is_finite() {
        return Err(Error::OutOfRange {
            name: "fit",
            detail: "no sample projects into the image: check the camera and pose".into(),
        });
    }
    let raw: Vec<f64> = match options.score {
        MatchScore::Paper => scores.iter().map(|&s| if s.is_finite() { s.max(0.0) } else { 0.0 }).collect(),
        _ => scores.iter().map(|&s| ((s - max) / options.temperature).exp()).collect(),
    };
    let total: f64 = raw.iter().sum();
    if total <= 0.0 {
        return Ok(vec![1.0 / scores.len() as f64; scores.len()]);
    }
    Ok(raw.iter().map(|w| w / total).collect())
}

/// Systematic resampling: `m` draws from `population` with normalised `weights`, one uniform
/// offset and `m` evenly spaced pointers into the CDF.
fn systematic_resample(population: &[Vec<f64>], weights: &[f64], m: usize, rng: &mut ChaCha8Rng) -> Vec<Vec<f64>> {
    let n = population.len();
    let u0: f64 = rng.random::<f64>() / m as f64;
    let mut out = Vec::with_capacity(m);
    let (mut cdf, mut j) = (weights[0], 0);
    for i in 0..m {
        let u = u0 + i as f64 / m as f64;
        while u > cdf && j + 1 < n {
            j += 1;
            cdf += weights[j];
        }
        out.push(population[j].clone());
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn systematic_resampling_follows_the_weights() {
        let pop: Vec<Vec<f64>> = (0..4).map(|i| vec![i as f64]).collect();
        let out = systematic_resample(&pop, &[0.0, 0.5, 0.5, 0.0], 4, &mut ChaCha8Rng::seed_from_u64(3));
        assert_eq!(out.iter().filter(|y| y[0] == 1.0).count(), 2);
        assert_eq!(out.iter().filter(|y| y[0] == 2.0).count(), 2);
    }

    #[test]
    fn paper_weights_are_the_scores_normalised() {
        let o = FitOptions { score: MatchScore::Paper, ..FitOptions::default() };
        let w = importance_weights(&[0.1, 0.3, f64::NEG_INFINITY], &o).unwrap();
        assert!((w[0] - 0.25).abs() < 1e-12 && (w[1] - 0.75).abs() < 1e-12 && w[2] == 0.0);
        assert!(importance_weights(&[f64::NEG_INFINITY; 2], &o).is_err());
    }
}
