//! Figures 5–7: one figure per system, one row per experiment, one column per algorithm (Q(0),
//! Q(λ)). Each panel is a heatmap of mean episodes over the experiment's varied axes (rows = first
//! axis, columns = second; a one-axis experiment is a single row) with the values printed, its own
//! colour scale, the best cell outlined in red, cells with a non-converged trial hatched and
//! starred, and cells without trials grey.
//!
//! Shapes are drawn with plotters into SVG and into an RGB buffer encoded as PNG. Text is collected
//! while drawing and then written as SVG `<text>` or rasterised into the PNG by [`crate::render::glyphs`]
//! from an embedded DejaVu Sans subset (`assets/fonts`), so no system font library is involved
//! and the PNG is identical on every machine. In SVG a hatched cell is one rectangle filled with a
//! `<pattern>` of the same diagonal lines ([`hatch_patterns`]), which keeps committed figures small.

use crate::derive::report_data::{CellData, ExpData, ReportData};
pub(crate) use crate::render::canvas::{paint_as, Canvas, Picture, Res};
pub use crate::render::canvas::{Drawn, HEADER_H};
pub(crate) use crate::render::canvas::{INK, SUBTLE};
use crate::render::text_fit::{self, Entry, Legend};
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, VPos};
use qsweep_engine::env::SystemKind;
use qsweep_engine::Algorithm;
use qsweep_pipeline::plan::Experiment;

/// Width of one panel, in pixels.
pub const PANEL_W: u32 = 500;
/// Height of one panel, in pixels.
pub const PANEL_H: u32 = 370;
/// Height of the legend band.
pub const FOOTER_H: u32 = 60;

pub(crate) const MISSING: RGBColor = RGBColor(200, 200, 200);
const BEST: RGBColor = RGBColor(220, 0, 0);
/// Outline of a race's final contenders (orange, inside the best cell's red).
const CONTENDER: RGBColor = RGBColor(255, 150, 0);

/// The legend band of a figure: what the cells' marks mean (a race's contenders too, when
/// `raced`). It is [`FOOTER_H`] tall (24 px more when raced) where its two columns fit the
/// figure, taller where its entries are stacked (a one-column figure).
fn legend_band(raced: bool) -> Legend {
    let entry = |text: &str, swatch| Entry { text: text.into(), size: 13.0, swatch };
    let mut entries = vec![
        entry("best cell (Table III)", true),
        entry("* and hatched: some trials never reached the goal (counted at the episode cap)", true),
        entry("no trials yet", true),
        entry("values: mean episodes over the cell's trials; one colour scale per panel", false),
    ];
    let mut rows = vec![vec![(20, 0), (220, 1)], vec![(20, 2), (220, 3)]];
    if raced {
        entries.push(entry("contender: still in the race, not significantly worse than the best", true));
        rows.push(vec![(20, 4)]);
    }
    Legend { entries, rows, first: 22, row_h: 24, bottom: FOOTER_H as i32 - 22 - 24 }
}

/// Height of the legend band of a figure `w` pixels wide.
fn footer_h(raced: bool, w: u32) -> u32 {
    legend_band(raced).place(w).1
}

/// The algorithms (figure columns) of a system's experiments, in the paper's order.
pub fn columns<E: AsRef<Experiment>>(exps: &[&E]) -> Vec<Algorithm> {
    let mut a: Vec<Algorithm> = exps.iter().flat_map(|e| e.as_ref().algorithms.iter().copied()).collect();
    a.sort();
    a.dedup();
    a
}

/// Pixel size of a system's figure.
pub fn figure_size<E: AsRef<Experiment>>(exps: &[&E]) -> (u32, u32) {
    let cols = columns(exps).len().max(1) as u32;
    let raced = exps.iter().any(|e| e.as_ref().race.is_some());
    let w = cols * PANEL_W;
    (w, HEADER_H + exps.len().max(1) as u32 * PANEL_H + footer_h(raced, w))
}

/// The figure of one system as SVG text and PNG bytes.
pub fn render(data: &ReportData, system: SystemKind) -> anyhow::Result<(String, Vec<u8>)> {
    let d = render_as(data, system, true, true)?;
    Ok((d.svg.unwrap_or_default(), d.png.unwrap_or_default()))
}

