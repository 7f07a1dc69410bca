//! The comparison's `README.md`, for repository web pages (which show Markdown and SVG images,
//! not HTML pages): the same contents as `index.html`, every table whole.

use super::answer;
use super::contents::{has_folder, heading, FigRef, Tables, NOTES};
use super::diff::DIFF_RULE;
use crate::formats::Formats;
use crate::render::escape;
use crate::render::table::{render, Markdown};
use crate::replication::compare::{consistency, explore, VariantDigest};
use qsweep_pipeline::plan::Plan;

/// The comparison as Markdown, for repository web pages (which show `README.md` and SVG images,
/// not HTML pages).
pub(super) fn readme(
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
