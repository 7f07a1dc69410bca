//! The numbers of a program pipeline's report (`qsweep_pipeline::program`): per experiment and
//! cell, every scalar metric's n, mean, sample std and seeded 95 % bootstrap interval of the mean
//! over the trials that succeeded (a bool counts as 0 or 1, so its mean is the share of `true`),
//! every list metric's curve (median and interquartile range over seeds at each index), and the
//! best cell by the declared objective. Pure functions of the plan and the rows: the same rows give
//! the same numbers, whatever order the cache served them in.

use qsweep_pipeline::analysis::{quantile_sorted, Summary};
use qsweep_pipeline::cache::Key;
use qsweep_pipeline::program::model::{
    Goal, MetricType, MetricValue, ParamValue, ProgramExperiment, ProgramPlan, ProgramRow, ProgramTrial,
};
use qsweep_pipeline::program::race::{best_by_goal, RaceStanding};
use std::collections::HashMap;

/// A list metric's curve over seeds: at each index, the median and the interquartile range of the
/// values of the trials whose list reaches that index, and how many do.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Curve {
    /// Per index: (median, 25th percentile, 75th percentile, trials reaching it).
    pub points: Vec<(f64, f64, f64, usize)>,
}

/// One cell of an experiment.
#[derive(Debug, Clone, PartialEq)]
pub struct CellStats {
    /// Every param's value, in the plan's param order.
    pub params: Vec<ParamValue>,
    /// The values of the experiment's axes.
    pub coords: Vec<ParamValue>,
    /// Planned trials (one per seed).
    pub planned: usize,
    /// Of those, with a row in the cache.
    pub present: usize,
    /// Of those, failed.
    pub failed: usize,
    /// Per scalar metric ([`ProgramStats::scalars`] order), its summary over the succeeded trials.
    pub scalars: Vec<Summary>,
    /// Per list metric ([`ProgramStats::lists`] order), its curve.
    pub curves: Vec<Curve>,
    /// In a raced experiment, whether the cell is still a contender (`None`: not raced).
    pub contender: Option<bool>,
    /// Its trials on the fresh seeds, when it is its experiment's best and they are planned.
    pub fresh: Option<FreshStats>,
}

/// A best cell measured again on the fresh seeds (`fresh:`): never part of its own numbers.
#[derive(Debug, Clone, PartialEq)]
pub struct FreshStats {
    /// Fresh trials planned (one per fresh seed).
    pub planned: usize,
    /// Of those, with a row in the cache.
    pub present: usize,
    /// Of those, failed.
    pub failed: usize,
    /// Per scalar metric, its summary over the fresh trials that succeeded.
    pub scalars: Vec<Summary>,
}

/// One experiment (of one variant) with its cells' numbers.
#[derive(Debug, Clone, PartialEq)]
pub struct ExperimentStats {
    /// The variant (`None`: the pipeline as written).
    pub variant: Option<String>,
    /// Its id.
    pub id: String,
    /// Its title.
    pub title: Option<String>,
    /// Its axes.
    pub axes: Vec<String>,
    /// Its cells, in the plan's order.
    pub cells: Vec<CellStats>,
    /// The index of the best cell by the objective among the contenders (`None` without an
    /// objective or values).
    pub best: Option<usize>,
    /// How its race stands (`None`: not raced).
    pub race: Option<RaceStanding>,
    /// Its fresh seeds (`fresh:`; 0: none declared).
    pub fresh_seeds: usize,
}

/// Every number of a program pipeline's report.
#[derive(Debug, Clone, PartialEq)]
pub struct ProgramStats {
    /// The scalar metrics (int, float, bool), in declared order, with their types.
    pub scalars: Vec<(String, MetricType)>,
    /// The list metrics, in declared order.
    pub lists: Vec<String>,
    /// The objective's index among [`Self::scalars`] and its goal, when declared.
    pub objective: Option<(usize, Goal)>,
    /// The experiments, in the plan's order.
    pub experiments: Vec<ExperimentStats>,
}

impl ProgramStats {
    /// The scalar metric a figure shows: the objective, else the first scalar metric.
    pub fn shown(&self) -> Option<usize> {
        self.objective.map(|o| o.0).or((!self.scalars.is_empty()).then_some(0))
    }
}

/// Whether a metric of type `t` is summarised as a scalar (its mean, std and interval).
pub fn is_scalar(t: MetricType) -> bool {
    matches!(t, MetricType::Int | MetricType::Float | MetricType::Bool)
}

