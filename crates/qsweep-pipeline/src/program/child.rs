//! One running program, as both protocols see it: started under the supervisor (or, without one,
//! directly in a process group of its own), its stdin fed, its stdout read up to a limit and the
//! tail of its stderr kept, all by one `poll` loop on the calling thread (no thread per pipe);
//! a deadline and an interrupt flag checked while it waits; killed as a whole process group;
//! reaped with `wait4` for its status and CPU time (the system calls are in `os`).
//!
//! Without a supervisor (library use) the program gets PR_SET_PDEATHSIG(SIGKILL) on Linux, best
//! effort: it fires when the *thread* that started it ends, and it reaches the program only, not
//! its children; a program whose leftover children hold its pipes is seen to exit (Linux) and its
//! group killed, elsewhere waited for until the timeout.

mod os;

use super::supervise::LIFELINE_FD;
pub(crate) use os::{cpu_of, program_of, Status};
use os::{lifeline, nonblocking, read_some, wait4, write_nosigpipe};
use std::ffi::OsStr;
use std::io;
use std::os::fd::{AsRawFd, OwnedFd, RawFd};
use std::os::unix::process::CommandExt;
use std::path::Path;
use std::process::{Command, Stdio};
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

/// How often a waiting loop looks at the interrupt flag.
const TICK: Duration = Duration::from_millis(50);

/// How long a killed program (or its supervisor) may take to be reaped before SIGKILL follows.
const GRACE: Duration = Duration::from_secs(5);

/// Why [`Proc::pump`] returned.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Pumped {
    /// stdout holds a whole line (when one was asked for).
    Line,
    /// stdout reached EOF (and stderr too, when reading to the end).
    Eof,
    /// The deadline passed.
    TimedOut,
    /// The interrupt flag was set.
    Interrupted,
    /// stdout passed the limit.
    Overflow,
}

/// The last bytes of a stream.
pub(crate) struct Tail {
    buf: Vec<u8>,
    keep: usize,
}

impl Tail {
    /// Keeping the last `keep` bytes.
    pub(crate) fn new(keep: usize) -> Self {
        Self { buf: Vec::new(), keep }
    }

    /// Append `bytes`, forgetting what falls out of the tail (in amortised O(1) per byte).
    pub(crate) fn push(&mut self, bytes: &[u8]) {
        self.buf.extend_from_slice(bytes);
        if self.buf.len() > 2 * self.keep.max(1) {
            self.buf.drain(..self.buf.len() - self.keep);
        }
    }

    /// Forget everything.
    pub(crate) fn clear(&mut self) {
        self.buf.clear();
    }

    /// The tail as text (lossy UTF-8, not starting inside a character).
    pub(crate) fn text(&self) -> String {
        let tail = &self.buf[self.buf.len().saturating_sub(self.keep)..];
        let start = tail.iter().position(|&b| b & 0xC0 != 0x80).unwrap_or(tail.len());
        String::from_utf8_lossy(&tail[start..]).into_owned()
    }
}

/// A running program (under its supervisor, or alone), its pipes and what it has written.
pub(crate) struct Proc {
    /// The supervisor's pid, or the program's without one; a process group's id either way.
    pid: libc::pid_t,
    supervised: bool,
    stdin: Option<OwnedFd>,
    stdout: Option<OwnedFd>,
    stderr: Option<OwnedFd>,
    /// stdout read and not yet taken.
    pub(crate) out: Vec<u8>,
    /// `out[..scanned]` holds no newline.
    scanned: usize,
    /// The tail of stderr.
    pub(crate) err: Tail,
    /// How it ended and its CPU time (its own and its reaped children's), once reaped.
    reaped: Option<(Status, Duration)>,
    /// Without a supervisor: the program has exited and its group was killed.
    swept: bool,
}

