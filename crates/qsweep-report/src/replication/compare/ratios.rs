//! The rows of the forest plot ([`crate::replication::pages::forest`]): each Table III row's ratio of
//! our estimate to the paper's mean, with its interval, as `table3.csv`'s ratio columns hold it.

use crate::derive::report_data::ReportData;
use qsweep_engine::env::SystemKind;
use qsweep_engine::repr::ReprKind;
use qsweep_engine::Algorithm;

/// One Table III row as the forest plots it.
#[derive(Debug, Clone, PartialEq)]
pub struct ForestRow {
    /// The system.
    pub system: SystemKind,
    /// The experiment id.
    pub experiment: String,
    /// The algorithm.
    pub algorithm: Algorithm,
    /// "Cart-Pole · Exp 3 · fuzzy Q(λ)".
    pub label: String,
    /// Ours ÷ reference (`table3.csv`'s `ratio`).
    pub ratio: f64,
    /// Its 95 % interval (`ratio_lo`, `ratio_hi`); `None` for a single trial.
    pub ci: Option<(f64, f64)>,
    /// Whether the estimate is the fresh-seed one.
    pub fresh: bool,
}

/// Every Table III row of `data` with a positive reference mean and a best cell, in report order,
/// with the numbers of `table3.csv`'s ratio columns.
pub fn rows_of(data: &ReportData) -> Vec<ForestRow> {
    let mut out = Vec::new();
    for e in &data.experiments {
        for &alg in &e.exp.algorithms {
            let Some(r) = e.exp.reference.get(&alg).filter(|r| r.mean > 0.0) else { continue };
            let Some(c) = e.best_of(alg).map(|b| &e.cells[b.cell]) else { continue };
            let est = c.estimate();
            let Some(mean) = est.summary.mean else { continue };
            let fuzzy = if e.exp.repr == ReprKind::Fuzzy { "fuzzy " } else { "" };
            out.push(ForestRow {
                system: e.exp.system,
                experiment: e.exp.id.clone(),
                algorithm: alg,
                label: format!("{} · Exp {} · {fuzzy}{}", e.exp.system.title(), e.exp.id, alg.symbol()),
                ratio: mean / r.mean,
                ci: est.summary.ci_lo.zip(est.summary.ci_hi).map(|(lo, hi)| (lo / r.mean, hi / r.mean)),
                fresh: est.fresh,
            });
        }
    }
    out
}
