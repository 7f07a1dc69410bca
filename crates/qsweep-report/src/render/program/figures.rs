//! A program pipeline's figures as SVG text: a heatmap of the shown metric for a two-axis
//! experiment, its mean with the 95 % interval per value for a one-axis one, and a list metric's
//! curves (median and interquartile band over seeds). Written by hand rather than through plotters
//! so that every label is escaped once ([`escape::xml`]) and the bytes depend on nothing but the
//! numbers.

use super::{figure_stem, file_part, num};
use crate::derive::program::{CellStats, Curve, ExperimentStats, ProgramStats};
use crate::render::escape;
use crate::render::figures::{nice_ticks, viridis};
use crate::render::svg::simplify_points;
use std::fmt::Write;

const FONT: &str = "font-family=\"sans-serif\" font-size=\"12\"";
const BEST: &str = "#d62728";
const MISSING: &str = "#dddddd";
/// Colours of the curves, cell by cell (Tableau 10).
const LINES: [&str; 8] =
    ["#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b", "#e377c2", "#7f7f7f"];
/// Most cells drawn in one curves figure (the best first, then in plan order).
pub const MAX_CURVES: usize = 8;

/// What a figure shows.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Shows {
    /// Scalar metric `m` per cell: a heatmap (two axes) or a line with intervals (one axis).
    Cells(usize),
    /// List metric `l`'s curves.
    Curves(usize),
}

/// A figure file of the report.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Figure {
    /// Path relative to the report folder.
    pub path: String,
    /// The text it stands for.
    pub alt: String,
    /// What it shows.
    pub shows: Shows,
}

/// The figures of `e`, in page order: the shown metric per cell when `e` has one or two axes, then
/// one per list metric that some cell has values of.
pub fn listed(stats: &ProgramStats, e: &ExperimentStats) -> Vec<Figure> {
    let mut out = Vec::new();
    if let (Some(m), 1 | 2) = (stats.shown(), e.axes.len()) {
        out.push(Figure {
            path: format!("figures/{}.svg", figure_stem(e)),
            alt: format!("{}: mean {} per cell", e.id, stats.scalars[m].0),
            shows: Shows::Cells(m),
        });
    }
    for (l, name) in stats.lists.iter().enumerate() {
        if !curve_cells(e, l).is_empty() {
            out.push(Figure {
                path: format!("figures/{}--{}.svg", figure_stem(e), file_part(name)),
                alt: format!("{}: {name}, median and interquartile band over seeds", e.id),
                shows: Shows::Curves(l),
            });
        }
    }
    out
}

/// The SVG of figure `f` of `e`.
pub fn draw(stats: &ProgramStats, e: &ExperimentStats, f: &Figure) -> String {
    match f.shows {
        Shows::Cells(m) if e.axes.len() == 1 => line(stats, e, m),
        Shows::Cells(m) => heatmap(stats, e, m),
        Shows::Curves(l) => curves(stats, e, l),
    }
}

fn open(w: u32, h: u32, title: &str) -> String {
    format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{w}\" height=\"{h}\" viewBox=\"0 0 {w} {h}\" {FONT}>\n\
         <rect width=\"{w}\" height=\"{h}\" fill=\"white\"/>\n\
         <text x=\"{}\" y=\"20\" text-anchor=\"middle\" font-size=\"14\">{}</text>\n",
        w / 2,
        escape::xml(title)
    )
}

fn title(stats: &ProgramStats, e: &ExperimentStats, m: usize) -> String {
    let variant = e.variant.as_deref().map(|v| format!(" [{v}]")).unwrap_or_default();
    format!("{}{variant}: mean {}", e.id, stats.scalars[m].0)
}

