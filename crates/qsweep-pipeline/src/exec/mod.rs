//! Executing trials: a rayon pool pulls trials longest-first from a shared counter (so the tail
//! is short), the calling thread collects finished trials and hands them to a sink in batches
//! bounded by count and by time (so an interrupted run keeps them), and reports [`Event`]s to the
//! caller's [`Reporter`].
//!
//! With leases ([`ExecOptions::leases`]) a run that shares its cache with others leases its trials,
//! a few at a time, before running them, sets aside those another run is computing, and waits for
//! them at the end ([`leased`]).
//!
//! Results never depend on the number of threads: each trial is a pure function of its config and
//! seed, and batches are written in completion order, which only affects segment layout.

mod collect;
mod events;
mod job;
pub mod leased;
mod ledger;
mod options;
pub mod shard;

pub use collect::Finished;
pub(crate) use collect::{finish, Collector};
pub use events::{Event, Reporter};
pub use options::{ExecOptions, ExecReport, INTERRUPTED};

use crate::cache::TrialRecord;
pub use job::{jobs, Job};
use leased::{Pick, Scheduler, POLL};
use ledger::Ledger;
use qsweep_engine::repr::ReprKind;
use qsweep_engine::{lanes, run_trial, TrialConfig};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc;
use std::time::Instant;

/// CPU seconds the calling thread has used so far (`CLOCK_THREAD_CPUTIME_ID`): what a trial costs,
/// whatever else the machine is doing. `None` where the clock is not available.
pub fn thread_cpu_seconds() -> Option<f64> {
    #[cfg(unix)]
    {
        let mut ts = libc::timespec { tv_sec: 0, tv_nsec: 0 };
        // SAFETY: clock_gettime only writes the timespec it is given.
        let rc = unsafe { libc::clock_gettime(libc::CLOCK_THREAD_CPUTIME_ID, &mut ts) };
        (rc == 0).then_some(ts.tv_sec as f64 + ts.tv_nsec as f64 * 1e-9)
    }
    #[cfg(not(unix))]
    {
        None
    }
}

