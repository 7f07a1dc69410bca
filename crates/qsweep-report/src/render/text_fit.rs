//! Figure text that fits its figure. Widths are measured with the embedded font
//! ([`crate::render::glyphs::text_width`]) at the size the PNG draws it; the SVG draws the same text
//! [`crate::render::svg_text::SVG_FONT_DIVISOR`] times smaller, which leaves room for a viewer's own
//! sans-serif. Titles shrink to their width ([`fit`]), and a legend band ([`Legend`]) keeps its
//! columns where every text fits before the next column, and otherwise stacks its entries, one per
//! line, wrapping a text too long for the figure, so its height depends on the figure's width.

use crate::render::glyphs;

/// Pixels kept clear at a figure's edges and between a legend's columns.
pub const MARGIN: i32 = 8;

/// Where an entry's text starts after its swatch (26 px wide, then 8 px of space).
pub const SWATCH_W: i32 = 34;

/// The advance width of `text` at `size` pixels per em (as the PNG draws it).
pub fn width(text: &str, size: f64) -> f64 {
    glyphs::text_width(glyphs::FONT, text, size)
}

/// `text` at the largest size up to `size` whose width is at most `max`, but not below `min`;
/// where even `min` is too wide, the text is cut at the end and marked with `…`.
pub fn fit(text: &str, max: f64, size: f64, min: f64) -> (String, f64) {
    let w = width(text, size);
    if w <= max {
        return (text.to_string(), size);
    }
    // Widths grow in proportion to the size; round down to the SVG's 0.01 px (and a hair more).
    let s = (size * max / w * 100.0 - 0.5).floor() / 100.0;
    if s >= min {
        return (text.to_string(), s);
    }
    let chars: Vec<char> = text.chars().collect();
    let mut n = chars.len();
    loop {
        n -= 1;
        let cut: String = chars[..n].iter().collect::<String>().trim_end().to_string() + "…";
        if n == 0 || width(&cut, min) <= max {
            return (cut, min);
        }
    }
}

/// `text` in lines no wider than `max` at `size`, broken at spaces (a word wider than `max` is a
/// line of its own).
pub fn wrap(text: &str, max: f64, size: f64) -> Vec<String> {
    let mut lines: Vec<String> = Vec::new();
    for word in text.split(' ') {
        match lines.last_mut() {
            Some(l) if width(&format!("{l} {word}"), size) <= max => {
                l.push(' ');
                l.push_str(word);
            }
            _ => lines.push(word.to_string()),
        }
    }
    lines
}

/// One entry of a legend band: a swatch the figure draws (or none) and its text.
#[derive(Debug, Clone)]
pub struct Entry {
    /// The text.
    pub text: String,
    /// Its size, pixels per em.
    pub size: f64,
    /// Drawn after a swatch ([`SWATCH_W`] to its left).
    pub swatch: bool,
}

/// Where an entry goes: its swatch centred at (`x`, `y`) (its left edge at `x`), its text in
/// `lines` from (`text_x`, `y`) down, [`Legend::line_h`] apart.
#[derive(Debug, Clone, PartialEq)]
pub struct Placed {
    /// The entry's index in [`Legend::entries`].
    pub entry: usize,
    /// Left edge of the swatch.
    pub x: i32,
    /// Centre of the first line, from the band's top.
    pub y: i32,
    /// Where the text starts.
    pub text_x: i32,
    /// The text's lines.
    pub lines: Vec<String>,
}

/// A legend band: its entries in columns (`rows` of (x, entry index)), with the vertical rhythm
/// of the figure (first line `first` below the band's top, rows `row_h` apart, `bottom` below the
/// last line).
pub struct Legend {
    /// The entries.
    pub entries: Vec<Entry>,
    /// The wide arrangement: per row, (left edge, entry index).
    pub rows: Vec<Vec<(i32, usize)>>,
    /// Offset of the first row's centre from the band's top.
    pub first: i32,
    /// Distance between rows.
    pub row_h: i32,
    /// Space below the last line.
    pub bottom: i32,
}

impl Legend {
    /// Distance between the lines of a wrapped text.
    pub fn line_h(size: f64) -> i32 {
        (size * 1.25).ceil() as i32
    }

