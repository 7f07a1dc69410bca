//! Concurrent runs on one cache (issue 39): leases keep them from computing a trial twice, a run
//! that dies strands nothing, and the results do not depend on who ran what.

use crate::helpers::{fails_with, stdout, Sandbox};
use qsweep_pipeline::cache::leases::lease::{Holder, LEASE};
use qsweep_pipeline::cache::leases::{Leases, LEASES_DIR};
use qsweep_pipeline::cache::{Key, Store};
use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant, SystemTime};

fn count(v: &Value, field: &str) -> u64 {
    v[field].as_u64().unwrap_or_else(|| panic!("no integer `{field}` in {v}"))
}

/// Rows stored (duplicates included) and distinct keys.
fn rows_and_distinct(cache: &Path) -> (usize, usize) {
    let scan = Store::open(cache).unwrap().keys().unwrap();
    assert!(scan.damaged.is_empty());
    (scan.segments.iter().map(|(_, k)| k.len()).sum(), scan.keys.len())
}

/// Lease files left in the cache (none once every run is over).
fn lease_files(cache: &Path) -> Vec<String> {
    let Ok(dir) = std::fs::read_dir(cache.join(LEASES_DIR)) else { return Vec::new() };
    dir.map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect()
}

/// `qsweep run` in the background with the sandbox's cache.
fn spawn_run(sb: &Sandbox, pipeline: &Path, extra: &[&str]) -> Child {
    Command::new(assert_cmd::cargo::cargo_bin("qsweep"))
        .current_dir(sb.dir.path())
        .env_remove("QSWEEP_CACHE")
        .args(["run", pipeline.to_str().unwrap(), "--json", "--jobs", "1", "--batch-seconds", "0.2"])
        .args(extra)
        .arg("--cache")
        .arg(sb.cache())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap()
}

fn finish(child: Child) -> Value {
    let out = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(0), "{stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
    serde_json::from_slice(&out.stdout).unwrap_or_else(|e| panic!("{e}: {stderr}"))
}

fn concurrent_runs_compute_each_trial_once(n: usize) {
    let sb = Sandbox::new();
    let p = sb.fixture("tiny.yaml");
    let runs: Vec<Child> = (0..n)
        .map(|i| {
            let out = format!("report-{i}");
            spawn_run(&sb, &p, &["--out", &out, "--formats", "csv"])
        })
        .collect();
    let summaries: Vec<Value> = runs.into_iter().map(finish).collect();
    let executed: u64 = summaries.iter().map(|v| count(v, "executed")).sum();
    assert_eq!(rows_and_distinct(&sb.cache()), (56, 56), "{summaries:?}");
    assert_eq!(executed, 56, "every trial computed by exactly one run: {summaries:?}");
    for v in &summaries {
        assert_eq!(count(v, "executed") + count(v, "elsewhere") + count(v, "cached"), 56, "{v}");
    }
    let table = |i: usize| std::fs::read_to_string(sb.path(&format!("report-{i}/table3.csv"))).unwrap();
    for i in 1..n {
        assert_eq!(table(i), table(0), "run {i}'s table3.csv");
    }
    assert_eq!(lease_files(&sb.cache()), Vec::<String>::new());
    assert!(!sb.cache().join(LEASES_DIR).exists(), "the leases folder goes with the last run");
    // The same table as one run alone.
    let alone = Sandbox::new();
    let q = alone.fixture("tiny.yaml");
    stdout(&mut alone.qsweep(&["run", q.to_str().unwrap(), "--out", "r", "--formats", "csv", "-q"]));
    assert_eq!(std::fs::read_to_string(alone.path("r/table3.csv")).unwrap(), table(0));
}

#[test]
fn two_concurrent_runs_on_one_empty_cache_compute_each_trial_once() {
    concurrent_runs_compute_each_trial_once(2);
}

#[test]
fn four_concurrent_runs_on_one_empty_cache_compute_each_trial_once() {
    concurrent_runs_compute_each_trial_once(4);
}

/// Mountain Car trials that take a while each (two long episodes).
const SLOW: &str = "name: slow\nseeds: 24\nsystems:\n  mountain-car:\n    success: { within: 1, streak: 1, max_episode_steps: 20000 }\n    settings: { max_episodes: 2 }\n    experiments:\n      - { id: 1, repr: crisp, algorithms: [q0], vary: { x == x_dot: [2] } }\n";

#[test]
fn a_sigkilled_run_strands_nothing_the_other_finishes_and_a_restart_has_nothing_to_do() {
    let sb = Sandbox::new();
    let p = sb.write("slow.yaml", SLOW);
    let mut a = spawn_run(&sb, &p, &["--no-report"]);
    let b = spawn_run(&sb, &p, &["--no-report"]);
    let start = Instant::now();
    while sb.segments() < 2 {
        assert!(start.elapsed() < Duration::from_secs(120), "no segment was written");
        std::thread::sleep(Duration::from_millis(20));
    }
    a.kill().unwrap(); // SIGKILL: no handler runs, its leases stay on disk with their locks dropped
    a.wait().unwrap();
    let killed_at = Instant::now();
    let v = finish(b);
    assert!(killed_at.elapsed() < Duration::from_secs(120));
    assert_eq!(rows_and_distinct(&sb.cache()), (24, 24), "{v}");
    assert_eq!(lease_files(&sb.cache()), Vec::<String>::new(), "the dead run's leases were taken over");
    let again = sb.run_json(&p, &[]);
    assert_eq!((count(&again, "executed"), count(&again, "cached")), (0, 24));
}

