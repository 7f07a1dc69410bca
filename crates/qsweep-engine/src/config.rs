//! The fully resolved configuration of one trial: every value the simulation reads, nothing
//! implicit. Pipelines expand to these; the cache key hashes their canonical JSON encoding.

use super::env::{
    with_env_type, BeamControl, EnvParams, Environment, StartKind, SystemKind, TaskKind,
    BALL_BEAM_DEFAULT_RATE_MAX,
};
use super::repr::{Binning, ReprKind};
use super::rules;
use serde::{Deserialize, Serialize};

/// Q(0) or Q(λ).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
pub enum Algorithm {
    /// One-step Q-learning, eqs. (4)–(5) / (19).
    #[serde(rename = "q0")]
    Q0,
    /// Q(λ) with eligibility traces, eqs. (6)–(7) / (20)–(21).
    #[serde(rename = "q-lambda")]
    QLambda,
}

impl Algorithm {
    /// Command-line / YAML name.
    pub fn name(self) -> &'static str {
        match self {
            Self::Q0 => "q0",
            Self::QLambda => "q-lambda",
        }
    }

    /// Short label, `Q(0)` or `Q(λ)` (for tables whose caption names the representation).
    pub fn symbol(self) -> &'static str {
        match self {
            Self::Q0 => "Q(0)",
            Self::QLambda => "Q(λ)",
        }
    }

    /// Label as the paper writes it.
    pub fn label(self, repr: ReprKind) -> &'static str {
        match (repr, self) {
            (ReprKind::Crisp, Self::Q0) => "Q(0)-learning",
            (ReprKind::Crisp, Self::QLambda) => "Q(λ)-learning",
            (ReprKind::Fuzzy, Self::Q0) => "Fuzzy Q(0)-learning",
            (ReprKind::Fuzzy, Self::QLambda) => "Fuzzy Q(λ)-learning",
        }
    }
}

/// How greedy ties between equal Q-values are broken.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
#[serde(rename_all = "kebab-case")]
pub enum TieBreak {
    /// Uniformly at random among the tied actions (uses the trial's random stream).
    Random,
    /// The tied action with the lowest index (the most negative action value).
    First,
}

/// Eligibility-trace increment rule.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum TraceKind {
    /// e ← γλe + w (eqs. 7 and 20).
    Accumulating,
    /// e ← max(γλe, w): a crisp trace is reset to 1 instead of growing.
    Replacing,
}

/// The state representation of one trial.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ReprConfig {
    /// Crisp bins or fuzzy sets.
    pub kind: ReprKind,
    /// Bins or fuzzy sets per state variable, in state order.
    pub resolution: Vec<u32>,
    /// `[lo, hi]` per state variable: bin range, or first and last fuzzy centre.
    pub ranges: Vec<[f64; 2]>,
    /// Fuzzy only: σ = width × centre spacing (0 for crisp).
    pub width: f64,
    /// Fuzzy only: memberships below this are skipped (0 = exact; 0 for crisp).
    pub prune: f64,
    /// Crisp only: where the bin edges lie (midpoint for fuzzy). Left out of the canonical JSON
    /// when it is the default, so configurations from before the setting keep their keys.
    #[serde(default, skip_serializing_if = "Binning::is_default")]
    pub binning: Binning,
}

/// Learning rule and its hyperparameters (Table II).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LearnerConfig {
    /// Q(0) or Q(λ).
    pub algorithm: Algorithm,
    /// Exploration rate ε.
    pub epsilon: f64,
    /// Discount γ.
    pub gamma: f64,
    /// Learning rate α.
    pub alpha: f64,
    /// Trace decay λ (0 for Q(0)).
    pub lambda: f64,
    /// Initial value of every Q parameter.
    pub q_init: f64,
    /// Greedy tie-breaking.
    pub tie_break: TieBreak,
    /// Trace increment rule (accumulating for Q(0), where it is irrelevant).
    pub traces: TraceKind,
    /// Watkins's Q(λ): clear the traces after an exploratory action (false for Q(0)).
    pub watkins_cut: bool,
    /// Traces below this are dropped from the active list (0 for Q(0)).
    pub trace_cutoff: f64,
}

