//! `sketchbody-lab train-gender --train DS=RESULTS … [--test DS=RESULTS …] [--ridge R] [--shipped]`:
//! fits the gender classifier (`sketchbody::fit::GenderClassifier`, a logistic regression on
//! the sketch's geometric gender features) to the features `run-dataset` wrote
//! (`gender_features` of each results `STEM.json`) against each dataset's true gender, prints its
//! coefficients as the Rust constant to ship, and for every test set the confusion table, the
//! accuracy, the log loss and a calibration table (predicted vs observed share of males in
//! five bins of the predicted probability). `--shipped` evaluates the shipped classifier instead
//! of training one. `--fits` trains the final choice of the automatic gender (the classifier's
//! log-odds with the two gendered fits' score margin; with `--margin-only` the margin alone); `--recalibrate` refits that combination's
//! intercept to automatic-gender runs of sketches it was not trained on.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use sketchbody::fit::gender_evidence::{GENDER_FEATURE_NAMES, NUM_GENDER_FEATURES};
use sketchbody::fit::{GenderClassifier, GenderFeatures, MarginCombination};
use sketchbody_lab::eval::score::dataset_samples;

use sketchbody_cli::CliError;

/// Arguments of `sketchbody-lab train-gender`.
#[derive(clap::Args)]
pub struct Args {
    /// The classifier's training and test sets (any gender mode, e.g. `--gender truth
    /// --mean-shape`, which is fast).
    #[command(flatten)]
    sets: Sets,
    /// L2 penalty on the standardised coefficients.
    #[arg(long, default_value_t = 1.0, value_parser = sketchbody_cli::ranges::real(0.0, 1e6, false))]
    ridge: f64,
    /// Evaluate the shipped classifier (or with --test-fits the shipped combination) on the
    /// test sets instead of training.
    #[arg(long, conflicts_with_all = ["train", "fits"])]
    shipped: bool,
    /// Train the final choice of `run --classify-gender` instead ([`MarginCombination`]: the
    /// shipped classifier's log-odds and the score margin of the two gendered fits):
    /// DATASET=RF,RM with RF / RM run-dataset results of `--gender f` / `--gender m`. Repeatable.
    #[arg(long, value_parser = parse_fits)]
    fits: Vec<(PathBuf, PathBuf, PathBuf)>,
    /// With --fits: train the decision by the score margin alone (the classifier's log-odds
    /// weighted 0, no intercept; `train_margin_only`) instead of the two-input combination.
    #[arg(long, requires = "fits")]
    margin_only: bool,
    /// Test set of the combination, same form as --fits. Repeatable.
    #[arg(long, value_parser = parse_fits)]
    test_fits: Vec<(PathBuf, PathBuf, PathBuf)>,
    /// Joints from the detector: with --shipped evaluate the classifier for detected joints
    /// (`SHIPPED_DETECTED`); with --fits / --test-fits take its log-odds instead of the
    /// given-joints classifier's. No effect when training a classifier (--train).
    #[arg(long)]
    detected: bool,
    /// Refit the combination's intercept (the shipped one's, or with --fits the trained one's)
    /// to held-out sketches ([`MarginCombination::recalibrated`]): DATASET=RESULTS with RESULTS a
    /// run-dataset of `--gender auto` with given joints and one deciding seed (the classifier's
    /// features and the two deciding fits' scores of each results file). Repeatable; prints the
    /// recalibrated constant and each set before and after.
    #[arg(long, value_parser = parse_pair)]
    recalibrate: Vec<(PathBuf, PathBuf)>,
    /// Use only the first N samples of each set.
    #[arg(long)]
    first: Option<usize>,
}

fn parse_fits(s: &str) -> Result<(PathBuf, PathBuf, PathBuf), String> {
    let (d, r) = parse_pair(s)?;
    let text = r.to_string_lossy().into_owned();
    let (f, m) = text.split_once(',').ok_or_else(|| format!("{s:?}: expected DATASET=RF,RM"))?;
    Ok((d, PathBuf::from(f), PathBuf::from(m)))
}

