//! The report of a program pipeline (`qsweep_pipeline::program`), as far as it goes today: its
//! trials as typed rows (`trials.parquet`: the cache's columns, after the experiment and variant
//! each trial belongs to) and a page of counts per experiment and cell (`README.md`). Written
//! atomically, each file only when its bytes change; an incomplete report never replaces a kept
//! one of more trials (unless forced), a complete one always does.

use crate::render::escape;
use crate::render::folder::existing_trials;
use arrow::array::{ArrayRef, StringArray};
use arrow::datatypes::{DataType, Field, Schema};
use arrow::record_batch::RecordBatch;
use qsweep_pipeline::atomic::write_if_changed;
use qsweep_pipeline::cache::Key;
use qsweep_pipeline::error::user_error;
use qsweep_pipeline::program::model::{MetricValue, ParamValue, ProgramPlan, ProgramRow};
use qsweep_pipeline::program::rows::{to_batch, RowSchema};
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// What a program report wrote.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ProgramReport {
    /// Files written or left as they were, relative to the report directory.
    pub files: Vec<PathBuf>,
    /// Of those, written (new, or their bytes changed); the others were left as they were.
    pub written: usize,
    /// Planned (cell, seed) trials.
    pub planned: usize,
    /// Of those, with a row in the cache.
    pub present: usize,
    /// Of those, failed.
    pub failed: usize,
}

/// Write the report of `plan` into `dir` from `rows` (the cache's row of each key present).
pub fn write(
    plan: &ProgramPlan,
    schema: &RowSchema,
    rows: &HashMap<Key, ProgramRow>,
    dir: &Path,
    force: bool,
) -> anyhow::Result<ProgramReport> {
    if dir.exists() && !dir.is_dir() {
        return Err(user_error(format!(
            "report directory {} is a file, not a directory; give another with --out DIR",
            dir.display()
        )));
    }
    let present: Vec<(&str, Option<&str>, &ProgramRow)> = plan
        .experiments
        .iter()
        .flat_map(|e| e.cells.iter().map(move |c| (e, c)))
        .flat_map(|(e, c)| {
            c.trials
                .iter()
                .filter_map(move |t| rows.get(&t.key).map(|r| (e.id.as_str(), e.variant.as_deref(), r)))
        })
        .collect();
    let distinct = present.iter().map(|p| p.2.key).collect::<std::collections::HashSet<_>>().len();
    let planned: usize = plan.experiments.iter().flat_map(|e| &e.cells).map(|c| c.trials.len()).sum();
    // The engine's rule: a complete report of the plan replaces whatever is kept; an incomplete
    // one never replaces a report of more trials (a fresh clone's empty cache, a wrong --cache).
    if !force && present.len() < planned {
        if let Some(kept) = existing_trials(dir)? {
            if kept > distinct {
                // Exit 1 like the engine's refusal: the pipeline is fine, the cache lacks trials.
                anyhow::bail!(
                    "{} holds a report of {kept} trials; this plan has {distinct} of its trials in the cache and \
                     lacks others: not replaced (run the missing trials, write elsewhere with --out DIR, or \
                     pass --force)",
                    dir.display()
                );
            }
        }
    }
    std::fs::create_dir_all(dir).map_err(|e| anyhow::anyhow!("cannot create {}: {e}", dir.display()))?;
    let mut out = ProgramReport {
        planned,
        present: present.len(),
        failed: present.iter().filter(|p| p.2.result.is_err()).count(),
        files: Vec::new(),
        written: 0,
    };
    let trials: Vec<ProgramRow> = present.iter().map(|p| p.2.clone()).collect();
    let batch = to_batch(schema, &trials)?;
    let with_variants = !plan.variants.is_empty();
    let mut fields: Vec<Field> = Vec::new();
    let mut columns: Vec<ArrayRef> = Vec::new();
    if with_variants {
        fields.push(Field::new("variant", DataType::Utf8, true));
        columns.push(Arc::new(present.iter().map(|p| p.1).collect::<StringArray>()));
    }
    fields.push(Field::new("experiment", DataType::Utf8, false));
    columns.push(Arc::new(StringArray::from_iter_values(present.iter().map(|p| p.0))));
    fields.extend(batch.schema().fields().iter().map(|f| f.as_ref().clone()));
    columns.extend(batch.columns().iter().cloned());
    let all = RecordBatch::try_new(
        Arc::new(Schema::new_with_metadata(fields, batch.schema().metadata().clone())),
        columns,
    )?;
    let parquet = qsweep_pipeline::parquet_io::to_parquet(&all)?;
    out.written += usize::from(write_if_changed(&dir.join("trials.parquet"), &parquet)?);
    out.files.push("trials.parquet".into());
    out.written += usize::from(write_if_changed(&dir.join("README.md"), page(plan, rows, &out).as_bytes())?);
    out.files.push("README.md".into());
    Ok(out)
}

