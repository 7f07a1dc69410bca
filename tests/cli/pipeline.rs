//! `qsweep run` and `qsweep status` on real pipelines: incremental reruns, keys that ignore
//! formatting, thread-count independence, clean errors and interruption.

use crate::helpers::{fails_with, stdout, Sandbox};
use qsweep_pipeline::cache::Store;
use serde_json::Value;

fn count(v: &Value, field: &str) -> u64 {
    v[field].as_u64().unwrap_or_else(|| panic!("no {field} in {v}"))
}

#[test]
fn second_run_executes_nothing_and_a_new_seed_executes_only_its_trials() {
    let sb = Sandbox::new();
    let p = sb.fixture("tiny.yaml");
    let first = sb.run_json(&p, &[]);
    assert_eq!((count(&first, "executed"), count(&first, "cached"), count(&first, "failed")), (56, 0, 0));
    let segments = sb.segments();
    assert!(segments >= 1);
    let again = sb.run_json(&p, &[]);
    assert_eq!((count(&again, "executed"), count(&again, "cached")), (0, 56));
    assert_eq!(sb.segments(), segments, "a no-op run writes nothing");
    // 28 cells × one more seed.
    let more = sb.run_json(&p, &["--set", "seeds=3"]);
    assert_eq!((count(&more, "executed"), count(&more, "cached")), (28, 56));
    let forced = sb.run_json(&p, &["--force"]);
    assert_eq!(count(&forced, "executed"), 56);
}

#[test]
fn editing_one_systems_alpha_reruns_only_that_system_and_representation() {
    let sb = Sandbox::new();
    let p = sb.fixture("tiny.yaml");
    sb.run_json(&p, &[]);
    // Ball-Beam crisp: experiment 1, 2×2 grid × 2 algorithms × 2 seeds.
    let v = sb.run_json(&p, &["--set", "systems.ball-beam.crisp.alpha=0.2"]);
    assert_eq!((count(&v, "executed"), count(&v, "cached")), (16, 40));
    let status = stdout(&mut sb.qsweep(&["status", p.to_str().unwrap(), "--explain"]));
    assert!(status.contains("56 cached, 0 missing"), "nothing is missing for the original file:\n{status}");
    let explain = stdout(&mut sb.qsweep(&[
        "status",
        p.to_str().unwrap(),
        "--explain",
        "--set",
        "systems.ball-beam.crisp.alpha=0.3",
    ]));
    // The nearest cached cells differ only in alpha (0.1 from the file, 0.2 from the first --set).
    assert!(explain.contains("learner.alpha: 0.1 → 0.3"), "{explain}");
    assert!(!explain.contains("learner.gamma"), "{explain}");
    assert!(explain.contains("total: 56 trials, 40 cached, 16 missing"), "{explain}");
}

#[test]
fn key_order_comments_and_number_spelling_do_not_change_keys() {
    let sb = Sandbox::new();
    let p = sb.fixture("tiny.yaml");
    sb.run_json(&p, &[]);
    let text = std::fs::read_to_string(&p).unwrap();
    let rewritten = text
        .replace(
            "{ epsilon: 1.0e-6, gamma: 0.9, alpha: 0.1, lambda: 0.9 }",
            "{ lambda: 0.90, alpha: 1e-1, gamma: 0.9, epsilon: 0.000001 }  # reordered",
        )
        .replace("name: tiny", "# a comment\nname: tiny");
    assert_ne!(rewritten, text);
    let q = sb.write("rewritten.yaml", &rewritten);
    let v = sb.run_json(&q, &[]);
    assert_eq!((count(&v, "executed"), count(&v, "cached")), (0, 56));
}

#[test]
fn results_are_bit_identical_on_one_and_two_threads() {
    let (a, b) = (Sandbox::new(), Sandbox::new());
    let pa = a.fixture("tiny.yaml");
    let pb = b.fixture("tiny.yaml");
    a.run_json(&pa, &["--jobs", "1", "--set", "seeds=3"]);
    b.run_json(&pb, &["--jobs", "2", "--set", "seeds=3", "--batch-trials", "3"]);
    let read = |sb: &Sandbox| {
        let mut r: Vec<_> = Store::open(&sb.cache()).unwrap().read_all().unwrap();
        r.sort_by_key(|r| r.key);
        r.into_iter().map(|r| (r.key, r.config, r.seed, r.outcome)).collect::<Vec<_>>()
    };
    let (ra, rb) = (read(&a), read(&b));
    assert_eq!(ra.len(), 84);
    assert!(ra == rb, "outcomes differ between --jobs 1 and --jobs 2");
    assert!(b.segments() > a.segments(), "small batches flush several segments");
}

