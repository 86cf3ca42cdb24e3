//! The held-out synthetic evaluation of a 2-D detector: sketches from another seed whose hair
//! style is forced to one never used in training, scored by PCK of the 15 canonical joints.

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

use nalgebra::Vector3;
use sketchbody::detect::{detect, DetectOptions, Model};
use sketchbody::error::{Error, Result};
use sketchbody::image::ImageView;
use sketchbody::render::sketch::truth::{sample_seed, GroundTruth};
use sketchbody::render::sketch::{Hair, Sketch, SketchRenderer, SketchRequest, SketchStyle};

use super::metrics::pck;

/// Stream tag of the held-out styles.
const STYLE_STREAM: u64 = 0x0048_454C_444F_5554;

/// Request `i` of the held-out set of `seed`: a random sketch whose style (drawn from its own
/// stream) has hair `hair` (all other style choices random as usual).
pub fn held_out_request(seed: u64, i: u64, size: usize, hair: Option<Hair>) -> SketchRequest {
    let s = sample_seed(seed, i);
    let mut style = SketchStyle::random(&mut ChaCha8Rng::seed_from_u64(s ^ STYLE_STREAM));
    if let Some(h) = hair {
        style.hair = h;
    }
    SketchRequest { style: Some(style), ..SketchRequest::random(s, size) }
}

/// One model's result on one sketch.
#[derive(Clone, Debug, PartialEq)]
pub struct SketchScore {
    /// PCK at each requested alpha (0 when the model finds nothing).
    pub pck: Vec<f64>,
    /// Wall time of the detection, s.
    pub seconds: f64,
    /// The scale the best detection was found at, as the figure height its pyramid level is
    /// tuned to over the shorter image side: cell px × `Model::rest_height_cells` / shorter
    /// side. `None` when the model finds nothing.
    pub found_fraction: Option<f64>,
}

/// The models' scores on one sketch, and the drawn figure's size.
#[derive(Clone, Debug, PartialEq)]
pub struct SketchResult {
    /// Height of the drawn figure (vertical extent of the projected posed mesh) over the shorter
    /// image side.
    pub figure_fraction: f64,
    /// One score per model, in the order given.
    pub scores: Vec<SketchScore>,
    /// The sketch's ground truth (style, camera angles, pose source), for [`style_breakdown`].
    pub truth: GroundTruth,
}

/// A named subset of the held-out sketches: a predicate on the ground truth.
pub struct StyleGroup {
    /// Short label, e.g. "hatching".
    pub name: &'static str,
    /// Whether a sketch belongs to the group.
    pub member: fn(&GroundTruth) -> bool,
}

fn costume(t: &GroundTruth) -> bool {
    let c = &t.style.costume;
    c.belt || c.boots || c.gloves || c.collar || c.armour || c.cape
}

fn custom_proportions(t: &GroundTruth) -> bool {
    t.style.proportions != sketchbody::body::proportions::Proportions::default()
}

/// The groups [`style_breakdown`] reports: every rendering choice that could make a figure
/// harder to find (and the complements of the two most common).
pub const STYLE_GROUPS: [StyleGroup; 13] = [
    StyleGroup { name: "all", member: |_| true },
    StyleGroup { name: "hatching", member: |t| t.style.hatching > 0.0 },
    StyleGroup { name: "no hatching", member: |t| t.style.hatching == 0.0 },
    StyleGroup { name: "creases", member: |t| t.style.crease_deg < 180.0 },
    StyleGroup { name: "costume piece", member: costume },
    StyleGroup { name: "cape", member: |t| t.style.costume.cape },
    StyleGroup { name: "stray strokes >= 5", member: |t| t.style.stray_strokes >= 5 },
    StyleGroup { name: "scribbles >= 2", member: |t| t.style.scribbles >= 2 },
    StyleGroup { name: "custom proportions", member: custom_proportions },
    StyleGroup { name: "wobble >= 1 px", member: |t| t.style.wobble >= 1.0 },
    StyleGroup { name: "strokes < 80 px", member: |t| t.style.stroke_length < 80.0 },
    StyleGroup { name: "|yaw| >= 20 deg", member: |t| t.camera.angles.yaw_deg.abs() >= 20.0 },
    StyleGroup { name: "|yaw| < 20 deg", member: |t| t.camera.angles.yaw_deg.abs() < 20.0 },
];