/// When an episode and a trial end, and what counts as reaching the learning goal.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "kebab-case")]
pub enum Success {
    /// Survival tasks: an episode of `steps` steps without failure is the goal (the paper's 100,000).
    Balance {
        /// Steps without failure that end the trial successfully.
        steps: u64,
    },
    /// Goal tasks: `streak` consecutive episodes each reaching the goal within `within` steps.
    Reach {
        /// Largest episode length that counts as a success.
        within: u64,
        /// Consecutive successful episodes needed.
        streak: u32,
        /// Episodes still short of the goal after this many steps are cut off.
        max_episode_steps: u64,
    },
    /// Gym's "solved" rule, either task kind ([`super::solved`]): the goal is the first episode
    /// E ≥ `window` whose last `window` episodes have a mean length ≥ `mean_length` (survival
    /// tasks: CartPole's return is the episode length) or ≤ `mean_length` (goal tasks:
    /// MountainCar's return is −length, a cut-off episode counting at its cut length). Episodes
    /// are cut at `episode_steps`, an ordinary truncated episode: reaching the cut does not end
    /// the trial.
    Solved {
        /// Consecutive episodes the mean is taken over (Gym: 100).
        window: u32,
        /// The threshold on the window's mean episode length (CartPole-v0: 195; MountainCar-v0: 110).
        mean_length: f64,
        /// Episodes are cut off after this many steps (CartPole-v0 and MountainCar-v0: 200).
        episode_steps: u64,
    },
}

impl Success {
    /// The solved rule's window, `None` under any other criterion.
    pub fn solved_window(&self) -> Option<u32> {
        match self {
            Self::Solved { window, .. } => Some(*window),
            _ => None,
        }
    }
}

/// What the learner does with the last transition of an episode cut off by the episode step limit
/// (Mountain Car's `max_episode_steps`; a TimeLimit in Gymnasium's terms).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Truncation {
    /// The cut is not an end of the task: δ = r + γ max Q(s′, ·) − Q(s, a), as for any other step.
    #[default]
    Bootstrap,
    /// The cut is treated as terminal: δ = r − Q(s, a), as code that learns from gym's `done` does.
    Terminal,
}

impl Truncation {
    /// Whether this is the default (left out of the canonical JSON).
    pub fn is_default(&self) -> bool {
        *self == Self::default()
    }
}

/// Caps and success criterion of a trial.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Limits {
    /// Learning-goal criterion.
    pub success: Success,
    /// Most episodes a trial runs.
    pub max_episodes: u32,
    /// Most steps a trial runs (checked at episode ends).
    pub max_total_steps: u64,
    /// How an episode cut off at the step limit is learned from. Left out of the canonical JSON
    /// when it is the default, so configurations from before the setting keep their keys.
    #[serde(default, skip_serializing_if = "Truncation::is_default")]
    pub truncation: Truncation,
}

impl Limits {
    /// Longest possible episode.
    pub fn episode_cap(&self) -> u64 {
        match self.success {
            Success::Balance { steps } => steps,
            Success::Reach { max_episode_steps, .. } => max_episode_steps,
            Success::Solved { episode_steps, .. } => episode_steps,
        }
    }
}

/// Everything one trial needs except its seed.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TrialConfig {
    /// System and its physical parameters.
    pub env: EnvParams,
    /// State representation.
    pub repr: ReprConfig,
    /// Number of actions n of A_n (eq. 22).
    pub actions: u32,
    /// Learning rule.
    pub learner: LearnerConfig,
    /// Caps and success criterion.
    pub limits: Limits,
    /// Where episodes start: the fixed start state or Gymnasium's `reset()` distribution. Left out
    /// of the canonical JSON when it is the default, so older configurations keep their keys.
    #[serde(default, skip_serializing_if = "StartKind::is_default")]
    pub start: StartKind,
}

/// Table II hyperparameters.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Hyper {
    /// ε.
    pub epsilon: f64,
    /// γ.
    pub gamma: f64,
    /// α.
    pub alpha: f64,
    /// λ.
    pub lambda: f64,
}

/// Table II of the paper.
pub fn table2(system: SystemKind, repr: ReprKind) -> Hyper {
    let h = |epsilon, gamma, alpha, lambda| Hyper { epsilon, gamma, alpha, lambda };
    match (system, repr) {
        (SystemKind::BallBeam, ReprKind::Crisp) => h(1e-6, 0.9, 0.1, 0.9),
        (SystemKind::BallBeam, ReprKind::Fuzzy) => h(1e-6, 0.995, 0.1, 0.5),
        (SystemKind::CartPole, _) => h(1e-2, 0.995, 0.1, 0.5),
        (SystemKind::MountainCar, _) => h(5e-2, 0.95, 0.01, 0.6),
    }
}

