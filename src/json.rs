//! The `--json` outputs of `run`, `report`, `status` (an engine's or a program's pipeline), `trial`, `bench`,
//! `feasible` and `compare`: one struct per format, each with a `format_version`.
//!
//! Like cargo-nextest's machine-readable formats, a format's version is bumped only on an
//! incompatible change (a field removed, renamed or given another type or meaning); new fields may
//! appear at any time without a bump, so readers should ignore fields they do not know. Every
//! format is at version 1. docs/json.md documents each one.

use qsweep_engine::env::SystemKind;
use qsweep_engine::feasible::Feasibility;
use qsweep_engine::{Outcome, TrialConfig};
use qsweep_pipeline::bench::BenchResult;
use qsweep_pipeline::status::Status;
use serde::{Deserialize, Serialize};

/// `qsweep run --json`: one object, printed after the trials ran (before the report is written).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RunSummary {
    /// Version of this format ([`RunSummary::FORMAT_VERSION`]).
    pub format_version: u32,
    /// Pipeline name.
    pub pipeline: String,
    /// Trials computed by this run (diverged ones included).
    pub executed: usize,
    /// Distinct trials of the plan (or shard) found in the cache and not run.
    pub cached: usize,
    /// Distinct trials another run on the same cache computed while this one ran (leased by it,
    /// waited for, not run here); an addition, not a new version.
    #[serde(default)]
    pub elsewhere: usize,
    /// Executed trials that diverged (stored with their reason; the run exits 1).
    pub failed: usize,
    /// A program pipeline's trials that did not finish (timed out or killed: nothing stored, they
    /// run next time; the run exits 1); absent for the engine's pipelines. An addition, not a new
    /// version.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub unfinished: Option<usize>,
    /// The run was stopped by Ctrl-C or SIGTERM (it exits 130).
    pub interrupted: bool,
    /// Wall-clock seconds of the run.
    pub seconds: f64,
}

impl RunSummary {
    /// The current version of the `run --json` format.
    pub const FORMAT_VERSION: u32 = 1;
}

/// `qsweep report --json`: what the report stage computed, reused and wrote.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ReportJson {
    /// Version of this format ([`ReportJson::FORMAT_VERSION`]).
    pub format_version: u32,
    /// Pipeline name.
    pub pipeline: String,
    /// The report directory.
    pub dir: String,
    /// Cells whose statistics were computed from their trials.
    pub cells_recomputed: usize,
    /// Cells of report folders whose memo matched (nothing read or computed for them).
    pub cells_reused: usize,
    /// Bootstrap intervals (cells', differences', claim sets) computed by the folders recomputed.
    pub intervals_computed: usize,
    /// Of those folders' intervals, taken from the statistics' memo (`<cache>/_derived/`).
    pub intervals_reused: usize,
    /// Files written (new, or their bytes changed).
    pub files_written: usize,
    /// Files left alone because their bytes would not change.
    pub files_unchanged: usize,
    /// Wall-clock seconds of the command.
    pub seconds: f64,
}

impl ReportJson {
    /// The current version of the `report --json` format.
    pub const FORMAT_VERSION: u32 = 1;
}

/// `qsweep status --json`: the pipeline's distinct trials, cached and missing, overall and per
/// experiment.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StatusReport {
    /// Version of this format ([`StatusReport::FORMAT_VERSION`]).
    pub format_version: u32,
    /// Pipeline name.
    pub pipeline: String,
    /// Distinct trials of the plan (a trial shared by two cells counts once).
    pub trials: usize,
    /// Of those, in the cache.
    pub cached: usize,
    /// Of those, not in the cache.
    pub missing: usize,
    /// Of the missing, being computed now by another run on the cache (a live lease); an
    /// addition, not a new version.
    #[serde(default)]
    pub running_elsewhere: usize,
    /// One entry per experiment, in report order.
    pub experiments: Vec<StatusExperiment>,
    /// Cache segments that could not be read (their trials count as missing).
    pub damaged_segments: usize,
    /// One entry per raced heatmap; only for pipelines with a `race:` (an addition, not a new version).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub race: Option<Vec<StatusRace>>,
}

