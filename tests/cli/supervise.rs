//! `qsweep __supervise`, the parent of every program a program pipeline runs: no process of the
//! program outlives qsweep, even a qsweep killed by SIGKILL; and the process and worker protocols
//! run through it (the library's runner with the real binary as its supervisor) as they do without
//! it (the pipeline crate's own tests, which cannot run the binary).

use qsweep_pipeline::cache::Key;
use qsweep_pipeline::program::model::{Failure, MetricType, MetricValue, Program, Protocol, TrialResult};
use qsweep_pipeline::program::runner::{run_process, RunnerOptions, TrialEnv};
use qsweep_pipeline::program::worker::Worker;
use serde_json::json;
use std::io::{BufRead, BufReader};
use std::os::unix::process::CommandExt;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

fn qsweep_bin() -> PathBuf {
    assert_cmd::cargo::cargo_bin("qsweep")
}

/// Runner options with the real binary as the supervisor.
fn supervised() -> RunnerOptions {
    RunnerOptions { supervisor: Some(qsweep_bin()), ..Default::default() }
}

/// `sh -c SCRIPT` as a program reporting `metrics`.
fn sh(script: &str, metrics: &[(&str, MetricType)]) -> Program {
    Program {
        command: vec!["sh".into(), "-c".into(), script.into()],
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

fn run(p: &Program, opts: &RunnerOptions) -> TrialResult {
    run_process(p, &json!({"x": 1}), TrialEnv { seed: 9, key: Key([1; 32]) }, opts).0
}

/// Whether `pid` is gone (or a zombie that runs no more, waiting for a reaper).
fn gone(pid: i32) -> bool {
    // SAFETY: kill with signal 0 only checks.
    if unsafe { libc::kill(pid, 0) } != 0 {
        return true;
    }
    std::fs::read_to_string(format!("/proc/{pid}/stat"))
        .map_or(true, |s| s.rfind(')').is_some_and(|i| s[i + 1..].trim_start().starts_with('Z')))
}

/// Wait up to `within` for every pid to be gone.
fn all_gone_within(pids: &[i32], within: Duration) -> Vec<i32> {
    let end = Instant::now() + within;
    loop {
        let left: Vec<i32> = pids.iter().copied().filter(|&p| !gone(p)).collect();
        if left.is_empty() || Instant::now() >= end {
            return left;
        }
        std::thread::sleep(Duration::from_millis(10));
    }
}

/// The pid a program wrote into `path`, waiting up to 20 s for it.
fn pid_in(path: &Path) -> i32 {
    let end = Instant::now() + Duration::from_secs(20);
    loop {
        if let Some(pid) = std::fs::read_to_string(path).ok().and_then(|s| s.trim().parse().ok()) {
            return pid;
        }
        assert!(Instant::now() < end, "{} never written", path.display());
        std::thread::sleep(Duration::from_millis(10));
    }
}

/// The supervisor started the way qsweep starts it, by a Python process holding the lifeline's
/// write end: it forks, puts the read end on fd 3, execs `qsweep __supervise`, prints its pid and
/// sleeps until killed.
const PARENT: &str = r#"
import os, sys, time
qsweep, script = sys.argv[1], sys.argv[2]
r, w = os.pipe()
pid = os.fork()
if pid == 0:
    os.dup2(r, 3)
    os.set_inheritable(3, True)
    os.execv(qsweep, [qsweep, "__supervise", "--", "sh", "-c", script])
os.close(r)
print(pid, flush=True)
time.sleep(1000)
"#;

#[test]
fn no_program_process_outlives_a_sigkilled_qsweep() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path().display();
    let script = format!("echo $$ > {d}/pid; sleep 100 & echo $! > {d}/grandchild; wait");
    let mut parent = Command::new("python3")
        .args(["-c", PARENT])
        .arg(qsweep_bin())
        .arg(&script)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .spawn()
        .unwrap();
    let mut line = String::new();
    BufReader::new(parent.stdout.take().unwrap()).read_line(&mut line).unwrap();
    let supervisor: i32 = line.trim().parse().unwrap();
    let program = pid_in(&dir.path().join("pid"));
    let grandchild = pid_in(&dir.path().join("grandchild"));
    assert!(!gone(program) && !gone(grandchild) && !gone(supervisor));
    parent.kill().unwrap(); // SIGKILL: nothing of qsweep's runs after it
    parent.wait().unwrap();
    let left = all_gone_within(&[program, grandchild, supervisor], Duration::from_secs(2));
    assert!(left.is_empty(), "still running 2 s after their qsweep was SIGKILLed: {left:?}");
}

#[test]
fn the_supervisor_is_hidden_and_runs_only_with_a_lifeline() {
    let help = Command::new(qsweep_bin()).arg("--help").output().unwrap();
    assert!(!String::from_utf8_lossy(&help.stdout).contains("supervise"));
    let mut cmd = Command::new(qsweep_bin());
    cmd.args(["__supervise", "--", "true"]);
    // SAFETY: close is async-signal-safe; fd 3 is closed whatever the test runner left there.
    unsafe {
        cmd.pre_exec(|| {
            libc::close(3);
            Ok(())
        });
    }
    let out = cmd.output().unwrap();
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("no lifeline on fd 3"), "{err}");
}

