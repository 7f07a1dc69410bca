//! Races and fresh seeds in a program pipeline (issue 62, items 1 and 2): a race spends fewer
//! trials than the full grid and keeps the expected best cell, a rerun runs nothing, the best cell
//! runs its fresh seeds exactly once and the report shows them; a race without an objective is a
//! `FILE:LINE:COL` error (exit 2) before anything runs.

use crate::helpers::{fails_with, stdout, Sandbox};
use crate::programs::{read_parquet, summary};
use arrow::array::{Array, BooleanArray, Float64Array, Int64Array, StringArray, UInt64Array};

/// A deterministic agent: y = x + (7·seed mod 5), the same noise in every cell, so the cells differ
/// by x exactly; it logs every trial it runs as `x seed`.
const AGENT: &str = r#"import json, sys
c = json.load(sys.stdin)
with open("runs.log", "a") as f:
    f.write(f"{c['x']} {c['seed']}\n")
print(json.dumps({"y": c["x"] + (7 * c["seed"]) % 5}))
"#;

/// Cells x = 0, 1, 5, 9 from 3 seeds, raced in batches of 3 to 9 seeds, the best cell then on 4
/// fresh seeds.
const RACED: &str =
    "name: raced\nseeds: 3\nprogram:\n  command: [python3, agent.py]\n  inputs: [agent.py]\n  \
metrics: { y: float }\n  objective: { metric: y, goal: minimize }\nparams: { x: 0 }\n\
race: { confidence: 0.95, batch: 3, max_seeds: 9 }\nfresh: { first_seed: 100, seeds: 4 }\n\
experiments:\n  - { id: e, vary: { x: [0, 1, 5, 9] } }\n";

fn sandbox(yaml: &str) -> Sandbox {
    let sb = Sandbox::new();
    sb.write("agent.py", AGENT);
    sb.write("x.yaml", yaml);
    sb
}

/// Each logged trial as (x, seed).
fn runs(sb: &Sandbox) -> Vec<(i64, u64)> {
    let text = std::fs::read_to_string(sb.path("runs.log")).unwrap_or_default();
    let mut out: Vec<(i64, u64)> = text
        .lines()
        .map(|l| {
            let (x, s) = l.split_once(' ').unwrap();
            (x.parse().unwrap(), s.parse().unwrap())
        })
        .collect();
    out.sort_unstable();
    out
}

#[test]
fn program_race_spends_fewer_trials_than_the_grid_keeps_the_best_and_a_rerun_runs_nothing() {
    let sb = sandbox(RACED);
    let out = stdout(&mut sb.qsweep(&["run", "x.yaml", "--jobs", "2"]));
    // x = 5 and x = 9 leave after round 0 (3 seeds); x = 0 and x = 1 are too close to tell apart
    // and run to max_seeds: 9 + 9 + 3 + 3 = 24 of the grid's 4 × 9 = 36, then 4 fresh seeds.
    assert!(summary(&out).starts_with("executed 28, cached 0, failed 0 "), "{out}");
    let ran = runs(&sb);
    assert_eq!(ran.len(), 28);
    let of = |x: i64| ran.iter().filter(|r| r.0 == x).map(|r| r.1).collect::<Vec<u64>>();
    assert_eq!(of(0), [0, 1, 2, 3, 4, 5, 6, 7, 8, 100, 101, 102, 103], "the best cell, then its fresh seeds");
    assert_eq!(of(1), (0..9).collect::<Vec<u64>>());
    assert_eq!(of(5), [0, 1, 2]);
    assert_eq!(of(9), [0, 1, 2]);

    // A rerun replays the race and the fresh stage from the cache: nothing runs.
    let again = stdout(&mut sb.qsweep(&["run", "x.yaml"]));
    assert!(summary(&again).starts_with("executed 0, cached 28,"), "{again}");
    assert_eq!(runs(&sb).len(), 28);
    let status = stdout(&mut sb.qsweep(&["status", "x.yaml"]));
    assert!(status.contains("total: 28 trials, 28 cached (0 failed), 0 missing"), "{status}");
    assert!(
        status.contains("race exp e: 3 of at most 3 rounds decided (over), 2 of 4 cells contenders, 24 trials so far of 36 for the full grid"),
        "{status}"
    );

    // The report: the race's spending, the best cell with its fresh-seed estimate.
    let dir = sb.path("reports/raced");
    let readme = std::fs::read_to_string(dir.join("README.md")).unwrap();
    assert!(readme.contains("Trials present: 28 of 28 planned"), "{readme}");
    assert!(
        readme.contains("the race spent 24 trials where the full grid at max_seeds would take 36"),
        "{readme}"
    );
    // Selection: y over seeds 0..8 of x = 0 is 0 2 4 1 3 0 2 4 1 (mean 17/9); fresh seeds 100..103
    // give 0 2 4 1 (mean 1.75).
    assert!(
        readme.contains("Best cell by y (lowest mean among the race's contenders): x = 0, 1.8889 ± "),
        "{readme}"
    );
    assert!(readme.contains("over n = 9 (selection estimate: on the seeds that chose it). On 4 fresh seeds, which took no part in choosing it: 1.75 ± 1.7078 \\[0.5, 3.25\\] (95 % interval) over n = 4."), "{readme}");
    let html = std::fs::read_to_string(dir.join("index.html")).unwrap();
    assert!(html.contains("On 4 fresh seeds"), "the pages say the same");
    let svg = std::fs::read_to_string(dir.join("figures/e.svg")).unwrap();
    assert!(svg.contains("left the race"), "the legend explains the marking");

    let cells = read_parquet(&dir.join("cells.parquet"));
    assert_eq!(cells.num_rows(), 4);
    let col = |n: &str| cells.column_by_name(n).unwrap_or_else(|| panic!("no column {n}"));
    let x = col("x").as_any().downcast_ref::<Int64Array>().unwrap();
    let contender = col("contender").as_any().downcast_ref::<BooleanArray>().unwrap();
    let best = col("best").as_any().downcast_ref::<BooleanArray>().unwrap();
    let n = col("n").as_any().downcast_ref::<UInt64Array>().unwrap();
    let fresh_n = col("fresh_n").as_any().downcast_ref::<UInt64Array>().unwrap();
    let fresh_mean = col("fresh_mean").as_any().downcast_ref::<Float64Array>().unwrap();
    let rows: Vec<(i64, bool, bool, u64)> =
        (0..4).map(|i| (x.value(i), contender.value(i), best.value(i), n.value(i))).collect();
    assert_eq!(rows, [(0, true, true, 9), (1, true, false, 9), (5, false, false, 3), (9, false, false, 3)]);
    assert_eq!((fresh_n.value(0), fresh_mean.value(0)), (4, 1.75));
    assert!((1..4).all(|i| fresh_n.is_null(i) && fresh_mean.is_null(i)));
    let trials = read_parquet(&dir.join("trials.parquet"));
    let fresh = trials.column_by_name("fresh").unwrap().as_any().downcast_ref::<BooleanArray>().unwrap();
    assert_eq!(trials.num_rows(), 28);
    assert_eq!((0..28).filter(|&i| fresh.value(i)).count(), 4);
    let experiment =
        trials.column_by_name("experiment").unwrap().as_any().downcast_ref::<StringArray>().unwrap();
    assert!((0..28).all(|i| experiment.value(i) == "e"));

    // `report --rebuild` gives the same bytes.
    let before = std::fs::read(dir.join("cells.parquet")).unwrap();
    sb.qsweep(&["report", "x.yaml", "--rebuild"]).assert().success();
    assert_eq!(std::fs::read(dir.join("cells.parquet")).unwrap(), before);
}

