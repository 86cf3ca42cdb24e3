//! `sketchbody-lab learn-poses`: learns the basis-pose dictionary from motion tables and BVH files.

use std::path::PathBuf;

use sketchbody::body::BodyModel;
use sketchbody::pose::dict_io;
use sketchbody::pose::LearnParams;
use sketchbody_lab::pose::learn::{body_model_skeletons, default_held_out, learn_from_sources, lying_clips, LearnSpec};

use sketchbody_cli::CliError;

/// Arguments of `sketchbody-lab learn-poses`.
#[derive(clap::Args)]
pub struct Args {
    /// Folder of motion tables (`*.csv`, canonical joints, e.g. ../shared/data/mocap/deepmimic);
    /// repeatable (the library's dictionary: the DeepMimic and the CMU folders).
    #[arg(long)]
    mocap: Vec<PathBuf>,
    /// BVH files to learn from (CMU-, Mixamo- or Rokoko-style joint names); repeatable.
    #[arg(long)]
    bvh: Vec<PathBuf>,
    /// Clip names held out for measurement (comma-separated; `SS_*` = a whole CMU subject);
    /// default: the library's list.
    #[arg(long, value_delimiter = ',')]
    holdout: Option<Vec<String>>,
    /// Further clip names to leave out (comma-separated).
    #[arg(long, value_delimiter = ',')]
    exclude: Vec<String>,
    /// Also leave out the lying / upside-down clips (crawl, roll, getup_*, backflip, cartwheel, sideflip).
    #[arg(long)]
    exclude_lying: bool,
    /// Most principal components per action.
    #[arg(long, default_value_t = LearnParams::default().max_per_action)]
    max_per_action: usize,
    /// Fraction of each action's variance to keep, in (0, 1].
    #[arg(long, default_value_t = LearnParams::default().energy)]
    energy: f64,
    /// Exemplar spacing, metres: the RMS joint distance below which a training pose is not kept
    /// as another exemplar of its action (0 = no exemplars).
    #[arg(long, default_value_t = LearnParams::default().exemplar_spacing)]
    exemplar_spacing: f64,
    /// Do not add left/right mirrored poses.
    #[arg(long)]
    no_mirror: bool,
    /// Learn in the clips' own joint convention instead of retargeting every frame onto the
    /// body model's mean skeletons (the default; see docs/formats.md).
    #[arg(long)]
    source_skeleton: bool,
    /// Output dictionary file (.skbpd).
    #[arg(long)]
    out: PathBuf,
}

/// Runs the command.
pub fn run(a: Args) -> Result<(), CliError> {
    if a.mocap.is_empty() && a.bvh.is_empty() {
        return Err(CliError("learn-poses: give --mocap DIR and/or --bvh FILE".into()));
    }
    let mut excluded = a.exclude.clone();
    if a.exclude_lying {
        excluded.extend(lying_clips());
    }
    let spec = LearnSpec {
        held_out: a.holdout.unwrap_or_else(default_held_out),
        excluded,
        params: LearnParams {
            max_per_action: a.max_per_action,
            energy: a.energy,
            mirror: !a.no_mirror,
            exemplar_spacing: a.exemplar_spacing,
        },
        retarget: if a.source_skeleton { Vec::new() } else { body_model_skeletons(&BodyModel::embedded()?) },
    };
    let d = learn_from_sources(&a.mocap, &a.bvh, &spec)?;
    dict_io::write(&d, &a.out)?;
    println!(
        "{}: {} bases in {} actions, {} exemplars",
        a.out.display(),
        d.num_bases(),
        d.actions.len(),
        d.exemplars.ncols()
    );
    Ok(())
}
