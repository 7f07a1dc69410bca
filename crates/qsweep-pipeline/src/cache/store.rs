//! The append-only Parquet store: one directory of segment files, each a batch of trial rows.
//!
//! A segment is written to a hidden temp file (`.tmp-*`) in the cache directory and renamed into
//! place, so a trial is stored exactly when its row is in a renamed `seg-*.parquet`. Nothing is ever
//! rewritten in place; several processes may append at once (segment names are unique), and a trial
//! stored twice is identical by determinism, so duplicates are dropped on read. Reading which keys
//! exist reads only the `key` column. A segment written by a run (`qsweep run`) names it:
//! `seg-<hash>.<run>.parquet`, where `<run>` is the run's mark in `_runs/`
//! ([`super::leases::runs`]), so that `qsweep gc` leaves a live run's rows alone.
//!
//! A segment that cannot be read (truncated, garbage, wrong schema) is reported as damaged and its
//! rows are treated as missing, so they are recomputed rather than served.
//! How a row is encoded and decoded is [`super::rows`].
//!
//! Segments do go away: `qsweep gc` replaces many by few (writing the new ones before removing the
//! old, [`super::gc`]) and `qsweep verify` moves damaged ones aside. A reader that listed a segment
//! which is gone when it opens it ([`Vanished`]) lists the segments again and reads again, from
//! the segments the cache holds now (at most [`RELISTS`] times: only a gc that replaced segments
//! in between makes it read again, and a gc with nothing to change replaces none). It costs
//! nothing until it happens; then one more listing and read of every segment's keys and of the
//! rows wanted. No lock is taken, so the rule holds for any store that can list and read files
//! (a bucket too: a listed object that is gone reads as "not found").
//!
//! A store may keep its segments in a [`Remote`] (a bucket, [`super::remote`]): then the remote
//! lists them, each is fetched once into the directory (a read-through copy, never stale since a
//! segment never changes), and a new one is uploaded with one create-only request before its copy
//! is written. Everything that reads a segment reads the copy, exactly as it reads a local cache.

use super::key::Key;
use super::record::TrialRecord;
use super::remote::{object_of, RemoteRef};
use super::rows::{read_keys, read_outcome_rows, read_segment, to_batch, StoredTrial};
use crate::atomic::write_atomic;
use crate::parquet_io::to_parquet;
use std::collections::HashSet;
use std::path::{Path, PathBuf};

/// Segment file names start with this and end with `.parquet`.
pub const SEGMENT_PREFIX: &str = "seg-";

/// A segment that could not be read, and why.
#[derive(Debug, Clone, PartialEq)]
pub struct Damaged {
    /// The segment file.
    pub path: PathBuf,
    /// What went wrong.
    pub error: String,
}

impl std::fmt::Display for Damaged {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}: {}", self.path.display(), self.error)
    }
}

/// The cache's keys, where each row lives, and the segments that could not be read.
#[derive(Debug, Default)]
pub struct KeySet {
    /// Every stored key.
    pub keys: HashSet<Key>,
    /// Unreadable segments (their rows count as missing).
    pub damaged: Vec<Damaged>,
    /// Every readable segment with its keys in row order, sorted by path: where each row lives,
    /// so a read of some keys decodes only the rows (and segments) that hold them.
    pub segments: Vec<(PathBuf, Vec<Key>)>,
}

impl KeySet {
    /// Every stored key with `segment` of the segment its outcome is read from: of the segments
    /// holding it, the first in `segments`' order. Every read of this scan follows this one rule
    /// ([`Store::read_outcomes`]), so a report's memo can name a trial's row by its segment.
    pub fn reading_segment<T: Copy>(
        &self,
        segment: impl Fn(&Path) -> T,
    ) -> std::collections::HashMap<Key, T> {
        let mut out = std::collections::HashMap::with_capacity(self.keys.len());
        for (path, keys) in &self.segments {
            let id = segment(path);
            for k in keys {
                out.entry(*k).or_insert(id);
            }
        }
        out
    }

    /// The rows to read for the keys in `wanted`, per segment in `segments`' order: each key from
    /// the first segment holding it ([`KeySet::reading_segment`]'s rule).
    fn rows_to_read(&self, wanted: &HashSet<Key>) -> Vec<(&Path, Vec<usize>)> {
        let mut taken = HashSet::new();
        let mut work = Vec::new();
        for (path, keys) in &self.segments {
            let rows: Vec<usize> =
                (0..keys.len()).filter(|&i| wanted.contains(&keys[i]) && taken.insert(keys[i])).collect();
            if !rows.is_empty() {
                work.push((path.as_path(), rows));
            }
        }
        work
    }
}

