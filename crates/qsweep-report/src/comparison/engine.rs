//! An engine pipeline (or one of its variants) as a side of `qsweep compare`: its plan replayed
//! against the cache as `qsweep report` replays it (a raced experiment's cells with the seeds
//! their race gave them), its trials' outcomes read as the report reads them, and each cell's
//! per-trial values of three metrics taken from the report's own view of them
//! ([`ReportData`], so a cell's `episodes` are exactly the values its `cells.parquet` row
//! summarizes):
//!
//! - `episodes` ([`EPISODES`], the default): the episodes Table III counts
//!   ([`qsweep_pipeline::analysis::episodes_counted`]): to the learning goal, at the cap when
//!   it was never reached;
//! - `converged`: 1 when the trial reached the goal, else 0 (its mean is the share converged);
//! - `total_steps`: the steps the trial ran, over all its episodes.
//!
//! A cell's params are [`super::cells::ENGINE_PARAMS`], then one per varied setting. The fresh
//! seeds of a `fresh:` block are no cell's own trials, so they take no part.

use super::cells::{
    count_value, experiment_value, resolution_value, CellSet, Sample, SetCell, ABSENT, ENGINE_PARAMS,
    EPISODES,
};
use crate::derive::report_data::{Outcomes, ReportData, Variables};
use qsweep_pipeline::cache::store::Store;
use qsweep_pipeline::cache::Key;
use qsweep_pipeline::declared::Target;
use qsweep_pipeline::plan::Plan;
use qsweep_pipeline::program::model::ParamValue;
use qsweep_pipeline::race::{read_cached, replay};
use std::collections::HashSet;

/// The engine's metrics, the default first.
pub const METRICS: [&str; 3] = [EPISODES, "converged", "total_steps"];

/// The cells of `plan` (one variant's, or a pipeline without variants), read from `store` (none:
/// no cache, every trial missing) after replaying the plan against it.
pub fn read(plan: Plan, store: Option<&Store>) -> anyhow::Result<CellSet> {
    let Some(store) = store else {
        return Ok(cells(
            &plan,
            &std::collections::HashMap::<Key, qsweep_pipeline::cache::TrialRecord>::new(),
        ));
    };
    let scan = qsweep_pipeline::run::scan(store)?;
    for (d, to) in &scan.quarantined {
        eprintln!("warning: damaged cache segment {d}; moved to {}", to.display());
    }
    let replayed = replay(plan, &scan.stored.keys, &mut read_cached(store, &scan.stored))?;
    let plan = replayed.plan();
    let wanted: HashSet<Key> =
        plan.experiments.iter().flat_map(|e| &e.cells).flat_map(|c| &c.trials).map(|t| t.key).collect();
    let outcomes = store.read_outcomes(&scan.stored, &wanted, false)?;
    Ok(cells(plan, &outcomes))
}

/// The names of the settings and physical parameters `plan`'s experiments vary, in first-seen
/// order: each is a param of every cell.
fn varied_settings(plan: &Plan) -> Vec<&'static str> {
    let mut out: Vec<&'static str> = Vec::new();
    for t in plan.experiments.iter().flat_map(|e| &e.axes).flat_map(|a| &a.targets) {
        if let Target::Setting(n) | Target::Param(n) = t {
            if !out.contains(n) {
                out.push(n);
            }
        }
    }
    out
}

/// The cells of `plan` with the outcomes `records` holds.
pub fn cells(plan: &Plan, records: &dyn Outcomes) -> CellSet {
    let data = ReportData::build_as(plan, records, None);
    let vars = Variables::engine();
    let settings = varied_settings(plan);
    let mut params: Vec<String> = ENGINE_PARAMS.iter().map(|s| s.to_string()).collect();
    params.extend(settings.iter().map(|s| s.to_string()));
    let mut out = Vec::new();
    for e in &data.experiments {
        let exp = e.exp;
        for c in &e.cells {
            let cell = c.cell;
            let res = &cell.config.repr.resolution;
            let mut values = vec![
                ParamValue::Str(exp.system.name().to_string()),
                ParamValue::Str(exp.repr.name().to_string()),
                ParamValue::Str(cell.algorithm.name().to_string()),
                experiment_value(&exp.id),
            ];
            values.extend(vars.resolution(exp.system, res).into_iter().map(count_value));
            values.push(ParamValue::Int(i64::from(cell.config.actions)));
            values.push(resolution_value(res));
            for s in &settings {
                let at = exp.axes.iter().position(|a| {
                    a.targets.iter().any(|t| matches!(t, Target::Setting(n) | Target::Param(n) if n == s))
                });
                values.push(at.map_or_else(
                    || ParamValue::Str(ABSENT.to_string()),
                    |i| ParamValue::Float(cell.coords[i]),
                ));
            }
            let mut h = blake3::Hasher::new();
            for t in &cell.trials {
                h.update(&t.key.0);
            }
            let metric = |f: &dyn Fn(&crate::derive::report_data::TrialData) -> f64| {
                Sample::Values(c.trials.iter().map(f).collect())
            };
            out.push(SetCell {
                params: values,
                identity: h.finalize().to_hex().to_string(),
                samples: vec![
                    metric(&|t| f64::from(t.counted)),
                    metric(&|t| if t.outcome.converged { 1.0 } else { 0.0 }),
                    metric(&|t| t.outcome.total_steps as f64),
                ],
            });
        }
    }
    CellSet {
        what: "engine pipeline",
        params,
        metrics: METRICS.iter().map(|s| s.to_string()).collect(),
        cells: out,
    }
}
