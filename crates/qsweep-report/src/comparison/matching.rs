//! The two sides of a comparison matched cell by cell. A side is a program pipeline's plan (its
//! experiments of one variant, or of the pipeline as written) and the cache's rows of it, or a
//! [`CellSet`]: an engine pipeline's cells ([`super::engine`]) or a report folder's
//! ([`super::folder`]). Its cells are keyed by the values of the shared params (named in both
//! sides, after `--map`); the same configuration in two experiments is one cell, and two cells of
//! one side with the same shared values but other unshared ones are ambiguous (an error naming
//! those params). Every error here is the user's input (exit 2) and says what to change.

use super::cells::{CellSet, Sample, ABSENT};
use qsweep_pipeline::cache::Key;
use qsweep_pipeline::error::user_error;
use qsweep_pipeline::program::model::{
    MetricType, MetricValue, ParamType, ParamValue, ProgramPlan, ProgramRow,
};
use std::collections::HashMap;

/// One side of a comparison.
#[derive(Debug, Clone, Copy)]
pub struct Side<'a> {
    /// How messages name it (the path as given, with `@variant`).
    pub label: &'a str,
    /// Its cells.
    pub source: Source<'a>,
}

/// Where a side's cells come from.
#[derive(Debug, Clone, Copy)]
pub enum Source<'a> {
    /// A program pipeline.
    Program {
        /// Its plan.
        plan: &'a ProgramPlan,
        /// The variant compared (`None`: the pipeline as written, experiments of no variant).
        variant: Option<&'a str>,
        /// The cache's rows of its plan, one per key (`qsweep_pipeline::program::stored::plan_rows`).
        rows: &'a HashMap<Key, ProgramRow>,
    },
    /// Cells already gathered: an engine pipeline's or a report folder's.
    Cells(&'a CellSet),
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
    /// `--where-a NAME=V,…`: only A's cells whose param NAME shows one of the values.
    pub where_a: Vec<(String, Vec<String>)>,
    /// `--where-b`, for B.
    pub where_b: Vec<(String, Vec<String>)>,
}

/// The default equivalence margin on B ÷ A: the conventional 0.80–1.25, symmetric on a log scale.
pub const DEFAULT_MARGIN: (f64, f64) = (0.80, 1.25);

/// One cell of the comparison: its shared values and each side's sample of the metric (succeeded
/// trials only; of none when the cache has none).
#[derive(Debug, Clone, PartialEq)]
pub struct CellSamples {
    /// The shared params' values, in [`Matched::shared`] order (A's values).
    pub values: Vec<ParamValue>,
    /// A's sample of the metric.
    pub a: Sample,
    /// B's sample of the metric.
    pub b: Sample,
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

/// `name=value …` of a cell's shared values, by A's names (a param the cell has no value of,
/// [`ABSENT`], left out).
pub fn cell_label(shared: &[(String, String)], values: &[ParamValue]) -> String {
    shared
        .iter()
        .zip(values)
        .filter(|(_, v)| !matches!(v, ParamValue::Str(s) if s == ABSENT))
        .map(|(p, v)| format!("{}={v}", p.0))
        .collect::<Vec<_>>()
        .join(" ")
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
    let names_a: Vec<&str> = shared.iter().map(|(n, _)| n.as_str()).collect();
    let names_b: Vec<&str> = shared.iter().map(|(_, n)| n.as_str()).collect();
    let cells_a = cells_of(a, &names_a, &metric.0, &Filter::new(a, &request.where_a)?)?;
    let cells_b = cells_of(b, &names_b, &metric.1, &Filter::new(b, &request.where_b)?)?;
    let by_key_b: HashMap<&Vec<String>, &SideCell> = cells_b.iter().map(|c| (&c.key, c)).collect();
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
                a: c.sample.clone(),
                b: cb.sample.clone(),
            }),
            None => out.only_a.push(c.values.clone()),
        }
    }
    let keys_a: std::collections::HashSet<&Vec<String>> = cells_a.iter().map(|c| &c.key).collect();
    out.only_b = cells_b.iter().filter(|c| !keys_a.contains(&c.key)).map(|c| c.values.clone()).collect();
    Ok(out)
}

/// A side's params' names, in order.
fn param_names(s: &Side) -> Vec<String> {
    match s.source {
        Source::Program { plan, .. } => plan.params.iter().map(|(n, _)| n.clone()).collect(),
        Source::Cells(set) => set.params.clone(),
    }
}

/// A param's declared type (`None`: a [`CellSet`]'s, whose values are of any type).
fn param_type(s: &Side, name: &str) -> Option<ParamType> {
    match s.source {
        Source::Program { plan, .. } => plan.params.iter().find(|(p, _)| p == name).map(|(_, t)| *t),
        Source::Cells(_) => None,
    }
}

/// A side's metrics, for messages.
fn metric_names(s: &Side) -> String {
    match s.source {
        Source::Program { plan, .. } => {
            plan.program.metrics.iter().map(|(n, _)| n.as_str()).collect::<Vec<_>>().join(", ")
        }
        Source::Cells(set) => set.metrics.join(", "),
    }
}

