//! `sketchbody-lab calibrate-fit --train DS=RESULTS … [--test DS=RESULTS …] [--first-dim K] [--cv F]
//! [--shipped]`: fits the fitted body's calibration (`sketchbody::fit::FitCalibration`) to
//! `run-dataset` results: the shape map (`ShapeCalibration`: per gender and dimension ≥ K, the
//! true shape weight against the SIR's, least squares, on samples fitted in their true gender),
//! then the height calibration (`HeightCalibration`: ln true height against the mapped body's
//! ln height, the gender value and the `--height-evidence` values). Prints the Rust constants to ship and, for every set, the
//! RMS error of ln height and the mean rest AED centred (docs/dataset.md) of the fit before and
//! after calibration. `--cv F` first prints an F-fold cross-validation of that AED over the
//! training samples for every K (only for K = `--first-dim` when that is given); `--shipped`
//! evaluates the shipped calibration instead.

use std::path::Path;

use sketchbody::body::proportions::Proportions;
use sketchbody::body::rig::{scale_to_height, y_extent};
use sketchbody::body::{BodyModel, Gender, RestShape, ShapeChoice};
use sketchbody::fit::gender_evidence::NUM_GENDER_FEATURES;
use sketchbody::fit::{
    FitCalibration, GenderFeatures, HeightCalibration, HeightEvidence, CALIBRATED_DIMS, HEIGHT_EVIDENCE_NAMES,
    NUM_HEIGHT_EVIDENCE,
};
use sketchbody::pipeline::{calibrated_weights, rest_body};
use sketchbody::render::sketch::truth::parse_mesh;
use sketchbody::render::sketch::GroundTruth;
use sketchbody_lab::eval::metrics::{aed, centred};
use sketchbody_lab::eval::score::dataset_samples;
use sketchbody_lab::fit::height_calibration::HeightSample;

use crate::train_gender::{read_json, Sets};
use sketchbody_cli::CliError;

/// Arguments of `sketchbody-lab calibrate-fit`.
#[derive(clap::Args)]
pub struct Args {
    /// The calibration's training and test sets (`run-dataset` results of 10-dimension fits in a
    /// gendered space: `--gender truth`, `f`, `m` or `auto`; not `--mean-shape`).
    #[command(flatten)]
    sets: Sets,
    /// Report the shipped calibration on the --test sets instead of fitting one.
    #[arg(long, conflicts_with = "train")]
    shipped: bool,
    /// Use only the first N samples of each set.
    #[arg(long)]
    first: Option<usize>,
    /// First shape dimension the map changes; lower ones keep the fit's weights [default: 3].
    #[arg(long, value_parser = clap::value_parser!(u32).range(0..=CALIBRATED_DIMS as i64))]
    first_dim: Option<u32>,
    /// The evidence the height calibration reads beyond the fitted height and gender:
    /// comma-separated names (log_legs_factor … log_torso_factor, then the gender features'
    /// names, see `sketchbody::fit::HEIGHT_EVIDENCE_NAMES`), `none` or `all`.
    #[arg(long, default_value = DEFAULT_EVIDENCE, value_parser = parse_evidence)]
    height_evidence: EvidenceSet,
    /// Before training, print an F-fold cross-validation (the k-th sample of each true gender in
    /// fold k mod F) of the calibrated rest AED centred over the training samples for every
    /// first dimension.
    #[arg(long, value_parser = clap::value_parser!(u32).range(2..=50))]
    cv: Option<u32>,
}

/// The evidence the shipped height calibration reads (docs/benchmarks.md, "Height evidence").
const DEFAULT_EVIDENCE: &str = "all";

/// Which [`HEIGHT_EVIDENCE_NAMES`] values the height calibration reads.
#[derive(Clone, Copy, Debug)]
struct EvidenceSet([bool; NUM_HEIGHT_EVIDENCE]);

fn parse_evidence(s: &str) -> Result<EvidenceSet, String> {
    let mut used = [false; NUM_HEIGHT_EVIDENCE];
    match s.trim() {
        "none" => {}
        "all" => used = [true; NUM_HEIGHT_EVIDENCE],
        list => {
            for name in list.split(',').map(str::trim) {
                let k = HEIGHT_EVIDENCE_NAMES.iter().position(|n| *n == name).ok_or_else(|| {
                    format!("unknown height evidence {name:?}; one of {}, none, all", HEIGHT_EVIDENCE_NAMES.join(", "))
                })?;
                used[k] = true;
            }
        }
    }
    Ok(EvidenceSet(used))
}

/// One result with its ground truth.
struct Sample {
    /// The fitted gendered space.
    gender: Gender,
    /// The fit's gender value (0 female, 1 male).
    gender_value: f64,
    /// The SIR's weights.
    fit: Vec<f64>,
    /// The fitted bone factors.
    proportions: Option<Proportions>,
    /// The drawing's measured widths (`gender_features`).
    widths: GenderFeatures,
    /// The true gender.
    true_gender: Gender,
    /// The true shape weights.
    truth: Vec<f64>,
    /// The true rest height, metres.
    height: f64,
    /// The true rest mesh, centred.
    reference: Vec<[f64; 3]>,
}

