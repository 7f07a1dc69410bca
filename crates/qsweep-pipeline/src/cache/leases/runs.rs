//! A run's mark in the cache: how `qsweep gc` knows which rows a live run has stored.
//!
//! A run's leases go as soon as its trials are stored, so they cannot tell `gc` whose rows are
//! whose. So each run ([`super::Leases::open`]) also puts a mark in `<cache>/_runs/`, a file
//! `run-<16 hex>` made like a lease (locked, naming its holder, its modification time renewed every
//! [`HEARTBEAT`] by a thread of its own) and kept for the run's whole life; every segment the run
//! writes carries the mark's name (`seg-<hash>.run-<16 hex>.parquet`,
//! [`crate::cache::store::writer_of`]). `gc` lists the segments first, then judges the marks
//! ([`live`], as a lease is judged: [`super::judge`]), and leaves every listed segment of a live
//! mark as it is, neither compacted nor pruned. A run that wrote a listed segment began before
//! the listing, so it is judged; a run that begins later writes only segments `gc` never listed.
//!
//! A mark whose holder died (SIGKILL) is debris like a dead lease: [`sweep`] removes it, and its
//! segments are ordinary segments again. The rule needs no lock to hold: where locks do not reach
//! (a `nolock` mount, an object store) the mark's lease decides, as for leases, so a bucket store
//! keeps the same rule by rewriting the mark object every [`HEARTBEAT`] and judging it by its age.
//!
//! In a bucket ([`crate::cache::remote`]) a mark is the object `_runs/run-<16 hex>`, judged by the
//! time the store last wrote it against the store's own clock ([`store_now`]): [`live_runs`] and
//! [`sweep_runs`]; the run's side (writing it every beat) is the bucket's leases'.

