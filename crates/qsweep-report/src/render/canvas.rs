//! The drawing surface of every figure: a [`Canvas`] (a plotters drawing area plus the text kept
//! aside to be written last), a [`Picture`] drawn once as SVG and once as PNG with the same result,
//! and the hatch patterns of the SVG.

use crate::render::glyphs::{self, TextCmd};
use crate::render::text_fit::{self, Entry, Legend};
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, VPos};
use plotters::style::FontStyle;
use std::sync::Once;

const FONT: &str = "sans-serif";
static FONT_BYTES: &[u8] = glyphs::FONT;
static REGISTER: Once = Once::new();

/// Height of the figure's title band.
pub const HEADER_H: u32 = 50;
pub(crate) const INK: RGBColor = RGBColor(30, 30, 30);
pub(crate) const SUBTLE: RGBColor = RGBColor(90, 90, 90);

/// A figure drawn as SVG text and/or PNG bytes.
#[derive(Debug, Clone, Default)]
pub struct Drawn {
    /// The SVG text ([`crate::render::svg::compact`]ed), if asked for.
    pub svg: Option<String>,
    /// The PNG bytes, if asked for.
    pub png: Option<Vec<u8>>,
}

/// What a figure draws: called once for the SVG and once for the bitmap, with the same result.
pub(crate) trait Picture {
    /// Draw onto `cv` (shapes directly, text through [`Canvas::text`]).
    fn draw<DB: DrawingBackend>(&self, cv: &mut Canvas<DB>) -> Res;
}

/// Draw `picture` as SVG (if `svg`) and PNG (if `png`).
pub(crate) fn paint_as(
    picture: &impl Picture,
    size: (u32, u32),
    svg: bool,
    png: bool,
) -> Result<Drawn, String> {
    REGISTER.call_once(|| {
        if plotters::style::register_font(FONT, FontStyle::Normal, FONT_BYTES).is_err() {
            panic!("the embedded font is a valid TrueType file");
        }
    });
    Ok(Drawn {
        svg: if svg { Some(paint_svg(picture, size)?) } else { None },
        png: if png { Some(paint_png(picture, size)?) } else { None },
    })
}

fn paint_svg(picture: &impl Picture, (w, h): (u32, u32)) -> Result<String, String> {
    let mut svg = String::new();
    let (hatches, texts) = {
        let mut canvas = Canvas {
            root: SVGBackend::with_string(&mut svg, (w, h)).into_drawing_area(),
            texts: Vec::new(),
            hatch_marks: Some(Vec::new()),
        };
        picture.draw(&mut canvas)?;
        canvas.root.present().map_err(|e| e.to_string())?;
        (canvas.hatch_marks.unwrap_or_default(), canvas.texts)
    };
    // The texts after every shape, written (and escaped) by this crate.
    let end = svg.rfind("</svg>").ok_or("plotters wrote no </svg>")?;
    let tail = svg.split_off(end);
    for t in &texts {
        svg.push_str(&crate::render::svg_text::element(t));
    }
    svg.push_str(&tail);
    Ok(crate::render::svg::compact_with(&svg, |s| hatch_patterns(&s, &hatches)))
}

fn paint_png(picture: &impl Picture, (w, h): (u32, u32)) -> Result<Vec<u8>, String> {
    let mut rgb = vec![255u8; (w * h * 3) as usize];
    let texts = {
        let mut canvas = Canvas {
            root: BitMapBackend::with_buffer(&mut rgb, (w, h)).into_drawing_area(),
            texts: Vec::new(),
            hatch_marks: None,
        };
        picture.draw(&mut canvas)?;
        canvas.root.present().map_err(|e| e.to_string())?;
        canvas.texts
    };
    glyphs::draw(FONT_BYTES, &mut rgb, w, h, &texts).map_err(|e| e.to_string())?;
    encode_png(&rgb, w, h).map_err(|e| e.to_string())
}

fn encode_png(rgb: &[u8], w: u32, h: u32) -> anyhow::Result<Vec<u8>> {
    let mut out = Vec::new();
    {
        let mut enc = png::Encoder::new(&mut out, w, h);
        enc.set_color(png::ColorType::Rgb);
        enc.set_depth(png::BitDepth::Eight);
        let mut writer = enc.write_header()?;
        writer.write_image_data(rgb)?;
        writer.finish()?;
    }
    Ok(out)
}

/// A drawing step's result (plotters' errors as text).
pub(crate) type Res = Result<(), String>;

/// A drawing area plus the text drawn on it, kept aside to be written last.
pub(crate) struct Canvas<DB: DrawingBackend> {
    /// The drawing area.
    pub(crate) root: DrawingArea<DB, Shift>,
    /// Text to write after the shapes.
    pub(crate) texts: Vec<TextCmd>,
    /// In SVG: the hatch colours used so far. A hatched area is then one rectangle filled with a
    /// marker colour that [`hatch_patterns`] turns into a pattern fill (one element instead of a
    /// dozen lines); in PNG (`None`) the lines are drawn.
    pub(crate) hatch_marks: Option<Vec<RGBColor>>,
}

/// The marker fill of hatch colour `k` (an otherwise unused near-black).
fn hatch_marker(k: usize) -> RGBColor {
    RGBColor(1, 2, k as u8)
}