/// Training and test sets of a model fitted to run-dataset results.
#[derive(clap::Args)]
pub struct Sets {
    /// Training set: DATASET=RESULTS (a make-dataset folder and a run-dataset results folder of
    /// it). Repeatable.
    #[arg(long, value_parser = parse_pair)]
    pub train: Vec<(PathBuf, PathBuf)>,
    /// Test set, same form; reported, never trained on. Repeatable.
    #[arg(long, value_parser = parse_pair)]
    pub test: Vec<(PathBuf, PathBuf)>,
}

/// Reads a JSON file; errors name the file.
pub fn read_json(p: &Path) -> Result<serde_json::Value, CliError> {
    let text = std::fs::read_to_string(p).map_err(|e| CliError(format!("{}: {e}", p.display())))?;
    serde_json::from_str(&text).map_err(|e| CliError(format!("{}: {e}", p.display())))
}

/// Parses DATASET=RESULTS.
fn parse_pair(s: &str) -> Result<(PathBuf, PathBuf), String> {
    let (a, b) = s.split_once('=').ok_or_else(|| format!("{s:?}: expected DATASET=RESULTS"))?;
    Ok((PathBuf::from(a), PathBuf::from(b)))
}

/// `(classifier log-odds, score margin male − female, is_male)` of every sample with both fits.
fn load_fits(
    d: &Path,
    rf: &Path,
    rm: &Path,
    first: Option<usize>,
    classifier: &GenderClassifier,
) -> Result<Vec<(f64, f64, bool)>, CliError> {
    let f = load(d, rf, first)?;
    let mut out = Vec::new();
    let stems = dataset_samples(d)?;
    let score = |r: &Path, stem: &str, key: &str| -> Result<f64, CliError> {
        let v = read_json(&r.join(format!("{stem}.json")))?;
        Ok(v["scores"][key].as_f64().unwrap_or(f64::NAN))
    };
    let done: Vec<&String> =
        stems.iter().take(first.unwrap_or(usize::MAX)).filter(|s| rf.join(format!("{s}.json")).is_file()).collect();
    for (stem, (features, male)) in done.into_iter().zip(f) {
        let margin = score(rm, stem, "male")? - score(rf, stem, "female")?;
        out.push((classifier.log_odds(&features), margin, male));
    }
    Ok(out)
}

/// `(classifier log-odds, score margin male − female, is_male)` of every sample of an automatic
/// gender run: its `scores` hold both deciding fits' scores, so it is its own female and male
/// run ([`load_fits`]). Errors when a sample lacks either score (a run with a given gender).
fn load_auto(
    d: &Path,
    r: &Path,
    first: Option<usize>,
    classifier: &GenderClassifier,
) -> Result<Vec<(f64, f64, bool)>, CliError> {
    let samples = load_fits(d, r, r, first, classifier)?;
    if samples.iter().any(|s| !s.1.is_finite()) {
        return Err(CliError(format!(
            "{}: no score of both gendered fits (a run-dataset of --gender auto with given joints writes them)",
            r.display()
        )));
    }
    Ok(samples)
}

/// Prints `c` as the Rust constant to ship.
fn print_combination(c: &MarginCombination) {
    println!(
        "MarginCombination {{\n    means: [{:.6}, {:.6}],\n    scales: [{:.6}, {:.6}],\n    coefficients: [{:.6}, {:.6}],\n    intercept: {:.6},\n}}",
        c.means[0], c.means[1], c.scales[0], c.scales[1], c.coefficients[0], c.coefficients[1], c.intercept
    );
}