fn heatmap(stats: &ProgramStats, e: &ExperimentStats, m: usize) -> String {
    let rows = distinct(e.cells.iter().map(|c| c.coords[0].to_string()));
    let cols = distinct(e.cells.iter().map(|c| c.coords[1].to_string()));
    let (cw, ch, left, top) = (64u32, 32u32, 90u32, 60u32);
    let (w, h) = ((left + cw * cols.len() as u32 + 20).max(480), top + ch * rows.len() as u32 + 60);
    let means: Vec<f64> = e.cells.iter().filter_map(|c| c.scalars[m].mean).collect();
    let lo = means.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = means.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let mut s = open(w, h, &title(stats, e, m));
    if e.race.is_some() {
        s.push_str(OUT_PATTERN);
    }
    for (i, c) in e.cells.iter().enumerate() {
        let r = rows.iter().position(|v| *v == c.coords[0].to_string()).unwrap_or(0) as u32;
        let k = cols.iter().position(|v| *v == c.coords[1].to_string()).unwrap_or(0) as u32;
        let (x, y) = (left + k * cw, top + r * ch);
        let (fill, ink, label) = match c.scalars[m].mean {
            Some(v) => {
                let t = if hi > lo { (v - lo) / (hi - lo) } else { 0.5 };
                let col = viridis(t);
                let lum = 0.299 * f64::from(col.0) + 0.587 * f64::from(col.1) + 0.114 * f64::from(col.2);
                let ink = if lum > 140.0 { "#222222" } else { "white" };
                (format!("#{:02x}{:02x}{:02x}", col.0, col.1, col.2), ink, num(v) + &failed_mark(c))
            }
            None => (MISSING.to_string(), "#222222", "—".to_string()),
        };
        let _ = writeln!(s, "<rect x=\"{x}\" y=\"{y}\" width=\"{cw}\" height=\"{ch}\" fill=\"{fill}\"/>");
        let _ = writeln!(
            s,
            "<text x=\"{}\" y=\"{}\" text-anchor=\"middle\" fill=\"{ink}\">{}</text>",
            x + cw / 2,
            y + ch / 2 + 4,
            escape::xml(&label)
        );
        if c.contender == Some(false) {
            // Faded and hatched: the cell left the race.
            let _ =
                writeln!(s, "<rect x=\"{x}\" y=\"{y}\" width=\"{cw}\" height=\"{ch}\" fill=\"url(#out)\"/>");
        }
        if e.best == Some(i) {
            let _ = writeln!(
                s,
                "<rect x=\"{}\" y=\"{}\" width=\"{}\" height=\"{}\" fill=\"none\" stroke=\"{BEST}\" stroke-width=\"3\"/>",
                x + 2,
                y + 2,
                cw - 4,
                ch - 4
            );
        }
    }
    for (k, v) in cols.iter().enumerate() {
        let x = left + k as u32 * cw + cw / 2;
        let _ =
            writeln!(s, "<text x=\"{x}\" y=\"{}\" text-anchor=\"middle\">{}</text>", top - 6, escape::xml(v));
    }
    for (r, v) in rows.iter().enumerate() {
        let y = top + r as u32 * ch + ch / 2 + 4;
        let _ =
            writeln!(s, "<text x=\"{}\" y=\"{y}\" text-anchor=\"end\">{}</text>", left - 6, escape::xml(v));
    }
    let _ = writeln!(
        s,
        "<text x=\"{}\" y=\"{}\" text-anchor=\"middle\">{}</text>\n<text x=\"{}\" y=\"{}\" text-anchor=\"middle\">{}</text>",
        left + cw * cols.len() as u32 / 2,
        top - 24,
        escape::xml(&e.axes[1]),
        left / 2,
        top - 24,
        escape::xml(&e.axes[0])
    );
    let mut legend = legend(stats, e);
    if e.race.is_some() {
        legend.push_str("; faded, hatched: left the race (significantly worse)");
    }
    let _ = writeln!(s, "<text x=\"{left}\" y=\"{}\">{legend}</text>", h - 24, legend = escape::xml(&legend));
    s.push_str("</svg>\n");
    s
}

/// A white wash with grey diagonal hatching, laid over a cell that left the race.
const OUT_PATTERN: &str =
    "<defs><pattern id=\"out\" width=\"6\" height=\"6\" patternUnits=\"userSpaceOnUse\" \
patternTransform=\"rotate(45)\"><rect width=\"6\" height=\"6\" fill=\"white\" fill-opacity=\"0.6\"/>\
<line x1=\"0\" y1=\"0\" x2=\"0\" y2=\"6\" stroke=\"#666666\" stroke-width=\"1.5\"/></pattern></defs>\n";

/// The line under a figure: the colour scale or the bars, and the best cell's outline.
fn legend(stats: &ProgramStats, e: &ExperimentStats) -> String {
    let n: Vec<usize> = e.cells.iter().map(|c| c.present - c.failed).collect();
    let (lo, hi) = (n.iter().min().copied().unwrap_or(0), n.iter().max().copied().unwrap_or(0));
    let seeds = if lo == hi { format!("n = {lo}") } else { format!("n = {lo}–{hi}") };
    let best = match (stats.objective, e.best) {
        (Some((_, goal)), Some(_)) => format!("; red: the best cell ({})", goal_name(goal)),
        _ => String::new(),
    };
    format!("{seeds} trials per cell; * a trial failed{best}")
}

fn goal_name(g: qsweep_pipeline::program::model::Goal) -> &'static str {
    match g {
        qsweep_pipeline::program::model::Goal::Minimize => "lowest mean",
        qsweep_pipeline::program::model::Goal::Maximize => "highest mean",
    }
}

