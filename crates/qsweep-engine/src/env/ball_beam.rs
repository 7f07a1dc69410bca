//! Ball-Beam, eq. (1): the ball rolls under gravity along a beam tilted by the beam angle θ.
//! Reward eq. (23): 0 while |x| ≤ L/2, −1 (terminal) when the ball falls off.
//!
//! What the action sets is the `control` parameter. Under `angle` (the paper's reading, the
//! default) the action is θ itself. Under `rate` (ballbeam-gym's discrete mode,
//! `ballbeam_gym/envs/base.py`) the action is θ's rate of change: each step first moves the beam,
//! θ ← clamp(θ + rate·τ, −angle_max, angle_max), then eq. (1) advances the ball with sin(θ). θ is
//! 0 at every episode start and is the system's hidden third state entry: the representation
//! sees only (x, ẋ).

use super::environment::{scalar_params, Environment, State, TaskKind, Transition, LANES};
use serde::{Deserialize, Serialize};

/// What a Ball-Beam action sets.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
#[serde(rename_all = "kebab-case")]
pub enum BeamControl {
    /// The action is the beam angle θ (rad): A_n spans [−angle_max, angle_max] (the paper's eq. 1).
    #[default]
    Angle,
    /// The action is θ's rate of change (rad/s): A_n spans [−rate_max, rate_max], and θ is kept
    /// within [−angle_max, angle_max] (ballbeam-gym's discrete mode).
    Rate,
}

impl BeamControl {
    /// Whether this is the default (left out of the canonical JSON).
    pub fn is_default(&self) -> bool {
        *self == Self::default()
    }

    /// YAML / command-line name.
    pub fn name(self) -> &'static str {
        match self {
            Self::Angle => "angle",
            Self::Rate => "rate",
        }
    }
}

/// Default largest beam rate under `rate` control: ballbeam-gym's `angle_change_speed` (rad/s).
pub const DEFAULT_RATE_MAX: f64 = 0.8;

/// Whether `rate_max` is [`DEFAULT_RATE_MAX`] (left out of the canonical JSON).
fn is_default_rate_max(v: &f64) -> bool {
    *v == DEFAULT_RATE_MAX
}

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
    /// Largest tilt (rad): the bounds of A_n under `angle` control, the bounds θ is kept within
    /// under `rate` control. Default π/4.
    pub angle_max: f64,
    /// Start state (x, ẋ).
    pub start: [f64; 2],
    /// What the action sets: the angle (default) or its rate. Left out of the canonical JSON when
    /// it is the default, so configurations from before the setting keep their keys.
    #[serde(skip_serializing_if = "BeamControl::is_default")]
    pub control: BeamControl,
    /// Largest beam rate (rad/s) under `rate` control: A_n spans [−rate_max, rate_max]. Unused
    /// (and normalised to the default) under `angle`; left out of the canonical JSON at the default.
    #[serde(skip_serializing_if = "is_default_rate_max")]
    pub rate_max: f64,
}

impl Default for BallBeamParams {
    fn default() -> Self {
        Self {
            gravity: 9.81,
            tau: 0.02,
            beam_length: 2.0,
            angle_max: std::f64::consts::FRAC_PI_4,
            start: [0.0; 2],
            control: BeamControl::Angle,
            rate_max: DEFAULT_RATE_MAX,
        }
    }
}

impl BallBeamParams {
    /// The symmetric action bound: A_n spans `[-max, max]` (an angle, or a rate under `rate`).
    pub fn action_max(&self) -> f64 {
        match self.control {
            BeamControl::Angle => self.angle_max,
            BeamControl::Rate => self.rate_max,
        }
    }
}

scalar_params!(BallBeamParams { gravity, tau, beam_length, angle_max, rate_max });

/// Where the beam angle θ lives in the state vector under `rate` control (after x, ẋ).
const THETA: usize = 2;

/// The Ball-Beam system.
#[derive(Debug, Clone)]
pub struct BallBeam {
    p: BallBeamParams,
    half_length: f64,
    state: State,
}

impl BallBeam {
    /// A ball-beam at its start state (beam level).
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

    /// (x, ẋ), and under `rate` control the beam angle from entry 2 (0 when not given).
    fn set_state(&mut self, state: &[f64]) {
        self.state[..2].copy_from_slice(&state[..2]);
        if self.p.control == BeamControl::Rate {
            self.state[THETA] = state.get(THETA).copied().unwrap_or(0.0);
        }
    }

    fn state(&self) -> &State {
        &self.state
    }

    #[inline]
    fn step(&mut self, action: f64) -> Transition {
        let angle = self.angle(action);
        self.advance(crate::math::sin(angle))
    }

    fn step_each(envs: &mut [Self], actions: &[f64], out: &mut [Transition]) {
        super::environment::step_each_in_lanes(envs, actions, out, step_lanes_at);
    }
}

impl BallBeam {
    /// The beam angle of this step under `action` (under `rate` control, kept as state).
    #[inline(always)]
    fn angle(&mut self, action: f64) -> f64 {
        match self.p.control {
            BeamControl::Angle => action,
            BeamControl::Rate => {
                let theta =
                    (self.state[THETA] + action * self.p.tau).clamp(-self.p.angle_max, self.p.angle_max);
                self.state[THETA] = theta;
                theta
            }
        }
    }

