//! The read-through copy of a cache in a bucket: a store's segments listed by its remote, each
//! fetched once into its directory (never stale: a segment never changes once written), and
//! fetched again when `verify` finds a copy damaged.

use super::{Store, Vanished, SEGMENT_PREFIX};
use crate::cache::remote::{connect, copy_dir, object_of, Address, RemoteRef};
use std::path::{Path, PathBuf};

impl Store {
    /// The cache in the bucket `url` (`s3://BUCKET/PREFIX`): connected to and checked
    /// ([`super::remote::connect`]), its read-through copy in [`super::remote::copy_dir`].
    pub fn open_bucket(url: &str) -> anyhow::Result<Self> {
        let address = Address::parse(url)?;
        let remote = connect(&address)?;
        let dir = copy_dir(&address);
        Self::open_remote(remote, &dir)
            .map_err(|e| anyhow::anyhow!("cannot make the copy of {url} in {}: {e}", dir.display()))
    }

    /// The segments `remote` lists, each copied into the directory unless a copy of its length is
    /// there (a segment never changes, so a copy is never stale); fetched in parallel. A segment
    /// listed and gone when fetched is [`Vanished`]: the reader lists again.
    pub(super) fn fetch_listed(&self, remote: &RemoteRef) -> anyhow::Result<Vec<PathBuf>> {
        use rayon::prelude::*;
        let listed: Vec<_> = remote
            .list("")?
            .into_iter()
            .filter(|o| o.name.starts_with(SEGMENT_PREFIX) && o.name.ends_with(".parquet"))
            .collect();
        let mut out: Vec<PathBuf> = listed
            .par_iter()
            .map(|o| {
                let path = self.dir.join(&o.name);
                if std::fs::metadata(&path).is_ok_and(|m| m.len() == o.size) {
                    return Ok(path);
                }
                let bytes = remote.get(&o.name)?.ok_or_else(|| Vanished(path.clone()))?;
                write_copy(&path, &bytes)?;
                Ok(path)
            })
            .collect::<anyhow::Result<_>>()?;
        out.sort();
        Ok(out)
    }

    /// Fetch the segment whose copy is at `path` again from the remote (`verify` does, before it
    /// calls a segment damaged: the damage may be the copy's alone); `false` when the store has
    /// no remote or the segment is gone from it.
    pub fn refetch(&self, path: &Path) -> anyhow::Result<bool> {
        let Some(remote) = &self.remote else { return Ok(false) };
        match remote.get(&object_of(path)?)? {
            Some(bytes) => write_copy(path, &bytes).map(|()| true),
            None => Ok(false),
        }
    }
}

/// Numbers this process's copies being written.
static COPYING: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);

/// Write a fetched segment's copy at `path` through a temporary name of its own (two threads may
/// fetch one segment at once), renamed into place. No fsync: a copy cut short by a crash has
/// another length than the listing's and is fetched again.
fn write_copy(path: &Path, bytes: &[u8]) -> anyhow::Result<()> {
    let n = COPYING.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let dir = path.parent().unwrap_or(Path::new("."));
    let tmp = dir.join(format!("{}copy.{}.{n}", crate::atomic::TEMP_PREFIX, std::process::id()));
    let result = std::fs::write(&tmp, bytes).and_then(|()| std::fs::rename(&tmp, path));
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result.map_err(|e| anyhow::anyhow!("cannot write the copy {}: {e}", path.display()))
}
