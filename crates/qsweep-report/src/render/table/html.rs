//! HTML: a `<table>` with its caption, header and body; highlighted rows get `class="best"`,
//! number columns `class="r"`, or, when the number columns are all the columns after the first
//! k ≤ 4, the table gets `class="aK"` instead (the page's stylesheet right-aligns them), which
//! keeps a table of a thousand cells a third smaller; for the same reason cells omit their end
//! tags (`</td>`, `</th>`), which HTML implies before the next cell or the row's end. Styling is
//! left to the page.

use crate::derive::table::model::{display, Align, Column, Row, Symbols, Table, TableWriter};
use crate::render::escape::html;

/// HTML table exporter.
#[derive(Debug, Clone, Copy, Default)]
pub struct Html;

const SYMBOLS: Symbols = Symbols { dash: "—", pm: " ± ", dagger: "†", escape: html, user: html };

/// `k` when the right-aligned columns are exactly those after the first `k` (1 ≤ k ≤ 4).
fn right_suffix(columns: &[Column]) -> Option<usize> {
    let k = columns.iter().position(|c| c.align == Align::Right)?;
    ((1..=4).contains(&k) && columns[k..].iter().all(|c| c.align == Align::Right)).then_some(k)
}

fn class(columns: &[Column], c: &Column) -> &'static str {
    match c.align {
        Align::Right if right_suffix(columns).is_none() => " class=\"r\"",
        _ => "",
    }
}

impl TableWriter for Html {
    fn begin(&self, table: &Table, out: &mut String) {
        let class = right_suffix(&table.columns).map(|k| format!(" class=\"a{k}\"")).unwrap_or_default();
        out.push_str(&format!("<table{class}>\n"));
        if !table.caption.is_empty() {
            out.push_str(&format!(
                "<caption><b>{}.</b> {}</caption>\n",
                html(&table.title),
                html(&table.caption)
            ));
        }
    }

    fn header(&self, columns: &[Column], out: &mut String) {
        out.push_str("<thead><tr>");
        for c in columns {
            out.push_str(&format!("<th{}>{}", class(columns, c), html(&c.title)));
        }
        out.push_str("</tr></thead>\n<tbody>\n");
    }

    fn row(&self, columns: &[Column], row: &Row, out: &mut String) {
        out.push_str(if row.highlight { "<tr class=\"best\">" } else { "<tr>" });
        for (c, v) in columns.iter().zip(&row.values) {
            out.push_str(&format!("<td{}>{}", class(columns, c), display(v, &SYMBOLS)));
        }
        out.push_str("</tr>\n");
    }

    fn end(&self, _table: &Table, out: &mut String) {
        out.push_str("</tbody>\n</table>\n");
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::derive::table::{render, tests::sample};

    #[test]
    fn golden() {
        let expected = "\
<table>
<caption><b>Table T.</b> Mean ± std of Q(λ) runs; 50% &amp; more.</caption>
<thead><tr><th>Algorithm<th class=\"r\">ẋ<th class=\"r\">Performance<th>Config<th class=\"r\">Δ</tr></thead>
<tbody>
<tr><td>Q(λ)-learning<td class=\"r\">3<td class=\"r\">2.13 ± 1.00<td>5, —<td class=\"r\">+0.50</tr>
<tr class=\"best\"><td>a|b, &quot;c&quot;<td class=\"r\">—<td class=\"r\">200.00 ± —†<td>—<td class=\"r\">—</tr>
</tbody>
</table>
";
        assert_eq!(render(&sample(), &Html), expected);
        // Number columns after the first one only: the table's class aligns them.
        let mut t = sample();
        for c in &mut t.columns[1..] {
            c.align = Align::Right;
        }
        let out = render(&t, &Html);
        assert!(out.starts_with("<table class=\"a1\">\n"), "{out}");
        assert!(!out.contains("class=\"r\""), "{out}");
        assert!(out.contains("<tr><td>Q(λ)-learning<td>3<td>2.13 ± 1.00<td>5, —<td>+0.50</tr>"), "{out}");
    }
}
