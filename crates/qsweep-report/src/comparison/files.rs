//! The files of `qsweep compare --out DIR`: `compare.csv` (one row per compared cell),
//! `compare.md` (the answer, then the same table, then the cells lacking trials) and
//! `compare.svg` ([`super::figure`]), each written atomically and only when its bytes change.

use super::stats::{p_text, Comparison};
use crate::derive::table::{render, Align, Column, Row, Table, Value};
use crate::render::escape::{markdown, markdown_code};
use crate::render::table::{Csv, Markdown};
use std::path::{Path, PathBuf};

/// The files written, in order.
pub const FILES: [&str; 3] = ["compare.csv", "compare.md", "compare.svg"];

/// The table of compared cells: a column per shared param (A's names), then the numbers.
pub fn table(c: &Comparison) -> Table {
    let mut columns: Vec<Column> = c.shared.iter().map(|(a, _)| Column::new(a, a, Align::Left)).collect();
    for (title, csv) in [("n A", "n_a"), ("n B", "n_b")] {
        columns.push(Column::new(title, csv, Align::Right));
    }
    for (title, csv) in [("mean A", "mean_a"), ("mean B", "mean_b"), ("std A", "std_a"), ("std B", "std_b")] {
        columns.push(Column::new(title, csv, Align::Right));
    }
    columns.push(Column::new("B ÷ A", "ratio", Align::Right));
    columns.push(Column::new("95 % interval", "ratio_lo", Align::Right).fields(&["ratio_lo", "ratio_hi"]));
    columns.push(Column::new("interval", "ratio_interval", Align::Left));
    columns.push(Column::new("Welch p", "p", Align::Right));
    columns.push(Column::new("TOST p", "tost_p", Align::Right));
    columns.push(Column::new("verdict", "verdict", Align::Left));
    columns.push(Column::new("note", "note", Align::Left));
    let num = |v: Option<f64>, decimals: usize| match v {
        Some(value) if value.is_finite() => Value::Num { value, decimals, signed: false },
        Some(value) => Value::Text(format!("{value}")),
        None => Value::Missing,
    };
    let rows = c
        .cells
        .iter()
        .map(|x| {
            let mut values: Vec<Value> = x.values.iter().map(|v| Value::User(v.to_string())).collect();
            values.push(Value::Int(x.n.0 as u64));
            values.push(Value::Int(x.n.1 as u64));
            values.push(num(Some(x.mean.0), 4));
            values.push(num(Some(x.mean.1), 4));
            values.push(num(x.std.0, 4));
            values.push(num(x.std.1, 4));
            values.push(num(x.ratio, 3));
            values.push(match x.ratio_ci {
                Some((lo, hi)) if lo.is_finite() && hi.is_finite() => Value::Range { lo, hi, decimals: 3 },
                Some((lo, hi)) => Value::Text(format!("[{lo}, {hi}]")),
                None => Value::Missing,
            });
            values.push(Value::Text(x.interval.word().to_string()));
            values.push(num(x.p, 4));
            values.push(num(x.tost.map(|t| t.p), 4));
            values.push(Value::Text(x.verdict.word().to_string()));
            values.push(x.note.clone().map_or(Value::Missing, Value::Text));
            Row { values, highlight: false }
        })
        .collect();
    let caption = format!(
        "B ÷ A of metric {} per matched cell, with a 95 % interval (`bootstrap`: the seeded percentile \
         bootstrap of both sides' trials; `delta-log`: from the moments alone, the delta method on the log ratio); Welch's two-sided p; \
         TOST on B ÷ A at the margin {:.2}–{:.2}; equivalent: TOST shows it, differs: p < 0.05 and not \
         equivalent, undecided: neither.",
        c.metric.0, c.margin.0, c.margin.1
    );
    Table { title: "Compare".into(), caption, columns, rows }
}

/// `compare.csv`.
pub fn csv(c: &Comparison) -> String {
    render(&table(c), &Csv)
}

/// `compare.md`: the answer, the verdicts, the table, the cells lacking trials.
pub fn markdown_page(c: &Comparison) -> String {
    let o = &c.overall;
    let mut s = format!("# {} vs {}\n\n", markdown(&c.labels.0), markdown(&c.labels.1));
    let shared: Vec<String> =
        c.shared
            .iter()
            .map(|(a, b)| {
                if a == b {
                    markdown_code(a)
                } else {
                    format!("{} = {}", markdown_code(a), markdown_code(b))
                }
            })
            .collect();
    let metric = if c.metric.0 == c.metric.1 {
        markdown_code(&c.metric.0)
    } else {
        format!("{} (A) vs {} (B)", markdown_code(&c.metric.0), markdown_code(&c.metric.1))
    };
    s.push_str(&format!(
        "Metric {metric}, cells matched on {}. **{}.**\n\n",
        shared.join(", "),
        markdown(&o.line())
    ));
    s.push_str(&format!(
        "Verdicts: {} equivalent, {} differs, {} undecided.\n\n",
        o.verdicts.0, o.verdicts.1, o.verdicts.2
    ));
    s.push_str(&render(&table(c), &Markdown));
    if !c.missing.is_empty() {
        s.push_str("\nCells without trials on a side (not compared):\n\n");
        for m in &c.missing {
            s.push_str(&format!("- {}: no trials in {}\n", markdown(&m.label), m.side));
        }
    }
    for (side, only) in [("A", &c.only.0), ("B", &c.only.1)] {
        if !only.is_empty() {
            s.push_str(&format!("\nCells only {side} plans: {}.\n", markdown(&only.join("; "))));
        }
    }
    s.push_str(&format!("\nAll {} p-values: {}.\n", c.cells.len(), {
        let ps: Vec<String> = c.cells.iter().filter_map(|x| x.p).map(p_text).collect();
        if ps.is_empty() {
            "none".to_string()
        } else {
            ps.join(", ")
        }
    }));
    s
}

/// Write the files of `c` into `dir` (created if needed), atomically; returns their paths.
pub fn write(c: &Comparison, dir: &Path) -> anyhow::Result<Vec<PathBuf>> {
    std::fs::create_dir_all(dir)
        .map_err(|e| anyhow::anyhow!("cannot create the output folder {}: {e}", dir.display()))?;
    let svg = super::figure::svg(c)?;
    let mut out = Vec::new();
    for (name, bytes) in FILES.iter().zip([csv(c), markdown_page(c), svg]) {
        let path = dir.join(name);
        qsweep_pipeline::atomic::write_if_changed(&path, bytes.as_bytes())?;
        out.push(path);
    }
    Ok(out)
}
