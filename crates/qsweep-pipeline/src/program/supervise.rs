//! The supervisor: `qsweep __supervise -- PROGRAM [ARGS…]`, the parent of every program qsweep
//! runs, so that no process outlives qsweep, even a qsweep killed by SIGKILL.
//!
//! qsweep starts it with the program's pipes on its stdin, stdout and stderr (the program inherits
//! them) and a *lifeline* on fd 3: the read end of a pipe whose write end only qsweep holds. It
//! starts the program in a process group of its own and waits. When the lifeline reads EOF (qsweep
//! died, however) or it gets SIGTERM, SIGINT, SIGHUP or SIGQUIT (qsweep's timeout or interrupt),
//! it SIGKILLs the program's whole group, reaps, and exits (re-raising the signal, if one). When
//! the program exits, it SIGKILLs what is left of the group and exits as the program did: the same
//! code, or killed by the same signal. qsweep's `wait4` of the supervisor then gives the
//! program's status and, in its rusage, the CPU time of the program and of everything the
//! supervisor reaped.
//!
//! On Linux it is also a child subreaper, so a process of the program's whose parent died comes to
//! it and is reaped (or, if it left the group with `setsid`, killed) before it exits, and the
//! program dies with it (PR_SET_PDEATHSIG) should it be killed itself. Elsewhere (macOS) the group
//! is all it guards.

use std::ffi::OsString;
use std::io;
use std::os::unix::process::CommandExt;
use std::process::Command;
use std::sync::atomic::{AtomicI32, Ordering};
use std::time::{Duration, Instant};

/// The file descriptor the lifeline arrives on.
pub const LIFELINE_FD: libc::c_int = 3;

/// The exit code of a supervisor that could not start its program (as a shell's): its stderr's
/// last line then starts with [`CANNOT_START`].
pub const CANNOT_START_CODE: i32 = 127;

/// How the supervisor's message starts when the program cannot be started.
pub const CANNOT_START: &str = "qsweep: cannot start";

/// The signals that end the program's group (qsweep sends SIGTERM; the others are for people).
const STOPPING: [libc::c_int; 4] = [libc::SIGTERM, libc::SIGINT, libc::SIGHUP, libc::SIGQUIT];

/// How long the supervisor waits for the killed group's processes to be reaped before it exits.
const SWEEP: Duration = Duration::from_secs(1);

/// The self-pipe's write end, for the signal handler.
static SIGNALS: AtomicI32 = AtomicI32::new(-1);

/// Why the supervisor stops waiting.
enum End {
    /// The program exited (its raw wait status).
    Exited(libc::c_int),
    /// A stopping signal arrived.
    Signal(libc::c_int),
    /// qsweep is gone (exit 1, to nobody).
    Lifeline,
}

/// Run `argv` under supervision (see the module's doc) and exit as it did; never returns. Call
/// it in a process with one thread (the CLI does, before anything starts one): it sets the
/// process's signal mask and handlers.
pub fn supervise(argv: &[OsString]) -> ! {
    match run(argv) {
        Ok(end) => exit_as(end),
        Err(e) => {
            eprintln!("qsweep __supervise: {e}");
            std::process::exit(2)
        }
    }
}