/// `--recalibrate`: `combination` with its intercept refitted to the automatic-gender runs,
/// printed as the constant to ship, with each set before and after.
fn recalibrate(
    a: &Args,
    classifier: &GenderClassifier,
    combination: MarginCombination,
) -> Result<MarginCombination, CliError> {
    let mut sets = Vec::new();
    for (d, r) in &a.recalibrate {
        sets.push((d, r, load_auto(d, r, a.first, classifier)?));
    }
    let all: Vec<(f64, f64, bool)> = sets.iter().flat_map(|s| s.2.iter().copied()).collect();
    let c = sketchbody_lab::fit::gender::recalibrated(&combination, &all)?;
    println!(
        "recalibrated on {} sketches: intercept {:.6} -> {:.6} (decides male above P(male) {:.3} of the combination before)",
        all.len(),
        combination.intercept,
        c.intercept,
        1.0 / (1.0 + (c.intercept - combination.intercept).exp())
    );
    print_combination(&c);
    for (d, r, samples) in &sets {
        let probs = |k: &MarginCombination| -> Vec<(f64, bool)> {
            samples.iter().map(|&(z, m, male)| (k.male_probability(z, m), male)).collect()
        };
        println!("{} ({}) before:\n{}", d.display(), r.display(), report_probs(&probs(&combination)));
        println!("{} ({}) recalibrated:\n{}", d.display(), r.display(), report_probs(&probs(&c)));
    }
    Ok(c)
}

/// `(features, is_male)` of every sample of `dataset` that has a results file.
fn load(dataset: &Path, results: &Path, first: Option<usize>) -> Result<Vec<(GenderFeatures, bool)>, CliError> {
    let mut out = Vec::new();
    let stems = dataset_samples(dataset)?;
    for stem in stems.iter().take(first.unwrap_or(usize::MAX)) {
        let rp = results.join(format!("{stem}.json"));
        if !rp.is_file() {
            continue;
        }
        let (truth, r) = (read_json(&dataset.join(format!("{stem}.json")))?, read_json(&rp)?);
        let male = match truth["gender"].as_str() {
            Some("male") => true,
            Some("female") => false,
            g => return Err(CliError(format!("{stem}: truth gender {g:?}"))),
        };
        let arr = r["gender_features"].as_array().ok_or_else(|| {
            CliError(format!("{}: no gender_features (run-dataset of this version writes them)", rp.display()))
        })?;
        if arr.len() != NUM_GENDER_FEATURES {
            return Err(CliError(format!("{}: {} features, expected {NUM_GENDER_FEATURES}", rp.display(), arr.len())));
        }
        let values = std::array::from_fn(|k| arr[k].as_f64());
        out.push((GenderFeatures { values }, male));
    }
    Ok(out)
}

/// Confusion table, accuracy, log loss and calibration of `c` on `samples`.
fn report(c: &GenderClassifier, samples: &[(GenderFeatures, bool)]) -> String {
    let probs: Vec<(f64, bool)> = samples.iter().map(|(f, m)| (c.male_probability(f), *m)).collect();
    report_probs(&probs)
}

/// Confusion table, accuracy, log loss and calibration of predicted `(P(male), is_male)`.
fn report_probs(samples: &[(f64, bool)]) -> String {
    let mut s = String::new();
    let mut table = [[0usize; 2]; 2]; // [truth][predicted], 0 female 1 male
    let mut loss = 0.0;
    let mut bins = [(0usize, 0.0f64, 0usize); 5];
    for &(p, ref male) in samples {
        table[*male as usize][(p > 0.5) as usize] += 1;
        loss -= if *male { p.max(1e-12).ln() } else { (1.0 - p).max(1e-12).ln() };
        let b = ((p * 5.0) as usize).min(4);
        bins[b].0 += 1;
        bins[b].1 += p;
        bins[b].2 += *male as usize;
    }
    let n = samples.len().max(1);
    let right = table[0][0] + table[1][1];
    let _ = writeln!(s, "| truth \\ chosen | female | male |\n|---|---:|---:|");
    let _ = writeln!(s, "| female | {} | {} |\n| male | {} | {} |", table[0][0], table[0][1], table[1][0], table[1][1]);
    let _ = writeln!(
        s,
        "accuracy {right}/{} = {:.3}, log loss {:.3} (0.693 = a coin)",
        samples.len(),
        right as f64 / n as f64,
        loss / n as f64
    );
    let _ = writeln!(s, "| P(male) bin | samples | mean predicted | observed male |\n|---|---:|---:|---:|");
    for (i, (count, sum_p, males)) in bins.iter().enumerate() {
        if *count > 0 {
            let _ = writeln!(
                s,
                "| {:.1}–{:.1} | {count} | {:.2} | {:.2} |",
                i as f64 / 5.0,
                (i + 1) as f64 / 5.0,
                sum_p / *count as f64,
                *males as f64 / *count as f64
            );
        }
    }
    s
}

