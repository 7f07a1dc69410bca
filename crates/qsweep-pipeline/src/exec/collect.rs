//! The calling thread's side of an execution: finished trials gathered into batches and handed
//! to a sink, the run's leases kept alive and released as trials are stored, events reported.
//! Generic over what a finished trial is ([`Finished`]), so engine trials and program trials
//! (`crate::program`) are collected the same way.

use super::events::{Event, Reporter};
use super::leased::Scheduler;
use super::options::{ExecOptions, ExecReport, INTERRUPTED};
use crate::cache::leases::{lease::HEARTBEAT, Leases};
use crate::cache::{Key, TrialRecord};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc;
use std::time::{Duration, Instant};

/// A finished trial as the collector sees it.
pub trait Finished {
    /// Its key.
    fn key(&self) -> Key;
    /// Whether it is stored as failed.
    fn failed(&self) -> bool;
}

impl Finished for TrialRecord {
    fn key(&self) -> Key {
        self.key
    }

    fn failed(&self) -> bool {
        self.outcome.failure.is_some()
    }
}

/// The calling thread's side of a run: finished records, gathered into batches, handed to the
/// sink; leases kept alive; events reported.
pub(crate) struct Collector<'l, T, S> {
    /// Where batches go.
    sink: S,
    /// The cache's leases, when the run takes them.
    leases: Option<&'l Leases>,
    /// Records finished since the last flush.
    batch: Vec<T>,
    /// What the run did so far.
    pub(crate) report: ExecReport,
    /// When the batch was last flushed.
    last_flush: Instant,
    /// When the leases were last renewed.
    last_beat: Instant,
    /// Trials running and stored elsewhere, as last reported.
    elsewhere: (usize, usize),
}

impl<'l, T: Finished, S: FnMut(&[T]) -> anyhow::Result<()>> Collector<'l, T, S> {
    /// A collector with nothing collected yet.
    pub(crate) fn new(sink: S, leases: Option<&'l Leases>) -> Self {
        Self {
            sink,
            leases,
            batch: Vec::new(),
            report: ExecReport::default(),
            last_flush: Instant::now(),
            last_beat: Instant::now(),
            elsewhere: (0, 0),
        }
    }

    /// Collect records from `rx` until the workers are done or a flush fails; on a failure, stop
    /// the workers and drain the channel so that none is left blocked.
    pub(crate) fn collect(
        &mut self,
        rx: &mpsc::Receiver<T>,
        opts: &ExecOptions,
        sched: &Scheduler<'_>,
        stop: &AtomicBool,
        reporter: &mut dyn Reporter,
    ) -> anyhow::Result<()> {
        let result = loop {
            match rx.recv_timeout(Duration::from_millis(200)) {
                Ok(rec) => {
                    reporter.event(&Event::Finished { key: rec.key(), failed: rec.failed() });
                    self.batch.push(rec);
                }
                Err(mpsc::RecvTimeoutError::Timeout) => reporter.event(&Event::Tick),
                Err(mpsc::RecvTimeoutError::Disconnected) => break self.flush(reporter),
            }
            self.tend_leases(sched, reporter);
            if self.flush_due(opts, sched) {
                if let Err(e) = self.flush(reporter) {
                    break Err(e);
                }
                self.last_flush = Instant::now();
            }
        };
        if result.is_err() {
            stop.store(true, Ordering::Relaxed);
            // Drain so workers are never blocked; their trials are lost, the stored ones are not.
            while rx.recv().is_ok() {}
        }
        result
    }

    /// With leases: renew them every [`HEARTBEAT`], and report a change in the trials other runs
    /// are computing or have stored.
    fn tend_leases(&mut self, sched: &Scheduler<'_>, reporter: &mut dyn Reporter) {
        let Some(c) = self.leases else { return };
        if self.last_beat.elapsed() >= HEARTBEAT {
            c.heartbeat();
            self.last_beat = Instant::now();
        }
        let now =
            (sched.running_elsewhere.load(Ordering::Relaxed), sched.stored_elsewhere.load(Ordering::Relaxed));
        if now != self.elsewhere {
            self.elsewhere = now;
            reporter.event(&Event::Elsewhere { running: now.0, stored: now.1 });
        }
    }

    /// Whether the batch is to be flushed now: full, old, or wanted at once.
    fn flush_due(&self, opts: &ExecOptions, sched: &Scheduler<'_>) -> bool {
        // On an interrupt (Ctrl-C, or SIGTERM from a scheduler's time limit, which sends
        // SIGKILL soon after) store what is finished at once rather than at the next batch.
        // So in the tail of a run that shares the cache: other runs may be waiting for
        // exactly these trials, which their leases keep from them until they are stored.
        self.batch.len() >= opts.batch_trials
            || self.last_flush.elapsed() >= opts.batch_interval
            || INTERRUPTED.load(Ordering::Relaxed)
            || (!self.batch.is_empty()
                && sched.exhausted()
                && self.leases.is_some_and(|c| c.others_present()))
    }

    /// Hand the batch to the sink, release its leases and count it.
    fn flush(&mut self, reporter: &mut dyn Reporter) -> anyhow::Result<()> {
        let batch = &mut self.batch;
        if !batch.is_empty() {
            (self.sink)(batch)?;
            if let Some(c) = self.leases {
                c.release(&batch.iter().map(Finished::key).collect::<Vec<_>>());
            }
            reporter.event(&Event::Flushed { trials: batch.len() });
            self.report.executed += batch.len();
            self.report.failed += batch.iter().filter(|r| r.failed()).count();
            batch.clear();
        }
        Ok(())
    }
}

/// The run's report once its workers are done: leases released, trials stored elsewhere counted,
/// an interruption and the end reported.
pub(crate) fn finish(
    mut report: ExecReport,
    jobs: usize,
    sched: &Scheduler<'_>,
    leases: Option<&Leases>,
    reporter: &mut dyn Reporter,
) -> ExecReport {
    // Nothing is held between executions: leases of trials a failing sink did not store go now.
    if let Some(c) = leases {
        c.release_all();
    }
    report.elsewhere = sched.stored_elsewhere.load(Ordering::Relaxed);
    report.interrupted = INTERRUPTED.load(Ordering::Relaxed) && report.executed + report.elsewhere < jobs;
    if report.interrupted {
        reporter.event(&Event::Interrupted);
    }
    reporter.event(&Event::Done { executed: report.executed, failed: report.failed });
    report
}
