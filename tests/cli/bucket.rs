//! A cache in a bucket (issue 63), against a real S3 server: moto's, started on 127.0.0.1 on a
//! free port for each test (`.ci/run` and `scripts/test` install it into `.venv`). Without the
//! server the tests say so and pass, except with `CI=true`, where they fail.
//!
//! moto keeps its buckets in memory and accepts any credentials unless told to check them
//! (`INITIAL_NO_AUTH_ACTION_COUNT=0`, as the wrong-credentials test does); its conditional
//! create is checked then written, not atomic (docs/cache-in-a-bucket.md), so the two-runs test
//! asserts what holds on any server: each trial stored once, the rows identical.

use crate::helpers::{fails_with, qsweep, repo, stdout, Sandbox};
use qsweep_pipeline::cache::{Store, TrialRecord};
use std::io::{Read, Write};
use std::net::TcpStream;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

/// A moto S3 server of this test, killed when dropped.
struct Server {
    child: Child,
    port: u16,
}

/// The moto server executable: `$QSWEEP_MOTO_SERVER`, else `.venv/bin/moto_server`.
fn moto() -> Option<PathBuf> {
    let exe = std::env::var_os("QSWEEP_MOTO_SERVER")
        .map(PathBuf::from)
        .unwrap_or_else(|| repo().join(".venv/bin/moto_server"));
    exe.is_file().then_some(exe)
}

impl Server {
    /// Start a server (with `env` set), or `None` when moto is not installed outside CI.
    fn start(env: &[(&str, &str)]) -> Option<Self> {
        let Some(exe) = moto() else {
            assert!(
                std::env::var("CI").as_deref() != Ok("true"),
                "moto_server not found (.venv/bin/moto_server or QSWEEP_MOTO_SERVER): CI must run the bucket tests"
            );
            eprintln!("skipped: no moto_server (pip install 'moto[server]' into .venv)");
            return None;
        };
        let port = std::net::TcpListener::bind("127.0.0.1:0").unwrap().local_addr().unwrap().port();
        Some(Self::on(&exe, port, env))
    }

    fn on(exe: &Path, port: u16, env: &[(&str, &str)]) -> Self {
        let mut cmd = Command::new(exe);
        cmd.args(["-H", "127.0.0.1", "-p", &port.to_string()]).stdout(Stdio::null()).stderr(Stdio::null());
        for (k, v) in env {
            cmd.env(k, v);
        }
        let child = cmd.spawn().expect("moto_server starts");
        let server = Self { child, port };
        let start = Instant::now();
        while TcpStream::connect(("127.0.0.1", port)).is_err() {
            assert!(start.elapsed() < Duration::from_secs(30), "moto_server did not listen on {port}");
            std::thread::sleep(Duration::from_millis(100));
        }
        server
    }

    /// One plain HTTP request (moto takes unsigned ones); the status code.
    fn http(&self, method: &str, path: &str, body: &[u8]) -> u16 {
        let mut s = TcpStream::connect(("127.0.0.1", self.port)).unwrap();
        let head = format!(
            "{method} {path} HTTP/1.1\r\nHost: 127.0.0.1:{}\r\nContent-Length: {}\r\nConnection: close\r\n\r\n",
            self.port,
            body.len()
        );
        s.write_all(head.as_bytes()).unwrap();
        s.write_all(body).unwrap();
        let mut answer = String::new();
        let _ = s.read_to_string(&mut answer);
        answer.split_whitespace().nth(1).and_then(|c| c.parse().ok()).unwrap_or(0)
    }

    fn make_bucket(&self, name: &str) {
        assert_eq!(self.http("PUT", &format!("/{name}"), b""), 200, "bucket {name} made");
    }

    /// `qsweep` talking to this server, its bucket copies in `copies`.
    fn qsweep(&self, copies: &Path) -> assert_cmd::Command {
        let mut c = qsweep();
        c.envs(self.vars(copies));
        c
    }

    fn env(&self, c: &mut Command, copies: &Path) {
        c.envs(self.vars(copies));
    }