/// How many times a reader lists the segments again when one it listed was removed meanwhile
/// (see the module documentation); past that it fails, naming the cache.
pub const RELISTS: usize = 8;

/// A segment listed by a reader was gone when the reader opened it: compacted by `qsweep gc` or
/// moved aside by `qsweep verify` since the listing. The reader lists the segments again.
#[derive(Debug, thiserror::Error)]
#[error("cache segment {} was removed while it was being read (compacted by `qsweep gc`)", .0.display())]
pub struct Vanished(pub PathBuf);

/// `error`, met reading the segment at `path`, as [`Vanished`] when the segment is gone.
pub(super) fn vanished_or(path: &Path, error: anyhow::Error) -> anyhow::Error {
    if std::fs::symlink_metadata(path).is_err_and(|e| e.kind() == std::io::ErrorKind::NotFound) {
        Vanished(path.to_path_buf()).into()
    } else {
        error
    }
}

/// Whether `error` says that a listed segment vanished.
pub fn is_vanished(error: &anyhow::Error) -> bool {
    error.chain().any(|c| c.is::<Vanished>())
}

/// Run `read` (which lists the segments itself) until it does not meet a [`Vanished`] segment,
/// at most [`RELISTS`] times more.
pub(super) fn relisting<T>(dir: &Path, mut read: impl FnMut() -> anyhow::Result<T>) -> anyhow::Result<T> {
    for _ in 0..RELISTS {
        match read() {
            Err(e) if is_vanished(&e) => continue,
            other => return other,
        }
    }
    read().map_err(|e| {
        e.context(format!(
            "cannot read the cache {}: its segments were replaced {RELISTS} times while it was read \
             (`qsweep gc` in a loop?)",
            dir.display()
        ))
    })
}

/// The run that wrote the segment at `path`, as its name says (`seg-<hash>.<run>.parquet`);
/// `None` for a segment written by anything else (`gc`, an older qsweep, a library user).
pub fn writer_of(path: &Path) -> Option<&str> {
    let name = path.file_name()?.to_str()?;
    let stem = name.strip_prefix(SEGMENT_PREFIX)?.strip_suffix(".parquet")?;
    stem.split_once('.').map(|(_, run)| run).filter(|run| !run.is_empty())
}

/// A cache directory, or a cache in a [`super::remote::Remote`] with its read-through copy.
#[derive(Debug, Clone)]
pub struct Store {
    dir: PathBuf,
    /// The run whose segments this store writes ([`Store::writing_as`]).
    writer: Option<String>,
    /// Where the segments live when not in `dir` alone; `dir` then holds their copies.
    remote: Option<RemoteRef>,
}

impl Store {
    /// Open (creating if needed) the cache directory.
    pub fn open(dir: &Path) -> std::io::Result<Self> {
        std::fs::create_dir_all(dir)?;
        if !std::fs::metadata(dir)?.is_dir() {
            return Err(std::io::Error::other("not a directory"));
        }
        Ok(Self { dir: dir.to_path_buf(), writer: None, remote: None })
    }

    /// The cache in `remote`, its segments copied into `dir` (created if needed) as they are read.
    pub fn open_remote(remote: RemoteRef, dir: &Path) -> std::io::Result<Self> {
        let mut store = Self::open(dir)?;
        store.remote = Some(remote);
        Ok(store)
    }

    /// The remote holding this cache, if it is not a directory alone.
    pub fn remote(&self) -> Option<&RemoteRef> {
        self.remote.as_ref()
    }

    /// The cache as its user named it: the bucket's address, or the directory.
    pub fn location(&self) -> String {
        match &self.remote {
            Some(r) => r.url().to_string(),
            None => self.dir.display().to_string(),
        }
    }

    /// This store, writing segments named for the run `writer` (its mark in `_runs/`,
    /// [`super::leases::runs::RunMark::name`]): `qsweep gc` leaves them alone while it lives.
    pub fn writing_as(mut self, writer: &str) -> Self {
        self.writer = Some(writer.to_string());
        self
    }

