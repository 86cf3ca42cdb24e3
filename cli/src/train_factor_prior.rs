//! `sketchbody train-factor-prior`: trains the learned prior on the drawn proportions
//! (`pose::factor_prior`, `assets/factor_prior.json`) on projected training motion.

use std::path::PathBuf;
use std::time::Instant;

use sketchbody::body::BodyModel;
use sketchbody::pose::dict_io;
use sketchbody::pose::factor_train::{train, TrainParams};
use sketchbody::pose::learn::{body_model_skeletons, clip_matches, default_held_out, motion_files, retarget_frames};
use sketchbody::pose::motion::{normalize_pose, read_motion_csv};

use crate::CliError;

/// Arguments of `sketchbody train-factor-prior`.
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
    /// Ridge penalty per sample.
    #[arg(long, default_value_t = TrainParams::default().ridge)]
    ridge: f64,
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
    let (mut frames, mut clips) = (Vec::new(), Vec::new());
    for dir in &a.mocap {
        for f in motion_files(dir)? {
            let name = f.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
            if held_out.iter().any(|h| clip_matches(h, &name)) {
                continue;
            }
            frames.extend(retarget_frames(&name, read_motion_csv(&f)?, &skeletons)?.iter().filter_map(normalize_pose));
            clips.push(name);
        }
    }
    let params = TrainParams {
        seed: a.seed,
        samples: a.samples,
        ridge: a.ridge,
        standard_share: a.standard_share,
        ..TrainParams::default()
    };
    let dirs: Vec<String> = a.mocap.iter().map(|d| d.display().to_string()).collect();
    let provenance = format!(
        "sketchbody train-factor-prior --mocap {} (held out: {}; bone lengths of {}), deterministic. \
         Data: DeepMimic clips (MIT licence) and CMU Graphics Lab clips (mocap.cs.cmu.edu, created \
         with funding from NSF EIA-0196217), retargeted onto the body model's mean skeletons and \
         normalised to 1.75 m; the file holds regression weights only, no motion data.\n\
         clips ({}, {} frames): {}\nheld_out: {}",
        dirs.join(" --mocap "),
        held_out.join(","),
        a.dictionary.as_ref().map(|p| p.display().to_string()).unwrap_or_else(|| "the embedded dictionary".into()),
        clips.len(),
        frames.len(),
        clips.join(","),
        held_out.join(",")
    );
    let prior = train(&frames, &dict.bone_lengths, &params, &provenance)?;
    std::fs::write(&a.out, prior.to_json() + "\n")
        .map_err(|e| CliError(format!("train-factor-prior: {}: {e}", a.out.display())))?;
    println!(
        "{}: {} clips, {} frames, {} samples; predictive spread of ln factor {:?}; {:.1} s",
        a.out.display(),
        clips.len(),
        frames.len(),
        params.samples,
        prior.sd.iter().map(|v| (v * 1e3).round() / 1e3).collect::<Vec<_>>(),
        t0.elapsed().as_secs_f64()
    );
    Ok(())
}
