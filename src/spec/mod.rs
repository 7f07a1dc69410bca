//! Pipeline files: the raw, typed form of a YAML pipeline (`pipelines/*.yaml`), parsed with
//! serde_yaml. Unknown keys are rejected, and every value is range-checked while parsing so errors
//! carry the file, line and column. Nothing here resolves defaults: that is `plan`'s job.
//!
//! ```yaml
//! name: quick                     # report folder name: reports/<name>/
//! seeds: 2                        # a count (seeds 0..n-1) or a list [0, 7, 9]
//! defaults: { max_episodes: 500 } # settings for every system (see Settings)
//! systems:
//!   cart-pole:
//!     params: { gravity: 9.81 }   # physical parameters (defaults: the paper's)
//!     ranges: { x_dot: [-2, 2] }  # bin range / first and last fuzzy centre per variable
//!     success: { steps: 100000 }  # survival: steps; mountain-car: {within, streak, max_episode_steps}
//!     crisp: { epsilon: 0.01 }    # settings for crisp experiments of this system (Table II)
//!     fuzzy: { width: 0.4247 }    # settings for fuzzy experiments of this system
//!     experiments:
//!       - id: 1
//!         repr: crisp
//!         algorithms: [q0, q-lambda]
//!         vary: { x == theta: 2..10, x_dot == theta_dot: 2..10 }   # Table I: v(x == θ), v(ẋ == θ̇)
//!         fixed: { actions: 2 }                                     # Table I: c(Actions)
//!         race: { confidence: 0.95, batch: 5, max_seeds: 40 }       # optional (or pipeline-wide)
//! ```

mod experiment;
pub mod explore;
pub mod grid;
mod load;
pub mod locate;
mod overrides;
mod race;
mod values;
mod variants;

pub use experiment::{format_value, target_name, Axis, ExperimentSpec, Reference, Target, AXIS_SETTINGS};
pub use load::{load, load_str, LoadedSpec};
pub use locate::locate;
pub use overrides::Override;
pub use race::{Problem, RaceSpec};
pub use values::{
    AtLeastOne, AxisValues, Bounds, Confidence, Finite, Positive, Seeds, SubUnit, Unit, Values,
};
pub use variants::{LoadedVariant, VariantSpec};

use crate::sim::config::{TieBreak, TraceKind, Truncation};
use crate::sim::env::{BallBeamParams, CartPoleParams, EnvParams, MountainCarParams, StartKind, SystemKind};
use crate::sim::repr::Binning;
use crate::sim::rules;
use load::at_field;
use serde::de::{self, DeserializeOwned, Deserializer, MapAccess, Visitor};
use serde::{Deserialize, Serialize};
use std::fmt;
use std::marker::PhantomData;
use values::CheckedKey;

/// A whole pipeline file.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PipelineSpec {
    /// Pipeline name; reports go to `reports/<name>/`.
    #[serde(deserialize_with = "safe_name")]
    pub name: String,
    /// Free text shown in reports.
    #[serde(default)]
    pub description: Option<String>,
    /// Seeds per cell.
    pub seeds: Seeds,
    /// Race seeds into the cells that can still be the best (every experiment; see [`race`]).
    #[serde(default)]
    pub race: Option<RaceSpec>,
    /// Where the experiments' `reference:` values come from (shown in reports).
    #[serde(default)]
    pub reference_source: Option<String>,
    /// Settings for every system and experiment.
    #[serde(default)]
    pub defaults: Settings,
    /// The systems and their experiments.
    pub systems: Systems,
    /// Alternative readings or settings of the whole pipeline (see [`variants`]).
    #[serde(default, deserialize_with = "opt_variants")]
    pub variants: Option<Vec<VariantSpec>>,
    /// Variants generated as a product of value lists (see [`grid`]).
    #[serde(default)]
    pub variant_grid: Option<grid::VariantGrid>,
    /// An exploratory search: the Table III rows that choose the best reading (see [`explore`]).
    #[serde(default)]
    pub exploratory: Option<explore::Exploratory>,
}

