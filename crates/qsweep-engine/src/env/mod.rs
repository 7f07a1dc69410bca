//! The paper's three control systems (Section III-A) behind one small [`Environment`] trait.
//!
//! Each system is a plain struct of named physical parameters (defaults are the paper's values) plus
//! its current state. States are fixed-size arrays padded to [`MAX_DIM`] so the per-step loop never
//! allocates; only the first [`Environment::DIM`] entries are observed (the representation sees
//! them). A system may keep hidden state in the padding: Ball-Beam's beam angle under rate control.
//!
//! The rest of the engine reaches a system's concrete type only through `with_env_type!` (by
//! [`SystemKind`]) and `with_env!` (by [`EnvParams`], building the system through [`FromParams`],
//! implemented here), so the list of systems is written here once, and a system's own file knows
//! only itself.

mod ball_beam;
mod cart_pole;
mod environment;
mod mountain_car;

pub use ball_beam::{BallBeam, BallBeamParams, BeamControl, DEFAULT_RATE_MAX as BALL_BEAM_DEFAULT_RATE_MAX};
pub use cart_pole::{CartPole, CartPoleParams, GYM_START as CART_POLE_GYM_START};
pub use environment::{Environment, State, TaskKind, Transition, LANES, MAX_DIM};
pub use mountain_car::{MountainCar, MountainCarParams, GYM_START_X as MOUNTAIN_CAR_GYM_START_X};

use serde::{Deserialize, Serialize};
use std::fmt;

/// Where episodes start.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
#[serde(rename_all = "kebab-case")]
pub enum StartKind {
    /// The system's fixed start state (`params.start`; Cart-Pole and Ball-Beam at rest at 0,
    /// Mountain Car at x = −0.5 at rest), every episode.
    #[default]
    Fixed,
    /// Gymnasium's `reset()` distribution, drawn from the trial's random stream at each episode
    /// start: Cart-Pole U(−0.05, 0.05) per variable (CartPole-v0/v1), Mountain Car x ~ U(−0.6, −0.4)
    /// and ẋ = 0 (MountainCar-v0). Ball-Beam has no Gymnasium environment and keeps its fixed start.
    Gym,
}

impl StartKind {
    /// Whether this is the default (left out of the canonical JSON).
    pub fn is_default(&self) -> bool {
        *self == Self::default()
    }

    /// YAML / command-line name.
    pub fn name(self) -> &'static str {
        match self {
            Self::Fixed => "fixed",
            Self::Gym => "gym",
        }
    }
}

/// The systems qsweep knows, by their command-line and YAML names.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum SystemKind {
    /// Ball-Beam, eq. (1).
    BallBeam,
    /// Cart-Pole, eq. (2).
    CartPole,
    /// Mountain Car, eq. (3).
    MountainCar,
}

impl SystemKind {
    /// Every system, in report order (the paper's Figures 5, 6, 7).
    pub const ALL: [SystemKind; 3] = [Self::BallBeam, Self::CartPole, Self::MountainCar];

    /// Command-line / YAML name.
    pub fn name(self) -> &'static str {
        match self {
            Self::BallBeam => "ball-beam",
            Self::CartPole => "cart-pole",
            Self::MountainCar => "mountain-car",
        }
    }

    /// Human-readable name as the paper writes it.
    pub fn title(self) -> &'static str {
        match self {
            Self::BallBeam => "Ball-Beam",
            Self::CartPole => "Cart-Pole",
            Self::MountainCar => "Mountain Car",
        }
    }

    /// Parse a command-line / YAML name.
    pub fn parse(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|s| s.name() == name)
    }

    /// The systems' names as a message lists them: `ball-beam, cart-pole or mountain-car`.
    pub fn listed() -> String {
        let names: Vec<&str> = Self::ALL.iter().map(|s| s.name()).collect();
        match names.split_last() {
            Some((last, [])) => last.to_string(),
            Some((last, rest)) => format!("{} or {last}", rest.join(", ")),
            None => String::new(),
        }
    }

    /// State variable names, in state-vector order.
    pub fn variables(self) -> &'static [&'static str] {
        match self {
            Self::BallBeam | Self::MountainCar => &["x", "x_dot"],
            Self::CartPole => &["x", "x_dot", "theta", "theta_dot"],
        }
    }

    /// Number of state variables.
    pub fn dim(self) -> usize {
        self.variables().len()
    }

    /// How reports write the state variable `name` of [`SystemKind::variables`]: its Unicode
    /// symbol and its LaTeX in math mode (`x_dot`: `ẋ`, `\dot{x}`). A name without a symbol of
    /// its own is written as itself (`\mathrm{…}` in LaTeX), so a new system's variables need
    /// nothing here to be reported.
    pub fn variable_symbol(name: &str) -> (String, String) {
        let known = match name {
            "x" => Some(("x", "x")),
            "x_dot" => Some(("ẋ", "\\dot{x}")),
            "theta" => Some(("θ", "\\theta")),
            "theta_dot" => Some(("θ̇", "\\dot{\\theta}")),
            _ => None,
        };
        match known {
            Some((symbol, latex)) => (symbol.to_string(), latex.to_string()),
            None => (name.to_string(), format!("\\mathrm{{{}}}", name.replace('_', "\\_"))),
        }
    }

    /// The paper's fixed action count for the system (Section III-A).
    pub fn default_actions(self) -> u32 {
        match self {
            Self::CartPole => 2,
            Self::BallBeam | Self::MountainCar => 3,
        }
    }
}

