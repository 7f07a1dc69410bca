//! The report's view of a plan and its trial records: per experiment, per cell, the trials that
//! are present, the episode count each contributes, the cell's statistics, and the best cell per
//! algorithm (the paper's red rectangle and Table III row).
//!
//! The rules it applies (episodes counted, the best cell) and the statistics are
//! [`qsweep_pipeline::analysis`]'s, shared with the race.

use crate::memo::stats::StatsMemo;
use qsweep_engine::env::SystemKind;
use qsweep_engine::{Algorithm, Outcome};
use qsweep_pipeline::analysis::{best_cell, episodes_counted, Best, Candidate, Summary};
use qsweep_pipeline::cache::rows::StoredTrial;
use qsweep_pipeline::cache::{Key, TrialRecord};
use qsweep_pipeline::plan::{Cell, Experiment, Plan, PlannedTrial};
use rayon::prelude::*;
use std::collections::HashMap;

/// Where a report finds a trial's outcome by key: the cache's outcome columns
/// ([`StoredTrial`]), or whole records (in tests and tools that ran the trials themselves).
pub trait Outcomes: Sync {
    /// The outcome of `key`, its wall-clock and its CPU seconds, if present.
    fn outcome(&self, key: &Key) -> Option<(&Outcome, f64, Option<f64>)>;
}

impl Outcomes for HashMap<Key, StoredTrial> {
    fn outcome(&self, key: &Key) -> Option<(&Outcome, f64, Option<f64>)> {
        self.get(key).map(|s| (&s.outcome, s.seconds, s.cpu_seconds))
    }
}

impl Outcomes for HashMap<Key, TrialRecord> {
    fn outcome(&self, key: &Key) -> Option<(&Outcome, f64, Option<f64>)> {
        self.get(key).map(|r| (&r.outcome, r.seconds, r.cpu_seconds))
    }
}

/// The state variables a report writes a column for, and where each system's come from: every
/// variable of the engine's systems ([`SystemKind::variables`], the one list), in the order they
/// first appear over [`SystemKind::ALL`], so every report has the same columns whatever systems
/// its pipeline runs ("—" where a system lacks the variable).
#[derive(Debug, Clone)]
pub struct Variables {
    /// Each system's state variables, in state-vector order ([`SystemKind::variables`]).
    pub of: fn(SystemKind) -> &'static [&'static str],
    /// The columns: every system's variables, each once, in first-seen order.
    pub columns: Vec<&'static str>,
}

impl Variables {
    /// The columns of the systems' variables as `of` gives them.
    pub fn from(of: fn(SystemKind) -> &'static [&'static str]) -> Self {
        let mut columns: Vec<&'static str> = Vec::new();
        for s in SystemKind::ALL {
            for v in of(s) {
                if !columns.contains(v) {
                    columns.push(v);
                }
            }
        }
        Self { of, columns }
    }

    /// The engine's: [`SystemKind::variables`].
    pub fn engine() -> Self {
        Self::from(SystemKind::variables)
    }

    /// Bins or fuzzy sets per column of a cell of `system` with `resolution` (in the system's
    /// state order); `None` where the system lacks the variable.
    pub fn resolution(&self, system: SystemKind, resolution: &[u32]) -> Vec<Option<u32>> {
        let vars = (self.of)(system);
        self.columns
            .iter()
            .map(|name| vars.iter().position(|v| v == name).and_then(|j| resolution.get(j).copied()))
            .collect()
    }

    /// Each column's Unicode symbol and LaTeX (math mode), as [`SystemKind::variable_symbol`]
    /// writes them.
    pub fn symbols(&self) -> Vec<(String, String)> {
        self.columns.iter().map(|v| SystemKind::variable_symbol(v)).collect()
    }
}

