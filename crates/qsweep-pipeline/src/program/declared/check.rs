//! The rules between a program pipeline's fields: names known and not reserved, each value of
//! its param's type (an integer is fine for a float param), ranges read against the param,
//! experiment and variant ids unique, a variant setting only `params.*`. Each broken rule is a
//! [`Problem`] at the offending field's path, which the loader turns into `FILE:LINE:COL`.

use super::checked::{ExperimentDecl, ProgramDecl, VariantDecl, DEFAULT_EXPERIMENT, DEFAULT_TIMEOUT};
use super::spec::{ExperimentEntry, GoalName, Named, ProgramFile, ProtocolName, VariantEntry};
use super::values::{MetricName, Scalar, Vary};
use crate::declared::{suggest, Problem};
use crate::program::model::{Goal, MetricType, Objective, ParamType, ParamValue, Protocol, Provenance};

/// The most values a range `"A..B"` may give.
const MAX_RANGE: i64 = 10_000;

/// Check `raw` (the file with any `--set` applied) whole. Each param's type is its default's in
/// `file_params` (the file as written, so a `--set` cannot change a type); a param only `--set`
/// adds takes its value's type. Params named in `set_by_cli` keep their `--set` value in every
/// variant.
pub fn check(
    raw: &ProgramFile,
    file_params: &Named<Scalar>,
    set_by_cli: &[String],
) -> Result<ProgramDecl, Problem> {
    let p = &raw.program;
    let metrics = metrics(&p.metrics)?;
    let objective = match &p.objective {
        Some(o) => Some(objective(&o.metric, o.goal, &metrics)?),
        None => None,
    };
    for (i, g) in p.inputs.0.iter().enumerate() {
        if g.trim().is_empty() {
            return Err(problem(&["program", "inputs", &i.to_string()], "the glob is empty; remove it"));
        }
    }
    let params = params(&raw.params, file_params)?;
    for (name, _) in &metrics {
        if params.iter().any(|(n, _)| n == name) {
            return Err(problem(
                &["program", "metrics", name],
                format!(
                    "`{name}` is both a param and a metric; rename one (each is a column of the trial rows)"
                ),
            ));
        }
    }
    let mut experiments = experiments(raw.experiments.as_deref(), &params)?;
    let fresh = stages(raw, objective.is_some(), &mut experiments)?;
    let variants = variants(raw.variants.as_deref(), &params, &experiments, set_by_cli)?;
    Ok(ProgramDecl {
        name: raw.name.clone(),
        description: raw.description.clone(),
        seeds: raw.seeds.0.clone(),
        command: p.command.0.clone(),
        inputs: p.inputs.0.clone(),
        protocol: match p.protocol {
            ProtocolName::Process => Protocol::Process,
            ProtocolName::Worker => Protocol::Worker,
        },
        timeout: p.timeout.map_or(DEFAULT_TIMEOUT, |t| t.0),
        metrics,
        objective,
        provenance: p
            .provenance
            .iter()
            .map(|e| Provenance { command: e.command.0.clone(), key: e.key })
            .collect(),
        params,
        experiments,
        variants,
        fresh,
    })
}

/// The rules of `race:` and `fresh:` (the engine's blocks, `crate::declared`): each race checked
/// against the first round's seeds and given to the experiments it covers (an experiment's own
/// block wins over the pipeline's); the fresh seeds disjoint from the grid's and the races'. Both
/// choose a best cell, so both need an `objective`. The fresh seeds, or none.
fn stages(
    raw: &ProgramFile,
    has_objective: bool,
    experiments: &mut [ExperimentDecl],
) -> Result<Vec<u64>, Problem> {
    let seeds = &raw.seeds.0;
    let need_objective = |path: Vec<String>, what: &str| {
        Problem {
        path,
        message: format!(
            "{what} picks each experiment's best cell by the objective, but `program.objective` is not declared; \
             add e.g. `objective: {{ metric: loss, goal: minimize }}` under `program:`"
        ),
    }
    };
    if let Some(r) = &raw.race {
        if !has_objective {
            return Err(need_objective(vec!["race".into()], "a race"));
        }
        crate::declared::check_race(r, seeds, &["race".to_string()])?;
    }
    let entries = raw.experiments.as_deref().unwrap_or_default();
    for (i, e) in entries.iter().enumerate() {
        if let Some(r) = &e.race {
            let at = vec!["experiments".to_string(), i.to_string(), "race".to_string()];
            if !has_objective {
                return Err(need_objective(at, "a race"));
            }
            crate::declared::check_race(r, seeds, &at)?;
        }
    }
    for e in experiments.iter_mut() {
        e.race = e.race.or(raw.race);
    }
    let Some(f) = &raw.fresh else { return Ok(Vec::new()) };
    if !has_objective {
        return Err(need_objective(vec!["fresh".into()], "`fresh:`"));
    }
    let races: Vec<_> = experiments.iter().filter_map(|e| e.race).collect();
    crate::declared::check_fresh_seeds(f, seeds, &races)?;
    Ok(f.seed_list().expect("checked by check_fresh_seeds"))
}

