//! A program pipeline's report files from its numbers ([`crate::derive::program`]): `cells.parquet`
//! (one row per cell and scalar metric), the figures ([`figures`]) and the pages ([`pages`]). Pure
//! functions: the same numbers give the same bytes.

pub mod figures;
pub mod pages;

use crate::derive::program::{ExperimentStats, FreshStats, ProgramStats};
use arrow::array::{ArrayRef, BooleanArray, Float64Array, StringArray, UInt64Array};
use arrow::datatypes::{DataType, Field, Schema};
use arrow::record_batch::RecordBatch;
use qsweep_pipeline::program::model::ProgramPlan;
use qsweep_pipeline::program::rows::{param_column, param_type};
use std::sync::Arc;

/// The columns of `cells.parquet` after `variant` (only with variants), `experiment` and one column
/// per param: one row per cell and scalar metric (docs/reports.md).
pub const CELL_COLUMNS: [&str; 17] = [
    "metric",
    "n",
    "mean",
    "std",
    "ci_lo",
    "ci_hi",
    "best",
    "planned",
    "present",
    "failed",
    "contender",
    "fresh_n",
    "fresh_mean",
    "fresh_std",
    "fresh_ci_lo",
    "fresh_ci_hi",
    "fresh_failed",
];

/// A number as pages and figures print it: at most four decimals, trailing zeros dropped.
pub fn num(x: f64) -> String {
    let s = format!("{x:.4}");
    let s = if s.contains('.') { s.trim_end_matches('0').trim_end_matches('.').to_string() } else { s };
    if s == "-0" {
        "0".into()
    } else {
        s
    }
}

/// A file name part from a free id: letters, digits, `-`, `_` and `.` kept, anything else `_`.
pub fn file_part(id: &str) -> String {
    id.chars().map(|c| if c.is_ascii_alphanumeric() || "-_.".contains(c) { c } else { '_' }).collect()
}

/// The stem of an experiment's figure files: `<experiment>` or `<variant>--<experiment>`.
pub fn figure_stem(e: &ExperimentStats) -> String {
    match &e.variant {
        Some(v) => format!("{}--{}", file_part(v), file_part(&e.id)),
        None => file_part(&e.id),
    }
}

