//! Comparing the variants of one pipeline (each the whole pipeline with some settings changed),
//! from a small [`VariantDigest`] per variant, so the trials of each variant can be dropped once
//! its own report is written:
//!
//! - `variants.md`, `variants.csv`: one row per variant, scoring how well its Table III reproduces
//!   the pipeline's `reference:` values ([`fit`]), best fit first;
//! - `consistency.md`, `consistency.csv` (pipelines with reference values): every pair of Table III
//!   rows whose grids overlap, with the Welch test of their published means ([`consistency`]);
//! - `verdicts_by_n.csv` (with reference values, not in an exploratory search): every variant's rows judged with the paper's n
//!   taken as 3, 5 and 10, each with the closest variant ([`verdicts`]); `cross_validation.csv`
//!   (two or more declared variants): each row judged under the variant chosen on the others
//!   ([`selection`]);
//! - `figures/forest.svg` (and `.png`), where the pipeline has reference values: every Table III
//!   row's ours ÷ reference with its interval, as written and under the best declared variant
//!   ([`forest`]);
//! - `figures/diff-<variant>-<system>.svg` (and `.png` with `--formats png`), for every variant
//!   but the first: per cell, the change of mean episodes against the first variant ([`diff`]);
//! - `index.html` and `README.md` (for repository web pages): the answer in a few sentences
//!   ([`answer`]) and the forest plot first, then links to each variant's own report, the table and the difference
//!   figures.

pub mod answer;
pub mod diff;
pub mod forest;

pub use diff::{all_diffs, diff_figure, diff_label, diff_seed, diverging, matching, CellDiff, DIFF_RULE};

use crate::derive::compare::{
    comparison_table, conclusions, consistency, explore, selection, verdicts, ExpDigest, Fit, VariantDigest,
    VariantInfo,
};
use crate::formats::{Format, Formats};
use crate::render::escape::{self, html as esc};
use crate::render::table::{render, Csv, Html, Markdown, Table};
use qsweep_engine::env::SystemKind;
use qsweep_pipeline::plan::Plan;
use std::path::{Path, PathBuf};

