//! `qsweep gc`: compact the cache and drop rows (and statistics' memos) no given pipeline
//! references; the segments of runs still alive stay as they are (`qsweep_pipeline::cache::gc`).

use super::pipeline_args::CacheArgs;
use clap::Args;
use qsweep_pipeline::declared::load;
use qsweep_pipeline::error::exit;
use qsweep_pipeline::plan::plan;
use std::path::PathBuf;

/// Arguments of `qsweep gc`.
#[derive(Debug, Args)]
pub struct GcArgs {
    /// Keep only the trials of these pipelines (none: keep every row, just compact).
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
    let (keep, names) = if a.pipelines.is_empty() {
        (None, None)
    } else {
        let plans =
            a.pipelines.iter().map(|p| plan(&load(p, &[])?, None)).collect::<anyhow::Result<Vec<_>>>()?;
        let names = plans.iter().map(|p| p.name.clone()).collect();
        (Some(qsweep_pipeline::run::referenced_keys(&plans, &store)?), Some(names))
    };
    let r = store.gc(keep.as_ref(), a.dry_run)?;
    let version = qsweep_report::memo::ANALYSIS_VERSION;
    let memos = qsweep_report::memo::stats::gc(store.dir(), names.as_ref(), version, a.dry_run)?;
    for s in &r.skipped {
        eprintln!("warning: left unreadable segment in place (run `qsweep verify`): {s}");
    }
    for p in &memos.in_use {
        eprintln!(
            "warning: left trial parts in place, a report is reading them (run `qsweep gc` again later): {}",
            p.display()
        );
    }
    let mib = |b: u64| b as f64 / (1 << 20) as f64;
    let sizes = if a.dry_run {
        format!("{:.2} MiB now", mib(r.bytes_before))
    } else {
        format!(
            "{:.2} MiB → {:.2} MiB ({:.2} MiB freed)",
            mib(r.bytes_before),
            mib(r.bytes_after),
            mib(r.bytes_before.saturating_sub(r.bytes_after))
        )
    };
    println!(
        "{}{} segments → {}, {} rows kept, {} removed (no given pipeline references them), {} rows kept: written by a live run, {} duplicates dropped, {} stale temp files, {} dead runs' leases, {} statistics' memos and trial parts; {sizes}",
        if a.dry_run { "dry run: " } else { "" },
        r.segments_before,
        r.segments_after,
        r.rows_kept,
        r.rows_removed,
        r.rows_live,
        r.duplicates,
        r.stale_temps,
        r.stale_leases,
        memos.removed,
    );
    Ok(exit::OK)
}