/// Replace the marker fills of [`Canvas::hatch`] in compacted SVG text by pattern fills: the same
/// diagonal lines every 7 px at 45 % opacity, defined once per colour after the root element.
pub(crate) fn hatch_patterns(svg: &str, colors: &[RGBColor]) -> String {
    if colors.is_empty() {
        return svg.to_string();
    }
    let hex = |c: &RGBColor| format!("#{:02X}{:02X}{:02X}", c.0, c.1, c.2);
    let mut defs = String::from("<defs>");
    for (k, c) in colors.iter().enumerate() {
        defs.push_str(&format!(
            "<pattern id=\"hatch{k}\" width=\"7\" height=\"7\" patternUnits=\"userSpaceOnUse\"><path d=\"M-1,1 L1,-1 M0,7 L7,0 M6,8 L8,6\" stroke=\"{}\" stroke-opacity=\"0.45\" stroke-width=\"1\"/></pattern>",
            hex(c)
        ));
    }
    defs.push_str("</defs>\n");
    let subs: Vec<(String, String)> = (0..colors.len())
        .map(|k| (format!("fill=\"{}\"", hex(&hatch_marker(k))), format!("fill=\"url(#hatch{k})\"")))
        .collect();
    let mut out = String::with_capacity(svg.len() + defs.len());
    for (i, line) in svg.lines().enumerate() {
        let mut l = line.to_string();
        for (from, to) in &subs {
            l = l.replace(from, to);
        }
        out.push_str(&l);
        out.push('\n');
        if i == 0 {
            out.push_str(&defs);
        }
    }
    out
}

impl<DB: DrawingBackend> Canvas<DB> {
    /// A figure's title, centred in its header band, shrunk (and at worst shortened) to fit the
    /// figure's width `w`.
    pub(crate) fn title(&mut self, title: &str, w: u32) {
        let (text, size) = text_fit::fit(title, f64::from(w) - 2.0 * f64::from(text_fit::MARGIN), 20.0, 9.0);
        self.text(&text, (w as i32 / 2, HEADER_H as i32 / 2), size, INK, HPos::Center, VPos::Center);
    }

    /// A text centred at (`cx`, `y`) in at most `max` pixels: shrunk from `size` down to 9 px, then
    /// shortened.
    pub(crate) fn text_within(&mut self, s: &str, (cx, y): (i32, i32), max: i32, size: f64, color: RGBColor) {
        let (text, size) = text_fit::fit(s, f64::from(max), size, 9.0);
        self.text(&text, (cx, y), size, color, HPos::Center, VPos::Center);
    }

    /// `band` at the bottom of a figure `h` pixels tall, placed by [`Legend::place`] for the
    /// figure's width: each entry's swatch drawn by `swatch` (given the entry's index and the
    /// swatch's left edge and centre line; it returns the colour of the entry's text), then its
    /// text lines.
    pub(crate) fn legend(
        &mut self,
        band: &Legend,
        h: u32,
        mut swatch: impl FnMut(&mut Self, usize, (i32, i32)) -> Result<RGBColor, String>,
    ) -> Res {
        let (w, _) = self.root.dim_in_pixel();
        let (placed, band_h) = band.place(w);
        let top = (h - band_h) as i32;
        for p in &placed {
            let color = swatch(self, p.entry, (p.x, top + p.y))?;
            self.lines(p, top, &band.entries[p.entry], color);
        }
        Ok(())
    }

    /// A legend entry's text lines, placed by [`Legend::place`] in the band whose top is at `top`.
    fn lines(&mut self, p: &text_fit::Placed, top: i32, e: &Entry, color: RGBColor) {
        for (k, l) in p.lines.iter().enumerate() {
            let y = top + p.y + k as i32 * Legend::line_h(e.size);
            self.text(l, (p.text_x, y), e.size, color, HPos::Left, VPos::Center);
        }
    }

    pub(crate) fn text(&mut self, s: &str, at: (i32, i32), size: f64, color: RGBColor, h: HPos, v: VPos) {
        self.texts.push(TextCmd { text: s.to_string(), at, size, color, h, v, rotate: false });
    }

    pub(crate) fn text_up(&mut self, s: &str, at: (i32, i32), size: f64, color: RGBColor) {
        self.texts.push(TextCmd {
            text: s.to_string(),
            at,
            size,
            color,
            h: HPos::Center,
            v: VPos::Center,
            rotate: true,
        });
    }

    pub(crate) fn rect(&self, a: (i32, i32), b: (i32, i32), style: ShapeStyle) -> Res {
        self.root.draw(&Rectangle::new([a, b], style)).map_err(|e| e.to_string())
    }

    pub(crate) fn line(&self, a: (i32, i32), b: (i32, i32), style: ShapeStyle) -> Res {
        self.root.draw(&PathElement::new(vec![a, b], style)).map_err(|e| e.to_string())
    }

    /// Diagonal hatching clipped to a rectangle.
    pub(crate) fn hatch(&mut self, (x0, y0): (i32, i32), (x1, y1): (i32, i32), color: RGBColor) -> Res {
        if let Some(colors) = &mut self.hatch_marks {
            let k = colors.iter().position(|c| *c == color).unwrap_or_else(|| {
                colors.push(color);
                colors.len() - 1
            });
            return self.rect((x0, y0), (x1, y1), hatch_marker(k).filled());
        }
        let style = color.mix(0.45).stroke_width(1);
        let mut k = 4;
        while k < (x1 - x0) + (y1 - y0) {
            // The line x + y = c clipped to the rectangle, from lower-left to upper-right.
            let c = x0 + y0 + k;
            let (xa, xb) = (x0.max(c - y1), x1.min(c - y0));
            if xa < xb {
                self.line((xa, c - xa), (xb, c - xb), style)?;
            }
            k += 7;
        }
        Ok(())
    }
}