/// The keys of tiny.yaml's trials, computed in a scratch cache.
fn tiny_records() -> Vec<qsweep_pipeline::cache::TrialRecord> {
    let sb = Sandbox::new();
    sb.run_json(&sb.fixture("tiny.yaml"), &[]);
    let mut r = Store::open(&sb.cache()).unwrap().read_all().unwrap();
    r.sort_by_key(|r| r.key);
    r
}

fn fake_lease(cache: &Path, key: &Key, holder: &Holder, age: Duration) -> PathBuf {
    let path = cache.join(LEASES_DIR).join(key.hex());
    std::fs::create_dir_all(path.parent().unwrap()).unwrap();
    std::fs::write(&path, holder.to_text()).unwrap();
    std::fs::File::options().write(true).open(&path).unwrap().set_modified(SystemTime::now() - age).unwrap();
    path
}

#[test]
fn dead_holders_leases_are_taken_over_and_gc_removes_their_debris() {
    let records = tiny_records();
    let sb = Sandbox::new();
    let p = sb.fixture("tiny.yaml");
    let here_dead = Holder { host: Holder::me().host, pid: u32::MAX - 1 };
    let there_stale = Holder { host: "node-lost-from-the-cluster".into(), pid: 7 };
    for (i, r) in records.iter().enumerate() {
        let (holder, age) = if i % 2 == 0 { (&here_dead, Duration::ZERO) } else { (&there_stale, LEASE * 2) };
        fake_lease(&sb.cache(), &r.key, holder, age);
    }
    let status: Value =
        serde_json::from_str(&stdout(&mut sb.qsweep(&["status", p.to_str().unwrap(), "--json"]))).unwrap();
    assert_eq!(count(&status, "running_elsewhere"), 0, "dead holders run nothing");
    let start = Instant::now();
    let v = sb.run_json(&p, &[]);
    assert!(start.elapsed() < Duration::from_secs(60));
    assert_eq!((count(&v, "executed"), count(&v, "elsewhere")), (56, 0));
    assert_eq!(lease_files(&sb.cache()), Vec::<String>::new());
    // Debris a killed run leaves (as above, and a temp file of a lease being made) goes with gc;
    // a live run's lease (another machine's, lease fresh) stays.
    fake_lease(&sb.cache(), &records[0].key, &here_dead, Duration::ZERO);
    fake_lease(&sb.cache(), &records[1].key, &there_stale, LEASE * 2);
    let live = Holder { host: "node-still-running".into(), pid: 9 };
    fake_lease(&sb.cache(), &records[2].key, &live, Duration::ZERO);
    let out = stdout(&mut sb.qsweep(&["gc"]));
    assert!(out.contains("2 dead runs' leases"), "{out}");
    assert_eq!(lease_files(&sb.cache()), vec![records[2].key.hex()]);
    assert!(stdout(&mut sb.qsweep(&["verify"])).contains("56"), "verify is unaffected");
}

#[test]
fn a_trial_leased_by_a_live_run_is_waited_for_and_shown_as_running_elsewhere() {
    let records = tiny_records();
    let sb = Sandbox::new();
    let p = sb.fixture("tiny.yaml");
    // This test process is the other run: it holds a lease on the first trial.
    let store = Store::open(&sb.cache()).unwrap();
    let other = Leases::open(&store).unwrap();
    assert_eq!(other.try_take(records[0].key).unwrap(), qsweep_pipeline::cache::leases::Take::Taken);
    let status = stdout(&mut sb.qsweep(&["status", p.to_str().unwrap(), "--json"]));
    let status: Value = serde_json::from_str(&status).unwrap();
    assert_eq!((count(&status, "missing"), count(&status, "running_elsewhere")), (56, 1));
    let text = stdout(&mut sb.qsweep(&["status", p.to_str().unwrap()]));
    assert!(text.contains("56 missing, 1 of them running elsewhere"), "{text}");
    let run = spawn_run(&sb, &p, &["--no-report"]);
    // The run does the other 55 and waits; then "the other run" stores its trial and lets go.
    let start = Instant::now();
    while rows_and_distinct(&sb.cache()).1 < 55 {
        assert!(start.elapsed() < Duration::from_secs(120), "the other 55 trials were not stored");
        std::thread::sleep(Duration::from_millis(50));
    }
    std::thread::sleep(Duration::from_millis(300));
    store.write_segment(&records[..1]).unwrap();
    other.release(&[records[0].key]);
    let v = finish(run);
    assert_eq!((count(&v, "executed"), count(&v, "elsewhere")), (55, 1), "{v}");
    assert_eq!(rows_and_distinct(&sb.cache()), (56, 56));
}

#[test]
fn a_cache_that_is_a_file_or_unwritable_is_a_usage_error() {
    let sb = Sandbox::new();
    let p = sb.fixture("tiny.yaml");
    let file = sb.write("cfile", "not a cache");
    let run = |cache: &Path| {
        let mut c = crate::helpers::qsweep();
        c.current_dir(sb.dir.path()).args(["run", p.to_str().unwrap(), "--cache"]).arg(cache);
        fails_with(&mut c, 2)
    };
    let err = run(&file);
    assert!(err.contains("is a file, not a directory") && err.contains("--cache DIR"), "{err}");
    let err = run(&file.join("sub"));
    assert!(err.contains("cannot be made") && err.contains("--cache DIR"), "{err}");
    // Unwritable: only testable where permissions bind (not as root).
    let ro = sb.path("ro");
    std::fs::create_dir(&ro).unwrap();
    let mut perms = std::fs::metadata(&ro).unwrap().permissions();
    std::os::unix::fs::PermissionsExt::set_mode(&mut perms, 0o555);
    std::fs::set_permissions(&ro, perms).unwrap();
    if std::fs::File::create(ro.join("probe")).is_err() {
        let err = run(&ro);
        assert!(err.contains("cannot be written") && err.contains("permissions"), "{err}");
    }
}
