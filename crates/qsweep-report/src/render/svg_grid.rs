//! Heatmap grids drawn as one image: a figure's heatmaps are most of its bytes (one `<rect>` of
//! about 60 bytes per cell, 81 cells per heatmap, eight heatmaps per figure). [`grid_images`]
//! replaces every complete grid of cell rectangles by a PNG, scaled to the grid's box, and one
//! white path of the cell borders the rectangles' strokes drew; what was drawn over the cells
//! (hatching) is kept, after the image. A run of rectangles that is not a complete grid is left as
//! it was.
//!
//! A heatmap's PNG draws each cell as a uniform block of k × k pixels ([`block_px`]: at least 2,
//! and enough that one image pixel covers at most [`MAX_SCALE`] pixels of the figure), so a viewer
//! that smooths the image as it scales it up (librsvg, Inkscape and most converters ignore
//! `image-rendering: pixelated`, which browsers honour) blends two cells only in a band of about
//! `MAX_SCALE` pixels at their edge, half of it under the white border, and every cell shows its
//! own colour as in a browser. (PNG's row filters and deflate store the repeated pixels in a few
//! bytes; a larger k would cost the committed reports more than their budget.) A colour bar's PNG keeps one
//! pixel per step: smoothed, its steps of a continuous scale become the gradient they stand for.
//! An image drawn more than once in a figure (every panel's colour bar is the same) is stored once,
//! as a `<symbol>` that each place `<use>`s.
//!
//! A cell here is what [`crate::render::svg`]'s merge step writes for a heatmap cell,
//! `<rect x="X" y="Y" width="W" height="H" fill="#RRGGBB" stroke="#FFFFFF"/>` (whole pixels), or
//! for a colour bar's step, the same with `stroke="none"` (drawn without borders).

/// One cell rectangle, and what was drawn right after it over it.
#[derive(Debug, Clone)]
struct Cell<'a> {
    x: i64,
    y: i64,
    w: i64,
    h: i64,
    rgb: [u8; 3],
    /// Drawn with the white cell border (a heatmap), or with none (a colour bar).
    bordered: bool,
    line: &'a str,
    overlays: Vec<&'a str>,
}

/// The smallest grid worth an image.
const MIN_CELLS: usize = 4;

/// At most this many pixels of the figure per pixel of a heatmap's PNG, along either side.
pub const MAX_SCALE: f64 = 4.0;

/// Pixels per side of the blocks of a heatmap's PNG whose cells are drawn `cw` × `ch` pixels: the
/// fewest that keep each image pixel within [`MAX_SCALE`] figure pixels, and at least 2.
pub fn block_px(cw: f64, ch: f64) -> usize {
    ((cw.max(ch) / MAX_SCALE).ceil() as usize).max(2)
}

/// What replaces a grid: lines of SVG, and its image (placed where the grid was).
enum Piece<'a> {
    Line(&'a str),
    Owned(String),
    Image {
        /// The box the image fills: x, y, width, height.
        at: (i64, i64, i64, i64),
        /// The PNG's pixel size.
        px: (usize, usize),
        /// The PNG, base64.
        data: String,
    },
}

/// Rewrite every complete grid of heatmap cells in `svg` (one element per line) as described in
/// the module documentation.
pub fn grid_images(svg: &str) -> String {
    let lines: Vec<&str> = svg.lines().collect();
    let mut pieces = Vec::with_capacity(lines.len());
    let mut i = 0;
    while i < lines.len() {
        let Some(first) = cell(lines[i]) else {
            pieces.push(Piece::Line(lines[i]));
            i += 1;
            continue;
        };
        // A run of cells, each followed by its overlays (rectangles without a stroke, drawn on it).
        let mut run = vec![first];
        i += 1;
        while i < lines.len() {
            if let Some(c) = cell(lines[i]) {
                run.push(c);
            } else if is_overlay(lines[i]) {
                run.last_mut().expect("a run starts with a cell").overlays.push(lines[i]);
            } else {
                break;
            }
            i += 1;
        }
        for grid in split_grids(run) {
            emit(&mut pieces, &grid);
        }
    }
    write(&pieces, svg.len())
}

