//! Leases and run marks in a bucket, where there are neither hard links nor locks: small objects
//! made by create-only PUTs, judged by their age on the store's own clock.
//!
//! - A run's mark is the object `_runs/run-<16 hex>` (its host and pid), rewritten every
//!   [`HEARTBEAT`] by a thread of its own for the run's whole life, and removed when the run ends.
//! - A lease is the object `_leases/<key>`, made only if absent (`If-None-Match: *`), naming the
//!   holder's mark. One object per key (a create-only PUT cannot make several names at once); the
//!   lease is live exactly while its mark is. Leases themselves are never rewritten: a run's one
//!   heartbeat keeps all of them.
//! - A mark is live while the store's clock says it was last written at most [`LEASE`] ago. The
//!   store's clock, not this machine's: a run reads the time the store gave its own mark at each
//!   beat and adds the time elapsed since by its own monotonic clock; a command without a mark
//!   (`gc`, `status`) writes a tiny probe object, reads the time the store gave it, and removes
//!   it. So a run killed by SIGKILL frees its leases at most [`LEASE`] (30 s) after its last beat,
//!   whatever the machines' clocks say.
//!
//! Taking over a dead holder's lease is a removal and a new create-only PUT; two runs taking over
//! one lease at once may then both compute the trial (an object store cannot remove only the
//! object it judged), which costs work, never a result: its rows are identical and one is read.

use super::lease::{is_stale, Holder, HEARTBEAT, LEASE};
use super::runs::{live_runs, RUNS_DIR, RUN_PREFIX};
use super::{lock_ok, Swept, Take, LEASES_DIR};
use crate::cache::remote::{join, RemoteRef};
use crate::cache::rows::read_keys;
use crate::cache::store::{KeySet, Store};
use crate::cache::Key;
use std::collections::{HashMap, HashSet};
use std::path::PathBuf;
use std::sync::atomic::{AtomicU64, AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant, SystemTime};

/// How long an answer of [`BucketLeases::others_present`] is reused: it costs a listing, and the
/// collector asks it at every turn of a run's tail.
const OTHERS_EVERY: Duration = Duration::from_secs(1);

/// Numbers this process's marks and probes.
static MADE: AtomicU64 = AtomicU64::new(0);

pub(super) fn io(e: anyhow::Error) -> std::io::Error {
    std::io::Error::other(format!("{e:#}"))
}

fn lease_name(key: &Key) -> String {
    join(LEASES_DIR, &key.hex())
}

fn mark_name(run: &str) -> String {
    join(RUNS_DIR, run)
}

/// A lease's body: the holder's mark, then its host and pid (for people reading the bucket).
fn lease_body(run: &str, me: &Holder) -> String {
    format!("{run} {}", me.to_text())
}

/// The mark a lease body names.
fn holder_of(body: &[u8]) -> Option<String> {
    let text = std::str::from_utf8(body).ok()?;
    let run = text.split_whitespace().next()?;
    run.starts_with(RUN_PREFIX).then(|| run.to_string())
}

/// Remove the leases whose mark is dead (or that name none); with `dry_run`, count them.
pub fn sweep(remote: &RemoteRef, dry_run: bool) -> std::io::Result<Swept> {
    let listed = remote.list(LEASES_DIR).map_err(io)?;
    let mut out = Swept::default();
    if listed.is_empty() {
        return Ok(out);
    }
    let live = live_runs(remote)?;
    for o in listed {
        let Some(body) = remote.get(&o.name).map_err(io)? else { continue };
        if holder_of(&body).is_some_and(|run| live.contains(&run)) {
            out.live += 1;
        } else {
            out.removed += 1;
            if !dry_run {
                remote.delete(&o.name).map_err(io)?;
            }
        }
    }
    Ok(out)
}

/// Of `keys`, how many a live run holds a lease on (`status`'s `running_elsewhere`).
pub fn running_elsewhere<'a>(remote: &RemoteRef, keys: impl IntoIterator<Item = &'a Key>) -> usize {
    let Ok(listed) = remote.list(LEASES_DIR) else { return 0 };
    let leased: HashSet<String> =
        listed.into_iter().filter_map(|o| o.name.rsplit('/').next().map(str::to_string)).collect();
    let wanted: Vec<&Key> = keys.into_iter().filter(|k| leased.contains(&k.hex())).collect();
    if wanted.is_empty() {
        return 0;
    }
    let Ok(live) = live_runs(remote) else { return 0 };
    wanted
        .into_iter()
        .filter(|k| {
            remote
                .get(&lease_name(k))
                .ok()
                .flatten()
                .and_then(|b| holder_of(&b))
                .is_some_and(|r| live.contains(&r))
        })
        .count()
}

