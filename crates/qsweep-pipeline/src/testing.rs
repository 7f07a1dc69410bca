//! Fixtures for tests of this crate and of the crates built on it (with the `test-support`
//! feature, which the report's tests turn on): a plan whose best cell gets fresh seeds, and a
//! store of planted outcomes to race it to the end against.

use crate::cache::Key;
use crate::declared::{load_str, LoadedSpec};
use crate::plan::{plan, Plan, TrialBrief};
use crate::race::replay;
use qsweep_engine::trial::StopReason;
use qsweep_engine::Outcome;
use std::collections::{HashMap, HashSet};

/// A plan of one heatmap of 9 cells (Cart-Pole, actions 2..10), 5 seeds each, fresh seeds
/// 100..119.
pub fn fresh_plan() -> Plan {
    let text = "name: t\nseeds: 5\nfresh: { first_seed: 100, seeds: 20 }\nsystems:\n  cart-pole:\n    settings: { max_episodes: 500 }\n    experiments:\n      - { id: a, repr: crisp, algorithms: [q0], vary: { actions: 2..10 }, fixed: { x == x_dot == theta == theta_dot: 2 } }\n";
    let spec = load_str(text, "t.yaml", &[]).unwrap();
    let loaded = LoadedSpec { spec, path: "t.yaml".into(), variants: Vec::new() };
    plan(&loaded, None).unwrap()
}

/// A trial's outcome that reached the goal in `episodes` episodes.
pub fn outcome(episodes: u32) -> Outcome {
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

/// A trial's planted number of episodes: every cell draws from the same distribution, 10 to 40
/// episodes, by a hash of (cell, seed).
pub fn planted(cell: usize, seed: u64) -> u32 {
    let h = blake3::hash(&[cell.to_le_bytes(), seed.to_le_bytes()].concat());
    10 + u32::from(h.as_bytes()[0]) % 31
}

/// Replay against a store, running what it plans until nothing is missing.
pub fn run_to_the_end(p: &Plan) -> (Plan, HashMap<Key, Outcome>, usize) {
    let mut store: HashMap<Key, Outcome> = HashMap::new();
    let mut stages = 0;
    loop {
        let cached: HashSet<Key> = store.keys().copied().collect();
        let out =
            replay(p, &cached, &mut |w| Ok(w.iter().map(|k| (*k, TrialBrief::from(&store[k]))).collect()))
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
