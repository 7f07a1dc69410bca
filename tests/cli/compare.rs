//! `qsweep compare A B` end to end (issue 62): one deterministic program whose value is 100 plus
//! seeded Gaussian noise (sd 10), swept over 40 cells, compared with itself on other seeds is
//! within chance; the same program scaled by 1.2 is beyond chance with most cells `differs`;
//! `--map` matches differently named params; bad inputs exit 2 naming the fix; a cache without
//! any matched cell exits 1; `--out`'s files are byte-identical on a rerun and `--json` has the
//! fields docs/json.md lists. Engine sides: an engine pipeline with itself (p = 1 everywhere),
//! on other seeds (within chance), a report folder with itself and with its pipeline (the same
//! moments), a program matched onto engine cells with `--map`, and their bad inputs.

use crate::helpers::{fails_with, stdout, Sandbox};

/// A worker-protocol program: `value` = `scale` × (100 + N(0, 10) drawn from the seed and `x`),
/// so every cell's noise is its own and a trial is a function of its params and seed.
fn noise(scale: &str, param: &str) -> String {
    format!(
        "import json, random, sys\nfor line in sys.stdin:\n    c = json.loads(line)\n    \
         rng = random.Random(c[\"seed\"] * 1000 + c[\"{param}\"])\n    \
         print(json.dumps({{\"value\": {scale} * (100 + rng.gauss(0, 10)), \"label\": \"l\"}}), flush=True)\n"
    )
}

/// A pipeline of `program` over `param` = 1..`cells`, on `seeds`.
fn pipeline(name: &str, program: &str, param: &str, cells: u32, seeds: &str) -> String {
    format!(
        "name: {name}\nseeds: {seeds}\nprogram:\n  command: [python3, {program}]\n  inputs: [{program}]\n  \
         protocol: worker\n  metrics: {{ value: float, label: string }}\n  objective: {{ metric: value, goal: maximize }}\n\
         params: {{ {param}: 1 }}\nexperiments:\n  - {{ id: grid, vary: {{ {param}: 1..{cells} }} }}\n"
    )
}

const SEEDS_A: &str = "[1, 2, 3, 4, 5, 6, 7, 8, 9, 10]";
const SEEDS_B: &str = "[11, 12, 13, 14, 15, 16, 17, 18, 19, 20]";

/// A sandbox with `a.yaml` (the program, seeds 1–10) and `b.yaml` (the program `b_scale` times,
/// seeds 11–20), both run, over `cells` cells.
fn before_after(cells: u32, b_scale: &str) -> Sandbox {
    let sb = Sandbox::new();
    sb.write("before.py", &noise("1", "x"));
    sb.write("after.py", &noise(b_scale, "x"));
    sb.write("a.yaml", &pipeline("a", "before.py", "x", cells, SEEDS_A));
    sb.write("b.yaml", &pipeline("b", "after.py", "x", cells, SEEDS_B));
    for p in ["a.yaml", "b.yaml"] {
        stdout(&mut sb.qsweep(&["run", p, "--quiet", "--no-report", "--jobs", "2"]));
    }
    sb
}

fn json(sb: &Sandbox, args: &[&str]) -> serde_json::Value {
    let mut all = vec!["compare"];
    all.extend_from_slice(args);
    all.push("--json");
    serde_json::from_str(&stdout(&mut sb.qsweep(&all))).expect("compare --json prints JSON")
}