/// `cells.parquet`'s rows as one batch.
pub fn cells_batch(plan: &ProgramPlan, stats: &ProgramStats) -> anyhow::Result<RecordBatch> {
    let with_variants = !plan.variants.is_empty();
    let rows: Vec<(&ExperimentStats, usize, usize)> = stats
        .experiments
        .iter()
        .flat_map(|e| (0..e.cells.len()).flat_map(move |c| (0..stats.scalars.len()).map(move |m| (e, c, m))))
        .collect();
    let mut fields: Vec<Field> = Vec::new();
    let mut columns: Vec<ArrayRef> = Vec::new();
    if with_variants {
        fields.push(Field::new("variant", DataType::Utf8, true));
        columns.push(Arc::new(rows.iter().map(|r| r.0.variant.as_deref()).collect::<StringArray>()));
    }
    fields.push(Field::new("experiment", DataType::Utf8, false));
    columns.push(Arc::new(StringArray::from_iter_values(rows.iter().map(|r| r.0.id.as_str()))));
    for (p, (name, t)) in plan.params.iter().enumerate() {
        fields.push(Field::new(name, param_type(*t), false));
        columns.push(param_column(name, *t, rows.iter().map(|r| r.0.cells[r.1].params.get(p)))?);
    }
    let summary = |r: &(&ExperimentStats, usize, usize)| r.0.cells[r.1].scalars[r.2];
    let opt = |f: fn(&qsweep_pipeline::analysis::Summary) -> Option<f64>| -> ArrayRef {
        Arc::new(rows.iter().map(|r| f(&summary(r))).collect::<Float64Array>())
    };
    let count = |f: &dyn Fn(&(&ExperimentStats, usize, usize)) -> usize| -> ArrayRef {
        Arc::new(rows.iter().map(|r| f(r) as u64).collect::<UInt64Array>())
    };
    // The best cell's fresh-seed estimate (null in every other cell's rows).
    fn fresh<'a>(r: &(&'a ExperimentStats, usize, usize)) -> Option<&'a FreshStats> {
        r.0.cells[r.1].fresh.as_ref()
    }
    let fresh_opt = |f: fn(&qsweep_pipeline::analysis::Summary) -> Option<f64>| -> ArrayRef {
        Arc::new(rows.iter().map(|r| fresh(r).and_then(|x| f(&x.scalars[r.2]))).collect::<Float64Array>())
    };
    let fresh_count = |f: &dyn Fn(&FreshStats) -> usize| -> ArrayRef {
        Arc::new(rows.iter().map(|r| fresh(r).map(|x| f(x) as u64)).collect::<UInt64Array>())
    };
    let values: Vec<(DataType, bool, ArrayRef)> = vec![
        (
            DataType::Utf8,
            false,
            Arc::new(StringArray::from_iter_values(rows.iter().map(|r| stats.scalars[r.2].0.as_str()))),
        ),
        (DataType::UInt64, false, count(&|r| summary(r).n)),
        (DataType::Float64, true, opt(|s| s.mean)),
        (DataType::Float64, true, opt(|s| s.std)),
        (DataType::Float64, true, opt(|s| s.ci_lo)),
        (DataType::Float64, true, opt(|s| s.ci_hi)),
        (
            DataType::Boolean,
            false,
            Arc::new(rows.iter().map(|r| Some(r.0.best == Some(r.1))).collect::<BooleanArray>()),
        ),
        (DataType::UInt64, false, count(&|r| r.0.cells[r.1].planned)),
        (DataType::UInt64, false, count(&|r| r.0.cells[r.1].present)),
        (DataType::UInt64, false, count(&|r| r.0.cells[r.1].failed)),
        (
            DataType::Boolean,
            true,
            Arc::new(rows.iter().map(|r| r.0.cells[r.1].contender).collect::<BooleanArray>()),
        ),
        (
            DataType::UInt64,
            true,
            Arc::new(rows.iter().map(|r| fresh(r).map(|x| x.scalars[r.2].n as u64)).collect::<UInt64Array>()),
        ),
        (DataType::Float64, true, fresh_opt(|s| s.mean)),
        (DataType::Float64, true, fresh_opt(|s| s.std)),
        (DataType::Float64, true, fresh_opt(|s| s.ci_lo)),
        (DataType::Float64, true, fresh_opt(|s| s.ci_hi)),
        (DataType::UInt64, true, fresh_count(&|f| f.failed)),
    ];
    for (name, (t, nullable, column)) in CELL_COLUMNS.iter().zip(values) {
        fields.push(Field::new(*name, t, nullable));
        columns.push(column);
    }
    Ok(RecordBatch::try_new(Arc::new(Schema::new(fields)), columns)?)
}

/// `cells.parquet`'s bytes.
pub fn cells_parquet(plan: &ProgramPlan, stats: &ProgramStats) -> anyhow::Result<Vec<u8>> {
    qsweep_pipeline::parquet_io::to_parquet(&cells_batch(plan, stats)?)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_print_with_at_most_four_decimals_and_no_trailing_zeros() {
        assert_eq!(num(12.0), "12");
        assert_eq!(num(0.12345), "0.1235");
        assert_eq!(num(2.5), "2.5");
        assert_eq!(num(-0.00001), "0");
        assert_eq!(num(1234.5), "1234.5");
    }

    #[test]
    fn file_parts_keep_safe_characters_only() {
        assert_eq!(file_part("bins-alpha_2.x"), "bins-alpha_2.x");
        assert_eq!(file_part("a/b <c>"), "a_b__c_");
    }
}
