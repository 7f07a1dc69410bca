//! Engine benchmark: the production trial loop ([`run_trial`]) run for a fixed step budget on a
//! standard set of configurations, timed, and reported as steps per second.
//!
//! Nothing here is a copy of the engine. A budget is imposed purely through a trial's limits (see
//! [`with_budget`]), so the measured code is exactly what a sweep runs: environment, representation,
//! learner, episode bookkeeping and all. `qsweep bench` and `cargo bench` both call [`run_cases`].
//! [`pipeline`] benchmarks the real work instead: a pipeline's costliest cells with their real seeds.

pub mod pipeline;

use qsweep_engine::config::{Success, TrialConfig};
use qsweep_engine::env::SystemKind;
use qsweep_engine::repr::ReprKind;
use qsweep_engine::{run_trial, Algorithm};
use serde::{Deserialize, Serialize};
use std::time::Instant;

/// Default step budget per run.
pub const DEFAULT_STEPS: u64 = 1_000_000;
/// Default number of timed runs per configuration (the fastest is kept).
pub const DEFAULT_REPEATS: u32 = 3;
/// Seed of every benchmark trial (any fixed seed would do: a trial's cost depends on its episodes).
pub const SEED: u64 = 0;

/// One benchmark configuration: a name and the trial it runs (before the budget is applied).
#[derive(Debug, Clone)]
pub struct BenchCase {
    /// `system/repr/algorithm/resolution/actions`, e.g. `cart-pole/fuzzy/q-lambda/4^4/2a`.
    pub name: String,
    /// The paper's configuration for that cell.
    pub config: TrialConfig,
}

/// The measured speed of one configuration.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BenchResult {
    /// The case name.
    pub config: String,
    /// Steps run by one timed trial.
    pub steps: u64,
    /// Wall-clock seconds of the fastest timed trial.
    pub seconds: f64,
    /// `steps / seconds`.
    pub steps_per_s: f64,
}

/// The standard set: every system × crisp/fuzzy × Q(0)/Q(λ), at a coarse and a fine resolution
/// (crisp 2 and 10 bins per variable; fuzzy 2, 4 and 10 sets per variable), with the system's own
/// action count, plus the finest resolution with 10 actions (the paper's largest action set).
pub fn standard_cases() -> Vec<BenchCase> {
    let mut out = Vec::new();
    for system in SystemKind::ALL {
        for repr in [ReprKind::Crisp, ReprKind::Fuzzy] {
            for algorithm in [Algorithm::Q0, Algorithm::QLambda] {
                let resolutions: &[u32] = match repr {
                    ReprKind::Crisp => &[2, 10],
                    ReprKind::Fuzzy => &[2, 4, 10],
                };
                let mut cells: Vec<(u32, u32)> =
                    resolutions.iter().map(|&r| (r, system.default_actions())).collect();
                cells.push((10, 10));
                for (res, actions) in cells {
                    let dim = system.dim();
                    let name =
                        format!("{system}/{}/{}/{res}^{dim}/{actions}a", repr.name(), algorithm.name());
                    let config = TrialConfig::paper(system, repr, algorithm, vec![res; dim], actions);
                    out.push(BenchCase { name, config });
                }
            }
        }
    }
    out
}

/// `cfg` with limits that make [`run_trial`] run at least `steps` steps (and fewer than `2 · steps`)
/// whatever happens: the learning goal is made unreachable or too far away to matter, episodes are
/// capped at `steps`, and the trial stops at the first episode end past `steps` in total.
/// `steps` must be in `1..=u32::MAX`.
pub fn with_budget(mut cfg: TrialConfig, steps: u64) -> TrialConfig {
    assert!((1..=u64::from(u32::MAX)).contains(&steps), "step budget out of range");
    cfg.limits.max_episodes = u32::MAX;
    cfg.limits.max_total_steps = steps;
    cfg.limits.success = match cfg.limits.success {
        // Balancing for the whole budget ends the trial, which is also the budget.
        Success::Balance { .. } => Success::Balance { steps },
        // Reaching the goal in one step is impossible and an endless streak never completes.
        Success::Reach { .. } => Success::Reach { within: 1, streak: u32::MAX, max_episode_steps: steps },
        // A window of u32::MAX episodes is never full.
        Success::Solved { mean_length, .. } => {
            Success::Solved { window: u32::MAX, mean_length, episode_steps: steps }
        }
    };
    cfg
}

