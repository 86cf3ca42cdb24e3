//! MakeHuman's modifier weighting, written from the description in `shared/data/makehuman.md`:
//! a macro target's weight is the product of the factors named in its file name; a local
//! decr/incr slider s in [−1, 1] weighs its `incr` target by max(s, 0) and its `decr` target by
//! max(−s, 0).

use crate::error::{Error, Result};

/// Macro slider values, each in [0, 1] (MakeHuman's "macro details").
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MacroParams {
    /// 0 female … 1 male.
    pub gender: f64,
    /// 0 → 1 year, 0.1875 → 10, 0.5 → 25, 1 → 90 years.
    pub age: f64,
    /// Muscularity: 0 min, 0.5 average, 1 max.
    pub muscle: f64,
    /// Body weight: 0 min, 0.5 average, 1 max.
    pub weight: f64,
    /// Height: 0.5 applies no height target.
    pub height: f64,
    /// Body proportions: 0 uncommon, 0.5 none, 1 ideal.
    pub proportions: f64,
    /// Ethnic mix (african, asian, caucasian), non-negative; normalised to sum 1 when used.
    pub ethnic: [f64; 3],
}

impl MacroParams {
    /// MakeHuman's default human: every slider 0.5, equal ethnic mix.
    pub fn default_human() -> MacroParams {
        MacroParams { gender: 0.5, age: 0.5, muscle: 0.5, weight: 0.5, height: 0.5, proportions: 0.5, ethnic: [1.0; 3] }
    }

    /// The value of one file-name token (`female`, `young`, `maxmuscle`, `asian`, ...), or `None`
    /// for a token that is not a macro factor.
    pub fn factor(&self, token: &str) -> Option<f64> {
        let low_high = |x: f64| {
            let max = (2.0 * x - 1.0).max(0.0);
            let min = (1.0 - 2.0 * x).max(0.0);
            (min, 1.0 - max - min, max)
        };
        let a = self.age;
        let (baby, child, young, old) = if a < 0.5 {
            let young = ((a - 0.1875) * 3.2).max(0.0);
            let baby = (1.0 - a / 0.1875).max(0.0);
            let child = ((a / 0.1875).min(1.0) - young).max(0.0);
            (baby, child, young, 0.0)
        } else {
            let old = 2.0 * a - 1.0;
            (0.0, 0.0, 1.0 - old, old)
        };
        let (min_m, avg_m, max_m) = low_high(self.muscle);
        let (min_w, avg_w, max_w) = low_high(self.weight);
        let eth_sum: f64 = self.ethnic.iter().sum();
        let eth = |i: usize| if eth_sum > 0.0 { self.ethnic[i] / eth_sum } else { 1.0 / 3.0 };
        Some(match token {
            "universal" => 1.0,
            "female" => 1.0 - self.gender,
            "male" => self.gender,
            "baby" => baby,
            "child" => child,
            "young" => young,
            "old" => old,
            "minmuscle" => min_m,
            "averagemuscle" => avg_m,
            "maxmuscle" => max_m,
            "minweight" => min_w,
            "averageweight" => avg_w,
            "maxweight" => max_w,
            "minheight" => (1.0 - 2.0 * self.height).max(0.0),
            "maxheight" => (2.0 * self.height - 1.0).max(0.0),
            "uncommonproportions" => (1.0 - 2.0 * self.proportions).max(0.0),
            "idealproportions" => (2.0 * self.proportions - 1.0).max(0.0),
            "african" => eth(0),
            "asian" => eth(1),
            "caucasian" => eth(2),
            _ => return None,
        })
    }

    /// Weight of the macro target whose file stem (name without folders and `.target.gz`) is
    /// `stem`, e.g. `universal-female-young-maxmuscle-minweight`.
    pub fn target_weight(&self, stem: &str) -> Result<f64> {
        stem.split('-').try_fold(1.0, |acc, token| {
            self.factor(token)
                .map(|f| acc * f)
                .ok_or_else(|| Error::CorruptData(format!("macro target {stem}: unknown factor {token:?}")))
        })
    }
}

/// One local decr/incr slider (one side of a left/right pair, or an unsided one).
#[derive(Clone, Debug, PartialEq)]
pub struct Slider {
    /// Data path of the `decr` (negative) target.
    pub decr: String,
    /// Data path of the `incr` (positive) target.
    pub incr: String,
}

/// A modifier category of `targets/target.json`: one slider, or a left and a right one that the
/// sampler sets to the same value (symmetric bodies).
#[derive(Clone, Debug, PartialEq)]
pub struct Category {
    /// Category name, e.g. `upperlegs-height-decr-incr`.
    pub name: String,
    /// Its sliders (1 unsided, or 2: left then right).
    pub sliders: Vec<Slider>,
}

