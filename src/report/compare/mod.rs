//! Comparing the variants of one pipeline (each the whole pipeline with some settings changed),
//! from a small [`VariantDigest`] per variant, so the trials of each variant can be dropped once
//! its own report is written:
//!
//! - `variants.md`, `variants.csv`: one row per variant, scoring how well its Table III reproduces
//!   the pipeline's `reference:` values ([`fit`]), best fit first;
//! - `figures/forest.svg` (and `.png`), where the pipeline has reference values: every Table III
//!   row's ours ÷ reference with its interval, as written and under the best declared reading
//!   ([`forest`]);
//! - `figures/diff-<variant>-<system>.svg` (and `.png` with `--formats png`), for every variant
//!   but the first: per cell, the change of mean episodes against the first variant ([`diff`]);
//! - `index.html` and `README.md` (for repository web pages): the answer in a few sentences
//!   ([`answer`]) and the forest plot first, then links to each variant's own report, the table and the difference
//!   figures.

pub mod answer;
pub mod conclusions;
pub mod diff;
mod digest;
pub mod explore;
pub mod fit;
pub mod forest;
mod info;

pub use digest::{CellDigest, ExpDigest, VariantDigest, VariantInfo};

pub use diff::{all_diffs, diff_figure, diff_label, diff_seed, diverging, matching, CellDiff, DIFF_RULE};
pub use fit::{
    comparison_table, fit_order, rows_of, verdict, Fit, RowFit, Verdict, FIT_ORDER, REFERENCE_N, VERDICT_RULE,
};

use super::formats::{Format, Formats};
use super::table::html::escape_html as esc;
use super::table::{render, Csv, Html, Markdown, Table};
use crate::plan::Plan;
use crate::sim::env::SystemKind;
use std::path::{Path, PathBuf};

