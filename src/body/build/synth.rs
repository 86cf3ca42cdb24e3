//! Loading MakeHuman's targets and synthesising humans: `base + Σ_t w_t · Δ_t` over all 19158
//! vertices (decimetres, OBJ axes), with the weights of `macros.rs`.

use rayon::prelude::*;

use crate::error::Result;

use super::macros::{local_categories, Category, MacroParams};
use super::sample::HumanParams;
use super::wheel::{parse_target, Target, Wheel};

/// Folders of the macro targets.
const MACRO_DIRS: [&str; 3] =
    ["targets/macrodetails/", "targets/macrodetails/height/", "targets/macrodetails/proportions/"];

/// The base mesh and every target the model uses.
pub struct TargetSet {
    /// Base mesh vertices (all 19158), decimetres.
    pub base: Vec<[f64; 3]>,
    /// Macro target file stems (e.g. `universal-female-young-maxmuscle-minweight`), sorted by path.
    pub macro_stems: Vec<String>,
    /// Macro targets, parallel to `macro_stems`.
    pub macro_targets: Vec<Target>,
    /// Local slider categories (`targets/target.json`).
    pub categories: Vec<Category>,
    /// Per category, per slider: (decr target, incr target).
    pub local_targets: Vec<Vec<(Target, Target)>>,
}

impl TargetSet {
    /// Reads every macro target and the local targets of [`super::macros::LOCAL_GROUPS`].
    /// Files are read in sorted order and decompressed in parallel (order-preserving).
    pub fn load(wheel: &mut Wheel, base: Vec<[f64; 3]>) -> Result<TargetSet> {
        let n = base.len();
        let mut macro_paths = Vec::new();
        for dir in MACRO_DIRS {
            macro_paths.extend(wheel.list(dir, ".target.gz"));
        }
        let categories = local_categories(&wheel.read_json("targets/target.json")?)?;
        let local_paths: Vec<String> =
            categories.iter().flat_map(|c| c.sliders.iter().flat_map(|s| [s.decr.clone(), s.incr.clone()])).collect();
        let raw: Vec<(String, Vec<u8>)> =
            macro_paths.iter().chain(&local_paths).map(|p| Ok((p.clone(), wheel.read(p)?))).collect::<Result<_>>()?;
        let mut parsed: Vec<Target> = raw.par_iter().map(|(p, gz)| parse_target(p, gz, n)).collect::<Result<_>>()?;
        let mut local_iter = parsed.split_off(macro_paths.len()).into_iter();
        let local_targets = categories
            .iter()
            .map(|c| {
                c.sliders
                    .iter()
                    .map(|_| (local_iter.next().unwrap_or_default(), local_iter.next().unwrap_or_default()))
                    .collect()
            })
            .collect();
        let macro_stems = macro_paths
            .iter()
            .map(|p| p.rsplit('/').next().unwrap_or(p).trim_end_matches(".target.gz").to_string())
            .collect();
        Ok(TargetSet { base, macro_stems, macro_targets: parsed, categories, local_targets })
    }

    /// Number of local sliders (left and right counted separately).
    pub fn num_sliders(&self) -> usize {
        self.categories.iter().map(|c| c.sliders.len()).sum()
    }

    /// All vertices of the human with macro sliders `macros` and per-category local values
    /// `local` (missing values are 0), decimetres, OBJ axes. Targets are added in a fixed order.
    pub fn synthesize(&self, macros: &MacroParams, local: &[f64]) -> Result<Vec<[f64; 3]>> {
        let mut v = self.base.clone();
        let add = |v: &mut [[f64; 3]], t: &Target, w: f64| {
            if w != 0.0 {
                for &(i, d) in &t.offsets {
                    let p = &mut v[i as usize];
                    p[0] += w * d[0];
                    p[1] += w * d[1];
                    p[2] += w * d[2];
                }
            }
        };
        for (stem, t) in self.macro_stems.iter().zip(&self.macro_targets) {
            add(&mut v, t, macros.target_weight(stem)?);
        }
        for (c, targets) in self.local_targets.iter().enumerate() {
            let s = local.get(c).copied().unwrap_or(0.0);
            for (decr, incr) in targets {
                add(&mut v, decr, (-s).max(0.0));
                add(&mut v, incr, s.max(0.0));
            }
        }
        Ok(v)
    }

    /// [`TargetSet::synthesize`] for a batch, in parallel; the output order follows the input.
    pub fn synthesize_all(&self, humans: &[HumanParams]) -> Result<Vec<Vec<[f64; 3]>>> {
        humans.par_iter().map(|h| self.synthesize(&h.macros, &h.local)).collect()
    }
}
