//! What `qsweep status --explain` says of the next report: which report folders it recomputes
//! (their memos, [`crate::memo::folders`]) and which cells' bootstrap intervals it computes rather than
//! takes from the statistics' memo ([`crate::memo::stats`]).

use crate::derive::report_data::{interval_inputs, ReportData};
use crate::formats::Formats;
use crate::memo::folders::{self as memo, Inputs, Role};
use crate::memo::stats::StatsMemo;
use qsweep_pipeline::analysis::BOOTSTRAP_RESAMPLES;
use qsweep_pipeline::cache::store::{KeySet, Store};
use qsweep_pipeline::cache::Key;
use qsweep_pipeline::plan::Plan;
use qsweep_pipeline::race::{read_cached, replay};
use std::collections::HashSet;
use std::path::{Path, PathBuf};

/// What the next report of a plan recomputes.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Staleness {
    /// Each folder the report writes, with why it is recomputed (`None`: its memo is intact).
    pub folders: Vec<(PathBuf, Option<String>)>,
    /// The statistics' memo file read.
    pub memo: PathBuf,
    /// Cell intervals (each cell's sample and fresh-seed sample) the report shows.
    pub intervals: usize,
    /// Those not in the memo: the cell (`variant:system/repr/algorithm/resolution/actions`, with
    /// `fresh` for its fresh-seed sample), each computed by the next report that recomputes it.
    pub stale: Vec<String>,
}

/// What the next report of `plan` into `dir` in `formats` recomputes (see [`Staleness`]).
pub fn staleness(
    plan: Plan,
    store: &Store,
    scan: &KeySet,
    dir: &Path,
    formats: Formats,
) -> anyhow::Result<Staleness> {
    let plan = replay(plan, &scan.keys, &mut read_cached(store, scan))?.into_plan();
    let folders = folders(&plan, scan, dir, formats);
    let path = StatsMemo::path(store.dir(), &plan.name);
    let memo = StatsMemo::load(&path, crate::memo::ANALYSIS_VERSION, true);
    // The cells whose intervals a report shows: every declared variant's (an exploratory one
    // shows none in a full report).
    let declared: Vec<Plan> = if plan.variants.is_empty() {
        vec![plan.clone()]
    } else {
        plan.variants.iter().filter(|v| !v.exploratory).map(|v| plan.only_variant(&v.id)).collect()
    };
    let wanted: HashSet<Key> = declared.iter().flat_map(|r| r.trials().map(|(_, _, t)| t.key)).collect();
    let outcomes = store.read_outcomes(scan, &wanted, false)?;
    let (mut intervals, mut stale) = (0, Vec::new());
    for r in &declared {
        let data = ReportData::build_as(r, &outcomes, None);
        for (e, c) in data.experiments.iter().flat_map(|e| e.cells.iter().map(move |c| (e, c))) {
            let variant = e.exp.variant.as_deref();
            for (sample, fresh) in [(&c.trials, false), (&c.fresh, true)] {
                if sample.is_empty() {
                    continue;
                }
                intervals += 1;
                let (values, seed) = interval_inputs(sample);
                if !memo.has_ci(&values, BOOTSTRAP_RESAMPLES, seed) {
                    let name = c.cell.name(variant);
                    stale.push(if fresh { format!("{name} fresh") } else { name });
                }
            }
        }
    }
    Ok(Staleness { folders, memo: path, intervals, stale })
}

/// For each folder a report of `plan` (replayed) into `dir` in `formats` would write (each
/// variant's with a folder, the comparison's, the chosen variant's as the comparison's memo names
/// it), why it would be recomputed, or `None` when its memo is intact.
fn folders(plan: &Plan, scan: &KeySet, dir: &Path, formats: Formats) -> Vec<(PathBuf, Option<String>)> {
    let inputs = Inputs::new(plan, scan);
    let mut out = Vec::new();
    if plan.variants.is_empty() {
        let h = inputs.of(plan, None, formats, Role::Folder { own_trials: true });
        out.push((dir.to_path_buf(), memo::why_stale(dir, &h)));
        return out;
    }
    let with_comparison = !plan.variant_subset;
    let chosen = memo::read(dir).and_then(|m| m.chosen);
    for v in &plan.variants {
        let deferred = with_comparison && (plan.has_grid() || v.exploratory);
        if deferred && chosen.as_deref() != Some(v.id.as_str()) {
            continue;
        }
        let sub = plan.variant_header(&v.id);
        let h = inputs.of(&sub, Some(&v.id), formats, Role::Folder { own_trials: false });
        let d = dir.join(&v.id);
        out.push((d.clone(), memo::why_stale(&d, &h)));
    }
    if with_comparison {
        let h = inputs.of(plan, None, formats, Role::Comparison);
        out.push((dir.to_path_buf(), memo::why_stale(dir, &h)));
    }
    out
}
