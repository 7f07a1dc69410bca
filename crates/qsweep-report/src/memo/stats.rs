//! The statistics' memo: the report's expensive numbers — each cell's bootstrap interval, each
//! difference figure's per-cell interval, and any other statistic a part above keeps here through
//! [`StatsMemo::entry`] (the replication's claims) — addressed by content, as trials are. An
//! entry's id is blake3 over the statistic's kind, the definitions' version
//! (`ANALYSIS_VERSION`), its parameters (resamples, seed) and its inputs' bits (the values it
//! resamples), so an entry is exactly what recomputation would give: a changed input is a
//! different id, never a stale number. A report recomputes only the statistics whose inputs
//! changed (one more seed in one cell: that cell's interval, the differences it takes part in,
//! its variant's claims) and takes every other one from the memo.
//!
//! The memo of a pipeline lives in the cache, `<cache>/_derived/<pipeline>.bin` (the leading `_`
//! keeps pandas, polars and pyarrow from reading the folder as trial rows). A full report keeps
//! in it exactly the entries it used, so the file never holds what no report of the pipeline
//! needs; a report of some variants (`--variant`) adds to it. Its layout (all integers
//! little-endian):
//!
//! ```text
//! b"QSWDRV01"  u32 format (1)  u32 analysis version  u64 entries
//! entries, sorted by id: [u8; 16] id, u32 n, n × u64 (f64 bits, or 0/1 for "present")
//! [u8; 32] blake3 of everything above
//! ```
//!
//! No timestamps, nothing machine-dependent: the same entries give the same bytes. A missing,
//! damaged (checksum), older-format or other-version file is read as empty: everything is
//! recomputed, never an error.

pub mod readers;

use std::collections::{BTreeMap, HashMap};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;

/// The folder of the cache that holds the memos.
pub const DERIVED_DIR: &str = "_derived";

/// The file format this build reads and writes.
pub const DERIVED_FORMAT: u32 = 1;

const MAGIC: &[u8; 8] = b"QSWDRV01";

/// An entry's id: the first 16 bytes of blake3 of its inputs.
type Id = [u8; 16];

/// The statistics' memo of one report (see the module documentation).
#[derive(Debug)]
pub struct StatsMemo {
    /// The definitions' version mixed into every id.
    version: u32,
    /// Entries read from the file.
    kept: HashMap<Id, Box<[u64]>>,
    /// Whether statistics are taken from `kept` (not with `--rebuild`, which only keeps them).
    reuse: bool,
    /// Every entry this report asked for, kept or computed.
    used: Mutex<BTreeMap<Id, Box<[u64]>>>,
    computed: AtomicUsize,
    reused: AtomicUsize,
}

/// What one report did with the memo.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct MemoCounts {
    /// Statistics computed (not in the memo, or `--rebuild`).
    pub computed: usize,
    /// Statistics taken from the memo.
    pub reused: usize,
}

impl StatsMemo {
    /// A memo that reuses nothing (every statistic is computed) but records what it computes, to
    /// be saved: `--rebuild`, and callers without a cache.
    pub fn fresh(version: u32) -> Self {
        Self {
            version,
            kept: HashMap::new(),
            reuse: true,
            used: Mutex::new(BTreeMap::new()),
            computed: AtomicUsize::new(0),
            reused: AtomicUsize::new(0),
        }
    }

    /// The memo kept at `path` for definitions `version`; empty when there is none this build
    /// can trust (see the module documentation). Without `reuse` (`--rebuild`) every statistic is
    /// computed again, and the kept entries only stay in the file when the report is partial.
    pub fn load(path: &Path, version: u32, reuse: bool) -> Self {
        let mut d = Self { reuse, ..Self::fresh(version) };
        if let Ok(bytes) = std::fs::read(path) {
            if let Some(entries) = decode(&bytes, version) {
                d.kept = entries.into_iter().collect();
            }
        }
        d
    }

