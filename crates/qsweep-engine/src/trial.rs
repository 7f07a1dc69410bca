//! One trial: a configuration and a seed, run episode after episode until the learning goal (one
//! long enough episode, a streak of quick ones, or Gym's solved rule, [`super::solved`]) or a
//! cap. Everything random comes from one ChaCha stream seeded by the seed, so a trial's outcome is a
//! pure function of its inputs, on any thread.

use super::actions::action_set;
use super::config::{Success, TieBreak, TrialConfig, Truncation};
use super::dense_path::{dense_enabled, dense_pays, takes_dense_path};
use super::env::{with_env, EnvParams, Environment, StartKind, State, TaskKind, Transition};
use super::learner::{grid_row_len, Learner};
use super::repr::{Crisp, DenseFuzzy, Encode, Fuzzy, ReprKind, Representation};
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
    with_env!(&cfg.env, |env: E| with_repr(cfg, seed, env, simd))
}

fn with_repr<E: Environment>(cfg: &TrialConfig, seed: u64, env: E, simd: Simd) -> Outcome {
    let r = &cfg.repr;
    match r.kind {
        ReprKind::Crisp => {
            run(cfg, seed, env, Crisp::with_binning(&r.resolution, &r.ranges, r.binning), simd)
        }
        ReprKind::Fuzzy => {
            let repr = Fuzzy::new(&r.resolution, &r.ranges, r.width, r.prune).with_simd(simd);
            if dense_enabled() && dense_pays(&repr, cfg.actions, &cfg.learner) {
                run_dense(cfg, seed, env, DenseFuzzy::new(repr, grid_row_len(cfg.actions as usize)), simd).0
            } else {
                run(cfg, seed, env, repr, simd)
            }
        }
    }
}

/// A fuzzy trial's outcome and final Q parameters through the dense path (`dense`, where its rule
/// base fits) or the windowed one.
fn dense_or_windowed<E: Environment>(
    cfg: &TrialConfig,
    seed: u64,
    env: E,
    repr: Fuzzy,
    simd: Simd,
    dense: bool,
) -> (Outcome, Learner) {
    if dense && dense_pays(&repr, cfg.actions, &cfg.learner) {
        run_dense(cfg, seed, env, DenseFuzzy::new(repr, grid_row_len(cfg.actions as usize)), simd)
    } else {
        let learner = Learner::new(repr.n_features(), cfg.actions as usize, repr.max_active(), &cfg.learner)
            .with_simd(simd);
        episodes(env, TrialRun::new::<E>(cfg, seed, repr, learner))
    }
}

fn run_dense<E: Environment>(
    cfg: &TrialConfig,
    seed: u64,
    env: E,
    repr: DenseFuzzy,
    simd: Simd,
) -> (Outcome, Learner) {
    episodes_at(simd, env, TrialRun::dense_with::<E>(cfg, seed, repr, simd))
}

/// [`episodes`] with the whole step loop compiled for `simd`'s level, so that the activation, the
/// ε-greedy choice and the system's step inline into one function of that width (the same bits:
/// [`crate::simd`]'s module doc).
fn episodes_at<E: Environment, R: Encode>(simd: Simd, env: E, run: TrialRun<'_, R>) -> (Outcome, Learner) {
    #[cfg(target_arch = "x86_64")]
    {
        #[target_feature(enable = "avx2")]
        unsafe fn avx2<E: Environment, R: Encode>(env: E, run: TrialRun<'_, R>) -> (Outcome, Learner) {
            episodes(env, run)
        }
        #[target_feature(enable = "avx512f")]
        unsafe fn avx512<E: Environment, R: Encode>(env: E, run: TrialRun<'_, R>) -> (Outcome, Learner) {
            episodes(env, run)
        }
        match simd.capped() {
            // SAFETY: capped by what the CPU has.
            Simd::Avx2 => return unsafe { avx2(env, run) },
            Simd::Avx512 => return unsafe { avx512(env, run) },
            Simd::Baseline => {}
        }
    }
    episodes(env, run)
}

