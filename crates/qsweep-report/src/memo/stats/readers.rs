//! Who reads a pipeline's trial parts (`<cache>/_derived/<pipeline>.trials/`, `report::trials`)
//! right now, so that nothing removes a part another report is about to splice.
//!
//! Every report that uses the folder holds an advisory `flock` on its lock file, [`LOCK_FILE`],
//! shared ([`Reading::hold`]), from before it decides which parts to reuse until it has spliced
//! them. Removing parts (a full report pruning those it did not use, `qsweep gc` dropping the
//! folder of a pipeline it was not given) happens only with the lock taken exclusively without
//! waiting ([`alone`]): while another report holds it, the parts stay, and the next report that
//! finds itself alone prunes them. Pruning holds the lock for a listing and a few unlinks; a
//! report that starts meanwhile waits for it.
//!
//! The kernel drops a lock when its holder ends, however it ends, so a dead report holds nothing.
//! Linux NFS clients map `flock` to the server's locks (NFS v4, v3 with lockd): reports on several
//! machines see each other there. Where locks are local only (NFS mounted `nolock`), reports on
//! other machines are not seen; where the file system refuses locks ([`Alone::Unknown`]), parts
//! are pruned as if alone. Then a report whose part was removed under it fails, saying so, and a
//! rerun succeeds (the parts are derived from the cache's rows; no trial is lost).

use qsweep_pipeline::cache::leases::lock::{self, Lock};
use std::fs::File;
use std::io::ErrorKind;
use std::path::Path;
use std::time::{Duration, Instant};

/// The lock file inside a parts folder (hidden, and not a part: neither `.parquet` nor `.b3`).
pub const LOCK_FILE: &str = ".lock";

/// How long a report waits for a pruner to let go before it reads without holding the folder
/// (pruning takes milliseconds; this only bounds a lock that a lost file server keeps).
const WAIT: Duration = Duration::from_secs(30);

/// A report's shared hold on a parts folder: while it lives, nobody removes a part of it.
#[derive(Debug)]
pub struct Reading {
    /// The locked lock file; `None` where no lock could be had (see the module documentation).
    _file: Option<File>,
}

impl Reading {
    /// Hold the parts folder `dir` (made if missing) shared, waiting while it is pruned. Holds
    /// nothing where the lock file cannot be made or locked.
    pub fn hold(dir: &Path) -> Self {
        let path = dir.join(LOCK_FILE);
        let start = Instant::now();
        loop {
            let Some(file) = open(dir, &path) else { return Self { _file: None } };
            match lock::try_lock_shared(&file) {
                // The folder may have been removed (by `qsweep gc`) while we waited: a lock on a
                // lock file no longer at its path holds nothing; take the new one.
                Ok(Lock::Taken) if lock::is_at(&file, &path) => return Self { _file: Some(file) },
                Ok(Lock::Taken) => {}
                Ok(Lock::Busy) if start.elapsed() < WAIT => std::thread::sleep(Duration::from_millis(20)),
                Ok(Lock::Busy | Lock::Unsupported) | Err(_) => return Self { _file: None },
            }
        }
    }
}

/// Whether a report or `qsweep gc` may remove parts of a folder now.
#[derive(Debug)]
pub enum Alone {
    /// No other report holds the folder; keep the guard while removing.
    Yes(Guard),
    /// Another report holds it: remove nothing.
    No,
    /// Locks do not work here: no other report can be seen.
    Unknown,
}

/// The exclusive lock of a parts folder, held while parts are removed.
#[derive(Debug)]
pub struct Guard {
    _file: File,
}

/// Try to take the parts folder `dir` exclusively without waiting. A caller that holds it shared
/// drops its [`Reading`] first.
pub fn alone(dir: &Path) -> Alone {
    let path = dir.join(LOCK_FILE);
    let Some(file) = open(dir, &path) else { return Alone::Unknown };
    match lock::try_lock(&file) {
        Ok(Lock::Taken) if lock::is_at(&file, &path) => Alone::Yes(Guard { _file: file }),
        // Removed meanwhile (by another `qsweep gc`): nothing left to prune.
        Ok(Lock::Taken | Lock::Busy) => Alone::No,
        Ok(Lock::Unsupported) | Err(_) => Alone::Unknown,
    }
}

/// Whether a report holds the parts folder `dir` now, making nothing (for `qsweep gc --dry-run`;
/// a report makes the lock file before it holds it, so none means no holder).
pub fn in_use(dir: &Path) -> bool {
    let path = dir.join(LOCK_FILE);
    let file = File::options().read(true).write(true).open(&path).or_else(|_| File::open(&path));
    file.is_ok_and(|f| matches!(lock::try_lock(&f), Ok(Lock::Busy)))
}

/// The lock file at `path` in `dir`, opened (made if missing) for reading and, where allowed,
/// writing (NFS grants an exclusive lock only to a file open for writing).
fn open(dir: &Path, path: &Path) -> Option<File> {
    let rw = || File::options().read(true).write(true).create(true).truncate(false).open(path);
    match rw() {
        Ok(f) => Some(f),
        Err(e) if e.kind() == ErrorKind::NotFound => {
            std::fs::create_dir_all(dir).ok()?;
            rw().ok()
        }
        Err(_) => File::open(path).ok(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn readers_share_the_folder_and_keep_pruners_out_until_they_let_go() {
        let cache = tempfile::tempdir().unwrap();
        let dir = cache.path().join("p.trials");
        let a = Reading::hold(&dir);
        assert!(a._file.is_some() && dir.join(LOCK_FILE).is_file(), "the folder and its lock are made");
        let b = Reading::hold(&dir);
        assert!(b._file.is_some(), "two readers at once");
        assert!(matches!(alone(&dir), Alone::No) && in_use(&dir));
        drop(a);
        assert!(matches!(alone(&dir), Alone::No), "one reader left");
        drop(b);
        let Alone::Yes(guard) = alone(&dir) else { panic!("no reader left: alone") };
        assert!(matches!(alone(&dir), Alone::No), "one pruner at a time");
        drop(guard);
        assert!(!in_use(&dir));
        assert!(matches!(alone(&dir), Alone::Yes(_)));
        assert!(!in_use(&cache.path().join("none.trials")) && !cache.path().join("none.trials").exists());
    }

    #[test]
    fn a_reader_waits_for_a_pruner_and_follows_a_removed_folder() {
        let cache = tempfile::tempdir().unwrap();
        let dir = cache.path().join("p.trials");
        let Alone::Yes(guard) = alone(&dir) else { panic!("alone on a new folder") };
        let d = dir.clone();
        let reader = std::thread::spawn(move || {
            let r = Reading::hold(&d);
            (r, Instant::now())
        });
        std::thread::sleep(Duration::from_millis(150));
        // What `qsweep gc` does with a pipeline's folder it may drop: removed under the lock.
        std::fs::remove_dir_all(&dir).unwrap();
        let released = Instant::now();
        drop(guard);
        let (r, held_at) = reader.join().unwrap();
        assert!(held_at >= released, "the reader waited for the pruner");
        assert!(
            r._file.as_ref().is_some_and(|f| lock::is_at(f, &dir.join(LOCK_FILE))),
            "it holds the new lock file"
        );
        assert!(matches!(alone(&dir), Alone::No));
    }
}