/// Write the comparison of `variants` (the first is the base of the difference figures) of
/// `plan` into `dir` in `formats`. Returns the files written, relative to `dir`, in writing order.
pub fn write_comparison(
    dir: &Path,
    plan: &Plan,
    variants: &[VariantDigest],
    formats: Formats,
    memo: &crate::memo::stats::StatsMemo,
) -> anyhow::Result<Vec<PathBuf>> {
    let mut out = crate::render::folder::Folder::create(dir)?;
    let mut put = |name: &str, bytes: &[u8]| out.put(name, bytes);
    let table = match &plan.exploratory {
        Some(x) => explore::search_table(plan, x, variants),
        None => {
            let fits: Vec<(&VariantInfo, Fit)> = variants.iter().map(|v| (&v.info, v.fit)).collect();
            comparison_table(&fits, plan.has_fresh())
        }
    };
    if formats.has(Format::Md) {
        put("variants.md", render(&table, &Markdown).as_bytes())?;
    }
    if formats.has(Format::Csv) {
        put("variants.csv", render(&table, &Csv).as_bytes())?;
    }
    let held_out = plan.exploratory.as_ref().and_then(|x| explore::held_out_table(plan, x, variants));
    let claims = variants.iter().any(|v| !v.claims.is_empty());
    let matrix = claims.then(|| conclusions::matrix_table(variants));
    if claims {
        // The long table as CSV only: the pages show the matrix.
        let t = conclusions::conclusions_table(variants);
        if formats.has(Format::Csv) {
            put("conclusions.csv", render(&t, &Csv).as_bytes())?;
        }
    }
    // An exploratory search judges its choice on held-out rows of its own (held_out.csv).
    let by_n = plan.exploratory.is_none().then(|| verdicts::verdicts_by_n_table(variants)).flatten();
    if let Some(t) = &by_n {
        if formats.has(Format::Csv) {
            put("verdicts_by_n.csv", render(t, &Csv).as_bytes())?;
        }
    }
    let selection = selection::selection(plan.exploratory.is_some(), variants);
    if let (Some(s), true) = (&selection, formats.has(Format::Csv)) {
        put("cross_validation.csv", render(&selection::table(s), &Csv).as_bytes())?;
    }
    let consistency = consistency::consistency_table(plan).map(|c| c.1);
    if let Some(t) = &consistency {
        if formats.has(Format::Md) {
            put("consistency.md", render(t, &Markdown).as_bytes())?;
        }
        if formats.has(Format::Csv) {
            put("consistency.csv", render(t, &Csv).as_bytes())?;
        }
    }
    if let Some(t) = &held_out {
        if formats.has(Format::Md) {
            put("held_out.md", render(t, &Markdown).as_bytes())?;
        }
        if formats.has(Format::Csv) {
            put("held_out.csv", render(t, &Csv).as_bytes())?;
        }
    }
    let (svg, png) = (formats.has(Format::Svg), formats.has(Format::Png));
    let series = answer::series(plan, variants);
    let forest_size = forest::write(&plan.name, &series, (svg, png), &mut put)?;
    let mut figs = Vec::new();
    let chosen = explore::chosen(plan, variants).map(|c| c.id.as_str());
    if let Some(base) = variants.first() {
        // A generated variant has its own folder and difference figures only when chosen.
        for v in variants[1..].iter().filter(|v| has_folder(plan, chosen, &v.info.id)) {
            let diffs = if svg || png { all_diffs(base, v, memo) } else { Vec::new() };
            for system in v.systems() {
                let stem = format!("figures/diff-{}-{}", v.info.id, system.name());
                if svg || png {
                    let d = diff_figure(base, v, &diffs, system, (svg, png))?;
                    if let Some(s) = d.svg {
                        put(&format!("{stem}.svg"), s.as_bytes())?;
                    }
                    if let Some(p) = d.png {
                        put(&format!("{stem}.png"), &p)?;
                    }
                }
                let exps: Vec<&ExpDigest> = v.exps.iter().filter(|e| e.exp.system == system).collect();
                figs.push((&v.info, system, stem, diff::figure_size(&exps)));
            }
        }
    }
    let notes = dir.join(NOTES).is_file();
    let tables = Tables {
        fit: &table,
        held_out: held_out.as_ref(),
        matrix: matrix.as_ref(),
        consistency: consistency.as_ref(),
        by_n: by_n.is_some(),
    };
    let answer = answer::Answer { series: &series, figure: forest_size, selection: selection.as_ref() };
    if formats.has(Format::Html) {
        put("index.html", page(plan, variants, &tables, &answer, &figs, formats, notes).as_bytes())?;
    }
    if formats.has(Format::Md) {
        put("README.md", readme(plan, variants, &tables, &answer, &figs, formats, notes).as_bytes())?;
    }
    Ok(out.files)
}

/// Whether the report writes the folder of variant `id` (and its difference figures): every
/// declared (not exploratory) variant of a pipeline without a grid; with a `variant_grid:`, only the chosen variant, so a
/// grid of many variants does not write (or commit) a full report each; the rest are written on
/// demand with `qsweep report PIPELINE --variant ID`.
/// `chosen` is [`explore::chosen`]'s id, worked out once per page rather than once per variant.
pub fn has_folder(plan: &Plan, chosen: Option<&str>, id: &str) -> bool {
    (!plan.has_grid() || chosen == Some(id)) && !plan.variants.iter().any(|v| v.id == id && v.exploratory)
}

/// The heading of the comparison pages: `qsweep variants: NAME`, labelled when exploratory.
fn heading(plan: &Plan) -> String {
    match plan.exploratory {
        Some(_) => format!("qsweep variants: {} ({})", plan.name, explore::LABEL),
        None => format!("qsweep variants: {}", plan.name),
    }
}

type FigRef<'a> = (&'a VariantInfo, SystemKind, String, (u32, u32));

/// The tables of the comparison pages.
struct Tables<'a> {
    /// The fit of every variant.
    fit: &'a Table,
    /// An exploratory search's held-out rows.
    held_out: Option<&'a Table>,
    /// The variant × claim matrix (pipelines with reference values).
    matrix: Option<&'a Table>,
    /// The pairs of Table III rows whose grids overlap (pipelines with reference values).
    consistency: Option<&'a Table>,
    /// Whether `verdicts_by_n.csv` is written.
    by_n: bool,
}