use super::lease::{is_stale, Holder, HEARTBEAT, LEASE};
use super::lock::{is_at, try_lock};
use super::{inspect, Liveness, Swept};
use crate::cache::remote::{join, RemoteRef};
use crate::cache::store::Store;
use std::collections::{HashMap, HashSet};
use std::fs::File;
use std::io::{ErrorKind, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;
use std::time::SystemTime;

/// The folder inside the cache that holds the live runs' marks (its leading `_` keeps Parquet
/// dataset readers out, as `_leases`'s does).
pub const RUNS_DIR: &str = "_runs";

/// A mark's file name starts with this.
pub const RUN_PREFIX: &str = "run-";

/// Numbers this process's marks, so two made in one clock tick never share a name.
static MADE: AtomicU64 = AtomicU64::new(0);

/// This process's mark in a cache, removed when dropped (the last one out removes the folder).
#[derive(Debug)]
pub struct RunMark {
    name: String,
    path: PathBuf,
    file: Arc<File>,
}

impl RunMark {
    /// Put this process's mark in `store`: written and locked under a temporary name, then renamed
    /// into place, so it appears whole and already locked. A thread renews its lease until the
    /// mark is dropped.
    pub fn register(store: &Store) -> std::io::Result<Self> {
        let dir = store.dir().join(RUNS_DIR);
        let me = Holder::me();
        let nanos = SystemTime::now().duration_since(SystemTime::UNIX_EPOCH).map_or(0, |d| d.as_nanos());
        let mut h = blake3::Hasher::new();
        h.update(me.to_text().as_bytes());
        h.update(&nanos.to_le_bytes());
        h.update(&MADE.fetch_add(1, Ordering::Relaxed).to_le_bytes());
        let name = format!("{RUN_PREFIX}{}", &h.finalize().to_hex()[..16]);
        let path = dir.join(&name);
        let tmp = dir.join(format!("{}{name}", crate::atomic::TEMP_PREFIX));
        let mut made = None;
        // Twice: another run leaving may remove the empty folder between its making and the rename.
        for _ in 0..2 {
            std::fs::create_dir_all(&dir)?;
            let result = (|| -> std::io::Result<File> {
                let mut file = File::options().read(true).write(true).create_new(true).open(&tmp)?;
                // A fresh file nobody else has open: the lock is ours (or locks are unsupported).
                try_lock(&file)?;
                file.write_all(me.to_text().as_bytes())?;
                std::fs::rename(&tmp, &path)?;
                Ok(file)
            })();
            match result {
                Ok(file) => {
                    made = Some(file);
                    break;
                }
                Err(e) => {
                    let _ = std::fs::remove_file(&tmp);
                    if e.kind() != ErrorKind::NotFound {
                        return Err(e);
                    }
                }
            }
        }
        let file = Arc::new(
            made.ok_or_else(|| std::io::Error::other(format!("{} keeps vanishing", dir.display())))?,
        );
        let beat = Arc::downgrade(&file);
        // Only a weak handle: the thread ends at the first beat after the mark is dropped.
        let _ = std::thread::Builder::new().name("qsweep-run-mark".into()).spawn(move || loop {
            std::thread::sleep(HEARTBEAT);
            let Some(file) = beat.upgrade() else { break };
            let _ = file.set_modified(SystemTime::now());
        });
        Ok(Self { name, path, file })
    }

    /// The mark's name (`run-<16 hex>`), which the run's segments carry.
    pub fn name(&self) -> &str {
        &self.name
    }
}

impl Drop for RunMark {
    fn drop(&mut self) {
        if is_at(&self.file, &self.path) {
            let _ = std::fs::remove_file(&self.path);
        }
        if let Some(dir) = self.path.parent() {
            // Fails harmlessly while other runs' marks are there.
            let _ = std::fs::remove_dir(dir);
        }
    }
}

/// The marks in `store` whose run is alive (or may be: its lease has not run out).
pub fn live(store: &Store) -> std::io::Result<HashSet<String>> {
    if let Some(remote) = store.remote() {
        return live_runs(remote);
    }
    let mut out = HashSet::new();
    visit(store, |name, liveness, _, _| {
        if liveness == Liveness::Live {
            out.insert(name.to_string());
        }
    })?;
    Ok(out)
}

/// Remove the marks of dead runs (and a mark's temporary file a run killed while making it left).
/// With `dry_run`, only count them.
pub fn sweep(store: &Store, dry_run: bool) -> std::io::Result<Swept> {
    if let Some(remote) = store.remote() {
        return sweep_runs(remote, dry_run);
    }
    let mut out = Swept::default();
    visit(store, |_, liveness, file, path| match liveness {
        Liveness::Live => out.live += 1,
        Liveness::Dead => {
            out.removed += 1;
            if !dry_run && file.is_none_or(|f| is_at(f, path)) {
                let _ = std::fs::remove_file(path);
            }
        }
    })?;
    Ok(out)
}

/// Judge each mark in `store`'s runs folder: `f(name, liveness, its handle, its path)`. A
/// temporary file counts as a dead mark once older than a lease, and has no handle.
fn visit(store: &Store, mut f: impl FnMut(&str, Liveness, Option<&File>, &Path)) -> std::io::Result<()> {
    let dir = store.dir().join(RUNS_DIR);
    let entries = match std::fs::read_dir(&dir) {
        Ok(e) => e,
        Err(e) if e.kind() == ErrorKind::NotFound => return Ok(()),
        Err(e) => return Err(e),
    };
    let me = Holder::me();
    for entry in entries {
        let entry = entry?;
        let path = entry.path();
        let name = entry.file_name().to_string_lossy().into_owned();
        if name.starts_with(crate::atomic::TEMP_PREFIX) {
            let old = entry.metadata()?.modified()?.elapsed().is_ok_and(|age| age > super::lease::LEASE);
            if old {
                f(&name, Liveness::Dead, None, &path);
            }
            continue;
        }
        if !name.starts_with(RUN_PREFIX) {
            continue;
        }
        match inspect(&path, &me) {
            Ok((file, liveness)) => f(&name, liveness, Some(&file), &path),
            Err(e) if e.kind() == ErrorKind::NotFound => {}
            Err(e) => return Err(e),
        }
    }
    Ok(())
}

/// An error of the bucket, as the I/O error the marks' functions return.
fn bucket_io(e: anyhow::Error) -> std::io::Error {
    std::io::Error::other(format!("{e:#}"))
}

/// The store's clock now, as it dates an object written now: a probe written, looked at and removed.
pub fn store_now(remote: &RemoteRef) -> std::io::Result<SystemTime> {
    let nanos = SystemTime::now().duration_since(SystemTime::UNIX_EPOCH).map_or(0, |d| d.as_nanos());
    let n = MADE.fetch_add(1, Ordering::Relaxed);
    let name =
        join(RUNS_DIR, &format!("{}clock.{}.{nanos}.{n}", crate::atomic::TEMP_PREFIX, std::process::id()));
    remote.put(&name, b"").map_err(bucket_io)?;
    let made = remote.head(&name).map_err(bucket_io)?;
    let _ = remote.delete(&name);
    made.map(|m| m.modified)
        .ok_or_else(|| std::io::Error::other(format!("{}: the clock probe {name} vanished", remote.url())))
}

/// The marks in the bucket with the time the store last wrote each (temporary probes left out).
fn marks(remote: &RemoteRef) -> std::io::Result<HashMap<String, SystemTime>> {
    Ok(remote
        .list(RUNS_DIR)
        .map_err(bucket_io)?
        .into_iter()
        .filter_map(|o| {
            let name = o.name.rsplit('/').next()?.to_string();
            name.starts_with(RUN_PREFIX).then_some((name, o.modified))
        })
        .collect())
}

/// The marks whose run is alive (written within a lease by the store's clock).
pub fn live_runs(remote: &RemoteRef) -> std::io::Result<HashSet<String>> {
    let marks = marks(remote)?;
    if marks.is_empty() {
        return Ok(HashSet::new());
    }
    let now = store_now(remote)?;
    Ok(marks.into_iter().filter(|(_, at)| !is_stale(*at, now, LEASE)).map(|(n, _)| n).collect())
}

/// Remove the marks of dead runs and probes older than a lease; with `dry_run`, count them.
pub fn sweep_runs(remote: &RemoteRef, dry_run: bool) -> std::io::Result<Swept> {
    let listed = remote.list(RUNS_DIR).map_err(bucket_io)?;
    let mut out = Swept::default();
    if listed.is_empty() {
        return Ok(out);
    }
    let now = store_now(remote)?;
    for o in listed {
        let name = o.name.rsplit('/').next().unwrap_or_default();
        if !(name.starts_with(RUN_PREFIX) || name.starts_with(crate::atomic::TEMP_PREFIX)) {
            continue;
        }
        if is_stale(o.modified, now, LEASE) {
            out.removed += 1;
            if !dry_run {
                remote.delete(&o.name).map_err(bucket_io)?;
            }
        } else if name.starts_with(RUN_PREFIX) {
            out.live += 1;
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::time::Duration;

    #[test]
    fn a_mark_is_live_while_held_and_dead_debris_once_its_holder_is_gone() {
        let dir = tempfile::tempdir().unwrap();
        let store = Store::open(dir.path()).unwrap();
        assert!(live(&store).unwrap().is_empty(), "no folder, no runs");
        let a = RunMark::register(&store).unwrap();
        let b = RunMark::register(&store).unwrap();
        assert_ne!(a.name(), b.name());
        assert!(a.name().starts_with(RUN_PREFIX) && a.name().len() == RUN_PREFIX.len() + 16);
        assert_eq!(live(&store).unwrap(), [a.name().to_string(), b.name().to_string()].into());
        // A mark left by a killed run of this machine: nobody holds its lock.
        let dead = store.dir().join(RUNS_DIR).join("run-00000000deadbeef");
        std::fs::write(&dead, Holder { host: Holder::me().host, pid: u32::MAX - 1 }.to_text()).unwrap();
        // Another machine's run, whose lock does not reach us: its lease decides.
        let remote = store.dir().join(RUNS_DIR).join("run-0000000000remote");
        std::fs::write(&remote, Holder { host: "node-9".into(), pid: 3 }.to_text()).unwrap();
        assert_eq!(live(&store).unwrap().len(), 3, "{:?}", live(&store));
        File::options()
            .write(true)
            .open(&remote)
            .unwrap()
            .set_modified(SystemTime::now() - super::super::lease::LEASE - Duration::from_secs(1))
            .unwrap();
        assert_eq!(sweep(&store, true).unwrap(), Swept { removed: 2, live: 2 });
        assert!(dead.exists() && remote.exists(), "a dry run removes nothing");
        assert_eq!(sweep(&store, false).unwrap(), Swept { removed: 2, live: 2 });
        assert!(!dead.exists() && !remote.exists());
        drop(a);
        assert_eq!(live(&store).unwrap(), [b.name().to_string()].into());
        drop(b);
        assert!(!store.dir().join(RUNS_DIR).exists(), "the last run out removes the folder");
    }
}