/// Everything but the exit.
fn run(argv: &[OsString]) -> io::Result<End> {
    let Some((program, args)) = argv.split_first() else {
        return Err(io::Error::other("no program given"));
    };
    // SAFETY: fstat into a local and fcntl on a descriptor number; an unopened one gives EBADF.
    let is_pipe = unsafe {
        let mut st: libc::stat = std::mem::zeroed();
        libc::fstat(LIFELINE_FD, &mut st) == 0 && st.st_mode & libc::S_IFMT == libc::S_IFIFO
    };
    if !is_pipe || unsafe { libc::fcntl(LIFELINE_FD, libc::F_SETFD, libc::FD_CLOEXEC) } != 0 {
        return Err(io::Error::other(format!(
            "no lifeline on fd {LIFELINE_FD} (this subcommand is qsweep's own: it runs it for every program)"
        )));
    }
    let self_pipe = signals_to_pipe()?;
    #[cfg(target_os = "linux")]
    // SAFETY: a prctl with integer arguments. Best effort: without it orphans go to init.
    unsafe {
        libc::prctl(libc::PR_SET_CHILD_SUBREAPER, 1, 0, 0, 0);
    }
    if lifeline_gone(0) {
        return Ok(End::Lifeline);
    }
    let mut cmd = Command::new(program);
    cmd.args(args).process_group(0);
    #[cfg(target_os = "linux")]
    {
        // SAFETY: getpid is always safe.
        let me = unsafe { libc::getpid() };
        // SAFETY: prctl, getppid and _exit are async-signal-safe.
        unsafe {
            cmd.pre_exec(move || {
                libc::prctl(libc::PR_SET_PDEATHSIG, libc::SIGKILL, 0, 0, 0);
                if libc::getppid() != me {
                    libc::_exit(CANNOT_START_CODE);
                }
                Ok(())
            });
        }
    }
    let pid = match cmd.spawn() {
        // The std handle is dropped unwaited: this process reaps with waitpid itself.
        Ok(child) => child.id() as libc::pid_t,
        Err(e) => {
            eprintln!("{CANNOT_START} `{}`: {e}", program.to_string_lossy());
            unblock(&STOPPING);
            std::process::exit(CANNOT_START_CODE);
        }
    };
    unblock(&[STOPPING.as_slice(), &[libc::SIGCHLD]].concat());
    let end = wait(pid, self_pipe);
    let status = kill_group(pid, &end);
    if matches!(end, End::Lifeline) {
        remove_trial_dir();
    }
    Ok(match end {
        // Not reaped within the sweep (it cannot happen to a zombie): exit 1, as on a lost lifeline.
        End::Exited(_) => status.map_or(End::Lifeline, End::Exited),
        other => other,
    })
}

/// qsweep is gone (its lifeline closed) and cannot remove the trial's scratch directory
/// (`QSWEEP_TRIAL_DIR`, one of qsweep's own `qsweep-…` directories): remove it for it.
fn remove_trial_dir() {
    let Some(dir) = std::env::var_os("QSWEEP_TRIAL_DIR").map(std::path::PathBuf::from) else { return };
    if dir.file_name().is_some_and(|n| n.to_string_lossy().starts_with("qsweep-")) {
        let _ = std::fs::remove_dir_all(&dir);
    }
}

/// Block the stopping signals and SIGCHLD (so none is lost while the program starts) and have
/// their handler write each one's number into a self-pipe; returns its read end.
fn signals_to_pipe() -> io::Result<libc::c_int> {
    let mut fds = [0; 2];
    // SAFETY: pipe with a two-int array; fcntl on the descriptors it made.
    unsafe {
        if libc::pipe(fds.as_mut_ptr()) != 0 {
            return Err(io::Error::last_os_error());
        }
        for fd in fds {
            libc::fcntl(fd, libc::F_SETFD, libc::FD_CLOEXEC);
            libc::fcntl(fd, libc::F_SETFL, libc::fcntl(fd, libc::F_GETFL) | libc::O_NONBLOCK);
        }
    }
    SIGNALS.store(fds[1], Ordering::SeqCst);
    block(&[STOPPING.as_slice(), &[libc::SIGCHLD]].concat());
    for sig in STOPPING.into_iter().chain([libc::SIGCHLD]) {
        // SAFETY: a zeroed sigaction with a handler that only calls write (async-signal-safe).
        unsafe {
            let mut act: libc::sigaction = std::mem::zeroed();
            act.sa_sigaction = on_signal as extern "C" fn(libc::c_int) as libc::sighandler_t;
            libc::sigemptyset(&mut act.sa_mask);
            act.sa_flags = libc::SA_NOCLDSTOP;
            libc::sigaction(sig, &act, std::ptr::null_mut());
        }
    }
    Ok(fds[0])
}

