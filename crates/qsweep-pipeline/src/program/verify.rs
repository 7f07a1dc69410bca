//! Checking program rows like `git fsck` (`qsweep verify`), and recomputing a sample of a program
//! pipeline's stored trials in fresh processes (`qsweep verify PIPELINE --recompute N`).
//!
//! A program segment is damaged when it cannot be read as Parquet, lacks the `key` column or the
//! program marker (`qsweep.program_rows`), has columns that make no program schema or another
//! schema than its folder's, holds a row that does not decode, or a row whose command, inputs,
//! keyed provenance, params and seed no longer hash to its key (bit rot, a hand-edited file).
//! Damaged segments are moved aside into the folder's `_quarantine/` by the caller, as the
//! engine's are, so their trials run again.
//!
//! Recomputing reruns each sampled trial by the process protocol, one fresh process per trial
//! (whatever the pipeline's protocol: a worker that leaks state from one trial to the next shows
//! up), and compares every metric exactly (floats bit for bit) with the stored row. A program that
//! reads the clock, or draws randomness that is not from its seed, differs.

use super::exec::jobs;
use super::folders::{list, schema_from_arrow};
use super::key::Identity;
use super::model::{MetricValue, ParamValue, ProgramPlan, TrialResult};
use super::provenance::parse_record;
use super::rows::{read_segment, RowSchema};
use super::runner::{run_process, RunnerOptions, TrialEnv};
use super::stored::rows;
use crate::cache::store::{Damaged, KeySet};
use crate::cache::Key;
use parquet::arrow::arrow_reader::ParquetRecordBatchReaderBuilder;
use std::collections::HashSet;
use std::path::Path;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;

/// What [`check`] found in the program folders of a cache.
#[derive(Debug, Default)]
pub struct FoldersReport {
    /// Program folders.
    pub folders: usize,
    /// Segments checked.
    pub segments: usize,
    /// Rows in intact segments.
    pub rows: usize,
    /// Distinct keys in intact segments.
    pub distinct: usize,
    /// Damaged segments and why.
    pub damaged: Vec<Damaged>,
}

/// Read every segment of every program folder of the cache at `cache` in full and re-hash every
/// row (see the module documentation).
pub fn check(cache: &Path) -> anyhow::Result<FoldersReport> {
    let mut report = FoldersReport::default();
    let mut keys = HashSet::new();
    for folder in list(cache)? {
        report.folders += 1;
        for path in folder.segments()? {
            // A segment gone since the listing (gc compacted it) is not damage.
            if !path.exists() {
                continue;
            }
            report.segments += 1;
            match check_segment(&path, &folder.id) {
                Ok(found) => {
                    report.rows += found.len();
                    keys.extend(found);
                }
                Err(_) if !path.exists() => {}
                Err(e) => report.damaged.push(Damaged { path, error: format!("{e:#}") }),
            }
        }
    }
    report.distinct = keys.len();
    Ok(report)
}

/// The keys of the intact segment at `path` in the folder of schema `id`, or why it is damaged.
fn check_segment(path: &Path, id: &str) -> anyhow::Result<Vec<Key>> {
    let builder = ParquetRecordBatchReaderBuilder::try_new(std::fs::File::open(path)?)?;
    let key =
        builder.schema().field_with_name("key").map_err(|_| anyhow::anyhow!("column `key` is missing"))?;
    anyhow::ensure!(
        *key.data_type() == arrow::datatypes::DataType::Utf8,
        "column `key` has type {}, expected Utf8",
        key.data_type()
    );
    let schema = schema_from_arrow(builder.schema())?;
    anyhow::ensure!(schema.id() == id, "rows of schema {} in the folder of schema {id}", schema.id());
    let rows = read_segment(path, &schema, &|_| true)?;
    for (i, r) in rows.iter().enumerate() {
        let keyed = parse_record(&r.provenance_json)
            .ok_or_else(|| anyhow::anyhow!("row {i}: its provenance is not a provenance record"))?;
        let keyed: Vec<serde_json::Value> =
            keyed.into_iter().filter(|(p, _)| p.key).map(|(_, out)| serde_json::Value::String(out)).collect();
        let identity = Identity {
            command_json: r.command_json.clone(),
            inputs_json: r.inputs_json.clone(),
            provenance_json: r.provenance_json.clone(),
            keyed_provenance_json: super::model::canonical_json(&serde_json::Value::Array(keyed)),
        };
        anyhow::ensure!(
            identity.key(&schema.params, &r.params, r.seed) == r.key,
            "row {i}: its command, inputs, provenance, params and seed do not hash to its key"
        );
    }
    Ok(rows.into_iter().map(|r| r.key).collect())
}

