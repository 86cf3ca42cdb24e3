//! Labelled image sets for the detector backends' calibration (`calibrate-detector`) and
//! evaluation (`eval-detector --sets`): rendered sketches, PARSE photos plain or through a
//! stylisation never used in training, and pages without a figure.

use std::path::Path;
use std::time::Instant;

use rayon::prelude::*;
use sketchbody::detect::figure::FigureOptions;
use sketchbody::detect::joints::parse_to_canonical;
use sketchbody::detect::landmark::LandmarkNet;
use sketchbody::detect::Model;
use sketchbody::image::{load_rgb_image, ImageView, RgbImage};
use sketchbody::render::sketch::{Hair, SketchRenderer};
use sketchbody::skeleton::NUM_JOINTS;
use sketchbody_lab::detect::parse_eval::read_labels;
use sketchbody_lab::eval::backends::{gather_sample, Sample};
use sketchbody_lab::eval::detector::held_out_request;
use sketchbody_lab::render::photo_npr::{photo_npr, PhotoNpr};
use sketchbody_lab::render::stylise::{negative_page, stylise, NegativePage, Stylisation};

use sketchbody_cli::CliError;

/// One named set of images.
#[derive(Clone, Debug, PartialEq)]
pub enum SetSpec {
    /// `n` rendered sketches of `seed` (`size`² px), hair forced to `hair` (None: random).
    Synthetic { seed: u64, n: usize, size: usize, hair: Option<Hair> },
    /// PARSE images `first..=last`, plain or through a benchmark stylisation or a training
    /// filter (`npr`; at most one of the two), seeded by the image number.
    Parse { first: usize, last: usize, style: Option<Stylisation>, npr: Option<PhotoNpr> },
    /// `n` pages without a figure of `kind` (512² px), seeds from `seed`.
    Negative { kind: NegativePage, n: usize, seed: u64 },
}

impl SetSpec {
    /// Short label for tables.
    pub fn label(&self) -> String {
        match self {
            SetSpec::Synthetic { seed, .. } => format!("synthetic (seed {seed})"),
            SetSpec::Parse { first, last, style: Some(s), .. } => format!("PARSE {first}-{last} {}", s.name()),
            SetSpec::Parse { first, last, npr: Some(f), .. } => format!("PARSE {first}-{last} npr {}", f.name()),
            SetSpec::Parse { first, last, .. } => format!("PARSE {first}-{last}"),
            SetSpec::Negative { kind, .. } => format!("no figure: {}", kind.name()),
        }
    }

    fn len(&self) -> usize {
        match *self {
            SetSpec::Synthetic { n, .. } | SetSpec::Negative { n, .. } => n,
            SetSpec::Parse { first, last, .. } => last + 1 - first,
        }
    }
}

/// What the sets need: the renderer, PARSE's folder and labels, both models.
pub struct SetContext<'a> {
    /// Renderer for synthetic sets.
    pub renderer: &'a SketchRenderer,
    /// `../shared/data/parse` (images/ and labels.csv).
    pub parse_dir: &'a Path,
    /// The sketch model.
    pub model: &'a Model,
    /// The landmark network.
    pub net: &'a LandmarkNet,
}

/// The true canonical joints of an image (continuous px), `None` for a page without a figure.
type Truth = Option<[[f64; 2]; NUM_JOINTS]>;

/// Builds image `i` of `spec` with its truth.
fn image_of(
    spec: &SetSpec,
    i: usize,
    ctx: &SetContext<'_>,
    labels: &[sketchbody_lab::detect::parse_eval::Labelled],
) -> Result<(RgbImage, Truth), CliError> {
    Ok(match *spec {
        SetSpec::Synthetic { seed, size, hair, .. } => {
            let s = ctx.renderer.render(&held_out_request(seed, i as u64, size, hair))?;
            let rgb = s.pixels.iter().flat_map(|&g| [g; 3]).collect();
            let truth: [[f64; 2]; NUM_JOINTS] = s
                .truth
                .joints2d
                .as_slice()
                .try_into()
                .map_err(|_| CliError(format!("sketch {i}: {} true joints", s.truth.joints2d.len())))?;
            (RgbImage::from_vec(size, size, rgb)?, Some(truth))
        }
        SetSpec::Parse { first, style, npr, .. } => {
            let name = format!("im{:04}.jpg", first + i);
            let l = labels
                .iter()
                .find(|l| l.image == name)
                .ok_or_else(|| CliError(format!("PARSE labels have no {name}")))?;
            let img = load_rgb_image(&ctx.parse_dir.join("images").join(&name))?;
            let img = match (style, npr) {
                (Some(st), _) => stylise(&img.view(), st, (first + i) as u64)?,
                (None, Some(f)) => {
                    let g = photo_npr(&img.view(), f, (first + i) as u64)?;
                    RgbImage::from_vec(img.width(), img.height(), g.iter().flat_map(|&v| [v; 3]).collect())?
                }
                (None, None) => img,
            };
            let (j, _) = parse_to_canonical(&l.joints, &[1.0; 14]);
            // PARSE labels are pixel indices (centres at integers); the library's frame is continuous.
            (img, Some(j.xy.map(|p| [p[0] + 0.5, p[1] + 0.5])))
        }
        SetSpec::Negative { kind, seed, .. } => {
            (negative_page(kind, 512, 512, seed.wrapping_mul(1000) + i as u64)?, None)
        }
    })
}

/// Gathers both backends' evidence on every image of `spec`, in parallel.
pub fn gather_set(spec: &SetSpec, ctx: &SetContext<'_>, options: &FigureOptions) -> Result<Vec<Sample>, CliError> {
    let labels = match spec {
        SetSpec::Parse { .. } => read_labels(&ctx.parse_dir.join("labels.csv"))?,
        _ => Vec::new(),
    };
    let t0 = Instant::now();
    let out = (0..spec.len())
        .into_par_iter()
        .map(|i| {
            let (img, truth) = image_of(spec, i, ctx, &labels)?;
            let view: ImageView<'_> = img.view();
            Ok(gather_sample(&view, truth, ctx.model, ctx.net, options)?)
        })
        .collect::<Result<Vec<_>, CliError>>()?;
    eprintln!("{}: {} images gathered in {:.1} s", spec.label(), out.len(), t0.elapsed().as_secs_f64());
    Ok(out)
}
