//! A report under way ([`Report`]), once its folders are guarded ([`super::layout`]): the steps
//! of [`crate::stage::write_replayed`] that read trials and write files, in order:
//!
//! 1. [`Report::start`]: the statistics' memo loaded, the trial parts opened;
//! 2. [`Report::needs`]: what each folder needs ([`FolderNeed`]), decided before any trial is read;
//! 3. [`Report::read_shared`]: one read of the outcomes that the variants without episode lengths
//!    share;
//! 4. [`Report::summarize_light`]: the variants that draw nothing and encode no rows, summarized
//!    for the comparison at once, in parallel ([`Summarized`]);
//! 5. per folder, in order: [`Report::add_summarized`], [`Report::skip`] (an intact folder
//!    without a comparison) or [`Report::draw_folder`];
//! 6. [`Report::write_chosen`]: a grid's chosen variant gets its folder;
//! 7. [`Report::write_comparison_folder`]: the comparison's files;
//! 8. [`Report::save_memo`]: the statistics' memo, and what the report did.

use crate::derive::report_data::ReportData;
use crate::formats::{Format, Formats};
use crate::memo::folders::{self as memo, Memo};
use crate::memo::parts::TrialParts;
use crate::memo::stats::StatsMemo;
use crate::render::datasets;
use crate::render::folder::{write_folder, ReportSummary};
use crate::replication::compare::{VariantDigest, VariantInfo};
use crate::replication::table3;
use crate::stage::layout::{deferred, intact, with_comparison, Folder};
use crate::stage::manifest::Counts;
use crate::stage::outcome::{ReportOptions, ReportWritten};
use crate::stage::target::Target;
use arrow::record_batch::RecordBatch;
use qsweep_pipeline::atomic::write_if_changed;
use qsweep_pipeline::cache::rows::StoredTrial;
use qsweep_pipeline::cache::store::{KeySet, Store};
use qsweep_pipeline::cache::Key;
use qsweep_pipeline::plan::Plan;
use rayon::prelude::*;
use std::collections::{HashMap, HashSet};
use std::path::{Path, PathBuf};

/// Outcomes read from the cache, by trial key.
pub(super) type Read = HashMap<Key, StoredTrial>;

/// What one folder needs, decided before any trial is read.
pub(super) struct FolderNeed {
    /// Its memo, when intact: the folder is kept (without a comparison, skipped altogether).
    pub(super) kept: Option<Memo>,
    /// The digest of its part of the combined `trials.parquet` (a declared variant's).
    part: Option<blake3::Hash>,
    /// That part is there to reuse.
    reuse_part: bool,
    /// Its folder is drawn and written.
    draws: bool,
    /// Its trials are read with their episode lengths (for its curves or its trial rows).
    lengths: bool,
}

/// What the report keeps of a variant once its folder is written or kept: its counts, its rows of
/// the combined `cells.parquet` and its digest for the comparison.
pub(super) struct Summarized<'p> {
    counted: ReportSummary,
    cells: Option<RecordBatch>,
    digest: VariantDigest<'p>,
}

impl<'p> Summarized<'p> {
    /// What is kept of `data`, the report data of variant `v` (`sub`), with its `cells.parquet`
    /// rows when `cells` (an exploratory variant's cells are written with its folder, on demand).
    fn of(
        v: &VariantInfo,
        sub: &'p Plan,
        data: &ReportData,
        cells: bool,
        derived: &StatsMemo,
    ) -> anyhow::Result<Self> {
        Ok(Self {
            counted: ReportSummary::of(data, Vec::new()),
            cells: cells.then(|| datasets::cells_batch(data)).transpose()?,
            digest: VariantDigest::of(v.clone(), sub, data, derived),
        })
    }
}

/// Whether `folder`'s rows go into the combined `cells.parquet` (a declared variant's, with a
/// comparison that writes it): its intervals are computed then.
fn in_cells(plan: &Plan, formats: Formats, folder: &Folder) -> bool {
    with_comparison(plan) && formats.has(Format::Cells) && !folder.exploratory()
}

/// A report under way, once its folders are guarded: what it was asked and what it has done.
pub(super) struct Report<'a> {
    plan: &'a Plan,
    store: &'a Store,
    scan: &'a KeySet,
    opts: &'a ReportOptions,
    /// What it has done so far.
    out: ReportWritten,
    /// The statistics' memo: every interval and claim set whose inputs are unchanged is reused.
    derived: StatsMemo,
    /// Where the statistics' memo is kept.
    memo_path: PathBuf,
    /// A folder was skipped by its memo: it used no statistics, so the memo keeps what it holds.
    skipped: bool,
    /// The combined `trials.parquet`, from one part per declared variant (with a comparison).
    parts: Option<TrialParts>,
    /// Each variant's digest, for the comparison.
    digests: Vec<VariantDigest<'a>>,
    /// Each declared variant's rows of the combined `cells.parquet`.
    cells: Vec<RecordBatch>,
}

