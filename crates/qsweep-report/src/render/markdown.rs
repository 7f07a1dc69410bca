//! `README.md` of a report folder: what a repository web page shows of it (such pages render
//! Markdown and SVG images, not HTML pages). The same identity as `index.html` (pipeline,
//! variant, its `set` overrides), what a higher part adds (the replication's Table III,
//! [`crate::render::addition`]), and each system's figures. What the pipeline's author
//! wrote (description, names, titles) is escaped ([`escape::markdown`]): it shows as written and
//! never becomes HTML, a link or a heading.

use crate::derive::report_data::ReportData;
use crate::formats::{Format, Formats};
use crate::render::addition::Addition;
use crate::render::escape;
use crate::render::html::identity;
use qsweep_pipeline::analysis::CENSORING;

/// The Markdown page of one report, with what `added` adds.
pub fn page(data: &ReportData, formats: Formats, added: &Addition) -> String {
    let (name, notes) = identity(data, escape::markdown);
    let name = escape::markdown(&name);
    let mut m = format!("# qsweep report: {name}\n\n");
    if data.plan.report_variant().is_some() {
        m.push_str(&format!("{} [All variants compared](../README.md).\n\n", notes.join(" ")));
    }
    if let Some(d) = &data.plan.description {
        m.push_str(&format!("{}\n\n", escape::markdown(d.trim())));
    }
    // Only the files this report writes (`--formats`).
    let mut links = added.md_links.clone();
    if formats.has(Format::Cells) {
        links.push("[cells.parquet](cells.parquet)".to_string());
    }
    m.push_str(&format!("Trials present: {} of {} planned.", data.trials_cached, data.trials_planned));
    if !links.is_empty() {
        m.push_str(&format!(" Data: {}", links.join(", ")));
    }
    if formats.has(Format::Html) {
        m.push_str(if links.is_empty() {
            " `index.html` shows every cell."
        } else {
            "; `index.html` shows every cell."
        });
    } else if !links.is_empty() {
        m.push('.');
    }
    m.push_str("\n\n");
    m.push_str(&added.markdown);
    if let Some(ext) = formats.figure_ext() {
        for s in data.systems() {
            m.push_str(&format!("\n## {}\n\n", s.title()));
            m.push_str(&format!(
                "![{0}: mean episodes per cell ({name})](figures/{1}.{ext})\n\n",
                s.title(),
                s.name()
            ));
            m.push_str(&format!(
                "![{0}: learning curves of the best cells ({name})](figures/{1}-curves.{ext})\n",
                s.title(),
                s.name()
            ));
        }
    }
    m.push_str(&format!("\n{CENSORING}\n"));
    m
}
