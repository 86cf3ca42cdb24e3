//! `sketchbody-lab shape-floor DATASET [--dims 4,10]`: the floor of the shape fit on a dataset:
//! each sample's true rest mesh projected (least squares) onto its true gender's shape space of
//! the body model at a few dimension counts, scored as `eval` scores a fit (rest AED centred and
//! at the true height, over the true height), beside the gender's mean shape. No fit reaches
//! below its dimension count's row; a floor near the mean shape's row says the model cannot
//! express the set's bodies.

use std::path::PathBuf;

use sketchbody::body::{BodyModel, Gender};
use sketchbody::render::sketch::truth::{parse_mesh, GroundTruth};
use sketchbody_lab::eval::metrics::{aed, centred, scale_to_height};
use sketchbody_lab::eval::score::dataset_samples;

use sketchbody_cli::CliError;

/// Arguments of `sketchbody-lab shape-floor`.
#[derive(clap::Args)]
pub struct Args {
    /// Dataset folder (make-dataset or scripts/make-blender-set.sh layout).
    dataset: PathBuf,
    /// Dimension counts to project onto (comma-separated; each at most the space's components).
    #[arg(long, value_delimiter = ',', default_value = "4,10")]
    dims: Vec<usize>,
}

/// The two AEDs of a rest estimate against the truth: centred, and scaled to the true height.
fn rest_aeds(reference: &[[f64; 3]], estimate: &[[f64; 3]], height: f64) -> Result<[f64; 2], CliError> {
    Ok([
        aed(&centred(reference), &centred(estimate), height)?,
        aed(reference, &scale_to_height(reference, estimate, height)?, height)?,
    ])
}

fn to_f64(v: &[[f32; 3]]) -> Vec<[f64; 3]> {
    v.iter().map(|p| [p[0] as f64, p[1] as f64, p[2] as f64]).collect()
}

/// Runs the command.
pub fn run(a: Args) -> Result<(), CliError> {
    let model = BodyModel::embedded()?;
    let stems = dataset_samples(&a.dataset)?;
    if stems.is_empty() {
        return Err(CliError(format!("{}: no samples (STEM.json with STEM.mesh)", a.dataset.display())));
    }
    // Per row (the mean shape, then each dimension count): sums of the two AEDs.
    let mut sums = vec![[0.0f64; 2]; 1 + a.dims.len()];
    for stem in &stems {
        let jp = a.dataset.join(format!("{stem}.json"));
        let text = std::fs::read_to_string(&jp).map_err(|e| CliError(format!("{}: {e}", jp.display())))?;
        let truth = GroundTruth::from_json(&text, &jp.display().to_string())?;
        let mp = a.dataset.join(format!("{stem}.mesh"));
        let bytes = std::fs::read(&mp).map_err(|e| CliError(format!("{}: {e}", mp.display())))?;
        let rest = parse_mesh(&bytes, &mp.display().to_string())?.0;
        let space = model.space(Gender::parse(&truth.gender)?);
        let reference = to_f64(&rest);
        let mean = rest_aeds(&reference, &to_f64(space.mean()), truth.height_m)?;
        let mut row = vec![mean];
        for &d in &a.dims {
            let w = space.project(&rest, d)?;
            let shape = space.synthesize(&w)?;
            row.push(rest_aeds(&reference, &to_f64(&shape.vertices), truth.height_m)?);
        }
        for (s, r) in sums.iter_mut().zip(&row) {
            s[0] += r[0];
            s[1] += r[1];
        }
    }
    let n = stems.len() as f64;
    println!("{} samples of {}", stems.len(), a.dataset.display());
    println!("| shape | rest centred | rest at height | × mean (centred) |");
    println!("|---|---:|---:|---:|");
    let mean_centred = sums[0][0] / n;
    let labels =
        std::iter::once("mean shape".to_string()).chain(a.dims.iter().map(|d| format!("truth projected, {d} dims")));
    for (label, s) in labels.zip(&sums) {
        println!("| {label} | {:.4} | {:.4} | {:.3} |", s[0] / n, s[1] / n, s[0] / n / mean_centred);
    }
    Ok(())
}
