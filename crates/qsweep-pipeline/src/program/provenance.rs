//! Provenance commands (`provenance:`): each run once when a plan is made (argv without a shell,
//! in the directory the program runs in, stdin empty, at most [`TIMEOUT`], stdout captured,
//! trimmed and at most [`OUTPUT_LIMIT`]), its output recorded with the rows; a command declared
//! `key: true` has its output join every trial's key, so an upgraded package shows up in
//! `status --explain` instead of silently mixing results. A command that cannot start, exits
//! non-zero, prints too much or runs too long is an error naming it.

use crate::program::model::Provenance;
use std::io::Read;
use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// The longest a provenance command may run.
pub const TIMEOUT: Duration = Duration::from_secs(60);

/// The most a provenance command may print on stdout (64 KiB).
pub const OUTPUT_LIMIT: usize = 64 << 10;

/// How much of a failing command's stderr its error shows.
const STDERR_SHOWN: usize = 2048;

/// Run every command in `cwd`, in order: their trimmed outputs, or the index of the first that
/// failed and why.
pub fn run_all(commands: &[Provenance], cwd: &Path) -> Result<Vec<String>, (usize, String)> {
    commands.iter().enumerate().map(|(i, p)| run(&p.command, cwd, TIMEOUT).map_err(|e| (i, e))).collect()
}

/// Run one command in `cwd` within `timeout`: its stdout, trimmed, or what went wrong (naming
/// the command).
pub fn run(argv: &[String], cwd: &Path, timeout: Duration) -> Result<String, String> {
    let shown = shell_words(argv);
    let (program, args) = argv.split_first().ok_or("the provenance command is empty")?;
    let mut cmd = Command::new(program);
    cmd.args(args).current_dir(cwd).stdin(Stdio::null()).stdout(Stdio::piped()).stderr(Stdio::piped());
    own_group(&mut cmd);
    let mut child = cmd.spawn().map_err(|e| format!("provenance command `{shown}` cannot start: {e}"))?;
    let pid = child.id() as i32;
    let mut stdout = child.stdout.take().expect("piped");
    let mut stderr = child.stderr.take().expect("piped");
    // Read both pipes while waiting, so a command that fills one never blocks.
    let out = std::thread::spawn(move || {
        let mut buf = Vec::new();
        let r = (&mut stdout).take(OUTPUT_LIMIT as u64 + 1).read_to_end(&mut buf);
        r.map(|_| buf)
    });
    let err = std::thread::spawn(move || {
        let mut buf = Vec::new();
        let _ = stderr.read_to_end(&mut buf);
        buf
    });
    let start = Instant::now();
    let status = loop {
        match child.try_wait() {
            Ok(Some(status)) => break Some(status),
            Ok(None) if start.elapsed() >= timeout => break None,
            Ok(None) => std::thread::sleep(Duration::from_millis(5)),
            Err(e) => return Err(format!("provenance command `{shown}`: cannot wait for it: {e}")),
        }
    };
    // Whatever it left behind (and itself, on a timeout) ends with it. Its group outlives it only
    // while a member lives, so the id names no other group (pid reuse within these microseconds
    // aside).
    kill_group(pid);
    let _ = child.wait();
    let stdout = out.join().unwrap_or_else(|_| Ok(Vec::new()));
    let stderr = err.join().unwrap_or_default();
    let status = status.ok_or_else(|| {
        format!(
            "provenance command `{shown}` did not finish within {} s; it was stopped",
            timeout.as_secs_f64()
        )
    })?;
    let stdout = stdout.map_err(|e| format!("provenance command `{shown}`: cannot read its output: {e}"))?;
    // Past the limit its output is no longer read, so it may also have failed (SIGPIPE): the
    // limit is the reason.
    if stdout.len() > OUTPUT_LIMIT {
        return Err(format!(
            "provenance command `{shown}` printed more than {} KiB; record something shorter",
            OUTPUT_LIMIT >> 10
        ));
    }
    if !status.success() {
        let tail = tail(&stderr);
        let why = match status.code() {
            Some(c) => format!("exit code {c}"),
            None => "killed by a signal".to_string(),
        };
        let tail = if tail.is_empty() { String::new() } else { format!("; its stderr ends: {tail}") };
        return Err(format!("provenance command `{shown}` failed ({why}){tail}"));
    }
    Ok(String::from_utf8_lossy(&stdout).trim().to_string())
}

/// The last [`STDERR_SHOWN`] bytes of `bytes`, lossy UTF-8, trimmed.
fn tail(bytes: &[u8]) -> String {
    let from = bytes.len().saturating_sub(STDERR_SHOWN);
    String::from_utf8_lossy(&bytes[from..]).trim().to_string()
}

/// The command in its own process group (so a timeout ends all of it), ended with qsweep on
/// Linux (`PR_SET_PDEATHSIG`).
fn own_group(cmd: &mut Command) {
    use std::os::unix::process::CommandExt;
    cmd.process_group(0);
    #[cfg(target_os = "linux")]
    // SAFETY: prctl is async-signal-safe and touches no memory of the parent.
    unsafe {
        cmd.pre_exec(|| {
            libc::prctl(libc::PR_SET_PDEATHSIG, libc::SIGKILL);
            Ok(())
        });
    }
}

