//! `qsweep compare A B`: did a change move a program pipeline's results beyond chance? Two
//! program pipelines (often the same program before and after an edit) are matched cell by cell
//! on the params they share, and each matched cell's trials on one metric are compared:
//!
//! - [`matching`]: the two sides' cells, the shared params (after `--map`), the metric, each
//!   cell's values from the cache's rows, and every bad input as a usage error;
//! - [`stats`]: per cell the means, stds, the ratio of means B ÷ A with a seeded bootstrap 95 %
//!   interval, Welch's two-sided p, TOST on the ratio at the margin and a verdict; overall, how
//!   many cells have p < 0.05 against the 5 % chance gives (an exact binomial test);
//! - [`files`]: `compare.csv`, `compare.md` and `compare.svg` ([`figure`]), written atomically.
//!
//! Generic: it knows nothing of the paper's replication (whose `replication::compare` compares
//! a pipeline's variants with the paper), and takes its statistics from the statistics layer,
//! `qsweep_pipeline::analysis`.

pub mod figure;
pub mod files;
pub mod matching;
pub mod stats;

pub use matching::{Request, Side};
pub use stats::{CellComparison, Comparison, Overall, Verdict};

/// Compare `a` with `b` as `request` asks: match their cells, then test each matched cell.
pub fn compare(a: &Side, b: &Side, request: &Request) -> anyhow::Result<Comparison> {
    let matched = matching::match_cells(a, b, request)?;
    Ok(stats::compare_matched(matched, request.margin))
}