    /// The memo file of pipeline `name` in the cache at `cache`.
    pub fn path(cache: &Path, name: &str) -> PathBuf {
        cache.join(DERIVED_DIR).join(format!("{name}.bin"))
    }

    /// How many statistics were computed and reused so far.
    pub fn counts(&self) -> MemoCounts {
        MemoCounts {
            computed: self.computed.load(Ordering::Relaxed),
            reused: self.reused.load(Ordering::Relaxed),
        }
    }

    /// Write the entries used (and, unless `prune`, every kept one too) to `path`, atomically and
    /// only when its bytes would change; `true` when written.
    pub fn save(&self, path: &Path, prune: bool) -> anyhow::Result<bool> {
        let mut all = self.used.lock().expect("memo lock").clone();
        if !prune {
            for (id, v) in &self.kept {
                all.entry(*id).or_insert_with(|| v.clone());
            }
        }
        if let Some(dir) = path.parent() {
            std::fs::create_dir_all(dir)
                .map_err(|e| anyhow::anyhow!("cannot create {}: {e}", dir.display()))?;
        }
        qsweep_pipeline::atomic::write_if_changed(path, &encode(&all, self.version))
    }

    /// The entry `id`, from the memo or computed by `compute`, recorded as used.
    fn get(&self, id: Id, compute: impl FnOnce() -> Vec<u64>) -> Box<[u64]> {
        let value = match self.kept.get(&id).filter(|_| self.reuse) {
            Some(v) => {
                self.reused.fetch_add(1, Ordering::Relaxed);
                v.clone()
            }
            None => {
                self.computed.fetch_add(1, Ordering::Relaxed);
                compute().into_boxed_slice()
            }
        };
        self.used.lock().expect("memo lock").insert(id, value.clone());
        value
    }

    /// The entry of a statistic of kind `kind` whose parameters and inputs `inputs` writes into
    /// its id ([`put_params`], [`put_values`]): taken from the memo, or computed by `compute` (its
    /// result as 64-bit words, e.g. `f64::to_bits`), and recorded as used. How a statistic outside
    /// this module (the replication's claims) is memoized.
    pub fn entry(
        &self,
        kind: &str,
        inputs: impl FnOnce(&mut blake3::Hasher),
        compute: impl FnOnce() -> Vec<u64>,
    ) -> Box<[u64]> {
        let mut h = self.hasher(kind);
        inputs(&mut h);
        self.get(id(&h), compute)
    }

    /// An id hasher for a statistic of kind `kind` under this memo's definitions.
    fn hasher(&self, kind: &str) -> blake3::Hasher {
        let mut h = blake3::Hasher::new();
        h.update(b"qsweep-derived\0");
        h.update(&self.version.to_le_bytes());
        h.update(kind.as_bytes());
        h.update(b"\0");
        h
    }

    /// The id of [`StatsMemo::bootstrap_ci`]'s entry.
    fn ci_id(&self, values: &[f64], resamples: usize, seed: u64) -> Id {
        let mut h = self.hasher("bootstrap-ci");
        put_params(&mut h, resamples, seed);
        put_values(&mut h, values);
        id(&h)
    }

    /// Whether [`StatsMemo::bootstrap_ci`] of these inputs is in the memo (what a report would
    /// reuse rather than compute).
    pub fn has_ci(&self, values: &[f64], resamples: usize, seed: u64) -> bool {
        self.reuse && self.kept.contains_key(&self.ci_id(values, resamples, seed))
    }

    /// [`qsweep_pipeline::analysis::bootstrap_ci`], memoized.
    pub fn bootstrap_ci(&self, values: &[f64], resamples: usize, seed: u64) -> (f64, f64) {
        let v = self.get(self.ci_id(values, resamples, seed), || {
            let (lo, hi) = qsweep_pipeline::analysis::bootstrap_ci(values, resamples, seed);
            vec![lo.to_bits(), hi.to_bits()]
        });
        (f64::from_bits(v[0]), f64::from_bits(v[1]))
    }