/// The body-shape groups of `targets/target.json` whose sliders the model uses (111 sliders).
pub const LOCAL_GROUPS: [&str; 9] = ["arms", "buttocks", "feet", "hands", "hip", "legs", "pelvis", "stomach", "torso"];

/// Reads the categories of [`LOCAL_GROUPS`] from `targets/target.json`, in file order.
pub fn local_categories(target_json: &serde_json::Value) -> Result<Vec<Category>> {
    let bad = |what: String| Error::CorruptData(format!("targets/target.json: {what}"));
    let mut out = Vec::new();
    for group in LOCAL_GROUPS {
        let cats = target_json
            .get(group)
            .and_then(|g| g.get("categories"))
            .and_then(|c| c.as_array())
            .ok_or_else(|| bad(format!("no categories for group {group}")))?;
        for cat in cats {
            let name =
                cat.get("name").and_then(|n| n.as_str()).ok_or_else(|| bad(format!("unnamed category in {group}")))?;
            let opp = cat.get("opposites").ok_or_else(|| bad(format!("{name}: no opposites")))?;
            let get = |key: &str| -> Result<String> {
                let t = opp.get(key).and_then(|t| t.as_str()).filter(|t| !t.is_empty());
                t.map(|t| format!("targets/{group}/{t}.target.gz"))
                    .ok_or_else(|| bad(format!("{name}: no {key} target")))
            };
            let sided = cat.get("has_left_and_right").and_then(|b| b.as_bool()).unwrap_or(false);
            let sliders = if sided {
                vec![
                    Slider { decr: get("negative-left")?, incr: get("positive-left")? },
                    Slider { decr: get("negative-right")?, incr: get("positive-right")? },
                ]
            } else {
                vec![Slider { decr: get("negative-unsided")?, incr: get("positive-unsided")? }]
            };
            out.push(Category { name: name.to_string(), sliders });
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn factors_follow_the_documented_formulas() {
        let mut p = MacroParams::default_human();
        assert_eq!(p.target_weight("universal-female-young-averagemuscle-averageweight").unwrap(), 0.5);
        assert_eq!(p.target_weight("female-young-averagemuscle-averageweight-maxheight").unwrap(), 0.0);
        assert!((p.target_weight("caucasian-male-young").unwrap() - 0.5 / 3.0).abs() < 1e-15);
        p.age = 0.75;
        assert_eq!((p.factor("old").unwrap(), p.factor("young").unwrap()), (0.5, 0.5));
        p.age = 0.1875;
        assert_eq!(
            (p.factor("baby").unwrap(), p.factor("child").unwrap(), p.factor("young").unwrap()),
            (0.0, 1.0, 0.0)
        );
        p.age = 0.3;
        let (c, y) = (p.factor("child").unwrap(), p.factor("young").unwrap());
        assert!((c + y - 1.0).abs() < 1e-12 && (y - 0.36).abs() < 1e-12, "child {c} young {y}");
        p.muscle = 0.75;
        assert_eq!(
            (p.factor("minmuscle").unwrap(), p.factor("averagemuscle").unwrap(), p.factor("maxmuscle").unwrap()),
            (0.0, 0.5, 0.5)
        );
        p.height = 0.2;
        assert!((p.factor("minheight").unwrap() - 0.6).abs() < 1e-12);
        assert_eq!(p.factor("maxheight").unwrap(), 0.0);
        assert!(p.target_weight("female-bogus").is_err());
    }

    #[test]
    fn reads_sided_and_unsided_categories() {
        let json: serde_json::Value = serde_json::from_str(
            r#"{"arms":{"categories":[{"name":"a-decr-incr","has_left_and_right":true,"opposites":{"negative-left":"l-a-decr","positive-left":"l-a-incr","negative-right":"r-a-decr","positive-right":"r-a-incr"}}]},
                "buttocks":{"categories":[]},"feet":{"categories":[]},"hands":{"categories":[]},"hip":{"categories":[{"name":"h","has_left_and_right":false,"opposites":{"negative-unsided":"h-in","positive-unsided":"h-out"}}]},
                "legs":{"categories":[]},"pelvis":{"categories":[]},"stomach":{"categories":[]},"torso":{"categories":[]}}"#,
        )
        .unwrap();
        let cats = local_categories(&json).unwrap();
        assert_eq!(cats.len(), 2);
        assert_eq!(cats[0].sliders[1].incr, "targets/arms/r-a-incr.target.gz");
        assert_eq!(
            cats[1].sliders,
            vec![Slider { decr: "targets/hip/h-in.target.gz".into(), incr: "targets/hip/h-out.target.gz".into() }]
        );
    }
}
