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
mod contents;
pub mod diff;
pub mod forest;
mod html;
mod markdown;

pub use contents::{has_folder, NOTES};
pub use diff::{all_diffs, diff_figure, diff_label, diff_seed, diverging, matching, CellDiff, DIFF_RULE};

use crate::derive::table::Table;
use crate::formats::{Format, Formats};
use crate::memo::stats::StatsMemo;
use crate::render::table::{render, Csv, Markdown};
use crate::replication::compare::{
    comparison_table, conclusions, consistency, explore, selection, verdicts, ExpDigest, Fit, VariantDigest,
    VariantInfo,
};
use contents::{FigRef, Tables};
use qsweep_pipeline::plan::Plan;
use std::path::{Path, PathBuf};

/// Where a file of the comparison goes: its name in the folder and its bytes.
type Put<'p> = dyn FnMut(&str, &[u8]) -> anyhow::Result<()> + 'p;

/// Write the comparison of `variants` (the first is the base of the difference figures) of
/// `plan` into `dir` in `formats`. Returns the files written, relative to `dir`, in writing order.
pub fn write_comparison(
    dir: &Path,
    plan: &Plan,
    variants: &[VariantDigest],
    formats: Formats,
    memo: &StatsMemo,
) -> anyhow::Result<Vec<PathBuf>> {
    let mut out = crate::render::folder::Folder::create(dir)?;
    let mut put = |name: &str, bytes: &[u8]| out.put(name, bytes).map(drop);
    let t = Computed::of(plan, variants);
    t.write(formats, &mut put)?;
    let (svg, png) = (formats.has(Format::Svg), formats.has(Format::Png));
    let series = answer::series(plan, variants);
    let forest_size = forest::write(&plan.name, &series, (svg, png), &mut put)?;
    let figs = write_diffs(plan, variants, memo, (svg, png), &mut put)?;
    let notes = dir.join(NOTES).is_file();
    let tables = Tables {
        fit: &t.fit,
        held_out: t.held_out.as_ref(),
        matrix: t.matrix.as_ref(),
        consistency: t.consistency.as_ref(),
        by_n: t.by_n.is_some(),
    };
    let answer = answer::Answer { series: &series, figure: forest_size, selection: t.selection.as_ref() };
    if formats.has(Format::Html) {
        put("index.html", html::page(plan, variants, &tables, &answer, &figs, formats, notes).as_bytes())?;
    }
    if formats.has(Format::Md) {
        put(
            "README.md",
            markdown::readme(plan, variants, &tables, &answer, &figs, formats, notes).as_bytes(),
        )?;
    }
    Ok(out.files)
}

/// The comparison's tables, computed once for its files and its pages.
struct Computed {
    /// The fit of every variant (an exploratory search: its ranking).
    fit: Table,
    /// An exploratory search's held-out rows.
    held_out: Option<Table>,
    /// The variant × claim matrix and the long table of claims (pipelines with claims).
    matrix: Option<Table>,
    conclusions: Option<Table>,
    /// Every variant's rows judged at each assumed n (not in an exploratory search).
    by_n: Option<Table>,
    /// Each row judged under the variant chosen on the others (two or more declared variants).
    selection: Option<selection::Selection>,
    /// The pairs of Table III rows whose grids overlap (pipelines with reference values).
    consistency: Option<Table>,
}

impl Computed {
    fn of(plan: &Plan, variants: &[VariantDigest]) -> Self {
        let fit = match &plan.exploratory {
            Some(x) => explore::search_table(plan, x, variants),
            None => {
                let fits: Vec<(&VariantInfo, Fit)> = variants.iter().map(|v| (&v.info, v.fit)).collect();
                comparison_table(&fits, plan.has_fresh())
            }
        };
        let claims = variants.iter().any(|v| !v.claims.is_empty());
        Self {
            fit,
            held_out: plan.exploratory.as_ref().and_then(|x| explore::held_out_table(plan, x, variants)),
            matrix: claims.then(|| conclusions::matrix_table(variants)),
            conclusions: claims.then(|| conclusions::conclusions_table(variants)),
            // An exploratory search judges its choice on held-out rows of its own (held_out.csv).
            by_n: plan.exploratory.is_none().then(|| verdicts::verdicts_by_n_table(variants)).flatten(),
            selection: selection::selection(plan.exploratory.is_some(), variants),
            consistency: consistency::consistency_table(plan).map(|c| c.1),
        }
    }

    /// The tables' files in `formats`, in order; the long table of claims as CSV only (the pages
    /// show the matrix).
    fn write(&self, formats: Formats, put: &mut Put) -> anyhow::Result<()> {
        let (md, csv) = (formats.has(Format::Md), formats.has(Format::Csv));
        let both = |name: &str, t: &Table, put: &mut Put| -> anyhow::Result<()> {
            if md {
                put(&format!("{name}.md"), render(t, &Markdown).as_bytes())?;
            }
            if csv {
                put(&format!("{name}.csv"), render(t, &Csv).as_bytes())?;
            }
            Ok(())
        };
        both("variants", &self.fit, put)?;
        if csv {
            if let Some(t) = &self.conclusions {
                put("conclusions.csv", render(t, &Csv).as_bytes())?;
            }
            if let Some(t) = &self.by_n {
                put("verdicts_by_n.csv", render(t, &Csv).as_bytes())?;
            }
            if let Some(s) = &self.selection {
                put("cross_validation.csv", render(&selection::table(s), &Csv).as_bytes())?;
            }
        }
        if let Some(t) = &self.consistency {
            both("consistency", t, put)?;
        }
        if let Some(t) = &self.held_out {
            both("held_out", t, put)?;
        }
        Ok(())
    }
}

/// The difference figures of every variant with a folder but the first, against the first, in
/// `(svg, png)`; what was drawn, for the pages.
fn write_diffs<'v>(
    plan: &Plan,
    variants: &'v [VariantDigest],
    memo: &StatsMemo,
    (svg, png): (bool, bool),
    put: &mut Put,
) -> anyhow::Result<Vec<FigRef<'v>>> {
    let mut figs = Vec::new();
    let chosen = explore::chosen(plan, variants).map(|c| c.id.as_str());
    let Some(base) = variants.first() else { return Ok(figs) };
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
    Ok(figs)
}

#[cfg(test)]
mod tests;