impl Proc {
    /// Start `argv` with `env` added to qsweep's environment, under `supervisor` when given,
    /// keeping `stderr_tail` bytes of its stderr.
    pub(crate) fn spawn(
        argv: &[String],
        env: &[(&str, &OsStr)],
        supervisor: Option<&Path>,
        stderr_tail: usize,
    ) -> io::Result<Self> {
        let Some((program, args)) = argv.split_first() else {
            return Err(io::Error::new(io::ErrorKind::InvalidInput, "the command is empty"));
        };
        let mut cmd = match supervisor {
            Some(sup) => {
                let mut c = Command::new(sup);
                c.arg("__supervise").arg("--").args(argv);
                let lifeline = lifeline()?;
                // SAFETY: dup2 is async-signal-safe; the lifeline's descriptor is above 3, so the
                // copy on fd 3 is a new one, without FD_CLOEXEC.
                unsafe {
                    c.pre_exec(move || match libc::dup2(lifeline, LIFELINE_FD) {
                        -1 => Err(io::Error::last_os_error()),
                        _ => Ok(()),
                    });
                }
                c
            }
            None => {
                let mut c = Command::new(program);
                c.args(args);
                #[cfg(target_os = "linux")]
                {
                    // SAFETY: getpid is always safe.
                    let me = unsafe { libc::getpid() };
                    // SAFETY: prctl, getppid and _exit are async-signal-safe.
                    unsafe {
                        c.pre_exec(move || {
                            libc::prctl(libc::PR_SET_PDEATHSIG, libc::SIGKILL, 0, 0, 0);
                            if libc::getppid() != me {
                                libc::_exit(1);
                            }
                            Ok(())
                        });
                    }
                }
                c
            }
        };
        cmd.envs(env.iter().copied())
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .process_group(0);
        let mut child = cmd.spawn()?;
        let own = |fd: Option<OwnedFd>| -> io::Result<Option<OwnedFd>> {
            let fd = fd.ok_or_else(|| io::Error::other("a pipe is missing"))?;
            nonblocking(fd.as_raw_fd())?;
            Ok(Some(fd))
        };
        // The std handle is dropped unwaited: this type reaps with wait4 itself (for the rusage).
        let proc = Self {
            pid: child.id() as libc::pid_t,
            supervised: supervisor.is_some(),
            stdin: own(child.stdin.take().map(OwnedFd::from))?,
            stdout: own(child.stdout.take().map(OwnedFd::from))?,
            stderr: own(child.stderr.take().map(OwnedFd::from))?,
            out: Vec::new(),
            scanned: 0,
            err: Tail::new(stderr_tail),
            reaped: None,
            swept: false,
        };
        Ok(proc)
    }

    /// The pid of the process started (the supervisor, when there is one).
    pub(crate) fn pid(&self) -> libc::pid_t {
        self.pid
    }

    /// Whether it runs under a supervisor.
    pub(crate) fn supervised(&self) -> bool {
        self.supervised
    }

    /// Write `input` (advancing it) and read its output until, with `line`, stdout holds a whole
    /// line, or else until stdout and stderr both reach EOF; or until the deadline passes, the
    /// interrupt flag is set, or more than `limit` bytes of stdout are held. With `close`, stdin
    /// is closed once `input` is written. A stdin the program closed takes no more input.
    pub(crate) fn pump(
        &mut self,
        input: &mut &[u8],
        close: bool,
        line: bool,
        deadline: Instant,
        limit: usize,
        interrupt: &AtomicBool,
    ) -> Pumped {
        loop {
            if line && self.has_line() {
                return Pumped::Line;
            }
            if self.out.len() > limit {
                return Pumped::Overflow;
            }
            if self.stdout.is_none() && (line || self.stderr.is_none()) {
                return Pumped::Eof;
            }
            if input.is_empty() && close {
                self.stdin = None;
            }
            if interrupt.load(Ordering::Relaxed) {
                return Pumped::Interrupted;
            }
            let now = Instant::now();
            if now >= deadline {
                return Pumped::TimedOut;
            }
            let wait = (deadline - now).min(TICK);
            if self.poll_once(input, wait, limit) == 0 && !self.supervised && !self.swept {
                self.sweep_if_exited();
            }
        }
    }

