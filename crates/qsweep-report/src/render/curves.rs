//! Learning curves: one figure per system, one panel per experiment, one curve per algorithm
//! from the experiment's best cell (its Table III row): episode length against episode number,
//! the median over the cell's seeds as a line and the interquartile range as a band, on a log
//! scale, with the learning goal as a dashed line.
//!
//! Seeds stop at different episodes (a trial ends when it reaches the goal), so the band needs a
//! rule past a seed's end ([`CURVE_RULE`]): a seed that reached the goal keeps counting at the
//! length of its last episode (the performance it stopped at, which met the goal); a seed that
//! stopped without reaching it (diverged) drops out; a curve ends where its last seed stopped.
//! With that rule the median crosses the goal line where half of the seeds have reached it.
//!
//! Drawn like [`crate::render::figures`]: shapes through plotters, text through [`crate::render::glyphs`] in the
//! embedded font, so the PNG bytes are the same everywhere.

use crate::derive::report_data::{CellData, ExpData, ReportData};
use crate::render::figures::{self, nice_ticks, Canvas, Picture, Res, INK, SUBTLE};
use crate::render::text_fit::{self, Entry, Legend};
use plotters::element::DashedPathElement;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, VPos};
use qsweep_engine::config::Success;
use qsweep_engine::env::{SystemKind, TaskKind};
use qsweep_engine::Algorithm;
use qsweep_pipeline::analysis::quantile_sorted;

/// Width of one panel, in pixels.
pub const PANEL_W: u32 = 500;
/// Height of one panel, in pixels.
pub const PANEL_H: u32 = 330;
/// Panels per figure row.
pub const PANELS_PER_ROW: u32 = 2;
/// Height of the figure's title band.
pub const HEADER_H: u32 = 50;
/// Height of the legend band.
pub const FOOTER_H: u32 = 64;

/// How the median and band are computed, as stated in every caption.
pub const CURVE_RULE: &str = "Line: median episode length over the best cell's seeds; band: \
interquartile range (25th to 75th percentile). A seed that reached the goal counts at its last \
episode's length after it stopped; a seed that stopped without reaching it drops out; a curve ends \
where its last seed stopped.";

const GOAL: RGBColor = RGBColor(200, 0, 0);
const GRID: RGBColor = RGBColor(215, 215, 215);
const MINOR: RGBColor = RGBColor(240, 240, 240);

/// Line colour of an algorithm's curve.
pub fn colour(a: Algorithm) -> RGBColor {
    match a {
        Algorithm::Q0 => RGBColor(230, 110, 0),
        Algorithm::QLambda => RGBColor(30, 100, 200),
    }
}

/// Per-episode statistics of one cell's seeds.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Curve {
    /// Median episode length at episode `i + 1`.
    pub median: Vec<f64>,
    /// 25th percentile at episode `i + 1`.
    pub q1: Vec<f64>,
    /// 75th percentile at episode `i + 1`.
    pub q3: Vec<f64>,
    /// Seeds counted at episode `i + 1` (running, or stopped at the goal).
    pub counted: Vec<usize>,
}

impl Curve {
    /// The curve of seeds given as (episode lengths, reached the goal), under [`CURVE_RULE`].
    pub fn of(seeds: &[(&[u32], bool)]) -> Self {
        let len = seeds.iter().map(|(l, _)| l.len()).max().unwrap_or(0);
        let mut c = Self::default();
        for i in 0..len {
            let mut v: Vec<f64> = seeds
                .iter()
                .filter_map(|&(l, converged)| match l.get(i) {
                    Some(&x) => Some(f64::from(x)),
                    None if converged => l.last().map(|&x| f64::from(x)),
                    None => None,
                })
                .collect();
            if v.is_empty() {
                break;
            }
            v.sort_by(f64::total_cmp);
            c.median.push(quantile_sorted(&v, 0.5));
            c.q1.push(quantile_sorted(&v, 0.25));
            c.q3.push(quantile_sorted(&v, 0.75));
            c.counted.push(v.len());
        }
        c
    }