/// The pieces as SVG text: an image drawn once in place, one drawn more often as a symbol (defined
/// where it is first drawn) that each place uses.
fn write(pieces: &[Piece], capacity: usize) -> String {
    let mut count = std::collections::HashMap::new();
    for p in pieces {
        if let Piece::Image { data, .. } = p {
            *count.entry(data.as_str()).or_insert(0usize) += 1;
        }
    }
    let mut ids: Vec<&str> = Vec::new();
    let mut out = String::with_capacity(capacity);
    for p in pieces {
        match p {
            Piece::Line(l) => out.push_str(l),
            Piece::Owned(l) => out.push_str(l),
            Piece::Image { at: (x, y, w, h), px: (pw, ph), data } => {
                const STYLE: &str = "style=\"image-rendering:pixelated\"";
                if count[data.as_str()] == 1 {
                    out.push_str(&format!(
                        "<image x=\"{x}\" y=\"{y}\" width=\"{w}\" height=\"{h}\" preserveAspectRatio=\"none\" \
                         {STYLE} href=\"data:image/png;base64,{data}\"/>"
                    ));
                } else {
                    let k = ids.iter().position(|d| d == data).unwrap_or_else(|| {
                        out.push_str(&format!(
                            "<defs><symbol id=\"px{}\" viewBox=\"0 0 {pw} {ph}\" preserveAspectRatio=\"none\">\
                             <image width=\"{pw}\" height=\"{ph}\" {STYLE} href=\"data:image/png;base64,{data}\"/>\
                             </symbol></defs>\n",
                            ids.len()
                        ));
                        ids.push(data);
                        ids.len() - 1
                    });
                    out.push_str(&format!(
                        "<use href=\"#px{k}\" x=\"{x}\" y=\"{y}\" width=\"{w}\" height=\"{h}\"/>"
                    ));
                }
            }
        }
        out.push('\n');
    }
    out
}

fn cell(line: &str) -> Option<Cell<'_>> {
    let rest = line.strip_prefix("<rect x=\"")?;
    let (x, rest) = rest.split_once("\" y=\"")?;
    let (y, rest) = rest.split_once("\" width=\"")?;
    let (w, rest) = rest.split_once("\" height=\"")?;
    let (h, rest) = rest.split_once("\" fill=\"#")?;
    let (hex, bordered) = match rest.strip_suffix("\" stroke=\"#FFFFFF\"/>") {
        Some(hex) => (hex, true),
        None => (rest.strip_suffix("\" stroke=\"none\"/>")?, false),
    };
    if hex.len() != 6 {
        return None;
    }
    let byte = |k: usize| u8::from_str_radix(hex.get(k..k + 2)?, 16).ok();
    Some(Cell {
        x: x.parse().ok()?,
        y: y.parse().ok()?,
        w: w.parse().ok()?,
        h: h.parse().ok()?,
        rgb: [byte(0)?, byte(2)?, byte(4)?],
        bordered,
        line,
        overlays: Vec::new(),
    })
}

fn is_overlay(line: &str) -> bool {
    line.starts_with("<rect ") && line.ends_with(" stroke=\"none\"/>") && line.contains(" fill=\"url(#")
}

