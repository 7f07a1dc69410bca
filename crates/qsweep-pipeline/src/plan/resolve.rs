//! Expanding a typed pipeline into the experiments of a [`super::Plan`]: layering settings,
//! building each cell's `TrialConfig`, validating it, and keying its trials.

use super::keys::KeyMemo;
use super::resolved::{Cell, Experiment};
use crate::declared::{each_system, BallBeamM, CartPoleM, MountainCarM};
use crate::declared::{
    format_value, BalanceSpec, ExperimentSpec, PipelineSpec, ReachSpec, Settings, SystemMarker, SystemSpec,
    Target,
};
use crate::error::user_error;
use qsweep_engine::config::{default_ranges, default_success, Success, TrialConfig};
use qsweep_engine::env::{EnvParams, SystemKind};
use qsweep_engine::Algorithm;
use rayon::prelude::*;

/// How a system's typed sections become resolved values.
trait Resolve: SystemMarker {
    fn success(s: Option<&Self::Success>) -> Success;
}

impl Resolve for BallBeamM {
    fn success(s: Option<&BalanceSpec>) -> Success {
        balance(Self::SYSTEM, s)
    }
}

impl Resolve for CartPoleM {
    fn success(s: Option<&BalanceSpec>) -> Success {
        balance(Self::SYSTEM, s)
    }
}

impl Resolve for MountainCarM {
    fn success(s: Option<&ReachSpec>) -> Success {
        let Success::Reach { within, streak, max_episode_steps } = default_success(Self::SYSTEM) else {
            unreachable!("mountain car is goal-reaching")
        };
        let s = s.cloned().unwrap_or_default();
        let max_episode_steps = s.max_episode_steps.unwrap_or(max_episode_steps);
        if let (Some(window), Some(mean_length)) = (s.window, s.mean_length) {
            return Success::Solved { window, mean_length: mean_length.0, episode_steps: max_episode_steps };
        }
        Success::Reach {
            within: s.within.unwrap_or(within),
            streak: s.streak.map_or(streak, |v| v.min(u64::from(u32::MAX)) as u32),
            max_episode_steps,
        }
    }
}

fn balance(system: SystemKind, s: Option<&BalanceSpec>) -> Success {
    match s {
        Some(BalanceSpec { steps, window: Some(window), mean_length: Some(mean_length) }) => {
            Success::Solved { window: *window, mean_length: mean_length.0, episode_steps: *steps }
        }
        Some(b) => Success::Balance { steps: b.steps },
        None => default_success(system),
    }
}

impl Settings {
    /// Take every value `other` sets (generic over the fields, so new settings need no code here).
    pub fn merge(&mut self, other: &Settings) {
        let (Ok(serde_yaml::Value::Mapping(mut mine)), Ok(serde_yaml::Value::Mapping(theirs))) =
            (serde_yaml::to_value(&*self), serde_yaml::to_value(other))
        else {
            unreachable!("settings serialise to a mapping")
        };
        mine.retain(|_, v| !v.is_null());
        for (k, v) in theirs {
            if !v.is_null() {
                mine.insert(k, v);
            }
        }
        *self = serde_yaml::from_value(serde_yaml::Value::Mapping(mine)).expect("merged settings stay valid");
    }

    /// Overwrite the configuration's values with the ones this level sets.
    pub fn apply(&self, c: &mut TrialConfig) {
        let l = &mut c.learner;
        if let Some(v) = self.epsilon {
            l.epsilon = v.0;
        }
        if let Some(v) = self.gamma {
            l.gamma = v.0;
        }
        if let Some(v) = self.alpha {
            l.alpha = v.0;
        }
        if let Some(v) = self.lambda {
            l.lambda = v.0;
        }
        if let Some(v) = self.q_init {
            l.q_init = v.0;
        }
        if let Some(v) = self.tie_break {
            l.tie_break = v;
        }
        if let Some(v) = self.traces {
            l.traces = v;
        }
        if let Some(v) = self.watkins_cut {
            l.watkins_cut = v;
        }
        if let Some(v) = self.trace_cutoff {
            l.trace_cutoff = v.0;
        }
        if let Some(v) = self.width {
            c.repr.width = v.0;
        }
        if let Some(v) = self.prune {
            c.repr.prune = v.0;
        }
        if let Some(v) = self.max_episodes {
            c.limits.max_episodes = v;
        }
        if let Some(v) = self.max_total_steps {
            c.limits.max_total_steps = v;
        }
        if let Some(v) = self.truncation {
            c.limits.truncation = v;
        }
        if let Some(v) = self.start {
            c.start = v;
        }
        if let Some(v) = self.binning {
            c.repr.binning = v;
        }
    }
}