fn problem(path: &[&str], message: impl Into<String>) -> Problem {
    Problem { path: path.iter().map(|s| s.to_string()).collect(), message: message.into() }
}

/// A param's or metric's name: not reserved, and usable as a `--set params.NAME` path and a
/// column name.
fn check_name(kind: &str, name: &str) -> Result<(), String> {
    if name == "seed" {
        return Err(format!(
            "`seed` is reserved: qsweep gives each trial its seed itself (`seed` in the JSON it sends); \
             rename this {kind}"
        ));
    }
    if name.starts_with("qsweep_") {
        return Err(format!("names starting with `qsweep_` are reserved for qsweep; rename this {kind}"));
    }
    if crate::program::model::REPORT_COLUMNS.contains(&name) {
        return Err(format!(
            "`{name}` is reserved: a report's trials.parquet has an `{name}` column of its own; rename this {kind}"
        ));
    }
    if crate::program::model::FIXED_COLUMNS.contains(&name) {
        return Err(format!(
            "`{name}` is reserved: every row has a `{name}` column of its own (docs/programs.md, typed rows); \
             rename this {kind}"
        ));
    }
    let mut chars = name.chars();
    let ok = chars.next().is_some_and(|c| c.is_ascii_alphabetic() || c == '_')
        && chars.all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-')
        && name.len() <= 64;
    if !ok {
        return Err(format!(
            "{kind} name `{name}` is not allowed; use 1-64 letters, digits, '_' or '-', starting with a letter \
             or '_'"
        ));
    }
    Ok(())
}

/// The index of the first entry named `name` before entry `i`, if any.
fn earlier<V>(entries: &[(String, V)], i: usize) -> bool {
    entries[..i].iter().any(|(n, _)| *n == entries[i].0)
}

fn metrics(raw: &Named<MetricName>) -> Result<Vec<(String, MetricType)>, Problem> {
    if raw.0.is_empty() {
        return Err(problem(
            &["program", "metrics"],
            "no metric is declared; name each metric the program reports with its type, e.g. `episodes: int`",
        ));
    }
    for (i, (name, _)) in raw.0.iter().enumerate() {
        check_name("metric", name).map_err(|m| problem(&["program", "metrics", name], m))?;
        if earlier(&raw.0, i) {
            return Err(problem(&["program", "metrics", name], format!("metric `{name}` is declared twice")));
        }
    }
    Ok(raw.0.iter().map(|(n, t)| (n.clone(), t.0)).collect())
}

fn objective(metric: &str, goal: GoalName, metrics: &[(String, MetricType)]) -> Result<Objective, Problem> {
    let at = ["program", "objective", "metric"];
    let Some((_, ty)) = metrics.iter().find(|(n, _)| n == metric) else {
        let names: Vec<&str> = metrics.iter().map(|(n, _)| n.as_str()).collect();
        let hint = suggest(metric, names.iter().copied())
            .map(|s| format!("; did you mean `{s}`?"))
            .unwrap_or_default();
        return Err(problem(
            &at,
            format!(
                "unknown metric `{metric}`{hint}; the objective is one of the metrics: {}",
                names.join(", ")
            ),
        ));
    };
    if !ty.is_scalar_number() {
        return Err(problem(
            &at,
            format!("`{metric}` is a {} metric; the objective must be an int or float metric", ty.name()),
        ));
    }
    let goal = match goal {
        GoalName::Minimize => Goal::Minimize,
        GoalName::Maximize => Goal::Maximize,
    };
    Ok(Objective { metric: metric.to_string(), goal })
}

