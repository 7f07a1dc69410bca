//! Running a program pipeline's missing trials: worker threads, each with a runner of its own
//! (one process per trial, or one long-lived worker process: [`RunTrial`]), take trials from the
//! engine's lease-aware scheduler, and the calling thread gathers the finished ones into
//! segments with the engine's collector, so concurrent runs on one cache start each trial once and
//! an interrupted run keeps what finished. A trial that did not finish (timed out, killed,
//! interrupted) stores nothing: its lease is let go at once and it runs next time.

use super::model::{ProgramPlan, ProgramRow, TrialResult};
use crate::cache::Key;
use crate::exec::leased::{Pick, Scheduler, POLL};
use crate::exec::{finish, Collector, Event, ExecOptions, ExecReport, Finished, Reporter, INTERRUPTED};
use std::collections::HashSet;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::mpsc;

/// One distinct trial to run: its params (in the plan's order), seed and key.
#[derive(Debug, Clone, Copy)]
pub struct ProgramJob<'p> {
    /// Every param's value, in [`ProgramPlan::params`] order.
    pub params: &'p [super::model::ParamValue],
    /// The seed.
    pub seed: u64,
    /// The key.
    pub key: Key,
}

/// The distinct trials of `plan`, in plan order, each cell's own then its fresh ones (a trial
/// shared by two cells, or two variants, once).
pub fn jobs(plan: &ProgramPlan) -> Vec<ProgramJob<'_>> {
    let mut seen = HashSet::new();
    let mut out = Vec::new();
    for e in &plan.experiments {
        for c in &e.cells {
            for t in c.trials.iter().chain(&c.fresh) {
                if seen.insert(t.key) {
                    out.push(ProgramJob { params: &c.params, seed: t.seed, key: t.key });
                }
            }
        }
    }
    out
}

/// What running one trial gave, with its cost.
#[derive(Debug, Clone, PartialEq)]
pub struct Ran {
    /// The result.
    pub result: TrialResult,
    /// Wall-clock seconds.
    pub seconds: f64,
    /// CPU seconds of the program, when measured.
    pub cpu_seconds: Option<f64>,
}

/// Runs trials on one worker thread, one at a time (a process per trial, or a worker process kept
/// between trials).
pub trait RunTrial {
    /// Run `job`.
    fn run(&mut self, job: &ProgramJob<'_>) -> Ran;
}

/// What [`execute`] did: the engine's counts, and the trials that did not finish.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ProgramExecReport {
    /// Trials stored (ok or failed), failed among them, stored elsewhere, interrupted.
    pub exec: ExecReport,
    /// Trials that did not finish (timed out or killed by a signal): nothing stored, each with
    /// why, in the order they ended.
    pub unfinished: Vec<(Key, String)>,
}

/// A finished trial on its way to the collector: its row, to be stored.
struct Done(ProgramRow);

impl Finished for Done {
    fn key(&self) -> Key {
        self.0.key
    }

    fn failed(&self) -> bool {
        self.0.result.is_err()
    }
}

