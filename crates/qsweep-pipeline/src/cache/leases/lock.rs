//! The first layer of a lease's liveness: an advisory `flock` the holder keeps on its lease file.
//! The kernel drops it when the holder dies however it dies (SIGKILL included), so on one machine
//! a dead holder is seen at once. Linux NFS clients map `flock` to the server's byte-range locks
//! (NFS v4, and v3 with lockd), so there it covers several machines too; on a `nolock` mount the
//! lock is local only and the lease ([`super::lease`]) decides for other machines.

use std::fs::File;
use std::path::Path;

/// What trying to lock a lease file found.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Lock {
    /// This file handle now holds the lock: no live holder on a machine that shares our locks.
    Taken,
    /// Another open file holds it: a live holder.
    Busy,
    /// The file system refuses locks: only the lease can tell.
    Unsupported,
}

/// Try to lock `file` exclusively without waiting.
pub fn try_lock(file: &File) -> std::io::Result<Lock> {
    flock_nb(file, true)
}

/// Try to lock `file` shared (any number of shared holders, no exclusive one) without waiting;
/// the report's trial parts are held this way while a report reads them.
pub fn try_lock_shared(file: &File) -> std::io::Result<Lock> {
    flock_nb(file, false)
}

fn flock_nb(file: &File, exclusive: bool) -> std::io::Result<Lock> {
    #[cfg(unix)]
    {
        use std::os::unix::io::AsRawFd;
        let op = if exclusive { libc::LOCK_EX } else { libc::LOCK_SH };
        loop {
            // SAFETY: flock only acts on the descriptor, which `file` keeps open.
            if unsafe { libc::flock(file.as_raw_fd(), op | libc::LOCK_NB) } == 0 {
                return Ok(Lock::Taken);
            }
            let e = std::io::Error::last_os_error();
            return match e.raw_os_error() {
                Some(libc::EINTR) => continue,
                Some(libc::EWOULDBLOCK) => Ok(Lock::Busy),
                Some(libc::ENOLCK | libc::EOPNOTSUPP | libc::ENOSYS) => Ok(Lock::Unsupported),
                _ => Err(e),
            };
        }
    }
    #[cfg(not(unix))]
    {
        let _ = (file, exclusive);
        Ok(Lock::Unsupported)
    }
}

/// Whether `file` is still the file at `path` (not unlinked or replaced since it was opened):
/// a lease released or taken over meanwhile must not be judged, or removed, by its old handle.
pub fn is_at(file: &File, path: &Path) -> bool {
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        match (file.metadata(), std::fs::metadata(path)) {
            (Ok(a), Ok(b)) => a.dev() == b.dev() && a.ino() == b.ino(),
            _ => false,
        }
    }
    #[cfg(not(unix))]
    {
        let _ = file;
        path.exists()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_second_handle_sees_the_lock_until_the_first_is_closed() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("c");
        std::fs::write(&path, "x").unwrap();
        let a = File::open(&path).unwrap();
        assert_eq!(try_lock(&a).unwrap(), Lock::Taken);
        let b = File::open(&path).unwrap();
        assert_eq!(try_lock(&b).unwrap(), Lock::Busy);
        drop(a);
        assert_eq!(try_lock(&b).unwrap(), Lock::Taken);
        assert!(is_at(&b, &path));
        std::fs::remove_file(&path).unwrap();
        assert!(!is_at(&b, &path));
        std::fs::write(&path, "y").unwrap();
        assert!(!is_at(&b, &path), "a new file at the path is another lease");
    }
}