    /// The curve of a cell's present trials.
    pub fn of_cell(cell: &CellData) -> Self {
        let seeds: Vec<(&[u32], bool)> =
            cell.trials.iter().map(|t| (&t.outcome.episode_lengths[..], t.outcome.converged)).collect();
        Self::of(&seeds)
    }

    /// Episodes the curve covers.
    pub fn len(&self) -> usize {
        self.median.len()
    }

    /// Whether the curve has no episode.
    pub fn is_empty(&self) -> bool {
        self.median.is_empty()
    }
}

/// The episode length a cell's learning goal asks for, with its legend text.
pub fn goal(success: &Success) -> (f64, String) {
    match success {
        Success::Balance { steps } => (*steps as f64, format!("goal: an episode of {steps} steps")),
        Success::Reach { within, streak, .. } => {
            let n =
                if *streak == 1 { "an episode".to_string() } else { format!("{streak} episodes in a row") };
            (*within as f64, format!("goal: {n} within {within} steps"))
        }
        Success::Solved { window, mean_length, .. } => {
            (*mean_length, format!("goal: a mean of {mean_length} steps over {window} episodes"))
        }
    }
}

/// Pixel size of a system's curves figure with `panels` experiments.
pub fn figure_size(panels: usize) -> (u32, u32) {
    let rows = (panels.max(1) as u32).div_ceil(PANELS_PER_ROW);
    let w = PANELS_PER_ROW * PANEL_W;
    (w, HEADER_H + rows * PANEL_H + legend_band().place(w).1)
}

/// The legend band: the two algorithms' lines and bands, the goal's line, and the rule past a
/// seed's end; [`FOOTER_H`] tall where its columns fit.
fn legend_band() -> Legend {
    let mut entries: Vec<Entry> = [Algorithm::Q0, Algorithm::QLambda]
        .into_iter()
        .map(|a| Entry {
            text: format!("{} (median, interquartile band)", a.label(qsweep_engine::repr::ReprKind::Crisp)),
            size: 13.0,
            swatch: true,
        })
        .collect();
    entries.push(Entry { text: "learning goal".into(), size: 13.0, swatch: true });
    entries.push(Entry {
        text: "After a seed stops: counted at its last episode's length if it reached the goal, dropped if \
               not. Cells: bins or fuzzy sets per state variable, in state order."
            .into(),
        size: 12.0,
        swatch: false,
    });
    let rows = vec![vec![(20, 0), (350, 1), (680, 2)], vec![(20, 3)]];
    Legend { entries, rows, first: 16, row_h: 22, bottom: FOOTER_H as i32 - 16 - 22 }
}

/// The curves figure of one system as SVG text and PNG bytes.
pub fn render(data: &ReportData, system: SystemKind) -> anyhow::Result<(String, Vec<u8>)> {
    let d = render_as(data, system, true, true)?;
    Ok((d.svg.unwrap_or_default(), d.png.unwrap_or_default()))
}

/// The curves figure of one system, drawn only in the formats asked for.
pub fn render_as(
    data: &ReportData,
    system: SystemKind,
    svg: bool,
    png: bool,
) -> anyhow::Result<figures::Drawn> {
    let exps: Vec<&ExpData> = data.experiments.iter().filter(|e| e.exp.system == system).collect();
    let title =
        format!("{}: learning curves of the best cells ({})", system.title(), data.plan.report_name());
    figures::paint_as(&Curves { exps: &exps, title: &title }, figure_size(exps.len()), svg, png)
        .map_err(|e| anyhow::anyhow!("drawing the {system} learning curves: {e}"))
}

struct Curves<'a, 'b> {
    exps: &'a [&'a ExpData<'b>],
    title: &'a str,
}

impl Picture for Curves<'_, '_> {
    fn draw<DB: DrawingBackend>(&self, cv: &mut Canvas<DB>) -> Res {
        cv.root.fill(&WHITE).map_err(|e| e.to_string())?;
        let (w, h) = cv.root.dim_in_pixel();
        cv.title(self.title, w);
        for (i, e) in self.exps.iter().enumerate() {
            let (r, c) = (i as u32 / PANELS_PER_ROW, i as u32 % PANELS_PER_ROW);
            panel(cv, ((c * PANEL_W) as i32, (HEADER_H + r * PANEL_H) as i32), e)?;
        }
        legend(cv, h)
    }
}

