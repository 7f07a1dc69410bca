//! HTML: a `<table>` with its caption, header and body; highlighted rows get `class="best"`,
//! number columns `class="r"`. Styling is left to the page.

use super::{display, Align, Column, Row, Symbols, Table, TableWriter};

/// HTML table exporter.
#[derive(Debug, Clone, Copy, Default)]
pub struct Html;

const SYMBOLS: Symbols = Symbols { dash: "—", pm: " ± ", dagger: "†", escape: escape_html };

/// Escape text for HTML element content and attribute values.
pub fn escape_html(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&#39;"),
            _ => out.push(c),
        }
    }
    out
}

fn class(c: &Column) -> &'static str {
    match c.align {
        Align::Left => "",
        Align::Right => " class=\"r\"",
    }
}

impl TableWriter for Html {
    fn begin(&self, table: &Table, out: &mut String) {
        out.push_str(&format!(
            "<table>\n<caption><b>{}.</b> {}</caption>\n",
            escape_html(&table.title),
            escape_html(&table.caption)
        ));
    }

    fn header(&self, columns: &[Column], out: &mut String) {
        out.push_str("<thead><tr>");
        for c in columns {
            out.push_str(&format!("<th{}>{}</th>", class(c), escape_html(&c.title)));
        }
        out.push_str("</tr></thead>\n<tbody>\n");
    }

    fn row(&self, columns: &[Column], row: &Row, out: &mut String) {
        out.push_str(if row.highlight { "<tr class=\"best\">" } else { "<tr>" });
        for (c, v) in columns.iter().zip(&row.values) {
            out.push_str(&format!("<td{}>{}</td>", class(c), display(v, &SYMBOLS)));
        }
        out.push_str("</tr>\n");
    }

    fn end(&self, _table: &Table, out: &mut String) {
        out.push_str("</tbody>\n</table>\n");
    }
}

#[cfg(test)]
mod tests {
    use super::super::{render, tests::sample};
    use super::*;

    #[test]
    fn golden() {
        let expected = "\
<table>
<caption><b>Table T.</b> Mean ± std of Q(λ) runs; 50% &amp; more.</caption>
<thead><tr><th>Algorithm</th><th class=\"r\">ẋ</th><th class=\"r\">Performance</th><th>Config</th><th class=\"r\">Δ</th></tr></thead>
<tbody>
<tr><td>Q(λ)-learning</td><td class=\"r\">3</td><td class=\"r\">2.13 ± 1.00</td><td>5, —</td><td class=\"r\">+0.50</td></tr>
<tr class=\"best\"><td>a|b, &quot;c&quot;</td><td class=\"r\">—</td><td class=\"r\">200.00 ± —†</td><td>—</td><td class=\"r\">—</td></tr>
</tbody>
</table>
";
        assert_eq!(render(&sample(), &Html), expected);
    }
}
