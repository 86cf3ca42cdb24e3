//! The shape keys of a fitted body ([`crate::body::rig::shape_keys`]): the body's shape
//! dimensions, each the displacement one standard deviation along its principal component
//! makes, through the fit's bone-length factors and the same scaling to the body's height.

use crate::body::proportions::Proportions;
use crate::body::rig::shape_keys::{key_name, ShapeKey};
use crate::body::{BodyModel, ShapeChoice};
use crate::error::{Error, Result};

use super::body_fit::{rest_body, FittedBody};
use super::PipelineResult;

/// How a body's rest mesh was made from the shape space: enough to make its shape keys. Owns
/// its data.
#[derive(Clone, Debug, PartialEq)]
pub struct ShapeOrigin {
    /// The shape space.
    pub space: ShapeChoice,
    /// The body's weights in it, metres (shorter than the space's default dimension: the rest
    /// are 0).
    pub weights: Vec<f64>,
    /// The bone-length factors applied after the shape (`None`: none).
    pub proportions: Option<Proportions>,
    /// The uniform scale applied last (the body's height over its height before scaling; 1 for
    /// an unscaled body).
    pub scale: f64,
}

impl ShapeOrigin {
    /// The origin of a pipeline result's mesh: its space and weights, the chosen fit's
    /// bone-length factors, scaled by the mesh's height over [`PipelineResult::fit_height`].
    /// Errors: a zero or non-finite fit height ([`Error::Degenerate`]).
    pub fn of_result(r: &PipelineResult) -> Result<ShapeOrigin> {
        let proportions = r.chosen_fit().and_then(|g| g.fit.as_ref()).and_then(|f| f.proportions);
        ShapeOrigin::scaled(r.space, &r.weights, proportions, r.mesh.height(), r.fit_height)
    }

    /// The origin of [`super::body_fit::fit_body`]'s body (its rest, as
    /// [`ShapeOrigin::of_result`]). Errors: as [`ShapeOrigin::of_result`].
    pub fn of_fit(body: &FittedBody) -> Result<ShapeOrigin> {
        let proportions = body.fits.last().and_then(|g| g.fit.as_ref()).and_then(|f| f.proportions);
        let height = crate::body::rig::y_extent(&body.rest.vertices);
        ShapeOrigin::scaled(body.space, &body.weights, proportions, height, body.fit_height)
    }

    fn scaled(
        space: ShapeChoice,
        weights: &[f64],
        proportions: Option<Proportions>,
        height: f64,
        fit_height: f64,
    ) -> Result<ShapeOrigin> {
        let scale = height / fit_height;
        if !(fit_height > 0.0 && scale.is_finite()) {
            return Err(Error::Degenerate(format!("fit height {fit_height}")));
        }
        Ok(ShapeOrigin { space, weights: weights.to_vec(), proportions, scale })
    }

    /// One key per shape dimension (the weights' count; the space's default dimension for the
    /// mean shape): the rest body (model frame, metres) with that weight one standard deviation
    /// larger, minus the body, both with the bone-length factors, times the scale. Errors: the
    /// space's and the factors'.
    pub fn keys(&self, model: &BodyModel) -> Result<Vec<ShapeKey>> {
        let space = model.shape_space(self.space)?;
        let dims = if self.weights.is_empty() { space.default_dim() } else { self.weights.len() };
        let mut weights = self.weights.clone();
        weights.resize(dims, 0.0);
        let proportions = self.proportions.as_ref();
        let base = rest_body(model, self.space, &weights, proportions)?;
        (0..dims)
            .map(|k| {
                let mut w = weights.clone();
                w[k] += space.variances()[k].sqrt();
                let moved = rest_body(model, self.space, &w, proportions)?;
                let deltas = moved
                    .vertices
                    .iter()
                    .zip(&base.vertices)
                    .map(|(a, b)| [0, 1, 2].map(|c| ((a[c] as f64 - b[c] as f64) * self.scale) as f32))
                    .collect();
                Ok(ShapeKey { name: key_name(k), deltas })
            })
            .collect()
    }
}

/// The shape keys of a pipeline result ([`ShapeOrigin::of_result`], [`ShapeOrigin::keys`]).
pub fn shape_keys(model: &BodyModel, r: &PipelineResult) -> Result<Vec<ShapeKey>> {
    ShapeOrigin::of_result(r)?.keys(model)
}
