//! Comparing the variants of one pipeline (each the whole pipeline with some settings changed),
//! from a small [`VariantDigest`] per variant, so the trials of each variant can be dropped once
//! its own report is written:
//!
//! - `variants.md`, `variants.csv`: one row per variant, scoring how well its Table III reproduces
//!   the pipeline's `reference:` values ([`fit`]), best fit first;
//! - `figures/diff-<variant>-<system>.svg` (and `.png` with `--formats png`), for every variant
//!   but the first: per cell, the change of mean episodes against the first variant ([`diff`]);
//! - `index.html` and `README.md` (for repository web pages): links to each variant's own report,
//!   the table and the difference figures.

pub mod diff;
pub mod fit;

pub use diff::{all_diffs, diff_figure, diff_label, diff_seed, diverging, matching, CellDiff, DIFF_RULE};
pub use fit::{comparison_table, fit_order, verdict, Fit, Verdict, FIT_ORDER, REFERENCE_N, VERDICT_RULE};

use super::formats::{Format, Formats};
use super::model::ReportData;
use super::table::html::escape_html as esc;
use super::table::{render, Csv, Html, Markdown, Table};
use super::write_atomic;
use crate::cache::Key;
use crate::plan::{Cell, Experiment, Plan};
use crate::sim::env::SystemKind;
use crate::sim::Algorithm;
use anyhow::Context;
use std::path::{Path, PathBuf};

/// A variant's identity, as the pipeline declares it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct VariantInfo {
    /// Identifier (also its report folder's name).
    pub id: String,
    /// Optional title.
    pub title: Option<String>,
}

/// What the comparison keeps of one cell: its present trials' keys (for the bootstrap seed) and
/// counted episodes, and their mean.
#[derive(Debug, Clone)]
pub struct CellDigest<'p> {
    /// The planned cell.
    pub cell: &'p Cell,
    /// Keys of the present trials, in seed order.
    pub keys: Vec<Key>,
    /// Their counted episodes.
    pub values: Vec<f64>,
    /// Mean of `values`.
    pub mean: Option<f64>,
}

/// What the comparison keeps of one experiment.
#[derive(Debug, Clone)]
pub struct ExpDigest<'p> {
    /// The planned experiment.
    pub exp: &'p Experiment,
    /// Its cells, in plan order.
    pub cells: Vec<CellDigest<'p>>,
}

impl AsRef<Experiment> for ExpDigest<'_> {
    fn as_ref(&self) -> &Experiment {
        self.exp
    }
}

impl ExpDigest<'_> {
    /// The index of the cell with this algorithm and coordinates.
    pub fn find(&self, algorithm: Algorithm, coords: &[f64]) -> Option<usize> {
        self.cells.iter().position(|c| c.cell.algorithm == algorithm && c.cell.coords == coords)
    }
}

/// What the comparison keeps of one variant's report.
#[derive(Debug, Clone)]
pub struct VariantDigest<'p> {
    /// The variant.
    pub info: VariantInfo,
    /// Its fit to the reference values.
    pub fit: Fit,
    /// Planned (cell, seed) trials.
    pub trials_planned: usize,
    /// Of those, present.
    pub trials_present: usize,
    /// Its experiments.
    pub exps: Vec<ExpDigest<'p>>,
}

impl<'p> VariantDigest<'p> {
    /// The digest of `data`, the report data of `plan` (whose cells the digest borrows, so it
    /// outlives the trials `data` borrows).
    pub fn of(info: VariantInfo, plan: &'p Plan, data: &ReportData) -> Self {
        let exps = plan
            .experiments
            .iter()
            .zip(&data.experiments)
            .map(|(exp, e)| ExpDigest {
                exp,
                cells: exp
                    .cells
                    .iter()
                    .zip(&e.cells)
                    .map(|(cell, c)| CellDigest {
                        cell,
                        keys: c.trials.iter().map(|t| t.planned.key).collect(),
                        values: c.trials.iter().map(|t| f64::from(t.counted)).collect(),
                        mean: c.summary.mean,
                    })
                    .collect(),
            })
            .collect();
        Self {
            info,
            fit: Fit::of(data),
            trials_planned: data.trials_planned,
            trials_present: data.trials_present,
            exps,
        }
    }

    /// Systems present, in report order.
    pub fn systems(&self) -> Vec<SystemKind> {
        SystemKind::ALL.into_iter().filter(|s| self.exps.iter().any(|e| e.exp.system == *s)).collect()
    }
}

