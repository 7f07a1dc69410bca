//! Comparing the variants of one pipeline (each the whole pipeline with some settings changed):
//!
//! - `variants.md`, `variants.csv`: one row per variant, scoring how well its Table III reproduces
//!   the pipeline's `reference:` values ([`Fit`]), best fit first ([`FIT_ORDER`]);
//! - `figures/diff-<variant>-<system>.svg` and `.png`, for every variant but the first: per cell,
//!   the change of mean episodes against the first variant, in the layout of the system's figure,
//!   cells whose bootstrap 95% interval of the difference excludes 0 marked ([`CellDiff`]);
//! - `index.html`: links to each variant's own report (`<id>/index.html`, written by
//!   [`super::write_report`]), the table and the difference figures.
//!
//! The verdict rule is the one of `scripts/replication_summary.py` (and REPLICATION.md), so the
//! CSV can be recomputed from each variant's `table3.csv`.

use super::figures::{self, cell_label_value, columns, ink_on, Canvas, Picture, Res, INK, MISSING, SUBTLE};
use super::model::{resolution_columns, CellData, ExpData, ReportData};
use super::stats::{bootstrap_diff_ci, BOOTSTRAP_RESAMPLES};
use super::table::html::escape_html as esc;
use super::table::{render, Align, Column, Csv, Html, Markdown, Row, Table, Value};
use super::write_atomic;
use crate::cache::Key;
use crate::sim::env::SystemKind;
use crate::sim::Algorithm;
use anyhow::Context;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, VPos};
use std::path::{Path, PathBuf};

/// A variant's identity, as the pipeline declares it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct VariantInfo {
    /// Identifier (also its report folder's name).
    pub id: String,
    /// Optional title.
    pub title: Option<String>,
}

/// Seeds behind each reference value (the paper's ten runs), for the standard error.
pub const REFERENCE_N: f64 = 10.0;

/// The verdict rule, as stated in the caption.
pub const VERDICT_RULE: &str = "A Table III row replicates its reference when |ours − reference| ≤ \
2·√(s_ref²/10 + s_ours²/n) (two standard errors; the reference has 10 runs, a row with a single \
trial has no std and does not replicate); it is within 2× when it does not replicate but 0.5 ≤ \
ours/reference ≤ 2.";

/// How the rows are ordered, as stated in the caption.
pub const FIT_ORDER: &str = "Rows are ordered by fit (the measure pre-registered in \
docs/preregistration.md): most replicating rows first, then most rows within 2×, then most matching \
best configurations, then the geometric mean of ours/reference closest to 1 (smallest |ln|), then \
pipeline order.";

/// How well one variant's Table III matches the reference values.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Fit {
    /// Table III rows with a reference value and a best cell.
    pub rows: usize,
    /// Of those, rows that replicate ([`VERDICT_RULE`]).
    pub replicating: usize,
    /// Rows that do not replicate but are within a factor 2.
    pub within_2x: usize,
    /// Rows whose best cell has the reference's resolution and action count.
    pub config_match: usize,
    /// Experiments whose algorithms rank by mean as in the reference.
    pub order_match: usize,
    /// Experiments with two or more algorithms, every one with a reference and a best cell.
    pub order_experiments: usize,
    /// Geometric mean of ours / reference over the rows (`None` without rows).
    pub geo_mean: Option<f64>,
}

/// Verdict of one Table III row against its reference.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Verdict {
    /// Within two standard errors.
    Replicates,
    /// Not replicating, but ours/reference ∈ [0.5, 2].
    Within2x,
    /// Neither.
    DoesNotReplicate,
}

/// The verdict for our mean and std over `n` trials against a reference mean and std.
pub fn verdict(ours: f64, ours_std: Option<f64>, n: usize, ref_mean: f64, ref_std: f64) -> Verdict {
    let replicates = ours_std.is_some_and(|s| {
        let se = (ref_std * ref_std / REFERENCE_N + s * s / n as f64).sqrt();
        (ours - ref_mean).abs() <= 2.0 * se
    });
    if replicates {
        Verdict::Replicates
    } else if ref_mean > 0.0 && (0.5..=2.0).contains(&(ours / ref_mean)) {
        Verdict::Within2x
    } else {
        Verdict::DoesNotReplicate
    }
}

