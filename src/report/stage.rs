//! The report stage of a pipeline, streaming: one variant at a time, read only that variant's
//! outcome columns for only its rows, compute every cell's statistics once, write its folder,
//! keep a small digest ([`VariantDigest`]) for the comparison and the rows for the combined
//! `trials.parquet`, and drop its trials before the next variant. Memory is one variant's.
//!
//! Before anything is written, the overwrite guard ([`manifest::guard`]) reads the manifest of
//! every folder the report would replace: it refuses (exit 1, nothing written) only when the new
//! report's plan lacks trials and the kept report holds more. A complete report of a changed
//! plan replaces the old one, and [`ReportOutcome::replaced`] says what changed.
//!
//! Each folder's memo ([`memo`]) lets a rerun skip what has not changed: a folder whose inputs
//! digest matches its memo and whose files are intact is neither recomputed nor rewritten. With a
//! comparison of variants, which needs every variant's numbers, the whole report is skipped when
//! every folder is intact, and otherwise recomputed (each file still written only when its bytes
//! change). `--rebuild` ([`ReportOptions::rebuild`]) ignores the memos.

use super::compare::{self, VariantDigest, VariantInfo};
use super::datasets;
use super::folder::{write_folder, ReportSummary};
use super::formats::{Format, Formats};
use super::manifest::{self, Counts, Kept, Manifest, MANIFEST_VERSION};
use super::memo::{self, Counted, Inputs, Memo, Role};
use super::model::ReportData;
use super::trials::TrialParts;
use crate::analysis::derived::{Derived, DerivedCounts};
use crate::atomic::write_if_changed;
use crate::cache::store::{KeySet, Store};
use crate::cache::Key;
use crate::error::user_error;
use crate::plan::Plan;
use crate::race::Replayed;
use rayon::prelude::*;
use std::borrow::Cow;
use std::collections::HashSet;
use std::path::{Path, PathBuf};

/// How to write a pipeline's report.
#[derive(Debug, Clone)]
pub struct ReportOptions {
    /// The report directory (`reports/<name>` unless `--out`).
    pub dir: PathBuf,
    /// Which files to write.
    pub formats: Formats,
    /// Replace a kept report even when the new one holds fewer trials.
    pub force: bool,
    /// Ignore the folders' memos: recompute every folder (`--rebuild`).
    pub rebuild: bool,
}

/// Where a pipeline's report goes unless `--out` says otherwise: `reports/<name>`.
pub fn default_dir(plan: &Plan) -> PathBuf {
    Path::new("reports").join(&plan.name)
}

/// What the stage wrote.
#[derive(Debug, Clone)]
pub struct ReportOutcome {
    /// Counts over the whole plan and every file written (relative to the directory).
    pub summary: ReportSummary,
    /// The whole plan's distinct-trial counts.
    pub counts: Counts,
    /// One line per replaced folder whose contents changed: `DIR: 216 trials, 24 cells → 144
    /// trials, 16 cells`.
    pub replaced: Vec<String>,
    /// Files of the kept reports that this one no longer writes, removed.
    pub removed: Vec<PathBuf>,
    /// Files (manifests included) whose bytes changed or that were new: written.
    pub files_written: usize,
    /// Files whose bytes would not change: left alone, their mtimes kept.
    pub files_unchanged: usize,
    /// Cells whose statistics were computed (those of every folder or variant not skipped).
    pub cells_recomputed: usize,
    /// Cells of the folders skipped as their memos say (nothing read, nothing computed).
    pub cells_reused: usize,
    /// Bootstrap intervals and claim sets computed, and taken from the statistics' memo
    /// ([`Derived`]), by the folders recomputed.
    pub statistics: DerivedCounts,
    /// What went wrong without failing the report (the statistics' memo could not be saved).
    pub warnings: Vec<String>,
}

