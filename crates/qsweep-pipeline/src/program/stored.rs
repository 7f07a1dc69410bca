//! What the cache holds of a program pipeline: one row per key, read from its schema's folder.
//! A key stored more than once (a failed trial retried with `--retry-failed`, every trial of a
//! `--force` run, a trial two runs computed at once) is served by one rule: a row that succeeded
//! wins over a failed one, and among rows of the same status the one in the most recently written
//! segment wins (segments are written once, so a segment's modification time is when its rows
//! were stored). [`plan_rows`] is what a plan's readers (the report, `qsweep compare`) take: the
//! rows of every trial the plan plans.

use super::model::{ProgramPlan, ProgramRow};
use super::rows::{read_segment, RowSchema};
use crate::cache::store::{KeySet, Store};
use crate::cache::Key;
use std::collections::{HashMap, HashSet};
use std::path::Path;
use std::time::SystemTime;

/// The rows of the keys in `wanted` that `scan` (of a program folder of `schema`) found, one per
/// key (see the module documentation).
pub fn rows(
    scan: &KeySet,
    schema: &RowSchema,
    wanted: &HashSet<Key>,
) -> anyhow::Result<HashMap<Key, ProgramRow>> {
    let mut best: HashMap<Key, (bool, SystemTime, ProgramRow)> = HashMap::new();
    for (path, keys) in &scan.segments {
        if !keys.iter().any(|k| wanted.contains(k)) {
            continue;
        }
        let written = written_at(path);
        let read = read_segment(path, schema, &|k| wanted.contains(k))
            .map_err(|e| e.context(format!("cannot read cache segment {}", path.display())))?;
        for r in read {
            let rank = (r.result.is_ok(), written);
            match best.get(&r.key) {
                Some((ok, at, _)) if (*ok, *at) >= rank => {}
                _ => {
                    best.insert(r.key, (rank.0, rank.1, r));
                }
            }
        }
    }
    Ok(best.into_iter().map(|(k, (_, _, r))| (k, r)).collect())
}

/// The rows of every trial `plan` plans (every experiment, every variant it was planned with), one
/// per key by the module's rule, from `store`, the folder of the plan's schema (`None`: no rows
/// yet, so none). A planned trial without a row is simply absent from the map.
pub fn plan_rows(plan: &ProgramPlan, store: Option<&Store>) -> anyhow::Result<HashMap<Key, ProgramRow>> {
    let Some(store) = store else { return Ok(HashMap::new()) };
    let scan = store.keys()?;
    let schema = RowSchema { params: plan.params.clone(), metrics: plan.program.metrics.clone() };
    let wanted: HashSet<Key> = plan
        .experiments
        .iter()
        .flat_map(|e| &e.cells)
        .flat_map(|c| c.trials.iter().chain(&c.fresh))
        .map(|t| t.key)
        .collect();
    rows(&scan, &schema, &wanted)
}

/// When the segment at `path` was written (the epoch when its file system cannot say).
fn written_at(path: &Path) -> SystemTime {
    std::fs::metadata(path).and_then(|m| m.modified()).unwrap_or(SystemTime::UNIX_EPOCH)
}

/// The keys among `wanted` whose row (by the module's rule) is a failure.
pub fn failed_keys(scan: &KeySet, schema: &RowSchema, wanted: &HashSet<Key>) -> anyhow::Result<HashSet<Key>> {
    Ok(rows(scan, schema, wanted)?.into_iter().filter(|(_, r)| r.result.is_err()).map(|(k, _)| k).collect())
}