/// A present trial of a cell.
#[derive(Debug, Clone, Copy)]
pub struct TrialData<'a> {
    /// The planned trial (seed, key).
    pub planned: &'a PlannedTrial,
    /// Its outcome.
    pub outcome: &'a Outcome,
    /// Wall-clock seconds it took when computed (informational).
    pub seconds: f64,
    /// CPU seconds of its thread, when recorded.
    pub cpu_seconds: Option<f64>,
    /// Episodes it contributes ([`episodes_counted`]).
    pub counted: u32,
}

/// A cell with its present trials and statistics.
#[derive(Debug, Clone)]
pub struct CellData<'a> {
    /// The planned cell.
    pub cell: &'a Cell,
    /// Present trials, in seed order.
    pub trials: Vec<TrialData<'a>>,
    /// Present trials that reached the goal.
    pub successes: usize,
    /// Statistics of the counted episodes.
    pub summary: Summary,
    /// Its present trials on the fresh seeds (only a best cell of a pipeline with `fresh:` has
    /// any: [`qsweep_pipeline::fresh`]); never part of [`CellData::summary`].
    pub fresh: Vec<TrialData<'a>>,
    /// Statistics of those, with their bootstrap interval; `None` without fresh trials present.
    pub fresh_summary: Option<Summary>,
}

/// The sample a Table III row is judged on: the fresh-seed trials of its best cell where it has
/// them, else the cell's own (the selection estimate).
#[derive(Debug, Clone, Copy)]
pub struct Estimate<'c, 'a> {
    /// Its statistics.
    pub summary: &'c Summary,
    /// Its trials.
    pub trials: &'c [TrialData<'a>],
    /// Whether it is the fresh-seed estimate.
    pub fresh: bool,
}

impl Estimate<'_, '_> {
    /// Trials in the sample.
    pub fn n(&self) -> usize {
        self.trials.len()
    }

    /// Fraction of the sample's trials that hit the episode cap without reaching the goal.
    pub fn censored_fraction(&self) -> Option<f64> {
        let n = self.trials.len();
        (n > 0).then(|| self.trials.iter().filter(|t| !t.outcome.converged).count() as f64 / n as f64)
    }
}

impl<'a> CellData<'a> {
    /// The sample a Table III row of this cell is judged on ([`Estimate`]).
    pub fn estimate(&self) -> Estimate<'_, 'a> {
        match &self.fresh_summary {
            Some(summary) => Estimate { summary, trials: &self.fresh, fresh: true },
            None => Estimate { summary: &self.summary, trials: &self.trials, fresh: false },
        }
    }

    /// Whether some present trial did not reach the goal.
    pub fn any_failed(&self) -> bool {
        self.successes < self.trials.len()
    }

    /// Planned trials of the cell.
    pub fn planned(&self) -> usize {
        self.cell.trials.len()
    }
}

/// An experiment with its cells and best cells.
#[derive(Debug, Clone)]
pub struct ExpData<'a> {
    /// The planned experiment.
    pub exp: &'a Experiment,
    /// Cells in plan order (algorithm-major).
    pub cells: Vec<CellData<'a>>,
    /// Per algorithm of the experiment, in its order: the best cell, if any cell has trials.
    pub best: Vec<(Algorithm, Option<Best>)>,
}

impl AsRef<Experiment> for ExpData<'_> {
    fn as_ref(&self) -> &Experiment {
        self.exp
    }
}

