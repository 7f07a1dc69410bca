//! Leases in a cache directory: a file per batch of keys, hard-linked under each key's name in
//! `_leases/`, locked by its holder and renewed by a heartbeat on its modification time (the
//! module documentation of [`super`] tells the whole rule).

use super::batch::Batch;
use super::lease::Holder;
use super::seen::Seen;
use super::{inspect, lock_ok, remove_own, runs, Liveness, Take, LEASES_DIR};
use crate::cache::store::{KeySet, Store};
use crate::cache::Key;
use std::collections::HashMap;
use std::fs::File;
use std::io::ErrorKind;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};
use std::time::SystemTime;

/// This run's leases in a cache directory.
#[derive(Debug)]
pub struct FileLeases {
    dir: PathBuf,
    me: Holder,
    /// The run's mark, which its segments carry ([`runs`]).
    mark: runs::RunMark,
    /// Each leased key's file; the keys of one batch share one file (one lock, one heartbeat),
    /// closed, and so unlocked, once the last of them is released.
    held: Mutex<HashMap<Key, Arc<File>>>,
    /// Keys whose leases are being made (linked, not yet in `held`): [`Self::others_present`]
    /// counts their files as this run's.
    taking: std::sync::atomic::AtomicUsize,
    seen: Mutex<Seen>,
}

/// Counts keys as being taken for as long as it lives.
struct Taking<'l>(&'l std::sync::atomic::AtomicUsize, usize);

impl Drop for Taking<'_> {
    fn drop(&mut self) {
        self.0.fetch_sub(self.1, std::sync::atomic::Ordering::SeqCst);
    }
}

impl FileLeases {
    /// The leases of a run on `store` (creating the leases folder), and the run's mark.
    pub fn open(store: &Store) -> std::io::Result<Self> {
        let dir = store.dir().join(LEASES_DIR);
        std::fs::create_dir_all(&dir)?;
        Ok(Self {
            dir,
            me: Holder::me(),
            mark: runs::RunMark::register(store)?,
            held: Mutex::new(HashMap::new()),
            taking: std::sync::atomic::AtomicUsize::new(0),
            seen: Mutex::new(Seen::from_scan(store.dir(), &KeySet::default(), false)),
        })
    }

    /// Judge whether a key is stored against `scan` (the scan this execution planned from) and
    /// whatever is stored after it; with `force`, only against what is stored after it.
    pub fn reset_view(&self, scan: &KeySet, force: bool) {
        let cache = self.dir.parent().unwrap_or(&self.dir).to_path_buf();
        *lock_ok(&self.seen) = Seen::from_scan(&cache, scan, force);
    }

    fn path(&self, key: &Key) -> PathBuf {
        self.dir.join(key.hex())
    }

    /// The run's mark: the segments it writes carry it ([`Store::writing_as`]), and `qsweep gc`
    /// leaves them alone while the run lives.
    pub fn run_mark(&self) -> &str {
        self.mark.name()
    }

    /// Lease each of `keys` (distinct), answering for each as [`Self::try_take`] does. The batch
    /// costs one lease file, however many keys it leases: the file is made once and hard-linked
    /// under each key's name (`batch.rs`), and what is stored is looked at once, after every link.
    /// An error on one key (its lease could not be made) leaves the others leased.
    pub fn try_take_batch(&self, keys: &[Key]) -> Vec<std::io::Result<Take>> {
        self.taking.fetch_add(keys.len(), std::sync::atomic::Ordering::SeqCst);
        let _taking = Taking(&self.taking, keys.len());
        let mut file = Batch::new(&self.dir, &self.me);
        let linked: Vec<std::io::Result<Option<Arc<File>>>> =
            keys.iter().map(|k| self.link(&self.path(k), &mut file)).collect();
        drop(file);
        if !linked.iter().any(|l| matches!(l, Ok(Some(_)))) {
            return linked.into_iter().map(|l| l.map(|_| Take::Busy)).collect();
        }
        // Whoever stored a key removed its lease after storing it, so a key stored before its link
        // here shows now: look once for the batch (a segment written since is read once).
        let mut seen = lock_ok(&self.seen);
        seen.refresh();
        let mut held = lock_ok(&self.held);
        keys.iter()
            .zip(linked)
            .map(|(key, l)| match l {
                Ok(Some(file)) if seen.knows(key) => {
                    remove_own(&file, &self.path(key));
                    Ok(Take::Stored)
                }
                Ok(Some(file)) => {
                    held.insert(*key, file);
                    Ok(Take::Taken)
                }
                Ok(None) => Ok(Take::Busy),
                Err(e) => Err(e),
            })
            .collect()
    }

