//! The process protocol: one process per trial. The program gets the trial's params plus `seed`
//! as one JSON object on stdin, qsweep's environment plus `QSWEEP_SEED`, `QSWEEP_TRIAL` (the key)
//! and `QSWEEP_TRIAL_DIR` (an empty directory of the trial's own, removed after it), and qsweep's
//! working directory; its result is the last non-empty line of its stdout. What it gave becomes a
//! [`TrialResult`] as docs/programs.md's failure table says ([`run_process`]); the options and
//! the outcome rules here serve the worker protocol too.

use super::child::{Proc, Pumped, Status};
use super::model::{canonical_json, Failure, MetricValue, Program, TrialResult, STDERR_TAIL, STDOUT_LIMIT};
use super::result;
use super::supervise::{CANNOT_START, CANNOT_START_CODE};
use crate::cache::Key;
use crate::exec::INTERRUPTED;
use serde_json::Value;
use std::ffi::OsStr;
use std::io;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::time::{Duration, Instant};

/// How programs are run.
#[derive(Debug, Clone)]
pub struct RunnerOptions {
    /// The `qsweep` binary, run as `qsweep __supervise` to be every program's parent (the CLI
    /// passes `std::env::current_exe()`). `None` (library use): the program is started directly
    /// in a process group of its own with PR_SET_PDEATHSIG on Linux, which is best effort (see
    /// `child`'s doc): it does not outlive a qsweep killed by SIGKILL, but its children may.
    pub supervisor: Option<PathBuf>,
    /// The per-trial timeout; `None`: the program's own (`timeout:`).
    pub timeout: Option<Duration>,
    /// The most stdout a trial may write (a worker: the most one result line may hold).
    pub stdout_limit: usize,
    /// How much of stderr a failure keeps.
    pub stderr_tail: usize,
    /// Checked while a trial runs: once set, the program's group is killed and the trial is
    /// unfinished ("interrupted"). qsweep's Ctrl-C / SIGTERM flag by default.
    pub interrupt: &'static AtomicBool,
}

impl Default for RunnerOptions {
    fn default() -> Self {
        Self {
            supervisor: None,
            timeout: None,
            stdout_limit: STDOUT_LIMIT,
            stderr_tail: STDERR_TAIL,
            interrupt: &INTERRUPTED,
        }
    }
}

impl RunnerOptions {
    /// The timeout for `program`'s trials.
    pub fn timeout_of(&self, program: &Program) -> Duration {
        self.timeout.unwrap_or(program.timeout)
    }
}

/// What a process-protocol trial's environment names.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct TrialEnv {
    /// The seed (`QSWEEP_SEED`, and `seed` in the JSON).
    pub seed: u64,
    /// The trial's key (`QSWEEP_TRIAL`, hex).
    pub key: Key,
}

/// How long a trial took.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Timing {
    /// Wall-clock time from its start to its end (a new worker's startup counts to its first trial).
    pub wall: Duration,
    /// CPU time of the program and the children it (or its supervisor) waited for, when measured.
    pub cpu: Option<Duration>,
}

impl Timing {
    /// Wall-clock seconds (a row's `seconds`).
    pub fn seconds(&self) -> f64 {
        self.wall.as_secs_f64()
    }

    /// CPU seconds (a row's `cpu_seconds`).
    pub fn cpu_seconds(&self) -> Option<f64> {
        self.cpu.map(|d| d.as_secs_f64())
    }
}

