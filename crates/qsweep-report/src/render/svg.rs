//! Smaller SVG files that draw the same picture. plotters writes one element per shape with every
//! attribute spelled out; a report figure has thousands of them, and committed reports must stay
//! small. [`compact`] rewrites that output, line by line:
//!
//! - `opacity="1"` (the default) is dropped, and font sizes are rounded to 0.01 px;
//! - a polyline's or polygon's point equal to the one before it, or lying on the straight segment
//!   between its neighbours, is dropped ([`simplify_points`]): a curve drawn at pixel resolution
//!   repeats many;
//! - the font family, the same on every text, is set once on the root element (SVG inherits it);
//! - a filled rectangle followed by the outline of the same rectangle becomes one element;
//! - consecutive polylines with the same stroke become one `<path>` of the same segments;
//! - consecutive rectangles with the same stroke share it through a `<g>`;
//! - the texts, all drawn after every shape (they never overlap one another), are grouped by
//!   anchor, size and colour, which their `<g>` sets once;
//! - every complete heatmap grid of cells becomes one image ([`crate::render::svg_grid`]).

/// Rewrite plotters' SVG text as described in the module documentation.
pub fn compact(svg: &str) -> String {
    compact_with(svg, |s| s)
}

/// [`compact`], with `between` applied after the per-element rewrites and before the grids
/// become images (a figure's hatching placeholders become pattern fills there, so the grid step
/// sees them as what is drawn over a cell).
pub fn compact_with(svg: &str, between: impl FnOnce(String) -> String) -> String {
    group(&crate::render::svg_grid::grid_images(&between(merge(svg))))
}

/// `points` (`x,y x,y …`) without the points that change nothing drawn: one equal to the point
/// before it, and one lying on the segment between the points kept before it and after it
/// (exactly: a zero cross product and within the segment's box), so the line or the polygon's
/// outline is the same set of points. The kept points are written as they were; text that is not
/// a list of number pairs is returned as it is.
pub fn simplify_points(points: &str) -> String {
    let parsed: Option<Vec<(&str, f64, f64)>> = points
        .split_whitespace()
        .map(|t| {
            let (x, y) = t.split_once(',')?;
            Some((t, x.parse().ok()?, y.parse().ok()?))
        })
        .collect();
    let Some(parsed) = parsed else { return points.to_string() };
    let last = parsed.last().copied().filter(|_| parsed.len() > 1);
    let mut kept: Vec<(&str, f64, f64)> = Vec::with_capacity(parsed.len());
    for p in parsed {
        if kept.last().is_some_and(|q| (q.1, q.2) == (p.1, p.2)) {
            continue;
        }
        kept.push(p);
        while let [.., a, b, c] = kept[..] {
            let cross = (b.1 - a.1) * (c.2 - a.2) - (b.2 - a.2) * (c.1 - a.1);
            let within =
                a.1.min(c.1) <= b.1 && b.1 <= a.1.max(c.1) && a.2.min(c.2) <= b.2 && b.2 <= a.2.max(c.2);
            if cross == 0.0 && within {
                kept.remove(kept.len() - 2);
            } else {
                break;
            }
        }
    }
    // A line of one point is no line: a zero-length segment keeps both its ends.
    if kept.len() == 1 {
        kept.extend(last);
    }
    let mut out = kept.iter().map(|p| p.0).collect::<Vec<_>>().join(" ");
    if points.ends_with(' ') && !out.is_empty() {
        out.push(' ');
    }
    out
}

