//! The library without the CLI: a pipeline run in-process reports its events to the caller's
//! reporter (what `examples/library_run.rs` shows), and a rerun finds everything cached.

use crate::helpers::repo;
use qsweep::exec::{Event, ExecOptions};
use qsweep::pipeline::{run_trials, scan, Selection};

#[test]
fn a_library_user_runs_a_pipeline_and_reads_its_events() {
    let dir = tempfile::tempdir().unwrap();
    let loaded = qsweep::spec::load(&repo().join("tests/fixtures/pipelines/tiny.yaml"), &[]).unwrap();
    let plan = qsweep::plan::plan(&loaded, None).unwrap();
    let store = qsweep::cache::Store::open(&dir.path().join("cache")).unwrap();
    let sel = Selection { shard: None, force: false };
    let opts = ExecOptions { jobs: 2, batch_trials: 10, ..Default::default() };
    let mut events: Vec<Event> = Vec::new();
    let done = run_trials(&plan, &store, &scan(&store).unwrap().stored, sel, &opts, &mut events).unwrap();
    assert_eq!((done.exec.executed, done.cached), (56, 0));
    assert_eq!(events.first(), Some(&Event::Started { trials: 56 }));
    assert_eq!(events.last(), Some(&Event::Done { executed: 56, failed: 0 }));
    let mut keys: Vec<_> = events
        .iter()
        .filter_map(|e| if let Event::Finished { key, .. } = e { Some(*key) } else { None })
        .collect();
    keys.sort();
    keys.dedup();
    assert_eq!(keys.len(), 56, "one Finished per distinct trial");
    let stored: usize =
        events.iter().map(|e| if let Event::Flushed { trials } = e { *trials } else { 0 }).sum();
    assert_eq!(stored, 56);
    assert!(
        events.iter().filter(|e| matches!(e, Event::Flushed { .. })).count() >= 6,
        "batches of at most 10"
    );
    // Every finished key is now in the cache; a rerun runs nothing.
    let scanned = scan(&store).unwrap().stored;
    let mut again: Vec<Event> = Vec::new();
    let done = run_trials(&plan, &store, &scanned, sel, &opts, &mut again).unwrap();
    assert_eq!((done.exec.executed, done.cached), (0, 56));
    assert!(!again.iter().any(|e| matches!(e, Event::Finished { .. })));
}