/// Expand every system of `spec`, tagging the experiments with `variant`.
pub(super) fn expand_all(
    spec: &PipelineSpec,
    origin: &str,
    variant: Option<&str>,
    out: &mut Vec<Experiment>,
    memo: &KeyMemo,
) -> anyhow::Result<()> {
    let first = out.len();
    each_system!(&spec.systems, |sys| expand(spec, sys, origin, out, memo)?);
    for e in &mut out[first..] {
        e.variant = variant.map(str::to_string);
    }
    Ok(())
}

fn expand<M: Resolve>(
    spec: &PipelineSpec,
    sys: &SystemSpec<M>,
    origin: &str,
    out: &mut Vec<Experiment>,
    memo: &KeyMemo,
) -> anyhow::Result<()> {
    let system = M::SYSTEM;
    let mut ranges = default_ranges(system);
    for (j, r) in &sys.ranges.entries {
        ranges[*j] = *r;
    }
    let env = M::env(&sys.params);
    for (idx, e) in sys.experiments.iter().enumerate() {
        let mut ranges = ranges.clone();
        for (j, r) in &e.ranges.entries {
            ranges[*j] = *r;
        }
        let success = M::success(e.success.as_ref().or(sys.success.as_ref()));
        out.push(expand_experiment(spec, sys, e, &env, &ranges, &success, (origin, idx), memo)?);
    }
    Ok(())
}