    /// The cache directory.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// Every segment file, sorted by name (so reads are deterministic). With a remote, the
    /// segments it lists, each copied into the directory first if it is not there yet.
    pub fn segments(&self) -> anyhow::Result<Vec<PathBuf>> {
        if let Some(remote) = &self.remote {
            return self.fetch_listed(remote);
        }
        let mut out = Vec::new();
        let entries = std::fs::read_dir(&self.dir)
            .map_err(|e| anyhow::anyhow!("cannot list cache {}: {e}", self.dir.display()))?;
        for entry in entries {
            let entry = entry?;
            let name = entry.file_name();
            let name = name.to_string_lossy();
            if name.starts_with(SEGMENT_PREFIX) && name.ends_with(".parquet") && entry.file_type()?.is_file()
            {
                out.push(entry.path());
            }
        }
        out.sort();
        Ok(out)
    }

    /// Append `records` as one new segment (temp file + fsync + rename); returns its path.
    pub fn write_segment(&self, records: &[TrialRecord]) -> anyhow::Result<PathBuf> {
        anyhow::ensure!(!records.is_empty(), "refusing to write an empty segment");
        let keys: Vec<Key> = records.iter().map(|r| r.key).collect();
        self.write_batch(&keys, &to_batch(records)?)
    }

    /// Append `batch`, the rows of trials `keys`, as one new segment named as every segment is
    /// (after its keys, this process and the time, and the run writing it): how rows of another
    /// schema (a program pipeline's, `crate::program`) are stored with the same guarantees.
    pub fn write_batch(
        &self,
        keys: &[Key],
        batch: &arrow::record_batch::RecordBatch,
    ) -> anyhow::Result<PathBuf> {
        anyhow::ensure!(!keys.is_empty(), "refusing to write an empty segment");
        let name = segment_name(keys, self.writer.as_deref());
        let path = self.dir.join(&name);
        to_parquet(batch)
            .and_then(|bytes| {
                if let Some(remote) = &self.remote {
                    // One create-only PUT under the final name: the segment is listed whole or not
                    // at all. Its name is this writer's alone, so a refusal is never expected.
                    anyhow::ensure!(remote.create(&name, &bytes)?, "segment {name} exists already");
                }
                write_atomic(&path, &bytes)
            })
            .map_err(|e| e.context(format!("cannot write cache segment in {}", self.location())))?;
        Ok(path)
    }

    /// Store `bytes`, a whole segment file named `name` elsewhere (`qsweep cache push`/`pull`),
    /// under that name unless a segment of that name is here already: a name is never reused, so
    /// it is the same segment. One create-only write in a bucket, an atomic one in a directory.
    pub fn put_segment(&self, name: &str, bytes: &[u8]) -> anyhow::Result<()> {
        anyhow::ensure!(
            name.starts_with(SEGMENT_PREFIX) && name.ends_with(".parquet") && !name.contains('/'),
            "{name} is not a segment name"
        );
        let path = self.dir.join(name);
        if let Some(remote) = &self.remote {
            remote.create(name, bytes)?;
        } else if path.exists() {
            return Ok(());
        }
        write_atomic(&path, bytes)
    }

    /// Remove the segment at `path` (from the remote too, if any); one already gone is no error
    /// (another gc removed it first: its rows are in that gc's segments).
    pub fn remove_segment(&self, path: &Path) -> anyhow::Result<()> {
        if let Some(remote) = &self.remote {
            remote.delete(&object_of(path)?)?;
        }
        match std::fs::remove_file(path) {
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(()),
            r => r.map_err(|e| anyhow::anyhow!("cannot remove {}: {e}", path.display())),
        }
    }

    /// Every stored key, reading only the `key` column of each segment (listed again when one
    /// vanishes meanwhile: see the module documentation).
    pub fn keys(&self) -> anyhow::Result<KeySet> {
        relisting(&self.dir, || {
            let mut scan = KeySet::default();
            for path in self.segments()? {
                match read_keys(&path).map_err(|e| vanished_or(&path, e)) {
                    Ok(keys) => {
                        scan.keys.extend(keys.iter().copied());
                        scan.segments.push((path, keys));
                    }
                    Err(e) if is_vanished(&e) => return Err(e),
                    Err(e) => scan.damaged.push(Damaged { path, error: format!("{e:#}") }),
                }
            }
            Ok(scan)
        })
    }

    /// The outcomes of the `wanted` keys, one per key (the first segment holding it wins), reading
    /// only the outcome columns (`episode_lengths` only when `lengths`) of only the rows that hold
    /// them, at the positions `scan` found. Segments are decoded in parallel; the result does not
    /// depend on the number of threads.
    pub fn read_outcomes(
        &self,
        scan: &KeySet,
        wanted: &HashSet<Key>,
        lengths: bool,
    ) -> anyhow::Result<std::collections::HashMap<Key, StoredTrial>> {
        Ok(self.read_outcomes_as(scan, wanted, lengths, |k, s| (k, s))?.into_iter().collect())
    }

