//! Format-neutral tables and one small exporter trait. A [`Table`] holds typed [`Value`]s; a
//! [`TableWriter`] (Markdown, CSV, LaTeX, HTML) only decides how a caption, the header and a row
//! are written. A value may span several CSV fields (mean ± std → `mean`, `std`), which is why
//! each [`Column`] names its CSV fields.

mod cells;
pub(crate) mod model;

pub use cells::cell_table;
pub use model::{render, Align, Column, Row, Table, TableWriter, Value};

#[cfg(test)]
pub(crate) mod tests {
    use super::model::fixed;
    use super::*;

    /// The small fixed table of the exporter golden tests.
    pub(crate) fn sample() -> Table {
        Table {
            title: "Table T".into(),
            caption: "Mean ± std of Q(λ) runs; 50% & more.".into(),
            columns: vec![
                Column::new("Algorithm", "algorithm", Align::Left),
                Column::new("ẋ", "x_dot", Align::Right).latex("$\\dot{x}$"),
                Column::new("Performance", "mean", Align::Right).fields(&["mean", "std"]),
                Column::new("Config", "config", Align::Left).fields(&["c_x", "c_theta"]),
                Column::new("Δ", "diff", Align::Right),
            ],
            rows: vec![
                Row {
                    values: vec![
                        Value::Text("Q(λ)-learning".into()),
                        Value::Int(3),
                        Value::MeanStd { mean: 2.126, std: Some(1.0), decimals: 2, marked: false },
                        Value::List(vec![Some(5), None]),
                        Value::Num { value: 0.5, decimals: 2, signed: true },
                    ],
                    highlight: false,
                },
                Row {
                    values: vec![
                        Value::Text("a|b, \"c\"".into()),
                        Value::Missing,
                        Value::MeanStd { mean: 200.0, std: None, decimals: 2, marked: true },
                        Value::Missing,
                        Value::Missing,
                    ],
                    highlight: true,
                },
            ],
        }
    }

    #[test]
    fn fixed_formats_signs_and_negative_zero() {
        assert_eq!(fixed(-0.001, 2, false), "0.00");
        assert_eq!(fixed(-0.001, 2, true), "0.00");
        assert_eq!(fixed(1.005, 1, true), "+1.0");
        assert_eq!(fixed(-2.5, 1, true), "-2.5");
        assert_eq!(fixed(3.0, 0, false), "3");
    }
}