impl Fit {
    /// Score a variant's report data.
    pub fn of(data: &ReportData) -> Self {
        let mut f = Self::default();
        let mut logs = Vec::new();
        for e in &data.experiments {
            let system = e.exp.system;
            let mut ranked = Vec::new();
            for &alg in &e.exp.algorithms {
                let Some(r) = e.exp.reference.get(&alg) else { continue };
                let Some(c) = e.best_of(alg).map(|b| &e.cells[b.cell]) else { continue };
                let Some(mean) = c.summary.mean else { continue };
                f.rows += 1;
                match verdict(mean, c.summary.std, c.trials.len(), r.mean, r.std) {
                    Verdict::Replicates => f.replicating += 1,
                    Verdict::Within2x => f.within_2x += 1,
                    Verdict::DoesNotReplicate => {}
                }
                let cfg = &c.cell.config;
                let ours: Vec<u32> = resolution_columns(system, &cfg.repr.resolution)
                    .into_iter()
                    .flatten()
                    .chain([cfg.actions])
                    .collect();
                let theirs: Vec<u32> = r
                    .resolution
                    .as_ref()
                    .map_or([None; 4], |res| resolution_columns(system, res))
                    .into_iter()
                    .flatten()
                    .chain(r.actions)
                    .collect();
                f.config_match += usize::from(ours == theirs);
                if mean > 0.0 && r.mean > 0.0 {
                    logs.push((mean / r.mean).ln());
                }
                ranked.push((mean, r.mean));
            }
            if ranked.len() >= 2 && ranked.len() == e.exp.algorithms.len() {
                f.order_experiments += 1;
                f.order_match +=
                    usize::from(rank(ranked.iter().map(|r| r.0)) == rank(ranked.iter().map(|r| r.1)));
            }
        }
        if !logs.is_empty() {
            f.geo_mean = Some((logs.iter().sum::<f64>() / logs.len() as f64).exp());
        }
        f
    }
}

/// Indices in ascending order of value (stable: ties keep algorithm order).
fn rank(values: impl Iterator<Item = f64>) -> Vec<usize> {
    let v: Vec<f64> = values.collect();
    let mut idx: Vec<usize> = (0..v.len()).collect();
    idx.sort_by(|&i, &j| v[i].total_cmp(&v[j]));
    idx
}

/// Indices of `fits` in [`FIT_ORDER`].
pub fn fit_order(fits: &[Fit]) -> Vec<usize> {
    let off = |f: &Fit| f.geo_mean.map_or(f64::INFINITY, |g| g.ln().abs());
    let mut idx: Vec<usize> = (0..fits.len()).collect();
    idx.sort_by(|&i, &j| {
        let (a, b) = (&fits[i], &fits[j]);
        b.replicating
            .cmp(&a.replicating)
            .then(b.within_2x.cmp(&a.within_2x))
            .then(b.config_match.cmp(&a.config_match))
            .then(off(a).total_cmp(&off(b)))
    });
    idx
}

/// The comparison table: one row per variant, in [`FIT_ORDER`].
pub fn comparison_table(variants: &[(&VariantInfo, Fit)]) -> Table {
    let columns = vec![
        Column::new("Rank", "rank", Align::Right),
        Column::new("Variant", "variant", Align::Left),
        Column::new("Title", "title", Align::Left),
        Column::new("Rows with reference", "rows", Align::Right),
        Column::new("Replicate", "replicating", Align::Right),
        Column::new("Within 2×", "within_2x", Align::Right),
        Column::new("Config matches", "config_match", Align::Right),
        Column::new("Order matches", "order_match", Align::Right),
        Column::new("Experiments ordered", "order_experiments", Align::Right),
        Column::new("Geo. mean ours/ref.", "geo_mean_ratio", Align::Right),
    ];
    let fits: Vec<Fit> = variants.iter().map(|v| v.1).collect();
    let rows = fit_order(&fits)
        .into_iter()
        .enumerate()
        .map(|(k, i)| {
            let (v, f) = &variants[i];
            let int = |n: usize| Value::Int(n as u64);
            Row {
                values: vec![
                    int(k + 1),
                    Value::Text(v.id.clone()),
                    v.title.clone().map_or(Value::Missing, Value::Text),
                    int(f.rows),
                    int(f.replicating),
                    int(f.within_2x),
                    int(f.config_match),
                    int(f.order_match),
                    int(f.order_experiments),
                    f.geo_mean.map_or(Value::Missing, |value| Value::Num {
                        value,
                        decimals: 3,
                        signed: false,
                    }),
                ],
                highlight: k == 0,
            }
        })
        .collect();
    let caption = format!(
        "How well each variant reproduces the reference values (one row per variant; counts over its \
         Table III rows that have a reference value and a best cell). {VERDICT_RULE} Config matches: the \
         best cell has the reference's bins or sets per variable and action count. Order matches: of the \
         experiments where every algorithm has a reference, those whose algorithms (Q(0), Q(λ)) rank by \
         mean as in the reference. Geo. mean: exp of the mean of ln(ours/reference) over the rows. {FIT_ORDER}"
    );
    Table { title: "Variants".into(), caption, columns, rows }
}

