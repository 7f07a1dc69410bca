//! One trial: a configuration and a seed, run episode after episode until the learning goal (one
//! long enough episode, a streak of quick ones, or Gym's solved rule, [`super::solved`]) or a
//! cap. Everything random comes from one ChaCha stream seeded by the seed, so a trial's outcome is a
//! pure function of its inputs, on any thread.

use super::actions::action_set;
use super::config::{Success, TieBreak, TrialConfig, Truncation};
use super::env::{BallBeam, CartPole, EnvParams, Environment, MountainCar, StartKind, TaskKind};
use super::learner::Learner;
use super::repr::{Crisp, Encode, Fuzzy, ReprKind};
use super::rng::TrialRng;
use super::simd::{self, Simd};
use super::solved::SolvedWindow;
use serde::{Deserialize, Serialize};

/// Why a trial stopped.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum StopReason {
    /// The learning goal was reached.
    Goal,
    /// `max_episodes` episodes ran without reaching the goal.
    MaxEpisodes,
    /// `max_total_steps` steps ran without reaching the goal.
    MaxTotalSteps,
    /// The simulation produced a non-finite state or TD error.
    Diverged,
}

impl StopReason {
    /// Kebab-case name as stored in the cache.
    pub fn name(self) -> &'static str {
        match self {
            Self::Goal => "goal",
            Self::MaxEpisodes => "max-episodes",
            Self::MaxTotalSteps => "max-total-steps",
            Self::Diverged => "diverged",
        }
    }
}

/// How a trial's outcome becomes the episodes Table III averages: a report setting (the pipeline's
/// `counting:`), never part of a trial's key, so switching it needs no reruns.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Counting {
    /// The episode in which the goal was first reached (`episodes_to_goal`): the paper's text.
    #[default]
    Episodes,
    /// The failed episodes before it (`episodes_to_goal − 1`): an exploratory reading.
    Failures,
    /// Under Gym's solved rule, the window's first episode (`episodes_to_goal − window + 1`), as
    /// "solved after N episodes" is sometimes read; like `episodes` under any other criterion.
    WindowStart,
}

/// What a trial produced.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Outcome {
    /// Whether the learning goal was reached.
    pub converged: bool,
    /// Episodes up to and including the one that reached the goal; `None` if never reached.
    pub episodes_to_goal: Option<u32>,
    /// Episodes run.
    pub episodes: u32,
    /// Steps run, over all episodes.
    pub total_steps: u64,
    /// Why the trial stopped.
    pub stop: StopReason,
    /// For a diverged trial, what went wrong and where.
    pub failure: Option<String>,
    /// Length of every episode, in order.
    pub episode_lengths: Vec<u32>,
}

/// Run one trial. The configuration must be valid (`TrialConfig::validate`).
pub fn run_trial(cfg: &TrialConfig, seed: u64) -> Outcome {
    run_trial_at(cfg, seed, simd::level())
}

/// [`run_trial`] with the learner's and the activation's kernels at `simd` (capped by what the CPU
/// has): the same outcome at every level, only the speed differs ([`crate::simd`]).
pub fn run_trial_at(cfg: &TrialConfig, seed: u64, simd: Simd) -> Outcome {
    match &cfg.env {
        EnvParams::BallBeam(p) => with_repr(cfg, seed, BallBeam::new(p.clone()), simd),
        EnvParams::CartPole(p) => with_repr(cfg, seed, CartPole::new(p.clone()), simd),
        EnvParams::MountainCar(p) => with_repr(cfg, seed, MountainCar::new(p.clone()), simd),
    }
}

fn with_repr<E: Environment>(cfg: &TrialConfig, seed: u64, env: E, simd: Simd) -> Outcome {
    let r = &cfg.repr;
    match r.kind {
        ReprKind::Crisp => {
            run(cfg, seed, env, Crisp::with_binning(&r.resolution, &r.ranges, r.binning), simd)
        }
        ReprKind::Fuzzy => {
            let repr = Fuzzy::new(&r.resolution, &r.ranges, r.width, r.prune).with_simd(simd);
            run(cfg, seed, env, repr, simd)
        }
    }
}

