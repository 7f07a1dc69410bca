//! One experiment of a system (a row of the paper's Table I): representation, algorithms and the
//! resolution grid in Table I's notation — `vary` holds the varied axes `v(·)`, each a group of
//! variables sharing one value (`x == theta`), `fixed` the constants `c(·)`.

use super::fields::at_field;
use super::fields::{suggest, variable_index};
use super::settings::{Ranges, Settings, SystemMarker};
use super::values::AxisValues;
use super::values::{CheckedKey, CheckedValue};
use qsweep_engine::env::{EnvParams, SystemKind};
use qsweep_engine::repr::ReprKind;
use qsweep_engine::rules;
use qsweep_engine::Algorithm;
use serde::de::{self, Deserializer, MapAccess, Visitor};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::fmt;
use std::marker::PhantomData;

/// What a grid axis or constant sets.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Target {
    /// Bins or fuzzy sets of the state variable with this index.
    Var(usize),
    /// The number of actions n of A_n.
    Actions,
    /// A numeric setting ([`AXIS_SETTINGS`]), e.g. `alpha` (axes only).
    Setting(&'static str),
    /// A physical parameter of the system, e.g. `gravity` (axes only).
    Param(&'static str),
}

impl Target {
    /// Whether the target takes a count (bins, sets, actions) rather than any number.
    pub fn is_count(self) -> bool {
        matches!(self, Target::Var(_) | Target::Actions)
    }
}

/// Numeric settings that a `vary` axis may sweep (the keys of a `settings:` section).
pub const AXIS_SETTINGS: &[&str] = &[
    "epsilon",
    "gamma",
    "alpha",
    "lambda",
    "q_init",
    "trace_cutoff",
    "width",
    "prune",
    "max_episodes",
    "max_total_steps",
];

/// A varied axis: a group of targets that share each value.
#[derive(Debug, Clone, PartialEq)]
pub struct Axis {
    /// Table I-style label, e.g. `x == theta` or `alpha`.
    pub label: String,
    /// The grouped targets.
    pub targets: Vec<Target>,
    /// Values, in file order (whole numbers for bins, sets and actions).
    pub values: Vec<f64>,
}

impl Axis {
    /// Whether the axis sweeps counts (bins, sets, actions) rather than a setting or parameter.
    pub fn is_count(&self) -> bool {
        self.targets.iter().all(|t| t.is_count())
    }
}

/// A grid value as written in labels: whole numbers without a decimal point, others in their
/// shortest round-trip form.
pub fn format_value(v: f64) -> String {
    if v.fract() == 0.0 && v.abs() < 1e15 {
        format!("{}", v as i64)
    } else {
        format!("{v}")
    }
}

/// A published result to compare with (e.g. the paper's Table III row).
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Reference {
    /// Mean episodes to the learning goal.
    pub mean: f64,
    /// Standard deviation.
    pub std: f64,
    /// Best configuration's bins or sets per variable, in state order.
    #[serde(default)]
    pub resolution: Option<Vec<u32>>,
    /// Best configuration's action count.
    #[serde(default)]
    pub actions: Option<u32>,
}

/// An experiment, validated.
#[derive(Debug, Clone)]
pub struct ExperimentSpec<M: SystemMarker> {
    /// Identifier within the system (Table I's "Exp." number).
    pub id: String,
    /// Optional title, e.g. "Bins only".
    pub title: Option<String>,
    /// Crisp bins or fuzzy sets.
    pub repr: ReprKind,
    /// Algorithms to run on every grid point (figure columns).
    pub algorithms: Vec<Algorithm>,
    /// Varied axes, in file order (first = heatmap rows, second = columns).
    pub axes: Vec<Axis>,
    /// Constants.
    pub fixed: Vec<(Target, u32)>,
    /// Settings overriding the system's.
    pub settings: Settings,
    /// Per-variable ranges overriding the system's.
    pub ranges: Ranges<M>,
    /// Learning-goal criterion replacing the system's.
    pub success: Option<M::Success>,
    /// Published results per algorithm.
    pub reference: BTreeMap<Algorithm, Reference>,
    /// This experiment's race (replaces a pipeline-wide one).
    pub race: Option<super::race::RaceSpec>,
    _m: PhantomData<M>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields, bound = "")]
struct RawExperiment<M: SystemMarker> {
    #[serde(deserialize_with = "id_string")]
    id: String,
    #[serde(default)]
    title: Option<String>,
    repr: ReprKind,
    #[serde(default = "both_algorithms")]
    algorithms: Vec<Algorithm>,
    vary: AxesRaw<M>,
    #[serde(default)]
    fixed: FixedRaw<M>,
    #[serde(default)]
    settings: Settings,
    #[serde(default)]
    ranges: Ranges<M>,
    #[serde(default)]
    success: Option<M::Success>,
    #[serde(default)]
    reference: BTreeMap<Algorithm, Reference>,
    #[serde(default)]
    race: Option<super::race::RaceSpec>,
}

fn both_algorithms() -> Vec<Algorithm> {
    vec![Algorithm::Q0, Algorithm::QLambda]
}