/// The change of one cell's mean episodes from the base variant to another.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CellDiff {
    /// mean(other) − mean(base).
    pub diff: f64,
    /// Bootstrap 95% interval of the difference.
    pub ci: (f64, f64),
    /// Whether the interval excludes 0 (and both cells have at least two trials).
    pub significant: bool,
}

/// How cells are compared, as stated in the captions.
pub const DIFF_RULE: &str = "Value: mean episodes of the variant's cell minus the first variant's \
(same experiment, algorithm and grid point); red: more episodes (slower), blue: fewer. Outlined with \
a dot: the percentile-bootstrap 95% interval of the difference (2000 resamples of each cell's trials, \
drawn independently, seeded by the two cells' trial keys) excludes 0; cells with fewer than two \
trials on either side are never marked. Grey: the cell has no trials in one of the two variants.";

/// The bootstrap seed of a pair of cells: derived from both cells' present trial keys.
pub fn diff_seed(base: &CellData, other: &CellData) -> u64 {
    let mut h = blake3::Hasher::new();
    h.update(b"qsweep-bootstrap-diff\0");
    let keys = |c: &CellData| c.trials.iter().map(|t| t.planned.key).collect::<Vec<Key>>();
    for k in keys(base) {
        h.update(&k.0);
    }
    h.update(b"\0");
    for k in keys(other) {
        h.update(&k.0);
    }
    u64::from_le_bytes(h.finalize().as_bytes()[..8].try_into().expect("8 bytes"))
}

impl CellDiff {
    /// Compare two cells; `None` when either has no trials.
    pub fn of(base: &CellData, other: &CellData) -> Option<Self> {
        let values = |c: &CellData| c.trials.iter().map(|t| f64::from(t.counted)).collect::<Vec<f64>>();
        let (a, b) = (values(base), values(other));
        if a.is_empty() || b.is_empty() {
            return None;
        }
        let ci = bootstrap_diff_ci(&a, &b, BOOTSTRAP_RESAMPLES, diff_seed(base, other));
        let diff = other.summary.mean? - base.summary.mean?;
        let significant = a.len() >= 2 && b.len() >= 2 && (ci.0 > 0.0 || ci.1 < 0.0);
        Some(Self { diff, ci, significant })
    }
}

/// The base's cell matching cell `i` of `e` (same system, experiment id, algorithm, coordinates).
pub fn matching<'d, 'a>(base: &'d ReportData<'a>, e: &ExpData, i: usize) -> Option<&'d CellData<'a>> {
    let c = &e.cells[i];
    let be = base.experiments.iter().find(|b| b.exp.system == e.exp.system && b.exp.id == e.exp.id)?;
    be.find(c.cell.algorithm, &c.cell.coords).map(|j| &be.cells[j])
}

/// The difference figure of `other` against `base` for one system: SVG text and PNG bytes.
pub fn diff_figure(
    base: (&VariantInfo, &ReportData),
    other: (&VariantInfo, &ReportData),
    system: SystemKind,
) -> anyhow::Result<(String, Vec<u8>)> {
    let exps: Vec<&ExpData> = other.1.experiments.iter().filter(|e| e.exp.system == system).collect();
    let title = format!(
        "{}: change of mean episodes, variant {} − variant {}",
        system.title(),
        other.0.id,
        base.0.id
    );
    figures::paint(&Diffs { base: base.1, exps: &exps, title: &title }, figures::figure_size(&exps))
        .map_err(|e| anyhow::anyhow!("drawing the {system} difference figure of {}: {e}", other.0.id))
}

struct Diffs<'a, 'b> {
    base: &'a ReportData<'b>,
    exps: &'a [&'a ExpData<'b>],
    title: &'a str,
}

