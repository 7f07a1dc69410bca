//! `qsweep gc`: compact the cache and drop rows (and statistics' memos) no given pipeline
//! references; the segments of runs still alive stay as they are (`qsweep_pipeline::cache::gc`).
//! The program folders are compacted each on its own, and pruned only by the program pipelines
//! given (`qsweep_pipeline::program::gc`); engine rows are pruned only by engine pipelines.

use super::pipeline_args::CacheArgs;
use clap::Args;
use qsweep_pipeline::declared::load;
use qsweep_pipeline::error::exit;
use qsweep_pipeline::plan::plan;
use std::path::PathBuf;

/// Arguments of `qsweep gc`.
#[derive(Debug, Args)]
pub struct GcArgs {
    /// Keep only the trials of these pipelines (none: keep every row, just compact). Engine
    /// pipelines prune the engine's rows, program pipelines the program folders of their schema.
    pub pipelines: Vec<PathBuf>,
    #[command(flatten)]
    pub cache: CacheArgs,
    /// Say what would be removed and compacted; change nothing.
    #[arg(long)]
    pub dry_run: bool,
}

/// Run `qsweep gc`.
pub fn run(a: GcArgs) -> anyhow::Result<u8> {
    let store = a.cache.required_store()?;
    let (programs, engines): (Vec<PathBuf>, Vec<PathBuf>) =
        a.pipelines.iter().cloned().partition(|p| super::program::is_program_file(p));
    // Engine rows are pruned only by engine pipelines, program rows only by program pipelines.
    let (keep, names) = if engines.is_empty() {
        (None, None)
    } else {
        let plans = engines.iter().map(|p| plan(&load(p, &[])?, None)).collect::<anyhow::Result<Vec<_>>>()?;
        let names = plans.iter().map(|p| p.name.clone()).collect();
        (Some(qsweep_pipeline::run::referenced_keys(&plans, &store)?), Some(names))
    };
    let program_keep = if a.pipelines.is_empty() {
        None
    } else {
        Some(super::program::referenced_keys(&programs, &a.cache)?)
    };
    let r = store.gc(keep.as_ref(), a.dry_run)?;
    let version = qsweep_report::memo::ANALYSIS_VERSION;
    let memos = qsweep_report::memo::stats::gc(store.dir(), names.as_ref(), version, a.dry_run)?;
    let p = qsweep_pipeline::program::gc::gc(store.dir(), program_keep.as_ref(), a.dry_run)?;
    for s in r.skipped.iter().chain(&p.skipped) {
        eprintln!("warning: left unreadable segment in place (run `qsweep verify`): {s}");
    }
    for p in &memos.in_use {
        eprintln!(
            "warning: left trial parts in place, a report is reading them (run `qsweep gc` again later): {}",
            p.display()
        );
    }
    let mib = |b: u64| b as f64 / (1 << 20) as f64;
    let (before, after) = (r.bytes_before + p.bytes_before, r.bytes_after + p.bytes_after);
    let sizes = if a.dry_run {
        format!("{:.2} MiB now", mib(before))
    } else {
        format!(
            "{:.2} MiB → {:.2} MiB ({:.2} MiB freed)",
            mib(before),
            mib(after),
            mib(before.saturating_sub(after))
        )
    };
    let programs = program_summary(&p, a.pipelines.is_empty());
    println!(
        "{}{} segments → {}, {} rows kept, {} removed (no given pipeline references them), {} rows kept: written by a live run, {} duplicates dropped, {} stale temp files, {} dead runs' leases, {} statistics' memos and trial parts{programs}; {sizes}",
        if a.dry_run { "dry run: " } else { "" },
        r.segments_before,
        r.segments_after,
        r.rows_kept,
        r.rows_removed,
        r.rows_live,
        r.duplicates,
        r.stale_temps + p.stale_temps,
        r.stale_leases + p.stale_leases,
        memos.removed,
    );
    Ok(exit::OK)
}

/// What gc did to the program folders, as a clause of its summary line (empty when the cache has
/// none). `all` when no pipeline was given (nothing pruned).
fn program_summary(p: &qsweep_pipeline::program::gc::ProgramGcReport, all: bool) -> String {
    if p.folders == 0 && p.left_alone.is_empty() {
        return String::new();
    }
    let mut s = format!(
        "; program rows ({} folders): {} segments → {}, {} rows kept, {} removed (no given program pipeline references them), {} rows kept: written by a live run, {} duplicates dropped",
        p.folders, p.segments_before, p.segments_after, p.rows_kept, p.rows_removed, p.rows_live, p.duplicates
    );
    if !all && !p.left_alone.is_empty() {
        s.push_str(&format!(
            ", {} folders left alone (no given program pipeline has their params and metrics: {})",
            p.left_alone.len(),
            p.left_alone
                .iter()
                .map(|id| format!("{}/{id}", qsweep_pipeline::program::rows::PROGRAMS_DIR))
                .collect::<Vec<_>>()
                .join(", ")
        ));
    }
    s
}
