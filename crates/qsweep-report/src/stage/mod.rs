//! The report stage of a pipeline: for a pipeline without variants one folder, with variants
//! each variant's folder and the comparison of all of them.
//!
//! Before anything is written, the overwrite guard ([`crate::stage::manifest::guard`], through
//! [`Target`]) reads the manifest of every folder the report would replace: it refuses (exit 1,
//! nothing written) only when the new report's plan lacks trials and the kept report holds more.
//! A complete report of a changed plan replaces the old one, and [`ReportOutcome::replaced`] says
//! what changed.
//!
//! Only what changed is recomputed. Each folder's memo ([`memo`]) says whether its inputs changed:
//! an intact folder is neither recomputed nor rewritten; with a comparison, the whole report is
//! skipped when every folder is intact, and otherwise the variants whose folders are intact keep
//! their files and are only summarized for the comparison (in parallel, from one shared read
//! without episode lengths), while the others are drawn one at a time (memory: one variant's
//! episode lengths). Every bootstrap interval and claim set comes from the statistics' memo
//! ([`Derived`]) when its inputs are unchanged; the combined `trials.parquet` is spliced from one
//! part per reading ([`TrialParts`]), encoding only the changed ones; every file is written only
//! when its bytes change. `--rebuild` ([`ReportOptions::rebuild`]) ignores every memo.

pub mod manifest;
mod outcome;
pub mod stale;
mod target;

