//! The dense fuzzy path ([`crate::repr::DenseFuzzy`]) against the windowed one: the same outcome
//! and the same Q parameters, bit for bit, after many steps, at every vector level, for every rule
//! base size and action count the dense path takes, and in each case that needs its fallback.

use super::config::{Algorithm, Success, TraceKind, TrialConfig};
use super::env::SystemKind;
use super::repr::{DenseFuzzy, Fuzzy, ReprKind};
use super::simd::Simd;
use super::trial::run_fuzzy_with_q;

/// A fuzzy trial of `sets` and `actions` capped at `steps` steps in all.
fn config(system: SystemKind, algorithm: Algorithm, sets: [u32; 2], actions: u32, steps: u64) -> TrialConfig {
    let mut c = TrialConfig::paper(system, ReprKind::Fuzzy, algorithm, sets.to_vec(), actions);
    c.limits.max_total_steps = steps;
    c.limits.max_episodes = 1_000_000;
    // Never reached within the cap, so every trial runs all its steps.
    c.limits.success = match c.limits.success {
        Success::Balance { .. } => Success::Balance { steps: 1_000_000 },
        Success::Reach { max_episode_steps, .. } => {
            Success::Reach { within: 1, streak: 1_000, max_episode_steps }
        }
        s => s,
    };
    c
}

/// The dense path's outcome and parameters equal the windowed path's (at the baseline level) at
/// every level; `dense`: whether the dense path takes the rule base (else both runs are windowed).
fn same_bits(label: &str, c: &mut TrialConfig, seed: u64, dense: bool) {
    let r = &c.repr;
    let fits = DenseFuzzy::fits(&Fuzzy::new(&r.resolution, &r.ranges, r.width, r.prune));
    assert_eq!(fits, dense, "{label}: whether the dense path takes it");
    c.normalize();
    c.validate().expect("valid test case");
    let (want_outcome, want_q) = run_fuzzy_with_q(c, seed, Simd::Baseline, false);
    let bits = |q: &[f64]| q.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
    for simd in Simd::available() {
        for dense in [false, true] {
            let (outcome, q) = run_fuzzy_with_q(c, seed, simd, dense);
            assert_eq!(outcome, want_outcome, "{label} at {simd:?}, dense {dense}");
            assert_eq!(bits(&q), bits(&want_q), "{label} at {simd:?}, dense {dense}: Q parameters");
        }
    }
}

/// Every rule base of two variables of the study's sizes and more (one set a variable included),
/// under Q(0) and Q(λ), on Mountain Car and Ball-Beam.
#[test]
fn dense_fuzzy_path_gives_the_windowed_paths_bits_for_every_size() {
    let mut sizes = 0;
    for n0 in 1..=12u32 {
        for n1 in 1..=12u32 {
            sizes += 1;
            for (i, algorithm) in [Algorithm::Q0, Algorithm::QLambda].into_iter().enumerate() {
                let system = if (n0 + n1) % 2 == 0 { SystemKind::MountainCar } else { SystemKind::BallBeam };
                let actions = [3, 2, 5, 4, 7, 10, 6, 16, 9][(n0 * n1 + i as u32) as usize % 9];
                let mut c = config(system, algorithm, [n0, n1], actions, 3_000);
                same_bits(
                    &format!("{system} {n0}x{n1} {} {actions}a", algorithm.name()),
                    &mut c,
                    u64::from(n0 * 13 + n1),
                    true,
                );
            }
        }
    }
    assert_eq!(sizes, 144);
}

/// The study's standard cells, long: 4², 3², 2×4, 2×5 and 9×3 with 3 actions, under both
/// algorithms and both systems, 100,000 steps.
#[test]
fn dense_fuzzy_path_gives_the_windowed_paths_bits_over_long_trials() {
    for system in [SystemKind::MountainCar, SystemKind::BallBeam] {
        for algorithm in [Algorithm::Q0, Algorithm::QLambda] {
            for sets in [[4, 4], [3, 3], [2, 4], [2, 5], [9, 3]] {
                let mut c = config(system, algorithm, sets, 3, 100_000);
                same_bits(&format!("{system} {sets:?} {}", algorithm.name()), &mut c, 7, true);
            }
        }
    }
}

/// The settings that reach the fallbacks and the windows' own rules: a tiny width (empty windows),
/// a narrow one (windows of one or two sets), replacing traces with Watkins's cut, a zero cutoff,
/// and a step size that overflows α·δ (a non-finite step: the literal per-trace pass, then
/// infinite parameters outside the windows, whose Q(s, ·) the grid sums would make NaN); and the
/// rule bases the dense path leaves to the windowed one: no prune (every set in the window, and
/// memberships that underflow to a zero normaliser) and wide sets (windows of more than four).
#[test]
fn dense_fuzzy_path_gives_the_windowed_paths_bits_in_every_fallback() {
    for system in [SystemKind::MountainCar, SystemKind::BallBeam] {
        for algorithm in [Algorithm::Q0, Algorithm::QLambda] {
            let base = || config(system, algorithm, [4, 3], 3, 8_000);
            let mut c = base();
            c.repr.prune = 0.0;
            same_bits("no prune", &mut c, 1, false);
            let mut c = base();
            c.repr.width = 0.02;
            same_bits("tiny width", &mut c, 2, true);
            let mut c = base();
            c.repr.width = 0.25;
            same_bits("narrow width", &mut c, 2, true);
            let mut c = base();
            c.repr.width = 1e-4;
            c.repr.prune = 0.0;
            same_bits("underflowing memberships", &mut c, 3, false);
            let mut c = base();
            c.repr.width = 3.0;
            same_bits("wide sets", &mut c, 4, false);
            let mut c = base();
            c.learner.traces = TraceKind::Replacing;
            c.learner.watkins_cut = true;
            c.learner.epsilon = 0.2;
            c.learner.trace_cutoff = 0.0;
            same_bits("replacing, watkins, no cutoff", &mut c, 5, true);
            let mut c = base();
            c.learner.alpha = 1e300;
            c.learner.q_init = 1e300;
            same_bits("overflowing step", &mut c, 6, true);
        }
    }
}
