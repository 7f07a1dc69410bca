//! A directory serving as a [`Remote`]: each object a file, a folder per `/`. It holds the rules
//! of a bucket cache to their tests without a server (its create-only write is a hard link, which
//! fails when the name is taken, so it is as atomic as a bucket's conditional PUT).

use super::{Listed, Remote};
use std::io::ErrorKind;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

/// A remote whose objects are the files under a directory.
#[derive(Debug)]
pub struct DirRemote {
    root: PathBuf,
    url: String,
}

/// Numbers this process's temporary files.
static MADE: AtomicU64 = AtomicU64::new(0);

impl DirRemote {
    /// The remote whose objects live under `root` (created if needed).
    pub fn new(root: &Path) -> std::io::Result<Self> {
        std::fs::create_dir_all(root)?;
        Ok(Self { root: root.to_path_buf(), url: format!("dir://{}", root.display()) })
    }

    fn path(&self, name: &str) -> PathBuf {
        self.root.join(name)
    }

    /// `body` under a temporary name beside `name`'s file.
    fn temp(&self, name: &str, body: &[u8]) -> std::io::Result<PathBuf> {
        let path = self.path(name);
        let dir = path.parent().unwrap_or(&self.root).to_path_buf();
        std::fs::create_dir_all(&dir)?;
        let n = MADE.fetch_add(1, Ordering::Relaxed);
        let tmp = dir.join(format!("{}remote.{}.{n}", crate::atomic::TEMP_PREFIX, std::process::id()));
        std::fs::write(&tmp, body)?;
        Ok(tmp)
    }
}

fn listed(name: String, meta: &std::fs::Metadata) -> std::io::Result<Listed> {
    Ok(Listed { name, size: meta.len(), modified: meta.modified()? })
}

impl Remote for DirRemote {
    fn url(&self) -> &str {
        &self.url
    }

    fn list(&self, dir: &str) -> anyhow::Result<Vec<Listed>> {
        let entries = match std::fs::read_dir(self.path(dir)) {
            Ok(e) => e,
            Err(e) if e.kind() == ErrorKind::NotFound => return Ok(Vec::new()),
            Err(e) => return Err(e.into()),
        };
        let mut out = Vec::new();
        for entry in entries {
            let entry = entry?;
            let name = entry.file_name().to_string_lossy().into_owned();
            let meta = entry.metadata()?;
            if meta.is_file() && !name.starts_with(crate::atomic::TEMP_PREFIX) {
                out.push(listed(super::join(dir, &name), &meta)?);
            }
        }
        out.sort_by(|a, b| a.name.cmp(&b.name));
        Ok(out)
    }

    fn get(&self, name: &str) -> anyhow::Result<Option<Vec<u8>>> {
        match std::fs::read(self.path(name)) {
            Ok(b) => Ok(Some(b)),
            Err(e) if e.kind() == ErrorKind::NotFound => Ok(None),
            Err(e) => Err(e.into()),
        }
    }

    fn head(&self, name: &str) -> anyhow::Result<Option<Listed>> {
        match std::fs::metadata(self.path(name)) {
            Ok(m) => Ok(Some(listed(name.to_string(), &m)?)),
            Err(e) if e.kind() == ErrorKind::NotFound => Ok(None),
            Err(e) => Err(e.into()),
        }
    }

    fn create(&self, name: &str, body: &[u8]) -> anyhow::Result<bool> {
        let tmp = self.temp(name, body)?;
        let made = std::fs::hard_link(&tmp, self.path(name));
        let _ = std::fs::remove_file(&tmp);
        match made {
            Ok(()) => Ok(true),
            Err(e) if e.kind() == ErrorKind::AlreadyExists => Ok(false),
            Err(e) => Err(e.into()),
        }
    }

    fn put(&self, name: &str, body: &[u8]) -> anyhow::Result<()> {
        let tmp = self.temp(name, body)?;
        std::fs::rename(&tmp, self.path(name)).map_err(|e| {
            let _ = std::fs::remove_file(&tmp);
            e.into()
        })
    }

    fn delete(&self, name: &str) -> anyhow::Result<()> {
        match std::fs::remove_file(self.path(name)) {
            Err(e) if e.kind() != ErrorKind::NotFound => Err(e.into()),
            _ => Ok(()),
        }
    }
}
