//! A program pipeline's rows in the cache (issue 61): `verify` checks the program folders like the
//! engine's segments and `verify PIPELINE --recompute N` reruns stored trials in fresh processes,
//! naming each metric that differs; `gc` compacts each program folder on its own and prunes it
//! only by the program pipelines of its schema; `status` says when rows may be under another
//! schema.

use crate::helpers::{fails_with, stdout, Sandbox};
use crate::programs::{doubler_yaml, DOUBLER};
use qsweep_pipeline::program::model::{MetricType, ParamType};
use qsweep_pipeline::program::rows::{folder, read_segment, write_segment, RowSchema};
use std::path::PathBuf;

/// The program folders of the sandbox's cache, and their segments.
fn folders(sb: &Sandbox) -> Vec<(PathBuf, Vec<PathBuf>)> {
    let mut out: Vec<(PathBuf, Vec<PathBuf>)> =
        std::fs::read_dir(sb.cache().join(qsweep_pipeline::program::rows::PROGRAMS_DIR))
            .unwrap()
            .map(|e| e.unwrap().path())
            .map(|d| {
                let mut segs: Vec<PathBuf> = std::fs::read_dir(&d)
                    .unwrap()
                    .map(|e| e.unwrap().path())
                    .filter(|p| p.file_name().unwrap().to_string_lossy().starts_with("seg-"))
                    .collect();
                segs.sort();
                (d, segs)
            })
            .collect();
    out.sort();
    out
}

/// A pipeline of a program reporting `time.time()`: it never gives the same row twice.
const CLOCK: &str = "name: clock\nseeds: 1\nprogram:\n  command: [python3, -c, 'import json, sys, time; json.loads(sys.stdin.readline()); print(json.dumps({\"t\": time.time(), \"n\": 1}))']\n  metrics: { t: float, n: int }\nparams: { x: 1 }\nexperiments:\n  - { id: e, vary: { x: [1, 2, 3] } }\n";

#[test]
fn program_verify_recompute_catches_a_program_that_returns_the_time_and_passes_a_deterministic_one() {
    let sb = Sandbox::new();
    sb.write("clock.yaml", CLOCK);
    sb.write("prog.sh", DOUBLER);
    sb.write("det.yaml", &doubler_yaml("det", "1, 2, 3", 2));
    stdout(&mut sb.qsweep(&["run", "clock.yaml"]));
    stdout(&mut sb.qsweep(&["run", "det.yaml"]));
    let out =
        sb.qsweep(&["verify", "clock.yaml", "--recompute", "5"]).assert().code(1).get_output().stdout.clone();
    let out = String::from_utf8(out).unwrap();
    let differs: Vec<&str> = out.lines().filter(|l| l.starts_with("differs: trial ")).collect();
    assert_eq!(differs.len(), 3, "{out}");
    assert!(
        differs
            .iter()
            .all(|l| l.contains("metric `t`: stored ") && l.contains(", now ") && !l.contains("`n`")),
        "{out}"
    );
    assert!(
        out.contains("recomputed 3 of 3 stored trials of pipeline 'clock'") && out.contains("3 differ"),
        "{out}"
    );
    let out = stdout(&mut sb.qsweep(&["verify", "det.yaml", "--recompute", "4", "--seed", "9"]));
    assert!(out.contains("recomputed 4 of 6 stored trials of pipeline 'det' (draw seed 9)"), "{out}");
    assert!(out.contains("all 4 agree with the stored rows"), "{out}");
    assert!(
        out.contains("program rows: 2 folders, 2 segments, 9 rows (9 distinct trials) intact, 0 damaged"),
        "{out}"
    );
    // The draw is a fixed function of the seed and the cache.
    let again = stdout(&mut sb.qsweep(&["verify", "det.yaml", "--recompute", "4", "--seed", "9"]));
    let drawn = |s: &str| {
        s.lines().find(|l| l.starts_with("recomputed")).unwrap().split(" in ").next().unwrap().to_string()
    };
    assert_eq!(drawn(&out), drawn(&again));
    // An engine pipeline is no program to rerun.
    let tiny = sb.fixture("tiny.yaml");
    let err = fails_with(&mut sb.qsweep(&["verify", tiny.to_str().unwrap(), "--recompute", "1"]), 2);
    assert!(err.contains("is not a program pipeline"), "{err}");
}