/// A value as written, untyped.
fn value_of(v: &Scalar) -> ParamValue {
    match v {
        Scalar::Int(i) => ParamValue::Int(*i),
        Scalar::Float(x) => ParamValue::Float(*x),
        Scalar::Bool(b) => ParamValue::Bool(*b),
        Scalar::Str(s) => ParamValue::Str(s.clone()),
    }
}

/// A value as messages show it: text in backticks.
fn shown(v: &ParamValue) -> String {
    match v {
        ParamValue::Str(s) => format!("`{s}`"),
        ParamValue::Float(x) => format!("{x:?}"),
        other => other.to_string(),
    }
}

/// `v` as a value of param `name`, whose default is `default`.
fn typed(name: &str, default: &ParamValue, v: &Scalar) -> Result<ParamValue, String> {
    let ty = default.kind();
    match (ty, v) {
        (ParamType::Float, Scalar::Int(i)) => return Ok(ParamValue::Float(*i as f64)),
        (t, v) if value_of(v).kind() == t => return Ok(value_of(v)),
        _ => {}
    }
    let what = match v {
        Scalar::Int(_) => "a whole number",
        Scalar::Float(_) => "a number with a fraction",
        Scalar::Bool(_) => "true/false",
        Scalar::Str(_) => "text",
    };
    let hint = match (ty, v) {
        (ParamType::Int, Scalar::Float(_)) => format!(
            "; give a whole number, or write the default with a fraction ({}.0) to make `{name}` a float param",
            default
        ),
        (ParamType::Str, other) => format!("; quote it to give it as text: \"{}\"", value_of(other)),
        (_, Scalar::Str(s)) if s.contains("..") => {
            "; a range \"A..B\" is an axis's whole value, not an item of a list".to_string()
        }
        _ => String::new(),
    };
    let article = if ty == ParamType::Int { "an" } else { "a" };
    Err(format!(
        "`{name}` is {article} {} param (its default is {}), so {} ({what}) is not allowed here{hint}",
        ty.name(),
        shown(default),
        shown(&value_of(v))
    ))
}

fn params(raw: &Named<Scalar>, file: &Named<Scalar>) -> Result<Vec<(String, ParamValue)>, Problem> {
    let mut out: Vec<(String, ParamValue)> = Vec::new();
    for (i, (name, v)) in raw.0.iter().enumerate() {
        let at = ["params", name.as_str()];
        check_name("param", name).map_err(|m| problem(&at, m))?;
        if earlier(&raw.0, i) {
            return Err(problem(&at, format!("param `{name}` is declared twice")));
        }
        let value = match file.0.iter().find(|(n, _)| n == name) {
            Some((_, d)) => typed(name, &value_of(d), v).map_err(|m| problem(&at, m))?,
            None => value_of(v),
        };
        out.push((name.clone(), value));
    }
    Ok(out)
}

/// The default of param `name`, or the error of an unknown param (with the closest name).
fn param<'a>(params: &'a [(String, ParamValue)], name: &str, at: &[&str]) -> Result<&'a ParamValue, Problem> {
    params.iter().find(|(n, _)| n == name).map(|(_, v)| v).ok_or_else(|| {
        let names: Vec<&str> = params.iter().map(|(n, _)| n.as_str()).collect();
        let hint = suggest(name, names.iter().copied()).map(|s| format!("; did you mean `{s}`?")).unwrap_or_default();
        problem(
            at,
            format!(
                "unknown param `{name}`{hint}; the params are {} (declare a new one under `params:` with its default)",
                names.join(", ")
            ),
        )
    })
}

