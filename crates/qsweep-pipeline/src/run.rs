//! The pipeline as the library runs it, the same for every command: scan the cache's keys (and
//! move damaged segments aside, [`scan`]), choose the trials to run ([`select`]: shard, cached,
//! `--force`), execute and store them ([`run_trials`]); the report stage is [`qsweep_report::write`].
//! A staged plan (a race, [`crate::race`], or fresh seeds, [`crate::fresh`]) is replayed against
//! the cache first ([`crate::race::replay`]), and [`run_trials`] runs its stages one after
//! another (one stage per call under `--shard`).

use crate::cache::store::{Damaged, KeySet, Store};
use crate::cache::Key;
use crate::exec::shard::{assign, key_owner, Shard};
use crate::exec::{execute, ExecOptions, ExecReport, Job};
use crate::plan::Plan;
use crate::race::{read_cached, replay, Replayed, Unreplay};
use std::path::PathBuf;

/// The cache's keys, after every damaged segment was moved to the quarantine folder.
#[derive(Debug, Default)]
pub struct Scan {
    /// The readable segments' keys.
    pub stored: KeySet,
    /// Each damaged segment and where it went.
    pub quarantined: Vec<(Damaged, PathBuf)>,
}

/// Scan the cache's keys; a segment that cannot be read is never served or kept being read: it
/// moves to `_quarantine/` and its trials count as missing (so `run` recomputes them).
pub fn scan(store: &Store) -> anyhow::Result<Scan> {
    let stored = store.keys()?;
    let mut quarantined = Vec::new();
    for d in &stored.damaged {
        let to = store.quarantine(&d.path)?;
        quarantined.push((d.clone(), to));
    }
    Ok(Scan { stored, quarantined })
}

/// What to run of a plan.
#[derive(Debug, Clone, Copy, Default)]
pub struct Selection {
    /// Only this shard of the plan's distinct trials.
    pub shard: Option<Shard>,
    /// Run cached trials again.
    pub force: bool,
}

/// The shard (1..=count) that owns each of `trials`, the distinct trials of `plan` or, for a race,
/// of one of its rounds. A race's trials are owned by key alone ([`key_owner`]): its plan grows
/// as rounds are decided, so a split of the whole plan would move trials between tasks started at
/// different times. Any other plan is split cost-balanced over all its trials ([`assign`]), which
/// does not depend on what the cache holds either.
pub fn shard_owners(plan: &Plan, trials: &[Job], count: u32) -> Vec<u32> {
    if plan.has_race() {
        trials.iter().map(|t| key_owner(&t.key, count)).collect()
    } else if plan.has_fresh() {
        // The grid is split cost-balanced as planned (it does not depend on the cache); the fresh
        // trials, planned once the grid is stored, by key.
        let grid = crate::exec::jobs(plan);
        let owner: std::collections::HashMap<Key, u32> =
            grid.iter().map(|t| t.key).zip(assign(&grid, count)).collect();
        trials
            .iter()
            .map(|t| owner.get(&t.key).copied().unwrap_or_else(|| key_owner(&t.key, count)))
            .collect()
    } else {
        assign(trials, count)
    }
}

/// `trials` (of `plan`, see [`shard_owners`]) that `shard` owns; all of them without a shard.
fn in_shard<'p>(plan: &Plan, trials: Vec<Job<'p>>, shard: Option<Shard>) -> Vec<Job<'p>> {
    let Some(shard) = shard else { return trials };
    let owners = shard_owners(plan, &trials, shard.count);
    trials.into_iter().zip(owners).filter(|&(_, s)| s == shard.index).map(|(t, _)| t).collect()
}

/// The plan's distinct trials that `sel` keeps (its shard), and of those the ones to run.
pub fn select<'p>(plan: &'p Plan, scan: &KeySet, sel: Selection) -> (Vec<Job<'p>>, Vec<Job<'p>>) {
    let unique = in_shard(plan, crate::exec::jobs(plan), sel.shard);
    let jobs = unique.iter().filter(|t| sel.force || !scan.keys.contains(&t.key)).copied().collect();
    (unique, jobs)
}

/// What [`run_trials`] did.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct RunSummary {
    /// The execution's counts.
    pub exec: ExecReport,
    /// Distinct trials of the selection already cached (not run).
    pub cached: usize,
}

/// Run the selected missing trials of `plan` and store them in batches. A raced plan runs round
/// after round, each planned from the outcomes of the rounds before, until its races are over;
/// under a shard, only the shard's own trials (by key, [`key_owner`]) of the rounds the cache lets
/// it plan, then it stops (the other shards' parts must be stored before the next round can be
/// planned).
pub fn run_trials(
    plan: &Plan,
    store: &Store,
    scan: &KeySet,
    sel: Selection,
    opts: &ExecOptions,
    reporter: &mut dyn crate::exec::Reporter,
) -> anyhow::Result<RunSummary> {
    Ok(run_trials_replayed(plan.clone(), store, scan, sel, opts, reporter)?.0)
}

/// The plan after [`run_trials_replayed`].
#[derive(Debug)]
pub enum AfterRun {
    /// A staged plan of which nothing ran (its first round found every trial cached), as it
    /// was replayed against the caller's scan: exactly what a report of that scan would replay.
    Replayed(Replayed),
    /// The plan as planned: it has no stages (its report reads it as it is), or something ran
    /// (the cache changed since the caller's scan).
    Planned(Plan),
}