/// Every sample of `dataset` with a results file in `results`.
fn load(dataset: &Path, results: &Path, first: Option<usize>) -> Result<Vec<Sample>, CliError> {
    let mut out = Vec::new();
    for stem in dataset_samples(dataset)?.iter().take(first.unwrap_or(usize::MAX)) {
        let rp = results.join(format!("{stem}.json"));
        if !rp.is_file() {
            continue;
        }
        let r = read_json(&rp)?;
        if r["score"].is_null() {
            return Err(CliError(format!("{}: mean-shape results have no fit to calibrate", rp.display())));
        }
        let bad = |what: &str| CliError(format!("{}: {what}", rp.display()));
        let fit: Vec<f64> = serde_json::from_value(r["fit_shape_weights"].clone())
            .map_err(|_| bad("no fit_shape_weights (run-dataset of this version writes them)"))?;
        if fit.len() != CALIBRATED_DIMS {
            return Err(bad(&format!(
                "{} fitted weights; the calibration maps {CALIBRATED_DIMS}-dimension fits",
                fit.len()
            )));
        }
        let gender = Gender::parse(r["gender"].as_str().ok_or_else(|| bad("no gender"))?)?;
        let gender_value = r["gender_value"].as_f64().ok_or_else(|| bad("no gender_value"))?;
        let proportions = serde_json::from_value(r["proportions"].clone()).map_err(|e| bad(&e.to_string()))?;
        let widths: Vec<Option<f64>> = serde_json::from_value(r["gender_features"].clone())
            .map_err(|_| bad("no gender_features (run-dataset of this version writes them)"))?;
        let widths = GenderFeatures {
            values: widths.try_into().map_err(|_| bad(&format!("gender_features: need {NUM_GENDER_FEATURES}")))?,
        };
        let tp = dataset.join(format!("{stem}.json"));
        let text = std::fs::read_to_string(&tp).map_err(|e| CliError(format!("{}: {e}", tp.display())))?;
        let t = GroundTruth::from_json(&text, &tp.display().to_string())?;
        let mp = dataset.join(format!("{stem}.mesh"));
        let bytes = std::fs::read(&mp).map_err(|e| CliError(format!("{}: {e}", mp.display())))?;
        let rest = parse_mesh(&bytes, &mp.display().to_string())?.0;
        let reference: Vec<[f64; 3]> = rest.iter().map(|p| [p[0] as f64, p[1] as f64, p[2] as f64]).collect();
        out.push(Sample {
            gender,
            gender_value,
            fit,
            proportions,
            widths,
            true_gender: Gender::parse(&t.gender)?,
            truth: t.shape_weights,
            height: t.height_m,
            reference: centred(&reference),
        });
    }
    if out.is_empty() {
        return Err(CliError(format!("{}: no results of {}", results.display(), dataset.display())));
    }
    Ok(out)
}

/// A sample's height evidence.
fn evidence(s: &Sample) -> HeightEvidence {
    HeightEvidence::new(s.proportions.as_ref(), Some(&s.widths))
}

/// A sample's rest body: its fitted weights mapped by `c` (or left as fitted), the fitted bone
/// factors applied, and its height (metres).
fn body(model: &BodyModel, s: &Sample, c: Option<&FitCalibration>) -> Result<(RestShape, f64), CliError> {
    let space = ShapeChoice::Gendered(s.gender);
    let w = match c {
        Some(c) => calibrated_weights(model, space, c, s.gender, s.fit.clone())?,
        None => s.fit.clone(),
    };
    let rest = rest_body(model, space, &w, s.proportions.as_ref())?;
    let h = y_extent(&rest.vertices);
    Ok((rest, h))
}

/// `(RMS ln height error, mean rest AED centred)` of `samples`' bodies, uncalibrated (`None`) or
/// calibrated by `c`.
fn score(model: &BodyModel, samples: &[&Sample], c: Option<&FitCalibration>) -> Result<(f64, f64), CliError> {
    let (mut sq, mut sum) = (0.0, 0.0);
    for s in samples {
        let (mut rest, fit_height) = body(model, s, c)?;
        let h = match c {
            Some(c) => c.height.calibrated(fit_height, s.gender_value, &evidence(s))?,
            None => fit_height,
        };
        scale_to_height(&mut rest.vertices, &mut rest.joints, h)?;
        let scaled: Vec<[f64; 3]> = rest.vertices.iter().map(|p| p.map(f64::from)).collect();
        sq += (h / s.height).ln().powi(2);
        sum += aed(&s.reference, &centred(&scaled), s.height)?;
    }
    let n = samples.len() as f64;
    Ok(((sq / n).sqrt(), sum / n))
}

