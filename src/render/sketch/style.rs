//! [`SketchStyle`]: every drawing parameter of the sketch renderer, with its accepted range and
//! the range [`SketchStyle::random`] draws from. Lengths are in pixels *at 512×512*; they scale
//! with the smaller image side.

use rand::Rng;
use serde::{Deserialize, Serialize};

use super::costume::{Costume, Hair};
use super::scene::random_proportions;
use crate::body::proportions::Proportions;
use crate::error::{ensure_finite, Error, Result};

/// Drawing parameters. Field docs give: meaning; accepted range; random range.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SketchStyle {
    /// Full-pressure contour width, px; 0.3..=8; random 1.0..2.8.
    pub stroke_width: f64,
    /// Pressure variation along a stroke; 0..=1; random 0..0.7.
    pub pressure_jitter: f64,
    /// Wobble amplitude, px; 0..=8; random 0..1.8.
    pub wobble: f64,
    /// Ink darkness at full pressure; 0.1..=1; random 0.6..1.
    pub ink: f64,
    /// Mean length of one pencil stroke before the line is lifted and restarted, px; 10..=2000;
    /// random 40..220.
    pub stroke_length: f64,
    /// Overshoot of each stroke past its ends, px; 0..=20; random 0..4.
    pub overshoot: f64,
    /// Probability that a contour is traced a second time, slightly offset; 0..=1; random 0..0.5.
    pub retrace: f64,
    /// Crease angle, degrees (edges whose faces meet at more than this are drawn; 180 = none);
    /// 10..=180; random 50..100 or 180 (off) with probability 0.3.
    pub crease_deg: f64,
    /// Crease darkness relative to contours; 0..=1; random 0.3..0.8.
    pub crease_ink: f64,
    /// Hatching amount (0 = off; fraction of the shade range hatched); 0..=1; random 0 with
    /// probability 0.5, else 0.15..0.5.
    pub hatching: f64,
    /// Hatch line spacing, px; 2..=30; random 3.5..8.
    pub hatch_spacing: f64,
    /// Costume pieces; each random with probability 0.25 (cape 0.12).
    pub costume: Costume,
    /// Hair shape; random uniform over [`Hair::ALL`].
    pub hair: Hair,
    /// Bone-length scaling; random: custom with probability 0.5 (see [`Proportions`]).
    pub proportions: Proportions,
    /// Paper brightness; 0.3..=1; random 0.82..1.
    pub paper_tone: f64,
    /// Paper blotches and grain strength; 0..=0.5; random 0..0.07.
    pub paper_noise: f64,
    /// Stray strokes; 0..=500; random 0..10.
    pub stray_strokes: usize,
    /// Scribble patches; 0..=100; random 0..3.
    pub scribbles: usize,
    /// Rows of text-like marks in a corner; 0..=40; random 0 (p 0.6) or 2..7.
    pub text_rows: usize,
    /// Ground line under the feet; random with probability 0.5.
    pub ground_line: bool,
    /// Free margin around the figure, fraction of the smaller side; 0..=0.4; random 0.04..0.14.
    pub margin: f64,
}

impl Default for SketchStyle {
    /// A clean style: even lines, no costume, hair, shading or clutter, white paper.
    fn default() -> Self {
        SketchStyle {
            stroke_width: 1.8,
            pressure_jitter: 0.3,
            wobble: 0.5,
            ink: 0.95,
            stroke_length: 150.0,
            overshoot: 1.0,
            retrace: 0.0,
            crease_deg: 180.0,
            crease_ink: 0.5,
            hatching: 0.0,
            hatch_spacing: 5.0,
            costume: Costume::default(),
            hair: Hair::None,
            proportions: Proportions::default(),
            paper_tone: 1.0,
            paper_noise: 0.0,
            stray_strokes: 0,
            scribbles: 0,
            text_rows: 0,
            ground_line: false,
            margin: 0.08,
        }
    }
}