/// One raced heatmap of [`StatusReport`] (experiment × algorithm of one variant).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StatusRace {
    /// The variant's id, for pipelines that declare `variants:`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub variant: Option<String>,
    /// `ball-beam`, `cart-pole` or `mountain-car`.
    pub system: String,
    /// Experiment id.
    pub experiment: String,
    /// `q0` or `q-lambda`.
    pub algorithm: String,
    /// Cells of the heatmap.
    pub cells: usize,
    /// Rounds decided (all their trials present).
    pub rounds_done: u32,
    /// The most rounds the race can take.
    pub rounds_max: u32,
    /// Whether the race is over.
    pub finished: bool,
    /// Cells still in the race.
    pub contenders: usize,
    /// Trials of the decided rounds and the pending one.
    pub trials: usize,
    /// Of those, in the cache.
    pub cached: usize,
    /// Trials with `max_seeds` seeds in every cell.
    pub without_race: usize,
}

impl StatusReport {
    /// The current version of the `status --json` format.
    pub const FORMAT_VERSION: u32 = 1;

    /// The format of a status the library computed.
    pub fn of(s: &Status) -> Self {
        let plan = &s.plan;
        let experiments = plan
            .experiments
            .iter()
            .zip(&s.experiments)
            .map(|(e, n)| StatusExperiment {
                variant: e.variant.clone(),
                system: e.system.name().into(),
                experiment: e.id.clone(),
                repr: e.repr.name().into(),
                cells: e.cells.len(),
                trials: n.trials,
                cached: n.cached,
                missing: n.missing(),
            })
            .collect();
        let race = s.heats.as_ref().map(|heats| {
            heats
                .iter()
                .map(|h| {
                    let e = &plan.experiments[h.experiment];
                    StatusRace {
                        variant: e.variant.clone(),
                        system: e.system.name().into(),
                        experiment: e.id.clone(),
                        algorithm: h.algorithm.name().into(),
                        cells: h.cells,
                        rounds_done: h.rounds_done,
                        rounds_max: h.rounds_max,
                        finished: h.finished,
                        contenders: h.contenders,
                        trials: h.trials,
                        cached: h.cached,
                        without_race: h.without_race,
                    }
                })
                .collect()
        });
        Self {
            format_version: Self::FORMAT_VERSION,
            pipeline: plan.name.clone(),
            trials: s.total.trials,
            cached: s.total.cached,
            missing: s.total.missing(),
            running_elsewhere: s.running_elsewhere,
            experiments,
            damaged_segments: s.damaged.len(),
            race,
        }
    }
}

/// One experiment of [`StatusReport`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StatusExperiment {
    /// The variant's id; only for pipelines that declare `variants:` (an addition, not a new version).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub variant: Option<String>,
    /// `ball-beam`, `cart-pole` or `mountain-car`.
    pub system: String,
    /// Experiment id.
    pub experiment: String,
    /// `crisp` or `fuzzy`.
    pub repr: String,
    /// Cells of the experiment.
    pub cells: usize,
    /// Distinct trials of the experiment.
    pub trials: usize,
    /// Of those, in the cache.
    pub cached: usize,
    /// Of those, not in the cache.
    pub missing: usize,
}

/// `qsweep status --json` on a program pipeline (docs/programs.md): its distinct trials, stored
/// (succeeded or failed) and missing, overall and per experiment.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ProgramStatusReport {
    /// Version of this format ([`ProgramStatusReport::FORMAT_VERSION`]).
    pub format_version: u32,
    /// Pipeline name.
    pub pipeline: String,
    /// The folder of the cache that holds this pipeline's rows (`<cache>/_programs/<schema-id>`).
    pub folder: String,
    /// Distinct trials of the plan.
    pub trials: usize,
    /// Of those, stored (succeeded or failed: a run does not run them again).
    pub cached: usize,
    /// Of the stored, failed (`qsweep run --retry-failed` runs them again).
    pub failed: usize,
    /// Of the trials, not stored.
    pub missing: usize,
    /// Of the missing, being computed now by another run on the cache (a live lease).
    pub running_elsewhere: usize,
    /// One entry per experiment (of each variant), in plan order.
    pub experiments: Vec<ProgramStatusExperiment>,
    /// Segments of the folder that cannot be read (their trials count as missing).
    pub damaged_segments: usize,
    /// When the folder holds no rows: the schema ids of the other program folders that do.
    pub other_schemas: Vec<String>,
    /// One entry per raced experiment; only for pipelines with a `race:` (an addition, not a new
    /// version).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub race: Option<Vec<ProgramStatusRace>>,
}

/// One raced experiment of [`ProgramStatusReport`] (of one variant).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ProgramStatusRace {
    /// The variant's id; only for pipelines that declare `variants:`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub variant: Option<String>,
    /// Experiment id.
    pub experiment: String,
    /// Cells of the experiment.
    pub cells: usize,
    /// Rounds decided (all their trials stored).
    pub rounds_done: u32,
    /// The most rounds the race can take.
    pub rounds_max: u32,
    /// Whether the race is over.
    pub finished: bool,
    /// Cells still in the race.
    pub contenders: usize,
    /// Trials of the decided rounds and the pending one.
    pub trials: usize,
    /// Trials with `max_seeds` seeds in every cell.
    pub without_race: usize,
}

