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

mod events;
mod job;
pub mod leased;
mod ledger;
pub mod shard;

pub use events::{Event, Reporter};

use crate::cache::leases::{lease::HEARTBEAT, Leases};
use crate::cache::TrialRecord;
pub use job::{jobs, Job};
use leased::{Pick, Scheduler, POLL};
use ledger::Ledger;
use qsweep_engine::repr::ReprKind;
use qsweep_engine::{lanes, run_trial, TrialConfig};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{mpsc, Arc};
use std::time::{Duration, Instant};

/// Set by the Ctrl-C / SIGTERM handler: workers start no new trials, the run flushes and stops.
pub static INTERRUPTED: AtomicBool = AtomicBool::new(false);

/// How to run.
#[derive(Debug, Clone)]
pub struct ExecOptions {
    /// Worker threads.
    pub jobs: usize,
    /// Flush after this many finished trials...
    pub batch_trials: usize,
    /// ...or after this long since the last flush, whichever comes first.
    pub batch_interval: Duration,
    /// Lease each trial in the cache before running it (in batches, [`leased::batch_len`]), so
    /// that concurrent runs on the cache never compute one twice (`None`: run every job, as a
    /// library user without a shared cache).
    pub leases: Option<Arc<Leases>>,
    /// Run crisp trials in lockstep, several as lanes of one loop ([`lanes::run_lockstep`]):
    /// faster, the same rows. Default: on unless `QSWEEP_LOCKSTEP=off`.
    pub lockstep: bool,
}

impl Default for ExecOptions {
    fn default() -> Self {
        Self {
            jobs: std::thread::available_parallelism().map_or(1, |n| n.get()),
            batch_trials: 500,
            batch_interval: Duration::from_secs(10),
            leases: None,
            lockstep: lanes::enabled(),
        }
    }
}

