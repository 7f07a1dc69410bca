//! A program pipeline's cache status, as data (`qsweep status` on a `program:` pipeline): of its
//! distinct trials, how many are stored as succeeded, stored as failed (rerun with
//! `--retry-failed`) and missing, overall and per experiment; how many of the missing another run
//! is computing now; and (on request) why each cell's trials are missing ([`super::explain`]).
//! Reads only the plan's schema folder and runs no trial (planning runs the provenance commands). When that folder holds no rows but other
//! program folders do, the rows may be under another schema: a param's type or a metric changed.

use super::exec::jobs;
use super::explain::{why_missing, MissingCell, StoredIdentity};
use super::folders::list;
use super::model::ProgramPlan;
use super::rows::{folder, read_segment, RowSchema};
use super::stored::rows;
use crate::cache::store::{Damaged, KeySet, Store};
use crate::cache::Key;
use std::collections::HashSet;
use std::path::{Path, PathBuf};

/// Distinct trials, and how many of them are stored as succeeded and as failed.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct ProgramCount {
    /// Distinct trials (a trial shared by two cells or variants counts once).
    pub trials: usize,
    /// Of those, stored as succeeded.
    pub ok: usize,
    /// Of those, stored as failed.
    pub failed: usize,
}

impl ProgramCount {
    /// Of the trials, stored (succeeded or failed: a run does not run them again).
    pub fn cached(&self) -> usize {
        self.ok + self.failed
    }

    /// Of the trials, not stored.
    pub fn missing(&self) -> usize {
        self.trials - self.cached()
    }

    fn of<'a>(keys: impl Iterator<Item = &'a Key>, ok: &HashSet<Key>, failed: &HashSet<Key>) -> Self {
        let keys: HashSet<&Key> = keys.collect();
        Self {
            trials: keys.len(),
            ok: keys.iter().filter(|k| ok.contains(k)).count(),
            failed: keys.iter().filter(|k| failed.contains(k)).count(),
        }
    }
}

/// What [`status`] found.
#[derive(Debug, Clone)]
pub struct ProgramStatus {
    /// The plan's schema folder (`<cache>/_programs/<schema-id>/`).
    pub folder: PathBuf,
    /// Whether the folder exists.
    pub exists: bool,
    /// The plan's distinct trials.
    pub total: ProgramCount,
    /// One count per experiment of the plan, in plan order.
    pub experiments: Vec<ProgramCount>,
    /// Segments of the folder that could not be read (their trials count as missing).
    pub damaged: Vec<Damaged>,
    /// Of the missing trials, how many another run is computing now (a live lease).
    pub running_elsewhere: usize,
    /// Why missing cells are missing: only when asked for and some trial is missing.
    pub explanation: Option<Vec<MissingCell>>,
    /// When the plan's folder holds no rows: the ids of the other program folders that do (the
    /// rows may be under another schema: a param's type or a metric changed).
    pub other_schemas: Vec<String>,
}

/// The status of `plan` against the cache at `cache` (which may not exist: every trial missing);
/// with `explain`, also why each missing cell is missing (this reads every row of the folder).
pub fn status(plan: &ProgramPlan, cache: &Path, explain: bool) -> anyhow::Result<ProgramStatus> {
    let schema = RowSchema { params: plan.params.clone(), metrics: plan.program.metrics.clone() };
    let dir = folder(cache, &schema);
    let exists = dir.is_dir();
    let store = exists.then(|| Store::open(&dir)).transpose()?;
    let scan = match &store {
        Some(s) => s.keys()?,
        None => KeySet::default(),
    };
    let wanted: HashSet<Key> = jobs(plan).iter().map(|j| j.key).collect();
    let stored = rows(&scan, &schema, &wanted)?;
    let (mut ok, mut failed) = (HashSet::new(), HashSet::new());
    for (k, r) in &stored {
        if r.result.is_ok() { &mut ok } else { &mut failed }.insert(*k);
    }
    let keys_of = |e: &super::model::ProgramExperiment| -> Vec<Key> {
        e.cells.iter().flat_map(|c| c.trials.iter().chain(&c.fresh).map(|t| t.key)).collect()
    };
    let experiments =
        plan.experiments.iter().map(|e| ProgramCount::of(keys_of(e).iter(), &ok, &failed)).collect();
    let total = ProgramCount::of(wanted.iter(), &ok, &failed);
    let cached: HashSet<Key> = ok.union(&failed).copied().collect();
    let explanation =
        (explain && total.missing() > 0).then(|| why_missing(plan, &cached, &identities(&scan, &schema)));
    let running_elsewhere = match &store {
        Some(s) if total.missing() > 0 => {
            crate::cache::leases::running_elsewhere(s, wanted.iter().filter(|k| !cached.contains(k)))
        }
        _ => 0,
    };
    let other_schemas = if scan.segments.is_empty() {
        let mut others = Vec::new();
        for f in list(cache)? {
            if f.path != dir && !f.segments()?.is_empty() {
                others.push(f.id);
            }
        }
        others
    } else {
        Vec::new()
    };
    Ok(ProgramStatus {
        folder: dir,
        exists,
        total,
        experiments,
        damaged: scan.damaged,
        running_elsewhere,
        explanation,
        other_schemas,
    })
}

/// What every readable row of the folder `scan` listed was keyed by (a segment that cannot be
/// read as `schema`'s rows is left out: `qsweep verify` names it).
fn identities(scan: &KeySet, schema: &RowSchema) -> Vec<StoredIdentity> {
    scan.segments
        .iter()
        .filter_map(|(path, _)| read_segment(path, schema, &|_| true).ok())
        .flatten()
        .map(|r| StoredIdentity::of_row(&r, &schema.params))
        .collect()
}
