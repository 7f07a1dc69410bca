//! `qsweep report`: read the pipeline's trials from the cache and write tables, figures and data.

use super::pipeline_args::PipelineArgs;
use crate::cache::store::Store;
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
    /// Print nothing but errors.
    #[arg(long, short = 'q')]
    pub quiet: bool,
}

/// Run `qsweep report`.
pub fn run(a: ReportArgs) -> anyhow::Result<u8> {
    let plan = a.pipeline.plan()?;
    let store = a.pipeline.store()?;
    write(&plan, &store, a.out.as_deref(), a.quiet)?;
    Ok(0)
}

/// Write the report of `plan` from the cached trials.
pub fn write(plan: &Plan, store: &Store, out: Option<&Path>, quiet: bool) -> anyhow::Result<()> {
    let keys: HashSet<_> = plan.trials().map(|(_, _, t)| t.key).collect();
    let records: HashMap<_, _> = store.read(&keys)?.into_iter().map(|r| (r.key, r)).collect();
    let dir = out.map(Path::to_path_buf).unwrap_or_else(|| Path::new("reports").join(&plan.name));
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