/// Runs the command.
pub fn run(a: Args) -> Result<(), CliError> {
    if !a.fits.is_empty() || !a.test_fits.is_empty() || !a.recalibrate.is_empty() {
        return run_fits(&a);
    }
    let classifier = if a.shipped {
        if a.detected {
            GenderClassifier::SHIPPED_DETECTED
        } else {
            GenderClassifier::SHIPPED
        }
    } else {
        let mut train = Vec::new();
        for (d, r) in &a.sets.train {
            train.extend(load(d, r, a.first)?);
        }
        let c = sketchbody_lab::fit::gender::train_gender_classifier(&train, a.ridge)?;
        let males = train.iter().filter(|s| s.1).count();
        println!("trained on {} samples ({} f / {males} m), ridge {}", train.len(), train.len() - males, a.ridge);
        let list = |v: &[f64]| v.iter().map(|x| format!("{x:.6}")).collect::<Vec<_>>().join(", ");
        println!("features: {}", GENDER_FEATURE_NAMES.join(", "));
        println!(
            "GenderClassifier {{\n    means: [{}],\n    scales: [{}],\n    coefficients: [{}],\n    intercept: {:.6},\n}}",
            list(&c.means),
            list(&c.scales),
            list(&c.coefficients),
            c.intercept
        );
        println!("training set:\n{}", report(&c, &train));
        c
    };
    for (d, r) in &a.sets.test {
        let test = load(d, r, a.first)?;
        println!("test {} ({}):\n{}", d.display(), r.display(), report(&classifier, &test));
    }
    Ok(())
}

/// `--fits`: trains (or with `--shipped` takes) the [`MarginCombination`] and reports it.
fn run_fits(a: &Args) -> Result<(), CliError> {
    let classifier = if a.detected { GenderClassifier::SHIPPED_DETECTED } else { GenderClassifier::SHIPPED };
    let combination = if a.shipped || a.fits.is_empty() {
        MarginCombination::SHIPPED
    } else {
        let mut train = Vec::new();
        for (d, f, m) in &a.fits {
            train.extend(load_fits(d, f, m, a.first, &classifier)?);
        }
        let c = if a.margin_only {
            sketchbody_lab::fit::gender::train_margin_only(&train)?
        } else {
            sketchbody_lab::fit::gender::train_margin_combination(&train, a.ridge)?
        };
        let males = train.iter().filter(|s| s.2).count();
        let how = if a.margin_only { "the margin alone".to_string() } else { format!("ridge {}", a.ridge) };
        println!("trained on {} samples ({} f / {males} m), {how}", train.len(), train.len() - males);
        print_combination(&c);
        let probs: Vec<(f64, bool)> = train.iter().map(|&(z, m, male)| (c.male_probability(z, m), male)).collect();
        println!("training set:\n{}", report_probs(&probs));
        c
    };
    let combination = if a.recalibrate.is_empty() { combination } else { recalibrate(a, &classifier, combination)? };
    for (d, f, m) in &a.test_fits {
        let test = load_fits(d, f, m, a.first, &classifier)?;
        let probs: Vec<(f64, bool)> =
            test.iter().map(|&(z, mg, male)| (combination.male_probability(z, mg), male)).collect();
        println!("test {} ({}, {}):\n{}", d.display(), f.display(), m.display(), report_probs(&probs));
        let alone: Vec<(f64, bool)> = test.iter().map(|&(z, _, male)| (1.0 / (1.0 + (-z).exp()), male)).collect();
        println!("the classifier alone on it:\n{}", report_probs(&alone));
    }
    Ok(())
}
