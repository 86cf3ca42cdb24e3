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
use sketchbody::render::sketch::{ArtStyle, CameraAngles, GroundTruth, Hair, SketchRenderer};
use sketchbody::skeleton::NUM_JOINTS;
use sketchbody_lab::detect::parse_eval::read_labels;
use sketchbody_lab::eval::backends::{gather_sample, Sample};
use sketchbody_lab::eval::detector::held_out_request;
use sketchbody_lab::eval::facing::torso_yaw_deg;
use sketchbody_lab::render::photo_npr::{photo_npr, PhotoNpr};
use sketchbody_lab::render::stylise::{negative_page, stylise, NegativePage, Stylisation};

use sketchbody_cli::CliError;

/// The camera yaw of a synthetic set's sketches.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum View {
    /// The renderer's own near-frontal angles (yaw ±30°).
    Random,
    /// Back views: yaw 180° ± 20° (pitch ±10°, roll ±5°).
    Back,
    /// Profiles: yaw ±(70°..110°), either side.
    Profile,
    /// Any yaw in ±180° (for fitting the facing model).
    AnyYaw,
}

impl View {
    /// The camera angles of sketch `seed` of this view (`None`: the renderer's own), drawn from
    /// a stream of their own.
    pub fn angles(self, seed: u64) -> Option<CameraAngles> {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed ^ 0x0059_4157_5649_4557);
        let yaw = match self {
            View::Random => return None,
            View::Back => {
                let y: f64 = 180.0 + rng.random_range(-20.0..=20.0);
                if y > 180.0 {
                    y - 360.0
                } else {
                    y
                }
            }
            View::Profile => rng.random_range(70.0..=110.0) * if rng.random_bool(0.5) { 1.0 } else { -1.0 },
            View::AnyYaw => rng.random_range(-180.0..=180.0),
        };
        Some(CameraAngles {
            yaw_deg: yaw,
            pitch_deg: rng.random_range(-10.0..=10.0),
            roll_deg: rng.random_range(-5.0..=5.0),
        })
    }

    fn label(self) -> &'static str {
        match self {
            View::Random => "",
            View::Back => ", back views",
            View::Profile => ", profiles",
            View::AnyYaw => ", any yaw",
        }
    }
}

/// One named set of images.
#[derive(Clone, Debug, PartialEq)]
pub enum SetSpec {
    /// `n` rendered sketches of `seed` (`size`² px), hair forced to `hair` (None: random), the
    /// camera's yaw as `view` says, painted in a random art style when `art`.
    Synthetic { seed: u64, n: usize, size: usize, hair: Option<Hair>, view: View, art: bool },
    /// The first `n` samples of a rendered dataset folder (`STEM.png`, `STEM.json`; e.g. the
    /// independent Blender set of docs/dataset.md), in file-name order.
    Dataset { dir: std::path::PathBuf, n: usize },
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
            SetSpec::Synthetic { seed, view, art, .. } => {
                format!("synthetic (seed {seed}{}{})", view.label(), if *art { ", art" } else { "" })
            }
            SetSpec::Dataset { dir, .. } => format!("dataset {}", dir.display()),
            SetSpec::Parse { first, last, style: Some(s), .. } => format!("PARSE {first}-{last} {}", s.name()),
            SetSpec::Parse { first, last, npr: Some(f), .. } => format!("PARSE {first}-{last} npr {}", f.name()),
            SetSpec::Parse { first, last, .. } => format!("PARSE {first}-{last}"),
            SetSpec::Negative { kind, .. } => format!("no figure: {}", kind.name()),
        }
    }

    fn len(&self) -> usize {
        match *self {
            SetSpec::Synthetic { n, .. } | SetSpec::Negative { n, .. } | SetSpec::Dataset { n, .. } => n,
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

/// The true joints of a rendered sketch's ground truth.
fn truth_joints(t: &GroundTruth, i: usize) -> Result<[[f64; 2]; NUM_JOINTS], CliError> {
    t.joints2d.as_slice().try_into().map_err(|_| CliError(format!("sketch {i}: {} true joints", t.joints2d.len())))
}

/// The sketches of a rendered dataset folder: its `STEM.png` files that have a `STEM.json`, in
/// file-name order.
pub fn dataset_images(dir: &std::path::Path) -> Result<Vec<std::path::PathBuf>, CliError> {
    let mut v: Vec<std::path::PathBuf> = std::fs::read_dir(dir)
        .map_err(|e| CliError(format!("{}: {e}", dir.display())))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "png") && p.with_extension("json").is_file())
        .collect();
    v.sort();
    Ok(v)
}

