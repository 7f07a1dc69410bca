//! The pipeline as the library runs it, the same for every command: scan the cache's keys (and
//! move damaged segments aside, [`scan`]), choose the trials to run ([`select`]: shard, cached,
//! `--force`), execute and store them ([`run`]); the report stage is [`crate::report::write`].

use crate::cache::store::{Damaged, KeyScan, Store};
use crate::exec::shard::{shard_keys, Shard};
use crate::exec::{execute, ExecOptions, ExecReport, Job};
use crate::plan::Plan;
use std::path::PathBuf;

/// The cache's keys, after every damaged segment was moved to the quarantine folder.
#[derive(Debug, Default)]
pub struct Scan {
    /// The readable segments' keys.
    pub keys: KeyScan,
    /// Each damaged segment and where it went.
    pub quarantined: Vec<(Damaged, PathBuf)>,
}

/// Scan the cache's keys; a segment that cannot be read is never served or kept being read: it
/// moves to `_quarantine/` and its trials count as missing (so `run` recomputes them).
pub fn scan(store: &Store) -> anyhow::Result<Scan> {
    let keys = store.keys()?;
    let mut quarantined = Vec::new();
    for d in &keys.damaged {
        let to = store.quarantine(&d.path)?;
        quarantined.push((d.clone(), to));
    }
    Ok(Scan { keys, quarantined })
}

/// What to run of a plan.
#[derive(Debug, Clone, Copy, Default)]
pub struct Selection {
    /// Only this shard of the plan's distinct trials.
    pub shard: Option<Shard>,
    /// Run cached trials again.
    pub force: bool,
}

/// The plan's distinct trials that `sel` keeps (its shard), and of those the ones to run.
pub fn select<'p>(plan: &'p Plan, scan: &KeyScan, sel: Selection) -> (Vec<Job<'p>>, Vec<Job<'p>>) {
    let unique = plan.unique_trials();
    let unique = match sel.shard {
        Some(shard) => {
            let mine = shard_keys(&unique, shard);
            unique.into_iter().filter(|t| mine.contains(&t.key)).collect()
        }
        None => unique,
    };
    let jobs = unique.iter().filter(|t| sel.force || !scan.keys.contains(&t.key)).copied().collect();
    (unique, jobs)
}

/// What [`run`] did.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct RunOutcome {
    /// The execution's counts.
    pub exec: ExecReport,
    /// Distinct trials of the selection already cached (not run).
    pub cached: usize,
}

/// Run the selected missing trials of `plan` and store them in batches.
pub fn run(
    plan: &Plan,
    store: &Store,
    scan: &KeyScan,
    sel: Selection,
    opts: &ExecOptions,
) -> anyhow::Result<RunOutcome> {
    let (unique, jobs) = select(plan, scan, sel);
    let exec = execute(&jobs, opts, |batch| {
        store.write_segment(batch)?;
        Ok(())
    })?;
    Ok(RunOutcome { exec, cached: unique.len() - jobs.len() })
}