use crate::derive::compare::{VariantDigest, VariantInfo};
use crate::derive::model::ReportData;
use crate::kinds::Format;
use crate::memo::folders::{self as memo, Counted, Inputs, Memo, Role};
use crate::memo::parts::TrialParts;
use crate::memo::stats::Derived;
use crate::render::compare;
use crate::render::datasets;
use crate::render::folder::{write_folder, ReportSummary};
use crate::stage::manifest::Counts;
pub use crate::stage::outcome::{ReportOptions, ReportOutcome};
use crate::stage::target::Target;
use qsweep_pipeline::atomic::write_if_changed;
use qsweep_pipeline::cache::store::{KeySet, Store};
use qsweep_pipeline::cache::Key;
use qsweep_pipeline::error::user_error;
use qsweep_pipeline::plan::Plan;
use qsweep_pipeline::race::{read_cached, replay, Replayed};
use rayon::prelude::*;
use std::borrow::Cow;
use std::collections::HashSet;
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
) -> anyhow::Result<ReportOutcome> {
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
) -> anyhow::Result<ReportOutcome> {
    let dir = &opts.dir;
    if dir.exists() && !dir.is_dir() {
        return Err(not_a_dir(dir));
    }
    let plan = plan.plan();
    let formats = opts.formats;
    // Each folder's plan: the whole plan, or one variant's header ([`Plan::variant_header`]),
    // enough for the memos; a variant's cells are copied only once something is computed.
    let subs: Vec<(Option<VariantInfo>, Cow<'_, Plan>)> = if plan.variants.is_empty() {
        vec![(None, Cow::Borrowed(plan))]
    } else {
        plan.variants
            .iter()
            .map(|v| {
                (
                    Some(VariantInfo {
                        id: v.id.clone(),
                        title: v.title.clone(),
                        exploratory: v.exploratory,
                    }),
                    Cow::Owned(plan.variant_header(&v.id)),
                )
            })
            .collect()
    };
    let with_comparison = !plan.variants.is_empty() && !plan.variant_subset;

    // Each folder's inputs digest, against which its memo is checked.
    let inputs = Inputs::new(plan, scan);
    let sub_inputs: Vec<blake3::Hash> = subs
        .iter()
        .map(|(info, sub)| {
            inputs.of(
                sub,
                info.as_ref().map(|v| v.id.as_str()),
                formats,
                Role::Folder { own_trials: info.is_none() },
            )
        })
        .collect();
    let top_inputs = inputs.of(plan, None, formats, Role::Comparison);
    drop(inputs);
    let intact = |dir: &Path, h: &blake3::Hash| if opts.rebuild { None } else { memo::intact(dir, h) };
    if with_comparison {
        if let Some(done) = all_intact(plan, &subs, &sub_inputs, (&top_inputs, dir), scan, &intact) {
            return Ok(done);
        }
    }

    // Something is computed: each variant's plan in full (the comparison's digests borrow them).
    let subs: Vec<(Option<VariantInfo>, Cow<'_, Plan>)> = subs
        .into_iter()
        .map(|(info, head)| {
            let sub = match &info {
                Some(v) => Cow::Owned(plan.only_variant(&v.id)),
                None => head,
            };
            (info, sub)
        })
        .collect();

    // In a full report of a pipeline with a grid, only the chosen reading gets a folder, written
    // after the comparison has chosen it (compare::has_folder); an exploratory reading gets none;
    // `--variant` writes any on demand.
    let deferred = |info: &Option<VariantInfo>| {
        with_comparison && info.as_ref().is_some_and(|v| plan.has_grid() || v.exploratory)
    };
    // The guard first, over every folder this report replaces: nothing is written on a refusal.
    let mut targets = Vec::new();
    for (info, _) in &subs {
        let id = info.as_ref().map(|v| v.id.as_str());
        let d = id.map_or_else(|| dir.clone(), |id| dir.join(id));
        let target = || Target::new(d, (plan, id), &scan.keys, opts.force);
        targets.push(if deferred(info) { None } else { Some(target()?) });
    }
    let top = if with_comparison {
        Some(Target::new(dir.clone(), (plan, None), &scan.keys, opts.force)?)
    } else {
        None
    };
    for t in targets.iter().flatten().chain(&top) {
        t.guard(opts.force, store.dir())?;
    }

    let mut out = ReportOutcome::empty(Counts::of(plan, &scan.keys));
    // The statistics' memo: every interval and claim set whose inputs are unchanged is reused.
    let memo_path = Derived::path(store.dir(), &plan.name);
    let derived = Derived::load(&memo_path, crate::memo::ANALYSIS_VERSION, !opts.rebuild);
    // A folder skipped by its memo used no statistics: the memo then keeps what it holds.
    let mut skipped = false;
    let lengths = formats.has(Format::Trials) || formats.has(Format::Svg) || formats.has(Format::Png);
    let mut digests: Vec<VariantDigest> = Vec::new();
    let mut cells = Vec::new();
    // The combined trials.parquet, from one part per declared reading (report::trials).
    let mut trials = (with_comparison && formats.has(Format::Trials))
        .then(|| {
            std::fs::create_dir_all(dir)
                .map_err(|e| anyhow::anyhow!("cannot create {}: {e}", dir.display()))?;
            anyhow::Ok(TrialParts::new(store.dir(), &plan.name, dir, scan, opts.rebuild))
        })
        .transpose()?;
    if trials.as_ref().is_some_and(|p| !p.kept()) {
        out.warnings.push(format!(
            "the cache {} cannot keep trial parts: every reading's rows were encoded for this report",
            store.dir().display()
        ));
    }
    // What each folder needs, decided before any trial is read (see Need).
    let needs: Vec<Need> = subs
        .iter()
        .zip(&targets)
        .zip(&sub_inputs)
        .map(|(((info, sub), target), sub_hash)| {
            let kept = target.as_ref().and_then(|t| intact(&t.dir, sub_hash));
            let exploratory = info.as_ref().is_some_and(|v| v.exploratory);
            // An exploratory reading's rows are its declared twin's: written with its folder.
            let part = trials.as_ref().filter(|_| info.is_some() && !exploratory).map(|p| p.digest(sub));
            // A kept part holds a row per present trial (each cell's, its fresh ones included).
            let rows = || sub.trials().filter(|(_, _, t)| scan.keys.contains(&t.key)).count();
            let reuse_part =
                part.as_ref().is_some_and(|d| trials.as_ref().is_some_and(|p| p.have(d, rows())));
            let draws = target.is_some() && kept.is_none();
            // Episode lengths only for what draws or stores them: a folder's curves, the trial rows.
            let lengths = lengths && (draws || (part.is_some() && !reuse_part));
            Need { kept, part, reuse_part, draws, lengths }
        })
        .collect();
    // The outcomes of every variant that needs no episode lengths, read once for all of them
    // (variants share most trials).
    let shared = if with_comparison {
        let wanted: HashSet<Key> = subs
            .iter()
            .zip(&needs)
            .filter(|(_, n)| !n.lengths)
            .flat_map(|((_, sub), _)| sub.trials().map(|(_, _, t)| t.key))
            .collect();
        store.read_outcomes(scan, &wanted, false)?
    } else {
        std::collections::HashMap::new()
    };
    // The variants that draw nothing and encode no rows only summarize the shared outcomes for
    // the comparison: done in parallel, each a pure function of its inputs.
    let in_cells = |info: &Option<VariantInfo>| {
        with_comparison && formats.has(Format::Cells) && !info.as_ref().is_some_and(|v| v.exploratory)
    };
    let light: Vec<Option<anyhow::Result<Light>>> = subs
        .par_iter()
        .zip(&needs)
        .map(|((info, sub), need)| {
            let v = info.as_ref().filter(|_| with_comparison && !need.draws && !need.lengths)?;
            let cells = in_cells(info);
            let data = ReportData::build_as(sub, &shared, cells.then_some(&derived));
            Some(Light::of(v, sub, &data, cells, &derived))
        })
        .collect();
    for (((((info, sub), target), sub_hash), need), light) in
        subs.iter().zip(&targets).zip(&sub_inputs).zip(needs).zip(light)
    {
        if let Some(done) = light {
            let done = done?;
            if let (Some(parts), Some(d)) = (&mut trials, &need.part) {
                parts.reuse(d);
            }
            if let (Some(m), Some(v)) = (&need.kept, info) {
                keep_files(m, Path::new(&v.id), &mut out);
            }
            out.summary.add(&done.counted);
            out.cells_recomputed += done.counted.cells;
            cells.extend(done.cells);
            digests.push(done.digest);
            continue;
        }
        // Without a comparison, a folder stands alone: an intact one is skipped by itself.
        if let (Some(m), false) = (&need.kept, with_comparison) {
            let prefix = info.as_ref().map_or_else(PathBuf::new, |v| PathBuf::from(&v.id));
            reuse(m, &prefix, &mut out);
            skipped = true;
            continue;
        }
        let Need { kept, part, reuse_part, draws, .. } = need;
        let own;
        let outcomes = if need.lengths || !with_comparison {
            let wanted: HashSet<Key> = sub.trials().map(|(_, _, t)| t.key).collect();
            own = store.read_outcomes(scan, &wanted, need.lengths)?;
            &own
        } else {
            &shared
        };
        // Intervals where a page or the combined cells.parquet shows them.
        let in_cells = in_cells(info);
        let data = ReportData::build_as(sub, outcomes, (draws || in_cells).then_some(&derived));
        // The folder's files and this variant's rows of the combined trials.parquet at once.
        let (written, pushed) = rayon::join(
            || {
                target
                    .as_ref()
                    .filter(|_| draws)
                    .map(|t| write_folder(&data, &t.dir, formats, info.is_none()))
                    .transpose()
            },
            || match (&mut trials, &part) {
                (Some(parts), Some(d)) if reuse_part => {
                    parts.reuse(d);
                    Ok(())
                }
                (Some(parts), Some(d)) => parts.write(d, &data),
                _ => Ok(()),
            },
        );
        pushed?;
        let counted = ReportSummary::of(&data, Vec::new());
        if let (Some(t), Some(files)) = (target, written?) {
            let id = info.as_ref().map(|v| v.id.as_str());
            t.finish(sub, id, formats, files, (sub_hash, Counted::of(&counted), None), &mut out)?;
        }
        if let (Some(m), Some(v)) = (&kept, info) {
            keep_files(m, Path::new(&v.id), &mut out);
        }
        out.summary.add(&counted);
        out.cells_recomputed += counted.cells;
        if let (Some(v), true) = (info, with_comparison) {
            let done = Light::of(v, sub, &data, in_cells, &derived)?;
            cells.extend(done.cells);
            digests.push(done.digest);
        }
    }

    // The chosen reading of a grid gets its folder once the comparison has chosen it.
    let chosen = crate::derive::compare::explore::chosen(plan, &digests).filter(|_| plan.has_grid()).cloned();
    let mut chosen_folder = None;
    if let Some(((info, sub), sub_hash)) = subs
        .iter()
        .zip(&sub_inputs)
        .find(|((i, _), _)| deferred(i) && i.as_ref().map(|v| &v.id) == chosen.as_ref().map(|c| &c.id))
    {
        let id = &info.as_ref().expect("a deferred folder is a variant's").id;
        chosen_folder = Some(id.as_str());
        let t = Target::new(dir.join(id), (plan, Some(id.as_str())), &scan.keys, opts.force)?;
        if let Some(m) = intact(&t.dir, sub_hash) {
            keep_files(&m, Path::new(id), &mut out);
        } else {
            t.guard(opts.force, store.dir())?;
            let wanted: HashSet<Key> = sub.trials().map(|(_, _, t)| t.key).collect();
            let outcomes = store.read_outcomes(scan, &wanted, lengths)?;
            let data = ReportData::build_as(sub, &outcomes, Some(&derived));
            let files = write_folder(&data, &t.dir, formats, false)?;
            let counted = Counted::of(&ReportSummary::of(&data, Vec::new()));
            t.finish(sub, Some(id), formats, files, (sub_hash, counted, None), &mut out)?;
        }
    }

    if let Some(top) = &top {
        let mut files = Vec::new();
        if let Some(first) = cells.first() {
            let all = arrow::compute::concat_batches(&first.schema(), &cells)?;
            write_if_changed(&dir.join("cells.parquet"), &qsweep_pipeline::parquet_io::to_parquet(&all)?)?;
            files.push(PathBuf::from("cells.parquet"));
        }
        let prune = !plan.variant_subset;
        if trials.take().map(|p| p.finish(&dir.join("trials.parquet"), prune)).transpose()?.unwrap_or(false) {
            files.push(PathBuf::from("trials.parquet"));
        }
        files.extend(compare::write_comparison(dir, plan, &digests, formats, &derived)?);
        let counted = Counted::of(&out.summary);
        top.finish(plan, None, formats, files, (&top_inputs, counted, chosen_folder), &mut out)?;
    }
    out.statistics = derived.counts();
    // The memo is saved only when something was computed, so a report that reused everything
    // (another `--out`, fewer `--formats`) leaves it as it is. Then a full report keeps exactly
    // the statistics it used; a partial one adds to the memo. A cache this run cannot write to
    // costs only the next report's recomputation.
    if out.statistics.computed > 0 {
        if let Err(e) = derived.save(&memo_path, !plan.variant_subset && !skipped) {
            out.warnings.push(format!("the statistics' memo {} was not saved: {e:#}", memo_path.display()));
        }
    }
    Ok(out)
}

/// What the report keeps of a variant's data once its folder is written or kept: its counts, its
/// rows of the combined `cells.parquet` and its digest for the comparison. A variant that draws
/// nothing and encodes no rows is reduced to this at once (in parallel).
struct Light<'p> {
    counted: ReportSummary,
    cells: Option<arrow::record_batch::RecordBatch>,
    digest: VariantDigest<'p>,
}

