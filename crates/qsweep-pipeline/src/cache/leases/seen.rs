//! What a run knows is stored, kept current cheaply: a lease just taken must not run a trial that
//! another run stored after this run scanned the cache. Segments are immutable and only ever
//! added (or compacted by `gc`), so only the segments not seen before are read, and only when the
//! cache directory's modification time says something changed.

use crate::cache::rows::read_keys;
use crate::cache::store::{KeySet, SEGMENT_PREFIX};
use crate::cache::Key;
use std::collections::HashSet;
use std::path::{Path, PathBuf};
use std::time::{Duration, SystemTime};

/// A directory changed this recently may change again within its timestamp's granularity
/// (a kernel tick; seconds on some network file systems), so its time is not trusted yet.
const SETTLE: Duration = Duration::from_secs(2);

/// The stored keys as last read, and the segments they came from.
#[derive(Debug, Default)]
pub struct Seen {
    dir: PathBuf,
    segments: HashSet<PathBuf>,
    keys: HashSet<Key>,
    mtime: Option<SystemTime>,
}

impl Seen {
    /// Start from a scan of the cache in `dir`. With `force`, what that scan holds does not count
    /// as stored (the run computes it again); only what other runs store from now on does.
    pub fn from_scan(dir: &Path, scan: &KeySet, force: bool) -> Self {
        let mut segments: HashSet<PathBuf> = scan.segments.iter().map(|(p, _)| p.clone()).collect();
        segments.extend(scan.damaged.iter().map(|d| d.path.clone()));
        let keys = if force { HashSet::new() } else { scan.keys.clone() };
        Self { dir: dir.to_path_buf(), segments, keys, mtime: None }
    }

    /// Whether `key` was stored as of the last look ([`Self::refresh`]): a batch of leases looks
    /// once for all its keys.
    pub fn knows(&self, key: &Key) -> bool {
        self.keys.contains(key)
    }

    /// Read the segments added since the last look, if the cache directory changed.
    pub fn refresh(&mut self) {
        let Ok(mtime) = std::fs::metadata(&self.dir).and_then(|m| m.modified()) else { return };
        if self.mtime == Some(mtime) {
            return;
        }
        let Ok(entries) = std::fs::read_dir(&self.dir) else { return };
        for entry in entries.flatten() {
            let name = entry.file_name();
            let name = name.to_string_lossy();
            if !(name.starts_with(SEGMENT_PREFIX) && name.ends_with(".parquet")) {
                continue;
            }
            let path = entry.path();
            if self.segments.contains(&path) {
                continue;
            }
            // A segment is renamed into place whole; one that cannot be read is damaged, and
            // its trials are not stored as far as this run is concerned.
            if let Ok(keys) = read_keys(&path) {
                self.keys.extend(keys);
            }
            self.segments.insert(path);
        }
        let settled = SystemTime::now().duration_since(mtime).is_ok_and(|age| age > SETTLE);
        self.mtime = settled.then_some(mtime);
    }
}
