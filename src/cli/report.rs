//! `qsweep report`: write the pipeline's report from the cache ([`qsweep_report::write`]).
//!
//! It never replaces a report with one lacking trials of its own plan when the kept one holds
//! more (a fresh clone's empty cache would otherwise overwrite the committed report) unless told
//! to with `--force`, and never creates the cache.
//!
//! Ctrl-C or SIGTERM stops it before its next file and exits 130; every file is written
//! atomically and a folder's memo comes after its files, so the next report completes the folder.

use super::pipeline_args::{print_report, warn_quarantined, PipelineArgs, ReportFlags};
use clap::Args;
use qsweep_pipeline::error::exit;
use qsweep_pipeline::exec::INTERRUPTED;
use std::sync::atomic::Ordering;

/// Arguments of `qsweep report`.
#[derive(Debug, Args)]
pub struct ReportArgs {
    #[command(flatten)]
    pub pipeline: PipelineArgs,
    #[command(flatten)]
    pub report: ReportFlags,
    /// Replace the report in the report directory even if the cache lacks some of the plan's
    /// trials and the kept report holds more (without it, that exits 1 and writes nothing).
    #[arg(long)]
    pub force: bool,
    /// Print nothing but errors.
    #[arg(long, short = 'q')]
    pub quiet: bool,
    /// Print what was recomputed, reused and written as one JSON object (README: JSON formats).
    #[arg(long)]
    pub json: bool,
}

/// Run `qsweep report`.
pub fn run(a: ReportArgs) -> anyhow::Result<u8> {
    let start = std::time::Instant::now();
    install_ctrlc();
    let plan = a.pipeline.plan()?;
    let pipeline = plan.name.clone();
    let store = a.pipeline.cache.required_store()?;
    let scan = qsweep_pipeline::run::scan(&store)?;
    warn_quarantined(&scan);
    let opts = a.report.options(&plan, a.force);
    let outcome = qsweep_report::write(plan, &store, &scan.stored, &opts)?;
    if a.json {
        let v = crate::json::ReportJson {
            format_version: crate::json::ReportJson::FORMAT_VERSION,
            pipeline,
            dir: opts.dir.display().to_string(),
            cells_recomputed: outcome.cells_recomputed,
            cells_reused: outcome.cells_reused,
            intervals_computed: outcome.statistics.computed,
            intervals_reused: outcome.statistics.reused,
            files_written: outcome.files_written,
            files_unchanged: outcome.files_unchanged,
            seconds: start.elapsed().as_secs_f64(),
        };
        println!("{}", serde_json::to_string(&v)?);
        for w in &outcome.warnings {
            eprintln!("warning: {w}");
        }
    } else if !a.quiet {
        print_report(&outcome, &opts);
    }
    Ok(exit::OK)
}

/// Ctrl-C or SIGTERM stops the report before its next file (`Folder::put` checks); a second one
/// exits at once (every file written so far is whole).
pub(super) fn install_ctrlc() {
    let _ = ctrlc::set_handler(|| {
        if INTERRUPTED.swap(true, Ordering::SeqCst) {
            std::process::exit(i32::from(exit::INTERRUPTED));
        }
        eprintln!("\ninterrupted (Ctrl-C or SIGTERM): stopping before the next file; press Ctrl-C again to stop now");
    });
}