/// The figure of one system, drawn only in the formats asked for.
pub fn render_as(data: &ReportData, system: SystemKind, svg: bool, png: bool) -> anyhow::Result<Drawn> {
    let exps: Vec<&ExpData> = data.experiments.iter().filter(|e| e.exp.system == system).collect();
    let (w, h) = figure_size(&exps);
    let title =
        format!("{}: mean episodes to the learning goal ({})", system.title(), data.plan.report_name());
    paint_as(&Heatmaps { exps: &exps, title: &title }, (w, h), svg, png)
        .map_err(|e| anyhow::anyhow!("drawing the {system} figure: {e}"))
}

struct Heatmaps<'a, 'b> {
    exps: &'a [&'a ExpData<'b>],
    title: &'a str,
}

impl Picture for Heatmaps<'_, '_> {
    fn draw<DB: DrawingBackend>(&self, cv: &mut Canvas<DB>) -> Res {
        draw(cv, self.exps, self.title)
    }
}

fn draw<DB: DrawingBackend>(cv: &mut Canvas<DB>, exps: &[&ExpData], title: &str) -> Res {
    cv.root.fill(&WHITE).map_err(|e| e.to_string())?;
    let (w, h) = cv.root.dim_in_pixel();
    cv.title(title, w);
    let cols = columns(exps);
    for (r, e) in exps.iter().enumerate() {
        for (c, &alg) in cols.iter().enumerate() {
            let origin = ((c as u32 * PANEL_W) as i32, (HEADER_H + r as u32 * PANEL_H) as i32);
            panel(cv, origin, e, alg)?;
        }
    }
    let raced = exps.iter().any(|e| e.exp.race.is_some());
    legend(cv, h, raced)
}

/// Sequential colour map (viridis, 9 anchors, linear in between) at t ∈ [0, 1].
pub fn viridis(t: f64) -> RGBColor {
    const A: [(u8, u8, u8); 9] = [
        (68, 1, 84),
        (71, 44, 122),
        (59, 81, 139),
        (44, 113, 142),
        (33, 144, 141),
        (39, 173, 129),
        (92, 200, 99),
        (170, 220, 50),
        (253, 231, 37),
    ];
    let t = if t.is_finite() { t.clamp(0.0, 1.0) } else { 0.0 } * 8.0;
    let i = (t.floor() as usize).min(7);
    let f = t - i as f64;
    let mix = |a: u8, b: u8| (f64::from(a) + f * (f64::from(b) - f64::from(a))).round() as u8;
    let (a, b) = (A[i], A[i + 1]);
    RGBColor(mix(a.0, b.0), mix(a.1, b.1), mix(a.2, b.2))
}

/// Text colour readable on `c`.
pub(crate) fn ink_on(c: RGBColor) -> RGBColor {
    let lum = 0.299 * f64::from(c.0) + 0.587 * f64::from(c.1) + 0.114 * f64::from(c.2);
    if lum > 140.0 {
        INK
    } else {
        WHITE
    }
}

/// A cell's printed value: 2 decimals below 10, 1 below 100, none above; `*` if a trial failed.
pub fn cell_label(c: &CellData) -> String {
    let Some(m) = c.summary.mean else { return "—".into() };
    let v = cell_label_value(m);
    if c.any_failed() {
        format!("{v}*")
    } else {
        v
    }
}

/// A non-negative value as printed in a cell: 2 decimals below 10, 1 below 100, none above.
pub fn cell_label_value(m: f64) -> String {
    if m < 10.0 {
        format!("{m:.2}")
    } else if m < 100.0 {
        format!("{m:.1}")
    } else {
        format!("{m:.0}")
    }
}