impl ReportOutcome {
    /// Nothing written yet, of a plan with these counts.
    fn empty(counts: Counts) -> Self {
        Self {
            summary: ReportSummary::default(),
            counts,
            replaced: Vec::new(),
            removed: Vec::new(),
            files_written: 0,
            files_unchanged: 0,
            cells_recomputed: 0,
            cells_reused: 0,
            statistics: DerivedCounts::default(),
            warnings: Vec::new(),
        }
    }
}

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
struct Target {
    dir: PathBuf,
    counts: Counts,
    kept: Option<Kept>,
    /// The folder's files before this report wrote them.
    before: Stamps,
}

impl Target {
    /// The folder of `variant` of `plan` (`None`: the whole plan). With `force`, a kept report
    /// that cannot be read is replaced like any other.
    fn new(
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
    fn guard(&self, force: bool, cache: &Path) -> anyhow::Result<()> {
        match (&self.kept, force) {
            (Some(kept), false) => {
                manifest::guard(&self.dir, kept, &self.counts, cache).map_err(|e| anyhow::anyhow!(e))
            }
            _ => Ok(()),
        }
    }

    /// Write the manifest and the memo (from `inputs`, with the folder's `counted` summary and the
    /// comparison's `chosen` reading), remove the kept report's files that were not written again,
    /// say what changed, and list the folder's files (under the variant's id) in the outcome's
    /// summary.
    #[allow(clippy::too_many_arguments)]
    fn finish(
        &self,
        plan: &Plan,
        variant: Option<&str>,
        formats: Formats,
        files: Vec<PathBuf>,
        memo: (&blake3::Hash, Counted, Option<&str>),
        out: &mut ReportOutcome,
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
    write_replayed(Replayed::of(plan, store, scan)?, store, scan, opts)
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
    let derived = Derived::load(&memo_path, memo::ANALYSIS_VERSION, !opts.rebuild);
    // A folder skipped by its memo used no statistics: the memo then keeps what it holds.
    let mut skipped = false;
    let lengths = formats.has(Format::Trials) || formats.has(Format::Svg) || formats.has(Format::Png);
    let mut digests: Vec<VariantDigest> = Vec::new();
    let mut cells = Vec::new();
    // The combined trials.parquet, from one part per declared reading (report::trials).
    let mut trials = (with_comparison && formats.has(Format::Trials))
        .then(|| TrialParts::new(store.dir(), &plan.name, scan, opts.rebuild));
    if trials.is_some() {
        std::fs::create_dir_all(dir).map_err(|e| anyhow::anyhow!("cannot create {}: {e}", dir.display()))?;
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
            Some((|| {
                let cells = in_cells(info);
                let data = ReportData::build_as(sub, &shared, cells.then_some(&derived));
                Ok(Light {
                    counted: ReportSummary::of(&data, Vec::new()),
                    cells: cells.then(|| datasets::cells_batch(&data)).transpose()?,
                    digest: VariantDigest::of(v.clone(), sub, &data, &derived),
                })
            })())
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
            // An exploratory reading's cells are written with its folder, on demand.
            if in_cells {
                cells.push(datasets::cells_batch(&data)?);
            }
            digests.push(VariantDigest::of(v.clone(), sub, &data, &derived));
        }
    }

    // The chosen reading of a grid gets its folder once the comparison has chosen it.
    let chosen = compare::explore::chosen(plan, &digests).filter(|_| plan.has_grid()).cloned();
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
            write_if_changed(&dir.join("cells.parquet"), &crate::parquet_io::to_parquet(&all)?)?;
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
    // A full report keeps exactly the statistics it used; a partial one adds to the memo. A cache
    // this run cannot write to costs only the next report's recomputation.
    if let Err(e) = derived.save(&memo_path, !plan.variant_subset && !skipped) {
        out.warnings.push(format!("the statistics' memo {} was not saved: {e:#}", memo_path.display()));
    }
    Ok(out)
}

/// What the comparison keeps of a variant that draws nothing and encodes no rows.
struct Light<'p> {
    counted: ReportSummary,
    cells: Option<arrow::record_batch::RecordBatch>,
    digest: VariantDigest<'p>,
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
