//! The numbers of a comparison of variants: each variant's fit to the published Table
//! III, its verdicts at each assumed number of paper runs, the honest choice among variants, the
//! paper against itself, its conclusions tested, and what the comparison keeps of each variant.

pub mod conclusions;
pub mod consistency;
mod digest;
pub mod explore;
pub mod fit;
mod info;
pub mod ratios;
pub mod selection;
pub mod verdicts;

pub use digest::{CellDigest, ExpDigest, VariantDigest, VariantInfo};
pub use fit::{
    comparison_table, fit_order, fit_verdict, rows_of, Fit, FitVerdict, RowFit, Verdict, FIT_ORDER,
    REFERENCE_N, VERDICT_RULE,
};