#[test]
fn compare_the_same_program_on_other_seeds_is_within_chance() {
    let sb = before_after(40, "1");
    let out = stdout(&mut sb.qsweep(&["compare", "a.yaml", "b.yaml"]));
    assert!(
        out.contains("compared 40 cells of a.yaml and b.yaml on metric value (shared params: x"),
        "{out}"
    );
    assert!(out.contains(", within chance"), "{out}");
    let v = json(&sb, &["a.yaml", "b.yaml"]);
    assert_eq!((v["tested"].as_u64(), v["statement"].as_str()), (Some(40), Some("within chance")));
    let k = v["significant"].as_u64().unwrap();
    assert!(k <= 4, "{k} of 40 cells with p < 0.05 where chance gives 2");
    assert!(v["binomial_p"].as_f64().unwrap() >= 0.05, "{v}");
    // Every cell's ratio interval holds its ratio, and the verdicts add up to the cells.
    let cells = v["cells"].as_array().unwrap();
    assert_eq!(cells.len(), 40);
    for c in cells {
        let (r, lo, hi) =
            (c["ratio"].as_f64().unwrap(), c["ratio_lo"].as_f64().unwrap(), c["ratio_hi"].as_f64().unwrap());
        assert!(lo <= r && r <= hi && lo > 0.8 && hi < 1.25, "{c}");
        assert_eq!((c["n_a"].as_u64(), c["n_b"].as_u64()), (Some(10), Some(10)));
    }
    let verdicts = &v["verdicts"];
    let total: u64 =
        ["equivalent", "differs", "undecided"].iter().map(|k| verdicts[k].as_u64().unwrap()).sum();
    assert_eq!(total, 40);
}

#[test]
fn compare_a_program_scaled_by_1_2_is_beyond_chance_and_most_cells_differ() {
    let sb = before_after(40, "1.2");
    let out = stdout(&mut sb.qsweep(&["compare", "a.yaml", "b.yaml"]));
    assert!(out.contains(", beyond chance"), "{out}");
    assert!(out.lines().any(|l| l.starts_with("differs: x=")), "the differing cells are listed: {out}");
    let v = json(&sb, &["a.yaml", "b.yaml"]);
    assert_eq!(v["statement"], "beyond chance");
    assert!(v["significant"].as_u64().unwrap() >= 30, "{v}");
    assert!(v["binomial_p"].as_f64().unwrap() < 1e-10);
    assert!(v["verdicts"]["differs"].as_u64().unwrap() > 20, "most cells differ: {}", v["verdicts"]);
    let mean_ratio: f64 =
        v["cells"].as_array().unwrap().iter().map(|c| c["ratio"].as_f64().unwrap()).sum::<f64>() / 40.0;
    assert!((mean_ratio - 1.2).abs() < 0.03, "{mean_ratio}");
}

#[test]
fn compare_maps_a_param_named_otherwise_in_b() {
    let sb = Sandbox::new();
    sb.write("before.py", &noise("1", "x"));
    sb.write("after.py", &noise("1", "size"));
    sb.write("a.yaml", &pipeline("a", "before.py", "x", 4, "3"));
    // B sweeps 2..6 under another name: cells 2–4 match, 1 is only A's, 5–6 only B's.
    sb.write("b.yaml", &pipeline("b", "after.py", "size", 6, "3").replace("1..6", "2..6"));
    for p in ["a.yaml", "b.yaml"] {
        stdout(&mut sb.qsweep(&["run", p, "--quiet", "--no-report"]));
    }
    let err = fails_with(&mut sb.qsweep(&["compare", "a.yaml", "b.yaml"]), 2);
    assert!(err.contains("share no param") && err.contains("--map"), "{err}");
    let v = json(&sb, &["a.yaml", "b.yaml", "--map", "x=size"]);
    assert_eq!(v["shared"], serde_json::json!([["x", "size"]]));
    let xs: Vec<i64> =
        v["cells"].as_array().unwrap().iter().map(|c| c["params"]["x"].as_i64().unwrap()).collect();
    assert_eq!(xs, [2, 3, 4]);
    assert_eq!((v["only_a"].as_array().unwrap().len(), v["only_b"].as_array().unwrap().len()), (1, 2));
    // The same seeds and program on both sides: identical values, ratio 1 and p = 1, never
    // `differs` (three noisy trials are too few to show equivalence within 0.80–1.25).
    for c in v["cells"].as_array().unwrap() {
        assert_eq!((c["p"].as_f64(), c["ratio"].as_f64()), (Some(1.0), Some(1.0)), "{c}");
        assert_ne!(c["verdict"], "differs", "{c}");
    }
}

