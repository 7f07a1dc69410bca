//! The report's layout: which folders it writes, decided before any trial is read (the first steps of
//! [`crate::stage::write_replayed`]): each folder's plan ([`folders_of`]) and the digest of its
//! inputs ([`inputs_of`]), the whole report kept when every folder of a comparison is intact
//! ([`all_intact`]), each variant's plan in full once something is computed ([`in_full`]), and the
//! guard over every folder it replaces ([`guard`]).

use crate::formats::Formats;
use crate::memo::folders::{self as memo, Inputs, Memo, Role};
use crate::render::folder::ReportSummary;
use crate::replication::compare::VariantInfo;
use crate::stage::manifest::Counts;
use crate::stage::outcome::{ReportOptions, ReportWritten};
use crate::stage::target::Target;
use qsweep_pipeline::cache::store::{KeySet, Store};
use qsweep_pipeline::plan::Plan;
use std::borrow::Cow;
use std::path::{Path, PathBuf};

/// One folder of a report: a variant's, or the whole plan's for a pipeline without variants.
pub(super) struct Folder<'p> {
    /// Its variant (`None`: the whole plan).
    pub(super) info: Option<VariantInfo>,
    /// Its plan: a variant's header ([`Plan::variant_header`], enough for the memos) until
    /// something is computed ([`in_full`]), the whole plan without variants.
    pub(super) plan: Cow<'p, Plan>,
}

impl Folder<'_> {
    /// Its variant's id (`None`: the whole plan).
    pub(super) fn id(&self) -> Option<&str> {
        self.info.as_ref().map(|v| v.id.as_str())
    }

    /// Whether its variant is exploratory.
    pub(super) fn exploratory(&self) -> bool {
        self.info.as_ref().is_some_and(|v| v.exploratory)
    }
}

/// Whether the report compares variants: a pipeline with variants, all of them selected.
pub(super) fn with_comparison(plan: &Plan) -> bool {
    !plan.variants.is_empty() && !plan.variant_subset
}

/// Each folder's plan: the whole plan, or one variant's header per variant; a variant's cells
/// are copied only once something is computed ([`in_full`]).
pub(super) fn folders_of(plan: &Plan) -> Vec<Folder<'_>> {
    if plan.variants.is_empty() {
        return vec![Folder { info: None, plan: Cow::Borrowed(plan) }];
    }
    plan.variants
        .iter()
        .map(|v| Folder {
            info: Some(VariantInfo { id: v.id.clone(), title: v.title.clone(), exploratory: v.exploratory }),
            plan: Cow::Owned(plan.variant_header(&v.id)),
        })
        .collect()
}

/// The digests of a report's inputs, against which its folders' memos are checked.
pub(super) struct FolderInputs {
    /// Each folder's, in the order of [`folders_of`].
    pub(super) each: Vec<blake3::Hash>,
    /// The comparison's.
    pub(super) top: blake3::Hash,
}

/// The digest of each folder's inputs and of the comparison's.
pub(super) fn inputs_of(plan: &Plan, scan: &KeySet, formats: Formats, folders: &[Folder]) -> FolderInputs {
    let inputs = Inputs::new(plan, scan);
    let each = folders
        .iter()
        .map(|f| inputs.of(&f.plan, f.id(), formats, Role::Folder { own_trials: f.info.is_none() }))
        .collect();
    FolderInputs { each, top: inputs.of(plan, None, formats, Role::Comparison) }
}

/// The memo of the folder `dir` when it is intact against `inputs` (never with `--rebuild`).
pub(super) fn intact(opts: &ReportOptions, dir: &Path, inputs: &blake3::Hash) -> Option<Memo> {
    if opts.rebuild {
        None
    } else {
        memo::intact(dir, inputs)
    }
}

/// The outcome of a report with a comparison whose every folder is intact (the comparison's, each
/// variant's with a folder, the chosen variant's): nothing to compute or write. `None` when one
/// of them is not.
pub(super) fn all_intact(
    plan: &Plan,
    folders: &[Folder],
    inputs: &FolderInputs,
    scan: &KeySet,
    opts: &ReportOptions,
) -> Option<ReportWritten> {
    let dir = &opts.dir;
    let top = intact(opts, dir, &inputs.top)?;
    let mut out = ReportWritten {
        summary: ReportSummary::from_counted(&top.summary),
        cells_reused: top.summary.cells,
        ..ReportWritten::empty(Counts::of(plan, &scan.keys))
    };
    for (f, h) in folders.iter().zip(&inputs.each) {
        let Some(v) = &f.info else { continue };
        // The same rule as the stage's: a grid's variants and exploratory ones have no folder,
        // but the chosen one.
        let has_folder = !(plan.has_grid() || v.exploratory) || top.chosen.as_deref() == Some(v.id.as_str());
        if has_folder {
            let m = intact(opts, &dir.join(&v.id), h)?;
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

/// The folders with each variant's plan in full, once something is computed (the comparison's
/// digests borrow them).
pub(super) fn in_full<'p>(plan: &'p Plan, folders: Vec<Folder<'p>>) -> Vec<Folder<'p>> {
    folders
        .into_iter()
        .map(|Folder { info, plan: head }| {
            let plan = match &info {
                Some(v) => Cow::Owned(plan.only_variant(&v.id)),
                None => head,
            };
            Folder { info, plan }
        })
        .collect()
}

/// Whether `folder` is written only once the comparison has chosen it: in a full report of a
/// pipeline with a grid only the chosen variant gets a folder (written once chosen), and an
/// exploratory variant gets none (`--variant` writes any on demand).
pub(super) fn deferred(plan: &Plan, folder: &Folder) -> bool {
    with_comparison(plan) && folder.info.as_ref().is_some_and(|v| plan.has_grid() || v.exploratory)
}

/// The folders a report replaces, each guarded before anything is written.
pub(super) struct Targets {
    /// Each folder's, in the order of [`folders_of`]; `None` for a deferred one ([`deferred`]).
    pub(super) each: Vec<Option<Target>>,
    /// The comparison's.
    pub(super) top: Option<Target>,
}

/// The guard first, over every folder this report replaces (but the deferred ones, guarded once
/// chosen): nothing is written on a refusal.
pub(super) fn guard(
    plan: &Plan,
    folders: &[Folder],
    store: &Store,
    scan: &KeySet,
    opts: &ReportOptions,
) -> anyhow::Result<Targets> {
    let dir = &opts.dir;
    let mut each = Vec::new();
    for f in folders {
        let id = f.id();
        let d = id.map_or_else(|| dir.clone(), |id| dir.join(id));
        let target = || Target::new(d, (plan, id), &scan.keys, opts.force);
        each.push(if deferred(plan, f) { None } else { Some(target()?) });
    }
    let top = if with_comparison(plan) {
        Some(Target::new(dir.clone(), (plan, None), &scan.keys, opts.force)?)
    } else {
        None
    };
    for t in each.iter().flatten().chain(&top) {
        t.guard(opts.force, store.dir())?;
    }
    Ok(Targets { each, top })
}
