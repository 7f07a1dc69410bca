//! Ball-Beam, eq. (1): the ball rolls under gravity along a beam tilted by the action angle φ.
//! Reward eq. (23): 0 while |x| ≤ L/2, −1 (terminal) when the ball falls off.

use super::environment::{scalar_params, Environment, State, TaskKind, Transition};
use serde::{Deserialize, Serialize};

/// Ball-Beam constants; the beam length is not given in the paper (see the replication notes).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct BallBeamParams {
    /// Gravitational acceleration g (m/s²).
    pub gravity: f64,
    /// Time step τ (s).
    pub tau: f64,
    /// Beam length L: failure when |x| > L/2 (m). Default 2 (Fig. 4 implies x ∈ [−1, 1]).
    pub beam_length: f64,
    /// Largest tilt: A_n spans [−angle_max, angle_max] (rad). Default π/4.
    pub angle_max: f64,
    /// Start state (x, ẋ).
    pub start: [f64; 2],
}

impl Default for BallBeamParams {
    fn default() -> Self {
        Self {
            gravity: 9.81,
            tau: 0.02,
            beam_length: 2.0,
            angle_max: std::f64::consts::FRAC_PI_4,
            start: [0.0; 2],
        }
    }
}

scalar_params!(BallBeamParams { gravity, tau, beam_length, angle_max });

/// The Ball-Beam system.
#[derive(Debug, Clone)]
pub struct BallBeam {
    p: BallBeamParams,
    half_length: f64,
    state: State,
}

impl BallBeam {
    /// A ball-beam at its start state.
    pub fn new(p: BallBeamParams) -> Self {
        let half_length = p.beam_length / 2.0;
        let state = [p.start[0], p.start[1], 0.0, 0.0];
        Self { p, half_length, state }
    }
}

impl Environment for BallBeam {
    const DIM: usize = 2;
    const TASK: TaskKind = TaskKind::Survival;

    fn reset(&mut self) {
        self.state = [self.p.start[0], self.p.start[1], 0.0, 0.0];
    }

    fn set_state(&mut self, state: &[f64]) {
        self.state[..2].copy_from_slice(&state[..2]);
    }

    fn state(&self) -> &State {
        &self.state
    }

    #[inline]
    fn step(&mut self, angle: f64) -> Transition {
        let [x, x_dot, ..] = self.state;
        // Eq. (1): position advances with the previous velocity (explicit Euler).
        let x = x + self.p.tau * x_dot;
        let x_dot = x_dot + self.p.tau * self.p.gravity * crate::sim::math::sin(angle);
        self.state[0] = x;
        self.state[1] = x_dot;
        let failed = x.abs() > self.half_length;
        Transition { reward: if failed { -1.0 } else { 0.0 }, terminal: failed }
    }
}
