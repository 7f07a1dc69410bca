//! The combined `trials.parquet` of a comparison, assembled from one part per variant.
//!
//! Each declared variant's rows are encoded once into a part, `<cache>/_derived/<pipeline>.trials/
//! <digest>.parquet`, whose name is a blake3 digest of everything the rows depend on
//! ([`TrialParts::digest`]: the variant's id, its experiments' identity columns and counting
//! rule, every cell's algorithm and coordinates, and each trial's seed, key and the segment it
//! is read from). The combined file is the parts' row groups spliced one after the other, byte
//! for byte, without decoding them (as `parquet-concat` does), so a report in which one variant
//! changed encodes that variant's rows and copies the others'. `--rebuild` encodes every part
//! again; either way the combined file is the same concatenation, so it is byte-identical.
//!
//! A part is written atomically (temporary file, then rename) with its blake3 beside it
//! (`<digest>.b3`), and checked before it is reused (its bytes are those written, and it holds the
//! rows the variant has); anything else is encoded again. `qsweep verify` checks every part.
//! A full report removes the parts it did not use, unless another report is using the folder: a
//! report holds the folder shared ([`readers::Reading`]) from before it decides which parts to
//! reuse until it has spliced them, and parts are removed only with the folder taken exclusively
//! ([`readers::alone`]); otherwise they stay for the next report to prune. The parts are not
//! committed: a fresh clone encodes them on its first recomputed report.

use crate::memo::stats::readers;
use arrow::record_batch::RecordBatch;
use parquet::arrow::ArrowWriter;
use parquet::column::writer::ColumnCloseResult;
use parquet::file::metadata::{PageIndexPolicy, ParquetMetaData, ParquetMetaDataReader};
use parquet::file::writer::SerializedFileWriter;
use qsweep_pipeline::cache::store::KeySet;
use qsweep_pipeline::cache::Key;
use qsweep_pipeline::plan::Plan;
use std::collections::HashMap;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// Rows per row group of a part (and so of the combined `trials.parquet`).
const TRIALS_ROW_GROUP: usize = 1024;

/// The parts of one report's combined `trials.parquet`, in the order the variants are pushed.
pub struct TrialParts {
    dir: PathBuf,
    rebuild: bool,
    /// The parts live in the report directory for this report only (the cache is not writable).
    transient: bool,
    /// Where each stored key is read from ([`crate::memo::folders::where_stored`]).
    found: HashMap<Key, u64>,
    /// The parts of this report, in order.
    used: Vec<PathBuf>,
    /// This report's shared hold on the kept folder: no other report removes a part meanwhile.
    reading: Option<readers::Reading>,
}

impl TrialParts {
    /// The parts of pipeline `pipeline` in the cache at `cache`, against the cache scan `scan`;
    /// with `rebuild`, none is reused. When the cache cannot take them (read-only, or its
    /// `_derived` is not a folder), the parts are encoded into a hidden folder in the report
    /// directory `out`, spliced and removed: the report is the same, nothing is kept.
    pub fn new(cache: &Path, pipeline: &str, out: &Path, scan: &KeySet, rebuild: bool) -> Self {
        let kept = cache.join(crate::memo::stats::DERIVED_DIR).join(format!("{pipeline}.trials"));
        let (dir, transient) = if writable(&kept) {
            (kept, false)
        } else {
            (out.join(format!("{}parts.{}", qsweep_pipeline::atomic::TEMP_PREFIX, std::process::id())), true)
        };
        // Held before any part is checked for reuse, until the parts are spliced.
        let reading = (!transient).then(|| readers::Reading::hold(&dir));
        Self {
            dir,
            rebuild: rebuild || transient,
            transient,
            found: crate::memo::folders::where_stored(scan),
            used: Vec::new(),
            reading,
        }
    }

    /// Whether the parts are kept in the cache (`false`: encoded for this report only).
    pub fn kept(&self) -> bool {
        !self.transient
    }