/// What [`recompute`] found.
#[derive(Debug, Default)]
pub struct Recomputed {
    /// The plan's distinct trials stored as succeeded (the population drawn from).
    pub eligible: usize,
    /// Trials rerun.
    pub checked: usize,
    /// The rerun trials whose metrics differ from the stored row, in key order.
    pub differing: Vec<Differs>,
}

/// A stored trial its rerun does not reproduce.
#[derive(Debug, Clone, PartialEq)]
pub struct Differs {
    /// Its key.
    pub key: Key,
    /// Its seed.
    pub seed: u64,
    /// Its params, by name.
    pub params: Vec<(String, ParamValue)>,
    /// What differs: `metric `t`: stored 1.5, now 1.7` per metric, or how the rerun did not
    /// succeed.
    pub what: Vec<String>,
}

/// Rerun `n` of the plan's trials stored as succeeded (the draw a fixed function of `seed` and
/// the stored keys; every one when there are at most `n`) in fresh processes, `threads` at a time,
/// and compare every metric with the stored row. `scan` is the plan's schema folder's.
pub fn recompute(
    plan: &ProgramPlan,
    scan: &KeySet,
    n: usize,
    seed: u64,
    threads: usize,
    runner: &RunnerOptions,
) -> anyhow::Result<Recomputed> {
    let schema = RowSchema { params: plan.params.clone(), metrics: plan.program.metrics.clone() };
    let all = jobs(plan);
    let wanted: HashSet<Key> = all.iter().map(|j| j.key).collect();
    let stored = rows(scan, &schema, &wanted)?;
    let mut keys: Vec<Key> = stored.iter().filter(|(_, r)| r.result.is_ok()).map(|(k, _)| *k).collect();
    keys.sort_unstable();
    let eligible = keys.len();
    // A partial Fisher–Yates shuffle of the sorted keys, as the engine's recompute draws: the same
    // sample for the same seed and cache contents on every machine.
    let take = n.min(keys.len());
    let mut rng = qsweep_engine::rng::TrialRng::new(seed);
    for i in 0..take {
        let j = i + rng.below(keys.len() - i);
        keys.swap(i, j);
    }
    let mut sample: Vec<Key> = keys[..take].to_vec();
    sample.sort_unstable();
    let job_of = |k: &Key| all.iter().find(|j| j.key == *k).copied().expect("a sampled key is planned");
    let sampled: Vec<_> = sample.iter().map(job_of).collect();
    let next = AtomicUsize::new(0);
    let found: Mutex<Vec<(usize, TrialResult)>> = Mutex::new(Vec::new());
    std::thread::scope(|s| {
        for _ in 0..threads.clamp(1, sampled.len().max(1)) {
            s.spawn(|| loop {
                let i = next.fetch_add(1, Ordering::Relaxed);
                let Some(job) = sampled.get(i) else { break };
                let json = serde_json::Value::Object(super::key::params_object(&plan.params, job.params));
                let (result, _) =
                    run_process(&plan.program, &json, TrialEnv { seed: job.seed, key: job.key }, runner);
                found.lock().unwrap_or_else(std::sync::PoisonError::into_inner).push((i, result));
            });
        }
    });
    let mut found = found.into_inner().unwrap_or_else(std::sync::PoisonError::into_inner);
    found.sort_by_key(|(i, _)| *i);
    let differing = found
        .into_iter()
        .filter_map(|(i, again)| {
            let job = &sampled[i];
            let Ok(before) = &stored[&job.key].result else { unreachable!("only succeeded rows are drawn") };
            let what = compare(&schema, before, &again);
            (!what.is_empty()).then(|| Differs {
                key: job.key,
                seed: job.seed,
                params: plan.params.iter().map(|(n, _)| n.clone()).zip(job.params.iter().cloned()).collect(),
                what,
            })
        })
        .collect();
    Ok(Recomputed { eligible, checked: sampled.len(), differing })
}