fn failed_mark(c: &CellStats) -> String {
    if c.failed > 0 {
        "*".into()
    } else {
        String::new()
    }
}

/// The values in first-seen order, each once.
fn distinct(values: impl Iterator<Item = String>) -> Vec<String> {
    let mut out: Vec<String> = Vec::new();
    for v in values {
        if !out.contains(&v) {
            out.push(v);
        }
    }
    out
}

/// A y axis from `lo` to `hi` (padded when flat) with its ticks drawn across `[x0, x1]`.
struct Axis {
    lo: f64,
    hi: f64,
    y0: f64,
    y1: f64,
}

impl Axis {
    fn new(lo: f64, hi: f64, y0: f64, y1: f64) -> Self {
        let (lo, hi) = if hi > lo { (lo, hi) } else { (lo - 1.0, hi + 1.0) };
        let pad = (hi - lo) * 0.05;
        Self { lo: lo - pad, hi: hi + pad, y0, y1 }
    }

    fn y(&self, v: f64) -> f64 {
        self.y1 - (v - self.lo) / (self.hi - self.lo) * (self.y1 - self.y0)
    }

    fn draw(&self, s: &mut String, x0: f64, x1: f64) {
        let (ticks, decimals) = nice_ticks(self.lo, self.hi);
        for t in ticks {
            let y = self.y(t);
            let _ = writeln!(
                s,
                "<line x1=\"{x0}\" y1=\"{y:.1}\" x2=\"{x1}\" y2=\"{y:.1}\" stroke=\"#eeeeee\"/>\n\
                 <text x=\"{}\" y=\"{:.1}\" text-anchor=\"end\">{t:.decimals$}</text>",
                x0 - 6.0,
                y + 4.0
            );
        }
        let _ = writeln!(
            s,
            "<line x1=\"{x0}\" y1=\"{}\" x2=\"{x0}\" y2=\"{}\" stroke=\"#222222\"/>\n\
             <line x1=\"{x0}\" y1=\"{}\" x2=\"{x1}\" y2=\"{}\" stroke=\"#222222\"/>",
            self.y0, self.y1, self.y1, self.y1
        );
    }
}

fn line(stats: &ProgramStats, e: &ExperimentStats, m: usize) -> String {
    let (left, top, step, plot_h) = (80.0, 40.0, 56.0, 240.0);
    let w = (left + step * e.cells.len() as f64 + 30.0).max(360.0);
    let h = top + plot_h + 80.0;
    let points: Vec<(usize, f64, f64, f64)> = e
        .cells
        .iter()
        .enumerate()
        .filter_map(|(i, c)| {
            let s = &c.scalars[m];
            let mean = s.mean?;
            Some((i, mean, s.ci_lo.unwrap_or(mean), s.ci_hi.unwrap_or(mean)))
        })
        .collect();
    let lo = points.iter().map(|p| p.2).fold(f64::INFINITY, f64::min);
    let hi = points.iter().map(|p| p.3).fold(f64::NEG_INFINITY, f64::max);
    let mut s = open(w as u32, h as u32, &title(stats, e, m));
    let axis = Axis::new(
        if lo.is_finite() { lo } else { 0.0 },
        if hi.is_finite() { hi } else { 1.0 },
        top,
        top + plot_h,
    );
    axis.draw(&mut s, left, w - 20.0);
    let x = |i: usize| left + step * (i as f64 + 0.5);
    let path: Vec<String> = points.iter().map(|p| format!("{:.1},{:.1}", x(p.0), axis.y(p.1))).collect();
    let _ = writeln!(s, "<polyline points=\"{}\" fill=\"none\" stroke=\"{}\"/>", path.join(" "), LINES[0]);
    for &(i, mean, lo, hi) in &points {
        let colour = if e.best == Some(i) { BEST } else { LINES[0] };
        // A cell that left the race: faded, its point hollow.
        let (opacity, fill) =
            if e.cells[i].contender == Some(false) { ("0.35", "white") } else { ("1", colour) };
        let _ = writeln!(
            s,
            "<line x1=\"{0:.1}\" y1=\"{1:.1}\" x2=\"{0:.1}\" y2=\"{2:.1}\" stroke=\"{colour}\" stroke-width=\"2\" opacity=\"{opacity}\"/>\n\
             <circle cx=\"{0:.1}\" cy=\"{3:.1}\" r=\"4\" fill=\"{fill}\" stroke=\"{colour}\" opacity=\"{opacity}\"/>",
            x(i),
            axis.y(lo),
            axis.y(hi),
            axis.y(mean)
        );
    }
    for (i, c) in e.cells.iter().enumerate() {
        let label = c.coords[0].to_string() + &failed_mark(c);
        let _ = writeln!(
            s,
            "<text x=\"{:.1}\" y=\"{}\" text-anchor=\"middle\">{}</text>",
            x(i),
            top + plot_h + 18.0,
            escape::xml(&label)
        );
    }
    let _ = writeln!(
        s,
        "<text x=\"{:.1}\" y=\"{}\" text-anchor=\"middle\">{}</text>\n<text x=\"{left}\" y=\"{}\">{}</text>",
        (left + w - 20.0) / 2.0,
        top + plot_h + 38.0,
        escape::xml(&e.axes[0]),
        h - 16.0,
        escape::xml(&format!(
            "{}; bars: 95 % bootstrap interval of the mean{}",
            legend(stats, e),
            if e.race.is_some() { "; faded, hollow: left the race (significantly worse)" } else { "" }
        ))
    );
    s.push_str("</svg>\n");
    s
}