#[allow(clippy::too_many_arguments)]
fn expand_experiment<M: Resolve>(
    spec: &PipelineSpec,
    sys: &SystemSpec<M>,
    e: &ExperimentSpec<M>,
    env: &EnvParams,
    ranges: &[[f64; 2]],
    success: &Success,
    (origin, idx): (&str, usize),
    memo: &KeyMemo,
) -> anyhow::Result<Experiment> {
    let system = M::SYSTEM;
    let mut fixed = e.fixed.clone();
    let actions_varied = e.axes.iter().any(|a| a.targets.contains(&Target::Actions));
    if !actions_varied && !fixed.iter().any(|(t, _)| *t == Target::Actions) {
        fixed.push((Target::Actions, system.default_actions()));
    }
    let repr_settings = match e.repr {
        qsweep_engine::repr::ReprKind::Crisp => &sys.crisp,
        qsweep_engine::repr::ReprKind::Fuzzy => &sys.fuzzy,
    };
    let grid = grid_points(&e.axes.iter().map(|a| a.values.len()).collect::<Vec<_>>());
    let points: Vec<(Algorithm, &Vec<usize>)> =
        e.algorithms.iter().flat_map(|&a| grid.iter().map(move |p| (a, p))).collect();
    // Cells are resolved, and their trials keyed (one blake3 per trial), in parallel; the first
    // error in grid order is the one reported, whatever the number of threads.
    let resolved: Vec<anyhow::Result<Cell>> = points
        .par_iter()
        .map(|&(algorithm, point)| -> anyhow::Result<Cell> {
            let coords: Vec<f64> = e.axes.iter().zip(point).map(|(a, &i)| a.values[i]).collect();
            let at = || coords.iter().map(|&v| format_value(v)).collect::<Vec<_>>().join("×");
            let fail = |msg: String| {
                user_error(format!(
                    "{origin}: systems.{system}.experiments[{idx}] (id {}), {} at {}: {msg}",
                    e.id,
                    algorithm.name(),
                    at()
                ))
            };
            let mut resolution = vec![0u32; system.dim()];
            let mut actions = 0;
            let assignments = fixed
                .iter()
                .map(|&(t, v)| (t, f64::from(v)))
                .chain(e.axes.iter().zip(&coords).flat_map(|(a, &v)| a.targets.iter().map(move |&t| (t, v))));
            let mut axis_level = Settings::default();
            let mut axis_params = Vec::new();
            for (t, v) in assignments {
                // Count targets were checked to be whole numbers while parsing.
                match t {
                    Target::Var(j) => resolution[j] = v as u32,
                    Target::Actions => actions = v as u32,
                    Target::Setting(name) => {
                        let one = crate::declared::setting_level(name, v)
                            .map_err(|m| fail(format!("vary.{name}: {m}")))?;
                        axis_level.merge(&one);
                    }
                    Target::Param(name) => axis_params.push((name, v)),
                }
            }
            let mut c = TrialConfig::paper(system, e.repr, algorithm, resolution, actions);
            c.env = env.clone();
            for (name, v) in axis_params {
                c.env.set_param(name, v).map_err(|m| fail(format!("params.{name}: {m}")))?;
            }
            c.env.validate().map_err(|m| fail(format!("params: {m}")))?;
            c.repr.ranges = ranges.to_vec();
            c.limits.success = success.clone();
            // An axis over settings is the innermost level: it overrides every `settings:` section.
            // Its values pass through the same typed, range-checked parse as a settings section.
            for level in [&spec.defaults, &sys.settings, repr_settings, &e.settings, &axis_level] {
                level.apply(&mut c);
            }
            c.normalize();
            c.validate().map_err(fail)?;
            // One canonical encoding per cell, hashed once per seed (planning many variants stays fast).
            let canonical = crate::cache::key::canonical_config(&c);
            let trials = memo.trials(&canonical, &spec.seeds.0);
            Ok(Cell { algorithm, coords, config: c, trials, contender: None, fresh: Vec::new() })
        })
        .collect();
    let cells = resolved.into_iter().collect::<anyhow::Result<Vec<Cell>>>()?;
    Ok(Experiment {
        variant: None,
        system,
        id: e.id.clone(),
        title: e.title.clone(),
        repr: e.repr,
        algorithms: e.algorithms.clone(),
        axes: e.axes.clone(),
        fixed,
        counting: spec.counting,
        reference: e.reference.clone(),
        race: e.race.or(spec.race),
        fresh: spec.fresh.and_then(|f| f.seed_list()),
        cells,
    })
}

