//! Pipeline overhead benchmark (`cargo bench --bench pipeline`): planning and key scans on the
//! paper grid with a warm cache, and the share of a real run spent outside the trials.
//!
//! Targets: planning, `status` and a no-op `run` each under 1 s on the full paper grid with all
//! of its variants (8 variants of the paper, 79,560 distinct trials) and a warm cache; the report
//! for that grid (every variant's report and the comparison) measured; planning + hashing +
//! storing under 1% of trial compute on the quick pipeline, and so leasing the trials in the
//! cache, in batches (what lets concurrent runs share it, `docs/sharing-a-cache.md`); the real
//! report of `paper.yaml` from the committed cache (every variant, real trials): the no-op `run`
//! (≤ 1 s, ≤ 1.3× the CPU of `status`, ≤ 120 MB) and the report recomputed with and without the
//! statistics' memo; the paper race (`paper-race.yaml`) against `max_seeds` seeds in every cell,
//! in trials and in simulated steps (target: at most 25 % of the trials).

use qsweep_engine::{Outcome, StopReason};
use qsweep_pipeline::cache::{Store, TrialRecord};
use qsweep_pipeline::race::{read_cached, replay};
use std::path::Path;
use std::process::Command;
use std::time::Instant;

fn qsweep(args: &[&str], cache: &Path) -> (f64, String) {
    let start = Instant::now();
    let out = Command::new(env!("CARGO_BIN_EXE_qsweep"))
        .args(args)
        .arg("--cache")
        .arg(cache)
        .output()
        .expect("qsweep runs");
    let secs = start.elapsed().as_secs_f64();
    assert!(out.status.success(), "{args:?}: {}", String::from_utf8_lossy(&out.stderr));
    (secs, String::from_utf8_lossy(&out.stdout).into_owned())
}

/// One run of `qsweep args` in `dir`: wall seconds, CPU seconds (user + system), peak RSS (MB)
/// and its report line (else its last), from the child's own rusage (`wait4`), so that neither other
/// load nor earlier children count.
// The child is reaped by wait4 (for its own rusage), which clippy cannot see.
#[allow(clippy::zombie_processes)]
fn measured(dir: &Path, args: &[&str]) -> (f64, f64, f64, String) {
    use std::io::Read;
    let start = Instant::now();
    let mut child = Command::new(env!("CARGO_BIN_EXE_qsweep"))
        .current_dir(dir)
        .args(args)
        .stdout(std::process::Stdio::piped())
        .spawn()
        .expect("qsweep runs");
    let mut said = String::new();
    child.stdout.take().expect("piped").read_to_string(&mut said).expect("stdout");
    let mut status = 0;
    // SAFETY: wait4 only writes the status and the struct it is given, for our own child.
    let mut u: libc::rusage = unsafe { std::mem::zeroed() };
    let pid = unsafe { libc::wait4(child.id() as libc::pid_t, &mut status, 0, &mut u) };
    let wall = start.elapsed().as_secs_f64();
    assert!(pid > 0 && libc::WIFEXITED(status) && libc::WEXITSTATUS(status) == 0, "{args:?} failed");
    let secs = |t: libc::timeval| t.tv_sec as f64 + t.tv_usec as f64 * 1e-6;
    // The report line, else the last one.
    let line =
        said.lines().find(|l| l.starts_with("report:")).or(said.lines().last()).unwrap_or("").to_string();
    (wall, secs(u.ru_utime) + secs(u.ru_stime), u.ru_maxrss as f64 / 1024.0, line)
}