#[test]
fn compare_bad_inputs_exit_2_with_a_clear_message() {
    let sb = Sandbox::new();
    sb.write("before.py", &noise("1", "x"));
    sb.write("a.yaml", &pipeline("a", "before.py", "x", 2, "2"));
    sb.write(
        "noobj.yaml",
        &pipeline("n", "before.py", "x", 2, "2")
            .replace("  objective: { metric: value, goal: maximize }\n", ""),
    );
    sb.write(
        "engine.yaml",
        &std::fs::read_to_string(crate::helpers::repo().join("tests/fixtures/pipelines/tiny.yaml")).unwrap(),
    );
    let cases: &[(&[&str], &str)] = &[
        (&["a.yaml", "a.yaml", "--map", "nope=x"], "a.yaml has no param `nope`"),
        (&["a.yaml", "a.yaml", "--map", "x=nope"], "a.yaml has no param `nope`"),
        (&["a.yaml", "a.yaml", "--map", "x"], "expected NAME=OTHER"),
        (&["a.yaml", "a.yaml", "--metric", "nope"], "has no metric `nope`"),
        (&["a.yaml", "a.yaml", "--metric", "value=nope"], "--metric value=B_NAME"),
        (&["a.yaml", "a.yaml", "--metric", "label"], "compare takes an int, float or bool metric"),
        (&["noobj.yaml", "a.yaml"], "declares no objective: name the metric to compare with --metric"),
        (&["a.yaml", "a.yaml", "--margin", "1.2,0.8"], "expected LO,HI"),
        (&["a.yaml", "engine.yaml"], "engine.yaml (engine pipeline) has no metric `value` (its metrics: episodes, converged, total_steps)"),
        // The engine's cells have a param `x` too, but many cells share each x: ambiguous.
        (&["a.yaml", "engine.yaml", "--metric", "value=episodes"], "differ only in params the other side does not have"),
        (&["a.yaml", "missing.yaml"], "missing.yaml: no such pipeline file"),
        (&["a.yaml@v1", "a.yaml"], "v1"),
    ];
    for (args, want) in cases {
        let mut all = vec!["compare"];
        all.extend_from_slice(args);
        let err = fails_with(&mut sb.qsweep(&all), 2);
        assert!(err.contains(want), "qsweep {}: {err}", all.join(" "));
    }
}

#[test]
fn compare_without_any_matched_cell_in_the_cache_exits_1() {
    let sb = Sandbox::new();
    sb.write("before.py", &noise("1", "x"));
    sb.write("a.yaml", &pipeline("a", "before.py", "x", 2, "2"));
    let err = fails_with(&mut sb.qsweep(&["compare", "a.yaml", "a.yaml"]), 1);
    assert!(
        err.contains("holds no trials of any of the 2 matched cells") && err.contains("qsweep run a.yaml"),
        "{err}"
    );
}

#[test]
fn compare_out_files_are_byte_identical_on_a_rerun_and_json_has_the_documented_fields() {
    let sb = before_after(6, "1.2");
    let out = stdout(&mut sb.qsweep(&["compare", "a.yaml", "b.yaml", "--out", "cmp"]));
    assert!(out.contains("wrote ") && out.contains("compare.svg"), "{out}");
    let read = |n: &str| std::fs::read(sb.path("cmp").join(n)).unwrap();
    let first: Vec<Vec<u8>> = ["compare.csv", "compare.md", "compare.svg"].iter().map(|n| read(n)).collect();
    std::fs::remove_dir_all(sb.path("cmp")).unwrap();
    stdout(&mut sb.qsweep(&["compare", "a.yaml", "b.yaml", "--out", "cmp"]));
    let second: Vec<Vec<u8>> = ["compare.csv", "compare.md", "compare.svg"].iter().map(|n| read(n)).collect();
    assert_eq!(first, second, "a rerun writes the same bytes");
    let csv = String::from_utf8(first[0].clone()).unwrap();
    let rows = crate::helpers::csv_rows(&csv);
    assert_eq!(rows.len(), 6);
    assert_eq!(rows[0]["x"], "1");
    for col in [
        "n_a", "n_b", "mean_a", "mean_b", "std_a", "std_b", "ratio", "ratio_lo", "ratio_hi", "p", "tost_p",
        "verdict",
    ] {
        assert!(rows[0].contains_key(col), "compare.csv lacks {col}: {csv}");
    }
    let md = String::from_utf8(first[1].clone()).unwrap();
    assert!(md.contains("| x | n A | n B |") && md.contains("beyond chance"), "{md}");
    let svg = String::from_utf8(first[2].clone()).unwrap();
    assert!(svg.starts_with("<svg") && svg.contains("equivalence margin 0.80–1.25"), "{svg}");
    // The JSON's fields are docs/json.md's table for `qsweep compare --json`.
    let v = json(&sb, &["a.yaml", "b.yaml"]);
    let doc = std::fs::read_to_string(crate::helpers::repo().join("docs/json.md")).unwrap();
    let section = &doc[doc.find("`qsweep compare --json`").expect("docs/json.md documents compare")..];
    for key in v.as_object().unwrap().keys() {
        assert!(section.contains(&format!("`{key}`")), "docs/json.md's compare table lacks `{key}`");
    }
    for key in v["cells"][0].as_object().unwrap().keys() {
        assert!(
            section.contains(&format!("`{key}`")),
            "docs/json.md's compare table lacks the cell field `{key}`"
        );
    }
}

