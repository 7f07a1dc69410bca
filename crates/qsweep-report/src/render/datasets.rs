//! The report's data files, Parquet with zstd, in plain types that pandas, polars and DuckDB read
//! (utf8, uint32, uint64, int64, float64, bool, list<uint32>). Rows are in plan order.
//!
//! Columns shared by both files (one cell's identity):
//!
//! | column | type | meaning |
//! | --- | --- | --- |
//! | `variant` | utf8 | the variant's id; only in pipelines that declare `variants:` |
//! | `system` | utf8 | `ball-beam`, `cart-pole`, `mountain-car` |
//! | `system_title` | utf8 | as the paper writes it, e.g. `Ball-Beam` |
//! | `experiment` | utf8 | experiment id (Table I's "Exp.") |
//! | `experiment_title` | utf8, null | e.g. `Bins only` |
//! | `repr` | utf8 | `crisp` or `fuzzy` |
//! | `algorithm` | utf8 | `q0` or `q-lambda` |
//! | `label` | utf8 | e.g. `Fuzzy Q(λ)-learning` |
//! | `axis1_label`, `axis1_value` | utf8, float64 | first varied axis (heatmap rows), e.g. `x == theta`, 3 (or a setting, e.g. `alpha`, 0.05) |
//! | `axis2_label`, `axis2_value` | utf8 null, float64 null | second varied axis (columns); null for 1-axis experiments |
//! | `x`, `x_dot`, `theta`, `theta_dot` | uint32, null | bins or fuzzy sets per state variable; null where the system has no such variable |
//! | `actions` | uint32 | number of actions n of A_n |
//! | `max_episodes` | uint32 | the episode cap, at which non-converged trials are counted |
//!
//! `cells.parquet`, one row per cell, then:
//!
//! | column | type | meaning |
//! | --- | --- | --- |
//! | `planned` | int64 | trials planned (seeds) |
//! | `n` | int64 | trials present |
//! | `successes` | int64 | present trials that reached the goal |
//! | `all_converged` | bool | `n > 0` and every present trial reached the goal |
//! | `best` | bool | the Table III cell of its experiment and algorithm |
//! | `mean`, `std` | float64, null | of `episodes_counted`; std is the sample std (ddof = 1), null for n < 2 |
//! | `min`, `median`, `max` | float64, null | of `episodes_counted` |
//! | `iqm` | float64, null | interquartile mean: mean after dropping ⌊n/4⌋ values at each end |
//! | `ci_lo`, `ci_hi` | float64, null | 95% percentile-bootstrap interval of the mean (2000 resamples, seeded by the cell's trial keys) |
//! | `contender` | bool, null | only in pipelines with a `race:`: the cell is still in its heatmap's race (not significantly worse than the best); null in experiments without a race. `planned` and `n` are then the seeds the race gave the cell |
//! | `fresh_n` | int64 | only in pipelines with a `fresh:` block: the best cell's trials present on the fresh seeds (0 for every other cell); not in `n`, `mean` or any other column above |
//! | `fresh_mean`, `fresh_std` | float64, null | their mean and sample std of `episodes_counted` (the winner's-curse-free estimate of the best cell) |
//! | `fresh_ci_lo`, `fresh_ci_hi` | float64, null | their 95% percentile-bootstrap interval (2000 resamples, seeded by the fresh trials' keys) |
//!
//! `trials.parquet`, one row per present trial of each cell (a trial shared by two cells, e.g. the
//! same configuration in two experiments, appears once per cell), then:
//!
//! | column | type | meaning |
//! | --- | --- | --- |
//! | `seed` | uint64 | the trial's seed |
//! | `key` | utf8 | cache key, 64 hex characters |
//! | `converged` | bool | the learning goal was reached |
//! | `episodes_to_goal` | uint32, null | episodes up to and including the goal; null if never reached |
//! | `episodes` | uint32 | episodes run |
//! | `episodes_counted` | uint32 | what enters the cell's statistics: `episodes_to_goal` (with `counting: failures`, one less; with `counting: window-start` under the solved rule, the window's first episode, `episodes_to_goal − window + 1`), or `max_episodes` if the goal was never reached |
//! | `total_steps` | uint64 | steps over all episodes |
//! | `stop` | utf8 | `goal`, `max-episodes`, `max-total-steps` or `diverged` |
//! | `failure` | utf8, null | what went wrong, for diverged trials |
//! | `episode_lengths` | list<uint32> | length of every episode, in order |
//! | `epsilon`, `gamma`, `alpha`, `lambda` | float64 | hyperparameters (λ = 0 for Q(0)) |
//! | `seconds` | float64 | wall-clock seconds the trial took when computed (informational) |
//! | `cpu_seconds` | float64, null | CPU seconds of the thread that ran it (load does not inflate them); null for trials cached before qsweep recorded them |
//! | `fresh` | bool | only in pipelines with a `fresh:` block: a trial on a fresh seed of its heatmap's best cell (`fresh_n` of `cells.parquet`), not one of the cell's own; filter it out to recompute `mean`, keep only it to recompute `fresh_mean` |