/// Run one trial of `program` by the process protocol: `params_json` (the trial's params, a JSON
/// object; a `seed` in it is replaced by `env.seed`) plus `seed` on stdin. Returns its result as
/// docs/programs.md's failure table says, and how long it took. Blocks the calling thread until
/// the trial ends, times out, or [`RunnerOptions::interrupt`] is set.
///
/// # Panics
/// If `params_json` is not a JSON object.
pub fn run_process(
    program: &Program,
    params_json: &Value,
    env: TrialEnv,
    opts: &RunnerOptions,
) -> (TrialResult, Timing) {
    let started = Instant::now();
    let input = input_line(params_json, env.seed);
    let key = env.key.hex();
    let dir = match TrialDir::new(&key[..16]) {
        Ok(d) => d,
        Err(e) => {
            let why = format!("cannot make the trial's directory in {}: {e}", std::env::temp_dir().display());
            return (TrialResult::Unfinished(why), Timing::default());
        }
    };
    let seed = env.seed.to_string();
    let vars = [
        ("QSWEEP_SEED", OsStr::new(&seed)),
        ("QSWEEP_TRIAL", OsStr::new(&key)),
        ("QSWEEP_TRIAL_DIR", dir.path().as_os_str()),
    ];
    let mut proc = match Proc::spawn(&program.command, &vars, opts.supervisor.as_deref(), opts.stderr_tail) {
        Ok(p) => p,
        Err(e) => return (cannot_start(&program.command, &e), since(started, None)),
    };
    let timeout = opts.timeout_of(program);
    let deadline = started + timeout;
    let pumped = proc.pump(&mut &input[..], true, false, deadline, opts.stdout_limit, opts.interrupt);
    let ended = match pumped {
        Pumped::Eof => proc.reap_by(deadline, opts.interrupt),
        stopped => Err(stopped),
    };
    let (result, cpu) = match ended {
        Ok((status, cpu)) => {
            let stdout = std::mem::take(&mut proc.out);
            let parse = || match result::last_line(&stdout) {
                Some(line) => result::parse(line, &program.metrics),
                None => Err("no result line: stdout was empty".to_string()),
            };
            (judge(status, proc.err.text(), opts.interrupt, parse), cpu)
        }
        Err(why) => {
            let (_, cpu) = proc.kill_and_reap();
            proc.drain_stderr();
            (stopped(why, timeout, opts.stdout_limit, proc.err.text()), cpu)
        }
    };
    drop(dir);
    (result, since(started, Some(cpu)))
}

/// A `Timing` from `started` to now.
pub(crate) fn since(started: Instant, cpu: Option<Duration>) -> Timing {
    Timing { wall: started.elapsed(), cpu }
}

/// The line a trial's input is: `params` plus `seed`, canonical JSON (keys sorted), `\n`.
pub(crate) fn input_line(params: &Value, seed: u64) -> Vec<u8> {
    let Value::Object(object) = params else { panic!("a trial's params are a JSON object, not {params}") };
    let mut object = object.clone();
    object.insert("seed".to_string(), Value::from(seed));
    let mut line = canonical_json(&Value::Object(object));
    line.push('\n');
    line.into_bytes()
}

/// The result of a program that ended with `status`: exit 0 gives `result` (Ok, or a failure
/// naming the line and field), another code a failure with the code and `stderr_tail`, a signal
/// an unfinished trial ("interrupted" when `interrupt` is set), and a supervisor's "cannot start"
/// an unfinished one with its message.
pub(crate) fn judge(
    status: Status,
    stderr_tail: String,
    interrupt: &AtomicBool,
    result: impl FnOnce() -> Result<Vec<MetricValue>, String>,
) -> TrialResult {
    let failed = |exit_code, reason| {
        TrialResult::Failed(Failure { exit_code, reason, stderr_tail: stderr_tail.clone() })
    };
    match status {
        // Ctrl-C or SIGTERM reaches a program too (a terminal's, a Slurm step's): however it
        // ended, the trial was stopped, not failed, and runs next time.
        Status::Signal(_) | Status::Code(1..) if interrupt.load(Ordering::Relaxed) => {
            TrialResult::Unfinished("interrupted".into())
        }
        Status::Signal(sig) => TrialResult::Unfinished(format!("killed by signal {sig}{}", signal_name(sig))),
        Status::Code(0) => match result() {
            Ok(values) => TrialResult::Ok(values),
            Err(reason) => failed(None, reason),
        },
        Status::Code(CANNOT_START_CODE) if last_line_of(&stderr_tail).starts_with(CANNOT_START) => {
            TrialResult::Unfinished(last_line_of(&stderr_tail).to_string())
        }
        Status::Code(code) => failed(Some(code), format!("exit {code}")),
    }
}

