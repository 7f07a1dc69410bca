//! `manifest.json`: what a report folder holds, written last, read by the next report to decide
//! whether it may replace the folder (the overwrite guard, [`guard`]) and which of its files are
//! stale. A few hundred bytes, so the guard never reads a large Parquet file.
//!
//! ```json
//! { "format_version": 1, "pipeline": "paper", "variant": "gym-v0-reset",
//!   "plan_digest": "…64 hex…", "trials_planned": 18360, "trials_present": 18360,
//!   "cells": 1944, "cells_with_trials": 1944, "formats": "md,csv,tex,cells,trials,svg,html",
//!   "files": ["table3.md", …] }
//! ```
//!
//! Trial counts are of distinct trials (cache keys); `plan_digest` is blake3 over the plan's
//! sorted distinct keys, so two reports of the same plan have the same digest. Nothing in it
//! depends on the time or the machine.

use qsweep_pipeline::cache::Key;
use qsweep_pipeline::error::user_error;
use qsweep_pipeline::plan::{Experiment, Plan};
use serde::{Deserialize, Serialize};
use std::collections::HashSet;
use std::path::{Path, PathBuf};

/// The manifest's file name in a report folder.
pub const MANIFEST: &str = "manifest.json";

/// The manifest format this build writes and reads.
pub const MANIFEST_VERSION: u32 = 1;

/// A report folder's manifest (see the module documentation).
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Manifest {
    /// [`MANIFEST_VERSION`].
    pub format_version: u32,
    /// Pipeline name.
    pub pipeline: String,
    /// Variant id, for a variant's folder.
    pub variant: Option<String>,
    /// The plan's counts.
    #[serde(flatten)]
    pub counts: Counts,
    /// The formats written (`--formats`).
    pub formats: String,
    /// Files written, relative to the folder, the manifest itself excluded.
    pub files: Vec<String>,
}

/// How complete a report's plan is, in distinct trials and in cells.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Counts {
    /// blake3 over the sorted distinct planned keys, hex.
    pub plan_digest: String,
    /// Distinct planned trials.
    pub trials_planned: usize,
    /// Of those, in the cache (`trials_present` in the file: the format is stable).
    #[serde(rename = "trials_present")]
    pub trials_cached: usize,
    /// Cells of the plan.
    pub cells: usize,
    /// Cells with at least one trial present.
    pub cells_with_trials: usize,
}

impl Counts {
    /// The counts of `plan` given the keys present in the cache.
    pub fn of(plan: &Plan, cached: &HashSet<Key>) -> Self {
        Self::of_experiments(&plan.experiments.iter().collect::<Vec<_>>(), cached)
    }

    /// The counts of the plan of one variant (`Some(id)`, as [`Plan::only_variant`] cuts it) or
    /// of the whole plan (`None`), without copying its cells.
    pub fn of_variant(plan: &Plan, variant: Option<&str>, cached: &HashSet<Key>) -> Self {
        let exps: Vec<&Experiment> = match variant {
            None => plan.experiments.iter().collect(),
            Some(id) => plan.experiments.iter().filter(|e| e.variant.as_deref() == Some(id)).collect(),
        };
        Self::of_experiments(&exps, cached)
    }

    fn of_experiments(exps: &[&Experiment], cached: &HashSet<Key>) -> Self {
        use rayon::slice::ParallelSliceMut;
        let cells: Vec<_> = exps.iter().flat_map(|e| &e.cells).collect();
        let mut keys: Vec<Key> =
            cells.iter().flat_map(|c| c.trials.iter().chain(&c.fresh)).map(|t| t.key).collect();
        keys.par_sort_unstable();
        keys.dedup();
        let mut h = blake3::Hasher::new();
        h.update(b"qsweep-plan\0");
        // The keys in runs of 2,048, so blake3 hashes whole chunks at once (one update per key
        // is several times slower; the digest is the same).
        let mut buf = Vec::with_capacity(2048 * 32);
        for run in keys.chunks(2048) {
            buf.clear();
            buf.extend(run.iter().flat_map(|k| k.0));
            h.update(&buf);
        }
        Self {
            plan_digest: h.finalize().to_hex().to_string(),
            trials_planned: keys.len(),
            trials_cached: keys.iter().filter(|k| cached.contains(k)).count(),
            cells: cells.len(),
            cells_with_trials: cells
                .iter()
                .filter(|c| c.trials.iter().any(|t| cached.contains(&t.key)))
                .count(),
        }
    }

    /// Whether every planned trial is present.
    pub fn complete(&self) -> bool {
        self.trials_cached == self.trials_planned
    }
}

/// What a report folder holds now, as far as the guard needs to know.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Kept {
    /// A report with a manifest.
    Manifest(Manifest),
    /// A report of an earlier qsweep without a manifest: the distinct trials of its
    /// `trials.parquet`.
    Legacy { trials: usize },
}

impl Kept {
    /// Distinct trials the kept report holds.
    pub fn trials(&self) -> usize {
        match self {
            Kept::Manifest(m) => m.counts.trials_cached,
            Kept::Legacy { trials } => *trials,
        }
    }