/// `README.md`: the pipeline, its counts, and per experiment each cell's trials and the mean of
/// its objective (or first numeric metric) over the trials that succeeded.
fn page(plan: &ProgramPlan, rows: &HashMap<Key, ProgramRow>, out: &ProgramReport) -> String {
    let metric = plan
        .program
        .objective
        .as_ref()
        .and_then(|o| plan.program.metrics.iter().position(|(n, _)| *n == o.metric))
        .or_else(|| plan.program.metrics.iter().position(|(_, t)| t.is_scalar_number()));
    let mut m = format!("# qsweep report: {}\n\n", escape::markdown(&plan.name));
    if let Some(d) = &plan.description {
        m.push_str(&format!("{}\n\n", escape::markdown(d.trim())));
    }
    m.push_str(&format!(
        "Trials present: {} of {} planned; {} failed. Every trial's row: [trials.parquet](trials.parquet).\n",
        out.present, out.planned, out.failed
    ));
    for e in &plan.experiments {
        let variant =
            e.variant.as_deref().map(|v| format!(" (variant {})", escape::markdown(v))).unwrap_or_default();
        let title = e.title.as_deref().map(|t| format!(": {}", escape::markdown(t))).unwrap_or_default();
        m.push_str(&format!("\n## Experiment {}{title}{variant}\n\n", escape::markdown(&e.id)));
        let mut header: Vec<String> = e.axes.iter().map(|a| escape::markdown_cell(a)).collect();
        header.extend(["n".to_string(), "failed".to_string()]);
        if let Some(j) = metric {
            header.push(format!("mean {}", escape::markdown_cell(&plan.program.metrics[j].0)));
        }
        m.push_str(&format!("| {} |\n|{}\n", header.join(" | "), "---|".repeat(header.len())));
        for c in &e.cells {
            let got: Vec<&ProgramRow> = c.trials.iter().filter_map(|t| rows.get(&t.key)).collect();
            let ok: Vec<&Vec<MetricValue>> = got.iter().filter_map(|r| r.result.as_ref().ok()).collect();
            // Numbers and booleans are qsweep's text; only a string value is the author's.
            let mut cells: Vec<String> = c
                .coords
                .iter()
                .map(|v| match v {
                    ParamValue::Str(s) => escape::markdown_cell(s),
                    other => other.to_string(),
                })
                .collect();
            cells.push(got.len().to_string());
            cells.push((got.len() - ok.len()).to_string());
            if let Some(j) = metric {
                let values: Vec<f64> = ok
                    .iter()
                    .filter_map(|m| match m.get(j) {
                        Some(MetricValue::Int(i)) => Some(*i as f64),
                        Some(MetricValue::Float(x)) => Some(*x),
                        _ => None,
                    })
                    .collect();
                cells.push(if values.is_empty() {
                    "—".to_string()
                } else {
                    format!("{:.4}", qsweep_pipeline::analysis::mean(&values))
                });
            }
            m.push_str(&format!("| {} |\n", cells.join(" | ")));
        }
    }
    m
}