/// [`run_trials`] of a plan the caller gives up, and the plan back ([`AfterRun`]): `qsweep run`
/// hands a replayed plan on to its report instead of replaying it a second time. Each round
/// replays the plan in place and takes the replay back when another round follows, so no second
/// copy of its cells is made (under a shard, whose owners are decided on the plan as planned, a
/// copy is replayed).
pub fn run_trials_replayed(
    plan: Plan,
    store: &Store,
    scan: &KeySet,
    sel: Selection,
    opts: &ExecOptions,
    reporter: &mut dyn crate::exec::Reporter,
) -> anyhow::Result<(RunSummary, AfterRun)> {
    // A run on a shared cache names its segments after its mark, so `gc` leaves them alone.
    let ours = opts.leases.as_ref().map(|l| store.clone().writing_as(l.run_mark()));
    let writer = ours.as_ref().unwrap_or(store);
    let flush = |batch: &[crate::cache::TrialRecord]| {
        writer.write_segment(batch)?;
        Ok(())
    };
    if !plan.is_staged() {
        let (unique, jobs) = select(&plan, scan, sel);
        if let Some(c) = &opts.leases {
            c.reset_view(scan, sel.force);
        }
        let exec = execute(&jobs, opts, flush, reporter)?;
        let done = RunSummary { exec, cached: unique.len() - jobs.len() };
        drop((jobs, unique));
        return Ok((done, AfterRun::Planned(plan)));
    }
    let mut total = ExecReport::default();
    let mut rescanned;
    let mut scan = scan;
    // `--force` recomputes each trial once, not once per round.
    let mut forced: std::collections::HashSet<crate::cache::Key> = std::collections::HashSet::new();
    // Whether this round replays against the caller's `scan` (nothing run yet).
    let mut first = true;
    let mut plan = plan;
    loop {
        // Replayed in place, but under a shard: this round's trials are the shard's, whose owners
        // are decided on the plan as planned (by key: see shard_owners), kept beside a copy.
        let copy = sel.shard.is_some();
        let (replayed, back) = Unreplay::replay(plan, copy, &scan.keys, &mut read_cached(store, scan))?;
        let round = crate::exec::jobs(replayed.plan());
        let unique = match back.planned() {
            Some(planned) => in_shard(planned, round, sel.shard),
            None => round,
        };
        let jobs: Vec<Job> = if sel.force {
            unique.iter().filter(|t| forced.insert(t.key)).copied().collect()
        } else {
            unique.iter().filter(|t| !scan.keys.contains(&t.key)).copied().collect()
        };
        if jobs.is_empty() {
            let done = RunSummary { cached: unique.len() - total.executed.min(unique.len()), exec: total };
            drop((jobs, unique));
            let after =
                if first { AfterRun::Replayed(replayed) } else { AfterRun::Planned(back.undo(replayed)) };
            return Ok((done, after));
        }
        if let Some(c) = &opts.leases {
            c.reset_view(scan, sel.force);
        }
        let exec = execute(&jobs, opts, flush, reporter)?;
        let cached = unique.len() - jobs.len();
        drop((jobs, unique));
        total.executed += exec.executed;
        total.elsewhere += exec.elsewhere;
        total.failed += exec.failed;
        total.interrupted |= exec.interrupted;
        plan = back.undo(replayed);
        if exec.interrupted || sel.shard.is_some() {
            return Ok((RunSummary { cached, exec: total }, AfterRun::Planned(plan)));
        }
        rescanned = store.keys()?;
        scan = &rescanned;
        first = false;
    }
}

/// Every key the given plans reference (what `qsweep gc PIPELINES` keeps): all their trials,
/// and for a race every round it has run and for fresh seeds the best cells' fresh trials,
/// replayed from the cache (they are planned from the outcomes stored).
pub fn referenced_keys(plans: &[Plan], store: &Store) -> anyhow::Result<std::collections::HashSet<Key>> {
    let mut keep = std::collections::HashSet::new();
    let mut scan = None;
    for planned in plans {
        if planned.is_staged() {
            if scan.is_none() {
                scan = Some(store.keys()?);
            }
            let scan = scan.as_ref().expect("scanned just above");
            let replayed = replay(planned, &scan.keys, &mut read_cached(store, scan))?;
            keep.extend(replayed.plan().trials().map(|(_, _, t)| t.key));
        } else {
            keep.extend(planned.trials().map(|(_, _, t)| t.key));
        }
    }
    Ok(keep)
}

/// One shard's share of a plan's distinct trials (what `qsweep slurm` prints per task).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct ShardCount {
    /// Distinct trials the shard owns.
    pub trials: usize,
    /// Of those, not in `cached`.
    pub missing: usize,
}

/// Per shard 1..=`shards` (index 0 is shard 1), its trials of `unique` and how many are missing.
pub fn shard_counts(
    plan: &Plan,
    unique: &[Job<'_>],
    cached: &std::collections::HashSet<Key>,
    shards: u32,
) -> Vec<ShardCount> {
    let mut per_shard = vec![ShardCount::default(); shards as usize];
    for (t, s) in unique.iter().zip(shard_owners(plan, unique, shards)) {
        let c = &mut per_shard[s as usize - 1];
        c.trials += 1;
        c.missing += usize::from(!cached.contains(&t.key));
    }
    per_shard
}