impl Picture for Diffs<'_, '_> {
    fn draw<DB: DrawingBackend>(&self, cv: &mut Canvas<DB>) -> Res {
        cv.root.fill(&WHITE).map_err(|e| e.to_string())?;
        let (w, h) = cv.root.dim_in_pixel();
        // Shrink a title that would not fit a one-column figure (as the system's figure does).
        let size = (w as f64 / (0.52 * self.title.chars().count() as f64)).min(20.0);
        let at = (w as i32 / 2, figures::HEADER_H as i32 / 2);
        cv.text(self.title, at, size, INK, HPos::Center, VPos::Center);
        let cols = columns(self.exps);
        for (r, e) in self.exps.iter().enumerate() {
            for (c, &alg) in cols.iter().enumerate() {
                let origin = (
                    (c as u32 * figures::PANEL_W) as i32,
                    (figures::HEADER_H + r as u32 * figures::PANEL_H) as i32,
                );
                diff_panel(cv, origin, self.base, e, alg)?;
            }
        }
        diff_legend(cv, (h - figures::FOOTER_H) as i32)
    }
}

/// Diverging colour map (blue, white, red) at t ∈ [−1, 1].
pub fn diverging(t: f64) -> RGBColor {
    const A: [(u8, u8, u8); 5] =
        [(33, 102, 172), (146, 197, 222), (247, 247, 247), (244, 165, 130), (178, 24, 43)];
    let t = (if t.is_finite() { t.clamp(-1.0, 1.0) } else { 0.0 } + 1.0) * 2.0;
    let i = (t.floor() as usize).min(3);
    let f = t - i as f64;
    let mix = |a: u8, b: u8| (f64::from(a) + f * (f64::from(b) - f64::from(a))).round() as u8;
    let (a, b) = (A[i], A[i + 1]);
    RGBColor(mix(a.0, b.0), mix(a.1, b.1), mix(a.2, b.2))
}

/// A signed difference as printed in a cell: `+1.25`, `−12.5`, `+130`.
pub fn diff_label(d: f64) -> String {
    let s = cell_label_value(d.abs());
    if s.chars().all(|c| c == '0' || c == '.') {
        s
    } else if d < 0.0 {
        format!("−{s}")
    } else {
        format!("+{s}")
    }
}

