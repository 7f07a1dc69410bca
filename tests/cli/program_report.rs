//! A program pipeline's report (issue 62): every file a reader expects (cells with intervals,
//! the best cell, a heatmap and a line, curves of a list metric, both pages), a rerun that
//! rewrites nothing, `--rebuild` byte-identical, and a user's text escaped in every file. The
//! cells' numbers are recomputed independently by tests/python/test_programs.py.

use crate::helpers::{stdout, Sandbox};
use crate::programs::{read_parquet, AGENT, ISSUE_EXAMPLE};
use arrow::array::{Array, BooleanArray, Float64Array, StringArray, UInt64Array};

/// The issue's example with a hostile experiment title, its agent beside it.
fn sandbox() -> Sandbox {
    let sb = Sandbox::new();
    std::fs::create_dir_all(sb.path("agents")).unwrap();
    sb.write(
        "x.yaml",
        &ISSUE_EXAMPLE.replace("title: Bins x learning rate", "title: \"<i>Bins</i> & [x](y)\""),
    );
    sb.write("agents/q_learning.py", AGENT);
    sb
}

/// Every file of a folder, relative path and bytes, sorted.
fn files(dir: &std::path::Path) -> Vec<(String, Vec<u8>)> {
    let mut out = Vec::new();
    for sub in ["", "figures"] {
        let Ok(read) = std::fs::read_dir(dir.join(sub)) else { continue };
        for e in read.map(Result::unwrap).filter(|e| e.path().is_file()) {
            let name = if sub.is_empty() {
                e.file_name().into_string().unwrap()
            } else {
                format!("{sub}/{}", e.file_name().into_string().unwrap())
            };
            out.push((name, std::fs::read(e.path()).unwrap()));
        }
    }
    out.sort();
    out
}

#[test]
fn program_report_has_cells_best_cells_figures_and_pages_and_a_rerun_rewrites_nothing() {
    let sb = sandbox();
    sb.qsweep(&["run", "x.yaml", "--set", "seeds=2", "--jobs", "2"]).assert().success();
    let dir = sb.path("reports/my-sweep");
    let names: Vec<String> = files(&dir).into_iter().map(|f| f.0).collect();
    assert_eq!(
        names,
        [
            "README.md",
            "cells.parquet",
            "figures/mountain-car--bins-alpha--returns.svg",
            "figures/mountain-car--bins-alpha.svg",
            "figures/mountain-car--gamma--returns.svg",
            "figures/mountain-car--gamma.svg",
            "index.html",
            "trials.parquet",
        ]
    );
    // One row per cell and scalar metric (episodes, solved): 27 + 3 cells of the one variant.
    let cells = read_parquet(&dir.join("cells.parquet"));
    assert_eq!(cells.num_rows(), 60);
    let col = |n: &str| cells.column_by_name(n).unwrap_or_else(|| panic!("no column {n}"));
    let metric = col("metric").as_any().downcast_ref::<StringArray>().unwrap();
    let mean = col("mean").as_any().downcast_ref::<Float64Array>().unwrap();
    let (lo, hi) = (
        col("ci_lo").as_any().downcast_ref::<Float64Array>().unwrap(),
        col("ci_hi").as_any().downcast_ref::<Float64Array>().unwrap(),
    );
    let n = col("n").as_any().downcast_ref::<UInt64Array>().unwrap();
    let best = col("best").as_any().downcast_ref::<BooleanArray>().unwrap();
    let bins = col("bins").as_any().downcast_ref::<arrow::array::Int64Array>().unwrap();
    let experiment = col("experiment").as_any().downcast_ref::<StringArray>().unwrap();
    for i in 0..cells.num_rows() {
        assert_eq!(n.value(i), 2);
        assert!(lo.value(i) <= mean.value(i) && mean.value(i) <= hi.value(i), "row {i}");
    }
    // The agent's episodes are bins * 10 + alpha * 100 + seed: the best (lowest) cell of bins x
    // alpha is bins 2, alpha 0.05, and its mean over seeds 1 and 2 is 25.5.
    let best_rows: Vec<usize> =
        (0..cells.num_rows()).filter(|&i| best.value(i) && metric.value(i) == "episodes").collect();
    assert_eq!(best_rows.len(), 2, "one best cell per experiment");
    let grid = best_rows.iter().find(|&&i| experiment.value(i) == "bins-alpha").unwrap();
    assert_eq!((bins.value(*grid), mean.value(*grid)), (2, 25.5));
    let readme = std::fs::read_to_string(dir.join("README.md")).unwrap();
    assert!(
        readme.contains("Best cell by episodes (lowest mean): bins = 2, alpha = 0.05, 25.5 ± 0.7071"),
        "{readme}"
    );
    assert!(readme.contains("| 2 (best) | 0.05 | 2 | 0 | 25.5 ± 0.7071 |"), "{readme}");
    assert!(readme.contains("![bins-alpha: mean episodes per cell](figures/mountain-car--bins-alpha.svg)"));

    // The user's title is text in every file, never markup or a link.
    let html = std::fs::read_to_string(dir.join("index.html")).unwrap();
    assert!(html.contains("&lt;i&gt;Bins&lt;/i&gt; &amp; [x](y)") && !html.contains("<i>"), "{html}");
    assert!(readme.contains("&lt;i&gt;Bins&lt;/i&gt; &amp; \\[x\\](y)"), "{readme}");
    for (name, bytes) in files(&dir).iter().filter(|f| f.0.ends_with(".svg")) {
        let svg = String::from_utf8(bytes.clone()).unwrap();
        roxmltree::Document::parse(&svg).unwrap_or_else(|e| panic!("{name} is not XML: {e}"));
    }

    // A rerun rewrites nothing; --rebuild elsewhere gives the same bytes.
    let before = files(&dir);
    let json: serde_json::Value =
        serde_json::from_str(&stdout(&mut sb.qsweep(&["report", "x.yaml", "--set", "seeds=2", "--json"])))
            .unwrap();
    assert_eq!(
        (json["files_written"].as_u64(), json["files_unchanged"].as_u64()),
        (Some(0), Some(8)),
        "{json}"
    );
    assert_eq!(json["intervals_computed"].as_u64(), Some(60));
    sb.qsweep(&["report", "x.yaml", "--set", "seeds=2", "--rebuild", "--out", "again"]).assert().success();
    assert_eq!(files(&sb.path("again")), before, "--rebuild gave other bytes");
    assert_eq!(files(&dir), before);
}
