//! What a system is to the trial loop: the [`Environment`] trait, its state and the result of a
//! step, and the macro that gives every parameter struct its `--param NAME=VALUE` names.

use crate::rng::TrialRng;
use crate::simd::Simd;

/// Largest number of state variables of any system (Cart-Pole's four).
pub const MAX_DIM: usize = 4;

/// A state vector, padded beyond the system's dimension (with zeros, or a hidden variable).
pub type State = [f64; MAX_DIM];

/// What one step of a system returns besides the new state.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Transition {
    /// Reward of eqs. (23)–(25).
    pub reward: f64,
    /// True when the step entered a terminal state (failure, or Mountain Car's goal).
    pub terminal: bool,
}

/// How a system's episodes count as a success.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TaskKind {
    /// Avoid failure for a number of steps (Cart-Pole, Ball-Beam); terminal means failure.
    Survival,
    /// Reach a goal (Mountain Car); terminal means success.
    GoalReaching,
}

/// A discrete-time control system driven by real-valued actions.
pub trait Environment {
    /// Number of state variables.
    const DIM: usize;
    /// Whether the task is survival or goal reaching.
    const TASK: TaskKind;
    /// Return to the configured start state.
    fn reset(&mut self);
    /// Start an episode from Gymnasium's `reset()` distribution, drawn from `rng` (the fixed start
    /// where Gymnasium has no such system).
    fn reset_gym(&mut self, rng: &mut TrialRng) {
        let _ = rng;
        self.reset();
    }
    /// Overwrite the current state: the first `DIM` entries, and a hidden entry beyond them where
    /// the system has one (Ball-Beam's beam angle under rate control; 0 when `state` is shorter).
    fn set_state(&mut self, state: &[f64]);
    /// The current state.
    fn state(&self) -> &State;
    /// Advance one time step under the action value (force, tilt angle or rate, or throttle).
    fn step(&mut self, action: f64) -> Transition;
    /// Step every system in `envs` under its own action, `out[k] = envs[k].step(actions[k])`:
    /// several trials' steps at once (`crate::lanes`). A system may override it to run its
    /// dynamics as vector lanes; each lane's result must be the bits `step` gives.
    fn step_each(envs: &mut [Self], actions: &[f64], out: &mut [Transition])
    where
        Self: Sized,
    {
        for ((e, &a), t) in envs.iter_mut().zip(actions).zip(out) {
            *t = e.step(a);
        }
    }
}

/// Generates `NAMES` and `slot(name) -> &mut f64` for a parameter struct's scalar fields.
macro_rules! scalar_params {
    ($ty:ty { $($field:ident),* $(,)? }) => {
        impl $ty {
            /// Names of the scalar parameters, as accepted by `--param NAME=VALUE`.
            pub const NAMES: &'static [&'static str] = &[$(stringify!($field)),*];

            /// Mutable access to a scalar parameter by name.
            pub fn slot(&mut self, name: &str) -> Option<&mut f64> {
                match name {
                    $(stringify!($field) => Some(&mut self.$field),)*
                    _ => None,
                }
            }
        }
    };
}
pub(crate) use scalar_params;

/// Systems a vector kernel steps together ([`Environment::step_each`]).
pub const LANES: usize = 4;

/// [`Environment::step_each`] by `kernel`, which steps [`LANES`] systems at a time at a vector
/// level; the systems left over step one by one.
#[inline(always)]
pub(crate) fn step_each_in_lanes<E: Environment>(
    envs: &mut [E],
    actions: &[f64],
    out: &mut [Transition],
    kernel: fn(Simd, &mut [E; LANES], &[f64; LANES], &mut [Transition; LANES]),
) {
    let level = crate::simd::level();
    let mut e = envs.chunks_exact_mut(LANES);
    let mut a = actions.chunks_exact(LANES);
    let mut o = out.chunks_exact_mut(LANES);
    for ((e, a), o) in (&mut e).zip(&mut a).zip(&mut o) {
        let e: &mut [E; LANES] = e.try_into().expect("LANES systems");
        kernel(level, e, a.try_into().expect("LANES actions"), o.try_into().expect("LANES transitions"));
    }
    for ((e, &a), o) in e.into_remainder().iter_mut().zip(a.remainder()).zip(o.into_remainder()) {
        *o = e.step(a);
    }
}
