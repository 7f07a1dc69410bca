//! Shared helpers: the binary under test, sandboxes with their own cache, JSON output.

use assert_cmd::Command;
use std::path::{Path, PathBuf};

/// The repository root (where `pipelines/` and `tests/fixtures/` live).
pub fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// The `qsweep` binary with no cache configured from the environment.
pub fn qsweep() -> Command {
    let mut c = Command::cargo_bin("qsweep").expect("binary builds");
    c.env_remove("QSWEEP_CACHE");
    c
}

/// A temporary working directory with its own cache and pipeline files.
pub struct Sandbox {
    /// Kept alive for the test's duration.
    pub dir: tempfile::TempDir,
}

impl Sandbox {
    /// A fresh sandbox.
    pub fn new() -> Self {
        Self { dir: tempfile::tempdir().expect("tempdir") }
    }

    /// Path inside the sandbox.
    pub fn path(&self, rel: &str) -> PathBuf {
        self.dir.path().join(rel)
    }

    /// The sandbox's cache directory.
    pub fn cache(&self) -> PathBuf {
        self.path("cache")
    }

    /// Copy a fixture pipeline into the sandbox; returns its path there.
    pub fn fixture(&self, name: &str) -> PathBuf {
        let text = std::fs::read_to_string(repo().join("tests/fixtures/pipelines").join(name)).unwrap();
        self.write(name, &text)
    }

    /// Write a file into the sandbox; returns its path.
    pub fn write(&self, name: &str, text: &str) -> PathBuf {
        let p = self.path(name);
        std::fs::write(&p, text).unwrap();
        p
    }

    /// `qsweep` run from inside the sandbox with `--cache` pointing at its cache.
    pub fn qsweep(&self, args: &[&str]) -> Command {
        let mut c = qsweep();
        c.current_dir(self.dir.path()).args(args).arg("--cache").arg(self.cache());
        c
    }

    /// `qsweep run PIPELINE --json ...`, asserting success; returns the summary.
    pub fn run_json(&self, pipeline: &Path, extra: &[&str]) -> serde_json::Value {
        let mut args = vec!["run", pipeline.to_str().unwrap(), "--json", "--no-report"];
        args.extend_from_slice(extra);
        let out = self.qsweep(&args).assert().success().get_output().stdout.clone();
        serde_json::from_slice(&out).expect("run --json prints JSON")
    }

    /// The cache's segment files, sorted (none when the cache does not exist yet).
    pub fn segment_paths(&self) -> Vec<PathBuf> {
        let Ok(dir) = std::fs::read_dir(self.cache()) else { return Vec::new() };
        let mut v: Vec<PathBuf> = dir
            .map(|e| e.unwrap().path())
            .filter(|p| p.file_name().unwrap().to_string_lossy().starts_with("seg-"))
            .collect();
        v.sort();
        v
    }

    /// Number of segment files in the cache.
    pub fn segments(&self) -> usize {
        self.segment_paths().len()
    }
}

/// Stdout of a successful command as text.
pub fn stdout(c: &mut Command) -> String {
    String::from_utf8(c.assert().success().get_output().stdout.clone()).unwrap()
}

/// Stderr of a command that must exit with `code`.
pub fn fails_with(c: &mut Command, code: i32) -> String {
    String::from_utf8(c.assert().code(code).get_output().stderr.clone()).unwrap()
}

/// A fluent end-to-end test of one `qsweep` invocation, modelled on just's `Test`: say what goes
/// into a fresh sandbox and on the command line, what exit code and output to expect, then `run`.
///
/// ```ignore
/// Test::new().pipeline("tiny.yaml").args(["report", "tiny.yaml"]).status(2).stderr_contains("does not exist").run();
/// ```
///
/// The command runs inside the sandbox with `QSWEEP_CACHE` pointing at the sandbox's `cache/`
/// (which does not exist until something creates it); the expected status defaults to 0.
#[must_use]
pub struct Test {
    sandbox: Sandbox,
    args: Vec<std::ffi::OsString>,
    status: i32,
    stdout_contains: Vec<String>,
    stderr_contains: Vec<String>,
    stderr_lacks: Vec<String>,
}

