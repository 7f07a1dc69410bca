//! A program pipeline's stages, replayed from its stored rows: races (`race:`) and fresh seeds
//! (`fresh:`), the engine's two blocks (`crate::race`, `crate::fresh`) for any program, ranked by
//! the declared `objective`.
//!
//! **A race.** Within each experiment (of each variant) every cell starts as a contender. After
//! each round the best contender is the one with the lowest (`goal: minimize`) or highest
//! (`maximize`) mean of the objective, the first in plan order among equals
//! ([`best_by_goal`], the report's rule too); every other contender is tested against it with the
//! engine's round ([`crate::race::eliminate`]: a one-sided Welch test, Holm's procedure over the
//! round at α = 1 − `confidence`), on the objective's values (negated under `maximize`, so a higher
//! value is always the worse one), and the rejected cells leave. The race is over when one
//! contender is left or every contender has `max_seeds` seeds; otherwise each contender gets
//! `batch` more seeds, numbered on from the largest first-round seed
//! ([`crate::race::round_seeds`]).
//!
//! **Failed trials.** A round is decided once every contender's trials are stored, succeeded or
//! failed (a trial that did not finish stores nothing, so the round waits for it). A cell's sample
//! is the objective over its trials that succeeded: its failed trials are left out, as in its
//! report numbers. A contender with fewer than two values (or a best with fewer than two) is not
//! tested and stays; a cell with no value cannot be the best.
//!
//! **Fresh seeds.** Once an experiment's cells are all stored (and its race, if any, is over), its
//! best cell by the same rule among its contenders gets a trial on every fresh seed: they take no
//! part in choosing it, so their mean measures it without the winner's curse.
//!
//! Like the engine's, the replay is a pure function of the plan and the stored rows: rerunning a
//! finished race runs nothing, and every command that reads the plan (run, status, report, gc,
//! verify, slurm) replays it the same way.

use super::key::Identity;
use super::model::{Goal, MetricValue, ProgramExperiment, ProgramPlan, ProgramRow, ProgramTrial};
use super::stored::rows;
use crate::cache::store::{KeySet, Store};
use crate::cache::Key;
use std::collections::{HashMap, HashSet};

/// How one raced experiment stands after the replay.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct RaceStanding {
    /// Index of the experiment in the plan.
    pub experiment: usize,
    /// Its cells.
    pub cells: usize,
    /// Rounds decided.
    pub rounds_done: u32,
    /// The most rounds its race can take.
    pub rounds_max: u32,
    /// The race is over.
    pub finished: bool,
    /// Contenders after the last decided round (every cell before the first).
    pub contenders: usize,
    /// Trials planned so far (decided rounds and the pending one), fresh ones not counted.
    pub trials: usize,
    /// Trials of the full grid: every cell at `max_seeds`.
    pub without_race: usize,
}

/// A program plan with its stages replayed from the stored rows.
#[derive(Debug, Clone)]
pub struct ProgramReplayed {
    /// The plan: every raced cell's trials so far and its `contender` flag, the fresh trials of
    /// every decided best cell.
    pub plan: ProgramPlan,
    /// Every raced experiment, in plan order.
    pub races: Vec<RaceStanding>,
}

/// How a replay reads stored rows: those of the keys asked for (a key left out is not stored).
pub type ReadRows<'a> = dyn FnMut(&HashSet<Key>) -> anyhow::Result<HashMap<Key, ProgramRow>> + 'a;

/// The rows `store` holds of the keys asked for: how a replay reads a cache (`None`: no rows yet).
pub fn read_store<'a>(
    store: Option<&'a Store>,
    scan: &'a KeySet,
    plan: &ProgramPlan,
) -> impl FnMut(&HashSet<Key>) -> anyhow::Result<HashMap<Key, ProgramRow>> + 'a {
    let schema =
        super::rows::RowSchema { params: plan.params.clone(), metrics: plan.program.metrics.clone() };
    move |wanted| match store {
        Some(_) => rows(scan, &schema, wanted),
        None => Ok(HashMap::new()),
    }
}

/// Replay `plan` against the rows of `store` (`None`: nothing stored); a plan without stages comes
/// back as it is, nothing read.
pub fn replay_store(plan: ProgramPlan, store: Option<&Store>) -> anyhow::Result<ProgramReplayed> {
    if !plan.has_stages() {
        return Ok(ProgramReplayed { plan, races: Vec::new() });
    }
    let scan = match store {
        Some(s) => s.keys()?,
        None => KeySet::default(),
    };
    let mut read = read_store(store, &scan, &plan);
    replay(plan, &mut read)
}

