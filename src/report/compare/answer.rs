//! The opening sentences of a comparison with reference values: the answer with its uncertainty,
//! counted over the rows the forest plot ([`super::forest`]) draws, for the best declared reading
//! and the text as written, then the figure with its caption.

use super::digest::VariantDigest;
use super::forest::{Series, STEM, TWO_X};
use crate::analysis::equivalence::MARGIN;
use crate::plan::Plan;
use crate::report::formats::Formats;
use crate::report::table::html::escape_html;

/// The plotted readings: the as-written one (the listed variant without a `set`, else the first)
/// and the best-ranked declared one ([`super::explore::chosen`]), one series when they are the
/// same; empty when no reading has a row with a reference.
pub fn series<'a>(plan: &Plan, variants: &'a [VariantDigest]) -> Vec<Series<'a>> {
    let written = super::explore::as_written(plan)
        .and_then(|id| variants.iter().find(|v| v.info.id == id))
        .or(variants.first());
    let best =
        super::explore::chosen(plan, variants).and_then(|c| variants.iter().find(|v| v.info.id == c.id));
    let of = |v: &'a VariantDigest, role| Series { info: &v.info, role, rows: &v.forest, fit: v.fit };
    let best_role = if plan.exploratory.is_some() { "chosen by the search" } else { "best declared" };
    let out = match (written, best) {
        (Some(w), Some(b)) if w.info.id == b.info.id => vec![of(w, "as written and best declared")],
        (Some(w), Some(b)) => vec![of(w, "as written"), of(b, best_role)],
        (Some(w), None) => vec![of(w, "as written")],
        (None, Some(b)) => vec![of(b, best_role)],
        (None, None) => Vec::new(),
    };
    if out.iter().all(|s| s.rows.is_empty()) {
        Vec::new()
    } else {
        out
    }
}

/// What the opening sentences count for one series.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Tally {
    /// Rows plotted.
    pub rows: usize,
    /// Rows whose ratio is within [`TWO_X`].
    pub within_2x: usize,
    /// Rows whose whole 95 % interval is within [`TWO_X`].
    pub whole_interval: usize,
    /// Rows that replicate ([`super::VERDICT_RULE`]).
    pub replicating: usize,
    /// Rows equivalent at paper n = 10 and n = 100.
    pub equivalent: [usize; 2],
}

impl Tally {
    /// The tally of a series.
    pub fn of(s: &Series) -> Self {
        let inside = |x: f64| (TWO_X.0..=TWO_X.1).contains(&x);
        Self {
            rows: s.rows.len(),
            within_2x: s.rows.iter().filter(|r| inside(r.ratio)).count(),
            whole_interval: s
                .rows
                .iter()
                .filter(|r| r.ci.is_some_and(|(a, b)| inside(a) && inside(b)))
                .count(),
            replicating: s.fit.replicating,
            equivalent: s.fit.equivalent,
        }
    }
}

/// "none is", "1 is", "3 are".
fn are(n: usize) -> String {
    match n {
        0 => "none is".into(),
        1 => "1 is".into(),
        n => format!("{n} are"),
    }
}

/// The opening: a few sentences stating the answer with its uncertainty (the best declared
/// reading first, then the text as written for contrast), in plain text (the pages escape or
/// format it).
pub fn opening(series: &[Series]) -> String {
    let mut out = Vec::new();
    for (k, s) in series.iter().rev().enumerate() {
        let t = Tally::of(s);
        let geo =
            s.fit.geo_mean.map(|g| format!("; geometric mean of ours ÷ paper {g:.2}")).unwrap_or_default();
        if k == 0 {
            let who = match s.role {
                "as written" => format!("As written ({})", s.info.id),
                "best declared" => format!("Under the best-ranked declared reading, {}", s.info.id),
                "chosen by the search" => {
                    format!("Under the reading the search chose (ranked on its fit rows), {}", s.info.id)
                }
                _ => format!("As written ({}), also the best-ranked declared reading", s.info.id),
            };
            out.push(format!(
                "{who}, {} of {} Table III rows are within 2× of the paper ({} with their whole 95 % \
                 interval), {} replicate (within two standard errors) and {} equivalent by TOST (margin \
                 {:.2}–{:.2}, the paper's runs taken as 10; {} at 100){geo}.",
                t.within_2x,
                t.rows,
                t.whole_interval,
                t.replicating,
                are(t.equivalent[0]),
                MARGIN.0,
                MARGIN.1,
                t.equivalent[1],
            ));
        } else {
            out.push(format!(
                "As written ({}): {} of {} within 2× ({} whole-interval), {} replicate, {} equivalent \
                 ({} at 100){geo}.",
                s.info.id,
                t.within_2x,
                t.rows,
                t.whole_interval,
                t.replicating,
                t.equivalent[0],
                t.equivalent[1],
            ));
        }
    }
    out.join(" ")
}

/// The figure's caption.
pub fn caption(series: &[Series]) -> String {
    let fresh = series.iter().any(|s| s.rows.iter().any(|r| r.fresh));
    format!(
        "Every Table III row: ours ÷ paper (dot) with its 95 % interval (bar){}; green: the equivalence \
         margin {:.2}–{:.2}; grey: within 2×.",
        if fresh { ", on fresh seeds where the best cell was re-run" } else { "" },
        MARGIN.0,
        MARGIN.1
    )
}

/// The opening of the comparison pages: the plotted readings and the forest plot's pixel size
/// (`None` when not drawn).
pub struct Answer<'a> {
    /// The plotted readings ([`series`]); empty: no opening.
    pub series: &'a [Series<'a>],
    /// The figure's pixel size, when drawn.
    pub figure: Option<(u32, u32)>,
}

/// The forest plot's alt text.
pub const ALT: &str = "Forest plot: ours ÷ paper per Table III row on a log axis, with 95 % intervals";

impl Answer<'_> {
    /// The opening as HTML: the sentences, then the figure (the SVG when written, else the PNG).
    pub fn html(&self, formats: Formats) -> String {
        if self.series.is_empty() {
            return String::new();
        }
        let mut h = format!("<div id=\"answer\">\n<p>{}</p>\n", escape_html(&opening(self.series)));
        if let (Some((w, ht)), Some(ext)) = (self.figure, formats.figure_ext()) {
            h.push_str(&format!(
                "<figure><img src=\"{STEM}.{ext}\" width=\"{w}\" height=\"{ht}\" alt=\"{ALT}\">\n\
                 <figcaption class=\"caption\">{}</figcaption></figure>\n",
                escape_html(&caption(self.series))
            ));
        }
        h.push_str("</div>\n");
        h
    }

    /// The opening as Markdown.
    pub fn markdown(&self, formats: Formats) -> String {
        let mut m = String::new();
        if self.series.is_empty() {
            return m;
        }
        m.push_str(&format!("{}\n\n", opening(self.series)));
        if let (Some(_), Some(ext)) = (self.figure, formats.figure_ext()) {
            m.push_str(&format!("![{ALT}]({STEM}.{ext})\n\n{}\n\n", caption(self.series)));
        }
        m
    }
}