/// Run `jobs` with `threads` workers, each with the runner `runner(slot)` makes, and hand the
/// rows `row(job, ran)` builds to `sink` in batches (bounded by count and time, as the engine's);
/// stops early, after flushing, on [`INTERRUPTED`]. With leases (`opts.leases`), a trial another
/// run holds is left to it and waited for.
pub fn execute<'p, R: RunTrial>(
    jobs: &[ProgramJob<'p>],
    opts: &ExecOptions,
    runner: impl Fn(usize) -> R + Sync,
    row: impl Fn(&ProgramJob<'p>, Ran) -> ProgramRow + Sync,
    mut sink: impl FnMut(&[ProgramRow]) -> anyhow::Result<()>,
    reporter: &mut dyn Reporter,
) -> anyhow::Result<ProgramExecReport> {
    let threads = opts.jobs.max(1);
    let leases = opts.leases.as_deref();
    let sched =
        Scheduler::new(jobs.iter().map(|j| j.key).collect(), (0..jobs.len()).collect(), threads, leases);
    let stop = AtomicBool::new(false);
    let (tx, rx) = mpsc::channel::<Done>();
    let (utx, urx) = mpsc::channel::<(Key, String)>();
    let mut collector =
        Collector::new(|b: &[Done]| sink(&b.iter().map(|d| d.0.clone()).collect::<Vec<_>>()), leases);
    reporter.event(&Event::Started { trials: jobs.len() });
    let unfinished_count = AtomicUsize::new(0);
    let collected = std::thread::scope(|scope| {
        for slot in 0..threads {
            let (tx, utx) = (tx.clone(), utx.clone());
            let (sched, stop, runner, row, unf) = (&sched, &stop, &runner, &row, &unfinished_count);
            scope.spawn(move || {
                let mut r = runner(slot);
                loop {
                    if stop.load(Ordering::Relaxed) || INTERRUPTED.load(Ordering::Relaxed) {
                        break;
                    }
                    let j = match sched.pick() {
                        Pick::Run(j) => j,
                        Pick::Wait => {
                            std::thread::sleep(POLL);
                            continue;
                        }
                        Pick::Done => break,
                    };
                    let job = &jobs[j];
                    let ran = r.run(job);
                    if let TrialResult::Unfinished(why) = &ran.result {
                        // Nothing to store: the lease goes now, and the trial runs next time.
                        if let Some(l) = leases {
                            l.release(&[job.key]);
                        }
                        unf.fetch_add(1, Ordering::Relaxed);
                        if utx.send((job.key, why.clone())).is_err() {
                            break;
                        }
                        continue;
                    }
                    if tx.send(Done(row(job, ran))).is_err() {
                        break;
                    }
                }
            });
        }
        drop((tx, utx));
        collector.collect(&rx, opts, &sched, &stop, reporter)
    });
    let exec = finish(collector.report, jobs.len(), &sched, leases, reporter);
    collected?;
    let unfinished: Vec<(Key, String)> = urx.try_iter().collect();
    debug_assert_eq!(unfinished.len(), unfinished_count.load(Ordering::Relaxed));
    Ok(ProgramExecReport { exec, unfinished })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::program::model::{Failure, MetricValue, ParamValue};

    /// A runner that answers from the seed: seed % 3 == 1 fails, seed % 3 == 2 does not finish.
    struct Fake;

    impl RunTrial for Fake {
        fn run(&mut self, job: &ProgramJob<'_>) -> Ran {
            let result = match job.seed % 3 {
                0 => TrialResult::Ok(vec![MetricValue::Int(job.seed as i64)]),
                1 => TrialResult::Failed(Failure {
                    exit_code: Some(1),
                    reason: "exit 1".into(),
                    stderr_tail: String::new(),
                }),
                _ => TrialResult::Unfinished("timed out after 1 s".into()),
            };
            Ran { result, seconds: 0.0, cpu_seconds: None }
        }
    }

    fn row(job: &ProgramJob<'_>, ran: Ran) -> ProgramRow {
        ProgramRow {
            key: job.key,
            seed: job.seed,
            params: job.params.to_vec(),
            result: match ran.result {
                TrialResult::Ok(m) => Ok(m),
                TrialResult::Failed(f) => Err(f),
                TrialResult::Unfinished(_) => unreachable!("never stored"),
            },
            seconds: ran.seconds,
            cpu_seconds: ran.cpu_seconds,
            command_json: "[]".into(),
            inputs_json: "{}".into(),
            provenance_json: "[]".into(),
        }
    }

    #[test]
    fn ok_and_failed_trials_are_stored_unfinished_ones_are_not() {
        let params = [ParamValue::Int(1)];
        let jobs: Vec<ProgramJob> = (0..30u64)
            .map(|seed| ProgramJob {
                params: &params,
                seed,
                key: Key(*blake3::hash(&seed.to_le_bytes()).as_bytes()),
            })
            .collect();
        let mut stored: Vec<ProgramRow> = Vec::new();
        let opts = ExecOptions { jobs: 3, batch_trials: 4, ..ExecOptions::default() };
        let mut events: Vec<Event> = Vec::new();
        let report = execute(
            &jobs,
            &opts,
            |_| Fake,
            row,
            |b| {
                stored.extend_from_slice(b);
                Ok(())
            },
            &mut events,
        )
        .unwrap();
        assert_eq!((report.exec.executed, report.exec.failed, report.unfinished.len()), (20, 10, 10));
        let mut seeds: Vec<u64> = stored.iter().map(|r| r.seed).collect();
        seeds.sort_unstable();
        assert_eq!(seeds, (0..30).filter(|s| s % 3 != 2).collect::<Vec<_>>());
        assert!(report.unfinished.iter().all(|(_, why)| why.contains("timed out")));
        assert!(matches!(events.last(), Some(Event::Done { executed: 20, failed: 10 })));
    }
}
