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
