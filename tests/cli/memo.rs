//! The report reruns only what changed (issue 37): a file whose bytes would not change is not
//! rewritten (its mtime stays), and the report line says how many files were rewritten.

use crate::helpers::Sandbox;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::SystemTime;

/// Every file under `dir` (recursively) with its mtime.
fn mtimes(dir: &Path) -> BTreeMap<PathBuf, SystemTime> {
    let mut out = BTreeMap::new();
    let mut todo = vec![dir.to_path_buf()];
    while let Some(d) = todo.pop() {
        for e in std::fs::read_dir(&d).unwrap().flatten() {
            let p = e.path();
            if p.is_dir() {
                todo.push(p);
            } else {
                out.insert(
                    p.strip_prefix(dir).unwrap().to_path_buf(),
                    e.metadata().unwrap().modified().unwrap(),
                );
            }
        }
    }
    out
}

/// `files: N rewritten, M unchanged` of a report line.
fn files_line(stdout: &str) -> (usize, usize) {
    let tail = stdout.split("files: ").nth(1).unwrap_or_else(|| panic!("no files count: {stdout}"));
    let n: Vec<usize> = tail
        .split(|c: char| !c.is_ascii_digit())
        .filter(|s| !s.is_empty())
        .take(2)
        .map(|s| s.parse().unwrap())
        .collect();
    (n[0], n[1])
}

#[test]
fn a_second_report_rewrites_no_file_and_keeps_every_mtime() {
    let sb = Sandbox::new();
    let p = sb.fixture("variants.yaml");
    let (p, out) = (p.to_str().unwrap(), sb.path("rep"));
    let o = out.to_str().unwrap();
    let first = crate::helpers::stdout(&mut sb.qsweep(&["run", p, "--out", o]));
    let (written, unchanged) = files_line(&first);
    assert!(written > 20 && unchanged == 0, "{first}");
    let before = mtimes(&out);
    std::thread::sleep(std::time::Duration::from_millis(50));
    let again = crate::helpers::stdout(&mut sb.qsweep(&["report", p, "--out", o]));
    assert_eq!(files_line(&again), (0, written), "{again}");
    assert_eq!(mtimes(&out), before, "no file rewritten, trials.parquet included");
    assert!(before.contains_key(Path::new("trials.parquet")));
}
