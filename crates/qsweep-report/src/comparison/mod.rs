//! `qsweep compare A B`: did a change move a pipeline's results beyond chance? Two sides (a
//! program pipeline, an engine pipeline, either's `@variant`, or an engine report folder; often
//! the same thing before and after an edit) are matched cell by cell on the params they share,
//! and each matched cell's trials on one metric are compared:
//!
//! - [`matching`]: the two sides' cells, the shared params (after `--map`), the metric, each
//!   cell's sample (a program's from the cache's rows), and every bad input as a usage error;
//! - [`cells`]: a side given as cells already gathered, with the engine cells' param names;
//!   [`engine`] gathers an engine pipeline's from the cache as the report reads them, [`folder`]
//!   a report folder's from its `cells.parquet` (each cell's moments alone);
//! - [`stats`]: per cell the means, stds, the ratio of means B ÷ A with a 95 % interval (seeded
//!   bootstrap from trials, the delta method on the log ratio from moments), Welch's two-sided p,
//!   TOST on the ratio at the margin and a verdict; overall, how many cells have p < 0.05 against
//!   the 5 % chance gives (an exact binomial test);
//! - [`files`]: `compare.csv`, `compare.md` and `compare.svg` ([`figure`]), written atomically.
//!
//! Generic: it knows nothing of the paper's replication (whose `replication::compare` compares
//! a pipeline's variants with the paper), and takes its statistics from the statistics layer,
//! `qsweep_pipeline::analysis`.

pub mod cells;
pub mod engine;
pub mod figure;
pub mod files;
pub mod folder;
pub mod matching;
pub mod stats;

pub use cells::CellSet;
pub use matching::{Request, Side, Source};
pub use stats::{CellComparison, Comparison, Overall, RatioInterval, Verdict};

/// Compare `a` with `b` as `request` asks: match their cells, then test each matched cell.
pub fn compare(a: &Side, b: &Side, request: &Request) -> anyhow::Result<Comparison> {
    let matched = matching::match_cells(a, b, request)?;
    Ok(stats::compare_matched(matched, request.margin))
}
