//! One run of a program pipeline: its schema's store folder opened, the trials the cache lacks
//! (of the selected shard) chosen, run under leases with a runner per worker thread in the
//! pipeline's protocol, and stored as typed rows. What `qsweep run` calls for a `program:`
//! pipeline; the engine's counterpart is [`crate::run`].

use super::exec::{execute, jobs, ProgramExecReport, ProgramJob, Ran, RunTrial};
use super::key::{params_object, Identity};
use super::model::{Program, ProgramPlan, ProgramRow, Protocol, TrialResult};
use super::rows::{folder, write_segment, RowSchema};
use super::runner::{run_process, RunnerOptions, TrialEnv};
use super::stored::failed_keys;
use super::worker::Worker;
use crate::cache::store::{KeySet, Store};
use crate::cache::Key;
use crate::exec::shard::{key_owner, Shard};
use crate::exec::{ExecOptions, Reporter};
use std::collections::HashSet;
use std::path::Path;

/// The typed columns of `plan`'s rows.
pub fn schema(plan: &ProgramPlan) -> RowSchema {
    RowSchema { params: plan.params.clone(), metrics: plan.program.metrics.clone() }
}

/// The store folder of `plan`'s rows in the cache at `cache` (created if needed).
pub fn store(cache: &Path, plan: &ProgramPlan) -> std::io::Result<Store> {
    Store::open(&folder(cache, &schema(plan)))
}

/// Which trials a run takes.
#[derive(Debug, Clone, Copy, Default)]
pub struct Selection {
    /// Only this shard of the plan's distinct trials (by key, as the engine's shards).
    pub shard: Option<Shard>,
    /// Run every trial again, even those already stored.
    pub force: bool,
    /// Run again the trials stored as failed.
    pub retry_failed: bool,
}

/// The plan's distinct trials in the shard of `sel`, and of those the ones to run: those the cache
/// lacks, those stored as failed with `retry_failed`, every one with `force`.
pub fn select<'p>(
    plan: &'p ProgramPlan,
    scan: &KeySet,
    failed: &HashSet<Key>,
    sel: Selection,
) -> (Vec<ProgramJob<'p>>, Vec<ProgramJob<'p>>) {
    let all: Vec<ProgramJob> = jobs(plan)
        .into_iter()
        .filter(|j| sel.shard.is_none_or(|s| key_owner(&j.key, s.count) == s.index))
        .collect();
    let run = all
        .iter()
        .filter(|j| sel.force || !scan.keys.contains(&j.key) || (sel.retry_failed && failed.contains(&j.key)))
        .copied()
        .collect();
    (all, run)
}

/// `scan` as the leases are to see it: its segments, and its keys but those of `failed` when they
/// run again.
fn rerun_view(scan: &KeySet, failed: &HashSet<Key>, retry_failed: bool) -> KeySet {
    KeySet {
        keys: scan.keys.iter().filter(|k| !(retry_failed && failed.contains(k))).copied().collect(),
        damaged: scan.damaged.clone(),
        // Only the paths count (their keys are those above).
        segments: scan.segments.iter().map(|(p, _)| (p.clone(), Vec::new())).collect(),
    }
}

/// The runner of one worker thread, in the program's protocol.
enum Runner<'p> {
    /// A process per trial.
    Process { program: &'p Program, plan: &'p ProgramPlan, opts: RunnerOptions },
    /// One worker process, kept between trials.
    Worker { worker: Box<Worker>, plan: &'p ProgramPlan },
}

impl RunTrial for Runner<'_> {
    fn run(&mut self, job: &ProgramJob<'_>) -> Ran {
        let (result, timing) = match self {
            Runner::Process { program, plan, opts } => {
                let json = serde_json::Value::Object(params_object(&plan.params, job.params));
                run_process(program, &json, TrialEnv { seed: job.seed, key: job.key }, opts)
            }
            Runner::Worker { worker, plan } => {
                let json = serde_json::Value::Object(params_object(&plan.params, job.params));
                worker.run(&json, job.seed)
            }
        };
        Ran { result, seconds: timing.seconds(), cpu_seconds: timing.cpu_seconds() }
    }
}

/// What [`run_trials`] did.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ProgramRunSummary {
    /// The execution's counts and the trials that did not finish.
    pub exec: ProgramExecReport,
    /// Distinct trials of the selection already stored (not run).
    pub cached: usize,
}

