//! No clipped text: in the figures of reports with one, two and three experiments per system, one
//! algorithm (a 500 px figure) or both (1000 px), raced or not, and with variants (difference
//! figures), every `<text>` lies inside its SVG. A text's extent is estimated with the font the
//! figures embed (`crates/qsweep-report/assets/fonts`, read here with ab_glyph) at the size the PNG draws it (1.24
//! times the SVG's `font-size`), which bounds the SVG's own; and the heatmaps' embedded images
//! draw each cell as a uniform block of pixels.

use crate::helpers::Sandbox;
use ab_glyph::{Font, FontRef, PxScale, ScaleFont};
use std::path::{Path, PathBuf};

/// The font the figures' text is drawn with.
static FONT: &[u8] = include_bytes!("../../crates/qsweep-report/assets/fonts/DejaVuSans-subset.ttf");

/// How many times larger the PNG draws a text than the SVG's `font-size` says.
const PNG_SCALE: f64 = 1.24;

/// Advance width of `text` at `em` pixels per em, kerned.
fn advance(font: &FontRef, text: &str, em: f64) -> f64 {
    let per_em = font.height_unscaled() / font.units_per_em().unwrap();
    let sf = font.as_scaled(PxScale::from(em as f32 * per_em));
    let mut w = 0.0;
    let mut prev = None;
    for c in text.chars() {
        let id = sf.glyph_id(c);
        if let Some(p) = prev {
            w += sf.kern(p, id);
        }
        w += sf.h_advance(id);
        prev = Some(id);
    }
    f64::from(w)
}

/// Every text of an SVG that reaches past its viewBox, described.
fn clipped(svg: &str) -> Vec<String> {
    let font = FontRef::try_from_slice(FONT).unwrap();
    let doc = roxmltree::Document::parse(svg).unwrap();
    let root = doc.root_element();
    let view: Vec<f64> = root.attribute("viewBox").unwrap().split(' ').map(|v| v.parse().unwrap()).collect();
    let (x0, y0, x1, y1) = (view[0], view[1], view[0] + view[2], view[1] + view[3]);
    let mut out = Vec::new();
    for t in doc.descendants().filter(|n| n.has_tag_name("text")) {
        let inherited = |a: &str| t.ancestors().find_map(|n| n.attribute(a));
        let num = |a: &str| inherited(a).unwrap_or("0").parse::<f64>().unwrap();
        let text = t.text().unwrap_or_default();
        let em = num("font-size") * PNG_SCALE;
        let w = advance(&font, text, em);
        let (x, y) = (num("x"), num("y"));
        // Along the text: from its anchor; across it: one em, placed by its `dy`.
        let (start, end) = match inherited("text-anchor").unwrap_or("start") {
            "middle" => (-w / 2.0, w / 2.0),
            "end" => (-w, 0.0),
            _ => (0.0, w),
        };
        let (top, bottom) = match t.attribute("dy") {
            Some("0.76em") => (0.0, em),
            Some("-0.5ex") => (-em, 0.0),
            _ => (-em / 2.0, em / 2.0),
        };
        let (l, r, u, d) = match t.attribute("transform") {
            // rotate(270, x, y): reads upwards, `start..end` running up from (x, y).
            Some(tr) if tr.starts_with("rotate(270") => (x + top, x + bottom, y - end, y - start),
            Some(tr) => panic!("an unexpected transform {tr}"),
            None => (x + start, x + end, y + top, y + bottom),
        };
        if l < x0 || r > x1 || u < y0 || d > y1 {
            out.push(format!("{text:?} at {em:.1} px spans x {l:.0}..{r:.0}, y {u:.0}..{d:.0} of {view:?}"));
        }
    }
    out
}

fn svgs(dir: &Path, out: &mut Vec<PathBuf>) {
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.is_dir() {
            svgs(&p, out);
        } else if p.extension().is_some_and(|x| x == "svg") {
            out.push(p);
        }
    }
}

