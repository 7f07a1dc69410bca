//! The report stage as a user meets it: `--formats`, the manifest the overwrite guard reads, bad
//! input about the report folder, stale files of a changed report, and damaged segments handled
//! by `report` exactly as by `run`.

use crate::helpers::{Sandbox, Test};

#[test]
fn formats_choose_the_files_and_a_report_removes_the_files_it_no_longer_writes() {
    let sb = Sandbox::new();
    let p = sb.fixture("tiny.yaml");
    let p = p.to_str().unwrap();
    sb.qsweep(&["run", p, "--quiet", "--formats", "md,svg,png"]).assert().success();
    let dir = sb.path("reports/tiny");
    assert!(dir.join("figures/ball-beam.png").is_file() && dir.join("figures/ball-beam.svg").is_file());
    assert!(dir.join("table3.md").is_file() && dir.join("README.md").is_file());
    for absent in ["table3.csv", "index.html", "cells.parquet", "trials.parquet"] {
        assert!(!dir.join(absent).exists(), "{absent} was not asked for");
    }
    let manifest: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("manifest.json")).unwrap()).unwrap();
    assert_eq!(manifest["formats"], "md,svg,png");
    assert_eq!(manifest["trials_present"], 56);
    assert_eq!(manifest["trials_planned"], 56);
    // The default formats: the PNGs the earlier report wrote are removed, nothing else of ours stays.
    let out = sb.qsweep(&["report", p]).assert().success().get_output().stdout.clone();
    let out = String::from_utf8(out).unwrap();
    assert!(out.contains("removed 4 files the earlier report wrote"), "{out}");
    assert!(!dir.join("figures/ball-beam.png").exists());
    assert!(dir.join("trials.parquet").is_file() && dir.join("index.html").is_file());
    // Unchanged cache: the report is byte-identical and says nothing was replaced.
    let before = std::fs::read(dir.join("index.html")).unwrap();
    let out = sb.qsweep(&["report", p]).assert().success().get_output().stdout.clone();
    assert!(!String::from_utf8(out).unwrap().contains("replaced"));
    assert_eq!(std::fs::read(dir.join("index.html")).unwrap(), before);
}

/// The local files a page links: `href="X"` in HTML, `](X)` in Markdown, without anchors or URLs.
fn local_links(page: &str) -> Vec<String> {
    let mut out = Vec::new();
    for open in ["href=\"", "](", "src=\""] {
        let close = if open == "](" { ')' } else { '"' };
        for part in page.split(open).skip(1) {
            let target = part.split(close).next().unwrap_or("");
            let target = target.split('#').next().unwrap_or("");
            if !target.is_empty() && !target.contains("://") && !target.starts_with("data:") {
                out.push(target.to_string());
            }
        }
    }
    out
}

#[test]
fn pages_linked_files_that_formats_did_not_write() {
    let sb = Sandbox::new();
    let p = sb.fixture("tiny.yaml");
    let p = p.to_str().unwrap();
    let dir = sb.path("reports/tiny");
    for formats in ["md,html", "html,svg", "csv,html,md", "cells,html,tex,md"] {
        sb.qsweep(&["run", p, "--quiet", "--force", "--formats", formats]).assert().success();
        for page in ["index.html", "README.md"] {
            let Ok(text) = std::fs::read_to_string(dir.join(page)) else { continue };
            let links = local_links(&text);
            for l in &links {
                assert!(
                    dir.join(l).exists(),
                    "{page} with --formats {formats} links {l}, which was not written"
                );
            }
            if formats.contains("csv") {
                assert!(
                    links.iter().any(|l| l == "table3.csv"),
                    "{page} with --formats {formats}: {links:?}"
                );
            }
        }
    }
}

#[test]
fn bad_formats_an_out_that_is_a_file_and_unknown_manifests_are_usage_errors() {
    let done = Test::new()
        .pipeline("tiny.yaml")
        .args(["run", "tiny.yaml", "--quiet", "--no-report"])
        .run()
        .then()
        .args(["report", "tiny.yaml", "--formats", "md,pdf"])
        .status(2)
        .stderr_contains("invalid value 'pdf' for '--formats <LIST>'")
        .run()
        .then()
        .file("afile", "x")
        .args(["report", "tiny.yaml", "--out", "afile"])
        .status(2)
        .stderr_contains("report directory afile is a file, not a directory")
        .run();
    assert_eq!(std::fs::read(done.sandbox.path("afile")).unwrap(), b"x");
    let done = done
        .then()
        .file("reports/tiny/manifest.json", "{\"format_version\": 7}")
        .args(["report", "tiny.yaml"])
        .status(2)
        .stderr_contains("reports/tiny/manifest.json: manifest format_version 7 is not 1")
        .stderr_contains("--force")
        .run()
        .then()
        .file("reports/tiny/manifest.json", "not json")
        .args(["report", "tiny.yaml"])
        .status(2)
        .stderr_contains("reports/tiny/manifest.json: not a qsweep report manifest")
        .run();
    assert!(!done.sandbox.path("reports/tiny/index.html").exists(), "nothing written");
    done.then().args(["report", "tiny.yaml", "--force"]).stdout_contains("(56 of 56 planned").run();
}

/// Regression: `report` silently skipped a damaged segment that `run` quarantines; both now move
/// it aside with the same warning.
#[test]
fn report_quarantines_a_damaged_segment_like_run() {
    let sb = Sandbox::new();
    let p = sb.fixture("tiny.yaml");
    sb.run_json(&p, &[]);
    std::fs::write(sb.cache().join("seg-zzz.parquet"), b"garbage").unwrap();
    let out = sb.qsweep(&["report", p.to_str().unwrap()]).assert().success().get_output().clone();
    let err = String::from_utf8(out.stderr).unwrap();
    assert!(err.contains("warning: damaged cache segment") && err.contains("seg-zzz.parquet"), "{err}");
    assert!(!sb.cache().join("seg-zzz.parquet").exists());
    assert!(sb.cache().join("_quarantine/seg-zzz.parquet").is_file());
    assert!(String::from_utf8(out.stdout).unwrap().contains("(56 of 56 planned trials present"));
}

/// Two pipelines that share a `name` write one folder: a complete report of either replaces the
/// other's (saying so); an incomplete one of fewer trials is refused.
#[test]
fn pipelines_sharing_a_name_replace_each_others_complete_reports() {
    let sb = Sandbox::new();
    let p = sb.fixture("tiny.yaml");
    let text = std::fs::read_to_string(&p).unwrap();
    let q = sb.write("tiny-one-system.yaml", &text.replace("seeds: 2", "seeds: 1"));
    sb.qsweep(&["run", p.to_str().unwrap(), "--quiet"]).assert().success();
    let out = sb.qsweep(&["run", q.to_str().unwrap()]).assert().success().get_output().stdout.clone();
    let out = String::from_utf8(out).unwrap();
    assert!(out.contains("replaced reports/tiny: 56 trials, 28 cells → 28 trials, 28 cells"), "{out}");
}