impl<'p> Light<'p> {
    /// What is kept of `data`, the report data of variant `v` (`sub`), with its `cells.parquet`
    /// rows when `cells` (an exploratory reading's cells are written with its folder, on demand).
    fn of(
        v: &VariantInfo,
        sub: &'p Plan,
        data: &ReportData,
        cells: bool,
        derived: &Derived,
    ) -> anyhow::Result<Self> {
        Ok(Self {
            counted: ReportSummary::of(data, Vec::new()),
            cells: cells.then(|| datasets::cells_batch(data)).transpose()?,
            digest: VariantDigest::of(v.clone(), sub, data, derived),
        })
    }
}

/// What one folder of a report needs, decided before any trial is read.
struct Need {
    /// Its memo, when intact: the folder is kept (without a comparison, skipped altogether).
    kept: Option<Memo>,
    /// The digest of its part of the combined `trials.parquet` (a declared variant's).
    part: Option<blake3::Hash>,
    /// That part is there to reuse.
    reuse_part: bool,
    /// Its folder is drawn and written.
    draws: bool,
    /// Its trials are read with their episode lengths (for its curves or its trial rows).
    lengths: bool,
}

/// Count a folder kept as its memo says: its counts into the summary, its files as unchanged.
fn reuse(m: &Memo, prefix: &Path, out: &mut ReportOutcome) {
    out.summary.add(&m.summary.summary());
    out.cells_reused += m.summary.cells;
    keep_files(m, prefix, out);
}

