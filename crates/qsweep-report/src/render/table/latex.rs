//! LaTeX (booktabs): a `table` float with the caption on top and a `tabular`; Unicode symbols
//! of the report (λ, θ, ẋ, ±, —, †, Δ) become math or TeX ligatures so pdflatex needs nothing
//! beyond `\usepackage{booktabs}`.

use crate::derive::table::model::{display, Align, Column, Row, Symbols, Table, TableWriter};
use crate::render::escape::{latex, latex_comment};

/// LaTeX exporter.
#[derive(Debug, Clone, Copy, Default)]
pub struct Latex;

const SYMBOLS: Symbols =
    Symbols { dash: "---", pm: " $\\pm$ ", dagger: "$^\\dagger$", escape: latex, user: latex };

impl TableWriter for Latex {
    fn begin(&self, table: &Table, out: &mut String) {
        let spec: String = table
            .columns
            .iter()
            .map(|c| match c.align {
                Align::Left => 'l',
                Align::Right => 'r',
            })
            .collect();
        out.push_str(&format!(
            "% {}: written by qsweep; needs \\usepackage{{booktabs}}.\n\\begin{{table}}[htbp]\n\\centering\n\\small\n\\caption{{{}}}\n\\begin{{tabular}}{{{spec}}}\n\\toprule\n",
            latex_comment(&table.title),
            latex(&table.caption)
        ));
    }

    fn header(&self, columns: &[Column], out: &mut String) {
        let titles: Vec<String> =
            columns.iter().map(|c| c.latex.clone().unwrap_or_else(|| latex(&c.title))).collect();
        out.push_str(&format!("{} \\\\\n\\midrule\n", titles.join(" & ")));
    }

    fn row(&self, _columns: &[Column], row: &Row, out: &mut String) {
        let cells: Vec<String> = row.values.iter().map(|v| display(v, &SYMBOLS)).collect();
        out.push_str(&format!("{} \\\\\n", cells.join(" & ")));
    }

    fn end(&self, _table: &Table, out: &mut String) {
        out.push_str("\\bottomrule\n\\end{tabular}\n\\end{table}\n");
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::derive::table::{render, tests::sample};

    #[test]
    fn golden() {
        let expected = r#"% Table T: written by qsweep; needs \usepackage{booktabs}.
\begin{table}[htbp]
\centering
\small
\caption{Mean $\pm$ std of Q($\lambda$) runs; 50\% \& more.}
\begin{tabular}{lrrlr}
\toprule
Algorithm & $\dot{x}$ & Performance & Config & $\Delta$ \\
\midrule
Q($\lambda$)-learning & 3 & 2.13 $\pm$ 1.00 & 5, --- & +0.50 \\
a\textbar{}b, "c" & --- & 200.00 $\pm$ ---$^\dagger$ & --- & --- \\
\bottomrule
\end{tabular}
\end{table}
"#;
        assert_eq!(render(&sample(), &Latex), expected);
    }
}