    /// The digest of the rows of `sub` (one variant of the plan, as reported).
    pub fn digest(&self, sub: &Plan) -> blake3::Hash {
        let mut h = blake3::Hasher::new();
        h.update(b"qsweep-trial-rows\0");
        h.update(&crate::memo::ANALYSIS_VERSION.to_le_bytes());
        let mut buf: Vec<u8> = Vec::new();
        for e in &sub.experiments {
            // What the identity columns and `episodes_counted` read of the experiment; the cells'
            // configurations are pinned by their trials' keys (a cell without trials has no rows).
            let head = (&e.variant, &e.system, &e.id, &e.title, &e.repr, &e.axes, &e.counting, &e.fresh);
            let _ = write!(h, "{head:?}");
            for c in &e.cells {
                buf.clear();
                let _ = write!(buf, "\0{:?} {:?}", c.algorithm, c.coords);
                crate::memo::folders::put_trials(&mut buf, &c.trials, &self.found);
                crate::memo::folders::put_trials(&mut buf, &c.fresh, &self.found);
                h.update(&buf);
            }
        }
        h.finalize()
    }

    fn path(&self, digest: &blake3::Hash) -> PathBuf {
        self.dir.join(format!("{}.parquet", &digest.to_hex()[..32]))
    }

    /// Whether the part `digest` is there to reuse: its bytes as written (its `.b3` sidecar), and
    /// holding `rows` rows (never with `rebuild`).
    pub fn have(&self, digest: &blake3::Hash, rows: usize) -> bool {
        let path = self.path(digest);
        !self.rebuild
            && whole(&path)
            && footer(&path)
                .is_some_and(|m| m.row_groups().iter().map(|g| g.num_rows() as usize).sum::<usize>() == rows)
    }

    /// Use the part `digest` as it is (checked with [`TrialParts::have`]).
    pub fn reuse(&mut self, digest: &blake3::Hash) {
        self.used.push(self.path(digest));
    }

    /// Encode `batches` (a variant's trial rows, one batch per experiment, as
    /// [`crate::render::datasets::trials_batches`] makes them) into the part `digest` and use it.
    pub fn write(
        &mut self,
        digest: &blake3::Hash,
        batches: impl Iterator<Item = anyhow::Result<RecordBatch>>,
    ) -> anyhow::Result<()> {
        std::fs::create_dir_all(&self.dir)
            .map_err(|e| anyhow::anyhow!("cannot create {}: {e}", self.dir.display()))?;
        let path = self.path(digest);
        let mut sink = PartWriter::new(path.clone());
        sink.push(batches)?;
        // A variant without experiments has no rows and no part.
        if sink.finish()? {
            let sum = crate::memo::folders::file_digest(&path)
                .ok_or_else(|| anyhow::anyhow!("cannot read {} back", path.display()))?;
            qsweep_pipeline::atomic::write_atomic(&sidecar(&path), sum.to_hex().as_bytes())?;
            self.used.push(path);
        }
        Ok(())
    }

    /// Splice the parts used into `out` (rewritten only when its bytes change); with `prune`
    /// (a full report), then remove the parts not used, unless another report holds the folder.
    /// `false` when there is no part (no file).
    pub fn finish(self, out: &Path, prune: bool) -> anyhow::Result<bool> {
        let wrote = if self.used.is_empty() {
            false
        } else {
            let tmp = qsweep_pipeline::atomic::temp_beside(out);
            let done = concat(&self.used, &tmp).and_then(|()| {
                if qsweep_pipeline::atomic::same_files(&tmp, out) {
                    std::fs::remove_file(&tmp)?;
                    return Ok(());
                }
                std::fs::File::open(&tmp)?.sync_all()?;
                std::fs::rename(&tmp, out).map_err(|e| anyhow::anyhow!("cannot write {}: {e}", out.display()))
            });
            if done.is_err() {
                let _ = std::fs::remove_file(&tmp);
            }
            done?;
            true
        };
        let Self { dir, transient, used, reading, .. } = self;
        if transient {
            let _ = std::fs::remove_dir_all(&dir);
        } else if prune {
            // Read: let go of the folder, then prune it only if no other report holds it.
            drop(reading);
            prune_unused(&dir, &used);
        }
        Ok(wrote)
    }
}

