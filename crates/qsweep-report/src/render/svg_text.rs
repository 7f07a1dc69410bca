//! A figure's text as SVG `<text>` elements, written here (not by plotters) so that the text is
//! escaped by this crate's one rule for SVG ([`crate::render::escape::xml`]). The element is laid out as
//! plotters' SVG backend writes it (the element on three lines: start tag, text, end tag; the
//! same attributes in the same order), which is what [`crate::render::svg::compact`] groups.

use crate::render::escape;
use crate::render::glyphs::TextCmd;
use plotters::style::text_anchor::{HPos, VPos};

/// The SVG font size of a text of size `size` (pixels per em, as drawn in the PNG) is
/// `size / SVG_FONT_DIVISOR`, as plotters' SVG backend wrote it, so the SVG text is smaller than
/// the PNG's.
pub const SVG_FONT_DIVISOR: f64 = 1.24;

/// The `<text>` element drawing `t`, on three lines, each ending in a line break.
pub fn element(t: &TextCmd) -> String {
    let (x, y) = t.at;
    let dy = match t.v {
        VPos::Top => "0.76em",
        VPos::Center => "0.5ex",
        VPos::Bottom => "-0.5ex",
    };
    let anchor = match t.h {
        HPos::Left => "start",
        HPos::Right => "end",
        HPos::Center => "middle",
    };
    let c = &t.color;
    let rotate = if t.rotate { format!(" transform=\"rotate(270, {x}, {y})\"") } else { String::new() };
    format!(
        "<text x=\"{x}\" y=\"{y}\" dy=\"{dy}\" text-anchor=\"{anchor}\" font-family=\"sans-serif\" \
         font-size=\"{}\" opacity=\"1\" fill=\"#{:02X}{:02X}{:02X}\"{rotate}>\n{}\n</text>\n",
        t.size / SVG_FONT_DIVISOR,
        c.0,
        c.1,
        c.2,
        escape::xml(&t.text)
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use plotters::style::RGBColor;

    #[test]
    fn writes_what_plotters_wrote_with_the_text_escaped() {
        let mut t = TextCmd {
            text: "Exp. 1: <b>'&'</b>".into(),
            at: (250, 64),
            size: 15.0,
            color: RGBColor(30, 30, 30),
            h: HPos::Center,
            v: VPos::Center,
            rotate: false,
        };
        assert_eq!(
            element(&t),
            "<text x=\"250\" y=\"64\" dy=\"0.5ex\" text-anchor=\"middle\" font-family=\"sans-serif\" \
             font-size=\"12.096774193548388\" opacity=\"1\" fill=\"#1E1E1E\">\n\
             Exp. 1: &lt;b&gt;&apos;&amp;&apos;&lt;/b&gt;\n</text>\n"
        );
        t.rotate = true;
        (t.h, t.v) = (HPos::Left, VPos::Top);
        assert!(element(&t).contains(
            " dy=\"0.76em\" text-anchor=\"start\" font-family=\"sans-serif\" font-size=\"12.096774193548388\" \
             opacity=\"1\" fill=\"#1E1E1E\" transform=\"rotate(270, 250, 64)\">\n"
        ));
    }
}