/// A panel's title ("Exp. id: title — algorithm"); for an algorithm the experiment does not run,
/// also a note in the middle, and `false`.
pub(crate) fn panel_header<DB: DrawingBackend>(
    cv: &mut Canvas<DB>,
    (ox, oy): (i32, i32),
    exp: &qsweep_pipeline::plan::Experiment,
    alg: Algorithm,
) -> bool {
    let cx = ox + PANEL_W as i32 / 2;
    let name = match &exp.title {
        Some(t) => format!("Exp. {}: {t}", exp.id),
        None => format!("Exp. {}", exp.id),
    };
    let within = PANEL_W as i32 - 2 * text_fit::MARGIN;
    cv.text_within(&format!("{name} — {}", alg.label(exp.repr)), (cx, oy + 14), within, 15.0, INK);
    if exp.algorithms.contains(&alg) {
        return true;
    }
    let mid = (cx, oy + PANEL_H as i32 / 2);
    cv.text("not run in this experiment", mid, 13.0, SUBTLE, HPos::Center, VPos::Center);
    false
}

/// One heatmap panel: experiment `e`, algorithm `alg`, top-left corner at `(ox, oy)`.
fn panel<DB: DrawingBackend>(cv: &mut Canvas<DB>, (ox, oy): (i32, i32), e: &ExpData, alg: Algorithm) -> Res {
    let exp = e.exp;
    let cx = ox + PANEL_W as i32 / 2;
    if !panel_header(cv, (ox, oy), exp, alg) {
        return Ok(());
    }
    let best = e.best_of(alg);
    let seeds = e.cells.iter().map(CellData::planned).max().unwrap_or(0);
    let fewest = e.cells.iter().map(CellData::planned).min().unwrap_or(0);
    let mut sub = vec![match exp.race {
        Some(_) => format!("raced: {fewest}–{seeds} seeds"),
        None => format!("{seeds} seeds"),
    }];
    sub.extend(
        exp.fixed
            .iter()
            .map(|(t, v)| format!("{} = {v}", qsweep_pipeline::declared::target_name(exp.system, *t))),
    );
    if best.is_some_and(|b| !b.all_converged) {
        sub.push("no cell fully converged".into());
    }
    cv.text_within(&sub.join("; "), (cx, oy + 33), PANEL_W as i32 - 2 * text_fit::MARGIN, 12.0, SUBTLE);

    let g = Grid::of(exp, (ox, oy));

    // Colour scale of this panel.
    let means: Vec<f64> =
        e.cells.iter().filter(|c| c.cell.algorithm == alg).filter_map(|c| c.summary.mean).collect();
    let lo = means.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = means.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let scale = |m: f64| if hi > lo { (m - lo) / (hi - lo) } else { 0.5 };

    let font = g.font();
    let mut best_rect = None;
    for ri in 0..g.rows.len() {
        for ci in 0..g.cols.len() {
            let (a, b) = (g.at(ri, ci), g.at(ri + 1, ci + 1));
            let idx = e.find(alg, &g.coords(ri, ci));
            let cell = idx.map(|i| &e.cells[i]);
            let fill = cell.and_then(|c| c.summary.mean).map_or(MISSING, |m| viridis(scale(m)));
            cv.rect(a, b, fill.filled())?;
            cv.rect(a, b, WHITE.stroke_width(1))?;
            if cell.is_some_and(|c| c.any_failed()) {
                cv.hatch((a.0 + 1, a.1 + 1), (b.0 - 1, b.1 - 1), ink_on(fill))?;
            }
            let label = cell.map_or_else(|| "—".to_string(), cell_label);
            cv.text(
                &label,
                ((a.0 + b.0) / 2, (a.1 + b.1) / 2),
                font,
                ink_on(fill),
                HPos::Center,
                VPos::Center,
            );
            if cell.is_some_and(|c| c.cell.contender == Some(true)) {
                cv.rect((a.0 + 4, a.1 + 4), (b.0 - 4, b.1 - 4), CONTENDER.stroke_width(2))?;
            }
            if idx.is_some() && idx == best.map(|b| b.cell) {
                best_rect = Some((a, b));
            }
        }
    }
    if let Some((a, b)) = best_rect {
        cv.rect((a.0 + 1, a.1 + 1), (b.0 - 1, b.1 - 1), BEST.stroke_width(3))?;
    }

    g.axes(cv, exp);
    if means.is_empty() {
        return Ok(());
    }
    let (a, b) = g.bar();
    colorbar(cv, a, b, lo, hi)
}

