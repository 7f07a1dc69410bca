//! Variants and setting axes end to end: incremental runs across variants, `--variant`, the
//! report layout, and the errors for bad `variants:` sections.

use crate::helpers::{fails_with, stdout, Sandbox};
use serde_json::Value;

fn counts(v: &Value) -> (u64, u64) {
    (v["executed"].as_u64().unwrap(), v["cached"].as_u64().unwrap())
}

/// Mountain Car: 12 cells × 2 seeds = 24 trials per variant; `fast-crisp` changes the 8 crisp
/// cells (16 trials), `short-episodes` every cell (24 trials).
#[test]
fn adding_a_variant_runs_exactly_the_trials_its_set_changes() {
    let sb = Sandbox::new();
    let p = sb.fixture("variants.yaml");
    let ps = p.to_str().unwrap();
    assert_eq!(counts(&sb.run_json(&p, &["--variant", "as-written"])), (24, 0));
    assert_eq!(counts(&sb.run_json(&p, &["--variant", "as-written", "--variant", "fast-crisp"])), (16, 24));
    assert_eq!(counts(&sb.run_json(&p, &[])), (24, 40));
    assert_eq!(counts(&sb.run_json(&p, &[])), (0, 64));

    // A variant identical to another executes nothing and is reported as a warning.
    let text = std::fs::read_to_string(&p).unwrap();
    let same = sb.write(
        "same.yaml",
        &format!("{text}  - id: same-alpha\n    set: {{ systems.mountain-car.crisp.alpha: 0.01 }}\n"),
    );
    let out = sb
        .qsweep(&["run", same.to_str().unwrap(), "--json", "--no-report"])
        .assert()
        .success()
        .get_output()
        .clone();
    let v: Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(counts(&v), (0, 64));
    let err = String::from_utf8(out.stderr).unwrap();
    assert!(err.contains("warning: variant `same-alpha` changes no trial"), "{err}");

    // Removing a variant loses no cached rows.
    let cut = text[..text.find("  - id: short-episodes").unwrap()].to_string();
    let cut = sb.write("cut.yaml", &cut);
    assert_eq!(counts(&sb.run_json(&cut, &[])), (0, 40));
    let status = stdout(&mut sb.qsweep(&["status", ps]));
    assert!(status.contains("total: 64 trials, 64 cached, 0 missing"), "{status}");
}

#[test]
fn variant_flag_selects_and_unknown_ids_list_the_choices() {
    let sb = Sandbox::new();
    let p = sb.fixture("variants.yaml");
    let ps = p.to_str().unwrap();
    let err = fails_with(&mut sb.qsweep(&["run", ps, "--variant", "short-episode"]), 2);
    assert!(err.contains("--variant short-episode"), "{err}");
    assert!(err.contains("as-written, fast-crisp, short-episodes"), "{err}");
    assert!(err.contains("did you mean `short-episodes`?"), "{err}");
    assert!(!sb.cache().exists(), "nothing is written on bad input");

    let status = stdout(&mut sb.qsweep(&["status", ps, "--variant", "short-episodes", "--json"]));
    let v: Value = serde_json::from_str(&status).unwrap();
    assert_eq!(v["trials"], 24);
    let exps = v["experiments"].as_array().unwrap();
    assert!(exps.iter().all(|e| e["variant"] == "short-episodes"), "{status}");

    let tiny = sb.fixture("tiny.yaml");
    let err = fails_with(&mut sb.qsweep(&["status", tiny.to_str().unwrap(), "--variant", "x"]), 2);
    assert!(err.contains("declares no variants"), "{err}");
}

