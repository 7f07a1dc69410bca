//! Which trial a worker runs next when the run shares its cache ([`crate::cache::leases`]): the
//! next one in order that it can lease; a trial another run has leased is set aside, and once
//! the order is used up the workers look at the set-aside trials every [`POLL`] until each is
//! stored (by its holder) or leaseable (its holder stopped or died); before that, every
//! [`BUSY_POLL`], so a dead holder's trials go to the next free worker.
//!
//! Trials are leased in batches ([`batch_len`]): a worker that finds no leased trial waiting
//! leases the next few in order at once, runs the first and leaves the rest to the run's next
//! free workers. A batch costs one lease file ([`Leases::try_take_batch`]), so leasing costs less
//! per trial; a trial leased and not yet started is held like a running one (other runs set it
//! aside, a killed run's is taken over). Batches shrink with the trials left, so at the end a
//! run holds no more than it is about to start and the runs sharing a cache finish together.

use crate::cache::leases::{lock_ok, Leases, Take};
use crate::cache::Key;
use std::collections::VecDeque;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;
use std::time::{Duration, Instant};

/// How often the trials running elsewhere are looked at: a dead holder on this machine is
/// noticed within this, a stored trial too.
pub const POLL: Duration = Duration::from_millis(100);

/// How often they are looked at while the run still has other trials to start: rarely enough
/// that a long list of them costs nothing next to the trials.
pub const BUSY_POLL: Duration = Duration::from_secs(1);

/// The most trials leased at once. Leasing a batch costs one lease file plus a link and an
/// unlink per trial (`cargo bench --bench pipeline` prints both costs); past 16 the file's share
/// is a few µs per trial, while a longer batch would hold more trials back from the other runs.
pub const MAX_BATCH: usize = 16;

/// How many trials to lease at once when `left` are not yet handed out to `threads` workers: a
/// quarter of each worker's share, at most [`MAX_BATCH`], at least one (guided scheduling). A run
/// then holds at most a quarter of the trials left beyond those it runs, so near the end it
/// leases one at a time, as it did before batches, and no run idles while another works through
/// a batch.
pub fn batch_len(left: usize, threads: usize) -> usize {
    (left / (4 * threads.max(1))).clamp(1, MAX_BATCH)
}

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

/// Hands out the jobs of one execution (by index into their keys), longest first, leasing each
/// when the run has leases. It knows only the jobs' keys, so engine trials and program trials
/// (`crate::program`) share it.
pub struct Scheduler<'a> {
    keys: Vec<Key>,
    order: Vec<usize>,
    next: AtomicUsize,
    threads: usize,
    leases: Option<&'a Leases>,
    /// Trials leased in a batch and not yet started, in order: the next free worker runs them.
    leased: Mutex<VecDeque<usize>>,
    waiting: Mutex<Waiting>,
    /// Trials set aside that are not stored yet.
    pub running_elsewhere: AtomicUsize,
    /// Trials another run stored meanwhile (not run here).
    pub stored_elsewhere: AtomicUsize,
}

