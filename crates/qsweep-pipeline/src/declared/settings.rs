//! The settings a pipeline gives per system or pipeline-wide (learner, limits, representation,
//! ranges), the per-system markers that type them, and their numeric checks.

use super::fields::{at_field, variable_index};
use super::values::{AtLeastOne, Bounds, CheckedKey, Finite, Positive, SubUnit, Unit};
use qsweep_engine::config::{TieBreak, TraceKind, Truncation};
use qsweep_engine::env::{
    BallBeamParams, CartPoleParams, EnvParams, MountainCarParams, StartKind, SystemKind,
};
use qsweep_engine::repr::Binning;
use qsweep_engine::rules;
use serde::de::{self, DeserializeOwned, Deserializer, MapAccess, Visitor};
use serde::{Deserialize, Serialize};
use std::fmt;
use std::marker::PhantomData;

/// Compile-time identity of a system, so its section can check variable names while parsing.
pub trait SystemMarker: fmt::Debug + Clone + Sync + 'static {
    /// The system.
    const SYSTEM: SystemKind;
    /// Its physical parameter struct.
    type Params: DeserializeOwned + Serialize + Default + Clone + fmt::Debug + Sync;
    /// Its success-criterion section.
    type Success: DeserializeOwned + Serialize + Clone + fmt::Debug + Sync;
    /// The parameters as the simulation's tagged form.
    fn env(p: &Self::Params) -> EnvParams;
    /// The success section's rules across its fields (`Err`: what is wrong and the fix).
    fn check_success(s: &Self::Success) -> Result<(), String>;
}

/// Physical parameters, validated together inside deserialisation; an error names the parameter.
pub(super) fn valid_params<'de, M: SystemMarker, D: Deserializer<'de>>(d: D) -> Result<M::Params, D::Error> {
    let p = M::Params::deserialize(d)?;
    match M::env(&p).invalid_field() {
        Some((name, e)) => Err(at_field(&[name], e)),
        None => Ok(p),
    }
}

/// Marker for Ball-Beam.
#[derive(Debug, Clone)]
pub struct BallBeamM;

/// Marker for Cart-Pole.
#[derive(Debug, Clone)]
pub struct CartPoleM;

/// Marker for Mountain Car.
#[derive(Debug, Clone)]
pub struct MountainCarM;

impl SystemMarker for BallBeamM {
    const SYSTEM: SystemKind = SystemKind::BallBeam;
    type Params = BallBeamParams;
    type Success = BalanceSpec;
    fn env(p: &BallBeamParams) -> EnvParams {
        EnvParams::BallBeam(p.clone())
    }
    fn check_success(s: &Self::Success) -> Result<(), String> {
        s.check()
    }
}

impl SystemMarker for CartPoleM {
    const SYSTEM: SystemKind = SystemKind::CartPole;
    type Params = CartPoleParams;
    type Success = BalanceSpec;
    fn env(p: &CartPoleParams) -> EnvParams {
        EnvParams::CartPole(p.clone())
    }
    fn check_success(s: &Self::Success) -> Result<(), String> {
        s.check()
    }
}

impl SystemMarker for MountainCarM {
    const SYSTEM: SystemKind = SystemKind::MountainCar;
    type Params = MountainCarParams;
    type Success = ReachSpec;
    fn env(p: &MountainCarParams) -> EnvParams {
        EnvParams::MountainCar(p.clone())
    }
    fn check_success(s: &Self::Success) -> Result<(), String> {
        s.check()
    }
}

/// Survival success criterion: `steps` alone (one episode that long without failure), or with
/// `window` and `mean_length` Gym's solved rule, episodes cut at `steps` (`qsweep_engine::solved`). Each
/// value is range-checked at its own key; the rule across them is [`BalanceSpec::check`].
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BalanceSpec {
    /// Steps without failure that reach the learning goal (under the solved rule: the episode cut).
    #[serde(deserialize_with = "step_count")]
    pub steps: u64,
    /// The solved rule's window of consecutive episodes (given with `mean_length`).
    #[serde(default, deserialize_with = "opt_at_least_one_u32", skip_serializing_if = "Option::is_none")]
    pub window: Option<u32>,
    /// The solved rule's threshold: the window's mean episode length must reach it (≥).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mean_length: Option<Positive>,
}

