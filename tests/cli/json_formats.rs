//! The `--json` formats of `run`, `status`, `trial` and `bench` (docs/json.md): each is one
//! object with `format_version` 1 and exactly the documented fields, and parses as the library's
//! struct for it.

use crate::helpers::{qsweep, stdout, Sandbox};
use qsweep::json::{BenchReport, RunSummary, StatusReport, TrialReport};
use serde_json::Value;

/// The object's keys, sorted.
fn keys(v: &Value) -> Vec<&str> {
    let mut k: Vec<&str> = v.as_object().expect("a JSON object").keys().map(String::as_str).collect();
    k.sort_unstable();
    k
}

#[test]
fn run_json_is_format_1() {
    let sb = Sandbox::new();
    let p = sb.fixture("tiny.yaml");
    let v = sb.run_json(&p, &["--set", "seeds=1"]);
    assert_eq!(v["format_version"], 1);
    assert_eq!(
        keys(&v),
        ["cached", "elsewhere", "executed", "failed", "format_version", "interrupted", "pipeline", "seconds"]
    );
    let s: RunSummary = serde_json::from_value(v).unwrap();
    assert_eq!(s.format_version, RunSummary::FORMAT_VERSION);
    assert_eq!(
        (s.pipeline.as_str(), s.executed, s.cached, s.failed, s.interrupted),
        ("tiny", 28, 0, 0, false)
    );
}

#[test]
fn status_json_is_format_1() {
    let sb = Sandbox::new();
    let p = sb.fixture("tiny.yaml");
    let v: Value =
        serde_json::from_str(&stdout(&mut sb.qsweep(&["status", p.to_str().unwrap(), "--json"]))).unwrap();
    assert_eq!(v["format_version"], 1);
    assert_eq!(
        keys(&v),
        [
            "cached",
            "damaged_segments",
            "experiments",
            "format_version",
            "missing",
            "pipeline",
            "running_elsewhere",
            "trials"
        ]
    );
    assert_eq!(
        keys(&v["experiments"][0]),
        ["cached", "cells", "experiment", "missing", "repr", "system", "trials"]
    );
    let s: StatusReport = serde_json::from_value(v).unwrap();
    assert_eq!(s.format_version, StatusReport::FORMAT_VERSION);
    assert_eq!((s.trials, s.cached, s.missing, s.experiments.len()), (56, 0, 56, 4));
}

#[test]
fn trial_json_is_format_1() {
    let out = stdout(qsweep().args([
        "trial",
        "--env",
        "ball-beam",
        "--repr",
        "crisp",
        "--resolution",
        "3",
        "--algorithm",
        "q0",
        "--max-episodes",
        "3",
        "--json",
    ]));
    let v: Value = serde_json::from_str(&out).unwrap();
    assert_eq!(v["format_version"], 1);
    assert_eq!(keys(&v), ["config", "format_version", "outcome", "seconds", "seed"]);
    let t: TrialReport = serde_json::from_value(v).unwrap();
    assert_eq!(t.format_version, TrialReport::FORMAT_VERSION);
    assert_eq!(t.outcome.episodes, 3);
    assert_eq!(t.outcome.episode_lengths.iter().map(|&n| u64::from(n)).sum::<u64>(), t.outcome.total_steps);
}

#[test]
fn bench_json_is_format_1() {
    let out = stdout(qsweep().args([
        "bench",
        "--steps",
        "1000",
        "--repeat",
        "1",
        "--filter",
        "ball-beam/crisp/q0/",
        "--json",
    ]));
    let v: Value = serde_json::from_str(&out).unwrap();
    assert_eq!(v["format_version"], 1);
    assert_eq!(keys(&v), ["format_version", "results"]);
    assert_eq!(keys(&v["results"][0]), ["config", "seconds", "steps", "steps_per_s"]);
    let b: BenchReport = serde_json::from_value(v).unwrap();
    assert_eq!(b.format_version, BenchReport::FORMAT_VERSION);
    assert!(!b.results.is_empty());
    assert!(b.results.iter().all(|r| r.config.starts_with("ball-beam/crisp/q0/") && r.steps >= 1000));
}

/// A program pipeline's `run --json` and `status --json` (docs/json.md): format 1, the
/// documented fields, and the library's structs.
#[test]
fn program_run_and_status_json_are_format_1() {
    use crate::programs::{doubler_yaml, DOUBLER};
    use qsweep::json::ProgramStatusReport;
    let sb = Sandbox::new();
    sb.write("prog.sh", DOUBLER);
    sb.write("d.yaml", &doubler_yaml("dj", "1, 2", 2));
    let v: Value =
        serde_json::from_str(&stdout(&mut sb.qsweep(&["run", "d.yaml", "--json", "--no-report"]))).unwrap();
    assert_eq!(
        keys(&v),
        [
            "cached",
            "elsewhere",
            "executed",
            "failed",
            "format_version",
            "interrupted",
            "pipeline",
            "seconds",
            "unfinished"
        ]
    );
    let s: RunSummary = serde_json::from_value(v).unwrap();
    assert_eq!((s.executed, s.cached, s.failed, s.unfinished), (4, 0, 0, Some(0)));
    let v: Value = serde_json::from_str(&stdout(&mut sb.qsweep(&["status", "d.yaml", "--json"]))).unwrap();
    assert_eq!(
        keys(&v),
        [
            "cached",
            "damaged_segments",
            "experiments",
            "failed",
            "folder",
            "format_version",
            "missing",
            "other_schemas",
            "pipeline",
            "running_elsewhere",
            "trials"
        ]
    );
    assert_eq!(keys(&v["experiments"][0]), ["cached", "cells", "experiment", "failed", "missing", "trials"]);
    let s: ProgramStatusReport = serde_json::from_value(v).unwrap();
    assert_eq!((s.format_version, s.trials, s.cached, s.missing), (1, 4, 4, 0));
}
