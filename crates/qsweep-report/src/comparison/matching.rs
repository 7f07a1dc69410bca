//! The two sides of a comparison matched cell by cell. A side is a program pipeline's plan (its
//! experiments of one variant, or of the pipeline as written) and the cache's rows of it. Its
//! cells are keyed by the values of the shared params (named in both pipelines, after `--map`);
//! the same values in two experiments are one cell, and two cells of one side with the same
//! shared values but other unshared ones are ambiguous (an error naming those params). Every
//! error here is the user's input (exit 2) and says what to change.

use qsweep_pipeline::cache::Key;
use qsweep_pipeline::error::user_error;
use qsweep_pipeline::program::model::{MetricType, MetricValue, ParamValue, ProgramPlan, ProgramRow};
use std::collections::HashMap;

/// One side of a comparison.
#[derive(Debug, Clone, Copy)]
pub struct Side<'a> {
    /// How messages name it (the pipeline's path as given, with `@variant`).
    pub label: &'a str,
    /// Its plan.
    pub plan: &'a ProgramPlan,
    /// The variant compared (`None`: the pipeline as written, experiments of no variant).
    pub variant: Option<&'a str>,
    /// The cache's rows of its plan, one per key (`qsweep_pipeline::program::stored::plan_rows`).
    pub rows: &'a HashMap<Key, ProgramRow>,
}

/// What to compare: how A's params are named in B, which metric, and the equivalence margin.
#[derive(Debug, Clone, PartialEq)]
pub struct Request {
    /// `--map a=b`: A's param `a` is B's param `b`.
    pub map: Vec<(String, String)>,
    /// `--metric x=y`: A's metric `x` against B's `y` (`None`: A's objective on both sides).
    pub metric: Option<(String, String)>,
    /// The equivalence margin on B ÷ A.
    pub margin: (f64, f64),
}

/// The default equivalence margin on B ÷ A: the conventional 0.80–1.25, symmetric on a log scale.
pub const DEFAULT_MARGIN: (f64, f64) = (0.80, 1.25);

/// One cell of the comparison: its shared values and each side's metric values (succeeded trials
/// only; empty when the cache has none).
#[derive(Debug, Clone, PartialEq)]
pub struct CellSamples {
    /// The shared params' values, in [`Matched::shared`] order (A's values).
    pub values: Vec<ParamValue>,
    /// A's values of the metric.
    pub a: Vec<f64>,
    /// B's values of the metric.
    pub b: Vec<f64>,
}

/// The two sides matched.
#[derive(Debug, Clone, PartialEq)]
pub struct Matched {
    /// The sides' labels.
    pub labels: (String, String),
    /// The shared params: (A's name, B's name), in A's declared order.
    pub shared: Vec<(String, String)>,
    /// The metric: (A's name, B's name).
    pub metric: (String, String),
    /// The cells both sides plan, in A's plan order.
    pub cells: Vec<CellSamples>,
    /// Cells only A plans (their shared values).
    pub only_a: Vec<Vec<ParamValue>>,
    /// Cells only B plans (their shared values, in A's param order).
    pub only_b: Vec<Vec<ParamValue>>,
}

/// `name=value …` of a cell's shared values, by A's names.
pub fn cell_label(shared: &[(String, String)], values: &[ParamValue]) -> String {
    shared.iter().zip(values).map(|(p, v)| format!("{}={v}", p.0)).collect::<Vec<_>>().join(" ")
}

/// A value as a matching key: an integral float matches the integer (`3.0` in one pipeline,
/// `3` in the other), text never matches a number.
fn value_key(v: &ParamValue) -> String {
    match v {
        ParamValue::Int(i) => i.to_string(),
        ParamValue::Float(f) if f.fract() == 0.0 && f.abs() < 9.0e15 => format!("{}", *f as i64),
        ParamValue::Float(f) => format!("{f:?}"),
        ParamValue::Bool(b) => b.to_string(),
        ParamValue::Str(s) => format!("{s:?}"),
    }
}

