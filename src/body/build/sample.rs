//! The distributions of the training humans (documented in docs/assets.md, "Body model").
//! All draws come from one seeded ChaCha8 stream in a fixed order, so a seed fixes the set.

use rand::Rng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Exp1, Normal};

use crate::error::{Error, Result};

use super::macros::{Category, MacroParams};

/// The parameters of one MakeHuman human: macro sliders and one value in [−1, 1] per local
/// category (left and right sliders of a category share it).
#[derive(Clone, Debug, PartialEq)]
pub struct HumanParams {
    /// Macro sliders.
    pub macros: MacroParams,
    /// Per-category local slider values, in the order of the categories given to the sampler.
    pub local: Vec<f64>,
}

/// Concept-art build the sampler exaggerates for one human.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Build {
    /// Only the base distributions.
    Average,
    /// Longer upper and lower legs, ideal proportions.
    LongLegged,
    /// Wider shoulders, V-shaped torso, more muscle.
    BroadShouldered,
    /// High body weight, wider waist.
    Heavy,
    /// Low body weight, narrower waist.
    Slim,
}

/// Probability of each [`Build`] (average, long-legged, broad-shouldered, heavy, slim).
pub const BUILD_PROBABILITIES: [f64; 5] = [0.4, 0.15, 0.15, 0.15, 0.15];
/// Standard deviation of the local sliders before clipping to [−1, 1].
pub const LOCAL_SIGMA: f64 = 0.2;

/// Draws training humans of one gender from the documented distributions.
pub struct Sampler<'a> {
    categories: &'a [Category],
    idx: [usize; 5],
}

const NAMED: [&str; 5] = [
    "upperlegs-height-decr-incr",
    "lowerlegs-height-decr-incr",
    "measure-shoulder-dist-decr-incr",
    "torso-vshape-decr-incr",
    "measure-waist-circ-decr-incr",
];

impl<'a> Sampler<'a> {
    /// A sampler over `categories` (which must include the five categories the builds adjust).
    pub fn new(categories: &'a [Category]) -> Result<Sampler<'a>> {
        let mut idx = [0; 5];
        for (i, name) in NAMED.iter().enumerate() {
            idx[i] = categories
                .iter()
                .position(|c| c.name == *name)
                .ok_or_else(|| Error::CorruptData(format!("targets/target.json has no category {name}")))?;
        }
        Ok(Sampler { categories, idx })
    }

    /// Draws one adult of gender `gender` (0 female, 1 male) and the build it was given.
    pub fn draw(&self, gender: f64, rng: &mut ChaCha8Rng) -> (HumanParams, Build) {
        let u: f64 = rng.random();
        let mut acc = 0.0;
        let mut build = Build::Slim;
        for (p, b) in BUILD_PROBABILITIES.iter().zip([
            Build::Average,
            Build::LongLegged,
            Build::BroadShouldered,
            Build::Heavy,
            Build::Slim,
        ]) {
            acc += p;
            if u < acc {
                build = b;
                break;
            }
        }
        let height_dist = Normal::<f64>::new(0.5, 0.1).unwrap_or_else(|_| unreachable!("constant parameters"));
        let local_dist = Normal::<f64>::new(0.0, LOCAL_SIGMA).unwrap_or_else(|_| unreachable!("constant parameters"));
        let mut m = MacroParams {
            gender,
            age: rng.random_range(0.5..0.8),
            muscle: rng.random_range(0.0..1.0),
            weight: rng.random_range(0.0..1.0),
            height: height_dist.sample(rng).clamp(0.2, 0.8),
            proportions: rng.random_range(0.25..1.0),
            ethnic: [0.0; 3],
        };
        for e in &mut m.ethnic {
            *e = Exp1.sample(rng);
        }
        let mut local: Vec<f64> = (0..self.categories.len()).map(|_| local_dist.sample(rng)).collect();
        let [upper_legs, lower_legs, shoulders, vshape, waist] = self.idx;
        match build {
            Build::Average => {}
            Build::LongLegged => {
                local[upper_legs] += rng.random_range(0.3..0.9);
                local[lower_legs] += rng.random_range(0.3..0.9);
                m.proportions = rng.random_range(0.6..1.0);
            }
            Build::BroadShouldered => {
                local[shoulders] += rng.random_range(0.3..0.9);
                local[vshape] += rng.random_range(0.3..0.9);
                m.muscle = rng.random_range(0.5..1.0);
            }
            Build::Heavy => {
                m.weight = rng.random_range(0.75..1.0);
                local[waist] += rng.random_range(0.2..0.6);
            }
            Build::Slim => {
                m.weight = rng.random_range(0.0..0.25);
                m.muscle = rng.random_range(0.2..0.6);
                local[waist] -= rng.random_range(0.2..0.6);
            }
        }
        for v in &mut local {
            *v = v.clamp(-1.0, 1.0);
        }
        (HumanParams { macros: m, local }, build)
    }
}

#[cfg(test)]
mod tests {
    use super::super::macros::Slider;
    use super::*;
    use rand::SeedableRng;

    fn cats() -> Vec<Category> {
        let s = Slider { decr: String::new(), incr: String::new() };
        ["x"].iter().chain(NAMED.iter()).map(|n| Category { name: n.to_string(), sliders: vec![s.clone()] }).collect()
    }

    #[test]
    fn draws_are_seeded_in_range_and_cover_every_build() {
        let c = cats();
        let s = Sampler::new(&c).unwrap();
        let run = |seed| {
            let mut rng = ChaCha8Rng::seed_from_u64(seed);
            (0..300).map(|_| s.draw(1.0, &mut rng)).collect::<Vec<_>>()
        };
        let a = run(3);
        assert_eq!(a, run(3));
        for b in [Build::Average, Build::LongLegged, Build::BroadShouldered, Build::Heavy, Build::Slim] {
            assert!(a.iter().any(|(_, x)| *x == b), "{b:?} never drawn");
        }
        for (h, _) in &a {
            let m = h.macros;
            assert!((0.5..0.8).contains(&m.age) && (0.2..=0.8).contains(&m.height) && m.gender == 1.0);
            assert!(h.local.iter().all(|v| (-1.0..=1.0).contains(v)));
        }
        assert!(Sampler::new(&c[..2]).is_err());
    }
}
