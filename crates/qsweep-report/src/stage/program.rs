//! The report of a program pipeline (`qsweep_pipeline::program`): its trials as typed rows
//! (`trials.parquet`: the cache's columns, after the experiment and variant each trial belongs
//! to), its cells' numbers (`cells.parquet`, [`crate::derive::program`]), the figures and the pages
//! (`README.md`, `index.html`, [`crate::render::program`]). Written atomically, each file only when its bytes change; an incomplete report never replaces a kept
//! one of more trials (unless forced), a complete one always does.

use crate::derive;
use crate::render::folder::{existing_trials, Folder};
use crate::render::program::{
    self, figures,
    pages::{self, Counts},
};
use arrow::array::{ArrayRef, BooleanArray, StringArray};
use arrow::datatypes::{DataType, Field, Schema};
use arrow::record_batch::RecordBatch;
use qsweep_pipeline::cache::Key;
use qsweep_pipeline::error::user_error;
use qsweep_pipeline::program::model::ProgramRow;
use qsweep_pipeline::program::race::ProgramReplayed;
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
    /// Bootstrap intervals computed (one per cell and scalar metric).
    pub intervals: usize,
}

/// Write the report of the `replayed` plan (its races' rounds and fresh seeds replayed from the
/// cache, `qsweep_pipeline::program::race`) into `dir` from `rows` (the cache's row of each key
/// present).
pub fn write(
    replayed: &ProgramReplayed,
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
    let plan = &replayed.plan;
    // Each cell's own trials, then its fresh ones (flagged in `trials.parquet`).
    let present: Vec<(&str, Option<&str>, &ProgramRow, bool)> = plan
        .experiments
        .iter()
        .flat_map(|e| e.cells.iter().map(move |c| (e, c)))
        .flat_map(|(e, c)| {
            let own = c.trials.iter().map(|t| (t, false));
            own.chain(c.fresh.iter().map(|t| (t, true))).filter_map(move |(t, fresh)| {
                rows.get(&t.key).map(|r| (e.id.as_str(), e.variant.as_deref(), r, fresh))
            })
        })
        .collect();
    let distinct = present.iter().map(|p| p.2.key).collect::<std::collections::HashSet<_>>().len();
    let planned: usize =
        plan.experiments.iter().flat_map(|e| &e.cells).map(|c| c.trials.len() + c.fresh.len()).sum();
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
        intervals: 0,
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
    if plan.experiments.iter().any(|e| !e.fresh.is_empty()) {
        fields.push(Field::new("fresh", DataType::Boolean, false));
        columns.push(Arc::new(present.iter().map(|p| Some(p.3)).collect::<BooleanArray>()));
    }
    fields.extend(batch.schema().fields().iter().map(|f| f.as_ref().clone()));
    columns.extend(batch.columns().iter().cloned());
    let all = RecordBatch::try_new(
        Arc::new(Schema::new_with_metadata(fields, batch.schema().metadata().clone())),
        columns,
    )?;
    let stats = derive::program::derive(plan, rows, &replayed.races);
    out.intervals = stats.experiments.iter().map(|e| e.cells.len()).sum::<usize>() * stats.scalars.len();
    let counts = Counts { planned: out.planned, present: out.present, failed: out.failed };
    let mut files: Vec<(String, Vec<u8>)> = vec![
        ("trials.parquet".into(), qsweep_pipeline::parquet_io::to_parquet(&all)?),
        ("cells.parquet".into(), program::cells_parquet(plan, &stats)?),
    ];
    for e in &stats.experiments {
        for f in figures::listed(&stats, e) {
            let svg = figures::draw(&stats, e, &f);
            files.push((f.path, svg.into_bytes()));
        }
    }
    files.push(("README.md".into(), pages::markdown(plan, &stats, counts).into_bytes()));
    files.push(("index.html".into(), pages::html(plan, &stats, counts).into_bytes()));
    let mut folder = Folder::create(dir)?;
    for (name, bytes) in files {
        out.written += usize::from(folder.put(&name, &bytes)?);
    }
    out.files = folder.files;
    Ok(out)
}
