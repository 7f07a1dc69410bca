//! Mountain Car, eq. (3), as in the classic task (Sutton & Barto; Gymnasium's MountainCar-v0):
//! velocity clipped to ±v_max, position clipped to [x_min, x_max], and a negative velocity zeroed at
//! the left wall. Reward eq. (25): 1 (terminal) at the goal x ≥ goal, −1 otherwise.

use super::environment::{scalar_params, Environment, State, TaskKind, Transition, LANES};
use crate::math;
use crate::rng::TrialRng;
use serde::{Deserialize, Serialize};

/// Mountain Car constants; defaults are the paper's (and MountainCar-v0's).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct MountainCarParams {
    /// Engine power per unit action (0.001 in eq. 3).
    pub force: f64,
    /// Gravity term coefficient (0.0025 in eq. 3).
    pub gravity: f64,
    /// Left wall.
    pub x_min: f64,
    /// Right end of the track.
    pub x_max: f64,
    /// Velocity bound: ẋ is clipped to [−v_max, v_max].
    pub v_max: f64,
    /// Goal position: the episode ends when x ≥ goal.
    pub goal: f64,
    /// Largest throttle: A_n spans [−action_max, action_max]. Default 1.
    pub action_max: f64,
    /// Start state (x, ẋ).
    pub start: [f64; 2],
}

impl Default for MountainCarParams {
    fn default() -> Self {
        Self {
            force: 0.001,
            gravity: 0.0025,
            x_min: -1.2,
            x_max: 0.5,
            v_max: 0.07,
            goal: 0.5,
            action_max: 1.0,
            start: [-0.5, 0.0],
        }
    }
}

scalar_params!(MountainCarParams { force, gravity, x_min, x_max, v_max, goal, action_max });

/// MountainCar-v0's `reset()`: x ~ U(−0.6, −0.4), ẋ = 0
/// (`np.array([self.np_random.uniform(low=-0.6, high=-0.4), 0])`).
pub const GYM_START_X: [f64; 2] = [-0.6, -0.4];

/// The Mountain Car system.
#[derive(Debug, Clone)]
pub struct MountainCar {
    p: MountainCarParams,
    state: State,
}

impl MountainCar {
    /// A mountain car at its start state.
    pub fn new(p: MountainCarParams) -> Self {
        let state = [p.start[0], p.start[1], 0.0, 0.0];
        Self { p, state }
    }
}

impl Environment for MountainCar {
    const DIM: usize = 2;
    const TASK: TaskKind = TaskKind::GoalReaching;

    fn reset(&mut self) {
        self.state = [self.p.start[0], self.p.start[1], 0.0, 0.0];
    }

    fn reset_gym(&mut self, rng: &mut TrialRng) {
        let [lo, hi] = GYM_START_X;
        self.state = [lo + (hi - lo) * rng.unit(), 0.0, 0.0, 0.0];
    }

    fn set_state(&mut self, state: &[f64]) {
        self.state[..2].copy_from_slice(&state[..2]);
    }

    fn state(&self) -> &State {
        &self.state
    }

    #[inline]
    fn step(&mut self, action: f64) -> Transition {
        self.advance(action, math::cos(3.0 * self.state[0]))
    }

    fn step_each(envs: &mut [Self], actions: &[f64], out: &mut [Transition]) {
        super::environment::step_each_in_lanes(envs, actions, out, step_lanes_at);
    }
}

impl MountainCar {
    /// The step under `action` from the current state, given cos(3x).
    #[inline(always)]
    fn advance(&mut self, action: f64, cos_3x: f64) -> Transition {
        let [x, v, ..] = self.state;
        // Operation order as in MountainCar-v0 (velocity first, then position from the new velocity).
        let mut v = v + action * self.p.force + cos_3x * (-self.p.gravity);
        v = v.clamp(-self.p.v_max, self.p.v_max);
        let mut x = x + v;
        x = x.clamp(self.p.x_min, self.p.x_max);
        if x == self.p.x_min && v < 0.0 {
            v = 0.0;
        }
        self.state[0] = x;
        self.state[1] = v;
        let goal = x >= self.p.goal;
        Transition { reward: if goal { 1.0 } else { -1.0 }, terminal: goal }
    }
}

crate::simd::dispatch! {
    /// [`step_lanes`] at `level`'s vector width.
    fn step_lanes_at => step_lanes(cars: &mut [MountainCar; LANES], actions: &[f64; LANES], out: &mut [Transition; LANES])
}

/// [`LANES`] cars' steps: their cos(3x) computed together ([`math::cos_lanes`]), the rest of each
/// step exactly as [`Environment::step`] takes it.
#[inline(always)]
fn step_lanes(cars: &mut [MountainCar; LANES], actions: &[f64; LANES], out: &mut [Transition; LANES]) {
    let cos_3x = math::cos_lanes::<LANES>(std::array::from_fn(|k| 3.0 * cars[k].state[0]));
    for k in 0..LANES {
        out[k] = cars[k].advance(actions[k], cos_3x[k]);
    }
}