/// ε-greedy action choice; returns the action and whether it is greedy.
#[inline(always)]
fn select(q: &[f64], epsilon: f64, tie: TieBreak, rng: &mut TrialRng) -> (usize, bool) {
    let mut best = f64::NEG_INFINITY;
    let mut n_best = 0usize;
    let mut first = 0usize;
    for (a, &v) in q.iter().enumerate() {
        if v > best {
            best = v;
            n_best = 1;
            first = a;
        } else if v == best {
            n_best += 1;
        }
    }
    if rng.unit() < epsilon {
        let a = rng.below(q.len());
        return (a, q[a] == best);
    }
    if n_best == 1 || tie == TieBreak::First {
        return (first, true);
    }
    let pick = rng.below(n_best);
    let a = q.iter().enumerate().filter(|(_, &v)| v == best).nth(pick).map_or(first, |(a, _)| a);
    (a, true)
}

fn run<E: Environment, R: Encode>(cfg: &TrialConfig, seed: u64, env: E, repr: R, simd: Simd) -> Outcome {
    let mut learner = Learner::new(repr.n_features(), cfg.actions as usize, repr.max_active(), &cfg.learner)
        .with_simd(simd);
    episodes(cfg, seed, env, repr, &mut learner)
}

/// A trial's outcome and its final Q parameters (for tests of single updates).
#[doc(hidden)]
pub fn run_with_q(cfg: &TrialConfig, seed: u64) -> (Outcome, Vec<f64>) {
    fn go<E: Environment>(cfg: &TrialConfig, seed: u64, env: E) -> (Outcome, Vec<f64>) {
        use super::repr::Representation;
        let r = &cfg.repr;
        assert_eq!(r.kind, ReprKind::Crisp);
        let repr = Crisp::with_binning(&r.resolution, &r.ranges, r.binning);
        let mut learner = Learner::new(repr.n_features(), cfg.actions as usize, 1, &cfg.learner);
        let o = episodes(cfg, seed, env, repr, &mut learner);
        (o, learner.params().to_vec())
    }
    match &cfg.env {
        EnvParams::BallBeam(p) => go(cfg, seed, BallBeam::new(p.clone())),
        EnvParams::CartPole(p) => go(cfg, seed, CartPole::new(p.clone())),
        EnvParams::MountainCar(p) => go(cfg, seed, MountainCar::new(p.clone())),
    }
}

