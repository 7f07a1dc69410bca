//! The report judges a row on its fresh estimate: a plan whose best cell gets fresh seeds, raced
//! to the end against a store of planted outcomes (`qsweep_pipeline::testing`, as in
//! `qsweep_pipeline::fresh`'s own tests), then read by [`crate::derive::report_data::ReportData`].

use qsweep_engine::Algorithm;
use qsweep_pipeline::cache::Key;
use qsweep_pipeline::testing::{fresh_plan as plan, run_to_the_end};
use std::collections::HashMap;

#[test]
fn the_report_judges_the_row_on_the_fresh_estimate() {
    let (done, store, _) = run_to_the_end(&plan());
    let records: HashMap<Key, qsweep_pipeline::cache::rows::StoredTrial> = store
        .into_iter()
        .map(|(k, o)| {
            (k, qsweep_pipeline::cache::rows::StoredTrial { outcome: o, seconds: 0.0, cpu_seconds: None })
        })
        .collect();
    let data = crate::derive::report_data::ReportData::build(&done, &records);
    let e = &data.experiments[0];
    let best = e.best_of(Algorithm::Q0).unwrap().cell;
    let c = &e.cells[best];
    assert_eq!((c.trials.len(), c.fresh.len()), (5, 20));
    let est = c.estimate();
    assert!(est.fresh && est.n() == 20);
    assert_eq!(est.summary.mean, c.fresh_summary.as_ref().unwrap().mean);
    assert_ne!(est.summary.mean, c.summary.mean, "the selection estimate is kept apart");
    assert_eq!((data.trials_planned, data.trials_cached), (65, 65));
    // Every other cell is judged, as before, on its own trials.
    let other = &e.cells[(best + 1) % e.cells.len()];
    assert!(!other.estimate().fresh && other.fresh_summary.is_none());
}
