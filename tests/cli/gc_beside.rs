//! `qsweep gc` beside live runs and reports (issue 64): it never removes a row a live run stored,
//! and a report that listed the segments gc replaces is written whole all the same; Ctrl-C stops
//! a report before its next file, and the next report completes it.
//!
//! The interleavings are made, not waited for: a run is held still with SIGSTOP while gc runs
//! (its mark's lock stays held, as a live run's does), and a report is held after it has listed
//! the segments by a named pipe in place of its statistics' memo (`_derived/<pipeline>.bin`,
//! which it opens once its scan is done and before it reads any trial or writes any file): the
//! test opens the pipe's other end once the report is waiting on it, does what it must, then
//! closes it, and the report reads an empty memo (as a first report does) and goes on.

use crate::helpers::{stdout, Sandbox};
use serde_json::Value;
use std::collections::BTreeMap;
use std::io::{BufRead, BufReader};
use std::os::unix::fs::OpenOptionsExt;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

/// `qsweep ARGS --cache <the sandbox's>` in the background, its output piped.
fn spawn(sb: &Sandbox, args: &[&str]) -> Child {
    Command::new(assert_cmd::cargo::cargo_bin("qsweep"))
        .current_dir(sb.dir.path())
        .env_remove("QSWEEP_CACHE")
        .args(args)
        .arg("--cache")
        .arg(sb.cache())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap()
}

/// Send `signal` (`-STOP`, `-INT`, …) to `child`.
fn signal(child: &Child, signal: &str) {
    let sent = Command::new("kill").args([signal, &child.id().to_string()]).status().unwrap();
    assert!(sent.success(), "kill {signal}");
}

/// Wait until `done` holds, failing after two minutes.
fn wait_for(what: &str, mut done: impl FnMut() -> bool) {
    let start = Instant::now();
    while !done() {
        assert!(start.elapsed() < Duration::from_secs(120), "waited two minutes for {what}");
        std::thread::sleep(Duration::from_millis(5));
    }
}

/// Every file under `dir` with its bytes.
fn tree(dir: &Path) -> BTreeMap<PathBuf, Vec<u8>> {
    let mut out = BTreeMap::new();
    let mut todo = vec![dir.to_path_buf()];
    while let Some(d) = todo.pop() {
        for p in std::fs::read_dir(&d).unwrap().flatten().map(|e| e.path()) {
            if p.is_dir() {
                todo.push(p);
            } else {
                out.insert(p.strip_prefix(dir).unwrap().to_path_buf(), std::fs::read(&p).unwrap());
            }
        }
    }
    out
}

/// A named pipe where the report of `pipeline` reads its statistics' memo.
fn memo_pipe(sb: &Sandbox, pipeline: &str) -> PathBuf {
    let path = sb.cache().join("_derived").join(format!("{pipeline}.bin"));
    std::fs::create_dir_all(path.parent().unwrap()).unwrap();
    let _ = std::fs::remove_file(&path);
    assert!(Command::new("mkfifo").arg(&path).status().unwrap().success(), "mkfifo");
    path
}

/// The writing end of `pipe`, once `reader` has opened it (the report is then past its scan and
/// waits for the memo's bytes until this end is closed).
fn once_reading(pipe: &Path, reader: &mut Child) -> std::fs::File {
    let mut end = None;
    wait_for("the report to open its statistics' memo", || {
        assert!(reader.try_wait().unwrap().is_none(), "the report ended before reading its memo");
        // Without a reader, opening a pipe's writing end without waiting fails (ENXIO).
        end = std::fs::OpenOptions::new().write(true).custom_flags(libc::O_NONBLOCK).open(pipe).ok();
        end.is_some()
    });
    end.unwrap()
}

/// A stopped child is continued, and a child left running killed, whatever the test does.
struct Reaped(Option<Child>);

impl Drop for Reaped {
    fn drop(&mut self) {
        if let Some(mut child) = self.0.take() {
            let _ = Command::new("kill").args(["-CONT", &child.id().to_string()]).status();
            let _ = child.kill();
            let _ = child.wait();
        }
    }
}

