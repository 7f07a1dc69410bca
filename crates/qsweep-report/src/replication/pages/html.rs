//! The comparison's `index.html`: the answer and the forest plot first, then each variant's
//! report, the data files, the tables that decide (the CSV and Markdown hold every column) and the
//! difference figures.

use super::answer;
use super::contents::{has_folder, heading, FigRef, Tables, NOTES};
use super::diff::DIFF_RULE;
use crate::derive::table::{Row, Table};
use crate::formats::{Format, Formats};
use crate::render::escape::html as esc;
use crate::render::table::{render, Html};
use crate::replication::compare::{consistency, explore, VariantDigest};
use qsweep_pipeline::plan::Plan;

/// The comparison page; `notes`: the folder holds [`NOTES`].
pub(super) fn page(
    plan: &Plan,
    variants: &[VariantDigest],
    tables: &Tables,
    answer: &answer::Answer,
    figs: &[FigRef],
    formats: Formats,
    notes: bool,
) -> String {
    let chosen = explore::chosen(plan, variants).map(|c| c.id.as_str());
    let mut h = String::new();
    h.push_str("<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n");
    h.push_str(&format!("<title>{}</title>\n", esc(&heading(plan))));
    h.push_str(&format!("<style>\n{}</style>\n</head>\n<body>\n", crate::render::html::STYLE));
    h.push_str(&format!("<h1>{}</h1>\n", esc(&heading(plan))));
    if let Some(d) = plan.description.as_deref() {
        h.push_str(&format!("<p>{}</p>\n", esc(d)));
    }
    h.push_str(&answer.html(formats));
    if let Some(t) = consistency::cause_tally(plan, variants) {
        h.push_str(&format!("<p id=\"causes\">{}</p>\n", esc(&t)));
    }
    h.push_str(&variant_list(plan, variants, chosen));
    if notes {
        h.push_str(&format!(
            "<p>What these results mean for the replication: <a href=\"{NOTES}\">{NOTES}</a>.</p>\n"
        ));
    }
    h.push_str(&data_links(tables, answer, formats));
    h.push_str(&tables_html(tables));
    h.push_str(&diff_figures(plan, variants, chosen, figs, formats));
    h.push_str("</body>\n</html>\n");
    h
}

/// Each variant with a link to its report, or the command that writes it on demand.
fn variant_list(plan: &Plan, variants: &[VariantDigest], chosen: Option<&str>) -> String {
    let mut h = String::new();
    h.push_str("<p>Each variant is the whole pipeline with some settings changed; each has its own full report:</p>\n<ul>\n");
    for v in variants {
        let title = v.info.title.as_deref().map(|t| format!(": {}", esc(t))).unwrap_or_default();
        if has_folder(plan, chosen, &v.info.id) {
            h.push_str(&format!(
                "<li><a href=\"{0}/index.html\"><code>{0}</code></a>{title} ({1} of {2} planned trials present)</li>\n",
                esc(&v.info.id),
                v.trials_cached,
                v.trials_planned
            ));
        } else {
            h.push_str(&format!(
                "<li><code>{0}</code>{title} ({1} of {2} planned trials present; its report on demand: \
                 <code>qsweep report {3} --variant '{0}'</code>)</li>\n",
                esc(&v.info.id),
                v.trials_cached,
                v.trials_planned,
                esc(&plan.source.display().to_string())
            ));
        }
    }
    h.push_str("</ul>\n");
    h
}

/// The links to the data files this report writes (`--formats`).
fn data_links(tables: &Tables, answer: &answer::Answer, formats: Formats) -> String {
    // Only the files this report writes (`--formats`).
    let links: Vec<&str> = [
        (Format::Csv, "<a href=\"variants.csv\">variants.csv</a>"),
        (Format::Md, "<a href=\"variants.md\">variants.md</a>"),
        (Format::Cells, "<a href=\"cells.parquet\">cells.parquet</a> (every variant's cells, with a <code>variant</code> column)"),
    ]
    .into_iter()
    .chain(tables.matrix.map(|_| (Format::Csv, "<a href=\"conclusions.csv\">conclusions.csv</a>")))
    .chain(tables.consistency.map(|_| (Format::Csv, "<a href=\"consistency.csv\">consistency.csv</a>")))
    .chain(tables.by_n.then_some((Format::Csv, "<a href=\"verdicts_by_n.csv\">verdicts_by_n.csv</a>")))
    .chain(answer.selection.map(|_| (Format::Csv, "<a href=\"cross_validation.csv\">cross_validation.csv</a>")))
    .filter(|(f, _)| formats.has(*f))
    .map(|(_, l)| l)
    .collect();
    if links.is_empty() {
        String::new()
    } else {
        format!("<p>Data: {}</p>\n", links.join(" · "))
    }
}

