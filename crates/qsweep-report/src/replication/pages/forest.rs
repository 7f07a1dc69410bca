//! The answer of a comparison with reference values, in a few sentences and one figure
//! (`figures/forest.svg`, and `.png` with `--formats png`): a forest plot of every Table III row,
//! ours ÷ reference on a log axis with its 95 % interval, for the as-written variant and the
//! best-ranked declared one, over the equivalence margin and the 2× band.
//!
//! The plotted numbers are `table3.csv`'s `ratio`, `ratio_lo` and `ratio_hi` ([`rows_of`] computes
//! them as the table does: from the fresh-seed estimate where the best cell was re-run), so the
//! figure and the table cannot disagree.

use crate::render::figures::{self, Canvas, Drawn, Picture, Res, INK, SUBTLE};
use crate::render::log_axis::LogAxis;
use crate::replication::compare::fit::Fit;
pub use crate::replication::compare::ratios::{rows_of, ForestRow};
use crate::replication::compare::VariantInfo;
use crate::replication::stats::equivalence::MARGIN;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, VPos};

/// The figure's path in the comparison folder, without extension.
pub const STEM: &str = "figures/forest";

/// The band of "within 2×".
pub const TWO_X: (f64, f64) = (0.5, 2.0);

/// Width of the figure, in pixels.
pub const WIDTH: u32 = 900;
/// Height of one Table III row.
const ROW_H: u32 = 16;
/// Title band.
const TOP: u32 = 44;
/// Axis, axis title and legend below the rows.
const BOTTOM: u32 = 80;
/// Where the plot area starts (the labels are right-aligned before it) and ends.
const PLOT_X: (i32, i32) = (250, WIDTH as i32 - 30);

/// Colours of the two series: the as-written variant and the best declared one (Okabe–Ito blue
/// and vermillion, told apart with colour-blindness too).
pub const COLORS: [RGBColor; 2] = [RGBColor(0, 114, 178), RGBColor(213, 94, 0)];
/// The 2× band's shade.
const BAND: RGBColor = RGBColor(236, 236, 236);
/// The equivalence margin's shade.
const MARGIN_SHADE: RGBColor = RGBColor(199, 229, 199);

/// One plotted variant.
#[derive(Debug, Clone)]
pub struct Series<'a> {
    /// The variant.
    pub info: &'a VariantInfo,
    /// Its role: "as written", "best declared" ("chosen by the search" in an exploratory
    /// search), or both.
    pub role: &'static str,
    /// Its rows.
    pub rows: &'a [ForestRow],
    /// Its rows as judged ([`crate::replication::compare::fit::RowFit`]: verdicts, spreads).
    pub scored: &'a [crate::replication::compare::fit::RowFit],
    /// Its fit (replicating and equivalent rows).
    pub fit: Fit,
}

/// Pixel size of the forest plot of `rows` rows.
pub fn figure_size(rows: usize) -> (u32, u32) {
    (WIDTH, TOP + rows.max(1) as u32 * ROW_H + BOTTOM)
}

/// The rows of the figure: every label of the first series, then any the others add, in order.
pub fn labels(series: &[Series]) -> Vec<String> {
    let mut out: Vec<String> = Vec::new();
    for s in series {
        for r in s.rows {
            if !out.contains(&r.label) {
                out.push(r.label.clone());
            }
        }
    }
    out
}

/// The axis for `series`: [`TWO_X`] and every ratio and interval end
/// ([`crate::render::log_axis`]).
pub fn axis_of(series: &[Series]) -> LogAxis {
    let values = series
        .iter()
        .flat_map(|s| s.rows)
        .flat_map(|r| [Some(r.ratio), r.ci.map(|c| c.0), r.ci.map(|c| c.1)].into_iter().flatten());
    LogAxis::around(TWO_X, values, PLOT_X)
}

/// A tick label: "0.05", "1", "20".
pub fn tick_label(v: f64) -> String {
    let s = format!("{v:.3}");
    s.trim_end_matches('0').trim_end_matches('.').to_string()
}

