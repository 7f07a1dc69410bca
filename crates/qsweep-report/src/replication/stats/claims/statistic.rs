//! Every claim's statistic under one view of the cells (the cells as they are, or one bootstrap
//! resample), each claim a method of [`Resample`], which holds what several claims share: each
//! heatmap's best cell (Table III's rule) and its rank correlation of state count and mean.

use super::definitions::{ClaimCell, View, CLAIMS, PAPER_SYSTEMS};
use super::groups::Groups;
use crate::derive::rank::{average_ranks, pearson, spearman};
use qsweep_engine::env::SystemKind;
use qsweep_engine::Algorithm;
use qsweep_pipeline::analysis::{best_cell, Candidate};

/// Every claim's statistic under `view`, in [`CLAIMS`] order.
pub(super) fn statistics(cells: &[ClaimCell], g: &Groups, view: &[View]) -> [Option<f64>; CLAIMS.len()] {
    let r = Resample::new(cells, g, view);
    [
        r.qlambda_beats_q0(),
        r.traces(),
        r.compact_best(),
        r.excessive(),
        r.robust(),
        r.fastest(),
        r.fuzzy_benefit(),
        r.narrowed(),
        r.richer(),
        success_rate(&g.cart_pole, view),
    ]
}

/// One view of the cells with what several claims share.
struct Resample<'a> {
    cells: &'a [ClaimCell],
    g: &'a Groups,
    view: &'a [View],
    /// Per heatmap: its best cell (Table III's rule).
    best: Vec<Option<usize>>,
    /// Per heatmap: ρ(state count, mean).
    rho: Vec<Option<f64>>,
}

impl<'a> Resample<'a> {
    fn new(cells: &'a [ClaimCell], g: &'a Groups, view: &'a [View]) -> Self {
        let mean = |i: usize| view[i].mean;
        let best = g
            .heatmaps
            .iter()
            .map(|h| {
                let cands = h.cells.iter().map(|&i| Candidate {
                    index: i,
                    n: view[i].n,
                    successes: view[i].successes,
                    mean: view[i].mean,
                });
                best_cell(cands).map(|b| b.cell)
            })
            .collect();
        let rho = g
            .heatmaps
            .iter()
            .map(|h| {
                let y: Vec<f64> = h.cells.iter().filter_map(|&i| mean(i)).collect();
                if y.len() == h.cells.len() {
                    pearson(&h.state_ranks, &average_ranks(&y))
                } else {
                    let (x, y): (Vec<f64>, Vec<f64>) = h
                        .cells
                        .iter()
                        .zip(&h.states)
                        .filter_map(|(&i, &s)| mean(i).map(|m| (s, m)))
                        .collect();
                    spearman(&x, &y)
                }
            })
            .collect();
        Self { cells, g, view, best, rho }
    }

    fn mean(&self, i: usize) -> Option<f64> {
        self.view[i].mean
    }

    /// The heatmap of experiment `e` and algorithm `a`.
    fn find(&self, e: usize, a: Algorithm) -> Option<usize> {
        self.g.heatmaps.iter().position(|h| h.experiment == e && h.algorithm == a)
    }

    /// The mean of heatmap `k`'s best cell.
    fn best_mean(&self, k: usize) -> Option<f64> {
        self.best[k].and_then(|i| self.mean(i))
    }

    /// |ln(best Q(0) ÷ best Q(λ))| of experiment `e`.
    fn gap(&self, e: usize) -> Option<f64> {
        let a = self.best_mean(self.find(e, Algorithm::Q0)?)?;
        let b = self.best_mean(self.find(e, Algorithm::QLambda)?)?;
        (a > 0.0 && b > 0.0).then(|| (a / b).ln().abs())
    }

    /// The system and representation (fuzzy) of experiment `e`.
    fn system_of(&self, e: usize) -> Option<(SystemKind, bool)> {
        self.g.heatmaps.iter().find(|h| h.experiment == e).map(|h| (h.system, h.fuzzy))
    }

    /// Per system, the share of paired cells where Q(λ) needs fewer episodes than Q(0) (ties
    /// count half); the smallest system's share.
    fn qlambda_beats_q0(&self) -> Option<f64> {
        if self.g.algorithm_pairs.len() < PAPER_SYSTEMS.len() {
            return None;
        }
        self.g
            .algorithm_pairs
            .iter()
            .filter_map(|pairs| {
                average(pairs.iter().filter_map(|&(q0, ql)| {
                    let (a, b) = (self.mean(q0)?, self.mean(ql)?);
                    Some(if b < a {
                        1.0
                    } else if b == a {
                        0.5
                    } else {
                        0.0
                    })
                }))
            })
            .min_by(f64::total_cmp)
    }

