//! The folder memos: each report folder's `memo.json` says what the folder was computed from (a
//! blake3 digest of its inputs) and what it holds (each file's blake3), so a rerun whose inputs
//! have not changed and whose files are intact skips the folder's computation altogether: no
//! trial is read, no statistic recomputed, no file rewritten.
//!
//! ```json
//! { "format_version": 1, "analysis_version": 1, "inputs": "…64 hex…",
//!   "summary": { "experiments": 4, "cells": 1944, … }, "chosen": null,
//!   "files": { "index.html": "…64 hex…", "manifest.json": "…", … }, "seal": "…64 hex…" }
//! ```
//!
//! The inputs digest ([`Inputs::of`]) covers everything a folder's bytes depend on:
//! [`ANALYSIS_VERSION`] (the definitions of the statistics and of the files), the formats asked
//! for, whether the folder holds its own `trials.parquet`, the plan as reported (its header and, for
//! every experiment of the folder, every field, every cell's coordinates, race state and trial
//! keys — a key is blake3 of the cell's configuration, so a cell's configuration is hashed only
//! when it has no trials), and for every trial whether it is cached and in which segment (a
//! segment's rows are immutable and its name unique, so this pins the informational `seconds`
//! columns too). A trial outcome is a pure function of its key, so nothing else can change a file.
//!
//! The memo holds no timestamps and nothing machine-dependent (no paths, only names relative to
//! the folder), so a committed report's memo is the same on every machine. A missing, unreadable,
//! older-format or damaged memo, a changed input or a file that differs from its recorded digest
//! means the folder is recomputed: never an error, never a stale number. `--rebuild` ignores it.

use super::ANALYSIS_VERSION;
use crate::formats::Formats;
use qsweep_pipeline::cache::store::KeySet;
use qsweep_pipeline::cache::Key;
use qsweep_pipeline::plan::{Experiment, Plan, PlannedTrial};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::collections::{BTreeMap, HashMap};
use std::io::Write;
use std::path::Path;

/// The memo's file name in a report folder.
pub const MEMO: &str = "memo.json";

/// The memo format this build writes and reads (another one is ignored: recomputed).
pub const MEMO_VERSION: u32 = 1;

/// A report folder's memo (see the module documentation).
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Memo {
    /// [`MEMO_VERSION`].
    pub format_version: u32,
    /// [`ANALYSIS_VERSION`] of the build that wrote the folder.
    pub analysis_version: u32,
    /// blake3 of the folder's inputs ([`Inputs::of`]), hex.
    pub inputs: String,
    /// The report's counts over what the folder covers (the comparison folder: the whole plan).
    pub summary: Counted,
    /// The variant the comparison chose for its folder (a pipeline with a `variant_grid:`).
    pub chosen: Option<String>,
    /// Every file of the folder (the manifest included, the memo excluded) with its blake3, hex.
    pub files: BTreeMap<String, String>,
    /// blake3 of the memo itself with an empty `seal`, hex: a memo edited or damaged in a way
    /// that still parses (a count changed) is not trusted.
    pub seal: String,
}

impl Memo {
    /// The seal of this memo's contents.
    fn sealed(&self) -> String {
        let bare = Memo { seal: String::new(), ..self.clone() };
        let bytes = serde_json::to_vec(&bare).expect("a memo serializes");
        blake3::hash(&bytes).to_hex().to_string()
    }
}

/// A report folder's counts (a report's summary without its file list).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[allow(missing_docs)]
pub struct Counted {
    pub experiments: usize,
    pub cells: usize,
    pub cells_with_trials: usize,
    pub trials_planned: usize,
    pub trials_cached: usize,
}

/// Which folder of a report an inputs digest is for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Role {
    /// One report's folder; `own_trials`: it holds its own `trials.parquet`.
    Folder {
        /// Whether the folder writes its own `trials.parquet`.
        own_trials: bool,
    },
    /// The comparison of every variant, with the combined `cells.parquet` and `trials.parquet`.
    Comparison,
}

/// The digests of a plan's experiments against a cache scan, computed once (in parallel) and
/// shared by every folder of the report.
pub struct Inputs {
    /// One digest per experiment of the plan, in plan order, with the experiment's variant.
    exps: Vec<(Option<String>, blake3::Hash)>,
}

impl Inputs {
    /// Digest every experiment of `plan`, with where each of its trials is stored in `scan`.
    pub fn new(plan: &Plan, scan: &KeySet) -> Self {
        let found = where_stored(scan);
        let exps = plan.experiments.par_iter().map(|e| (e.variant.clone(), experiment(e, &found))).collect();
        Self { exps }
    }

