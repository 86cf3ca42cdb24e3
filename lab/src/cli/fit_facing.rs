//! `sketchbody-lab fit-facing --out assets/facing_model.json`: fits the facing model
//! (`detect::facing`) on rendered sketches of every yaw (their torso's yaw gives the true
//! facing), of a seed no benchmark set uses.

use std::path::PathBuf;

use sketchbody::detect::figure::FigureOptions;
use sketchbody::detect::landmark::LandmarkNet;
use sketchbody::detect::Model;
use sketchbody_lab::eval::facing::{confusion, fit_facing};

use crate::backend_sets::{gather_set, SetContext, SetSpec, View};
use crate::render_sketch::renderer;
use sketchbody_cli::CliError;

/// Arguments of `sketchbody-lab fit-facing`.
#[derive(clap::Args)]
pub struct Args {
    /// Output model JSON.
    #[arg(long)]
    out: PathBuf,
    /// Rendered sketches of any yaw, plain.
    #[arg(long, default_value_t = 400)]
    n: usize,
    /// Further sketches of any yaw painted in art styles.
    #[arg(long, default_value_t = 100)]
    art: usize,
    /// Seed of the sketches (the benchmark's held-out sets use 2).
    #[arg(long, default_value_t = 11)]
    seed: u64,
    /// L2 penalty on the standardised coefficients.
    #[arg(long, default_value_t = 1e-2)]
    ridge: f64,
    /// Folder of mocap clips (default as in render-sketch).
    #[arg(long)]
    mocap: Option<PathBuf>,
}

/// Runs the command.
pub fn run(a: Args) -> Result<(), CliError> {
    let model = Model::embedded()?;
    let net = LandmarkNet::embedded()?;
    let r = renderer(a.mocap.as_deref())?;
    let parse = PathBuf::new();
    let ctx = SetContext { renderer: &r, parse_dir: &parse, model: &model, net: &net };
    let mut specs =
        vec![SetSpec::Synthetic { seed: a.seed, n: a.n, size: 512, hair: None, view: View::AnyYaw, art: false }];
    if a.art > 0 {
        specs.push(SetSpec::Synthetic {
            seed: a.seed + 1000,
            n: a.art,
            size: 512,
            hair: None,
            view: View::AnyYaw,
            art: true,
        });
    }
    let mut samples = Vec::new();
    for s in &specs {
        samples.extend(gather_set(s, &ctx, &FigureOptions::default())?);
    }
    let provenance = format!(
        "sketchbody-lab fit-facing --n {} --art {} --seed {} --ridge {}; {} sketches of any yaw rendered by the \
         library's sketch renderer (seeds {} and {}; the benchmark's sets use seed 2, the Blender set another \
         renderer), labelled by their torso's yaw. Data: the embedded body model (MakeHuman data, CC0), poses of the \
         clips of {} (by default the DeepMimic clips, MIT licence), BlazePose's outputs (Apache-2.0, assets/pose_landmark_full.LICENSE); the file \
         holds the coefficients only, no image or motion data.",
        a.n,
        a.art,
        a.seed,
        a.ridge,
        samples.len(),
        a.seed,
        a.seed + 1000,
        a.mocap.as_ref().map_or("mocap/deepmimic".into(), |p| p.display().to_string())
    );
    let m = fit_facing(&samples, a.ridge, &provenance)?;
    eprintln!("decided facing on the fitting sketches (rows: true front, back, left, right; columns: decided front, back, left, right, unknown):");
    for (k, row) in confusion(&samples, &m).iter().enumerate() {
        eprintln!("  {:<6} {row:?}", ["front", "back", "left", "right"][k]);
    }
    let mut text = m.to_json();
    text.push('\n');
    std::fs::write(&a.out, text).map_err(|e| CliError(format!("{}: {e}", a.out.display())))?;
    eprintln!("wrote {}", a.out.display());
    Ok(())
}
