//! Atomic file writes: every file qsweep writes (report files, cache segments) goes through
//! [`write_atomic`], so a reader sees the old file or the new one, never a partial one.

use anyhow::Context;
use std::io::Write;
use std::path::{Path, PathBuf};

/// Prefix of the temporary files [`write_atomic`] makes (hidden; `qsweep gc` removes stale ones).
pub const TEMP_PREFIX: &str = ".tmp-";

/// The hidden temporary file a write of `path` goes to before it is renamed into place: beside
/// it (one file system, so the rename is atomic), named for it and this process.
pub fn temp_beside(path: &Path) -> PathBuf {
    let dir = path.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new("."));
    let name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    dir.join(format!("{TEMP_PREFIX}{name}.{}", std::process::id()))
}

/// Write `bytes` to `path` through a temporary file in the same directory, fsync and a rename;
/// on failure the temporary file is removed and the old file, if any, is left as it was.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> anyhow::Result<()> {
    let tmp = temp_beside(path);
    let result = (|| -> std::io::Result<()> {
        let mut f = std::fs::File::create(&tmp)?;
        f.write_all(bytes)?;
        f.sync_all()?;
        std::fs::rename(&tmp, path)
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result.with_context(|| format!("cannot write {}", path.display()))?;
    // Make the rename durable too; best effort (not every filesystem allows opening a directory).
    let dir = path.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new("."));
    if let Ok(d) = std::fs::File::open(dir) {
        let _ = d.sync_all();
    }
    Ok(())
}

/// Write `bytes` to `path` like [`write_atomic`], unless the file already holds exactly these
/// bytes: then it is left alone (its mtime stays, so build tools and `git status` see nothing).
/// Returns whether the file was written.
pub fn write_if_changed(path: &Path, bytes: &[u8]) -> anyhow::Result<bool> {
    if same_bytes(path, bytes) {
        return Ok(false);
    }
    write_atomic(path, bytes)?;
    Ok(true)
}

/// Whether `path` is a file holding exactly `bytes` (the length is compared first, so a changed
/// file of another size is not read).
fn same_bytes(path: &Path, bytes: &[u8]) -> bool {
    match std::fs::metadata(path) {
        Ok(m) if m.is_file() && m.len() == bytes.len() as u64 => {
            std::fs::read(path).is_ok_and(|old| old == bytes)
        }
        _ => false,
    }
}

/// Whether two files hold the same bytes, read in chunks (for files too large to hold twice,
/// like the combined `trials.parquet`). A file that cannot be read differs.
pub fn same_files(a: &Path, b: &Path) -> bool {
    use std::io::Read;
    let (Ok(ma), Ok(mb)) = (std::fs::metadata(a), std::fs::metadata(b)) else { return false };
    if !ma.is_file() || !mb.is_file() || ma.len() != mb.len() {
        return false;
    }
    let (Ok(mut fa), Ok(mut fb)) = (std::fs::File::open(a), std::fs::File::open(b)) else { return false };
    let (mut ba, mut bb) = (vec![0u8; 1 << 16], vec![0u8; 1 << 16]);
    loop {
        let Ok(n) = fa.read(&mut ba) else { return false };
        if n == 0 {
            return fb.read(&mut bb[..1]).is_ok_and(|m| m == 0);
        }
        if fb.read_exact(&mut bb[..n]).is_err() || ba[..n] != bb[..n] {
            return false;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn replaces_the_file_and_leaves_no_temp_file() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("a.txt");
        write_atomic(&p, b"one").unwrap();
        write_atomic(&p, b"two").unwrap();
        assert_eq!(std::fs::read(&p).unwrap(), b"two");
        let names: Vec<_> = std::fs::read_dir(dir.path()).unwrap().map(|e| e.unwrap().file_name()).collect();
        assert_eq!(names, ["a.txt"]);
    }

    #[test]
    fn an_unchanged_file_is_not_rewritten() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("a.txt");
        assert!(write_if_changed(&p, b"one").unwrap(), "a new file is written");
        let before = std::fs::metadata(&p).unwrap().modified().unwrap();
        std::thread::sleep(std::time::Duration::from_millis(20));
        assert!(!write_if_changed(&p, b"one").unwrap(), "same bytes: left alone");
        assert_eq!(std::fs::metadata(&p).unwrap().modified().unwrap(), before, "mtime kept");
        assert!(write_if_changed(&p, b"two").unwrap());
        assert!(write_if_changed(&p, b"twos").unwrap(), "another length");
        assert_eq!(std::fs::read(&p).unwrap(), b"twos");
        let q = dir.path().join("b.txt");
        std::fs::write(&q, b"twos").unwrap();
        assert!(same_files(&p, &q));
        std::fs::write(&q, b"twoz").unwrap();
        assert!(!same_files(&p, &q));
        assert!(!same_files(&p, &dir.path().join("missing")));
    }

    #[test]
    fn a_failed_write_names_the_file_and_keeps_nothing() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("missing-dir").join("a.txt");
        let e = write_atomic(&p, b"x").unwrap_err();
        assert!(format!("{e:#}").contains("missing-dir"), "{e:#}");
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
    }
}
