//! The detector's search flags, shared by `sketchbody detect` and `sketchbody-lab eval-detector`:
//! figure sizes (`--min-figure`, `--max-figure`, `--all-scales`), pyramid cells (`--min-cell`,
//! `--max-cell`) and `--levels-per-octave`, turned into `DetectOptions`.

use sketchbody::detect::{DetectOptions, SearchScales, SKETCH_LEVELS_PER_OCTAVE, SKETCH_SEARCH};

/// Which scales the detector searches.
#[derive(clap::Args, Clone, Debug)]
pub struct SearchArgs {
    /// Skip pyramid levels with cells smaller than this many pixels (faster; misses small figures).
    #[arg(long, default_value_t = 0.0)]
    pub min_cell: f64,
    /// Skip pyramid levels with cells larger than this many pixels (faster; misses large figures).
    #[arg(long, default_value_t = f64::INFINITY)]
    pub max_cell: f64,
    /// Smallest figure searched, as a fraction of the shorter image side (default 0.5, the
    /// sketch search range of `DetectOptions`).
    #[arg(long)]
    pub min_figure: Option<f64>,
    /// Largest figure searched, as a fraction of the longer image side (default 1.0).
    #[arg(long)]
    pub max_figure: Option<f64>,
    /// Search every pyramid level (small figures in photos) instead of the sketch range.
    #[arg(long, conflicts_with_all = ["min_figure", "max_figure"])]
    pub all_scales: bool,
    /// Pyramid levels per octave (0 = the model's own, 10 for the embedded and the PARSE model:
    /// finer in scale, 1.4 times the work of the sketch default 7; 5 = every other level of 10).
    #[arg(long, default_value_t = SKETCH_LEVELS_PER_OCTAVE)]
    pub levels_per_octave: usize,
    /// Ink-box normalisation: a drawing whose ink square is larger than N px is cropped to it and
    /// downscaled to N² before the search (0 = off: the whole page, downscaled to 1024 px).
    #[arg(long, default_value_t = sketchbody::detect::DEFAULT_NORMALISE_SIDE, value_parser = normalise_side)]
    pub normalise: usize,
}

/// `--normalise`: 0 or at least the detector's smallest side.
fn normalise_side(s: &str) -> Result<usize, String> {
    let n: usize = s.parse().map_err(|e| format!("{e}"))?;
    let min = sketchbody::detect::MIN_DETECT_SIDE;
    if n != 0 && n < min {
        return Err(format!("{n}: expected 0 (off) or at least {min}"));
    }
    Ok(n)
}

impl SearchArgs {
    /// The search as detection options (other fields at their defaults).
    pub fn options(&self) -> DetectOptions {
        let search = match (self.all_scales, SKETCH_SEARCH) {
            (true, _) => SearchScales::All,
            (false, SearchScales::FigureFraction { min, max }) => SearchScales::FigureFraction {
                min: self.min_figure.unwrap_or(min),
                max: self.max_figure.unwrap_or(max),
            },
            (false, s) => s,
        };
        let levels_per_octave = (self.levels_per_octave > 0).then_some(self.levels_per_octave);
        DetectOptions {
            min_cell_px: self.min_cell,
            max_cell_px: self.max_cell,
            search,
            levels_per_octave,
            normalise: (self.normalise > 0).then_some(self.normalise),
            ..DetectOptions::default()
        }
    }

    /// One-line description of the search, for reports.
    pub fn describe(&self) -> String {
        let o = self.options();
        let search = match o.search {
            SearchScales::All => "all scales".to_string(),
            SearchScales::FigureFraction { min, max } => format!("figures {min}..{max} of the side"),
        };
        let levels = o
            .levels_per_octave
            .map_or("the model's levels per octave".to_string(), |n| format!("{n} levels per octave"));
        format!("{search}, cells {}..{} px, {levels}", self.min_cell, self.max_cell)
    }
}