impl BalanceSpec {
    /// The rule across the fields: the solved rule's two values come together.
    pub fn check(&self) -> Result<(), String> {
        solved_pair(self.window, self.mean_length, rules::SOLVED_BALANCE_SYNTAX)
    }
}

/// Goal-reaching success criterion; unset fields keep their defaults. With `window` and
/// `mean_length` it is Gym's solved rule instead of `within`/`streak`, episodes cut at
/// `max_episode_steps`. Each value is range-checked at its own key; the rule across them is
/// [`ReachSpec::check`].
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ReachSpec {
    /// An episode reaching the goal within this many steps is a success (unused by the solved rule).
    #[serde(default, deserialize_with = "opt_at_least_one_u64")]
    pub within: Option<u64>,
    /// Consecutive successful episodes needed.
    #[serde(default, deserialize_with = "opt_at_least_one_u64")]
    pub streak: Option<u64>,
    /// Episodes are cut off after this many steps.
    #[serde(default, deserialize_with = "opt_step_count")]
    pub max_episode_steps: Option<u64>,
    /// The solved rule's window of consecutive episodes (given with `mean_length`).
    #[serde(default, deserialize_with = "opt_at_least_one_u32", skip_serializing_if = "Option::is_none")]
    pub window: Option<u32>,
    /// The solved rule's threshold: the window's mean episode length must reach it (≤).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mean_length: Option<Positive>,
}

impl ReachSpec {
    /// The rules across the fields: the solved rule's two values come together, and replace the
    /// streak rule rather than join it.
    pub fn check(&self) -> Result<(), String> {
        solved_pair(self.window, self.mean_length, rules::SOLVED_REACH_SYNTAX)?;
        if self.window.is_some() && self.streak.is_some() {
            return Err("`streak` and `window` are two different goals (`streak` episodes in a row \
                        within `within` steps, or Gym's solved rule over `window` episodes); remove one"
                .into());
        }
        Ok(())
    }
}

/// The solved rule's two values come together: `Err` says which is missing and how to write it.
fn solved_pair(window: Option<u32>, mean_length: Option<Positive>, syntax: &str) -> Result<(), String> {
    let (given, missing) = match (window, mean_length) {
        (Some(_), None) => ("window", "mean_length"),
        (None, Some(_)) => ("mean_length", "window"),
        _ => return Ok(()),
    };
    Err(format!(
        "`{given}` needs `{missing}`: Gym's solved rule takes both (the mean episode length over \
         `window` episodes must reach `mean_length`), e.g. `{syntax}`; or give neither"
    ))
}

/// Learner, representation and cap settings; every field optional so levels can be layered:
/// built-in defaults < pipeline `defaults` < system `settings` < system `crisp`/`fuzzy` <
/// experiment `settings`.
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Settings {
    /// Exploration rate ε.
    #[serde(default)]
    pub epsilon: Option<Unit>,
    /// Discount γ.
    #[serde(default)]
    pub gamma: Option<Unit>,
    /// Learning rate α.
    #[serde(default)]
    pub alpha: Option<Positive>,
    /// Trace decay λ (Q(λ) only).
    #[serde(default)]
    pub lambda: Option<Unit>,
    /// Initial Q value.
    #[serde(default)]
    pub q_init: Option<Finite>,
    /// Greedy tie-breaking: random or first.
    #[serde(default)]
    pub tie_break: Option<TieBreak>,
    /// Trace rule: accumulating or replacing (Q(λ) only).
    #[serde(default)]
    pub traces: Option<TraceKind>,
    /// Watkins's trace cut after exploratory actions (Q(λ) only).
    #[serde(default)]
    pub watkins_cut: Option<bool>,
    /// Traces below this are dropped (Q(λ) only).
    #[serde(default)]
    pub trace_cutoff: Option<SubUnit>,
    /// Fuzzy σ as a multiple of the centre spacing.
    #[serde(default)]
    pub width: Option<Positive>,
    /// Fuzzy memberships below this are skipped (0 = exact).
    #[serde(default)]
    pub prune: Option<SubUnit>,
    /// Episode cap per trial.
    #[serde(default, deserialize_with = "opt_at_least_one_u32")]
    pub max_episodes: Option<u32>,
    /// Step cap per trial.
    #[serde(default, deserialize_with = "opt_at_least_one_u64")]
    pub max_total_steps: Option<u64>,
    /// An episode cut off at the step limit: bootstrap from its last state, or treat it as terminal.
    #[serde(default)]
    pub truncation: Option<Truncation>,
    /// Episode start states: fixed, or Gymnasium's `reset()` distribution.
    #[serde(default)]
    pub start: Option<StartKind>,
    /// Crisp bin edges: midpoint (equal bins) or digitize (`np.digitize` over `np.linspace(lo, hi, n)`).
    #[serde(default)]
    pub binning: Option<Binning>,
}

