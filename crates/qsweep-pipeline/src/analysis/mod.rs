//! Statistics in one layer, below both the race and the report: cell summaries (mean, std,
//! quantiles, bootstrap intervals), Table III's rules (episodes counted, the best cell) and the
//! race's test (Welch, Holm), equivalence with the published values (TOST) and the verdict scale, what choosing among variants is worth (a permutation yardstick), survival under the
//! episode cap (Kaplan–Meier), rank correlation, and the paper's claims as tests. Everything is a pure, seeded function of its inputs, so reports stay
//! byte-identical; the race only decides rounds with these, the report only renders them.

mod best;
pub mod claims;
pub mod consistency;

pub mod equivalence;
pub mod rank;
pub mod selection;
mod summary;
pub mod survival;
pub mod verdict;
pub mod welch;

pub use best::{best_cell, episodes_counted, Best, Candidate, BEST_RULE, CENSORING, RACE_RULE};
pub use summary::{
    bootstrap_ci, bootstrap_diff_ci, iqm_sorted, mean, quantile_sorted, sample_std, Summary,
    BOOTSTRAP_RESAMPLES,
};
