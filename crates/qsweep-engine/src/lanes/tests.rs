use super::*;
use crate::config::{Algorithm, Success, TieBreak, TraceKind, Truncation};
use crate::env::Environment;
use crate::env::{MountainCar, StartKind};
use crate::repr::Binning;

/// Crisp trials of `system` of every kind a lane must handle: both algorithms, both binnings,
/// fixed and Gym starts, Watkins's cut, replacing traces, first-index ties, `terminal`
/// truncation, trials that stop at their first episode cap, at `max_episodes`, at
/// `max_total_steps` and before their first step, and (one per system) a diverging one.
fn trials(system: SystemKind) -> Vec<(TrialConfig, u64)> {
    let dim = system.dim();
    let mut out = Vec::new();
    for (i, algorithm) in [Algorithm::Q0, Algorithm::QLambda].into_iter().enumerate() {
        for (j, res) in [3u32, 6, 10].into_iter().enumerate() {
            let mut c = TrialConfig::paper(system, ReprKind::Crisp, algorithm, vec![res; dim], 2 + j as u32);
            // Short trials with room to vary.
            (c.limits.max_episodes, c.limits.success) = match c.limits.success {
                Success::Balance { .. } => (40, Success::Balance { steps: 1_500 }),
                Success::Reach { .. } => {
                    (12, Success::Reach { within: 1_500, streak: 1, max_episode_steps: 2_500 })
                }
                Success::Solved { .. } => unreachable!("the paper's criteria"),
            };
            match 3 * i + j {
                1 => c.repr.binning = Binning::Digitize,
                2 => c.start = StartKind::Gym,
                3 => (c.learner.watkins_cut, c.learner.traces) = (true, TraceKind::Replacing),
                4 => (c.learner.tie_break, c.limits.truncation) = (TieBreak::First, Truncation::Terminal),
                5 => c.limits.max_total_steps = 3_000,
                _ => {}
            }
            c.normalize();
            for seed in 0..3 {
                out.push((c.clone(), seed + 10 * (i + 3 * j) as u64));
            }
        }
    }
    let mut none = out[0].0.clone();
    none.limits.max_episodes = 0;
    out.insert(5, (none, 1));
    let mut wild = out[3].0.clone();
    // A step size this large overflows the table within a few episodes.
    (wild.learner.alpha, wild.learner.q_init) = (1e300, 1e300);
    out.insert(9, (wild, 2));
    out
}

fn lockstep_outcomes(system: SystemKind, jobs: &[(TrialConfig, u64)]) -> Vec<Outcome> {
    let mut out = vec![None; jobs.len()];
    let mut queue = jobs.iter().enumerate();
    run_lockstep(
        system,
        || queue.next().map(|(i, (c, s))| (i, c, *s)),
        |i, o| {
            assert!(out[i].replace(o).is_none(), "trial {i} handed out twice");
        },
    );
    out.into_iter().map(|o| o.expect("every trial handed out")).collect()
}

#[test]
fn a_trial_in_lockstep_is_the_trial_alone() {
    for system in SystemKind::ALL {
        let jobs = trials(system);
        let got = lockstep_outcomes(system, &jobs);
        let stops: std::collections::BTreeSet<_> = got.iter().map(|o| o.stop.name()).collect();
        assert!(stops.len() >= 3, "{system}: the trials should stop in several ways: {stops:?}");
        for ((c, seed), o) in jobs.iter().zip(&got) {
            assert_eq!(o, &run_trial(c, *seed), "{system} seed {seed}: {c:?}");
        }
        // Fewer trials than lanes, and every trial in a different company.
        for k in [1, 3] {
            let few: Vec<_> = jobs.iter().rev().step_by(k + 2).take(k).cloned().collect();
            for ((c, seed), o) in few.iter().zip(lockstep_outcomes(system, &few)) {
                assert_eq!(o, run_trial(c, *seed), "{system} with {k} trials: seed {seed}");
            }
        }
    }
}

#[test]
fn trials_that_do_not_fit_the_lanes_run_alone_with_the_same_outcome() {
    let mut jobs = trials(SystemKind::MountainCar);
    jobs.truncate(8);
    let fuzzy = TrialConfig::paper(SystemKind::MountainCar, ReprKind::Fuzzy, Algorithm::Q0, vec![3, 3], 3);
    let other = TrialConfig::paper(SystemKind::CartPole, ReprKind::Crisp, Algorithm::Q0, vec![3; 4], 2);
    jobs.insert(2, (fuzzy, 4));
    jobs.insert(6, (other, 5));
    for ((c, seed), o) in jobs.iter().zip(lockstep_outcomes(SystemKind::MountainCar, &jobs)) {
        assert_eq!(o, run_trial(c, *seed));
    }
}