/// One difference panel: experiment `e` of the other variant, algorithm `alg`.
fn diff_panel<DB: DrawingBackend>(
    cv: &mut Canvas<DB>,
    (ox, oy): (i32, i32),
    base: &ReportData,
    e: &ExpData,
    alg: Algorithm,
) -> Res {
    let (pw, ph) = (figures::PANEL_W as i32, figures::PANEL_H as i32);
    let exp = e.exp;
    let cx = ox + pw / 2;
    if !figures::panel_header(cv, (ox, oy), exp, alg) {
        return Ok(());
    }
    let diffs: Vec<(usize, Option<CellDiff>)> = (0..e.cells.len())
        .filter(|&i| e.cells[i].cell.algorithm == alg)
        .map(|i| (i, matching(base, e, i).and_then(|b| CellDiff::of(b, &e.cells[i]))))
        .collect();
    let marked = diffs.iter().filter(|(_, d)| d.is_some_and(|d| d.significant)).count();
    let compared = diffs.iter().filter(|(_, d)| d.is_some()).count();
    let sub = format!("{compared} cells compared; {marked} with a 95% interval excluding 0");
    cv.text(&sub, (cx, oy + 33), 12.0, SUBTLE, HPos::Center, VPos::Center);

    let two = exp.axes.len() > 1;
    let (rows, cols) = if two {
        (&exp.axes[0].values[..], &exp.axes[1].values[..])
    } else {
        (&[0.0][..], &exp.axes[0].values[..])
    };
    let (left, right, top) = (ox + 78, ox + pw - 88, oy + 52);
    let full = (oy + ph - 58 - top) as f64;
    let cw = (right - left) as f64 / cols.len() as f64;
    let ch = if two { full / rows.len() as f64 } else { full.min(cw.max(60.0)) };
    let bottom = top + (ch * rows.len() as f64).round() as i32;
    let at = |ri: usize, ci: usize| {
        (left + (ci as f64 * cw).round() as i32, top + (ri as f64 * ch).round() as i32)
    };

    let span = diffs.iter().filter_map(|(_, d)| d.map(|d| d.diff.abs())).fold(0.0, f64::max);
    let scale = |d: f64| if span > 0.0 { d / span } else { 0.0 };
    let font = (cw / 4.2).min(ch / 2.2).clamp(8.0, 14.0);
    let mut outlines = Vec::new();
    for (ri, &rv) in rows.iter().enumerate() {
        for (ci, &cv_) in cols.iter().enumerate() {
            let (a, b) = (at(ri, ci), at(ri + 1, ci + 1));
            let coords: Vec<f64> = if two { vec![rv, cv_] } else { vec![cv_] };
            let d =
                e.find(alg, &coords).and_then(|i| diffs.iter().find(|(j, _)| *j == i)).and_then(|(_, d)| *d);
            let fill = d.map_or(MISSING, |d| diverging(scale(d.diff)));
            let ink = ink_on(fill);
            cv.rect(a, b, fill.filled())?;
            cv.rect(a, b, WHITE.stroke_width(1))?;
            let label = d.map_or_else(|| "—".to_string(), |d| diff_label(d.diff));
            cv.text(&label, ((a.0 + b.0) / 2, (a.1 + b.1) / 2), font, ink, HPos::Center, VPos::Center);
            if d.is_some_and(|d| d.significant) {
                outlines.push((a, b));
            }
        }
    }
    for (a, b) in outlines {
        cv.rect((a.0 + 2, a.1 + 2), (b.0 - 2, b.1 - 2), INK.stroke_width(3))?;
        let r = (font / 3.0).round() as i32;
        cv.root.draw(&Circle::new((b.0 - 6 - r, a.1 + 6 + r), r, INK.filled())).map_err(|e| e.to_string())?;
    }

    for (ci, v) in cols.iter().enumerate() {
        let x = left + ((ci as f64 + 0.5) * cw).round() as i32;
        cv.text(&crate::spec::format_value(*v), (x, bottom + 5), 12.0, INK, HPos::Center, VPos::Top);
    }
    let col_axis = &exp.axes[usize::from(two)].label;
    cv.text(col_axis, ((left + right) / 2, bottom + 25), 13.0, INK, HPos::Center, VPos::Top);
    if two {
        for (ri, v) in rows.iter().enumerate() {
            let y = top + ((ri as f64 + 0.5) * ch).round() as i32;
            cv.text(&crate::spec::format_value(*v), (left - 6, y), 12.0, INK, HPos::Right, VPos::Center);
        }
        cv.text_up(&exp.axes[0].label, (ox + 30, (top + bottom) / 2), 13.0, INK);
    }
    if compared == 0 {
        return Ok(());
    }
    diverging_bar(cv, (right + 14, top), (right + 30, bottom.max(top + 120)), span)
}

/// A vertical diverging colour bar from −`span` (bottom) to +`span` (top).
fn diverging_bar<DB: DrawingBackend>(cv: &mut Canvas<DB>, a: (i32, i32), b: (i32, i32), span: f64) -> Res {
    let steps = 64;
    let height = (b.1 - a.1) as f64;
    for s in 0..steps {
        let y0 = b.1 - (s as f64 * height / steps as f64).round() as i32;
        let y1 = b.1 - ((s + 1) as f64 * height / steps as f64).round() as i32;
        let t = if span > 0.0 { (s as f64 + 0.5) / steps as f64 * 2.0 - 1.0 } else { 0.0 };
        cv.rect((a.0, y1), (b.0, y0), diverging(t).filled())?;
    }
    cv.rect(a, b, INK.stroke_width(1))?;
    let ticks: Vec<f64> = if span > 0.0 {
        let (pos, _) = figures::nice_ticks(0.0, span);
        pos.iter().rev().map(|v| -v).chain(pos.iter().copied().filter(|&v| v > 0.0)).collect()
    } else {
        vec![0.0]
    };
    for v in ticks {
        let frac = if span > 0.0 { (v + span) / (2.0 * span) } else { 0.5 };
        let y = b.1 - (height * frac).round() as i32;
        cv.line((b.0, y), (b.0 + 3, y), INK.stroke_width(1))?;
        let label = if v == 0.0 { "0".to_string() } else { diff_label(v) };
        cv.text(&label, (b.0 + 5, y), 11.0, INK, HPos::Left, VPos::Center);
    }
    Ok(())
}