    /// One `poll` of the pipes for up to `wait`, then the reads and writes it allows; returns
    /// how many pipes were ready.
    fn poll_once(&mut self, input: &mut &[u8], wait: Duration, limit: usize) -> usize {
        let want_in = !input.is_empty();
        let slots = [
            self.stdin.as_ref().filter(|_| want_in).map(|f| (f.as_raw_fd(), libc::POLLOUT)),
            self.stdout.as_ref().map(|f| (f.as_raw_fd(), libc::POLLIN)),
            self.stderr.as_ref().map(|f| (f.as_raw_fd(), libc::POLLIN)),
        ];
        let mut fds: Vec<libc::pollfd> =
            slots.iter().flatten().map(|&(fd, events)| libc::pollfd { fd, events, revents: 0 }).collect();
        let ms = wait.as_micros().div_ceil(1000).min(60_000) as libc::c_int;
        // SAFETY: poll on a slice of pollfds (an empty slice just sleeps).
        let n = unsafe { libc::poll(fds.as_mut_ptr(), fds.len() as libc::nfds_t, ms) };
        if n <= 0 {
            return 0;
        }
        let ready = |fd: RawFd| fds.iter().any(|p| p.fd == fd && p.revents != 0);
        if let Some(fd) = self.stdin.as_ref().map(AsRawFd::as_raw_fd).filter(|&fd| want_in && ready(fd)) {
            match write_nosigpipe(fd, input) {
                Ok(k) => *input = &input[k..],
                Err(e) if e.kind() == io::ErrorKind::WouldBlock => {}
                // EPIPE and the like: it will not read any more.
                Err(_) => {
                    *input = &[];
                    self.stdin = None;
                }
            }
        }
        if let Some(fd) = self.stdout.as_ref().map(AsRawFd::as_raw_fd).filter(|&fd| ready(fd)) {
            let room = (limit + 1).saturating_sub(self.out.len()).clamp(1, 1 << 16);
            let start = self.out.len();
            self.out.resize(start + room, 0);
            let got = read_some(fd, &mut self.out[start..]);
            self.out.truncate(start + got.unwrap_or(0));
            if got == Some(0) {
                self.stdout = None;
            }
        }
        if let Some(fd) = self.stderr.as_ref().map(AsRawFd::as_raw_fd).filter(|&fd| ready(fd)) {
            if self.drain_stderr_from(fd) {
                self.stderr = None;
            }
        }
        n as usize
    }

    /// Read what stderr holds now into the tail; true at EOF.
    fn drain_stderr_from(&mut self, fd: RawFd) -> bool {
        let mut buf = [0u8; 1 << 14];
        loop {
            match read_some(fd, &mut buf) {
                Some(0) => return true,
                Some(k) => self.err.push(&buf[..k]),
                None => return false,
            }
        }
    }

    /// Read what stderr holds now (after the program is gone: its last words).
    pub(crate) fn drain_stderr(&mut self) {
        if let Some(fd) = self.stderr.as_ref().map(AsRawFd::as_raw_fd) {
            if self.drain_stderr_from(fd) {
                self.stderr = None;
            }
        }
    }

    /// Whether `out` holds a newline (scanning only what is new).
    fn has_line(&mut self) -> bool {
        match self.out[self.scanned..].iter().position(|&b| b == b'\n') {
            Some(i) => {
                self.scanned += i;
                true
            }
            None => {
                self.scanned = self.out.len();
                false
            }
        }
    }

    /// Take the first line of `out` (without its newline), if it holds a whole one.
    pub(crate) fn take_line(&mut self) -> Option<Vec<u8>> {
        if !self.has_line() {
            return None;
        }
        let mut line: Vec<u8> = self.out.drain(..=self.scanned).collect();
        line.pop();
        self.scanned = 0;
        Some(line)
    }

    /// Read stdout without waiting; whether it held anything but whitespace (a worker's output
    /// that no trial asked for).
    pub(crate) fn stray_output(&mut self) -> bool {
        self.poll_once(&mut &[][..], Duration::ZERO, usize::MAX - 1);
        let stray = !self.out.trim_ascii().is_empty();
        self.out.clear();
        self.scanned = 0;
        stray
    }

    /// Whether its stdout has reached EOF (a worker that closed it, or is ending, takes no trial).
    pub(crate) fn stdout_closed(&self) -> bool {
        self.stdout.is_none()
    }