impl ProgramStatusReport {
    /// The current version of the format.
    pub const FORMAT_VERSION: u32 = 1;
}

/// One experiment of [`ProgramStatusReport`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ProgramStatusExperiment {
    /// The variant's id; only for pipelines that declare `variants:`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub variant: Option<String>,
    /// Experiment id.
    pub experiment: String,
    /// Cells of the experiment.
    pub cells: usize,
    /// Distinct trials of the experiment.
    pub trials: usize,
    /// Of those, stored.
    pub cached: usize,
    /// Of the stored, failed.
    pub failed: usize,
    /// Of those, not stored.
    pub missing: usize,
}

/// `qsweep trial --json`: the resolved configuration, the seed and everything the trial produced.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TrialReport {
    /// Version of this format ([`TrialReport::FORMAT_VERSION`]).
    pub format_version: u32,
    /// The fully resolved configuration, as the cache's `config_json` stores it.
    pub config: TrialConfig,
    /// The seed.
    pub seed: u64,
    /// What the trial produced (fields as the cache's columns of the same names).
    pub outcome: Outcome,
    /// Wall-clock seconds of the trial.
    pub seconds: f64,
}

impl TrialReport {
    /// The current version of the `trial --json` format.
    pub const FORMAT_VERSION: u32 = 1;
}

/// `qsweep bench --json`: one result per configuration measured, in the standard order.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BenchReport {
    /// Version of this format ([`BenchReport::FORMAT_VERSION`]).
    pub format_version: u32,
    /// The configurations measured.
    pub results: Vec<BenchResult>,
}

impl BenchReport {
    /// The current version of the `bench --json` format.
    pub const FORMAT_VERSION: u32 = 1;
}

/// `qsweep bench --pipeline P --json`.
#[derive(Debug, Serialize)]
pub struct PipelineBenchReport {
    /// Version of this format ([`PipelineBenchReport::FORMAT_VERSION`]).
    pub format_version: u32,
    /// Pipeline name.
    pub pipeline: String,
    /// How the cells were ranked: `cached` (CPU seconds of the cached trials) or `estimated`.
    pub basis: qsweep_pipeline::bench::pipeline::CostBasis,
    /// Distinct cells of the plan.
    pub cells: usize,
    /// The timed cells, most expensive first.
    pub results: Vec<qsweep_pipeline::bench::pipeline::CellBench>,
}

impl PipelineBenchReport {
    /// The current version of the `bench --pipeline --json` format.
    pub const FORMAT_VERSION: u32 = 1;
}

/// One visited cell of the best policy (defined with the search).
pub use qsweep_engine::feasible::PolicyCell as FeasibleCell;

/// `qsweep feasible --json`: the search's settings, its result and the best policy's visited cells.
#[derive(Debug, Serialize)]
pub struct FeasibleReport {
    /// Version of this format ([`FeasibleReport::FORMAT_VERSION`]).
    pub format_version: u32,
    pub system: SystemKind,
    pub resolution: Vec<u32>,
    pub actions: u32,
    pub ranges: Vec<[f64; 2]>,
    pub binning: &'static str,
    pub start: Vec<f64>,
    pub max_steps: u64,
    pub max_nodes: u64,
    #[serde(flatten)]
    pub result: Feasibility,
    pub policy_cells: Vec<FeasibleCell>,
}

impl FeasibleReport {
    /// Current version of the `feasible --json` format.
    pub const FORMAT_VERSION: u32 = 1;
}

/// `qsweep compare --json`: two program pipelines compared cell by cell (docs/json.md).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CompareJson {
    /// Version of this format ([`CompareJson::FORMAT_VERSION`]).
    pub format_version: u32,
    /// Side A as given (`PATH`, `PATH@VARIANT` or a report folder).
    pub a: String,
    /// Pipeline B as given.
    pub b: String,
    /// The metric compared: A's name, B's name.
    pub metric: [String; 2],
    /// The shared params, each A's name and B's name.
    pub shared: Vec<[String; 2]>,
    /// The equivalence margin on B ÷ A.
    pub margin: [f64; 2],
    /// Cells with a Welch p (m).
    pub tested: usize,
    /// Of those, with p < 0.05 (k).
    pub significant: usize,
    /// 0.05 m: what chance alone gives.
    pub expected: f64,
    /// P(X ≥ k | Binomial(m, 0.05)).
    pub binomial_p: f64,
    /// `beyond chance` (binomial_p < 0.05) or `within chance`.
    pub statement: String,
    /// Cells per verdict.
    pub verdicts: CompareVerdicts,
    /// The compared cells, in A's plan order.
    pub cells: Vec<CompareCell>,
    /// Matched cells without trials on a side.
    pub missing: Vec<CompareMissing>,
    /// Cells only A plans (labels `name=value …`).
    pub only_a: Vec<String>,
    /// Cells only B plans.
    pub only_b: Vec<String>,
}

