//! Parse-time range checks for numeric options, so that a bad value fails at once (exit 2)
//! with clap's message naming the option, before any file is read or model loaded.

use std::ops::RangeInclusive;

use clap::builder::RangedU64ValueParser;

/// An integer option in `range` (clap reports "`VALUE` is not in LO..=HI" naming the option).
pub fn count(range: RangeInclusive<u64>) -> RangedU64ValueParser<usize> {
    RangedU64ValueParser::new().range(range)
}

/// A finite real option in `lo..=hi`, or above `lo` when `open_low` (for "must be > 0").
pub fn real(lo: f64, hi: f64, open_low: bool) -> impl Fn(&str) -> Result<f64, String> + Clone + Send + Sync + 'static {
    move |s: &str| {
        let v: f64 = s.trim().parse().map_err(|_| format!("`{s}` is not a number"))?;
        let low_ok = if open_low { v > lo } else { v >= lo };
        if v.is_finite() && low_ok && v <= hi {
            Ok(v)
        } else {
            let low = if open_low { format!("> {lo}") } else { format!(">= {lo}") };
            Err(format!("{v} is not {low} and <= {hi}"))
        }
    }
}