impl fmt::Display for SystemKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// `$body` with `$E` naming the [`Environment`] type of system `$kind` (a [`SystemKind`]): the one
/// place the engine maps a system to its type, so generic code over `E: Environment` runs
/// monomorphized per system and a new system is one arm here (the match is exhaustive). Expanded
/// once per arm; only the taken arm runs, so `$body` may move values.
macro_rules! with_env_type {
    ($kind:expr, $E:ident => $body:expr) => {
        match $kind {
            $crate::env::SystemKind::BallBeam => {
                type $E = $crate::env::BallBeam;
                $body
            }
            $crate::env::SystemKind::CartPole => {
                type $E = $crate::env::CartPole;
                $body
            }
            $crate::env::SystemKind::MountainCar => {
                type $E = $crate::env::MountainCar;
                $body
            }
        }
    };
}
pub(crate) use with_env_type;

/// `$body` with `$env` bound to the system `$params` (an `&EnvParams`) describe, at its start state,
/// and `$E` naming its type: [`with_env_type`] over the parameters' system. Once per trial (or
/// rollout), outside any step loop.
macro_rules! with_env {
    ($params:expr, |$env:ident: $E:ident| $body:expr) => {{
        let params: &$crate::env::EnvParams = $params;
        $crate::env::with_env_type!(params.system(), $E => {
            let $env = <$E as $crate::env::FromParams>::from_params(params)
                .expect("parameters build their own system");
            $body
        })
    }};
}
pub(crate) use with_env;

/// A system built from its tagged parameters, as [`with_env`] and the lockstep lanes build one.
/// Implemented here, beside [`EnvParams`], so that a system's own file needs nothing of the enum
/// that lists every system.
pub trait FromParams: Environment + Sized {
    /// The system `params` describe, at its start state; `None` for another system's parameters.
    fn from_params(params: &EnvParams) -> Option<Self>;
}

impl FromParams for BallBeam {
    fn from_params(params: &EnvParams) -> Option<Self> {
        match params {
            EnvParams::BallBeam(p) => Some(Self::new(p.clone())),
            _ => None,
        }
    }
}

impl FromParams for CartPole {
    fn from_params(params: &EnvParams) -> Option<Self> {
        match params {
            EnvParams::CartPole(p) => Some(Self::new(p.clone())),
            _ => None,
        }
    }
}

impl FromParams for MountainCar {
    fn from_params(params: &EnvParams) -> Option<Self> {
        match params {
            EnvParams::MountainCar(p) => Some(Self::new(p.clone())),
            _ => None,
        }
    }
}

/// Physical parameters of one system, tagged by system.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "system", rename_all = "kebab-case")]
pub enum EnvParams {
    /// Ball-Beam parameters.
    BallBeam(BallBeamParams),
    /// Cart-Pole parameters.
    CartPole(CartPoleParams),
    /// Mountain Car parameters.
    MountainCar(MountainCarParams),
}

impl EnvParams {
    /// The paper's parameters for a system.
    pub fn default_for(system: SystemKind) -> Self {
        match system {
            SystemKind::BallBeam => Self::BallBeam(BallBeamParams::default()),
            SystemKind::CartPole => Self::CartPole(CartPoleParams::default()),
            SystemKind::MountainCar => Self::MountainCar(MountainCarParams::default()),
        }
    }

