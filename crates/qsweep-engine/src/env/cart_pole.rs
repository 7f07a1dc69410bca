//! Cart-Pole, eq. (2): Euler integration of the frictionless cart-pole (Barto et al.; Gymnasium's
//! CartPole-v1 step, with the paper's g = 9.81). Reward eq. (24): 0, or −1 on failure.

use super::environment::{scalar_params, Environment, State, TaskKind, Transition, LANES};
use crate::math;
use crate::rng::TrialRng;
use serde::{Deserialize, Serialize};

/// Cart-Pole's physical constants and failure limits; defaults are the paper's.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct CartPoleParams {
    /// Gravitational acceleration g (m/s²).
    pub gravity: f64,
    /// Cart mass m_c (kg).
    pub mass_cart: f64,
    /// Pole mass m (kg).
    pub mass_pole: f64,
    /// Half the pole length l (m).
    pub half_length: f64,
    /// Time step τ (s).
    pub tau: f64,
    /// Force magnitude: A_n spans [−force, force] (N).
    pub force: f64,
    /// Track limit: failure when |x| > x_limit (m).
    pub x_limit: f64,
    /// Angle limit: failure when |θ| > theta_limit_deg (degrees).
    pub theta_limit_deg: f64,
    /// Start state (x, ẋ, θ, θ̇).
    pub start: [f64; 4],
}

impl Default for CartPoleParams {
    fn default() -> Self {
        Self {
            gravity: 9.81,
            mass_cart: 1.0,
            mass_pole: 0.1,
            half_length: 0.5,
            tau: 0.02,
            force: 10.0,
            x_limit: 2.4,
            theta_limit_deg: 12.0,
            start: [0.0; 4],
        }
    }
}

scalar_params!(CartPoleParams {
    gravity,
    mass_cart,
    mass_pole,
    half_length,
    tau,
    force,
    x_limit,
    theta_limit_deg
});

/// Gymnasium's CartPole `reset()`: every variable ~ U(−0.05, 0.05)
/// (`self.np_random.uniform(low=-0.05, high=0.05, size=(4,))`).
pub const GYM_START: [f64; 2] = [-0.05, 0.05];

impl CartPoleParams {
    /// θ limit in radians, computed as Gymnasium does (`12 * 2 * pi / 360`) so limits agree bit for bit.
    pub fn theta_limit_rad(&self) -> f64 {
        self.theta_limit_deg * 2.0 * std::f64::consts::PI / 360.0
    }
}

/// The Cart-Pole system.
#[derive(Debug, Clone)]
pub struct CartPole {
    p: CartPoleParams,
    total_mass: f64,
    pole_mass_length: f64,
    theta_limit: f64,
    state: State,
}

impl CartPole {
    /// A cart-pole at its start state.
    pub fn new(p: CartPoleParams) -> Self {
        let total_mass = p.mass_pole + p.mass_cart;
        let pole_mass_length = p.mass_pole * p.half_length;
        let theta_limit = p.theta_limit_rad();
        let state = p.start;
        Self { p, total_mass, pole_mass_length, theta_limit, state }
    }
}

impl Environment for CartPole {
    const DIM: usize = 4;
    const TASK: TaskKind = TaskKind::Survival;

    fn reset(&mut self) {
        self.state = self.p.start;
    }

    fn reset_gym(&mut self, rng: &mut TrialRng) {
        // numpy's uniform(low, high) is low + (high − low)·u; x, ẋ, θ, θ̇ in that order.
        let [lo, hi] = GYM_START;
        for v in &mut self.state {
            *v = lo + (hi - lo) * rng.unit();
        }
    }

    fn set_state(&mut self, state: &[f64]) {
        self.state[..4].copy_from_slice(&state[..4]);
    }

    fn state(&self) -> &State {
        &self.state
    }

    #[inline]
    fn step(&mut self, force: f64) -> Transition {
        let (sin, cos) = math::sin_cos(self.state[2]);
        self.advance(force, sin, cos)
    }

    fn step_each(envs: &mut [Self], actions: &[f64], out: &mut [Transition]) {
        super::environment::step_each_in_lanes(envs, actions, out, step_lanes_at);
    }
}

impl CartPole {
    /// The step under `force` from the current state, given sin θ and cos θ.
    #[inline(always)]
    fn advance(&mut self, force: f64, sin: f64, cos: f64) -> Transition {
        let [x, x_dot, theta, theta_dot] = self.state;
        // Same operation order as Gymnasium's CartPole-v1, so trajectories agree to the last bit.
        let temp = (force + self.pole_mass_length * theta_dot * theta_dot * sin) / self.total_mass;
        let theta_acc = (self.p.gravity * sin - cos * temp)
            / (self.p.half_length * (4.0 / 3.0 - self.p.mass_pole * cos * cos / self.total_mass));
        let x_acc = temp - self.pole_mass_length * theta_acc * cos / self.total_mass;
        let tau = self.p.tau;
        self.state =
            [x + tau * x_dot, x_dot + tau * x_acc, theta + tau * theta_dot, theta_dot + tau * theta_acc];
        let (x, theta) = (self.state[0], self.state[2]);
        let failed = x < -self.p.x_limit
            || x > self.p.x_limit
            || theta < -self.theta_limit
            || theta > self.theta_limit;
        Transition { reward: if failed { -1.0 } else { 0.0 }, terminal: failed }
    }
}

crate::simd::dispatch! {
    /// [`step_lanes`] at `level`'s vector width.
    fn step_lanes_at => step_lanes(envs: &mut [CartPole; LANES], actions: &[f64; LANES], out: &mut [Transition; LANES])
}

/// [`LANES`] cart-poles' steps: their sin θ and cos θ computed together
/// ([`math::sin_cos_lanes`]), the rest of each step exactly as [`Environment::step`] takes it.
#[inline(always)]
fn step_lanes(envs: &mut [CartPole; LANES], actions: &[f64; LANES], out: &mut [Transition; LANES]) {
    let (sin, cos) = math::sin_cos_lanes::<LANES>(std::array::from_fn(|k| envs[k].state[2]));
    for k in 0..LANES {
        out[k] = envs[k].advance(actions[k], sin[k], cos[k]);
    }
}
