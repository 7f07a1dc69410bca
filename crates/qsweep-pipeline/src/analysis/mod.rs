//! Statistics in one layer below both the race and the report: cell summaries (mean, std,
//! quantiles, bootstrap intervals), Table III's rules (episodes counted, the best cell) and the
//! race's test (Welch, Holm), and what `qsweep compare` adds: the two-sided Welch test, the
//! equivalence test on a ratio of means (TOST, shared with the replication), the bootstrap
//! interval of a ratio of means (and, from moments alone, its delta-method interval and Welch's test)
//! and the binomial tail. Everything is a pure, seeded function of its inputs, so reports stay
//! byte-identical; the race only decides rounds with these, the report renders them. Statistics
//! only the report uses live in the report crate (`qsweep_report::derive::rank`, and the
//! replication's own in `qsweep_report::replication::stats`).

mod best;
mod binomial;
pub mod equivalence;
mod summary;
pub mod welch;

pub use best::{best_cell, episodes_counted, Best, Candidate, BEST_RULE, CENSORING, RACE_RULE};
pub use binomial::binomial_sf;
pub use equivalence::{ratio_ci_delta, tost_ratio, Tost};
pub use summary::{
    bootstrap_ci, bootstrap_diff_ci, bootstrap_ratio_ci, interval_95, iqm_sorted, mean, quantile_sorted,
    resample_mean, sample_std, Moments, Summary, BOOTSTRAP_RESAMPLES,
};