impl<'a> Report<'a> {
    /// Nothing written yet: the statistics' memo loaded (not with `--rebuild`) and, for a
    /// comparison that writes `trials.parquet`, its parts opened (the report's folder created).
    pub(super) fn start(
        plan: &'a Plan,
        store: &'a Store,
        scan: &'a KeySet,
        opts: &'a ReportOptions,
    ) -> anyhow::Result<Self> {
        let out = ReportWritten::empty(Counts::of(plan, &scan.keys));
        let memo_path = StatsMemo::path(store.dir(), &plan.name);
        let derived = StatsMemo::load(&memo_path, crate::memo::ANALYSIS_VERSION, !opts.rebuild);
        let dir = &opts.dir;
        let parts = (with_comparison(plan) && opts.formats.has(Format::Trials))
            .then(|| {
                std::fs::create_dir_all(dir)
                    .map_err(|e| anyhow::anyhow!("cannot create {}: {e}", dir.display()))?;
                anyhow::Ok(TrialParts::new(store.dir(), &plan.name, dir, scan, opts.rebuild))
            })
            .transpose()?;
        let mut report = Self {
            plan,
            store,
            scan,
            opts,
            out,
            derived,
            memo_path,
            skipped: false,
            parts,
            digests: Vec::new(),
            cells: Vec::new(),
        };
        if report.parts.as_ref().is_some_and(|p| !p.kept()) {
            report.out.warnings.push(format!(
                "the cache {} cannot keep trial parts: every variant's rows were encoded for this report",
                store.dir().display()
            ));
        }
        Ok(report)
    }

    /// Whether the formats need the trials' episode lengths (the trial rows, the curves).
    fn lengths(&self) -> bool {
        let formats = self.opts.formats;
        formats.has(Format::Trials) || formats.has(Format::Svg) || formats.has(Format::Png)
    }

    /// What each folder needs ([`FolderNeed`]), decided before any trial is read.
    pub(super) fn needs(
        &self,
        folders: &[Folder],
        targets: &[Option<Target>],
        inputs: &[blake3::Hash],
    ) -> Vec<FolderNeed> {
        let parts = self.parts.as_ref();
        folders
            .iter()
            .zip(targets)
            .zip(inputs)
            .map(|((f, target), h)| {
                let kept = target.as_ref().and_then(|t| intact(self.opts, &t.dir, h));
                // An exploratory variant's rows are its declared twin's: written with its folder.
                let part = parts.filter(|_| f.info.is_some() && !f.exploratory()).map(|p| p.digest(&f.plan));
                // A kept part holds a row per present trial (each cell's, its fresh ones included).
                let rows = || f.plan.trials().filter(|(_, _, t)| self.scan.keys.contains(&t.key)).count();
                let reuse_part = part.as_ref().is_some_and(|d| parts.is_some_and(|p| p.have(d, rows())));
                let draws = target.is_some() && kept.is_none();
                // Episode lengths only for what draws or stores them: a folder's curves, the trial rows.
                let lengths = self.lengths() && (draws || (part.is_some() && !reuse_part));
                FolderNeed { kept, part, reuse_part, draws, lengths }
            })
            .collect()
    }

    /// The outcomes of every variant that needs no episode lengths, read once for all of them
    /// (variants share most trials); none without a comparison.
    pub(super) fn read_shared(&self, folders: &[Folder], needs: &[FolderNeed]) -> anyhow::Result<Read> {
        if !with_comparison(self.plan) {
            return Ok(HashMap::new());
        }
        let wanted: HashSet<Key> = folders
            .iter()
            .zip(needs)
            .filter(|(_, n)| !n.lengths)
            .flat_map(|(f, _)| f.plan.trials().map(|(_, _, t)| t.key))
            .collect();
        self.store.read_outcomes(self.scan, &wanted, false)
    }