    /// Which system these parameters belong to.
    pub fn system(&self) -> SystemKind {
        match self {
            Self::BallBeam(_) => SystemKind::BallBeam,
            Self::CartPole(_) => SystemKind::CartPole,
            Self::MountainCar(_) => SystemKind::MountainCar,
        }
    }

    /// The symmetric action bounds of eq. (22): A_n spans `[-max, max]` (Ball-Beam: its angle, or
    /// its rate under `control: rate`).
    pub fn action_max(&self) -> f64 {
        match self {
            Self::BallBeam(p) => p.action_max(),
            Self::CartPole(p) => p.force,
            Self::MountainCar(p) => p.action_max,
        }
    }

    /// Names of the scalar parameters `set_param` accepts.
    pub fn param_names(&self) -> &'static [&'static str] {
        match self {
            Self::BallBeam(_) => BallBeamParams::NAMES,
            Self::CartPole(_) => CartPoleParams::NAMES,
            Self::MountainCar(_) => MountainCarParams::NAMES,
        }
    }

    /// Set one scalar parameter by name; `Err` lists the valid names.
    pub fn set_param(&mut self, name: &str, value: f64) -> Result<(), String> {
        let slot = match self {
            Self::BallBeam(p) => p.slot(name),
            Self::CartPole(p) => p.slot(name),
            Self::MountainCar(p) => p.slot(name),
        };
        match slot {
            Some(v) => {
                *v = value;
                Ok(())
            }
            None => Err(format!(
                "unknown parameter '{name}' for {}; valid: {}",
                self.system(),
                self.param_names().join(", ")
            )),
        }
    }

    /// The start state (first `dim` entries meaningful).
    pub fn start(&self) -> State {
        match self {
            Self::BallBeam(p) => [p.start[0], p.start[1], 0.0, 0.0],
            Self::CartPole(p) => p.start,
            Self::MountainCar(p) => [p.start[0], p.start[1], 0.0, 0.0],
        }
    }

    /// Check physical sanity; `Err` says which parameter and what is allowed.
    pub fn validate(&self) -> Result<(), String> {
        self.invalid_field().map_or(Ok(()), |(name, e)| Err(format!("{name}: {e}")))
    }

    /// The first parameter that breaks its rule (see `crate::rules`), with the message, if any.
    pub fn invalid_field(&self) -> Option<(&'static str, String)> {
        use super::rules::{FINITE, POSITIVE};
        type Fields = Vec<(&'static str, f64)>;
        let (positive, finite): (Fields, Fields) = match self {
            Self::BallBeam(p) => (
                vec![("tau", p.tau), ("beam_length", p.beam_length), ("rate_max", p.rate_max)],
                vec![
                    ("gravity", p.gravity),
                    ("angle_max", p.angle_max),
                    ("start", p.start[0]),
                    ("start", p.start[1]),
                ],
            ),
            Self::CartPole(p) => (
                vec![
                    ("tau", p.tau),
                    ("mass_cart", p.mass_cart),
                    ("mass_pole", p.mass_pole),
                    ("half_length", p.half_length),
                    ("x_limit", p.x_limit),
                    ("theta_limit_deg", p.theta_limit_deg),
                ],
                [("gravity", p.gravity), ("force", p.force)]
                    .into_iter()
                    .chain(p.start.iter().map(|&v| ("start", v)))
                    .collect(),
            ),
            Self::MountainCar(p) => (
                vec![("v_max", p.v_max), ("action_max", p.action_max)],
                [
                    ("force", p.force),
                    ("gravity", p.gravity),
                    ("x_min", p.x_min),
                    ("x_max", p.x_max),
                    ("goal", p.goal),
                ]
                .into_iter()
                .chain(p.start.iter().map(|&v| ("start", v)))
                .collect(),
            ),
        };
        let rules =
            positive.into_iter().map(|f| (f, POSITIVE)).chain(finite.into_iter().map(|f| (f, FINITE)));
        for ((name, v), rule) in rules {
            if let Err(e) = rule.check(v) {
                return Some((name, e));
            }
        }
        if let Self::MountainCar(p) = self {
            if p.x_min >= p.x_max {
                return Some((
                    "x_min",
                    format!("{} is not allowed here; expected x_min < x_max = {}", p.x_min, p.x_max),
                ));
            }
        }
        None
    }
}