/// `tiny.yaml` with its seed list replaced by `seeds`.
fn tiny(seeds: &str) -> String {
    std::fs::read_to_string(crate::helpers::repo().join("tests/fixtures/pipelines/tiny.yaml"))
        .unwrap()
        .replace("seeds: 2\n", &format!("seeds: {seeds}\n"))
}

#[test]
fn compare_an_engine_pipeline_with_itself_gives_p_1_in_every_cell() {
    let sb = Sandbox::new();
    sb.write("tiny.yaml", &tiny("[1, 2, 3]"));
    stdout(&mut sb.qsweep(&["run", "tiny.yaml", "--quiet", "--no-report", "--jobs", "2"]));
    let out = stdout(&mut sb.qsweep(&["compare", "tiny.yaml", "tiny.yaml"]));
    assert!(
        out.contains("compared 28 cells of tiny.yaml and tiny.yaml on metric episodes (shared params: system, repr, algorithm, experiment, x, x_dot, theta, theta_dot, actions, resolution;"),
        "{out}"
    );
    assert!(out.contains("0 of 28 cells with p < 0.05") && out.contains("within chance"), "{out}");
    let v = json(&sb, &["tiny.yaml", "tiny.yaml"]);
    for c in v["cells"].as_array().unwrap() {
        assert_eq!(
            (c["p"].as_f64(), c["ratio"].as_f64(), c["n_a"].as_u64()),
            (Some(1.0), Some(1.0), Some(3)),
            "{c}"
        );
        assert_eq!(c["ratio_interval"], "bootstrap");
        assert_ne!(c["verdict"], "differs");
    }
    // A cell's params, as a reader writes them: ball-beam has no theta (`-`).
    let first = &v["cells"][0]["params"];
    assert_eq!(
        (
            first["system"].as_str(),
            first["repr"].as_str(),
            first["algorithm"].as_str(),
            first["experiment"].as_i64()
        ),
        (Some("ball-beam"), Some("crisp"), Some("q0"), Some(1))
    );
    assert_eq!(
        (first["x"].as_i64(), first["theta"].as_str(), first["actions"].as_i64()),
        (Some(2), Some("-"), Some(3))
    );
    // The other metrics: the share converged and the steps run.
    let steps = json(&sb, &["tiny.yaml", "tiny.yaml", "--metric", "total_steps"]);
    assert_eq!(steps["metric"], serde_json::json!(["total_steps", "total_steps"]));
    assert!(steps["cells"][0]["mean_a"].as_f64().unwrap() > 30.0, "{}", steps["cells"][0]);
    let err = fails_with(&mut sb.qsweep(&["compare", "tiny.yaml", "tiny.yaml", "--metric", "score"]), 2);
    assert!(err.contains("has no metric `score` (its metrics: episodes, converged, total_steps)"), "{err}");
}