/// What an execution did.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ExecReport {
    /// Trials run and stored.
    pub executed: usize,
    /// Of those, trials whose simulation diverged (stored with a failure reason).
    pub failed: usize,
    /// Trials another run (sharing the cache) stored while this one ran: not run here.
    pub elsewhere: usize,
    /// Whether Ctrl-C stopped the run early.
    pub interrupted: bool,
}

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
/// collector hangs up. With `lockstep`, crisp trials run several as lanes of one loop
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
    mut sink: impl FnMut(&[TrialRecord]) -> anyhow::Result<()>,
    reporter: &mut dyn Reporter,
) -> anyhow::Result<ExecReport> {
    let order = schedule(jobs);
    let threads = opts.jobs.max(1);
    let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build()?;
    let leases = opts.leases.as_deref();
    let sched = Scheduler::new(jobs, order, threads, leases);
    let stop = AtomicBool::new(false);
    let lockstep = opts.lockstep;
    let (tx, rx) = mpsc::channel::<TrialRecord>();
    let mut report = ExecReport::default();
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

        let mut batch: Vec<TrialRecord> = Vec::new();
        let mut last_flush = Instant::now();
        let mut last_beat = Instant::now();
        let mut elsewhere = (0, 0);
        let mut flush = |batch: &mut Vec<TrialRecord>,
                         report: &mut ExecReport,
                         reporter: &mut dyn Reporter|
         -> anyhow::Result<()> {
            if !batch.is_empty() {
                sink(batch)?;
                if let Some(c) = leases {
                    c.release(&batch.iter().map(|r| r.key).collect::<Vec<_>>());
                }
                reporter.event(&Event::Flushed { trials: batch.len() });
                report.executed += batch.len();
                report.failed += batch.iter().filter(|r| r.outcome.failure.is_some()).count();
                batch.clear();
            }
            Ok(())
        };
        let result = loop {
            match rx.recv_timeout(Duration::from_millis(200)) {
                Ok(rec) => {
                    reporter.event(&Event::Finished { key: rec.key, failed: rec.outcome.failure.is_some() });
                    batch.push(rec);
                }
                Err(mpsc::RecvTimeoutError::Timeout) => reporter.event(&Event::Tick),
                Err(mpsc::RecvTimeoutError::Disconnected) => {
                    break flush(&mut batch, &mut report, &mut *reporter)
                }
            }
            if let Some(c) = leases {
                if last_beat.elapsed() >= HEARTBEAT {
                    c.heartbeat();
                    last_beat = Instant::now();
                }
                let now = (
                    sched.running_elsewhere.load(Ordering::Relaxed),
                    sched.stored_elsewhere.load(Ordering::Relaxed),
                );
                if now != elsewhere {
                    elsewhere = now;
                    reporter.event(&Event::Elsewhere { running: now.0, stored: now.1 });
                }
            }
            // On an interrupt (Ctrl-C, or SIGTERM from a scheduler's time limit, which sends
            // SIGKILL soon after) store what is finished at once rather than at the next batch.
            // So in the tail of a run that shares the cache: other runs may be waiting for
            // exactly these trials, which their leases keep from them until they are stored.
            if batch.len() >= opts.batch_trials
                || last_flush.elapsed() >= opts.batch_interval
                || INTERRUPTED.load(Ordering::Relaxed)
                || (!batch.is_empty() && sched.exhausted() && leases.is_some_and(|c| c.others_present()))
            {
                if let Err(e) = flush(&mut batch, &mut report, &mut *reporter) {
                    break Err(e);
                }
                last_flush = Instant::now();
            }
        };
        if result.is_err() {
            stop.store(true, Ordering::Relaxed);
            // Drain so workers are never blocked; their trials are lost, the stored ones are not.
            while rx.recv().is_ok() {}
        }
        result
    });
    // Nothing is held between executions: leases of trials a failing sink did not store go now.
    if let Some(c) = leases {
        c.release_all();
    }
    report.elsewhere = sched.stored_elsewhere.load(Ordering::Relaxed);
    report.interrupted =
        INTERRUPTED.load(Ordering::Relaxed) && report.executed + report.elsewhere < jobs.len();
    if report.interrupted {
        reporter.event(&Event::Interrupted);
    }
    reporter.event(&Event::Done { executed: report.executed, failed: report.failed });
    collected?;
    Ok(report)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cache::Key;
    use qsweep_engine::env::SystemKind;
    use qsweep_engine::Algorithm;

    fn jobs_for(configs: &[TrialConfig]) -> Vec<Job<'_>> {
        configs
            .iter()
            .flat_map(|c| (0..3).map(move |seed| Job { config: c, seed, key: Key::of(c, seed) }))
            .collect()
    }

    #[test]
    fn results_are_identical_on_one_or_two_threads_in_lockstep_or_alone_and_batches_cover_every_job() {
        let mut configs = Vec::new();
        for (sys, res) in [(SystemKind::BallBeam, vec![3, 3]), (SystemKind::MountainCar, vec![4, 4])] {
            for repr in [ReprKind::Crisp, ReprKind::Fuzzy] {
                let mut c = TrialConfig::paper(sys, repr, Algorithm::QLambda, res.clone(), 3);
                c.limits.max_episodes = 30;
                configs.push(c);
            }
        }
        let jobs = jobs_for(&configs);
        let run = |threads, lockstep| {
            let opts = ExecOptions { jobs: threads, batch_trials: 4, lockstep, ..Default::default() };
            let mut got = Vec::new();
            let mut batches = 0;
            let mut events: Vec<Event> = Vec::new();
            let r = execute(
                &jobs,
                &opts,
                |b| {
                    assert!(b.len() <= 4);
                    batches += 1;
                    got.extend(b.iter().cloned());
                    Ok(())
                },
                &mut events,
            )
            .unwrap();
            assert_eq!(r.executed, jobs.len());
            // Started first, Done last, one Finished per trial, the flushes add up to the trials.
            assert_eq!(events.first(), Some(&Event::Started { trials: jobs.len() }));
            assert_eq!(events.last(), Some(&Event::Done { executed: jobs.len(), failed: 0 }));
            let finished = events.iter().filter(|e| matches!(e, Event::Finished { .. })).count();
            let flushed: usize =
                events.iter().map(|e| if let Event::Flushed { trials } = e { *trials } else { 0 }).sum();
            assert_eq!((finished, flushed), (jobs.len(), jobs.len()));
            assert!(batches >= jobs.len() / 4);
            got.sort_by_key(|r| r.key);
            got.into_iter().map(|r| (r.key, r.outcome)).collect::<Vec<_>>()
        };
        // Crisp trials in lockstep (interleaved with fuzzy ones that run alone) or all alone.
        let alone = run(1, false);
        assert_eq!(run(1, true), alone);
        assert_eq!(run(2, true), alone);
        assert_eq!(run(2, false), alone);
    }

    /// Regression: lockstep rows were charged their loop's time so far in proportion to their
    /// steps, which over-counts (the crisp cells of `paper.yaml` summed to 10 % more CPU than the
    /// process used). On one thread, the rows' seconds add up to at most the run's.
    #[test]
    fn lockstep_rows_charge_no_more_time_than_the_run_took() {
        let mut configs = Vec::new();
        for res in [vec![6, 6], vec![10, 10], vec![3, 8]] {
            let mut c = TrialConfig::paper(SystemKind::MountainCar, ReprKind::Crisp, Algorithm::Q0, res, 3);
            c.limits.max_episodes = 40;
            configs.push(c);
        }
        let jobs = jobs_for(&configs);
        let opts = ExecOptions { jobs: 1, lockstep: true, ..Default::default() };
        let mut rows = Vec::new();
        let start = Instant::now();
        let sink = |b: &[TrialRecord]| {
            rows.extend(b.iter().cloned());
            Ok(())
        };
        execute(&jobs, &opts, sink, &mut Vec::<Event>::new()).unwrap();
        let took = start.elapsed().as_secs_f64();
        assert_eq!(rows.len(), jobs.len());
        let charged: f64 = rows.iter().map(|r| r.seconds).sum();
        assert!(charged <= took, "rows charged {charged} s of a {took} s run");
        assert!(rows.iter().all(|r| r.seconds > 0.0), "every trial took some time");
        if let Some(cpu) = rows.iter().map(|r| r.cpu_seconds).sum::<Option<f64>>() {
            assert!(cpu <= took * 1.01 + 0.01, "rows charged {cpu} CPU s in a {took} s run on one thread");
        }
    }

    #[test]
    fn trials_that_run_alone_go_first_then_each_lockstep_group_together_longest_first() {
        let mut configs = Vec::new();
        for sys in [SystemKind::MountainCar, SystemKind::BallBeam] {
            for alg in [Algorithm::Q0, Algorithm::QLambda] {
                for (repr, actions) in [(ReprKind::Crisp, 3), (ReprKind::Fuzzy, 3), (ReprKind::Crisp, 9)] {
                    configs.push(TrialConfig::paper(sys, repr, alg, vec![3, 3], actions));
                }
            }
        }
        let jobs = jobs_for(&configs);
        let order: Vec<&Job<'_>> = schedule(&jobs).into_iter().map(|j| &jobs[j]).collect();
        let groups: Vec<_> = order.iter().map(|j| lanes::group(j.config)).collect();
        let alone = groups.iter().take_while(|g| g.is_none()).count();
        assert_eq!(alone, jobs.iter().filter(|j| j.config.repr.kind == ReprKind::Fuzzy).count());
        // Each group is one run of the order, its trials longest first.
        let mut runs = groups.clone();
        runs.dedup();
        assert_eq!(runs.len(), 1 + 4, "{runs:?}");
        for w in order.windows(2) {
            if lanes::group(w[0].config) == lanes::group(w[1].config) {
                assert!(estimated_cost(w[0].config) >= estimated_cost(w[1].config));
            }
        }
        let mut sorted = schedule(&jobs);
        sorted.sort_unstable();
        assert_eq!(sorted, (0..jobs.len()).collect::<Vec<_>>(), "every job once");
    }

    #[test]
    fn rows_are_the_same_with_leases_taken_in_batches_as_without_leases() {
        let mut configs = Vec::new();
        for repr in [ReprKind::Crisp, ReprKind::Fuzzy] {
            for actions in [2, 3] {
                let mut c =
                    TrialConfig::paper(SystemKind::BallBeam, repr, Algorithm::Q0, vec![2, 3], actions);
                c.limits.max_episodes = 10;
                configs.push(c);
            }
        }
        // 12 trials on 1 thread: batches of 3 at first, then of 1.
        let jobs = jobs_for(&configs);
        let dir = tempfile::tempdir().unwrap();
        let store = crate::cache::Store::open(dir.path()).unwrap();
        let run = |leases: Option<Arc<Leases>>| {
            let opts = ExecOptions { jobs: 1, leases, ..Default::default() };
            let mut got: Vec<TrialRecord> = Vec::new();
            let sink = |b: &[TrialRecord]| {
                got.extend(b.iter().cloned());
                Ok(())
            };
            let r = execute(&jobs, &opts, sink, &mut Vec::<Event>::new()).unwrap();
            assert_eq!((r.executed, r.elsewhere), (jobs.len(), 0));
            got.sort_by_key(|r| r.key);
            // Everything but the timings, which no two runs share.
            got.into_iter()
                .map(|r| (r.key, r.engine_version, r.config_json(), r.seed, r.outcome))
                .collect::<Vec<_>>()
        };
        let leases = Leases::open(&store).unwrap();
        assert_eq!(run(Some(Arc::clone(&leases))), run(None));
        assert_eq!(leases.held(), 0, "every lease is released once its trial is stored");
    }

    #[test]
    fn a_failing_sink_stops_the_run_and_reports_the_error() {
        let c = TrialConfig::paper(SystemKind::BallBeam, ReprKind::Crisp, Algorithm::Q0, vec![2, 2], 3);
        let cs = vec![c];
        let jobs = jobs_for(&cs);
        let opts = ExecOptions { jobs: 2, batch_trials: 1, ..Default::default() };
        let mut events: Vec<Event> = Vec::new();
        let err = execute(&jobs, &opts, |_| anyhow::bail!("disk full"), &mut events).unwrap_err();
        assert!(err.to_string().contains("disk full"));
        assert!(matches!(events.last(), Some(Event::Done { executed: 0, .. })), "{events:?}");
    }
}
