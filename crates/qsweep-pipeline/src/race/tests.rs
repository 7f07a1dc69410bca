//! Tests of the race: one round's decision (Welch and Holm over the contenders) and whole races
//! replayed against a made-up cache (rounds, stopping where the cache stops, undoing a replay).

use super::*;
use crate::declared::load_str;
use qsweep_engine::trial::StopReason;

fn sample(values: &[f64], cap: f64) -> Option<Sample> {
    Some(Sample { values: values.to_vec(), successes: values.iter().filter(|&&v| v < cap).count() })
}

#[test]
fn a_clearly_worse_cell_leaves_and_the_best_and_ties_stay() {
    let s = [
        sample(&[5.0, 6.0, 4.0, 5.0], 30.0),
        sample(&[30.0; 4], 30.0),            // censored everywhere: far worse
        sample(&[5.0, 6.0, 4.0, 5.0], 30.0), // the same as the best: a tie
        sample(&[6.0, 7.0, 5.0, 6.0], 30.0), // a little worse: not significantly at n = 4
        None,                                // left in an earlier round: stays out
    ];
    assert_eq!(decide(&s, 0.05), vec![true, false, true, true, false]);
    // Nothing is dropped at a confidence that demands more than 4 seeds can give.
    assert_eq!(decide(&s[..4], 1e-12), vec![true, true, true, true]);
}

#[test]
fn holm_protects_the_family_of_a_round() {
    // Each of these alone is worse at 5 % one-sided (p ≈ 0.03), but not after Holm over 3.
    let best = [10.0, 11.0, 9.0, 10.0, 10.0];
    let worse = [10.5, 12.5, 10.5, 11.5, 11.0];
    let p = welch::welch_p_greater(&worse, &best);
    assert!(p < 0.05 && p > 0.05 / 3.0, "{p}");
    let s = [sample(&best, 1e9), sample(&worse, 1e9), sample(&worse, 1e9), sample(&worse, 1e9)];
    assert_eq!(decide(&s, 0.05), vec![true; 4]);
    assert_eq!(decide(&s[..2], 0.05), vec![true, false], "alone it leaves");
}

/// A plan of one raced heatmap of three cells, and outcomes made up per (cell, seed).
fn plan(race: &str) -> Plan {
    let text = format!(
        "name: t\nseeds: 3\nrace: {race}\nsystems:\n  cart-pole:\n    settings: {{ max_episodes: 50 }}\n    experiments:\n      - {{ id: a, repr: crisp, algorithms: [q0], vary: {{ actions: [2, 3, 4] }}, fixed: {{ x == x_dot == theta == theta_dot: 2 }} }}\n"
    );
    let spec = load_str(&text, "t.yaml", &[]).unwrap();
    let loaded = crate::declared::LoadedSpec { spec, path: "t.yaml".into(), variants: Vec::new() };
    crate::plan::plan(&loaded, None).unwrap()
}

fn outcome(episodes: u32) -> Outcome {
    Outcome {
        converged: episodes < 50,
        episodes_to_goal: (episodes < 50).then_some(episodes),
        episodes,
        total_steps: 0,
        stop: StopReason::Goal,
        failure: None,
        episode_lengths: Vec::new(),
    }
}

/// Resolve against a cache that holds every planned trial the closure gives an outcome for,
/// running "trials" until the race is over; returns the rounds' trial counts and the outcomes.
/// Outcomes by key: a cache.
type Stored = HashMap<Key, Outcome>;

/// Read from `store`, as a replay reads a cache.
fn reader(store: &Stored) -> impl FnMut(&HashSet<Key>) -> anyhow::Result<Vec<(Key, TrialBrief)>> + '_ {
    |w| Ok(w.iter().map(|k| (*k, TrialBrief::from(&store[k]))).collect())
}

fn race_to_the_end(plan: &Plan, value: impl Fn(usize, u64) -> u32) -> (Replayed, Vec<usize>, Stored) {
    let mut store: Stored = HashMap::new();
    let mut per_round = Vec::new();
    loop {
        let cached: HashSet<Key> = store.keys().copied().collect();
        let raced = replay(plan, &cached, &mut reader(&store)).unwrap();
        let missing: Vec<(usize, u64, Key)> = raced.plan.experiments[0]
            .cells
            .iter()
            .enumerate()
            .flat_map(|(i, c)| c.trials.iter().map(move |t| (i, t.seed, t.key)))
            .filter(|(_, _, k)| !cached.contains(k))
            .collect();
        if missing.is_empty() {
            return (raced, per_round, store);
        }
        per_round.push(missing.len());
        for (i, seed, key) in missing {
            store.insert(key, outcome(value(i, seed)));
        }
    }
}