#[test]
fn status_json_counts_cached_and_missing_per_experiment() {
    let sb = Sandbox::new();
    let p = sb.fixture("tiny.yaml");
    let out = stdout(&mut sb.qsweep(&["status", p.to_str().unwrap(), "--json"]));
    let v: Value = serde_json::from_str(&out).unwrap();
    assert_eq!((count(&v, "trials"), count(&v, "cached"), count(&v, "missing")), (56, 0, 56));
    assert!(!sb.cache().join("seg-").exists());
    sb.run_json(&p, &[]);
    let v: Value =
        serde_json::from_str(&stdout(&mut sb.qsweep(&["status", p.to_str().unwrap(), "--json"]))).unwrap();
    assert_eq!((count(&v, "cached"), count(&v, "missing")), (56, 0));
    let exps = v["experiments"].as_array().unwrap();
    assert_eq!(exps.len(), 4);
    assert_eq!(exps[0]["system"], "ball-beam");
    assert_eq!(count(&exps[0], "trials"), 16);
}

#[test]
fn bad_pipelines_name_file_line_and_field_and_write_nothing() {
    let sb = Sandbox::new();
    let text = std::fs::read_to_string(sb.fixture("tiny.yaml")).unwrap();
    let cases: Vec<(&str, String, &str)> = vec![
        ("typo.yaml", text.replace("seeds: 2", "sedes: 2"), "typo.yaml:4:1: unknown field `sedes`"),
        ("typo.yaml", text.replace("seeds: 2", "sedes: 2"), "did you mean `seeds`?"),
        ("gamma.yaml", text.replace("gamma: 0.9,", "gamma: 1.5,"), "gamma.yaml:9:"),
        ("gamma.yaml", text.replace("gamma: 0.9,", "gamma: 1.5,"), "expected a number in [0, 1]"),
        ("actions.yaml", text.replace("fixed: { actions: 3 }", "fixed: { actions: 1 }"), "A_n needs n ≥ 2"),
        ("var.yaml", text.replace("x_dot: [2, 3] }", "theta: [2, 3] }"), "`theta` for ball-beam"),
        ("tabs.yaml", text.replace("  ball-beam:", "\tball-beam:"), "tabs.yaml:8:"),
        ("empty.yaml", String::new(), "the file is empty"),
        (
            "alg.yaml",
            text.replace("repr: crisp,", "repr: crisp, algorithms: [q-lamda],"),
            "did you mean `q-lambda`?",
        ),
    ];
    for (name, body, want) in cases {
        let p = sb.write(name, &body);
        let err = fails_with(&mut sb.qsweep(&["run", p.to_str().unwrap()]), 2);
        assert!(err.contains(want), "{name}: wanted {want:?} in:\n{err}");
        assert!(!err.contains("panicked"), "{err}");
    }
    let err = fails_with(&mut sb.qsweep(&["run", sb.dir.path().to_str().unwrap()]), 2);
    assert!(err.contains("is a directory"), "{err}");
    let err = fails_with(&mut sb.qsweep(&["run", "does-not-exist.yaml"]), 2);
    assert!(err.contains("does-not-exist.yaml"), "{err}");
    let p = sb.fixture("tiny.yaml");
    let err = fails_with(&mut sb.qsweep(&["run", p.to_str().unwrap(), "--set", "seeds"]), 2);
    assert!(err.contains("expected PATH=VALUE"), "{err}");
    assert_eq!(sb.segments(), 0, "nothing was written to the cache");
}

#[test]
fn ctrl_c_flushes_finished_trials_exits_130_and_a_rerun_finishes_the_rest() {
    interrupt_flushes_exits_130_and_a_rerun_finishes_the_rest("-INT");
}