/// A cell's configuration, e.g. "5×3 bins, 3 actions" (resolution in state-variable order).
fn cell_name(c: &CellData) -> String {
    let cfg = &c.cell.config;
    let res: Vec<String> = cfg.repr.resolution.iter().map(u32::to_string).collect();
    let unit = match cfg.repr.kind {
        qsweep_engine::repr::ReprKind::Crisp => "bins",
        qsweep_engine::repr::ReprKind::Fuzzy => "sets",
    };
    format!("{} {unit}, {} actions", res.join("×"), cfg.actions)
}

/// Decade ticks 10^lo … 10^hi as text: 1, 10, 100, 1k, 10k, …
fn decade_label(d: i32) -> String {
    match d {
        ..=2 => format!("{}", 10f64.powi(d)),
        3..=5 => format!("{}k", 10i64.pow(d as u32 - 3)),
        _ => format!("{}M", 10i64.pow(d as u32 - 6)),
    }
}

/// One panel: experiment `e`, top-left corner at `(ox, oy)`.
fn panel<DB: DrawingBackend>(cv: &mut Canvas<DB>, (ox, oy): (i32, i32), e: &ExpData) -> Res {
    let exp = e.exp;
    let cx = ox + PANEL_W as i32 / 2;
    let name = match &exp.title {
        Some(t) => format!("Exp. {}: {t} ({})", exp.id, exp.repr.name()),
        None => format!("Exp. {} ({})", exp.id, exp.repr.name()),
    };
    cv.text_within(&name, (cx, oy + 14), PANEL_W as i32 - 2 * text_fit::MARGIN, 15.0, INK);

    // One curve per algorithm with a best cell.
    let curves: Vec<(Algorithm, &CellData, Curve)> = exp
        .algorithms
        .iter()
        .filter_map(|&a| e.best_of(a).map(|b| (a, &e.cells[b.cell])))
        .map(|(a, c)| (a, c, Curve::of_cell(c)))
        .filter(|(_, _, k)| !k.is_empty())
        .collect();
    for (k, (a, c, _)) in curves.iter().enumerate() {
        let y = oy + 32 + 16 * k as i32;
        cv.line((ox + 20, y), (ox + 40, y), colour(*a).stroke_width(3))?;
        let text = format!("{}: {}; {} seeds", a.label(exp.repr), cell_name(c), c.trials.len());
        cv.text(&text, (ox + 46, y), 12.0, INK, HPos::Left, VPos::Center);
    }
    if curves.is_empty() {
        let mid = (cx, oy + PANEL_H as i32 / 2);
        cv.text("no trials yet", mid, 13.0, SUBTLE, HPos::Center, VPos::Center);
        return Ok(());
    }
    let goals = goal_lines(&curves);
    let axes = Axes::fit((ox, oy), &curves, &goals);
    axes.draw(cv, ox)?;
    draw_curves(cv, &axes, &curves, &goals)
}

/// The learning goals of the cells drawn, each once, lowest first: (episode length, label, a goal
/// to get under rather than to rise to).
fn goal_lines(curves: &[(Algorithm, &CellData, Curve)]) -> Vec<(f64, String, bool)> {
    let mut goals: Vec<(f64, String, bool)> = curves
        .iter()
        .map(|(_, c, _)| {
            let s = &c.cell.config.limits.success;
            let (v, text) = goal(s);
            (v, text, TaskKind::of(c.cell.config.system()) == TaskKind::GoalReaching)
        })
        .collect();
    goals.sort_by(|a, b| a.0.total_cmp(&b.0));
    goals.dedup_by(|a, b| a.0 == b.0);
    goals
}

/// A panel's plot area and scales: episodes 1..=n linear, lengths on decades 10^lo … 10^hi.
struct Axes {
    left: i32,
    right: i32,
    top: i32,
    bottom: i32,
    n: usize,
    lo: i32,
    hi: i32,
}