/// Match `a` with `b` as `request` asks (see the module documentation).
pub fn match_cells(a: &Side, b: &Side, request: &Request) -> anyhow::Result<Matched> {
    let shared = shared_params(a, b, &request.map)?;
    let metric = metric(a, b, request.metric.as_ref())?;
    let idx_a: Vec<usize> = shared.iter().map(|(n, _)| param_index(a.plan, n)).collect();
    let idx_b: Vec<usize> = shared.iter().map(|(_, n)| param_index(b.plan, n)).collect();
    let cells_a = cells_of(a, &idx_a)?;
    let cells_b = cells_of(b, &idx_b)?;
    let by_key_b: HashMap<&Vec<String>, &SideCell> = cells_b.iter().map(|c| (&c.key, c)).collect();
    let m_a = metric_index(a.plan, &metric.0);
    let m_b = metric_index(b.plan, &metric.1);
    let mut out = Matched {
        labels: (a.label.to_string(), b.label.to_string()),
        shared: shared.clone(),
        metric: metric.clone(),
        cells: Vec::new(),
        only_a: Vec::new(),
        only_b: Vec::new(),
    };
    for c in &cells_a {
        match by_key_b.get(&c.key) {
            Some(cb) => out.cells.push(CellSamples {
                values: c.values.clone(),
                a: samples(a, &c.keys, m_a),
                b: samples(b, &cb.keys, m_b),
            }),
            None => out.only_a.push(c.values.clone()),
        }
    }
    let keys_a: std::collections::HashSet<&Vec<String>> = cells_a.iter().map(|c| &c.key).collect();
    out.only_b = cells_b.iter().filter(|c| !keys_a.contains(&c.key)).map(|c| c.values.clone()).collect();
    Ok(out)
}

/// The shared params, (A's name, B's name) in A's order, after checking every `--map` entry.
fn shared_params(a: &Side, b: &Side, map: &[(String, String)]) -> anyhow::Result<Vec<(String, String)>> {
    let names = |s: &Side| s.plan.params.iter().map(|(n, _)| n.clone()).collect::<Vec<_>>();
    let (na, nb) = (names(a), names(b));
    let listed = |v: &[String]| if v.is_empty() { "none".to_string() } else { v.join(", ") };
    for (x, y) in map {
        if !na.contains(x) {
            return Err(user_error(format!(
                "--map {x}={y}: {} has no param `{x}` (its params: {})",
                a.label,
                listed(&na)
            )));
        }
        if !nb.contains(y) {
            return Err(user_error(format!(
                "--map {x}={y}: {} has no param `{y}` (its params: {})",
                b.label,
                listed(&nb)
            )));
        }
    }
    let mut shared: Vec<(String, String)> = Vec::new();
    for p in &na {
        let to = map.iter().rev().find(|(x, _)| x == p).map_or(p, |(_, y)| y);
        if !nb.contains(to) {
            continue;
        }
        if let Some((other, _)) = shared.iter().find(|(_, q)| q == to) {
            return Err(user_error(format!(
                "{}'s param `{to}` is matched by both `{other}` and `{p}` of {}: map one of them to another param with --map",
                b.label, a.label
            )));
        }
        shared.push((p.clone(), to.clone()));
    }
    if shared.is_empty() {
        return Err(user_error(format!(
            "{} and {} share no param (A's: {}; B's: {}): name A's param in B with --map A_NAME=B_NAME",
            a.label,
            b.label,
            listed(&na),
            listed(&nb)
        )));
    }
    // Params of the same type on both sides are what a cell's values can match on.
    for (x, y) in &shared {
        let t = |s: &Side, n: &str| s.plan.params.iter().find(|(p, _)| p == n).map(|(_, t)| *t);
        let (ta, tb) = (t(a, x), t(b, y));
        let numeric = |t: Option<qsweep_pipeline::program::model::ParamType>| {
            matches!(
                t,
                Some(
                    qsweep_pipeline::program::model::ParamType::Int
                        | qsweep_pipeline::program::model::ParamType::Float
                )
            )
        };
        if ta != tb && !(numeric(ta) && numeric(tb)) {
            return Err(user_error(format!(
                "param `{x}` of {} is {} but `{y}` of {} is {}: their values never match; map `{x}` to another param with --map",
                a.label,
                ta.map_or("?", |t| t.name()),
                b.label,
                tb.map_or("?", |t| t.name())
            )));
        }
    }
    Ok(shared)
}

/// The metric, (A's name, B's name): `--metric`, else A's objective on both sides; each must be a
/// declared `int`, `float` or `bool` metric.
fn metric(a: &Side, b: &Side, given: Option<&(String, String)>) -> anyhow::Result<(String, String)> {
    let declared =
        |s: &Side| s.plan.program.metrics.iter().map(|(n, _)| n.as_str()).collect::<Vec<_>>().join(", ");
    let (x, y) = match given {
        Some(m) => m.clone(),
        None => match &a.plan.program.objective {
            Some(o) => (o.metric.clone(), o.metric.clone()),
            None => {
                return Err(user_error(format!(
                    "{} declares no objective: name the metric to compare with --metric NAME (or --metric A_NAME=B_NAME); its metrics: {}",
                    a.label,
                    declared(a)
                )))
            }
        },
    };
    for (s, n, is_a) in [(a, &x, true), (b, &y, false)] {
        let Some((_, t)) = s.plan.program.metrics.iter().find(|(m, _)| m == n) else {
            let how = if is_a {
                "name one of them with --metric NAME (or --metric NAME=B_NAME)".to_string()
            } else {
                format!("name B's with --metric {x}=B_NAME")
            };
            return Err(user_error(format!(
                "{} has no metric `{n}` (its metrics: {}): {how}",
                s.label,
                declared(s)
            )));
        };
        if !matches!(t, MetricType::Int | MetricType::Float | MetricType::Bool) {
            return Err(user_error(format!(
                "metric `{n}` of {} is a {}: compare takes an int, float or bool metric (its metrics: {})",
                s.label,
                t.name(),
                declared(s)
            )));
        }
    }
    Ok((x, y))
}