/// Replay every stage of `plan`: its races' rounds as far as their trials are stored (`read`
/// gives the stored rows of the keys asked for; a key it leaves out is not stored), the next
/// round's trials planned, then the fresh trials of every experiment whose best cell is decided.
pub fn replay(mut plan: ProgramPlan, read: &mut ReadRows) -> anyhow::Result<ProgramReplayed> {
    if !plan.has_stages() {
        return Ok(ProgramReplayed { plan, races: Vec::new() });
    }
    let objective = plan.program.objective.as_ref().and_then(|o| {
        let j = plan.program.metrics.iter().position(|(n, _)| *n == o.metric)?;
        Some((j, o.goal))
    });
    let Some((metric, goal)) = objective else {
        // The loader refuses a stage without an objective; a plan built otherwise has none.
        return Ok(ProgramReplayed { plan, races: Vec::new() });
    };
    let identity = Identity::of(&plan.program);
    let first = plan.seeds.len();
    let mut heats: Vec<Heat> = Vec::new();
    for (ei, e) in plan.experiments.iter_mut().enumerate() {
        if e.race.is_some() {
            for c in &mut e.cells {
                c.contender = Some(true);
            }
            heats.push(Heat { exp: ei, rounds_done: 0, finished: false });
        }
    }
    // Per stored key, the objective's value when the trial succeeded.
    let mut known: Known = HashMap::new();
    let mut learn = |wanted: HashSet<Key>, known: &mut Known| -> anyhow::Result<()> {
        if !wanted.is_empty() {
            for (k, r) in read(&wanted)? {
                known.insert(k, objective_value(&r, metric));
            }
        }
        Ok(())
    };
    run_rounds(&mut plan, &identity, &mut heats, goal, &mut known, &mut learn)?;
    plan_fresh(&mut plan, &identity, &heats, goal, &mut known, &mut learn)?;
    let races = standings(&plan, heats, first);
    Ok(ProgramReplayed { plan, races })
}

/// Per stored key, the objective's value when the trial succeeded.
type Known = HashMap<Key, Option<f64>>;

/// How a replay learns the objective's values of the keys asked for.
type Learn<'a> = dyn FnMut(HashSet<Key>, &mut Known) -> anyhow::Result<()> + 'a;

/// Replay every race's rounds as far as their trials are stored, planning the next round's.
fn run_rounds(
    plan: &mut ProgramPlan,
    identity: &Identity,
    heats: &mut [Heat],
    goal: Goal,
    known: &mut Known,
    learn: &mut Learn,
) -> anyhow::Result<()> {
    let first = plan.seeds.len();
    let next_seed = plan.seeds.iter().max().map_or(0, |m| m + 1);
    loop {
        let wanted: HashSet<Key> = heats
            .iter()
            .filter(|h| !h.finished)
            .flat_map(|h| plan.experiments[h.exp].cells.iter().filter(|c| c.contender == Some(true)))
            .flat_map(|c| c.trials.iter().map(|t| t.key))
            .filter(|k| !known.contains_key(k))
            .collect();
        learn(wanted, known)?;
        let mut advanced = false;
        for h in heats.iter_mut().filter(|h| !h.finished) {
            let e = &mut plan.experiments[h.exp];
            let Some(samples) = samples(e, known, goal) else { continue };
            let race = e.race.expect("a raced experiment");
            let best = best_by_goal(
                samples.iter().enumerate().map(|(i, s)| (i, s.as_deref().and_then(signed_mean))),
                Goal::Minimize,
            );
            let keep = match best {
                Some(b) => {
                    let values: Vec<Option<&[f64]>> = samples.iter().map(|s| s.as_deref()).collect();
                    crate::race::eliminate(&values, b, 1.0 - race.confidence.0)
                }
                None => samples.iter().map(Option::is_some).collect(),
            };
            for (c, k) in e.cells.iter_mut().zip(keep) {
                c.contender = Some(k);
            }
            h.rounds_done += 1;
            advanced = true;
            let n_max = race.max_seeds as usize;
            let left: Vec<usize> =
                (0..e.cells.len()).filter(|&i| e.cells[i].contender == Some(true)).collect();
            if left.len() <= 1 || left.iter().all(|&i| e.cells[i].trials.len() >= n_max) {
                h.finished = true;
                continue;
            }
            for i in left {
                let cell = &mut e.cells[i];
                let seeds =
                    crate::race::round_seeds(next_seed, first, cell.trials.len(), race.batch as usize, n_max);
                for seed in seeds {
                    let key = identity.key(&plan.params, &cell.params, seed);
                    cell.trials.push(ProgramTrial { seed, key });
                }
            }
        }
        if !advanced {
            break;
        }
    }
    Ok(())
}