/// The rules that need the whole pipeline: races and the exploratory block.
pub(crate) fn check_whole(spec: &PipelineSpec) -> Result<(), Problem> {
    race::check(spec)?;
    explore::check(spec)
}

fn opt_variants<'de, D: Deserializer<'de>>(d: D) -> Result<Option<Vec<VariantSpec>>, D::Error> {
    variants::variants(d).map(Some)
}

/// The systems a pipeline covers; at least one.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Systems {
    /// Ball-Beam.
    #[serde(rename = "ball-beam", default)]
    pub ball_beam: Option<SystemSpec<BallBeamM>>,
    /// Cart-Pole.
    #[serde(rename = "cart-pole", default)]
    pub cart_pole: Option<SystemSpec<CartPoleM>>,
    /// Mountain Car.
    #[serde(rename = "mountain-car", default)]
    pub mountain_car: Option<SystemSpec<MountainCarM>>,
}

/// Compile-time identity of a system, so its section can check variable names while parsing.
pub trait SystemMarker: fmt::Debug + Clone + 'static {
    /// The system.
    const SYSTEM: SystemKind;
    /// Its physical parameter struct.
    type Params: DeserializeOwned + Serialize + Default + Clone + fmt::Debug;
    /// Its success-criterion section.
    type Success: DeserializeOwned + Serialize + Clone + fmt::Debug;
    /// The parameters as the simulation's tagged form.
    fn env(p: &Self::Params) -> EnvParams;
}

/// Physical parameters, validated together inside deserialisation; an error names the parameter.
fn valid_params<'de, M: SystemMarker, D: Deserializer<'de>>(d: D) -> Result<M::Params, D::Error> {
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
}
impl SystemMarker for CartPoleM {
    const SYSTEM: SystemKind = SystemKind::CartPole;
    type Params = CartPoleParams;
    type Success = BalanceSpec;
    fn env(p: &CartPoleParams) -> EnvParams {
        EnvParams::CartPole(p.clone())
    }
}
impl SystemMarker for MountainCarM {
    const SYSTEM: SystemKind = SystemKind::MountainCar;
    type Params = MountainCarParams;
    type Success = ReachSpec;
    fn env(p: &MountainCarParams) -> EnvParams {
        EnvParams::MountainCar(p.clone())
    }
}

/// One system's section.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields, bound = "")]
pub struct SystemSpec<M: SystemMarker> {
    /// Physical parameters (unset ones keep the paper's values), checked while parsing.
    #[serde(default, deserialize_with = "valid_params::<M, _>")]
    pub params: M::Params,
    /// Per-variable `[lo, hi]` ranges (unset ones keep the defaults).
    #[serde(default)]
    pub ranges: Ranges<M>,
    /// Learning-goal criterion (unset: the default for the system).
    #[serde(default)]
    pub success: Option<M::Success>,
    /// Settings for all of this system's experiments.
    #[serde(default)]
    pub settings: Settings,
    /// Settings for this system's crisp experiments (Table II, "Discrete").
    #[serde(default)]
    pub crisp: Settings,
    /// Settings for this system's fuzzy experiments (Table II, "Fuzzy").
    #[serde(default)]
    pub fuzzy: Settings,
    /// Experiments (Table I rows), at least one, ids unique.
    #[serde(deserialize_with = "experiments::<M, _>")]
    pub experiments: Vec<ExperimentSpec<M>>,
}

/// Survival success criterion.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BalanceSpec {
    /// Steps without failure that reach the learning goal.
    #[serde(deserialize_with = "step_count")]
    pub steps: u64,
}

