//! Writing one report folder: its files (tables, figures, data, pages) in the formats asked for,
//! each atomically, and what the folder holds.

use crate::formats::{Format, Formats};
use crate::memo::folders::Counted;

use crate::derive::report_data::ReportData;
use crate::render::addition::Addition;
use crate::render::{curves, datasets, figures, html, markdown};
use anyhow::Context;
use qsweep_pipeline::atomic::write_if_changed;
use qsweep_pipeline::error::Interrupted;
use std::path::{Path, PathBuf};

/// What a report wrote.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
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
    pub trials_cached: usize,
    /// Of those, missing.
    pub trials_missing: usize,
    /// Files written, relative to the report directory, in writing order.
    pub files: Vec<PathBuf>,
}

impl ReportSummary {
    /// The summary of `data` with the files written.
    pub(crate) fn of(data: &ReportData, files: Vec<PathBuf>) -> Self {
        let cells: Vec<_> = data.experiments.iter().flat_map(|e| &e.cells).collect();
        Self {
            experiments: data.experiments.len(),
            cells: cells.len(),
            cells_with_trials: cells.iter().filter(|c| !c.trials.is_empty()).count(),
            trials_planned: data.trials_planned,
            trials_cached: data.trials_cached,
            trials_missing: data.trials_planned - data.trials_cached,
            files,
        }
    }

    /// Its counts, as a folder's memo keeps them.
    pub fn counted(&self) -> Counted {
        Counted {
            experiments: self.experiments,
            cells: self.cells,
            cells_with_trials: self.cells_with_trials,
            trials_planned: self.trials_planned,
            trials_cached: self.trials_cached,
        }
    }

    /// The summary of a folder kept as its memo's counts `c` say, without files.
    pub fn from_counted(c: &Counted) -> Self {
        Self {
            experiments: c.experiments,
            cells: c.cells,
            cells_with_trials: c.cells_with_trials,
            trials_planned: c.trials_planned,
            trials_cached: c.trials_cached,
            trials_missing: c.trials_planned - c.trials_cached.min(c.trials_planned),
            files: Vec::new(),
        }
    }

    /// Add another report's counts (the files stay).
    pub(crate) fn add(&mut self, o: &ReportSummary) {
        self.experiments += o.experiments;
        self.cells += o.cells;
        self.cells_with_trials += o.cells_with_trials;
        self.trials_planned += o.trials_planned;
        self.trials_cached += o.trials_cached;
        self.trials_missing += o.trials_missing;
    }
}

/// A report folder being written: every file atomically, the names kept in writing order.
pub(crate) struct Folder<'d> {
    dir: &'d Path,
    /// Files written, relative to the folder.
    pub files: Vec<PathBuf>,
}

impl<'d> Folder<'d> {
    /// Create `dir` (and its `figures/`).
    pub fn create(dir: &'d Path) -> anyhow::Result<Self> {
        std::fs::create_dir_all(dir.join("figures"))
            .with_context(|| format!("cannot create the report directory {}", dir.display()))?;
        Ok(Self { dir, files: Vec::new() })
    }

    /// Write `name` (relative to the folder), unless it already holds these bytes (then it is
    /// left alone, its mtime kept); either way it is one of the folder's files. After Ctrl-C or
    /// SIGTERM it writes nothing and fails ([`Interrupted`]): the folder's memo and manifest come
    /// after its files, so the next report sees it incomplete and writes it again. Whether it wrote.
    pub fn put(&mut self, name: &str, bytes: &[u8]) -> anyhow::Result<bool> {
        if qsweep_pipeline::exec::INTERRUPTED.load(std::sync::atomic::Ordering::Relaxed) {
            let at = self.dir.join(name);
            return Err(Interrupted(format!(
                "stopped before {}: that report is not complete; the next report completes it",
                at.display()
            ))
            .into());
        }
        let written = write_if_changed(&self.dir.join(name), bytes)?;
        self.files.push(PathBuf::from(name));
        Ok(written)
    }
}

/// Write one report folder of `data` into `dir` in `formats`, with what `added` adds (its files
/// first); `trials.parquet` only if `own_trials` (a variant's trial rows go to the pipeline's
/// combined file instead). Returns the files written, relative to `dir`, in writing order.
pub fn write_folder(
    data: &ReportData,
    dir: &Path,
    formats: Formats,
    own_trials: bool,
    added: &Addition,
) -> anyhow::Result<Vec<PathBuf>> {
    let mut out = Folder::create(dir)?;
    let mut put = |name: &str, bytes: &[u8]| out.put(name, bytes);
    for (name, bytes) in &added.files {
        put(name, bytes)?;
    }
    if formats.has(Format::Cells) {
        put("cells.parquet", &datasets::cells_parquet(data)?)?;
    }
    if own_trials && formats.has(Format::Trials) {
        put("trials.parquet", &datasets::trials_parquet(data)?)?;
    }
    let (svg, png) = (formats.has(Format::Svg), formats.has(Format::Png));
    if svg || png {
        for system in data.systems() {
            for (stem, d) in [
                (system.name().to_string(), figures::render_as(data, system, svg, png)?),
                (format!("{}-curves", system.name()), curves::render_as(data, system, svg, png)?),
            ] {
                if let Some(s) = d.svg {
                    put(&format!("figures/{stem}.svg"), s.as_bytes())?;
                }
                if let Some(p) = d.png {
                    put(&format!("figures/{stem}.png"), &p)?;
                }
            }
        }
    }
    if formats.has(Format::Html) {
        put("index.html", html::page(data, formats, added).as_bytes())?;
    }
    if formats.has(Format::Md) {
        put("README.md", markdown::page(data, formats, added).as_bytes())?;
    }
    Ok(out.files)
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
