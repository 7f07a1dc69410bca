//! Expanding a typed pipeline into a [`Plan`]: layering settings, building each cell's
//! `TrialConfig`, validating it, and keying its trials.

use super::{Cell, Experiment, Plan, PlannedTrial};
use crate::cache::Key;
use crate::error::user_error;
use crate::sim::config::{default_ranges, default_success, Success, TrialConfig};
use crate::sim::env::{EnvParams, SystemKind};
use crate::spec::{
    BalanceSpec, ExperimentSpec, LoadedSpec, PipelineSpec, ReachSpec, Settings, SystemMarker, SystemSpec,
    Target,
};
use crate::spec::{BallBeamM, CartPoleM, MountainCarM};

/// Plans larger than this many trials need confirmation (`--yes`).
pub const DEFAULT_MAX_TRIALS: usize = 200_000;

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
        let s = s.cloned().unwrap_or(ReachSpec { within: None, streak: None, max_episode_steps: None });
        Success::Reach {
            within: s.within.unwrap_or(within),
            streak: s.streak.map_or(streak, |v| v.min(u64::from(u32::MAX)) as u32),
            max_episode_steps: s.max_episode_steps.unwrap_or(max_episode_steps),
        }
    }
}

fn balance(system: SystemKind, s: Option<&BalanceSpec>) -> Success {
    match s {
        Some(b) => Success::Balance { steps: b.steps },
        None => default_success(system),
    }
}

impl Settings {
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

/// Expand a loaded pipeline into a plan. Fails (as a user error naming the file) if a resolved
/// configuration is invalid or the plan exceeds `max_trials`.
pub fn plan(loaded: &LoadedSpec, max_trials: Option<usize>) -> anyhow::Result<Plan> {
    let spec = &loaded.spec;
    let origin = loaded.path.display().to_string();
    if let Some(limit) = max_trials {
        // Counted from the spec, before any configuration is built or hashed, so an accidental
        // huge grid is refused at once.
        let n = planned_trials(spec);
        if n > limit as u128 {
            return Err(too_many(&origin, n, limit));
        }
    }
    let mut experiments = Vec::new();
    let s = &spec.systems;
    if let Some(sys) = &s.ball_beam {
        expand(spec, sys, &origin, &mut experiments)?;
    }
    if let Some(sys) = &s.cart_pole {
        expand(spec, sys, &origin, &mut experiments)?;
    }
    if let Some(sys) = &s.mountain_car {
        expand(spec, sys, &origin, &mut experiments)?;
    }
    let plan = Plan {
        name: spec.name.clone(),
        description: spec.description.clone(),
        source: loaded.path.clone(),
        reference_source: spec.reference_source.clone(),
        seeds: spec.seeds.0.clone(),
        experiments,
    };
    Ok(plan)
}

fn too_many(origin: &str, n: u128, limit: usize) -> anyhow::Error {
    user_error(format!(
        "{origin}: the plan has {n} trials, more than the confirmation limit of {limit}; \
         rerun with --yes if this is intended, or shrink the grid or the seeds"
    ))
}

/// Trials the spec expands to (cells × seeds), without building anything.
fn planned_trials(spec: &PipelineSpec) -> u128 {
    fn system<M: SystemMarker>(s: &Option<SystemSpec<M>>) -> u128 {
        s.iter()
            .flat_map(|s| &s.experiments)
            .map(|e| {
                e.axes.iter().map(|a| a.values.len() as u128).product::<u128>() * e.algorithms.len() as u128
            })
            .sum()
    }
    let cells = system(&spec.systems.ball_beam)
        + system(&spec.systems.cart_pole)
        + system(&spec.systems.mountain_car);
    cells * spec.seeds.0.len() as u128
}

fn expand<M: Resolve>(
    spec: &PipelineSpec,
    sys: &SystemSpec<M>,
    origin: &str,
    out: &mut Vec<Experiment>,
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
        out.push(expand_experiment(spec, sys, e, &env, &ranges, &success, origin, idx)?);
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
    origin: &str,
    idx: usize,
) -> anyhow::Result<Experiment> {
    let system = M::SYSTEM;
    let mut fixed = e.fixed.clone();
    let actions_varied = e.axes.iter().any(|a| a.targets.contains(&Target::Actions));
    if !actions_varied && !fixed.iter().any(|(t, _)| *t == Target::Actions) {
        fixed.push((Target::Actions, system.default_actions()));
    }
    let repr_settings = match e.repr {
        crate::sim::repr::ReprKind::Crisp => &sys.crisp,
        crate::sim::repr::ReprKind::Fuzzy => &sys.fuzzy,
    };
    let grid = grid_points(&e.axes.iter().map(|a| a.values.len()).collect::<Vec<_>>());
    let mut cells = Vec::with_capacity(grid.len() * e.algorithms.len());
    for &algorithm in &e.algorithms {
        for point in &grid {
            let coords: Vec<u32> = e.axes.iter().zip(point).map(|(a, &i)| a.values[i]).collect();
            let mut resolution = vec![0u32; system.dim()];
            let mut actions = 0;
            let assignments = fixed
                .iter()
                .copied()
                .chain(e.axes.iter().zip(&coords).flat_map(|(a, &v)| a.targets.iter().map(move |&t| (t, v))));
            for (t, v) in assignments {
                match t {
                    Target::Var(j) => resolution[j] = v,
                    Target::Actions => actions = v,
                }
            }
            let mut c = TrialConfig::paper(system, e.repr, algorithm, resolution, actions);
            c.env = env.clone();
            c.repr.ranges = ranges.to_vec();
            c.limits.success = success.clone();
            for level in [&spec.defaults, &sys.settings, repr_settings, &e.settings] {
                level.apply(&mut c);
            }
            c.normalize();
            c.validate().map_err(|msg| {
                user_error(format!(
                    "{origin}: systems.{system}.experiments[{idx}] (id {}), {} at {}: {msg}",
                    e.id,
                    algorithm.name(),
                    coords.iter().map(u32::to_string).collect::<Vec<_>>().join("×")
                ))
            })?;
            let trials =
                spec.seeds.0.iter().map(|&seed| PlannedTrial { seed, key: Key::of(&c, seed) }).collect();
            cells.push(Cell { algorithm, coords, config: c, trials });
        }
    }
    Ok(Experiment {
        system,
        id: e.id.clone(),
        title: e.title.clone(),
        repr: e.repr,
        algorithms: e.algorithms.clone(),
        axes: e.axes.clone(),
        fixed,
        reference: e.reference.clone(),
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
    use crate::spec::load_str;

    fn plan_of(text: &str) -> Plan {
        let spec = load_str(text, "test.yaml", &[]).unwrap();
        plan(&LoadedSpec { spec, path: "test.yaml".into() }, None).unwrap()
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
}