fn id_string<'de, D: Deserializer<'de>>(d: D) -> Result<String, D::Error> {
    struct V;
    impl Visitor<'_> for V {
        type Value = String;
        fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
            f.write_str("an experiment id (number or short name)")
        }
        fn visit_u64<E: de::Error>(self, v: u64) -> Result<String, E> {
            Ok(v.to_string())
        }
        fn visit_i64<E: de::Error>(self, v: i64) -> Result<String, E> {
            Ok(v.to_string())
        }
        fn visit_str<E: de::Error>(self, v: &str) -> Result<String, E> {
            if v.is_empty()
                || v.len() > 40
                || !v.chars().all(|c| c.is_ascii_alphanumeric() || "-_.".contains(c))
            {
                return Err(E::custom(format!("id `{v}`: use 1-40 letters, digits, '-', '_' or '.'")));
            }
            Ok(v.to_string())
        }
    }
    d.deserialize_any(V)
}

/// The targets named by a `vary`/`fixed` key such as `x == theta`; `axis` also allows numeric
/// settings and physical parameters.
fn parse_targets(system: SystemKind, key: &str, axis: bool) -> Result<Vec<Target>, String> {
    let params = EnvParams::default_for(system).param_names();
    let mut out = Vec::new();
    for name in key.split("==").map(str::trim) {
        let t = if name == "actions" {
            Target::Actions
        } else if let Ok(j) = variable_index(system, name) {
            Target::Var(j)
        } else if let (true, Some(s)) = (axis, AXIS_SETTINGS.iter().find(|s| **s == name)) {
            Target::Setting(s)
        } else if let (true, Some(p)) = (axis, params.iter().find(|p| **p == name)) {
            Target::Param(p)
        } else {
            return Err(unknown_target(system, name, axis));
        };
        if out.contains(&t) {
            return Err(format!("`{key}` names `{name}` twice"));
        }
        out.push(t);
    }
    if out.contains(&Target::Actions) && out.len() > 1 {
        return Err(format!("`{key}`: actions cannot share a value with state variables"));
    }
    if out.iter().any(|t| t.is_count()) && out.iter().any(|t| !t.is_count()) {
        return Err(format!(
            "`{key}`: bins and actions cannot share a value with settings or parameters; give them separate axes"
        ));
    }
    Ok(out)
}

fn unknown_target(system: SystemKind, name: &str, axis: bool) -> String {
    let vars = system.variables();
    let params = EnvParams::default_for(system).param_names();
    let mut all: Vec<&str> = vars.iter().copied().chain(["actions"]).collect();
    if axis {
        all.extend(AXIS_SETTINGS.iter().copied().chain(params.iter().copied()));
    }
    let hint =
        suggest(name, all.iter().copied()).map(|s| format!("; did you mean `{s}`?")).unwrap_or_default();
    if axis {
        format!(
            "unknown axis `{name}` for {system}: an axis is a state variable ({}), `actions`, a numeric setting ({}) or a physical parameter ({}){hint}",
            vars.join(", "),
            AXIS_SETTINGS.join(", "),
            params.join(", ")
        )
    } else {
        format!(
            "unknown variable `{name}` for {system}; its variables are {}, or `actions`{hint}",
            vars.join(", ")
        )
    }
}

/// A grid value for a target: a whole count for bins and actions (their rules in `qsweep_engine::rules`;
/// the representation's own limit is checked when trials are resolved), a setting's own rule.
fn check_value(t: Target, v: f64) -> Result<(), String> {
    if t.is_count() && !(v.fract() == 0.0 && v >= 0.0 && v <= f64::from(u32::MAX)) {
        return Err(format!("{v} is not allowed; bins, fuzzy sets and actions are whole numbers"));
    }
    match t {
        Target::Actions => rules::actions(v as u32).map(drop),
        Target::Var(_) => rules::resolution(v as u32, None).map(drop),
        Target::Setting(name) => super::settings::setting_level(name, v).map(drop),
        _ => Ok(()),
    }
}

struct AxesRaw<M>(Vec<Axis>, PhantomData<M>);