extern "C" fn on_signal(sig: libc::c_int) {
    let byte = sig as u8;
    // SAFETY: write is async-signal-safe; errno is saved and restored around it.
    unsafe {
        let errno = errno_location();
        let saved = *errno;
        libc::write(SIGNALS.load(Ordering::Relaxed), (&byte as *const u8).cast(), 1);
        *errno = saved;
    }
}

#[cfg(target_os = "linux")]
unsafe fn errno_location() -> *mut libc::c_int {
    libc::__errno_location()
}

#[cfg(not(target_os = "linux"))]
unsafe fn errno_location() -> *mut libc::c_int {
    libc::__error()
}

/// Wait until the program exits, a stopping signal arrives or the lifeline closes.
fn wait(pid: libc::pid_t, self_pipe: libc::c_int) -> End {
    let mut fds = [
        libc::pollfd { fd: LIFELINE_FD, events: libc::POLLIN, revents: 0 },
        libc::pollfd { fd: self_pipe, events: libc::POLLIN, revents: 0 },
    ];
    loop {
        // SAFETY: poll on two valid pollfds.
        let n = unsafe { libc::poll(fds.as_mut_ptr(), 2, -1) };
        if n < 0 {
            if io::Error::last_os_error().raw_os_error() == Some(libc::EINTR) {
                continue;
            }
            // Nothing to wait with: end the program rather than leave it unguarded.
            return End::Lifeline;
        }
        if fds[0].revents != 0 && lifeline_gone(0) {
            return End::Lifeline;
        }
        if fds[1].revents != 0 {
            let mut buf = [0u8; 64];
            // SAFETY: read into a local buffer from the non-blocking self-pipe.
            let n = unsafe { libc::read(self_pipe, buf.as_mut_ptr().cast(), buf.len()) };
            let got = &buf[..n.max(0) as usize];
            if let Some(&sig) = got.iter().find(|&&s| STOPPING.contains(&libc::c_int::from(s))) {
                return End::Signal(libc::c_int::from(sig));
            }
            if let Some(status) = exited(pid) {
                return End::Exited(status);
            }
        }
    }
}

/// Whether the lifeline has closed, waiting up to `ms` milliseconds to see.
fn lifeline_gone(ms: libc::c_int) -> bool {
    let mut fd = libc::pollfd { fd: LIFELINE_FD, events: libc::POLLIN, revents: 0 };
    // SAFETY: poll on one pollfd.
    if unsafe { libc::poll(&mut fd, 1, ms) } <= 0 {
        return false;
    }
    if fd.revents & (libc::POLLHUP | libc::POLLERR | libc::POLLNVAL) != 0 {
        return true;
    }
    // Readable: nobody writes into a lifeline, so this is its EOF.
    let mut byte = 0u8;
    // SAFETY: read one byte into a local.
    unsafe { libc::read(LIFELINE_FD, (&mut byte as *mut u8).cast(), 1) <= 0 }
}

/// The program's wait status if it has exited. On Linux it is left a zombie (its pid, and so its
/// group's id, cannot be reused until it is reaped), and other exited children (orphans that
/// came to this subreaper) are reaped on the way.
#[cfg(target_os = "linux")]
fn exited(pid: libc::pid_t) -> Option<libc::c_int> {
    loop {
        // SAFETY: waitid into a zeroed siginfo_t.
        let mut info: libc::siginfo_t = unsafe { std::mem::zeroed() };
        let rc =
            unsafe { libc::waitid(libc::P_ALL, 0, &mut info, libc::WEXITED | libc::WNOHANG | libc::WNOWAIT) };
        // SAFETY: si_pid is set by a successful waitid (0 when no child has exited).
        let who = unsafe { info.si_pid() };
        if rc != 0 || who == 0 {
            return None;
        }
        if who == pid {
            return Some(0); // the status is taken when it is reaped, after its group is killed
        }
        let mut st = 0;
        // SAFETY: reap the orphan waitid named.
        unsafe { libc::waitpid(who, &mut st, 0) };
    }
}

#[cfg(not(target_os = "linux"))]
fn exited(pid: libc::pid_t) -> Option<libc::c_int> {
    let mut st = 0;
    // SAFETY: waitpid on our child.
    (unsafe { libc::waitpid(pid, &mut st, libc::WNOHANG) } == pid).then_some(st)
}