    /// The inputs digest of the folder reporting `sub` (the whole plan, or one variant of it,
    /// `variant`) in `formats` as `role`.
    pub fn of(&self, sub: &Plan, variant: Option<&str>, formats: Formats, role: Role) -> blake3::Hash {
        let mut h = blake3::Hasher::new();
        h.update(b"qsweep-report-inputs\0");
        h.update(&ANALYSIS_VERSION.to_le_bytes());
        h.update(formats.to_string().as_bytes());
        h.update(format!("\0{role:?}\0").as_bytes());
        // The header as reported; warnings are printed, never written into a report. How many
        // variants the pipeline declares is the comparison's (what an exploratory search tried):
        // a variant added leaves the other variants' folders as they are.
        let variant_count = (role == Role::Comparison).then_some(sub.variant_count);
        let header = (
            &sub.name,
            &sub.description,
            &sub.source,
            &sub.reference_source,
            &sub.seeds,
            &sub.variants,
            sub.variant_subset,
            sub.raced,
            &sub.exploratory,
            variant_count,
        );
        let _ = write!(h, "{header:?}");
        for (v, d) in &self.exps {
            if variant.is_none() || v.as_deref() == variant {
                h.update(d.as_bytes());
            }
        }
        h.finalize()
    }
}

/// For every stored key, an 8-byte id of the segment its outcome is read from (the store's rule,
/// [`KeySet::reading_segment`]).
pub(crate) fn where_stored(scan: &KeySet) -> HashMap<Key, u64> {
    scan.reading_segment(|path| {
        let name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
        u64::from_le_bytes(blake3::hash(name.as_bytes()).as_bytes()[..8].try_into().expect("8 bytes"))
    })
}

/// The digest of one experiment: every field but the cells as written by `Debug` (no hash maps in
/// a plan, so the text is deterministic), then per cell its algorithm, coordinates, race state,
/// configuration (only for a cell without trials: a trial key pins it) and trials.
fn experiment(e: &Experiment, found: &HashMap<Key, u64>) -> blake3::Hash {
    let mut h = blake3::Hasher::new();
    let head = (
        &e.variant,
        &e.system,
        &e.id,
        &e.title,
        &e.repr,
        &e.algorithms,
        &e.axes,
        &e.fixed,
        &e.counting,
        &e.reference,
        &e.race,
        &e.fresh,
    );
    let _ = write!(h, "{head:?}");
    // Each cell into one buffer, hashed at once (many small updates are slow).
    let mut buf: Vec<u8> = Vec::new();
    for c in &e.cells {
        buf.clear();
        let _ = write!(buf, "\0{:?} {:?} {:?}", c.algorithm, c.coords, c.contender);
        // A trial's key is blake3 of the cell's canonical configuration (and its seed), so the
        // keys below pin the configuration; only a cell without trials needs it written out
        // (writing every cell's configuration was a tenth of a no-op run).
        if c.trials.is_empty() && c.fresh.is_empty() {
            let _ = write!(buf, " {:?}", c.config);
        }
        put_trials(&mut buf, &c.trials, found);
        put_trials(&mut buf, &c.fresh, found);
        h.update(&buf);
    }
    h.finalize()
}

/// Append to `buf` what a digest needs of trials `ts`: their count, then each one's seed, key and
/// the id of the segment it is read from (`found`, [`where_stored`]; 0: not cached, an id of 0 is
/// as good as impossible and would only cost a recompute).
pub(crate) fn put_trials(buf: &mut Vec<u8>, ts: &[PlannedTrial], found: &HashMap<Key, u64>) {
    buf.extend_from_slice(&(ts.len() as u64).to_le_bytes());
    for t in ts {
        buf.extend_from_slice(&t.seed.to_le_bytes());
        buf.extend_from_slice(&t.key.0);
        buf.extend_from_slice(&found.get(&t.key).copied().unwrap_or(0).to_le_bytes());
    }
}

/// The memo kept in `dir`, if there is one this build reads; anything else is `None`.
pub fn read(dir: &Path) -> Option<Memo> {
    let bytes = std::fs::read(dir.join(MEMO)).ok()?;
    let m: Memo = serde_json::from_slice(&bytes).ok()?;
    let current = m.format_version == MEMO_VERSION && m.analysis_version == ANALYSIS_VERSION;
    (current && m.seal == m.sealed()).then_some(m)
}

/// The memo kept in `dir` if it was written from `inputs` and every file it lists is still there
/// with its recorded digest (a file edited or deleted by hand means the folder is rewritten).
pub fn intact(dir: &Path, inputs: &blake3::Hash) -> Option<Memo> {
    let m = read(dir)?;
    if m.inputs != inputs.to_hex().as_str() {
        return None;
    }
    let ok = m.files.par_iter().all(|(name, digest)| {
        !name.contains("..") && file_digest(&dir.join(name)).is_some_and(|d| d.to_hex().as_str() == digest)
    });
    ok.then_some(m)
}

