//! qsweep's report stage: from a plan and the trial outcomes found for it, write
//!
//! - `table3.md`, `table3.csv`, `table3.tex`: the paper's Table III (best cell per system,
//!   experiment and algorithm, with the paper's values when the pipeline gives them);
//! - `cells.parquet`, `trials.parquet`: the data behind it (schemas in [`render::datasets`]);
//! - `figures/<system>.svg` (`.png` on request): the paper's Figures 5–7 (see [`render::figures`]);
//! - `figures/<system>-curves.svg`: learning curves of the best cells (see [`render::curves`]);
//! - `index.html` and `README.md`: the tables and the figures on one page, for a browser and for
//!   a repository web page;
//! - `manifest.json`: what the folder holds ([`stage::manifest`]), read by the overwrite guard;
//! - `memo.json`: what the folder was computed from and each file's digest ([`memo::folders`]), so a
//!   rerun skips a folder whose inputs have not changed.
//!
//! [`stage::write`] is the whole stage for a pipeline, one variant at a time ([`render::compare`]
//! for the comparison of variants). Which files are written is chosen by [`formats`]. Trials missing from the records are left
//! out and counted. Every file is written atomically (a temporary file in the same directory,
//! then a rename), and the output is a pure function of the inputs: no timestamps, no hash-map
//! order, a seeded bootstrap.

//!
//! The crate's parts, each built only on those before it:
//!
//! - [`formats`]: which files a report writes (`--formats`);
//! - [`memo`]: the one owner of derived results kept between reports (the statistics' memo in the
//!   cache, the per-variant trial parts, each folder's `memo.json`), with [`memo::ANALYSIS_VERSION`];
//! - [`derive`]: the numbers (per-cell statistics, Table III as a format-neutral table, the fit of
//!   each variant to the paper, its verdicts, claims and causes), computed or taken from the memo;
//! - [`render`]: pure functions of derived numbers into files (CSV, Markdown, LaTeX, HTML tables;
//!   SVG/PNG figures; pages; Parquet datasets);
//! - [`comparison`]: `qsweep compare A B`, two program pipelines matched cell by cell and
//!   tested (generic, beside the replication, never importing it);
//! - [`stage`]: the report stage itself: which folders to write, guarded against writing less
//!   than they hold, reusing what the memo says is unchanged.
//!
//! `derive` never imports `render` or `stage`, and `render` never imports `stage`
//! (`tests/cli/layering.rs`).

// clippy.toml lists the platform's transcendental functions; only the trial path (the engine,
// which denies the lint) must do without them.
#![allow(clippy::disallowed_methods)]

pub mod comparison;
pub mod derive;
pub mod formats;
pub mod memo;
pub mod render;
pub mod replication;
pub mod stage;

pub use derive::report_data::{Outcomes, ReportData};
pub use render::folder::{existing_trials, write_folder, ReportSummary};
pub use stage::stale::{staleness, Staleness};
pub use stage::{default_dir, write, write_replayed, ReportOptions, ReportWritten};