/// Write the forest plot of `series` (none without a row) through `put` as [`STEM`]`.svg` and/or
/// `.png`; returns its pixel size when drawn.
pub fn write(
    name: &str,
    series: &[Series],
    (svg, png): (bool, bool),
    put: &mut impl FnMut(&str, &[u8]) -> anyhow::Result<()>,
) -> anyhow::Result<Option<(u32, u32)>> {
    if series.is_empty() || !(svg || png) {
        return Ok(None);
    }
    let d = forest_figure(name, series, (svg, png))?;
    if let Some(s) = d.svg {
        put(&format!("{STEM}.svg"), s.as_bytes())?;
    }
    if let Some(p) = d.png {
        put(&format!("{STEM}.png"), &p)?;
    }
    Ok(Some(figure_size(labels(series).len())))
}

/// The forest plot of `series`, titled with the pipeline's name.
pub fn forest_figure(name: &str, series: &[Series], (svg, png): (bool, bool)) -> anyhow::Result<Drawn> {
    let labels = labels(series);
    let forest = Forest { name, series, labels: &labels, axis: axis_of(series) };
    figures::paint_as(&forest, figure_size(labels.len()), svg, png)
        .map_err(|e| anyhow::anyhow!("drawing the forest plot: {e}"))
}

struct Forest<'a> {
    name: &'a str,
    series: &'a [Series<'a>],
    labels: &'a [String],
    axis: LogAxis,
}

/// The y pixel of the middle of row `i`.
pub fn row_y(i: usize) -> i32 {
    (TOP + i as u32 * ROW_H + ROW_H / 2) as i32
}

/// The vertical offset of series `k` of `n` within its row.
pub fn series_dy(k: usize, n: usize) -> i32 {
    if n < 2 {
        0
    } else if k == 0 {
        -4
    } else {
        4
    }
}

