//! `compare.svg`: each compared cell's B ÷ A with its 95 % interval on a log axis, the
//! equivalence margin shaded and 1 marked, the dot coloured by the cell's verdict. Drawn with the
//! report's figure helpers (`crate::render::canvas`), so its text is escaped by the one rule for
//! SVG and its bytes are the same on every run.

use super::stats::{Comparison, Verdict};
use crate::render::figures::{Canvas, Picture, Res, INK, SUBTLE};
use crate::render::log_axis::LogAxis;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, VPos};

/// Width of the figure, in pixels.
pub const WIDTH: u32 = 900;
const ROW_H: u32 = 16;
const TOP: u32 = 44;
const BOTTOM: u32 = 80;
const PLOT_X: (i32, i32) = (250, WIDTH as i32 - 30);
const MARGIN_SHADE: RGBColor = RGBColor(199, 229, 199);

/// A verdict's colour (Okabe–Ito: bluish green, vermillion, grey).
fn color(v: Verdict) -> RGBColor {
    match v {
        Verdict::Equivalent => RGBColor(0, 158, 115),
        Verdict::Differs => RGBColor(213, 94, 0),
        Verdict::Undecided => RGBColor(120, 120, 120),
    }
}

/// The axis of `c`: its margin, 1, and every ratio and interval end
/// ([`crate::render::log_axis`]).
pub fn axis_of(c: &Comparison) -> LogAxis {
    let values =
        c.cells.iter().flat_map(|x| [x.ratio, x.ratio_ci.map(|r| r.0), x.ratio_ci.map(|r| r.1)]).flatten();
    LogAxis::around((c.margin.0.min(1.0), c.margin.1.max(1.0)), values, PLOT_X)
}

/// Pixel size of the figure of `rows` cells.
pub fn size(rows: usize) -> (u32, u32) {
    (WIDTH, TOP + rows.max(1) as u32 * ROW_H + BOTTOM)
}

/// The y pixel of the middle of row `i`.
fn row_y(i: usize) -> i32 {
    (TOP + i as u32 * ROW_H + ROW_H / 2) as i32
}

/// The figure of `c` as SVG text.
pub fn svg(c: &Comparison) -> anyhow::Result<String> {
    let d =
        crate::render::figures::paint_as(&Figure { c, axis: axis_of(c) }, size(c.cells.len()), true, false)
            .map_err(|e| anyhow::anyhow!("drawing compare.svg: {e}"))?;
    d.svg.ok_or_else(|| anyhow::anyhow!("drawing compare.svg: no SVG"))
}

struct Figure<'a> {
    c: &'a Comparison,
    axis: LogAxis,
}