/// The shared params, (A's name, B's name) in A's order, after checking every `--map` entry.
fn shared_params(a: &Side, b: &Side, map: &[(String, String)]) -> anyhow::Result<Vec<(String, String)>> {
    let (na, nb) = (param_names(a), param_names(b));
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
    // Params of the same type on both sides are what a cell's values can match on (a cell set's
    // values are of any type: its cells match where the values do).
    for (x, y) in &shared {
        let (ta, tb) = (param_type(a, x), param_type(b, y));
        let numeric = |t: Option<ParamType>| matches!(t, Some(ParamType::Int | ParamType::Float));
        if ta.is_some() && tb.is_some() && ta != tb && !(numeric(ta) && numeric(tb)) {
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

/// The metric, (A's name, B's name): `--metric`, else A's default on both sides (a program's
/// objective, an engine side's `episodes`); each must be a declared `int`, `float` or `bool`
/// metric of a program, or one of a cell set's metrics.
fn metric(a: &Side, b: &Side, given: Option<&(String, String)>) -> anyhow::Result<(String, String)> {
    let (x, y) = match given {
        Some(m) => m.clone(),
        None => match a.source {
            Source::Program { plan, .. } => match &plan.program.objective {
                Some(o) => (o.metric.clone(), o.metric.clone()),
                None => {
                    return Err(user_error(format!(
                        "{} declares no objective: name the metric to compare with --metric NAME (or --metric A_NAME=B_NAME); its metrics: {}",
                        a.label,
                        metric_names(a)
                    )))
                }
            },
            Source::Cells(set) => (set.metrics[0].clone(), set.metrics[0].clone()),
        },
    };
    for (s, n, is_a) in [(a, &x, true), (b, &y, false)] {
        let how = || {
            if is_a {
                "name one of them with --metric NAME (or --metric NAME=B_NAME)".to_string()
            } else {
                format!("name B's with --metric {x}=B_NAME")
            }
        };
        match s.source {
            Source::Program { plan, .. } => {
                let Some((_, t)) = plan.program.metrics.iter().find(|(m, _)| m == n) else {
                    return Err(user_error(format!(
                        "{} has no metric `{n}` (its metrics: {}): {}",
                        s.label,
                        metric_names(s),
                        how()
                    )));
                };
                if !matches!(t, MetricType::Int | MetricType::Float | MetricType::Bool) {
                    return Err(user_error(format!(
                        "metric `{n}` of {} is a {}: compare takes an int, float or bool metric (its metrics: {})",
                        s.label,
                        t.name(),
                        metric_names(s)
                    )));
                }
            }
            Source::Cells(set) => {
                if !set.metrics.contains(n) {
                    return Err(user_error(format!(
                        "{} ({}) has no metric `{n}` (its metrics: {}): {}",
                        s.label,
                        set.what,
                        metric_names(s),
                        how()
                    )));
                }
            }
        }
    }
    Ok((x, y))
}

/// One side's cell: its matching key, shared values and its sample of the metric.
struct SideCell {
    key: Vec<String>,
    values: Vec<ParamValue>,
    sample: Sample,
}

/// `--where-a`/`--where-b` of one side: each param's position and the values it may show (as
/// the param prints: `cart-pole`, `0.1`, `true`).
struct Filter(Vec<(usize, Vec<String>)>);

impl Filter {
    /// The filter of `side` from `wheres`; a param the side does not have is the user's error.
    fn new(side: &Side, wheres: &[(String, Vec<String>)]) -> anyhow::Result<Self> {
        let names = param_names(side);
        let mut out = Vec::new();
        for (name, values) in wheres {
            let Some(i) = names.iter().position(|n| n == name) else {
                return Err(user_error(format!(
                    "--where on {}: it has no param `{name}`; its params: {}",
                    side.label,
                    names.join(", ")
                )));
            };
            out.push((i, values.clone()));
        }
        Ok(Self(out))
    }

    /// Whether a cell of these param values is kept.
    fn keeps(&self, params: &[ParamValue]) -> bool {
        self.0.iter().all(|(i, values)| values.contains(&params[*i].to_string()))
    }
}

/// The cells of `side` (of its variant) that `filter` keeps, one per shared-value tuple (`shared`:
/// their names on this side), in plan order, each with its sample of `metric`.
fn cells_of(side: &Side, shared: &[&str], metric: &str, filter: &Filter) -> anyhow::Result<Vec<SideCell>> {
    match side.source {
        Source::Program { plan, variant, rows } => {
            program_cells(side, plan, variant, rows, shared, metric, filter)
        }
        Source::Cells(set) => set_cells(side, set, shared, metric, filter),
    }
}

/// A [`CellSet`]'s cells: two with the same shared values are one when they are one configuration
/// (their identity, e.g. in two experiments), else ambiguous.
fn set_cells(
    side: &Side,
    set: &CellSet,
    shared: &[&str],
    metric: &str,
    filter: &Filter,
) -> anyhow::Result<Vec<SideCell>> {
    let idx: Vec<usize> = shared
        .iter()
        .map(|n| set.params.iter().position(|p| p == n).expect("a shared param is named"))
        .collect();
    let m = set.metrics.iter().position(|x| x == metric).expect("the metric is checked");
    let mut out: Vec<SideCell> = Vec::new();
    let mut first_of: HashMap<Vec<String>, usize> = HashMap::new();
    for (ci, c) in set.cells.iter().enumerate().filter(|(_, c)| filter.keeps(&c.params)) {
        let values: Vec<ParamValue> = idx.iter().map(|&i| c.params[i].clone()).collect();
        let key: Vec<String> = values.iter().map(value_key).collect();
        match first_of.get(&key) {
            Some(&first) if set.cells[first].identity == c.identity => {}
            Some(&first) => {
                return Err(ambiguous(side, &set.params, &set.cells[first].params, &c.params, &values, &idx))
            }
            None => {
                first_of.insert(key.clone(), ci);
                out.push(SideCell { key, values, sample: c.samples[m].clone() });
            }
        }
    }
    Ok(out)
}

/// A program pipeline's cells: the same params in two experiments are one cell (their trials
/// together).
fn program_cells(
    side: &Side,
    plan: &ProgramPlan,
    variant: Option<&str>,
    rows: &HashMap<Key, ProgramRow>,
    shared: &[&str],
    metric: &str,
    filter: &Filter,
) -> anyhow::Result<Vec<SideCell>> {
    let idx: Vec<usize> = shared
        .iter()
        .map(|n| plan.params.iter().position(|(p, _)| p == n).expect("a shared param"))
        .collect();
    let m = plan.program.metrics.iter().position(|(n, _)| n == metric).expect("the metric is declared");
    let exps: Vec<_> = plan.experiments.iter().filter(|e| e.variant.as_deref() == variant).collect();
    if exps.is_empty() {
        let ids: Vec<&str> = plan.variants.iter().map(|v| v.id.as_str()).collect();
        return Err(user_error(match variant {
            None if !ids.is_empty() => format!(
                "{} declares variants ({}), so it plans no cell as written: compare one with {}@ID",
                side.label,
                ids.join(", "),
                side.label
            ),
            _ => format!("{} plans no cell", side.label),
        }));
    }
    let names: Vec<String> = plan.params.iter().map(|(n, _)| n.clone()).collect();
    // (key, values, params, trial keys), merged over experiments.
    type Merged<'p> = (Vec<String>, Vec<ParamValue>, &'p Vec<ParamValue>, Vec<Key>);
    let mut cells: Vec<Merged> = Vec::new();
    let mut at: HashMap<Vec<String>, usize> = HashMap::new();
    for e in exps {
        for c in e.cells.iter().filter(|c| filter.keeps(&c.params)) {
            let values: Vec<ParamValue> = idx.iter().map(|&i| c.params[i].clone()).collect();
            let key: Vec<String> = values.iter().map(value_key).collect();
            match at.get(&key) {
                Some(&i) => {
                    let first = &mut cells[i];
                    if *first.2 != c.params {
                        return Err(ambiguous(side, &names, first.2, &c.params, &values, &idx));
                    }
                    for t in &c.trials {
                        if !first.3.contains(&t.key) {
                            first.3.push(t.key);
                        }
                    }
                }
                None => {
                    at.insert(key.clone(), cells.len());
                    cells.push((key, values, &c.params, c.trials.iter().map(|t| t.key).collect()));
                }
            }
        }
    }
    Ok(cells
        .into_iter()
        .map(|(key, values, _, keys)| SideCell {
            key,
            values,
            sample: Sample::Values(samples(rows, &keys, m)),
        })
        .collect())
}

/// The error of two cells with the same shared values and other unshared ones.
fn ambiguous(
    side: &Side,
    names: &[String],
    first: &[ParamValue],
    other: &[ParamValue],
    values: &[ParamValue],
    shared: &[usize],
) -> anyhow::Error {
    let differ: Vec<String> = (0..first.len())
        .filter(|i| first[*i] != other[*i])
        .map(|i| format!("`{}` ({} vs {})", names[i], first[i], other[i]))
        .collect();
    let at: Vec<String> = shared.iter().zip(values).map(|(&i, v)| format!("{}={v}", names[i])).collect();
    user_error(format!(
        "{}: two cells at {} differ only in params the other side does not have: {}; \
         name them in the other side with --map A_NAME=B_NAME (a program pipeline can declare an \
         engine cell's params, e.g. `system: cart-pole`), or compare sides that fix them",
        side.label,
        at.join(" "),
        differ.join(", ")
    ))
}

/// The metric's values (index `m`) of the succeeded rows of `keys`; a bool counts as 0 or 1.
fn samples(rows: &HashMap<Key, ProgramRow>, keys: &[Key], m: usize) -> Vec<f64> {
    keys.iter()
        .filter_map(|k| rows.get(k))
        .filter_map(|r| r.result.as_ref().ok())
        .filter_map(|metrics| match metrics.get(m)? {
            MetricValue::Int(i) => Some(*i as f64),
            MetricValue::Float(f) => Some(*f),
            MetricValue::Bool(b) => Some(if *b { 1.0 } else { 0.0 }),
            _ => None,
        })
        .collect()
}
