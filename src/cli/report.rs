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

/// Refuse (an error, exit 1) when `target` holds a report of more distinct trials than `present`.
fn refuse_smaller(target: &Path, present: usize, store: &Store, planned: usize) -> anyhow::Result<()> {
    let existing = crate::report::existing_trials(target).map_err(|e| {
        e.context(format!(
            "{} holds a report whose size cannot be read; replace it with --force",
            target.display()
        ))
    })?;
    if let Some(old) = existing {
        anyhow::ensure!(
            present >= old,
            "{} holds a report of {old} distinct trials, but the cache ({}) has only {present} of this \
             pipeline's {planned} distinct trials now; not replacing it with a smaller report. Run the \
             missing trials first (`qsweep run`), write elsewhere with --out DIR, or replace it \
             anyway with `qsweep report ... --force`",
            target.display(),
            store.dir().display(),
        );
    }
    Ok(())
}

/// Write the report of `plan` from the cached trials. Unless `force`, refuse (an error, exit 1)
/// when the directory already holds a report of more distinct trials than the cache has now.
pub fn write(plan: &Plan, store: &Store, out: Option<&Path>, quiet: bool, force: bool) -> anyhow::Result<()> {
    let keys: HashSet<_> = plan.trials().map(|(_, _, t)| t.key).collect();
    let records: HashMap<_, _> = store.read(&keys)?.into_iter().map(|r| (r.key, r)).collect();
    let dir = out.map(Path::to_path_buf).unwrap_or_else(|| Path::new("reports").join(&plan.name));
    if !force {
        // A report of some variants replaces only their folders; any other report, the whole directory.
        let targets: Vec<(PathBuf, usize)> = if plan.variant_subset {
            plan.variants
                .iter()
                .map(|v| {
                    let mine: HashSet<_> = plan
                        .trials()
                        .filter(|(e, _, _)| e.variant.as_deref() == Some(v.id.as_str()))
                        .map(|(_, _, t)| t.key)
                        .filter(|k| records.contains_key(k))
                        .collect();
                    (dir.join(&v.id), mine.len())
                })
                .collect()
        } else {
            vec![(dir.clone(), records.len())]
        };
        for (target, present) in targets {
            refuse_smaller(&target, present, store, keys.len())?;
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
