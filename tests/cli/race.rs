//! Races end to end (`tests/fixtures/pipelines/race.yaml`): a planted worse cell leaves after the
//! first round, a tie runs to `max_seeds`, the trials run are exactly what the rounds imply, a
//! rerun runs nothing, raising `max_seeds` runs only the new rounds, and the result is the same
//! on 1 or 2 threads and under `--shard`.

use crate::helpers::{stdout, Sandbox};
use arrow::array::{Array, BooleanArray, Float64Array, Int64Array, StringArray};
use parquet::arrow::arrow_reader::ParquetRecordBatchReaderBuilder;
use serde_json::Value;

/// Per cell of `cells.parquet`: (experiment, axis value, n, contender).
fn cells(path: &std::path::Path) -> Vec<(String, f64, i64, Option<bool>)> {
    let reader = ParquetRecordBatchReaderBuilder::try_new(std::fs::File::open(path).unwrap())
        .unwrap()
        .build()
        .unwrap();
    let mut out = Vec::new();
    for b in reader {
        let b = b.unwrap();
        let col = |n: &str| b.column(b.schema().index_of(n).unwrap()).clone();
        let exp = col("experiment");
        let exp = exp.as_any().downcast_ref::<StringArray>().unwrap();
        let axis = col("axis1_value");
        let axis = axis.as_any().downcast_ref::<Float64Array>().unwrap();
        let n = col("n");
        let n = n.as_any().downcast_ref::<Int64Array>().unwrap();
        let c = col("contender");
        let c = c.as_any().downcast_ref::<BooleanArray>().unwrap();
        for i in 0..b.num_rows() {
            out.push((
                exp.value(i).to_string(),
                axis.value(i),
                n.value(i),
                (!c.is_null(i)).then(|| c.value(i)),
            ));
        }
    }
    out
}

fn executed(v: &Value) -> u64 {
    v["executed"].as_u64().unwrap()
}

#[test]
fn a_race_drops_the_planted_worse_cell_runs_the_tie_to_max_seeds_and_reruns_nothing() {
    let sb = Sandbox::new();
    let p = sb.fixture("race.yaml");
    let ps = p.to_str().unwrap();
    let first = sb.run_json(&p, &["--jobs", "1"]);
    stdout(&mut sb.qsweep(&["report", ps, "--out", "rep"]));
    let got = cells(&sb.path("rep/cells.parquet"));
    // The planted cell (ε = 1) left after round 0 with its 3 seeds; every contender ran to 7.
    let planted: Vec<_> = got.iter().filter(|c| c.0 == "planted").collect();
    assert_eq!(planted.len(), 3);
    for c in &planted {
        let worse = c.1 == 1.0;
        assert_eq!(c.3, Some(!worse), "{c:?}");
        assert_eq!(c.2, if worse { 3 } else { 7 }, "{c:?}");
    }
    // The tie: both cells count 3 episodes in every trial, so neither can be dropped.
    let tie: Vec<_> = got.iter().filter(|c| c.0 == "tie").collect();
    assert!(tie.iter().all(|c| c.2 == 7 && c.3 == Some(true)), "{tie:?}");
    // Exactly the trials the rounds imply: every cell's n, nothing else.
    let implied: i64 = got.iter().map(|c| c.2).sum();
    assert_eq!(executed(&first) as i64, implied);
    assert_eq!(implied, 3 + 7 + 7 + 7 + 7);

    let table = std::fs::read_to_string(sb.path("rep/table3.csv")).unwrap();
    let header = table.lines().next().unwrap();
    assert!(header.contains(",contenders,reference_config_tied,"), "{header}");
    let rows = crate::helpers::csv_rows(&table);
    assert_eq!(
        (rows[0]["contenders"].as_str(), rows[0]["reference_config_tied"].as_str()),
        ("2", "true"),
        "{table}"
    );
    assert_eq!(
        (rows[1]["contenders"].as_str(), rows[1]["reference_config_tied"].as_str()),
        ("2", ""),
        "no reference, no verdict: {table}"
    );

    // Rerun: nothing to do. Status: every round decided.
    assert_eq!(executed(&sb.run_json(&p, &[])), 0);
    let status: Value = serde_json::from_str(&stdout(&mut sb.qsweep(&["status", ps, "--json"]))).unwrap();
    let race = status["race"].as_array().unwrap();
    assert_eq!(race.len(), 2);
    assert!(race.iter().all(|r| r["finished"] == true && r["rounds_done"] == 3 && r["rounds_max"] == 3));
    assert_eq!(status["missing"], 0);
    let text = stdout(&mut sb.qsweep(&["status", ps]));
    assert!(text.contains("race: 2 heatmaps, 2 finished, 0 still racing"), "{text}");

    // Raising max_seeds runs only the new round: 2 more seeds for each of the 4 contenders.
    let more = sb.run_json(&p, &["--set", "race.max_seeds=9"]);
    assert_eq!(executed(&more), 4 * 2);
    assert_eq!(executed(&sb.run_json(&p, &["--set", "race.max_seeds=9"])), 0);
}

