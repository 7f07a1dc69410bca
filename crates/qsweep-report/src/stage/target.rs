//! One folder a report writes ([`Target`]): its plan's counts, the report kept there (guarded
//! against being replaced by one of fewer trials), and, once written, its manifest and memo, the
//! kept files it no longer writes removed, and which of its files were rewritten.

use crate::formats::Formats;
use crate::memo::folders::{self as memo, Counted};
use crate::stage::manifest::{self, Counts, Kept, Manifest, MANIFEST_VERSION};
use crate::stage::outcome::ReportWritten;
use qsweep_pipeline::cache::Key;
use qsweep_pipeline::plan::Plan;
use std::collections::HashSet;
use std::path::{Path, PathBuf};

/// When each file of a report folder (and of its `figures/`) was last written, and its size: taken
/// before the folder is written, compared after, to tell rewritten files from unchanged ones
/// (every write is a rename of a new file, so a rewritten file has a new mtime).
#[derive(Debug, Default)]
struct Stamps(std::collections::HashMap<String, (std::time::SystemTime, u64)>);

impl Stamps {
    fn of(dir: &Path) -> Self {
        let mut out = std::collections::HashMap::new();
        for (sub, prefix) in [(dir.to_path_buf(), ""), (dir.join("figures"), "figures/")] {
            let Ok(entries) = std::fs::read_dir(&sub) else { continue };
            for e in entries.flatten() {
                if let Some(st) = stamp(&e.path()) {
                    out.insert(format!("{prefix}{}", e.file_name().to_string_lossy()), st);
                }
            }
        }
        Self(out)
    }

    /// Whether `name` (relative to the folder) is as it was when the stamps were taken.
    fn unchanged(&self, dir: &Path, name: &str) -> bool {
        self.0.get(name).is_some_and(|before| stamp(&dir.join(name)).as_ref() == Some(before))
    }
}

fn stamp(path: &Path) -> Option<(std::time::SystemTime, u64)> {
    let m = std::fs::metadata(path).ok().filter(std::fs::Metadata::is_file)?;
    Some((m.modified().ok()?, m.len()))
}

/// The files an earlier qsweep wrote into a report folder without a manifest, as far as they are
/// there: they are replaced or, when no longer written, removed.
fn legacy_files(dir: &Path) -> Vec<String> {
    let mut out = Vec::new();
    for name in ["table3.md", "table3.csv", "table3.tex", "cells.parquet", "trials.parquet", "index.html"] {
        if dir.join(name).is_file() {
            out.push(name.to_string());
        }
    }
    if let Ok(entries) = std::fs::read_dir(dir.join("figures")) {
        let mut figs: Vec<String> = entries
            .flatten()
            .map(|e| e.file_name().to_string_lossy().into_owned())
            .filter(|n| n.ends_with(".svg") || n.ends_with(".png"))
            .map(|n| format!("figures/{n}"))
            .collect();
        figs.sort();
        out.extend(figs);
    }
    out
}

/// One folder the report writes: where, its plan's counts, and what is there now.
pub(super) struct Target {
    pub(super) dir: PathBuf,
    counts: Counts,
    kept: Option<Kept>,
    /// The folder's files before this report wrote them.
    before: Stamps,
}

impl Target {
    /// The folder of `variant` of `plan` (`None`: the whole plan). With `force`, a kept report
    /// that cannot be read is replaced like any other.
    pub(super) fn new(
        dir: PathBuf,
        (plan, variant): (&Plan, Option<&str>),
        cached: &HashSet<Key>,
        force: bool,
    ) -> anyhow::Result<Self> {
        let kept = match manifest::read(&dir) {
            Ok(k) => k,
            Err(_) if force => None,
            Err(e) => return Err(e),
        };
        Ok(Self { counts: Counts::of_variant(plan, variant, cached), kept, before: Stamps::of(&dir), dir })
    }

    /// Refuse (unless `force`) to replace a kept report that holds more than this one would.
    pub(super) fn guard(&self, force: bool, cache: &Path) -> anyhow::Result<()> {
        match (&self.kept, force) {
            (Some(kept), false) => {
                manifest::guard(&self.dir, kept, &self.counts, cache).map_err(|e| anyhow::anyhow!(e))
            }
            _ => Ok(()),
        }
    }

    /// Write the manifest and the memo (from `inputs`, with the folder's `counted` summary and the
    /// comparison's `chosen` variant), remove the kept report's files that were not written again,
    /// say what changed, and list the folder's files (under the variant's id) in the outcome's
    /// summary.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn finish(
        &self,
        plan: &Plan,
        variant: Option<&str>,
        formats: Formats,
        files: Vec<PathBuf>,
        memo: (&blake3::Hash, Counted, Option<&str>),
        out: &mut ReportWritten,
    ) -> anyhow::Result<()> {
        let names: Vec<String> = files.iter().map(|f| f.to_string_lossy().into_owned()).collect();
        let m = Manifest {
            format_version: MANIFEST_VERSION,
            pipeline: plan.name.clone(),
            variant: variant.map(str::to_owned),
            counts: self.counts.clone(),
            formats: formats.to_string(),
            files: names.clone(),
        };
        manifest::write(&self.dir, &m)?;
        let mut listed = names.clone();
        listed.push(manifest::MANIFEST.to_string());
        memo::write(&self.dir, memo.0, memo.1, memo.2, &listed)?;
        for name in names.iter().map(String::as_str).chain([manifest::MANIFEST, memo::MEMO]) {
            if self.before.unchanged(&self.dir, name) {
                out.files_unchanged += 1;
            } else {
                out.files_written += 1;
            }
        }
        let prefix = variant.map_or_else(PathBuf::new, PathBuf::from);
        out.summary.files.extend(files.into_iter().map(|f| prefix.join(f)));
        out.summary.files.push(prefix.join(manifest::MANIFEST));
        out.summary.files.push(prefix.join(memo::MEMO));
        let Some(kept) = &self.kept else { return Ok(()) };
        // What the kept report wrote: its manifest says; an earlier layout's are known by name.
        let stale: Vec<String> = match kept {
            Kept::Manifest(k) => k.files.clone(),
            Kept::Legacy { .. } => legacy_files(&self.dir),
        };
        for f in stale.iter().filter(|f| !names.contains(f)) {
            let p = self.dir.join(f);
            // Only plain files inside the folder, named by our own manifest or layout.
            if !f.contains("..") && p.is_file() {
                std::fs::remove_file(&p)
                    .map_err(|e| anyhow::anyhow!("cannot remove {}: {e}", p.display()))?;
                out.removed.push(p);
            }
        }
        let same = match kept {
            Kept::Manifest(k) => k.counts == self.counts,
            Kept::Legacy { .. } => false,
        };
        if !same {
            out.replaced.push(format!(
                "{}: {} → {} trials, {} cells",
                self.dir.display(),
                kept.describe(),
                self.counts.trials_cached,
                self.counts.cells_with_trials
            ));
        }
        Ok(())
    }
}