/// `paper.yaml` on the committed cache and reports: the no-op run against `status` (issue 37's
/// targets: ≤ 1 s wall, ≤ 1.3× status's CPU, ≤ 120 MB), then the report recomputed into a new
/// folder with every statistic computed (`--rebuild`) and with every statistic in the memo.
fn committed_cache_figures(root: &Path, paper: &Path, cache: &Path) {
    // Relative, as the README writes it: the pages name the pipeline's path.
    let p = paper.strip_prefix(root).unwrap_or(paper).to_str().unwrap();
    let c = cache.to_str().unwrap();
    let show = |what: &str, (wall, cpu, rss, _): &(f64, f64, f64, String)| {
        println!("{what}: {wall:.2} s wall, {cpu:.2} s CPU, peak RSS {rss:.0} MB");
    };
    let status = measured(root, &["status", p, "--cache", c]);
    show("status paper.yaml (committed cache)", &status);
    let noop = measured(root, &["run", p, "--cache", c]);
    assert!(noop.3.contains("files: 0 rewritten"), "the no-op run rewrote files: {}", noop.3);
    show("no-op run paper.yaml (committed cache and reports; targets ≤ 1 s, ≤ 120 MB)", &noop);
    println!("no-op run / status, CPU: {:.2} (target ≤ 1.3)", noop.1 / status.1);
    let out = tempfile::tempdir().unwrap();
    let dir = |name: &str| out.path().join(name).to_str().unwrap().to_string();
    let (a, b) = (dir("rebuilt"), dir("memo"));
    let rebuild = measured(root, &["report", p, "--cache", c, "--rebuild", "--out", &a]);
    show("report paper.yaml into a new folder, --rebuild (every statistic computed)", &rebuild);
    let memo = measured(root, &["report", p, "--cache", c, "--out", &b]);
    assert!(memo.3.contains("intervals: 0 computed"), "{}", memo.3);
    show("report paper.yaml into a new folder, every statistic from the memo", &memo);
    println!("with the memo / --rebuild, CPU: {:.2}", memo.1 / rebuild.1);
    changed_pipelines(paper, cache, &root.join("reports/paper"));
}

/// Two changes to `paper.yaml` whose trials are all cached, each reported into a copy of the
/// committed report and cache, from a folder where the pipeline is `pipelines/paper.yaml` (as the
/// pages name it): one variant's `set` changed (gym-v1's Cart-Pole goal set to gym-v0's: that
/// variant's cells change, issue 37's "≤ 2 s"), and a 20th variant added (gym-v0's settings under
/// another id), against that variant's report alone (`--variant`; the target: ≤ 1 s more).
fn changed_pipelines(paper: &Path, cache: &Path, report: &Path) {
    let tmp = tempfile::tempdir().unwrap();
    let copy = |from: &Path, to: &Path| {
        let _ = std::fs::remove_dir_all(to);
        let ok = Command::new("cp").arg("-a").arg(from).arg(to).status().is_ok_and(|s| s.success());
        assert!(ok, "cp -a {} {}", from.display(), to.display());
    };
    let text = std::fs::read_to_string(paper).unwrap();
    std::fs::create_dir_all(tmp.path().join("pipelines")).unwrap();
    let (c, r) = (tmp.path().join("cache"), tmp.path().join("report"));
    copy(cache, &c);
    let c = c.to_str().unwrap();
    let run = |yaml: String, extra: &[&str]| {
        std::fs::write(tmp.path().join("pipelines/paper.yaml"), yaml).unwrap();
        copy(report, &r);
        let mut args = vec!["report", "pipelines/paper.yaml", "--cache", c, "--out", "report"];
        args.extend(extra);
        measured(tmp.path(), &args)
    };
    let v1 = "  - id: gym-v1\n    title: \"Gymnasium TimeLimits: CartPole-v1 500, MountainCar-v0 200\"\n    set:\n      \
              systems.cart-pole.success.steps: 500";
    assert!(text.contains(v1), "paper.yaml's gym-v1 variant is not as this benchmark expects");
    let changed = run(text.replace(v1, &v1.replace("steps: 500", "steps: 200")), &[]);
    println!(
        "one variant's set changed (gym-v1 as gym-v0), trials cached: the report {:.2} s wall, {:.2} s CPU \
         (target ≤ 2 s): {}",
        changed.0, changed.1, changed.3
    );
    let added = "  - id: gym-v0-again\n    title: \"gym-v0 under another id\"\n    set:\n      \
                   systems.cart-pole.success.steps: 200\n      systems.mountain-car.success.within: 200\n      \
                   systems.mountain-car.success.max_episode_steps: 200\n";
    let all = run(format!("{text}{added}"), &[]);
    let alone = run(format!("{text}{added}"), &["--variant", "gym-v0-again"]);
    println!(
        "a 20th variant, trials cached: the report {:.2} s wall ({:.2} s CPU); that variant alone {:.2} s wall \
         ({:.2} s CPU); {:.2} s more (target ≤ 1 s)",
        all.0,
        all.1,
        alone.0,
        alone.1,
        all.0 - alone.0
    );
}

