//! Heatmaps look the same in every viewer: a heatmap's cells are one embedded PNG, and a viewer
//! that smooths the PNG as it scales it (librsvg, Inkscape) must still show every cell in its own
//! colour. So each cell is a uniform block of k × k pixels (k ≥ 2), the image is the cells × k,
//! and the white cell borders drawn over it fall on the blocks' edges.

use crate::helpers::Sandbox;

fn base64(s: &str) -> Vec<u8> {
    let val = |c: u8| {
        b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/".iter().position(|&x| x == c)
    };
    let digits: Vec<u32> = s.bytes().filter_map(val).map(|v| v as u32).collect();
    let mut out = Vec::new();
    for chunk in digits.chunks(4) {
        let n = chunk.iter().fold(0u32, |n, &d| n << 6 | d) << (6 * (4 - chunk.len()));
        out.extend(&[(n >> 16) as u8, (n >> 8) as u8, n as u8][..chunk.len() - 1]);
    }
    out
}

/// Width, height and RGB pixels of a `data:image/png;base64,` URL.
fn decode(href: &str) -> (usize, usize, Vec<u8>) {
    let bytes = base64(href.strip_prefix("data:image/png;base64,").expect("an embedded PNG"));
    let mut dec = png::Decoder::new(std::io::Cursor::new(bytes)).read_info().unwrap();
    let mut buf = vec![0; dec.output_buffer_size().unwrap()];
    let info = dec.next_frame(&mut buf).unwrap();
    assert_eq!(info.color_type, png::ColorType::Rgb);
    buf.truncate(info.buffer_size());
    (info.width as usize, info.height as usize, buf)
}

/// The numbers of a path's `M… H…` (rows) and `M… V…` (columns) edges.
fn edges(d: &str) -> (usize, usize) {
    (d.matches('H').count(), d.matches('V').count())
}

#[test]
fn each_heatmap_cell_is_a_uniform_block_of_pixels() {
    let sb = Sandbox::new();
    let p = sb.fixture("tiny.yaml");
    let out = sb.path("rep");
    let args = ["run", p.to_str().unwrap(), "--quiet", "--formats", "svg", "--out", out.to_str().unwrap()];
    sb.qsweep(&args).assert().success();
    let mut heatmaps = 0;
    for system in ["ball-beam", "mountain-car"] {
        let svg = std::fs::read_to_string(out.join(format!("figures/{system}.svg"))).unwrap();
        let doc = roxmltree::Document::parse(&svg).unwrap();
        let symbol = |id: &str| {
            let s = doc.descendants().find(|n| n.attribute("id") == Some(id)).expect("the symbol used");
            s.children().find(|n| n.has_tag_name("image")).unwrap()
        };
        let drawn: Vec<roxmltree::Node> = doc.root_element().children().filter(|n| n.is_element()).collect();
        for (i, n) in drawn.iter().enumerate() {
            let image = match n.tag_name().name() {
                "image" => *n,
                "use" => symbol(n.attribute("href").unwrap().trim_start_matches('#')),
                _ => continue,
            };
            // A heatmap's image is followed by the white path of its cell borders.
            let Some(border) = drawn
                .get(i + 1)
                .filter(|b| b.has_tag_name("path") && b.attribute("stroke") == Some("#FFFFFF"))
            else {
                continue;
            };
            let (rows, cols) = edges(border.attribute("d").unwrap());
            let (ny, nx) = (rows - 1, cols - 1);
            let (w, h, rgb) = decode(image.attribute("href").unwrap());
            let k = w / nx;
            assert!(k >= 2, "{system}: {k} pixels per cell");
            assert_eq!((w, h), (nx * k, ny * k), "{system}: {nx} × {ny} cells of {k} × {k} pixels");
            for cy in 0..ny {
                for cx in 0..nx {
                    let px = |x: usize, y: usize| &rgb[(y * w + x) * 3..(y * w + x) * 3 + 3];
                    let first = px(cx * k, cy * k);
                    for y in cy * k..(cy + 1) * k {
                        for x in cx * k..(cx + 1) * k {
                            assert_eq!(px(x, y), first, "{system}: cell ({cx}, {cy}) is one colour");
                        }
                    }
                }
            }
            heatmaps += 1;
        }
    }
    // tiny.yaml: two experiments per system, each drawn for both algorithms; Mountain Car's
    // Exp. 3 has two cells, too few for an image (they stay rectangles).
    assert_eq!(heatmaps, 6);
}