impl<'de, M: SystemMarker> Deserialize<'de> for AxesRaw<M> {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V<M>(PhantomData<M>);
        impl<'de, M: SystemMarker> Visitor<'de> for V<M> {
            type Value = AxesRaw<M>;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                write!(
                    f,
                    "a map from variable groups (e.g. `x == x_dot`, `actions`) to values, for {}",
                    M::SYSTEM
                )
            }
            fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<AxesRaw<M>, A::Error> {
                let mut axes: Vec<Axis> = Vec::new();
                let too_many = |n: usize| {
                    format!(
                        "{n} axes given; an experiment varies 1 or 2 axes (the heatmap's rows and columns)"
                    )
                };
                while let Some(targets) = map.next_key_seed(CheckedKey(|key: String| {
                    let targets = parse_targets(M::SYSTEM, &key, true)?;
                    if axes.len() == 2 {
                        return Err(too_many(3));
                    }
                    let label = targets_label(M::SYSTEM, &targets);
                    for &t in &targets {
                        if let Some(prev) = axes.iter().find(|a| a.targets.contains(&t)) {
                            return Err(format!(
                                "`{}` appears in `{}` and in `{label}`; each variable belongs to one axis",
                                target_name(M::SYSTEM, t),
                                prev.label
                            ));
                        }
                    }
                    Ok(targets)
                }))? {
                    let values = map.next_value_seed(CheckedValue(
                        |values: AxisValues| {
                            for &t in &targets {
                                for &v in &values.0 {
                                    check_value(t, v)?;
                                }
                            }
                            Ok(values.0)
                        },
                        PhantomData,
                    ))?;
                    let label = targets_label(M::SYSTEM, &targets);
                    axes.push(Axis { label, targets, values });
                }
                if axes.is_empty() {
                    return Err(de::Error::custom(too_many(0)));
                }
                Ok(AxesRaw(axes, PhantomData))
            }
        }
        d.deserialize_map(V(PhantomData))
    }
}

struct FixedRaw<M>(Vec<(Target, u32)>, PhantomData<M>);

impl<M> Default for FixedRaw<M> {
    fn default() -> Self {
        Self(Vec::new(), PhantomData)
    }
}

impl<'de, M: SystemMarker> Deserialize<'de> for FixedRaw<M> {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V<M>(PhantomData<M>);
        impl<'de, M: SystemMarker> Visitor<'de> for V<M> {
            type Value = FixedRaw<M>;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                write!(
                    f,
                    "a map from variables (or variable groups, or `actions`) to one value, for {}",
                    M::SYSTEM
                )
            }
            fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<FixedRaw<M>, A::Error> {
                let mut out: Vec<(Target, u32)> = Vec::new();
                while let Some(targets) = map.next_key_seed(CheckedKey(|key: String| {
                    let targets = parse_targets(M::SYSTEM, &key, false)?;
                    match targets.iter().find(|t| out.iter().any(|(o, _)| o == *t)) {
                        Some(&t) => Err(format!("`{}` is set twice", target_name(M::SYSTEM, t))),
                        None => Ok(targets),
                    }
                }))? {
                    let v = map.next_value_seed(CheckedValue(
                        |v: u32| targets.iter().try_for_each(|&t| check_value(t, f64::from(v))).map(|()| v),
                        PhantomData,
                    ))?;
                    out.extend(targets.into_iter().map(|t| (t, v)));
                }
                Ok(FixedRaw(out, PhantomData))
            }
        }
        d.deserialize_map(V(PhantomData))
    }
}

/// Name of a target for messages and labels.
pub fn target_name(system: SystemKind, t: Target) -> &'static str {
    match t {
        Target::Var(j) => system.variables()[j],
        Target::Actions => "actions",
        Target::Setting(s) | Target::Param(s) => s,
    }
}

fn targets_label(system: SystemKind, targets: &[Target]) -> String {
    targets.iter().map(|&t| target_name(system, t)).collect::<Vec<_>>().join(" == ")
}

impl<'de, M: SystemMarker> Deserialize<'de> for ExperimentSpec<M> {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let raw = RawExperiment::<M>::deserialize(d)?;
        let system = M::SYSTEM;
        let axes = raw.vary.0;
        let fixed = raw.fixed.0;
        for (t, _) in &fixed {
            if let Some(a) = axes.iter().find(|a| a.targets.contains(t)) {
                return Err(at_field(
                    &["fixed"],
                    format!(
                        "`{}` is both varied (in `{}`) and fixed; remove one",
                        target_name(system, *t),
                        a.label
                    ),
                ));
            }
        }
        for j in 0..system.dim() {
            let t = Target::Var(j);
            if !axes.iter().any(|a| a.targets.contains(&t)) && !fixed.iter().any(|(f, _)| *f == t) {
                return Err(at_field(
                    &["vary"],
                    format!(
                        "variable `{}` has no resolution; add it to `vary` (e.g. `{} == ...`) or to `fixed`",
                        system.variables()[j],
                        system.variables()[j]
                    ),
                ));
            }
        }
        let mut algorithms = Vec::new();
        for a in raw.algorithms {
            if algorithms.contains(&a) {
                return Err(at_field(&["algorithms"], format!("algorithm {} is listed twice", a.name())));
            }
            algorithms.push(a);
        }
        if algorithms.is_empty() {
            return Err(at_field(&["algorithms"], "the list is empty; use [q0, q-lambda]"));
        }
        for a in raw.reference.keys() {
            if !algorithms.contains(a) {
                return Err(at_field(
                    &["reference", a.name()],
                    format!("reference for {} but the experiment does not run it", a.name()),
                ));
            }
        }
        Ok(ExperimentSpec {
            id: raw.id,
            title: raw.title,
            repr: raw.repr,
            algorithms,
            axes,
            fixed,
            settings: raw.settings,
            ranges: raw.ranges,
            success: raw.success,
            reference: raw.reference,
            race: raw.race,
            _m: PhantomData,
        })
    }
}
