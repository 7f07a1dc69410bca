//! The types every part of a program pipeline shares: a param's type and value, a metric's type
//! and value, the program as declared and resolved, the plan of its cells and trials, what running
//! one trial gave, and the row stored for it. Nothing here runs or reads anything.

use crate::cache::Key;
use std::collections::BTreeMap;
use std::path::PathBuf;
use std::time::Duration;

/// The type of a param, fixed by its default in `params:`; every value it takes has this type
/// (an integer is accepted where a float is declared, and stored as a float).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ParamType {
    /// A whole number (`bins: 6`).
    Int,
    /// A number with a fraction or exponent (`alpha: 0.1`).
    Float,
    /// `true` or `false`.
    Bool,
    /// Text (`env: CartPole-v1`).
    Str,
}

impl ParamType {
    /// The name in messages and in docs/programs.md: `int`, `float`, `bool`, `string`.
    pub fn name(self) -> &'static str {
        match self {
            Self::Int => "int",
            Self::Float => "float",
            Self::Bool => "bool",
            Self::Str => "string",
        }
    }
}

/// One value of a param.
#[derive(Debug, Clone, PartialEq)]
pub enum ParamValue {
    /// An integer.
    Int(i64),
    /// A finite float.
    Float(f64),
    /// A boolean.
    Bool(bool),
    /// Text.
    Str(String),
}

impl ParamValue {
    /// Its type.
    pub fn kind(&self) -> ParamType {
        match self {
            Self::Int(_) => ParamType::Int,
            Self::Float(_) => ParamType::Float,
            Self::Bool(_) => ParamType::Bool,
            Self::Str(_) => ParamType::Str,
        }
    }

    /// As JSON (a float stays a float: `1.0`, never `1`).
    pub fn to_json(&self) -> serde_json::Value {
        match self {
            Self::Int(i) => serde_json::Value::from(*i),
            Self::Float(f) => {
                serde_json::Number::from_f64(*f).map_or(serde_json::Value::Null, serde_json::Value::Number)
            }
            Self::Bool(b) => serde_json::Value::Bool(*b),
            Self::Str(s) => serde_json::Value::String(s.clone()),
        }
    }
}

impl std::fmt::Display for ParamValue {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Int(i) => write!(f, "{i}"),
            Self::Float(x) => write!(
                f,
                "{}",
                serde_json::Number::from_f64(*x).map_or_else(|| x.to_string(), |n| n.to_string())
            ),
            Self::Bool(b) => write!(f, "{b}"),
            Self::Str(s) => f.write_str(s),
        }
    }
}

/// The type of a metric as `metrics:` declares it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum MetricType {
    /// `int`: int64.
    Int,
    /// `float`: float64 (a JSON integer is accepted).
    Float,
    /// `bool`.
    Bool,
    /// `string`.
    Str,
    /// `list<float>`: list of float64.
    ListFloat,
    /// `list<uint32>`: list of uint32.
    ListU32,
}

impl MetricType {
    /// Every type, in the order docs/programs.md lists them.
    pub const ALL: [MetricType; 6] =
        [Self::Int, Self::Float, Self::Bool, Self::Str, Self::ListFloat, Self::ListU32];

    /// The name as written in `metrics:`.
    pub fn name(self) -> &'static str {
        match self {
            Self::Int => "int",
            Self::Float => "float",
            Self::Bool => "bool",
            Self::Str => "string",
            Self::ListFloat => "list<float>",
            Self::ListU32 => "list<uint32>",
        }
    }

    /// The type named `name`, if any.
    pub fn parse(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|t| t.name() == name)
    }

    /// Whether it is a single number (a cell's statistics are taken of these).
    pub fn is_scalar_number(self) -> bool {
        matches!(self, Self::Int | Self::Float)
    }
}

/// One value of a metric.
#[derive(Debug, Clone, PartialEq)]
pub enum MetricValue {
    /// An integer.
    Int(i64),
    /// A finite float (JSON has no NaN or infinity).
    Float(f64),
    /// A boolean.
    Bool(bool),
    /// Text.
    Str(String),
    /// A list of floats.
    ListFloat(Vec<f64>),
    /// A list of unsigned 32-bit integers.
    ListU32(Vec<u32>),
}

/// How qsweep talks to the program.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Protocol {
    /// One process per trial (the default).
    #[default]
    Process,
    /// One process per worker slot, many trials each, one JSON line per trial each way.
    Worker,
}

/// Which way a metric is better.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Goal {
    /// Smaller is better.
    Minimize,
    /// Larger is better.
    Maximize,
}

/// The objective: a scalar numeric metric and its goal (the best cell, races, compare).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Objective {
    /// The metric.
    pub metric: String,
    /// Its goal.
    pub goal: Goal,
}