impl SketchStyle {
    /// A random style (ranges in the field docs). Draws from `rng` in a fixed order.
    pub fn random<R: Rng + ?Sized>(rng: &mut R) -> SketchStyle {
        let stroke_width = rng.random_range(1.0..2.8);
        let pressure_jitter = rng.random_range(0.0..0.7);
        let wobble = rng.random_range(0.0..1.8);
        let ink = rng.random_range(0.6..1.0);
        let stroke_length = rng.random_range(40.0..220.0);
        let overshoot = rng.random_range(0.0..4.0);
        let retrace = rng.random_range(0.0..0.5);
        let crease_deg = if rng.random_bool(0.3) { 180.0 } else { rng.random_range(50.0..100.0) };
        let crease_ink = rng.random_range(0.3..0.8);
        let hatching = if rng.random_bool(0.5) { 0.0 } else { rng.random_range(0.15..0.5) };
        let hatch_spacing = rng.random_range(3.5..8.0);
        let costume = Costume {
            belt: rng.random_bool(0.25),
            boots: rng.random_bool(0.25),
            gloves: rng.random_bool(0.25),
            collar: rng.random_bool(0.25),
            armour: rng.random_bool(0.25),
            cape: rng.random_bool(0.12),
        };
        let hair = Hair::ALL[rng.random_range(0..Hair::ALL.len())];
        let proportions = random_proportions(rng, 0.5);
        let paper_tone = rng.random_range(0.82..1.0);
        let paper_noise = rng.random_range(0.0..0.07);
        let stray_strokes = rng.random_range(0..10);
        let scribbles = rng.random_range(0..3);
        let text_rows = if rng.random_bool(0.6) { 0 } else { rng.random_range(2..7) };
        let ground_line = rng.random_bool(0.5);
        let margin = rng.random_range(0.04..0.14);
        SketchStyle {
            stroke_width,
            pressure_jitter,
            wobble,
            ink,
            stroke_length,
            overshoot,
            retrace,
            crease_deg,
            crease_ink,
            hatching,
            hatch_spacing,
            costume,
            hair,
            proportions,
            paper_tone,
            paper_noise,
            stray_strokes,
            scribbles,
            text_rows,
            ground_line,
            margin,
        }
    }

    /// Checks every field against its accepted range ([`Error::NonFinite`] / [`Error::OutOfRange`]
    /// naming the field).
    pub fn validate(&self) -> Result<()> {
        let ranges: [(&'static str, f64, f64, f64); 13] = [
            ("style.stroke_width", self.stroke_width, 0.3, 8.0),
            ("style.pressure_jitter", self.pressure_jitter, 0.0, 1.0),
            ("style.wobble", self.wobble, 0.0, 8.0),
            ("style.ink", self.ink, 0.1, 1.0),
            ("style.stroke_length", self.stroke_length, 10.0, 2000.0),
            ("style.overshoot", self.overshoot, 0.0, 20.0),
            ("style.retrace", self.retrace, 0.0, 1.0),
            ("style.crease_deg", self.crease_deg, 10.0, 180.0),
            ("style.crease_ink", self.crease_ink, 0.0, 1.0),
            ("style.hatching", self.hatching, 0.0, 1.0),
            ("style.hatch_spacing", self.hatch_spacing, 2.0, 30.0),
            ("style.paper_tone", self.paper_tone, 0.3, 1.0),
            ("style.paper_noise", self.paper_noise, 0.0, 0.5),
        ];
        for (name, v, lo, hi) in ranges {
            ensure_finite(name, v)?;
            if !(lo..=hi).contains(&v) {
                return Err(Error::OutOfRange { name, detail: format!("{v} is outside {lo}..={hi}") });
            }
        }
        ensure_finite("style.margin", self.margin)?;
        if !(0.0..=0.4).contains(&self.margin) {
            return Err(Error::OutOfRange {
                name: "style.margin",
                detail: format!("{} is outside 0..=0.4", self.margin),
            });
        }
        for (name, v, hi) in [
            ("style.stray_strokes", self.stray_strokes, 500),
            ("style.scribbles", self.scribbles, 100),
            ("style.text_rows", self.text_rows, 40),
        ] {
            if v > hi {
                return Err(Error::OutOfRange { name, detail: format!("{v} is more than {hi}") });
            }
        }
        self.proportions.validate()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;

    #[test]
    fn random_styles_are_valid_and_bad_fields_are_named() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(9);
        for _ in 0..200 {
            SketchStyle::random(&mut rng).validate().unwrap();
        }
        SketchStyle::default().validate().unwrap();
        let bad = SketchStyle { wobble: 100.0, ..Default::default() };
        assert!(bad.validate().unwrap_err().to_string().contains("style.wobble"));
        let bad = SketchStyle { ink: f64::NAN, ..Default::default() };
        assert!(matches!(bad.validate(), Err(Error::NonFinite { name: "style.ink", .. })));
    }
}
