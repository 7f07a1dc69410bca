//! Which trial a worker runs next when the run shares its cache ([`crate::cache::leases`]): the
//! next one in order that it can lease; a trial another run has leased is set aside, and once
//! the order is used up the workers look at the set-aside trials every [`POLL`] until each is
//! stored (by its holder) or leaseable (its holder stopped or died); before that, every
//! [`BUSY_POLL`], so a dead holder's trials go to the next free worker.

use super::job::Job;
use crate::cache::leases::{Leases, Take};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;
use std::time::{Duration, Instant};

/// How often the trials running elsewhere are looked at: a dead holder on this machine is
/// noticed within this, a stored trial too.
pub const POLL: Duration = Duration::from_millis(100);

/// How often they are looked at while the run still has other trials to start: rarely enough
/// that a long list of them costs nothing next to the trials.
pub const BUSY_POLL: Duration = Duration::from_secs(1);

/// What a look at the set-aside trials found.
enum Polled {
    /// This one is free now: run it.
    Run(usize),
    /// Some are still held elsewhere (or another worker is looking).
    Wait,
    /// None is left.
    Empty,
}

/// What a worker does next.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Pick {
    /// Run the job at this index (its lease is held, if the run has leases).
    Run(usize),
    /// Nothing to run now; trials are running elsewhere: sleep [`POLL`] and ask again.
    Wait,
    /// Nothing left.
    Done,
}

/// The set-aside trials and when they were last looked at.
struct Waiting {
    jobs: Vec<usize>,
    last_poll: Option<Instant>,
}

/// Hands out the jobs of one execution, longest first, leasing each when the run has leases.
pub struct Scheduler<'a> {
    jobs: &'a [Job<'a>],
    order: Vec<usize>,
    next: AtomicUsize,
    leases: Option<&'a Leases>,
    waiting: Mutex<Waiting>,
    /// Trials set aside that are not stored yet.
    pub running_elsewhere: AtomicUsize,
    /// Trials another run stored meanwhile (not run here).
    pub stored_elsewhere: AtomicUsize,
}

impl<'a> Scheduler<'a> {
    /// Jobs in `order`, leased through `leases` if given.
    pub fn new(jobs: &'a [Job<'a>], order: Vec<usize>, leases: Option<&'a Leases>) -> Self {
        Self {
            jobs,
            order,
            next: AtomicUsize::new(0),
            leases,
            waiting: Mutex::new(Waiting { jobs: Vec::new(), last_poll: None }),
            running_elsewhere: AtomicUsize::new(0),
            stored_elsewhere: AtomicUsize::new(0),
        }
    }

    /// Whether every job was handed out or set aside: the run is in its tail.
    pub fn exhausted(&self) -> bool {
        self.next.load(Ordering::Relaxed) >= self.order.len()
    }

    /// The next job to run, or whether to wait or stop.
    pub fn pick(&self) -> Pick {
        // While there is other work, the set-aside trials are looked at now and then too, so a
        // dead holder's trials are taken over by the next free worker, not only in the tail.
        if self.leases.is_some() && !self.exhausted() {
            if let Polled::Run(j) = self.poll_waiting(BUSY_POLL) {
                return Pick::Run(j);
            }
        }
        while let Some(&j) = self.order.get(self.next.fetch_add(1, Ordering::Relaxed)) {
            let Some(leases) = self.leases else { return Pick::Run(j) };
            match leases.try_take(self.jobs[j].key) {
                Ok(Take::Busy) => {
                    self.running_elsewhere.fetch_add(1, Ordering::Relaxed);
                    self.waiting.lock().unwrap_or_else(std::sync::PoisonError::into_inner).jobs.push(j);
                }
                Ok(Take::Stored) => {
                    self.stored_elsewhere.fetch_add(1, Ordering::Relaxed);
                }
                // Leases only save work: a cache whose leases cannot be made still gets its trial.
                Ok(Take::Taken) | Err(_) => return Pick::Run(j),
            }
        }
        if self.leases.is_none() {
            return Pick::Done;
        }
        match self.poll_waiting(POLL) {
            Polled::Run(j) => Pick::Run(j),
            Polled::Wait => Pick::Wait,
            Polled::Empty => Pick::Done,
        }
    }

    /// Look at the set-aside trials if the last look is `every` ago: take the first that is free,
    /// drop those stored meanwhile.
    fn poll_waiting(&self, every: Duration) -> Polled {
        let Some(leases) = self.leases else { return Polled::Empty };
        // One worker looks at a time; the others wait for its answer.
        let Ok(mut w) = self.waiting.try_lock() else { return Polled::Wait };
        if w.jobs.is_empty() {
            return Polled::Empty;
        }
        if w.last_poll.is_some_and(|t| t.elapsed() < every) {
            return Polled::Wait;
        }
        w.last_poll = Some(Instant::now());
        let mut i = 0;
        while i < w.jobs.len() {
            let j = w.jobs[i];
            match leases.try_take(self.jobs[j].key) {
                Ok(Take::Busy) => i += 1,
                Ok(Take::Stored) => {
                    w.jobs.remove(i);
                    self.running_elsewhere.fetch_sub(1, Ordering::Relaxed);
                    self.stored_elsewhere.fetch_add(1, Ordering::Relaxed);
                }
                Ok(Take::Taken) | Err(_) => {
                    w.jobs.remove(i);
                    self.running_elsewhere.fetch_sub(1, Ordering::Relaxed);
                    return Polled::Run(j);
                }
            }
        }
        if w.jobs.is_empty() {
            Polled::Empty
        } else {
            Polled::Wait
        }
    }
}