/// Why the folder `dir` would be recomputed by a report whose inputs digest is `inputs`; `None`
/// when its memo is intact (the folder would be skipped).
pub fn why_stale(dir: &Path, inputs: &blake3::Hash) -> Option<String> {
    if !dir.join(MEMO).is_file() {
        return Some("no memo.json (never reported, or by an older qsweep)".to_string());
    }
    let Some(m) = read(dir) else {
        return Some("memo.json damaged or of another qsweep version".to_string());
    };
    if m.inputs != inputs.to_hex().as_str() {
        return Some("its inputs changed (trials cached, settings, reference values or formats)".to_string());
    }
    let bad: Vec<&str> = m
        .files
        .iter()
        .filter(|(name, digest)| file_digest(&dir.join(name)).is_none_or(|d| d.to_hex().as_str() != *digest))
        .map(|(name, _)| name.as_str())
        .collect();
    (!bad.is_empty()).then(|| format!("files edited or missing since written: {}", bad.join(", ")))
}

/// blake3 of a file's bytes, read in chunks; `None` if it cannot be read.
pub fn file_digest(path: &Path) -> Option<blake3::Hash> {
    let mut f = std::fs::File::open(path).ok()?;
    let mut h = blake3::Hasher::new();
    std::io::copy(&mut f, &mut h).ok()?;
    Some(h.finalize())
}

/// Write the memo of `dir`: its inputs, counts, chosen variant and the digest of each of `files`
/// (relative to `dir`, as they are on disk now). Left alone when its bytes would not change.
pub fn write(
    dir: &Path,
    inputs: &blake3::Hash,
    summary: Counted,
    chosen: Option<&str>,
    files: &[String],
) -> anyhow::Result<()> {
    let digests: Vec<(String, String)> = files
        .par_iter()
        .map(|f| {
            let p = dir.join(f);
            file_digest(&p)
                .map(|d| (f.clone(), d.to_hex().to_string()))
                .ok_or_else(|| anyhow::anyhow!("cannot read {} back", p.display()))
        })
        .collect::<anyhow::Result<_>>()?;
    let mut m = Memo {
        format_version: MEMO_VERSION,
        analysis_version: ANALYSIS_VERSION,
        inputs: inputs.to_hex().to_string(),
        summary,
        chosen: chosen.map(str::to_owned),
        files: digests.into_iter().collect(),
        seal: String::new(),
    };
    m.seal = m.sealed();
    let mut text = serde_json::to_string_pretty(&m)?;
    text.push('\n');
    qsweep_pipeline::atomic::write_if_changed(&dir.join(MEMO), text.as_bytes())?;
    Ok(())
}

/// What `qsweep verify` found of the memos under a reports directory.
#[derive(Debug, Default, Clone, PartialEq, Eq)]
pub struct MemoCheck {
    /// Memos read and intact (every file they list present with its digest, or missing).
    pub intact: usize,
    /// Memos that cannot be read (unparsable, unsealed, another version): `(memo, why)`.
    pub damaged: Vec<(std::path::PathBuf, String)>,
    /// Files whose bytes differ from their memo's digest (edited since they were written).
    pub differing: Vec<std::path::PathBuf>,
    /// Files a memo lists that are not there (uncommitted ones like `trials.parquet` in a fresh
    /// clone): not damage, the next report writes them.
    pub missing: Vec<std::path::PathBuf>,
}

