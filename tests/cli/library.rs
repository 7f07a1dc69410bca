//! The library without the CLI: a pipeline run in-process reports its events to the caller's
//! reporter (what `examples/library_run.rs` shows), and a rerun finds everything cached.

use crate::helpers::repo;
use qsweep_pipeline::exec::{Event, ExecOptions};
use qsweep_pipeline::run::{run_trials, scan, Selection};

#[test]
fn a_library_user_runs_a_pipeline_and_reads_its_events() {
    let dir = tempfile::tempdir().unwrap();
    let loaded =
        qsweep_pipeline::declared::load(&repo().join("tests/fixtures/pipelines/tiny.yaml"), &[]).unwrap();
    let plan = qsweep_pipeline::plan::plan(&loaded, None).unwrap();
    let store = qsweep_pipeline::cache::Store::open(&dir.path().join("cache")).unwrap();
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

/// Each cell's trials, race state and fresh trials: what a replay decides.
fn replayed_cells(
    p: &qsweep_pipeline::plan::Plan,
) -> Vec<(Vec<qsweep_pipeline::plan::PlannedTrial>, Option<bool>, Vec<qsweep_pipeline::plan::PlannedTrial>)> {
    p.experiments
        .iter()
        .flat_map(|e| &e.cells)
        .map(|c| (c.trials.clone(), c.contender, c.fresh.clone()))
        .collect()
}

/// Regression (issue 37): a no-op `qsweep run` hands its report the plan its first round replayed
/// instead of replaying it a second time; that plan must be exactly the one the report would
/// replay itself, and a run that stored trials hands nothing on (the cache changed).
#[test]
fn the_plan_a_no_op_run_hands_its_report_is_the_one_the_report_would_replay() {
    use qsweep_pipeline::race::{read_cached, replay};
    use qsweep_pipeline::run::run_trials_replayed;
    for fixture in ["fresh.yaml", "race.yaml"] {
        let dir = tempfile::tempdir().unwrap();
        let loaded =
            qsweep_pipeline::declared::load(&repo().join("tests/fixtures/pipelines").join(fixture), &[])
                .unwrap();
        let plan = qsweep_pipeline::plan::plan(&loaded, None).unwrap();
        let store = qsweep_pipeline::cache::Store::open(&dir.path().join("cache")).unwrap();
        let sel = Selection { shard: None, force: false };
        let opts = ExecOptions { jobs: 2, ..Default::default() };
        let first = scan(&store).unwrap().stored;
        let (done, handed) = run_trials_replayed(plan.clone(), &store, &first, sel, &opts, &mut ()).unwrap();
        let qsweep_pipeline::run::AfterRun::Planned(back) = handed else {
            panic!("{fixture}: trials ran, nothing is handed on")
        };
        // Each round replayed the plan in place and took it back: the plan as planned.
        assert_eq!(replayed_cells(&back), replayed_cells(&plan), "{fixture}");
        let scanned = scan(&store).unwrap().stored;
        let (again, handed) =
            run_trials_replayed(plan.clone(), &store, &scanned, sel, &opts, &mut ()).unwrap();
        assert_eq!(again.exec.executed, 0, "{fixture}");
        let qsweep_pipeline::run::AfterRun::Replayed(handed) = handed else {
            panic!("{fixture}: nothing ran: the replayed plan is handed on")
        };
        let own = replay(&plan, &scanned.keys, &mut read_cached(&store, &scanned)).unwrap();
        // Every trial of the replayed plan ran in the first call, each once.
        let distinct: std::collections::HashSet<_> = own.plan().trials().map(|(_, _, t)| t.key).collect();
        assert_eq!(done.exec.executed, distinct.len(), "{fixture}");
        assert_eq!(replayed_cells(handed.plan()), replayed_cells(own.plan()), "{fixture}");
        // It is the staged plan, replayed: the fresh seeds or the later rounds are in it.
        assert!(handed.plan().trial_count() > plan.trial_count(), "{fixture}");
        // And the report written from it is the report's own, byte for byte.
        let to = |out: &str| qsweep_report::ReportOptions {
            dir: dir.path().join(out),
            formats: Default::default(),
            force: false,
            rebuild: false,
        };
        qsweep_report::write_replayed(handed, &store, &scanned, &to("handed")).unwrap();
        qsweep_report::write(plan.clone(), &store, &scanned, &to("own")).unwrap();
        for name in ["table3.md", "table3.csv", "index.html", "memo.json", "manifest.json"] {
            let a = std::fs::read(dir.path().join("handed").join(name)).unwrap();
            let b = std::fs::read(dir.path().join("own").join(name)).unwrap();
            assert!(a == b, "{fixture}: {name} differs");
        }
    }
}
