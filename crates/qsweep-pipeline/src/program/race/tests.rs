//! Tests of a program pipeline's race and fresh seeds, replayed against rows made up in memory:
//! the rounds, who leaves, the seeds the contenders get, the fresh trials of the best cell, and
//! the errors of the blocks.

use super::*;
use crate::program::declared::load_str;
use crate::program::model::{Failure, MetricValue};

/// A pipeline over `x` in 0..=5 whose objective (`y`, minimized) is `x` plus noise; `extra`
/// appends blocks.
fn plan_of(extra: &str) -> ProgramPlan {
    let text = format!(
        "name: r\nseeds: 4\nprogram:\n  command: [prog]\n  metrics: {{ y: float }}\n  \
         objective: {{ metric: y, goal: minimize }}\nparams: {{ x: 0 }}\n\
         experiments:\n  - {{ id: e, vary: {{ x: 0..5 }} }}\n{extra}"
    );
    let decl = load_str(&text, "r.yaml", &[]).unwrap();
    let loaded =
        crate::program::declared::LoadedProgram { decl, path: "r.yaml".into(), text, overrides: vec![] };
    let dir = tempfile::tempdir().unwrap();
    crate::program::plan::plan(&loaded, dir.path(), None, &[]).unwrap()
}

/// The stored row of a trial of the cell with `x`: y = 10·x + noise from the seed, or a failure
/// where `fail` says so.
fn row(key: Key, x: i64, seed: u64, fail: bool) -> ProgramRow {
    let noise = ((seed * 7919) % 13) as f64 / 13.0;
    ProgramRow {
        key,
        seed,
        params: vec![],
        result: if fail {
            Err(Failure { exit_code: Some(1), reason: "boom".into(), stderr_tail: String::new() })
        } else {
            Ok(vec![MetricValue::Float(10.0 * x as f64 + noise)])
        },
        seconds: 0.0,
        cpu_seconds: None,
        command_json: String::new(),
        inputs_json: String::new(),
        provenance_json: String::new(),
    }
}

/// Replay `plan` to the end: each pass stores every planned trial (`fail` picks failures), until
/// a replay plans nothing new; the final replay and how many passes ran trials.
fn run_to_the_end(plan: &ProgramPlan, fail: &dyn Fn(i64, u64) -> bool) -> (ProgramReplayed, usize) {
    let mut store: HashMap<Key, ProgramRow> = HashMap::new();
    let mut passes = 0;
    loop {
        let mut read = |w: &HashSet<Key>| -> anyhow::Result<HashMap<Key, ProgramRow>> {
            Ok(w.iter().filter_map(|k| store.get(k).map(|r| (*k, r.clone()))).collect())
        };
        let r = replay(plan.clone(), &mut read).unwrap();
        let mut new = 0;
        for c in r.plan.experiments.iter().flat_map(|e| &e.cells) {
            let x = match c.params[0] {
                crate::program::model::ParamValue::Int(x) => x,
                _ => unreachable!(),
            };
            for t in c.trials.iter().chain(&c.fresh) {
                if let std::collections::hash_map::Entry::Vacant(v) = store.entry(t.key) {
                    v.insert(row(t.key, x, t.seed, fail(x, t.seed)));
                    new += 1;
                }
            }
        }
        if new == 0 {
            return (r, passes);
        }
        passes += 1;
    }
}

#[test]
fn a_race_drops_the_clearly_worse_cells_and_gives_the_rest_seeds_numbered_on() {
    let plan = plan_of("race: { confidence: 0.95, batch: 2, max_seeds: 10 }\n");
    let (done, passes) = run_to_the_end(&plan, &|_, _| false);
    let e = &done.plan.experiments[0];
    // x = 0 is best by far; every other cell is 10 or more worse with a spread below 1.
    let contenders: Vec<bool> = e.cells.iter().map(|c| c.contender == Some(true)).collect();
    assert_eq!(contenders, [true, false, false, false, false, false]);
    assert_eq!(passes, 1, "one round decides it: every other cell is far worse");
    assert!(e.cells.iter().all(|c| c.trials.len() == 4));
    let s = &done.races[0];
    assert!(s.finished);
    assert_eq!((s.rounds_done, s.contenders, s.trials, s.without_race), (1, 1, 24, 60));
    assert_eq!(s.rounds_max, 1 + 3);
}

