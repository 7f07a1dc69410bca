//! The report's view of a plan and its trial records: per experiment, per cell, the trials that
//! are present, the episode count each contributes, the cell's statistics, and the best cell per
//! algorithm (the paper's red rectangle and Table III row).
//!
//! The rules it applies (episodes counted, the best cell) and the statistics are
//! [`qsweep_pipeline::analysis`]'s, shared with the race.

use crate::memo::stats::StatsMemo;
use qsweep_engine::env::SystemKind;
use qsweep_engine::repr::ReprKind;
use qsweep_engine::{Algorithm, Outcome};
use qsweep_pipeline::analysis::claims::ClaimCell;
use qsweep_pipeline::analysis::consistency::Published;
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

/// State-variable columns of the report, in Table III order.
pub const VAR_COLUMNS: [&str; 4] = ["x", "x_dot", "theta", "theta_dot"];

/// Bins or fuzzy sets per report column ([`VAR_COLUMNS`]); `None` where the system lacks the
/// variable.
pub fn resolution_columns(system: SystemKind, resolution: &[u32]) -> [Option<u32>; 4] {
    let vars = system.variables();
    VAR_COLUMNS.map(|name| vars.iter().position(|v| *v == name).and_then(|j| resolution.get(j).copied()))
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

    /// Kaplan–Meier median of the sample's counted episodes, trials that never reached the goal
    /// censored at the cap ([`qsweep_pipeline::analysis::survival::km_median`]).
    pub fn km_median(&self) -> Option<f64> {
        let times: Vec<(f64, bool)> =
            self.trials.iter().map(|t| (f64::from(t.counted), t.outcome.converged)).collect();
        qsweep_pipeline::analysis::survival::km_median(&times)
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

    /// The cell of `algorithm` with the reference's configuration (bins or sets per variable and
    /// action count), when the experiment has a reference that gives one and runs it.
    pub fn reference_cell(&self, algorithm: Algorithm) -> Option<usize> {
        let r = self.exp.reference.get(&algorithm)?;
        let (res, actions) = (r.resolution.as_ref()?, r.actions?);
        self.cells.iter().position(|c| {
            c.cell.algorithm == algorithm
                && &c.cell.config.repr.resolution == res
                && c.cell.config.actions == actions
        })
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
    /// Mann–Whitney U test ([`qsweep_pipeline::analysis::rank::mann_whitney_p_greater`]), Holm-corrected
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
            let p: Vec<f64> = others
                .iter()
                .map(|&i| qsweep_pipeline::analysis::rank::mann_whitney_p_greater(&values(i), &b))
                .collect();
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
        Self { plan, experiments, trials_planned: planned, trials_cached: present }
    }

    /// Systems present in the plan, in report order.
    pub fn systems(&self) -> Vec<SystemKind> {
        SystemKind::ALL.into_iter().filter(|s| self.experiments.iter().any(|e| e.exp.system == *s)).collect()
    }

    /// Every cell as the claims read it (cells without trials included, with none).
    pub fn claim_cells(&self) -> Vec<ClaimCell> {
        let mut out = Vec::new();
        for (k, e) in self.experiments.iter().enumerate() {
            for c in &e.cells {
                let cfg = &c.cell.config;
                out.push(ClaimCell {
                    system: e.exp.system,
                    experiment: k,
                    experiment_id: e.exp.id.clone(),
                    fuzzy: e.exp.repr == ReprKind::Fuzzy,
                    algorithm: c.cell.algorithm,
                    resolution: cfg.repr.resolution.clone(),
                    actions: cfg.actions,
                    counted: c.trials.iter().map(|t| f64::from(t.counted)).collect(),
                    converged: c.trials.iter().map(|t| t.outcome.converged).collect(),
                    seed: seed_of(b"qsweep-claims\0", c.trials.iter().map(|t| &t.planned.key)),
                });
            }
        }
        out
    }

    /// Table III's rows that belong to a pair the paper's own numbers contradict, and the rows
    /// those pairs designate ([`qsweep_pipeline::analysis::consistency`]), each published mean taken over
    /// `paper_n` runs.
    pub fn contradictions(&self, paper_n: usize) -> Contradictions {
        use qsweep_pipeline::analysis::consistency::{designated, in_contradiction, pairs};
        let mut out = Contradictions::default();
        for rows in published_rows(self.plan) {
            let published: Vec<Published> = rows.iter().map(|r| r.2.clone()).collect();
            let pairs = pairs(&published, paper_n);
            for (i, r) in rows.iter().enumerate() {
                if in_contradiction(&pairs, i) {
                    out.in_pair.push((r.0, r.1));
                }
                if designated(&pairs, i) {
                    out.designated.push((r.0, r.1));
                }
            }
        }
        out
    }

    /// Whether any experiment carries published reference values.
    pub fn has_reference(&self) -> bool {
        self.experiments.iter().any(|e| !e.exp.reference.is_empty())
    }
}

/// Table III rows (experiment index, algorithm) in contradictory pairs, and those the pairs
/// designate ([`ReportData::contradictions`]).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Contradictions {
    /// Rows that belong to a contradictory pair.
    pub in_pair: Vec<(usize, Algorithm)>,
    /// Rows a contradictory pair designates (one per pair).
    pub designated: Vec<(usize, Algorithm)>,
}

/// A published Table III row with its experiment's index and its algorithm.
pub type PublishedRow = (usize, Algorithm, Published);

/// The plan's Table III rows that have a published value, as the consistency check reads them
/// ([`qsweep_pipeline::analysis::consistency`]): each with its experiment's index and its grid (the
/// experiment's cells of the algorithm), in plan order, one group per variant (a plan of several
/// variants holds each variant's copy of the paper's values; pairs are sought within one).
pub fn published_rows(plan: &Plan) -> Vec<Vec<PublishedRow>> {
    let mut groups: Vec<(Option<&str>, Vec<PublishedRow>)> = Vec::new();
    for (ei, e) in plan.experiments.iter().enumerate() {
        let variant = e.variant.as_deref();
        if !groups.iter().any(|g| g.0 == variant) {
            groups.push((variant, Vec::new()));
        }
        let group = &mut groups.iter_mut().find(|g| g.0 == variant).expect("just added").1;
        for &alg in &e.algorithms {
            let Some(r) = e.reference.get(&alg) else { continue };
            let grid = e
                .cells
                .iter()
                .filter(|c| c.algorithm == alg)
                .map(|c| (c.config.repr.resolution.clone(), c.config.actions))
                .collect();
            let row = Published {
                system: e.system,
                repr: e.repr,
                experiment: e.id.clone(),
                algorithm: alg,
                mean: r.mean,
                std: r.std,
                config: r.resolution.clone().zip(r.actions),
                grid,
            };
            group.push((ei, alg, row));
        }
    }
    groups.into_iter().map(|g| g.1).filter(|g| !g.is_empty()).collect()
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
        assert_eq!(resolution_columns(SystemKind::BallBeam, &[5, 3]), [Some(5), Some(3), None, None]);
        assert_eq!(
            resolution_columns(SystemKind::CartPole, &[1, 2, 3, 4]),
            [Some(1), Some(2), Some(3), Some(4)]
        );
    }
}
