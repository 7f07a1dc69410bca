//! One lease file for a batch of keys: made once (written and locked under a temporary name) and
//! hard-linked under each key's name in the leases folder.
//!
//! Every link is the same file, so each `_leases/<key>` looks exactly as a lease made alone does
//! (the holder's line, the holder's lock, the modification time the heartbeat renews): other
//! runs, and older builds, judge it the same way, and a link fails if the key is leased, as a
//! lone lease's does. What a batch saves is the making of a file per key (create, lock, write,
//! remove the temporary name): a key costs one `link`, and its release one `unlink`. The file
//! stays open, and so locked, until the last of its keys is released.

use super::lease::Holder;
use super::lock::try_lock;
use std::fs::File;
use std::io::{ErrorKind, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;
use std::time::SystemTime;

/// Numbers this process's batch files, so two workers making one in the same clock tick never
/// pick the same temporary name.
static MADE: AtomicU64 = AtomicU64::new(0);

/// The lease file of the batch being leased, made when its first key is linked.
pub struct Batch<'a> {
    dir: &'a Path,
    me: &'a Holder,
    /// The file and its temporary name, once made.
    made: Option<(PathBuf, Arc<File>)>,
    /// The file system refused a hard link: each key gets a file of its own, made in place.
    in_place: bool,
}

impl<'a> Batch<'a> {
    /// A batch of leases in `dir` held by `me`; nothing is made yet.
    pub fn new(dir: &'a Path, me: &'a Holder) -> Self {
        Self { dir, me, made: None, in_place: false }
    }

    /// Put the batch's lease at `path` and return its file; fails with `AlreadyExists` if a lease
    /// is there, `NotFound` if the folder (or the batch's file with it) is gone.
    pub fn link(&mut self, path: &Path) -> std::io::Result<Arc<File>> {
        if self.in_place {
            return self.in_place(path);
        }
        if self.made.is_none() {
            self.made = Some(self.make()?);
        }
        let (tmp, file) = self.made.as_ref().expect("made above");
        match std::fs::hard_link(tmp, path) {
            Ok(()) => Ok(Arc::clone(file)),
            Err(e) if e.kind() == ErrorKind::Unsupported || e.raw_os_error() == Some(libc::EPERM) => {
                self.in_place = true;
                self.forget();
                self.in_place(path)
            }
            Err(e) => Err(e),
        }
    }

    /// Drop the batch's file (its folder was removed, or links are refused): the keys linked so
    /// far keep it open; the next link makes another.
    pub fn forget(&mut self) {
        if let Some((tmp, _)) = self.made.take() {
            let _ = std::fs::remove_file(tmp);
        }
    }

    /// The batch's file under a temporary name nobody else uses, locked, naming its holder.
    fn make(&self) -> std::io::Result<(PathBuf, Arc<File>)> {
        let nanos = SystemTime::now().duration_since(SystemTime::UNIX_EPOCH).map_or(0, |d| d.as_nanos());
        let n = MADE.fetch_add(1, Ordering::Relaxed);
        let tmp = self.dir.join(format!("{}batch.{}.{nanos}.{n}", crate::atomic::TEMP_PREFIX, self.me.pid));
        let made = (|| {
            let mut file = File::options().read(true).write(true).create_new(true).open(&tmp)?;
            // A fresh file nobody else has open: the lock is ours (or locks are unsupported).
            try_lock(&file)?;
            file.write_all(self.me.to_text().as_bytes())?;
            Ok(file)
        })();
        match made {
            Ok(file) => Ok((tmp, Arc::new(file))),
            Err(e) => {
                let _ = std::fs::remove_file(&tmp);
                Err(e)
            }
        }
    }

    /// No hard links on this file system: create the key's own file in place (the holder's line
    /// follows a moment later; an empty lease counts as live within its lease).
    fn in_place(&self, path: &Path) -> std::io::Result<Arc<File>> {
        let mut file = File::options().read(true).write(true).create_new(true).open(path)?;
        try_lock(&file)?;
        file.write_all(self.me.to_text().as_bytes())?;
        Ok(Arc::new(file))
    }
}

impl Drop for Batch<'_> {
    /// The temporary name goes once the batch is linked; the links keep the file.
    fn drop(&mut self) {
        self.forget();
    }
}
