//! The process protocol end to end with small shell and Python programs, started directly (the
//! library's way, without a supervisor); tests/cli/supervise.rs runs the same cases through
//! `qsweep __supervise`.

use super::*;
use crate::program::model::{MetricType, MetricValue, Program, Protocol};
use serde_json::json;
use std::path::Path;
use std::time::{Duration, Instant};

/// `script` written into `dir` and run by `interpreter` (`sh` or `python3`), reporting `metrics`.
pub(crate) fn program(
    dir: &Path,
    interpreter: &str,
    script: &str,
    metrics: &[(&str, MetricType)],
) -> Program {
    let path = dir.join(if interpreter == "python3" { "prog.py" } else { "prog.sh" });
    std::fs::write(&path, script).unwrap();
    Program {
        command: vec![interpreter.into(), path.to_string_lossy().into_owned()],
        input_globs: vec![],
        inputs: vec![],
        protocol: Protocol::Process,
        timeout: Duration::from_secs(30),
        metrics: metrics.iter().map(|(n, t)| (n.to_string(), *t)).collect(),
        objective: None,
        provenance: vec![],
        provenance_outputs: vec![],
    }
}

/// Whether `pid` is gone (or a zombie nobody has reaped yet: it runs no more).
pub(crate) fn gone(pid: i32) -> bool {
    // SAFETY: kill with signal 0 only checks.
    if unsafe { libc::kill(pid, 0) } != 0 && io::Error::last_os_error().raw_os_error() == Some(libc::ESRCH) {
        return true;
    }
    std::fs::read_to_string(format!("/proc/{pid}/stat"))
        .map_or(true, |s| s.rfind(')').is_some_and(|i| s[i + 1..].trim_start().starts_with('Z')))
}

/// Wait up to `within` for `pid` to be gone.
pub(crate) fn gone_within(pid: i32, within: Duration) -> bool {
    let end = Instant::now() + within;
    while Instant::now() < end {
        if gone(pid) {
            return true;
        }
        std::thread::sleep(Duration::from_millis(10));
    }
    gone(pid)
}

/// The pid a program wrote into `path`.
pub(crate) fn pid_in(path: &Path) -> i32 {
    std::fs::read_to_string(path).unwrap().trim().parse().unwrap()
}

fn run(p: &Program, params: Value, opts: &RunnerOptions) -> (TrialResult, Timing) {
    run_process(p, &params, TrialEnv { seed: 3, key: Key([7; 32]) }, opts)
}

fn failed(r: TrialResult) -> Failure {
    match r {
        TrialResult::Failed(f) => f,
        other => panic!("expected a failure, got {other:?}"),
    }
}

fn unfinished(r: TrialResult) -> String {
    match r {
        TrialResult::Unfinished(why) => why,
        other => panic!("expected an unfinished trial, got {other:?}"),
    }
}

#[test]
fn a_valid_result_gives_typed_metrics_and_the_program_sees_the_protocol() {
    let dir = tempfile::tempdir().unwrap();
    let script = r#"
import json, os, sys
raw = sys.stdin.read()
cfg = json.loads(raw)
print("a log line on stdout")
print("a log line on stderr", file=sys.stderr)
d = os.environ["QSWEEP_TRIAL_DIR"]
print(json.dumps({"raw": raw, "alpha": cfg["alpha"], "seed": cfg["seed"], "env_seed": int(os.environ["QSWEEP_SEED"]),
                  "trial": os.environ["QSWEEP_TRIAL"], "dir": d, "dir_empty": os.listdir(d) == [], "cwd": os.getcwd()}))
print()
"#;
    use MetricType::*;
    let metrics = [
        ("raw", Str),
        ("alpha", Float),
        ("seed", Int),
        ("env_seed", Int),
        ("trial", Str),
        ("dir", Str),
        ("dir_empty", Bool),
        ("cwd", Str),
    ];
    let p = program(dir.path(), "python3", script, &metrics);
    // A `seed` among the params is the trial's seed in what the program reads.
    let (r, timing) = run(&p, json!({"bins": 6, "alpha": 0.5, "seed": 99}), &RunnerOptions::default());
    let TrialResult::Ok(v) = r else { panic!("{r:?}") };
    assert_eq!(
        v[0],
        MetricValue::Str("{\"alpha\":0.5,\"bins\":6,\"seed\":3}\n".into()),
        "canonical JSON, one line"
    );
    assert_eq!(&v[1..4], &[MetricValue::Float(0.5), MetricValue::Int(3), MetricValue::Int(3)]);
    assert_eq!(v[4], MetricValue::Str("07".repeat(32)));
    let MetricValue::Str(trial_dir) = &v[5] else { panic!() };
    assert_eq!(v[6], MetricValue::Bool(true));
    assert_eq!(v[7], MetricValue::Str(std::env::current_dir().unwrap().to_string_lossy().into_owned()));
    assert!(!Path::new(trial_dir).exists(), "the trial's directory is removed after it");
    assert!(timing.wall > Duration::ZERO);
    assert!(timing.cpu.is_some_and(|c| c > Duration::ZERO), "{timing:?}");
}