fn main() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let paper = root.join("pipelines/paper.yaml");
    let quick = root.join("pipelines/quick.yaml");

    // The real pipeline on the committed cache first: the README's main command with nothing to
    // do, against `status` of the same plan, then the report recomputed with and without the
    // statistics' memo.
    let cache = root.join("cache");
    if cache.is_dir() {
        committed_cache_figures(root, &paper, &cache);
    }

    if cache.is_dir() {
        race_cost(&root.join("pipelines/paper-race.yaml"), &cache);
    }

    // Plan the paper grid in-process.
    let start = Instant::now();
    let loaded = qsweep_pipeline::declared::load(&paper, &[]).unwrap();
    let plan = qsweep_pipeline::plan::plan(&loaded, None).unwrap();
    let plan_secs = start.elapsed().as_secs_f64();
    let unique = qsweep_pipeline::exec::jobs(&plan);
    println!(
        "plan paper.yaml ({} variants): {} distinct trials in {:.3} s (target < 1 s)",
        plan.variants.len(),
        unique.len(),
        plan_secs
    );

    // A warm cache: one synthetic row per trial, in segments of 500 (what --batch-trials writes).
    let dir = tempfile::tempdir().unwrap();
    let store = Store::open(dir.path()).unwrap();
    let synthetic = |jobs: &[qsweep_pipeline::exec::Job<'_>]| -> Vec<TrialRecord> {
        jobs.iter()
            .map(|t| {
                let outcome = Outcome {
                    converged: true,
                    episodes_to_goal: Some(20),
                    episodes: 20,
                    total_steps: 20 * 500,
                    stop: StopReason::Goal,
                    failure: None,
                    episode_lengths: vec![500; 20],
                };
                TrialRecord::new(t.config.clone(), t.seed, outcome, 0.1)
            })
            .collect()
    };
    let mut records = synthetic(&unique);
    let start = Instant::now();
    for chunk in records.chunks(500) {
        store.write_segment(chunk).unwrap();
    }
    // The fresh-seed stage is planned from the grid's stored outcomes: replay it and store its
    // trials too, so that the no-op run below has nothing to run.
    let scan = store.keys().unwrap();
    let staged = replay(&plan, &scan.keys, &mut read_cached(&store, &scan)).unwrap().into_plan();
    let grid: std::collections::HashSet<_> = unique.iter().map(|t| t.key).collect();
    let fresh: Vec<_> =
        qsweep_pipeline::exec::jobs(&staged).into_iter().filter(|t| !grid.contains(&t.key)).collect();
    let fresh_records = synthetic(&fresh);
    for chunk in fresh_records.chunks(500) {
        store.write_segment(chunk).unwrap();
    }
    records.extend(fresh_records);
    println!(
        "store {} rows in {} segments: {:.3} s",
        records.len(),
        records.len().div_ceil(500),
        start.elapsed().as_secs_f64()
    );

    let p = paper.to_str().unwrap();
    let (status_secs, _) = qsweep(&["status", p], dir.path());
    let (noop_secs, out) = qsweep(&["run", p, "--no-report", "--quiet", "--json"], dir.path());
    assert!(out.contains("\"executed\":0"), "{out}");
    println!("status paper.yaml, warm cache: {status_secs:.3} s (target < 1 s)");
    println!("no-op run paper.yaml, warm cache: {noop_secs:.3} s (target < 1 s)");
    let out_dir = dir.path().join("report");
    let (report_secs, _) = qsweep(&["report", p, "--quiet", "--out", out_dir.to_str().unwrap()], dir.path());
    println!("report paper.yaml ({} planned trials): {report_secs:.3} s", plan.trial_count());

    // Overhead on the quick pipeline, one thread: wall time minus the trials' own time.
    let qdir = tempfile::tempdir().unwrap();
    let (wall, _) =
        qsweep(&["run", quick.to_str().unwrap(), "--no-report", "--quiet", "--jobs", "1"], qdir.path());
    let trial_secs: f64 =
        Store::open(qdir.path()).unwrap().read_all().unwrap().iter().map(|r| r.seconds).sum();
    let overhead = (wall - trial_secs).max(0.0);
    println!(
        "quick.yaml --jobs 1: {wall:.2} s wall, {trial_secs:.2} s in trials, overhead {overhead:.3} s = {:.2}% of trial compute (target < 1%)",
        100.0 * overhead / trial_secs
    );
    lease_overhead(&Store::open(qdir.path()).unwrap().read_all().unwrap());
}

