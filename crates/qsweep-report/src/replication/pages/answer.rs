//! The opening sentences of a comparison with reference values: the answer with its uncertainty,
//! counted over the rows the forest plot ([`crate::replication::pages::forest`]) draws, for the best declared variant
//! and the text as written — replicating rows on the verdict scale, how they move with the paper's
//! unstated n, what choosing the variant is worth ([`crate::replication::compare::selection`]), the spreads — then the
//! figure with its caption.

use crate::formats::Formats;
use crate::render::escape::html as escape_html;
use crate::replication::compare::selection::Selection;
use crate::replication::compare::VariantDigest;
use crate::replication::pages::forest::{Series, STEM, TWO_X};
use crate::replication::stats::equivalence::{MARGIN, MARGIN_2X};
use qsweep_pipeline::plan::Plan;

/// The plotted variants: the as-written one (the listed variant without a `set`, else the first)
/// and the best-ranked declared one ([`crate::replication::compare::explore::chosen`]), one series when they are the
/// same; empty when no variant has a row with a reference.
pub fn series<'a>(plan: &Plan, variants: &'a [VariantDigest]) -> Vec<Series<'a>> {
    let written = crate::replication::compare::explore::as_written(plan)
        .and_then(|id| variants.iter().find(|v| v.info.id == id))
        .or(variants.first());
    let best = crate::replication::compare::explore::chosen(plan, variants)
        .and_then(|c| variants.iter().find(|v| v.info.id == c.id));
    let of = |v: &'a VariantDigest, role| Series {
        info: &v.info,
        role,
        rows: &v.forest,
        scored: &v.rows,
        fit: v.fit,
    };
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
    /// Rows that replicate on the verdict scale (equivalent or within-2x) at the paper's n taken
    /// as 3, 5 and 10.
    pub replicating: [usize; 3],
    /// Rows per verdict at n = 10, in [`crate::replication::compare::fit::Verdict::ALL`]'s order.
    pub scale: [usize; 5],
    /// Rows within two standard errors (the old rule).
    pub within_2se: usize,
    /// Rows equivalent at paper n = 10 and n = 100.
    pub equivalent: [usize; 2],
    /// Rows whose spread differs from the paper's: (ours wider, ours narrower).
    pub spread: (usize, usize),
}

impl Tally {
    /// The tally of a series.
    pub fn of(s: &Series) -> Self {
        let inside = |x: f64| (TWO_X.0..=TWO_X.1).contains(&x);
        let differs = |wider: bool| {
            s.scored
                .iter()
                .filter_map(|r| r.spread)
                .filter(|sp| sp.differs() && (sp.lo > 1.0) == wider)
                .count()
        };
        Self {
            rows: s.rows.len(),
            within_2x: s.rows.iter().filter(|r| inside(r.ratio)).count(),
            whole_interval: s
                .rows
                .iter()
                .filter(|r| r.ci.is_some_and(|(a, b)| inside(a) && inside(b)))
                .count(),
            replicating: s.fit.replicating_by_n,
            scale: s.fit.scale,
            within_2se: s.fit.within_2se,
            equivalent: s.fit.equivalent,
            spread: (differs(true), differs(false)),
        }
    }
}

/// "1 row", "3 rows".
fn n_rows(n: usize) -> String {
    if n == 1 {
        "1 row".into()
    } else {
        format!("{n} rows")
    }
}

/// "1 row is", "3 rows are": the count, then `one` or `many`.
fn rows(n: usize, one: &str, many: &str) -> String {
    format!("{} {}", n_rows(n), if n == 1 { one } else { many })
}

/// The sentences on choosing the variant: leave-one-row-out and the yardstick.
fn chosen_sentences(s: &Selection) -> String {
    let (cv, cv_eq, cv_se) = s.cross_validated();
    let mut out = format!(
        "Chosen without the row it judges (leave-one-row-out over the {} declared variants), {cv} of \
         {} rows replicate ({cv_eq} equivalent; {cv_se} within two standard errors), against {} ({}; {}) \
         for `{}` in sample.",
        s.variants,
        s.held_out.len(),
        s.in_sample.0,
        s.in_sample.1,
        s.in_sample.2,
        s.best
    );
    if let Some(y) = s.yardstick_2se {
        out.push_str(&format!(
            " The best of {} variants has {} within two standard errors; were all variants equally \
             good, the best would reach a median {} (95th percentile {}, p = {:.3}).",
            s.variants,
            n_rows(y.observed),
            y.median,
            y.p95,
            y.p
        ));
    }
    if let Some(y) = s.yardstick_scale {
        out.push_str(&format!(
            " For replicating rows: {} against a median {} (95th percentile {}, p = {:.3}).",
            y.observed, y.median, y.p95, y.p
        ));
    }
    out
}

