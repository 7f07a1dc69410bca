//! `qsweep bench`: steps per second of the production engine on the standard configurations.

use super::pipeline_args::{CacheArgs, PipelineArgs};
use clap::Args;
use qsweep_pipeline::bench::{self, BenchResult};
use qsweep_pipeline::error::user_error;
use std::path::PathBuf;

/// Arguments of `qsweep bench`.
#[derive(Debug, Args)]
// The shared `--cache`, whose help says what the cache is for here.
#[command(mut_arg("cache", |a| a.help(
    "With --pipeline: the cache whose trials rank the cells [env: QSWEEP_CACHE; default: cache]"
)))]
pub struct BenchArgs {
    /// Step budget per timed trial (each trial runs at least this many steps, under twice as many).
    #[arg(long, default_value_t = bench::DEFAULT_STEPS)]
    pub steps: u64,
    /// Timed trials per configuration; the fastest is reported.
    #[arg(long, default_value_t = bench::DEFAULT_REPEATS)]
    pub repeat: u32,
    /// Only configurations whose name contains this, e.g. `cart-pole/fuzzy`.
    #[arg(long, default_value = "")]
    pub filter: String,
    /// Print JSON (`{format_version, results: [{config, steps, seconds, steps_per_s}]}`) instead of a table.
    #[arg(long)]
    pub json: bool,
    /// Benchmark real work instead: the most expensive cells of this pipeline's plan, each with its
    /// real seeds to its real stop, timed by thread CPU time (ranked by the cached trials' CPU
    /// time, or by the engine's estimate where some are not cached).
    #[arg(long, value_name = "FILE")]
    pub pipeline: Option<PathBuf>,
    /// With --pipeline: how many cells to time.
    #[arg(long, default_value_t = 10, value_name = "N")]
    pub top: usize,
    /// With --pipeline: only this variant (repeatable).
    #[arg(long = "variant", value_name = "ID")]
    pub variant: Vec<String>,
    /// With --pipeline: override a field, as for `run`.
    #[arg(long = "set", value_name = "PATH=VALUE")]
    pub set: Vec<String>,
    #[command(flatten)]
    pub cache: CacheArgs,
}

/// Run `qsweep bench`.
pub fn run(a: BenchArgs) -> anyhow::Result<u8> {
    if let Some(pipeline) = a.pipeline.clone() {
        return run_pipeline(a, pipeline);
    }
    if !(1..=u64::from(u32::MAX)).contains(&a.steps) {
        return Err(user_error(format!("--steps: {} is not allowed; use 1 to {}", a.steps, u32::MAX)));
    }
    if a.repeat == 0 {
        return Err(user_error("--repeat: must be at least 1"));
    }
    let cases = bench::standard_cases();
    if !cases.iter().any(|c| c.name.contains(&a.filter)) {
        let names: Vec<_> = cases.iter().map(|c| c.name.as_str()).collect();
        return Err(user_error(format!(
            "--filter: no configuration contains '{}'; they are:\n  {}",
            a.filter,
            names.join("\n  ")
        )));
    }
    let print_row = |r: &BenchResult| {
        if !a.json {
            println!("{}", bench::format_row(r));
        }
    };
    if !a.json {
        println!("{}", bench::header());
    }
    let results = bench::run_cases(&cases, &a.filter, a.steps, a.repeat, print_row);
    if a.json {
        let v =
            crate::json::BenchReport { format_version: crate::json::BenchReport::FORMAT_VERSION, results };
        println!("{}", serde_json::to_string_pretty(&v)?);
    } else {
        println!("{}", simd_line());
    }
    Ok(qsweep_pipeline::error::exit::OK)
}

/// The table's last line: which vector kernels ran, and whether two-variable fuzzy rule bases took
/// the dense path.
fn simd_line() -> String {
    format!(
        "vector kernels: {} (QSWEEP_SIMD: off, avx2, avx512 or auto); dense fuzzy path: {} (QSWEEP_DENSE)",
        qsweep_engine::simd::level().name(),
        if qsweep_engine::dense_path::dense_enabled() { "on" } else { "off" }
    )
}

/// `qsweep bench --pipeline P`: time the plan's most expensive cells.
fn run_pipeline(a: BenchArgs, pipeline: PathBuf) -> anyhow::Result<u8> {
    use qsweep_pipeline::bench::pipeline::{format_row, header, ranked_cells, time_cell, CostBasis};
    if a.top == 0 {
        return Err(user_error("--top: must be at least 1"));
    }
    let p = PipelineArgs { pipeline, set: a.set, variant: a.variant, cache: a.cache, yes: true };
    let plan = p.plan()?;
    // The cache only ranks the cells; a missing one is not created (ranking by the estimate).
    let cache = match p.cache.existing_store()? {
        Some(store) => {
            let scan = store.keys()?;
            Some((store, scan))
        }
        None => None,
    };
    let (cells, basis) = ranked_cells(&plan, cache.as_ref().map(|(s, k)| (s, k)))?;
    let total: f64 = cells.iter().map(|c| c.cost).sum();
    let unit = match basis {
        CostBasis::Cached => "the cached trials' CPU seconds",
        CostBasis::Estimated => "the engine's estimate (not every trial is cached)",
    };
    if !a.json {
        println!(
            "{}: the {} most expensive of {} distinct cells, ranked by {unit}",
            plan.name,
            a.top.min(cells.len()),
            cells.len()
        );
        println!("{}", header());
    }
    let mut results = Vec::new();
    for c in cells.iter().take(a.top) {
        let r = time_cell(c, total);
        if !a.json {
            println!("{}", format_row(&r));
        }
        results.push(r);
    }
    if a.json {
        let v = crate::json::PipelineBenchReport {
            format_version: crate::json::PipelineBenchReport::FORMAT_VERSION,
            pipeline: plan.name.clone(),
            basis,
            cells: cells.len(),
            results,
        };
        println!("{}", serde_json::to_string_pretty(&v)?);
    } else {
        let share: f64 = results.iter().map(|r| r.share).sum();
        println!("these cells: {:.1}% of the pipeline's cost", 100.0 * share);
        println!("{}", simd_line());
    }
    Ok(qsweep_pipeline::error::exit::OK)
}
