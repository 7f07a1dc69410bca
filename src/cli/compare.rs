//! `qsweep compare A B`: did a change move a program pipeline's results beyond chance? Parses
//! the two pipelines (`path@variant`), plans each, reads the cache's rows of each plan, and calls
//! the library (`qsweep_report::comparison`), then prints its summary or JSON and, with `--out`,
//! has it write its files.

use super::pipeline_args::CacheArgs;
use clap::Args;
use qsweep_pipeline::error::{exit, user_error};
use qsweep_report::comparison::{self, Comparison, Request, Side, Verdict};
use std::path::{Path, PathBuf};

/// Arguments of `qsweep compare`.
#[derive(Debug, Args)]
pub struct CompareArgs {
    /// The pipeline before (a program pipeline file; `PATH@VARIANT` for one of its variants).
    pub a: String,
    /// The pipeline after, compared with A (`PATH@VARIANT` as for A).
    pub b: String,
    /// A's param NAME is B's param OTHER (repeatable); params named alike in both are shared
    /// without it.
    #[arg(long = "map", value_name = "NAME=OTHER")]
    pub map: Vec<String>,
    /// The metric: `NAME` in both, or `NAME=OTHER` (A's NAME against B's OTHER)
    /// [default: A's objective].
    #[arg(long, value_name = "NAME[=OTHER]")]
    pub metric: Option<String>,
    /// The equivalence margin on B ÷ A, `LO,HI`.
    #[arg(long, value_name = "LO,HI", default_value = "0.80,1.25")]
    pub margin: String,
    /// Write compare.csv, compare.md and compare.svg into DIR.
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// Print the comparison as one JSON object.
    #[arg(long)]
    pub json: bool,
    #[command(flatten)]
    pub cache: CacheArgs,
}

/// `NAME=OTHER` as a pair; `NAME` alone is itself on both sides when `alone` allows it.
fn pair(flag: &str, s: &str, alone: bool) -> anyhow::Result<(String, String)> {
    match s.split_once('=') {
        Some((a, b)) if !a.is_empty() && !b.is_empty() => Ok((a.to_string(), b.to_string())),
        None if alone && !s.is_empty() => Ok((s.to_string(), s.to_string())),
        _ => {
            Err(user_error(format!("{flag} {s}: expected NAME=OTHER{}", if alone { " or NAME" } else { "" })))
        }
    }
}

fn margin(s: &str) -> anyhow::Result<(f64, f64)> {
    let bad = || user_error(format!("--margin {s}: expected LO,HI with 0 < LO < 1 < HI, e.g. 0.80,1.25"));
    let (lo, hi) = s.split_once(',').ok_or_else(bad)?;
    let (lo, hi): (f64, f64) = (lo.trim().parse().map_err(|_| bad())?, hi.trim().parse().map_err(|_| bad())?);
    if !(lo > 0.0 && lo < 1.0 && hi > 1.0 && hi.is_finite()) {
        return Err(bad());
    }
    Ok((lo, hi))
}

/// `PATH@VARIANT` split (an existing file whose name holds `@` is a path as a whole).
fn split_spec(s: &str) -> (PathBuf, Option<String>) {
    if Path::new(s).is_file() {
        return (PathBuf::from(s), None);
    }
    match s.rsplit_once('@') {
        Some((p, v)) if !p.is_empty() && !v.is_empty() => (PathBuf::from(p), Some(v.to_string())),
        _ => (PathBuf::from(s), None),
    }
}

/// One side planned, with the cache's rows of its plan.
struct Loaded {
    label: String,
    variant: Option<String>,
    plan: qsweep_pipeline::program::model::ProgramPlan,
    rows: std::collections::HashMap<qsweep_pipeline::cache::Key, qsweep_pipeline::program::model::ProgramRow>,
}

impl Loaded {
    fn side(&self) -> Side<'_> {
        Side { label: &self.label, plan: &self.plan, variant: self.variant.as_deref(), rows: &self.rows }
    }
}