/// What differs between the stored metrics `before` and the rerun's result `again`.
fn compare(schema: &RowSchema, before: &[MetricValue], again: &TrialResult) -> Vec<String> {
    match again {
        TrialResult::Ok(now) => schema
            .metrics
            .iter()
            .zip(before.iter().zip(now))
            .filter(|(_, (a, b))| !same(a, b))
            .map(|((name, _), (a, b))| format!("metric `{name}`: stored {}, now {}", shown(a), shown(b)))
            .collect(),
        TrialResult::Failed(f) => vec![format!("now fails: {}", f.reason)],
        TrialResult::Unfinished(why) => vec![format!("did not finish: {why}")],
    }
}

/// Whether two values are exactly equal (floats bit for bit).
fn same(a: &MetricValue, b: &MetricValue) -> bool {
    match (a, b) {
        (MetricValue::Float(x), MetricValue::Float(y)) => x.to_bits() == y.to_bits(),
        (MetricValue::ListFloat(x), MetricValue::ListFloat(y)) => {
            x.len() == y.len() && x.iter().zip(y).all(|(a, b)| a.to_bits() == b.to_bits())
        }
        _ => a == b,
    }
}

/// A metric value as JSON text (a long list cut after 8 values).
pub fn shown(v: &MetricValue) -> String {
    fn list<T: std::fmt::Display>(xs: &[T], f: impl Fn(&T) -> String) -> String {
        let mut parts: Vec<String> = xs.iter().take(8).map(f).collect();
        if xs.len() > 8 {
            parts.push(format!("… {} values", xs.len()));
        }
        format!("[{}]", parts.join(", "))
    }
    let float = |x: &f64| serde_json::Number::from_f64(*x).map_or_else(|| x.to_string(), |n| n.to_string());
    match v {
        MetricValue::Int(i) => i.to_string(),
        MetricValue::Float(x) => float(x),
        MetricValue::Bool(b) => b.to_string(),
        MetricValue::Str(s) => serde_json::Value::String(s.clone()).to_string(),
        MetricValue::ListFloat(xs) => list(xs, float),
        MetricValue::ListU32(xs) => list(xs, u32::to_string),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::program::model::Failure;

    #[test]
    fn metrics_compare_exactly_and_name_what_differs() {
        let schema = RowSchema {
            params: vec![],
            metrics: vec![
                ("t".into(), crate::program::model::MetricType::Float),
                ("xs".into(), crate::program::model::MetricType::ListFloat),
            ],
        };
        let before = [MetricValue::Float(0.0), MetricValue::ListFloat(vec![1.0, 2.0])];
        let same_again = TrialResult::Ok(before.to_vec());
        assert!(compare(&schema, &before, &same_again).is_empty());
        let again = TrialResult::Ok(vec![MetricValue::Float(-0.0), MetricValue::ListFloat(vec![1.0, 2.5])]);
        assert_eq!(
            compare(&schema, &before, &again),
            ["metric `t`: stored 0.0, now -0.0", "metric `xs`: stored [1.0, 2.0], now [1.0, 2.5]"]
        );
        let failed = TrialResult::Failed(Failure {
            exit_code: Some(1),
            reason: "exit 1".into(),
            stderr_tail: String::new(),
        });
        assert_eq!(compare(&schema, &before, &failed), ["now fails: exit 1"]);
    }
}