/// The legend band of a difference figure at `y`.
fn diff_legend<DB: DrawingBackend>(cv: &mut Canvas<DB>, y: i32) -> Res {
    let y = y + 22;
    cv.rect((20, y - 9), (46, y + 9), diverging(0.8).filled())?;
    cv.text("more episodes (slower)", (54, y), 13.0, INK, HPos::Left, VPos::Center);
    cv.rect((230, y - 9), (256, y + 9), diverging(-0.8).filled())?;
    cv.text("fewer episodes (faster)", (264, y), 13.0, INK, HPos::Left, VPos::Center);
    let x = 450;
    cv.rect((x, y - 9), (x + 26, y + 9), diverging(0.3).filled())?;
    cv.rect((x + 2, y - 7), (x + 24, y + 7), INK.stroke_width(3))?;
    cv.root.draw(&Circle::new((x + 17, y), 3, INK.filled())).map_err(|e| e.to_string())?;
    cv.text(
        "95% bootstrap interval of the difference excludes 0",
        (x + 34, y),
        13.0,
        INK,
        HPos::Left,
        VPos::Center,
    );
    let y = y + 24;
    cv.rect((20, y - 9), (46, y + 9), MISSING.filled())?;
    cv.text("no trials in one of the two variants", (54, y), 13.0, INK, HPos::Left, VPos::Center);
    let note = "symmetric colour scale per panel";
    cv.text(note, (450, y), 13.0, INK, HPos::Left, VPos::Center);
    Ok(())
}

/// Write the comparison of `variants` (the first is the base of the difference figures) into
/// `dir`: `variants.md`, `variants.csv`, the difference figures and `index.html`. Returns the
/// files written, relative to `dir`, in writing order.
pub fn write_comparison(dir: &Path, variants: &[(VariantInfo, ReportData)]) -> anyhow::Result<Vec<PathBuf>> {
    std::fs::create_dir_all(dir.join("figures"))
        .with_context(|| format!("cannot create the report directory {}", dir.display()))?;
    let mut files = Vec::new();
    let mut put = |name: &str, bytes: &[u8]| -> anyhow::Result<()> {
        write_atomic(&dir.join(name), bytes)?;
        files.push(PathBuf::from(name));
        Ok(())
    };
    let fits: Vec<(&VariantInfo, Fit)> = variants.iter().map(|(v, d)| (v, Fit::of(d))).collect();
    let table = comparison_table(&fits);
    put("variants.md", render(&table, &Markdown).as_bytes())?;
    put("variants.csv", render(&table, &Csv).as_bytes())?;
    let mut figs = Vec::new();
    if let Some((base_info, base)) = variants.first() {
        for (info, data) in &variants[1..] {
            for system in data.systems() {
                let (svg, png) = diff_figure((base_info, base), (info, data), system)?;
                let stem = format!("figures/diff-{}-{}", info.id, system.name());
                put(&format!("{stem}.svg"), svg.as_bytes())?;
                put(&format!("{stem}.png"), &png)?;
                let exps: Vec<&ExpData> =
                    data.experiments.iter().filter(|e| e.exp.system == system).collect();
                figs.push((info, system, stem, figures::figure_size(&exps)));
            }
        }
    }
    put("index.html", page(variants, &table, &figs).as_bytes())?;
    Ok(files)
}

type FigRef<'a> = (&'a VariantInfo, SystemKind, String, (u32, u32));