/// Trains the calibration on `samples` with the shape map from dimension `first_dim` and the
/// height calibration reading `used`.
fn train(
    model: &BodyModel,
    samples: &[&Sample],
    first_dim: usize,
    used: &EvidenceSet,
) -> Result<FitCalibration, CliError> {
    let matched: Vec<(Gender, &[f64], &[f64])> =
        samples.iter().filter(|s| s.gender == s.true_gender).map(|s| (s.gender, &s.fit[..], &s.truth[..])).collect();
    let shape = sketchbody_lab::fit::shape_calibration::train_shape_calibration(&matched, first_dim)?;
    let mapped = FitCalibration { shape, height: HeightCalibration::SHIPPED };
    let mut heights = Vec::with_capacity(samples.len());
    for s in samples {
        heights.push(HeightSample {
            fit_height: body(model, s, Some(&mapped))?.1,
            gender_value: s.gender_value,
            evidence: evidence(s),
            true_height: s.height,
        });
    }
    Ok(FitCalibration {
        shape,
        height: sketchbody_lab::fit::height_calibration::train_height_calibration(&heights, &used.0)?,
    })
}

fn print_calibration(c: &FitCalibration) {
    let rows = |a: &[[f64; CALIBRATED_DIMS]; 2]| {
        let row = |r: &[f64; CALIBRATED_DIMS]| r.iter().map(|x| format!("{x:.6}")).collect::<Vec<_>>().join(", ");
        format!("[[{}], [{}]]", row(&a[0]), row(&a[1]))
    };
    println!(
        "ShapeCalibration {{ first_dim: {}, intercept: {}, slope: {} }}",
        c.shape.first_dim,
        rows(&c.shape.intercept),
        rows(&c.shape.slope)
    );
    let h = &c.height;
    let row = |r: &[f64; NUM_HEIGHT_EVIDENCE]| r.iter().map(|x| format!("{x:.6}")).collect::<Vec<_>>().join(", ");
    println!(
        "HeightCalibration {{ intercept: {:.6}, slope: {:.6}, male: {:.6}, evidence_means: [{}], evidence_weights: [{}] }}",
        h.intercept,
        h.slope,
        h.male,
        row(&h.evidence_means),
        row(&h.evidence_weights)
    );
}

fn report(model: &BodyModel, what: &str, samples: &[&Sample], c: &FitCalibration) -> Result<(), CliError> {
    let (h0, a0) = score(model, samples, None)?;
    let (h1, a1) = score(model, samples, Some(c))?;
    println!(
        "{what}: {} samples, RMS ln height {h0:.4} fitted -> {h1:.4} calibrated, rest AED centred {a0:.5} fitted -> {a1:.5} calibrated",
        samples.len()
    );
    Ok(())
}

/// Runs the command.
pub fn run(a: Args) -> Result<(), CliError> {
    let model = BodyModel::embedded()?;
    let c = if a.shipped {
        if a.sets.test.is_empty() {
            return Err(CliError("--shipped needs at least one --test DATASET=RESULTS".into()));
        }
        FitCalibration::SHIPPED
    } else {
        if a.sets.train.is_empty() {
            return Err(CliError("give --train DATASET=RESULTS (or --shipped with --test)".into()));
        }
        let mut samples = Vec::new();
        for (d, r) in &a.sets.train {
            samples.extend(load(d, r, a.first)?);
        }
        let all: Vec<&Sample> = samples.iter().collect();
        if let Some(folds) = a.cv {
            // The k-th sample of each true gender is in fold k mod F.
            let mut seen = [0usize; 2];
            let fold: Vec<usize> = all
                .iter()
                .map(|s| {
                    let k = &mut seen[s.true_gender.index()];
                    *k += 1;
                    (*k - 1) % folds as usize
                })
                .collect();
            let dims = match a.first_dim {
                Some(k) => k as usize..=k as usize,
                None => 0..=CALIBRATED_DIMS,
            };
            for first_dim in dims {
                let mut sum = 0.0;
                for f in 0..folds as usize {
                    let pick = |held: bool| -> Vec<&Sample> {
                        all.iter().zip(&fold).filter(|(_, &k)| (k == f) == held).map(|(s, _)| *s).collect()
                    };
                    let (held, rest) = (pick(true), pick(false));
                    if held.is_empty() {
                        continue;
                    }
                    let c = train(&model, &rest, first_dim, &a.height_evidence)?;
                    sum += score(&model, &held, Some(&c))?.1 * held.len() as f64;
                }
                println!(
                    "cv {folds}-fold, first dimension {first_dim}: rest AED centred {:.5}",
                    sum / all.len() as f64
                );
            }
        }
        let c = train(
            &model,
            &all,
            a.first_dim.map_or(FitCalibration::SHIPPED.shape.first_dim, |k| k as usize),
            &a.height_evidence,
        )?;
        let matched = all.iter().filter(|s| s.gender == s.true_gender).count();
        println!("training: {} samples ({matched} fitted in their true gender train the shape map)", all.len());
        print_calibration(&c);
        report(&model, "training", &all, &c)?;
        c
    };
    for (d, r) in &a.sets.test {
        let samples = load(d, r, a.first)?;
        let refs: Vec<&Sample> = samples.iter().collect();
        report(&model, &format!("test {}", d.display()), &refs, &c)?;
    }
    Ok(())
}