fn episodes<E: Environment, R: Encode>(
    cfg: &TrialConfig,
    seed: u64,
    mut env: E,
    repr: R,
    learner: &mut Learner,
) -> Outcome {
    let l = &cfg.learner;
    let actions = action_set(cfg.env.action_max(), cfg.actions);
    let na = actions.len();
    let gym_start = cfg.start == StartKind::Gym;
    let cut_is_terminal = cfg.limits.truncation == Truncation::Terminal;
    let mut rng = TrialRng::new(seed);
    let (mut phi, mut phi_next) = (R::Active::default(), R::Active::default());
    let (mut qs, mut qs_next) = (vec![0.0; na], vec![0.0; na]);
    let cap = cfg.limits.episode_cap();
    let mut lengths = Vec::new();
    let mut total_steps = 0u64;
    let mut streak = 0u32;
    let mut window = match cfg.limits.success {
        Success::Solved { window, mean_length, .. } => Some(SolvedWindow::new(window, mean_length, E::TASK)),
        _ => None,
    };

    let finish = |stop, lengths: Vec<u32>, total_steps, failure| Outcome {
        converged: stop == StopReason::Goal,
        episodes_to_goal: (stop == StopReason::Goal).then_some(lengths.len() as u32),
        episodes: lengths.len() as u32,
        total_steps,
        stop,
        failure,
        episode_lengths: lengths,
    };

    for episode in 1..=cfg.limits.max_episodes {
        if gym_start {
            env.reset_gym(&mut rng);
        } else {
            env.reset();
        }
        learner.clear_traces();
        repr.encode(env.state(), &mut phi);
        learner.q_values(&phi, &mut qs);
        let mut len = 0u64;
        let terminal = loop {
            let (a, greedy) = select(&qs, l.epsilon, l.tie_break, &mut rng);
            if l.watkins_cut && !greedy {
                learner.clear_traces();
            }
            let t = env.step(actions[a]);
            len += 1;
            let s = env.state();
            // At the episode step limit, `terminal` truncation learns as if the task ended there.
            let target = if t.terminal || (cut_is_terminal && len >= cap) {
                t.reward
            } else {
                repr.encode(s, &mut phi_next);
                learner.q_values(&phi_next, &mut qs_next);
                t.reward + l.gamma * qs_next.iter().copied().fold(f64::NEG_INFINITY, f64::max)
            };
            let delta = target - qs[a];
            if !delta.is_finite() || !s[..E::DIM].iter().all(|v| v.is_finite()) {
                lengths.push(len as u32);
                let what = if delta.is_finite() { "state" } else { "TD error" };
                let msg =
                    format!("non-finite {what} at episode {episode}, step {len} (state {:?})", &s[..E::DIM]);
                return finish(StopReason::Diverged, lengths, total_steps + len, Some(msg));
            }
            learner.update(&phi, a, delta);
            if t.terminal || len >= cap {
                break t.terminal;
            }
            std::mem::swap(&mut phi, &mut phi_next);
            // qs_next is Q(s_{t+1}, ·) from before the update; phi_next is now φ(s_t).
            std::mem::swap(&mut qs, &mut qs_next);
            learner.refresh_after_update(&phi, &phi_next, a, &mut qs);
        };
        lengths.push(len as u32);
        total_steps += len;
        let success = match (&cfg.limits.success, E::TASK) {
            (Success::Balance { .. }, TaskKind::Survival) => !terminal,
            (Success::Reach { within, streak: need, .. }, TaskKind::GoalReaching) => {
                streak = if terminal && len <= *within { streak + 1 } else { 0 };
                streak >= *need
            }
            // A cut episode is an ordinary one here: only the window's mean length counts.
            (Success::Solved { .. }, _) => window.as_mut().expect("built for Solved").push(&lengths),
            _ => unreachable!("validated: success criterion matches the task kind"),
        };
        if success {
            return finish(StopReason::Goal, lengths, total_steps, None);
        }
        if total_steps >= cfg.limits.max_total_steps {
            return finish(StopReason::MaxTotalSteps, lengths, total_steps, None);
        }
    }
    finish(StopReason::MaxEpisodes, lengths, total_steps, None)
}

/// Roll a system forward from `state` under the given action values, stopping after the first
/// terminal step. Returns, per step, the action value, the state after it and the transition.
pub fn simulate(
    env: &EnvParams,
    state: &[f64],
    actions: &[f64],
) -> Vec<(f64, [f64; 4], super::env::Transition)> {
    fn go<E: Environment>(
        mut e: E,
        state: &[f64],
        actions: &[f64],
    ) -> Vec<(f64, [f64; 4], super::env::Transition)> {
        e.set_state(state);
        let mut out = Vec::with_capacity(actions.len());
        for &a in actions {
            let t = e.step(a);
            out.push((a, *e.state(), t));
            if t.terminal {
                break;
            }
        }
        out
    }
    match env {
        EnvParams::BallBeam(p) => go(BallBeam::new(p.clone()), state, actions),
        EnvParams::CartPole(p) => go(CartPole::new(p.clone()), state, actions),
        EnvParams::MountainCar(p) => go(MountainCar::new(p.clone()), state, actions),
    }
}