    /// [`Store::read_outcomes`], each outcome mapped by `f` as its segment is decoded (a caller
    /// that keeps a little of each holds no full outcome of every key at once), in segment order.
    /// A segment of `scan` that is gone (gc compacted it since) makes the read start again from
    /// the segments the cache holds now; it fails only if a row of `wanted` that `scan` found is
    /// no longer stored at all (gc given other pipelines removed it).
    pub fn read_outcomes_as<T: Send>(
        &self,
        scan: &KeySet,
        wanted: &HashSet<Key>,
        lengths: bool,
        f: impl Fn(Key, StoredTrial) -> T + Sync,
    ) -> anyhow::Result<Vec<T>> {
        match read_outcomes_of(scan, wanted, lengths, &f) {
            Err(e) if is_vanished(&e) => {}
            done => return done,
        }
        relisting(&self.dir, || {
            let now = self.keys()?;
            let gone = scan.keys.iter().filter(|k| wanted.contains(k) && !now.keys.contains(k)).count();
            anyhow::ensure!(
                gone == 0,
                "{gone} trials read from the cache {} were removed from it while they were read (by \
                 `qsweep gc` given other pipelines): run the command again",
                self.dir.display()
            );
            read_outcomes_of(&now, wanted, lengths, &f)
        })
    }

    /// The stored records whose key is in `wanted`, one per key (duplicates dropped), in segment
    /// order. Unreadable segments are skipped (see [`Store::keys`] to list them).
    pub fn read(&self, wanted: &HashSet<Key>) -> anyhow::Result<Vec<TrialRecord>> {
        self.read_filtered(|k| wanted.contains(k))
    }

    /// Every stored record, one per key.
    pub fn read_all(&self) -> anyhow::Result<Vec<TrialRecord>> {
        self.read_filtered(|_| true)
    }

    fn read_filtered(&self, keep: impl Fn(&Key) -> bool) -> anyhow::Result<Vec<TrialRecord>> {
        relisting(&self.dir, || {
            let mut seen = HashSet::new();
            let mut out = Vec::new();
            for path in self.segments()? {
                let records = match read_segment(&path, &|k| keep(k) && !seen.contains(k)) {
                    Ok(records) => records,
                    Err(e) => match vanished_or(&path, e) {
                        e if is_vanished(&e) => return Err(e),
                        _ => continue,
                    },
                };
                for r in records {
                    if seen.insert(r.key) {
                        out.push(r);
                    }
                }
            }
            Ok(out)
        })
    }
}

/// The outcomes of the `wanted` keys at the rows `scan` found ([`Store::read_outcomes_as`]);
/// [`Vanished`] when a segment of `scan` is gone.
fn read_outcomes_of<T: Send>(
    scan: &KeySet,
    wanted: &HashSet<Key>,
    lengths: bool,
    f: &(impl Fn(Key, StoredTrial) -> T + Sync),
) -> anyhow::Result<Vec<T>> {
    use rayon::prelude::*;
    let work = scan.rows_to_read(wanted);
    let parts: Vec<Vec<T>> = work
        .par_iter()
        .map(|(path, rows)| {
            read_outcome_rows(path, rows, lengths)
                .map(|got| got.into_iter().map(|(k, s)| f(k, s)).collect())
                .map_err(|e| vanished_or(path, e))
                .map_err(|e| e.context(format!("cannot read cache segment {}", path.display())))
        })
        .collect::<anyhow::Result<_>>()?;
    let mut out = Vec::with_capacity(parts.iter().map(Vec::len).sum());
    for p in parts {
        out.extend(p);
    }
    Ok(out)
}

/// A name no other writer picks: a hash of the batch's keys, the process and the time, then the
/// run that writes it, if any ([`writer_of`]).
fn segment_name(keys: &[Key], writer: Option<&str>) -> String {
    let mut h = blake3::Hasher::new();
    for k in keys {
        h.update(&k.0);
    }
    h.update(&std::process::id().to_le_bytes());
    let nanos =
        std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).map_or(0, |d| d.as_nanos());
    h.update(&nanos.to_le_bytes());
    let hash = h.finalize().to_hex();
    match writer {
        Some(run) => format!("{SEGMENT_PREFIX}{}.{run}.parquet", &hash[..32]),
        None => format!("{SEGMENT_PREFIX}{}.parquet", &hash[..32]),
    }
}

mod copy;
#[cfg(test)]
mod tests;