#[test]
fn a_race_is_the_same_on_one_or_two_threads_and_in_shards() {
    let runs: Vec<Sandbox> = (0..3).map(|_| Sandbox::new()).collect();
    for (k, sb) in runs.iter().enumerate() {
        let p = sb.fixture("race.yaml");
        match k {
            0 => drop(sb.run_json(&p, &["--jobs", "1"])),
            1 => drop(sb.run_json(&p, &["--jobs", "2"])),
            _ => {
                // Shards run one round per call: call both until neither has anything left.
                let mut calls = 0;
                loop {
                    let a = executed(&sb.run_json(&p, &["--shard", "1/2"]));
                    let b = executed(&sb.run_json(&p, &["--shard", "2/2"]));
                    calls += 1;
                    if a + b == 0 {
                        break;
                    }
                    assert!(calls < 10, "a sharded race must end");
                }
                assert_eq!(calls, 4, "3 rounds, then a call that finds nothing");
            }
        }
        stdout(&mut sb.qsweep(&["report", p.to_str().unwrap(), "--out", "rep"]));
    }
    let read = |sb: &Sandbox, f: &str| std::fs::read(sb.path(&format!("rep/{f}"))).unwrap();
    for f in ["cells.parquet", "table3.csv", "figures/ball-beam.svg"] {
        assert_eq!(read(&runs[0], f), read(&runs[1], f), "{f}: --jobs 1 vs 2");
        assert_eq!(read(&runs[0], f), read(&runs[2], f), "{f}: one machine vs shards");
    }
}

#[test]
fn without_a_race_reports_have_no_race_columns() {
    let sb = Sandbox::new();
    let p = sb.fixture("race.yaml");
    let text = std::fs::read_to_string(&p).unwrap().replace("race: {", "# race: {");
    let plain = sb.write("plain.yaml", &text);
    sb.run_json(&plain, &[]);
    stdout(&mut sb.qsweep(&["report", plain.to_str().unwrap(), "--out", "rep"]));
    let table = std::fs::read_to_string(sb.path("rep/table3.csv")).unwrap();
    assert!(!table.contains("contenders"), "{table}");
    let f = std::fs::File::open(sb.path("rep/cells.parquet")).unwrap();
    let schema = ParquetRecordBatchReaderBuilder::try_new(f).unwrap().schema().clone();
    assert!(schema.index_of("contender").is_err());
    let status = stdout(&mut sb.qsweep(&["status", plain.to_str().unwrap(), "--json"]));
    let status: Value = serde_json::from_str(&status).unwrap();
    assert!(status.get("race").is_none(), "{status}");
}

#[test]
fn slurm_chains_one_array_per_round_for_a_race() {
    let sb = Sandbox::new();
    let p = sb.fixture("race.yaml");
    let script = stdout(&mut sb.qsweep(&["slurm", p.to_str().unwrap(), "--array", "2"]));
    assert_eq!(script.matches("<<'QSWEEP_SHARD_JOB'").count(), 3, "3 rounds at most: {script}");
    assert_eq!(script.matches("--dependency=afterany:\"$array_job\"").count(), 2, "rounds 2 and 3");
    assert_eq!(script.matches("--dependency=afterok:\"$array_job\"").count(), 1, "the report");
}

/// `pipelines/paper-race.yaml` writes paper.yaml's grid out again with the `gym-v0-reset`
/// settings: its trials must be that variant's (same keys), so its first rounds come from the
/// committed cache and its report compares with the variant's.
#[test]
fn paper_race_races_the_trials_of_paper_yaml_gym_v0_reset() {
    let root = crate::helpers::repo().join("pipelines");
    let race = qsweep_pipeline::declared::load(&root.join("paper-race.yaml"), &[]).unwrap();
    let race = qsweep_pipeline::plan::plan(&race, None).unwrap();
    let paper = qsweep_pipeline::declared::load(&root.join("paper.yaml"), &[]).unwrap();
    let paper = qsweep_pipeline::plan::plan_variants(&paper, None, &["gym-v0-reset".to_string()]).unwrap();
    assert_eq!(race.experiments.len(), paper.experiments.len());
    let mut cells = 0;
    for (r, p) in race.experiments.iter().zip(&paper.experiments) {
        assert!(r.race.is_some() && p.race.is_none());
        assert_eq!(r.reference, p.reference, "{} exp {}", r.system, r.id);
        for (rc, pc) in r.cells.iter().zip(&p.cells) {
            assert_eq!(
                rc.trials[..],
                pc.trials[..rc.trials.len()],
                "{} exp {} {:?}",
                r.system,
                r.id,
                rc.coords
            );
            cells += 1;
        }
    }
    assert_eq!(cells, 1944);
}

