//! Table III: the best cell per system, experiment and algorithm, with the paper's values, ours
//! at the paper's configuration and each row's cause when the pipeline has reference values. Its
//! columns are one list ([`columns`]); the CSV holds every column, the pages show it in parts of
//! the same rows ([`table3_parts`]), and [`addition`] is what it adds to a report folder.

mod columns;

use crate::derive::report_data::ReportData;
use crate::derive::table::{Row, Table};
use crate::formats::{Format, Formats};
use crate::render::addition::{Addition, Section};
use crate::render::table::{render, Csv, Html, Latex, Markdown, TableWriter};
use crate::replication::published::{contradictions, has_reference};
use crate::replication::stats::consistency::CONSISTENCY_RULE;
use crate::replication::stats::equivalence::EQUIVALENCE_RULE;
use crate::replication::stats::survival::SURVIVAL_RULE;
use crate::replication::stats::verdict::{CAUSE_RULE, HEADLINE_N, SCALE_RULE, SPREAD_RULE};
use columns::{columns, Col, Part, RowCtx};
use qsweep_pipeline::analysis::{BEST_RULE, CENSORING, RACE_RULE};

/// Table III: one row per system, experiment and algorithm, every column, the caption of every
/// part.
pub fn table3(data: &ReportData) -> Table {
    let (cols, rows) = built(data);
    let captions = captions(data);
    let mut t = table(data, &cols, rows, |_| true, captions.main.clone());
    for part in [&captions.uncertainty, &captions.paper_config, &captions.cause].into_iter().flatten() {
        t.caption.push(' ');
        t.caption.push_str(part);
    }
    t
}

/// The columns and every row's values.
fn built(data: &ReportData) -> (Vec<Col>, Vec<Row>) {
    let cols = columns(data);
    let contradictions =
        if has_reference(data) { contradictions(data, HEADLINE_N) } else { Default::default() };
    let mut rows = Vec::new();
    for (ei, e) in data.experiments.iter().enumerate() {
        for &alg in &e.exp.algorithms {
            let ctx = RowCtx::new(data, ei, e, alg, &contradictions);
            rows.push(Row { values: cols.iter().map(|c| (c.value)(&ctx)).collect(), highlight: false });
        }
    }
    (cols, rows)
}

/// The table of the columns `keep` selects, with its caption.
fn table(
    data: &ReportData,
    cols: &[Col],
    rows: Vec<Row>,
    keep: impl Fn(usize) -> bool,
    caption: String,
) -> Table {
    let kept: Vec<usize> = (0..cols.len()).filter(|&i| keep(i)).collect();
    Table {
        title: format!("Table III ({})", data.plan.report_name()),
        caption,
        columns: kept.iter().map(|&i| cols[i].column.clone()).collect(),
        rows: rows
            .into_iter()
            .map(|r| Row {
                values: kept.iter().map(|&i| r.values[i].clone()).collect(),
                highlight: r.highlight,
            })
            .collect(),
    }
}

/// The captions of Table III's parts (`None`: the part has no columns).
struct Captions {
    main: String,
    uncertainty: Option<String>,
    paper_config: Option<String>,
    cause: Option<String>,
}

fn captions(data: &ReportData) -> Captions {
    let reference = has_reference(data);
    let fresh = data.plan.has_fresh();
    let raced = data.plan.raced;
    let mut caption = String::from(
        "Best-performing configuration per system, experiment and algorithm (the paper's Table III): \
         mean ± std of the episodes needed to reach the learning goal over the best cell's trials, and \
         that cell's bins or fuzzy sets per state variable (— where the system has no such variable) \
         and number of actions; n = trials present, successes = trials that reached the goal. ",
    );
    caption.push_str(BEST_RULE);
    caption.push(' ');
    caption.push_str(CENSORING);
    if reference {
        caption.push_str(" Paper: the published value and configuration; Δ mean = ours − paper.");
    }
    let mut uncertainty = String::from("95% CI: bootstrap interval of the best cell's mean. ");
    if fresh {
        uncertainty.push_str(qsweep_pipeline::fresh::FRESH_RULE);
        uncertainty.push(' ');
    }
    uncertainty.push_str(SURVIVAL_RULE);
    if reference {
        uncertainty.push(' ');
        uncertainty.push_str(EQUIVALENCE_RULE);
    }
    if raced {
        caption.push(' ');
        caption.push_str(RACE_RULE);
        if reference {
            caption
                .push_str(" Paper config tied: whether the paper's configuration is among the contenders.");
        }
    }
    if data.trials_cached < data.trials_planned {
        caption.push_str(&format!(
            " Only {} of {} planned trials are present.",
            data.trials_cached, data.trials_planned
        ));
    }
    let paper_config = "At paper config: the cell of the same heatmap at the paper's stated configuration \
         (mean ± std over the grid's seeds, n, successes), with the same interval, censoring and \
         equivalence verdicts as the best cell; table3.csv adds its fresh-seed estimate (only \
         where it is also the best cell), Kaplan–Meier median and TOST p-values.";
    let cause = format!(
        "Verdicts of the best cell and of the paper's cell, on their fresh-seed estimate where \
         present. {SCALE_RULE} Contradictory pair, paper inconsistent: {CONSISTENCY_RULE} \
         {CAUSE_RULE} {SPREAD_RULE} table3.csv adds the within-2× TOST's p and, for comparison, \
         the old rule of two standard errors (verdict_2se, paper_cell_verdict_2se, cause_2se; \
         docs/reports.md)."
    );
    Captions {
        main: caption,
        uncertainty: Some(uncertainty),
        paper_config: reference.then(|| paper_config.to_string()),
        cause: reference.then_some(cause),
    }
}