#[test]
fn a_worse_cell_leaves_after_round_0_and_a_tie_runs_to_max_seeds() {
    let p = plan("{ confidence: 0.95, batch: 2, max_seeds: 8 }");
    // Cells 0 and 2 alternate 4 and 6 episodes (a tie); cell 1 always fails (50).
    let (raced, rounds, _) =
        race_to_the_end(&p, |i, seed| if i == 1 { 50 } else { 4 + 2 * (seed % 2) as u32 });
    assert_eq!(rounds, vec![9, 4, 4, 2], "round 0: 3 cells × 3 seeds; then 2 contenders × 2, 2, 1 seeds");
    let cells = &raced.plan.experiments[0].cells;
    let n: Vec<usize> = cells.iter().map(|c| c.trials.len()).collect();
    assert_eq!(n, vec![8, 3, 8]);
    assert_eq!(
        cells.iter().map(|c| c.contender).collect::<Vec<_>>(),
        vec![Some(true), Some(false), Some(true)]
    );
    let seeds: Vec<u64> = cells[0].trials.iter().map(|t| t.seed).collect();
    assert_eq!(seeds, (0..8).collect::<Vec<_>>(), "extra seeds continue the numbering");
    let h = &raced.heats[0];
    assert_eq!((h.rounds_done, h.rounds_max, h.finished, h.contenders), (4, 4, true, 2));
    assert_eq!((h.trials, h.cached, h.without_race), (19, 19, 24));
}

/// Each cell's trials, race state and fresh trials.
type CellState = (Vec<PlannedTrial>, Option<bool>, Vec<PlannedTrial>);

fn cells(p: &Plan) -> Vec<CellState> {
    p.experiments
        .iter()
        .flat_map(|e| &e.cells)
        .map(|c| (c.trials.clone(), c.contender, c.fresh.clone()))
        .collect()
}

#[test]
fn an_undone_replay_is_the_plan_as_planned() {
    let p = plan("{ confidence: 0.95, batch: 2, max_seeds: 8 }");
    let (raced, _, store) =
        race_to_the_end(&p, |i, seed| if i == 1 { 50 } else { 4 + 2 * (seed % 2) as u32 });
    assert_ne!(cells(&raced.plan), cells(&p), "the replay added rounds and decided the race");
    let cached: HashSet<Key> = store.keys().copied().collect();
    // Replayed in place: the same replay, taken back to the plan as planned.
    let (in_place, undo) = Unreplay::replay(p.clone(), false, &cached, &mut reader(&store)).unwrap();
    assert!(undo.planned().is_none(), "no copy is kept");
    assert_eq!(cells(&in_place.plan), cells(&raced.plan));
    assert_eq!(cells(&undo.undo(in_place)), cells(&p));
    // A copy replayed when asked: the plan as planned is kept beside it.
    let (copied, kept) = Unreplay::replay(p.clone(), true, &cached, &mut reader(&store)).unwrap();
    assert_eq!(kept.planned().map(cells), Some(cells(&p)));
    assert_eq!(cells(&copied.plan), cells(&raced.plan));
    assert_eq!(cells(&kept.undo(copied)), cells(&p));
    // A plan whose cells already have fresh trials is not undone (a replay replaces them): a
    // copy is replayed.
    let mut with_fresh = p.clone();
    with_fresh.experiments[0].fresh = Some(vec![100]);
    with_fresh.experiments[0].cells[0].fresh = with_fresh.experiments[0].cells[1].trials.clone();
    let (_, kept) = Unreplay::replay(with_fresh.clone(), false, &cached, &mut reader(&store)).unwrap();
    assert_eq!(kept.planned().map(cells), Some(cells(&with_fresh)));
}

#[test]
fn raising_max_seeds_adds_rounds_and_keeps_the_earlier_ones() {
    let value = |i: usize, seed: u64| if i == 1 { 50 } else { 4 + 2 * (seed % 2) as u32 };
    let (short, _, _) = race_to_the_end(&plan("{ confidence: 0.95, batch: 2, max_seeds: 5 }"), value);
    let (long, _, _) = race_to_the_end(&plan("{ confidence: 0.95, batch: 2, max_seeds: 9 }"), value);
    for (a, b) in short.plan.experiments[0].cells.iter().zip(&long.plan.experiments[0].cells) {
        assert_eq!(a.trials[..], b.trials[..a.trials.len()], "the short race's trials are a prefix");
    }
    assert_eq!(long.plan.experiments[0].cells[0].trials.len(), 9);
}

#[test]
fn a_race_stops_where_the_cache_stops_and_plans_the_next_round() {
    let p = plan("{ confidence: 0.95, batch: 2, max_seeds: 8 }");
    let none = replay(&p, &HashSet::new(), &mut |_| Ok(Vec::new())).unwrap();
    let h = &none.heats[0];
    assert_eq!((h.rounds_done, h.finished, h.contenders, h.trials, h.cached), (0, false, 3, 9, 0));
    assert!(none.plan.experiments[0].cells.iter().all(|c| c.contender == Some(true) && c.trials.len() == 3));
    // Without a race the plan comes back untouched.
    let mut plain = p.clone();
    plain.experiments[0].race = None;
    let r = replay(&plain, &HashSet::new(), &mut |_| Ok(Vec::new())).unwrap();
    assert!(r.heats.is_empty() && r.plan.experiments[0].cells.iter().all(|c| c.contender.is_none()));
}
