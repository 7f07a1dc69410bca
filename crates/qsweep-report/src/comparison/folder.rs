//! An engine report folder as a side of `qsweep compare`: its `cells.parquet` (a variant's folder,
//! `reports/paper/as-written`, or the root of a pipeline with variants, `reports/paper`, whose
//! rows carry a `variant` column), one cell per row with the moments (n, mean, std) of the
//! episodes Table III counts. Two engine versions plan different keys, so no one binary can plan
//! both: their committed reports are what can be compared. The params are the engine
//! pipeline's ([`super::cells::ENGINE_PARAMS`], each varied setting after them), led by
//! `variant` when the rows have one and no `@VARIANT` picked it.

use super::cells::{
    count_value, experiment_value, CellSet, Sample, SetCell, ABSENT, ENGINE_PARAMS, EPISODES,
};
use arrow::array::{Array, Float64Array, Int64Array, RecordBatch, StringArray};
use arrow::datatypes::DataType;
use parquet::arrow::arrow_reader::ParquetRecordBatchReaderBuilder;
use qsweep_pipeline::analysis::Moments;
use qsweep_pipeline::error::user_error;
use qsweep_pipeline::program::model::ParamValue;
use std::path::Path;

/// The file a report folder is read from.
pub const CELLS: &str = "cells.parquet";

/// The state variables' columns, in [`ENGINE_PARAMS`] order.
const VARIABLES: [&str; 4] = ["x", "x_dot", "theta", "theta_dot"];

/// One column read as text, integers or floats (cast from what the file holds, so a report of
/// an older engine with other integer widths reads alike).
fn column(
    batch: &RecordBatch,
    name: &str,
    to: &DataType,
    file: &Path,
) -> anyhow::Result<Option<arrow::array::ArrayRef>> {
    let Some(c) = batch.column_by_name(name) else { return Ok(None) };
    arrow::compute::cast(c, to)
        .map(Some)
        .map_err(|e| user_error(format!("{}: column `{name}` cannot be read as {to}: {e}", file.display())))
}

/// The cells of the report folder `dir`, only those of `variant` when given.
pub fn read(dir: &Path, variant: Option<&str>) -> anyhow::Result<CellSet> {
    let (file, batches) = open(dir)?;
    let schema_has = |n: &str| batches.first().is_some_and(|b| b.column_by_name(n).is_some());
    let has_variant = schema_has("variant");
    if let Some(v) = variant {
        if !has_variant {
            return Err(user_error(format!(
                "{}@{v}: this folder's {CELLS} has no variant column (one variant's folder already); drop @{v}",
                dir.display()
            )));
        }
    }
    let settings = varied_settings(&batches, &file)?;
    let lead_variant = has_variant && variant.is_none();
    let mut params: Vec<String> = Vec::new();
    if lead_variant {
        params.push("variant".into());
    }
    params.extend(ENGINE_PARAMS.iter().map(|s| s.to_string()));
    params.extend(settings.iter().cloned());
    let mut cells = Vec::new();
    for b in &batches {
        let text = |n: &str| -> anyhow::Result<Option<StringArray>> {
            Ok(column(b, n, &DataType::Utf8, &file)?
                .map(|c| c.as_any().downcast_ref::<StringArray>().expect("cast to utf8").clone()))
        };
        let int = |n: &str| -> anyhow::Result<Option<Int64Array>> {
            Ok(column(b, n, &DataType::Int64, &file)?
                .map(|c| c.as_any().downcast_ref::<Int64Array>().expect("cast to int64").clone()))
        };
        let float = |n: &str| -> anyhow::Result<Option<Float64Array>> {
            Ok(column(b, n, &DataType::Float64, &file)?
                .map(|c| c.as_any().downcast_ref::<Float64Array>().expect("cast to float64").clone()))
        };
        let need = |c: Option<StringArray>| c.expect("checked above");
        let (system, repr, algorithm, experiment) =
            (need(text("system")?), need(text("repr")?), need(text("algorithm")?), need(text("experiment")?));
        let vars: Vec<Option<Int64Array>> = VARIABLES.iter().map(|v| int(v)).collect::<Result<_, _>>()?;
        let actions = int("actions")?.expect("checked above");
        let n = int("n")?.expect("checked above");
        let (mean, std) = (float("mean")?.expect("checked above"), float("std")?.expect("checked above"));
        let variant_col = text("variant")?;
        let max_episodes = int("max_episodes")?;
        let axes =
            [(text("axis1_label")?, float("axis1_value")?), (text("axis2_label")?, float("axis2_value")?)];
        for i in 0..b.num_rows() {
            let row_variant = variant_col.as_ref().filter(|c| c.is_valid(i)).map(|c| c.value(i).to_string());
            if variant.is_some() && row_variant.as_deref() != variant {
                continue;
            }
            let s = |c: &StringArray| if c.is_valid(i) { c.value(i).to_string() } else { String::new() };
            let count = |c: &Option<Int64Array>| {
                c.as_ref().filter(|c| c.is_valid(i)).map(|c| u32::try_from(c.value(i)).unwrap_or(u32::MAX))
            };
            let mut values = Vec::new();
            if lead_variant {
                values.push(ParamValue::Str(row_variant.clone().unwrap_or_default()));
            }
            values.push(ParamValue::Str(s(&system)));
            values.push(ParamValue::Str(s(&repr)));
            values.push(ParamValue::Str(s(&algorithm)));
            values.push(experiment_value(&s(&experiment)));
            let res: Vec<u32> = vars.iter().filter_map(count).collect();
            values.extend(vars.iter().map(|c| count_value(count(c))));
            values.push(count_value(count(&Some(actions.clone()))));
            values.push(super::cells::resolution_value(&res));
            for name in &settings {
                let at = axes.iter().find_map(|(l, v)| {
                    let (l, v) = (l.as_ref()?, v.as_ref()?);
                    (l.is_valid(i)
                        && v.is_valid(i)
                        && l.value(i).split("==").map(str::trim).any(|x| x == name))
                    .then(|| v.value(i))
                });
                values.push(at.map_or_else(|| ParamValue::Str(ABSENT.to_string()), ParamValue::Float));
            }
            // One configuration's cells (e.g. in two experiments) have the same values besides the
            // experiment and its axes, and the same cap.
            let identity = values
                .iter()
                .enumerate()
                .filter(|(k, _)| params[*k] != "experiment")
                .map(|(_, v)| v.to_string())
                .chain(count(&max_episodes).map(|m| m.to_string()))
                .collect::<Vec<_>>()
                .join("\0");
            let n_i = if n.is_valid(i) { usize::try_from(n.value(i)).unwrap_or(0) } else { 0 };
            let moments = Moments {
                mean: if mean.is_valid(i) { mean.value(i) } else { f64::NAN },
                std: std.is_valid(i).then(|| std.value(i)),
                n: n_i,
            };
            cells.push(SetCell { params: values, identity, samples: vec![Sample::Moments(moments)] });
        }
    }
    if let (Some(v), true) = (variant, cells.is_empty()) {
        return Err(no_such_variant(dir, v, &batches, &file)?);
    }
    Ok(CellSet { what: "report folder", params, metrics: vec![EPISODES.to_string()], cells })
}

