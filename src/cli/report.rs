//! `qsweep report`: read the pipeline's trials from the cache and write tables, figures and data.
//!
//! It never replaces a report with one of fewer trials (a fresh clone's empty cache would otherwise
//! overwrite the committed report) unless told to with `--force`, and never creates the cache.

use super::pipeline_args::{require_cache, PipelineArgs};
use crate::cache::store::Store;
use crate::error::exit;
use crate::plan::Plan;
use clap::Args;
use std::collections::{HashMap, HashSet};
use std::path::{Path, PathBuf};

/// Arguments of `qsweep report`.
#[derive(Debug, Args)]
pub struct ReportArgs {
    #[command(flatten)]
    pub pipeline: PipelineArgs,
    /// Report directory [default: reports/<pipeline name>].
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// Replace the report in the report directory even if it holds more trials than the cache
    /// has for this pipeline now (without it, that exits 1 and writes nothing).
    #[arg(long)]
    pub force: bool,
    /// Print nothing but errors.
    #[arg(long, short = 'q')]
    pub quiet: bool,
}

/// Run `qsweep report`.
pub fn run(a: ReportArgs) -> anyhow::Result<u8> {
    let plan = a.pipeline.plan()?;
    require_cache(&a.pipeline.cache_dir())?;
    let store = a.pipeline.store()?;
    write(&plan, &store, a.out.as_deref(), a.quiet, a.force)?;
    Ok(exit::OK)
}

/// Write the report of `plan` from the cached trials. Unless `force`, refuse (an error, exit 1)
/// when the directory already holds a report of more distinct trials than the cache has now.
pub fn write(plan: &Plan, store: &Store, out: Option<&Path>, quiet: bool, force: bool) -> anyhow::Result<()> {
    let keys: HashSet<_> = plan.trials().map(|(_, _, t)| t.key).collect();
    let records: HashMap<_, _> = store.read(&keys)?.into_iter().map(|r| (r.key, r)).collect();
    let dir = out.map(Path::to_path_buf).unwrap_or_else(|| Path::new("reports").join(&plan.name));
    if !force {
        let existing = crate::report::existing_trials(&dir).map_err(|e| {
            e.context(format!(
                "{} holds a report whose size cannot be read; replace it with --force",
                dir.display()
            ))
        })?;
        if let Some(old) = existing {
            anyhow::ensure!(
                records.len() >= old,
                "{} holds a report of {old} distinct trials, but the cache ({}) has only {} of this \
                 pipeline's {} distinct trials now; not replacing it with a smaller report. Run the \
                 missing trials first (`qsweep run`), write elsewhere with --out DIR, or replace it \
                 anyway with `qsweep report ... --force`",
                dir.display(),
                store.dir().display(),
                records.len(),
                keys.len()
            );
        }
    }
    let s = crate::report::write_reports(plan, &records, &dir)?;
    if !quiet {
        println!(
            "report: {} ({} of {} planned trials present, {} of {} cells)",
            dir.join("index.html").display(),
            s.trials_present,
            s.trials_planned,
            s.cells_with_trials,
            s.cells
        );
    }
    Ok(())
}
