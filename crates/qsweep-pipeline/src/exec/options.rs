//! How an execution is asked to run ([`ExecOptions`]), what it did ([`ExecReport`]), and the flag
//! that stops it ([`INTERRUPTED`]): what the executor, its collector and program executions share.

use crate::cache::leases::Leases;
use qsweep_engine::lanes;
use std::sync::atomic::AtomicBool;
use std::sync::Arc;
use std::time::Duration;

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