fn experiments(
    raw: Option<&[ExperimentEntry]>,
    params: &[(String, ParamValue)],
) -> Result<Vec<ExperimentDecl>, Problem> {
    let Some(raw) = raw else {
        return Ok(vec![ExperimentDecl {
            id: DEFAULT_EXPERIMENT.into(),
            title: None,
            axes: vec![],
            fixed: vec![],
            race: None,
        }]);
    };
    if raw.is_empty() {
        return Err(problem(
            &["experiments"],
            "the list is empty; remove `experiments:` (one cell of the defaults) or give at least one",
        ));
    }
    if params.is_empty() {
        return Err(problem(
            &["experiments"],
            "experiments vary and fix params, but `params:` declares none; declare each param with its default",
        ));
    }
    let mut out = Vec::with_capacity(raw.len());
    for (i, e) in raw.iter().enumerate() {
        let i = i.to_string();
        if out.iter().any(|o: &ExperimentDecl| o.id == e.id) {
            return Err(problem(
                &["experiments", &i, "id"],
                format!("id `{}` is used twice; experiment ids must be unique", e.id),
            ));
        }
        out.push(experiment(e, &i, params)?);
    }
    Ok(out)
}

fn experiment(
    e: &ExperimentEntry,
    i: &str,
    params: &[(String, ParamValue)],
) -> Result<ExperimentDecl, Problem> {
    let mut axes = Vec::with_capacity(e.vary.0.len());
    for (j, (name, v)) in e.vary.0.iter().enumerate() {
        let at = ["experiments", i, "vary", name.as_str()];
        let default = param(params, name, &at)?;
        if earlier(&e.vary.0, j) {
            return Err(problem(&at, format!("`{name}` is varied twice")));
        }
        axes.push((name.clone(), axis_values(name, default, v, &at)?));
    }
    let mut fixed = Vec::with_capacity(e.fixed.0.len());
    for (j, (name, v)) in e.fixed.0.iter().enumerate() {
        let at = ["experiments", i, "fixed", name.as_str()];
        let default = param(params, name, &at)?;
        if earlier(&e.fixed.0, j) {
            return Err(problem(&at, format!("`{name}` is fixed twice")));
        }
        if axes.iter().any(|(n, _)| n == name) {
            return Err(problem(
                &at,
                format!(
                    "`{name}` is both varied (vary:) and fixed in experiment {}; remove it from one of them",
                    e.id
                ),
            ));
        }
        fixed.push((name.clone(), typed(name, default, v).map_err(|m| problem(&at, m))?));
    }
    Ok(ExperimentDecl { id: e.id.clone(), title: e.title.clone(), axes, fixed, race: e.race })
}

/// The values of an axis of param `name`: one value, a list, or a range `"A..B"` of an int or
/// float param.
fn axis_values(name: &str, default: &ParamValue, v: &Vary, at: &[&str]) -> Result<Vec<ParamValue>, Problem> {
    let numeric = matches!(default.kind(), ParamType::Int | ParamType::Float);
    match v {
        Vary::One(Scalar::Str(s)) if numeric && s.contains("..") => {
            let ints = range(s).map_err(|m| problem(at, m))?;
            Ok(ints
                .map(|i| match default.kind() {
                    ParamType::Float => ParamValue::Float(i as f64),
                    _ => ParamValue::Int(i),
                })
                .collect())
        }
        Vary::One(x) => Ok(vec![typed(name, default, x).map_err(|m| problem(at, m))?]),
        Vary::List(items) => {
            let mut out: Vec<ParamValue> = Vec::with_capacity(items.len());
            for (k, x) in items.iter().enumerate() {
                let k = k.to_string();
                let item: Vec<&str> = at.iter().copied().chain([k.as_str()]).collect();
                let value = typed(name, default, x).map_err(|m| problem(&item, m))?;
                if out.contains(&value) {
                    return Err(problem(&item, format!("value {} is listed twice", shown(&value))));
                }
                out.push(value);
            }
            Ok(out)
        }
    }
}

