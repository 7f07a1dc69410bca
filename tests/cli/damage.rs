//! A damaged cache and diverging trials: detected, reported with paths, moved aside, recomputed;
//! never served and never a panic.

use crate::helpers::{stdout, Sandbox};
use serde_json::Value;
use std::path::PathBuf;

fn segments(sb: &Sandbox) -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(sb.cache())
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.file_name().unwrap().to_string_lossy().starts_with("seg-"))
        .collect();
    v.sort();
    v
}

#[test]
fn truncated_and_garbage_segments_are_quarantined_and_their_trials_recomputed() {
    let sb = Sandbox::new();
    let p = sb.fixture("tiny.yaml");
    sb.run_json(&p, &["--batch-trials", "10"]);
    let segs = segments(&sb);
    assert!(segs.len() >= 5);
    // Truncate one real segment (its 10 trials are lost) and add garbage.
    let bytes = std::fs::read(&segs[0]).unwrap();
    std::fs::write(&segs[0], &bytes[..bytes.len() / 2]).unwrap();
    std::fs::write(sb.cache().join("seg-garbage.parquet"), b"PAR1 not really").unwrap();

    let out = sb.qsweep(&["verify"]).assert().code(1).get_output().stdout.clone();
    let out = String::from_utf8(out).unwrap();
    assert!(out.contains(&format!("damaged: {}", segs[0].display())), "{out}");
    assert!(out.contains("seg-garbage.parquet"), "{out}");
    assert!(out.contains("46 rows (46 distinct trials) intact, 2 damaged"), "{out}");
    assert!(sb.cache().join("_quarantine").join("seg-garbage.parquet").is_file());
    let again = stdout(&mut sb.qsweep(&["verify"]));
    assert!(again.contains("0 damaged"), "{again}");

    let v = sb.run_json(&p, &[]);
    assert_eq!((v["executed"].as_u64(), v["cached"].as_u64()), (Some(10), Some(46)));
}

#[test]
fn run_moves_an_unreadable_segment_aside_with_a_warning() {
    let sb = Sandbox::new();
    let p = sb.fixture("tiny.yaml");
    sb.run_json(&p, &[]);
    std::fs::write(sb.cache().join("seg-zzz.parquet"), b"garbage").unwrap();
    let out = sb.qsweep(&["run", p.to_str().unwrap(), "--no-report"]).assert().success().get_output().clone();
    let err = String::from_utf8(out.stderr).unwrap();
    assert!(err.contains("warning: damaged cache segment") && err.contains("seg-zzz.parquet"), "{err}");
    assert!(String::from_utf8(out.stdout).unwrap().contains("executed 0, cached 56"));
    assert!(!sb.cache().join("seg-zzz.parquet").exists());
}

#[test]
fn diverging_trials_are_stored_as_failed_and_the_run_exits_1() {
    let sb = Sandbox::new();
    let p = sb.write(
        "absurd.yaml",
        "name: absurd\nseeds: 2\nsystems:\n  cart-pole:\n    params: { gravity: 1.0e308 }\n    settings: { max_episodes: 5 }\n    experiments:\n      - { id: 1, repr: crisp, vary: { x == x_dot == theta == theta_dot: [2] } }\n",
    );
    let out = sb.qsweep(&["run", p.to_str().unwrap(), "--json"]).assert().code(1).get_output().clone();
    let v: Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!((v["executed"].as_u64(), v["failed"].as_u64()), (Some(4), Some(4)), "{v}");
    let err = String::from_utf8(out.stderr).unwrap();
    assert!(err.contains("4 trials failed"), "{err}");
    let recs = qsweep::cache::Store::open(&sb.cache()).unwrap().read_all().unwrap();
    assert!(recs.iter().all(|r| r.outcome.failure.as_deref().is_some_and(|f| f.contains("non-finite"))));
    // Failed trials are results too: a rerun serves them from the cache.
    let v = sb.run_json(&p, &[]);
    assert_eq!(v["cached"].as_u64(), Some(4));
}
