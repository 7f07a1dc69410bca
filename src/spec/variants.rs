//! Variants: alternative readings or settings of one pipeline, declared side by side.
//!
//! ```yaml
//! variants:
//!   - id: as-written                 # no `set`: the pipeline as written
//!     title: The paper's text
//!   - id: gym-time-limits
//!     title: Episodes cut at Gymnasium's registered TimeLimits
//!     set: { systems.cart-pole.success.steps: 200 }
//! ```
//!
//! Every variant is the whole pipeline with its `set` applied: each entry is a dotted path and a
//! value, exactly like `--set PATH=VALUE` ([`Override`]), applied to the parsed document before it
//! is typed, so a variant is checked by the same parser as the file itself. Command-line `--set`
//! overrides are applied after a variant's own, so they win. Trials that two variants share have
//! the same key and run once.

use super::{locate, safe_folder_name, AXIS_SETTINGS};
use super::{Override, PipelineSpec};
use crate::error::user_error;
use crate::sim::env::{EnvParams, SystemKind};
use serde::de::{self, Deserializer};
use serde::Deserialize;

/// One entry of `variants:`, as written.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct VariantSpec {
    /// Identifier; names the variant's report folder `reports/<name>/<id>/`.
    #[serde(deserialize_with = "variant_id")]
    pub id: String,
    /// Short title shown in reports.
    #[serde(default)]
    pub title: Option<String>,
    /// Free text: the reading this variant stands for and its source.
    #[serde(default)]
    pub description: Option<String>,
    /// Dotted path → value, applied to the pipeline (empty: the pipeline as written).
    #[serde(default)]
    pub set: serde_yaml::Mapping,
}

fn variant_id<'de, D: Deserializer<'de>>(d: D) -> Result<String, D::Error> {
    let s = String::deserialize(d)?;
    safe_folder_name(&s)
        .map_err(|why| de::Error::custom(format!("variant id `{s}` is not allowed: {why}")))?;
    if s == "figures" {
        return Err(de::Error::custom(
            "variant id `figures` is not allowed: the comparison report keeps its figures there",
        ));
    }
    Ok(s)
}

/// Check the list: ids unique.
pub(super) fn variants<'de, D: Deserializer<'de>>(d: D) -> Result<Vec<VariantSpec>, D::Error> {
    let v = Vec::<VariantSpec>::deserialize(d)?;
    if v.is_empty() {
        return Err(de::Error::custom(
            "variants: the list is empty; remove `variants:` or give at least one",
        ));
    }
    for (i, e) in v.iter().enumerate() {
        if v[..i].iter().any(|o| o.id == e.id) {
            return Err(de::Error::custom(format!(
                "variants[{i}]: id `{}` is used twice; variant ids must be unique",
                e.id
            )));
        }
    }
    Ok(v)
}

/// A variant, resolved: its pipeline with the `set` applied.
#[derive(Debug, Clone)]
pub struct LoadedVariant {
    /// Identifier.
    pub id: String,
    /// Title.
    pub title: Option<String>,
    /// Description.
    pub description: Option<String>,
    /// The `set` entries as `PATH=VALUE`, in file order.
    pub set: Vec<String>,
    /// The whole pipeline with the `set` (and command-line overrides) applied.
    pub spec: PipelineSpec,
}

/// Resolve every variant of `base` (the pipeline as typed from `text`), applying each variant's
/// `set` and then the command-line `overrides` to the document. Errors name the file, the line of
/// the offending `set` entry, the variant and the field.
pub fn resolve(
    base: &PipelineSpec,
    text: &str,
    origin: &str,
    overrides: &[Override],
) -> anyhow::Result<Vec<LoadedVariant>> {
    let Some(list) = &base.variants else { return Ok(Vec::new()) };
    let doc: serde_yaml::Value =
        serde_yaml::from_str(text).map_err(|e| user_error(format!("{origin}: {e}")))?;
    let mut out = Vec::with_capacity(list.len());
    for (i, v) in list.iter().enumerate() {
        let mut d = doc.clone();
        let mut set = Vec::new();
        for (k, value) in &v.set {
            let key = match k {
                serde_yaml::Value::String(s) => s.clone(),
                other => serde_yaml::to_string(other).unwrap_or_default().trim().to_string(),
            };
            let at = |msg: String| {
                let path = ["variants".to_string(), i.to_string(), "set".to_string(), key.clone()];
                let pos = locate(text, &path).map(|(l, c)| format!("{l}:{c}:")).unwrap_or_default();
                user_error(format!("{origin}:{pos} variant `{}`: set `{key}`: {msg}", v.id))
            };
            let o = override_of(&key, value).map_err(at)?;
            check_target(base, &o).map_err(at)?;
            check_not_varied(base, &o).map_err(at)?;
            o.apply(&mut d).map_err(|m| at(m.replace(&format!("--set {}: ", o.raw), "")))?;
            // Every entry alone must still give a valid pipeline, so an error points at its line.
            let mut alone = doc.clone();
            o.apply(&mut alone).map_err(at)?;
            strip_variants(&mut alone);
            serde_yaml::from_value::<PipelineSpec>(alone).map_err(|e| at(super::load::message(&e)))?;
            set.push(o.raw);
        }
        for o in overrides {
            o.apply(&mut d).map_err(user_error)?;
        }
        strip_variants(&mut d);
        let whole = |msg: String| {
            let pos = locate(text, &["variants".into(), i.to_string()])
                .map(|(l, c)| format!("{l}:{c}:"))
                .unwrap_or_default();
            user_error(format!("{origin}:{pos} variant `{}`: {msg}", v.id))
        };
        let spec: PipelineSpec = serde_yaml::from_value(d).map_err(|e| whole(super::load::message(&e)))?;
        super::race::check(&spec).map_err(|p| whole(format!("{}: {}", p.path.join("."), p.message)))?;
        out.push(LoadedVariant {
            id: v.id.clone(),
            title: v.title.clone(),
            description: v.description.clone(),
            set,
            spec,
        });
    }
    Ok(out)
}