use crate::derive::report_data::{CellData, ExpData, ReportData, TrialData, Variables};
use qsweep_engine::config::LearnerConfig;
use qsweep_engine::Outcome;
use qsweep_pipeline::parquet_io::Cols;
use qsweep_pipeline::plan::{Cell, Experiment};

/// A cell's identity: its experiment and itself.
type Id<'a> = (&'a ExpData<'a>, &'a CellData<'a>);

/// The columns identifying a cell, one row per entry of `ids`, with a column per state variable of
/// `variables`.
fn cell_identity(cols: &mut Cols, ids: &[Id], variables: &Variables) {
    fn exp<'a>(r: &Id<'a>) -> &'a Experiment {
        r.0.exp
    }
    fn cell<'a>(r: &Id<'a>) -> &'a Cell {
        r.1.cell
    }
    let res: Vec<Vec<Option<u32>>> =
        ids.iter().map(|r| variables.resolution(exp(r).system, &cell(r).config.repr.resolution)).collect();
    // Only pipelines with variants have the column, so other pipelines' files keep their bytes.
    if ids.iter().any(|r| exp(r).variant.is_some()) {
        cols.str("variant", ids, |r| exp(r).variant.as_deref().unwrap_or_default());
    }
    cols.str("system", ids, |r| exp(r).system.name());
    cols.str("system_title", ids, |r| exp(r).system.title());
    cols.str("experiment", ids, |r| exp(r).id.as_str());
    cols.str_opt("experiment_title", ids, |r| exp(r).title.as_deref());
    cols.str("repr", ids, |r| exp(r).repr.name());
    cols.str("algorithm", ids, |r| cell(r).algorithm.name());
    cols.str("label", ids, |r| cell(r).algorithm.label(exp(r).repr));
    cols.str("axis1_label", ids, |r| exp(r).axes[0].label.as_str());
    cols.f64("axis1_value", ids, |r| cell(r).coords[0]);
    cols.str_opt("axis2_label", ids, |r| exp(r).axes.get(1).map(|a| a.label.as_str()));
    cols.f64_opt("axis2_value", ids, |r| cell(r).coords.get(1).copied());
    for (j, name) in variables.columns.iter().enumerate() {
        cols.u32_opt(name, &res, |r| r[j]);
    }
    cols.u32("actions", ids, |r| cell(r).config.actions);
    cols.u32("max_episodes", ids, |r| cell(r).config.limits.max_episodes);
}

/// `cells.parquet`: one row per cell (schema in the module documentation).
pub fn cells_parquet(data: &ReportData) -> anyhow::Result<Vec<u8>> {
    qsweep_pipeline::parquet_io::to_parquet(&cells_batch(data)?)
}

/// The rows of `cells.parquet` as one Arrow batch.
pub fn cells_batch(data: &ReportData) -> anyhow::Result<arrow::record_batch::RecordBatch> {
    let ids: Vec<Id> = data.experiments.iter().flat_map(|e| e.cells.iter().map(move |c| (e, c))).collect();
    let best: Vec<bool> =
        data.experiments.iter().flat_map(|e| (0..e.cells.len()).map(move |i| e.is_best(i))).collect();
    let mut cols = Cols::default();
    cell_identity(&mut cols, &ids, &data.variables);
    cols.i64("planned", &ids, |r| r.1.planned() as i64);
    cols.i64("n", &ids, |r| r.1.trials.len() as i64);
    cols.i64("successes", &ids, |r| r.1.successes as i64);
    cols.bool("all_converged", &ids, |r| !r.1.trials.is_empty() && !r.1.any_failed());
    cols.bool("best", &best, |b| *b);
    cols.f64_opt("mean", &ids, |r| r.1.summary.mean);
    cols.f64_opt("std", &ids, |r| r.1.summary.std);
    cols.f64_opt("min", &ids, |r| r.1.summary.min);
    cols.f64_opt("median", &ids, |r| r.1.summary.median);
    cols.f64_opt("max", &ids, |r| r.1.summary.max);
    cols.f64_opt("iqm", &ids, |r| r.1.summary.iqm);
    cols.f64_opt("ci_lo", &ids, |r| r.1.summary.ci_lo);
    cols.f64_opt("ci_hi", &ids, |r| r.1.summary.ci_hi);
    // Only raced pipelines have the column, so other pipelines' files keep their bytes.
    if data.plan.raced {
        cols.bool_opt("contender", &ids, |r| r.1.cell.contender);
    }
    // Likewise only pipelines with a `fresh:` block have the fresh-seed columns.
    if data.plan.has_fresh() {
        fn fresh<'a>(r: &Id<'a>) -> Option<&'a qsweep_pipeline::analysis::Summary> {
            r.1.fresh_summary.as_ref()
        }
        cols.i64("fresh_n", &ids, |r| r.1.fresh.len() as i64);
        cols.f64_opt("fresh_mean", &ids, |r| fresh(r).and_then(|s| s.mean));
        cols.f64_opt("fresh_std", &ids, |r| fresh(r).and_then(|s| s.std));
        cols.f64_opt("fresh_ci_lo", &ids, |r| fresh(r).and_then(|s| s.ci_lo));
        cols.f64_opt("fresh_ci_hi", &ids, |r| fresh(r).and_then(|s| s.ci_hi));
    }
    cols.into_batch()
}