#[test]
fn tied_cells_get_batches_up_to_max_seeds_and_maximize_flips_the_test() {
    let plan = plan_of("race: { confidence: 0.95, batch: 3, max_seeds: 9 }\n");
    let mut max = plan.clone();
    max.program.objective.as_mut().unwrap().goal = Goal::Maximize;
    let (done, _) = run_to_the_end(&max, &|_, _| false);
    let e = &done.plan.experiments[0];
    let contenders: Vec<bool> = e.cells.iter().map(|c| c.contender == Some(true)).collect();
    assert_eq!(contenders, [false, false, false, false, false, true], "the highest wins under maximize");
    // A tie: one cell, all equal values; nothing can be dropped, so seeds run to max_seeds in
    // batches of 3 numbered on from the largest first-round seed (3): 4, 5, 6, then 7, 8.
    let tied = plan_of("race: { confidence: 0.95, batch: 3, max_seeds: 9 }\n");
    let mut read = |w: &HashSet<Key>| -> anyhow::Result<HashMap<Key, ProgramRow>> {
        Ok(w.iter().map(|k| (*k, row(*k, 1, 0, false))).collect())
    };
    let r = replay(tied, &mut read).unwrap();
    let e = &r.plan.experiments[0];
    assert!(e.cells.iter().all(|c| c.contender == Some(true)));
    let seeds: Vec<u64> = e.cells[3].trials.iter().map(|t| t.seed).collect();
    assert_eq!(seeds, [0, 1, 2, 3, 4, 5, 6, 7, 8]);
    assert!(r.races[0].finished);
    assert_eq!(r.races[0].rounds_done, 3);
}

#[test]
fn failed_trials_are_left_out_of_a_cells_sample() {
    // x = 0's trials all fail: it has no value, so it can neither be best nor be tested; x = 1 is best.
    let plan =
        plan_of("race: { confidence: 0.95, batch: 2, max_seeds: 6 }\nfresh: { first_seed: 100, seeds: 3 }\n");
    let (done, _) = run_to_the_end(&plan, &|x, _| x == 0);
    let e = &done.plan.experiments[0];
    let contenders: Vec<bool> = e.cells.iter().map(|c| c.contender == Some(true)).collect();
    assert_eq!(contenders, [true, true, false, false, false, false]);
    assert_eq!(e.cells[0].trials.len(), 6, "kept to max_seeds: never testable");
    // Fresh seeds go to x = 1, the best with values, once the race is over.
    let fresh: Vec<u64> = e.cells[1].fresh.iter().map(|t| t.seed).collect();
    assert_eq!(fresh, [100, 101, 102]);
    assert!(e.cells.iter().enumerate().all(|(i, c)| i == 1 || c.fresh.is_empty()));
}

#[test]
fn fresh_seeds_without_a_race_wait_for_the_whole_grid() {
    let plan = plan_of("fresh: { first_seed: 50, seeds: 2 }\n");
    let keys: Vec<Key> = plan.experiments[0].cells.iter().flat_map(|c| &c.trials).map(|t| t.key).collect();
    let mut partial = |w: &HashSet<Key>| -> anyhow::Result<HashMap<Key, ProgramRow>> {
        Ok(w.iter().filter(|k| **k != keys[0]).map(|k| (*k, row(*k, 1, 0, false))).collect())
    };
    let r = replay(plan.clone(), &mut partial).unwrap();
    assert!(r.plan.experiments[0].cells.iter().all(|c| c.fresh.is_empty()));
    let (done, passes) = run_to_the_end(&plan, &|_, _| false);
    assert_eq!(passes, 2, "the grid, then the fresh seeds");
    let with: Vec<usize> = (0..6).filter(|&i| !done.plan.experiments[0].cells[i].fresh.is_empty()).collect();
    assert_eq!(with, [0]);
    assert!(done.races.is_empty());
}

#[test]
fn a_race_or_fresh_seeds_without_an_objective_is_an_error_at_the_block() {
    let text = "name: r\nseeds: 4\nprogram:\n  command: [prog]\n  metrics: { y: float }\nparams: { x: 0 }\n\
                experiments:\n  - { id: e, vary: { x: 0..5 }, race: { confidence: 0.9, batch: 1, max_seeds: 5 } }\n";
    let err = load_str(text, "r.yaml", &[]).unwrap_err().to_string();
    assert!(err.starts_with("r.yaml:8:"), "{err}");
    assert!(err.contains("objective"), "{err}");
    let text = "name: r\nseeds: 4\nprogram:\n  command: [prog]\n  metrics: { y: float }\n\
                fresh: { first_seed: 10, seeds: 2 }\n";
    let err = load_str(text, "r.yaml", &[]).unwrap_err().to_string();
    assert!(err.starts_with("r.yaml:6:1"), "{err}");
    // The engine's rules: fresh seeds overlapping the race's extra seeds.
    let text = "name: r\nseeds: 4\nprogram:\n  command: [prog]\n  metrics: { y: float }\n  \
                objective: { metric: y, goal: minimize }\nrace: { confidence: 0.9, batch: 1, max_seeds: 8 }\n\
                fresh: { first_seed: 6, seeds: 2 }\n";
    let err = load_str(text, "r.yaml", &[]).unwrap_err().to_string();
    assert!(err.contains("overlap the race's extra seeds 4..7"), "{err}");
}