/// Check every `memo.json` under `root` (its report folders and their variants' folders, two
/// levels deep): sealed and current, and each listed file with its recorded digest.
pub fn check_tree(root: &Path) -> MemoCheck {
    let mut out = MemoCheck::default();
    let mut dirs = vec![root.to_path_buf()];
    let mut i = 0;
    while i < dirs.len() {
        let depth = dirs[i].strip_prefix(root).map_or(0, |p| p.components().count());
        if depth < 2 {
            if let Ok(entries) = std::fs::read_dir(&dirs[i]) {
                let mut subs: Vec<_> = entries.flatten().map(|e| e.path()).filter(|p| p.is_dir()).collect();
                subs.sort();
                dirs.extend(subs);
            }
        }
        i += 1;
    }
    for dir in dirs {
        let path = dir.join(MEMO);
        if !path.is_file() {
            continue;
        }
        let Some(m) = read(&dir) else {
            let why = match std::fs::read(&path).ok().and_then(|b| serde_json::from_slice::<Memo>(&b).ok()) {
                None => "not a memo this qsweep reads (unparsable or another format)".to_string(),
                Some(m) if m.format_version != MEMO_VERSION || m.analysis_version != ANALYSIS_VERSION => {
                    format!(
                        "written by another qsweep (format {}, analysis {}); the next report recomputes it",
                        m.format_version, m.analysis_version
                    )
                }
                Some(_) => "its seal does not match its contents (edited or damaged)".to_string(),
            };
            out.damaged.push((path, why));
            continue;
        };
        let mut ok = true;
        for (name, digest) in &m.files {
            let p = dir.join(name);
            match file_digest(&p) {
                None => out.missing.push(p),
                Some(d) if d.to_hex().as_str() != digest => {
                    ok = false;
                    out.differing.push(p);
                }
                Some(_) => {}
            }
        }
        out.intact += usize::from(ok);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A plan of one heatmap of 9 Cart-Pole cells, 2 seeds each.
    fn plan() -> Plan {
        let text = "name: t\nseeds: 2\nsystems:\n  cart-pole:\n    settings: { max_episodes: 50 }\n    experiments:\n      - { id: a, repr: crisp, algorithms: [q0], vary: { actions: 2..10 }, fixed: { x == x_dot == theta == theta_dot: 2 } }\n";
        let spec = qsweep_pipeline::declared::load_str(text, "t.yaml", &[]).unwrap();
        let loaded =
            qsweep_pipeline::declared::LoadedSpec { spec, path: "t.yaml".into(), variants: Vec::new() };
        qsweep_pipeline::plan::plan(&loaded, None).unwrap()
    }

    fn digest(p: &Plan) -> blake3::Hash {
        Inputs::new(p, &KeySet::default()).of(p, None, Formats::default(), Role::Folder { own_trials: true })
    }

    #[test]
    fn the_inputs_pin_a_cells_configuration_by_its_keys_or_by_its_text_without_trials() {
        let p = plan();
        let base = digest(&p);
        assert_eq!(digest(&p), base, "deterministic");
        // A changed configuration changes the cell's keys, and with them the digest.
        let mut changed = p.clone();
        let cell = &mut changed.experiments[0].cells[0];
        cell.config.learner.alpha += 0.01;
        let canonical = qsweep_pipeline::cache::key::canonical_config(&cell.config);
        for t in &mut cell.trials {
            t.key = Key::from_canonical(&canonical, t.seed, qsweep_pipeline::cache::ENGINE_VERSION);
        }
        assert_ne!(digest(&changed), base);
        // A cell without trials is pinned by its configuration's text.
        let mut empty = p.clone();
        empty.experiments[0].cells[0].trials.clear();
        let without = digest(&empty);
        assert_ne!(without, base);
        empty.experiments[0].cells[0].config.learner.alpha += 0.01;
        assert_ne!(digest(&empty), without);
    }

    #[test]
    fn a_damaged_or_other_version_memo_reads_as_none_and_an_edited_file_breaks_it() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        let inputs = blake3::hash(b"inputs");
        assert_eq!(read(d), None, "no memo");
        std::fs::write(d.join("a.md"), "a").unwrap();
        write(d, &inputs, Counted::default(), None, &["a.md".to_string()]).unwrap();
        assert!(intact(d, &inputs).is_some());
        assert!(intact(d, &blake3::hash(b"other")).is_none(), "other inputs");
        std::fs::write(d.join("a.md"), "b").unwrap();
        assert!(intact(d, &inputs).is_none(), "a file edited by hand");
        std::fs::write(d.join("a.md"), "a").unwrap();
        assert!(intact(d, &inputs).is_some());
        std::fs::remove_file(d.join("a.md")).unwrap();
        assert!(intact(d, &inputs).is_none(), "a file deleted");
        let text = std::fs::read_to_string(d.join(MEMO)).unwrap();
        std::fs::write(d.join(MEMO), &text[..text.len() / 2]).unwrap();
        assert_eq!(read(d), None, "a truncated memo");
        std::fs::write(d.join(MEMO), text.replace("\"format_version\": 1", "\"format_version\": 0")).unwrap();
        assert_eq!(read(d), None, "an older format");
        let older = text.replace(
            &format!("\"analysis_version\": {ANALYSIS_VERSION}"),
            &format!("\"analysis_version\": {}", ANALYSIS_VERSION - 1),
        );
        assert_ne!(older, text);
        std::fs::write(d.join(MEMO), older).unwrap();
        assert_eq!(read(d), None, "an older analysis");
        std::fs::write(d.join(MEMO), text.replace("\"cells\": 0", "\"cells\": 7")).unwrap();
        assert_eq!(read(d), None, "a count edited");
    }
}
