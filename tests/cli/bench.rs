//! `qsweep bench` from the command line: JSON shape, filtering and argument errors.

use crate::helpers::{qsweep, Test};

#[test]
fn json_lists_config_steps_seconds_and_rate() {
    let out = qsweep()
        .args(["bench", "--steps", "2000", "--repeat", "1", "--filter", "cart-pole/crisp/q0/", "--json"])
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let rows = v["results"].as_array().unwrap();
    assert_eq!(rows.len(), 3, "2^4/2a, 10^4/2a and 10^4/10a");
    for r in rows {
        assert!(r["config"].as_str().unwrap().starts_with("cart-pole/crisp/q0/"));
        let steps = r["steps"].as_u64().unwrap();
        assert!((2000..4000).contains(&steps));
        assert!(r["seconds"].as_f64().unwrap() > 0.0);
        assert!(r["steps_per_s"].as_f64().unwrap() > 0.0);
    }
}

/// The table names the vector level it ran with; `QSWEEP_SIMD` picks it, capped by the CPU, and a
/// value it does not know falls back to the baseline with a warning that names the accepted ones.
#[test]
fn the_table_names_its_vector_level() {
    let args = ["bench", "--steps", "2000", "--repeat", "1", "--filter", "mountain-car/fuzzy/q0/2^2"];
    let out = qsweep().args(args).env("QSWEEP_SIMD", "off").output().unwrap();
    assert!(out.status.success());
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.lines().last().unwrap().starts_with("vector kernels: off ("), "{text}");
    let out = qsweep().args(args).env("QSWEEP_SIMD", "sse9").output().unwrap();
    assert!(out.status.success());
    assert!(String::from_utf8_lossy(&out.stdout).contains("vector kernels: off ("));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("QSWEEP_SIMD=\"sse9\": expected off, avx2, avx512 or auto"), "{err}");
}

#[test]
fn unknown_filter_and_bad_budget_are_usage_errors() {
    Test::new()
        .args(["bench", "--filter", "no-such-system"])
        .status(2)
        .stderr_contains("cart-pole/fuzzy/q-lambda/4^4/2a")
        .run();
    Test::new().args(["bench", "--steps", "0"]).status(2).stderr_contains("--steps: 0 is not allowed").run();
}

/// `bench --pipeline`: real cells with their real seeds to their real stop, so each timed cell's
/// steps are exactly what its cached trials ran; ranked by the cached trials' cost, or by the
/// estimate without a cache; shares of the pipeline's cost add up to at most 1.
#[test]
fn pipeline_bench_times_the_costliest_cells_to_their_real_stop() {
    use crate::helpers::Sandbox;
    let sb = Sandbox::new();
    let p = sb.fixture("tiny.yaml");
    let p = p.to_str().unwrap();
    let bench = |sb: &Sandbox, extra: &[&str]| -> serde_json::Value {
        let mut args = vec!["bench", "--pipeline", p, "--top", "3", "--json"];
        args.extend_from_slice(extra);
        let out = sb.qsweep(&args).output().unwrap();
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
        serde_json::from_slice(&out.stdout).unwrap()
    };
    let v = bench(&sb, &[]);
    assert_eq!(v["basis"], "estimated", "no cache yet: {v}");
    assert!(!sb.cache().exists(), "bench does not create the cache");
    sb.run_json(std::path::Path::new(p), &[]);
    let v = bench(&sb, &[]);
    assert_eq!(v["format_version"], 1);
    assert_eq!(v["basis"], "cached");
    let rows = v["results"].as_array().unwrap();
    assert_eq!(rows.len(), 3);
    // The cache's own record of the same trials: total steps per cell.
    let store = qsweep_pipeline::cache::Store::open(&sb.cache()).unwrap();
    let recs = store.read_all().unwrap();
    let mut share = 0.0;
    for r in rows {
        let name = r["cell"].as_str().unwrap();
        let steps: u64 = recs
            .iter()
            .filter(|rec| qsweep_pipeline::bench::pipeline::cell_name(None, &cell_of(rec)) == name)
            .map(|rec| rec.outcome.total_steps)
            .sum();
        assert_eq!(r["steps"].as_u64().unwrap(), steps, "{name}: the real trials, to their real stop");
        assert_eq!(r["seeds"], 2);
        assert!(r["cpu_seconds"].as_f64().unwrap() > 0.0);
        share += r["share"].as_f64().unwrap();
    }
    assert!(share > 0.0 && share <= 1.0 + 1e-9, "{share}");
    Test::new()
        .pipeline("tiny.yaml")
        .args(["bench", "--pipeline", "tiny.yaml", "--top", "0"])
        .status(2)
        .stderr_contains("--top: must be at least 1")
        .run();
}

/// A plan cell standing for a cached record (same configuration), for naming.
fn cell_of(rec: &qsweep_pipeline::cache::TrialRecord) -> qsweep_pipeline::plan::Cell {
    qsweep_pipeline::plan::Cell {
        algorithm: rec.config.learner.algorithm,
        coords: vec![],
        config: rec.config.clone(),
        trials: vec![],
        contender: None,
        fresh: vec![],
    }
}

/// `QSWEEP_DENSE` picks the path a two-variable fuzzy rule base takes, never its outcome: `qsweep
/// trial` gives the same outcome (every episode's length) with it on and off, under both
/// algorithms, on both two-variable systems, small and large rule bases; the bench table says
/// which path ran.
#[test]
fn dense_fuzzy_path_switch_changes_no_outcome() {
    for (env, algorithm, sets) in
        [("mountain-car", "q-lambda", "3,4"), ("ball-beam", "q0", "3,4"), ("mountain-car", "q0", "7,9")]
    {
        let args = [
            "trial",
            "--env",
            env,
            "--repr",
            "fuzzy",
            "--resolution",
            sets,
            "--actions",
            "3",
            "--algorithm",
            algorithm,
            "--seed",
            "5",
            "--max-episodes",
            "40",
            "--json",
        ];
        let outcome = |dense: &str| {
            let out = qsweep().args(args).env("QSWEEP_DENSE", dense).output().unwrap();
            assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
            let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
            v["outcome"].clone()
        };
        let on = outcome("on");
        assert!(on["episodes"].as_u64().unwrap() > 1, "{on}");
        assert_eq!(on, outcome("off"), "{env} {algorithm} {sets}");
    }
    let bench = ["bench", "--steps", "2000", "--repeat", "1", "--filter", "mountain-car/fuzzy/q0/2^2"];
    for (dense, says) in [("on", "dense fuzzy path: on"), ("off", "dense fuzzy path: off")] {
        let out = qsweep().args(bench).env("QSWEEP_DENSE", dense).output().unwrap();
        assert!(String::from_utf8_lossy(&out.stdout).contains(says));
    }
}
