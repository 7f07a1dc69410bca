//! The difference figures of the comparison: per cell, the change of mean episodes of a variant
//! against the first, in the layout of the system's figure ([`crate::render::figures::Grid`]),
//! cells whose bootstrap 95% interval of the difference excludes 0 marked ([`CellDiff`]).

use crate::memo::stats::StatsMemo;
use crate::render::figures::{
    self, cell_label_value, columns, ink_on, Canvas, Drawn, Grid, Picture, Res, INK, MISSING, SUBTLE,
};
use crate::render::text_fit::{self, Entry, Legend};
use crate::replication::compare::{CellDigest, ExpDigest, VariantDigest};
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, VPos};
use qsweep_engine::env::SystemKind;
use qsweep_engine::Algorithm;
use qsweep_pipeline::analysis::BOOTSTRAP_RESAMPLES;

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
pub fn diff_seed(base: &CellDigest, other: &CellDigest) -> u64 {
    let mut h = blake3::Hasher::new();
    h.update(b"qsweep-bootstrap-diff\0");
    for k in &base.keys {
        h.update(&k.0);
    }
    h.update(b"\0");
    for k in &other.keys {
        h.update(&k.0);
    }
    u64::from_le_bytes(h.finalize().as_bytes()[..8].try_into().expect("8 bytes"))
}

impl CellDiff {
    /// Compare two cells; `None` when either has no trials.
    pub fn of(base: &CellDigest, other: &CellDigest, memo: &StatsMemo) -> Option<Self> {
        let (a, b) = (&base.values, &other.values);
        if a.is_empty() || b.is_empty() {
            return None;
        }
        let ci = memo.bootstrap_diff_ci(a, b, BOOTSTRAP_RESAMPLES, diff_seed(base, other));
        let diff = other.mean? - base.mean?;
        let significant = a.len() >= 2 && b.len() >= 2 && (ci.0 > 0.0 || ci.1 < 0.0);
        Some(Self { diff, ci, significant })
    }
}

/// The base's cell matching cell `i` of `e` (same system, experiment id, algorithm, coordinates).
pub fn matching<'d, 'a>(base: &'d VariantDigest<'a>, e: &ExpDigest, i: usize) -> Option<&'d CellDigest<'a>> {
    let c = &e.cells[i];
    let be = base.exps.iter().find(|b| b.exp.system == e.exp.system && b.exp.id == e.exp.id)?;
    be.find(c.cell.algorithm, &c.cell.coords).map(|j| &be.cells[j])
}

/// Every cell's difference of `other` against `base`, in `other`'s experiment and cell order.
/// Each is its own seeded bootstrap, so they are computed in parallel.
pub fn all_diffs(
    base: &VariantDigest,
    other: &VariantDigest,
    memo: &StatsMemo,
) -> Vec<Vec<Option<CellDiff>>> {
    use rayon::prelude::*;
    other
        .exps
        .iter()
        .map(|e| {
            (0..e.cells.len())
                .into_par_iter()
                .map(|i| matching(base, e, i).and_then(|b| CellDiff::of(b, &e.cells[i], memo)))
                .collect()
        })
        .collect()
}

/// The difference figure of `other` against `base` for one system, given every cell's
/// difference ([`all_diffs`]).
pub fn diff_figure(
    base: &VariantDigest,
    other: &VariantDigest,
    diffs: &[Vec<Option<CellDiff>>],
    system: SystemKind,
    (svg, png): (bool, bool),
) -> anyhow::Result<Drawn> {
    let exps: Vec<(&ExpDigest, &[Option<CellDiff>])> = other
        .exps
        .iter()
        .zip(diffs)
        .filter(|(e, _)| e.exp.system == system)
        .map(|(e, d)| (e, d.as_slice()))
        .collect();
    let title = format!(
        "{}: change of mean episodes, variant {} − variant {}",
        system.title(),
        other.info.id,
        base.info.id
    );
    let only: Vec<&ExpDigest> = exps.iter().map(|e| e.0).collect();
    figures::paint_as(&Diffs { exps: &exps, title: &title }, figure_size(&only), svg, png)
        .map_err(|e| anyhow::anyhow!("drawing the {system} difference figure of {}: {e}", other.info.id))
}

/// Pixel size of a difference figure of these experiments: the system figure's panels
/// ([`figures::figure_size`]) above this figure's own legend band ([`legend_band`]).
pub fn figure_size(exps: &[&ExpDigest]) -> (u32, u32) {
    let w = columns(exps).len().max(1) as u32 * figures::PANEL_W;
    (w, figures::HEADER_H + exps.len().max(1) as u32 * figures::PANEL_H + legend_band().place(w).1)
}