impl<'a> Scheduler<'a> {
    /// The jobs with these `keys`, in `order`, for `threads` workers, leased through `leases` if
    /// given.
    pub fn new(keys: Vec<Key>, order: Vec<usize>, threads: usize, leases: Option<&'a Leases>) -> Self {
        Self {
            keys,
            order,
            next: AtomicUsize::new(0),
            threads,
            leases,
            leased: Mutex::new(VecDeque::new()),
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
        let Some(leases) = self.leases else {
            return self
                .order
                .get(self.next.fetch_add(1, Ordering::Relaxed))
                .map_or(Pick::Done, |&j| Pick::Run(j));
        };
        // While there is other work, the set-aside trials are looked at now and then too, so a
        // dead holder's trials are taken over by the next free worker, not only in the tail.
        if !self.exhausted() || !lock_ok(&self.leased).is_empty() {
            if let Polled::Run(j) = self.poll_waiting(BUSY_POLL) {
                return Pick::Run(j);
            }
        }
        loop {
            if let Some(j) = lock_ok(&self.leased).pop_front() {
                return Pick::Run(j);
            }
            let left = self.order.len().saturating_sub(self.next.load(Ordering::Relaxed));
            let n = batch_len(left, self.threads);
            let start = self.next.fetch_add(n, Ordering::Relaxed);
            let Some(batch) = self.order.get(start..self.order.len().min(start + n)) else { break };
            if batch.is_empty() {
                break;
            }
            let keys: Vec<Key> = batch.iter().map(|&j| self.keys[j]).collect();
            let mut mine = Vec::with_capacity(batch.len());
            for (&j, take) in batch.iter().zip(leases.try_take_batch(&keys)) {
                match take {
                    Ok(Take::Busy) => {
                        self.running_elsewhere.fetch_add(1, Ordering::Relaxed);
                        lock_ok(&self.waiting).jobs.push(j);
                    }
                    Ok(Take::Stored) => {
                        self.stored_elsewhere.fetch_add(1, Ordering::Relaxed);
                    }
                    // Leases only save work: a cache whose leases cannot be made still gets its trial.
                    Ok(Take::Taken) | Err(_) => mine.push(j),
                }
            }
            if let Some((&first, rest)) = mine.split_first() {
                lock_ok(&self.leased).extend(rest);
                return Pick::Run(first);
            }
        }
        match self.poll_waiting(POLL) {
            Polled::Run(j) => Pick::Run(j),
            Polled::Wait => Pick::Wait,
            Polled::Empty => Pick::Done,
        }
    }

    /// Look at the set-aside trials if the last look is `every` ago: lease those that are free
    /// (run the first, queue the rest for the next free workers), drop those stored meanwhile.
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
        // Every free one is leased in one batch: a dead run may have held a whole batch, and its
        // trials go to this run's free workers together, not one per look.
        let keys: Vec<Key> = w.jobs.iter().map(|&j| self.keys[j]).collect();
        let mut mine = Vec::new();
        let mut still = Vec::with_capacity(w.jobs.len());
        for (&j, take) in w.jobs.iter().zip(leases.try_take_batch(&keys)) {
            match take {
                Ok(Take::Busy) => still.push(j),
                Ok(Take::Stored) => {
                    self.running_elsewhere.fetch_sub(1, Ordering::Relaxed);
                    self.stored_elsewhere.fetch_add(1, Ordering::Relaxed);
                }
                Ok(Take::Taken) | Err(_) => {
                    self.running_elsewhere.fetch_sub(1, Ordering::Relaxed);
                    mine.push(j);
                }
            }
        }
        w.jobs = still;
        if let Some((&first, rest)) = mine.split_first() {
            lock_ok(&self.leased).extend(rest);
            return Polled::Run(first);
        }
        if w.jobs.is_empty() {
            Polled::Empty
        } else {
            Polled::Wait
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cache::{Store, TrialRecord};
    use crate::exec::Job;
    use qsweep_engine::env::SystemKind;
    use qsweep_engine::repr::ReprKind;
    use qsweep_engine::{run_trial, Algorithm, TrialConfig};

    #[test]
    fn batches_shrink_to_one_trial_as_the_run_ends() {
        assert_eq!(batch_len(10_000, 2), MAX_BATCH);
        assert_eq!(batch_len(40, 2), 5);
        assert_eq!(batch_len(7, 2), 1);
        assert_eq!(batch_len(0, 8), 1);
        assert_eq!(batch_len(100, 0), MAX_BATCH, "no workers counts as one");
    }

    fn picks(s: &Scheduler<'_>, n: usize) -> Vec<usize> {
        (0..n).map_while(|_| if let Pick::Run(j) = s.pick() { Some(j) } else { None }).collect()
    }

    #[test]
    fn trials_another_live_run_leased_in_a_batch_are_set_aside_until_it_lets_go() {
        let mut c = TrialConfig::paper(SystemKind::BallBeam, ReprKind::Crisp, Algorithm::Q0, vec![2, 2], 3);
        c.limits.max_episodes = 3;
        let jobs: Vec<Job<'_>> =
            (0..64).map(|seed| Job { config: &c, seed, key: crate::cache::Key::of(&c, seed) }).collect();
        let dir = tempfile::tempdir().unwrap();
        let store = Store::open(dir.path()).unwrap();
        let (la, lb) = (Leases::open(&store).unwrap(), Leases::open(&store).unwrap());
        let a = Scheduler::new(jobs.iter().map(|j| j.key).collect(), (0..64).collect(), 1, Some(&la));
        let b = Scheduler::new(jobs.iter().map(|j| j.key).collect(), (0..64).collect(), 1, Some(&lb));
        // Run a starts one trial and holds the rest of its batch, not yet started.
        assert_eq!(a.pick(), Pick::Run(0));
        let batch = batch_len(64, 1);
        assert_eq!(la.held(), batch);
        // Run b meets them leased and runs everything else, never one of a's.
        let mut ran_b = picks(&b, 64);
        assert_eq!(ran_b, (batch..64).collect::<Vec<_>>());
        assert_eq!(b.running_elsewhere.load(Ordering::Relaxed), batch);
        assert_eq!(b.pick(), Pick::Wait, "a is alive: b waits for its trials");
        // Run a goes on with its own batch, stores the four trials it ran and stops (released,
        // as on Ctrl-C) with the rest not started, which b takes over at its next look.
        assert_eq!(picks(&a, 3), vec![1, 2, 3]);
        let ran_a: Vec<TrialRecord> = jobs[..4]
            .iter()
            .map(|j| TrialRecord::new(c.clone(), j.seed, run_trial(&c, j.seed), 0.1))
            .collect();
        store.write_segment(&ran_a).unwrap();
        la.release_all();
        std::thread::sleep(POLL);
        while ran_b.len() < 64 - 4 {
            match b.pick() {
                Pick::Run(j) => ran_b.push(j),
                Pick::Wait => std::thread::sleep(POLL),
                Pick::Done => break,
            }
        }
        ran_b.sort_unstable();
        let expected: Vec<usize> = (4..64).collect();
        assert_eq!(ran_b, expected, "b ran exactly what a never started");
        assert_eq!(b.pick(), Pick::Done);
        assert_eq!(b.stored_elsewhere.load(Ordering::Relaxed), 4);
        assert_eq!(b.running_elsewhere.load(Ordering::Relaxed), 0);
    }
}