/// The cells a curves figure of `e` draws: the best first, then the others in plan order, at most
/// [`MAX_CURVES`], only those with a curve for list metric `l`.
pub fn curve_cells(e: &ExperimentStats, l: usize) -> Vec<usize> {
    let order = e.best.into_iter().chain((0..e.cells.len()).filter(|&i| Some(i) != e.best));
    order.filter(|&i| !e.cells[i].curves[l].points.is_empty()).take(MAX_CURVES).collect()
}

/// The curves of list metric `l` for the cells [`curve_cells`] picks (at least one).
fn curves(stats: &ProgramStats, e: &ExperimentStats, l: usize) -> String {
    let cells = curve_cells(e, l);
    let (left, top, plot_w, plot_h) = (80.0, 40.0, 480.0, 260.0);
    let legend_h = 18.0 * cells.len() as f64;
    let (w, h) = (left + plot_w + 30.0, top + plot_h + 50.0 + legend_h);
    let all = |f: fn(&(f64, f64, f64, usize)) -> f64| {
        cells.iter().flat_map(move |&i| e.cells[i].curves[l].points.iter().map(f))
    };
    let lo = all(|p| p.1).fold(f64::INFINITY, f64::min);
    let hi = all(|p| p.2).fold(f64::NEG_INFINITY, f64::max);
    let len = cells.iter().map(|&i| e.cells[i].curves[l].points.len()).max().unwrap_or(1);
    let variant = e.variant.as_deref().map(|v| format!(" [{v}]")).unwrap_or_default();
    let mut s = open(
        w as u32,
        h as u32,
        &format!("{}{variant}: {} (median, interquartile band)", e.id, stats.lists[l]),
    );
    let axis = Axis::new(lo, hi, top, top + plot_h);
    axis.draw(&mut s, left, left + plot_w);
    let x = |k: usize| left + plot_w * if len > 1 { k as f64 / (len - 1) as f64 } else { 0.5 };
    for (n, &i) in cells.iter().enumerate() {
        let Curve { points } = &e.cells[i].curves[l];
        let colour = LINES[n % LINES.len()];
        let upper = points.iter().enumerate().map(|(k, p)| format!("{:.1},{:.1}", x(k), axis.y(p.2)));
        let lower = points.iter().enumerate().rev().map(|(k, p)| format!("{:.1},{:.1}", x(k), axis.y(p.1)));
        let band: Vec<String> = upper.chain(lower).collect();
        let median: Vec<String> =
            points.iter().enumerate().map(|(k, p)| format!("{:.1},{:.1}", x(k), axis.y(p.0))).collect();
        let _ = writeln!(
            s,
            "<polygon points=\"{}\" fill=\"{colour}\" fill-opacity=\"0.15\" stroke=\"none\"/>\n\
             <polyline points=\"{}\" fill=\"none\" stroke=\"{colour}\" stroke-width=\"1.5\"/>",
            simplify_points(&band.join(" ")),
            simplify_points(&median.join(" "))
        );
        let coords: Vec<String> =
            e.axes.iter().zip(&e.cells[i].coords).map(|(a, v)| format!("{a}={v}")).collect();
        let best = if e.best == Some(i) { " (best)" } else { "" };
        let y = top + plot_h + 44.0 + 18.0 * n as f64;
        let _ = writeln!(
            s,
            "<rect x=\"{left}\" y=\"{:.1}\" width=\"14\" height=\"4\" fill=\"{colour}\"/>\n\
             <text x=\"{}\" y=\"{y:.1}\">{}</text>",
            y - 5.0,
            left + 20.0,
            escape::xml(&format!("{}{best}", coords.join(", ")))
        );
    }
    let _ = writeln!(
        s,
        "<text x=\"{:.1}\" y=\"{}\" text-anchor=\"middle\">index</text>",
        left + plot_w / 2.0,
        top + plot_h + 22.0
    );
    s.push_str("</svg>\n");
    s
}
