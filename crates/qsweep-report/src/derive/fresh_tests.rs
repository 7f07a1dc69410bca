//! The report judges a row on its fresh estimate: a plan whose best cell gets fresh seeds, raced
//! to the end against a store of planted outcomes (as in `qsweep_pipeline::fresh`'s own tests),
//! then read by [`crate::derive::model::ReportData`].

use qsweep_engine::trial::StopReason;
use qsweep_engine::{Algorithm, Outcome};
use qsweep_pipeline::cache::Key;
use qsweep_pipeline::plan::Plan;
use qsweep_pipeline::plan::StageOutcome;
use qsweep_pipeline::race::replay;
use qsweep_pipeline::spec::load_str;
use std::collections::{HashMap, HashSet};

/// A plan of one heatmap of 9 cells (Cart-Pole, actions 2..10), 5 seeds each, fresh seeds
/// 100..119.
fn plan() -> Plan {
    let text = "name: t\nseeds: 5\nfresh: { first_seed: 100, seeds: 20 }\nsystems:\n  cart-pole:\n    settings: { max_episodes: 500 }\n    experiments:\n      - { id: a, repr: crisp, algorithms: [q0], vary: { actions: 2..10 }, fixed: { x == x_dot == theta == theta_dot: 2 } }\n";
    let spec = load_str(text, "t.yaml", &[]).unwrap();
    let loaded = qsweep_pipeline::spec::LoadedSpec { spec, path: "t.yaml".into(), variants: Vec::new() };
    qsweep_pipeline::plan::plan(&loaded, None).unwrap()
}

fn outcome(episodes: u32) -> Outcome {
    Outcome {
        converged: true,
        episodes_to_goal: Some(episodes),
        episodes,
        total_steps: 0,
        stop: StopReason::Goal,
        failure: None,
        episode_lengths: Vec::new(),
    }
}

/// Every cell draws from the same distribution: 10 to 40 episodes, by a hash of (cell, seed).
fn planted(cell: usize, seed: u64) -> u32 {
    let h = blake3::hash(&[cell.to_le_bytes(), seed.to_le_bytes()].concat());
    10 + u32::from(h.as_bytes()[0]) % 31
}

/// Replay against a store, running what it plans until nothing is missing.
fn run_to_the_end(p: &Plan) -> (Plan, HashMap<Key, Outcome>, usize) {
    let mut store: HashMap<Key, Outcome> = HashMap::new();
    let mut stages = 0;
    loop {
        let cached: HashSet<Key> = store.keys().copied().collect();
        let out =
            replay(p, &cached, &mut |w| Ok(w.iter().map(|k| (*k, StageOutcome::from(&store[k]))).collect()))
                .unwrap()
                .into_plan();
        let missing: Vec<(usize, u64, Key)> = out.experiments[0]
            .cells
            .iter()
            .enumerate()
            .flat_map(|(i, c)| c.trials.iter().chain(&c.fresh).map(move |t| (i, t.seed, t.key)))
            .filter(|(_, _, k)| !cached.contains(k))
            .collect();
        if missing.is_empty() {
            return (out, store, stages);
        }
        stages += 1;
        for (i, seed, key) in missing {
            store.insert(key, outcome(planted(i, seed)));
        }
    }
}

#[test]
fn the_report_judges_the_row_on_the_fresh_estimate() {
    let (done, store, _) = run_to_the_end(&plan());
    let records: HashMap<Key, qsweep_pipeline::cache::rows::StoredOutcome> = store
        .into_iter()
        .map(|(k, o)| {
            (k, qsweep_pipeline::cache::rows::StoredOutcome { outcome: o, seconds: 0.0, cpu_seconds: None })
        })
        .collect();
    let data = crate::derive::model::ReportData::build(&done, &records);
    let e = &data.experiments[0];
    let best = e.best_of(Algorithm::Q0).unwrap().cell;
    let c = &e.cells[best];
    assert_eq!((c.trials.len(), c.fresh.len()), (5, 20));
    let est = c.estimate();
    assert!(est.fresh && est.n() == 20);
    assert_eq!(est.summary.mean, c.fresh_summary.as_ref().unwrap().mean);
    assert_ne!(est.summary.mean, c.summary.mean, "the selection estimate is kept apart");
    assert_eq!((data.trials_planned, data.trials_cached), (65, 65));
    // Every other cell is judged, as before, on its own trials.
    let other = &e.cells[(best + 1) % e.cells.len()];
    assert!(!other.estimate().fresh && other.fresh_summary.is_none());
}