/// Cut a run where a cell does not continue the grid drawn so far (the next one in its row, or
/// the first of the next row, below or above).
fn split_grids(run: Vec<Cell<'_>>) -> Vec<Vec<Cell<'_>>> {
    let mut grids: Vec<Vec<Cell>> = Vec::new();
    for c in run {
        let continues = grids.last().is_some_and(|g| {
            let (first, prev) = (&g[0], &g[g.len() - 1]);
            c.bordered == prev.bordered
                && ((c.y == prev.y && c.x == prev.x + prev.w)
                    || (c.x == first.x && (c.y == prev.y + prev.h || c.y + c.h == prev.y)))
        });
        if continues {
            grids.last_mut().expect("checked").push(c);
        } else {
            grids.push(vec![c]);
        }
    }
    grids
}

/// The grid's column edges, its row edges from the top, and its rows (indices into `g`) from the
/// top, if its cells tile a rectangle row by row (rows drawn downwards or upwards).
fn lattice(g: &[Cell]) -> Option<(Vec<i64>, Vec<i64>, Vec<usize>)> {
    let nx = g.iter().take_while(|c| c.y == g[0].y).count();
    if g.len() < MIN_CELLS || !g.len().is_multiple_of(nx) {
        return None;
    }
    let mut xs: Vec<i64> = g[..nx].iter().map(|c| c.x).collect();
    xs.push(g[nx - 1].x + g[nx - 1].w);
    let mut rows: Vec<usize> = (0..g.len() / nx).map(|r| r * nx).collect();
    if rows.len() > 1 && g[nx].y < g[0].y {
        rows.reverse();
    }
    let mut ys = vec![g[rows[0]].y];
    for (r, &start) in rows.iter().enumerate() {
        let row = &g[start..start + nx];
        for (k, c) in row.iter().enumerate() {
            if c.x != xs[k] || c.x + c.w != xs[k + 1] || c.y != ys[r] || c.h != row[0].h {
                return None;
            }
        }
        ys.push(ys[r] + row[0].h);
    }
    // One pixel per cell is scaled evenly over the box: every edge must be within half a pixel
    // of its even place, where the 1-pixel border drawn over it hides the difference.
    let even = |edges: &[i64]| {
        let (first, n) = (edges[0] as f64, (edges.len() - 1) as f64);
        let step = (edges[edges.len() - 1] - edges[0]) as f64 / n;
        edges.iter().enumerate().all(|(k, &e)| (e as f64 - (first + step * k as f64)).abs() <= 0.5)
    };
    (even(&xs) && even(&ys)).then_some((xs, ys, rows))
}

fn emit<'a>(out: &mut Vec<Piece<'a>>, g: &[Cell<'a>]) {
    let Some((xs, ys, rows)) = lattice(g) else {
        for c in g {
            out.push(Piece::Line(c.line));
            out.extend(c.overlays.iter().map(|o| Piece::Line(o)));
        }
        return;
    };
    let (nx, ny) = (xs.len() - 1, ys.len() - 1);
    let (x0, y0, x1, y1) = (xs[0], ys[0], xs[nx], ys[ny]);
    // A heatmap's cell is a block of k × k pixels; a colour bar's step one pixel.
    let k =
        if g[0].bordered { block_px((x1 - x0) as f64 / nx as f64, (y1 - y0) as f64 / ny as f64) } else { 1 };
    let mut pixels = Vec::with_capacity(nx * ny * k * k * 3);
    for &r in &rows {
        let row: Vec<u8> = g[r..r + nx].iter().flat_map(|c| (0..k).flat_map(|_| c.rgb)).collect();
        for _ in 0..k {
            pixels.extend_from_slice(&row);
        }
    }
    let (pw, ph) = (nx * k, ny * k);
    out.push(Piece::Image {
        at: (x0, y0, x1 - x0, y1 - y0),
        px: (pw, ph),
        data: base64(&png(pw as u32, ph as u32, &pixels)),
    });
    if g[0].bordered {
        let mut d = String::new();
        for &y in &ys {
            d.push_str(&format!("M{x0} {y}H{x1}"));
        }
        for &x in &xs {
            d.push_str(&format!("M{x} {y0}V{y1}"));
        }
        out.push(Piece::Owned(format!("<path fill=\"none\" stroke=\"#FFFFFF\" d=\"{d}\"/>")));
    }
    out.extend(g.iter().flat_map(|c| &c.overlays).map(|o| Piece::Line(o)));
}

/// An 8-bit RGB PNG of `w` × `h` pixels, row by row.
fn png(w: u32, h: u32, rgb: &[u8]) -> Vec<u8> {
    let mut out = Vec::new();
    let mut enc = png::Encoder::new(&mut out, w, h);
    enc.set_color(png::ColorType::Rgb);
    enc.set_depth(png::BitDepth::Eight);
    enc.set_compression(png::Compression::High);
    let mut writer = enc.write_header().expect("writing a PNG header to memory cannot fail");
    writer.write_image_data(rgb).expect("the pixels match the size");
    writer.finish().expect("finishing a PNG in memory cannot fail");
    out
}

/// Standard base64 with padding (RFC 4648).
fn base64(bytes: &[u8]) -> String {
    const ABC: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut s = String::with_capacity(bytes.len().div_ceil(3) * 4);
    for chunk in bytes.chunks(3) {
        let b = [chunk[0], *chunk.get(1).unwrap_or(&0), *chunk.get(2).unwrap_or(&0)];
        let n = (u32::from(b[0]) << 16) | (u32::from(b[1]) << 8) | u32::from(b[2]);
        for k in 0..4 {
            if k <= chunk.len() {
                s.push(ABC[(n >> (18 - 6 * k) & 63) as usize] as char);
            } else {
                s.push('=');
            }
        }
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rect(x: i64, y: i64, w: i64, h: i64, fill: &str) -> String {
        format!(
            "<rect x=\"{x}\" y=\"{y}\" width=\"{w}\" height=\"{h}\" fill=\"#{fill}\" stroke=\"#FFFFFF\"/>"
        )
    }

    #[test]
    fn base64_matches_the_rfc_examples() {
        assert_eq!(base64(b""), "");
        assert_eq!(base64(b"f"), "Zg==");
        assert_eq!(base64(b"fo"), "Zm8=");
        assert_eq!(base64(b"foo"), "Zm9v");
        assert_eq!(base64(b"foobar"), "Zm9vYmFy");
    }

    #[test]
    fn a_complete_grid_becomes_one_image_that_decodes_to_its_cells() {
        let hatch = "<rect x=\"11\" y=\"1\" width=\"8\" height=\"8\" fill=\"url(#hatch0)\" stroke=\"none\"/>";
        let mut svg = String::from("<svg>\n");
        let fills = ["110000", "220000", "330000", "440000", "550000", "660000"];
        for (k, f) in fills.iter().enumerate() {
            let (col, row) = (k as i64 % 3, k as i64 / 3);
            svg.push_str(&rect(col * 10 + i64::from(col == 2), row * 10, 10 + i64::from(col == 1), 10, f));
            svg.push('\n');
            if k == 1 {
                svg.push_str(hatch);
                svg.push('\n');
            }
        }
        svg.push_str("<text>after</text>\n</svg>\n");
        // Columns 0..10, 10..21, 21..31 (uneven, as plotters rounds), rows 0..10, 10..20.
        let out = grid_images(&svg);
        assert_eq!(out.matches("<rect").count(), 1, "only the hatching is left: {out}");
        assert!(out.contains("<image x=\"0\" y=\"0\" width=\"31\" height=\"20\""), "{out}");
        assert!(out.contains("d=\"M0 0H31M0 10H31M0 20H31M0 0V20M10 0V20M21 0V20M31 0V20\""), "{out}");
        let image_at = out.find("<image").unwrap();
        assert!(image_at < out.find(hatch).unwrap(), "overlays are drawn after the image");
        assert!(out.ends_with("<text>after</text>\n</svg>\n"));
        // The PNG holds a block of k × k pixels per cell, row by row: cells of 10 or 11 × 10
        // pixels are blocks of 3 × 3 (at most 4 figure pixels per image pixel).
        let b64 = out.split("base64,").nth(1).unwrap().split('"').next().unwrap();
        let (w, h, rgb) = decode_png(b64);
        let k = 3;
        assert_eq!(block_px(31.0 / 3.0, 10.0), k);
        assert_eq!((w, h), (3 * k, 2 * k));
        for y in 0..h {
            for x in 0..w {
                let cell = y / k * 3 + x / k;
                assert_eq!(
                    rgb[(y * w + x) * 3],
                    [0x11, 0x22, 0x33, 0x44, 0x55, 0x66][cell],
                    "pixel ({x}, {y})"
                );
            }
        }
    }

    #[test]
    fn blocks_keep_an_image_pixel_within_four_figure_pixels() {
        assert_eq!(block_px(1.0, 1.0), 2, "at least 2");
        assert_eq!(block_px(8.0, 3.0), 2);
        assert_eq!(block_px(37.1, 28.9), 10);
        assert_eq!(block_px(40.0, 167.0), 42);
    }

    #[test]
    fn an_image_drawn_twice_is_stored_once() {
        let bar = |x: i64| -> String {
            (0..5)
                .map(|k| {
                    format!(
                        "<rect x=\"{x}\" y=\"{}\" width=\"3\" height=\"4\" fill=\"#0{k}0000\" stroke=\"none\"/>\n",
                        40 - 4 * k
                    )
                })
                .collect()
        };
        let tall: String = (0..5)
            .map(|k| format!("<rect x=\"200\" y=\"{}\" width=\"3\" height=\"8\" fill=\"#0{k}0000\" stroke=\"none\"/>\n", 80 - 8 * k))
            .collect();
        let out = grid_images(&format!(
            "<svg>\n{}<text>a</text>\n{}<text>b</text>\n{tall}</svg>\n",
            bar(7),
            bar(100)
        ));
        assert_eq!(out.matches("base64,").count(), 1, "{out}");
        assert!(out.starts_with("<svg>\n<defs><symbol id=\"px0\" viewBox=\"0 0 1 5\" preserveAspectRatio=\"none\"><image width=\"1\" height=\"5\" style=\"image-rendering:pixelated\" href=\"data:image/png;base64,"), "{out}");
        assert!(out.contains("</symbol></defs>\n<use href=\"#px0\" x=\"7\" y=\"24\" width=\"3\" height=\"20\"/>\n<text>a</text>\n<use href=\"#px0\" x=\"100\" y=\"24\" width=\"3\" height=\"20\"/>\n<text>b</text>\n<use href=\"#px0\" x=\"200\" y=\"48\" width=\"3\" height=\"40\"/>\n</svg>\n"), "{out}");
        let doc = roxmltree::Document::parse(&out).unwrap();
        assert_eq!(doc.descendants().filter(|n| n.has_tag_name("use")).count(), 3);
    }

    #[test]
    fn a_grid_whose_edges_stray_from_even_spacing_stays_as_it_was() {
        // Widths 10, 10, 13: the last edge is 2 px from its even place (11 px steps).
        let g: Vec<String> = (0..6)
            .map(|k| rect([0, 10, 20][k % 3], k as i64 / 3 * 10, [10, 10, 13][k % 3], 10, "123456"))
            .collect();
        let svg = format!("{}\n", g.join("\n"));
        assert_eq!(grid_images(&svg), svg);
    }

    #[test]
    fn what_is_not_a_complete_grid_stays_as_it_was() {
        // Three cells of a 2 × 2 grid, then two separate grids drawn one after the other.
        let partial = [rect(0, 0, 5, 5, "111111"), rect(5, 0, 5, 5, "222222"), rect(0, 5, 5, 5, "333333")];
        let svg = format!("{}\n", partial.join("\n"));
        assert_eq!(grid_images(&svg), svg);
        let a: Vec<String> = (0..4).map(|k| rect(k % 2 * 5, k / 2 * 5, 5, 5, "444444")).collect();
        let b: Vec<String> = (0..4).map(|k| rect(100 + k % 2 * 5, k / 2 * 5, 5, 5, "555555")).collect();
        let out = grid_images(&format!("{}\n{}\n", a.join("\n"), b.join("\n")));
        assert_eq!(out.matches("<image").count(), 2, "{out}");
        assert_eq!(out.matches("<rect").count(), 0);
    }

    #[test]
    fn a_colour_bar_drawn_upwards_becomes_an_image_without_borders() {
        let bar: Vec<String> = (0..5)
            .map(|k| {
                format!(
                    "<rect x=\"7\" y=\"{}\" width=\"3\" height=\"4\" fill=\"#0{k}0000\" stroke=\"none\"/>",
                    40 - 4 * k
                )
            })
            .collect();
        let out = grid_images(&format!("{}\n", bar.join("\n")));
        assert!(out.starts_with("<image x=\"7\" y=\"24\" width=\"3\" height=\"20\""), "{out}");
        assert!(!out.contains("<path") && !out.contains("<rect"), "{out}");
        let b64 = out.split("base64,").nth(1).unwrap().split('"').next().unwrap();
        let (w, h, rgb) = decode_png(b64);
        assert_eq!((w, h), (1, 5), "one pixel per step");
        let reds: Vec<u8> = rgb.chunks(3).map(|p| p[0]).collect();
        assert_eq!(reds, vec![4, 3, 2, 1, 0], "the top row is the last drawn");
    }

    /// A base64 PNG's width, height and RGB pixels.
    fn decode_png(b64: &str) -> (usize, usize, Vec<u8>) {
        let mut dec = png::Decoder::new(std::io::Cursor::new(decode_base64(b64))).read_info().unwrap();
        let mut buf = vec![0; dec.output_buffer_size().unwrap()];
        let info = dec.next_frame(&mut buf).unwrap();
        buf.truncate(info.buffer_size());
        (info.width as usize, info.height as usize, buf)
    }

    fn decode_base64(s: &str) -> Vec<u8> {
        let val = |c: u8| {
            b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/".iter().position(|&x| x == c)
        };
        let mut out = Vec::new();
        for chunk in s.as_bytes().chunks(4) {
            let v: Vec<u32> = chunk.iter().filter_map(|&c| val(c)).map(|v| v as u32).collect();
            let n = v.iter().fold(0u32, |n, &d| n << 6 | d) << (6 * (4 - v.len()));
            out.extend(&[(n >> 16) as u8, (n >> 8) as u8, n as u8][..v.len() - 1]);
        }
        out
    }
}