fn param_index(plan: &ProgramPlan, name: &str) -> usize {
    plan.params.iter().position(|(n, _)| n == name).expect("a shared param is declared")
}

fn metric_index(plan: &ProgramPlan, name: &str) -> usize {
    plan.program.metrics.iter().position(|(n, _)| n == name).expect("the metric is declared")
}

/// One side's cell: its matching key, shared values, full params and trial keys.
struct SideCell {
    key: Vec<String>,
    values: Vec<ParamValue>,
    params: Vec<ParamValue>,
    keys: Vec<Key>,
}

/// The cells of `side`'s experiments (of its variant), one per shared-value tuple, in plan order.
fn cells_of(side: &Side, shared: &[usize]) -> anyhow::Result<Vec<SideCell>> {
    let exps: Vec<_> =
        side.plan.experiments.iter().filter(|e| e.variant.as_deref() == side.variant).collect();
    if exps.is_empty() {
        let ids: Vec<&str> = side.plan.variants.iter().map(|v| v.id.as_str()).collect();
        return Err(user_error(match side.variant {
            None if !ids.is_empty() => format!(
                "{} declares variants ({}), so it plans no cell as written: compare one with {}@ID",
                side.label,
                ids.join(", "),
                side.label
            ),
            _ => format!("{} plans no cell", side.label),
        }));
    }
    let mut out: Vec<SideCell> = Vec::new();
    let mut at: HashMap<Vec<String>, usize> = HashMap::new();
    for e in exps {
        for c in &e.cells {
            let values: Vec<ParamValue> = shared.iter().map(|&i| c.params[i].clone()).collect();
            let key: Vec<String> = values.iter().map(value_key).collect();
            match at.get(&key) {
                Some(&i) => {
                    let first = &mut out[i];
                    if first.params != c.params {
                        return Err(ambiguous(side, &first.params, &c.params, &values, shared));
                    }
                    for t in &c.trials {
                        if !first.keys.contains(&t.key) {
                            first.keys.push(t.key);
                        }
                    }
                }
                None => {
                    at.insert(key.clone(), out.len());
                    out.push(SideCell {
                        key,
                        values,
                        params: c.params.clone(),
                        keys: c.trials.iter().map(|t| t.key).collect(),
                    });
                }
            }
        }
    }
    Ok(out)
}

/// The error of two cells with the same shared values and other unshared ones.
fn ambiguous(
    side: &Side,
    first: &[ParamValue],
    other: &[ParamValue],
    values: &[ParamValue],
    shared: &[usize],
) -> anyhow::Error {
    let differ: Vec<String> = (0..first.len())
        .filter(|i| first[*i] != other[*i])
        .map(|i| format!("`{}` ({} vs {})", side.plan.params[i].0, first[i], other[i]))
        .collect();
    let at: Vec<String> =
        shared.iter().zip(values).map(|(&i, v)| format!("{}={v}", side.plan.params[i].0)).collect();
    user_error(format!(
        "{}: two cells at {} differ only in params the other pipeline does not have: {}; \
         name them in the other pipeline with --map A_NAME=B_NAME, or compare pipelines that fix them",
        side.label,
        at.join(" "),
        differ.join(", ")
    ))
}

/// The metric's values (index `m`) of the succeeded rows of `keys`; a bool counts as 0 or 1.
fn samples(side: &Side, keys: &[Key], m: usize) -> Vec<f64> {
    keys.iter()
        .filter_map(|k| side.rows.get(k))
        .filter_map(|r| r.result.as_ref().ok())
        .filter_map(|metrics| match metrics.get(m)? {
            MetricValue::Int(i) => Some(*i as f64),
            MetricValue::Float(f) => Some(*f),
            MetricValue::Bool(b) => Some(if *b { 1.0 } else { 0.0 }),
            _ => None,
        })
        .collect()
}