/// The legend band: the colours, the mark of a significant difference, and grey;
/// [`figures::FOOTER_H`] tall where its columns fit.
fn legend_band() -> Legend {
    let entry = |text: &str, swatch| Entry { text: text.into(), size: 13.0, swatch };
    let entries = vec![
        entry("more episodes (slower)", true),
        entry("fewer episodes (faster)", true),
        entry("95% bootstrap interval of the difference excludes 0", true),
        entry("no trials in one of the two variants", true),
        entry("symmetric colour scale per panel", false),
    ];
    let rows = vec![vec![(20, 0), (230, 1), (450, 2)], vec![(20, 3), (450, 4)]];
    Legend { entries, rows, first: 22, row_h: 24, bottom: figures::FOOTER_H as i32 - 22 - 24 }
}

struct Diffs<'a, 'b> {
    exps: &'a [(&'a ExpDigest<'b>, &'a [Option<CellDiff>])],
    title: &'a str,
}

impl Picture for Diffs<'_, '_> {
    fn draw<DB: DrawingBackend>(&self, cv: &mut Canvas<DB>) -> Res {
        cv.root.fill(&WHITE).map_err(|e| e.to_string())?;
        let (w, h) = cv.root.dim_in_pixel();
        cv.title(self.title, w);
        let only: Vec<&ExpDigest> = self.exps.iter().map(|e| e.0).collect();
        let cols = columns(&only);
        for (r, (e, d)) in self.exps.iter().enumerate() {
            for (c, &alg) in cols.iter().enumerate() {
                let origin = (
                    (c as u32 * figures::PANEL_W) as i32,
                    (figures::HEADER_H + r as u32 * figures::PANEL_H) as i32,
                );
                diff_panel(cv, origin, e, d, alg)?;
            }
        }
        diff_legend(cv, h)
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

/// One difference panel: experiment `e` of the other variant with its cells' differences `d`,
/// algorithm `alg`.
fn diff_panel<DB: DrawingBackend>(
    cv: &mut Canvas<DB>,
    (ox, oy): (i32, i32),
    e: &ExpDigest,
    d: &[Option<CellDiff>],
    alg: Algorithm,
) -> Res {
    let exp = e.exp;
    let cx = ox + figures::PANEL_W as i32 / 2;
    if !figures::panel_header(cv, (ox, oy), exp, alg) {
        return Ok(());
    }
    let diffs: Vec<(usize, Option<CellDiff>)> =
        (0..e.cells.len()).filter(|&i| e.cells[i].cell.algorithm == alg).map(|i| (i, d[i])).collect();
    let marked = diffs.iter().filter(|(_, d)| d.is_some_and(|d| d.significant)).count();
    let compared = diffs.iter().filter(|(_, d)| d.is_some()).count();
    let sub = format!("{compared} cells compared; {marked} with a 95% interval excluding 0");
    cv.text_within(&sub, (cx, oy + 33), figures::PANEL_W as i32 - 2 * text_fit::MARGIN, 12.0, SUBTLE);

    let g = Grid::of(exp, (ox, oy));
    let span = diffs.iter().filter_map(|(_, d)| d.map(|d| d.diff.abs())).fold(0.0, f64::max);
    let scale = |d: f64| if span > 0.0 { d / span } else { 0.0 };
    let font = g.font();
    let mut outlines = Vec::new();
    for ri in 0..g.rows.len() {
        for ci in 0..g.cols.len() {
            let (a, b) = (g.at(ri, ci), g.at(ri + 1, ci + 1));
            let d = e.find(alg, &g.coords(ri, ci)).and_then(|i| d[i]);
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
    g.axes(cv, exp);
    if compared == 0 {
        return Ok(());
    }
    let (a, b) = g.bar();
    diverging_bar(cv, a, b, span)
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

/// The legend band at the bottom of a difference figure `h` pixels tall ([`legend_band`]).
fn diff_legend<DB: DrawingBackend>(cv: &mut Canvas<DB>, h: u32) -> Res {
    cv.legend(&legend_band(), h, |cv, entry, (x, y)| {
        match entry {
            0 => cv.rect((x, y - 9), (x + 26, y + 9), diverging(0.8).filled())?,
            1 => cv.rect((x, y - 9), (x + 26, y + 9), diverging(-0.8).filled())?,
            2 => {
                cv.rect((x, y - 9), (x + 26, y + 9), diverging(0.3).filled())?;
                cv.rect((x + 2, y - 7), (x + 24, y + 7), INK.stroke_width(3))?;
                cv.root.draw(&Circle::new((x + 17, y), 3, INK.filled())).map_err(|e| e.to_string())?;
            }
            3 => cv.rect((x, y - 9), (x + 26, y + 9), MISSING.filled())?,
            _ => {}
        }
        Ok(INK)
    })
}