/// The result of a trial qsweep stopped: timed out or interrupted (unfinished), or over the
/// stdout limit (failed).
pub(crate) fn stopped(why: Pumped, timeout: Duration, limit: usize, stderr_tail: String) -> TrialResult {
    match why {
        Pumped::Overflow => TrialResult::Failed(Failure {
            exit_code: None,
            reason: format!(
                "stdout passed its limit of {} (the result is one short line; large output belongs in files)",
                bytes(limit)
            ),
            stderr_tail,
        }),
        Pumped::Interrupted => TrialResult::Unfinished("interrupted".into()),
        _ => TrialResult::Unfinished(format!("timed out after {}", human(timeout))),
    }
}

/// The unfinished result of a program that could not be started.
pub(crate) fn cannot_start(command: &[String], e: &io::Error) -> TrialResult {
    TrialResult::Unfinished(format!("{CANNOT_START} `{}`: {e}", command.first().map_or("", String::as_str)))
}

/// The last non-empty line of `text`.
fn last_line_of(text: &str) -> &str {
    text.lines().rfind(|l| !l.trim().is_empty()).unwrap_or("").trim()
}

/// ` (SIGKILL)` for the signals people meet.
fn signal_name(sig: i32) -> &'static str {
    match sig {
        libc::SIGHUP => " (SIGHUP)",
        libc::SIGINT => " (SIGINT)",
        libc::SIGQUIT => " (SIGQUIT)",
        libc::SIGILL => " (SIGILL)",
        libc::SIGABRT => " (SIGABRT)",
        libc::SIGBUS => " (SIGBUS)",
        libc::SIGFPE => " (SIGFPE)",
        libc::SIGKILL => " (SIGKILL)",
        libc::SIGSEGV => " (SIGSEGV)",
        libc::SIGPIPE => " (SIGPIPE)",
        libc::SIGALRM => " (SIGALRM)",
        libc::SIGTERM => " (SIGTERM)",
        libc::SIGXCPU => " (SIGXCPU)",
        _ => "",
    }
}

/// `16 MiB`, `4096 bytes`.
fn bytes(n: usize) -> String {
    if n >= 1 << 20 && n.is_multiple_of(1 << 20) {
        format!("{} MiB", n >> 20)
    } else {
        format!("{n} bytes")
    }
}

/// `10m`, `90s`, `1.5s`, `2h`.
fn human(d: Duration) -> String {
    let s = d.as_secs();
    match (d.subsec_nanos(), s) {
        (0, s) if s >= 3600 && s.is_multiple_of(3600) => format!("{}h", s / 3600),
        (0, s) if s >= 60 && s.is_multiple_of(60) => format!("{}m", s / 60),
        (0, s) => format!("{s}s"),
        _ => format!("{}s", d.as_secs_f64()),
    }
}

/// A directory of a trial's (or a worker's) own under the system's temp dir, private to this
/// user, removed when dropped.
pub(crate) struct TrialDir {
    path: PathBuf,
}

impl TrialDir {
    /// A new empty directory, named after `tag`, this process and a counter.
    pub(crate) fn new(tag: &str) -> io::Result<Self> {
        use std::os::unix::fs::DirBuilderExt;
        static NEXT: AtomicU64 = AtomicU64::new(0);
        loop {
            let n = NEXT.fetch_add(1, Ordering::Relaxed);
            let path = std::env::temp_dir().join(format!("qsweep-{tag}-{}-{n}", std::process::id()));
            match std::fs::DirBuilder::new().mode(0o700).create(&path) {
                Ok(()) => return Ok(Self { path }),
                Err(e) if e.kind() == io::ErrorKind::AlreadyExists => continue,
                Err(e) => return Err(e),
            }
        }
    }

    /// Its path.
    pub(crate) fn path(&self) -> &Path {
        &self.path
    }

    /// Remove whatever is in it.
    pub(crate) fn empty(&self) -> io::Result<()> {
        if std::fs::read_dir(&self.path)?.next().is_none() {
            return Ok(());
        }
        std::fs::remove_dir_all(&self.path)?;
        use std::os::unix::fs::DirBuilderExt;
        std::fs::DirBuilder::new().mode(0o700).create(&self.path)
    }
}

impl Drop for TrialDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.path);
    }
}

#[cfg(test)]
pub(crate) mod tests;