/// SIGKILL the program's group (and, on Linux, every process that came to this subreaper), then
/// reap until nothing is left or [`SWEEP`] has passed; returns the program's wait status if it
/// was reaped here (or the one [`exited`] took).
fn kill_group(pid: libc::pid_t, end: &End) -> Option<libc::c_int> {
    let mut status = match end {
        End::Exited(st) if cfg!(not(target_os = "linux")) => Some(*st),
        _ => None,
    };
    // SAFETY: killpg of the program's group; on Linux the program is unreaped here, so its id is
    // still its group's.
    unsafe { libc::killpg(pid, libc::SIGKILL) };
    let deadline = Instant::now() + SWEEP;
    loop {
        loop {
            let mut st = 0;
            // SAFETY: waitpid on any child.
            let r = unsafe { libc::waitpid(-1, &mut st, libc::WNOHANG) };
            if r == pid {
                status = Some(st);
            } else if r == 0 {
                break;
            } else if r < 0 {
                if io::Error::last_os_error().raw_os_error() == Some(libc::EINTR) {
                    continue;
                }
                return status; // ECHILD: every child is reaped
            }
        }
        #[cfg(target_os = "linux")]
        for child in adopted() {
            // SAFETY: `child` is an unreaped child of this process, so its id is its own; when it
            // leads a group of its own (it left the program's with setsid), that group goes too.
            unsafe {
                if libc::getpgid(child) == child {
                    libc::killpg(child, libc::SIGKILL);
                }
                libc::kill(child, libc::SIGKILL);
            }
        }
        if Instant::now() >= deadline {
            return status;
        }
        std::thread::sleep(Duration::from_millis(1));
    }
}

/// This process's children (Linux; empty where the kernel does not list them).
#[cfg(target_os = "linux")]
fn adopted() -> Vec<libc::pid_t> {
    // SAFETY: getpid is always safe.
    let me = unsafe { libc::getpid() };
    std::fs::read_to_string(format!("/proc/{me}/task/{me}/children"))
        .unwrap_or_default()
        .split_whitespace()
        .filter_map(|p| p.parse().ok())
        .collect()
}

/// Exit as `end` says: the program's code, or killed by its signal (or the one received).
fn exit_as(end: End) -> ! {
    match end {
        End::Exited(st) if libc::WIFEXITED(st) => std::process::exit(libc::WEXITSTATUS(st)),
        End::Exited(st) if libc::WIFSIGNALED(st) => die_by(libc::WTERMSIG(st)),
        End::Exited(_) => std::process::exit(1),
        End::Signal(sig) => die_by(sig),
        End::Lifeline => std::process::exit(1),
    }
}

/// Die by `sig` with its default action, so qsweep sees "killed by signal `sig`" (no core file).
fn die_by(sig: libc::c_int) -> ! {
    // SAFETY: setrlimit, signal, sigprocmask and raise with valid arguments.
    unsafe {
        let none = libc::rlimit { rlim_cur: 0, rlim_max: 0 };
        libc::setrlimit(libc::RLIMIT_CORE, &none);
        libc::signal(sig, libc::SIG_DFL);
        unblock(&[sig]);
        libc::raise(sig);
    }
    std::process::exit(128 + sig)
}

/// Add `sigs` to the blocked signals.
fn block(sigs: &[libc::c_int]) {
    mask(libc::SIG_BLOCK, sigs);
}

/// Remove `sigs` from the blocked signals.
fn unblock(sigs: &[libc::c_int]) {
    mask(libc::SIG_UNBLOCK, sigs);
}

fn mask(how: libc::c_int, sigs: &[libc::c_int]) {
    // SAFETY: a sigset built with sigemptyset/sigaddset, given to sigprocmask.
    unsafe {
        let mut set: libc::sigset_t = std::mem::zeroed();
        libc::sigemptyset(&mut set);
        for &s in sigs {
            libc::sigaddset(&mut set, s);
        }
        libc::sigprocmask(how, &set, std::ptr::null_mut());
    }
}