/// `trials.parquet`: one row per present trial of each cell (schema in the module documentation).
pub fn trials_parquet(data: &ReportData) -> anyhow::Result<Vec<u8>> {
    qsweep_pipeline::parquet_io::to_parquet(&trials_batch(data)?)
}

/// The rows of `trials.parquet` as one Arrow batch.
pub fn trials_batch(data: &ReportData) -> anyhow::Result<arrow::record_batch::RecordBatch> {
    trials_batch_of(&data.experiments, &data.variables)
}

/// The rows of `trials.parquet`, one batch per experiment, each built when it is taken (memory: one
/// experiment's rows).
pub fn trials_batches<'d>(
    data: &'d ReportData,
) -> impl Iterator<Item = anyhow::Result<arrow::record_batch::RecordBatch>> + 'd {
    (0..data.experiments.len()).map(|k| trials_batch_of(&data.experiments[k..k + 1], &data.variables))
}

/// The rows of `trials.parquet` of some experiments, so a large report's rows can be streamed
/// into one file an experiment at a time.
pub fn trials_batch_of(
    experiments: &[ExpData],
    variables: &Variables,
) -> anyhow::Result<arrow::record_batch::RecordBatch> {
    let mut ids: Vec<Id> = Vec::new();
    let mut trials: Vec<(&TrialData, &LearnerConfig)> = Vec::new();
    let mut fresh: Vec<bool> = Vec::new();
    for e in experiments {
        for c in &e.cells {
            for (t, is_fresh) in c.trials.iter().map(|t| (t, false)).chain(c.fresh.iter().map(|t| (t, true)))
            {
                ids.push((e, c));
                trials.push((t, &c.cell.config.learner));
                fresh.push(is_fresh);
            }
        }
    }
    let with_fresh = experiments.iter().any(|e| e.exp.fresh.is_some());
    fn out<'a>(t: &(&'a TrialData, &LearnerConfig)) -> &'a Outcome {
        t.0.outcome
    }
    let mut cols = Cols::default();
    cell_identity(&mut cols, &ids, variables);
    cols.u64("seed", &trials, |t| t.0.planned.seed);
    cols.str("key", &trials, |t| t.0.planned.key.hex());
    cols.bool("converged", &trials, |t| out(t).converged);
    cols.u32_opt("episodes_to_goal", &trials, |t| out(t).episodes_to_goal);
    cols.u32("episodes", &trials, |t| out(t).episodes);
    cols.u32("episodes_counted", &trials, |t| t.0.counted);
    cols.u64("total_steps", &trials, |t| out(t).total_steps);
    cols.str("stop", &trials, |t| out(t).stop.name());
    cols.str_opt("failure", &trials, |t| out(t).failure.as_deref());
    cols.list_u32("episode_lengths", &trials, |t| &out(t).episode_lengths);
    cols.f64("epsilon", &trials, |t| t.1.epsilon);
    cols.f64("gamma", &trials, |t| t.1.gamma);
    cols.f64("alpha", &trials, |t| t.1.alpha);
    cols.f64("lambda", &trials, |t| t.1.lambda);
    cols.f64("seconds", &trials, |t| t.0.seconds);
    cols.f64_opt("cpu_seconds", &trials, |t| t.0.cpu_seconds);
    if with_fresh {
        cols.bool("fresh", &fresh, |f| *f);
    }
    cols.into_batch()
}
