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

/// One model's result on one sketch.
#[derive(Clone, Debug, PartialEq)]
pub struct SketchScore {
    /// PCK at each requested alpha (0 when the model finds nothing).
    pub pck: Vec<f64>,
    /// Wall time of the detection, s.
    pub seconds: f64,
}

/// PCK@alpha of each model's best detection on one rendered sketch, `alphas` in order, and the
/// detection time. Errors: the renderer's and the detector's (except no figure).
pub fn score_sketch(renderer: &SketchRenderer, req: &SketchRequest, models: &[&Model], options: &DetectOptions, alphas: &[f64]) -> Result<Vec<SketchScore>> {
    let s = renderer.render(req)?;
    let view = ImageView::gray(&s.pixels, req.width, req.height)?;
    models
        .iter()
        .map(|m| {
            let t0 = std::time::Instant::now();
            let d = detect(&view, m, options);
            let seconds = t0.elapsed().as_secs_f64();
            let pck = match d {
                Ok(d) => alphas.iter().map(|&a| pck(&s.truth.joints2d, &d.best().joints.xy, a)).collect::<Result<_>>()?,
                Err(Error::NoFigure { .. }) => vec![0.0; alphas.len()],
                Err(e) => return Err(e),
            };
            Ok(SketchScore { pck, seconds })
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
