//! The report stage: from a plan and the trial outcomes found for it, write
//!
//! - `table3.md`, `table3.csv`, `table3.tex`: the paper's Table III (best cell per system,
//!   experiment and algorithm, with the paper's values when the pipeline gives them);
//! - `cells.parquet`, `trials.parquet`: the data behind it (schemas in [`parquet`]);
//! - `figures/<system>.svg` (`.png` on request): the paper's Figures 5–7 (see [`figures`]);
//! - `figures/<system>-curves.svg`: learning curves of the best cells (see [`curves`]);
//! - `index.html` and `README.md`: the tables and the figures on one page, for a browser and for
//!   a repository web page;
//! - `manifest.json`: what the folder holds ([`manifest`]), read by the overwrite guard;
//! - `memo.json`: what the folder was computed from and each file's digest ([`memo`]), so a
//!   rerun skips a folder whose inputs have not changed.
//!
//! [`stage::write`] is the whole stage for a pipeline, one variant at a time ([`compare`] for the
//! comparison of variants). Which files are written is chosen by [`formats`]. Trials missing from the records are left
//! out and counted. Every file is written atomically (a temporary file in the same directory,
//! then a rename), and the output is a pure function of the inputs: no timestamps, no hash-map
//! order, a seeded bootstrap.

pub mod compare;
pub mod curves;
pub mod datasets;
pub mod escape;
pub mod figures;
mod folder;
pub mod formats;
pub mod glyphs;
pub mod html;
pub mod judgement;
pub mod manifest;
pub mod markdown;
pub mod memo;
pub mod model;
mod outcome;
pub mod stage;
pub mod stale;
pub mod svg;
pub mod svg_grid;
pub mod svg_text;
pub mod table;
mod target;
pub mod text_fit;
pub mod trials;

pub use crate::atomic::write_atomic;
pub use folder::{existing_trials, write_folder, ReportSummary};
pub use model::{Outcomes, ReportData};
pub use stage::{default_dir, write, write_replayed, ReportOptions, ReportOutcome};
pub use stale::{staleness, Staleness};