/// The hand-written notes a comparison folder may hold beside the report (the paper's
/// `REPLICATION.md`): never written or removed by qsweep, linked from the page when present.
pub const NOTES: &str = "REPLICATION.md";

/// The comparison page; `notes`: the folder holds [`NOTES`].
fn page(
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
    if notes {
        h.push_str(&format!(
            "<p>What these results mean for the replication: <a href=\"{NOTES}\">{NOTES}</a>.</p>\n"
        ));
    }
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
    if !links.is_empty() {
        h.push_str(&format!("<p>Data: {}</p>\n", links.join(" · ")));
    }
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
    h.push_str("</body>\n</html>\n");
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
            .map(|r| crate::derive::table::Row {
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

/// The comparison as Markdown, for repository web pages (which show `README.md` and SVG images,
/// not HTML pages).
fn readme(
    plan: &Plan,
    variants: &[VariantDigest],
    tables: &Tables,
    answer: &answer::Answer,
    figs: &[FigRef],
    formats: Formats,
    notes: bool,
) -> String {
    let chosen = explore::chosen(plan, variants).map(|c| c.id.as_str());
    let mut m = format!("# {}\n\n", escape::markdown(&heading(plan)));
    if let Some(d) = plan.description.as_deref() {
        m.push_str(&format!("{}\n\n", escape::markdown(d.trim())));
    }
    m.push_str(&answer.markdown(formats));
    if notes {
        m.push_str(&format!("What these results mean for the replication: [{NOTES}]({NOTES}).\n\n"));
    }
    if let Some(t) = consistency::cause_tally(plan, variants) {
        m.push_str(&format!("{t}\n\n"));
    }
    m.push_str(
        "Each variant is the whole pipeline with some settings changed; each has its own full report:\n\n",
    );
    for v in variants {
        let title = v.info.title.as_deref().map(|t| format!(": {}", escape::markdown(t))).unwrap_or_default();
        // The link's target is the variant's folder: its id is a safe folder name
        // (`declared::safe_folder_name`), so it needs no escaping there.
        let id = escape::markdown_code(&v.info.id);
        if has_folder(plan, chosen, &v.info.id) {
            m.push_str(&format!(
                "- [{id}]({}/README.md){title} ({} of {} planned trials present)\n",
                v.info.id, v.trials_cached, v.trials_planned
            ));
        } else {
            let command = format!("qsweep report {} --variant '{}'", plan.source.display(), v.info.id);
            m.push_str(&format!(
                "- {id}{title} ({} of {} planned trials present; report on demand: {})\n",
                v.trials_cached,
                v.trials_planned,
                escape::markdown_code(&command)
            ));
        }
    }
    m.push_str("\n## Fit to the reference values\n\n");
    m.push_str(&render(tables.fit, &Markdown));
    if let Some(t) = tables.held_out {
        m.push_str("\n## Held-out rows\n\n");
        m.push_str(&render(t, &Markdown));
    }
    if let Some(t) = tables.matrix {
        m.push_str("\n## The paper's conclusions, per variant\n\n");
        m.push_str(&render(t, &Markdown));
    }
    if let Some(t) = tables.consistency {
        m.push_str("\n## The paper against itself\n\n");
        m.push_str(&render(t, &Markdown));
    }
    if let (Some(base), Some(ext)) = (variants.first(), formats.figure_ext()) {
        for v in variants[1..].iter().filter(|v| has_folder(plan, chosen, &v.info.id)) {
            let (id, base_id) = (escape::markdown(&v.info.id), escape::markdown(&base.info.id));
            m.push_str(&format!("\n## {id} against {base_id}\n\n"));
            for (_, system, stem, _) in figs.iter().filter(|f| f.0.id == v.info.id) {
                m.push_str(&format!("![{}: {id} against {base_id}]({stem}.{ext})\n\n", system.title()));
            }
            m.push_str(&format!("{DIFF_RULE}\n"));
        }
    }
    m
}

#[cfg(test)]
mod tests;
