//! GitHub-flavoured Markdown: the caption as a bold-titled paragraph, then a pipe table.

use crate::derive::table::model::{display, Align, Column, Row, Symbols, Table, TableWriter};
use crate::render::escape::{markdown_cell, markdown_table_text as escape};

/// Markdown exporter.
#[derive(Debug, Clone, Copy, Default)]
pub struct Markdown;

const SYMBOLS: Symbols = Symbols { dash: "—", pm: " ± ", dagger: "†", escape, user: markdown_cell };

impl TableWriter for Markdown {
    fn begin(&self, table: &Table, out: &mut String) {
        out.push_str(&format!("**{}.** {}\n\n", escape(&table.title), escape(&table.caption)));
    }

    fn header(&self, columns: &[Column], out: &mut String) {
        let titles: Vec<String> = columns.iter().map(|c| escape(&c.title)).collect();
        let rules: Vec<&str> = columns
            .iter()
            .map(|c| match c.align {
                Align::Left => ":--",
                Align::Right => "--:",
            })
            .collect();
        out.push_str(&format!("| {} |\n| {} |\n", titles.join(" | "), rules.join(" | ")));
    }

    fn row(&self, _columns: &[Column], row: &Row, out: &mut String) {
        let cells: Vec<String> = row.values.iter().map(|v| display(v, &SYMBOLS)).collect();
        out.push_str(&format!("| {} |\n", cells.join(" | ")));
    }

    fn end(&self, _table: &Table, _out: &mut String) {}
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::derive::table::{render, tests::sample};

    #[test]
    fn golden() {
        let expected = "\
**Table T.** Mean ± std of Q(λ) runs; 50% & more.

| Algorithm | ẋ | Performance | Config | Δ |
| :-- | --: | --: | :-- | --: |
| Q(λ)-learning | 3 | 2.13 ± 1.00 | 5, — | +0.50 |
| a\\|b, \"c\" | — | 200.00 ± —† | — | — |
";
        assert_eq!(render(&sample(), &Markdown), expected);
    }
}