/// The integers of an inclusive range `"A..B"`.
fn range(s: &str) -> Result<std::ops::RangeInclusive<i64>, String> {
    let bad =
        || format!("\"{s}\" is not a range; write \"A..B\" with whole numbers (inclusive), e.g. \"2..10\"");
    let (a, b) = s.split_once("..").ok_or_else(bad)?;
    let a: i64 = a.trim().parse().map_err(|_| bad())?;
    let b: i64 = b.trim().parse().map_err(|_| bad())?;
    if a > b {
        return Err(format!("range \"{s}\" is empty; the first bound must be ≤ the second"));
    }
    if b.saturating_sub(a) >= MAX_RANGE {
        return Err(format!("range \"{s}\" has more than {MAX_RANGE} values"));
    }
    Ok(a..=b)
}

fn variants(
    raw: Option<&[VariantEntry]>,
    params: &[(String, ParamValue)],
    experiments: &[ExperimentDecl],
    set_by_cli: &[String],
) -> Result<Vec<VariantDecl>, Problem> {
    let Some(raw) = raw else { return Ok(Vec::new()) };
    if raw.is_empty() {
        return Err(problem(&["variants"], "the list is empty; remove `variants:` or give at least one"));
    }
    let mut out: Vec<VariantDecl> = Vec::with_capacity(raw.len());
    for (i, v) in raw.iter().enumerate() {
        let i = i.to_string();
        let id_at = ["variants", i.as_str(), "id"];
        if v.id == "figures" {
            return Err(problem(
                &id_at,
                "variant id `figures` is not allowed: the comparison report keeps its figures there",
            ));
        }
        if out.iter().any(|o| o.id == v.id) {
            return Err(problem(&id_at, format!("id `{}` is used twice; variant ids must be unique", v.id)));
        }
        out.push(variant(v, &i, params, experiments, set_by_cli)?);
    }
    Ok(out)
}

fn variant(
    v: &VariantEntry,
    i: &str,
    params: &[(String, ParamValue)],
    experiments: &[ExperimentDecl],
    set_by_cli: &[String],
) -> Result<VariantDecl, Problem> {
    let mut defaults: Vec<ParamValue> = params.iter().map(|(_, d)| d.clone()).collect();
    let mut set = Vec::with_capacity(v.set.0.len());
    for (j, (key, value)) in v.set.0.iter().enumerate() {
        let at = ["variants", i, "set", key.as_str()];
        let name = set_param(key, value).map_err(|m| problem(&at, m))?;
        let default = param(params, name, &at)?;
        if v.set.0[..j].iter().any(|(k, _)| set_param(k, &serde_yaml::Value::Null).ok() == Some(name)) {
            return Err(problem(&at, format!("`params.{name}` is set twice")));
        }
        let scalar: Scalar = serde_yaml::from_value(value.clone())
            .map_err(|e| problem(&at, format!("`params.{name}`: {e}")))?;
        let typed = typed(name, default, &scalar).map_err(|m| problem(&at, m))?;
        if let Some(e) = experiments.iter().find(|e| e.axes.iter().any(|(n, _)| n == name)) {
            return Err(problem(
                &at,
                format!(
                    "experiment {} varies `{name}` (vary:), so this value would be ignored there; remove `{name}` \
                     from that experiment's axes or from this variant's set",
                    e.id
                ),
            ));
        }
        set.push(format!("params.{name}={typed}"));
        if !set_by_cli.iter().any(|n| n == name) {
            let k = params.iter().position(|(n, _)| n == name).expect("a known param");
            defaults[k] = typed;
        }
    }
    Ok(VariantDecl { id: v.id.clone(), title: v.title.clone(), set, defaults })
}

/// The param a variant's `set` key names: `params.NAME`, nothing else (a variant is the same
/// program with other params).
fn set_param<'a>(key: &'a str, value: &serde_yaml::Value) -> Result<&'a str, String> {
    match key.trim().strip_prefix("params.") {
        Some(name) if !name.trim().is_empty() && !name.contains('.') => Ok(name.trim()),
        _ if key.trim() == "params" && value.is_mapping() => {
            Err("write each param as its own entry, `params.NAME: VALUE` (e.g. `params.env: MountainCar-v0`)".into())
        }
        _ => Err(format!(
            "a variant sets params only, as `params.NAME: VALUE` (it runs the same program with other params); \
             `{key}` is not one (`--set` on the command line may change any field)"
        )),
    }
}