/// Whether a metric of type `t` is drawn as a curve.
pub fn is_list(t: MetricType) -> bool {
    matches!(t, MetricType::ListFloat | MetricType::ListU32)
}

/// The numbers of `plan`'s report (replayed: its races' rounds and fresh trials planned, with
/// `races` how each race stands) from `rows` (the cache's row of each key present).
pub fn derive(plan: &ProgramPlan, rows: &HashMap<Key, ProgramRow>, races: &[RaceStanding]) -> ProgramStats {
    let metrics = &plan.program.metrics;
    let scalar_at: Vec<usize> = (0..metrics.len()).filter(|&j| is_scalar(metrics[j].1)).collect();
    let list_at: Vec<usize> = (0..metrics.len()).filter(|&j| is_list(metrics[j].1)).collect();
    let objective = plan
        .program
        .objective
        .as_ref()
        .and_then(|o| scalar_at.iter().position(|&j| metrics[j].0 == o.metric).map(|i| (i, o.goal)));
    let experiments = plan
        .experiments
        .iter()
        .enumerate()
        .map(|(i, e)| {
            let mut x = experiment(e, rows, &scalar_at, &list_at, objective);
            x.race = races.iter().find(|r| r.experiment == i).cloned();
            x
        })
        .collect();
    ProgramStats {
        scalars: scalar_at.iter().map(|&j| metrics[j].clone()).collect(),
        lists: list_at.iter().map(|&j| metrics[j].0.clone()).collect(),
        objective,
        experiments,
    }
}

fn experiment(
    e: &ProgramExperiment,
    rows: &HashMap<Key, ProgramRow>,
    scalar_at: &[usize],
    list_at: &[usize],
    objective: Option<(usize, Goal)>,
) -> ExperimentStats {
    let cells: Vec<CellStats> = e
        .cells
        .iter()
        .map(|c| {
            let (planned, present, failed, ok) = trials_of(&c.trials, rows);
            let keys: Vec<Key> = c.trials.iter().map(|t| t.key).collect();
            let fresh = (!c.fresh.is_empty()).then(|| {
                let (planned, present, failed, ok) = trials_of(&c.fresh, rows);
                let keys: Vec<Key> = c.fresh.iter().map(|t| t.key).collect();
                FreshStats { planned, present, failed, scalars: summaries(&ok, scalar_at, &keys) }
            });
            CellStats {
                params: c.params.clone(),
                coords: c.coords.clone(),
                planned,
                present,
                failed,
                scalars: summaries(&ok, scalar_at, &keys),
                curves: list_at.iter().map(|&j| curve(ok.iter().filter_map(|m| list(m.get(j)?)))).collect(),
                contender: c.contender,
                fresh,
            }
        })
        .collect();
    let best = objective.and_then(|(i, goal)| best_cell(&cells, i, goal));
    ExperimentStats {
        variant: e.variant.clone(),
        id: e.id.clone(),
        title: e.title.clone(),
        axes: e.axes.clone(),
        cells,
        best,
        race: None,
        fresh_seeds: e.fresh.len(),
    }
}

/// Of `trials`: planned, with a row, failed, and the metrics of those that succeeded.
fn trials_of<'r>(
    trials: &[ProgramTrial],
    rows: &'r HashMap<Key, ProgramRow>,
) -> (usize, usize, usize, Vec<&'r Vec<MetricValue>>) {
    let got: Vec<&ProgramRow> = trials.iter().filter_map(|t| rows.get(&t.key)).collect();
    let ok: Vec<&Vec<MetricValue>> = got.iter().filter_map(|r| r.result.as_ref().ok()).collect();
    (trials.len(), got.len(), got.len() - ok.len(), ok)
}

/// Each scalar metric's summary over `ok`, its interval seeded by the trials' `keys`.
fn summaries(ok: &[&Vec<MetricValue>], scalar_at: &[usize], keys: &[Key]) -> Vec<Summary> {
    scalar_at
        .iter()
        .map(|&j| {
            let values: Vec<f64> = ok.iter().filter_map(|m| scalar(m.get(j)?)).collect();
            Summary::of(&values, interval_seed(keys, j))
        })
        .collect()
}