#[test]
fn compare_an_engine_pipeline_on_other_seeds_is_within_chance() {
    let sb = Sandbox::new();
    sb.write("a.yaml", &tiny("[1, 2, 3, 4, 5]"));
    sb.write("b.yaml", &tiny("[11, 12, 13, 14, 15]"));
    for p in ["a.yaml", "b.yaml"] {
        stdout(&mut sb.qsweep(&["run", p, "--quiet", "--no-report", "--jobs", "2"]));
    }
    let v = json(&sb, &["a.yaml", "b.yaml"]);
    assert_eq!(v["statement"], "within chance", "{v}");
    assert_eq!(v["cells"].as_array().unwrap().len(), 28);
    assert!(v["binomial_p"].as_f64().unwrap() >= 0.05);
    for c in v["cells"].as_array().unwrap() {
        assert_eq!((c["n_a"].as_u64(), c["n_b"].as_u64()), (Some(5), Some(5)), "{c}");
    }
}

#[test]
fn compare_a_report_folder_with_itself_and_with_its_pipeline() {
    let sb = Sandbox::new();
    sb.write("tiny.yaml", &tiny("[1, 2, 3]"));
    stdout(&mut sb.qsweep(&["run", "tiny.yaml", "--quiet", "--no-report", "--jobs", "2"]));
    stdout(&mut sb.qsweep(&["report", "tiny.yaml", "--quiet", "--out", "rep", "--formats", "cells"]));
    let v = json(&sb, &["rep", "rep"]);
    assert_eq!((v["tested"].as_u64(), v["statement"].as_str()), (Some(28), Some("within chance")));
    for c in v["cells"].as_array().unwrap() {
        assert_eq!((c["p"].as_f64(), c["ratio"].as_f64()), (Some(1.0), Some(1.0)), "{c}");
        assert_eq!(c["ratio_interval"], "delta-log", "{c}");
        let (lo, hi) = (c["ratio_lo"].as_f64(), c["ratio_hi"].as_f64());
        // From moments: 1 · exp(±1.96 se), symmetric on a log scale (none without spread? 1, 1).
        if let (Some(lo), Some(hi)) = (lo, hi) {
            assert!(lo <= 1.0 && 1.0 <= hi && (lo * hi - 1.0).abs() < 1e-9, "{c}");
        }
    }
    // The folder's moments are its pipeline's cells': the same means and stds, cell by cell.
    let w = json(&sb, &["rep", "tiny.yaml"]);
    assert_eq!(w["tested"].as_u64(), Some(28));
    for c in w["cells"].as_array().unwrap() {
        assert_eq!(c["mean_a"], c["mean_b"], "{c}");
        let (sa, sb_) = (c["std_a"].as_f64().unwrap(), c["std_b"].as_f64().unwrap());
        assert!((sa - sb_).abs() < 1e-9, "{c}");
        assert_eq!(c["p"].as_f64(), Some(1.0), "{c}");
    }
}

#[test]
fn compare_a_program_onto_engine_cells_with_map() {
    let sb = Sandbox::new();
    sb.write("tiny.yaml", &tiny("[1, 2, 3]"));
    stdout(&mut sb.qsweep(&["run", "tiny.yaml", "--quiet", "--no-report", "--jobs", "2"]));
    // A stand-in for another implementation of ball-beam's crisp Q(0) with 3 actions: it fixes the
    // engine cell's other params as its own and names the bins of x `bins` (`experiment` is a
    // reserved name in a program's params; the engine's cells of one configuration in two
    // experiments are one cell).
    sb.write(
        "other.py",
        "import json, sys\nfor line in sys.stdin:\n    c = json.loads(line)\n    \
         print(json.dumps({\"episodes\": 20 + c[\"seed\"] + c[\"bins\"]}), flush=True)\n",
    );
    sb.write(
        "other.yaml",
        "name: other\nseeds: 3\nprogram:\n  command: [python3, other.py]\n  inputs: [other.py]\n  protocol: worker\n  \
         metrics: { episodes: int }\n  objective: { metric: episodes, goal: minimize }\n\
         params: { system: ball-beam, repr: crisp, algorithm: q0, actions: 3, bins: 2, x_dot: 2 }\n\
         experiments:\n  - { id: grid, vary: { bins: [2, 3], x_dot: [2, 3] } }\n",
    );
    stdout(&mut sb.qsweep(&["run", "other.yaml", "--quiet", "--no-report"]));
    let v = json(&sb, &["other.yaml", "tiny.yaml", "--map", "bins=x"]);
    assert_eq!(
        v["shared"],
        serde_json::json!([
            ["actions", "actions"],
            ["algorithm", "algorithm"],
            ["bins", "x"],
            ["repr", "repr"],
            ["system", "system"],
            ["x_dot", "x_dot"]
        ])
    );
    assert_eq!(v["metric"], serde_json::json!(["episodes", "episodes"]));
    let cells: Vec<(i64, i64)> = v["cells"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| (c["params"]["bins"].as_i64().unwrap(), c["params"]["x_dot"].as_i64().unwrap()))
        .collect();
    assert_eq!(cells, [(2, 2), (2, 3), (3, 2), (3, 3)]);
    // The program's episodes are 20 + seed + bins: for bins 2 over seeds 0–2, a mean of 23.
    assert_eq!(v["cells"][0]["mean_a"].as_f64(), Some(23.0));
    assert_eq!(v["only_a"].as_array().unwrap().len(), 0);
    assert_eq!(v["only_b"].as_array().unwrap().len(), 24, "the engine's other cells");
}