/// Write the comparison of `variants` (the first is the base of the difference figures) of
/// `plan` into `dir` in `formats`. Returns the files written, relative to `dir`, in writing order.
pub fn write_comparison(
    dir: &Path,
    plan: &Plan,
    variants: &[VariantDigest],
    formats: Formats,
) -> anyhow::Result<Vec<PathBuf>> {
    std::fs::create_dir_all(dir.join("figures"))
        .with_context(|| format!("cannot create the report directory {}", dir.display()))?;
    let mut files = Vec::new();
    let mut put = |name: &str, bytes: &[u8]| -> anyhow::Result<()> {
        write_atomic(&dir.join(name), bytes)?;
        files.push(PathBuf::from(name));
        Ok(())
    };
    let fits: Vec<(&VariantInfo, Fit)> = variants.iter().map(|v| (&v.info, v.fit)).collect();
    let table = comparison_table(&fits);
    if formats.has(Format::Md) {
        put("variants.md", render(&table, &Markdown).as_bytes())?;
    }
    if formats.has(Format::Csv) {
        put("variants.csv", render(&table, &Csv).as_bytes())?;
    }
    let (svg, png) = (formats.has(Format::Svg), formats.has(Format::Png));
    let mut figs = Vec::new();
    if let Some(base) = variants.first() {
        for v in &variants[1..] {
            let diffs = if svg || png { all_diffs(base, v) } else { Vec::new() };
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
                figs.push((&v.info, system, stem, super::figures::figure_size(&exps)));
            }
        }
    }
    if formats.has(Format::Html) {
        put("index.html", page(plan, variants, &table, &figs, formats).as_bytes())?;
    }
    if formats.has(Format::Md) {
        put("README.md", readme(plan, variants, &table, &figs, formats).as_bytes())?;
    }
    Ok(files)
}

type FigRef<'a> = (&'a VariantInfo, SystemKind, String, (u32, u32));

/// The comparison page.
fn page(plan: &Plan, variants: &[VariantDigest], table: &Table, figs: &[FigRef], formats: Formats) -> String {
    let name = plan.name.as_str();
    let mut h = String::new();
    h.push_str("<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n");
    h.push_str(&format!("<title>qsweep variants: {}</title>\n", esc(name)));
    h.push_str(&format!("<style>\n{}</style>\n</head>\n<body>\n", super::html::STYLE));
    h.push_str(&format!("<h1>qsweep variants: {}</h1>\n", esc(name)));
    if let Some(d) = plan.description.as_deref() {
        h.push_str(&format!("<p>{}</p>\n", esc(d)));
    }
    h.push_str("<p>Each variant is the whole pipeline with some settings changed; each has its own full report:</p>\n<ul>\n");
    for v in variants {
        let title = v.info.title.as_deref().map(|t| format!(": {}", esc(t))).unwrap_or_default();
        h.push_str(&format!(
            "<li><a href=\"{0}/index.html\"><code>{0}</code></a>{title} ({1} of {2} planned trials present)</li>\n",
            esc(&v.info.id),
            v.trials_present,
            v.trials_planned
        ));
    }
    h.push_str("</ul>\n<p>Data: <a href=\"variants.csv\">variants.csv</a> · <a href=\"variants.md\">variants.md</a> · \
                <a href=\"cells.parquet\">cells.parquet</a> (every variant's cells, with a <code>variant</code> column)</p>\n");
    h.push_str("<h2 id=\"fit\">Fit to the reference values</h2>\n");
    // The caption is a paragraph of its own: inside the table it would widen the table to its
    // own unwrapped length.
    h.push_str(&format!("<p class=\"caption\">{}</p>\n<div class=\"scroll\">\n", esc(&table.caption)));
    let mut bare = table.clone();
    bare.caption.clear();
    h.push_str(&render(&bare, &Html));
    h.push_str("</div>\n");
    if let (Some(base), Some(ext)) = (variants.first(), formats.figure_ext()) {
        for v in &variants[1..] {
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

/// The comparison as Markdown, for repository web pages (which show `README.md` and SVG images,
/// not HTML pages).
fn readme(
    plan: &Plan,
    variants: &[VariantDigest],
    table: &Table,
    figs: &[FigRef],
    formats: Formats,
) -> String {
    let mut m = format!("# qsweep variants: {}\n\n", plan.name);
    if let Some(d) = plan.description.as_deref() {
        m.push_str(&format!("{}\n\n", d.trim()));
    }
    m.push_str(
        "Each variant is the whole pipeline with some settings changed; each has its own full report:\n\n",
    );
    for v in variants {
        let title = v.info.title.as_deref().map(|t| format!(": {t}")).unwrap_or_default();
        m.push_str(&format!(
            "- [`{0}`]({0}/README.md){title} ({1} of {2} planned trials present)\n",
            v.info.id, v.trials_present, v.trials_planned
        ));
    }
    m.push_str("\n## Fit to the reference values\n\n");
    m.push_str(&render(table, &Markdown));
    if let (Some(base), Some(ext)) = (variants.first(), formats.figure_ext()) {
        for v in &variants[1..] {
            m.push_str(&format!("\n## {} against {}\n\n", v.info.id, base.info.id));
            for (_, system, stem, _) in figs.iter().filter(|f| f.0.id == v.info.id) {
                m.push_str(&format!(
                    "![{}: {} against {}]({stem}.{ext})\n\n",
                    system.title(),
                    v.info.id,
                    base.info.id
                ));
            }
            m.push_str(&format!("{DIFF_RULE}\n"));
        }
    }
    m
}