/// The batches of `dir`'s cells.parquet, checked to be an engine report's.
fn open(dir: &Path) -> anyhow::Result<(std::path::PathBuf, Vec<RecordBatch>)> {
    let file = dir.join(CELLS);
    if !file.is_file() {
        return Err(user_error(format!(
            "{}: no {CELLS} in this folder: give an engine report folder (e.g. reports/paper/as-written, \
             or reports/paper with its variant column), written with the `cells` format",
            dir.display()
        )));
    }
    let bad = |e: &dyn std::fmt::Display| {
        user_error(format!("{}: cannot read it as an engine report's cells: {e}", file.display()))
    };
    let reader = ParquetRecordBatchReaderBuilder::try_new(std::fs::File::open(&file)?)
        .map_err(|e| bad(&e))?
        .build()
        .map_err(|e| bad(&e))?;
    let batches: Vec<RecordBatch> = reader.collect::<Result<_, _>>().map_err(|e| bad(&e))?;
    let schema_has = |n: &str| batches.first().is_some_and(|b| b.column_by_name(n).is_some());
    for need in ["system", "repr", "algorithm", "experiment", "actions", "n", "mean", "std"] {
        if !batches.is_empty() && !schema_has(need) {
            return Err(user_error(format!(
                "{}: no column `{need}`: not an engine report's {CELLS} (a program pipeline's report is compared through its pipeline file)",
                file.display()
            )));
        }
    }
    Ok((file, batches))
}

/// The varied settings: every axis label's names that are no state variable and not `actions`.
fn varied_settings(batches: &[RecordBatch], file: &Path) -> anyhow::Result<Vec<String>> {
    let mut settings: Vec<String> = Vec::new();
    for b in batches {
        for axis in ["axis1_label", "axis2_label"] {
            let Some(c) = column(b, axis, &DataType::Utf8, file)? else { continue };
            let c = c.as_any().downcast_ref::<StringArray>().expect("cast to utf8");
            for label in c.iter().flatten() {
                for name in label.split("==").map(str::trim) {
                    if !VARIABLES.contains(&name) && name != "actions" && !settings.iter().any(|s| s == name)
                    {
                        settings.push(name.to_string());
                    }
                }
            }
        }
    }
    Ok(settings)
}

/// The error of `@v` naming no variant of the folder, with the variants it has.
fn no_such_variant(
    dir: &Path,
    v: &str,
    batches: &[RecordBatch],
    file: &Path,
) -> anyhow::Result<anyhow::Error> {
    let mut known: Vec<String> = Vec::new();
    for b in batches {
        if let Some(c) = column(b, "variant", &DataType::Utf8, file)? {
            for x in c.as_any().downcast_ref::<StringArray>().expect("utf8").iter().flatten() {
                if !known.iter().any(|k| k == x) {
                    known.push(x.to_string());
                }
            }
        }
    }
    Ok(user_error(format!(
        "{}@{v}: no variant `{v}` in its {CELLS} (its variants: {})",
        dir.display(),
        known.join(", ")
    )))
}