/// Goal-reaching success criterion; unset fields keep their defaults.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ReachSpec {
    /// An episode reaching the goal within this many steps is a success.
    #[serde(default, deserialize_with = "opt_at_least_one_u64")]
    pub within: Option<u64>,
    /// Consecutive successful episodes needed.
    #[serde(default, deserialize_with = "opt_at_least_one_u64")]
    pub streak: Option<u64>,
    /// Episodes are cut off after this many steps.
    #[serde(default, deserialize_with = "opt_step_count")]
    pub max_episode_steps: Option<u64>,
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
fn yaml_number(v: f64) -> serde_yaml::Value {
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

/// Index of a state variable by name, or an error listing the valid names.
pub fn variable_index(system: SystemKind, name: &str) -> Result<usize, String> {
    let vars = system.variables();
    vars.iter().position(|v| *v == name).ok_or_else(|| {
        let hint = suggest(name, vars.iter().copied().chain(["actions"]))
            .map(|s| format!("; did you mean `{s}`?"))
            .unwrap_or_default();
        format!("unknown variable `{name}` for {system}; its variables are {}{hint}", vars.join(", "))
    })
}

/// The closest candidate to `word` by edit distance, if reasonably close.
pub fn suggest<'a>(word: &str, candidates: impl IntoIterator<Item = &'a str>) -> Option<&'a str> {
    candidates
        .into_iter()
        .map(|c| (edit_distance(word, c), c))
        .filter(|(d, c)| *d <= (c.len().max(word.len()) / 3).max(2))
        .min_by_key(|(d, _)| *d)
        .map(|(_, c)| c)
}

fn edit_distance(a: &str, b: &str) -> usize {
    let b: Vec<char> = b.chars().collect();
    let mut prev: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.chars().enumerate() {
        let mut cur = vec![i + 1; b.len() + 1];
        for (j, cb) in b.iter().enumerate() {
            cur[j + 1] = (prev[j] + usize::from(ca != *cb)).min(prev[j + 1] + 1).min(cur[j] + 1);
        }
        prev = cur;
    }
    prev[b.len()]
}

/// Whether `s` is safe as one folder name on every platform: 1-100 letters, digits, '-', '_' or
/// '.', not starting with '.'.
pub fn safe_folder_name(s: &str) -> Result<(), String> {
    let ok = !s.is_empty()
        && s.len() <= 100
        && s.chars().all(|c| c.is_ascii_alphanumeric() || "-_.".contains(c))
        && !s.starts_with('.');
    if ok {
        Ok(())
    } else {
        Err("use 1-100 letters, digits, '-', '_' or '.', not starting with '.' (it names the report folder)"
            .into())
    }
}

fn safe_name<'de, D: Deserializer<'de>>(d: D) -> Result<String, D::Error> {
    let s = String::deserialize(d)?;
    safe_folder_name(&s).map_err(|why| de::Error::custom(format!("name `{s}` is not allowed; {why}")))?;
    Ok(s)
}

fn experiments<'de, M: SystemMarker, D: Deserializer<'de>>(d: D) -> Result<Vec<ExperimentSpec<M>>, D::Error> {
    let v = Vec::<ExperimentSpec<M>>::deserialize(d)?;
    if v.is_empty() {
        return Err(de::Error::custom("the list is empty; give at least one experiment"));
    }
    for (i, e) in v.iter().enumerate() {
        if v[..i].iter().any(|o| o.id == e.id) {
            return Err(at_field(
                &[&i.to_string(), "id"],
                format!("id {} is used twice; ids must be unique per system", e.id),
            ));
        }
    }
    Ok(v)
}

fn at_least_one_u64<'de, D: Deserializer<'de>>(d: D) -> Result<u64, D::Error> {
    AtLeastOne::deserialize(d).map(|v| v.0)
}

fn opt_at_least_one_u64<'de, D: Deserializer<'de>>(d: D) -> Result<Option<u64>, D::Error> {
    at_least_one_u64(d).map(Some)
}

fn opt_at_least_one_u32<'de, D: Deserializer<'de>>(d: D) -> Result<Option<u32>, D::Error> {
    let v = rules::at_least_one(u64::from(u32::deserialize(d)?)).map_err(de::Error::custom)?;
    Ok(Some(v as u32))
}

fn step_count<'de, D: Deserializer<'de>>(d: D) -> Result<u64, D::Error> {
    rules::steps(u64::deserialize(d)?).map_err(de::Error::custom)
}

fn opt_step_count<'de, D: Deserializer<'de>>(d: D) -> Result<Option<u64>, D::Error> {
    step_count(d).map(Some)
}