#[test]
fn report_has_one_folder_per_variant_and_combined_data_with_a_variant_column() {
    let sb = Sandbox::new();
    let p = sb.fixture("variants.yaml");
    let out = sb.path("rep");
    sb.qsweep(&["run", p.to_str().unwrap(), "--quiet", "--out", out.to_str().unwrap()]).assert().success();
    for id in ["as-written", "fast-crisp", "short-episodes"] {
        for f in ["index.html", "README.md", "table3.md", "table3.csv", "cells.parquet", "manifest.json"] {
            assert!(out.join(id).join(f).is_file(), "{id}/{f}");
        }
        // The trial rows live once, in the combined file (one raw copy: the cache).
        assert!(!out.join(id).join("trials.parquet").exists(), "{id}/trials.parquet");
        assert!(!out.join(id).join("figures/cart-pole.png").exists(), "no PNG by default");
        // Every page names the pipeline and the variant, and links back to the comparison.
        let page = std::fs::read_to_string(out.join(id).join("index.html")).unwrap();
        assert!(page.contains(&format!("<title>qsweep report: variants / {id}</title>")), "{page}");
        assert!(page.contains("href=\"../index.html\""), "{id} links back");
        let t3 = std::fs::read_to_string(out.join(id).join("table3.md")).unwrap();
        assert!(t3.starts_with(&format!("**Table III (variants / {id}).**")), "{t3}");
    }
    let fast = std::fs::read_to_string(out.join("fast-crisp/index.html")).unwrap();
    assert!(fast.contains("Its settings: the pipeline with systems."), "the set overrides are shown");
    for f in ["cells.parquet", "trials.parquet", "manifest.json", "README.md", "index.html"] {
        assert!(out.join(f).is_file(), "{f}");
    }
    // The shared trials (fuzzy experiment 3 in as-written and fast-crisp) are one row each in the
    // cache but appear under both variants in the combined trials.parquet.
    let rows = parquet_rows(&out.join("trials.parquet"));
    assert_eq!(rows, 3 * 24, "every variant's trials, shared ones repeated");

    // Regression (a --variant run replaced the comparison of all variants with one of a single
    // variant): a report of some variants rewrites only their folders.
    let comparison = std::fs::read(out.join("variants.csv")).unwrap();
    let before = std::fs::read(out.join("short-episodes/table3.csv")).unwrap();
    let p = p.to_str().unwrap();
    let o = out.to_str().unwrap();
    sb.qsweep(&["run", p, "--quiet", "--out", o, "--variant", "fast-crisp", "--set", "seeds=3"])
        .assert()
        .success();
    assert_eq!(std::fs::read(out.join("variants.csv")).unwrap(), comparison);
    assert_eq!(std::fs::read(out.join("short-episodes/table3.csv")).unwrap(), before);
    let manifest = |id: &str| -> Value {
        serde_json::from_str(&std::fs::read_to_string(out.join(id).join("manifest.json")).unwrap()).unwrap()
    };
    assert_eq!(manifest("fast-crisp")["trials_present"], 36, "3 seeds now");
    // Regression (the guard refused a complete report of a changed plan): back at 2 seeds, every
    // planned trial is cached, so the report replaces the bigger one and says what changed.
    let done = sb.qsweep(&["report", p, "--out", o, "--variant", "fast-crisp"]).output().unwrap();
    assert!(done.status.success(), "{}", String::from_utf8_lossy(&done.stderr));
    let said = String::from_utf8_lossy(&done.stdout);
    assert!(said.contains("fast-crisp: 36 trials, 12 cells → 24 trials, 12 cells"), "{said}");
    assert_eq!(manifest("fast-crisp")["trials_present"], 24);
}

fn parquet_rows(path: &std::path::Path) -> i64 {
    use parquet::file::reader::{FileReader, SerializedFileReader};
    let r = SerializedFileReader::new(std::fs::File::open(path).unwrap()).unwrap();
    r.metadata().file_metadata().num_rows()
}

#[test]
fn setting_axes_plan_one_cell_per_value_and_label_the_axis_by_name() {
    let sb = Sandbox::new();
    let p = sb.write(
        "tune.yaml",
        "name: tune\nseeds: 1\ndefaults: { max_episodes: 5 }\nsystems:\n  mountain-car:\n    success: { within: 400, max_episode_steps: 400 }\n    experiments:\n      - id: a\n        repr: crisp\n        algorithms: [q-lambda]\n        vary: { alpha: [0.05, 0.1, 0.2], lambda: [0.3, 0.9] }\n        fixed: { x: 4, x_dot: 4 }\n",
    );
    let v: Value =
        serde_json::from_str(&stdout(&mut sb.qsweep(&["status", p.to_str().unwrap(), "--json"]))).unwrap();
    assert_eq!(v["trials"], 6);
    let out = sb.path("rep");
    sb.qsweep(&["run", p.to_str().unwrap(), "--quiet", "--out", out.to_str().unwrap()]).assert().success();
    let svg = std::fs::read_to_string(out.join("figures/mountain-car.svg")).unwrap().replace(['\n', ' '], "");
    for label in [">alpha<", ">lambda<", ">0.05<", ">0.9<"] {
        assert!(svg.contains(label), "{label} in the heatmap");
    }
}