/// A provenance command: run once per run, its output recorded with the rows; with `key`, its
/// output joins every trial's key.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Provenance {
    /// argv, run without a shell.
    pub command: Vec<String>,
    /// Whether its output joins the key.
    pub key: bool,
}

/// A declared input file, resolved: its path as the glob found it (relative to qsweep's working
/// directory when the glob was relative) and the blake3 of its contents.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct InputFile {
    /// The path, as written in keys and messages (`/` separators).
    pub path: String,
    /// blake3 of the contents, hex.
    pub digest: String,
}

/// The program as resolved for one plan.
#[derive(Debug, Clone, PartialEq)]
pub struct Program {
    /// argv.
    pub command: Vec<String>,
    /// The declared globs, as written (for messages).
    pub input_globs: Vec<String>,
    /// Every file the globs matched, sorted by path, with its digest.
    pub inputs: Vec<InputFile>,
    /// The protocol.
    pub protocol: Protocol,
    /// Per-trial timeout.
    pub timeout: Duration,
    /// Declared metrics, in declared order.
    pub metrics: Vec<(String, MetricType)>,
    /// The objective, if declared.
    pub objective: Option<Objective>,
    /// Provenance commands, as declared.
    pub provenance: Vec<Provenance>,
    /// Their outputs (trimmed stdout), in order, run once when the plan was made.
    pub provenance_outputs: Vec<String>,
}

/// One planned trial of a cell: its seed and key.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ProgramTrial {
    /// The seed.
    pub seed: u64,
    /// The key.
    pub key: Key,
}

/// One cell: every param's value, in the plan's param order, its coordinates on the experiment's
/// axes, and its trials (one per seed).
#[derive(Debug, Clone, PartialEq)]
pub struct ProgramCell {
    /// Every param's value, in [`ProgramPlan::params`] order.
    pub params: Vec<ParamValue>,
    /// The values of the experiment's varied params, in axis order.
    pub coords: Vec<ParamValue>,
    /// One per seed: the pipeline's seeds, and in a race the extra seeds of the rounds replayed
    /// so far (`crate::program::race`).
    pub trials: Vec<ProgramTrial>,
    /// In a raced experiment, whether the cell is still in the race after the last decided round
    /// (`None`: not raced, or not replayed).
    pub contender: Option<bool>,
    /// Its trials on the fresh seeds, once the replay found it its experiment's best (`fresh:`);
    /// never part of its own numbers.
    pub fresh: Vec<ProgramTrial>,
}

/// One experiment: the cells of its grid (the product of its axes, first axis outermost).
#[derive(Debug, Clone, PartialEq)]
pub struct ProgramExperiment {
    /// The variant it belongs to (`None`: the pipeline as written, or a pipeline without variants).
    pub variant: Option<String>,
    /// Its id.
    pub id: String,
    /// Its title.
    pub title: Option<String>,
    /// The varied params, in declared order.
    pub axes: Vec<String>,
    /// The params it fixes, with their values.
    pub fixed: Vec<(String, ParamValue)>,
    /// Its race (`race:`; `None`: its full grid runs).
    pub race: Option<crate::declared::RaceSpec>,
    /// The fresh seeds its best cell gets (`fresh:`; empty: none).
    pub fresh: Vec<u64>,
    /// Its cells.
    pub cells: Vec<ProgramCell>,
}

/// A declared variant.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ProgramVariant {
    /// Its id.
    pub id: String,
    /// Its title.
    pub title: Option<String>,
    /// Its `set` entries as `PATH=VALUE`.
    pub set: Vec<String>,
}

impl ProgramPlan {
    /// Whether a stage of the plan is planned from the outcomes of the stages before it (a race's
    /// rounds, the fresh seeds), so a run goes round by round and readers replay it first.
    pub fn has_stages(&self) -> bool {
        self.experiments.iter().any(|e| e.race.is_some() || !e.fresh.is_empty())
    }

    /// The most stages the plan can take: a race's rounds (the most of any experiment), then one
    /// more for the fresh seeds.
    pub fn stages_max(&self) -> u32 {
        let rounds = self
            .experiments
            .iter()
            .filter_map(|e| {
                let r = e.race?;
                Some(crate::race::rounds_max(self.seeds.len() as u32, r.batch, r.max_seeds))
            })
            .max()
            .unwrap_or(1);
        rounds + u32::from(self.experiments.iter().any(|e| !e.fresh.is_empty()))
    }
}

/// The resolved plan of a program pipeline.
#[derive(Debug, Clone, PartialEq)]
pub struct ProgramPlan {
    /// The pipeline's name (reports go to `reports/<name>/`).
    pub name: String,
    /// Its description.
    pub description: Option<String>,
    /// The pipeline file.
    pub source: PathBuf,
    /// The program (variants set params only, so every variant runs this program).
    pub program: Program,
    /// Every param with its type, in declared order.
    pub params: Vec<(String, ParamType)>,
    /// The seeds.
    pub seeds: Vec<u64>,
    /// The experiments, of every variant, in order.
    pub experiments: Vec<ProgramExperiment>,
    /// The variants.
    pub variants: Vec<ProgramVariant>,
    /// Warnings to print (never written into a report).
    pub warnings: Vec<String>,
}