/// A Ball-Beam pipeline of `n` experiments (their titles of the paper's lengths and one longer),
/// running `algorithms`, raced or not, with `variants` (YAML) or none.
fn pipeline(n: usize, algorithms: &str, race: bool, variants: &str) -> String {
    let titles = ["Bins only", "Fuzzy sets + Actions", "Bins, actions and a title longer than the paper's"];
    let mut y = format!(
        "name: figtext\nseeds: 2\n{}defaults:\n  max_episodes: 20\nsystems:\n  ball-beam:\n\
         \x20   crisp: {{ epsilon: 1.0e-6, gamma: 0.9, alpha: 0.1, lambda: 0.9 }}\n\
         \x20   fuzzy: {{ epsilon: 1.0e-6, gamma: 0.995, alpha: 0.1, lambda: 0.5 }}\n\
         \x20   success: {{ steps: 2000 }}\n    experiments:\n",
        if race { "race: { confidence: 0.95, batch: 1, max_seeds: 3 }\n" } else { "" }
    );
    for (k, title) in titles.iter().enumerate().take(n) {
        let (repr, vary) = match k {
            0 => ("crisp", "{ x: [2, 3, 4], x_dot: [2, 3] }, fixed: { actions: 3 }"),
            1 => ("fuzzy", "{ x == x_dot: [2, 3], actions: [2, 3] }"),
            _ => ("crisp", "{ actions: [2, 3, 4] }, fixed: { x: 3, x_dot: 3 }"),
        };
        y.push_str(&format!(
            "      - {{ id: {}, title: \"{title}\", repr: {repr}, algorithms: {algorithms}, vary: {vary} }}\n",
            k + 1
        ));
    }
    y.push_str(variants);
    y
}

/// Write the report of `yaml`; every SVG it holds.
fn report(yaml: &str) -> (Sandbox, Vec<PathBuf>) {
    let sb = Sandbox::new();
    let p = sb.write("figtext.yaml", yaml);
    let out = sb.path("rep");
    let args = ["run", p.to_str().unwrap(), "--quiet", "--formats", "svg,md", "--out", out.to_str().unwrap()];
    sb.qsweep(&args).assert().success();
    let mut found = Vec::new();
    svgs(&out, &mut found);
    found.sort();
    (sb, found)
}

#[test]
fn every_figure_text_lies_inside_its_figure() {
    let variants =
        "variants:\n  - { id: base }\n  - { id: slower, set: { systems.ball-beam.crisp.alpha: 0.05 } }\n";
    let mut problems = Vec::new();
    let mut widths = std::collections::BTreeSet::new();
    let mut checked = 0;
    for (n, algorithms, race, variants) in [
        (1, "[q0]", false, ""),
        (2, "[q0]", false, ""),
        (3, "[q0]", true, ""),
        (1, "[q0, q-lambda]", false, ""),
        (2, "[q0, q-lambda]", true, ""),
        (3, "[q0, q-lambda]", false, ""),
        (1, "[q-lambda]", false, variants),
    ] {
        let (_sb, files) = report(&pipeline(n, algorithms, race, variants));
        assert!(files.iter().any(|f| f.ends_with("ball-beam.svg")), "{files:?}");
        assert!(files.iter().any(|f| f.ends_with("ball-beam-curves.svg")), "{files:?}");
        if !variants.is_empty() {
            assert!(
                files.iter().any(|f| f.file_name().unwrap().to_string_lossy().starts_with("diff-")),
                "{files:?}"
            );
        }
        for f in &files {
            let svg = std::fs::read_to_string(f).unwrap();
            widths.insert(svg.split("width=\"").nth(1).unwrap().split('"').next().unwrap().to_string());
            for p in clipped(&svg) {
                problems.push(format!(
                    "{n} experiments {algorithms}{}: {}: {p}",
                    if race { " raced" } else { "" },
                    f.display()
                ));
            }
            checked += 1;
        }
    }
    assert!(widths.contains("500") && widths.contains("1000"), "{widths:?}");
    assert!(checked >= 14);
    assert!(
        problems.is_empty(),
        "{} texts reach past their figure:\n{}",
        problems.len(),
        problems.join("\n")
    );
}

#[test]
fn the_extent_check_sees_a_clipped_text() {
    let svg = |x: i32, anchor: &str, transform: &str| {
        format!(
            "<svg width=\"100\" height=\"50\" viewBox=\"0 0 100 50\" xmlns=\"http://www.w3.org/2000/svg\">\
             <g text-anchor=\"{anchor}\" font-size=\"10\"><text x=\"{x}\" y=\"25\" dy=\"0.5ex\"{transform}>wide text here</text></g></svg>"
        )
    };
    assert!(clipped(&svg(2, "start", "")).is_empty());
    assert_eq!(clipped(&svg(40, "start", "")).len(), 1);
    assert_eq!(clipped(&svg(2, "middle", "")).len(), 1);
    assert_eq!(clipped(&svg(60, "end", "")).len(), 1);
    // Rotated, it runs up and down from its centre: 50 px tall is not enough.
    assert_eq!(clipped(&svg(50, "middle", " transform=\"rotate(270, 50, 25)\"")).len(), 1);
}