/// Time the cases whose name contains `filter` (all if empty): each runs `repeats` times on a
/// budget of `steps`, keeping the fastest run (the least disturbed by other processes).
/// `on_result` sees each result as soon as it is measured.
pub fn run_cases(
    cases: &[BenchCase],
    filter: &str,
    steps: u64,
    repeats: u32,
    mut on_result: impl FnMut(&BenchResult),
) -> Vec<BenchResult> {
    let mut out = Vec::new();
    for case in cases.iter().filter(|c| c.name.contains(filter)) {
        let cfg = with_budget(case.config.clone(), steps);
        let mut best: Option<(u64, f64)> = None;
        for _ in 0..repeats.max(1) {
            let start = Instant::now();
            let outcome = run_trial(&cfg, SEED);
            let seconds = start.elapsed().as_secs_f64();
            if best.is_none_or(|(_, s)| seconds < s) {
                best = Some((outcome.total_steps, seconds));
            }
        }
        let (steps, seconds) = best.expect("at least one run");
        let r = BenchResult {
            config: case.name.clone(),
            steps,
            seconds,
            steps_per_s: steps as f64 / seconds.max(1e-12),
        };
        on_result(&r);
        out.push(r);
    }
    out
}

/// One aligned text line for a result (the table `qsweep bench` and `cargo bench` print).
pub fn format_row(r: &BenchResult) -> String {
    format!("{:<40} {:>11} {:>9.3} {:>12.3}", r.config, r.steps, r.seconds, r.steps_per_s / 1e6)
}

/// The header matching [`format_row`].
pub fn header() -> String {
    format!("{:<40} {:>11} {:>9} {:>12}", "config", "steps", "seconds", "M steps/s")
}

#[cfg(test)]
mod tests {
    use super::*;
    use qsweep_engine::StopReason;

    #[test]
    fn standard_set_covers_every_system_repr_and_algorithm_and_is_valid() {
        let cases = standard_cases();
        for system in SystemKind::ALL {
            for repr in ["crisp", "fuzzy"] {
                for alg in ["q0", "q-lambda"] {
                    let prefix = format!("{system}/{repr}/{alg}/");
                    assert!(cases.iter().filter(|c| c.name.starts_with(&prefix)).count() >= 3, "{prefix}");
                }
            }
        }
        for name in ["cart-pole/crisp/q0/2^4/2a", "cart-pole/crisp/q-lambda/10^4/2a"] {
            assert!(cases.iter().any(|c| c.name == name), "{name}");
        }
        for name in ["cart-pole/fuzzy/q-lambda/4^4/2a", "cart-pole/fuzzy/q-lambda/10^4/10a"] {
            assert!(cases.iter().any(|c| c.name == name), "{name}");
        }
        let mut names: Vec<_> = cases.iter().map(|c| &c.name).collect();
        names.sort();
        names.dedup();
        assert_eq!(names.len(), cases.len(), "names are unique");
        for c in &cases {
            with_budget(c.config.clone(), 1000).validate().unwrap();
        }
    }

    #[test]
    fn budget_runs_between_one_and_two_budgets_of_steps() {
        for case in standard_cases().iter().filter(|c| c.name.contains("/2^") || c.name.contains("/q0/2")) {
            let o = run_trial(&with_budget(case.config.clone(), 3_000), SEED);
            assert!((3_000..6_000).contains(&o.total_steps), "{}: {}", case.name, o.total_steps);
            assert!(matches!(o.stop, StopReason::MaxTotalSteps | StopReason::Goal), "{}", case.name);
        }
    }

    #[test]
    fn run_cases_filters_and_reports_every_case() {
        let mut seen = 0;
        let r = run_cases(&standard_cases(), "ball-beam/crisp/q0/2^2", 500, 2, |_| seen += 1);
        assert_eq!((r.len(), seen), (1, 1));
        assert!(r[0].steps >= 500 && r[0].steps_per_s > 0.0);
        assert!(format_row(&r[0]).starts_with("ball-beam/crisp/q0/2^2/3a"));
    }
}
