//! `sketchbody-lab fit-landmark-joints --train DATASET [--test DATASET …] [--first N]`: fits
//! `detect::landmark::JointDefinitions`, the shifts from BlazePose's mapped landmarks to the
//! body model's joints, on `make-dataset` sketches (their true 2-D joints), and prints the Rust
//! constant and, per set, the BlazePose joints' mean distance to the true ones (fraction of the
//! true joints' box diagonal) and PCK@0.05 / @0.1 on that diagonal, as mapped and as shifted.
//! `--shipped` evaluates the shipped definitions on the --test sets instead.

use std::path::{Path, PathBuf};

use sketchbody::detect::landmark::{detect_blazepose, BlazePoseOptions, JointDefinitions, LandmarkNet};
use sketchbody::image::load_rgb_image;
use sketchbody::render::sketch::GroundTruth;
use sketchbody::skeleton::{Joints2, NUM_JOINTS};
use sketchbody_lab::eval::score::dataset_samples;

use sketchbody_cli::CliError;

/// Arguments of `sketchbody-lab fit-landmark-joints`.
#[derive(clap::Args)]
pub struct Args {
    /// Training set: a make-dataset folder. Repeatable.
    #[arg(long)]
    train: Vec<PathBuf>,
    /// Test set, same form; reported, never trained on. Repeatable.
    #[arg(long)]
    test: Vec<PathBuf>,
    /// Report the shipped definitions on the --test sets instead of fitting.
    #[arg(long, conflicts_with = "train")]
    shipped: bool,
    /// Use only the first N samples of each set.
    #[arg(long)]
    first: Option<usize>,
}

/// BlazePose's mapped joints (no shift) and the true joints of every sample of `dataset` where
/// BlazePose finds a figure; prints how many it missed.
fn load(net: &LandmarkNet, dataset: &Path, first: Option<usize>) -> Result<Vec<(Joints2, Joints2)>, CliError> {
    let opts = BlazePoseOptions { definitions: JointDefinitions::IDENTITY, ..BlazePoseOptions::default() };
    let stems = dataset_samples(dataset)?;
    let stems = &stems[..stems.len().min(first.unwrap_or(usize::MAX))];
    let mut out = Vec::with_capacity(stems.len());
    for stem in stems {
        let tp = dataset.join(format!("{stem}.json"));
        let text = std::fs::read_to_string(&tp).map_err(|e| CliError(format!("{}: {e}", tp.display())))?;
        let t = GroundTruth::from_json(&text, &tp.display().to_string())?;
        if t.joints2d.len() != NUM_JOINTS {
            return Err(CliError(format!("{}: {} joints, need {NUM_JOINTS}", tp.display(), t.joints2d.len())));
        }
        let truth = Joints2 {
            xy: std::array::from_fn(|k| t.joints2d[k]),
            visible: std::array::from_fn(|k| t.visible.get(k).copied().unwrap_or(true)),
        };
        let img = load_rgb_image(&dataset.join(format!("{stem}.png")))?;
        match detect_blazepose(net, &img.view(), &opts) {
            Ok(d) => out.push((d.joints, truth)),
            Err(sketchbody::Error::NoFigure { .. }) => {}
            Err(e) => return Err(e.into()),
        }
    }
    println!("{}: BlazePose found {} of {} figures", dataset.display(), out.len(), stems.len());
    Ok(out)
}

/// `(mean distance, PCK@0.05, PCK@0.1)` of `joints` against the truths, as fractions of each
/// true figure's joint-box diagonal.
fn score(pairs: &[(Joints2, Joints2)], shift: &JointDefinitions) -> (f64, f64, f64) {
    let (mut sum, mut p05, mut p10, mut n) = (0.0, 0, 0, 0usize);
    for (mapped, truth) in pairs {
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for p in &truth.xy {
            for a in 0..2 {
                lo[a] = lo[a].min(p[a]);
                hi[a] = hi[a].max(p[a]);
            }
        }
        let diag = (hi[0] - lo[0]).hypot(hi[1] - lo[1]).max(1.0);
        let shifted = shift.apply(mapped);
        for (p, q) in shifted.xy.iter().zip(&truth.xy) {
            let d = (p[0] - q[0]).hypot(p[1] - q[1]) / diag;
            sum += d;
            p05 += usize::from(d < 0.05);
            p10 += usize::from(d < 0.1);
            n += 1;
        }
    }
    let n = n.max(1) as f64;
    (sum / n, p05 as f64 / n, p10 as f64 / n)
}

fn report(what: &str, pairs: &[(Joints2, Joints2)], d: &JointDefinitions) {
    let (e0, a0, b0) = score(pairs, &JointDefinitions::IDENTITY);
    let (e1, a1, b1) = score(pairs, d);
    println!(
        "{what}: {} figures, mean distance {e0:.4} mapped -> {e1:.4} shifted, PCK@0.05 {a0:.3} -> {a1:.3}, PCK@0.1 {b0:.3} -> {b1:.3}",
        pairs.len()
    );
}

fn row(v: &[f64; NUM_JOINTS]) -> String {
    v.iter().map(|x| format!("{x:.6}")).collect::<Vec<_>>().join(", ")
}

/// Runs the command.
pub fn run(a: Args) -> Result<(), CliError> {
    let net = LandmarkNet::embedded()?;
    let d = if a.shipped {
        if a.test.is_empty() {
            return Err(CliError("--shipped needs at least one --test DATASET".into()));
        }
        JointDefinitions::SHIPPED
    } else {
        if a.train.is_empty() {
            return Err(CliError("give --train DATASET (or --shipped with --test)".into()));
        }
        let mut pairs = Vec::new();
        for t in &a.train {
            pairs.extend(load(&net, t, a.first)?);
        }
        let d = JointDefinitions::fit(&pairs)?;
        println!("JointDefinitions {{ along_torso: [{}], outward: [{}] }}", row(&d.along_torso), row(&d.outward));
        report("training", &pairs, &d);
        d
    };
    for t in &a.test {
        let pairs = load(&net, t, a.first)?;
        report(&format!("test {}", t.display()), &pairs, &d);
    }
    Ok(())
}