/// The comparison page.
fn page(variants: &[(VariantInfo, ReportData)], table: &Table, figs: &[FigRef]) -> String {
    let name = variants.first().map_or("", |(_, d)| d.plan.name.as_str());
    let mut h = String::new();
    h.push_str("<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n");
    h.push_str(&format!("<title>qsweep variants: {}</title>\n", esc(name)));
    h.push_str(&format!("<style>\n{}</style>\n</head>\n<body>\n", super::html::STYLE));
    h.push_str(&format!("<h1>qsweep variants: {}</h1>\n", esc(name)));
    if let Some(d) = variants.first().and_then(|(_, d)| d.plan.description.as_deref()) {
        h.push_str(&format!("<p>{}</p>\n", esc(d)));
    }
    h.push_str("<p>Each variant is the whole pipeline with some settings changed; each has its own full report:</p>\n<ul>\n");
    for (v, d) in variants {
        let title = v.title.as_deref().map(|t| format!(": {}", esc(t))).unwrap_or_default();
        h.push_str(&format!(
            "<li><a href=\"{0}/index.html\"><code>{0}</code></a>{title} ({1} of {2} planned trials present)</li>\n",
            esc(&v.id),
            d.trials_present,
            d.trials_planned
        ));
    }
    h.push_str("</ul>\n<p>Data: <a href=\"variants.csv\">variants.csv</a> · <a href=\"variants.md\">variants.md</a></p>\n");
    h.push_str("<h2 id=\"fit\">Fit to the reference values</h2>\n<div class=\"scroll\">\n");
    h.push_str(&render(table, &Html));
    h.push_str("</div>\n");
    if let Some((base, _)) = variants.first() {
        for (v, _) in &variants[1..] {
            h.push_str(&format!("<h2 id=\"diff-{0}\">{0} against {1}</h2>\n", esc(&v.id), esc(&base.id)));
            for (_, system, stem, (w, ht)) in figs.iter().filter(|f| f.0.id == v.id) {
                h.push_str(&format!(
                    "<figure><img src=\"{stem}.svg\" width=\"{w}\" height=\"{ht}\" alt=\"{0}: change of mean \
                     episodes per cell, {1} against {2}\">\n<figcaption>{0}. {3} <a href=\"{stem}.png\">PNG</a> · \
                     <a href=\"{stem}.svg\">SVG</a></figcaption></figure>\n",
                    esc(system.title()),
                    esc(&v.id),
                    esc(&base.id),
                    esc(DIFF_RULE)
                ));
            }
        }
    }
    h.push_str("</body>\n</html>\n");
    h
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cache::TrialRecord;
    use crate::plan::{plan, Plan};
    use crate::sim::run_trial;
    use crate::spec::{load_str, LoadedSpec, Override};
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
            .map(|j| (j.key, TrialRecord::new(j.config.clone(), j.seed, run_trial(j.config, j.seed), 0.0)))
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

    /// The fit recomputed from the trials, independently of [`Fit::of`]: (rows, replicating,
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
        let variants = vec![
            (
                VariantInfo { id: "as-written".into(), title: Some("The text".into()) },
                ReportData::build(&base, &rec_base),
            ),
            (VariantInfo { id: "fast".into(), title: None }, ReportData::build(&other, &rec_other)),
        ];
        let tmp = tempfile::tempdir().unwrap();
        let written = write_comparison(tmp.path(), &variants).unwrap();
        let names: Vec<String> = written.iter().map(|p| p.to_string_lossy().into_owned()).collect();
        assert_eq!(
            names,
            [
                "variants.md",
                "variants.csv",
                "figures/diff-fast-ball-beam.svg",
                "figures/diff-fast-ball-beam.png",
                "index.html"
            ]
        );
        let out = files(tmp.path());
        assert_eq!(
            out.keys().cloned().collect::<Vec<_>>().len(),
            5,
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
                "geo_mean_ratio"
            ]
        );
        let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
        assert_eq!(rows.len(), 2);
        let fits: Vec<_> = variants.iter().map(|(_, d)| by_hand(d)).collect();
        for (v, d) in &variants {
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
        let (b, o) = (&variants[0].1, &variants[1].1);
        let mut marked = 0;
        let mut unmarked = 0;
        let mut missing = 0;
        for e in &o.experiments {
            for (i, c) in e.cells.iter().enumerate() {
                let Some(d) = matching(b, e, i).and_then(|bc| CellDiff::of(bc, c)) else {
                    missing += 1;
                    continue;
                };
                let bc = matching(b, e, i).unwrap();
                let va: Vec<f64> = bc.trials.iter().map(|t| f64::from(t.counted)).collect();
                let vb: Vec<f64> = c.trials.iter().map(|t| f64::from(t.counted)).collect();
                let ci = bootstrap_diff_ci(&va, &vb, 2000, diff_seed(bc, c));
                assert_eq!(d.ci, ci);
                assert!(
                    (d.diff - (crate::report::stats::mean(&vb) - crate::report::stats::mean(&va))).abs()
                        < 1e-12
                );
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
        for link in
            ["as-written/index.html", "fast/index.html", "variants.csv", "figures/diff-fast-ball-beam.svg"]
        {
            assert!(html.contains(&format!("\"{link}\"")), "index.html links {link}");
        }

        // Determinism: a second write gives identical bytes.
        let again = tempfile::tempdir().unwrap();
        write_comparison(again.path(), &variants).unwrap();
        assert_eq!(files(again.path()), out);
        write_comparison(tmp.path(), &variants).unwrap();
        assert_eq!(files(tmp.path()), out);
    }
}
