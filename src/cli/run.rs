//! `qsweep run`: execute the pipeline's missing trials, store them, then write the report.

use super::pipeline_args::{print_report, warn_quarantined, PipelineArgs, ReportFlags};
use clap::Args;
use qsweep_pipeline::exec::{ExecOptions, Reporter, INTERRUPTED};
use qsweep_pipeline::race::{read_cached, replay};
use qsweep_pipeline::run::AfterRun;
use std::sync::atomic::Ordering;
use std::time::Instant;

/// Arguments of `qsweep run`.
#[derive(Debug, Args)]
pub struct RunArgs {
    #[command(flatten)]
    pub pipeline: PipelineArgs,
    /// Worker threads [default: number of CPUs].
    #[arg(long, short = 'j')]
    pub jobs: Option<usize>,
    /// Run every trial again, even those already cached.
    #[arg(long)]
    pub force: bool,
    /// Run again the trials stored as failed (a program pipeline's: docs/programs.md).
    #[arg(long)]
    pub retry_failed: bool,
    /// Run only shard I of N (1 ≤ I ≤ N, as `sbatch --array=1-N` numbers tasks): a deterministic,
    /// cost-balanced split of the plan's trials, so shards on several machines sharing one cache
    /// run every trial exactly once. Cached trials are skipped as usual.
    #[arg(long, value_name = "I/N")]
    pub shard: Option<qsweep_pipeline::exec::shard::Shard>,
    /// Print nothing but errors.
    #[arg(long, short = 'q')]
    pub quiet: bool,
    /// Print the summary as JSON.
    #[arg(long)]
    pub json: bool,
    /// Do not write the report afterwards.
    #[arg(long)]
    pub no_report: bool,
    #[command(flatten)]
    pub report: ReportFlags,
    /// Flush finished trials to the cache after this many...
    #[arg(long, default_value_t = 500, value_name = "N")]
    pub batch_trials: usize,
    /// ...or after this many seconds, whichever comes first.
    #[arg(long, default_value_t = 10.0, value_name = "SECONDS", value_parser = super::args::finite)]
    pub batch_seconds: f64,
}

/// Run `qsweep run`.
pub fn run(a: RunArgs) -> anyhow::Result<u8> {
    if a.retry_failed {
        return Err(qsweep_pipeline::error::user_error(
            "--retry-failed is for program pipelines (docs/programs.md): an engine trial that diverged is a \
             result, stored as such; run it again with --force",
        ));
    }
    let start = Instant::now();
    let plan = a.pipeline.plan()?;
    let store = a.pipeline.cache.writable_store()?;
    install_ctrlc("finishing running ones");
    let scan = qsweep_pipeline::run::scan(&store)?;
    warn_quarantined(&scan);
    let opts = ExecOptions {
        jobs: a.jobs.unwrap_or_else(|| ExecOptions::default().jobs).max(1),
        batch_trials: a.batch_trials.max(1),
        batch_interval: std::time::Duration::from_secs_f64(a.batch_seconds.clamp(0.0, 1e9)),
        leases: Some(leases(&store)?),
        ..ExecOptions::default()
    };
    let sel = qsweep_pipeline::run::Selection { shard: a.shard, force: a.force };
    let mut bar = super::progress::ProgressReporter::default();
    let reporter: &mut dyn Reporter = if a.quiet || a.json { &mut () } else { &mut bar };
    let (name, ropts) = (plan.name.clone(), a.report.options(&plan, false));
    let (done, after) =
        qsweep_pipeline::run::run_trials_replayed(plan, &store, &scan.stored, sel, &opts, reporter)?;
    let report = &done.exec;
    let seconds = start.elapsed().as_secs_f64();
    let v = crate::json::RunSummary {
        format_version: crate::json::RunSummary::FORMAT_VERSION,
        pipeline: name,
        executed: report.executed,
        cached: done.cached,
        elsewhere: report.elsewhere,
        failed: report.failed,
        unfinished: None,
        interrupted: report.interrupted,
        seconds,
    };
    print_summary(&v, a.json, a.quiet)?;
    if report.interrupted {
        if !a.quiet {
            eprintln!("interrupted: {} finished trials are stored; run again to continue", report.executed);
        }
        return Ok(qsweep_pipeline::error::exit::INTERRUPTED);
    }
    if !a.no_report {
        // The trials just stored are in new segments: scan again (the old scan's keys freed first);
        // when nothing was stored the scan stands (a no-op run reads the keys once).
        let (scan, plan) = match after {
            // Nothing ran: the plan as the run replayed it against this scan is the report's.
            AfterRun::Replayed(replayed) => (scan, replayed),
            AfterRun::Planned(plan) => {
                let scan = if report.executed == 0 && report.failed == 0 {
                    scan
                } else {
                    drop(scan);
                    let scan = qsweep_pipeline::run::scan(&store)?;
                    warn_quarantined(&scan);
                    scan
                };
                let plan = replay(plan, &scan.stored.keys, &mut read_cached(&store, &scan.stored))?;
                (scan, plan)
            }
        };
        let outcome = qsweep_report::write_replayed(plan, &store, &scan.stored, &ropts)?;
        if !(a.quiet || a.json) {
            print_report(&outcome, &ropts);
        }
    }
    if report.failed > 0 {
        eprintln!("{} trials failed (diverged); see the `failure` column of trials.parquet", report.failed);
        return Ok(qsweep_pipeline::error::exit::FAILURE);
    }
    Ok(qsweep_pipeline::error::exit::OK)
}