/// The cell grid of one heatmap panel (shared by the system figures and the comparison's
/// difference figures): rows = the first axis, columns = the second (a one-axis experiment is
/// one row), and where each cell, tick and colour bar goes.
pub(crate) struct Grid<'e> {
    /// Row values (`[0.0]` for a one-axis experiment).
    pub rows: &'e [f64],
    /// Column values.
    pub cols: &'e [f64],
    two: bool,
    ox: i32,
    left: i32,
    right: i32,
    top: i32,
    bottom: i32,
    cw: f64,
    ch: f64,
}

impl<'e> Grid<'e> {
    /// The grid of experiment `exp` in the panel whose top-left corner is `(ox, oy)`.
    pub fn of(exp: &'e Experiment, (ox, oy): (i32, i32)) -> Self {
        let two = exp.axes.len() > 1;
        let (rows, cols) = if two {
            (&exp.axes[0].values[..], &exp.axes[1].values[..])
        } else {
            (&[0.0][..], &exp.axes[0].values[..])
        };
        let (left, right, top) = (ox + 78, ox + PANEL_W as i32 - 88, oy + 52);
        let full = (oy + PANEL_H as i32 - 58 - top) as f64;
        let cw = (right - left) as f64 / cols.len() as f64;
        let ch = if two { full / rows.len() as f64 } else { full.min(cw.max(60.0)) };
        let bottom = top + (ch * rows.len() as f64).round() as i32;
        Self { rows, cols, two, ox, left, right, top, bottom, cw, ch }
    }

    /// Top-left pixel of cell (`ri`, `ci`); (`ri + 1`, `ci + 1`) is its bottom-right.
    pub fn at(&self, ri: usize, ci: usize) -> (i32, i32) {
        (self.left + (ci as f64 * self.cw).round() as i32, self.top + (ri as f64 * self.ch).round() as i32)
    }

    /// The experiment coordinates of cell (`ri`, `ci`).
    pub fn coords(&self, ri: usize, ci: usize) -> Vec<f64> {
        if self.two {
            vec![self.rows[ri], self.cols[ci]]
        } else {
            vec![self.cols[ci]]
        }
    }

    /// Font size of the cell labels.
    pub fn font(&self) -> f64 {
        (self.cw / 4.2).min(self.ch / 2.2).clamp(8.0, 14.0)
    }

    /// Corners of the colour bar right of the grid.
    pub fn bar(&self) -> ((i32, i32), (i32, i32)) {
        ((self.right + 14, self.top), (self.right + 30, self.bottom.max(self.top + 120)))
    }

    /// Ticks and axis labels.
    pub fn axes<DB: DrawingBackend>(&self, cv: &mut Canvas<DB>, exp: &Experiment) {
        for (ci, v) in self.cols.iter().enumerate() {
            let x = self.left + ((ci as f64 + 0.5) * self.cw).round() as i32;
            cv.text(
                &qsweep_pipeline::declared::format_value(*v),
                (x, self.bottom + 5),
                12.0,
                INK,
                HPos::Center,
                VPos::Top,
            );
        }
        let col_axis = &exp.axes[usize::from(self.two)].label;
        let mid = (self.left + self.right) / 2;
        cv.text(col_axis, (mid, self.bottom + 25), 13.0, INK, HPos::Center, VPos::Top);
        if self.two {
            for (ri, v) in self.rows.iter().enumerate() {
                let y = self.top + ((ri as f64 + 0.5) * self.ch).round() as i32;
                cv.text(
                    &qsweep_pipeline::declared::format_value(*v),
                    (self.left - 6, y),
                    12.0,
                    INK,
                    HPos::Right,
                    VPos::Center,
                );
            }
            cv.text_up(&exp.axes[0].label, (self.ox + 30, (self.top + self.bottom) / 2), 13.0, INK);
        }
    }
}

