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
//!
//! A cache in a bucket ([`crate::cache::remote`]) has neither links nor locks: there a lease is an
//! object `_leases/<key>` made by a create-only PUT and naming the holder's run mark, and it is
//! live while that mark is (`bucket.rs`): the rules above hold with the lease deciding alone.

mod batch;
mod bucket;
mod files;
pub mod lease;
pub mod lock;
pub mod runs;
mod seen;

use self::lease::{is_stale, process_alive, Holder, LEASE};
use self::lock::{is_at, try_lock, Lock};
use super::store::{KeySet, Store};
use super::Key;
use std::fs::File;
use std::io::{ErrorKind, Read};
use std::path::Path;
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

/// This run's leases in one cache: files in a cache directory (`files.rs`), objects in a bucket
/// (`bucket.rs`).
#[derive(Debug)]
pub struct Leases(Kind);

#[derive(Debug)]
enum Kind {
    Files(files::FileLeases),
    Bucket(bucket::BucketLeases),
}

/// `$call` on the leases of either kind.
macro_rules! either {
    ($self:ident, $l:ident => $call:expr) => {
        match &$self.0 {
            Kind::Files($l) => $call,
            Kind::Bucket($l) => $call,
        }
    };
}

impl Leases {
    /// The leases of a run on `store` (creating the leases folder), and the run's mark.
    pub fn open(store: &Store) -> std::io::Result<Arc<Self>> {
        let kind = match store.remote() {
            Some(_) => Kind::Bucket(bucket::BucketLeases::open(store)?),
            None => Kind::Files(files::FileLeases::open(store)?),
        };
        Ok(Arc::new(Self(kind)))
    }

    /// Judge whether a key is stored against `scan` (the scan this execution planned from) and
    /// whatever is stored after it; with `force`, only against what is stored after it.
    pub fn reset_view(&self, scan: &KeySet, force: bool) {
        either!(self, l => l.reset_view(scan, force))
    }

    /// The run's mark: the segments it writes carry it ([`Store::writing_as`]), and `qsweep gc`
    /// leaves them alone while the run lives.
    pub fn run_mark(&self) -> &str {
        either!(self, l => l.run_mark())
    }

    /// Lease `key`: [`Take::Taken`] when this run now holds it, [`Take::Busy`] when a live holder
    /// does, [`Take::Stored`] when it turns out to be stored already. A dead holder's lease is
    /// taken over. A batch of one ([`Self::try_take_batch`]).
    pub fn try_take(&self, key: Key) -> std::io::Result<Take> {
        self.try_take_batch(&[key]).pop().unwrap_or(Ok(Take::Busy))
    }

    /// Lease each of `keys` (distinct), answering for each as [`Self::try_take`] does; what is
    /// stored is looked at once for the batch. An error on one key (its lease could not be made)
    /// leaves the others leased.
    pub fn try_take_batch(&self, keys: &[Key]) -> Vec<std::io::Result<Take>> {
        either!(self, l => l.try_take_batch(keys))
    }

    /// Release the leases of `keys` (their trials are stored).
    pub fn release(&self, keys: &[Key]) {
        either!(self, l => l.release(keys))
    }

    /// Release every lease this run holds (the run ends, or was interrupted).
    pub fn release_all(&self) {
        either!(self, l => l.release_all())
    }

    /// Renew the leases held (call every [`lease::HEARTBEAT`]).
    pub fn heartbeat(&self) {
        either!(self, l => l.heartbeat())
    }

    /// Whether another run holds leases in this cache now (live or not): someone may be waiting
    /// for this run's trials.
    pub fn others_present(&self) -> bool {
        either!(self, l => l.others_present())
    }

    /// How many leases this run holds.
    pub fn held(&self) -> usize {
        either!(self, l => l.held())
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
    if let Some(remote) = store.remote() {
        return bucket::running_elsewhere(remote, keys);
    }
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
    if let Some(remote) = store.remote() {
        return bucket::sweep(remote, dry_run);
    }
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