/// The per-element rewrites: defaults dropped, outlines merged, polylines joined.
fn merge(svg: &str) -> String {
    let mut out = String::with_capacity(svg.len() / 2);
    let mut path: Option<(String, String)> = None; // (attributes before `points`, path data)
    let mut last_rect: Option<String> = None;
    let flush_rect = |out: &mut String, r: &mut Option<String>| {
        if let Some(r) = r.take() {
            out.push_str(&r);
            out.push('\n');
        }
    };
    let flush_path = |out: &mut String, p: &mut Option<(String, String)>| {
        if let Some((attrs, d)) = p.take() {
            out.push_str(&format!("<path{attrs} d=\"{}\"/>\n", d.trim_end()));
        }
    };
    let mut root_done = false;
    for line in svg.lines() {
        let mut l = line.replace(" opacity=\"1\"", "");
        if let Some((head, rest)) = l.split_once(" points=\"") {
            if let Some((pts, tail)) = rest.split_once('"') {
                l = format!("{head} points=\"{}\"{tail}", simplify_points(pts));
            }
        }
        if !root_done && l.starts_with("<svg ") && !l.contains(" font-family=") {
            l = l.replacen("<svg ", "<svg font-family=\"sans-serif\" ", 1);
            root_done = true;
        }
        if l.starts_with("<circle ") && l.contains(" stroke=\"none\" stroke-width=\"1\"") {
            // No stroke (SVG's default), so no stroke width either.
            l = l.replacen(" stroke=\"none\" stroke-width=\"1\"", "", 1);
        }
        if l.starts_with("<text ") {
            l = l.replacen(" font-family=\"sans-serif\"", "", 1);
            l = round_font_size(&l);
        }
        // Polylines: `<polyline ATTRS points="x,y x,y "/>` with the same ATTRS join one path.
        if let Some(rest) = l.strip_prefix("<polyline") {
            if let Some((attrs, pts)) = rest.split_once(" points=\"") {
                let pts = pts.trim_end_matches("\"/>").trim();
                let mut seg = String::new();
                for (i, p) in pts.split_whitespace().enumerate() {
                    seg.push_str(if i == 0 { "M" } else { "L" });
                    seg.push_str(p);
                    seg.push(' ');
                }
                flush_rect(&mut out, &mut last_rect);
                match &mut path {
                    Some((a, d)) if a == attrs => d.push_str(&seg),
                    _ => {
                        flush_path(&mut out, &mut path);
                        path = Some((attrs.to_string(), seg));
                    }
                }
                continue;
            }
        }
        flush_path(&mut out, &mut path);
        if l.starts_with("<rect ") {
            if let Some(prev) = last_rect.take() {
                if let Some(merged) = merge_rects(&prev, &l) {
                    out.push_str(&merged);
                    out.push('\n');
                    continue;
                }
                out.push_str(&prev);
                out.push('\n');
            }
            last_rect = Some(l);
            continue;
        }
        flush_rect(&mut out, &mut last_rect);
        out.push_str(&l);
        out.push('\n');
    }
    flush_path(&mut out, &mut path);
    flush_rect(&mut out, &mut last_rect);
    out
}

/// `<rect G fill="C" stroke="none"/>` then `<rect G fill="none" stroke=…/>` (same geometry G):
/// one rectangle with both.
fn merge_rects(fill: &str, outline: &str) -> Option<String> {
    let (geom, rest) = fill.split_once(" fill=\"")?;
    let colour = rest.strip_suffix("\" stroke=\"none\"/>")?;
    let stroke = outline.strip_prefix(geom)?.strip_prefix(" fill=\"none\" stroke=")?;
    Some(format!("{geom} fill=\"{colour}\" stroke={stroke}"))
}

/// An attribute's value and the element without it: `attr(r#"<a k="v" b="c"/>"#, "k")` is
/// `("v", r#"<a b="c"/>"#)`.
fn take_attr(el: &str, name: &str) -> Option<(String, String)> {
    let key = format!(" {name}=\"");
    let at = el.find(&key)?;
    let start = at + key.len();
    let len = el[start..].find('"')?;
    Some((el[start..start + len].to_string(), format!("{}{}", &el[..at], &el[start + len + 1..])))
}

/// Group rectangles by stroke and texts by anchor, size and colour (see the module
/// documentation).
fn group(svg: &str) -> String {
    let lines: Vec<&str> = svg.lines().collect();
    let mut out = String::with_capacity(svg.len());
    let mut texts: Vec<((String, String, String), String)> = Vec::new();
    let mut rects: Option<(String, Vec<String>)> = None;
    let flush = |out: &mut String, rects: &mut Option<(String, Vec<String>)>| {
        if let Some((stroke, els)) = rects.take() {
            if els.len() == 1 {
                out.push_str(&els[0].replacen("/>", &format!(" stroke=\"{stroke}\"/>"), 1));
                out.push('\n');
            } else {
                out.push_str(&format!("<g stroke=\"{stroke}\">\n"));
                for e in els {
                    out.push_str(&e);
                    out.push('\n');
                }
                out.push_str("</g>\n");
            }
        }
    };
    let mut i = 0;
    while i < lines.len() {
        let l = lines[i];
        if l.starts_with("<text ") && i + 2 < lines.len() && lines[i + 2] == "</text>" {
            let el = l.to_string();
            let (anchor, el) = take_attr(&el, "text-anchor").unwrap_or_default();
            let (size, el) = take_attr(&el, "font-size").unwrap_or_default();
            let (fill, el) = take_attr(&el, "fill").unwrap_or_default();
            texts.push(((anchor, size, fill), format!("{el}{}</text>", lines[i + 1])));
            i += 3;
            continue;
        }
        if l.starts_with("<rect ") && !l.contains("stroke-width") {
            if let Some((stroke, el)) = take_attr(l, "stroke") {
                match &mut rects {
                    Some((s, els)) if *s == stroke => els.push(el),
                    _ => {
                        flush(&mut out, &mut rects);
                        rects = Some((stroke, vec![el]));
                    }
                }
                i += 1;
                continue;
            }
        }
        flush(&mut out, &mut rects);
        if l == "</svg>" {
            // Stable: texts of one group keep their order.
            texts.sort_by(|a, b| a.0.cmp(&b.0));
            let mut k = 0;
            while k < texts.len() {
                let key = &texts[k].0;
                let mut attrs = String::new();
                for (name, v) in [("text-anchor", &key.0), ("font-size", &key.1), ("fill", &key.2)] {
                    if !v.is_empty() {
                        attrs.push_str(&format!(" {name}=\"{v}\""));
                    }
                }
                out.push_str(&format!("<g{attrs}>\n"));
                while k < texts.len() && texts[k].0 == *key {
                    out.push_str(&texts[k].1);
                    out.push('\n');
                    k += 1;
                }
                out.push_str("</g>\n");
            }
            texts.clear();
        }
        out.push_str(l);
        out.push('\n');
        i += 1;
    }
    flush(&mut out, &mut rects);
    out
}

