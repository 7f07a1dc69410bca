//! The report stage: from a plan and the trial records found for it, write
//!
//! - `table3.md`, `table3.csv`, `table3.tex`: the paper's Table III (best cell per system,
//!   experiment and algorithm, with the paper's values when the pipeline gives them);
//! - `cells.parquet`, `trials.parquet`: the data behind it (schemas in [`parquet`]);
//! - `figures/<system>.svg` and `.png`: the paper's Figures 5–7 (see [`figures`]);
//! - `figures/<system>-curves.svg` and `.png`: learning curves of the best cells (see [`curves`]);
//! - `index.html`: one self-contained page with all of the above (the figures inlined as SVG).
//!
//! Trials missing from the records are left out and counted. Every file is written atomically
//! (a temporary file in the same directory, then a rename), and the output is a pure function of
//! the inputs: no timestamps, no hash-map order, a seeded bootstrap.

pub mod curves;
pub mod figures;
pub mod glyphs;
pub mod html;
pub mod model;
pub mod parquet;
pub mod stats;
pub mod table;
pub mod variants;

use crate::cache::{Key, TrialRecord};
use crate::plan::Plan;
use anyhow::Context;
use std::collections::HashMap;
use std::path::{Path, PathBuf};

pub use crate::atomic::write_atomic;
pub use model::ReportData;

/// What [`write_report`] wrote.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ReportSummary {
    /// Experiments in the plan.
    pub experiments: usize,
    /// Cells in the plan.
    pub cells: usize,
    /// Cells with at least one trial present.
    pub cells_with_trials: usize,
    /// Planned (cell, seed) trials; a trial shared by two cells counts twice.
    pub trials_planned: usize,
    /// Of those, present in the records.
    pub trials_present: usize,
    /// Of those, missing.
    pub trials_missing: usize,
    /// Files written, relative to the report directory, in writing order.
    pub files: Vec<PathBuf>,
}

/// Write the report of `plan` into `dir`: for a pipeline without variants, [`write_report`]; with
/// variants, each variant's full report into `dir/<variant-id>/`, and into `dir` itself the
/// comparison of the variants and `cells.parquet` / `trials.parquet` of all of them (with a
/// `variant` column). Returns the summary of the whole plan.
pub fn write_reports(
    plan: &Plan,
    records: &HashMap<Key, TrialRecord>,
    dir: &Path,
) -> anyhow::Result<ReportSummary> {
    if plan.variants.is_empty() {
        return write_report(plan, records, dir);
    }
    std::fs::create_dir_all(dir.join("figures"))
        .with_context(|| format!("cannot create the report directory {}", dir.display()))?;
    let subs: Vec<Plan> = plan.variants.iter().map(|v| plan.only_variant(&v.id)).collect();
    let mut files = Vec::new();
    for (v, sub) in plan.variants.iter().zip(&subs) {
        let s = write_report(sub, records, &dir.join(&v.id))?;
        files.extend(s.files.into_iter().map(|f| Path::new(&v.id).join(f)));
    }
    let data = ReportData::build(plan, records);
    if plan.variant_subset {
        // The comparison and the combined data cover every variant: a report of some of them
        // would replace it with less, so it is left as it is.
        return Ok(summary(&data, files));
    }
    write_atomic(&dir.join("cells.parquet"), &parquet::cells_parquet(&data)?)?;
    write_atomic(&dir.join("trials.parquet"), &parquet::trials_parquet(&data)?)?;
    files.extend(["cells.parquet", "trials.parquet"].map(PathBuf::from));
    let per_variant: Vec<(variants::VariantInfo, ReportData)> = plan
        .variants
        .iter()
        .zip(&subs)
        .map(|(v, sub)| {
            (
                variants::VariantInfo { id: v.id.clone(), title: v.title.clone() },
                ReportData::build(sub, records),
            )
        })
        .collect();
    files.extend(variants::write_comparison(dir, &per_variant)?);
    Ok(summary(&data, files))
}

