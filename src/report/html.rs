//! `index.html`: one self-contained page (inline CSS, no script, no network) with the pipeline's
//! name and description, trial counts, Table III, each system's figure (the SVG of
//! `figures/<system>.svg`, inlined so the page alone shows everything) and a cell table per
//! experiment, plus links to the data files and the figure files.

use super::curves::CURVE_RULE;
use super::model::{ReportData, BEST_RULE, CENSORING};
use super::table::{cell_table, render, table3, Html};
use crate::report::table::html::escape_html as esc;

/// The pages' stylesheet.
pub(crate) const STYLE: &str = "\
body{font-family:system-ui,-apple-system,'Segoe UI',sans-serif;margin:2em auto;max-width:1100px;color:#1e1e1e;line-height:1.4;padding:0 1em}
h1{margin-bottom:.2em}h2{margin-top:2em;border-bottom:1px solid #ccc}
table{border-collapse:collapse;margin:1em 0;font-size:.9em}
caption{caption-side:top;text-align:left;padding:.3em 0;color:#444}
th,td{border-bottom:1px solid #ddd;padding:.25em .5em;text-align:left;white-space:nowrap}
th{white-space:normal;vertical-align:bottom}
th{background:#f3f3f3}td.r,th.r{text-align:right;font-variant-numeric:tabular-nums}
tr.best td{background:#ffecec;font-weight:600}
figure{margin:1em 0}figure svg{display:block;max-width:100%;height:auto;border:1px solid #eee}
.meta{color:#555}nav a{margin-right:1em}code{background:#f3f3f3;padding:0 .2em}
.scroll{overflow-x:auto}
";

/// The page; `figures` and `curves` hold each system's name and its heatmap / learning-curve
/// figure as SVG text.
pub fn page(data: &ReportData, figures: &[(String, String)], curves: &[(String, String)]) -> String {
    let plan = data.plan;
    let mut h = String::new();
    h.push_str("<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n");
    h.push_str(&format!("<title>qsweep report: {}</title>\n", esc(&plan.name)));
    h.push_str(&format!("<style>\n{STYLE}</style>\n</head>\n<body>\n"));
    h.push_str(&format!("<h1>qsweep report: {}</h1>\n", esc(&plan.name)));
    if let Some(d) = &plan.description {
        h.push_str(&format!("<p>{}</p>\n", esc(d)));
    }
    let cells: usize = data.experiments.iter().map(|e| e.cells.len()).sum();
    let missing = data.trials_planned - data.trials_present;
    h.push_str(&format!(
        "<p class=\"meta\">Pipeline <code>{}</code>: {} experiments, {} cells, {} seeds per cell. \
         Trials present: {} of {} planned{}.",
        esc(&plan.source.display().to_string()),
        data.experiments.len(),
        cells,
        plan.seeds.len(),
        data.trials_present,
        data.trials_planned,
        if missing > 0 {
            format!(" ({missing} missing: their cells show what is present)")
        } else {
            String::new()
        }
    ));
    if let Some(src) = &plan.reference_source {
        h.push_str(&format!(" Reference values: {}.", esc(src)));
    }
    h.push_str("</p>\n");
    h.push_str(
        "<p>Data: <a href=\"table3.csv\">table3.csv</a> · <a href=\"table3.md\">table3.md</a> · \
         <a href=\"table3.tex\">table3.tex</a> · <a href=\"cells.parquet\">cells.parquet</a> (one row per cell) · \
         <a href=\"trials.parquet\">trials.parquet</a> (one row per trial)</p>\n",
    );
    let systems = data.systems();
    h.push_str("<nav><a href=\"#table3\">Table III</a>");
    for s in &systems {
        h.push_str(&format!("<a href=\"#{}\">{}</a>", s.name(), esc(s.title())));
    }
    h.push_str("</nav>\n");

    h.push_str("<h2 id=\"table3\">Table III: best configurations</h2>\n<div class=\"scroll\">\n");
    h.push_str(&render(&table3(data), &Html));
    h.push_str("</div>\n");

    for s in systems {
        h.push_str(&format!("<h2 id=\"{}\">{}</h2>\n", s.name(), esc(s.title())));
        if let Some((_, svg)) = figures.iter().find(|(n, _)| n == s.name()) {
            h.push_str(&format!(
                "<figure>{1}\n<figcaption>Mean episodes to the learning goal per cell; \
                 red outline: the best cell (Table III); hatched with *: some trials never reached the goal; \
                 grey: no trials. {2} Files: <a href=\"figures/{0}.png\">PNG</a> · \
                 <a href=\"figures/{0}.svg\">SVG</a></figcaption></figure>\n",
                s.name(),
                inline_svg(
                    svg,
                    &format!("{}: heatmaps of mean episodes per experiment and algorithm", s.title())
                ),
                esc(BEST_RULE),
            ));
        }
        if let Some((_, svg)) = curves.iter().find(|(n, _)| n == s.name()) {
            h.push_str(&format!(
                "<figure>{1}\n<figcaption>Learning curves of the best cell of each experiment and \
                 algorithm (the Table III rows): episode length against episode, log scale; dashed red line: the \
                 learning goal. {2} <a href=\"figures/{0}-curves.png\">PNG</a> · \
                 <a href=\"figures/{0}-curves.svg\">SVG</a></figcaption></figure>\n",
                s.name(),
                inline_svg(svg, &format!("{}: learning curves of the best cells", s.title())),
                esc(CURVE_RULE)
            ));
        }
        for e in data.experiments.iter().filter(|e| e.exp.system == s) {
            let title = e.exp.title.as_deref().map(|t| format!(": {t}")).unwrap_or_default();
            h.push_str(&format!("<h3>Exp. {}{}</h3>\n<div class=\"scroll\">\n", esc(&e.exp.id), esc(&title)));
            h.push_str(&render(&cell_table(e), &Html));
            h.push_str("</div>\n");
        }
    }
    h.push_str(&format!("<p class=\"meta\">{}</p>\n</body>\n</html>\n", esc(CENSORING)));
    h
}

/// An SVG file's text for inlining in HTML: labelled as one image for screen readers, and without
/// the `xmlns` attribute, which HTML does not need (so the page names no URL at all).
pub(crate) fn inline_svg(svg: &str, label: &str) -> String {
    let svg = svg.trim().replacen(" xmlns=\"http://www.w3.org/2000/svg\"", "", 1);
    svg.replacen("<svg ", &format!("<svg role=\"img\" aria-label=\"{}\" ", esc(label)), 1)
}