#[test]
fn mountain_cars_stepped_together_are_stepped_alone() {
    // Every start position across the track (and past it) with every throttle, including lanes
    // whose cos(3x) takes cos's slow path (3x near a multiple of π/2).
    let p = crate::env::MountainCarParams::default();
    let mut xs: Vec<f64> = (0..4001).map(|i| -1.3 + f64::from(i) * 0.000_45).collect();
    xs.extend((-2..=1).map(|m| f64::from(m) * std::f64::consts::FRAC_PI_2 / 3.0 + 1e-14));
    for (c, chunk) in xs.chunks(7).enumerate() {
        let mk = |x: f64, k: usize| {
            let mut e = MountainCar::new(p.clone());
            e.set_state(&[x, (k as f64 - 3.0) * 0.02]);
            e
        };
        let mut together: Vec<_> = chunk.iter().enumerate().map(|(k, &x)| mk(x, k)).collect();
        let mut alone = together.clone();
        let actions: Vec<f64> = (0..chunk.len()).map(|k| [-1.0, 0.0, 1.0, 0.5][(k + c) % 4]).collect();
        for _ in 0..3 {
            let mut t = vec![Transition { reward: 0.0, terminal: false }; chunk.len()];
            MountainCar::step_each(&mut together, &actions, &mut t);
            for ((e, &a), (t, f)) in alone.iter_mut().zip(&actions).zip(t.iter().zip(&together)) {
                assert_eq!(e.step(a), *t);
                assert_eq!(e.state().map(f64::to_bits), f.state().map(f64::to_bits));
            }
        }
    }
}

#[test]
fn a_batch_is_each_trial_run_alone() {
    let mut trials = Vec::new();
    for system in SystemKind::ALL {
        trials.extend(trials_of(system, 7));
        let fuzzy = TrialConfig::paper(system, ReprKind::Fuzzy, Algorithm::QLambda, vec![3; system.dim()], 3);
        trials.push((fuzzy, 3));
    }
    // Systems interleaved, as a verify sample draws them.
    trials.sort_by_key(|(_, seed)| *seed);
    let refs: Vec<(&TrialConfig, u64)> = trials.iter().map(|(c, s)| (c, *s)).collect();
    let want: Vec<Outcome> = refs.iter().map(|&(c, s)| run_trial(c, s)).collect();
    assert_eq!(run_batch(&refs), want);
    assert!(run_batch(&[]).is_empty());
}

/// The first `n` of [`trials`].
fn trials_of(system: SystemKind, n: usize) -> Vec<(TrialConfig, u64)> {
    trials(system).into_iter().take(n).collect()
}

/// Small fuzzy rule bases on the dense path, in lockstep: every size it takes on both
/// two-variable systems, both algorithms, several action counts, and the settings that reach its
/// fallbacks (no prune, a tiny width, Watkins's cut with replacing traces, an overflowing step),
/// stopping in several ways; each trial's outcome is the trial's alone, with company and without.
#[test]
fn dense_fuzzy_trials_in_lockstep_are_the_trials_alone() {
    for system in [SystemKind::MountainCar, SystemKind::BallBeam] {
        let mut jobs = Vec::new();
        for (i, sets) in [[4, 4], [3, 3], [2, 4], [4, 1], [3, 2]].into_iter().enumerate() {
            for (j, algorithm) in [Algorithm::Q0, Algorithm::QLambda].into_iter().enumerate() {
                let mut c = TrialConfig::paper(
                    system,
                    ReprKind::Fuzzy,
                    algorithm,
                    sets.to_vec(),
                    [3, 2, 5, 7][(i + j) % 4],
                );
                c.limits.max_episodes = 6;
                c.limits.max_total_steps = 4_000 + 1_000 * i as u64;
                match (2 * i + j) % 5 {
                    1 => c.repr.width = 0.25,
                    2 => c.repr.width = 0.02,
                    3 => (c.learner.watkins_cut, c.learner.traces) = (true, TraceKind::Replacing),
                    4 if i == 2 => (c.learner.alpha, c.learner.q_init) = (1e300, 1e300),
                    _ => {}
                }
                c.normalize();
                assert!(benefits(&c), "{system} {sets:?}: the dense path takes it");
                jobs.push((c, (10 * i + j) as u64));
            }
        }
        let got = lockstep_outcomes(system, &jobs);
        let stops: std::collections::BTreeSet<_> = got.iter().map(|o| o.stop.name()).collect();
        assert!(stops.len() >= 2, "{system}: the trials should stop in several ways: {stops:?}");
        for ((c, seed), o) in jobs.iter().zip(&got) {
            assert_eq!(o, &run_trial(c, *seed), "{system} seed {seed}: {c:?}");
        }
        let few: Vec<_> = jobs.iter().step_by(4).take(3).cloned().collect();
        for ((c, seed), o) in few.iter().zip(lockstep_outcomes(system, &few)) {
            assert_eq!(o, run_trial(c, *seed), "{system} with 3 trials: seed {seed}");
        }
    }
}
