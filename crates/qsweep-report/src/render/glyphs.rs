//! Text for the PNG figures, rasterised with ab_glyph straight into the RGB buffer: kerning,
//! side bearings and anchoring done properly (plotters' own ab_glyph text path drops glyphs'
//! left side bearings, which squeezes `= 2` into `=2`). Sizes are CSS pixels (the em), as in the
//! SVG, so both files lay text out alike.

use ab_glyph::{point, Font, FontRef, Glyph, PxScale, ScaleFont};
use plotters::style::text_anchor::{HPos, VPos};
use plotters::style::RGBColor;

/// The figures' font: a DejaVu Sans subset (`assets/fonts`), embedded so that no system font
/// library is involved and the PNG is the same on every machine.
pub static FONT: &[u8] = include_bytes!("../../assets/fonts/DejaVuSans-subset.ttf");

/// One piece of text to draw.
#[derive(Clone)]
pub struct TextCmd {
    /// The text.
    pub text: String,
    /// Anchor point, in pixels.
    pub at: (i32, i32),
    /// Font size (em), in pixels.
    pub size: f64,
    /// Colour.
    pub color: RGBColor,
    /// Horizontal anchor.
    pub h: HPos,
    /// Vertical anchor.
    pub v: VPos,
    /// Rotated 90° counter-clockwise (reading upwards), anchored as if unrotated.
    pub rotate: bool,
}

/// The scale of a text of `size` pixels per em.
fn scale(font: &FontRef, size: f64) -> PxScale {
    let em_to_height = font.height_unscaled() / font.units_per_em().unwrap_or(2048.0);
    PxScale::from(size as f32 * em_to_height)
}

/// The glyphs of `text` on one line from x = 0 (kerned), and the line's advance width.
fn line(font: &FontRef, text: &str, scale: PxScale) -> (Vec<Glyph>, f32) {
    let sf = font.as_scaled(scale);
    let mut caret = 0.0f32;
    let mut prev = None;
    let mut glyphs = Vec::new();
    for c in text.chars() {
        let id = sf.glyph_id(c);
        if let Some(p) = prev {
            caret += sf.kern(p, id);
        }
        glyphs.push(id.with_scale_and_position(scale, point(caret, 0.0)));
        caret += sf.h_advance(id);
        prev = Some(id);
    }
    (glyphs, caret)
}

/// The advance width of `text` at `size` pixels per em in the font `font_bytes`, in pixels: the
/// width [`draw`] gives it.
pub fn text_width(font_bytes: &[u8], text: &str, size: f64) -> f64 {
    match FontRef::try_from_slice(font_bytes) {
        Ok(font) => f64::from(line(&font, text, scale(&font, size)).1),
        Err(_) => 0.6 * size * text.chars().count() as f64,
    }
}

/// Draw `cmds` onto an RGB8 buffer of width `w` and height `h`.
pub fn draw(font_bytes: &[u8], rgb: &mut [u8], w: u32, h: u32, cmds: &[TextCmd]) -> anyhow::Result<()> {
    let font = FontRef::try_from_slice(font_bytes).map_err(|e| anyhow::anyhow!("embedded font: {e}"))?;
    for cmd in cmds {
        let scale = scale(&font, cmd.size);
        let sf = font.as_scaled(scale);
        let (glyphs, caret) = line(&font, &cmd.text, scale);
        let dx = match cmd.h {
            HPos::Left => 0.0,
            HPos::Center => -caret / 2.0,
            HPos::Right => -caret,
        };
        // Baseline offset from the anchor: centre on the cap height, top at the ascent.
        let cap = sf.ascent() * 0.72;
        let dy = match cmd.v {
            VPos::Top => sf.ascent(),
            VPos::Center => cap / 2.0,
            VPos::Bottom => sf.descent(),
        };
        for g in glyphs {
            let Some(outline) = font.outline_glyph(g) else { continue };
            let b = outline.px_bounds();
            outline.draw(|x, y, coverage| {
                // Position relative to the anchor in unrotated text space.
                let tx = b.min.x + x as f32 + dx;
                let ty = b.min.y + y as f32 + dy;
                let (px, py) = if cmd.rotate { (ty, -tx) } else { (tx, ty) };
                let (px, py) = (cmd.at.0 + px.round() as i32, cmd.at.1 + py.round() as i32);
                if px < 0 || py < 0 || px >= w as i32 || py >= h as i32 {
                    return;
                }
                let i = (py as usize * w as usize + px as usize) * 3;
                let a = coverage.clamp(0.0, 1.0);
                for (k, c) in [cmd.color.0, cmd.color.1, cmd.color.2].into_iter().enumerate() {
                    let bg = f32::from(rgb[i + k]);
                    rgb[i + k] = (bg + a * (f32::from(c) - bg)).round() as u8;
                }
            });
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ink(rgb: &[u8]) -> usize {
        rgb.iter().filter(|&&b| b < 128).count()
    }

    fn cmd(text: &str, h: HPos, rotate: bool) -> TextCmd {
        TextCmd {
            text: text.into(),
            at: (50, 50),
            size: 14.0,
            color: RGBColor(0, 0, 0),
            h,
            v: VPos::Center,
            rotate,
        }
    }

    #[test]
    fn draws_anchored_text_deterministically() {
        let font = include_bytes!("../../assets/fonts/DejaVuSans-subset.ttf");
        let mut a = vec![255u8; 100 * 100 * 3];
        draw(font, &mut a, 100, 100, &[cmd("Q(λ) = 2", HPos::Left, false)]).unwrap();
        assert!(ink(&a) > 20);
        // Left-anchored text starts at the anchor: nothing left of x = 49.
        assert!((0..100).all(|y| (0..49).all(|x| a[(y * 100 + x) * 3] == 255)));
        let mut b = vec![255u8; 100 * 100 * 3];
        draw(font, &mut b, 100, 100, &[cmd("Q(λ) = 2", HPos::Left, false)]).unwrap();
        assert_eq!(a, b);
        // Rotated text is taller than wide.
        let mut r = vec![255u8; 100 * 100 * 3];
        draw(font, &mut r, 100, 100, &[cmd("rotated", HPos::Center, true)]).unwrap();
        let rows = (0..100).filter(|y| (0..100).any(|x| r[(y * 100 + x) * 3] < 128)).count();
        let cols = (0..100).filter(|x| (0..100).any(|y| r[(y * 100 + x) * 3] < 128)).count();
        assert!(rows > 2 * cols, "{rows} rows × {cols} cols");
    }
}