/// Each bad `variants:` or axis gives exit 2, names the file, line and the fix, and writes nothing.
#[test]
fn bad_variants_and_axes_are_usage_errors_with_a_location() {
    let base = "name: v\nseeds: 1\nsystems:\n  mountain-car:\n    experiments:\n      - { id: 1, repr: crisp, vary: { x == x_dot: [2, 3], alpha: [0.1, 0.2] } }\n";
    let cases: &[(&str, &str)] = &[
        ("variants:\n  - id: a\n  - id: a\n", "id `a` is used twice"),
        ("variants:\n  - id: a/b\n", "variant id `a/b` is not allowed"),
        ("variants:\n  - id: figures\n", "variant id `figures` is not allowed"),
        (
            "variants:\n  - id: a\n    set: { systems.mountain-car.crisp.alpa: 0.1 }\n",
            "variant `a`: set `systems.mountain-car.crisp.alpa`: unknown field `alpa`",
        ),
        ("variants:\n  - id: a\n    set: { defaults.gamma: high }\n", "variant `a`: set `defaults.gamma`"),
        (
            "variants:\n  - id: a\n    set: { systems.cart-pole.crisp.alpha: 0.1 }\n",
            "the pipeline has no system `cart-pole`",
        ),
        ("variants:\n  - id: a\n    set: { systems.mountain-car.crisp.alpha: 0.3 }\n", "varies `alpha`"),
        ("variants:\n  - id: a\n    set: { defaults.alpha: 0.3 }\n", "varies `alpha`"),
        ("variants:\n  - id: a\n    set: { seeds: 0 }\n", "variant `a`: set `seeds`"),
        ("variants: []\n", "the list is empty"),
    ];
    for (extra, want) in cases {
        let sb = Sandbox::new();
        let p = sb.write("bad.yaml", &format!("{base}{extra}"));
        let err = fails_with(&mut sb.qsweep(&["run", p.to_str().unwrap()]), 2);
        assert!(err.contains(want), "{extra}: expected `{want}` in:\n{err}");
        assert!(err.contains("bad.yaml"), "{err}");
        assert!(!sb.cache().exists() && !sb.path("reports").exists(), "nothing written for {extra}");
    }
    let sb = Sandbox::new();
    let p = sb.write("axis.yaml", &base.replace("alpha: [0.1, 0.2]", "alpah: [0.1, 0.2]"));
    let err = fails_with(&mut sb.qsweep(&["status", p.to_str().unwrap()]), 2);
    assert!(err.contains("axis.yaml:6:"), "{err}");
    assert!(err.contains("unknown axis `alpah`") && err.contains("did you mean `alpha`?"), "{err}");
    let p = sb.write("axis2.yaml", &base.replace("alpha: [0.1, 0.2]", "alpha: [0.1, -2]"));
    let err = fails_with(&mut sb.qsweep(&["status", p.to_str().unwrap()]), 2);
    assert!(err.contains("axis2.yaml:6:") && err.contains("alpha"), "{err}");
}

/// `qsweep trial` builds its configuration through the pipeline path, so the same settings give
/// the same configuration (and key) as a pipeline cell.
#[test]
fn trial_and_a_pipeline_cell_resolve_to_the_same_configuration() {
    let sb = Sandbox::new();
    let p = sb.write(
        "one.yaml",
        "name: one\nseeds: [3]\ndefaults: { max_episodes: 4, q_init: -0.5 }\nsystems:\n  cart-pole:\n    params: { gravity: 9.8 }\n    success: { steps: 300 }\n    experiments:\n      - { id: a, repr: fuzzy, algorithms: [q-lambda], vary: { actions: 3 }, fixed: { x: 2, x_dot: 3, theta: 2, theta_dot: 3 }, settings: { alpha: 0.2, width: 0.5 } }\n",
    );
    sb.run_json(&p, &[]);
    let stored = qsweep_pipeline::cache::Store::open(&sb.cache()).unwrap().read_all().unwrap();
    assert_eq!(stored.len(), 1);
    let out = stdout(crate::helpers::qsweep().args([
        "trial",
        "--env",
        "cart-pole",
        "--repr",
        "fuzzy",
        "--algorithm",
        "q-lambda",
        "--resolution",
        "2,3,2,3",
        "--actions",
        "3",
        "--seed",
        "3",
        "--max-episodes",
        "4",
        "--alpha",
        "0.2",
        "--param",
        "gravity=9.8",
        "--balance-steps",
        "300",
        "--set",
        "q_init=-0.5",
        "--set",
        "width=0.5",
        "--json",
    ]));
    let v: Value = serde_json::from_str(&out).unwrap();
    let from_trial: qsweep_engine::TrialConfig = serde_json::from_value(v["config"].clone()).unwrap();
    assert_eq!(from_trial, stored[0].config);
    assert_eq!(qsweep_pipeline::cache::Key::of(&from_trial, 3), stored[0].key);
}