/// The further parts of Table III on the pages after the best configurations: (HTML id, title).
pub const TABLE3_PARTS: [(&str, &str); 3] = [
    ("uncertainty", "uncertainty"),
    ("paper-config", "at the paper's configuration"),
    ("cause", "verdicts and cause"),
];

/// Table III as the pages show it, in tables of the same rows: the best configurations (the
/// paper's columns, and a race's), then their uncertainty (the rows' keys and the interval,
/// censoring and equivalence columns), then, with reference values, ours at the paper's
/// configuration and each row's cause; side by side they would be too wide to read. The CSV is the
/// whole [`table3`].
pub fn table3_parts(data: &ReportData) -> Vec<Table> {
    let (cols, rows) = built(data);
    let c = captions(data);
    let mut out = vec![table(data, &cols, rows.clone(), |i| cols[i].part == Part::Main, c.main)];
    let parts =
        [(Part::Uncertainty, c.uncertainty), (Part::PaperConfig, c.paper_config), (Part::Cause, c.cause)];
    for ((part, caption), (_, name)) in parts.into_iter().zip(TABLE3_PARTS) {
        let Some(caption) = caption else { continue };
        // Each part with the row's keys (system, experiment, algorithm) first.
        let shown = |i: usize| i < 3 || (cols[i].part == part && cols[i].pages);
        let mut t = table(data, &cols, rows.clone(), shown, caption);
        t.title = format!("{}: {name}", t.title);
        out.push(t);
    }
    out
}

/// What Table III adds to a report folder ([`Addition`]): `table3.md`, `table3.csv` and
/// `table3.tex` in `formats` (the CSV holds every column; the pages, Markdown and LaTeX show the
/// uncertainty apart), their links, and Table III's section of the pages.
pub fn addition(data: &ReportData, formats: Formats) -> Addition {
    let parts = table3_parts(data);
    let joined = |w: &dyn TableWriter| parts.iter().map(|t| render(t, w)).collect::<Vec<_>>().join("\n");
    let mut added = Addition::default();
    if formats.has(Format::Md) {
        added.files.push(("table3.md".into(), joined(&Markdown).into_bytes()));
    }
    if formats.has(Format::Csv) {
        added.files.push(("table3.csv".into(), render(&table3(data), &Csv).into_bytes()));
    }
    if formats.has(Format::Tex) {
        added.files.push(("table3.tex".into(), joined(&Latex).into_bytes()));
    }
    for (f, file) in [(Format::Csv, "table3.csv"), (Format::Md, "table3.md"), (Format::Tex, "table3.tex")] {
        if formats.has(f) {
            added.html_links.push(format!("<a href=\"{file}\">{file}</a>"));
            if f != Format::Md {
                added.md_links.push(format!("[{file}]({file})"));
            }
        }
    }
    let mut html =
        String::from("<h2 id=\"table3\">Table III: best configurations</h2>\n<div class=\"scroll\">\n");
    html.push_str(&render(&parts[0], &Html));
    for (t, (id, _)) in parts[1..].iter().zip(TABLE3_PARTS) {
        html.push_str(&format!("</div>\n<div class=\"scroll\" id=\"{id}\">\n"));
        html.push_str(&render(t, &Html));
    }
    html.push_str("</div>\n");
    added.html_sections.push(Section { id: "table3".into(), nav: "Table III".into(), html });
    added.markdown = joined(&Markdown);
    added
}

#[cfg(test)]
mod tests;