impl CompareJson {
    /// The current version of the `compare --json` format.
    pub const FORMAT_VERSION: u32 = 1;

    /// The JSON of `c`.
    pub fn of(c: &qsweep_report::comparison::Comparison) -> Self {
        let o = &c.overall;
        Self {
            format_version: Self::FORMAT_VERSION,
            a: c.labels.0.clone(),
            b: c.labels.1.clone(),
            metric: [c.metric.0.clone(), c.metric.1.clone()],
            shared: c.shared.iter().map(|(x, y)| [x.clone(), y.clone()]).collect(),
            margin: [c.margin.0, c.margin.1],
            tested: o.tested,
            significant: o.significant,
            expected: o.expected,
            binomial_p: o.binomial_p,
            statement: o.statement().to_string(),
            verdicts: CompareVerdicts {
                equivalent: o.verdicts.0,
                differs: o.verdicts.1,
                undecided: o.verdicts.2,
            },
            cells: c
                .cells
                .iter()
                .map(|x| CompareCell {
                    params: c
                        .shared
                        .iter()
                        .zip(&x.values)
                        .map(|((n, _), v)| (n.clone(), v.to_json()))
                        .collect(),
                    n_a: x.n.0,
                    n_b: x.n.1,
                    mean_a: x.mean.0,
                    mean_b: x.mean.1,
                    std_a: x.std.0,
                    std_b: x.std.1,
                    ratio: x.ratio,
                    ratio_lo: x.ratio_ci.map(|r| r.0).filter(|v| v.is_finite()),
                    ratio_hi: x.ratio_ci.map(|r| r.1).filter(|v| v.is_finite()),
                    ratio_interval: x.interval.word().to_string(),
                    p: x.p,
                    tost_p: x.tost.map(|t| t.p),
                    verdict: x.verdict.word().to_string(),
                    note: x.note.clone(),
                })
                .collect(),
            missing: c
                .missing
                .iter()
                .map(|m| CompareMissing { cell: m.label.clone(), side: m.side.to_string() })
                .collect(),
            only_a: c.only.0.clone(),
            only_b: c.only.1.clone(),
        }
    }
}

/// Cells per verdict in `compare --json`.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct CompareVerdicts {
    /// TOST shows B ÷ A within the margin.
    pub equivalent: usize,
    /// Welch p < 0.05 and not equivalent.
    pub differs: usize,
    /// Neither, or no test (fewer than 2 trials on a side).
    pub undecided: usize,
}

/// One compared cell in `compare --json`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CompareCell {
    /// The shared params' values, by A's names.
    pub params: serde_json::Map<String, serde_json::Value>,
    /// Succeeded trials of A.
    pub n_a: usize,
    /// Succeeded trials of B.
    pub n_b: usize,
    /// Mean of A.
    pub mean_a: f64,
    /// Mean of B.
    pub mean_b: f64,
    /// Sample std of A (null below 2 trials).
    pub std_a: Option<f64>,
    /// Sample std of B.
    pub std_b: Option<f64>,
    /// mean B ÷ mean A (null when mean A is not positive).
    pub ratio: Option<f64>,
    /// Its 95 % interval's lower end.
    pub ratio_lo: Option<f64>,
    /// Its upper end (null when unbounded).
    pub ratio_hi: Option<f64>,
    /// How the interval was computed: `bootstrap` (from trials) or `delta-log` (from moments).
    pub ratio_interval: String,
    /// Welch's two-sided p (null below 2 trials on a side).
    pub p: Option<f64>,
    /// TOST's p at the margin (null when it cannot be computed).
    pub tost_p: Option<f64>,
    /// `equivalent`, `differs` or `undecided`.
    pub verdict: String,
    /// Why no test could be computed, if none could.
    pub note: Option<String>,
}

/// A matched cell without trials on a side, in `compare --json`.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct CompareMissing {
    /// The cell, `name=value …`.
    pub cell: String,
    /// Which side lacks trials: `A`, `B` or `both`.
    pub side: String,
}