/// This run's mark in the bucket, rewritten by a thread every [`HEARTBEAT`] and removed when
/// dropped; it knows the store's clock from the time the store gave it at the last beat.
#[derive(Debug)]
struct Mark {
    name: String,
    remote: RemoteRef,
    /// The store's time of the last beat, and this machine's instant just before that beat.
    beat: Arc<Mutex<(SystemTime, Instant)>>,
}

impl Mark {
    fn register(remote: &RemoteRef, me: &Holder) -> std::io::Result<Self> {
        let nanos = SystemTime::now().duration_since(SystemTime::UNIX_EPOCH).map_or(0, |d| d.as_nanos());
        let mut h = blake3::Hasher::new();
        h.update(me.to_text().as_bytes());
        h.update(&nanos.to_le_bytes());
        h.update(&MADE.fetch_add(1, Ordering::Relaxed).to_le_bytes());
        let name = format!("{RUN_PREFIX}{}", &h.finalize().to_hex()[..16]);
        let at = beat(remote, &name, me)?;
        let beat_at = Arc::new(Mutex::new(at));
        let (weak, remote2, me2, name2) =
            (Arc::downgrade(&beat_at), Arc::clone(remote), me.clone(), name.clone());
        // Only a weak handle: the thread ends at the first beat after the mark is dropped.
        let _ = std::thread::Builder::new().name("qsweep-run-mark".into()).spawn(move || loop {
            std::thread::sleep(HEARTBEAT);
            let Some(slot) = weak.upgrade() else { break };
            if let Ok(at) = beat(&remote2, &name2, &me2) {
                *lock_ok(&slot) = at;
            }
        });
        Ok(Self { name, remote: Arc::clone(remote), beat: beat_at })
    }

    /// The store's clock now: its time of the last beat plus what elapsed here since (never
    /// ahead of the store's, so a lease is never judged dead early).
    fn now(&self) -> SystemTime {
        let (at, when) = *lock_ok(&self.beat);
        at + when.elapsed()
    }
}

/// Write the mark and read back the time the store gave it.
fn beat(remote: &RemoteRef, name: &str, me: &Holder) -> std::io::Result<(SystemTime, Instant)> {
    let object = mark_name(name);
    let when = Instant::now();
    remote.put(&object, me.to_text().as_bytes()).map_err(io)?;
    let at = remote.head(&object).map_err(io)?.map_or_else(SystemTime::now, |m| m.modified);
    Ok((at, when))
}

impl Drop for Mark {
    fn drop(&mut self) {
        let _ = self.remote.delete(&mark_name(&self.name));
    }
}

/// What a run knows is stored in the bucket: the segments it has read the keys of.
#[derive(Debug, Default)]
struct Seen {
    segments: HashSet<PathBuf>,
    keys: HashSet<Key>,
}

/// This run's leases in a bucket.
#[derive(Debug)]
pub struct BucketLeases {
    store: Store,
    remote: RemoteRef,
    me: Holder,
    mark: Mark,
    held: Mutex<HashSet<Key>>,
    /// Keys whose leases are being made: [`Self::others_present`] counts them as this run's.
    taking: AtomicUsize,
    seen: Mutex<Seen>,
    others: Mutex<Option<(Instant, bool)>>,
}

impl BucketLeases {
    /// The leases of a run on the bucket cache `store`, and the run's mark.
    pub fn open(store: &Store) -> std::io::Result<Self> {
        let remote = Arc::clone(store.remote().ok_or_else(|| std::io::Error::other("not a bucket cache"))?);
        let me = Holder::me();
        let mark = Mark::register(&remote, &me)?;
        Ok(Self {
            store: store.clone(),
            remote,
            me,
            mark,
            held: Mutex::new(HashSet::new()),
            taking: AtomicUsize::new(0),
            seen: Mutex::new(Seen::default()),
            others: Mutex::new(None),
        })
    }

    pub fn reset_view(&self, scan: &KeySet, force: bool) {
        let mut seen = lock_ok(&self.seen);
        seen.segments = scan.segments.iter().map(|(p, _)| p.clone()).collect();
        seen.segments.extend(scan.damaged.iter().map(|d| d.path.clone()));
        seen.keys = if force { HashSet::new() } else { scan.keys.clone() };
    }

    pub fn run_mark(&self) -> &str {
        &self.mark.name
    }

