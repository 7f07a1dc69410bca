//! The worker protocol: one long-lived process per `--jobs` slot runs many trials, one JSON object
//! per line on its stdin (the params plus `seed`) and exactly one result line per trial on its
//! stdout (blank lines are skipped; logs go to stderr). Its environment is qsweep's plus
//! `QSWEEP_WORKER` (the slot) and `QSWEEP_TRIAL_DIR` (a directory of its own, emptied before each
//! trial). A worker that times out, fails a result line, overflows, writes output no trial asked
//! for or exits is stopped; the next trial starts a new one. One [`Worker`] per thread: it is
//! driven by the thread that calls [`Worker::run`], which blocks until the trial ends.

use super::child::{cpu_of, program_of, Proc, Pumped, Status};
use super::model::{MetricType, Program, TrialResult};
use super::result;
use super::runner::{cannot_start, input_line, judge, since, stopped, RunnerOptions, Timing, TrialDir};
use serde_json::Value;
use std::ffi::OsStr;
use std::time::{Duration, Instant};

/// How long a worker told to finish (stdin closed) may take before it is killed.
const FINISH: Duration = Duration::from_millis(200);

/// One worker slot: its process (started on the first trial, restarted after one that stopped
/// it) and its directory.
pub struct Worker {
    command: Vec<String>,
    metrics: Vec<(String, MetricType)>,
    timeout: Duration,
    slot: usize,
    opts: RunnerOptions,
    proc: Option<Proc>,
    /// The program's pid (the supervisor's child), once known: its CPU clock is read per trial.
    program_pid: Option<libc::pid_t>,
    dir: Option<TrialDir>,
}

impl Worker {
    /// Slot `slot` (`QSWEEP_WORKER`) of `program`; nothing starts until the first trial.
    pub fn new(program: &Program, slot: usize, opts: RunnerOptions) -> Self {
        Self {
            command: program.command.clone(),
            metrics: program.metrics.clone(),
            timeout: opts.timeout_of(program),
            slot,
            opts,
            proc: None,
            program_pid: None,
            dir: None,
        }
    }

    /// Run one trial: `params_json` (the trial's params, a JSON object) plus `seed` as one line.
    /// Returns its result as docs/programs.md's failure table says and how long it took (a new
    /// process's startup counts to its first trial; CPU time from the program's CPU clock and
    /// its waited-for children's on Linux, `None` elsewhere or when the worker ended).
    ///
    /// # Panics
    /// If `params_json` is not a JSON object.
    pub fn run(&mut self, params_json: &Value, seed: u64) -> (TrialResult, Timing) {
        let input = input_line(params_json, seed);
        let started = Instant::now();
        let cpu_before = match self.ready() {
            Ok(cpu) => cpu,
            Err(unfinished) => return (unfinished, since(started, None)),
        };
        let proc = self.proc.as_mut().expect("ready() started it");
        proc.drain_stderr();
        proc.err.clear();
        let deadline = started + self.timeout;
        let mut rest = &input[..];
        let pumped = loop {
            match proc.pump(&mut rest, false, true, deadline, self.opts.stdout_limit, self.opts.interrupt) {
                Pumped::Line => match proc.take_line() {
                    Some(line) if line.trim_ascii().is_empty() => continue,
                    Some(line) => break Ok(line),
                    None => continue,
                },
                other => break Err(other),
            }
        };
        let (result, cpu) = match pumped {
            Ok(line) => match result::parse(&line, &self.metrics) {
                Ok(values) => {
                    let cpu = self.cpu().zip(cpu_before).map(|(after, before)| after.saturating_sub(before));
                    if !rest.is_empty() {
                        // It answered before reading its whole line: the rest would be taken for
                        // the start of the next trial's.
                        self.stop();
                    }
                    (TrialResult::Ok(values), cpu)
                }
                Err(reason) => {
                    // What it prints next cannot be trusted to belong to the next trial.
                    let failed = judge(Status::Code(0), proc.err.text(), self.opts.interrupt, || Err(reason));
                    self.stop();
                    (failed, None)
                }
            },
            Err(Pumped::Eof) => {
                let ended = proc.reap_by(deadline, self.opts.interrupt);
                proc.drain_stderr();
                let result = match ended {
                    Ok((status, _)) => judge(status, proc.err.text(), self.opts.interrupt, || {
                        Err("the worker exited 0 before printing its result line".into())
                    }),
                    Err(why) => {
                        proc.kill_and_reap();
                        stopped(why, self.timeout, self.opts.stdout_limit, proc.err.text())
                    }
                };
                self.proc = None;
                (result, None)
            }
            Err(why) => {
                proc.kill_and_reap();
                proc.drain_stderr();
                let result = stopped(why, self.timeout, self.opts.stdout_limit, proc.err.text());
                self.proc = None;
                (result, None)
            }
        };
        (result, since(started, cpu))
    }

    /// Make the worker ready for a trial: its directory empty, its process running (a new one if
    /// the last ended, or wrote what no trial asked for, whose lines would be taken for this
    /// trial's result). Returns the program's CPU time so far (zero for a new one: its startup
    /// counts to its first trial), or why it cannot run.
    fn ready(&mut self) -> Result<Option<Duration>, TrialResult> {
        if let Some(p) = &mut self.proc {
            if p.try_reap().is_some() || p.stray_output() || p.stdout_closed() {
                self.stop();
            }
        }
        let dir = match &self.dir {
            Some(d) => d.empty().map(|()| d),
            None => TrialDir::new(&format!("worker{}", self.slot)).map(|d| &*self.dir.insert(d)),
        };
        let dir = match dir {
            Ok(d) => d.path().to_path_buf(),
            Err(e) => {
                let why = format!("cannot make or empty the worker's directory: {e}");
                return Err(TrialResult::Unfinished(why));
            }
        };
        if self.proc.is_some() {
            return Ok(self.cpu());
        }
        let slot = self.slot.to_string();
        let vars = [("QSWEEP_WORKER", OsStr::new(&slot)), ("QSWEEP_TRIAL_DIR", dir.as_os_str())];
        let spawned =
            Proc::spawn(&self.command, &vars, self.opts.supervisor.as_deref(), self.opts.stderr_tail);
        self.proc = Some(spawned.map_err(|e| cannot_start(&self.command, &e))?);
        self.program_pid = None;
        Ok(Some(Duration::ZERO))
    }

    /// The program's CPU time so far (Linux), finding its pid first if need be.
    fn cpu(&mut self) -> Option<Duration> {
        let proc = self.proc.as_ref()?;
        if self.program_pid.is_none() {
            self.program_pid = if proc.supervised() { program_of(proc.pid()) } else { Some(proc.pid()) };
        }
        cpu_of(self.program_pid?)
    }

    /// Kill the process, if any, and forget it.
    fn stop(&mut self) {
        if let Some(mut p) = self.proc.take() {
            p.kill_and_reap();
        }
    }
}

impl Drop for Worker {
    /// The process is told to finish (its stdin closed), then killed if it has not.
    fn drop(&mut self) {
        if let Some(mut p) = self.proc.take() {
            p.close_stdin();
            let never = std::sync::atomic::AtomicBool::new(false);
            if p.reap_by(Instant::now() + FINISH, &never).is_err() {
                p.kill_and_reap();
            }
        }
    }
}

#[cfg(test)]
mod tests;
