//! One Table III row judged at one assumed number of paper runs: the verdict scale for its best
//! cell and its cell at the paper's configuration, the contradictions and the cause (the rules of
//! [`crate::replication::stats::verdict`]), shared by Table III's columns and the comparison.

use crate::derive::report_data::CellData;
use crate::replication::published::Contradictions;
use crate::replication::stats::equivalence::Moments;
use crate::replication::stats::verdict::{cause, judge, Cause, Judged};
use qsweep_engine::Algorithm;
use qsweep_pipeline::declared::Reference;

/// One Table III row judged at one assumed number of paper runs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RowJudgement {
    /// The assumed number of paper runs.
    pub paper_n: usize,
    /// The best cell's verdict.
    pub best: Judged,
    /// The verdict of the cell at the paper's configuration (`None`: no such cell with trials).
    pub paper_cell: Option<Judged>,
    /// The row belongs to a contradictory pair.
    pub in_pair: bool,
    /// A contradictory pair designates the row.
    pub designated: bool,
    /// The row's cause ([`cause`]).
    pub cause: Cause,
}

/// A cell's estimate as the verdicts read it (fresh-seed where present; `None` without trials).
pub fn moments(cell: &CellData) -> Option<Moments> {
    let est = cell.estimate();
    Some(Moments { mean: est.summary.mean?, std: est.summary.std, n: est.n() })
}

/// A row judged at `paper_n` from its best cell's and its paper's cell's estimates, against `r`.
pub fn judge_row(
    best: Moments,
    at: Option<Moments>,
    r: &Reference,
    contradictions: &Contradictions,
    row: (usize, Algorithm),
    paper_n: usize,
) -> RowJudgement {
    let best_j = judge(best, r.mean, r.std, paper_n);
    let at_j = at.map(|m| judge(m, r.mean, r.std, paper_n));
    let designated = contradictions.designated.contains(&row);
    RowJudgement {
        paper_n,
        best: best_j,
        paper_cell: at_j,
        in_pair: contradictions.in_pair.contains(&row),
        designated,
        cause: cause(best_j.verdict, designated, at_j.map(|j| j.verdict)),
    }
}
