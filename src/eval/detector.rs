//! The held-out synthetic evaluation of a 2-D detector: sketches from another seed whose hair
//! style is forced to one never used in training, scored by PCK of the 15 canonical joints.

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

use crate::detect::{detect, DetectOptions, Model};
use crate::error::{Error, Result};
use crate::image::ImageView;
use crate::render::sketch::truth::sample_seed;
use crate::render::sketch::{Hair, SketchRenderer, SketchRequest, SketchStyle};

use super::metrics::pck;

/// Stream tag of the held-out styles.
const STYLE_STREAM: u64 = 0x4845_4C44_4F55_54;

/// Request `i` of the held-out set of `seed`: a random sketch whose style (drawn from its own
/// stream) has hair `hair` (all other style choices random as usual).
pub fn held_out_request(seed: u64, i: u64, size: usize, hair: Option<Hair>) -> SketchRequest {
    let s = sample_seed(seed, i);
    let mut style = SketchStyle::random(&mut ChaCha8Rng::seed_from_u64(s ^ STYLE_STREAM));
    if let Some(h) = hair {
        style.hair = h;
    }
    SketchRequest { style: Some(style), ..SketchRequest::random(s, size) }
}

/// PCK@alpha of each model's best detection on one rendered sketch (0 for a model that finds
/// nothing); `alphas` in order. Errors: the renderer's and the detector's (except no figure).
pub fn score_sketch(renderer: &SketchRenderer, req: &SketchRequest, models: &[&Model], options: &DetectOptions, alphas: &[f64]) -> Result<Vec<Vec<f64>>> {
    let s = renderer.render(req)?;
    let view = ImageView::gray(&s.pixels, req.width, req.height)?;
    models
        .iter()
        .map(|m| match detect(&view, m, options) {
            Ok(d) => alphas.iter().map(|&a| pck(&s.truth.joints2d, &d.best().joints.xy, a)).collect(),
            Err(Error::NoFigure { .. }) => Ok(vec![0.0; alphas.len()]),
            Err(e) => Err(e),
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn held_out_requests_force_the_hair_and_are_deterministic() {
        let a = held_out_request(2, 5, 256, Some(Hair::Ponytail));
        assert_eq!(a.style.as_ref().map(|s| s.hair), Some(Hair::Ponytail));
        assert_eq!(a, held_out_request(2, 5, 256, Some(Hair::Ponytail)));
        assert_ne!(a.seed, held_out_request(2, 6, 256, Some(Hair::Ponytail)).seed);
        assert_eq!((a.width, a.height), (256, 256));
    }
}