impl Picture for Forest<'_> {
    fn draw<DB: DrawingBackend>(&self, cv: &mut Canvas<DB>) -> Res {
        cv.root.fill(&WHITE).map_err(|e| e.to_string())?;
        let ax = self.axis;
        let n = self.labels.len().max(1);
        let (top, bottom) = (TOP as i32, (TOP + n as u32 * ROW_H) as i32);
        let title = format!("Ours ÷ paper per Table III row, our 95 % intervals (pipeline {})", self.name);
        cv.text(&title, (WIDTH as i32 / 2, TOP as i32 / 2), 17.0, INK, HPos::Center, VPos::Center);
        cv.rect((ax.x(TWO_X.0), top), (ax.x(TWO_X.1), bottom), BAND.filled())?;
        cv.rect((ax.x(MARGIN.0), top), (ax.x(MARGIN.1), bottom), MARGIN_SHADE.filled())?;
        cv.line((ax.x(1.0), top), (ax.x(1.0), bottom), INK.stroke_width(1))?;
        // A rule between systems; the labels name them.
        let system = |l: &str| l.split(" · ").next().unwrap_or("").to_string();
        for i in 1..self.labels.len() {
            if system(&self.labels[i]) != system(&self.labels[i - 1]) {
                let y = top + (i as u32 * ROW_H) as i32;
                cv.line((20, y), (PLOT_X.1, y), SUBTLE.mix(0.5).stroke_width(1))?;
            }
        }
        for (i, l) in self.labels.iter().enumerate() {
            cv.text(l, (PLOT_X.0 - 8, row_y(i)), 12.0, INK, HPos::Right, VPos::Center);
        }
        for (k, s) in self.series.iter().enumerate() {
            let color = COLORS[k.min(1)];
            for r in s.rows {
                let Some(i) = self.labels.iter().position(|l| *l == r.label) else { continue };
                let y = row_y(i) + series_dy(k, self.series.len());
                if let Some((lo, hi)) = r.ci {
                    cv.line((ax.x(lo), y), (ax.x(hi), y), color.stroke_width(2))?;
                }
                cv.root
                    .draw(&Circle::new((ax.x(r.ratio), y), 4, color.filled()))
                    .map_err(|e| e.to_string())?;
            }
        }
        // The axis.
        cv.line((PLOT_X.0, bottom), (PLOT_X.1, bottom), INK.stroke_width(1))?;
        for v in ax.ticks() {
            let x = ax.x(v);
            cv.line((x, bottom), (x, bottom + 4), INK.stroke_width(1))?;
            cv.text(&tick_label(v), (x, bottom + 7), 11.0, INK, HPos::Center, VPos::Top);
        }
        let mid = (PLOT_X.0 + PLOT_X.1) / 2;
        cv.text("ours ÷ paper (log scale)", (mid, bottom + 30), 12.0, INK, HPos::Center, VPos::Center);
        // The legend: the series, then the bands.
        let y = bottom + 50;
        let mut x = 20;
        for (k, s) in self.series.iter().enumerate() {
            let color = COLORS[k.min(1)];
            cv.line((x, y), (x + 24, y), color.stroke_width(2))?;
            cv.root.draw(&Circle::new((x + 12, y), 4, color.filled())).map_err(|e| e.to_string())?;
            // A long variant id (a grid's) is cut to the figure's width.
            let room = ((WIDTH as i32 - x - 40) / 7).max(8) as usize;
            let mut text = format!("{} ({})", s.info.id, s.role);
            if text.chars().count() > room {
                text = format!("{}…", text.chars().take(room - 1).collect::<String>());
            }
            cv.text(&text, (x + 30, y), 12.0, INK, HPos::Left, VPos::Center);
            x += 50 + (text.chars().count() as i32) * 7;
        }
        let y = y + 19;
        cv.rect((20, y - 6), (44, y + 6), MARGIN_SHADE.filled())?;
        let m = format!("equivalence margin {:.2}–{:.2}", MARGIN.0, MARGIN.1);
        cv.text(&m, (50, y), 12.0, INK, HPos::Left, VPos::Center);
        cv.rect((260, y - 6), (284, y + 6), BAND.filled())?;
        cv.text("within 2× (0.5–2)", (290, y), 12.0, INK, HPos::Left, VPos::Center);
        cv.text("dot: mean ratio; bar: its 95 % interval", (440, y), 12.0, SUBTLE, HPos::Left, VPos::Center);
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::derive::report_data::ReportData;
    use crate::render::table::{render, Csv};
    use crate::replication::pages::answer::{opening, Tally};
    use crate::replication::table3::table3;
    use qsweep_engine::env::SystemKind;
    use qsweep_engine::run_trial;
    use qsweep_engine::Algorithm;
    use qsweep_pipeline::cache::{Key, TrialRecord};
    use qsweep_pipeline::declared::{load_str, LoadedSpec, Override};
    use qsweep_pipeline::plan::{plan, Plan};
    use std::collections::HashMap;

    /// Mountain Car with reference values on both algorithms of a crisp and a fuzzy experiment.
    const PIPELINE: &str = "\
name: fp
seeds: 3
defaults: { max_episodes: 25 }
systems:
  mountain-car:
    crisp: { epsilon: 0.05, gamma: 0.95, alpha: 0.01, lambda: 0.6 }
    fuzzy: { epsilon: 0.05, gamma: 0.95, alpha: 0.01, lambda: 0.6 }
    success: { within: 400, streak: 1, max_episode_steps: 2000 }
    experiments:
      - id: 2
        repr: crisp
        vary: { x == x_dot: [2, 4] }
        fixed: { actions: 3 }
        reference:
          q0: { mean: 20, std: 5 }
          q-lambda: { mean: 3, std: 1 }
      - id: 3
        repr: fuzzy
        vary: { x: [3], x_dot: [3, 4] }
        fixed: { actions: 3 }
        reference:
          q-lambda: { mean: 400, std: 30 }
";

    fn data_of(sets: &[&str]) -> (Plan, HashMap<Key, TrialRecord>) {
        let overrides: Vec<Override> = sets.iter().map(|s| Override::parse(s).unwrap()).collect();
        let spec = load_str(PIPELINE, "fp.yaml", &overrides).unwrap();
        let p = plan(&LoadedSpec { spec, path: "fp.yaml".into(), variants: Vec::new() }, None).unwrap();
        let recs = p
            .unique_trials()
            .into_iter()
            .map(|(c, t)| (t.key, TrialRecord::new(c.clone(), t.seed, run_trial(c, t.seed), 0.0)))
            .collect();
        (p, recs)
    }

    #[test]
    fn rows_are_table3s_ratio_columns() {
        let (p, recs) = data_of(&[]);
        let data = ReportData::build(&p, &recs);
        let rows = rows_of(&data);
        assert_eq!(rows.len(), 3, "one row per reference value");
        assert_eq!(
            rows.iter().map(|r| r.label.as_str()).collect::<Vec<_>>(),
            [
                "Mountain Car · Exp 2 · Q(0)",
                "Mountain Car · Exp 2 · Q(λ)",
                "Mountain Car · Exp 3 · fuzzy Q(λ)"
            ]
        );
        let csv = render(&table3(&data), &Csv);
        let mut lines = csv.lines();
        let header: Vec<&str> = lines.next().unwrap().split(',').collect();
        let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
        let with_ref: Vec<Vec<&str>> =
            lines.map(|l| l.split(',').collect::<Vec<_>>()).filter(|r| !r[col("ratio")].is_empty()).collect();
        assert_eq!(with_ref.len(), rows.len());
        let num = |s: &str| s.parse::<f64>().unwrap();
        for (r, t) in rows.iter().zip(&with_ref) {
            assert_eq!(r.ratio, num(t[col("ratio")]), "{}", r.label);
            let (lo, hi) = r.ci.unwrap();
            assert_eq!((lo, hi), (num(t[col("ratio_lo")]), num(t[col("ratio_hi")])), "{}", r.label);
            assert!(lo <= r.ratio && r.ratio <= hi);
        }
    }

    #[test]
    fn the_axis_is_logarithmic_round_and_invertible() {
        let info = VariantInfo { id: "a".into(), title: None, exploratory: false };
        let row = |ratio: f64, ci| ForestRow {
            system: SystemKind::CartPole,
            experiment: "1".into(),
            algorithm: Algorithm::Q0,
            label: format!("r{ratio}"),
            ratio,
            ci,
            fresh: false,
        };
        let rows = [row(0.06, Some((0.05, 0.074))), row(3.0, Some((2.5, 3.3))), row(1.0, None)];
        let s = [Series { info: &info, role: "as written", rows: &rows, scored: &[], fit: Fit::default() }];
        let ax = axis_of(&s);
        assert_eq!(ax.domain, (0.05, 5.0));
        assert_eq!(ax.ticks(), [0.05, 0.1, 0.2, 0.5, 1.0, 2.0, 5.0]);
        assert_eq!(
            ax.ticks().iter().map(|&v| tick_label(v)).collect::<Vec<_>>(),
            ["0.05", "0.1", "0.2", "0.5", "1", "2", "5"]
        );
        assert_eq!((ax.x(0.05), ax.x(5.0)), PLOT_X);
        assert_eq!(ax.x(0.5), (PLOT_X.0 + PLOT_X.1) / 2, "log: 0.5 halfway between 0.05 and 5");
        assert_eq!(ax.x(1e-9), PLOT_X.0, "clamped");
        for v in [0.07, 0.5, 1.3, 4.0] {
            assert!((ax.value(f64::from(ax.x(v))) / v - 1.0).abs() < 0.01, "{v}");
        }
        let t = Tally::of(&s[0]);
        assert_eq!((t.rows, t.within_2x, t.whole_interval), (3, 1, 0));
        // Nothing to plot: the default 2× band only.
        assert_eq!(axis_of(&[]).domain, (0.5, 2.0));
    }

    /// The plotted dots and bars, read back from the SVG, are the rows' ratios and intervals.
    #[test]
    fn the_figure_plots_the_rows_and_is_deterministic() {
        let (p, recs) = data_of(&[]);
        let (q, recs_q) = data_of(&["systems.mountain-car.crisp.alpha=0.2"]);
        let data = [ReportData::build(&p, &recs), ReportData::build(&q, &recs_q)];
        let infos = [
            VariantInfo { id: "as-written".into(), title: None, exploratory: false },
            VariantInfo { id: "fast".into(), title: None, exploratory: false },
        ];
        let rows: Vec<Vec<ForestRow>> = data.iter().map(rows_of).collect();
        let series: Vec<Series> = ["as written", "best declared"]
            .iter()
            .enumerate()
            .map(|(k, role)| Series {
                info: &infos[k],
                role,
                rows: &rows[k],
                scored: &[],
                fit: Fit::default(),
            })
            .collect();
        let d = forest_figure("fp", &series, (true, true)).unwrap();
        let svg = d.svg.unwrap();
        let doc = roxmltree::Document::parse(&svg).unwrap();
        let (w, h) = figure_size(3);
        assert_eq!(doc.root_element().attribute("width"), Some(w.to_string().as_str()));
        assert_eq!(doc.root_element().attribute("height"), Some(h.to_string().as_str()));
        let ax = axis_of(&series);
        let hex = |c: RGBColor| format!("#{:02X}{:02X}{:02X}", c.0, c.1, c.2);
        for (k, s) in series.iter().enumerate() {
            let mut dots: Vec<(i32, i32)> = doc
                .descendants()
                .filter(|n| n.has_tag_name("circle") && n.attribute("fill") == Some(hex(COLORS[k]).as_str()))
                .map(|n| {
                    (n.attribute("cx").unwrap().parse().unwrap(), n.attribute("cy").unwrap().parse().unwrap())
                })
                .collect();
            let legend = dots.pop().unwrap();
            assert!(legend.1 > row_y(2), "the legend's dot comes last");
            assert_eq!(dots.len(), s.rows.len(), "one dot per row");
            for (i, (r, dot)) in s.rows.iter().zip(&dots).enumerate() {
                assert_eq!(*dot, (ax.x(r.ratio), row_y(i) + series_dy(k, 2)), "{}", r.label);
                assert!((ax.value(f64::from(dot.0)) / r.ratio - 1.0).abs() < 0.02);
            }
        }
        // Each interval is a bar of its series' colour from lo to hi.
        for (k, s) in series.iter().enumerate() {
            for (i, r) in s.rows.iter().enumerate() {
                let (lo, hi) = r.ci.unwrap();
                let y = row_y(i) + series_dy(k, 2);
                let seg = format!("M{},{y} L{},{y}", ax.x(lo), ax.x(hi));
                assert!(svg.contains(&seg), "bar {seg} of {} in\n{svg}", r.label);
            }
        }
        for t in ["Mountain Car · Exp 3 · fuzzy Q(λ)", "as-written (as written)", "fast (best declared)"] {
            assert!(svg.contains(t), "{t}");
        }
        let png = d.png.unwrap();
        let reader = png::Decoder::new(std::io::Cursor::new(png.as_slice())).read_info().unwrap();
        assert_eq!((reader.info().width, reader.info().height), (w, h));
        let again = forest_figure("fp", &series, (true, true)).unwrap();
        assert_eq!((again.svg.unwrap(), again.png.unwrap()), (svg, png));

        // The opening states the counts of both series.
        let text = opening(&series, None);
        let t = Tally::of(&series[1]);
        assert!(
            text.starts_with(&format!(
                "Under the best-ranked declared variant, fast, {} of 3 Table III rows replicate",
                t.replicating[2]
            )),
            "{text}"
        );
        let within =
            if t.within_2x == 1 { "1 row is".to_string() } else { format!("{} rows are", t.within_2x) };
        assert!(text.contains(&format!("By ratio alone, {within} within 2×")), "{text}");
        let t = Tally::of(&series[0]);
        assert!(
            text.contains(&format!("As written (as-written): {} of 3 replicate", t.replicating[2])),
            "{text}"
        );
    }
}