/// A vertical colour bar from `lo` (bottom) to `hi` (top) with round ticks (one if `lo == hi`).
fn colorbar<DB: DrawingBackend>(cv: &mut Canvas<DB>, a: (i32, i32), b: (i32, i32), lo: f64, hi: f64) -> Res {
    let steps = 64;
    let height = (b.1 - a.1) as f64;
    for s in 0..steps {
        let y0 = b.1 - (s as f64 * height / steps as f64).round() as i32;
        let y1 = b.1 - ((s + 1) as f64 * height / steps as f64).round() as i32;
        let t = if hi > lo { (s as f64 + 0.5) / steps as f64 } else { 0.5 };
        cv.rect((a.0, y1), (b.0, y0), viridis(t).filled())?;
    }
    cv.rect(a, b, INK.stroke_width(1))?;
    let (ticks, decimals) =
        if hi > lo { nice_ticks(lo, hi) } else { (vec![lo], usize::from(lo.fract() != 0.0)) };
    for v in ticks {
        let frac = if hi > lo { (v - lo) / (hi - lo) } else { 0.5 };
        let y = b.1 - (height * frac).round() as i32;
        cv.line((b.0, y), (b.0 + 3, y), INK.stroke_width(1))?;
        cv.text(&format!("{v:.decimals$}"), (b.0 + 5, y), 11.0, INK, HPos::Left, VPos::Center);
    }
    Ok(())
}

/// Round tick values inside `[lo, hi]` (3 to 6 of them, steps of 1, 2, 2.5 or 5 × 10^k) and the
/// decimals they need.
pub fn nice_ticks(lo: f64, hi: f64) -> (Vec<f64>, usize) {
    let raw = (hi - lo) / 4.0;
    let mag = 10f64.powf(raw.log10().floor());
    let m = [1.0, 2.0, 2.5, 5.0, 10.0].into_iter().find(|m| m * mag >= raw).unwrap_or(10.0);
    let step = m * mag;
    let e = mag.log10().round();
    let decimals = (-e).max(0.0) as usize + usize::from(m == 2.5 && e <= 0.0);
    let unit = 10f64.powi(decimals as i32);
    let first = (lo / step - 1e-9).ceil() as i64;
    let last = (hi / step + 1e-9).floor() as i64;
    ((first..=last).map(|k| (k as f64 * step * unit).round() / unit).collect(), decimals)
}

/// The legend band at the bottom of a figure `h` pixels tall ([`legend_band`]).
fn legend<DB: DrawingBackend>(cv: &mut Canvas<DB>, h: u32, raced: bool) -> Res {
    cv.legend(&legend_band(raced), h, |cv, entry, (x, y)| {
        match entry {
            0 => {
                cv.rect((x, y - 9), (x + 26, y + 9), viridis(0.6).filled())?;
                cv.rect((x + 1, y - 8), (x + 25, y + 8), BEST.stroke_width(3))?;
            }
            1 => {
                cv.rect((x, y - 9), (x + 26, y + 9), viridis(0.3).filled())?;
                cv.hatch((x, y - 9), (x + 26, y + 9), WHITE)?;
            }
            2 => cv.rect((x, y - 9), (x + 26, y + 9), MISSING.filled())?,
            4 => {
                cv.rect((x, y - 9), (x + 26, y + 9), viridis(0.6).filled())?;
                cv.rect((x + 4, y - 5), (x + 22, y + 5), CONTENDER.stroke_width(2))?;
            }
            _ => {}
        }
        Ok(INK)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nice_ticks_are_round_and_inside() {
        assert_eq!(nice_ticks(25.5, 44.0), (vec![30.0, 35.0, 40.0], 0));
        assert_eq!(nice_ticks(0.0, 200.0), (vec![0.0, 50.0, 100.0, 150.0, 200.0], 0));
        assert_eq!(nice_ticks(1.3, 2.1), (vec![1.4, 1.6, 1.8, 2.0], 1));
        assert_eq!(nice_ticks(20.0, 114.0), (vec![25.0, 50.0, 75.0, 100.0], 0));
        assert_eq!(nice_ticks(1.0, 10.0), (vec![2.5, 5.0, 7.5, 10.0], 1));
        let (t, d) = nice_ticks(0.01, 0.02);
        assert_eq!((t.len(), d), (5, 4));
    }

    #[test]
    fn viridis_ends_and_clamps() {
        assert_eq!(viridis(0.0), RGBColor(68, 1, 84));
        assert_eq!(viridis(1.0), RGBColor(253, 231, 37));
        assert_eq!(viridis(2.0), viridis(1.0));
        assert_eq!(viridis(f64::NAN), viridis(0.0));
    }
}