/// What leasing costs per trial (make the lease, check the trial is not stored meanwhile,
/// release it once stored, as a run does), against the CPU time of `records`' trials: in batches
/// of one (a lease file per trial) up to 32, a run's batches being at most
/// [`qsweep_pipeline::exec::leased::MAX_BATCH`].
fn lease_overhead(records: &[TrialRecord]) {
    use qsweep_pipeline::cache::leases::{Leases, Take};
    use qsweep_pipeline::exec::leased::MAX_BATCH;
    let trial_cpu: f64 = records.iter().map(|r| r.cpu_seconds.unwrap_or(r.seconds)).sum();
    let per_trial_cpu = trial_cpu / records.len() as f64;
    let dir = tempfile::tempdir().unwrap();
    let store = Store::open(dir.path()).unwrap();
    let leases = Leases::open(&store).unwrap();
    let keys: Vec<_> = records.iter().map(|r| r.key).collect();
    let rounds = 20;
    for batch in [1, 4, 8, MAX_BATCH, 32] {
        let start = Instant::now();
        for _ in 0..rounds {
            for chunk in keys.chunks(batch) {
                for take in leases.try_take_batch(chunk) {
                    assert_eq!(take.unwrap(), Take::Taken);
                }
            }
            leases.heartbeat();
            leases.release(&keys);
        }
        let per_trial = start.elapsed().as_secs_f64() / (rounds * keys.len()) as f64;
        let run = if batch == MAX_BATCH { ", a run's batch" } else { "" };
        println!(
            "leases in batches of {batch}{run}: {:.1} µs per trial (lease, stored check, heartbeat, release) = {:.3}% of quick.yaml's mean trial CPU {:.1} ms (target ≤ 1%)",
            per_trial * 1e6,
            100.0 * per_trial / per_trial_cpu,
            per_trial_cpu * 1e3
        );
    }
}

/// What the paper race cost, from the committed cache: its trials against `max_seeds` seeds in
/// every cell, and its simulated steps (load-independent work) against every cell's mean steps
/// per trial times `max_seeds`.
fn race_cost(pipeline: &Path, cache: &Path) {
    let start = Instant::now();
    let loaded = qsweep_pipeline::declared::load(pipeline, &[]).unwrap();
    let plan = qsweep_pipeline::plan::plan(&loaded, None).unwrap();
    let store = Store::open(cache).unwrap();
    let scan = store.keys().unwrap();
    let raced = replay(plan, &scan.keys, &mut read_cached(&store, &scan)).unwrap();
    let secs = start.elapsed().as_secs_f64();
    let wanted = raced.plan().trials().map(|(_, _, t)| t.key).collect();
    let outcomes = store.read_outcomes(&scan, &wanted, false).unwrap();
    let (mut trials, mut all, mut steps, mut all_steps) = (0usize, 0usize, 0f64, 0f64);
    for e in &raced.plan().experiments {
        let most = e.race.map_or(0, |r| r.max_seeds as usize);
        for c in &e.cells {
            let s: Vec<f64> = c
                .trials
                .iter()
                .filter_map(|t| outcomes.get(&t.key))
                .map(|o| o.outcome.total_steps as f64)
                .collect();
            trials += c.trials.len();
            all += most.max(c.trials.len());
            steps += s.iter().sum::<f64>();
            all_steps += s.iter().sum::<f64>() / s.len().max(1) as f64 * most.max(c.trials.len()) as f64;
        }
    }
    let finished = raced.heats().iter().filter(|h| h.finished).count();
    println!(
        "race paper-race.yaml from the committed cache ({finished} of {} heatmaps finished, resolved in {secs:.2} s): \
         {trials} trials = {:.1}% of the {all} with max_seeds in every cell (target ≤ 25%); \
         {:.3e} simulated steps = {:.1}% of the {:.3e} those would take",
        raced.heats().len(),
        100.0 * trials as f64 / all as f64,
        steps,
        100.0 * steps / all_steps,
        all_steps
    );
}