#[test]
fn compare_engine_sides_bad_inputs_exit_2_with_a_clear_message() {
    let sb = Sandbox::new();
    sb.write("tiny.yaml", &tiny("[1, 2]"));
    sb.fixture("variants.yaml");
    std::fs::create_dir_all(sb.path("empty")).unwrap();
    stdout(&mut sb.qsweep(&["run", "tiny.yaml", "--quiet", "--no-report", "--jobs", "2"]));
    stdout(&mut sb.qsweep(&["report", "tiny.yaml", "--quiet", "--out", "rep", "--formats", "cells"]));
    let cases: &[(&[&str], &str)] = &[
        (&["empty", "tiny.yaml"], "empty: no cells.parquet in this folder"),
        (&["tiny.yaml@nope", "tiny.yaml"], "nope"),
        (&["variants.yaml", "tiny.yaml"], "declares variants (as-written, fast-crisp, short-episodes): compare one of them with variants.yaml@ID"),
        (&["variants.yaml@nope", "tiny.yaml"], "nope"),
        (&["rep@as-written", "rep"], "has no variant column"),
        (&["rep", "rep", "--metric", "converged"], "(report folder) has no metric `converged` (its metrics: episodes)"),
    ];
    for (args, want) in cases {
        let mut all = vec!["compare"];
        all.extend_from_slice(args);
        let err = fails_with(&mut sb.qsweep(&all), 2);
        assert!(err.contains(want), "qsweep {}: {err}", all.join(" "));
    }
}

#[test]
fn compare_where_keeps_only_the_cells_named_and_an_unknown_param_exits_2() {
    let sb = before_after(6, "1.2");
    // A's cells x = 2 and 5 only, B's x = 5 and 6: one cell is matched, the others are one side's.
    let v = json(&sb, &["a.yaml", "b.yaml", "--where-a", "x=2,5", "--where-b", "x=5", "--where-b", "x=5,6"]);
    let cells = v["cells"].as_array().unwrap();
    assert_eq!(cells.len(), 1, "{v}");
    assert_eq!(cells[0]["params"]["x"], 5, "{v}");
    let out = stdout(&mut sb.qsweep(&["compare", "a.yaml", "b.yaml", "--where-a", "x=1,2,3"]));
    assert!(out.starts_with("compared 3 cells of a.yaml and b.yaml"), "{out}");
    let err = fails_with(&mut sb.qsweep(&["compare", "a.yaml", "b.yaml", "--where-b", "y=1"]), 2);
    assert!(err.contains("--where on b.yaml: it has no param `y`; its params: x"), "{err}");
    let err = fails_with(&mut sb.qsweep(&["compare", "a.yaml", "b.yaml", "--where-a", "x"]), 2);
    assert!(err.contains("--where-a x: expected NAME=VALUE"), "{err}");
}