/// `counting: failures` is a report setting: an exploratory variant that only sets it runs no
/// trial, counts one episode fewer for every trial that reached the goal, is ranked after the
/// declared variants, and gets its folder only on demand.
#[test]
fn an_exploratory_counting_variant_reruns_nothing_and_counts_one_fewer() {
    let sb = Sandbox::new();
    let p = sb.fixture("variants.yaml");
    let text = std::fs::read_to_string(&p).unwrap();
    let cut = text[..text.find("  - id: fast-crisp").unwrap()].to_string();
    let with = sb.write(
        "counting.yaml",
        &format!("{cut}  - id: failures\n    exploratory: true\n    set: {{ counting: failures }}\n"),
    );
    let ws = with.to_str().unwrap();
    let out_dir = sb.path("rep");
    let od = out_dir.to_str().unwrap();
    let first = sb
        .qsweep(&["run", ws, "--json", "--out", od, "--formats", "csv,md"])
        .assert()
        .success()
        .get_output()
        .clone();
    let v: Value = serde_json::from_slice(&first.stdout).unwrap();
    assert_eq!(counts(&v), (24, 0), "the counting variant shares every trial");
    let err = String::from_utf8(first.stderr).unwrap();
    assert!(!err.contains("changes no trial"), "a report setting is not a no-op: {err}");

    // Ranked after the declared variant, labelled; no folder of its own.
    let variants = std::fs::read_to_string(out_dir.join("variants.csv")).unwrap();
    let rows = crate::helpers::csv_rows(&variants);
    assert_eq!(rows.len(), 2, "{variants}");
    assert_eq!((rows[1]["variant"].as_str(), rows[1]["exploratory"].as_str()), ("failures", "yes"));
    assert_eq!(rows[0]["exploratory"], "no");
    assert!(out_dir.join("as-written/table3.csv").is_file());
    assert!(!out_dir.join("failures").exists(), "an exploratory variant's folder is on demand");

    // On demand: its Table III counts one episode fewer wherever every trial converged.
    sb.qsweep(&["report", ws, "--variant", "failures", "--out", od, "--formats", "csv"]).assert().success();
    let base =
        crate::helpers::csv_rows(&std::fs::read_to_string(out_dir.join("as-written/table3.csv")).unwrap());
    let fail =
        crate::helpers::csv_rows(&std::fs::read_to_string(out_dir.join("failures/table3.csv")).unwrap());
    assert_eq!(base.len(), fail.len());
    let mut checked = 0;
    for (b, f) in base.iter().zip(&fail) {
        if b["n"] == b["successes"]
            && f["n"] == f["successes"]
            && b["x"] == f["x"]
            && b["actions"] == f["actions"]
        {
            let (mb, mf): (f64, f64) = (b["mean"].parse().unwrap(), f["mean"].parse().unwrap());
            assert!((mb - 1.0 - mf).abs() < 1e-9, "{b:?} {f:?}");
            checked += 1;
        }
    }
    assert!(checked > 0, "some row converged everywhere: {base:?}");

    // A value that does not exist names the file, the line and the choices.
    let bad = sb.write("bad.yaml", &format!("{cut}  - id: failures\n    set: {{ counting: fail }}\n"));
    let err = fails_with(&mut sb.qsweep(&["status", bad.to_str().unwrap()]), 2);
    assert!(err.contains("bad.yaml:"), "{err}");
    assert!(err.contains("episodes") && err.contains("failures"), "{err}");
}