    /// The client's environment: this server, any keys, plain http, the copies in `copies`.
    fn vars(&self, copies: &Path) -> Vec<(String, String)> {
        [
            ("AWS_ENDPOINT_URL", format!("http://127.0.0.1:{}", self.port)),
            ("AWS_ALLOW_HTTP", "true".into()),
            ("AWS_ACCESS_KEY_ID", "test".into()),
            ("AWS_SECRET_ACCESS_KEY", "test".into()),
            ("AWS_REGION", "us-east-1".into()),
            ("QSWEEP_S3_RETRY_SECONDS", "20".into()),
            ("QSWEEP_BUCKET_COPIES", copies.display().to_string()),
        ]
        .into_iter()
        .map(|(k, v)| (k.to_string(), v))
        .collect()
    }
}

impl Drop for Server {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// The stored rows of the cache directory `dir`, sorted by key, their timings cleared (the only
/// fields that are not the trial's result).
fn rows(dir: &Path) -> Vec<TrialRecord> {
    let mut rows = Store::open(dir).unwrap().read_all().unwrap();
    for r in &mut rows {
        r.seconds = 0.0;
        r.cpu_seconds = None;
    }
    rows.sort_by_key(|r| r.key);
    rows
}

/// (rows, distinct keys) in the segments of `dir`.
fn rows_and_distinct(dir: &Path) -> (usize, usize) {
    let scan = Store::open(dir).unwrap().keys().unwrap();
    (scan.segments.iter().map(|(_, k)| k.len()).sum(), scan.keys.len())
}

fn quick() -> String {
    repo().join("pipelines/quick.yaml").display().to_string()
}

fn json(out: &str) -> serde_json::Value {
    serde_json::from_str(out.lines().last().unwrap()).unwrap()
}

#[test]
fn quick_yaml_in_a_bucket_stores_the_rows_a_local_cache_gets_and_a_rerun_computes_nothing() {
    let Some(server) = Server::start(&[]) else { return };
    server.make_bucket("qsweep-test");
    let sb = Sandbox::new();
    let copies = sb.path("copies");
    let url = "s3://qsweep-test/team/quick";
    let run = |copies: &Path, cache: &str| {
        json(&stdout(
            server
                .qsweep(copies)
                .args(["run", &quick(), "--json", "--formats", "md", "--cache", cache, "--out"])
                .arg(sb.path("r")),
        ))
    };
    let first = run(&copies, url);
    assert_eq!((first["executed"].as_u64(), first["cached"].as_u64()), (Some(144), Some(0)), "{first}");
    // Another machine (an empty copy) finds every trial in the bucket.
    let again = run(&sb.path("copies2"), url);
    assert_eq!((again["executed"].as_u64(), again["cached"].as_u64()), (Some(0), Some(144)), "{again}");
    // The rows are those a local cache gets.
    let local = sb.path("local");
    let _ = run(&copies, local.to_str().unwrap());
    let copy = copies.join("qsweep-test/team/quick");
    assert_eq!(rows(&copy), rows(&local));
    assert_eq!(rows_and_distinct(&sb.path("copies2/qsweep-test/team/quick")), (144, 144));
    // status, report, verify and gc on the bucket.
    let status = stdout(server.qsweep(&copies).args(["status", &quick(), "--cache", url]));
    assert!(status.contains("total: 144 trials, 144 cached, 0 missing") && status.contains(url), "{status}");
    let verify = stdout(server.qsweep(&copies).args(["verify", "--cache", url]));
    assert!(verify.contains("144"), "{verify}");
    let gc = stdout(server.qsweep(&copies).args(["gc", "--cache", url]));
    assert!(gc.contains("144"), "{gc}");
    let after = run(&sb.path("copies3"), url);
    assert_eq!(after["executed"].as_u64(), Some(0), "gc kept every row: {after}");
}

#[test]
fn two_runs_on_one_bucket_store_each_trial_once() {
    let Some(server) = Server::start(&[]) else { return };
    server.make_bucket("qsweep-two");
    let sb = Sandbox::new();
    let url = "s3://qsweep-two/c";
    let spawn = |copies: &str| {
        let mut c = Command::new(assert_cmd::cargo::cargo_bin("qsweep"));
        server.env(&mut c, &sb.path(copies));
        c.env_remove("QSWEEP_CACHE")
            .args([
                "run",
                &quick(),
                "--json",
                "--jobs",
                "1",
                "--batch-seconds",
                "0.5",
                "--formats",
                "md",
                "--cache",
                url,
            ])
            .arg("--out")
            .arg(sb.path(copies).join("report"))
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap()
    };
    let (a, b) = (spawn("a"), spawn("b"));
    let (a, b) = (a.wait_with_output().unwrap(), b.wait_with_output().unwrap());
    assert!(
        a.status.success() && b.status.success(),
        "{}\n{}",
        String::from_utf8_lossy(&a.stderr),
        String::from_utf8_lossy(&b.stderr)
    );
    let (ja, jb) = (json(&String::from_utf8_lossy(&a.stdout)), json(&String::from_utf8_lossy(&b.stdout)));
    let executed = ja["executed"].as_u64().unwrap() + jb["executed"].as_u64().unwrap();
    assert!(executed >= 144, "{ja}\n{jb}");
    // A third run computes nothing, and the bucket holds each trial's row; a trial computed
    // twice (moto's conditional create is not atomic) is stored identically and read once.
    let third = json(&stdout(
        server
            .qsweep(&sb.path("c"))
            .args(["run", &quick(), "--json", "--formats", "md", "--cache", url, "--out"])
            .arg(sb.path("r3")),
    ));
    assert_eq!(third["executed"].as_u64(), Some(0), "{third}");
    let (_, distinct) = rows_and_distinct(&sb.path("c/qsweep-two/c"));
    assert_eq!(distinct, 144);
    eprintln!("two runs executed {executed} trials for 144");
    assert!(executed <= 150, "leases kept the runs from computing many trials twice: {executed}");
}

#[test]
fn a_run_killed_mid_write_strands_nothing_and_the_next_run_finishes_it() {
    let Some(server) = Server::start(&[]) else { return };
    server.make_bucket("qsweep-kill");
    let sb = Sandbox::new();
    let url = "s3://qsweep-kill/c";
    let mut c = Command::new(assert_cmd::cargo::cargo_bin("qsweep"));
    server.env(&mut c, &sb.path("a"));
    let mut child = c
        .env_remove("QSWEEP_CACHE")
        .args(["run", &quick(), "--jobs", "1", "--batch-trials", "4", "--formats", "md", "--cache", url])
        .arg("--out")
        .arg(sb.path("ra"))
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    // Killed once it has stored a segment or two, in the middle of the next ones.
    let copy = sb.path("a/qsweep-kill/c");
    let start = Instant::now();
    while rows_and_distinct(&copy).1 < 8 {
        assert!(start.elapsed() < Duration::from_secs(60), "no segment stored");
        std::thread::sleep(Duration::from_millis(50));
    }
    child.kill().unwrap();
    child.wait().unwrap();
    let status = stdout(server.qsweep(&sb.path("b")).args(["status", &quick(), "--cache", url]));
    assert!(status.contains("total: 144 trials"), "{status}");
    // The next run takes the dead run's leases over (after at most the lease, 30 s) and finishes.
    // The bound only catches a run that waits on dead leases without end: its own trials and
    // report take most of a minute on a loaded 2-core machine (93 s once, beside a build).
    let start = Instant::now();
    let done = json(&stdout(
        server
            .qsweep(&sb.path("b"))
            .args(["run", &quick(), "--json", "--formats", "md", "--cache", url, "--out"])
            .arg(sb.path("rb")),
    ));
    assert!(start.elapsed() < Duration::from_secs(300), "waited {:?}", start.elapsed());
    let (executed, cached) = (done["executed"].as_u64().unwrap(), done["cached"].as_u64().unwrap());
    assert_eq!(executed + cached, 144, "{done}");
    assert!(cached >= 8, "what the killed run stored stays stored: {done}");
    assert_eq!(rows_and_distinct(&sb.path("b/qsweep-kill/c")).1, 144);
}

#[test]
fn a_server_that_stops_answering_mid_run_is_retried_and_one_that_dies_fails_the_run_naming_the_bucket() {
    let Some(server) = Server::start(&[]) else { return };
    server.make_bucket("qsweep-stall");
    let sb = Sandbox::new();
    let url = "s3://qsweep-stall/c";
    let spawn = |copies: &str, out: &str, url: &str| {
        let mut c = Command::new(assert_cmd::cargo::cargo_bin("qsweep"));
        server.env(&mut c, &sb.path(copies));
        c.env_remove("QSWEEP_CACHE")
            .env("QSWEEP_S3_RETRY_SECONDS", "8")
            .args([
                "run",
                &quick(),
                "--json",
                "--jobs",
                "1",
                "--batch-trials",
                "4",
                "--formats",
                "md",
                "--cache",
                url,
            ])
            .arg("--out")
            .arg(sb.path(out))
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap()
    };
    let wait_rows_of = |copies: &str, prefix: &str, n: usize| {
        let start = Instant::now();
        while rows_and_distinct(&sb.path(copies).join("qsweep-stall").join(prefix)).1 < n {
            assert!(start.elapsed() < Duration::from_secs(60), "no segment stored");
            std::thread::sleep(Duration::from_millis(50));
        }
    };
    // Frozen for 3 s (SIGSTOP): requests time out or wait, are retried, and the run finishes.
    let child = spawn("a", "ra", url);
    wait_rows_of("a", "c", 8);
    let pid = server.child.id().to_string();
    assert!(Command::new("kill").args(["-STOP", &pid]).status().unwrap().success());
    std::thread::sleep(Duration::from_secs(3));
    assert!(Command::new("kill").args(["-CONT", &pid]).status().unwrap().success());
    let out = child.wait_with_output().unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let check = json(&stdout(
        server
            .qsweep(&sb.path("c"))
            .args(["run", &quick(), "--json", "--formats", "md", "--cache", url, "--out"])
            .arg(sb.path("rc")),
    ));
    assert_eq!(check["executed"].as_u64(), Some(0), "nothing stored was lost: {check}");
    // Killed for good (moto keeps buckets in memory, so a restarted moto is an empty server):
    // the run fails within the retry time, naming the bucket; nothing half-written is listed.
    let child = spawn("d", "rd", "s3://qsweep-stall/d");
    wait_rows_of("d", "d", 4);
    let start = Instant::now();
    assert!(Command::new("kill").args(["-KILL", &pid]).status().unwrap().success());
    let out = child.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "{err}");
    assert!(err.contains("qsweep-stall"), "{err}");
    assert!(start.elapsed() < Duration::from_secs(120), "{:?}", start.elapsed());
}