/// The order in which [`execute`] hands out `jobs`: those that run alone first, then those of each
/// lockstep group ([`lanes::group`]) together, so that its loops stay full (crisp trials, short
/// next to fuzzy ones, came last anyway); each longest first ([`estimated_cost`]), ties in plan
/// order, so scheduling is reproducible.
fn schedule(jobs: &[Job<'_>]) -> Vec<usize> {
    let keys: Vec<_> = jobs.iter().map(|j| (lanes::group(j.config), estimated_cost(j.config))).collect();
    let mut order: Vec<usize> = (0..jobs.len()).collect();
    order.sort_by(|&a, &b| keys[a].0.cmp(&keys[b].0).then_with(|| keys[b].1.total_cmp(&keys[a].1)));
    order
}

/// One worker: runs the jobs `sched` hands it until none is left, the run stops, or the
/// collector hangs up. With `lockstep`, crisp trials (and dense fuzzy ones) run several as lanes of one loop
/// ([`lanes::run_lockstep`]); the rows are the same either way.
fn work(
    jobs: &[Job<'_>],
    sched: &Scheduler<'_>,
    stop: &AtomicBool,
    lockstep: bool,
    tx: &mpsc::Sender<TrialRecord>,
) {
    let halted = || stop.load(Ordering::Relaxed) || INTERRUPTED.load(Ordering::Relaxed);
    // A job picked while filling lanes that does not fit them: it runs next.
    let mut stash = None;
    loop {
        if halted() {
            break;
        }
        let j = match stash.take() {
            Some(j) => j,
            None => match sched.pick() {
                Pick::Run(j) => j,
                Pick::Wait => {
                    std::thread::sleep(POLL);
                    continue;
                }
                Pick::Done => break,
            },
        };
        let sent = if lockstep && lanes::benefits(jobs[j].config) {
            in_lockstep(jobs, sched, j, &mut stash, &halted, tx)
        } else {
            alone(jobs[j], tx)
        };
        if !sent {
            break;
        }
    }
}

/// Run `job` alone and send its record; false once the collector has hung up.
fn alone(job: Job<'_>, tx: &mpsc::Sender<TrialRecord>) -> bool {
    let start = Instant::now();
    let cpu = thread_cpu_seconds();
    let outcome = run_trial(job.config, job.seed);
    let cpu = thread_cpu_seconds().zip(cpu).map(|(b, a)| b - a);
    let rec = TrialRecord::new(job.config.clone(), job.seed, outcome, start.elapsed().as_secs_f64())
        .with_cpu_seconds(cpu);
    debug_assert_eq!(rec.key, job.key);
    tx.send(rec).is_ok()
}

/// Run job `first` and the jobs `sched` hands out after it in one lockstep loop, as long as they
/// fit it (the same [`lanes::group`]); the first that does not is left in `stash`. A trial's
/// seconds and CPU seconds are its equal shares of the loop's while it was in it ([`Ledger`]).
/// False once the collector has hung up.
fn in_lockstep(
    jobs: &[Job<'_>],
    sched: &Scheduler<'_>,
    first: usize,
    stash: &mut Option<usize>,
    halted: &dyn Fn() -> bool,
    tx: &mpsc::Sender<TrialRecord>,
) -> bool {
    let (system, group) = (jobs[first].config.system(), lanes::group(jobs[first].config));
    let fits = |j: usize| lanes::group(jobs[j].config) == group;
    let mut first = Some(first);
    let open = std::cell::Cell::new(true);
    let start = Instant::now();
    let clock = || (thread_cpu_seconds(), start.elapsed().as_secs_f64());
    let ledger = {
        let (cpu, wall) = clock();
        std::cell::RefCell::new(Ledger::new(cpu, wall))
    };
    let next = || {
        let j = match first.take() {
            Some(j) => j,
            None if !open.get() || halted() || stash.is_some() => return None,
            None => match sched.pick() {
                Pick::Run(j) if fits(j) => j,
                Pick::Run(j) => {
                    *stash = Some(j);
                    return None;
                }
                Pick::Wait | Pick::Done => return None,
            },
        };
        let (cpu, wall) = clock();
        ledger.borrow_mut().join(j, cpu, wall);
        Some((j, jobs[j].config, jobs[j].seed))
    };
    let done = |j: usize, outcome: qsweep_engine::Outcome| {
        let job = jobs[j];
        let (cpu, wall) = clock();
        let (cpu, seconds) = ledger.borrow_mut().leave(j, cpu, wall);
        let rec = TrialRecord::new(job.config.clone(), job.seed, outcome, seconds).with_cpu_seconds(cpu);
        debug_assert_eq!(rec.key, job.key);
        if tx.send(rec).is_err() {
            open.set(false);
        }
    };
    lanes::run_lockstep(system, next, done);
    open.get()
}

/// A rough relative cost of a trial, used only to start long trials first.
pub fn estimated_cost(c: &TrialConfig) -> f64 {
    let per_step = match c.repr.kind {
        ReprKind::Crisp => 1.0 + 0.05 * f64::from(c.actions),
        // Active rules per step: about min(n, 5) sets per variable survive pruning.
        ReprKind::Fuzzy => {
            c.repr.resolution.iter().map(|&n| f64::from(n.min(5))).product::<f64>() * f64::from(c.actions)
        }
    };
    per_step * (c.limits.max_total_steps as f64).min(c.limits.episode_cap() as f64 * 10.0)
}

/// Run `jobs` and hand finished records to `sink` in batches; stops early (after flushing) when
/// [`INTERRUPTED`] is set. With leases, a job another run holds is left to it and waited for, and
/// each lease is released once its trial is handed to the sink. A sink error stops the run and is
/// returned; records already handed to the sink are kept. Every step is reported to `reporter`.
pub fn execute(
    jobs: &[Job<'_>],
    opts: &ExecOptions,
    sink: impl FnMut(&[TrialRecord]) -> anyhow::Result<()>,
    reporter: &mut dyn Reporter,
) -> anyhow::Result<ExecReport> {
    let order = schedule(jobs);
    let threads = opts.jobs.max(1);
    let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build()?;
    let leases = opts.leases.as_deref();
    let sched = Scheduler::new(jobs.iter().map(|j| j.key).collect(), order, threads, leases);
    let stop = AtomicBool::new(false);
    let lockstep = opts.lockstep;
    let (tx, rx) = mpsc::channel::<TrialRecord>();
    let mut collector = Collector::new(sink, leases);
    reporter.event(&Event::Started { trials: jobs.len() });

    let collected = std::thread::scope(|scope| -> anyhow::Result<()> {
        let (sched, stop) = (&sched, &stop);
        scope.spawn(move || {
            pool.scope(|s| {
                for _ in 0..threads {
                    let tx = tx.clone();
                    s.spawn(move |_| work(jobs, sched, stop, lockstep, &tx));
                }
            });
        });
        collector.collect(&rx, opts, sched, stop, reporter)
    });
    let report = finish(collector.report, jobs.len(), &sched, leases, reporter);
    collected?;
    Ok(report)
}

#[cfg(test)]
mod tests;