/// The opening: a few sentences stating the answer with its uncertainty (the best declared
/// variant first, then the text as written for contrast), in plain text (the pages escape or
/// format it).
pub fn opening(series: &[Series], selection: Option<&Selection>) -> String {
    let mut out = Vec::new();
    for (k, s) in series.iter().rev().enumerate() {
        let t = Tally::of(s);
        let geo =
            s.fit.geo_mean.map(|g| format!("; geometric mean of ours ÷ paper {g:.2}")).unwrap_or_default();
        let [rep3, rep5, rep10] = t.replicating;
        let [eq, w2, wide, differs, undecided] = t.scale;
        if k == 0 {
            let who = match s.role {
                "as written" => format!("As written ({})", s.info.id),
                "best declared" => format!("Under the best-ranked declared variant, {}", s.info.id),
                "chosen by the search" => {
                    format!("Under the variant the search chose (ranked on its fit rows), {}", s.info.id)
                }
                _ => format!("As written ({}), also the best-ranked declared variant", s.info.id),
            };
            out.push(format!(
                "{who}, {rep10} of {} Table III rows replicate, taking the paper's means to average 10 \
                 runs: {eq} equivalent (TOST, ours ÷ paper within {:.2}–{:.2}) and {w2} shown within 2× \
                 (the same test within {}–{}). {wide} more {} within two standard errors but not shown \
                 within 2× (consistent but wide), {differs} {}{}. With 5 runs behind each published \
                 mean {}, with 3 runs {rep3}; {} equivalent at 100 runs. By ratio alone, {} within 2× \
                 ({} with their whole 95 % interval){geo}.",
                t.rows,
                MARGIN.0,
                MARGIN.1,
                MARGIN_2X.0,
                MARGIN_2X.1,
                if wide == 1 { "is" } else { "are" },
                if differs == 1 { "differs" } else { "differ" },
                if undecided > 0 { format!(", {undecided} undecided") } else { String::new() },
                rows(rep5, "replicates", "replicate"),
                t.equivalent[1],
                rows(t.within_2x, "is", "are"),
                t.whole_interval,
            ));
            if let Some(sel) = selection {
                out.push(chosen_sentences(sel));
            }
            if t.spread.0 + t.spread.1 > 0 {
                out.push(format!(
                    "Our spread differs from the paper's in {} ({} wider, {} narrower; 95 % F \
                     interval of the std ratio).",
                    n_rows(t.spread.0 + t.spread.1),
                    t.spread.0,
                    t.spread.1
                ));
            }
        } else {
            out.push(format!(
                "As written ({}): {rep10} of {} replicate ({eq} equivalent, {w2} within 2×), {wide} \
                 consistent but wide, {differs} {}; {rep5} at 5 runs, {rep3} at 3; by ratio {} \
                 within 2× ({} whole-interval){geo}.",
                s.info.id,
                t.rows,
                if differs == 1 { "differs" } else { "differ" },
                t.within_2x,
                t.whole_interval,
            ));
        }
    }
    out.join(" ")
}

/// The figure's caption.
pub fn caption(series: &[Series]) -> String {
    let fresh = series.iter().any(|s| s.rows.iter().any(|r| r.fresh));
    format!(
        "Every Table III row: ours ÷ paper (dot) with the 95 % bootstrap interval of our mean (bar){}; \
         green: the equivalence margin {:.2}–{:.2}; grey: within 2×. The bars leave out the paper's own \
         uncertainty (its std over its unstated number of runs), so a bar inside a band is not a verdict: \
         a row replicates only when the TOST, which includes it, shows it equivalent or within 2× \
         (table3.csv's verdict).",
        if fresh { ", on fresh seeds where the best cell was re-run" } else { "" },
        MARGIN.0,
        MARGIN.1
    )
}

/// The opening of the comparison pages: the plotted variants and the forest plot's pixel size
/// (`None` when not drawn).
pub struct Answer<'a> {
    /// The plotted variants ([`series`]); empty: no opening.
    pub series: &'a [Series<'a>],
    /// The figure's pixel size, when drawn.
    pub figure: Option<(u32, u32)>,
    /// What choosing the variant is worth (a comparison of declared variants).
    pub selection: Option<&'a Selection>,
}

/// The forest plot's alt text.
pub const ALT: &str =
    "Forest plot: ours ÷ paper per Table III row on a log axis, with the 95 % intervals of our means";

impl Answer<'_> {
    /// The opening as HTML: the sentences, then the figure (the SVG when written, else the PNG).
    pub fn html(&self, formats: Formats) -> String {
        if self.series.is_empty() {
            return String::new();
        }
        let mut h =
            format!("<div id=\"answer\">\n<p>{}</p>\n", escape_html(&opening(self.series, self.selection)));
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
        m.push_str(&format!("{}\n\n", opening(self.series, self.selection)));
        if let (Some(_), Some(ext)) = (self.figure, formats.figure_ext()) {
            m.push_str(&format!("![{ALT}]({STEM}.{ext})\n\n{}\n\n", caption(self.series)));
        }
        m
    }
}