/// A run's summary: as JSON (`--json`), or one line (`executed N, cached M, failed F in S s`,
/// what another run computed meanwhile appended, so scripts that read the line's start, such as
/// scripts/slurm/test.sh, still can), or nothing (`--quiet`). The engine's and program pipelines'.
pub(super) fn print_summary(v: &crate::json::RunSummary, json: bool, quiet: bool) -> anyhow::Result<()> {
    if json {
        println!("{}", serde_json::to_string(v)?);
    } else if !quiet {
        let elsewhere = match v.elsewhere {
            0 => String::new(),
            n => format!("; {n} computed meanwhile by another run on this cache"),
        };
        println!(
            "executed {}, cached {}, failed {} in {:.1} s{elsewhere}",
            v.executed, v.cached, v.failed, v.seconds
        );
    }
    Ok(())
}

/// This run's leases on the cache, released at once by Ctrl-C / SIGTERM.
pub(super) fn leases(
    store: &qsweep_pipeline::cache::Store,
) -> anyhow::Result<std::sync::Arc<qsweep_pipeline::cache::leases::Leases>> {
    let dir = store.dir().join(qsweep_pipeline::cache::leases::LEASES_DIR);
    let leases = qsweep_pipeline::cache::leases::Leases::open(store)
        .map_err(|e| super::pipeline_args::unwritable(&dir, &e))?;
    qsweep_pipeline::cache::leases::register(&leases);
    Ok(leases)
}

/// Ctrl-C or SIGTERM stops the run: finished trials are stored, and the running ones are let
/// finish (`running`: what happens to them, as the message says).
pub(super) fn install_ctrlc(running: &'static str) {
    // A second Ctrl-C exits at once; finished trials are already in renamed segments.
    let _ = ctrlc::set_handler(move || {
        // Other runs on the cache may take this run's unfinished trials now.
        qsweep_pipeline::cache::leases::release_registered();
        if INTERRUPTED.swap(true, Ordering::SeqCst) {
            std::process::exit(i32::from(qsweep_pipeline::error::exit::INTERRUPTED));
        }
        eprintln!("\ninterrupted (Ctrl-C or SIGTERM): storing finished trials, {running}; press Ctrl-C again to stop now");
    });
}