#[test]
fn a_non_zero_exit_fails_with_its_code_and_stderr_tail() {
    let dir = tempfile::tempdir().unwrap();
    let p = program(
        dir.path(),
        "sh",
        "echo '{\"x\": 1}'\necho 'it broke' >&2\nexit 3\n",
        &[("x", MetricType::Int)],
    );
    let f = failed(run(&p, json!({}), &RunnerOptions::default()).0);
    assert_eq!(f, Failure { exit_code: Some(3), reason: "exit 3".into(), stderr_tail: "it broke\n".into() });
    // Only the tail of a long stderr is kept.
    let p =
        program(dir.path(), "sh", "head -c 100000 /dev/zero | tr '\\0' a >&2\necho end >&2\nexit 1\n", &[]);
    let f = failed(run(&p, json!({}), &RunnerOptions::default()).0);
    assert_eq!(f.stderr_tail.len(), STDERR_TAIL);
    assert!(f.stderr_tail.starts_with("aaa") && f.stderr_tail.ends_with("aaaend\n"), "{}", f.stderr_tail);
}

#[test]
fn a_malformed_result_fails_naming_the_line_and_the_field() {
    let dir = tempfile::tempdir().unwrap();
    let cases = [
        ("echo 'not json'", "result line `not json`: not JSON ("),
        ("echo '[1]'", "result line `[1]`: not a JSON object but a list"),
        (
            "echo '{\"x\": 1, \"y\": 2}'",
            "result line `{\"x\": 1, \"y\": 2}`: undeclared metric `y` (declared: x)",
        ),
        ("echo '{}'", "result line `{}`: missing metric `x` (int)"),
        (
            "echo '{\"x\": 1.5}'",
            "result line `{\"x\": 1.5}`: metric `x` should be an integer (int64) but is 1.5",
        ),
        ("echo 'log only' >&2 # and no stdout", "no result line: stdout was empty"),
    ];
    for (script, why) in cases {
        // Earlier lines are the program's log, whatever they hold.
        let log = if script.contains("no stdout") { "" } else { "echo '{\"x\": 1} (a log line)'" };
        let p = program(dir.path(), "sh", &format!("{log}\n{script}\n"), &[("x", MetricType::Int)]);
        let f = failed(run(&p, json!({}), &RunnerOptions::default()).0);
        assert_eq!(f.exit_code, None, "{script}");
        assert!(f.reason.starts_with(why), "{script}: {}", f.reason);
    }
}

#[test]
fn stdout_over_the_limit_fails_without_waiting_for_the_rest() {
    let dir = tempfile::tempdir().unwrap();
    // 20 MiB, then the program would go on for 30 s: reading stops at the limit and the program
    // is killed, so memory stays bounded and the trial ends at once.
    let p = program(dir.path(), "sh", "head -c 20971520 /dev/zero\necho '{\"x\": 1}'\nsleep 30\n", &[]);
    let start = Instant::now();
    let f = failed(run(&p, json!({}), &RunnerOptions::default()).0);
    assert!(start.elapsed() < Duration::from_secs(10), "{:?}", start.elapsed());
    assert_eq!(f.exit_code, None);
    assert!(f.reason.starts_with("stdout passed its limit of 16 MiB"), "{}", f.reason);
    let opts = RunnerOptions { stdout_limit: 1000, ..Default::default() };
    let p = program(dir.path(), "sh", "head -c 1001 /dev/zero\n", &[]);
    assert!(failed(run(&p, json!({}), &opts).0).reason.contains("limit of 1000 bytes"));
    let p = program(dir.path(), "sh", "head -c 990 /dev/zero | tr '\\0' ' '\necho '{}'\n", &[]);
    assert_eq!(run(&p, json!({}), &opts).0, TrialResult::Ok(vec![]), "at the limit is fine");
}

