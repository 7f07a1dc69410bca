//! Leases: how several runs sharing one cache avoid computing a trial twice, and how a run that
//! dies strands nothing.
//!
//! Before a run computes a trial it leases the trial's key: a small file `_leases/<key>` in the
//! cache directory, made atomically (written and locked under a temporary name, then hard-linked
//! into place, which fails if the key is leased already) and holding the holder's host and pid.
//! Keys are leased a few at a time ([`Leases::try_take_batch`]): one file per batch, linked under
//! each of its keys (`batch.rs`), so a lease costs a link instead of a file. Another run that
//! meets the lease skips the trial, does its other work, and at the end waits for the key to be
//! stored (see [`crate::exec`]). The holder removes its leases once their trials
//! are stored, and at once on Ctrl-C / SIGTERM ([`release_registered`]).
//!
//! A lease is live while its holder keeps an advisory lock on it ([`lock`]: dropped by the
//! kernel when the process dies, so on one machine a dead holder is seen at once) and refreshes it
//! within its lease ([`lease`]: for machines that do not share locks). A dead holder's lease is
//! removed and taken by whoever meets it next. Older builds ignore the folder, and the segments
//! stay the only truth: a trial stored twice (only possible where neither layer can see a live
//! holder) is identical and dropped on read. `docs/sharing-a-cache.md` is the user's account.
//!
//! A run also keeps a mark in the cache for its whole life ([`runs`]), which its segments name,
//! so that `qsweep gc` never removes the rows of a run that is still alive.

mod batch;
pub mod lease;
pub mod lock;
pub mod runs;
mod seen;

use self::batch::Batch;
use self::lease::{is_stale, process_alive, Holder, LEASE};
use self::lock::{is_at, try_lock, Lock};
use super::store::{KeySet, Store};
use super::Key;
use std::collections::HashMap;
use std::fs::File;
use std::io::{ErrorKind, Read};
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex, Weak};
use std::time::SystemTime;

pub use seen::Seen;

/// The folder inside the cache that holds the leases. Its leading `_` (like `_quarantine`'s)
/// makes readers that take the cache folder as a Parquet dataset (pyarrow, pandas, polars) skip
/// it, and older builds only ever list `seg-*.parquet`.
pub const LEASES_DIR: &str = "_leases";

/// What leasing a key found.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Take {
    /// This run now holds the lease: compute the trial.
    Taken,
    /// A live holder is computing it.
    Busy,
    /// It is stored already (by another run since this one scanned the cache).
    Stored,
}

/// What a lease file found in the cache says about its holder.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Liveness {
    /// Its holder is alive (or may be: its lease has not run out).
    Live,
    /// Its holder is gone: the lease is debris, free to remove or take over.
    Dead,
}

/// Judge a lease from what its file shows: the lock, its holder, and whether its lease ran out.
/// A lock someone holds means a live holder unless the lease ran out (a lost machine whose lock
/// the file server has not yet dropped). A lock this process could take means the holder is dead
/// if it was on this machine (the kernel dropped its lock); on another machine, whose lock may
/// not reach us, the lease decides; so it does for a file without a holder (one that died while
/// making it) and where locks do not work at all.
pub fn judge(lock: Lock, holder: Option<&Holder>, me: &Holder, stale: bool) -> Liveness {
    let live = match (lock, holder) {
        (Lock::Busy, _) => !stale,
        (Lock::Taken, Some(h)) if h.host == me.host => false,
        (Lock::Unsupported, Some(h)) if h.host == me.host => !stale && process_alive(h.pid),
        _ => !stale,
    };
    if live {
        Liveness::Live
    } else {
        Liveness::Dead
    }
}

/// One lease file as found: its handle (kept open while judged, so its lock means something) and
/// how live it is.
fn inspect(path: &Path, me: &Holder) -> std::io::Result<(File, Liveness)> {
    let mut file = File::open(path)?;
    let lock = try_lock(&file)?;
    let mut text = String::new();
    // A garbled file is no holder; an unreadable one too (the lease then decides).
    let _ = file.read_to_string(&mut text);
    let modified = file.metadata()?.modified()?;
    let stale = is_stale(modified, SystemTime::now(), LEASE);
    Ok((file, judge(lock, Holder::parse(&text).as_ref(), me, stale)))
}

