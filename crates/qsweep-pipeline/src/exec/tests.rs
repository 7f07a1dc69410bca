//! Tests of execution: the same rows on any number of threads, in lockstep or alone, with or
//! without leases; the schedule's order; lockstep time shares; a failing sink stopping the run.

use super::*;
use crate::cache::leases::Leases;
use crate::cache::Key;
use qsweep_engine::env::SystemKind;
use qsweep_engine::Algorithm;
use std::sync::Arc;

fn jobs_for(configs: &[TrialConfig]) -> Vec<Job<'_>> {
    configs
        .iter()
        .flat_map(|c| (0..3).map(move |seed| Job { config: c, seed, key: Key::of(c, seed) }))
        .collect()
}

#[test]
fn results_are_identical_on_one_or_two_threads_in_lockstep_or_alone_and_batches_cover_every_job() {
    let mut configs = Vec::new();
    for (sys, res) in [(SystemKind::BallBeam, vec![3, 3]), (SystemKind::MountainCar, vec![4, 4])] {
        for repr in [ReprKind::Crisp, ReprKind::Fuzzy] {
            let mut c = TrialConfig::paper(sys, repr, Algorithm::QLambda, res.clone(), 3);
            c.limits.max_episodes = 30;
            configs.push(c);
        }
    }
    let jobs = jobs_for(&configs);
    let run = |threads, lockstep| {
        let opts = ExecOptions { jobs: threads, batch_trials: 4, lockstep, ..Default::default() };
        let mut got = Vec::new();
        let mut batches = 0;
        let mut events: Vec<Event> = Vec::new();
        let r = execute(
            &jobs,
            &opts,
            |b| {
                assert!(b.len() <= 4);
                batches += 1;
                got.extend(b.iter().cloned());
                Ok(())
            },
            &mut events,
        )
        .unwrap();
        assert_eq!(r.executed, jobs.len());
        // Started first, Done last, one Finished per trial, the flushes add up to the trials.
        assert_eq!(events.first(), Some(&Event::Started { trials: jobs.len() }));
        assert_eq!(events.last(), Some(&Event::Done { executed: jobs.len(), failed: 0 }));
        let finished = events.iter().filter(|e| matches!(e, Event::Finished { .. })).count();
        let flushed: usize =
            events.iter().map(|e| if let Event::Flushed { trials } = e { *trials } else { 0 }).sum();
        assert_eq!((finished, flushed), (jobs.len(), jobs.len()));
        assert!(batches >= jobs.len() / 4);
        got.sort_by_key(|r| r.key);
        got.into_iter().map(|r| (r.key, r.outcome)).collect::<Vec<_>>()
    };
    // Crisp trials in lockstep (interleaved with fuzzy ones that run alone) or all alone.
    let alone = run(1, false);
    assert_eq!(run(1, true), alone);
    assert_eq!(run(2, true), alone);
    assert_eq!(run(2, false), alone);
}

/// Regression: lockstep rows were charged their loop's time so far in proportion to their
/// steps, which over-counts (the crisp cells of `paper.yaml` summed to 10 % more CPU than the
/// process used). On one thread, the rows' seconds add up to at most the run's.
#[test]
fn lockstep_rows_charge_no_more_time_than_the_run_took() {
    let mut configs = Vec::new();
    for res in [vec![6, 6], vec![10, 10], vec![3, 8]] {
        let mut c = TrialConfig::paper(SystemKind::MountainCar, ReprKind::Crisp, Algorithm::Q0, res, 3);
        c.limits.max_episodes = 40;
        configs.push(c);
    }
    let jobs = jobs_for(&configs);
    let opts = ExecOptions { jobs: 1, lockstep: true, ..Default::default() };
    let mut rows = Vec::new();
    let start = Instant::now();
    let sink = |b: &[TrialRecord]| {
        rows.extend(b.iter().cloned());
        Ok(())
    };
    execute(&jobs, &opts, sink, &mut Vec::<Event>::new()).unwrap();
    let took = start.elapsed().as_secs_f64();
    assert_eq!(rows.len(), jobs.len());
    let charged: f64 = rows.iter().map(|r| r.seconds).sum();
    assert!(charged <= took, "rows charged {charged} s of a {took} s run");
    assert!(rows.iter().all(|r| r.seconds > 0.0), "every trial took some time");
    if let Some(cpu) = rows.iter().map(|r| r.cpu_seconds).sum::<Option<f64>>() {
        assert!(cpu <= took * 1.01 + 0.01, "rows charged {cpu} CPU s in a {took} s run on one thread");
    }
}