#[test]
fn program_race_without_an_objective_is_file_line_col_and_exit_2() {
    let sb = sandbox(
        &RACED
            .replace("  objective: { metric: y, goal: minimize }\n", "")
            .replace("fresh: { first_seed: 100, seeds: 4 }\n", ""),
    );
    let err = fails_with(&mut sb.qsweep(&["run", "x.yaml"]), 2);
    assert!(err.contains("x.yaml:8:1: race:"), "{err}");
    assert!(err.contains("`program.objective` is not declared"), "{err}");
    assert_eq!(runs(&sb).len(), 0, "nothing ran");
    // Per experiment, at its own block.
    let per = RACED
        .replace("  objective: { metric: y, goal: minimize }\n", "")
        .replace(
            "race: { confidence: 0.95, batch: 3, max_seeds: 9 }\nfresh: { first_seed: 100, seeds: 4 }\n",
            "",
        )
        .replace(
            "vary: { x: [0, 1, 5, 9] } }",
            "vary: { x: [0, 1, 5, 9] }, race: { confidence: 0.95, batch: 3, max_seeds: 9 } }",
        );
    let sb = sandbox(&per);
    let err = fails_with(&mut sb.qsweep(&["status", "x.yaml"]), 2);
    assert!(err.contains("x.yaml:9:") && err.contains("experiments.0.race"), "{err}");
}

#[test]
fn program_gc_given_a_raced_pipeline_keeps_its_race_and_fresh_trials() {
    let sb = sandbox(RACED);
    stdout(&mut sb.qsweep(&["run", "x.yaml", "--jobs", "2", "--no-report"]));
    // A row no plan references: the same program at x = 42, dropped by gc with the raced pipeline.
    sb.write("other.yaml", &RACED.replace("name: raced", "name: other").replace("[0, 1, 5, 9]", "[42]"));
    stdout(&mut sb.qsweep(&["run", "other.yaml", "--no-report"]));
    let out = stdout(&mut sb.qsweep(&["gc", "x.yaml"]));
    assert!(out.contains("removed"), "{out}");
    // Every raced and fresh trial is still there: a rerun runs nothing, and neither does status miss any.
    let again = stdout(&mut sb.qsweep(&["run", "x.yaml", "--no-report"]));
    assert!(summary(&again).starts_with("executed 0, cached 28, failed 0 "), "{again}");
    assert_eq!(runs(&sb).len(), 28 + 3 + 4, "the other pipeline's 3 + 4 trials, and nothing since");
    // The other pipeline's rows are gone: its rerun runs them again.
    let other = stdout(&mut sb.qsweep(&["run", "other.yaml", "--no-report"]));
    assert!(summary(&other).starts_with("executed 7, cached 0, failed 0 "), "{other}");
}

#[test]
fn program_status_json_lists_each_race_as_the_text_does() {
    let sb = sandbox(RACED);
    stdout(&mut sb.qsweep(&["run", "x.yaml", "--jobs", "2", "--no-report"]));
    let v: serde_json::Value =
        serde_json::from_str(&stdout(&mut sb.qsweep(&["status", "x.yaml", "--json"]))).unwrap();
    let race = &v["race"][0];
    assert_eq!(
        (race["experiment"].as_str(), race["cells"].as_u64(), race["contenders"].as_u64()),
        (Some("e"), Some(4), Some(2)),
        "{v}"
    );
    assert_eq!((race["trials"].as_u64(), race["without_race"].as_u64()), (Some(24), Some(36)), "{v}");
    assert_eq!(race["finished"].as_bool(), Some(true), "{v}");
    assert_eq!(race["rounds_done"], race["rounds_max"], "{v}");
}