/// Builds image `i` of `spec` with its truth.
fn image_of(
    spec: &SetSpec,
    i: usize,
    ctx: &SetContext<'_>,
    labels: &[sketchbody_lab::detect::parse_eval::Labelled],
    stems: &[std::path::PathBuf],
) -> Result<(RgbImage, Truth, Option<f64>), CliError> {
    Ok(match spec {
        &SetSpec::Synthetic { seed, size, hair, view, art, .. } => {
            let mut req = held_out_request(seed, i as u64, size, hair);
            req.camera = view.angles(req.seed);
            let s = if art {
                use rand::SeedableRng;
                let style = ArtStyle::random(&mut rand_chacha::ChaCha8Rng::seed_from_u64(req.seed ^ 0x0041_5254));
                ctx.renderer.render_art(&req, &style)?
            } else {
                ctx.renderer.render(&req)?
            };
            let rgb = s.pixels.iter().flat_map(|&g| [g; 3]).collect();
            let truth = truth_joints(&s.truth, i)?;
            (RgbImage::from_vec(size, size, rgb)?, Some(truth), torso_yaw_deg(&s.truth))
        }
        SetSpec::Dataset { .. } => {
            let png = &stems[i];
            let json = png.with_extension("json");
            let text = std::fs::read_to_string(&json).map_err(|e| CliError(format!("{}: {e}", json.display())))?;
            let t = GroundTruth::from_json(&text, &json.display().to_string())?;
            (load_rgb_image(png)?, Some(truth_joints(&t, i)?), torso_yaw_deg(&t))
        }
        &SetSpec::Parse { first, style, npr, .. } => {
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
            (img, Some(j.xy.map(|p| [p[0] + 0.5, p[1] + 0.5])), None)
        }
        &SetSpec::Negative { kind, seed, .. } => {
            (negative_page(kind, 512, 512, seed.wrapping_mul(1000) + i as u64)?, None, None)
        }
    })
}

/// Gathers both backends' evidence on every image of `spec`, in parallel.
pub fn gather_set(spec: &SetSpec, ctx: &SetContext<'_>, options: &FigureOptions) -> Result<Vec<Sample>, CliError> {
    let labels = match spec {
        SetSpec::Parse { .. } => read_labels(&ctx.parse_dir.join("labels.csv"))?,
        _ => Vec::new(),
    };
    let stems = match spec {
        SetSpec::Dataset { dir, n } => {
            let mut v = dataset_images(dir)?;
            if v.len() < *n {
                return Err(CliError(format!("{}: {} samples, {n} asked", dir.display(), v.len())));
            }
            v.truncate(*n);
            v
        }
        _ => Vec::new(),
    };
    let t0 = Instant::now();
    let out = (0..spec.len())
        .into_par_iter()
        .map(|i| {
            let (img, truth, yaw) = image_of(spec, i, ctx, &labels, &stems)?;
            let view: ImageView<'_> = img.view();
            let mut s = gather_sample(&view, truth, ctx.model, ctx.net, options)?;
            s.yaw_deg = yaw;
            Ok(s)
        })
        .collect::<Result<Vec<_>, CliError>>()?;
    eprintln!("{}: {} images gathered in {:.1} s", spec.label(), out.len(), t0.elapsed().as_secs_f64());
    Ok(out)
}