#[test]
fn a_missing_bucket_missing_keys_and_refused_credentials_are_usage_errors_naming_the_bucket() {
    let Some(server) = Server::start(&[]) else { return };
    let sb = Sandbox::new();
    let err = fails_with(
        server.qsweep(&sb.path("c")).args(["run", &quick(), "--cache", "s3://no-such-bucket/x"]),
        2,
    );
    assert!(err.contains("the bucket `no-such-bucket` does not exist"), "{err}");
    let err = fails_with(
        server.qsweep(&sb.path("c")).env_remove("AWS_ACCESS_KEY_ID").args([
            "status",
            &quick(),
            "--cache",
            "s3://some-bucket/x",
        ]),
        2,
    );
    assert!(err.contains("no credentials for the bucket `some-bucket`"), "{err}");
    // A server that checks credentials (moto with its IAM checks on from the first request).
    let Some(strict) = Server::start(&[("INITIAL_NO_AUTH_ACTION_COUNT", "0")]) else { return };
    let err = fails_with(
        strict.qsweep(&sb.path("c")).args(["status", &quick(), "--cache", "s3://locked-bucket/x"]),
        2,
    );
    assert!(err.contains("the bucket `locked-bucket` refused these credentials"), "{err}");
}

#[test]
fn verify_finds_a_damaged_segment_in_a_bucket_and_moves_it_aside_there() {
    let Some(server) = Server::start(&[]) else { return };
    server.make_bucket("qsweep-verify");
    let sb = Sandbox::new();
    let url = "s3://qsweep-verify/c";
    stdout(
        server
            .qsweep(&sb.path("a"))
            .args(["run", &quick(), "--set", "seeds=1", "--formats", "md", "--cache", url, "--out"])
            .arg(sb.path("r")),
    );
    // A truncated upload under a segment's name (what a broken client could leave).
    let good = std::fs::read_dir(sb.path("a/qsweep-verify/c"))
        .unwrap()
        .flatten()
        .find(|e| e.file_name().to_string_lossy().starts_with("seg-"))
        .unwrap();
    let bytes = std::fs::read(good.path()).unwrap();
    assert_eq!(
        server.http("PUT", "/qsweep-verify/c/seg-0000truncated.parquet", &bytes[..bytes.len() / 2]),
        200
    );
    let out = server.qsweep(&sb.path("b")).args(["verify", "--cache", url]).output().unwrap();
    let said = format!("{}{}", String::from_utf8_lossy(&out.stdout), String::from_utf8_lossy(&out.stderr));
    assert_eq!(out.status.code(), Some(1), "{said}");
    assert!(
        said.contains("seg-0000truncated.parquet") && said.contains("s3://qsweep-verify/c/_quarantine/"),
        "{said}"
    );
    assert_eq!(
        server.http("GET", "/qsweep-verify/c/seg-0000truncated.parquet", b""),
        404,
        "moved out of the listing"
    );
    // The next verify, on a fresh copy, finds the cache whole.
    stdout(server.qsweep(&sb.path("c")).args(["verify", "--cache", url]));
}

