//! Fresh seeds for the best cells: the winner's curse, measured.
//!
//! A Table III value is the best of a heatmap's cell means (81 of them in the paper's grid), so it
//! is biased low: the cell that wins is, partly, the cell whose seeds happened to be lucky. With a
//! pipeline's `fresh: { first_seed, seeds }`, once a heatmap's cells are all present (and its race,
//! if any, is over) its best cell by Table III's rule ([`crate::analysis::best_cell`]) gets trials
//! on the fresh seeds, which took no part in choosing it. Their mean is an unbiased estimate of
//! that configuration's performance; the report shows it beside the selection estimate and judges
//! the row against the paper with it.
//!
//! Like a race, the stage is a pure function of the pipeline and the cached outcomes:
//! [`plan_fresh`] is called by [`crate::race::replay`] after the races, so every command that
//! replays a plan (run, status, report, gc, slurm) sees the same fresh trials.

use crate::analysis::{best_cell, episodes_counted, mean, Candidate};
use crate::cache::{Key, ENGINE_VERSION};
use crate::plan::{Experiment, Plan, PlannedTrial, ReadOutcomes, TrialBrief};
use qsweep_engine::{Algorithm, Outcome};
use std::collections::{HashMap, HashSet};

/// The stated rule, for captions and the README.
pub const FRESH_RULE: &str = "Fresh: the best cell re-run on seeds that took no part in choosing it \
(the pipeline's `fresh:` block); its mean, std, n and bootstrap 95% interval. Where a row has fresh \
trials, the censored fraction, KM median, ours/paper and the equivalence verdicts use them; the \
performance column, n and Δ mean stay the selection estimate (the heatmap's best cell on the grid's \
seeds, biased low by the choice).";

/// Plan the fresh-seed trials of every heatmap of `plan` whose best cell is decided: all trials of
/// its candidate cells (every cell, or a finished race's contenders) are in `cached`. `known` holds
/// outcomes already read; `read` fetches the others.
pub fn plan_fresh(
    plan: &mut Plan,
    cached: &HashSet<Key>,
    known: &mut HashMap<Key, TrialBrief>,
    read: &mut ReadOutcomes,
) -> anyhow::Result<()> {
    let mut ready: Vec<(usize, Algorithm)> = Vec::new();
    for (ei, e) in plan.experiments.iter().enumerate() {
        if e.fresh.is_none() {
            continue;
        }
        for &a in &e.algorithms {
            let all_cached =
                candidates(e, a).all(|i| e.cells[i].trials.iter().all(|t| cached.contains(&t.key)));
            if all_cached && candidates(e, a).next().is_some() {
                ready.push((ei, a));
            }
        }
    }
    let wanted: HashSet<Key> = ready
        .iter()
        .flat_map(|&(ei, a)| {
            let e = &plan.experiments[ei];
            candidates(e, a).flat_map(move |i| e.cells[i].trials.iter().map(|t| t.key))
        })
        .filter(|k| !known.contains_key(k))
        .collect();
    if !wanted.is_empty() {
        let got = read(&wanted)?;
        known.reserve(got.len());
        known.extend(got);
    }
    for (ei, a) in ready {
        let e = &mut plan.experiments[ei];
        let Some(best) = best_of(e, a, known) else { continue };
        let seeds = e.fresh.clone().expect("only experiments with fresh seeds are ready");
        let cell = &mut e.cells[best];
        let canonical = crate::cache::key::canonical_config(&cell.config);
        cell.fresh = seeds
            .into_iter()
            .map(|seed| PlannedTrial { seed, key: Key::from_canonical(&canonical, seed, ENGINE_VERSION) })
            .collect();
    }
    Ok(())
}

/// The cells of `algorithm` that can be its best: all of them, or a race's contenders.
fn candidates(e: &Experiment, algorithm: Algorithm) -> impl Iterator<Item = usize> + '_ {
    (0..e.cells.len())
        .filter(move |&i| e.cells[i].algorithm == algorithm && e.cells[i].contender != Some(false))
}

