//! `qsweep trial`'s flags resolved into a trial configuration: they become the settings of a
//! one-cell plan, so a trial and the pipeline cell with the same settings share their key.

use super::trial_args::TrialArgs;
use qsweep_engine::config::TrialConfig;
use qsweep_engine::env::{SystemKind, TaskKind};
use qsweep_pipeline::declared::Override;
use qsweep_pipeline::error::user_error;
use qsweep_pipeline::plan::{one_cell, CellRequest};

/// Resolve the arguments into a validated trial configuration: the flags become the settings of
/// a one-cell plan ([`one_cell`]), resolved exactly as a pipeline cell with the same settings, so
/// `qsweep trial` and that cell have the same configuration and the same cache key.
pub fn config(a: &TrialArgs) -> anyhow::Result<TrialConfig> {
    let system = a.env;
    let dim = system.dim();
    let resolution = match a.resolution.0.as_slice() {
        [one] => vec![*one; dim],
        many if many.len() == dim => many.to_vec(),
        many => {
            return Err(user_error(format!(
            "--resolution: {system} has {dim} state variables ({}); give {dim} values or one for all, got {}",
            system.variables().join(","),
            many.len()
        )))
        }
    };
    let mut overrides = Vec::new();
    let mut setting = |name: &str, v: Option<serde_yaml::Value>| {
        if let Some(v) = v {
            overrides.push(Override::setting(&["defaults", name], v));
        }
    };
    let num = |v: Option<f64>| v.map(serde_yaml::Value::from);
    setting("epsilon", num(a.epsilon));
    setting("gamma", num(a.gamma));
    setting("alpha", num(a.alpha));
    setting("lambda", num(a.lambda));
    setting("q_init", num(a.q_init));
    setting("tie_break", a.tie_break.map(|t| serde_yaml::to_value(t).unwrap_or_default()));
    setting("traces", a.replacing_traces.then(|| "replacing".into()));
    setting("watkins_cut", a.watkins_cut.then_some(true.into()));
    setting("width", num(a.width));
    setting("prune", num(a.prune));
    setting("trace_cutoff", num(a.trace_cutoff));
    setting("max_episodes", a.max_episodes.map(serde_yaml::Value::from));
    setting("max_total_steps", a.max_total_steps.map(serde_yaml::Value::from));
    if let Some(v) = a.balance_steps {
        if TaskKind::of(system) != TaskKind::Survival {
            return Err(user_error(format!(
                "--balance-steps: {system} is a goal-reaching task, not a survival task; use --set success.within=N"
            )));
        }
        overrides.push(Override::setting(&["systems", system.name(), "success", "steps"], v));
    }
    let mut env = qsweep_engine::env::EnvParams::default_for(system);
    for (name, v) in &a.params {
        env.set_param(name, *v).map_err(|e| user_error(format!("--param: {e}")))?;
        overrides.push(Override::setting(&["systems", system.name(), "params", name], *v));
    }
    for s in &a.set {
        overrides.push(trial_override(system, s)?);
    }
    one_cell(&CellRequest {
        system,
        repr: a.repr,
        resolution,
        actions: a.actions.unwrap_or(system.default_actions()),
        algorithm: a.algorithm,
        seed: a.seed,
        overrides,
    })
}

/// A `--set` of `qsweep trial`: a bare setting name (`start=gym`) means `defaults.NAME`, a path
/// starting `success.`, `params.` or `ranges.` is the system's, anything else a full pipeline path.
fn trial_override(system: SystemKind, arg: &str) -> anyhow::Result<Override> {
    let o = Override::parse(arg).map_err(user_error)?;
    let mut path = o.path.clone();
    match path[0].as_str() {
        "defaults" | "systems" | "seeds" => {}
        "success" | "params" | "ranges" => {
            path.splice(0..0, ["systems".to_string(), system.name().to_string()]);
        }
        _ if path.len() == 1 => path.insert(0, "defaults".to_string()),
        _ => {}
    }
    Ok(Override { path, ..o })
}