#[test]
fn push_then_pull_moves_each_trial_once_and_again_moves_nothing() {
    let Some(server) = Server::start(&[]) else { return };
    server.make_bucket("qsweep-push");
    let sb = Sandbox::new();
    let local = sb.path("local");
    stdout(
        qsweep()
            .args(["run", &quick(), "--set", "seeds=1", "--formats", "md", "--out"])
            .arg(sb.path("r"))
            .arg("--cache")
            .arg(&local),
    );
    let url = "s3://qsweep-push/shared";
    let copies = sb.path("copies");
    let push = |dry: bool| {
        let mut c = server.qsweep(&copies);
        c.args(["cache", "push"]).arg(&local).arg(url);
        if dry {
            c.arg("--dry-run");
        }
        stdout(&mut c)
    };
    assert!(push(true).starts_with("would have pushed 72 trials"), "{}", push(true));
    let first = push(false);
    assert!(first.starts_with("pushed 72 trials to s3://qsweep-push/shared"), "{first}");
    let second = push(false);
    assert!(
        second.starts_with("pushed 0 trials") && second.contains("72 of the 72 trials were there already"),
        "{second}"
    );
    let pulled = sb.path("pulled");
    let out = stdout(server.qsweep(&sb.path("copies2")).args(["cache", "pull", url]).arg(&pulled));
    assert!(out.starts_with("pulled 72 trials"), "{out}");
    assert_eq!(rows(&pulled), rows(&local));
    let again = stdout(server.qsweep(&sb.path("copies2")).args(["cache", "pull", url]).arg(&pulled));
    assert!(again.starts_with("pulled 0 trials"), "{again}");
}

