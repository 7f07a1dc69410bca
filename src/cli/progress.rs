//! The CLI's reporter of execution events: an indicatif bar with rate and ETA on a terminal,
//! plain lines every few seconds otherwise (nothing when quiet or `--json`: the `()` reporter).

use indicatif::{ProgressBar, ProgressStyle};
use qsweep_pipeline::exec::{Event, Reporter};
use std::io::IsTerminal;
use std::time::{Duration, Instant};

/// A bar on a terminal, plain lines otherwise; one per [`Event::Started`] (a raced run's round).
#[derive(Default)]
pub struct ProgressReporter {
    current: Option<Progress>,
}

impl Reporter for ProgressReporter {
    fn event(&mut self, e: &Event) {
        match e {
            Event::Started { trials } => self.current = Some(Progress::new(*trials)),
            Event::Finished { failed, .. } => {
                if let Some(p) = &mut self.current {
                    p.inc(*failed)
                }
            }
            Event::Tick => {
                if let Some(p) = &mut self.current {
                    p.tick()
                }
            }
            Event::Done { .. } => {
                if let Some(p) = self.current.take() {
                    p.finish()
                }
            }
            Event::Elsewhere { running, stored } => {
                if let Some(p) = &mut self.current {
                    p.elsewhere(*running, *stored)
                }
            }
            Event::Flushed { .. } | Event::Interrupted => {}
        }
    }
}

struct Progress {
    bar: Option<ProgressBar>,
    plain: bool,
    total: usize,
    done: usize,
    failed: usize,
    /// Trials another run on the cache has leased and not stored yet, and those it stored.
    running_elsewhere: usize,
    stored_elsewhere: usize,
    start: Instant,
    last_line: Instant,
}

impl Progress {
    fn new(total: usize) -> Self {
        let show = total > 0;
        let terminal = std::io::stderr().is_terminal();
        let bar = (show && terminal).then(|| {
            let b = ProgressBar::new(total as u64);
            b.set_style(
                ProgressStyle::with_template(
                    "{spinner} [{elapsed_precise}] {wide_bar} {pos}/{len} trials  {per_sec}  ETA {eta}  {msg}",
                )
                .expect("valid template"),
            );
            b.enable_steady_tick(Duration::from_millis(200));
            b
        });
        let now = Instant::now();
        Self {
            bar,
            plain: show && !terminal,
            total,
            done: 0,
            failed: 0,
            running_elsewhere: 0,
            stored_elsewhere: 0,
            start: now,
            last_line: now,
        }
    }

    fn inc(&mut self, failed: bool) {
        self.done += 1;
        self.failed += usize::from(failed);
        if let Some(b) = &self.bar {
            b.inc(1);
        }
        self.redraw_message();
        self.tick();
    }

    /// Another run's share: its stored trials count as done here, its running ones are shown.
    fn elsewhere(&mut self, running: usize, stored: usize) {
        self.done += stored - self.stored_elsewhere.min(stored);
        if let Some(b) = &self.bar {
            b.inc((stored - self.stored_elsewhere.min(stored)) as u64);
        }
        (self.running_elsewhere, self.stored_elsewhere) = (running, stored);
        self.redraw_message();
    }

    /// What the bar says after its counts: failures, and trials running elsewhere.
    fn suffix(&self) -> String {
        let mut parts = Vec::new();
        if self.failed > 0 {
            parts.push(format!("{} failed", self.failed));
        }
        if self.running_elsewhere > 0 {
            parts.push(format!("{} running elsewhere", self.running_elsewhere));
        }
        parts.join(", ")
    }

    fn redraw_message(&self) {
        if let Some(b) = &self.bar {
            b.set_message(self.suffix());
        }
    }

    fn tick(&mut self) {
        if self.plain && self.last_line.elapsed() >= Duration::from_secs(5) {
            self.last_line = Instant::now();
            let secs = self.start.elapsed().as_secs_f64();
            let rate = self.done as f64 / secs.max(1e-9);
            let eta = if rate > 0.0 { (self.total - self.done) as f64 / rate } else { f64::NAN };
            eprintln!(
                "progress: {}/{} trials ({:.0}%), {:.1} trials/s, ETA {:.0} s{}",
                self.done,
                self.total,
                100.0 * self.done as f64 / self.total as f64,
                rate,
                eta,
                match self.suffix() {
                    s if s.is_empty() => s,
                    s => format!(", {s}"),
                }
            );
        }
    }

    fn finish(&self) {
        if let Some(b) = &self.bar {
            b.finish_and_clear();
        }
    }
}