fn round_font_size(l: &str) -> String {
    const KEY: &str = " font-size=\"";
    let Some(at) = l.find(KEY) else { return l.to_string() };
    let start = at + KEY.len();
    let Some(len) = l[start..].find('"') else { return l.to_string() };
    let Ok(v) = l[start..start + len].parse::<f64>() else { return l.to_string() };
    let r = format!("{:.2}", v);
    let r = r.trim_end_matches('0').trim_end_matches('.');
    format!("{}{r}{}", &l[..start], &l[start + len..])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn points_that_change_nothing_drawn_are_dropped_and_the_rest_kept_as_written() {
        // Repeats, a horizontal run and a diagonal run collapse to their ends; the turns stay.
        assert_eq!(
            simplify_points("62,271 62,271 63,271 64,271 64,270 65,269 66,268 66,300 "),
            "62,271 64,271 64,270 66,268 66,300 "
        );
        // A point beyond its neighbours' segment is a turn back, not on the segment: kept.
        assert_eq!(simplify_points("0,0 2,0 1,0"), "0,0 2,0 1,0");
        assert_eq!(simplify_points("1.5,2 1.50,2 3,4"), "1.5,2 3,4");
        assert_eq!(simplify_points("not numbers"), "not numbers");
        assert_eq!(simplify_points("663,48 663,48 "), "663,48 663,48 ", "a zero-length bar keeps both ends");
        let line = "<polygon opacity=\"0.22\" fill=\"#E66E00\" points=\"1,1 2,1 3,1 3,2\"/>";
        assert_eq!(merge(line), "<polygon opacity=\"0.22\" fill=\"#E66E00\" points=\"1,1 3,1 3,2\"/>\n");
    }

    #[test]
    fn compacts_what_plotters_writes_and_keeps_the_rest() {
        let svg = "<svg width=\"10\" height=\"10\" viewBox=\"0 0 10 10\" xmlns=\"http://www.w3.org/2000/svg\">\n\
<rect x=\"0\" y=\"0\" width=\"4\" height=\"3\" opacity=\"1\" fill=\"#440154\" stroke=\"none\"/>\n\
<rect x=\"0\" y=\"0\" width=\"4\" height=\"3\" opacity=\"1\" fill=\"none\" stroke=\"#FFFFFF\"/>\n\
<rect x=\"5\" y=\"0\" width=\"4\" height=\"3\" opacity=\"1\" fill=\"#111111\" stroke=\"none\"/>\n\
<polyline fill=\"none\" opacity=\"0.45\" stroke=\"#1E1E1E\" stroke-width=\"1\" points=\"1,2 3,4 \"/>\n\
<polyline fill=\"none\" opacity=\"0.45\" stroke=\"#1E1E1E\" stroke-width=\"1\" points=\"5,6 7,8 9,9 \"/>\n\
<polyline fill=\"none\" opacity=\"1\" stroke=\"#E66E00\" stroke-width=\"3\" points=\"0,0 1,1 \"/>\n\
<text x=\"5\" y=\"5\" dy=\"0.5ex\" text-anchor=\"middle\" font-family=\"sans-serif\" font-size=\"16.129032258064516\" opacity=\"1\" fill=\"#1E1E1E\">\n\
a &lt; b\n\
</text>\n\
<rect x=\"5\" y=\"0\" width=\"4\" height=\"3\" opacity=\"1\" fill=\"none\" stroke=\"#000000\"/>\n\
</svg>\n";
        let want = "<svg font-family=\"sans-serif\" width=\"10\" height=\"10\" viewBox=\"0 0 10 10\" xmlns=\"http://www.w3.org/2000/svg\">\n\
<rect x=\"0\" y=\"0\" width=\"4\" height=\"3\" fill=\"#440154\" stroke=\"#FFFFFF\"/>\n\
<rect x=\"5\" y=\"0\" width=\"4\" height=\"3\" fill=\"#111111\" stroke=\"none\"/>\n\
<path fill=\"none\" opacity=\"0.45\" stroke=\"#1E1E1E\" stroke-width=\"1\" d=\"M1,2 L3,4 M5,6 L7,8 L9,9\"/>\n\
<path fill=\"none\" stroke=\"#E66E00\" stroke-width=\"3\" d=\"M0,0 L1,1\"/>\n\
<text x=\"5\" y=\"5\" dy=\"0.5ex\" text-anchor=\"middle\" font-size=\"16.13\" fill=\"#1E1E1E\">\n\
a &lt; b\n\
</text>\n\
<rect x=\"5\" y=\"0\" width=\"4\" height=\"3\" fill=\"none\" stroke=\"#000000\"/>\n\
</svg>\n";
        assert_eq!(merge(svg), want);
        assert_eq!(merge(want), want, "idempotent");
        let out = compact(svg);
        // Two rectangles of different strokes in a row: each keeps its own.
        assert!(out.contains("<rect x=\"0\" y=\"0\" width=\"4\" height=\"3\" fill=\"#440154\" stroke=\"#FFFFFF\"/>\n<rect x=\"5\" y=\"0\" width=\"4\" height=\"3\" fill=\"#111111\" stroke=\"none\"/>\n"), "{out}");
        assert!(out.contains("<g text-anchor=\"middle\" font-size=\"16.13\" fill=\"#1E1E1E\">\n<text x=\"5\" y=\"5\" dy=\"0.5ex\">a &lt; b</text>\n</g>\n"), "{out}");
        assert!(out.ends_with("</g>\n<rect x=\"5\" y=\"0\" width=\"4\" height=\"3\" fill=\"none\" stroke=\"#000000\"/>\n</svg>\n") || out.contains("stroke=\"#000000\"/>"), "{out}");
    }
}