    /// Mountain Car's success rate under Q(λ) less that under Q(0).
    fn traces(&self) -> Option<f64> {
        let g = self.g;
        Some(success_rate(&g.mountain_car[1], self.view)? - success_rate(&g.mountain_car[0], self.view)?)
    }

    /// The share of compact configurations among the best cells less that among all cells.
    fn compact_best(&self) -> Option<f64> {
        let compact = |i: usize| f64::from(u8::from(self.g.compact[i]));
        let all = average((0..self.cells.len()).filter(|&i| self.view[i].n > 0).map(compact))?;
        let chosen = average(self.best.iter().flatten().map(|&i| compact(i)))?;
        Some(chosen - all)
    }

    /// The mean over heatmaps of ρ(state count, mean).
    fn excessive(&self) -> Option<f64> {
        average(self.rho.iter().flatten().copied())
    }

    /// The mean over experiments of ρ under Q(0) less ρ under Q(λ).
    fn robust(&self) -> Option<f64> {
        average(self.g.experiments.iter().filter_map(|&e| {
            Some(self.rho[self.find(e, Algorithm::Q0)?]? - self.rho[self.find(e, Algorithm::QLambda)?]?)
        }))
    }

    /// The mean over systems of ln(best other combination ÷ best fuzzy Q(λ)).
    fn fastest(&self) -> Option<f64> {
        average(self.g.systems.iter().filter_map(|&s| {
            // The best mean of each (representation, algorithm) over the system's experiments.
            let combo = |fuzzy: bool, a: Algorithm| {
                self.g
                    .heatmaps
                    .iter()
                    .enumerate()
                    .filter(|(_, h)| h.system == s && h.fuzzy == fuzzy && h.algorithm == a)
                    .filter_map(|(k, _)| self.best_mean(k))
                    .min_by(f64::total_cmp)
            };
            let fl = combo(true, Algorithm::QLambda)?;
            let others = [
                combo(false, Algorithm::Q0)?,
                combo(false, Algorithm::QLambda)?,
                combo(true, Algorithm::Q0)?,
            ];
            let other = others.into_iter().min_by(f64::total_cmp)?;
            (fl > 0.0 && other > 0.0).then(|| (other / fl).ln())
        }))
    }

    /// The mean over (system, algorithm) of ρ(state count, ln(crisp ÷ fuzzy)) over paired cells.
    fn fuzzy_benefit(&self) -> Option<f64> {
        average(self.g.repr_pairs.iter().filter_map(|pairs| {
            let (x, y): (Vec<f64>, Vec<f64>) = pairs
                .iter()
                .filter_map(|&(c, f, states)| {
                    let (a, b) = (self.mean(c)?, self.mean(f)?);
                    (a > 0.0 && b > 0.0).then(|| (states, (a / b).ln()))
                })
                .unzip();
            spearman(&x, &y)
        }))
    }

    /// The algorithms' gap ([`Resample::gap`]) in Mountain Car less that in the other systems.
    fn narrowed(&self) -> Option<f64> {
        let mc = |want: bool| {
            average(
                self.g
                    .experiments
                    .iter()
                    .filter(|&&e| self.system_of(e).is_some_and(|s| (s.0 == SystemKind::MountainCar) == want))
                    .filter_map(|&e| self.gap(e)),
            )
        };
        Some(mc(true)? - mc(false)?)
    }

    /// The mean over fuzzy experiments of ln(states of Q(λ)'s best cell ÷ Q(0)'s).
    fn richer(&self) -> Option<f64> {
        average(self.g.experiments.iter().filter(|&&e| self.system_of(e).is_some_and(|s| s.1)).filter_map(
            |&e| {
                let a = self.cells[self.best[self.find(e, Algorithm::Q0)?]?].states();
                let b = self.cells[self.best[self.find(e, Algorithm::QLambda)?]?].states();
                Some((b / a).ln())
            },
        ))
    }
}

/// The mean of `v` (`None` when empty).
fn average(v: impl IntoIterator<Item = f64>) -> Option<f64> {
    let (mut s, mut n) = (0.0, 0usize);
    for x in v {
        s += x;
        n += 1;
    }
    (n > 0).then(|| s / n as f64)
}

/// Fraction of the trials of `idx` that reached the goal.
fn success_rate(idx: &[usize], view: &[View]) -> Option<f64> {
    let (ok, n) = idx.iter().fold((0, 0), |(ok, n), &i| (ok + view[i].successes, n + view[i].n));
    (n > 0).then(|| ok as f64 / n as f64)
}
