//! Nothing points nowhere: every relative link in README.md, ARCHITECTURE.md, the guide and the
//! committed reports' Markdown names a file or folder that exists, and every `#anchor` (alone or
//! after a Markdown file) names a heading of that file by GitHub's slug rule. Web links
//! (`http…`, `mailto:`) are not fetched: a test must not need the network.

use crate::markdown::{anchors, guide_docs, links, repo, report_docs, Doc};
use std::collections::HashMap;
use std::path::{Component, Path, PathBuf};

/// `base/rel` with `.` and `..` folded, relative to the repository; None when it leaves it.
fn join(base: &Path, rel: &str) -> Option<PathBuf> {
    let mut out = PathBuf::new();
    for c in base.join(rel).components() {
        match c {
            Component::ParentDir => {
                if !out.pop() {
                    return None;
                }
            }
            Component::CurDir => {}
            other => out.push(other),
        }
    }
    Some(out)
}

/// Every broken link of `docs`, as `FILE:LINE: TARGET: why`.
fn broken(docs: &[Doc]) -> Vec<String> {
    let mut anchor_cache: HashMap<PathBuf, Vec<String>> = HashMap::new();
    let mut out = Vec::new();
    for doc in docs {
        let dir = doc.path.parent().unwrap_or(Path::new(""));
        for (line, target) in links(&doc.text) {
            if target.contains("://") || target.starts_with("mailto:") || target.is_empty() {
                continue;
            }
            let at = format!("{}:{line}: {target}", doc.path.display());
            let (file, anchor) = match target.split_once('#') {
                Some((f, a)) => (f, Some(a)),
                None => (target.as_str(), None),
            };
            let path = if file.is_empty() {
                doc.path.clone()
            } else {
                match join(dir, file) {
                    Some(p) => p,
                    None => {
                        out.push(format!("{at}: leaves the repository"));
                        continue;
                    }
                }
            };
            if !repo().join(&path).exists() {
                out.push(format!("{at}: {} does not exist", path.display()));
                continue;
            }
            if let Some(anchor) = anchor {
                if path.extension().is_some_and(|x| x == "md") {
                    let known = anchor_cache.entry(path.clone()).or_insert_with(|| {
                        anchors(&std::fs::read_to_string(repo().join(&path)).unwrap_or_default())
                    });
                    if !known.iter().any(|a| a == anchor) {
                        out.push(format!("{at}: {} has no heading with anchor #{anchor}", path.display()));
                    }
                }
            }
        }
    }
    out
}

#[test]
fn every_link_and_anchor_of_the_guide_resolves() {
    let docs = guide_docs();
    let bad = broken(&docs);
    let n: usize = docs.iter().map(|d| links(&d.text).len()).sum();
    eprintln!("{n} links in {} guide files checked", docs.len());
    assert!(bad.is_empty(), "{} broken links:\n{}", bad.len(), bad.join("\n"));
}

#[test]
fn every_link_and_anchor_of_the_committed_reports_resolves() {
    let docs = report_docs();
    assert!(!docs.is_empty(), "no committed report Markdown found");
    let bad = broken(&docs);
    let n: usize = docs.iter().map(|d| links(&d.text).len()).sum();
    eprintln!("{n} links in {} report files checked", docs.len());
    assert!(bad.is_empty(), "{} broken links:\n{}", bad.len(), bad.join("\n"));
}

#[test]
fn every_long_help_ends_with_its_guide_chapter() {
    let mut cases: Vec<(Vec<&str>, &str)> = vec![(vec!["--help"], qsweep::cli::GUIDE_INDEX)];
    cases.extend(qsweep::cli::GUIDE.iter().map(|(sub, chapter)| (vec![*sub, "--help"], *chapter)));
    let mut subcommands: Vec<String> = qsweep::cli::command()
        .get_subcommands()
        .filter(|s| !s.is_hide_set()) // `__supervise`: qsweep's own, not for people
        .map(|s| s.get_name().to_string())
        .filter(|n| n != "help")
        .collect();
    let mut guided: Vec<String> = qsweep::cli::GUIDE.iter().map(|(s, _)| s.to_string()).collect();
    subcommands.sort();
    guided.sort();
    assert_eq!(subcommands, guided, "every subcommand has a guide chapter");
    for (args, chapter) in cases {
        let out = std::process::Command::new(env!("CARGO_BIN_EXE_qsweep")).args(&args).output().unwrap();
        let stdout = String::from_utf8_lossy(&out.stdout);
        let last = stdout.lines().rev().find(|l| !l.trim().is_empty()).unwrap_or("");
        assert_eq!(last.trim(), format!("Guide: {chapter}"), "qsweep {}", args.join(" "));
        let (file, anchor) = chapter.split_once('#').unwrap_or((chapter, ""));
        let text = std::fs::read_to_string(repo().join(file)).unwrap_or_else(|e| panic!("{chapter}: {e}"));
        assert!(
            anchor.is_empty() || anchors(&text).iter().any(|a| a == anchor),
            "{chapter}: no such heading"
        );
    }
}

#[test]
fn summary_lists_every_chapter_of_the_guide() {
    let summary = std::fs::read_to_string(repo().join("docs/SUMMARY.md")).unwrap();
    let listed: Vec<String> = links(&summary).into_iter().map(|(_, t)| t).collect();
    let mut missing = Vec::new();
    for doc in guide_docs() {
        let Ok(rel) = doc.path.strip_prefix("docs") else { continue };
        let rel = rel.to_string_lossy().to_string();
        if rel != "SUMMARY.md" && !listed.contains(&rel) {
            missing.push(rel);
        }
    }
    assert!(missing.is_empty(), "docs/SUMMARY.md (the guide's table of contents) does not list: {missing:?}");
}