/// Write the comparison of `variants` (the first is the base of the difference figures) of
/// `plan` into `dir` in `formats`. Returns the files written, relative to `dir`, in writing order.
pub fn write_comparison(
    dir: &Path,
    plan: &Plan,
    variants: &[VariantDigest],
    formats: Formats,
) -> anyhow::Result<Vec<PathBuf>> {
    let mut out = super::folder::Folder::create(dir)?;
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
        // A generated reading has its own folder and difference figures only when chosen.
        for v in variants[1..].iter().filter(|v| has_folder(plan, chosen, &v.info.id)) {
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
    let notes = dir.join(NOTES).is_file();
    if formats.has(Format::Html) {
        let tables = Tables { fit: &table, held_out: held_out.as_ref(), matrix: matrix.as_ref() };
        let answer = answer::Answer { series: &series, figure: forest_size };
        put("index.html", page(plan, variants, &tables, &answer, &figs, formats, notes).as_bytes())?;
    }
    if formats.has(Format::Md) {
        let tables = Tables { fit: &table, held_out: held_out.as_ref(), matrix: matrix.as_ref() };
        let answer = answer::Answer { series: &series, figure: forest_size };
        put("README.md", readme(plan, variants, &tables, &answer, &figs, formats, notes).as_bytes())?;
    }
    Ok(out.files)
}

/// Whether the report writes the folder of variant `id` (and its difference figures): every
/// declared (not exploratory) variant of a pipeline without a grid; with a `variant_grid:`, only the chosen reading, so a
/// grid of many readings does not write (or commit) a full report each; the rest are written on
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
    /// The fit of every reading.
    fit: &'a Table,
    /// An exploratory search's held-out rows.
    held_out: Option<&'a Table>,
    /// The reading × claim matrix (pipelines with reference values).
    matrix: Option<&'a Table>,
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
    h.push_str(&format!("<style>\n{}</style>\n</head>\n<body>\n", super::html::STYLE));
    h.push_str(&format!("<h1>{}</h1>\n", esc(&heading(plan))));
    if let Some(d) = plan.description.as_deref() {
        h.push_str(&format!("<p>{}</p>\n", esc(d)));
    }
    h.push_str(&answer.html(formats));
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
    .filter(|(f, _)| formats.has(*f))
    .map(|(_, l)| l)
    .collect();
    if !links.is_empty() {
        h.push_str(&format!("<p>Data: {}</p>\n", links.join(" · ")));
    }
    h.push_str("<h2 id=\"fit\">Fit to the reference values</h2>\n");
    h.push_str(&captioned(tables.fit));
    if let Some(t) = tables.held_out {
        h.push_str("<h2 id=\"held-out\">Held-out rows</h2>\n");
        h.push_str(&captioned(t));
    }
    if let Some(t) = tables.matrix {
        h.push_str("<h2 id=\"claims\">The paper's conclusions, per reading</h2>\n");
        h.push_str(&captioned(t));
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
    let mut m = format!("# {}\n\n", heading(plan));
    if let Some(d) = plan.description.as_deref() {
        m.push_str(&format!("{}\n\n", d.trim()));
    }
    m.push_str(&answer.markdown(formats));
    if notes {
        m.push_str(&format!("What these results mean for the replication: [{NOTES}]({NOTES}).\n\n"));
    }
    m.push_str(
        "Each variant is the whole pipeline with some settings changed; each has its own full report:\n\n",
    );
    for v in variants {
        let title = v.info.title.as_deref().map(|t| format!(": {t}")).unwrap_or_default();
        if has_folder(plan, chosen, &v.info.id) {
            m.push_str(&format!(
                "- [`{0}`]({0}/README.md){title} ({1} of {2} planned trials present)\n",
                v.info.id, v.trials_cached, v.trials_planned
            ));
        } else {
            m.push_str(&format!(
                "- `{0}`{title} ({1} of {2} planned trials present; report on demand: `qsweep report {3} --variant '{0}'`)\n",
                v.info.id,
                v.trials_cached,
                v.trials_planned,
                plan.source.display()
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
        m.push_str("\n## The paper's conclusions, per reading\n\n");
        m.push_str(&render(t, &Markdown));
    }
    if let (Some(base), Some(ext)) = (variants.first(), formats.figure_ext()) {
        for v in variants[1..].iter().filter(|v| has_folder(plan, chosen, &v.info.id)) {
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::analysis::bootstrap_diff_ci;
    use crate::cache::{Key, TrialRecord};
    use crate::plan::plan;
    use crate::report::model::ReportData;
    use crate::sim::run_trial;
    use crate::spec::{load_str, LoadedSpec, Override};
    use plotters::style::RGBColor;
    use std::collections::{BTreeMap, HashMap};

    /// Two Ball-Beam experiments (a 2 × 2 grid and a 3-cell row), 4 seeds, short trials.
    const PIPELINE: &str = "\
name: vt
seeds: 4
defaults: { max_episodes: 25 }
systems:
  ball-beam:
    crisp: { epsilon: 1.0e-6, gamma: 0.9, alpha: 0.1, lambda: 0.9 }
    success: { steps: 300 }
    experiments:
      - id: 1
        repr: crisp
        vary: { x: [2, 3], x_dot: [2, 3] }
        fixed: { actions: 3 }
        reference:
          q0: { mean: 6.0, std: 3.0, resolution: [3, 3], actions: 3 }
          q-lambda: { mean: 2.0, std: 1.0, resolution: [2, 3], actions: 3 }
      - id: 2
        repr: crisp
        vary: { x: [2, 3, 4] }
        fixed: { x_dot: 3, actions: 3 }
        reference:
          q0: { mean: 8.0, std: 3.0 }
";

    fn plan_with(sets: &[&str]) -> Plan {
        let overrides: Vec<Override> = sets.iter().map(|s| Override::parse(s).unwrap()).collect();
        let spec = load_str(PIPELINE, "vt.yaml", &overrides).unwrap();
        plan(&LoadedSpec { spec, path: "vt.yaml".into(), variants: Vec::new() }, None).unwrap()
    }

    fn run_all(plan: &Plan) -> HashMap<Key, TrialRecord> {
        plan.unique_trials()
            .into_iter()
            .map(|(c, t)| (t.key, TrialRecord::new(c.clone(), t.seed, run_trial(c, t.seed), 0.0)))
            .collect()
    }

    fn files(dir: &Path) -> BTreeMap<String, Vec<u8>> {
        let mut out = BTreeMap::new();
        for sub in ["", "figures"] {
            for entry in std::fs::read_dir(dir.join(sub)).unwrap() {
                let p = entry.unwrap().path();
                if p.is_file() {
                    let name = p.strip_prefix(dir).unwrap().to_string_lossy().into_owned();
                    out.insert(name, std::fs::read(&p).unwrap());
                }
            }
        }
        out
    }

    /// The fit recomputed from the trials, independently of [`Fit::from_rows`]: (rows, replicating,
    /// within 2×, config matches, order matches, experiments ordered, geometric mean).
    fn by_hand(d: &ReportData) -> (usize, usize, usize, usize, usize, usize, f64) {
        let (mut rows, mut rep, mut w2, mut cfg, mut ord, mut ord_n, mut logs) = (0, 0, 0, 0, 0, 0, vec![]);
        for e in &d.experiments {
            let mut means = vec![];
            for &a in &e.exp.algorithms {
                let Some(r) = e.exp.reference.get(&a) else { continue };
                let c = &e.cells[e.best_of(a).unwrap().cell];
                let v: Vec<f64> = c.trials.iter().map(|t| f64::from(t.counted)).collect();
                let n = v.len() as f64;
                let m = v.iter().sum::<f64>() / n;
                let s = (v.iter().map(|x| (x - m) * (x - m)).sum::<f64>() / (n - 1.0)).sqrt();
                rows += 1;
                if (m - r.mean).abs() <= 2.0 * (r.std * r.std / 10.0 + s * s / n).sqrt() {
                    rep += 1;
                } else if m / r.mean >= 0.5 && m / r.mean <= 2.0 {
                    w2 += 1;
                }
                let res = &c.cell.config.repr.resolution;
                if r.resolution.as_ref() == Some(res) && r.actions == Some(c.cell.config.actions) {
                    cfg += 1;
                }
                logs.push((m / r.mean).ln());
                means.push((m, r.mean));
            }
            if means.len() == 2 {
                ord_n += 1;
                if (means[0].0 <= means[1].0) == (means[0].1 <= means[1].1) {
                    ord += 1;
                }
            }
        }
        (rows, rep, w2, cfg, ord, ord_n, (logs.iter().sum::<f64>() / logs.len() as f64).exp())
    }

    #[test]
    fn verdicts_follow_the_replication_rule() {
        // se = √(3²/10 + 2²/4) = √1.9 ≈ 1.378; 2·se ≈ 2.757.
        assert_eq!(verdict(8.7, Some(2.0), 4, 6.0, 3.0), Verdict::Replicates);
        assert_eq!(verdict(8.8, Some(2.0), 4, 6.0, 3.0), Verdict::Within2x);
        assert_eq!(verdict(12.0, Some(2.0), 4, 6.0, 3.0), Verdict::Within2x);
        assert_eq!(verdict(12.1, Some(2.0), 4, 6.0, 3.0), Verdict::DoesNotReplicate);
        assert_eq!(verdict(6.0, None, 1, 6.0, 3.0), Verdict::Within2x, "no std: cannot replicate");
        let f = |replicating, within_2x, geo_mean| Fit { replicating, within_2x, geo_mean, ..Fit::default() };
        let fits =
            [f(1, 3, Some(1.1)), f(2, 0, None), f(1, 3, Some(0.95)), f(1, 3, None), f(1, 4, Some(3.0))];
        assert_eq!(fit_order(&fits), vec![1, 4, 2, 0, 3]);
        assert_eq!(diff_label(-12.345), "−12.3");
        assert_eq!(diff_label(0.001), "0.00");
        assert_eq!(diff_label(150.0), "+150");
        assert_eq!(diverging(0.0), RGBColor(247, 247, 247));
        assert_eq!(diverging(-1.0), RGBColor(33, 102, 172));
        assert_eq!(diverging(9.0), RGBColor(178, 24, 43));
    }

    #[test]
    fn comparison_of_two_variants_is_right_and_deterministic() {
        let base = plan_with(&[]);
        let other = plan_with(&["systems.ball-beam.crisp.alpha=0.5", "systems.ball-beam.crisp.lambda=0.3"]);
        let rec_base = run_all(&base);
        let mut rec_other = run_all(&other);
        // The other variant lacks every trial of one cell: grey in its difference figure.
        let gone = &other.experiments[1].cells[2];
        for t in &gone.trials {
            rec_other.remove(&t.key);
        }
        let data = [ReportData::build(&base, &rec_base), ReportData::build(&other, &rec_other)];
        let variants = vec![
            VariantDigest::of(
                VariantInfo { id: "as-written".into(), title: Some("The text".into()), exploratory: false },
                &base,
                &data[0],
            ),
            VariantDigest::of(
                VariantInfo { id: "fast".into(), title: None, exploratory: false },
                &other,
                &data[1],
            ),
        ];
        let all = Formats::of(&Format::ALL);
        let tmp = tempfile::tempdir().unwrap();
        let written = write_comparison(tmp.path(), &base, &variants, all).unwrap();
        let names: Vec<String> = written.iter().map(|p| p.to_string_lossy().into_owned()).collect();
        assert_eq!(
            names,
            [
                "variants.md",
                "variants.csv",
                "figures/forest.svg",
                "figures/forest.png",
                "figures/diff-fast-ball-beam.svg",
                "figures/diff-fast-ball-beam.png",
                "index.html",
                "README.md"
            ]
        );
        // The claims speak of all three systems: a Ball-Beam-only pipeline has no conclusions.
        assert!(variants.iter().all(|v| v.claims.is_empty()));
        let out = files(tmp.path());
        assert_eq!(
            out.keys().cloned().collect::<Vec<_>>().len(),
            8,
            "no temporary files left: {:?}",
            out.keys()
        );

        // The CSV's numbers, recomputed from the trials.
        let csv = String::from_utf8(out["variants.csv"].clone()).unwrap();
        let mut lines = csv.lines();
        let header: Vec<&str> = lines.next().unwrap().split(',').collect();
        assert_eq!(
            header,
            [
                "rank",
                "variant",
                "title",
                "rows",
                "replicating",
                "within_2x",
                "config_match",
                "order_match",
                "order_experiments",
                "geo_mean_ratio",
                "equivalent_n10",
                "equivalent_n100",
                "exploratory"
            ]
        );
        let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
        assert_eq!(rows.len(), 2);
        let fits: Vec<_> = data.iter().map(by_hand).collect();
        for (v, d) in variants.iter().map(|v| &v.info).zip(&data) {
            let row = rows.iter().find(|r| r[1] == v.id).unwrap();
            let (n, rep, w2, cfg, ord, ord_n, geo) = by_hand(d);
            let ints: Vec<usize> = row[3..9].iter().map(|s| s.parse().unwrap()).collect();
            assert_eq!(ints, [n, rep, w2, cfg, ord, ord_n], "{}", v.id);
            assert_eq!(n, 3);
            assert_eq!(ord_n, 1);
            let g: f64 = row[9].parse().unwrap();
            assert!((g - geo).abs() < 1e-12, "{g} vs {geo}");
            assert_eq!(row[2], v.title.as_deref().unwrap_or(""));
        }
        // Rows are in fit order.
        let first = if (fits[0].1, fits[0].2, -fits[0].6.ln().abs())
            >= (fits[1].1, fits[1].2, -fits[1].6.ln().abs())
        {
            "as-written"
        } else {
            "fast"
        };
        assert_eq!((rows[0][0], rows[0][1]), ("1", first));
        let md = String::from_utf8(out["variants.md"].clone()).unwrap();
        assert!(md.starts_with("**Variants.** How well each variant"));
        assert!(md.contains("most replicating rows first"));

        // Markers exactly where the difference's interval excludes 0.
        let (b, o) = (&variants[0], &variants[1]);
        let mut marked = 0;
        let mut unmarked = 0;
        let mut missing = 0;
        let diffs = all_diffs(b, o);
        for (k, e) in o.exps.iter().enumerate() {
            for (i, c) in e.cells.iter().enumerate() {
                let Some(d) = matching(b, e, i).and_then(|bc| CellDiff::of(bc, c)) else {
                    missing += 1;
                    assert_eq!(diffs[k][i], None);
                    continue;
                };
                assert_eq!(diffs[k][i], Some(d));
                // Recomputed from the trials themselves, not the digest.
                let bd = &data[0].experiments[k];
                let od = &data[1].experiments[k];
                let j = bd.find(c.cell.algorithm, &c.cell.coords).unwrap();
                let va: Vec<f64> = bd.cells[j].trials.iter().map(|t| f64::from(t.counted)).collect();
                let vb: Vec<f64> = od.cells[i].trials.iter().map(|t| f64::from(t.counted)).collect();
                let bc = matching(b, e, i).unwrap();
                let ci = bootstrap_diff_ci(&va, &vb, 2000, diff_seed(bc, c));
                assert_eq!(d.ci, ci);
                assert!((d.diff - (crate::analysis::mean(&vb) - crate::analysis::mean(&va))).abs() < 1e-12);
                assert_eq!(d.significant, ci.0 > 0.0 || ci.1 < 0.0);
                if d.significant {
                    marked += 1;
                } else {
                    unmarked += 1;
                }
            }
        }
        assert_eq!(missing, 1, "only the removed cell");
        assert!(marked >= 1 && unmarked >= 1, "{marked} marked, {unmarked} unmarked");
        let svg = String::from_utf8(out["figures/diff-fast-ball-beam.svg"].clone()).unwrap();
        assert_eq!(svg.matches("<circle").count(), marked + 1, "one dot per marked cell, one in the legend");
        assert!(svg.contains("#C8C8C8"), "the missing cell is grey");

        let html = String::from_utf8(out["index.html"].clone()).unwrap();
        for link in [
            "as-written/index.html",
            "fast/index.html",
            "variants.csv",
            "figures/forest.svg",
            "figures/diff-fast-ball-beam.svg",
        ] {
            assert!(html.contains(&format!("\"{link}\"")), "index.html links {link}");
        }
        // The opening and its figure come first (tests/cli/forest.rs checks their order).
        assert!(html.contains("<div id=\"answer\">"));

        // Determinism: a second write gives identical bytes.
        let again = tempfile::tempdir().unwrap();
        write_comparison(again.path(), &base, &variants, all).unwrap();
        assert_eq!(files(again.path()), out);
        write_comparison(tmp.path(), &base, &variants, all).unwrap();
        assert_eq!(files(tmp.path()), out);
    }
}
