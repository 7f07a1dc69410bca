//! What the comparison's pages show and share: the tables computed once for both pages, the
//! difference figures written, which variants have a folder, the heading and the hand-written
//! notes beside the report.

use crate::derive::table::Table;
use crate::replication::compare::{explore, VariantInfo};
use qsweep_engine::env::SystemKind;
use qsweep_pipeline::plan::Plan;

/// Whether the report writes the folder of variant `id` (and its difference figures): every
/// declared (not exploratory) variant of a pipeline without a grid; with a `variant_grid:`, only the chosen variant, so a
/// grid of many variants does not write (or commit) a full report each; the rest are written on
/// demand with `qsweep report PIPELINE --variant ID`.
/// `chosen` is [`explore::chosen`]'s id, worked out once per page rather than once per variant.
pub fn has_folder(plan: &Plan, chosen: Option<&str>, id: &str) -> bool {
    (!plan.has_grid() || chosen == Some(id)) && !plan.variants.iter().any(|v| v.id == id && v.exploratory)
}

/// The heading of the comparison pages: `qsweep variants: NAME`, labelled when exploratory.
pub(super) fn heading(plan: &Plan) -> String {
    match plan.exploratory {
        Some(_) => format!("qsweep variants: {} ({})", plan.name, explore::LABEL),
        None => format!("qsweep variants: {}", plan.name),
    }
}

/// A difference figure written: its variant, system, file stem and size.
pub(super) type FigRef<'a> = (&'a VariantInfo, SystemKind, String, (u32, u32));

/// The tables of the comparison pages.
pub(super) struct Tables<'a> {
    /// The fit of every variant.
    pub(super) fit: &'a Table,
    /// An exploratory search's held-out rows.
    pub(super) held_out: Option<&'a Table>,
    /// The variant × claim matrix (pipelines with reference values).
    pub(super) matrix: Option<&'a Table>,
    /// The pairs of Table III rows whose grids overlap (pipelines with reference values).
    pub(super) consistency: Option<&'a Table>,
    /// Whether `verdicts_by_n.csv` is written.
    pub(super) by_n: bool,
}

/// The hand-written notes a comparison folder may hold beside the report (the paper's
/// `REPLICATION.md`): never written or removed by qsweep, linked from the page when present.
pub const NOTES: &str = "REPLICATION.md";