/// Every index tuple of a grid with the given axis lengths, last axis fastest.
fn grid_points(lens: &[usize]) -> Vec<Vec<usize>> {
    let mut out = vec![vec![]];
    for &n in lens {
        out = out.into_iter().flat_map(|p| (0..n).map(move |i| [p.clone(), vec![i]].concat())).collect();
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::declared::{load_str, LoadedSpec};
    use crate::plan::{plan, Plan};

    fn plan_of(text: &str) -> Plan {
        let spec = load_str(text, "test.yaml", &[]).unwrap();
        plan(&LoadedSpec { spec, path: "test.yaml".into(), variants: Vec::new() }, None).unwrap()
    }

    #[test]
    fn settings_ranges_and_success_layer_from_system_to_experiment() {
        let p = plan_of(
            "name: t\nseeds: [3, 9]\ndefaults: { alpha: 0.2, max_episodes: 7 }\nsystems:\n  cart-pole:\n    ranges: { x_dot: [-1, 1] }\n    success: { steps: 500 }\n    crisp: { alpha: 0.3 }\n    experiments:\n      - { id: a, repr: crisp, vary: { x == theta: [2, 3], x_dot == theta_dot: 4 } }\n      - { id: b, repr: crisp, algorithms: [q0], vary: { x == x_dot == theta == theta_dot: 2, actions: 2..4 }, ranges: { theta_dot: [-5, 5] }, success: { steps: 9 }, settings: { alpha: 0.4 } }\n",
        );
        let (a, b) = (&p.experiments[0], &p.experiments[1]);
        assert_eq!(a.cells.len(), 2 * 2);
        assert_eq!(b.cells.len(), 3);
        let ca = &a.cells[1].config;
        assert_eq!(ca.repr.resolution, vec![3, 4, 3, 4]);
        assert_eq!(ca.actions, 2, "the paper's fixed Cart-Pole set");
        assert_eq!(ca.learner.alpha, 0.3);
        assert_eq!(ca.limits.max_episodes, 7);
        assert_eq!(ca.repr.ranges[1], [-1.0, 1.0]);
        assert_eq!(ca.limits.success, Success::Balance { steps: 500 });
        let cb = &b.cells[2].config;
        assert_eq!((cb.repr.resolution.clone(), cb.actions), (vec![2; 4], 4));
        assert_eq!(cb.learner.alpha, 0.4);
        assert_eq!(cb.learner.lambda, 0.0, "Q(0) normalises lambda away");
        assert_eq!((cb.repr.ranges[1], cb.repr.ranges[3]), ([-1.0, 1.0], [-5.0, 5.0]));
        assert_eq!(cb.limits.success, Success::Balance { steps: 9 });
        assert_eq!(a.cells[0].trials.iter().map(|t| t.seed).collect::<Vec<_>>(), vec![3, 9]);
        assert_eq!(p.unique_trials().len(), p.trial_count());
    }

    #[test]
    fn setting_and_parameter_axes_set_their_field_over_every_settings_level() {
        let p = plan_of(
            "name: t\nseeds: 1\nsystems:\n  cart-pole:\n    crisp: { alpha: 0.3, q_init: 5 }\n    experiments:\n      - { id: a, repr: crisp, algorithms: [q-lambda], vary: { alpha: [0.05, 0.2], q_init: [-1, 0] }, fixed: { x == x_dot == theta == theta_dot: 3 }, settings: { alpha: 0.4 } }\n      - { id: b, repr: fuzzy, algorithms: [q0], vary: { x == theta: [2, 3], gravity: [9.8, 9.81] }, fixed: { x_dot: 2, theta_dot: 2, actions: 3 } }\n      - { id: c, repr: crisp, algorithms: [q0], vary: { max_episodes: 10..11 }, fixed: { x: 2, x_dot: 2, theta: 2, theta_dot: 2 } }\n",
        );
        let a = &p.experiments[0];
        let got: Vec<(Vec<f64>, f64, f64)> = a
            .cells
            .iter()
            .map(|c| (c.coords.clone(), c.config.learner.alpha, c.config.learner.q_init))
            .collect();
        assert_eq!(
            got,
            vec![
                (vec![0.05, -1.0], 0.05, -1.0),
                (vec![0.05, 0.0], 0.05, 0.0),
                (vec![0.2, -1.0], 0.2, -1.0),
                (vec![0.2, 0.0], 0.2, 0.0)
            ]
        );
        assert!(a.cells.iter().all(|c| c.config.repr.resolution == vec![3; 4] && c.config.actions == 2));
        assert_eq!(a.axes[0].label, "alpha");
        let b = &p.experiments[1];
        let g: Vec<f64> = b
            .cells
            .iter()
            .map(|c| match &c.config.env {
                qsweep_engine::env::EnvParams::CartPole(p) => p.gravity,
                _ => unreachable!(),
            })
            .collect();
        assert_eq!(g, vec![9.8, 9.81, 9.8, 9.81]);
        assert_eq!(b.cells[2].config.repr.resolution, vec![3, 2, 3, 2]);
        let c = &p.experiments[2];
        assert_eq!(c.cells.iter().map(|c| c.config.limits.max_episodes).collect::<Vec<_>>(), vec![10, 11]);
        // The same configuration reached through an axis or through a settings section has one key.
        let q = plan_of(
            "name: t\nseeds: 1\nsystems:\n  cart-pole:\n    experiments:\n      - { id: a, repr: crisp, algorithms: [q-lambda], vary: { actions: 2 }, fixed: { x == x_dot == theta == theta_dot: 3 }, settings: { alpha: 0.2, q_init: 0 } }\n",
        );
        assert_eq!(q.experiments[0].cells[0].trials[0].key, a.cells[3].trials[0].key);
    }
}
