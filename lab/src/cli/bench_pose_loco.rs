//! `sketchbody-lab bench-pose --suite --loco`: leave-one-category-out validation of the 3-D pose
//! step (issue 46). For each action category of `cmu_more` ([`super::bench_pose_suite::CATEGORIES`]),
//! the learned parts — the dictionary (`learn-poses`) and the learned priors, i.e. the factor
//! network and the learned depths (`train-factor-prior`) — are retrained on every training clip
//! of DeepMimic, CMU and the *other* seven categories (the library's held-out clips stay out),
//! and only that category is scored, with the suite's cases (the same random stream as the
//! plain suite's row of that category). A `loco` row sums the folds.

use std::path::PathBuf;
use std::time::Instant;

use sketchbody::body::BodyModel;
use sketchbody::pose::{dict_io, PoseOptions};
use sketchbody_lab::pose::factor_train::{train_from_mocap, TrainParams};
use sketchbody_lab::pose::learn::{body_model_skeletons, default_held_out, learn_from_sources, LearnSpec};

use crate::bench_pose::thread_cpu_s;
use crate::bench_pose_suite::{
    print_category_rows, print_header, score_sets, suite_sets, CategoryScores, Suite, CATEGORIES,
};
use sketchbody_cli::CliError;

/// The motion folders a fold trains on: DeepMimic, CMU and every sub-folder of `cmu_more`.
fn training_folders(suite: &Suite) -> Result<Vec<PathBuf>, CliError> {
    let mut dirs = vec![suite.mocap.to_path_buf()];
    dirs.extend(suite.cmu.cloned());
    if let Some(root) = suite.cmu_more {
        let io = |e: std::io::Error| CliError(format!("bench-pose --loco {}: {e}", root.display()));
        let mut more: Vec<PathBuf> = std::fs::read_dir(root)
            .map_err(io)?
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.is_dir())
            .collect();
        more.sort();
        dirs.extend(more);
    }
    Ok(dirs)
}

/// Runs the leave-one-category-out folds with options `opts` (module doc); `only`: the
/// categories to run (all when empty). `train`: the learned priors' training parameters.
pub fn run(opts: &PoseOptions, suite: &Suite, only: &[String], train: &TrainParams) -> Result<(), CliError> {
    if suite.cmu_more.is_none() {
        return Err(CliError("bench-pose --loco: give --cmu-more DIR (the categories to hold out)".into()));
    }
    let unknown: Vec<&String> = only.iter().filter(|c| !CATEGORIES.iter().any(|(n, _)| n == c)).collect();
    if !unknown.is_empty() {
        return Err(CliError(format!("bench-pose --loco-categories: unknown categories {unknown:?}")));
    }
    let folders = training_folders(suite)?;
    let skeletons = body_model_skeletons(&BodyModel::embedded()?);
    // The sets in the plain suite's order, so that each category keeps its random stream.
    let sets = suite_sets(&dict_io::embedded()?, suite)?;
    println!("bench-pose --loco: seed {}; options {opts:?}; training folders {folders:?}", suite.seed);
    let mut all = CategoryScores::new();
    for (si, set) in sets.iter().enumerate().filter(|(_, s)| s.category) {
        if !only.is_empty() && !only.contains(&set.name) {
            continue;
        }
        let Some((_, prefix)) = CATEGORIES.iter().find(|(n, _)| *n == set.name) else { continue };
        let mut held_out = default_held_out();
        held_out.push(format!("{prefix}*"));
        let (t0, c0) = (Instant::now(), thread_cpu_s());
        let spec = LearnSpec { held_out: held_out.clone(), ..LearnSpec::library_default()? };
        let dict = learn_from_sources(&folders, &[], &spec)?;
        let prior = train_from_mocap(
            &folders,
            &held_out,
            &skeletons,
            &dict.bone_lengths,
            &format!("the fold without {}", set.name),
            train,
            |_, _| {},
        )?;
        println!(
            "fold {}: held out {prefix}*; {} bases in {} actions, {} exemplars; trained in {:.1} s ({:.1} s CPU)",
            set.name,
            dict.num_bases(),
            dict.actions.len(),
            dict.exemplars.ncols(),
            t0.elapsed().as_secs_f64(),
            thread_cpu_s() - c0
        );
        print_header();
        let fold = score_sets(&dict, opts, &[(si, set)], suite, Some(&prior), None)?;
        for (k, sc) in fold {
            all.entry(k).or_default().merge(&sc);
        }
    }
    print_header();
    print_category_rows("loco", &all, suite.sigmas);
    Ok(())
}