    /// "216 trials, 24 cells" (the cells only when known).
    pub fn describe(&self) -> String {
        match self {
            Kept::Manifest(m) => {
                format!("{} trials, {} cells", m.counts.trials_cached, m.counts.cells_with_trials)
            }
            Kept::Legacy { trials } => format!("{trials} trials"),
        }
    }
}

/// Read the report kept in `dir`: `None` when there is none. A manifest that cannot be parsed, or
/// of another format version, is a usage error (exit 2) naming the file and the fix.
pub fn read(dir: &Path) -> anyhow::Result<Option<Kept>> {
    let path = dir.join(MANIFEST);
    match std::fs::read(&path) {
        Ok(bytes) => {
            let fix = "move the folder aside, write elsewhere with --out DIR, or replace it with --force";
            let v: serde_json::Value = serde_json::from_slice(&bytes).map_err(|e| {
                user_error(format!("{}: not a qsweep report manifest ({e}); {fix}", path.display()))
            })?;
            let version = v.get("format_version").and_then(serde_json::Value::as_u64);
            if version != Some(u64::from(MANIFEST_VERSION)) {
                return Err(user_error(format!(
                    "{}: manifest format_version {} is not {MANIFEST_VERSION}, the one this qsweep reads \
                     (written by another version of qsweep?); {fix}",
                    path.display(),
                    version.map_or_else(|| "missing".to_string(), |n| n.to_string()),
                )));
            }
            let m: Manifest = serde_json::from_value(v)
                .map_err(|e| user_error(format!("{}: malformed manifest ({e}); {fix}", path.display())))?;
            Ok(Some(Kept::Manifest(m)))
        }
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            let legacy = crate::render::folder::existing_trials(dir).map_err(|e| {
                e.context(format!(
                    "{} holds a report whose size cannot be read; replace it with --force",
                    dir.display()
                ))
            })?;
            Ok(legacy.map(|trials| Kept::Legacy { trials }))
        }
        Err(e) => Err(anyhow::anyhow!("cannot read {}: {e}", path.display())),
    }
}

/// The overwrite guard, the one rule: a new report may replace `kept` unless its own plan lacks
/// trials and the kept report holds more than it would. `Err` carries the refusal's message.
pub fn guard(target: &Path, kept: &Kept, new: &Counts, cache: &Path) -> Result<(), String> {
    if new.complete() || kept.trials() <= new.trials_cached {
        return Ok(());
    }
    Err(format!(
        "{} holds a report of {}, but the cache ({}) has only {} of this pipeline's {} distinct trials \
         now; not replacing it with a smaller report. Run the missing trials first (`qsweep run`), \
         write elsewhere with --out DIR, or replace it anyway with `qsweep report ... --force`",
        target.display(),
        kept.describe(),
        cache.display(),
        new.trials_cached,
        new.trials_planned,
    ))
}

/// Write `m` into `dir` (atomically; left alone when its bytes would not change).
pub fn write(dir: &Path, m: &Manifest) -> anyhow::Result<PathBuf> {
    let path = dir.join(MANIFEST);
    let mut text = serde_json::to_string_pretty(m)?;
    text.push('\n');
    qsweep_pipeline::atomic::write_if_changed(&path, text.as_bytes())?;
    Ok(path)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn counts(planned: usize, cached: usize) -> Counts {
        Counts {
            plan_digest: "d".into(),
            trials_planned: planned,
            trials_cached: cached,
            cells: 1,
            cells_with_trials: 1,
        }
    }

    #[test]
    fn guard_refuses_only_an_incomplete_report_of_less() {
        let kept = Kept::Legacy { trials: 216 };
        let p = Path::new("reports/x");
        let c = Path::new("cache");
        assert!(guard(p, &kept, &counts(144, 144), c).is_ok(), "a complete plan replaces more");
        assert!(guard(p, &kept, &counts(300, 216), c).is_ok(), "as many as kept");
        let e = guard(p, &kept, &counts(300, 0), c).unwrap_err();
        assert!(e.contains("216 trials") && e.contains("only 0 of this pipeline's 300"), "{e}");
        assert!(guard(p, &kept, &counts(300, 215), c).is_err());
    }

    #[test]
    fn unreadable_and_unknown_manifests_are_usage_errors_naming_the_file() {
        let dir = tempfile::tempdir().unwrap();
        assert_eq!(read(dir.path()).unwrap(), None);
        std::fs::write(dir.path().join(MANIFEST), "{not json").unwrap();
        let e = read(dir.path()).unwrap_err();
        assert!(e.downcast_ref::<qsweep_pipeline::error::UserError>().is_some());
        assert!(format!("{e}").contains("manifest.json") && format!("{e}").contains("--force"), "{e}");
        std::fs::write(dir.path().join(MANIFEST), "{\"format_version\": 99}").unwrap();
        let e = format!("{}", read(dir.path()).unwrap_err());
        assert!(e.contains("format_version 99 is not 1"), "{e}");
        let m = Manifest {
            format_version: MANIFEST_VERSION,
            pipeline: "p".into(),
            variant: None,
            counts: counts(3, 2),
            formats: "md".into(),
            files: vec!["table3.md".into()],
        };
        write(dir.path(), &m).unwrap();
        assert_eq!(read(dir.path()).unwrap(), Some(Kept::Manifest(m)));
    }
}