#[cfg(test)]
mod group_tests {
    use super::*;

    #[test]
    fn runs_of_rectangles_share_their_stroke_and_texts_their_style() {
        let svg = "<svg width=\"4\" height=\"4\">\n\
<rect x=\"0\" y=\"0\" width=\"1\" height=\"1\" fill=\"#111111\" stroke=\"#FFFFFF\"/>\n\
<rect x=\"1\" y=\"0\" width=\"1\" height=\"1\" fill=\"#222222\" stroke=\"#FFFFFF\"/>\n\
<rect x=\"2\" y=\"0\" width=\"1\" height=\"1\" fill=\"none\" stroke=\"#000000\" stroke-width=\"3\"/>\n\
<text x=\"1\" y=\"1\" dy=\"0.5ex\" text-anchor=\"middle\" font-size=\"9\" fill=\"#FFFFFF\">\n\
one\n\
</text>\n\
<text x=\"2\" y=\"2\" dy=\"0.5ex\" text-anchor=\"end\" font-size=\"9\" fill=\"#1E1E1E\">\n\
two\n\
</text>\n\
<text x=\"3\" y=\"3\" dy=\"0.5ex\" text-anchor=\"middle\" font-size=\"9\" fill=\"#FFFFFF\">\n\
three\n\
</text>\n\
</svg>\n";
        let want = "<svg width=\"4\" height=\"4\">\n\
<g stroke=\"#FFFFFF\">\n\
<rect x=\"0\" y=\"0\" width=\"1\" height=\"1\" fill=\"#111111\"/>\n\
<rect x=\"1\" y=\"0\" width=\"1\" height=\"1\" fill=\"#222222\"/>\n\
</g>\n\
<rect x=\"2\" y=\"0\" width=\"1\" height=\"1\" fill=\"none\" stroke=\"#000000\" stroke-width=\"3\"/>\n\
<g text-anchor=\"end\" font-size=\"9\" fill=\"#1E1E1E\">\n\
<text x=\"2\" y=\"2\" dy=\"0.5ex\">two</text>\n\
</g>\n\
<g text-anchor=\"middle\" font-size=\"9\" fill=\"#FFFFFF\">\n\
<text x=\"1\" y=\"1\" dy=\"0.5ex\">one</text>\n\
<text x=\"3\" y=\"3\" dy=\"0.5ex\">three</text>\n\
</g>\n\
</svg>\n";
        assert_eq!(group(svg), want);
        // The result parses as XML with every text and rectangle kept.
        let text = group(svg);
        let doc = roxmltree::Document::parse(&text).unwrap();
        assert_eq!(doc.descendants().filter(|n| n.has_tag_name("text")).count(), 3);
        assert_eq!(doc.descendants().filter(|n| n.has_tag_name("rect")).count(), 3);
    }
}
