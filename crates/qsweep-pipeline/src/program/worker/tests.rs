//! The worker protocol end to end with a small Python worker, started directly (the library's way);
//! tests/cli/supervise.rs runs a worker through `qsweep __supervise`.

use super::*;
use crate::program::model::{Failure, MetricValue};
use crate::program::runner::tests::{gone_within, program};
use serde_json::json;
use std::sync::atomic::{AtomicBool, Ordering};

/// A worker that answers each line with its pid, `2 x`, the seed, its slot and how many files its
/// directory held; `mode` makes it crash, hang, print a bad line, print a blank line first, print
/// its result twice (in one write), or burn 0.2 s of CPU.
const WORKER: &str = r#"
import json, os, sys, time
d = os.environ["QSWEEP_TRIAL_DIR"]
for line in sys.stdin:
    cfg = json.loads(line)
    files = len(os.listdir(d))
    open(os.path.join(d, "scratch"), "w").write("x")
    mode = cfg["mode"]
    if mode == "crash":
        print("boom", file=sys.stderr)
        sys.exit(4)
    if mode == "hang":
        time.sleep(30)
    if mode == "bad":
        print("oops", flush=True)
        continue
    if mode == "blank":
        print("", flush=True)
    if mode == "busy":
        t = time.process_time()
        while time.process_time() - t < 0.2:
            pass
    out = json.dumps({"pid": os.getpid(), "y": cfg["x"] * 2, "seed": cfg["seed"],
                      "slot": int(os.environ["QSWEEP_WORKER"]), "files": files}) + "\n"
    sys.stdout.write(out * 2 if mode == "twice" else out)
    sys.stdout.flush()
"#;

fn worker(dir: &std::path::Path, opts: RunnerOptions) -> Worker {
    use MetricType::Int;
    let p = program(
        dir,
        "python3",
        WORKER,
        &[("pid", Int), ("y", Int), ("seed", Int), ("slot", Int), ("files", Int)],
    );
    Worker::new(&p, 5, opts)
}

/// The worker's answer to `x` in `mode`: its metrics (pid, y, seed, slot, files), or the result.
fn ask(w: &mut Worker, x: i64, mode: &str) -> Result<[i64; 5], TrialResult> {
    match w.run(&json!({"x": x, "mode": mode}), 40 + x as u64).0 {
        TrialResult::Ok(v) => Ok(v
            .iter()
            .map(|m| if let MetricValue::Int(i) = m { *i } else { panic!("{m:?}") })
            .collect::<Vec<_>>()
            .try_into()
            .unwrap()),
        other => Err(other),
    }
}

#[test]
fn three_trials_run_through_one_process() {
    let dir = tempfile::tempdir().unwrap();
    let mut w = worker(dir.path(), RunnerOptions::default());
    let a = ask(&mut w, 1, "ok").unwrap();
    let b = ask(&mut w, 2, "blank").unwrap();
    let c = ask(&mut w, 3, "ok").unwrap();
    assert_eq!(a[0], b[0], "one process");
    assert_eq!(b[0], c[0], "one process");
    // y = 2x, the seed in the line, QSWEEP_WORKER = the slot, the directory emptied before each.
    assert_eq!(
        [a[1..].to_vec(), b[1..].to_vec(), c[1..].to_vec()],
        [[2, 41, 5, 0], [4, 42, 5, 0], [6, 43, 5, 0]]
    );
    let pid = a[0] as i32;
    drop(w);
    assert!(gone_within(pid, Duration::from_secs(2)), "a dropped worker's process ends");
}

#[test]
fn a_worker_that_crashes_fails_its_trial_and_is_restarted_for_the_next() {
    let dir = tempfile::tempdir().unwrap();
    let mut w = worker(dir.path(), RunnerOptions::default());
    let first = ask(&mut w, 1, "ok").unwrap();
    let crashed = ask(&mut w, 2, "crash").unwrap_err();
    assert_eq!(
        crashed,
        TrialResult::Failed(Failure {
            exit_code: Some(4),
            reason: "exit 4".into(),
            stderr_tail: "boom\n".into()
        })
    );
    let third = ask(&mut w, 3, "ok").unwrap();
    assert_ne!(first[0], third[0], "a new process");
    assert_eq!(third[1..], [6, 43, 5, 0]);
}