/// One row of [`style_breakdown`]: a group's size and each model's mean PCK at each alpha.
#[derive(Clone, Debug, PartialEq)]
pub struct GroupRow {
    /// The group's label.
    pub name: &'static str,
    /// Sketches in the group.
    pub n: usize,
    /// `mean_pck[model][alpha]`; NaN for an empty group.
    pub mean_pck: Vec<Vec<f64>>,
}

/// Mean PCK of every model per [`STYLE_GROUPS`] group of `results`: which rendering choices
/// cost which model. Errors: results with different numbers of models or alphas
/// ([`Error::OutOfRange`]).
pub fn style_breakdown(results: &[SketchResult]) -> Result<Vec<GroupRow>> {
    let models = results.first().map_or(0, |r| r.scores.len());
    let alphas = results.first().and_then(|r| r.scores.first()).map_or(0, |s| s.pck.len());
    if let Some(i) =
        results.iter().position(|r| r.scores.len() != models || r.scores.iter().any(|s| s.pck.len() != alphas))
    {
        return Err(Error::OutOfRange {
            name: "sketch results",
            detail: format!("result {i} does not hold {models} models of {alphas} alphas like the first"),
        });
    }
    Ok(STYLE_GROUPS
        .iter()
        .map(|g| {
            let members: Vec<&SketchResult> = results.iter().filter(|r| (g.member)(&r.truth)).collect();
            let n = members.len();
            let mean_pck = (0..models)
                .map(|m| {
                    (0..alphas).map(|a| members.iter().map(|r| r.scores[m].pck[a]).sum::<f64>() / n as f64).collect()
                })
                .collect();
            GroupRow { name: g.name, n, mean_pck }
        })
        .collect())
}

/// Vertical extent of the sketch's projected posed mesh over the shorter image side.
/// Errors: the camera's (an invalid stored camera).
pub fn figure_fraction(s: &Sketch) -> Result<f64> {
    let cam = s.truth.camera.to_camera()?;
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for v in &s.posed_vertices {
        let y = cam.project(&Vector3::new(v[0] as f64, v[1] as f64, v[2] as f64))[1];
        (lo, hi) = (lo.min(y), hi.max(y));
    }
    Ok(((hi - lo) / s.truth.width.min(s.truth.height) as f64).max(0.0))
}

