//! What an execution reports while it runs: events handed to a [`Reporter`] the caller passes
//! in, so that a library user can run a pipeline without a terminal, and the CLI's progress bar,
//! plain progress lines and `--json` (which shows none) are reporters of its own.
//!
//! Events come from the one collecting thread, in order; a reporter needs no locking.

use crate::cache::Key;

/// One thing that happened during [`super::execute`].
#[derive(Debug, Clone, PartialEq)]
pub enum Event {
    /// Execution of `trials` trials starts (once per call: a raced pipeline calls once per round).
    Started {
        /// Trials to run in this call.
        trials: usize,
    },
    /// A trial finished (not yet stored).
    Finished {
        /// Its key.
        key: Key,
        /// Whether it stopped with a failure (diverged).
        failed: bool,
    },
    /// Nothing finished for a while (about 200 ms): a chance to redraw.
    Tick,
    /// A batch of finished trials was stored.
    Flushed {
        /// Trials in the batch.
        trials: usize,
    },
    /// Trials another run sharing the cache has leased: set aside, then waited for.
    Elsewhere {
        /// Set aside and not stored yet.
        running: usize,
        /// Stored by the other runs meanwhile (not run here).
        stored: usize,
    },
    /// An interrupt (Ctrl-C, SIGTERM) stopped the execution; finished trials were stored.
    Interrupted,
    /// The execution ended (also after an error or an interrupt).
    Done {
        /// Trials run and stored.
        executed: usize,
        /// Of those, failed.
        failed: usize,
    },
}

/// Receives every [`Event`] of an execution.
pub trait Reporter {
    /// Called for each event, in order, from the collecting thread.
    fn event(&mut self, e: &Event);
}

/// No reporting.
impl Reporter for () {
    fn event(&mut self, _: &Event) {}
}

/// Keeps every event (for a library user's own display, or a test).
impl Reporter for Vec<Event> {
    fn event(&mut self, e: &Event) {
        self.push(e.clone());
    }
}
