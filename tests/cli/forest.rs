//! The comparison folder's opening and forest plot (`figures/forest.svg`), end to end: the dots
//! the SVG draws, read back through its own axis, are the `ratio` column of each plotted variant's
//! `table3.csv`, and the pages open with the counts of those rows.

use crate::helpers::{csv_rows, Sandbox};
use std::collections::BTreeMap;

/// The as-written and best-declared series' colours (`forest::COLORS`).
const COLORS: [&str; 2] = ["#0072B2", "#D55E00"];

/// Points (x, y) or ticks (x, value).
type Points = Vec<(f64, f64)>;

/// Per series colour, the dots' (x, y) in drawing order; and the axis's (x, value) ticks.
fn read_svg(svg: &str) -> (BTreeMap<&'static str, Points>, Points) {
    let doc = roxmltree::Document::parse(svg).unwrap();
    let mut dots = BTreeMap::new();
    for c in COLORS {
        let pts = doc
            .descendants()
            .filter(|n| n.has_tag_name("circle") && n.attribute("fill") == Some(c))
            .map(|n| {
                (n.attribute("cx").unwrap().parse().unwrap(), n.attribute("cy").unwrap().parse().unwrap())
            })
            .collect();
        dots.insert(c, pts);
    }
    // Tick labels: the numeric texts, centred under their tick.
    let ticks = doc
        .descendants()
        .filter(|n| n.has_tag_name("text"))
        .filter_map(|n| Some((n.attribute("x")?.parse().ok()?, n.text()?.trim().parse().ok()?)))
        .collect();
    (dots, ticks)
}

#[test]
fn forest_plot_dots_are_table3_ratios_and_the_page_opens_with_the_answer() {
    let sb = Sandbox::new();
    let p = sb.fixture("variants.yaml");
    let out = sb.path("rep");
    sb.qsweep(&["run", p.to_str().unwrap(), "--quiet", "--out", out.to_str().unwrap()]).assert().success();
    let svg = std::fs::read_to_string(out.join("figures/forest.svg")).unwrap();
    assert!(svg.len() < 60_000, "small: {} bytes", svg.len());
    let (dots, ticks) = read_svg(&svg);
    assert!(ticks.len() >= 3, "{ticks:?}");
    // The axis from its outermost ticks: ln(value) linear in x.
    let ln = qsweep_engine::math::ln;
    let ((x0, v0), (x1, v1)) = (ticks[0], ticks[ticks.len() - 1]);
    let ln_value = |x: f64| ln(v0) + (x - x0) / (x1 - x0) * (ln(v1) - ln(v0));
    let px = (ln(v1) - ln(v0)) / (x1 - x0); // ln units per pixel

    // The plotted variants: as written, and the top-ranked declared one.
    let variants = csv_rows(&std::fs::read_to_string(out.join("variants.csv")).unwrap());
    let best = variants.iter().find(|r| r["exploratory"] == "no").unwrap()["variant"].clone();
    let plotted = if best == "as-written" { vec!["as-written"] } else { vec!["as-written", best.as_str()] };
    let readme = std::fs::read_to_string(out.join("README.md")).unwrap();
    for (k, id) in plotted.iter().enumerate() {
        let t3 = csv_rows(&std::fs::read_to_string(out.join(id).join("table3.csv")).unwrap());
        let ratios: Vec<f64> =
            t3.iter().filter(|r| !r["ratio"].is_empty()).map(|r| r["ratio"].parse().unwrap()).collect();
        assert_eq!(ratios.len(), 2, "{id}: both Table III rows have a reference");
        let mut got = dots[COLORS[k]].clone();
        got.pop(); // the legend's
        assert_eq!(got.len(), ratios.len(), "{id}: one dot per row");
        for (dot, want) in got.iter().zip(&ratios) {
            // Within the pixel rounding of the dot's position.
            assert!((ln_value(dot.0) - ln(*want)).abs() <= px, "{id}: dot at {dot:?} ≠ ratio {want}");
        }
        let within = ratios.iter().filter(|r| (0.5..=2.0).contains(*r)).count();
        let said = if plotted.len() == 1 || k == 1 {
            format!("By ratio alone, {within} {} within 2×", if within == 1 { "row is" } else { "rows are" })
        } else {
            format!("by ratio {within} within 2×")
        };
        assert!(readme.contains(&said), "{said} in\n{readme}");
    }
    // The answer and its figure come before the list of variants, on both pages.
    let html = std::fs::read_to_string(out.join("index.html")).unwrap();
    let at = |page: &str, s: &str| page.find(s).unwrap_or_else(|| panic!("{s} in\n{page}"));
    assert!(at(&html, "id=\"answer\"") < at(&html, "src=\"figures/forest.svg\""));
    assert!(at(&html, "src=\"figures/forest.svg\"") < at(&html, "href=\"as-written/index.html\""));
    assert!(at(&readme, "(figures/forest.svg)") < at(&readme, "(as-written/README.md)"));
    let manifest = std::fs::read_to_string(out.join("manifest.json")).unwrap();
    assert!(manifest.contains("\"figures/forest.svg\""), "{manifest}");
}