/// A settings level that sets only `name` to `v`, through the same typed, range-checked parse as
/// a `settings:` section (so an axis value obeys the same rules as a written one).
pub fn setting_level(name: &str, v: f64) -> Result<Settings, String> {
    let mut m = serde_yaml::Mapping::new();
    m.insert(name.into(), yaml_number(v));
    serde_yaml::from_value(serde_yaml::Value::Mapping(m)).map_err(|e| e.to_string())
}

/// A YAML number for `v`: an integer when `v` is whole, so integer settings (`max_episodes`) accept it.
pub(super) fn yaml_number(v: f64) -> serde_yaml::Value {
    if v.fract() == 0.0 && v.abs() < 9e15 {
        serde_yaml::Value::Number((v as i64).into())
    } else {
        serde_yaml::Value::Number(v.into())
    }
}

/// Per-variable ranges of one system, checked against its variable names.
#[derive(Debug, Clone)]
pub struct Ranges<M> {
    /// `(variable index, [lo, hi])`, in file order.
    pub entries: Vec<(usize, [f64; 2])>,
    _m: PhantomData<M>,
}

impl<M> Default for Ranges<M> {
    fn default() -> Self {
        Self { entries: Vec::new(), _m: PhantomData }
    }
}

impl<'de, M: SystemMarker> Deserialize<'de> for Ranges<M> {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V<M>(PhantomData<M>);
        impl<'de, M: SystemMarker> Visitor<'de> for V<M> {
            type Value = Ranges<M>;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                write!(f, "a map from {} variables to [lo, hi]", M::SYSTEM)
            }
            fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<Ranges<M>, A::Error> {
                let mut out = Ranges::default();
                while let Some(j) = map.next_key_seed(CheckedKey(|name: String| {
                    let j = variable_index(M::SYSTEM, &name)?;
                    match out.entries.iter().any(|(k, _)| *k == j) {
                        true => Err(format!("`{name}` is given twice")),
                        false => Ok(j),
                    }
                }))? {
                    let Bounds(b) = map.next_value()?;
                    out.entries.push((j, b));
                }
                Ok(out)
            }
        }
        d.deserialize_map(V(PhantomData))
    }
}

pub(super) fn at_least_one_u64<'de, D: Deserializer<'de>>(d: D) -> Result<u64, D::Error> {
    AtLeastOne::deserialize(d).map(|v| v.0)
}

pub(super) fn opt_at_least_one_u64<'de, D: Deserializer<'de>>(d: D) -> Result<Option<u64>, D::Error> {
    at_least_one_u64(d).map(Some)
}

pub(super) fn opt_at_least_one_u32<'de, D: Deserializer<'de>>(d: D) -> Result<Option<u32>, D::Error> {
    let v = rules::at_least_one(u64::from(u32::deserialize(d)?)).map_err(de::Error::custom)?;
    Ok(Some(v as u32))
}

pub(super) fn step_count<'de, D: Deserializer<'de>>(d: D) -> Result<u64, D::Error> {
    rules::steps(u64::deserialize(d)?).map_err(de::Error::custom)
}

pub(super) fn opt_step_count<'de, D: Deserializer<'de>>(d: D) -> Result<Option<u64>, D::Error> {
    step_count(d).map(Some)
}