    /// The entries placed for a figure `w` pixels wide, and the band's height: the columns where
    /// they fit, else one entry per line at the left, wrapped to the width.
    pub fn place(&self, w: u32) -> (Vec<Placed>, u32) {
        let w = w as i32;
        let text_x = |x: i32, e: &Entry| x + if e.swatch { SWATCH_W } else { 0 };
        let fits = self.rows.iter().all(|row| {
            row.iter().enumerate().all(|(k, &(x, i))| {
                let end = row.get(k + 1).map_or(w - MARGIN, |next| next.0 - MARGIN);
                f64::from(text_x(x, &self.entries[i])) + width(&self.entries[i].text, self.entries[i].size)
                    <= f64::from(end)
            })
        });
        let mut placed = Vec::new();
        if fits {
            for (r, row) in self.rows.iter().enumerate() {
                for &(x, i) in row.iter() {
                    let e = &self.entries[i];
                    let y = self.first + r as i32 * self.row_h;
                    placed.push(Placed { entry: i, x, y, text_x: text_x(x, e), lines: vec![e.text.clone()] });
                }
            }
        } else {
            let x = self.rows.iter().flat_map(|r| r.iter().map(|p| p.0)).min().unwrap_or(MARGIN);
            let mut y = self.first;
            for &(_, i) in self.rows.iter().flat_map(|r| r.iter()) {
                let e = &self.entries[i];
                let tx = x + SWATCH_W;
                let lines = wrap(&e.text, f64::from(w - MARGIN - tx), e.size);
                let n = lines.len() as i32;
                placed.push(Placed { entry: i, x, y, text_x: tx, lines });
                y += self.row_h + (n - 1) * Self::line_h(e.size);
            }
        }
        let last = placed
            .iter()
            .map(|p| p.y + (p.lines.len() as i32 - 1) * Self::line_h(self.entries[p.entry].size));
        let height = last.max().unwrap_or(0) + self.bottom;
        (placed, height.max(0) as u32)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn titles_shrink_then_shorten_to_fit() {
        let t = "Ball-Beam: mean episodes to the learning goal (tuning)";
        assert_eq!(fit(t, 2000.0, 20.0, 9.0), (t.to_string(), 20.0));
        let (s, size) = fit(t, 400.0, 20.0, 9.0);
        assert_eq!(s, t);
        assert!(size < 20.0 && width(t, size) <= 400.0 && width(t, size + 0.02) > 400.0, "{size}");
        let (s, size) = fit(t, 100.0, 20.0, 9.0);
        assert_eq!(size, 9.0);
        assert!(s.ends_with('…') && t.starts_with(s.trim_end_matches('…')) && width(&s, 9.0) <= 100.0, "{s}");
    }

    #[test]
    fn wrapped_lines_keep_every_word_and_fit() {
        let t = "* and hatched: some trials never reached the goal (counted at the episode cap)";
        let lines = wrap(t, 300.0, 13.0);
        assert!(lines.len() >= 2);
        assert_eq!(lines.join(" "), t);
        assert!(lines.iter().all(|l| width(l, 13.0) <= 300.0), "{lines:?}");
    }

    #[test]
    fn legend_keeps_its_columns_where_they_fit_and_stacks_otherwise() {
        let entry = |text: &str, swatch| Entry { text: text.into(), size: 13.0, swatch };
        let entries = vec![
            entry("best cell (Table III)", true),
            entry("* and hatched: some trials never reached the goal (counted at the episode cap)", true),
            entry("a note", false),
        ];
        let rows = vec![vec![(20, 0), (220, 1)], vec![(220, 2)]];
        let legend = Legend { entries, rows, first: 22, row_h: 24, bottom: 14 };
        let (wide, h) = legend.place(1000);
        assert_eq!(h, 22 + 24 + 14);
        assert_eq!(
            wide.iter().map(|p| (p.x, p.y, p.text_x)).collect::<Vec<_>>(),
            [(20, 22, 54), (220, 22, 254), (220, 46, 220)]
        );
        let (narrow, h) = legend.place(500);
        assert_eq!(
            narrow.iter().map(|p| (p.x, p.y, p.text_x)).collect::<Vec<_>>(),
            [(20, 22, 54), (20, 46, 54), (20, 46 + 24 + Legend::line_h(13.0), 54)]
        );
        assert_eq!(narrow[1].lines.len(), 2);
        assert_eq!(h, 87 + 14);
        for p in &narrow {
            assert!(p.lines.iter().all(|l| f64::from(p.text_x) + width(l, 13.0) <= f64::from(500 - MARGIN)));
        }
    }
}