/// Run the selected trials of `plan` the cache lacks and store them in `store` (the plan's
/// schema folder, [`store`]), reporting to `reporter`. `runner` says how a program is run (its
/// supervisor, the interrupt flag).
pub fn run_trials(
    plan: &ProgramPlan,
    store: &Store,
    scan: &KeySet,
    sel: Selection,
    opts: &ExecOptions,
    runner: &RunnerOptions,
    reporter: &mut dyn Reporter,
) -> anyhow::Result<ProgramRunSummary> {
    let schema = schema(plan);
    let wanted: HashSet<Key> = jobs(plan).iter().map(|j| j.key).collect();
    let failed = if sel.retry_failed { failed_keys(scan, &schema, &wanted)? } else { HashSet::new() };
    let (all, todo) = select(plan, scan, &failed, sel);
    let cached = all.len() - todo.len();
    if let Some(leases) = &opts.leases {
        // The leases judge a trial stored against this scan: a trial chosen to run again
        // (`--force`, `--retry-failed`) is not, or it would be taken as another run's.
        leases.reset_view(&rerun_view(scan, &failed, sel.retry_failed), sel.force);
    }
    // A run on a shared cache names its segments after its mark, so `gc` leaves them alone.
    let ours = opts.leases.as_ref().map(|l| store.clone().writing_as(l.run_mark()));
    let writer = ours.as_ref().unwrap_or(store);
    let identity = Identity::of(&plan.program);
    let make = |slot: usize| match plan.program.protocol {
        Protocol::Process => Runner::Process { program: &plan.program, plan, opts: runner.clone() },
        Protocol::Worker => {
            Runner::Worker { worker: Box::new(Worker::new(&plan.program, slot, runner.clone())), plan }
        }
    };
    let row = |job: &ProgramJob<'_>, ran: Ran| ProgramRow {
        key: job.key,
        seed: job.seed,
        params: job.params.to_vec(),
        result: match ran.result {
            TrialResult::Ok(m) => Ok(m),
            TrialResult::Failed(f) => Err(f),
            TrialResult::Unfinished(_) => unreachable!("an unfinished trial is never stored"),
        },
        seconds: ran.seconds,
        cpu_seconds: ran.cpu_seconds,
        command_json: identity.command_json.clone(),
        inputs_json: identity.inputs_json.clone(),
        provenance_json: identity.provenance_json.clone(),
    };
    let sink = |rows: &[ProgramRow]| write_segment(writer, &schema, rows).map(|_| ());
    let exec = execute(&todo, opts, make, row, sink, reporter)?;
    Ok(ProgramRunSummary { exec, cached })
}

/// Per shard 1..=`shards` (index 0 is shard 1), its distinct trials of `plan` and how many of
/// them are not in `cached`: the split `run --shard I/N` makes (by key, `key_owner`), for
/// `qsweep slurm`'s summary.
pub fn shard_counts(plan: &ProgramPlan, cached: &HashSet<Key>, shards: u32) -> Vec<crate::run::ShardCount> {
    let mut per_shard = vec![crate::run::ShardCount::default(); shards.max(1) as usize];
    for j in jobs(plan) {
        let c = &mut per_shard[key_owner(&j.key, shards.max(1)) as usize - 1];
        c.trials += 1;
        c.missing += usize::from(!cached.contains(&j.key));
    }
    per_shard
}

/// What [`run_stages`] did: the runs' counts together, and the plan as the last replay left it.
#[derive(Debug, Clone)]
pub struct StagedRun {
    /// Every stage's counts added up; `cached` is the trials of the final plan already stored
    /// before this run.
    pub summary: ProgramRunSummary,
    /// The plan replayed against the cache after the last stage that ran.
    pub replayed: super::race::ProgramReplayed,
}

/// Run `plan` stage by stage: replay it against the cache (`super::race`), run the trials the
/// replay plans that the cache lacks, and again, until a stage runs nothing new (a finished race
/// and its fresh seeds: a rerun runs nothing), a trial does not finish or the run is interrupted.
/// A plan without stages runs once, as [`run_trials`]; a shard (`sel.shard`) runs the trials it
/// owns of the stages the cache lets it plan now, then stops (the next round needs every shard's
/// outcomes). `--force` and `--retry-failed` apply to the first stage; the rounds after it are
/// new trials.
pub fn run_stages(
    plan: &ProgramPlan,
    store: &Store,
    mut sel: Selection,
    opts: &ExecOptions,
    runner: &RunnerOptions,
    reporter: &mut dyn Reporter,
) -> anyhow::Result<StagedRun> {
    let mut total = ProgramRunSummary::default();
    let mut executed_before = 0;
    loop {
        let scan = store.keys()?;
        let mut read = super::race::read_store(Some(store), &scan, plan);
        let replayed = super::race::replay(plan.clone(), &mut read)?;
        let done = run_trials(&replayed.plan, store, &scan, sel, opts, runner, reporter)?;
        let e = &done.exec;
        total.exec.exec.executed += e.exec.executed;
        total.exec.exec.failed += e.exec.failed;
        total.exec.exec.elsewhere += e.exec.elsewhere;
        total.exec.exec.interrupted |= e.exec.interrupted;
        total.exec.unfinished.extend(e.unfinished.iter().cloned());
        // The trials stored before this stage include those earlier stages ran.
        total.cached = done.cached.saturating_sub(executed_before);
        executed_before += e.exec.executed + e.exec.elsewhere;
        let stop = !plan.has_stages()
            || sel.shard.is_some()
            || e.exec.executed + e.exec.elsewhere == 0
            || e.exec.interrupted
            || !e.unfinished.is_empty()
            || crate::exec::INTERRUPTED.load(std::sync::atomic::Ordering::Relaxed);
        if stop {
            let replayed = if plan.has_stages() && e.exec.executed + e.exec.elsewhere > 0 {
                super::race::replay_store(plan.clone(), Some(store))?
            } else {
                replayed
            };
            return Ok(StagedRun { summary: total, replayed });
        }
        sel.force = false;
        sel.retry_failed = false;
    }
}
