//! `qsweep compare A B`: did a change move a pipeline's results beyond chance? Resolves each
//! side (a program pipeline, an engine pipeline, either as `path@variant`, or an engine report
//! folder), has the library gather its cells (`qsweep_report::comparison`: a program's rows, an
//! engine plan's cells as the report reads them, a folder's `cells.parquet`), compares them,
//! then prints its summary or JSON and, with `--out`, has it write its files.

use super::pipeline_args::CacheArgs;
use clap::Args;
use qsweep_pipeline::error::{exit, user_error};
use qsweep_report::comparison::{self, CellSet, Comparison, Request, Side, Source, Verdict};
use std::path::{Path, PathBuf};

/// Arguments of `qsweep compare`.
#[derive(Debug, Args)]
pub struct CompareArgs {
    /// The side before: a program or engine pipeline file (`PATH@VARIANT` for one of its
    /// variants), or an engine report folder holding cells.parquet (`DIR@VARIANT` for one
    /// variant's rows of a pipeline's root folder).
    pub a: String,
    /// The side after, compared with A (as for A).
    pub b: String,
    /// A's param NAME is B's param OTHER (repeatable); params named alike in both are shared
    /// without it.
    #[arg(long = "map", value_name = "NAME=OTHER")]
    pub map: Vec<String>,
    /// The metric: `NAME` in both, or `NAME=OTHER` (A's NAME against B's OTHER)
    /// [default: A's objective; an engine side's `episodes`].
    #[arg(long, value_name = "NAME[=OTHER]")]
    pub metric: Option<String>,
    /// Only A's cells whose param NAME has one of these values (repeatable: every one must hold),
    /// e.g. `--where-a system=cart-pole`.
    #[arg(long = "where-a", value_name = "NAME=VALUE[,VALUE…]")]
    pub where_a: Vec<String>,
    /// Only B's cells whose param NAME has one of these values (as `--where-a`).
    #[arg(long = "where-b", value_name = "NAME=VALUE[,VALUE…]")]
    pub where_b: Vec<String>,
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

/// `NAME=VALUE[,VALUE…]` as the name and its values.
fn filter(flag: &str, s: &str) -> anyhow::Result<(String, Vec<String>)> {
    match s.split_once('=') {
        Some((n, v)) if !n.is_empty() && !v.is_empty() => {
            Ok((n.to_string(), v.split(',').map(|x| x.trim().to_string()).collect()))
        }
        _ => Err(user_error(format!("{flag} {s}: expected NAME=VALUE or NAME=VALUE,VALUE,…"))),
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

/// `PATH@VARIANT` split (an existing file or folder whose name holds `@` is a path as a whole).
fn split_spec(s: &str) -> (PathBuf, Option<String>) {
    if Path::new(s).exists() {
        return (PathBuf::from(s), None);
    }
    match s.rsplit_once('@') {
        Some((p, v)) if !p.is_empty() && !v.is_empty() => (PathBuf::from(p), Some(v.to_string())),
        _ => (PathBuf::from(s), None),
    }
}

/// One side resolved: a program pipeline planned, with the cache's rows of its plan, or the cells
/// of an engine pipeline or a report folder.
enum Loaded {
    Program {
        label: String,
        variant: Option<String>,
        plan: Box<qsweep_pipeline::program::model::ProgramPlan>,
        rows: std::collections::HashMap<
            qsweep_pipeline::cache::Key,
            qsweep_pipeline::program::model::ProgramRow,
        >,
    },
    Cells {
        label: String,
        set: CellSet,
    },
}

impl Loaded {
    fn side(&self) -> Side<'_> {
        match self {
            Self::Program { label, variant, plan, rows } => {
                Side { label, source: Source::Program { plan, variant: variant.as_deref(), rows } }
            }
            Self::Cells { label, set } => Side { label, source: Source::Cells(set) },
        }
    }
}

fn load(spec: &str, cache: &CacheArgs) -> anyhow::Result<Loaded> {
    let (path, variant) = split_spec(spec);
    if path.is_dir() {
        let set = comparison::folder::read(&path, variant.as_deref())?;
        return Ok(Loaded::Cells { label: spec.to_string(), set });
    }
    if !path.is_file() {
        return Err(user_error(format!("{}: no such pipeline file or report folder", path.display())));
    }
    let mut args = super::program::bare(&path, cache);
    args.variant = variant.iter().cloned().collect();
    if !super::program::is_program_file(&path) {
        // An engine pipeline: one variant's cells (or the pipeline's, without variants).
        let plan = args.plan()?;
        if variant.is_none() && !plan.variants.is_empty() {
            let ids: Vec<&str> = plan.variants.iter().map(|v| v.id.as_str()).collect();
            return Err(user_error(format!(
                "{spec} declares variants ({}): compare one of them with {spec}@ID",
                ids.join(", ")
            )));
        }
        let store = cache.existing_store()?;
        let set = comparison::engine::read(plan, store.as_ref())?;
        return Ok(Loaded::Cells { label: spec.to_string(), set });
    }
    let plan = super::program::plan(&args)?;
    let store = super::program::existing_folder(cache, &plan)?;
    // A raced plan's cells hold the seeds their race gave them, as the report counts them.
    let plan = qsweep_pipeline::program::race::replay_store(plan, store.as_ref())?.plan;
    let rows = qsweep_pipeline::program::stored::plan_rows(&plan, store.as_ref())?;
    Ok(Loaded::Program { label: spec.to_string(), variant, plan: Box::new(plan), rows })
}

/// Run `qsweep compare`.
pub fn run(a: CompareArgs) -> anyhow::Result<u8> {
    let request = Request {
        map: a.map.iter().map(|m| pair("--map", m, false)).collect::<Result<_, _>>()?,
        metric: a.metric.as_deref().map(|m| pair("--metric", m, true)).transpose()?,
        margin: margin(&a.margin)?,
        where_a: a.where_a.iter().map(|w| filter("--where-a", w)).collect::<Result<_, _>>()?,
        where_b: a.where_b.iter().map(|w| filter("--where-b", w)).collect::<Result<_, _>>()?,
    };
    let (la, lb) = (load(&a.a, &a.cache)?, load(&a.b, &a.cache)?);
    let c = comparison::compare(&la.side(), &lb.side(), &request)?;
    if c.cells.is_empty() {
        let run = |spec: &str| {
            let (path, _) = split_spec(spec);
            if path.is_dir() {
                format!("{spec} has no trials of them")
            } else {
                format!("qsweep run {}", path.display())
            }
        };
        eprintln!(
            "compare: the cache {} holds no trials of any of the {} matched cells (run both pipelines first: {}; {})",
            a.cache.name(),
            c.missing.len(),
            run(&a.a),
            run(&a.b)
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
    // The cells that differ most (smallest p), at most LISTED of them: an engine plan has thousands.
    const LISTED: usize = 20;
    let mut differ: Vec<_> = c.cells.iter().filter(|x| x.verdict == Verdict::Differs).collect();
    differ.sort_by(|x, y| x.p.unwrap_or(1.0).total_cmp(&y.p.unwrap_or(1.0)));
    for x in differ.iter().take(LISTED) {
        let ci = x.ratio_ci.map_or(String::new(), |(lo, hi)| format!(" [{lo:.3}, {hi:.3}]"));
        println!(
            "differs: {}: B/A {}{ci}, p = {}",
            x.label,
            x.ratio.map_or("-".to_string(), |r| format!("{r:.3}")),
            x.p.map_or("-".to_string(), comparison::stats::p_text)
        );
    }
    if differ.len() > LISTED {
        println!(
            "… and {} more cells that differ (all of them: --json, or --out DIR's compare.csv)",
            differ.len() - LISTED
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