/// A fuzzy trial's outcome and final Q parameters through the dense path (`dense`, where the rule
/// base fits) or the windowed one, at `simd` (for the tests that the two give the same bits).
#[doc(hidden)]
pub fn run_fuzzy_with_q(cfg: &TrialConfig, seed: u64, simd: Simd, dense: bool) -> (Outcome, Vec<f64>) {
    fn go<E: Environment>(
        cfg: &TrialConfig,
        seed: u64,
        env: E,
        simd: Simd,
        dense: bool,
    ) -> (Outcome, Vec<f64>) {
        let r = &cfg.repr;
        assert_eq!(r.kind, ReprKind::Fuzzy);
        let repr = Fuzzy::new(&r.resolution, &r.ranges, r.width, r.prune).with_simd(simd);
        let (o, learner) = dense_or_windowed(cfg, seed, env, repr, simd.capped(), dense);
        // Each rule's actions, without a grid learner's values past them.
        let q = learner.params().chunks(learner.row_len()).flat_map(|r| &r[..cfg.actions as usize]);
        (o, q.copied().collect())
    }
    with_env!(&cfg.env, |env: E| go(cfg, seed, env, simd, dense))
}

/// ε-greedy action choice; returns the action and whether it is greedy. Among equal greatest
/// values (NaN never is one) the first, or a uniform pick by `tie`.
#[inline(always)]
fn select(q: &[f64], epsilon: f64, tie: TieBreak, rng: &mut TrialRng) -> (usize, bool) {
    // The study's usual action counts with the length a constant, so that the loops unroll.
    match q.len() {
        2 => select_in(fixed::<2>(q), epsilon, tie, rng),
        3 => select_in(fixed::<3>(q), epsilon, tie, rng),
        4 => select_in(fixed::<4>(q), epsilon, tie, rng),
        _ => select_in(q, epsilon, tie, rng),
    }
}

/// `q` (of `N` values) as a slice whose length the compiler knows.
#[inline(always)]
fn fixed<const N: usize>(q: &[f64]) -> &[f64] {
    q.first_chunk::<N>().expect("N values").as_slice()
}