    /// Put this batch's lease at `path`: the file when it is now ours, `None` when a live holder
    /// has it. A dead holder's lease there is removed and replaced.
    fn link(&self, path: &Path, batch: &mut Batch) -> std::io::Result<Option<Arc<File>>> {
        for _ in 0..4 {
            match batch.link(path) {
                Ok(file) => return Ok(Some(file)),
                Err(e) if e.kind() == ErrorKind::AlreadyExists => {}
                Err(e) if e.kind() == ErrorKind::NotFound => {
                    // Someone removed the folder (by hand), and the batch's file with it: make both
                    // again.
                    std::fs::create_dir_all(&self.dir)?;
                    batch.forget();
                    continue;
                }
                Err(e) => return Err(e),
            }
            let (file, liveness) = match inspect(path, &self.me) {
                Ok(found) => found,
                Err(e) if e.kind() == ErrorKind::NotFound => continue,
                Err(e) => return Err(e),
            };
            if liveness == Liveness::Live {
                return Ok(None);
            }
            // Take over: remove the dead lease (only if it is still the file judged) and make ours.
            remove_own(&file, path);
        }
        // Others keep making and removing it: treat it as busy and look again later.
        Ok(None)
    }

    /// Release the leases of `keys` (their trials are stored).
    pub fn release(&self, keys: &[Key]) {
        let mut held = lock_ok(&self.held);
        for k in keys {
            if let Some(file) = held.remove(k) {
                remove_own(&file, &self.path(k));
            }
        }
    }

    /// Release every lease this run holds (the run ends, or was interrupted).
    pub fn release_all(&self) {
        let mut held = lock_ok(&self.held);
        for (k, file) in held.drain() {
            remove_own(&file, &self.path(&k));
        }
    }

    /// Renew the lease of every lease held (call every [`lease::HEARTBEAT`]): once per batch,
    /// since a batch's keys are links to one file and share its modification time.
    pub fn heartbeat(&self) {
        let now = SystemTime::now();
        let held = lock_ok(&self.held);
        let mut files: Vec<&Arc<File>> = held.values().collect();
        files.sort_by_key(|f| Arc::as_ptr(f));
        files.dedup_by_key(|f| Arc::as_ptr(f));
        for file in files {
            let _ = file.set_modified(now);
        }
    }

    /// Whether another run holds leases in this cache now (live or not): someone may be waiting
    /// for this run's trials.
    ///
    /// The folder is listed under the lock of the leases held, so no lease of this run is
    /// released between the listing and the count; the files of leases being made count as this
    /// run's (`taking`). Without both, the tail of a lone run mistook its own leases for another
    /// run's now and then and flushed an early batch: two segments where one was due.
    pub fn others_present(&self) -> bool {
        let held = lock_ok(&self.held);
        let Ok(entries) = std::fs::read_dir(&self.dir) else { return false };
        let files = entries
            .flatten()
            .filter(|e| !e.file_name().to_string_lossy().starts_with(crate::atomic::TEMP_PREFIX))
            .count();
        files > held.len() + self.taking.load(std::sync::atomic::Ordering::SeqCst)
    }

    /// Remove every lease in the folder whose holder is dead (debris: see [`judge`]); a live
    /// holder's lease, and a file being made, are left alone.
    fn sweep_dead(&self) {
        let Ok(entries) = std::fs::read_dir(&self.dir) else { return };
        for e in entries.flatten() {
            if e.file_name().to_string_lossy().starts_with(crate::atomic::TEMP_PREFIX) {
                continue;
            }
            if let Ok((file, Liveness::Dead)) = inspect(&e.path(), &self.me) {
                remove_own(&file, &e.path());
            }
        }
    }

    /// How many leases this run holds.
    pub fn held(&self) -> usize {
        lock_ok(&self.held).len()
    }
}

impl Drop for FileLeases {
    fn drop(&mut self) {
        self.release_all();
        // A run killed between storing a segment and releasing its leases leaves leases of stored
        // keys that no later run needs to take over; the last run to see them dead removes them.
        self.sweep_dead();
        // The cache looks as before once no run is on it; a run that just made the folder and
        // meets it gone makes it again (see `try_take`). Fails harmlessly while others use it.
        let _ = std::fs::remove_dir(&self.dir);
    }
}
