//! CSV (RFC 4180, `\n` line ends): one header line of field names, then one line per row. Numbers
//! are written in their shortest exact form, missing values as empty fields; no caption.

use crate::derive::table::model::{Column, Row, Table, TableWriter, Value};

/// CSV exporter.
#[derive(Debug, Clone, Copy, Default)]
pub struct Csv;

fn quote(s: &str) -> String {
    if s.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

/// The `n` fields a value writes.
fn fields(v: &Value, n: usize) -> Vec<String> {
    let num = |x: f64| format!("{x}");
    let mut f = match v {
        Value::Missing => vec![],
        Value::Text(t) | Value::User(t) => vec![quote(t)],
        Value::Int(i) => vec![i.to_string()],
        Value::Num { value, .. } => vec![num(*value)],
        Value::MeanStd { mean, std, .. } => vec![num(*mean), std.map(num).unwrap_or_default()],
        Value::Range { lo, hi, .. } => vec![num(*lo), num(*hi)],
        Value::List(items) => items.iter().map(|i| i.map(|i| i.to_string()).unwrap_or_default()).collect(),
    };
    debug_assert!(f.len() <= n, "{v:?} writes more than {n} CSV fields");
    f.resize(n, String::new());
    f
}

impl TableWriter for Csv {
    fn begin(&self, _table: &Table, _out: &mut String) {}

    fn header(&self, columns: &[Column], out: &mut String) {
        let names: Vec<String> = columns.iter().flat_map(|c| c.csv.iter().map(|s| quote(s))).collect();
        out.push_str(&names.join(","));
        out.push('\n');
    }

    fn row(&self, columns: &[Column], row: &Row, out: &mut String) {
        let f: Vec<String> =
            columns.iter().zip(&row.values).flat_map(|(c, v)| fields(v, c.csv.len())).collect();
        out.push_str(&f.join(","));
        out.push('\n');
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
algorithm,x_dot,mean,std,c_x,c_theta,diff
Q(λ)-learning,3,2.126,1,5,,0.5
\"a|b, \"\"c\"\"\",,200,,,,
";
        assert_eq!(render(&sample(), &Csv), expected);
    }
}