/// Remove the parts in `dir` that are not in `used`, when no other report holds the folder (or
/// locks do not work there, [`readers::Alone::Unknown`]); `false` when they were left in place.
fn prune_unused(dir: &Path, used: &[PathBuf]) -> bool {
    let guard = readers::alone(dir);
    if matches!(guard, readers::Alone::No) {
        return false;
    }
    if let Ok(entries) = std::fs::read_dir(dir) {
        for p in entries.flatten().map(|e| e.path()) {
            if p.extension().is_some_and(|x| x == "parquet") && !used.contains(&p) {
                let _ = std::fs::remove_file(&p);
                let _ = std::fs::remove_file(sidecar(&p));
            }
        }
    }
    drop(guard);
    true
}

/// Whether `dir` is (or can be made) a folder this process can write a file into.
fn writable(dir: &Path) -> bool {
    if std::fs::create_dir_all(dir).is_err() {
        return false;
    }
    let probe = qsweep_pipeline::atomic::temp_beside(&dir.join("probe"));
    let ok = std::fs::File::create(&probe).is_ok();
    let _ = std::fs::remove_file(&probe);
    ok
}

/// The file holding the blake3 (hex) of the part at `path`, written with it.
fn sidecar(part: &Path) -> PathBuf {
    part.with_extension("b3")
}

/// Whether the part at `path` holds the bytes it was written with (its sidecar's blake3).
fn whole(path: &Path) -> bool {
    let (Ok(want), Some(got)) =
        (std::fs::read_to_string(sidecar(path)), crate::memo::folders::file_digest(path))
    else {
        return false;
    };
    want == got.to_hex().as_str()
}

/// What `qsweep verify` found of a cache's trial parts.
#[derive(Debug, Default, Clone, PartialEq, Eq)]
pub struct PartCheck {
    /// Parts holding the bytes their `.b3` records.
    pub whole: usize,
    /// Parts without a `.b3` (written by an older build): encoded again when next used.
    pub unrecorded: usize,
    /// Parts whose bytes are not those recorded: encoded again by the next report that needs them.
    pub damaged: Vec<PathBuf>,
}

/// Check every trial part of the cache at `cache` against its recorded blake3.
pub fn check(cache: &Path) -> PartCheck {
    let mut out = PartCheck::default();
    let Ok(dirs) = std::fs::read_dir(cache.join(crate::memo::stats::DERIVED_DIR)) else {
        return out;
    };
    let mut parts: Vec<PathBuf> = dirs
        .flatten()
        .map(|d| d.path())
        .filter(|d| d.is_dir() && d.extension().is_some_and(|x| x == "trials"))
        .flat_map(|d| std::fs::read_dir(d).into_iter().flatten().flatten().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "parquet"))
        .collect();
    parts.sort();
    for p in parts {
        if !sidecar(&p).is_file() {
            out.unrecorded += 1;
        } else if whole(&p) {
            out.whole += 1;
        } else {
            out.damaged.push(p);
        }
    }
    out
}

/// The footer of the Parquet file at `path`, page indexes included; `None` if it cannot be read.
fn footer(path: &Path) -> Option<ParquetMetaData> {
    let f = std::fs::File::open(path).ok()?;
    ParquetMetaDataReader::new().with_page_index_policy(PageIndexPolicy::Optional).parse_and_finish(&f).ok()
}

