//! The single-figure detector with the 3-D pose step as the referee between its two backends:
//! detection finds the candidates ([`crate::detect::figure`]), and this module, which sees both
//! steps, lets the pose step choose ([`proportion_choice`]) with the caller's dictionary.

use crate::detect::calibration::Calibration;
use crate::detect::figure::{self, Evidence, Figure, FigureOptions};
use crate::detect::landmark::LandmarkNet;
use crate::detect::Model;
use crate::error::Result;
use crate::image::ImageView;
use crate::pose::factor_prior::FactorPrior;
use crate::pose::{dict_io, estimate_pose_with_factor_prior, Dictionary, PoseOptions};
use crate::skeleton::Joints2;

/// Which of two candidate joint sets (0 or 1) the 3-D pose step (default options, dictionary
/// `dict`, the embedded factor prior) explains with drawn proportions nearer the body model's:
/// the smaller Σ_g |ln k_g| of the estimated group factors ([`crate::pose::figure`]). A
/// candidate with a misplaced joint needs a limb longer or shorter than any body has; both
/// candidates come from the same drawing, so a stylised figure stylises both alike. `Ok(None)`
/// when the pose step fails on either candidate or they tie. Errors: `CorruptData` when the
/// embedded factor prior does not parse (a build fault). Measured in docs/benchmarks.md ("The
/// pose step as the backends' referee").
pub fn proportion_choice(dict: &Dictionary, a: &Joints2, b: &Joints2) -> Result<Option<usize>> {
    let opts = PoseOptions::default();
    let prior = FactorPrior::embedded()?;
    let deviation = |j: &Joints2| -> Option<f64> {
        let est = estimate_pose_with_factor_prior(dict, j, &opts, None, Some(prior)).ok()?;
        let d: f64 = est.factors.k.iter().map(|k| k.ln().abs()).sum();
        d.is_finite().then_some(d)
    };
    let (Some(da), Some(db)) = (deviation(a), deviation(b)) else { return Ok(None) };
    Ok(match da.total_cmp(&db) {
        std::cmp::Ordering::Less => Some(0),
        std::cmp::Ordering::Greater => Some(1),
        std::cmp::Ordering::Equal => None,
    })
}

/// `dict`, or the embedded dictionary (parsed once per process) when `None`.
fn dictionary(dict: Option<&Dictionary>) -> Result<&Dictionary> {
    match dict {
        Some(d) => Ok(d),
        None => dict_io::embedded_shared(),
    }
}

/// [`figure::decide`] refereed by [`proportion_choice`] with `dict` (`None`: the embedded
/// dictionary). Errors as [`figure::decide`]; `CorruptData` when an embedded model does not parse.
pub fn decide(
    evidence: &Evidence,
    cal: &Calibration,
    options: &FigureOptions,
    dict: Option<&Dictionary>,
) -> Result<Figure> {
    let dict = dictionary(dict)?;
    figure::decide(evidence, cal, options, Some(&|a: &Joints2, b: &Joints2| proportion_choice(dict, a, b)))
}

/// The best figure of `image` ([`figure::detect_figure`]) refereed by [`proportion_choice`] with
/// `dict` (`None`: the embedded dictionary): the product's detection, used by `detect`, `run`,
/// `skb_context_detect_figure` and the pipeline. Errors as [`figure::detect_figure`].
pub fn detect_figure(
    image: &ImageView<'_>,
    model: &Model,
    net: &LandmarkNet,
    options: &FigureOptions,
    dict: Option<&Dictionary>,
) -> Result<Figure> {
    let dict = dictionary(dict)?;
    figure::detect_figure(image, model, net, options, Some(&|a: &Joints2, b: &Joints2| proportion_choice(dict, a, b)))
}