    /// The variants that draw nothing and encode no rows, summarized from the `shared` outcomes
    /// for the comparison: in parallel, each a pure function of its inputs (`None`: the others).
    pub(super) fn summarize_light(
        &self,
        folders: &'a [Folder],
        needs: &[FolderNeed],
        shared: &Read,
    ) -> Vec<Option<anyhow::Result<Summarized<'a>>>> {
        let (plan, formats, derived) = (self.plan, self.opts.formats, &self.derived);
        folders
            .par_iter()
            .zip(needs)
            .map(|(f, need)| {
                let v = f.info.as_ref().filter(|_| with_comparison(plan) && !need.draws && !need.lengths)?;
                let cells = in_cells(plan, formats, f);
                let data = ReportData::build_as(&f.plan, shared, cells.then_some(derived));
                Some(Summarized::of(v, &f.plan, &data, cells, derived))
            })
            .collect()
    }

    /// Add a folder's counts to the report's.
    fn count(&mut self, counted: &ReportSummary) {
        self.out.summary.add(counted);
        self.out.cells_recomputed += counted.cells;
    }

    /// Keep a variant's rows of the combined `cells.parquet` and its digest, for the comparison.
    fn compare(&mut self, done: Summarized<'a>) {
        self.cells.extend(done.cells);
        self.digests.push(done.digest);
    }

    /// A variant summarized at once ([`Report::summarize_light`]): its trial part reused, its kept
    /// folder's files listed, its counts, rows and digest added.
    pub(super) fn add_summarized(&mut self, folder: &Folder, need: &FolderNeed, done: Summarized<'a>) {
        if let (Some(parts), Some(d)) = (&mut self.parts, &need.part) {
            parts.reuse(d);
        }
        if let (Some(m), Some(v)) = (&need.kept, &folder.info) {
            keep_files(m, Path::new(&v.id), &mut self.out);
        }
        self.count(&done.counted);
        self.compare(done);
    }

    /// A folder that stands alone (no comparison) skipped as its memo `m` says: its counts and
    /// files as they are.
    pub(super) fn skip(&mut self, folder: &Folder, m: &Memo) {
        let prefix = folder.info.as_ref().map_or_else(PathBuf::new, |v| PathBuf::from(&v.id));
        reuse(m, &prefix, &mut self.out);
        self.skipped = true;
    }

    /// Draw a folder as `need` says: read its outcomes (its own, with episode lengths where it
    /// needs them, or the `shared` ones), write its files (into `target`) and its part of the
    /// combined `trials.parquet` at once, then its manifest and memo (from `inputs`); a variant's
    /// summary goes to the comparison.
    pub(super) fn draw_folder(
        &mut self,
        folder: &'a Folder,
        target: Option<&Target>,
        inputs: &blake3::Hash,
        need: FolderNeed,
        shared: &Read,
    ) -> anyhow::Result<()> {
        let (plan, formats, comparison) = (self.plan, self.opts.formats, with_comparison(self.plan));
        let FolderNeed { kept, part, reuse_part, draws, lengths } = need;
        let sub: &'a Plan = &folder.plan;
        let own;
        let outcomes = if lengths || !comparison {
            let wanted: HashSet<Key> = sub.trials().map(|(_, _, t)| t.key).collect();
            own = self.store.read_outcomes(self.scan, &wanted, lengths)?;
            &own
        } else {
            shared
        };
        // Intervals where a page or the combined cells.parquet shows them.
        let in_cells = in_cells(plan, formats, folder);
        let data = ReportData::build_as(sub, outcomes, (draws || in_cells).then_some(&self.derived));
        // The folder's files and this variant's rows of the combined trials.parquet at once.
        let parts = &mut self.parts;
        let (written, pushed) = rayon::join(
            || {
                target
                    .filter(|_| draws)
                    .map(|t| {
                        write_folder(
                            &data,
                            &t.dir,
                            formats,
                            folder.info.is_none(),
                            &table3::addition(&data, formats),
                        )
                    })
                    .transpose()
            },
            || match (parts, &part) {
                (Some(parts), Some(d)) if reuse_part => {
                    parts.reuse(d);
                    Ok(())
                }
                (Some(parts), Some(d)) => parts.write(d, datasets::trials_batches(&data)),
                _ => Ok(()),
            },
        );
        pushed?;
        let counted = ReportSummary::of(&data, Vec::new());
        if let (Some(t), Some(files)) = (target, written?) {
            t.finish(sub, folder.id(), formats, files, (inputs, counted.counted(), None), &mut self.out)?;
        }
        if let (Some(m), Some(v)) = (&kept, &folder.info) {
            keep_files(m, Path::new(&v.id), &mut self.out);
        }
        self.count(&counted);
        if let (Some(v), true) = (&folder.info, comparison) {
            let done = Summarized::of(v, sub, &data, in_cells, &self.derived)?;
            self.compare(done);
        }
        Ok(())
    }

    /// The chosen variant of a grid gets its folder once the comparison has chosen it: kept when
    /// its memo says it is intact, else guarded and drawn. Its id, if there is one.
    pub(super) fn write_chosen(
        &mut self,
        folders: &'a [Folder],
        inputs: &[blake3::Hash],
    ) -> anyhow::Result<Option<&'a str>> {
        let (plan, opts, formats) = (self.plan, self.opts, self.opts.formats);
        let chosen = crate::replication::compare::explore::chosen(plan, &self.digests)
            .filter(|_| plan.has_grid())
            .cloned();
        let chosen = chosen.as_ref().map(|c| c.id.as_str());
        let Some((folder, h)) =
            folders.iter().zip(inputs).find(|(f, _)| deferred(plan, f) && f.id() == chosen)
        else {
            return Ok(None);
        };
        let id = &folder.info.as_ref().expect("a deferred folder is a variant's").id;
        let t = Target::new(opts.dir.join(id), (plan, Some(id.as_str())), &self.scan.keys, opts.force)?;
        if let Some(m) = intact(opts, &t.dir, h) {
            keep_files(&m, Path::new(id), &mut self.out);
        } else {
            t.guard(opts.force, self.store.dir())?;
            let sub: &Plan = &folder.plan;
            let wanted: HashSet<Key> = sub.trials().map(|(_, _, t)| t.key).collect();
            let outcomes = self.store.read_outcomes(self.scan, &wanted, self.lengths())?;
            let data = ReportData::build_as(sub, &outcomes, Some(&self.derived));
            let files = write_folder(&data, &t.dir, formats, false, &table3::addition(&data, formats))?;
            let counted = ReportSummary::of(&data, Vec::new()).counted();
            t.finish(sub, Some(id), formats, files, (h, counted, None), &mut self.out)?;
        }
        Ok(Some(id.as_str()))
    }

    /// The comparison's folder (`top`): every declared variant's rows of `cells.parquet`, the
    /// combined `trials.parquet` spliced from its parts, the comparison's pages and figures, then
    /// its manifest and memo (from `inputs`, naming the `chosen` variant).
    pub(super) fn write_comparison_folder(
        &mut self,
        top: &Target,
        inputs: &blake3::Hash,
        chosen: Option<&str>,
    ) -> anyhow::Result<()> {
        let (plan, dir, formats) = (self.plan, &self.opts.dir, self.opts.formats);
        let mut files = Vec::new();
        if let Some(first) = self.cells.first() {
            let all = arrow::compute::concat_batches(&first.schema(), &self.cells)?;
            write_if_changed(&dir.join("cells.parquet"), &qsweep_pipeline::parquet_io::to_parquet(&all)?)?;
            files.push(PathBuf::from("cells.parquet"));
        }
        let prune = !plan.variant_subset;
        if self
            .parts
            .take()
            .map(|p| p.finish(&dir.join("trials.parquet"), prune))
            .transpose()?
            .unwrap_or(false)
        {
            files.push(PathBuf::from("trials.parquet"));
        }
        files.extend(crate::replication::pages::write_comparison(
            dir,
            plan,
            &self.digests,
            formats,
            &self.derived,
        )?);
        let counted = self.out.summary.counted();
        top.finish(plan, None, formats, files, (inputs, counted, chosen), &mut self.out)
    }

    /// What the report did, once the statistics' memo is saved. It is saved only when something
    /// was computed, so a report that reused everything (another `--out`, fewer `--formats`)
    /// leaves it as it is. Then a full report keeps exactly the statistics it used; a partial one
    /// adds to the memo. A cache this run cannot write to costs only the next report's
    /// recomputation (a warning).
    pub(super) fn save_memo(mut self) -> ReportWritten {
        self.out.statistics = self.derived.counts();
        if self.out.statistics.computed > 0 {
            if let Err(e) = self.derived.save(&self.memo_path, !self.plan.variant_subset && !self.skipped) {
                let path = self.memo_path.display();
                self.out.warnings.push(format!("the statistics' memo {path} was not saved: {e:#}"));
            }
        }
        self.out
    }
}

/// Count a folder kept as its memo says: its counts into the summary, its files as unchanged.
fn reuse(m: &Memo, prefix: &Path, out: &mut ReportWritten) {
    out.summary.add(&ReportSummary::from_counted(&m.summary));
    out.cells_reused += m.summary.cells;
    keep_files(m, prefix, out);
}

/// List a kept folder's files (under `prefix`) in the outcome, as unchanged.
fn keep_files(m: &Memo, prefix: &Path, out: &mut ReportWritten) {
    out.summary.files.extend(m.files.keys().map(|f| prefix.join(f)));
    out.summary.files.push(prefix.join(memo::MEMO));
    out.files_unchanged += m.files.len() + 1;
}