impl ExpData<'_> {
    /// The best cell of `algorithm`, if any.
    pub fn best_of(&self, algorithm: Algorithm) -> Option<Best> {
        self.best.iter().find(|(a, _)| *a == algorithm).and_then(|(_, b)| *b)
    }

    /// Whether cell `i` is the best of its algorithm.
    pub fn is_best(&self, i: usize) -> bool {
        self.best_of(self.cells[i].cell.algorithm).is_some_and(|b| b.cell == i)
    }

    /// How many cells of `algorithm` are still in its race (`None` without a race).
    pub fn contenders(&self, algorithm: Algorithm) -> Option<usize> {
        self.exp.race?;
        Some(
            self.cells
                .iter()
                .filter(|c| c.cell.algorithm == algorithm && c.cell.contender == Some(true))
                .count(),
        )
    }

    /// A raced experiment's cells tested against their algorithm's best cell by the one-sided
    /// Mann–Whitney U test ([`crate::derive::rank::mann_whitney_p_greater`]), Holm-corrected
    /// over the other cells of the heatmap at the race's level: per cell, its p and whether it is
    /// significantly worse (`None`: no race, the best cell itself, or no trials). A label beside
    /// the race, not its rule: the race decides by Welch's t.
    pub fn rank_tests(&self) -> Vec<Option<(f64, bool)>> {
        let mut out = vec![None; self.cells.len()];
        let Some(race) = self.exp.race else { return out };
        let values =
            |i: usize| -> Vec<f64> { self.cells[i].trials.iter().map(|t| f64::from(t.counted)).collect() };
        for &(alg, best) in &self.best {
            let Some(best) = best else { continue };
            let b = values(best.cell);
            let others: Vec<usize> = (0..self.cells.len())
                .filter(|&i| {
                    i != best.cell && self.cells[i].cell.algorithm == alg && !self.cells[i].trials.is_empty()
                })
                .collect();
            let p: Vec<f64> =
                others.iter().map(|&i| crate::derive::rank::mann_whitney_p_greater(&values(i), &b)).collect();
            let worse = qsweep_pipeline::analysis::welch::holm_reject(&p, 1.0 - race.confidence.0);
            for (k, &i) in others.iter().enumerate() {
                out[i] = Some((p[k], worse[k]));
            }
        }
        out
    }

    /// The index of the cell with this algorithm and coordinates.
    pub fn find(&self, algorithm: Algorithm, coords: &[f64]) -> Option<usize> {
        self.cells.iter().position(|c| c.cell.algorithm == algorithm && c.cell.coords == coords)
    }
}

/// The whole report's data.
#[derive(Debug, Clone)]
pub struct ReportData<'a> {
    /// The plan.
    pub plan: &'a Plan,
    /// Experiments in plan order.
    pub experiments: Vec<ExpData<'a>>,
    /// Planned (cell, seed) trials, counting a trial shared by two cells twice.
    pub trials_planned: usize,
    /// Of those, present in the records.
    pub trials_cached: usize,
    /// The state variables the report writes a column for ([`Variables::engine`]).
    pub variables: Variables,
}

impl<'a> ReportData<'a> {
    /// Gather the present trials of every cell and compute statistics and best cells.
    /// Each cell's statistics are computed here, once (in parallel; each cell's bootstrap is
    /// seeded by its own trials, so the result does not depend on the threads).
    pub fn build(plan: &'a Plan, records: &'a dyn Outcomes) -> Self {
        // A memo kept by nobody: every interval computed (its version names no file).
        Self::build_as(plan, records, Some(&StatsMemo::fresh(0)))
    }

    /// [`ReportData::build`], with the cells' bootstrap intervals only when `intervals` gives the
    /// statistics' memo they are taken from or recorded in: a variant that writes no folder (an
    /// exploratory or not-chosen one) only needs its means for the comparison.
    pub fn build_as(plan: &'a Plan, records: &'a dyn Outcomes, intervals: Option<&StatsMemo>) -> Self {
        let planned = plan.trial_count();
        let mut present = 0;
        let experiments = plan
            .experiments
            .iter()
            .map(|exp| {
                let cells: Vec<CellData> = exp
                    .cells
                    .par_iter()
                    .map(|cell| {
                        let limits = &cell.config.limits;
                        let present = |planned: &'a [PlannedTrial]| -> Vec<TrialData<'a>> {
                            planned
                                .iter()
                                .filter_map(|t| {
                                    records.outcome(&t.key).map(|(o, seconds, cpu_seconds)| TrialData {
                                        planned: t,
                                        outcome: o,
                                        seconds,
                                        cpu_seconds,
                                        counted: episodes_counted(o, limits, exp.counting),
                                    })
                                })
                                .collect()
                        };
                        cell_data(cell, present(&cell.trials), present(&cell.fresh), intervals)
                    })
                    .collect();
                present += cells.iter().map(|c| c.trials.len() + c.fresh.len()).sum::<usize>();
                let best = exp
                    .algorithms
                    .iter()
                    .map(|&a| {
                        // In a race only contenders can be the best: a cell that left it was
                        // significantly worse than a contender, on fewer seeds.
                        let candidates = cells
                            .iter()
                            .enumerate()
                            .filter(|(_, c)| c.cell.algorithm == a && c.cell.contender != Some(false))
                            .map(|(i, c)| Candidate {
                                index: i,
                                n: c.trials.len(),
                                successes: c.successes,
                                mean: c.summary.mean,
                            });
                        (a, best_cell(candidates))
                    })
                    .collect();
                ExpData { exp, cells, best }
            })
            .collect();
        Self {
            plan,
            experiments,
            trials_planned: planned,
            trials_cached: present,
            variables: Variables::engine(),
        }
    }

