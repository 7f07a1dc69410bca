//! The report stage of a pipeline: for a pipeline without variants one folder, with variants
//! each variant's folder and the comparison of all of them.
//!
//! Before anything is written, the overwrite guard ([`crate::stage::manifest::guard`], through
//! [`Target`](target::Target)) reads the manifest of every folder the report would replace: it
//! refuses (exit 1, nothing written) only when the new report's plan lacks trials and the kept
//! report holds more. A complete report of a changed plan replaces the old one, and
//! [`ReportWritten::replaced`] says what changed.
//!
//! Only what changed is recomputed. Each folder's memo ([`crate::memo::folders`]) says whether
//! its inputs changed: an intact folder is neither recomputed nor rewritten; with a comparison,
//! the whole report is skipped when every folder is intact, and otherwise the variants whose
//! folders are intact keep their files and are only summarized for the comparison (in parallel,
//! from one shared read without episode lengths), while the others are drawn one at a time
//! (memory: one variant's episode lengths). Every bootstrap interval and claim set comes from the
//! statistics' memo ([`StatsMemo`](crate::memo::stats::StatsMemo)) when its inputs are unchanged; the
//! combined `trials.parquet` is spliced from one part per variant
//! ([`TrialParts`](crate::memo::parts::TrialParts)), encoding only the changed ones; every file is
//! written only when its bytes change. `--rebuild` ([`ReportOptions::rebuild`]) ignores every memo.
//!
//! [`write_replayed`] takes the report's steps one after another, each a named function: those
//! decided before any trial is read in `layout.rs` (which folders, their memos, the guard), then
//! those of the report under way in `steps.rs` (what each folder needs, the shared read, the
//! summaries, the drawn folders, the chosen variant, the comparison, the statistics' memo).

mod layout;
pub mod manifest;
mod outcome;
pub mod program;
pub mod stale;
mod steps;
mod target;

use crate::stage::layout::{all_intact, folders_of, guard, in_full, inputs_of, with_comparison};
pub use crate::stage::outcome::{ReportOptions, ReportWritten};
use crate::stage::steps::Report;
use qsweep_pipeline::cache::store::{KeySet, Store};
use qsweep_pipeline::error::user_error;
use qsweep_pipeline::plan::Plan;
use qsweep_pipeline::race::{read_cached, replay, Replayed};
use std::path::{Path, PathBuf};

/// Where a pipeline's report goes unless `--out` says otherwise: `reports/<name>`.
pub fn default_dir(plan: &Plan) -> PathBuf {
    Path::new("reports").join(&plan.name)
}

/// Write the report of `plan` from the cache: for a pipeline without variants, one folder; with
/// variants, each variant's folder `DIR/<id>/`, then (unless only some variants were selected) the
/// comparison, every variant's `cells.parquet` rows and the combined `trials.parquet` in `DIR`.
pub fn write(
    plan: Plan,
    store: &Store,
    scan: &KeySet,
    opts: &ReportOptions,
) -> anyhow::Result<ReportWritten> {
    if opts.dir.exists() && !opts.dir.is_dir() {
        return Err(not_a_dir(&opts.dir));
    }
    // A raced plan is reported as far as its races have run: each cell with the seeds it got;
    // the best cells with the fresh seeds they got.
    write_replayed(replay(plan, &scan.keys, &mut read_cached(store, scan))?, store, scan, opts)
}

fn not_a_dir(dir: &Path) -> anyhow::Error {
    user_error(format!(
        "report directory {} is a file, not a directory; give another with --out DIR",
        dir.display()
    ))
}

/// [`write`] of a plan already replayed against `scan` (what `qsweep run` hands on when it ran
/// nothing): the same report, without replaying the plan again.
pub fn write_replayed(
    plan: Replayed,
    store: &Store,
    scan: &KeySet,
    opts: &ReportOptions,
) -> anyhow::Result<ReportWritten> {
    if opts.dir.exists() && !opts.dir.is_dir() {
        return Err(not_a_dir(&opts.dir));
    }
    let plan = plan.plan();
    let comparison = with_comparison(plan);
    // The memos are checked before anything is read: each folder's plan (a variant's header) and
    // the digest of its inputs.
    let folders = folders_of(plan);
    let inputs = inputs_of(plan, scan, opts.formats, &folders);
    if comparison {
        if let Some(done) = all_intact(plan, &folders, &inputs, scan, opts) {
            return Ok(done);
        }
    }
    // Something is computed: each variant's plan in full (the comparison's digests borrow them).
    let folders = in_full(plan, folders);
    // Nothing is written on a refusal.
    let targets = guard(plan, &folders, store, scan, opts)?;

    let mut report = Report::start(plan, store, scan, opts)?;
    let needs = report.needs(&folders, &targets.each, &inputs.each);
    let shared = report.read_shared(&folders, &needs)?;
    let summarized = report.summarize_light(&folders, &needs, &shared);
    // Each folder in order: summarized already, skipped, or drawn (one at a time: memory).
    let per_folder =
        folders.iter().zip(&targets.each).zip(&inputs.each).zip(needs.into_iter().zip(summarized));
    for (((folder, target), inputs), (need, summarized)) in per_folder {
        match (summarized, &need.kept) {
            (Some(done), _) => report.add_summarized(folder, &need, done?),
            // Without a comparison, a folder stands alone: an intact one is skipped by itself.
            (None, Some(m)) if !comparison => report.skip(folder, m),
            (None, _) => report.draw_folder(folder, target.as_ref(), inputs, need, &shared)?,
        }
    }
    // Then the comparison: a grid's chosen variant gets its folder, and the comparison its files.
    let chosen = report.write_chosen(&folders, &inputs.each)?;
    if let Some(top) = &targets.top {
        report.write_comparison_folder(top, &inputs.top, chosen)?;
    }
    Ok(report.save_memo())
}