/// Default state ranges per system (the paper gives only some; see the replication notes).
pub fn default_ranges(system: SystemKind) -> Vec<[f64; 2]> {
    match system {
        SystemKind::BallBeam => vec![[-1.0, 1.0], [-1.0, 1.0]],
        SystemKind::CartPole => {
            let theta = 12.0 * 2.0 * std::f64::consts::PI / 360.0;
            vec![[-2.4, 2.4], [-2.0, 2.0], [-theta, theta], [-2.0, 2.0]]
        }
        SystemKind::MountainCar => vec![[-1.2, 0.5], [-0.07, 0.07]],
    }
}

/// Default success criterion per system.
pub fn default_success(system: SystemKind) -> Success {
    match TaskKind::of(system) {
        TaskKind::Survival => Success::Balance { steps: 100_000 },
        TaskKind::GoalReaching => Success::Reach { within: 200, streak: 1, max_episode_steps: 10_000 },
    }
}

/// Default fuzzy membership width (neighbouring sets cross at 0.5).
pub const DEFAULT_WIDTH: f64 = super::repr::HALF_CROSSING_WIDTH;
/// Default fuzzy pruning threshold.
pub const DEFAULT_PRUNE: f64 = 1e-3;
/// Default trace cutoff.
pub const DEFAULT_TRACE_CUTOFF: f64 = 1e-10;
/// Default episode cap per trial.
pub const DEFAULT_MAX_EPISODES: u32 = 1000;
/// Default step cap per trial.
pub const DEFAULT_MAX_TOTAL_STEPS: u64 = 10_000_000;

impl TrialConfig {
    /// The paper's configuration for a system, representation, algorithm, resolution and action
    /// count, with qsweep's documented defaults for everything the paper leaves open.
    pub fn paper(
        system: SystemKind,
        repr: ReprKind,
        algorithm: Algorithm,
        resolution: Vec<u32>,
        actions: u32,
    ) -> Self {
        let h = table2(system, repr);
        let fuzzy = repr == ReprKind::Fuzzy;
        let mut c = Self {
            env: EnvParams::default_for(system),
            repr: ReprConfig {
                kind: repr,
                resolution,
                ranges: default_ranges(system),
                width: if fuzzy { DEFAULT_WIDTH } else { 0.0 },
                prune: if fuzzy { DEFAULT_PRUNE } else { 0.0 },
                binning: Binning::Midpoint,
            },
            actions,
            learner: LearnerConfig {
                algorithm,
                epsilon: h.epsilon,
                gamma: h.gamma,
                alpha: h.alpha,
                lambda: h.lambda,
                q_init: 0.0,
                tie_break: TieBreak::Random,
                traces: TraceKind::Accumulating,
                watkins_cut: false,
                trace_cutoff: DEFAULT_TRACE_CUTOFF,
            },
            limits: Limits {
                success: default_success(system),
                max_episodes: DEFAULT_MAX_EPISODES,
                max_total_steps: DEFAULT_MAX_TOTAL_STEPS,
                truncation: Truncation::Bootstrap,
            },
            start: StartKind::Fixed,
        };
        c.normalize();
        c
    }

    /// The system this trial runs.
    pub fn system(&self) -> SystemKind {
        self.env.system()
    }

    /// Reset settings that cannot affect the outcome to fixed values, so they never change a key:
    /// Q(0) has no traces, crisp bins have no width, fuzzy sets have no bin edges, a survival
    /// task's episode cut under `Balance` is its goal (the trial ends right after, so how the cut
    /// step is learned from never matters; under `Solved` it is an ordinary cut and does matter),
    /// Ball-Beam has no Gymnasium start distribution, and its `rate_max` is unused under angle
    /// control.
    pub fn normalize(&mut self) {
        if matches!(self.limits.success, Success::Balance { .. }) {
            self.limits.truncation = Truncation::Bootstrap;
        }
        if let EnvParams::BallBeam(p) = &mut self.env {
            self.start = StartKind::Fixed;
            if p.control == BeamControl::Angle {
                p.rate_max = BALL_BEAM_DEFAULT_RATE_MAX;
            }
        }
        if self.learner.algorithm == Algorithm::Q0 {
            self.learner.lambda = 0.0;
            self.learner.traces = TraceKind::Accumulating;
            self.learner.watkins_cut = false;
            self.learner.trace_cutoff = 0.0;
        }
        if self.repr.kind == ReprKind::Crisp {
            self.repr.width = 0.0;
            self.repr.prune = 0.0;
        } else {
            self.repr.binning = Binning::Midpoint;
        }
    }