#[test]
fn a_timeout_ends_the_program_and_its_background_children_quickly() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path().display();
    let script = format!("echo $$ > {d}/pid\nsleep 100 &\necho $! > {d}/grandchild\nsleep 30\n");
    let p = program(dir.path(), "sh", &script, &[]);
    let opts = RunnerOptions { timeout: Some(Duration::from_secs(1)), ..Default::default() };
    let start = Instant::now();
    let why = unfinished(run(&p, json!({}), &opts).0);
    assert_eq!(why, "timed out after 1s");
    assert!(start.elapsed() < Duration::from_secs(5), "{:?}", start.elapsed());
    for file in ["pid", "grandchild"] {
        let pid = pid_in(&dir.path().join(file));
        assert!(gone_within(pid, Duration::from_secs(2)), "{file} {pid} is still running");
    }
}

#[test]
fn an_interrupt_ends_a_running_trial_as_unfinished() {
    static STOP: AtomicBool = AtomicBool::new(false);
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path().display();
    let p = program(dir.path(), "sh", &format!("echo $$ > {d}/pid\nsleep 30\n"), &[]);
    let opts = RunnerOptions { interrupt: &STOP, ..Default::default() };
    let setter = std::thread::spawn(|| {
        std::thread::sleep(Duration::from_millis(300));
        STOP.store(true, Ordering::Relaxed);
    });
    let start = Instant::now();
    assert_eq!(unfinished(run(&p, json!({}), &opts).0), "interrupted");
    assert!(start.elapsed() < Duration::from_secs(5), "{:?}", start.elapsed());
    setter.join().unwrap();
    assert!(gone_within(pid_in(&dir.path().join("pid")), Duration::from_secs(2)));
}

#[test]
fn a_program_killed_by_a_signal_is_unfinished() {
    let dir = tempfile::tempdir().unwrap();
    let p = program(dir.path(), "sh", "echo '{}'\nkill -9 $$\n", &[]);
    assert_eq!(unfinished(run(&p, json!({}), &RunnerOptions::default()).0), "killed by signal 9 (SIGKILL)");
}

#[test]
fn a_program_that_cannot_start_is_unfinished() {
    let mut p = program(Path::new("/"), "sh", "", &[]);
    p.command = vec!["/nonexistent/qsweep-test-program".into()];
    let why = unfinished(run(&p, json!({}), &RunnerOptions::default()).0);
    assert!(why.starts_with("qsweep: cannot start `/nonexistent/qsweep-test-program`: "), "{why}");
}

#[test]
fn a_background_child_holding_stdout_does_not_hold_the_trial() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path().display();
    let p = program(dir.path(), "sh", &format!("sleep 30 &\necho $! > {d}/bg\necho '{{}}'\n"), &[]);
    let start = Instant::now();
    assert_eq!(run(&p, json!({}), &RunnerOptions::default()).0, TrialResult::Ok(vec![]));
    assert!(start.elapsed() < Duration::from_secs(5), "{:?}", start.elapsed());
    assert!(gone_within(pid_in(&dir.path().join("bg")), Duration::from_secs(2)));
}

#[test]
fn a_program_that_does_not_read_its_input_still_gives_its_result() {
    let dir = tempfile::tempdir().unwrap();
    let p = program(dir.path(), "sh", "echo '{}'\n", &[]);
    // More than a pipe holds: the write meets a closed pipe (EPIPE), which ends nothing.
    let (r, _) = run(&p, json!({"blob": "x".repeat(1 << 20)}), &RunnerOptions::default());
    assert_eq!(r, TrialResult::Ok(vec![]));
}

#[test]
fn cpu_time_comes_from_the_programs_rusage() {
    let dir = tempfile::tempdir().unwrap();
    let script =
        "import time\nt = time.process_time()\nwhile time.process_time() - t < 0.2: pass\nprint('{}')\n";
    let p = program(dir.path(), "python3", script, &[]);
    let (r, timing) = run(&p, json!({}), &RunnerOptions::default());
    assert_eq!(r, TrialResult::Ok(vec![]));
    let cpu = timing.cpu.unwrap();
    assert!(cpu >= Duration::from_millis(190), "{cpu:?}");
    assert!(timing.wall >= Duration::from_millis(190));
}

#[test]
fn timeouts_and_sizes_read_as_people_write_them() {
    assert_eq!(human(Duration::from_secs(600)), "10m");
    assert_eq!(human(Duration::from_secs(7200)), "2h");
    assert_eq!(human(Duration::from_secs(90)), "90s");
    assert_eq!(human(Duration::from_millis(1500)), "1.5s");
    assert_eq!(bytes(STDOUT_LIMIT), "16 MiB");
    assert_eq!(bytes(4096), "4096 bytes");
}
