//! Reports of different plans of one pipeline at once on one cache (a Slurm report job beside a
//! user's own report with `--set` or `--variant`): none removes a trial part another is about to
//! splice, each writes what it would alone, and a later report alone prunes what it did not use.

use crate::helpers::{stdout, Sandbox};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};

/// `qsweep report` of `pipeline` into `out` in the background, with the sandbox's cache.
fn spawn_report(sb: &Sandbox, pipeline: &Path, out: &str, extra: &[&str]) -> Child {
    Command::new(assert_cmd::cargo::cargo_bin("qsweep"))
        .current_dir(sb.dir.path())
        .env_remove("QSWEEP_CACHE")
        .args(["report", pipeline.to_str().unwrap(), "--quiet", "--out", out])
        .args(extra)
        .arg("--cache")
        .arg(sb.cache())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap()
}

/// Wait for a report started by [`spawn_report`]; it must succeed without a warning.
fn succeeds(child: Child, what: &str) {
    let out = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(0), "{what}: {stderr}");
    assert!(stderr.is_empty(), "{what}: {stderr}");
}

/// Every file under `dir` with its bytes.
fn tree(dir: &Path) -> BTreeMap<PathBuf, Vec<u8>> {
    let mut out = BTreeMap::new();
    let mut todo = vec![dir.to_path_buf()];
    while let Some(d) = todo.pop() {
        for p in std::fs::read_dir(&d).unwrap().flatten().map(|e| e.path()) {
            if p.is_dir() {
                todo.push(p);
            } else {
                out.insert(p.strip_prefix(dir).unwrap().to_path_buf(), std::fs::read(&p).unwrap());
            }
        }
    }
    out
}

/// The trial parts kept in the cache.
fn parts(sb: &Sandbox) -> Vec<PathBuf> {
    let dir = sb.cache().join("_derived/variants.trials");
    let mut v: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap()
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|x| x == "parquet"))
        .collect();
    v.sort();
    v
}

#[test]
fn reports_of_different_plans_at_once_never_remove_each_others_trial_parts() {
    let sb = Sandbox::new();
    let p = sb.fixture("variants.yaml");
    let ps = p.to_str().unwrap();
    // Both plans' trials in the cache; their variants' rows differ, so do their parts.
    let more = ["--set", "seeds=3"];
    stdout(&mut sb.qsweep(&["run", ps, "--quiet", "--no-report"]));
    stdout(&mut sb.qsweep(&["run", ps, "--quiet", "--no-report", "--set", "seeds=3"]));
    // Each plan's report alone, the reference for the concurrent ones.
    stdout(&mut sb.qsweep(&["report", ps, "--quiet", "--out", "alone-a"]));
    stdout(&mut sb.qsweep(&["report", ps, "--quiet", "--out", "alone-b", "--set", "seeds=3"]));
    stdout(&mut sb.qsweep(&["report", ps, "--quiet", "--out", "alone-v", "--variant", "fast-crisp"]));
    for round in 0..4 {
        // Fresh folders, so that every report decides which parts to reuse and splices them. The
        // first to finish used to prune the parts the other had chosen: `cannot read …`.
        let (a, b, v) = (format!("a{round}"), format!("b{round}"), format!("v{round}"));
        let ra = spawn_report(&sb, &p, &a, &[]);
        let rb = spawn_report(&sb, &p, &b, &more);
        let rv = spawn_report(&sb, &p, &v, &["--variant", "fast-crisp"]);
        succeeds(ra, &format!("round {round}, as written"));
        succeeds(rb, &format!("round {round}, --set seeds=3"));
        succeeds(rv, &format!("round {round}, --variant fast-crisp"));
        // Each report is the one it would be alone, file for file, trials.parquet included.
        for (dir, alone) in [(&a, "alone-a"), (&b, "alone-b"), (&v, "alone-v")] {
            let (got, want) = (tree(&sb.path(dir)), tree(&sb.path(alone)));
            assert_eq!(
                got.keys().collect::<Vec<_>>(),
                want.keys().collect::<Vec<_>>(),
                "round {round}: {dir}"
            );
            assert!(got.contains_key(Path::new("trials.parquet")) || dir == &v, "{dir}");
            for (name, bytes) in &got {
                assert!(
                    bytes == &want[name],
                    "round {round}: {dir}/{} is not the lone report's",
                    name.display()
                );
            }
        }
    }
    // A full report alone keeps only the parts it used: one per declared variant.
    stdout(&mut sb.qsweep(&["report", ps, "--quiet", "--out", "last"]));
    assert_eq!(parts(&sb).len(), 3, "{:?}", parts(&sb));
}

#[test]
fn a_report_prunes_and_gc_drops_trial_parts_only_when_no_report_holds_them() {
    use qsweep_report::memo::stats::readers::Reading;
    let sb = Sandbox::new();
    let p = sb.fixture("variants.yaml");
    let ps = p.to_str().unwrap();
    stdout(&mut sb.qsweep(&["run", ps, "--quiet", "--out", "a"]));
    stdout(&mut sb.qsweep(&["run", ps, "--quiet", "--no-report", "--set", "seeds=3"]));
    let first = parts(&sb);
    assert_eq!(first.len(), 3);
    let dir = sb.cache().join("_derived/variants.trials");
    // Another report holds the folder (this test, as a report between choosing and splicing its
    // parts would): a full report of another plan leaves the parts it did not use.
    let reading = Reading::hold(&dir);
    stdout(&mut sb.qsweep(&["report", ps, "--quiet", "--out", "b", "--set", "seeds=3"]));
    assert_eq!(parts(&sb).len(), 6, "the held parts stay beside the new ones");
    assert!(first.iter().all(|f| f.is_file()));
    // Let go: the next full report prunes what it did not use.
    drop(reading);
    stdout(&mut sb.qsweep(&["report", ps, "--quiet", "--out", "c", "--set", "seeds=3"]));
    let second = parts(&sb);
    assert_eq!(second.len(), 3);
    assert!(first.iter().all(|f| !second.contains(f)), "the other plan's parts went");
    // `qsweep gc` of another pipeline leaves a held folder, and says so; once let go, drops it.
    let reading = Reading::hold(&dir);
    let tiny = sb.fixture("tiny.yaml");
    let gc = || sb.qsweep(&["gc", tiny.to_str().unwrap()]).assert().success().get_output().stderr.clone();
    let err = String::from_utf8(gc()).unwrap();
    assert!(err.contains("warning: left trial parts in place, a report is reading them"), "{err}");
    assert_eq!(parts(&sb), second);
    drop(reading);
    let err = gc();
    assert!(err.is_empty(), "{}", String::from_utf8_lossy(&err));
    assert!(!dir.exists(), "no report holds it: gc drops the folder of a pipeline not given");
}