#[test]
fn trials_that_run_alone_go_first_then_each_lockstep_group_together_longest_first() {
    let mut configs = Vec::new();
    for sys in [SystemKind::MountainCar, SystemKind::BallBeam] {
        for alg in [Algorithm::Q0, Algorithm::QLambda] {
            // Fuzzy 5×5 without pruning runs alone (its windows hold every set); fuzzy 3×3 takes
            // the dense path, whose trials share loops.
            for (repr, sets, actions) in [
                (ReprKind::Crisp, 3, 3),
                (ReprKind::Fuzzy, 5, 3),
                (ReprKind::Crisp, 3, 9),
                (ReprKind::Fuzzy, 3, 4),
            ] {
                let mut c = TrialConfig::paper(sys, repr, alg, vec![sets, sets], actions);
                if sets == 5 {
                    c.repr.prune = 0.0;
                }
                configs.push(c);
            }
        }
    }
    let jobs = jobs_for(&configs);
    let order: Vec<&Job<'_>> = schedule(&jobs).into_iter().map(|j| &jobs[j]).collect();
    let groups: Vec<_> = order.iter().map(|j| lanes::group(j.config)).collect();
    let alone = groups.iter().take_while(|g| g.is_none()).count();
    assert_eq!(alone, jobs.iter().filter(|j| j.config.repr.resolution[0] == 5).count());
    // Each group (system × representation × algorithm) is one run of the order, its trials
    // longest first.
    let mut runs = groups.clone();
    runs.dedup();
    assert_eq!(runs.len(), 1 + 4 + 4, "{runs:?}");
    for w in order.windows(2) {
        if lanes::group(w[0].config) == lanes::group(w[1].config) {
            assert!(estimated_cost(w[0].config) >= estimated_cost(w[1].config));
        }
    }
    let mut sorted = schedule(&jobs);
    sorted.sort_unstable();
    assert_eq!(sorted, (0..jobs.len()).collect::<Vec<_>>(), "every job once");
}

#[test]
fn rows_are_the_same_with_leases_taken_in_batches_as_without_leases() {
    let mut configs = Vec::new();
    for repr in [ReprKind::Crisp, ReprKind::Fuzzy] {
        for actions in [2, 3] {
            let mut c = TrialConfig::paper(SystemKind::BallBeam, repr, Algorithm::Q0, vec![2, 3], actions);
            c.limits.max_episodes = 10;
            configs.push(c);
        }
    }
    // 12 trials on 1 thread: batches of 3 at first, then of 1.
    let jobs = jobs_for(&configs);
    let dir = tempfile::tempdir().unwrap();
    let store = crate::cache::Store::open(dir.path()).unwrap();
    let run = |leases: Option<Arc<Leases>>| {
        let opts = ExecOptions { jobs: 1, leases, ..Default::default() };
        let mut got: Vec<TrialRecord> = Vec::new();
        let sink = |b: &[TrialRecord]| {
            got.extend(b.iter().cloned());
            Ok(())
        };
        let r = execute(&jobs, &opts, sink, &mut Vec::<Event>::new()).unwrap();
        assert_eq!((r.executed, r.elsewhere), (jobs.len(), 0));
        got.sort_by_key(|r| r.key);
        // Everything but the timings, which no two runs share.
        got.into_iter()
            .map(|r| (r.key, r.engine_version, r.config_json(), r.seed, r.outcome))
            .collect::<Vec<_>>()
    };
    let leases = Leases::open(&store).unwrap();
    assert_eq!(run(Some(Arc::clone(&leases))), run(None));
    assert_eq!(leases.held(), 0, "every lease is released once its trial is stored");
}

#[test]
fn a_failing_sink_stops_the_run_and_reports_the_error() {
    let c = TrialConfig::paper(SystemKind::BallBeam, ReprKind::Crisp, Algorithm::Q0, vec![2, 2], 3);
    let cs = vec![c];
    let jobs = jobs_for(&cs);
    let opts = ExecOptions { jobs: 2, batch_trials: 1, ..Default::default() };
    let mut events: Vec<Event> = Vec::new();
    let err = execute(&jobs, &opts, |_| anyhow::bail!("disk full"), &mut events).unwrap_err();
    assert!(err.to_string().contains("disk full"));
    assert!(matches!(events.last(), Some(Event::Done { executed: 0, .. })), "{events:?}");
}