    /// [`qsweep_pipeline::analysis::bootstrap_diff_ci`], memoized.
    pub fn bootstrap_diff_ci(&self, a: &[f64], b: &[f64], resamples: usize, seed: u64) -> (f64, f64) {
        let mut h = self.hasher("bootstrap-diff-ci");
        put_params(&mut h, resamples, seed);
        put_values(&mut h, a);
        put_values(&mut h, b);
        let v = self.get(id(&h), || {
            let (lo, hi) = qsweep_pipeline::analysis::bootstrap_diff_ci(a, b, resamples, seed);
            vec![lo.to_bits(), hi.to_bits()]
        });
        (f64::from_bits(v[0]), f64::from_bits(v[1]))
    }
}

/// Write a statistic's parameters into its id: resamples and seed.
pub fn put_params(h: &mut blake3::Hasher, resamples: usize, seed: u64) {
    h.update(&(resamples as u64).to_le_bytes());
    h.update(&seed.to_le_bytes());
}

/// Write a sample into a statistic's id: its length, then every value's bits.
pub fn put_values(h: &mut blake3::Hasher, values: &[f64]) {
    h.update(&(values.len() as u64).to_le_bytes());
    let bytes: Vec<u8> = values.iter().flat_map(|v| v.to_bits().to_le_bytes()).collect();
    h.update(&bytes);
}

fn id(h: &blake3::Hasher) -> Id {
    h.finalize().as_bytes()[..16].try_into().expect("16 bytes")
}

/// The file's bytes for `entries`.
fn encode(entries: &BTreeMap<Id, Box<[u64]>>, version: u32) -> Vec<u8> {
    let mut out = Vec::with_capacity(24 + entries.len() * 40 + 32);
    out.extend_from_slice(MAGIC);
    out.extend_from_slice(&DERIVED_FORMAT.to_le_bytes());
    out.extend_from_slice(&version.to_le_bytes());
    out.extend_from_slice(&(entries.len() as u64).to_le_bytes());
    for (id, v) in entries {
        out.extend_from_slice(id);
        out.extend_from_slice(&(v.len() as u32).to_le_bytes());
        for x in v.iter() {
            out.extend_from_slice(&x.to_le_bytes());
        }
    }
    let sum = blake3::hash(&out);
    out.extend_from_slice(sum.as_bytes());
    out
}

/// The entries of a file's bytes, when they are whole (checksum), of this format and of
/// definitions `version`.
fn decode(bytes: &[u8], version: u32) -> Option<Vec<(Id, Box<[u64]>)>> {
    let (body, sum) = bytes.split_at_checked(bytes.len().checked_sub(32)?)?;
    if blake3::hash(body).as_bytes() != sum || body.get(..8)? != MAGIC {
        return None;
    }
    let u32_at =
        |at: usize| -> Option<u32> { Some(u32::from_le_bytes(body.get(at..at + 4)?.try_into().ok()?)) };
    let u64_at =
        |at: usize| -> Option<u64> { Some(u64::from_le_bytes(body.get(at..at + 8)?.try_into().ok()?)) };
    if u32_at(8)? != DERIVED_FORMAT || u32_at(12)? != version {
        return None;
    }
    let n = usize::try_from(u64_at(16)?).ok()?;
    let mut at = 24;
    let mut out = Vec::with_capacity(n.min(body.len() / 20));
    for _ in 0..n {
        let id: Id = body.get(at..at + 16)?.try_into().ok()?;
        let len = u32_at(at + 16)? as usize;
        at += 20;
        let v: Box<[u64]> = (0..len).map(|k| u64_at(at + 8 * k)).collect::<Option<_>>()?;
        at += 8 * len;
        out.push((id, v));
    }
    (at == body.len()).then_some(out)
}

