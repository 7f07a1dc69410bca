//! The second layer of a lease's liveness: who holds it, written in the lease file, and a lease
//! renewed by a heartbeat on the file's modification time. It covers what the first layer
//! ([`super::lock`]) cannot see: a holder on another machine whose lock the file system does not
//! share (NFS mounted `nolock`), or whose lock the server keeps after the machine was lost.

use std::time::{Duration, SystemTime};

/// A lease whose file was not refreshed for this long has lost its holder (died, machine lost).
pub const LEASE: Duration = Duration::from_secs(30);

/// How often a live holder refreshes its leases; a third of [`LEASE`], so two missed beats
/// (a long pause, a slow file server) do not yet lose a live holder's leases.
pub const HEARTBEAT: Duration = Duration::from_secs(10);

/// The process holding a lease: its machine and process id.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Holder {
    /// The machine's host name.
    pub host: String,
    /// The process id on that machine.
    pub pid: u32,
}

impl Holder {
    /// This process.
    pub fn me() -> Self {
        Self { host: hostname(), pid: std::process::id() }
    }

    /// The lease file's text: `host pid`, one line.
    pub fn to_text(&self) -> String {
        format!("{} {}\n", self.host, self.pid)
    }

    /// Parse a lease file's text; `None` for an empty or garbled file (a holder that died while
    /// writing it, or a file of some other program).
    pub fn parse(text: &str) -> Option<Self> {
        let mut words = text.split_whitespace();
        let host = words.next()?.to_string();
        let pid = words.next()?.parse().ok()?;
        words.next().is_none().then_some(Self { host, pid })
    }
}

/// This machine's host name (`unknown` when it cannot be read: then every lease looks remote
/// and only the lease decides, which is slower but still safe).
pub fn hostname() -> String {
    #[cfg(unix)]
    {
        let mut buf = [0u8; 256];
        // SAFETY: gethostname writes at most `len` bytes into the buffer it is given.
        let rc = unsafe { libc::gethostname(buf.as_mut_ptr().cast(), buf.len()) };
        if rc == 0 {
            let end = buf.iter().position(|&b| b == 0).unwrap_or(buf.len());
            let name = String::from_utf8_lossy(&buf[..end]).trim().to_string();
            if !name.is_empty() && !name.contains(char::is_whitespace) {
                return name;
            }
        }
    }
    "unknown".into()
}

/// Whether a lease last refreshed at `modified` has outlived its lease at `now`. A time in the
/// future (clocks of two machines apart) is fresh: the lease then errs towards waiting.
pub fn is_stale(modified: SystemTime, now: SystemTime, lease: Duration) -> bool {
    now.duration_since(modified).is_ok_and(|age| age > lease)
}

/// Whether process `pid` of this machine is alive (for a file system where locks do not work;
/// with working locks the lock itself answers).
pub fn process_alive(pid: u32) -> bool {
    #[cfg(unix)]
    {
        let Ok(pid) = libc::pid_t::try_from(pid) else { return false };
        // SAFETY: signal 0 only checks that the process exists and may be signalled.
        let rc = unsafe { libc::kill(pid, 0) };
        rc == 0 || std::io::Error::last_os_error().raw_os_error() == Some(libc::EPERM)
    }
    #[cfg(not(unix))]
    {
        let _ = pid;
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_holder_round_trips_and_garbage_is_no_holder() {
        let h = Holder { host: "node-7".into(), pid: 4242 };
        assert_eq!(Holder::parse(&h.to_text()), Some(h));
        for bad in ["", "\n", "node-7", "node-7 x", "node-7 12 extra"] {
            assert_eq!(Holder::parse(bad), None, "{bad:?}");
        }
        let me = Holder::me();
        assert_eq!(me.pid, std::process::id());
        assert_eq!(Holder::parse(&me.to_text()), Some(me));
    }

    #[test]
    fn a_lease_is_stale_only_past_its_length_and_never_from_the_future() {
        let now = SystemTime::now();
        assert!(!is_stale(now, now, LEASE));
        assert!(!is_stale(now - LEASE, now, LEASE));
        assert!(is_stale(now - LEASE - Duration::from_millis(1), now, LEASE));
        assert!(!is_stale(now + Duration::from_secs(3600), now, LEASE));
        assert!(HEARTBEAT * 3 <= LEASE);
    }

    #[test]
    fn this_process_is_alive() {
        assert!(process_alive(std::process::id()));
    }
}