/// Regression (issue 64): `gc PIPELINE`, run while a run of a plan it was not given stored its
/// trials, removed the rows the run had just stored; the run ended with exit 0 and most of its
/// trials missing. Every one of them is stored now, and gc says it kept them.
#[test]
fn gc_given_another_plan_beside_a_live_run_removes_none_of_the_rows_it_stores() {
    let sb = Sandbox::new();
    let p = sb.fixture("tiny.yaml");
    let p = p.to_str().unwrap();
    // 168 trials (tiny.yaml has 2 seeds: gc given it references 56 of them), one segment each.
    let args = ["run", p, "--set", "seeds=6", "--json", "--no-report", "--jobs", "1", "--batch-trials", "1"];
    let mut run = Reaped(Some(spawn(&sb, &args)));
    let mut said = Vec::new();
    for round in 0..3 {
        let child = run.0.as_mut().unwrap();
        let enough = sb.segments() + 4;
        wait_for("the run to store more trials", || {
            sb.segments() >= enough || child.try_wait().unwrap().is_some()
        });
        if child.try_wait().unwrap().is_some() {
            assert!(round > 0, "the run ended before gc ran beside it");
            break;
        }
        // Held still, alive: its mark and leases stay locked, as while it computes.
        signal(child, "-STOP");
        said.push(stdout(&mut sb.qsweep(&["gc", p])));
        signal(child, "-CONT");
    }
    let out = run.0.take().unwrap().wait_with_output().unwrap();
    assert_eq!(out.status.code(), Some(0), "{}", String::from_utf8_lossy(&out.stderr));
    let v: Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["executed"].as_u64(), Some(168), "{v}");
    let status = stdout(&mut sb.qsweep(&["status", p, "--set", "seeds=6", "--json"]));
    let status: Value = serde_json::from_str(&status).unwrap();
    assert_eq!((status["cached"].as_u64(), status["missing"].as_u64()), (Some(168), Some(0)), "{said:?}");
    for s in &said {
        let live: u64 = s
            .split(", ")
            .find_map(|part| part.strip_suffix(" rows kept: written by a live run"))
            .unwrap_or_else(|| panic!("{s}"))
            .parse()
            .unwrap();
        assert!(live >= 4, "{s}");
        assert!(s.contains(", 0 rows kept, 0 removed"), "all of them are the live run's: {s}");
    }
    // Once the run is over its rows are ordinary rows: gc given tiny.yaml drops the other seeds.
    let after = stdout(&mut sb.qsweep(&["gc", p]));
    assert!(after.contains("56 rows kept, 112 removed (no given pipeline references them), 0 rows kept: written by a live run"), "{after}");
    assert!(!sb.cache().join("_runs").exists(), "the run's mark went with it");
}

/// Regression (issue 64): a report that had listed the cache's segments failed with `cannot read
/// cache segment …: No such file or directory` when gc compacted them before it read them. It
/// reads the segments that replaced them, and writes what it writes alone.
#[test]
fn a_report_whose_segments_gc_compacts_is_written_whole_and_byte_identical_to_one_alone() {
    let sb = Sandbox::new();
    let p = sb.fixture("tiny.yaml");
    let p = p.to_str().unwrap();
    sb.run_json(Path::new(p), &["--batch-trials", "4"]);
    let listed = sb.segment_paths();
    assert!(listed.len() > 1, "{listed:?}");
    stdout(&mut sb.qsweep(&["report", p, "--rebuild", "--out", "alone", "-q"]));
    let pipe = memo_pipe(&sb, "tiny");
    let mut report = Reaped(Some(spawn(&sb, &["report", p, "--rebuild", "--out", "beside", "-q"])));
    let end = once_reading(&pipe, report.0.as_mut().unwrap());
    let said = stdout(&mut sb.qsweep(&["gc"]));
    assert!(said.starts_with(&format!("{} segments → 1, 56 rows kept", listed.len())), "{said}");
    assert!(listed.iter().all(|s| !s.exists()), "every segment the report listed was replaced");
    drop(end);
    let out = report.0.take().unwrap().wait_with_output().unwrap();
    assert_eq!(out.status.code(), Some(0), "{}", String::from_utf8_lossy(&out.stderr));
    let (alone, beside) = (tree(&sb.path("alone")), tree(&sb.path("beside")));
    assert!(alone.contains_key(Path::new("trials.parquet")), "{:?}", alone.keys());
    assert_eq!(alone.keys().collect::<Vec<_>>(), beside.keys().collect::<Vec<_>>());
    for (file, bytes) in &alone {
        assert!(beside[file] == *bytes, "{} differs", file.display());
    }
}

/// Ctrl-C during `qsweep report` was ignored where the shell that started it ignores SIGINT (a
/// background job), and otherwise killed it. It stops before the next file, exits 130, and the
/// next report completes the folder: the same bytes as a report written in one go.
#[test]
fn ctrl_c_stops_a_report_before_its_next_file_exits_130_and_the_next_report_completes_it() {
    let sb = Sandbox::new();
    let p = sb.fixture("tiny.yaml");
    let p = p.to_str().unwrap();
    sb.run_json(Path::new(p), &[]);
    let pipe = memo_pipe(&sb, "tiny");
    let mut report = Reaped(Some(spawn(&sb, &["report", p, "--rebuild", "--out", "r", "-q"])));
    let child = report.0.as_mut().unwrap();
    let end = once_reading(&pipe, child);
    let mut stderr = BufReader::new(child.stderr.take().unwrap());
    signal(child, "-INT");
    // The report goes on only once it has taken the signal in.
    let mut said = String::new();
    while !said.contains("stopping before the next file") {
        assert!(stderr.read_line(&mut said).unwrap() > 0, "the report ended without a word: {said}");
    }
    drop(end);
    let mut child = report.0.take().unwrap();
    let status = child.wait().unwrap();
    std::io::Read::read_to_string(&mut stderr, &mut said).unwrap();
    assert_eq!(status.code(), Some(130), "{said}");
    assert!(said.contains("that report is not complete; the next report completes it"), "{said}");
    assert!(!sb.path("r/memo.json").exists(), "the folder is not marked complete");
    assert!(!sb.path("r/index.html").exists(), "stopped at the first file");
    std::fs::remove_file(&pipe).unwrap();
    stdout(&mut sb.qsweep(&["report", p, "--out", "r", "-q"]));
    stdout(&mut sb.qsweep(&["report", p, "--out", "clean", "-q"]));
    let (done, clean) = (tree(&sb.path("r")), tree(&sb.path("clean")));
    assert_eq!(done.keys().collect::<Vec<_>>(), clean.keys().collect::<Vec<_>>());
    for (file, bytes) in &clean {
        assert!(done[file] == *bytes, "{} differs", file.display());
    }
}