    /// Check every value; `Err` names the field and what is allowed.
    pub fn validate(&self) -> Result<(), String> {
        let system = self.system();
        let dim = system.dim();
        self.env.validate().map_err(|e| format!("env: {e}"))?;
        if self.repr.resolution.len() != dim {
            return Err(format!(
                "resolution: {} has {dim} state variables ({}), got {} values",
                system,
                system.variables().join(", "),
                self.repr.resolution.len()
            ));
        }
        for &r in &self.repr.resolution {
            rules::resolution(r, Some(self.repr.kind)).map_err(|e| format!("resolution: {e}"))?;
        }
        let features: u64 = self.repr.resolution.iter().map(|&r| u64::from(r)).product();
        if features * u64::from(self.actions) > 1 << 27 {
            return Err(format!(
                "resolution: {features} features × {} actions is too large a table (limit 2^27 entries)",
                self.actions
            ));
        }
        if self.repr.ranges.len() != dim {
            return Err(format!(
                "ranges: {system} needs {dim} [lo, hi] pairs, got {}",
                self.repr.ranges.len()
            ));
        }
        for (name, r) in system.variables().iter().zip(&self.repr.ranges) {
            rules::bounds(r[0], r[1]).map_err(|e| format!("ranges.{name}: {e}"))?;
        }
        if self.repr.kind == ReprKind::Fuzzy {
            rules::POSITIVE.check(self.repr.width).map_err(|e| format!("width: {e}"))?;
            rules::SUB_UNIT.check(self.repr.prune).map_err(|e| format!("prune: {e}"))?;
        }
        rules::actions(self.actions).map_err(|e| format!("actions: {e}"))?;
        let l = &self.learner;
        let checks = [
            ("epsilon", rules::UNIT, l.epsilon),
            ("gamma", rules::UNIT, l.gamma),
            ("lambda", rules::UNIT, l.lambda),
            ("alpha", rules::POSITIVE, l.alpha),
            ("q_init", rules::FINITE, l.q_init),
            ("trace_cutoff", rules::SUB_UNIT, l.trace_cutoff),
        ];
        for (name, rule, v) in checks {
            rule.check(v).map_err(|e| format!("{name}: {e}"))?;
        }
        rules::at_least_one(u64::from(self.limits.max_episodes)).map_err(|e| format!("max_episodes: {e}"))?;
        rules::at_least_one(self.limits.max_total_steps).map_err(|e| format!("max_total_steps: {e}"))?;
        match (&self.limits.success, TaskKind::of(system)) {
            (Success::Balance { steps }, TaskKind::Survival) => {
                rules::steps(*steps).map_err(|e| format!("success.steps: {e}"))?;
            }
            (Success::Reach { within, streak, max_episode_steps }, TaskKind::GoalReaching) => {
                rules::at_least_one(*within).map_err(|e| format!("success.within: {e}"))?;
                rules::at_least_one(u64::from(*streak)).map_err(|e| format!("success.streak: {e}"))?;
                rules::steps(*max_episode_steps).map_err(|e| format!("success.max_episode_steps: {e}"))?;
            }
            (Success::Solved { window, mean_length, episode_steps }, task) => {
                rules::at_least_one(u64::from(*window)).map_err(|e| format!("success.window: {e}"))?;
                rules::POSITIVE.check(*mean_length).map_err(|e| format!("success.mean_length: {e}"))?;
                let steps_name =
                    if task == TaskKind::Survival { "success.steps" } else { "success.max_episode_steps" };
                rules::steps(*episode_steps).map_err(|e| format!("{steps_name}: {e}"))?;
            }
            (_, TaskKind::Survival) => {
                return Err(format!("success: {system} is a survival task; use `{}`", rules::BALANCE_SYNTAX))
            }
            (_, TaskKind::GoalReaching) => {
                return Err(format!(
                    "success: {system} is a goal-reaching task; use `{}`",
                    rules::REACH_SYNTAX
                ))
            }
        }
        Ok(())
    }
}

impl TaskKind {
    /// The task kind of a system (its [`Environment::TASK`]).
    pub fn of(system: SystemKind) -> Self {
        with_env_type!(system, E => E::TASK)
    }
}
