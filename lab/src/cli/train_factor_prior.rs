//! `sketchbody-lab train-factor-prior`: trains the learned prior on the drawn proportions
//! (`pose::factor_prior`, `assets/factor_prior.json`) on projected training motion.

use std::path::PathBuf;
use std::time::Instant;

use sketchbody::body::BodyModel;
use sketchbody::pose::dict_io;
use sketchbody_lab::pose::factor_train::{train_from_mocap, TrainParams};
use sketchbody_lab::pose::learn::{body_model_skeletons, default_held_out};

use sketchbody_cli::CliError;

/// Arguments of `sketchbody-lab train-factor-prior`.
#[derive(clap::Args)]
pub struct Args {
    /// Folder of motion tables (`*.csv`, canonical joints); repeatable (the library's prior:
    /// ../shared/data/mocap/deepmimic and ../shared/data/mocap/cmu).
    #[arg(long)]
    mocap: Vec<PathBuf>,
    /// Clip names held out (comma-separated; `SS_*` = a whole CMU subject); default: the
    /// library's held-out list (the dictionary's).
    #[arg(long, value_delimiter = ',')]
    holdout: Option<Vec<String>>,
    /// Dictionary whose bone lengths the factors refer to (default: the embedded one).
    #[arg(long)]
    dictionary: Option<PathBuf>,
    /// Seed of the poses, cameras, proportions and noise.
    #[arg(long, default_value_t = TrainParams::default().seed)]
    seed: u64,
    /// Number of projected samples.
    #[arg(long, default_value_t = TrainParams::default().samples)]
    samples: usize,
    /// Width of the network's two hidden layers.
    #[arg(long, default_value_t = TrainParams::default().hidden)]
    hidden: usize,
    /// Passes of the training over the samples.
    #[arg(long, default_value_t = TrainParams::default().epochs)]
    epochs: usize,
    /// Share of samples with the reference proportions.
    #[arg(long, default_value_t = TrainParams::default().standard_share)]
    standard_share: f64,
    /// Output file (JSON).
    #[arg(long)]
    out: PathBuf,
}

/// Runs the command.
pub fn run(a: Args) -> Result<(), CliError> {
    if a.mocap.is_empty() {
        return Err(CliError("train-factor-prior: give --mocap DIR".into()));
    }
    let t0 = Instant::now();
    let dict = match &a.dictionary {
        Some(p) => dict_io::read(p)?,
        None => dict_io::embedded()?,
    };
    let held_out = a.holdout.clone().unwrap_or_else(default_held_out);
    let skeletons = body_model_skeletons(&BodyModel::embedded()?);
    let params = TrainParams {
        seed: a.seed,
        samples: a.samples,
        hidden: a.hidden,
        epochs: a.epochs,
        standard_share: a.standard_share,
        ..TrainParams::default()
    };
    let lengths_of =
        a.dictionary.as_ref().map(|p| p.display().to_string()).unwrap_or_else(|| "the embedded dictionary".into());
    let progress = |epoch: usize, loss: f64| {
        eprintln!("train-factor-prior: epoch {epoch}/{}: training loss {loss:.4} (standardised)", params.epochs)
    };
    let prior = train_from_mocap(&a.mocap, &held_out, &skeletons, &dict.bone_lengths, &lengths_of, &params, progress)?;
    std::fs::write(&a.out, prior.to_json() + "\n")
        .map_err(|e| CliError(format!("train-factor-prior: {}: {e}", a.out.display())))?;
    println!(
        "{}: {} samples; predictive spread of ln factor {:?}; {:.1} s",
        a.out.display(),
        params.samples,
        prior.sd.iter().map(|v| (v * 1e3).round() / 1e3).collect::<Vec<_>>(),
        t0.elapsed().as_secs_f64()
    );
    Ok(())
}
