//! A program pipeline's processes (issue 61): no process of a program outlives a qsweep killed by
//! SIGKILL in the middle of a trial, and two runs on one empty cache start each trial once.

use crate::helpers::Sandbox;
use crate::programs::{doubler_yaml, lines, DOUBLER};
use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// Whether `pid` is gone (or a zombie that runs no more, waiting for a reaper).
fn gone(pid: i32) -> bool {
    // SAFETY: kill with signal 0 only checks.
    if unsafe { libc::kill(pid, 0) } != 0 {
        return true;
    }
    std::fs::read_to_string(format!("/proc/{pid}/stat"))
        .map_or(true, |s| s.rfind(')').is_some_and(|i| s[i + 1..].trim_start().starts_with('Z')))
}

/// The parent of `pid`, from /proc.
fn parent_of(pid: i32) -> i32 {
    let stat = std::fs::read_to_string(format!("/proc/{pid}/stat")).unwrap();
    let after = &stat[stat.rfind(')').unwrap() + 1..];
    after.split_whitespace().nth(1).unwrap().parse().unwrap()
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

/// `qsweep ARGS --cache <sandbox cache>` started in the sandbox, not waited for.
fn spawn(sb: &Sandbox, args: &[&str]) -> std::process::Child {
    Command::new(assert_cmd::cargo::cargo_bin("qsweep"))
        .current_dir(sb.dir.path())
        .args(args)
        .arg("--cache")
        .arg(sb.cache())
        .env_remove("QSWEEP_CACHE")
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap()
}

#[test]
fn program_no_process_survives_a_sigkilled_qsweep() {
    let sb = Sandbox::new();
    sb.write(
        "p.yaml",
        "name: hang\nseeds: 1\nprogram:\n  command: [sh, -c, 'echo $$ > prog.pid; sleep 100 & echo $! > sleep.pid; wait']\n  \
         metrics: { y: int }\nparams: { x: 1 }\nexperiments:\n  - { id: e, vary: { x: [1] } }\n",
    );
    let mut qsweep = spawn(&sb, &["run", "p.yaml"]);
    let program = pid_in(&sb.path("prog.pid"));
    let sleep = pid_in(&sb.path("sleep.pid"));
    let supervisor = parent_of(program);
    assert_ne!(supervisor, qsweep.id() as i32, "the program runs under its supervisor");
    assert!(![program, sleep, supervisor].into_iter().any(gone));
    qsweep.kill().unwrap(); // SIGKILL: qsweep runs nothing after it
    qsweep.wait().unwrap();
    let end = Instant::now() + Duration::from_secs(2);
    let mut left: Vec<i32> = vec![program, sleep, supervisor];
    while !left.is_empty() && Instant::now() < end {
        left.retain(|&p| !gone(p));
        std::thread::sleep(Duration::from_millis(10));
    }
    assert!(left.is_empty(), "still running 2 s after qsweep was SIGKILLed: {left:?}");
    // Nothing was stored: the trial runs next time.
    let status = crate::helpers::stdout(&mut sb.qsweep(&["status", "p.yaml"]));
    assert!(status.contains("1 missing"), "{status}");
}

#[test]
fn program_two_concurrent_runs_on_one_empty_cache_start_each_trial_once() {
    let sb = Sandbox::new();
    // Each trial takes a moment, so the two runs overlap.
    sb.write("prog.sh", &format!("sleep 0.2\n{DOUBLER}"));
    sb.write("p.yaml", &doubler_yaml("shared", "1, 2, 3, 4, 5, 6", 2));
    let runs: Vec<_> =
        (0..2).map(|_| spawn(&sb, &["run", "p.yaml", "--jobs", "2", "--json", "--no-report"])).collect();
    let mut executed = 0;
    for r in runs {
        let out = r.wait_with_output().unwrap();
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
        let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        executed += v["executed"].as_u64().unwrap();
    }
    assert_eq!(lines(&sb.path("trials.log")), 12, "a trial started twice");
    assert_eq!(executed, 12);
    let status = crate::helpers::stdout(&mut sb.qsweep(&["status", "p.yaml"]));
    assert!(status.contains("total: 12 trials, 12 cached (0 failed), 0 missing"), "{status}");
}