/// What `qsweep verify` found of a cache's memos.
#[derive(Debug, Default, Clone, PartialEq, Eq)]
pub struct StatsCheck {
    /// Memo files whole and of this build's format (any definitions' version).
    pub intact: usize,
    /// Entries in them.
    pub entries: usize,
    /// Memo files that are not: `(file, why)`. Not an error: the next report recomputes them.
    pub damaged: Vec<(PathBuf, String)>,
}

/// Check every memo file of the cache at `cache`.
pub fn check(cache: &Path) -> StatsCheck {
    let mut out = StatsCheck::default();
    let Ok(dir) = std::fs::read_dir(cache.join(DERIVED_DIR)) else { return out };
    let mut files: Vec<PathBuf> = dir.flatten().map(|e| e.path()).filter(|p| is_memo(p)).collect();
    files.sort();
    for p in files {
        let bytes = std::fs::read(&p).unwrap_or_default();
        let version = bytes.get(12..16).map_or(0, |b| u32::from_le_bytes(b.try_into().expect("4 bytes")));
        match decode(&bytes, version) {
            Some(e) => {
                out.intact += 1;
                out.entries += e.len();
            }
            None => out.damaged.push((p, "damaged or of another qsweep format".to_string())),
        }
    }
    out
}

/// What [`gc`] removed, or left because a report is reading it.
#[derive(Debug, Default, Clone, PartialEq, Eq)]
pub struct StatsGc {
    /// Memo files and parts' folders removed (with `dry_run`: that would be).
    pub removed: usize,
    /// Parts' folders of pipelines not kept, left in place because a report of the pipeline is
    /// reading them now ([`readers`]); the next `gc` removes them.
    pub in_use: Vec<PathBuf>,
}

/// Remove the memo files of the cache at `cache` that no report would read: those of pipelines
/// not in `keep` (when given), with their trial parts (unless a report is reading them), and
/// those not of this format and definitions `version`. With `dry_run`, remove nothing.
pub fn gc(
    cache: &Path,
    keep: Option<&std::collections::HashSet<String>>,
    version: u32,
    dry_run: bool,
) -> anyhow::Result<StatsGc> {
    let mut out = StatsGc::default();
    let Ok(dir) = std::fs::read_dir(cache.join(DERIVED_DIR)) else { return Ok(out) };
    let paths: Vec<PathBuf> = dir.flatten().map(|e| e.path()).collect();
    // A pipeline's trial parts (`<name>.trials/`, report::trials) go with it, once no report
    // holds them (removed under the folder's lock, so a report starting meanwhile waits).
    for p in paths.iter().filter(|p| p.is_dir() && p.extension().is_some_and(|x| x == "trials")) {
        let name = p.file_stem().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
        if keep.is_some_and(|k| !k.contains(&name)) {
            if dry_run {
                if readers::in_use(p) {
                    out.in_use.push(p.clone());
                } else {
                    out.removed += 1;
                }
                continue;
            }
            let guard = readers::alone(p);
            if matches!(guard, readers::Alone::No) {
                out.in_use.push(p.clone());
                continue;
            }
            out.removed += 1;
            std::fs::remove_dir_all(p).map_err(|e| anyhow::anyhow!("cannot remove {}: {e}", p.display()))?;
            drop(guard);
        }
    }
    for p in paths.iter().filter(|p| is_memo(p)) {
        let name = p.file_stem().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
        let unused = keep.is_some_and(|k| !k.contains(&name));
        let unreadable = std::fs::read(p).ok().and_then(|b| decode(&b, version)).is_none();
        if unused || unreadable {
            out.removed += 1;
            if !dry_run {
                std::fs::remove_file(p).map_err(|e| anyhow::anyhow!("cannot remove {}: {e}", p.display()))?;
            }
        }
    }
    Ok(out)
}

/// Whether `path` is a memo file (`<name>.bin` in `_derived/`).
pub fn is_memo(path: &Path) -> bool {
    path.is_file() && path.extension().is_some_and(|e| e == "bin")
}

#[cfg(test)]
mod tests;