fn summary(data: &ReportData, files: Vec<PathBuf>) -> ReportSummary {
    let cells: Vec<_> = data.experiments.iter().flat_map(|e| &e.cells).collect();
    ReportSummary {
        experiments: data.experiments.len(),
        cells: cells.len(),
        cells_with_trials: cells.iter().filter(|c| !c.trials.is_empty()).count(),
        trials_planned: data.trials_planned,
        trials_present: data.trials_present,
        trials_missing: data.trials_planned - data.trials_present,
        files,
    }
}

/// Write the report of `plan` from `records` (keyed by trial key) into `dir`, creating it.
pub fn write_report(
    plan: &Plan,
    records: &HashMap<Key, TrialRecord>,
    dir: &Path,
) -> anyhow::Result<ReportSummary> {
    std::fs::create_dir_all(dir.join("figures"))
        .with_context(|| format!("cannot create the report directory {}", dir.display()))?;
    let data = ReportData::build(plan, records);
    let mut files = Vec::new();
    let mut put = |name: &str, bytes: &[u8]| -> anyhow::Result<()> {
        write_atomic(&dir.join(name), bytes)?;
        files.push(PathBuf::from(name));
        Ok(())
    };

    let t3 = table::table3(&data);
    put("table3.md", table::render(&t3, &table::Markdown).as_bytes())?;
    put("table3.csv", table::render(&t3, &table::Csv).as_bytes())?;
    put("table3.tex", table::render(&t3, &table::Latex).as_bytes())?;
    put("cells.parquet", &parquet::cells_parquet(&data)?)?;
    put("trials.parquet", &parquet::trials_parquet(&data)?)?;
    let mut svgs = Vec::new();
    let mut curve_svgs = Vec::new();
    for system in data.systems() {
        let (svg, png) = figures::render(&data, system)?;
        put(&format!("figures/{}.svg", system.name()), svg.as_bytes())?;
        put(&format!("figures/{}.png", system.name()), &png)?;
        svgs.push((system.name().to_string(), svg));
        let (svg, png) = curves::render(&data, system)?;
        put(&format!("figures/{}-curves.svg", system.name()), svg.as_bytes())?;
        put(&format!("figures/{}-curves.png", system.name()), &png)?;
        curve_svgs.push((system.name().to_string(), svg));
    }
    put("index.html", html::page(&data, &svgs, &curve_svgs).as_bytes())?;
    Ok(summary(&data, files))
}

/// How many distinct trials the report already in `dir` holds (distinct `key`s of its
/// `trials.parquet`); `None` when there is no report there. Lets `qsweep report` refuse to replace
/// a report with a smaller one.
pub fn existing_trials(dir: &Path) -> anyhow::Result<Option<usize>> {
    use ::parquet::arrow::arrow_reader::ParquetRecordBatchReaderBuilder;
    use ::parquet::arrow::ProjectionMask;
    use arrow::array::{Array, StringArray};
    let path = dir.join("trials.parquet");
    if !path.exists() {
        return Ok(None);
    }
    let read = || -> anyhow::Result<usize> {
        let builder = ParquetRecordBatchReaderBuilder::try_new(std::fs::File::open(&path)?)?;
        let idx = builder.schema().index_of("key")?;
        let mask = ProjectionMask::roots(builder.parquet_schema(), [idx]);
        let mut keys = std::collections::HashSet::new();
        for batch in builder.with_projection(mask).build()? {
            let batch = batch?;
            let col = batch
                .column(0)
                .as_any()
                .downcast_ref::<StringArray>()
                .ok_or_else(|| anyhow::anyhow!("column `key` is not a string column"))?;
            keys.extend(col.iter().flatten().map(str::to_owned));
            anyhow::ensure!(col.null_count() == 0, "column `key` has nulls");
        }
        Ok(keys.len())
    };
    read().map(Some).with_context(|| format!("cannot read the existing report's {}", path.display()))
}
