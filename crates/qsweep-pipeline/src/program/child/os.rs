//! The system calls a running program needs: `wait4` with its rusage, the lifeline pipe, pipes
//! read and written without blocking (and without SIGPIPE), and a worker's CPU time on Linux.

use crate::program::supervise::LIFELINE_FD;
use std::io;
use std::os::fd::{AsRawFd, FromRawFd, OwnedFd, RawFd};
use std::sync::OnceLock;
use std::time::Duration;

/// How a program ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Status {
    /// It exited with this code.
    Code(i32),
    /// It was killed by this signal.
    Signal(i32),
}

/// `wait4(pid, options)`: its status and CPU time, once it has ended.
pub(crate) fn wait4(pid: libc::pid_t, options: libc::c_int) -> Option<(Status, Duration)> {
    loop {
        let mut st = 0;
        // SAFETY: wait4 into locals.
        let mut ru: libc::rusage = unsafe { std::mem::zeroed() };
        let r = unsafe { libc::wait4(pid, &mut st, options, &mut ru) };
        if r == pid {
            let status = if libc::WIFSIGNALED(st) {
                Status::Signal(libc::WTERMSIG(st))
            } else {
                Status::Code(libc::WEXITSTATUS(st))
            };
            let tv = |t: libc::timeval| Duration::new(t.tv_sec as u64, t.tv_usec as u32 * 1000);
            return Some((status, tv(ru.ru_utime) + tv(ru.ru_stime)));
        }
        if r < 0 && io::Error::last_os_error().raw_os_error() == Some(libc::EINTR) {
            continue;
        }
        // 0: still running. ECHILD: someone else reaped it (cannot happen here); report a loss.
        return (r < 0).then_some((Status::Signal(libc::SIGKILL), Duration::ZERO));
    }
}

/// The read end of qsweep's lifeline pipe (see `supervise`), made once: its write end stays open,
/// close-on-exec, until this process ends, however it ends. Both ends are above fd 3.
pub(crate) fn lifeline() -> io::Result<RawFd> {
    static LIFELINE: OnceLock<Result<(OwnedFd, OwnedFd), i32>> = OnceLock::new();
    let made = LIFELINE.get_or_init(|| {
        let mut fds = [0; 2];
        // SAFETY: pipe into a two-int array; the descriptors become owned at once.
        let (r, w) = unsafe {
            if libc::pipe(fds.as_mut_ptr()) != 0 {
                return Err(io::Error::last_os_error().raw_os_error().unwrap_or(libc::EIO));
            }
            (OwnedFd::from_raw_fd(fds[0]), OwnedFd::from_raw_fd(fds[1]))
        };
        Ok((above_3(r)?, above_3(w)?))
    });
    match made {
        Ok((read, _write)) => Ok(read.as_raw_fd()),
        Err(errno) => Err(io::Error::from_raw_os_error(*errno)),
    }
}

/// `fd` moved to a descriptor above 3, close-on-exec (so only a `dup2` onto fd 3 passes it on).
fn above_3(fd: OwnedFd) -> Result<OwnedFd, i32> {
    // SAFETY: F_DUPFD_CLOEXEC on an owned descriptor; the copy becomes owned at once.
    let copy = unsafe { libc::fcntl(fd.as_raw_fd(), libc::F_DUPFD_CLOEXEC, LIFELINE_FD + 1) };
    if copy < 0 {
        return Err(io::Error::last_os_error().raw_os_error().unwrap_or(libc::EIO));
    }
    drop(fd);
    // SAFETY: `copy` is a fresh descriptor nobody else owns.
    Ok(unsafe { OwnedFd::from_raw_fd(copy) })
}

/// Set O_NONBLOCK on `fd`.
pub(crate) fn nonblocking(fd: RawFd) -> io::Result<()> {
    // SAFETY: fcntl on a valid descriptor.
    let ok = unsafe { libc::fcntl(fd, libc::F_SETFL, libc::fcntl(fd, libc::F_GETFL) | libc::O_NONBLOCK) };
    if ok < 0 {
        return Err(io::Error::last_os_error());
    }
    Ok(())
}

/// `read` what is there: `Some(0)` at EOF, `None` when nothing is (or on an error, which ends
/// nothing: the process's exit does).
pub(crate) fn read_some(fd: RawFd, buf: &mut [u8]) -> Option<usize> {
    loop {
        // SAFETY: read into a live buffer of its length.
        let n = unsafe { libc::read(fd, buf.as_mut_ptr().cast(), buf.len()) };
        if n >= 0 {
            return Some(n as usize);
        }
        match io::Error::last_os_error().raw_os_error() {
            Some(libc::EINTR) => continue,
            Some(libc::EAGAIN) => return None,
            // EIO and the like: treat as EOF so the loop does not spin on it.
            _ => return Some(0),
        }
    }
}