/// The best cell of `algorithm` by Table III's rule, from the outcomes of its candidates' trials
/// (the report's choice: the same counting, the same mean, the same order).
fn best_of(e: &Experiment, algorithm: Algorithm, known: &HashMap<Key, TrialBrief>) -> Option<usize> {
    let cands: Vec<Candidate> = candidates(e, algorithm)
        .map(|i| {
            let cell = &e.cells[i];
            let limits = &cell.config.limits;
            let outcomes: Vec<Outcome> =
                cell.trials.iter().filter_map(|t| known.get(&t.key).map(TrialBrief::outcome)).collect();
            let values: Vec<f64> =
                outcomes.iter().map(|o| f64::from(episodes_counted(o, limits, e.counting))).collect();
            Candidate {
                index: i,
                n: values.len(),
                successes: outcomes.iter().filter(|o| o.converged).count(),
                mean: (!values.is_empty()).then(|| mean(&values)),
            }
        })
        .collect();
    best_cell(cands).map(|b| b.cell)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::race::replay;
    use crate::testing::{fresh_plan as plan, outcome, run_to_the_end};

    #[test]
    fn fresh_seeds_go_to_the_best_cell_once_the_grid_is_stored() {
        let p = plan();
        // Nothing stored: nothing is decided, no fresh trial is planned.
        let none = replay(&p, &HashSet::new(), &mut |_| Ok(Vec::new())).unwrap();
        assert!(none.plan().experiments[0].cells.iter().all(|c| c.fresh.is_empty()));
        // All but one trial stored: still undecided.
        let keys: Vec<Key> = p.trials().map(|(_, _, t)| t.key).collect();
        let almost: HashSet<Key> = keys[1..].iter().copied().collect();
        let read = |w: &HashSet<Key>| -> anyhow::Result<Vec<(Key, TrialBrief)>> {
            Ok(w.iter().map(|k| (*k, TrialBrief::from(&outcome(20)))).collect())
        };
        let part = replay(&p, &almost, &mut |w| read(w)).unwrap();
        assert!(part.plan().experiments[0].cells.iter().all(|c| c.fresh.is_empty()));

        let (done, store, stages) = run_to_the_end(&p);
        assert_eq!(stages, 2, "the grid, then the fresh seeds");
        let cells = &done.experiments[0].cells;
        let with_fresh: Vec<usize> = (0..cells.len()).filter(|&i| !cells[i].fresh.is_empty()).collect();
        assert_eq!(with_fresh.len(), 1, "one best cell per heatmap");
        let best = with_fresh[0];
        let seeds: Vec<u64> = cells[best].fresh.iter().map(|t| t.seed).collect();
        assert_eq!(seeds, (100..120).collect::<Vec<_>>());
        // The best cell is the one with the lowest mean on the grid's seeds (all converged).
        let mean_of = |ts: &[PlannedTrial]| {
            ts.iter().map(|t| f64::from(store[&t.key].episodes)).sum::<f64>() / ts.len() as f64
        };
        let lowest = (0..cells.len())
            .min_by(|&a, &b| mean_of(&cells[a].trials).total_cmp(&mean_of(&cells[b].trials)))
            .unwrap();
        assert_eq!(best, lowest);
        // The planted winner's curse: every cell has the same distribution (mean 25), so the
        // minimum of nine 5-seed means is low, and the fresh estimate is not.
        let (selection, fresh) = (mean_of(&cells[best].trials), mean_of(&cells[best].fresh));
        assert!(selection < 20.0 && fresh > selection + 3.0, "selection {selection}, fresh {fresh}");
        // Replayed against the full store, the plan is the same and nothing is missing; it counts
        // the fresh trials.
        let cached: HashSet<Key> = store.keys().copied().collect();
        let again =
            replay(&p, &cached, &mut |w| Ok(w.iter().map(|k| (*k, TrialBrief::from(&store[k]))).collect()))
                .unwrap();
        assert!(again.plan().trials().all(|(_, _, t)| cached.contains(&t.key)));
        assert_eq!(again.plan().experiments[0].cells[best].fresh, cells[best].fresh);
        assert_eq!(done.trial_count(), 9 * 5 + 20);
        // Replayed in place and taken back, it is the plan as planned: no fresh trials.
        let mut stored = |w: &HashSet<Key>| -> anyhow::Result<Vec<(Key, TrialBrief)>> {
            Ok(w.iter().map(|k| (*k, TrialBrief::from(&store[k]))).collect())
        };
        let (in_place, undo) = crate::race::Unreplay::replay(p.clone(), false, &cached, &mut stored).unwrap();
        assert_eq!(in_place.plan().experiments[0].cells[best].fresh, cells[best].fresh);
        assert!(undo.planned().is_none(), "replayed in place");
        let back = undo.undo(in_place);
        assert!(back.experiments[0].cells.iter().all(|c| c.fresh.is_empty()));
        let trials = |q: &Plan| q.experiments[0].cells.iter().map(|c| c.trials.clone()).collect::<Vec<_>>();
        assert_eq!(trials(&back), trials(&p));
    }
}