/// The fit, the held-out rows, the claims and the paper against itself, each with the columns
/// that decide.
fn tables_html(tables: &Tables) -> String {
    let mut h = String::new();
    h.push_str("<h2 id=\"fit\">Fit to the reference values</h2>\n");
    // The page shows the columns that decide; the CSV and Markdown hold them all.
    h.push_str(&captioned(&without(
        tables.fit,
        &[
            "ratio_within_2x",
            "config_match",
            "order_match",
            "order_experiments",
            "equivalent_n100",
            "fresh_over_selection",
        ],
        "variants.csv adds the old rule's ratio within 2×, the configuration and Q(0)/Q(λ) order \
         matches, the TOST at n = 100 and the fresh-seed geometric mean.",
    )));
    if let Some(t) = tables.held_out {
        h.push_str("<h2 id=\"held-out\">Held-out rows</h2>\n");
        h.push_str(&captioned(t));
    }
    if let Some(t) = tables.matrix {
        h.push_str("<h2 id=\"claims\">The paper's conclusions, per variant</h2>\n");
        h.push_str(&captioned(t));
    }
    if let Some(t) = tables.consistency {
        h.push_str("<h2 id=\"consistency\">The paper against itself</h2>\n");
        h.push_str(&captioned(&without(
            t,
            &["t", "df", "p_n5", "p_n3"],
            "consistency.csv adds Welch's t, its degrees of freedom and the p-values at n = 5 and 3.",
        )));
    }
    h
}

/// Each variant's difference figures against the first.
fn diff_figures(
    plan: &Plan,
    variants: &[VariantDigest],
    chosen: Option<&str>,
    figs: &[FigRef],
    formats: Formats,
) -> String {
    let mut h = String::new();
    if let (Some(base), Some(ext)) = (variants.first(), formats.figure_ext()) {
        for v in variants[1..].iter().filter(|v| has_folder(plan, chosen, &v.info.id)) {
            h.push_str(&format!(
                "<h2 id=\"diff-{0}\">{0} against {1}</h2>\n",
                esc(&v.info.id),
                esc(&base.info.id)
            ));
            for (_, system, stem, (w, ht)) in figs.iter().filter(|f| f.0.id == v.info.id) {
                h.push_str(&format!(
                    "<figure><img src=\"{stem}.{ext}\" width=\"{w}\" height=\"{ht}\" alt=\"{0}: change of mean \
                     episodes per cell, {1} against {2}\">\n<figcaption>{0}. {3}</figcaption></figure>\n",
                    esc(system.title()),
                    esc(&v.info.id),
                    esc(&base.info.id),
                    esc(DIFF_RULE)
                ));
            }
        }
    }
    h
}

/// `table` without the columns whose first CSV field is in `hide`, its caption followed by `note`
/// (where a column was hidden), for a page that must fit its width.
fn without(table: &Table, hide: &[&str], note: &str) -> Table {
    let keep: Vec<usize> =
        (0..table.columns.len()).filter(|&i| !hide.contains(&table.columns[i].csv[0].as_str())).collect();
    if keep.len() == table.columns.len() {
        return table.clone();
    }
    Table {
        title: table.title.clone(),
        caption: format!("{} {note}", table.caption),
        columns: keep.iter().map(|&i| table.columns[i].clone()).collect(),
        rows: table
            .rows
            .iter()
            .map(|r| Row {
                values: keep.iter().map(|&i| r.values[i].clone()).collect(),
                highlight: r.highlight,
            })
            .collect(),
    }
}

/// A comparison table as HTML. The caption is a paragraph of its own: inside the table it would
/// widen the table to its own unwrapped length. Its text columns wrap (`.fit`): variant titles
/// are long, and the table must fit the page.
fn captioned(table: &Table) -> String {
    let mut bare = table.clone();
    bare.caption.clear();
    format!(
        "<p class=\"caption\">{}</p>\n<div class=\"scroll fit\">\n{}</div>\n",
        esc(&table.caption),
        render(&bare, &Html)
    )
}