impl Axes {
    /// The axes of the panel at `(ox, oy)` that hold `curves` and `goals`.
    fn fit(
        (ox, oy): (i32, i32),
        curves: &[(Algorithm, &CellData, Curve)],
        goals: &[(f64, String, bool)],
    ) -> Self {
        let n = curves.iter().map(|(_, _, k)| k.len()).max().unwrap_or(1).max(2);
        let values =
            curves.iter().flat_map(|(_, _, k)| k.q1.iter().chain(&k.q3)).chain(goals.iter().map(|g| &g.0));
        let (vmin, vmax) = values.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| (a.min(v), b.max(v)));
        let lo = vmin.max(1.0).log10().floor() as i32;
        let hi = (vmax.max(1.0).log10().ceil() as i32).max(lo + 1);
        Self {
            left: ox + 62,
            right: ox + PANEL_W as i32 - 20,
            top: oy + 30 + 17 * 2,
            bottom: oy + PANEL_H as i32 - 42,
            n,
            lo,
            hi,
        }
    }

    fn px(&self, i: f64) -> f64 {
        self.left as f64 + (i - 1.0) / (self.n as f64 - 1.0) * (self.right - self.left) as f64
    }

    fn py(&self, v: f64) -> f64 {
        let t = (v.max(1.0).log10() - f64::from(self.lo)) / f64::from(self.hi - self.lo);
        self.bottom as f64 - t * (self.bottom - self.top) as f64
    }

    fn pt(&self, i: f64, v: f64) -> (i32, i32) {
        (self.px(i).round() as i32, self.py(v).round() as i32)
    }

    /// The grid, the ticks and the axis labels (the panel's left edge at `ox`).
    fn draw<DB: DrawingBackend>(&self, cv: &mut Canvas<DB>, ox: i32) -> Res {
        let (left, right, top, bottom, lo, hi) =
            (self.left, self.right, self.top, self.bottom, self.lo, self.hi);
        for d in lo..=hi {
            let y = self.py(10f64.powi(d)).round() as i32;
            cv.line((left, y), (right, y), GRID.stroke_width(1))?;
            cv.text(&decade_label(d), (left - 6, y), 11.0, INK, HPos::Right, VPos::Center);
            // 2× and 5× lines, labelled where decades are tall enough.
            for m in [2.0, 5.0].into_iter().filter(|_| d < hi) {
                let y = self.py(m * 10f64.powi(d)).round() as i32;
                cv.line((left, y), (right, y), MINOR.stroke_width(1))?;
                if hi - lo <= 2 {
                    let label = decade_label(d).replacen('1', &format!("{m}"), 1);
                    cv.text(&label, (left - 6, y), 10.0, SUBTLE, HPos::Right, VPos::Center);
                }
            }
        }
        let (ticks, _) = nice_ticks(1.0, self.n as f64);
        for t in ticks.into_iter().filter(|t| t.fract() == 0.0) {
            let x = self.px(t).round() as i32;
            cv.line((x, bottom), (x, bottom + 4), INK.stroke_width(1))?;
            cv.text(&format!("{t}"), (x, bottom + 6), 11.0, INK, HPos::Center, VPos::Top);
        }
        cv.text("episode", ((left + right) / 2, bottom + 22), 12.0, INK, HPos::Center, VPos::Top);
        cv.text_up("episode length (steps, log scale)", (ox + 16, (top + bottom) / 2), 12.0, INK);
        Ok(())
    }
}