    pub fn try_take_batch(&self, keys: &[Key]) -> Vec<std::io::Result<Take>> {
        self.taking.fetch_add(keys.len(), Ordering::SeqCst);
        let body = lease_body(&self.mark.name, &self.me);
        // Each mark judged once per batch: a dead run usually held many of these keys.
        let mut judged: HashMap<String, bool> = HashMap::new();
        // Every lease of the batch created at once; only those found taken are looked at.
        let objects: Vec<(String, Vec<u8>)> =
            keys.iter().map(|k| (lease_name(k), body.clone().into_bytes())).collect();
        let made: Vec<std::io::Result<bool>> = self
            .remote
            .create_each(&objects)
            .into_iter()
            .zip(keys)
            .map(|(made, k)| match made {
                Ok(true) => Ok(true),
                Ok(false) => self.take_over(k, &body, &mut judged),
                Err(e) => Err(io(e)),
            })
            .collect();
        let result = if made.iter().any(|m| matches!(m, Ok(true))) {
            // Whoever stored a key removed its lease after storing it: a key stored before this
            // lease was made shows in the segments listed now.
            let stored = self.refresh();
            let mut held = lock_ok(&self.held);
            keys.iter()
                .zip(made)
                .map(|(k, m)| match m {
                    Ok(true) if stored.contains(k) => {
                        let _ = self.remote.delete(&lease_name(k));
                        Ok(Take::Stored)
                    }
                    Ok(true) => {
                        held.insert(*k);
                        Ok(Take::Taken)
                    }
                    Ok(false) => Ok(Take::Busy),
                    Err(e) => Err(e),
                })
                .collect()
        } else {
            made.into_iter().map(|m| m.map(|_| Take::Busy)).collect()
        };
        self.taking.fetch_sub(keys.len(), Ordering::SeqCst);
        result
    }

    /// The lease of `key`, found taken: `true` when it is now this run's, `false` when a live run
    /// holds it. A lease whose mark is dead (or that names none) is removed and made again.
    fn take_over(&self, key: &Key, body: &str, judged: &mut HashMap<String, bool>) -> std::io::Result<bool> {
        let name = lease_name(key);
        for attempt in 0..3 {
            if attempt > 0 && self.remote.create(&name, body.as_bytes()).map_err(io)? {
                return Ok(true);
            }
            let Some(found) = self.remote.get(&name).map_err(io)? else { continue };
            let live = match holder_of(&found) {
                Some(run) if run == self.mark.name => return Ok(false),
                Some(run) => match judged.get(&run) {
                    Some(&live) => live,
                    None => {
                        let live = self.mark_live(&run)?;
                        judged.insert(run, live);
                        live
                    }
                },
                None => false,
            };
            if live {
                return Ok(false);
            }
            self.remote.delete(&name).map_err(io)?;
        }
        Ok(false)
    }

    /// Whether the run of mark `run` is alive: its mark was written within a lease.
    fn mark_live(&self, run: &str) -> std::io::Result<bool> {
        let Some(m) = self.remote.head(&mark_name(run)).map_err(io)? else { return Ok(false) };
        Ok(!is_stale(m.modified, self.mark.now(), LEASE))
    }

    /// Read the keys of the segments stored since the last look; every key known stored.
    fn refresh(&self) -> HashSet<Key> {
        let mut seen = lock_ok(&self.seen);
        if let Ok(paths) = self.store.segments() {
            for path in paths {
                if seen.segments.contains(&path) {
                    continue;
                }
                if let Ok(keys) = read_keys(&path) {
                    seen.keys.extend(keys);
                }
                seen.segments.insert(path);
            }
        }
        seen.keys.clone()
    }

    /// Release the leases of `keys`: one multi-object delete for them all.
    pub fn release(&self, keys: &[Key]) {
        let mut held = lock_ok(&self.held);
        let names: Vec<String> = keys.iter().filter(|k| held.remove(k)).map(lease_name).collect();
        if !names.is_empty() {
            let _ = self.remote.delete_each(&names);
        }
    }

    pub fn release_all(&self) {
        let mut held = lock_ok(&self.held);
        let names: Vec<String> = held.drain().map(|k| lease_name(&k)).collect();
        if !names.is_empty() {
            let _ = self.remote.delete_each(&names);
        }
    }

    /// Nothing to do per lease: the run's mark, rewritten by its own thread, keeps them all.
    pub fn heartbeat(&self) {}

    pub fn others_present(&self) -> bool {
        let mut cached = lock_ok(&self.others);
        if let Some((at, answer)) = *cached {
            if at.elapsed() < OTHERS_EVERY {
                return answer;
            }
        }
        let held = lock_ok(&self.held);
        let answer = self
            .remote
            .list(LEASES_DIR)
            .is_ok_and(|listed| listed.len() > held.len() + self.taking.load(Ordering::SeqCst));
        *cached = Some((Instant::now(), answer));
        answer
    }

    pub fn held(&self) -> usize {
        lock_ok(&self.held).len()
    }
}

impl Drop for BucketLeases {
    fn drop(&mut self) {
        self.release_all();
        // A run killed between storing a segment and releasing its leases leaves leases that no
        // later run needs: the last to see them dead removes them.
        let _ = sweep(&self.remote, false);
    }
}

#[cfg(test)]
#[path = "bucket_tests.rs"]
mod tests;