#[test]
fn a_worker_that_times_out_is_killed_and_replaced() {
    let dir = tempfile::tempdir().unwrap();
    let opts = RunnerOptions { timeout: Some(Duration::from_secs(1)), ..Default::default() };
    let mut w = worker(dir.path(), opts);
    let first = ask(&mut w, 1, "ok").unwrap();
    let start = Instant::now();
    assert_eq!(ask(&mut w, 2, "hang").unwrap_err(), TrialResult::Unfinished("timed out after 1s".into()));
    assert!(start.elapsed() < Duration::from_secs(5), "{:?}", start.elapsed());
    assert!(gone_within(first[0] as i32, Duration::from_secs(2)));
    let third = ask(&mut w, 3, "ok").unwrap();
    assert_ne!(first[0], third[0]);
}

#[test]
fn a_bad_result_line_fails_its_trial_and_the_worker_is_replaced() {
    let dir = tempfile::tempdir().unwrap();
    let mut w = worker(dir.path(), RunnerOptions::default());
    let first = ask(&mut w, 1, "ok").unwrap();
    let TrialResult::Failed(f) = ask(&mut w, 2, "bad").unwrap_err() else { panic!() };
    assert_eq!(
        (f.exit_code, f.reason.as_str()),
        (None, "result line `oops`: not JSON (expected value at line 1 column 1)")
    );
    let third = ask(&mut w, 3, "ok").unwrap();
    assert_ne!(first[0], third[0], "its next line cannot be trusted to be the next trial's");
}

#[test]
fn a_worker_that_prints_more_than_asked_is_replaced_before_its_lines_are_taken_for_the_next_trial() {
    let dir = tempfile::tempdir().unwrap();
    let mut w = worker(dir.path(), RunnerOptions::default());
    let first = ask(&mut w, 1, "twice").unwrap();
    let second = ask(&mut w, 2, "ok").unwrap();
    assert_eq!(second[1], 4, "the second trial's own result, not the first's copy");
    assert_ne!(first[0], second[0], "a new process");
}

#[test]
fn an_interrupt_ends_a_workers_trial() {
    static STOP: AtomicBool = AtomicBool::new(false);
    let dir = tempfile::tempdir().unwrap();
    let mut w = worker(dir.path(), RunnerOptions { interrupt: &STOP, ..Default::default() });
    let first = ask(&mut w, 1, "ok").unwrap();
    let setter = std::thread::spawn(|| {
        std::thread::sleep(Duration::from_millis(300));
        STOP.store(true, Ordering::Relaxed);
    });
    assert_eq!(ask(&mut w, 2, "hang").unwrap_err(), TrialResult::Unfinished("interrupted".into()));
    setter.join().unwrap();
    assert!(gone_within(first[0] as i32, Duration::from_secs(2)));
}

#[cfg(target_os = "linux")]
#[test]
fn a_workers_cpu_time_is_measured_per_trial() {
    let dir = tempfile::tempdir().unwrap();
    let mut w = worker(dir.path(), RunnerOptions::default());
    ask(&mut w, 1, "ok").unwrap();
    let (r, timing) = w.run(&json!({"x": 2, "mode": "busy"}), 1);
    assert!(matches!(r, TrialResult::Ok(_)), "{r:?}");
    let cpu = timing.cpu.unwrap();
    assert!(cpu >= Duration::from_millis(190) && cpu < Duration::from_secs(5), "{cpu:?}");
    let (_, quick) = w.run(&json!({"x": 3, "mode": "ok"}), 1);
    assert!(quick.cpu.unwrap() < Duration::from_millis(150), "only this trial's time: {quick:?}");
}

#[test]
fn a_worker_may_be_handed_to_another_thread() {
    fn send<T: Send>(_: &T) {}
    let dir = tempfile::tempdir().unwrap();
    let mut w = worker(dir.path(), RunnerOptions::default());
    send(&w);
    let pid = ask(&mut w, 1, "ok").unwrap()[0];
    let again = std::thread::spawn(move || ask(&mut w, 2, "ok").unwrap()[0]).join().unwrap();
    assert_eq!(pid, again, "the same process, driven from another thread");
}