/// A variant's pipeline has no variants of its own.
fn strip_variants(d: &mut serde_yaml::Value) {
    if let serde_yaml::Value::Mapping(m) = d {
        m.remove("variants");
    }
}

fn override_of(key: &str, value: &serde_yaml::Value) -> Result<Override, String> {
    if key.split('.').any(|p| p.trim().is_empty()) {
        return Err("the path has an empty part; write e.g. systems.cart-pole.crisp.alpha".into());
    }
    let path: Vec<String> = key.split('.').map(|p| p.trim().to_string()).collect();
    if path[0] == "variants" {
        return Err("a variant cannot change the list of variants".into());
    }
    let shown = serde_yaml::to_string(value).unwrap_or_default();
    let shown = shown.trim();
    Ok(Override { path, value: value.clone(), raw: format!("{key}={shown}") })
}

/// A path under `systems.` must name a system the pipeline has.
fn check_target(base: &PipelineSpec, o: &Override) -> Result<(), String> {
    if o.path[0] != "systems" {
        return Ok(());
    }
    let Some(name) = o.path.get(1) else { return Ok(()) };
    let present = present_systems(base);
    match SystemKind::parse(name) {
        Some(s) if present.contains(&s) => Ok(()),
        _ => Err(format!(
            "the pipeline has no system `{name}`; its systems are {}",
            present.iter().map(|s| s.name()).collect::<Vec<_>>().join(", ")
        )),
    }
}

fn present_systems(base: &PipelineSpec) -> Vec<SystemKind> {
    let s = &base.systems;
    let mut out = Vec::new();
    if s.ball_beam.is_some() {
        out.push(SystemKind::BallBeam);
    }
    if s.cart_pole.is_some() {
        out.push(SystemKind::CartPole);
    }
    if s.mountain_car.is_some() {
        out.push(SystemKind::MountainCar);
    }
    out
}

/// Axes of the experiments in the override's scope (all systems for `defaults.*`, one system,
/// or one experiment), as (system, experiment index, axis target names).
fn varied_names(
    base: &PipelineSpec,
    system: SystemKind,
    only: Option<usize>,
) -> Vec<(usize, String, Vec<String>)> {
    fn names<M: super::SystemMarker>(
        s: &Option<super::SystemSpec<M>>,
        only: Option<usize>,
    ) -> Vec<(usize, String, Vec<String>)> {
        s.iter()
            .flat_map(|s| s.experiments.iter().enumerate())
            .filter(|(i, _)| only.is_none_or(|o| o == *i))
            .map(|(i, e)| {
                let n = e
                    .axes
                    .iter()
                    .flat_map(|a| a.targets.iter().map(|&t| super::target_name(M::SYSTEM, t).to_string()))
                    .collect();
                (i, e.id.clone(), n)
            })
            .collect()
    }
    let s = &base.systems;
    match system {
        SystemKind::BallBeam => names(&s.ball_beam, only),
        SystemKind::CartPole => names(&s.cart_pole, only),
        SystemKind::MountainCar => names(&s.mountain_car, only),
    }
}

/// A variant must not set what an experiment in its scope varies: the axis would silently win.
fn check_not_varied(base: &PipelineSpec, o: &Override) -> Result<(), String> {
    let p = &o.path;
    let last = p.last().map(String::as_str).unwrap_or_default();
    let (systems, only): (Vec<SystemKind>, Option<usize>) = match p.as_slice() {
        [d, _] if d == "defaults" => (present_systems(base), None),
        [s, sys, level, _]
            if s == "systems" && ["settings", "crisp", "fuzzy", "params"].contains(&level.as_str()) =>
        {
            (SystemKind::parse(sys).into_iter().collect(), None)
        }
        [s, sys, e, i, level, _] if s == "systems" && e == "experiments" && level == "settings" => {
            (SystemKind::parse(sys).into_iter().collect(), i.parse().ok())
        }
        _ => return Ok(()),
    };
    let is_param = p.len() == 4 && p[2] == "params";
    for system in systems {
        let known = if is_param {
            EnvParams::default_for(system).param_names().contains(&last)
        } else {
            AXIS_SETTINGS.contains(&last)
        };
        if !known {
            continue;
        }
        for (_, id, names) in varied_names(base, system, only) {
            if names.iter().any(|n| n == last) {
                return Err(format!(
                    "{system} experiment {id} varies `{last}` (vary:), so this value would be ignored there; \
                     remove `{last}` from that experiment's axes or from this variant's set"
                ));
            }
        }
    }
    Ok(())
}