/// The curves on `axes`: bands first, then the goals, then the medians on top, then the frame.
fn draw_curves<DB: DrawingBackend>(
    cv: &mut Canvas<DB>,
    axes: &Axes,
    curves: &[(Algorithm, &CellData, Curve)],
    goals: &[(f64, String, bool)],
) -> Res {
    let (left, right) = (axes.left, axes.right);
    for (a, _, k) in curves {
        let mut poly: Vec<(i32, i32)> = (0..k.len()).map(|i| axes.pt(i as f64 + 1.0, k.q3[i])).collect();
        poly.extend((0..k.len()).rev().map(|i| axes.pt(i as f64 + 1.0, k.q1[i])));
        cv.root.draw(&Polygon::new(poly, colour(*a).mix(0.22).filled())).map_err(|e| e.to_string())?;
    }
    for (g, text, reach) in goals {
        let y = axes.py(*g).round() as i32;
        let path = DashedPathElement::new(vec![(left, y), (right, y)], 6, 4, GOAL.stroke_width(2));
        cv.root.draw(&path).map_err(|e| e.to_string())?;
        // Below the line, where the curves are not: at the right for goals to get under (Reach:
        // the curves fall towards it), at the left for goals to rise to (Balance).
        let (x, hpos) = if *reach { (right - 4, HPos::Right) } else { (left + 4, HPos::Left) };
        cv.text(text, (x, y + 4), 11.0, GOAL, hpos, VPos::Top);
    }
    for (a, _, k) in curves {
        let line: Vec<(i32, i32)> = (0..k.len()).map(|i| axes.pt(i as f64 + 1.0, k.median[i])).collect();
        let style = colour(*a).stroke_width(2);
        if line.len() == 1 {
            cv.root.draw(&Circle::new(line[0], 3, style.filled())).map_err(|e| e.to_string())?;
        } else {
            cv.root.draw(&PathElement::new(line, style)).map_err(|e| e.to_string())?;
        }
    }
    cv.rect((left, axes.top), (right, axes.bottom), INK.stroke_width(1))
}

/// The legend band at the bottom of a figure `h` pixels tall ([`legend_band`]).
fn legend<DB: DrawingBackend>(cv: &mut Canvas<DB>, h: u32) -> Res {
    cv.legend(&legend_band(), h, |cv, entry, (x, y)| {
        match entry {
            0 | 1 => {
                let a = [Algorithm::Q0, Algorithm::QLambda][entry];
                cv.rect((x, y - 7), (x + 26, y + 7), colour(a).mix(0.22).filled())?;
                cv.line((x, y), (x + 26, y), colour(a).stroke_width(2))?;
            }
            2 => {
                let path = DashedPathElement::new(vec![(x, y), (x + 26, y)], 6, 4, GOAL.stroke_width(2));
                cv.root.draw(&path).map_err(|e| e.to_string())?;
            }
            _ => {}
        }
        // The note under the swatches is set apart in grey.
        Ok(if entry == 3 { SUBTLE } else { INK })
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn converged_seeds_carry_their_last_length_and_stopped_ones_drop_out() {
        let a: &[u32] = &[10, 20, 500];
        let b: &[u32] = &[5, 40, 60, 80, 90];
        let c: &[u32] = &[7, 8];
        let k = Curve::of(&[(a, true), (b, false), (c, false)]);
        assert_eq!(k.len(), 5);
        assert_eq!(k.counted, vec![3, 3, 2, 2, 2]);
        // Episode 1: [5, 7, 10]; episode 2: [8, 20, 40].
        assert_eq!((k.median[0], k.q1[0], k.q3[0]), (7.0, 6.0, 8.5));
        assert_eq!((k.median[1], k.q1[1], k.q3[1]), (20.0, 14.0, 30.0));
        // Episode 4: a carried at 500, b at 80; c dropped out.
        assert_eq!((k.median[3], k.q1[3], k.q3[3]), (290.0, 185.0, 395.0));
        // A curve stops where no seed is left.
        let d: &[u32] = &[1, 2, 3];
        assert_eq!(Curve::of(&[(c, false), (d, false)]).len(), 3);
        assert!(Curve::of(&[]).is_empty());
    }

    #[test]
    fn goals_and_labels() {
        assert_eq!(goal(&Success::Balance { steps: 100_000 }).0, 100_000.0);
        let (v, t) = goal(&Success::Reach { within: 400, streak: 1, max_episode_steps: 2000 });
        assert_eq!((v, t.as_str()), (400.0, "goal: an episode within 400 steps"));
        assert_eq!(
            [0, 2, 3, 5, 6].map(decade_label),
            ["1".to_string(), "100".into(), "1k".into(), "100k".into(), "1M".into()]
        );
        assert_eq!(figure_size(4), (1000, 50 + 2 * 330 + 64));
        assert_eq!(figure_size(3), figure_size(4));
    }
}