/// [`select`]'s rule.
#[inline(always)]
fn select_in(q: &[f64], epsilon: f64, tie: TieBreak, rng: &mut TrialRng) -> (usize, bool) {
    // Without a branch per action (which way it goes changes from step to step, and a wrong guess
    // costs more than the few actions): the greatest value, then how many equal it and the first.
    let best = greatest(q);
    let mut n_best = 0usize;
    let mut first = 0;
    for (a, &v) in q.iter().enumerate().rev() {
        let eq = v == best;
        n_best += usize::from(eq);
        first = if eq { a } else { first };
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

/// The greatest of `q` (−∞ for none; NaN is skipped), as `fold(−∞, f64::max)` gives it but for
/// the sign of a zero, which no TD target can tell (r + γ·(±0) is r for the rewards of eqs.
/// 23–25): one comparison per value, without `max`'s NaN handling.
#[inline(always)]
fn greatest(q: &[f64]) -> f64 {
    let fold = |q: &[f64]| q.iter().fold(f64::NEG_INFINITY, |m, &v| if v > m { v } else { m });
    // As `select`: the usual action counts unrolled.
    match q.len() {
        2 => fold(fixed::<2>(q)),
        3 => fold(fixed::<3>(q)),
        4 => fold(fixed::<4>(q)),
        _ => fold(q),
    }
}

fn run<E: Environment, R: Encode>(cfg: &TrialConfig, seed: u64, env: E, repr: R, simd: Simd) -> Outcome {
    let learner = Learner::new(repr.n_features(), cfg.actions as usize, repr.max_active(), &cfg.learner)
        .with_simd(simd);
    episodes(env, TrialRun::new::<E>(cfg, seed, repr, learner)).0
}

/// A trial's outcome and its final Q parameters (for tests of single updates).
#[doc(hidden)]
pub fn run_with_q(cfg: &TrialConfig, seed: u64) -> (Outcome, Vec<f64>) {
    fn go<E: Environment>(cfg: &TrialConfig, seed: u64, env: E) -> (Outcome, Vec<f64>) {
        assert_eq!(cfg.repr.kind, ReprKind::Crisp);
        let (o, learner) = episodes(env, TrialRun::crisp::<E>(cfg, seed));
        (o, learner.params().to_vec())
    }
    with_env!(&cfg.env, |env: E| go(cfg, seed, env))
}

/// One trial run alone: `run`'s steps in one loop with its system.
#[inline(always)]
fn episodes<E: Environment, R: Encode>(mut env: E, mut run: TrialRun<'_, R>) -> (Outcome, Learner) {
    let outcome = match run.begin(&mut env) {
        Some(o) => o,
        None => loop {
            let action = run.choose();
            let t = env.step(action);
            if let Some(o) = run.learn(&mut env, t) {
                break o;
            }
        },
    };
    (outcome, run.learner)
}

/// One trial as a machine that the caller steps: [`choose`](Self::choose) an action, step the
/// system with it, and [`learn`](Self::learn) from the transition, until `learn` returns the
/// outcome. Run alone ([`run_trial`]) or as one lane of several sharing a loop
/// ([`crate::lanes`]), a trial performs the same operations in the same order, so its outcome is
/// the same.
pub(crate) struct TrialRun<'c, R: Encode> {
    cfg: &'c TrialConfig,
    repr: R,
    learner: Learner,
    /// The action values, A_n.
    actions: Vec<f64>,
    gym_start: bool,
    cut_is_terminal: bool,
    rng: TrialRng,
    /// φ(s_t), and scratch for φ(s_{t+1}).
    phi: R::Active,
    phi_next: R::Active,
    /// Q(s_t, ·), and scratch for Q(s_{t+1}, ·) (each with room for the learner's whole vectors,
    /// [`Learner::q_out_len`]; the values past the actions are scratch).
    qs: Vec<f64>,
    qs_next: Vec<f64>,
    cap: u64,
    lengths: Vec<u32>,
    total_steps: u64,
    streak: u32,
    window: Option<SolvedWindow>,
    /// The episode running (1-based; 0 before the first).
    episode: u32,
    /// Steps of this episode so far.
    len: u64,
    /// The action chosen at s_t.
    action: usize,
}

impl<'c> TrialRun<'c, Crisp> {
    /// The crisp trial `cfg` with `seed` on system `E`: its bins, and a learner for one active
    /// feature a state.
    pub(crate) fn crisp<E: Environment>(cfg: &'c TrialConfig, seed: u64) -> Self {
        let r = &cfg.repr;
        let repr = Crisp::with_binning(&r.resolution, &r.ranges, r.binning);
        let learner = Learner::new(repr.n_features(), cfg.actions as usize, 1, &cfg.learner);
        Self::new::<E>(cfg, seed, repr, learner)
    }
}

impl<'c> TrialRun<'c, DenseFuzzy> {
    /// The fuzzy trial `cfg` with `seed` on system `E` through the dense path, if it takes it
    /// ([`takes_dense_path`]), with its kernels at the process's vector level.
    pub(crate) fn dense<E: Environment>(cfg: &'c TrialConfig, seed: u64) -> Option<Self> {
        if !takes_dense_path(cfg) {
            return None;
        }
        let (r, simd) = (&cfg.repr, simd::level());
        let repr = Fuzzy::new(&r.resolution, &r.ranges, r.width, r.prune).with_simd(simd);
        Some(Self::dense_with::<E>(
            cfg,
            seed,
            DenseFuzzy::new(repr, grid_row_len(cfg.actions as usize)),
            simd,
        ))
    }

    fn dense_with<E: Environment>(cfg: &'c TrialConfig, seed: u64, repr: DenseFuzzy, simd: Simd) -> Self {
        // Rows of whole vectors: the actions, then values no action reads (`grid_row_len`).
        let row = grid_row_len(cfg.actions as usize);
        let learner = Learner::new(repr.n_features(), row, repr.max_active(), &cfg.learner)
            .with_simd(simd)
            .with_dense_traces();
        Self::new::<E>(cfg, seed, repr, learner)
    }
}

impl<'c, R: Encode> TrialRun<'c, R> {
    /// The trial `cfg` with `seed` on system `E`, before its first episode.
    pub(crate) fn new<E: Environment>(cfg: &'c TrialConfig, seed: u64, repr: R, learner: Learner) -> Self {
        let actions = action_set(cfg.env.action_max(), cfg.actions);
        let out = learner.q_out_len();
        let window = match cfg.limits.success {
            Success::Solved { window, mean_length, .. } => {
                Some(SolvedWindow::new(window, mean_length, E::TASK))
            }
            _ => None,
        };
        Self {
            cfg,
            repr,
            learner,
            actions,
            gym_start: cfg.start == StartKind::Gym,
            cut_is_terminal: cfg.limits.truncation == Truncation::Terminal,
            rng: TrialRng::new(seed),
            phi: R::Active::default(),
            phi_next: R::Active::default(),
            qs: vec![0.0; out],
            qs_next: vec![0.0; out],
            cap: cfg.limits.episode_cap(),
            lengths: Vec::new(),
            total_steps: 0,
            streak: 0,
            window,
            episode: 0,
            len: 0,
            action: 0,
        }
    }

    /// Start the next episode with `env` at its start state, or the outcome once `max_episodes`
    /// have run.
    pub(crate) fn begin<E: Environment>(&mut self, env: &mut E) -> Option<Outcome> {
        if self.episode >= self.cfg.limits.max_episodes {
            return Some(self.finish(StopReason::MaxEpisodes, None));
        }
        self.episode += 1;
        if self.gym_start {
            env.reset_gym(&mut self.rng);
        } else {
            env.reset();
        }
        self.learner.clear_traces();
        self.repr.encode(env.state(), &mut self.phi);
        self.learner.q_values(&self.phi, &mut self.qs);
        self.len = 0;
        None
    }

    /// The ε-greedy action at s_t (eq. 12), as the value to step the system with.
    #[inline(always)]
    pub(crate) fn choose(&mut self) -> f64 {
        let l = &self.cfg.learner;
        let (a, greedy) = select(&self.qs[..self.actions.len()], l.epsilon, l.tie_break, &mut self.rng);
        if l.watkins_cut && !greedy {
            self.learner.clear_traces();
        }
        self.action = a;
        self.actions[a]
    }

    /// Learn from the step `env` just took under the chosen action, which returned `t`; at an
    /// episode's end, judge it and begin the next. Returns the outcome once the trial stops.
    #[inline(always)]
    pub(crate) fn learn<E: Environment>(&mut self, env: &mut E, t: Transition) -> Option<Outcome> {
        let target = self.target(env, t);
        self.learn_toward(env, t, target)
    }

    /// [`learn`](Self::learn)'s first half: the TD target of the step `env` just took (which
    /// returned `t`), with φ(s_{t+1}) and Q(s_{t+1}, ·) where it needs them.
    #[inline(always)]
    pub(crate) fn target<E: Environment>(&mut self, env: &E, t: Transition) -> f64 {
        let bootstraps = self.encode_next(env, t);
        self.target_of(t, bootstraps)
    }

    /// The target's first part: counts the step and, where the target bootstraps (returned),
    /// encodes φ(s_{t+1}). Lockstep runs each part for every lane before the next part, so that
    /// the lanes' chains of dependent operations lie side by side for the CPU.
    #[inline(always)]
    pub(crate) fn encode_next<E: Environment>(&mut self, env: &E, t: Transition) -> bool {
        self.len += 1;
        // At the episode step limit, `terminal` truncation learns as if the task ended there.
        let bootstraps = !(t.terminal || (self.cut_is_terminal && self.len >= self.cap));
        if bootstraps {
            self.repr.encode(env.state(), &mut self.phi_next);
        }
        bootstraps
    }

    /// The target's second part, after [`encode_next`](Self::encode_next): r, or
    /// r + γ·max Q(s_{t+1}, ·) where it bootstraps.
    #[inline(always)]
    pub(crate) fn target_of(&mut self, t: Transition, bootstraps: bool) -> f64 {
        if bootstraps {
            self.learner.q_values(&self.phi_next, &mut self.qs_next);
            t.reward + self.cfg.learner.gamma * greatest(&self.qs_next[..self.actions.len()])
        } else {
            t.reward
        }
    }

    /// [`learn`](Self::learn)'s second half, toward the [`target`](Self::target) of the same
    /// step: the update (eqs. 20–21), then the episode's end, or s_{t+1} becomes s_t with
    /// Q(s_t, ·) as the update left it.
    #[inline(always)]
    pub(crate) fn learn_toward<E: Environment>(
        &mut self,
        env: &mut E,
        t: Transition,
        target: f64,
    ) -> Option<Outcome> {
        let a = self.action;
        let s = env.state();
        let delta = target - self.qs[a];
        if !delta.is_finite() || !s[..E::DIM].iter().all(|v| v.is_finite()) {
            return Some(self.diverged::<E>(delta, *s));
        }
        self.learner.update(&self.phi, a, delta);
        if t.terminal || self.len >= self.cap {
            return self.end_episode(env, t.terminal);
        }
        std::mem::swap(&mut self.phi, &mut self.phi_next);
        // qs_next is Q(s_{t+1}, ·) from before the update; phi_next is now φ(s_t).
        std::mem::swap(&mut self.qs, &mut self.qs_next);
        self.learner.refresh_after_update(&self.phi, &self.phi_next, a, &mut self.qs);
        None
    }

    /// The outcome of a trial whose TD error `delta` or state `s` stopped being finite.
    #[cold]
    fn diverged<E: Environment>(&mut self, delta: f64, s: State) -> Outcome {
        self.lengths.push(self.len as u32);
        self.total_steps += self.len;
        let what = if delta.is_finite() { "state" } else { "TD error" };
        let (episode, len) = (self.episode, self.len);
        let msg = format!("non-finite {what} at episode {episode}, step {len} (state {:?})", &s[..E::DIM]);
        self.finish(StopReason::Diverged, Some(msg))
    }

    /// Judge the episode that just ended (`terminal`: by a terminal state, else at the cap);
    /// stop the trial, or begin the next episode.
    fn end_episode<E: Environment>(&mut self, env: &mut E, terminal: bool) -> Option<Outcome> {
        let len = self.len;
        self.lengths.push(len as u32);
        self.total_steps += len;
        let success = match (&self.cfg.limits.success, E::TASK) {
            (Success::Balance { .. }, TaskKind::Survival) => !terminal,
            (Success::Reach { within, streak: need, .. }, TaskKind::GoalReaching) => {
                self.streak = if terminal && len <= *within { self.streak + 1 } else { 0 };
                self.streak >= *need
            }
            // A cut episode is an ordinary one here: only the window's mean length counts.
            (Success::Solved { .. }, _) => {
                self.window.as_mut().expect("built for Solved").push(&self.lengths)
            }
            _ => unreachable!("validated: success criterion matches the task kind"),
        };
        if success {
            return Some(self.finish(StopReason::Goal, None));
        }
        if self.total_steps >= self.cfg.limits.max_total_steps {
            return Some(self.finish(StopReason::MaxTotalSteps, None));
        }
        self.begin(env)
    }

    fn finish(&mut self, stop: StopReason, failure: Option<String>) -> Outcome {
        let lengths = std::mem::take(&mut self.lengths);
        Outcome {
            converged: stop == StopReason::Goal,
            episodes_to_goal: (stop == StopReason::Goal).then_some(lengths.len() as u32),
            episodes: lengths.len() as u32,
            total_steps: self.total_steps,
            stop,
            failure,
            episode_lengths: lengths,
        }
    }
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
    with_env!(env, |e: E| go(e, state, actions))
}