/// `gc PIPELINE` keeps the rows its plan references: for a race, every round it has run, which
/// only the cache can tell (the plan alone has round 0).
#[test]
fn gc_keeps_the_later_rounds_of_a_race() {
    let sb = Sandbox::new();
    let p = sb.fixture("race.yaml");
    assert_eq!(executed(&sb.run_json(&p, &[])), 31);
    let said = stdout(&mut sb.qsweep(&["gc", p.to_str().unwrap()]));
    assert!(said.contains("31 rows kept, 0 removed"), "{said}");
    assert_eq!(executed(&sb.run_json(&p, &[])), 0);
}

/// Regression: shards of a race started at different times used to split the plan as each saw
/// it, and the plan grows as rounds are decided, so a trial could move to a shard that had
/// already run and a round array could end with its round incomplete. Trials now have a fixed
/// owner, so four arrays (the most rounds with max_seeds 9) of seven tasks each, run one task
/// after another, finish the race (with the old split, 7 shards left a heatmap racing).
#[test]
fn shards_started_at_different_times_finish_a_race_in_its_number_of_rounds() {
    let sb = Sandbox::new();
    let p = sb.fixture("race.yaml");
    let more = ["--set", "race.max_seeds=9"];
    for _array in 0..4 {
        for i in 1..=7 {
            let shard = format!("{i}/7");
            sb.run_json(&p, &[more[0], more[1], "--shard", &shard]);
        }
    }
    let mut args = vec!["status", p.to_str().unwrap(), "--json"];
    args.extend(more);
    let status: Value = serde_json::from_str(&stdout(&mut sb.qsweep(&args))).unwrap();
    let race = status["race"].as_array().unwrap();
    assert!(race.iter().all(|r| r["finished"] == true), "{race:?}");
    assert_eq!(status["missing"], 0);
    assert_eq!(executed(&sb.run_json(&p, &more)), 0);
}

/// The confirmation limit counts a race at `max_seeds` (the most it can run), not its first round.
#[test]
fn a_race_that_could_run_huge_needs_yes() {
    let sb = Sandbox::new();
    let p = sb.fixture("race.yaml");
    let ps = p.to_str().unwrap();
    let err =
        crate::helpers::fails_with(&mut sb.qsweep(&["status", ps, "--set", "race.max_seeds=300000"]), 2);
    assert!(err.contains("the plan has 1500000 trials"), "{err}");
    stdout(&mut sb.qsweep(&["status", ps, "--set", "race.max_seeds=300000", "--yes"]));
}

/// A race set by one variant: every variant's files carry the race columns (null where the
/// variant does not race), whether reported together or alone with `--variant`, so the combined
/// files concatenate and a folder reads the same however it was written.
#[test]
fn a_race_in_one_variant_gives_every_variant_the_race_columns() {
    let sb = Sandbox::new();
    let text = std::fs::read_to_string(crate::helpers::repo().join("tests/fixtures/pipelines/race.yaml"))
        .unwrap()
        .replace("race: {", "# race: {");
    let text = format!(
        "{text}variants:\n  - id: plain\n  - id: raced\n    set: {{ race: {{ confidence: 0.95, batch: 2, max_seeds: 7 }} }}\n"
    );
    let p = sb.write("v.yaml", &text);
    let ps = p.to_str().unwrap();
    sb.run_json(&p, &[]);
    stdout(&mut sb.qsweep(&["report", ps, "--out", "all"]));
    stdout(&mut sb.qsweep(&["report", ps, "--out", "one", "--variant", "plain"]));
    for f in ["all/cells.parquet", "all/plain/cells.parquet", "one/plain/cells.parquet"] {
        let file = std::fs::File::open(sb.path(f)).unwrap();
        let schema = ParquetRecordBatchReaderBuilder::try_new(file).unwrap().schema().clone();
        assert!(schema.index_of("contender").is_ok(), "{f}");
    }
    assert_eq!(
        std::fs::read(sb.path("all/plain/cells.parquet")).unwrap(),
        std::fs::read(sb.path("one/plain/cells.parquet")).unwrap()
    );
}