/// List a kept folder's files (under `prefix`) in the outcome, as unchanged.
fn keep_files(m: &Memo, prefix: &Path, out: &mut ReportOutcome) {
    out.summary.files.extend(m.files.keys().map(|f| prefix.join(f)));
    out.summary.files.push(prefix.join(memo::MEMO));
    out.files_unchanged += m.files.len() + 1;
}

/// The outcome of a report with a comparison whose every folder is intact (the comparison's, each
/// variant's with a folder, the chosen reading's): nothing to compute or write. `None` when one
/// of them is not.
fn all_intact(
    plan: &Plan,
    subs: &[(Option<VariantInfo>, Cow<'_, Plan>)],
    sub_inputs: &[blake3::Hash],
    top: (&blake3::Hash, &Path),
    scan: &KeySet,
    intact: &dyn Fn(&Path, &blake3::Hash) -> Option<Memo>,
) -> Option<ReportOutcome> {
    let (top_inputs, dir) = top;
    let top = intact(dir, top_inputs)?;
    let mut out = ReportOutcome {
        summary: top.summary.summary(),
        cells_reused: top.summary.cells,
        ..ReportOutcome::empty(Counts::of(plan, &scan.keys))
    };
    for ((info, _), h) in subs.iter().zip(sub_inputs) {
        let Some(v) = info else { continue };
        // The same rule as the stage's: a grid's readings and exploratory ones have no folder,
        // but the chosen one.
        let has_folder = !(plan.has_grid() || v.exploratory) || top.chosen.as_deref() == Some(v.id.as_str());
        if has_folder {
            let m = intact(&dir.join(&v.id), h)?;
            out.summary.files.extend(m.files.keys().map(|f| PathBuf::from(&v.id).join(f)));
            out.summary.files.push(PathBuf::from(&v.id).join(memo::MEMO));
            out.files_unchanged += m.files.len() + 1;
        }
    }
    out.summary.files.extend(top.files.keys().map(PathBuf::from));
    out.summary.files.push(PathBuf::from(memo::MEMO));
    out.files_unchanged += top.files.len() + 1;
    Some(out)
}