/// The fresh trials of every experiment whose best cell is decided (its race over, its
/// candidates' trials stored).
fn plan_fresh(
    plan: &mut ProgramPlan,
    identity: &Identity,
    heats: &[Heat],
    goal: Goal,
    known: &mut Known,
    learn: &mut Learn,
) -> anyhow::Result<()> {
    // Fresh seeds last: an experiment's best cell is decided once its race is.
    let ready: Vec<usize> = (0..plan.experiments.len())
        .filter(|&ei| {
            let e = &plan.experiments[ei];
            !e.fresh.is_empty() && heats.iter().filter(|h| h.exp == ei).all(|h| h.finished)
        })
        .collect();
    let wanted: HashSet<Key> = ready
        .iter()
        .flat_map(|&ei| candidates(&plan.experiments[ei]))
        .flat_map(|c| c.trials.iter().map(|t| t.key))
        .filter(|k| !known.contains_key(k))
        .collect();
    learn(wanted, known)?;
    for ei in ready {
        let e = &mut plan.experiments[ei];
        let stored = candidates(e).all(|c| c.trials.iter().all(|t| known.contains_key(&t.key)));
        if !stored {
            continue;
        }
        let means = e.cells.iter().enumerate().filter(|(_, c)| c.contender != Some(false)).map(|(i, c)| {
            let values: Vec<f64> = c.trials.iter().filter_map(|t| known[&t.key]).collect();
            (i, (!values.is_empty()).then(|| crate::analysis::mean(&values)))
        });
        let Some(best) = best_by_goal(means, goal) else { continue };
        let cell = &mut e.cells[best];
        cell.fresh = e
            .fresh
            .iter()
            .map(|&seed| ProgramTrial { seed, key: identity.key(&plan.params, &cell.params, seed) })
            .collect();
    }
    Ok(())
}

/// Where each race stands.
fn standings(plan: &ProgramPlan, heats: Vec<Heat>, first: usize) -> Vec<RaceStanding> {
    heats
        .into_iter()
        .map(|h| {
            let e = &plan.experiments[h.exp];
            let race = e.race.expect("a raced experiment");
            RaceStanding {
                experiment: h.exp,
                cells: e.cells.len(),
                rounds_done: h.rounds_done,
                rounds_max: crate::race::rounds_max(first as u32, race.batch, race.max_seeds),
                finished: h.finished,
                contenders: e.cells.iter().filter(|c| c.contender == Some(true)).count(),
                trials: e.cells.iter().map(|c| c.trials.len()).sum(),
                without_race: e.cells.len() * first.max(race.max_seeds as usize),
            }
        })
        .collect()
}

/// One raced experiment while it is replayed.
struct Heat {
    /// Index of the experiment in the plan.
    exp: usize,
    /// Rounds decided.
    rounds_done: u32,
    /// The race is over.
    finished: bool,
}

/// The cells of `e` that can be its best: all of them, or a race's contenders.
fn candidates(e: &ProgramExperiment) -> impl Iterator<Item = &super::model::ProgramCell> {
    e.cells.iter().filter(|c| c.contender != Some(false))
}

/// Each contender's sample of `e` (the objective over its succeeded trials, negated under
/// `maximize` so that higher is worse; `None` for a cell out of the race), or nothing while one of
/// its trials is not stored.
fn samples(
    e: &ProgramExperiment,
    known: &HashMap<Key, Option<f64>>,
    goal: Goal,
) -> Option<Vec<Option<Vec<f64>>>> {
    let sign = match goal {
        Goal::Minimize => 1.0,
        Goal::Maximize => -1.0,
    };
    let mut out = Vec::with_capacity(e.cells.len());
    for c in &e.cells {
        if c.contender != Some(true) {
            out.push(None);
            continue;
        }
        let mut values = Vec::with_capacity(c.trials.len());
        for t in &c.trials {
            if let Some(v) = known.get(&t.key)? {
                values.push(sign * v);
            }
        }
        out.push(Some(values));
    }
    Some(out)
}

/// The mean of a sample already signed so that lower is better (`None` when empty).
fn signed_mean(values: &[f64]) -> Option<f64> {
    (!values.is_empty()).then(|| crate::analysis::mean(values))
}

/// The objective's value in `row` when the trial succeeded (an int or a float metric).
fn objective_value(row: &ProgramRow, metric: usize) -> Option<f64> {
    match row.result.as_ref().ok()?.get(metric)? {
        MetricValue::Int(i) => Some(*i as f64),
        MetricValue::Float(x) => Some(*x),
        _ => None,
    }
}

/// The best of `means` (each cell's index and its objective's mean, `None` without a value) under
/// `goal`: the lowest or highest mean, the first in order among equals. The race's, the fresh
/// stage's and the report's rule.
pub fn best_by_goal(means: impl IntoIterator<Item = (usize, Option<f64>)>, goal: Goal) -> Option<usize> {
    let mut best: Option<(usize, f64)> = None;
    for (i, m) in means {
        let Some(m) = m else { continue };
        let better = match (best, goal) {
            (None, _) => true,
            (Some((_, b)), Goal::Minimize) => m < b,
            (Some((_, b)), Goal::Maximize) => m > b,
        };
        if better {
            best = Some((i, m));
        }
    }
    best.map(|b| b.0)
}

#[cfg(test)]
mod tests;