fn load(spec: &str, cache: &CacheArgs) -> anyhow::Result<Loaded> {
    let (path, variant) = split_spec(spec);
    if !path.is_file() {
        return Err(user_error(format!("{}: no such pipeline file", path.display())));
    }
    if !super::program::is_program_file(&path) {
        return Err(user_error(format!(
            "{}: not a program pipeline (no `program:`): compare takes program pipelines for now (docs/programs.md)",
            path.display()
        )));
    }
    let mut args = super::program::bare(&path, cache);
    args.variant = variant.iter().cloned().collect();
    let plan = super::program::plan(&args)?;
    let store = super::program::existing_folder(cache, &plan)?;
    let rows = qsweep_pipeline::program::stored::plan_rows(&plan, store.as_ref())?;
    Ok(Loaded { label: spec.to_string(), variant, plan, rows })
}

/// Run `qsweep compare`.
pub fn run(a: CompareArgs) -> anyhow::Result<u8> {
    let request = Request {
        map: a.map.iter().map(|m| pair("--map", m, false)).collect::<Result<_, _>>()?,
        metric: a.metric.as_deref().map(|m| pair("--metric", m, true)).transpose()?,
        margin: margin(&a.margin)?,
    };
    let (la, lb) = (load(&a.a, &a.cache)?, load(&a.b, &a.cache)?);
    let c = comparison::compare(&la.side(), &lb.side(), &request)?;
    if c.cells.is_empty() {
        eprintln!(
            "compare: the cache {} holds no trials of any of the {} matched cells (run both pipelines first: qsweep run {}; qsweep run {})",
            a.cache.dir().display(),
            c.missing.len(),
            split_spec(&a.a).0.display(),
            split_spec(&a.b).0.display()
        );
        return Ok(exit::FAILURE);
    }
    let written = a.out.as_deref().map(|dir| comparison::files::write(&c, dir)).transpose()?;
    if a.json {
        println!("{}", serde_json::to_string_pretty(&crate::json::CompareJson::of(&c))?);
    } else {
        print_summary(&c);
        if let Some(files) = written {
            let names: Vec<String> = files.iter().map(|p| p.display().to_string()).collect();
            println!("wrote {}", names.join(", "));
        }
    }
    Ok(exit::OK)
}

/// The short human summary: what was compared, the overall line, the verdicts, the cells that
/// differ, and what was not compared.
fn print_summary(c: &Comparison) {
    let shared: Vec<String> =
        c.shared.iter().map(|(x, y)| if x == y { x.clone() } else { format!("{x}={y}") }).collect();
    let metric =
        if c.metric.0 == c.metric.1 { c.metric.0.clone() } else { format!("{}={}", c.metric.0, c.metric.1) };
    println!(
        "compared {} cells of {} and {} on metric {metric} (shared params: {}; margin {:.2}-{:.2})",
        c.cells.len(),
        c.labels.0,
        c.labels.1,
        shared.join(", "),
        c.margin.0,
        c.margin.1
    );
    let o = &c.overall;
    println!("{}", o.line());
    println!("verdicts: {} equivalent, {} differs, {} undecided", o.verdicts.0, o.verdicts.1, o.verdicts.2);
    for x in c.cells.iter().filter(|x| x.verdict == Verdict::Differs) {
        let ci = x.ratio_ci.map_or(String::new(), |(lo, hi)| format!(" [{lo:.3}, {hi:.3}]"));
        println!(
            "differs: {}: B/A {}{ci}, p = {}",
            x.label,
            x.ratio.map_or("-".to_string(), |r| format!("{r:.3}")),
            x.p.map_or("-".to_string(), comparison::stats::p_text)
        );
    }
    let untested = c.cells.iter().filter(|x| x.p.is_none()).count();
    if untested > 0 {
        println!("{untested} cells have fewer than 2 trials on a side: no test, counted undecided");
    }
    if !c.missing.is_empty() {
        let list: Vec<String> =
            c.missing.iter().take(5).map(|m| format!("{} (no trials in {})", m.label, m.side)).collect();
        println!(
            "not compared: {} cells without trials on a side: {}{}",
            c.missing.len(),
            list.join(", "),
            if c.missing.len() > 5 { ", …" } else { "" }
        );
    }
    for (side, only) in [("A", &c.only.0), ("B", &c.only.1)] {
        if !only.is_empty() {
            println!("{} cells only {side} plans (not compared)", only.len());
        }
    }
}