/// Slurm's time limit and scancel send SIGTERM (then SIGKILL): handled like Ctrl-C.
#[test]
fn sigterm_flushes_finished_trials_exits_130_and_a_rerun_finishes_the_rest() {
    interrupt_flushes_exits_130_and_a_rerun_finishes_the_rest("-TERM");
}

fn interrupt_flushes_exits_130_and_a_rerun_finishes_the_rest(signal: &str) {
    let sb = Sandbox::new();
    // Mountain Car trials that never succeed: two 100,000-step episodes each, many seeds.
    let p = sb.write(
        "slow.yaml",
        "name: slow\nseeds: 400\nsystems:\n  mountain-car:\n    success: { within: 1, streak: 1, max_episode_steps: 100000 }\n    settings: { max_episodes: 2 }\n    experiments:\n      - { id: 1, repr: crisp, algorithms: [q0], vary: { x == x_dot: [2] } }\n",
    );
    let bin = assert_cmd::cargo::cargo_bin("qsweep");
    let child = std::process::Command::new(bin)
        .current_dir(sb.dir.path())
        .args(["run", p.to_str().unwrap(), "--json", "--no-report", "--jobs", "1", "--batch-seconds", "0.2"])
        .arg("--cache")
        .arg(sb.cache())
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    // Wait until at least one batch is stored, then interrupt.
    let start = std::time::Instant::now();
    while sb.segments() == 0 {
        assert!(start.elapsed().as_secs() < 120, "no segment was written");
        std::thread::sleep(std::time::Duration::from_millis(50));
    }
    let killed = std::process::Command::new("kill").args([signal, &child.id().to_string()]).status().unwrap();
    assert!(killed.success());
    let out = child.wait_with_output().unwrap();
    assert_eq!(out.status.code(), Some(130), "{}", String::from_utf8_lossy(&out.stderr));
    let v: Value = serde_json::from_slice(&out.stdout).unwrap();
    let done = count(&v, "executed");
    assert!(v["interrupted"].as_bool().unwrap());
    assert!((1..400).contains(&done), "{v}");
    let names: Vec<String> = std::fs::read_dir(sb.cache())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert!(names.iter().all(|n| n.starts_with("seg-")), "no temp debris: {names:?}");
    let rest = sb.run_json(&p, &[]);
    assert_eq!(count(&rest, "cached"), done, "everything flushed before the interrupt is kept");
    assert_eq!(count(&rest, "executed"), 400 - done);
}

#[test]
fn infinite_batch_seconds_is_a_usage_error_not_a_panic() {
    let sb = Sandbox::new();
    let p = sb.fixture("tiny.yaml");
    let err = fails_with(&mut sb.qsweep(&["run", p.to_str().unwrap(), "--batch-seconds", "inf"]), 2);
    assert!(err.contains("expected a finite number") && !err.contains("panicked"), "{err}");
}

#[test]
fn two_shards_cover_every_trial_exactly_once_and_match_a_single_run() {
    let (sharded, single) = (Sandbox::new(), Sandbox::new());
    let p = sharded.fixture("tiny.yaml");
    let a = sharded.run_json(&p, &["--shard", "1/2"]);
    let b = sharded.run_json(&p, &["--shard", "2/2"]);
    assert_eq!(count(&a, "executed") + count(&b, "executed"), 56);
    assert!(count(&a, "executed") > 0 && count(&b, "executed") > 0);
    let again = sharded.run_json(&p, &["--shard", "2/2"]);
    assert_eq!(count(&again, "executed"), 0, "a requeued shard skips what is cached");
    single.run_json(&single.fixture("tiny.yaml"), &[]);
    let read = |sb: &Sandbox| {
        let mut r: Vec<_> = Store::open(&sb.cache()).unwrap().read_all().unwrap();
        r.sort_by_key(|r| r.key);
        r.into_iter().map(|r| (r.key, r.outcome)).collect::<Vec<_>>()
    };
    assert!(read(&sharded) == read(&single));
    let err = fails_with(&mut sharded.qsweep(&["run", p.to_str().unwrap(), "--shard", "3/2"]), 2);
    assert!(err.contains("I/N"), "{err}");
}