    /// Stop it: SIGTERM to the supervisor (which kills the program's group), or without one
    /// SIGKILL to the program's group. A reaped one is left alone (its pid may be reused).
    pub(crate) fn kill(&mut self) {
        if self.reaped.is_some() {
            return;
        }
        // SAFETY: signals to our unreaped child (or its group, whose id its pid keeps).
        unsafe {
            if self.supervised {
                libc::kill(self.pid, libc::SIGTERM);
            } else {
                libc::killpg(self.pid, libc::SIGKILL);
            }
        }
    }

    /// Close stdin (a worker's signal to finish).
    pub(crate) fn close_stdin(&mut self) {
        self.stdin = None;
    }

    /// Reap it if it has ended; without a supervisor, its group is killed first (while its pid
    /// still names the group).
    pub(crate) fn try_reap(&mut self) -> Option<(Status, Duration)> {
        if self.reaped.is_none() {
            if !self.supervised && !self.swept {
                self.sweep_if_exited();
            }
            self.reaped = wait4(self.pid, libc::WNOHANG);
        }
        self.reaped
    }

    /// Wait for it to end until the deadline passes or the flag is set (then `Err` says which).
    pub(crate) fn reap_by(
        &mut self,
        deadline: Instant,
        interrupt: &AtomicBool,
    ) -> Result<(Status, Duration), Pumped> {
        let mut nap = Duration::from_micros(50);
        loop {
            if let Some(r) = self.try_reap() {
                return Ok(r);
            }
            if interrupt.load(Ordering::Relaxed) {
                return Err(Pumped::Interrupted);
            }
            let now = Instant::now();
            if now >= deadline {
                return Err(Pumped::TimedOut);
            }
            std::thread::sleep(nap.min(deadline - now));
            nap = (nap * 2).min(Duration::from_millis(10));
        }
    }

    /// Kill it and reap it, whatever it takes (SIGKILL to the supervisor after [`GRACE`]).
    pub(crate) fn kill_and_reap(&mut self) -> (Status, Duration) {
        self.kill();
        let never = AtomicBool::new(false);
        if let Ok(r) = self.reap_by(Instant::now() + GRACE, &never) {
            return r;
        }
        // SAFETY: SIGKILL to our unreaped child.
        unsafe { libc::kill(self.pid, libc::SIGKILL) };
        let r = wait4(self.pid, 0).unwrap_or((Status::Signal(libc::SIGKILL), Duration::ZERO));
        self.reaped = Some(r);
        r
    }

    /// Without a supervisor: if the program has exited, SIGKILL what is left of its group, so
    /// that leftover children holding its pipes do not keep the trial waiting. On Linux the
    /// program is left unreaped, so its pid still names the group; elsewhere this waits for the
    /// timeout instead.
    fn sweep_if_exited(&mut self) {
        #[cfg(target_os = "linux")]
        {
            // SAFETY: waitid into a zeroed siginfo_t; si_pid is set by a successful waitid.
            let who = unsafe {
                let mut info: libc::siginfo_t = std::mem::zeroed();
                let rc = libc::waitid(
                    libc::P_PID,
                    self.pid as libc::id_t,
                    &mut info,
                    libc::WEXITED | libc::WNOHANG | libc::WNOWAIT,
                );
                if rc == 0 {
                    info.si_pid()
                } else {
                    0
                }
            };
            if who == self.pid {
                // SAFETY: the group of our unreaped (zombie) child.
                unsafe { libc::killpg(self.pid, libc::SIGKILL) };
                self.swept = true;
            }
        }
    }
}

impl Drop for Proc {
    fn drop(&mut self) {
        if self.reaped.is_none() {
            self.kill_and_reap();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_tail_keeps_the_last_bytes_and_starts_on_a_character() {
        let mut t = Tail::new(4);
        t.push(b"abcdef");
        assert_eq!(t.text(), "cdef");
        t.push(b"gh");
        assert_eq!(t.text(), "efgh");
        for _ in 0..1000 {
            t.push(b"0123456789");
        }
        assert!(t.buf.len() <= 8, "memory stays bounded: {}", t.buf.len());
        assert_eq!(t.text(), "6789");
        let mut t = Tail::new(4);
        t.push("xé€".as_bytes()); // x, é (2 bytes), € (3 bytes): the last 4 bytes cut é in half
        assert_eq!(t.text(), "€");
        t.clear();
        assert_eq!(t.text(), "");
    }
}
