//! `index.html`: one page (inline CSS, no script, no network) with the report's identity (the
//! pipeline, and for a variant its id, title, `set` overrides and a link back to the comparison),
//! trial counts, the sections a higher part adds (the replication's Table III,
//! [`crate::render::addition`]), each system's figures (linked from `figures/`, so every figure is
//! stored once) and a cell table per experiment, plus links to the data files.

use crate::derive::report_data::{ExpData, ReportData};
use crate::derive::table::cell_table;
use crate::formats::{Format, Formats};
use crate::render::addition::Addition;
use crate::render::curves::CURVE_RULE;
use crate::render::escape::html as esc;
use crate::render::table::{render, Html};
use qsweep_engine::env::SystemKind;
use qsweep_pipeline::analysis::{BEST_RULE, CENSORING};

/// The pages' stylesheet (`.aK`: the tables whose number columns follow the first K, see
/// [`crate::render::table::html`]).
pub(crate) const STYLE: &str = "\
body{font-family:system-ui,-apple-system,'Segoe UI',sans-serif;margin:2em auto;max-width:1200px;color:#1e1e1e;line-height:1.4;padding:0 1em}
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
img{max-width:100%;height:auto;border:1px solid #eee}
.a1 :is(td,th):nth-child(n+2),.a2 :is(td,th):nth-child(n+3),.a3 :is(td,th):nth-child(n+4),.a4 :is(td,th):nth-child(n+5){text-align:right;font-variant-numeric:tabular-nums}
.caption{color:#444;max-width:100%}.fit td{white-space:normal}.fit td:nth-child(3){min-width:9em}
";

/// Which report a page belongs to, as its heading and first paragraph say: the pipeline, and for
/// a variant's folder the variant's id, title and `set` overrides, with a link back to the
/// comparison of all variants. The name comes as written; in the notes, what the pipeline's
/// author wrote is already escaped with `esc` (the page's format, [`crate::render::escape`]).
pub(crate) fn identity(data: &ReportData, esc: fn(&str) -> String) -> (String, Vec<String>) {
    let plan = data.plan;
    let mut notes = Vec::new();
    if let Some(v) = plan.report_variant() {
        let title = v.title.as_deref().map(|t| format!(": {}", esc(t))).unwrap_or_default();
        notes.push(format!("Variant {}{title} of pipeline {}.", esc(&v.id), esc(&plan.name)));
        if v.set.is_empty() {
            notes.push("Its settings: the pipeline as written (no `set`).".into());
        } else {
            notes.push(format!("Its settings: the pipeline with {}.", esc(&v.set.join(", "))));
        }
    }
    (plan.report_name(), notes)
}

/// The page of one report with what `added` adds: tables inline, figures linked as
/// `figures/<system>.<ext>` (the SVG when written, else the PNG; none without either).
pub fn page(data: &ReportData, formats: Formats, added: &Addition) -> String {
    let (name, notes) = identity(data, esc);
    let mut h = String::new();
    h.push_str("<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n");
    h.push_str(&format!("<title>qsweep report: {}</title>\n", esc(&name)));
    h.push_str(&format!("<style>\n{STYLE}</style>\n</head>\n<body>\n"));
    h.push_str(&format!("<h1>qsweep report: {}</h1>\n", esc(&name)));
    if data.plan.report_variant().is_some() {
        h.push_str(&format!(
            "<p class=\"variant\">{} <a href=\"../index.html\">All variants compared</a></p>\n",
            notes.join(" ")
        ));
    }
    if let Some(d) = &data.plan.description {
        h.push_str(&format!("<p>{}</p>\n", esc(d)));
    }
    h.push_str(&counts(data));
    h.push_str(&data_links(data, formats, added));
    let systems = data.systems();
    h.push_str("<nav>");
    for s in &added.html_sections {
        h.push_str(&format!("<a href=\"#{}\">{}</a>", s.id, s.nav));
    }
    for s in &systems {
        h.push_str(&format!("<a href=\"#{}\">{}</a>", s.name(), esc(s.title())));
    }
    h.push_str("</nav>\n");
    for s in &added.html_sections {
        h.push_str(&s.html);
    }
    for s in systems {
        h.push_str(&system_section(data, s, formats, &name));
    }
    h.push_str(&format!("<p class=\"meta\">{}</p>\n</body>\n</html>\n", esc(CENSORING)));
    h
}

/// The paragraph of the pipeline's counts: experiments, cells, seeds, trials present.
fn counts(data: &ReportData) -> String {
    let plan = data.plan;
    let cells: usize = data.experiments.iter().map(|e| e.cells.len()).sum();
    let missing = data.trials_planned - data.trials_cached;
    let mut h = format!(
        "<p class=\"meta\">Pipeline <code>{}</code>: {} experiments, {} cells, {} seeds per cell. \
         Trials present: {} of {} planned{}.",
        esc(&plan.source.display().to_string()),
        data.experiments.len(),
        cells,
        plan.seeds.len(),
        data.trials_cached,
        data.trials_planned,
        if missing > 0 {
            format!(" ({missing} missing: their cells show what is present)")
        } else {
            String::new()
        }
    );
    if let Some(src) = &plan.reference_source {
        h.push_str(&format!(" Reference values: {}.", esc(src)));
    }
    h.push_str("</p>\n");
    h
}

/// The links to the data files: what `added` adds, then the cells and trials, only those
/// this report writes (`--formats`).
fn data_links(data: &ReportData, formats: Formats, added: &Addition) -> String {
    let mut links = added.html_links.clone();
    if formats.has(Format::Cells) {
        links.push("<a href=\"cells.parquet\">cells.parquet</a> (one row per cell)".to_string());
    }
    if formats.has(Format::Trials) {
        links.push(if data.plan.report_variant().is_some() {
            "<a href=\"../trials.parquet\">../trials.parquet</a> (one row per trial of every variant, with a \
             <code>variant</code> column; written by <code>qsweep report</code>, not committed)"
                .to_string()
        } else {
            "<a href=\"trials.parquet\">trials.parquet</a> (one row per trial)".to_string()
        });
    }
    if links.is_empty() {
        String::new()
    } else {
        format!("<p>Data: {}</p>\n", links.join(" · "))
    }
}

/// One system's section: its heatmaps and learning curves (with `formats`' figure type), then a
/// cell table per experiment.
fn system_section(data: &ReportData, s: SystemKind, formats: Formats, name: &str) -> String {
    let mut h = format!("<h2 id=\"{}\">{}</h2>\n", s.name(), esc(s.title()));
    let exps: Vec<&ExpData> = data.experiments.iter().filter(|e| e.exp.system == s).collect();
    if let Some(ext) = formats.figure_ext() {
        let (w, ht) = crate::render::figures::figure_size(&exps);
        h.push_str(&format!(
            "<figure><img src=\"figures/{0}.{ext}\" width=\"{w}\" height=\"{ht}\" alt=\"{1}\">\n\
             <figcaption>Mean episodes to the learning goal per cell; \
             red outline: the best cell (Table III); hatched with *: some trials never reached the goal; \
             grey: no trials. {2}</figcaption></figure>\n",
            s.name(),
            esc(&format!("{}: heatmaps of mean episodes per experiment and algorithm ({name})", s.title())),
            esc(BEST_RULE),
        ));
        let (w, ht) = crate::render::curves::figure_size(exps.len());
        h.push_str(&format!(
            "<figure><img src=\"figures/{0}-curves.{ext}\" width=\"{w}\" height=\"{ht}\" alt=\"{1}\">\n\
             <figcaption>Learning curves of the best cell of each experiment and \
             algorithm (the Table III rows): episode length against episode, log scale; dashed red line: the \
             learning goal. {2}</figcaption></figure>\n",
            s.name(),
            esc(&format!("{}: learning curves of the best cells ({name})", s.title())),
            esc(CURVE_RULE)
        ));
    }
    for e in exps {
        let title = e.exp.title.as_deref().map(|t| format!(": {t}")).unwrap_or_default();
        h.push_str(&format!("<h3>Exp. {}{}</h3>\n<div class=\"scroll\">\n", esc(&e.exp.id), esc(&title)));
        h.push_str(&render(&cell_table(e), &Html));
        h.push_str("</div>\n");
    }
    h
}