/// Write the row groups of `parts`, in order, into a new file at `out`: the column chunks copied
/// as they are encoded, with their page indexes, under the first part's schema and key-value
/// metadata (the Arrow schema).
fn concat(parts: &[PathBuf], out: &Path) -> anyhow::Result<()> {
    let inputs: Vec<(std::fs::File, ParquetMetaData)> = parts
        .iter()
        .map(|p| {
            let f = std::fs::File::open(p).map_err(|e| {
                if e.kind() == std::io::ErrorKind::NotFound {
                    // Only where locks do not reach (see readers), or by hand.
                    anyhow::anyhow!(
                        "cannot read {}: {e}; the trial part was removed while this report used it (by hand, \
                         by `qsweep gc`, or by a report on a machine whose locks this file system does not \
                         share): run the report again, it encodes the part anew",
                        p.display()
                    )
                } else {
                    anyhow::anyhow!("cannot read {}: {e}", p.display())
                }
            })?;
            let m = ParquetMetaDataReader::new()
                .with_page_index_policy(PageIndexPolicy::Optional)
                .parse_and_finish(&f)
                .map_err(|e| anyhow::anyhow!("cannot read {}: {e}", p.display()))?;
            Ok((f, m))
        })
        .collect::<anyhow::Result<_>>()?;
    let first = inputs[0].1.file_metadata();
    for ((_, m), p) in inputs.iter().zip(parts) {
        if m.file_metadata().schema() != first.schema() {
            anyhow::bail!("{} has another schema than {}", p.display(), parts[0].display());
        }
    }
    let file =
        std::fs::File::create(out).map_err(|e| anyhow::anyhow!("cannot write {}: {e}", out.display()))?;
    let props = Arc::new(qsweep_pipeline::parquet_io::writer_properties()?);
    let mut w = SerializedFileWriter::new(file, first.schema_descr().root_schema_ptr(), props)?;
    for kv in first.key_value_metadata().into_iter().flatten() {
        w.append_key_value_metadata(kv.clone());
    }
    for (input, m) in &inputs {
        let pages = m.page_index();
        for (g, group) in m.row_groups().iter().enumerate() {
            let mut out_group = w.next_row_group()?;
            for (c, column) in group.columns().iter().enumerate() {
                let close = ColumnCloseResult {
                    bytes_written: column.compressed_size() as _,
                    rows_written: group.num_rows() as _,
                    metadata: column.clone(),
                    bloom_filter: None,
                    column_index: pages.and_then(|p| p.column_index(g, c)).cloned(),
                    offset_index: pages.and_then(|p| p.offset_index(g, c)).cloned(),
                };
                out_group.append_column(input, close)?;
            }
            out_group.close()?;
        }
    }
    w.close()?;
    Ok(())
}

/// One part, written one experiment at a time in row groups of [`TRIALS_ROW_GROUP`] trials to a
/// hidden temporary file beside it, renamed into place when complete (so memory holds one
/// experiment's rows, and a reader never sees a partial part).
struct PartWriter {
    tmp: PathBuf,
    path: PathBuf,
    writer: Option<ArrowWriter<std::fs::File>>,
}

impl PartWriter {
    fn new(path: PathBuf) -> Self {
        Self { tmp: qsweep_pipeline::atomic::temp_beside(&path), path, writer: None }
    }

    /// Append one variant's rows, built a batch at a time and flushed every [`TRIALS_ROW_GROUP`]
    /// trials.
    fn push(&mut self, batches: impl Iterator<Item = anyhow::Result<RecordBatch>>) -> anyhow::Result<()> {
        for batch in batches {
            let batch = batch?;
            // An experiment without stored trials has no rows, and its empty batch is not the
            // schema of the others' (it lacks their `variant` column): skip it.
            if batch.num_rows() == 0 {
                continue;
            }
            if self.writer.is_none() {
                let file = std::fs::File::create(&self.tmp)
                    .map_err(|e| anyhow::anyhow!("cannot write {}: {e}", self.tmp.display()))?;
                let props = qsweep_pipeline::parquet_io::writer_properties()?;
                self.writer = Some(ArrowWriter::try_new(file, batch.schema(), Some(props))?);
            }
            let w = self.writer.as_mut().expect("created above");
            // A row group per TRIALS_ROW_GROUP rows: the writer buffers one group's encoded
            // columns, episode_lengths lists included, until it is flushed.
            for start in (0..batch.num_rows()).step_by(TRIALS_ROW_GROUP) {
                w.write(&batch.slice(start, TRIALS_ROW_GROUP.min(batch.num_rows() - start)))?;
                w.flush()?;
            }
        }
        Ok(())
    }

    /// Close, fsync and rename into place; `false` when nothing was pushed (no file).
    fn finish(mut self) -> anyhow::Result<bool> {
        let Some(w) = self.writer.take() else { return Ok(false) };
        let file = w.into_inner()?;
        file.sync_all()?;
        std::fs::rename(&self.tmp, &self.path)
            .map_err(|e| anyhow::anyhow!("cannot write {}: {e}", self.path.display()))?;
        Ok(true)
    }
}

impl Drop for PartWriter {
    fn drop(&mut self) {
        // Not finished (an error on the way): leave no temporary file behind.
        if self.writer.is_some() {
            let _ = std::fs::remove_file(&self.tmp);
        }
    }
}

#[cfg(test)]
mod tests;