    /// The rest of the step, given the sine of its beam angle.
    #[inline(always)]
    fn advance(&mut self, sin_angle: f64) -> Transition {
        let [x, x_dot, ..] = self.state;
        // Eq. (1): position advances with the previous velocity (explicit Euler).
        let x = x + self.p.tau * x_dot;
        let x_dot = x_dot + self.p.tau * self.p.gravity * sin_angle;
        self.state[0] = x;
        self.state[1] = x_dot;
        let failed = x.abs() > self.half_length;
        Transition { reward: if failed { -1.0 } else { 0.0 }, terminal: failed }
    }
}

crate::simd::dispatch! {
    /// [`step_lanes`] at `level`'s vector width.
    fn step_lanes_at => step_lanes(envs: &mut [BallBeam; LANES], actions: &[f64; LANES], out: &mut [Transition; LANES])
}

/// [`LANES`] ball-beams' steps: their sines computed together ([`crate::math::sin_cos_lanes`]), the
/// rest of each step exactly as [`Environment::step`] takes it.
#[inline(always)]
fn step_lanes(envs: &mut [BallBeam; LANES], actions: &[f64; LANES], out: &mut [Transition; LANES]) {
    let angle: [f64; LANES] = std::array::from_fn(|k| envs[k].angle(actions[k]));
    let (sin, _) = crate::math::sin_cos_lanes(angle);
    for k in 0..LANES {
        out[k] = envs[k].advance(sin[k]);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rate_params() -> BallBeamParams {
        BallBeamParams {
            tau: 0.1,
            beam_length: 1.0,
            angle_max: 0.2,
            control: BeamControl::Rate,
            ..BallBeamParams::default()
        }
    }

    #[test]
    fn rate_control_moves_the_beam_then_the_ball() {
        // By hand, τ = 0.1, g = 9.81, rate ±0.8 rad/s (θ moves 0.08 per step), θ within ±0.2:
        //   step 1, +0.8: θ = 0.08;             x = 0 + 0.1·0 = 0;           ẋ = 0.981·sin(0.08)
        //   step 2, +0.8: θ = 0.16;             x = 0.1·ẋ₁;                  ẋ₂ = ẋ₁ + 0.981·sin(0.16)
        //   step 3, +0.8: θ = 0.24 → 0.2;       x = x₂ + 0.1·ẋ₂;             ẋ₃ = ẋ₂ + 0.981·sin(0.2)
        //   step 4, −0.8: θ = 0.12
        let sin = crate::math::sin;
        let mut b = BallBeam::new(rate_params());
        let g_tau = 0.1 * 9.81;
        let v1 = g_tau * sin(0.08);
        let v2 = v1 + g_tau * sin(0.16);
        let x3 = 0.1 * v1 + 0.1 * v2;
        let v3 = v2 + g_tau * sin(0.2);
        for (rate, theta, x, v) in [(0.8, 0.08, 0.0, v1), (0.8, 0.16, 0.1 * v1, v2), (0.8, 0.2, x3, v3)] {
            let t = b.step(rate);
            assert!(!t.terminal);
            assert!((b.state()[THETA] - theta).abs() < 1e-15, "θ {} ≠ {theta}", b.state()[THETA]);
            assert!((b.state()[0] - x).abs() < 1e-15 && (b.state()[1] - v).abs() < 1e-15, "{:?}", b.state());
        }
        // The same by hand in decimals: sin(0.08) = 0.0799147, sin(0.16) = 0.1593182, sin(0.2) = 0.1986693.
        assert!(
            (v1 - 0.0783963).abs() < 1e-7 && (v2 - 0.2346875).abs() < 1e-7 && (v3 - 0.4295821).abs() < 1e-7
        );
        assert!((x3 - 0.0313084).abs() < 1e-7);
        b.step(-0.8);
        assert!((b.state()[THETA] - 0.12).abs() < 1e-15, "the clamp held θ at 0.2; −0.08 gives 0.12");
        b.reset();
        assert_eq!(b.state(), &[0.0; 4], "reset levels the beam");
    }

    #[test]
    fn angle_control_ignores_and_keeps_no_beam_state() {
        let mut b = BallBeam::new(BallBeamParams::default());
        b.step(0.5);
        assert_eq!(b.state()[THETA], 0.0);
        b.set_state(&[0.1, 0.2, 0.3, 0.0]);
        assert_eq!(b.state(), &[0.1, 0.2, 0.0, 0.0]);
        let mut r = BallBeam::new(rate_params());
        r.set_state(&[0.1, 0.2, 0.15, 0.0]);
        assert_eq!(r.state(), &[0.1, 0.2, 0.15, 0.0], "rate control restores the beam angle");
        r.set_state(&[0.1, 0.2]);
        assert_eq!(r.state()[THETA], 0.0, "a state without it starts level");
    }

    #[test]
    fn action_bounds_follow_the_control() {
        assert_eq!(BallBeamParams::default().action_max(), std::f64::consts::FRAC_PI_4);
        assert_eq!(rate_params().action_max(), 0.8);
    }
}