/// PCK@alpha of each model's best detection on one rendered sketch, `alphas` in order, the
/// detection time and scale, and the drawn figure's size. Errors: the renderer's and the
/// detector's (except no figure).
pub fn score_sketch(
    renderer: &SketchRenderer,
    req: &SketchRequest,
    models: &[&Model],
    options: &DetectOptions,
    alphas: &[f64],
) -> Result<SketchResult> {
    let s = renderer.render(req)?;
    let view = ImageView::gray(&s.pixels, req.width, req.height)?;
    let short = req.width.min(req.height) as f64;
    let scores = models
        .iter()
        .map(|m| {
            let t0 = std::time::Instant::now();
            let d = detect(&view, m, options);
            let seconds = t0.elapsed().as_secs_f64();
            let (pck, found_fraction) = match d {
                Ok(d) => (
                    alphas.iter().map(|&a| pck(&s.truth.joints2d, &d.best().joints.xy, a)).collect::<Result<_>>()?,
                    Some(d.best().cell_px * m.rest_height_cells() / short),
                ),
                Err(Error::NoFigure { .. }) => (vec![0.0; alphas.len()], None),
                Err(e) => return Err(e),
            };
            Ok(SketchScore { pck, seconds, found_fraction })
        })
        .collect::<Result<_>>()?;
    Ok(SketchResult { figure_fraction: figure_fraction(&s)?, scores, truth: s.truth })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn held_out_requests_force_the_hair_and_are_deterministic() {
        let a = held_out_request(2, 5, 256, Some(Hair::Ponytail));
        assert_eq!(a.style.as_ref().map(|s| s.hair), Some(Hair::Ponytail));
        assert_eq!(a, held_out_request(2, 5, 256, Some(Hair::Ponytail)));
        assert_ne!(a.seed, held_out_request(2, 6, 256, Some(Hair::Ponytail)).seed);
        assert_eq!((a.width, a.height), (256, 256));
    }

    /// The drawn figure fills the page up to the renderer's margin (0.04..0.14 of the shorter
    /// side on every side) along its longer extent, so it is at most 1 − 2 · 0.04 tall; the
    /// embedded detector finds it at a level tuned to a figure of about that size.
    #[test]
    fn figure_fraction_and_found_scale_of_a_rendered_sketch() {
        let r =
            SketchRenderer::new(std::sync::Arc::new(sketchbody::body::BodyModel::embedded().unwrap()), None).unwrap();
        let req = held_out_request(2, 0, 256, Some(Hair::Ponytail));
        let s = r.render(&req).unwrap();
        let f = figure_fraction(&s).unwrap();
        assert!(f > 0.3 && f <= 0.92 + 1e-9, "figure fraction {f}");
        let m = Model::embedded().unwrap();
        let res =
            score_sketch(&r, &req, &[&m], &DetectOptions { threshold: Some(-1e9), ..DetectOptions::default() }, &[0.2])
                .unwrap();
        assert_eq!(res.figure_fraction, f);
        let found = res.scores[0].found_fraction.unwrap();
        assert!(found > 0.5 * f && found < 2.0 * f, "found at {found} for a figure of {f}");
        let none =
            score_sketch(&r, &req, &[&m], &DetectOptions { threshold: Some(1e9), ..DetectOptions::default() }, &[0.2])
                .unwrap();
        assert_eq!((none.scores[0].found_fraction, none.scores[0].pck.clone()), (None, vec![0.0]));
        assert_eq!(res.truth, s.truth);
    }

    /// Groups average exactly their members' PCK; complements partition the set.
    #[test]
    fn style_breakdown_averages_each_group() {
        let r =
            SketchRenderer::new(std::sync::Arc::new(sketchbody::body::BodyModel::embedded().unwrap()), None).unwrap();
        let mut results = Vec::new();
        for (i, hatching) in [(0u64, 0.0), (1, 0.3), (2, 0.4)] {
            let mut req = held_out_request(2, i, 64, Some(Hair::Ponytail));
            req.style.as_mut().unwrap().hatching = hatching;
            let truth = r.render(&req).unwrap().truth;
            let p = [0.5, 0.25, 1.0][i as usize];
            results.push(SketchResult {
                figure_fraction: 0.8,
                scores: vec![SketchScore { pck: vec![p, 1.0], seconds: 0.0, found_fraction: None }],
                truth,
            });
        }
        let rows = style_breakdown(&results).unwrap();
        let row = |name: &str| rows.iter().find(|g| g.name == name).unwrap().clone();
        assert_eq!((row("all").n, row("all").mean_pck[0][0]), (3, 1.75 / 3.0));
        assert_eq!((row("hatching").n, row("hatching").mean_pck[0][0]), (2, 0.625));
        assert_eq!((row("no hatching").n, row("no hatching").mean_pck[0].clone()), (1, vec![0.5, 1.0]));
        assert_eq!(row("|yaw| >= 20 deg").n + row("|yaw| < 20 deg").n, 3);
        assert!(style_breakdown(&[]).unwrap().iter().all(|g| g.n == 0 && g.mean_pck.is_empty()));
        results[1].scores[0].pck.pop();
        assert!(matches!(style_breakdown(&results), Err(Error::OutOfRange { .. })));
    }
}