#[test]
fn a_supervised_program_ends_as_the_program_did() {
    let opts = supervised();
    let ok = sh("read line; echo \"log: $line\"; echo '{\"x\": '$QSWEEP_SEED'}'", &[("x", MetricType::Int)]);
    assert_eq!(run(&ok, &opts), TrialResult::Ok(vec![MetricValue::Int(9)]));
    let code = sh("echo 'went wrong' >&2; exit 7", &[]);
    assert_eq!(
        run(&code, &opts),
        TrialResult::Failed(Failure {
            exit_code: Some(7),
            reason: "exit 7".into(),
            stderr_tail: "went wrong\n".into()
        })
    );
    let signal = sh("kill -USR1 $$", &[]);
    assert_eq!(run(&signal, &opts), TrialResult::Unfinished(format!("killed by signal {}", libc::SIGUSR1)));
    let mut missing = sh("", &[]);
    missing.command = vec!["/nonexistent/qsweep-test-program".into()];
    let TrialResult::Unfinished(why) = run(&missing, &opts) else { panic!() };
    assert!(why.starts_with("qsweep: cannot start `/nonexistent/qsweep-test-program`: "), "{why}");
    let flood = sh("head -c 20971520 /dev/zero; sleep 30", &[]);
    let start = Instant::now();
    let TrialResult::Failed(f) = run(&flood, &opts) else { panic!() };
    assert!(f.reason.starts_with("stdout passed its limit of 16 MiB"), "{}", f.reason);
    assert!(start.elapsed() < Duration::from_secs(10));
}

#[test]
fn a_supervised_timeout_or_interrupt_ends_the_whole_group() {
    static STOP: AtomicBool = AtomicBool::new(false);
    let dir = tempfile::tempdir().unwrap();
    for (name, opts) in [
        ("timeout", RunnerOptions { timeout: Some(Duration::from_secs(1)), ..supervised() }),
        ("interrupt", RunnerOptions { interrupt: &STOP, ..supervised() }),
    ] {
        let d = dir.path().join(name);
        std::fs::create_dir(&d).unwrap();
        let d = d.display();
        let p = sh(&format!("echo $$ > {d}/pid; sleep 100 & echo $! > {d}/grandchild; sleep 30"), &[]);
        let setter = std::thread::spawn(move || {
            std::thread::sleep(Duration::from_millis(500));
            if name == "interrupt" {
                STOP.store(true, Ordering::Relaxed);
            }
        });
        let start = Instant::now();
        let r = run(&p, &opts);
        setter.join().unwrap();
        let expected = if name == "timeout" { "timed out after 1s" } else { "interrupted" };
        assert_eq!(r, TrialResult::Unfinished(expected.into()));
        assert!(start.elapsed() < Duration::from_secs(5), "{name}: {:?}", start.elapsed());
        let pids =
            [pid_in(&dir.path().join(name).join("pid")), pid_in(&dir.path().join(name).join("grandchild"))];
        let left = all_gone_within(&pids, Duration::from_secs(2));
        assert!(left.is_empty(), "{name}: still running: {left:?}");
    }
}

#[test]
fn a_supervised_worker_runs_many_trials_and_is_restarted_after_a_crash() {
    let script = r#"
import json, os, sys, time
for line in sys.stdin:
    cfg = json.loads(line)
    if cfg["x"] == 2:
        print("boom", file=sys.stderr)
        sys.exit(4)
    t = time.process_time()
    while time.process_time() - t < 0.05:
        pass
    print(json.dumps({"pid": os.getpid(), "y": cfg["x"] + cfg["seed"]}), flush=True)
"#;
    let mut p = sh("", &[("pid", MetricType::Int), ("y", MetricType::Int)]);
    p.command = vec!["python3".into(), "-c".into(), script.into()];
    p.protocol = Protocol::Worker;
    let mut w = Worker::new(&p, 0, supervised());
    let mut pids = Vec::new();
    for x in [1, 3, 2, 4] {
        let (r, timing) = w.run(&json!({ "x": x }), 10);
        match r {
            TrialResult::Ok(v) => {
                let [MetricValue::Int(pid), MetricValue::Int(y)] = v[..] else { panic!("{v:?}") };
                assert_eq!(y, x + 10);
                pids.push(pid);
                if cfg!(target_os = "linux") {
                    let cpu = timing.cpu.expect("a worker's CPU time is measured on Linux");
                    assert!(cpu >= Duration::from_millis(45), "{cpu:?}");
                }
            }
            other => {
                assert_eq!(x, 2);
                let expected =
                    Failure { exit_code: Some(4), reason: "exit 4".into(), stderr_tail: "boom\n".into() };
                assert_eq!(other, TrialResult::Failed(expected));
            }
        }
    }
    assert_eq!(pids[0], pids[1], "one process for the trials before the crash");
    assert_ne!(pids[1], pids[2], "a new one after it");
    drop(w);
    let left = all_gone_within(&[pids[2] as i32], Duration::from_secs(2));
    assert!(left.is_empty(), "a dropped worker's process ends");
}