/// SIGKILL the process group `pgid` (gone already: nothing to do).
fn kill_group(pgid: i32) {
    // SAFETY: kill(2) with a negative pid signals a process group; it touches no memory.
    unsafe {
        libc::kill(-pgid, libc::SIGKILL);
    }
}

/// argv as a shell would need it typed, for messages (never run through a shell).
pub fn shell_words(argv: &[String]) -> String {
    argv.iter()
        .map(|a| {
            let plain =
                !a.is_empty() && a.chars().all(|c| c.is_ascii_alphanumeric() || "-_./=:,+@%".contains(c));
            if plain {
                a.clone()
            } else {
                format!("'{}'", a.replace('\'', "'\\''"))
            }
        })
        .collect::<Vec<_>>()
        .join(" ")
}

/// What a row records of the provenance: a JSON array of `{"command": [...], "key": bool,
/// "output": "..."}`, one per command in declared order.
pub fn record_json(commands: &[Provenance], outputs: &[String]) -> String {
    let entries: Vec<serde_json::Value> = commands
        .iter()
        .zip(outputs)
        .map(|(p, out)| serde_json::json!({ "command": p.command, "key": p.key, "output": out }))
        .collect();
    crate::program::model::canonical_json(&serde_json::Value::Array(entries))
}

/// The commands and outputs a row recorded ([`record_json`]); `None` when it is not that form.
pub fn parse_record(json: &str) -> Option<Vec<(Provenance, String)>> {
    let v: serde_json::Value = serde_json::from_str(json).ok()?;
    v.as_array()?
        .iter()
        .map(|e| {
            let command = e
                .get("command")?
                .as_array()?
                .iter()
                .map(|a| a.as_str().map(String::from))
                .collect::<Option<_>>()?;
            let key = e.get("key")?.as_bool()?;
            let output = e.get("output")?.as_str()?.to_string();
            Some((Provenance { command, key }, output))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn argv(a: &[&str]) -> Vec<String> {
        a.iter().map(|s| s.to_string()).collect()
    }

    #[test]
    fn output_is_captured_and_trimmed_in_the_directory_given() {
        let d = tempfile::tempdir().unwrap();
        std::fs::write(d.path().join("v.txt"), "1.2.3\n").unwrap();
        let out = run(&argv(&["sh", "-c", "echo; cat v.txt; echo '  '"]), d.path(), TIMEOUT).unwrap();
        assert_eq!(out, "1.2.3");
    }

    #[test]
    fn failures_name_the_command_and_why() {
        let d = tempfile::tempdir().unwrap();
        let e = run(&argv(&["sh", "-c", "echo boom >&2; exit 3"]), d.path(), TIMEOUT).unwrap_err();
        assert_eq!(
            e,
            "provenance command `sh -c 'echo boom >&2; exit 3'` failed (exit code 3); its stderr ends: boom"
        );
        let e = run(&argv(&["no-such-program-qsweep"]), d.path(), TIMEOUT).unwrap_err();
        assert!(e.starts_with("provenance command `no-such-program-qsweep` cannot start: "), "{e}");
        let e = run(&argv(&["sh", "-c", "head -c 70000 /dev/zero"]), d.path(), TIMEOUT).unwrap_err();
        assert!(e.contains("printed more than 64 KiB"), "{e}");
    }

    #[test]
    fn a_command_past_its_timeout_is_stopped_with_its_children() {
        let d = tempfile::tempdir().unwrap();
        let t = Instant::now();
        // The child `sleep` holds stdout open: it too must go for the call to return.
        let e = run(&argv(&["sh", "-c", "sleep 30 & sleep 30"]), d.path(), Duration::from_millis(300))
            .unwrap_err();
        assert!(e.contains("did not finish within 0.3 s"), "{e}");
        assert!(t.elapsed() < Duration::from_secs(10));
    }

    #[test]
    fn run_all_says_which_command_failed() {
        let d = tempfile::tempdir().unwrap();
        let cmds = vec![
            Provenance { command: argv(&["echo", "a"]), key: false },
            Provenance { command: argv(&["false"]), key: true },
        ];
        assert_eq!(run_all(&cmds, d.path()).unwrap_err().0, 1);
        assert_eq!(run_all(&cmds[..1], d.path()).unwrap(), ["a"]);
    }

    #[test]
    fn records_round_trip() {
        let cmds = vec![Provenance { command: argv(&["python3", "--version"]), key: true }];
        let json = record_json(&cmds, &["Python 3.12.1".to_string()]);
        assert_eq!(json, r#"[{"command":["python3","--version"],"key":true,"output":"Python 3.12.1"}]"#);
        assert_eq!(parse_record(&json).unwrap(), vec![(cmds[0].clone(), "Python 3.12.1".to_string())]);
        assert_eq!(parse_record("[]").unwrap(), vec![]);
        assert_eq!(parse_record("{}"), None);
    }
}