#[test]
fn program_verify_moves_damaged_program_segments_aside() {
    let sb = Sandbox::new();
    sb.write("prog.sh", DOUBLER);
    sb.write("p.yaml", &doubler_yaml("p", "1, 2", 2));
    sb.write("q.yaml", &doubler_yaml("q", "1", 1).replace("y: int", "y: float"));
    stdout(&mut sb.qsweep(&["run", "p.yaml"]));
    stdout(&mut sb.qsweep(&["run", "q.yaml"]));
    let schema = |y| RowSchema { params: vec![("x".into(), ParamType::Int)], metrics: vec![("y".into(), y)] };
    let (p_dir, q_dir) =
        (folder(&sb.cache(), &schema(MetricType::Int)), folder(&sb.cache(), &schema(MetricType::Float)));
    let segs = |d: &PathBuf| folders(&sb).into_iter().find(|(f, _)| f == d).unwrap().1;
    let (p_segs, q_segs) = (segs(&p_dir), segs(&q_dir));
    assert_eq!((p_segs.len(), q_segs.len()), (1, 1));
    // Garbage, a segment of another schema, and a row whose params no longer hash to its key.
    std::fs::write(p_dir.join("seg-garbage.parquet"), b"PAR1 not really").unwrap();
    std::fs::copy(&q_segs[0], p_dir.join("seg-other-schema.parquet")).unwrap();
    let schema = qsweep_pipeline::program::folders::schema_of(&p_segs[0]).unwrap();
    let mut forged = read_segment(&p_segs[0], &schema, &|_| true).unwrap();
    forged.truncate(1);
    forged[0].params[0] = qsweep_pipeline::program::model::ParamValue::Int(99);
    let store = qsweep_pipeline::cache::Store::open(&p_dir).unwrap();
    let forged_path = write_segment(&store, &schema, &forged).unwrap();
    let out = sb.qsweep(&["verify"]).assert().code(1).get_output().stdout.clone();
    let out = String::from_utf8(out).unwrap();
    assert!(out.contains("seg-garbage.parquet"), "{out}");
    assert!(
        out.contains(&format!(
            "rows of schema {} in the folder of schema",
            q_dir.file_name().unwrap().to_string_lossy()
        )),
        "{out}"
    );
    assert!(out.contains("do not hash to its key"), "{out}");
    assert!(
        out.contains("program rows: 2 folders, 5 segments, 5 rows (4 distinct trials) intact, 3 damaged"),
        "{out}"
    );
    assert!(p_dir.join("_quarantine/seg-garbage.parquet").is_file() && !forged_path.exists());
    let out = stdout(&mut sb.qsweep(&["verify"]));
    assert!(
        out.contains("program rows: 2 folders, 2 segments, 5 rows (4 distinct trials) intact, 0 damaged"),
        "{out}"
    );
    let status = stdout(&mut sb.qsweep(&["status", "p.yaml"]));
    assert!(status.contains("total: 4 trials, 4 cached (0 failed), 0 missing"), "{status}");
}

#[test]
fn program_gc_compacts_each_folder_and_prunes_only_by_program_pipelines_of_its_schema() {
    let sb = Sandbox::new();
    sb.write("prog.sh", DOUBLER);
    sb.write("a.yaml", &doubler_yaml("a", "1, 2, 3", 1));
    sb.write("b.yaml", &doubler_yaml("b", "3, 4", 1));
    sb.write("c.yaml", &doubler_yaml("c", "1", 1).replace("y: int", "y: float"));
    let tiny = sb.fixture("tiny.yaml");
    for p in ["a.yaml", "b.yaml", "c.yaml"] {
        stdout(&mut sb.qsweep(&["run", p]));
    }
    let before = folders(&sb);
    assert_eq!(before.iter().map(|(_, s)| s.len()).collect::<Vec<_>>().iter().sum::<usize>(), 3);
    let cached = |p: &str| {
        let s = stdout(&mut sb.qsweep(&["status", p]));
        s.lines().find(|l| l.starts_with("total: ")).unwrap().to_string()
    };
    let dry = stdout(&mut sb.qsweep(&["gc", "--dry-run"]));
    assert!(dry.contains("program rows (2 folders): 3 segments → 2, 5 rows kept, 0 removed"), "{dry}");
    assert_eq!(folders(&sb), before, "a dry run changes nothing");
    let out = stdout(&mut sb.qsweep(&["gc"]));
    assert!(out.contains("program rows (2 folders): 3 segments → 2, 5 rows kept, 0 removed"), "{out}");
    assert!(folders(&sb).iter().all(|(_, s)| s.len() == 1));
    assert_eq!(
        cached("b.yaml"),
        format!("total: 2 trials, 2 cached (0 failed), 0 missing (cache: {})", sb.cache().display())
    );
    // An engine pipeline prunes no program row: every folder is left alone.
    let out = stdout(&mut sb.qsweep(&["gc", tiny.to_str().unwrap()]));
    assert!(out.contains("program rows (0 folders)") && out.contains("2 folders left alone"), "{out}");
    assert!(cached("b.yaml").contains("2 cached"));
    // A program pipeline prunes its schema's folder to its keys and leaves the other alone.
    let out = stdout(&mut sb.qsweep(&["gc", "a.yaml"]));
    assert!(out.contains("program rows (1 folders): 1 segments → 1, 3 rows kept, 1 removed"), "{out}");
    assert!(out.contains("1 folders left alone"), "{out}");
    assert!(cached("b.yaml").contains("1 cached (0 failed), 1 missing"), "{}", cached("b.yaml"));
    assert!(cached("c.yaml").contains("1 cached (0 failed), 0 missing"), "{}", cached("c.yaml"));
}

#[test]
fn program_status_says_when_rows_may_be_under_another_schema() {
    let sb = Sandbox::new();
    sb.write("prog.sh", DOUBLER);
    sb.write("p.yaml", &doubler_yaml("p", "1, 2", 1));
    stdout(&mut sb.qsweep(&["run", "p.yaml"]));
    sb.write("p.yaml", &doubler_yaml("p", "1, 2", 1).replace("y: int", "y: float"));
    let status = stdout(&mut sb.qsweep(&["status", "p.yaml", "--explain"]));
    assert!(status.contains("2 missing"), "{status}");
    assert!(
        status.contains("rows may be under another schema (a param's type or the metrics changed"),
        "{status}"
    );
}