/// What a [`Test`] produced; `then` starts the next test in the same sandbox.
pub struct Done {
    /// The sandbox, with whatever the command left in it.
    pub sandbox: Sandbox,
    /// Standard output.
    pub stdout: String,
    /// Standard error.
    pub stderr: String,
}

impl Done {
    /// A new test in the same sandbox.
    pub fn then(self) -> Test {
        Test::with(self.sandbox)
    }
}

impl Test {
    /// A test in a fresh sandbox.
    pub fn new() -> Self {
        Self::with(Sandbox::new())
    }

    /// A test in an existing sandbox.
    pub fn with(sandbox: Sandbox) -> Self {
        Self {
            sandbox,
            args: Vec::new(),
            status: 0,
            stdout_contains: Vec::new(),
            stderr_contains: Vec::new(),
            stderr_lacks: vec!["panicked".into()],
        }
    }

    /// Copy a pipeline into the sandbox under its file name: from `tests/fixtures/pipelines/`,
    /// else from `pipelines/`.
    pub fn pipeline(self, name: &str) -> Self {
        let fixture = repo().join("tests/fixtures/pipelines").join(name);
        let path = if fixture.is_file() { fixture } else { repo().join("pipelines").join(name) };
        let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        self.file(name, &text)
    }

    /// Write a file into the sandbox, creating its folders.
    pub fn file(self, name: &str, text: &str) -> Self {
        if let Some(parent) = std::path::Path::new(name).parent() {
            std::fs::create_dir_all(self.sandbox.path(&parent.to_string_lossy())).unwrap();
        }
        self.sandbox.write(name, text);
        self
    }

    /// Append command-line arguments.
    pub fn args<I, S>(mut self, args: I) -> Self
    where
        I: IntoIterator<Item = S>,
        S: AsRef<std::ffi::OsStr>,
    {
        self.args.extend(args.into_iter().map(|a| a.as_ref().to_owned()));
        self
    }

    /// The exit code to expect (default 0).
    pub fn status(mut self, code: i32) -> Self {
        self.status = code;
        self
    }

    /// Expect standard output to contain `text`.
    pub fn stdout_contains(mut self, text: &str) -> Self {
        self.stdout_contains.push(text.into());
        self
    }

    /// Expect standard error to contain `text`.
    pub fn stderr_contains(mut self, text: &str) -> Self {
        self.stderr_contains.push(text.into());
        self
    }

    /// Expect standard error not to contain `text` (it never contains `panicked`).
    pub fn stderr_lacks(mut self, text: &str) -> Self {
        self.stderr_lacks.push(text.into());
        self
    }

    /// Run the command and check every expectation; panics with the command's output if one fails.
    pub fn run(self) -> Done {
        let mut c = qsweep();
        c.current_dir(self.sandbox.dir.path()).env("QSWEEP_CACHE", self.sandbox.cache()).args(&self.args);
        let out = c.output().expect("qsweep starts");
        let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
        let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
        let shown = || format!("qsweep {:?}\n--- stdout:\n{stdout}\n--- stderr:\n{stderr}", self.args);
        assert_eq!(out.status.code(), Some(self.status), "exit code of {}", shown());
        for t in &self.stdout_contains {
            assert!(stdout.contains(t.as_str()), "stdout lacks {t:?}: {}", shown());
        }
        for t in &self.stderr_contains {
            assert!(stderr.contains(t.as_str()), "stderr lacks {t:?}: {}", shown());
        }
        for t in &self.stderr_lacks {
            assert!(!stderr.contains(t.as_str()), "stderr contains {t:?}: {}", shown());
        }
        Done { sandbox: self.sandbox, stdout, stderr }
    }
}

/// A CSV file's rows as maps from header name to field (fields hold no commas in our tables
/// except quoted titles, which these helpers' callers do not read).
pub fn csv_rows(text: &str) -> Vec<std::collections::BTreeMap<String, String>> {
    let mut lines = text.lines();
    let header: Vec<String> = lines.next().unwrap_or_default().split(',').map(str::to_string).collect();
    lines.map(|l| header.iter().cloned().zip(l.split(',').map(str::to_string)).collect()).collect()
}
