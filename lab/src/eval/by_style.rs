//! The shape fit's figures per rendering style ([`super::detector::STYLE_GROUPS`]: hatching,
//! costume, cape, …, plus the two true genders) and the confusion table of the automatic gender
//! (`sketchbody-lab eval --by-style`).

use std::path::Path;

use super::detector::STYLE_GROUPS;
use super::score::SampleScore;
use sketchbody::error::{Error, Result};
use sketchbody::render::sketch::truth::GroundTruth;

/// The metrics of a [`StyleRow`], in order.
pub const STYLE_METRICS: [&str; 4] = ["aed_rest", "aed_rest_centred", "aed_rest_at_height", "aed_posed"];

/// One group's size and mean of each of [`STYLE_METRICS`] (NaN when no member has it).
#[derive(Clone, Debug, PartialEq)]
pub struct StyleRow {
    /// The group's label.
    pub name: &'static str,
    /// Scored samples in the group.
    pub n: usize,
    /// Means in [`STYLE_METRICS`] order.
    pub means: [f64; 4],
}

fn read_truth(dataset: &Path, stem: &str) -> Result<GroundTruth> {
    let jp = dataset.join(format!("{stem}.json"));
    let text = std::fs::read_to_string(&jp).map_err(|source| Error::Io { path: jp.clone(), source })?;
    GroundTruth::from_json(&text, &jp.display().to_string())
}

/// Groups `scores` (of samples of `dataset`) by [`STYLE_GROUPS`] and by true gender. Errors:
/// an unreadable or damaged ground-truth file.
pub fn shape_by_style(dataset: &Path, scores: &[SampleScore]) -> Result<Vec<StyleRow>> {
    let truths: Vec<GroundTruth> = scores.iter().map(|s| read_truth(dataset, &s.sample)).collect::<Result<_>>()?;
    let female = |t: &GroundTruth| t.gender == "female";
    #[allow(clippy::type_complexity)] // (group name, membership test)
    let mut groups: Vec<(&'static str, Box<dyn Fn(&GroundTruth) -> bool>)> =
        STYLE_GROUPS.iter().map(|g| (g.name, Box::new(g.member) as Box<dyn Fn(&GroundTruth) -> bool>)).collect();
    groups.push(("true female", Box::new(female)));
    groups.push(("true male", Box::new(move |t: &GroundTruth| !female(t))));
    Ok(groups
        .iter()
        .map(|(name, member)| {
            let members: Vec<&SampleScore> =
                scores.iter().zip(&truths).filter(|(_, t)| member(t)).map(|(s, _)| s).collect();
            let mean = |f: fn(&SampleScore) -> Option<f64>| {
                let v: Vec<f64> = members.iter().filter_map(|s| f(s)).collect();
                if v.is_empty() {
                    f64::NAN
                } else {
                    v.iter().sum::<f64>() / v.len() as f64
                }
            };
            StyleRow {
                name,
                n: members.len(),
                means: [
                    mean(|s| s.aed_rest),
                    mean(|s| s.aed_rest_centred),
                    mean(|s| s.aed_rest_at_height),
                    mean(|s| s.aed_posed),
                ],
            }
        })
        .collect())
}

/// Confusion table of the results' gender against the truth: `table[true][estimated]`, 0 female
/// and 1 male, over the samples of `scores` whose result file (`RESULTS/STEM.json`) has a
/// `gender` field; `None` when none has. Errors: unreadable or damaged files.
pub fn gender_confusion(dataset: &Path, results: &Path, scores: &[SampleScore]) -> Result<Option<[[usize; 2]; 2]>> {
    let mut table = [[0usize; 2]; 2];
    let mut any = false;
    for s in scores {
        let rp = results.join(format!("{}.json", s.sample));
        let text = std::fs::read_to_string(&rp).map_err(|source| Error::Io { path: rp.clone(), source })?;
        let doc: serde_json::Value =
            serde_json::from_str(&text).map_err(|e| Error::CorruptData(format!("{}: {e}", rp.display())))?;
        let Some(est) = doc.get("gender").and_then(|g| g.as_str()) else { continue };
        let truth = read_truth(dataset, &s.sample)?;
        table[(truth.gender == "male") as usize][(est == "male") as usize] += 1;
        any = true;
    }
    Ok(any.then_some(table))
}