/// This run's leases in one cache.
#[derive(Debug)]
pub struct Leases {
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

impl Leases {
    /// The leases of a run on `store` (creating the leases folder), and the run's mark.
    pub fn open(store: &Store) -> std::io::Result<Arc<Self>> {
        let dir = store.dir().join(LEASES_DIR);
        std::fs::create_dir_all(&dir)?;
        Ok(Arc::new(Self {
            dir,
            me: Holder::me(),
            mark: runs::RunMark::register(store)?,
            held: Mutex::new(HashMap::new()),
            taking: std::sync::atomic::AtomicUsize::new(0),
            seen: Mutex::new(Seen::from_scan(store.dir(), &KeySet::default(), false)),
        }))
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

    /// Lease `key`: [`Take::Taken`] when this run now holds it, [`Take::Busy`] when a live holder
    /// does, [`Take::Stored`] when it turns out to be stored already. A dead holder's lease is
    /// taken over. A batch of one ([`Self::try_take_batch`]).
    pub fn try_take(&self, key: Key) -> std::io::Result<Take> {
        self.try_take_batch(&[key]).pop().unwrap_or(Ok(Take::Busy))
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

impl Drop for Leases {
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

/// Remove the lease at `path` if `file` is still it (a lease taken over meanwhile is not ours).
fn remove_own(file: &File, path: &Path) {
    if is_at(file, path) {
        let _ = std::fs::remove_file(path);
    }
}

/// A poisoned lock only means another thread panicked; the maps and lists it guards are still
/// sound (shared with the scheduler, `exec::leased`).
pub(crate) fn lock_ok<T>(m: &Mutex<T>) -> std::sync::MutexGuard<'_, T> {
    m.lock().unwrap_or_else(std::sync::PoisonError::into_inner)
}

static REGISTERED: Mutex<Option<Weak<Leases>>> = Mutex::new(None);

/// Let [`release_registered`] (the Ctrl-C / SIGTERM handler) release `leases`.
pub fn register(leases: &Arc<Leases>) {
    *lock_ok(&REGISTERED) = Some(Arc::downgrade(leases));
}

/// Release the registered run's leases now: an interrupted run gives its trials to the other
/// runs at once instead of making them wait for a lease (or for its exit).
pub fn release_registered() {
    let leases = lock_ok(&REGISTERED).as_ref().and_then(Weak::upgrade);
    if let Some(c) = leases {
        c.release_all();
    }
}

/// Of `keys`, how many another run is computing now (a live lease): `status`'s
/// `running_elsewhere`. Reads the leases folder once.
pub fn running_elsewhere<'a>(store: &Store, keys: impl IntoIterator<Item = &'a Key>) -> usize {
    let dir = store.dir().join(LEASES_DIR);
    let Ok(entries) = std::fs::read_dir(&dir) else { return 0 };
    let leased: std::collections::HashSet<Key> =
        entries.flatten().filter_map(|e| Key::parse_hex(&e.file_name().to_string_lossy())).collect();
    if leased.is_empty() {
        return 0;
    }
    let me = Holder::me();
    let wanted: std::collections::HashSet<&Key> = keys.into_iter().filter(|k| leased.contains(k)).collect();
    wanted
        .into_iter()
        .filter(|k| inspect(&dir.join(k.hex()), &me).is_ok_and(|(_, liveness)| liveness == Liveness::Live))
        .count()
}

/// What [`sweep`] found in the leases folder.
#[derive(Debug, Default, Clone, Copy, PartialEq, Eq)]
pub struct Swept {
    /// Leases of dead holders (and stray temporary files), removed.
    pub removed: usize,
    /// Leases of live holders, left alone.
    pub live: usize,
}

/// Remove the leases folder's debris: leases whose holder is dead, and temporary files left by
/// a holder killed while making a lease. With `dry_run`, only count them.
pub fn sweep(store: &Store, dry_run: bool) -> std::io::Result<Swept> {
    let dir = store.dir().join(LEASES_DIR);
    let mut out = Swept::default();
    let entries = match std::fs::read_dir(&dir) {
        Ok(e) => e,
        Err(e) if e.kind() == ErrorKind::NotFound => return Ok(out),
        Err(e) => return Err(e),
    };
    let me = Holder::me();
    for entry in entries {
        let entry = entry?;
        let path = entry.path();
        let name = entry.file_name().to_string_lossy().into_owned();
        if name.starts_with(crate::atomic::TEMP_PREFIX) {
            // Made and linked (or given up) within microseconds; an old one is a killed holder's.
            let old = entry.metadata()?.modified()?.elapsed().is_ok_and(|age| age > LEASE);
            if old {
                out.removed += 1;
                if !dry_run {
                    let _ = std::fs::remove_file(&path);
                }
            }
            continue;
        }
        let (file, liveness) = match inspect(&path, &me) {
            Ok(found) => found,
            Err(e) if e.kind() == ErrorKind::NotFound => continue,
            Err(e) => return Err(e),
        };
        match liveness {
            Liveness::Live => out.live += 1,
            Liveness::Dead => {
                out.removed += 1;
                if !dry_run {
                    remove_own(&file, &path);
                }
            }
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests;