#[test]
fn a_program_pipeline_given_a_bucket_is_told_to_use_a_directory() {
    let Some(server) = Server::start(&[]) else { return };
    server.make_bucket("qsweep-programs");
    let sb = Sandbox::new();
    sb.write("prog.sh", "echo '{\"y\": 1}'\n");
    let p = sb.write(
        "p.yaml",
        "name: e\nseeds: 1\nprogram:\n  command: [sh, prog.sh]\n  inputs: [prog.sh]\n  metrics: { y: int }\n\
         params: { x: 1 }\nexperiments:\n  - { id: e, vary: { x: [1, 2] } }\n",
    );
    let err = fails_with(
        server.qsweep(&sb.path("c")).current_dir(sb.dir.path()).args([
            "run",
            p.to_str().unwrap(),
            "--cache",
            "s3://qsweep-programs/x",
        ]),
        2,
    );
    assert!(err.contains("a bucket holds the trials of engine pipelines only"), "{err}");
}

#[test]
fn slurm_given_a_bucket_passes_it_to_every_job_as_given() {
    let Some(server) = Server::start(&[]) else { return };
    server.make_bucket("qsweep-slurm");
    let sb = Sandbox::new();
    let script = stdout(server.qsweep(&sb.path("c")).args([
        "slurm",
        &quick(),
        "--array",
        "2",
        "--cache",
        "s3://qsweep-slurm/x",
    ]));
    assert!(script.contains("--cache s3://qsweep-slurm/x"), "{script}");
    assert!(!script.contains(&format!("{}/s3:", sb.dir.path().display())), "not made a path: {script}");
}