    /// Systems present in the plan, in report order.
    pub fn systems(&self) -> Vec<SystemKind> {
        SystemKind::ALL.into_iter().filter(|s| self.experiments.iter().any(|e| e.exp.system == *s)).collect()
    }
}

fn cell_data<'a>(
    cell: &'a Cell,
    trials: Vec<TrialData<'a>>,
    fresh: Vec<TrialData<'a>>,
    intervals: Option<&StatsMemo>,
) -> CellData<'a> {
    let summarize = |trials: &[TrialData]| {
        let (values, seed) = interval_inputs(trials);
        Summary::with_interval_by(&values, intervals.and(Some(seed)), |v, r, s| {
            intervals.expect("a seed only with a memo").bootstrap_ci(v, r, s)
        })
    };
    let successes = trials.iter().filter(|t| t.outcome.converged).count();
    let summary = summarize(&trials);
    let fresh_summary = (!fresh.is_empty()).then(|| summarize(&fresh));
    CellData { cell, trials, successes, summary, fresh, fresh_summary }
}

/// What a sample's bootstrap interval is computed from: its counted episodes and its seed (from
/// its trials' keys).
pub fn interval_inputs(trials: &[TrialData]) -> (Vec<f64>, u64) {
    let values = trials.iter().map(|t| f64::from(t.counted)).collect();
    (values, seed_of(b"qsweep-bootstrap\0", trials.iter().map(|t| &t.planned.key)))
}

/// A seed for a cell's resamples: derived from the keys of its present trials (after a `domain`
/// that keeps two uses' streams apart), so it changes exactly when the sample does.
pub fn seed_of<'k>(domain: &[u8], keys: impl Iterator<Item = &'k Key>) -> u64 {
    let mut h = blake3::Hasher::new();
    h.update(domain);
    for k in keys {
        h.update(&k.0);
    }
    let b = h.finalize();
    u64::from_le_bytes(b.as_bytes()[..8].try_into().expect("8 bytes"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn resolution_columns_follow_variable_names() {
        let v = Variables::engine();
        assert_eq!(v.columns, ["x", "x_dot", "theta", "theta_dot"], "today's systems' variables, in order");
        assert_eq!(v.resolution(SystemKind::BallBeam, &[5, 3]), [Some(5), Some(3), None, None]);
        assert_eq!(v.resolution(SystemKind::CartPole, &[1, 2, 3, 4]), [Some(1), Some(2), Some(3), Some(4)]);
        // A system with a variable of its own gets a column of its own, after those seen before.
        let other =
            Variables::from(|s| if s == SystemKind::MountainCar { &["x", "phi"] } else { s.variables() });
        assert_eq!(other.columns, ["x", "x_dot", "theta", "theta_dot", "phi"]);
        assert_eq!(other.resolution(SystemKind::MountainCar, &[4, 7]), [Some(4), None, None, None, Some(7)]);
        assert_eq!(other.symbols()[1].0, "ẋ");
        assert_eq!(other.symbols()[4], ("phi".to_string(), "\\mathrm{phi}".to_string()));
    }
}