/// What running one trial gave.
#[derive(Debug, Clone, PartialEq)]
pub enum TrialResult {
    /// It exited 0 with a valid result line: every declared metric, in declared order.
    Ok(Vec<MetricValue>),
    /// It failed in a way that is stored (rerun with `--retry-failed`): non-zero exit, a malformed
    /// result, output over the limit.
    Failed(Failure),
    /// It did not finish: timed out, killed by a signal, or interrupted. Nothing is stored.
    Unfinished(String),
}

/// A stored failure.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Failure {
    /// The exit code (`None`: it exited 0 but its result was not valid).
    pub exit_code: Option<i32>,
    /// What went wrong, naming the line and the field for a bad result.
    pub reason: String,
    /// The tail of its stderr (at most [`STDERR_TAIL`] bytes, lossy UTF-8).
    pub stderr_tail: String,
}

/// The columns every program row has besides its params and metrics: no param or metric may take
/// one of these names.
pub const FIXED_COLUMNS: [&str; 11] = [
    "key",
    "seed",
    "status",
    "exit_code",
    "error",
    "stderr_tail",
    "seconds",
    "cpu_seconds",
    "command",
    "inputs",
    "provenance",
];

/// The columns a report's `trials.parquet` adds before a row's own (the trial's experiment and
/// variant, and whether it is a fresh-seed trial): no param or metric may take one of these names
/// either.
pub const REPORT_COLUMNS: [&str; 3] = ["experiment", "variant", "fresh"];

/// How much of a failed trial's stderr is kept.
pub const STDERR_TAIL: usize = 4096;

/// The most a trial may write on stdout (16 MiB): past it the trial fails, memory stays bounded.
pub const STDOUT_LIMIT: usize = 16 << 20;

/// One stored row: one trial of a program pipeline.
#[derive(Debug, Clone, PartialEq)]
pub struct ProgramRow {
    /// The key.
    pub key: Key,
    /// The seed.
    pub seed: u64,
    /// Every param's value, in the schema's param order.
    pub params: Vec<ParamValue>,
    /// `Ok` metrics (declared order) or the failure.
    pub result: Result<Vec<MetricValue>, Failure>,
    /// Wall-clock seconds.
    pub seconds: f64,
    /// CPU seconds of the program (its own and its waited-for children), when measured.
    pub cpu_seconds: Option<f64>,
    /// The command, as run (JSON array).
    pub command_json: String,
    /// The input files' digests (JSON object path → hex).
    pub inputs_json: String,
    /// The provenance outputs recorded with the row (JSON array).
    pub provenance_json: String,
}

/// The canonical JSON of `value`: object keys sorted, no whitespace, numbers as serde_json writes
/// them. What a key hashes.
pub fn canonical_json(value: &serde_json::Value) -> String {
    fn sorted(v: &serde_json::Value) -> serde_json::Value {
        match v {
            serde_json::Value::Object(m) => {
                let b: BTreeMap<&String, serde_json::Value> = m.iter().map(|(k, v)| (k, sorted(v))).collect();
                serde_json::Value::Object(b.into_iter().map(|(k, v)| (k.clone(), v)).collect())
            }
            serde_json::Value::Array(a) => serde_json::Value::Array(a.iter().map(sorted).collect()),
            other => other.clone(),
        }
    }
    // serde_json's Map keeps insertion order only with `preserve_order`; the BTreeMap above makes
    // the order explicit either way.
    serde_json::to_string(&sorted(value)).expect("JSON values serialize")
}

/// The schema id of a program pipeline's rows: the first 16 hex digits of blake3 over its params'
/// and metrics' names and types, each list taken by name (a plan lists them so, and the order a
/// file declares them in never matters). Rows of one schema id live in one folder.
pub fn schema_id(params: &[(String, ParamType)], metrics: &[(String, MetricType)]) -> String {
    let mut params: Vec<&(String, ParamType)> = params.iter().collect();
    params.sort_by(|a, b| a.0.cmp(&b.0));
    let mut metrics: Vec<&(String, MetricType)> = metrics.iter().collect();
    metrics.sort_by(|a, b| a.0.cmp(&b.0));
    let mut h = blake3::Hasher::new();
    h.update(b"qsweep-program-schema\0");
    for (n, t) in params {
        h.update(format!("p {n} {}\0", t.name()).as_bytes());
    }
    for (n, t) in metrics {
        h.update(format!("m {n} {}\0", t.name()).as_bytes());
    }
    h.finalize().to_hex()[..16].to_string()
}