impl Picture for Figure<'_> {
    fn draw<DB: DrawingBackend>(&self, cv: &mut Canvas<DB>) -> Res {
        cv.root.fill(&WHITE).map_err(|e| e.to_string())?;
        let (ax, c) = (self.axis, self.c);
        let n = c.cells.len().max(1);
        let (top, bottom) = (TOP as i32, (TOP + n as u32 * ROW_H) as i32);
        let title =
            format!("{} ÷ {} per cell, metric {}, 95 % intervals", c.labels.1, c.labels.0, c.metric.0);
        cv.text_within(&title, (WIDTH as i32 / 2, TOP as i32 / 2), WIDTH as i32 - 20, 16.0, INK);
        cv.rect((ax.x(c.margin.0), top), (ax.x(c.margin.1), bottom), MARGIN_SHADE.filled())?;
        cv.line((ax.x(1.0), top), (ax.x(1.0), bottom), INK.stroke_width(1))?;
        for (i, x) in c.cells.iter().enumerate() {
            let y = row_y(i);
            let label = crate::render::text_fit::fit(&x.label, f64::from(PLOT_X.0 - 28), 12.0, 9.0);
            cv.text(&label.0, (PLOT_X.0 - 8, y), label.1, INK, HPos::Right, VPos::Center);
            let col = color(x.verdict);
            if let Some((lo, hi)) = x.ratio_ci {
                cv.line((ax.x(lo), y), (ax.x(hi), y), col.stroke_width(2))?;
            }
            if let Some(r) = x.ratio {
                cv.root.draw(&Circle::new((ax.x(r), y), 4, col.filled())).map_err(|e| e.to_string())?;
            }
        }
        cv.line((PLOT_X.0, bottom), (PLOT_X.1, bottom), INK.stroke_width(1))?;
        for v in ax.ticks() {
            let x = ax.x(v);
            cv.line((x, bottom), (x, bottom + 4), INK.stroke_width(1))?;
            let s = format!("{v:.3}");
            let s = s.trim_end_matches('0').trim_end_matches('.');
            cv.text(s, (x, bottom + 7), 11.0, INK, HPos::Center, VPos::Top);
        }
        let mid = (PLOT_X.0 + PLOT_X.1) / 2;
        cv.text("B ÷ A (log scale)", (mid, bottom + 30), 12.0, INK, HPos::Center, VPos::Center);
        let y = bottom + 55;
        let mut x = 20;
        for v in [Verdict::Equivalent, Verdict::Differs, Verdict::Undecided] {
            cv.root.draw(&Circle::new((x + 6, y), 4, color(v).filled())).map_err(|e| e.to_string())?;
            cv.text(v.word(), (x + 16, y), 12.0, INK, HPos::Left, VPos::Center);
            x += 110;
        }
        cv.rect((x, y - 6), (x + 24, y + 6), MARGIN_SHADE.filled())?;
        let m = format!("equivalence margin {:.2}–{:.2}", c.margin.0, c.margin.1);
        cv.text(&m, (x + 30, y), 12.0, INK, HPos::Left, VPos::Center);
        cv.text("bar: 95 % interval", (x + 250, y), 12.0, SUBTLE, HPos::Left, VPos::Center);
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::comparison::cells::Sample;
    use crate::comparison::matching::{CellSamples, Matched};
    use crate::comparison::stats::compare_matched;
    use qsweep_pipeline::program::model::ParamValue;

    fn comparison() -> Comparison {
        let a: Vec<f64> = (0..6).map(|i| 100.0 + f64::from(i)).collect();
        let cells = (0..3)
            .map(|k| CellSamples {
                values: vec![ParamValue::Str(format!("<k{k}> & \"q\""))],
                a: Sample::Values(a.clone()),
                b: Sample::Values(a.iter().map(|v| v * (1.0 + 0.1 * f64::from(k))).collect()),
            })
            .collect();
        compare_matched(
            Matched {
                labels: ("a<1>.yaml".into(), "b&.yaml".into()),
                shared: vec![("env".into(), "env".into())],
                metric: ("score".into(), "score".into()),
                cells,
                only_a: vec![],
                only_b: vec![],
            },
            (0.8, 1.25),
        )
    }

    #[test]
    fn the_axis_is_logarithmic_and_spans_the_margin_and_the_ratios() {
        let c = comparison();
        let ax = axis_of(&c);
        assert_eq!(ax.domain, (0.5, 2.0));
        assert_eq!(ax.x(0.5), PLOT_X.0);
        assert_eq!(ax.x(2.0), PLOT_X.1);
        assert_eq!(ax.x(1.0), (PLOT_X.0 + PLOT_X.1) / 2, "log: 1 halfway between 0.5 and 2");
        assert_eq!(ax.x(f64::INFINITY), PLOT_X.1, "an unbounded interval ends at the edge");
        for v in [0.6, 1.0, 1.7] {
            assert!((ax.value(f64::from(ax.x(v))) / v - 1.0).abs() < 0.01, "{v}");
        }
    }

    #[test]
    fn the_figure_is_valid_escaped_and_deterministic() {
        let c = comparison();
        let s = svg(&c).unwrap();
        assert_eq!(s, svg(&c).unwrap());
        let doc = roxmltree::Document::parse(&s).unwrap();
        let texts: Vec<String> = doc
            .descendants()
            .filter(|n| n.has_tag_name("text"))
            .map(|n| n.text().unwrap_or("").to_string())
            .collect();
        assert!(texts.iter().any(|t| t == "env=<k2> & \"q\""), "{texts:?}");
        assert_eq!(
            doc.descendants().filter(|n| n.has_tag_name("circle")).count(),
            3 + 3,
            "a dot per cell, three in the legend"
        );
    }
}
