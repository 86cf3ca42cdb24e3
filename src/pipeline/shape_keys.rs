//! The shape keys of a pipeline result ([`crate::body::rig::shape_keys`]): the fitted body's
//! shape dimensions, each the displacement one standard deviation along its principal component
//! makes, through the fit's bone-length factors and the same scaling to the body's height.

use crate::body::rig::shape_keys::{key_name, ShapeKey};
use crate::body::BodyModel;
use crate::error::{Error, Result};

use super::body_fit::rest_body;
use super::PipelineResult;

/// One key per shape dimension of `r` (its weights; the space's default dimension for the mean
/// shape): the rest body (model frame, metres) with that weight one standard deviation larger,
/// minus the body, both with the chosen fit's bone-length factors, times the factor the result's
/// mesh was scaled by (its height over [`PipelineResult::fit_height`]). Errors: the space's and
/// the factors'; a zero fit height ([`Error::Degenerate`]).
pub fn shape_keys(model: &BodyModel, r: &PipelineResult) -> Result<Vec<ShapeKey>> {
    let space = model.shape_space(r.space)?;
    let dims = if r.weights.is_empty() { space.default_dim() } else { r.weights.len() };
    let mut weights = r.weights.clone();
    weights.resize(dims, 0.0);
    let proportions = r.chosen_fit().and_then(|g| g.fit.as_ref()).and_then(|f| f.proportions);
    if !(r.fit_height > 0.0) {
        return Err(Error::Degenerate(format!("fit height {}", r.fit_height)));
    }
    let scale = r.mesh.height() / r.fit_height;
    let base = rest_body(model, r.space, &weights, proportions.as_ref())?;
    (0..dims)
        .map(|k| {
            let mut w = weights.clone();
            w[k] += space.variances()[k].sqrt();
            let moved = rest_body(model, r.space, &w, proportions.as_ref())?;
            let deltas = moved
                .vertices
                .iter()
                .zip(&base.vertices)
                .map(|(a, b)| [0, 1, 2].map(|c| ((a[c] as f64 - b[c] as f64) * scale) as f32))
                .collect();
            Ok(ShapeKey { name: key_name(k), deltas })
        })
        .collect()
}