/// `write` without SIGPIPE: the qsweep binary restores SIGPIPE's default action (so `| head`
/// ends it quietly), which would kill it when a program exits without reading its input. The
/// signal is blocked on this thread for the write and a pending one taken back.
pub(crate) fn write_nosigpipe(fd: RawFd, buf: &[u8]) -> io::Result<usize> {
    // SAFETY: signal-mask calls on this thread with sets built by sigemptyset/sigaddset; write
    // from a live buffer of its length.
    unsafe {
        let mut pipe: libc::sigset_t = std::mem::zeroed();
        let mut old: libc::sigset_t = std::mem::zeroed();
        libc::sigemptyset(&mut pipe);
        libc::sigaddset(&mut pipe, libc::SIGPIPE);
        libc::pthread_sigmask(libc::SIG_BLOCK, &pipe, &mut old);
        let n = libc::write(fd, buf.as_ptr().cast(), buf.len());
        let err = io::Error::last_os_error();
        if n < 0 && err.raw_os_error() == Some(libc::EPIPE) && libc::sigismember(&old, libc::SIGPIPE) == 0 {
            take_pending(&pipe);
        }
        libc::pthread_sigmask(libc::SIG_SETMASK, &old, std::ptr::null_mut());
        if n < 0 {
            Err(err)
        } else {
            Ok(n as usize)
        }
    }
}

/// Take a pending SIGPIPE (in `set`) off this thread, if one is.
///
/// # Safety
/// `set` must be a valid signal set holding SIGPIPE only, blocked on this thread.
unsafe fn take_pending(set: &libc::sigset_t) {
    let mut pending: libc::sigset_t = std::mem::zeroed();
    libc::sigpending(&mut pending);
    if libc::sigismember(&pending, libc::SIGPIPE) == 1 {
        let mut sig = 0;
        libc::sigwait(set, &mut sig);
    }
}

/// This program's own CPU time plus that of the children it has waited for (Linux:
/// `/proc/<pid>/stat`), for a worker's per-trial time; `None` elsewhere or once it is gone.
#[cfg(target_os = "linux")]
pub(crate) fn cpu_of(pid: libc::pid_t) -> Option<Duration> {
    let stat = std::fs::read_to_string(format!("/proc/{pid}/stat")).ok()?;
    // Fields after the command (which may hold spaces and parentheses): state is field 3, utime
    // 14, stime 15, cutime 16, cstime 17.
    let rest = &stat[stat.rfind(')')? + 2..];
    let f: Vec<u64> = rest.split(' ').skip(11).take(4).map(|x| x.parse().unwrap_or(0)).collect();
    // SAFETY: sysconf is always safe.
    let hz = unsafe { libc::sysconf(libc::_SC_CLK_TCK) }.max(1) as u64;
    let children = Duration::from_nanos((f.get(2)? + f.get(3)?) * 1_000_000_000 / hz);
    // Its own time, to the nanosecond from its CPU clock where the kernel gives it.
    let mut clock: libc::clockid_t = 0;
    let mut ts = libc::timespec { tv_sec: 0, tv_nsec: 0 };
    // SAFETY: clock calls into locals.
    let own = if unsafe {
        libc::clock_getcpuclockid(pid, &mut clock) == 0 && libc::clock_gettime(clock, &mut ts) == 0
    } {
        Duration::new(ts.tv_sec as u64, ts.tv_nsec as u32)
    } else {
        Duration::from_nanos((f.first()? + f.get(1)?) * 1_000_000_000 / hz)
    };
    Some(own + children)
}

/// Not measured off Linux.
#[cfg(not(target_os = "linux"))]
pub(crate) fn cpu_of(_pid: libc::pid_t) -> Option<Duration> {
    None
}

/// The program a supervisor started: its only child (Linux: `/proc/<pid>/task/<pid>/children`).
#[cfg(target_os = "linux")]
pub(crate) fn program_of(supervisor: libc::pid_t) -> Option<libc::pid_t> {
    std::fs::read_to_string(format!("/proc/{supervisor}/task/{supervisor}/children"))
        .ok()?
        .split_whitespace()
        .next()?
        .parse()
        .ok()
}

/// Not known off Linux.
#[cfg(not(target_os = "linux"))]
pub(crate) fn program_of(_supervisor: libc::pid_t) -> Option<libc::pid_t> {
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn writing_to_a_closed_pipe_is_an_error_not_a_signal() {
        let mut fds = [0; 2];
        // SAFETY: pipe into a local array; both ends closed below.
        unsafe {
            assert_eq!(libc::pipe(fds.as_mut_ptr()), 0);
            libc::close(fds[0]);
            let old = libc::signal(libc::SIGPIPE, libc::SIG_DFL);
            let r = write_nosigpipe(fds[1], b"x");
            libc::signal(libc::SIGPIPE, old);
            libc::close(fds[1]);
            assert_eq!(r.unwrap_err().raw_os_error(), Some(libc::EPIPE));
        }
    }
}