/// The cell with the best mean of scalar `i` under `goal` among the contenders (every cell
/// without a race); the first of equals (plan order). The race's rule
/// ([`qsweep_pipeline::program::race::best_by_goal`]), so the report names the cell the race and
/// the fresh seeds chose.
pub fn best_cell(cells: &[CellStats], i: usize, goal: Goal) -> Option<usize> {
    let means = cells
        .iter()
        .enumerate()
        .filter(|(_, c)| c.contender != Some(false))
        .map(|(c, cell)| (c, cell.scalars[i].mean));
    best_by_goal(means, goal)
}

/// A scalar metric's value as a number (a bool as 0 or 1).
pub fn scalar(v: &MetricValue) -> Option<f64> {
    match v {
        MetricValue::Int(i) => Some(*i as f64),
        MetricValue::Float(x) => Some(*x),
        MetricValue::Bool(b) => Some(f64::from(u8::from(*b))),
        _ => None,
    }
}

fn list(v: &MetricValue) -> Option<Vec<f64>> {
    match v {
        MetricValue::ListFloat(x) => Some(x.clone()),
        MetricValue::ListU32(x) => Some(x.iter().map(|&u| f64::from(u)).collect()),
        _ => None,
    }
}

/// The bootstrap's seed of one cell's metric: from the cell's planned keys (its params, seeds and
/// program) and the metric's position, so it does not depend on which rows are present.
fn interval_seed(keys: &[Key], metric: usize) -> u64 {
    let mut h = blake3::Hasher::new();
    for k in keys {
        h.update(&k.0);
    }
    h.update(&(metric as u64).to_le_bytes());
    u64::from_le_bytes(h.finalize().as_bytes()[..8].try_into().expect("8 bytes"))
}

/// The median and interquartile range at each index over `lists`.
pub fn curve(lists: impl Iterator<Item = Vec<f64>>) -> Curve {
    let lists: Vec<Vec<f64>> = lists.collect();
    let len = lists.iter().map(Vec::len).max().unwrap_or(0);
    let points = (0..len)
        .map(|i| {
            let mut at: Vec<f64> = lists.iter().filter_map(|l| l.get(i).copied()).collect();
            at.sort_by(f64::total_cmp);
            (quantile_sorted(&at, 0.5), quantile_sorted(&at, 0.25), quantile_sorted(&at, 0.75), at.len())
        })
        .collect();
    Curve { points }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cell(means: &[Option<f64>]) -> CellStats {
        CellStats {
            params: vec![],
            coords: vec![],
            planned: 1,
            present: 1,
            failed: 0,
            scalars: means.iter().map(|m| Summary { n: 1, mean: *m, ..Summary::default() }).collect(),
            curves: vec![],
            contender: None,
            fresh: None,
        }
    }

    #[test]
    fn the_best_cell_follows_the_goal_and_the_first_of_equals_wins() {
        let cells =
            [cell(&[Some(3.0)]), cell(&[None]), cell(&[Some(1.0)]), cell(&[Some(1.0)]), cell(&[Some(5.0)])];
        assert_eq!(best_cell(&cells, 0, Goal::Minimize), Some(2));
        assert_eq!(best_cell(&cells, 0, Goal::Maximize), Some(4));
        assert_eq!(best_cell(&[cell(&[None])], 0, Goal::Minimize), None);
        // In a race, only the contenders can be best.
        let mut raced = cells.clone();
        raced[2].contender = Some(false);
        raced[3].contender = Some(true);
        assert_eq!(best_cell(&raced, 0, Goal::Minimize), Some(3));
    }

    #[test]
    fn a_curve_is_the_median_and_quartiles_of_the_lists_reaching_each_index() {
        let c = curve([vec![1.0, 10.0], vec![2.0], vec![3.0, 30.0, 7.0]].into_iter());
        assert_eq!(c.points.len(), 3);
        assert_eq!(c.points[0], (2.0, 1.5, 2.5, 3));
        assert_eq!(c.points[1], (20.0, 15.0, 25.0, 2));
        assert_eq!(c.points[2], (7.0, 7.0, 7.0, 1));
    }

    #[test]
    fn a_bool_counts_as_one_or_zero_and_a_list_is_no_scalar() {
        assert_eq!(scalar(&MetricValue::Bool(true)), Some(1.0));
        assert_eq!(scalar(&MetricValue::Int(-3)), Some(-3.0));
        assert_eq!(scalar(&MetricValue::ListFloat(vec![1.0])), None);
    }
}
