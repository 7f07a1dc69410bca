//! One trial per Parquet row: the cache's schema, encoding records into a batch, and decoding a
//! segment (all columns, only the keys, or only the outcome columns the report needs). The store
//! ([`super::store`]) decides which files these rows live in.
//!
//! The cache reads as one table in pandas (`pd.read_parquet("cache")`), polars
//! (`pl.read_parquet("cache/seg-*.parquet")`) and DuckDB (`read_parquet('cache/seg-*.parquet')`);
//! the schema is [`schema`].

use super::key::Key;
use super::record::TrialRecord;
use crate::parquet_io::{column, Cols};
use arrow::array::{Array, BooleanArray, Float64Array, ListArray, StringArray, UInt32Array, UInt64Array};
use arrow::datatypes::SchemaRef;
use arrow::record_batch::RecordBatch;
use parquet::arrow::arrow_reader::ParquetRecordBatchReaderBuilder;
use parquet::arrow::ProjectionMask;
use qsweep_engine::config::{TieBreak, TrialConfig};
use qsweep_engine::{Outcome, StopReason};
use std::fs::File;
use std::path::Path;
use std::sync::{Arc, OnceLock};

/// A stored trial's outcome without its configuration (which the plan already knows): what a
/// report reads.
#[derive(Debug, Clone, PartialEq)]
pub struct StoredTrial {
    /// The outcome; `episode_lengths` is empty when the read left that column out.
    pub outcome: Outcome,
    /// Wall-clock seconds (informational).
    pub seconds: f64,
    /// Thread CPU seconds, when recorded.
    pub cpu_seconds: Option<f64>,
}

/// The Parquet schema of a cache segment, one row per trial:
///
/// | column | type | meaning |
/// |---|---|---|
/// | `key` | utf8 | blake3 of (canonical config, seed, engine version), 64 hex chars |
/// | `engine_version` | uint32 | `ENGINE_VERSION` the row was computed with |
/// | `system` | utf8 | `ball-beam`, `cart-pole` or `mountain-car` |
/// | `repr` | utf8 | `crisp` or `fuzzy` |
/// | `algorithm` | utf8 | `q0` or `q-lambda` |
/// | `resolution` | list<uint32> | bins or fuzzy sets per state variable, in state order |
/// | `actions` | uint32 | n of A_n |
/// | `epsilon`, `gamma`, `alpha`, `lambda`, `q_init` | float64 | learner settings |
/// | `tie_break` | utf8 | `random` or `first` |
/// | `seed` | uint64 | the trial's seed |
/// | `config_json` | utf8 | the full canonical resolved configuration the key hashes |
/// | `converged` | bool | the learning goal was reached |
/// | `episodes_to_goal` | uint32, nullable | episodes up to the goal; null if never reached |
/// | `episodes` | uint32 | episodes run |
/// | `total_steps` | uint64 | steps run over all episodes |
/// | `stop` | utf8 | `goal`, `max-episodes`, `max-total-steps` or `diverged` |
/// | `failure` | utf8, nullable | why a diverged trial failed |
/// | `episode_lengths` | list<uint32> | every episode's length, in order |
/// | `seconds` | float64 | wall-clock time of the trial (informational only) |
/// | `cpu_seconds` | float64, nullable | CPU time of the thread that ran the trial (informational; load does not inflate it; a trial in lockstep: its equal share of its loop's while it was in it); absent in segments written before qsweep recorded it, which still read (as null) |
pub fn schema() -> SchemaRef {
    static SCHEMA: OnceLock<SchemaRef> = OnceLock::new();
    SCHEMA.get_or_init(|| Arc::new(columns(&[]).schema())).clone()
}

/// The segment columns of `records`: the one definition of the cache schema (see [`schema`]).
/// Changing a name, type, nullability or the order here makes existing segments unreadable.
fn columns(records: &[TrialRecord]) -> Cols {
    let r = records;
    let mut c = Cols::default();
    c.str("key", r, |r| r.key.hex());
    c.u32("engine_version", r, |r| r.engine_version);
    c.str("system", r, |r| r.config.system().name());
    c.str("repr", r, |r| r.config.repr.kind.name());
    c.str("algorithm", r, |r| r.config.learner.algorithm.name());
    c.list_u32("resolution", r, |r| &r.config.repr.resolution);
    c.u32("actions", r, |r| r.config.actions);
    c.f64("epsilon", r, |r| r.config.learner.epsilon);
    c.f64("gamma", r, |r| r.config.learner.gamma);
    c.f64("alpha", r, |r| r.config.learner.alpha);
    c.f64("lambda", r, |r| r.config.learner.lambda);
    c.f64("q_init", r, |r| r.config.learner.q_init);
    c.str("tie_break", r, |r| match r.config.learner.tie_break {
        TieBreak::Random => "random",
        TieBreak::First => "first",
    });
    c.u64("seed", r, |r| r.seed);
    c.str("config_json", r, TrialRecord::config_json);
    c.bool("converged", r, |r| r.outcome.converged);
    c.u32_opt("episodes_to_goal", r, |r| r.outcome.episodes_to_goal);
    c.u32("episodes", r, |r| r.outcome.episodes);
    c.u64("total_steps", r, |r| r.outcome.total_steps);
    c.str("stop", r, |r| r.outcome.stop.name());
    c.str_opt("failure", r, |r| r.outcome.failure.as_deref());
    c.list_u32("episode_lengths", r, |r| &r.outcome.episode_lengths);
    c.f64("seconds", r, |r| r.seconds);
    c.f64_opt("cpu_seconds", r, |r| r.cpu_seconds);
    c
}

/// Columns added to the schema after segments were first written: a segment without them still
/// reads, with nulls.
pub const LATER_COLUMNS: [&str; 1] = ["cpu_seconds"];

/// Encode records as one Arrow batch with [`schema`].
pub fn to_batch(records: &[TrialRecord]) -> anyhow::Result<RecordBatch> {
    columns(records).into_batch()
}

/// The Arrow schema metadata entry that marks a segment of a program pipeline's rows
/// (`crate::program`), its value the rows' schema id. Such a segment has its own typed columns;
/// what the store reads of every segment, the `key` column, it shares with the engine's.
pub const PROGRAM_ROWS: &str = "qsweep.program_rows";

/// Whether the segment `builder` reads is a program pipeline's ([`PROGRAM_ROWS`]).
fn is_program_segment(builder: &ParquetRecordBatchReaderBuilder<File>) -> bool {
    builder.schema().metadata().contains_key(PROGRAM_ROWS)
}

fn open_reader(path: &Path) -> anyhow::Result<ParquetRecordBatchReaderBuilder<File>> {
    let file = File::open(path)?;
    let builder = ParquetRecordBatchReaderBuilder::try_new(file)?;
    check_engine_schema(&builder)?;
    Ok(builder)
}

/// That an engine segment has every column of [`schema`] with its type.
fn check_engine_schema(builder: &ParquetRecordBatchReaderBuilder<File>) -> anyhow::Result<()> {
    let expected = schema();
    let found = builder.schema();
    for f in expected.fields() {
        match found.field_with_name(f.name()) {
            Ok(g) if g.data_type() == f.data_type() => {}
            Ok(g) => {
                anyhow::bail!("column `{}` has type {}, expected {}", f.name(), g.data_type(), f.data_type())
            }
            Err(_) if LATER_COLUMNS.contains(&f.name().as_str()) => {}
            Err(_) => anyhow::bail!("column `{}` is missing (not a qsweep segment?)", f.name()),
        }
    }
    Ok(())
}

/// Whether the segment at `path` has every column of [`schema`] (none of [`LATER_COLUMNS`]
/// missing): `gc` rewrites one that has not.
pub(super) fn in_current_layout(path: &Path) -> bool {
    open_reader(path).is_ok_and(|b| LATER_COLUMNS.iter().all(|c| b.schema().index_of(c).is_ok()))
}

/// The keys of a segment, in row order: an engine segment's schema is checked whole (a segment
/// that is not one is damaged), a program pipeline's ([`PROGRAM_ROWS`]) only for its `key` column.
pub(crate) fn read_keys(path: &Path) -> anyhow::Result<Vec<Key>> {
    let builder = ParquetRecordBatchReaderBuilder::try_new(File::open(path)?)?;
    if !is_program_segment(&builder) {
        check_engine_schema(&builder)?;
    }
    let idx = builder.schema().index_of("key")?;
    let mask = ProjectionMask::roots(builder.parquet_schema(), [idx]);
    let mut out = Vec::new();
    for batch in builder.with_projection(mask).build()? {
        let batch = batch?;
        let col = column::<StringArray>(&batch, "key")?;
        for s in col.iter() {
            let s = s.ok_or_else(|| anyhow::anyhow!("null key"))?;
            out.push(Key::parse_hex(s).ok_or_else(|| anyhow::anyhow!("malformed key `{s}`"))?);
        }
    }
    Ok(out)
}

/// The outcome columns of one batch, decoded row by row: the one reading of them, shared by the
/// full read ([`read_segment`]) and the report's projected one (`episode_lengths` may be left out).
struct OutcomeColumns<'b> {
    key: &'b StringArray,
    converged: &'b BooleanArray,
    to_goal: &'b UInt32Array,
    episodes: &'b UInt32Array,
    total: &'b UInt64Array,
    stop: &'b StringArray,
    failure: &'b StringArray,
    seconds: &'b Float64Array,
    cpu: Option<&'b Float64Array>,
    lengths: Option<&'b ListArray>,
}

impl<'b> OutcomeColumns<'b> {
    fn of(b: &'b RecordBatch) -> anyhow::Result<Self> {
        Ok(Self {
            key: column(b, "key")?,
            converged: column(b, "converged")?,
            to_goal: column(b, "episodes_to_goal")?,
            episodes: column(b, "episodes")?,
            total: column(b, "total_steps")?,
            stop: column(b, "stop")?,
            failure: column(b, "failure")?,
            seconds: column(b, "seconds")?,
            // Absent in segments written before it existed (LATER_COLUMNS), or left out.
            cpu: column(b, "cpu_seconds").ok(),
            lengths: column(b, "episode_lengths").ok(),
        })
    }

    fn key(&self, i: usize) -> anyhow::Result<Key> {
        Key::parse_hex(self.key.value(i)).ok_or_else(|| anyhow::anyhow!("row {i}: malformed key"))
    }

    fn outcome(&self, i: usize) -> anyhow::Result<Outcome> {
        let stop = parse_stop(self.stop.value(i)).ok_or_else(|| anyhow::anyhow!("row {i}: unknown stop"))?;
        let episode_lengths = match self.lengths {
            Some(l) => l
                .value(i)
                .as_any()
                .downcast_ref::<UInt32Array>()
                .ok_or_else(|| anyhow::anyhow!("episode_lengths has an unexpected type"))?
                .values()
                .to_vec(),
            None => Vec::new(),
        };
        Ok(Outcome {
            converged: self.converged.value(i),
            episodes_to_goal: self.to_goal.is_valid(i).then(|| self.to_goal.value(i)),
            episodes: self.episodes.value(i),
            total_steps: self.total.value(i),
            stop,
            failure: self.failure.is_valid(i).then(|| self.failure.value(i).to_string()),
            episode_lengths,
        })
    }

    fn seconds(&self, i: usize) -> (f64, Option<f64>) {
        (self.seconds.value(i), self.cpu.filter(|c| c.is_valid(i)).map(|c| c.value(i)))
    }
}

/// Decode the rows of one segment whose key passes `keep`.
pub fn read_segment(path: &Path, keep: &dyn Fn(&Key) -> bool) -> anyhow::Result<Vec<TrialRecord>> {
    let reader = open_reader(path)?.build()?;
    let mut out = Vec::new();
    for batch in reader {
        let b = batch?;
        let cols = OutcomeColumns::of(&b)?;
        let version = column::<UInt32Array>(&b, "engine_version")?;
        let seed = column::<UInt64Array>(&b, "seed")?;
        let config = column::<StringArray>(&b, "config_json")?;
        for i in 0..b.num_rows() {
            let k = cols.key(i)?;
            if !keep(&k) {
                continue;
            }
            let cfg: TrialConfig = serde_json::from_str(config.value(i))
                .map_err(|e| anyhow::anyhow!("row {i}: config_json does not parse: {e}"))?;
            let (seconds, cpu_seconds) = cols.seconds(i);
            out.push(TrialRecord {
                key: k,
                engine_version: version.value(i),
                config: cfg,
                seed: seed.value(i),
                outcome: cols.outcome(i)?,
                seconds,
                cpu_seconds,
            });
        }
    }
    Ok(out)
}

/// Decode the outcome columns of the given rows (ascending) of one segment.
pub(super) fn read_outcome_rows(
    path: &Path,
    rows: &[usize],
    lengths: bool,
) -> anyhow::Result<Vec<(Key, StoredTrial)>> {
    use parquet::arrow::arrow_reader::{RowSelection, RowSelector};
    let builder = open_reader(path)?;
    let mut names =
        vec!["key", "converged", "episodes_to_goal", "episodes", "total_steps", "stop", "failure"];
    names.push("seconds");
    if builder.schema().index_of("cpu_seconds").is_ok() {
        names.push("cpu_seconds");
    }
    if lengths {
        names.push("episode_lengths");
    }
    let idx: Vec<usize> = names.iter().map(|n| builder.schema().index_of(n)).collect::<Result<_, _>>()?;
    let mask = ProjectionMask::roots(builder.parquet_schema(), idx);
    let mut selectors = Vec::new();
    let mut at = 0;
    for &r in rows {
        if r > at {
            selectors.push(RowSelector::skip(r - at));
        }
        selectors.push(RowSelector::select(1));
        at = r + 1;
    }
    let reader = builder.with_projection(mask).with_row_selection(RowSelection::from(selectors)).build()?;
    let mut out = Vec::with_capacity(rows.len());
    for batch in reader {
        let b = batch?;
        let cols = OutcomeColumns::of(&b)?;
        for i in 0..b.num_rows() {
            let (seconds, cpu_seconds) = cols.seconds(i);
            out.push((cols.key(i)?, StoredTrial { outcome: cols.outcome(i)?, seconds, cpu_seconds }));
        }
    }
    anyhow::ensure!(out.len() == rows.len(), "expected {} rows, read {}", rows.len(), out.len());
    Ok(out)
}

fn parse_stop(s: &str) -> Option<StopReason> {
    [StopReason::Goal, StopReason::MaxEpisodes, StopReason::MaxTotalSteps, StopReason::Diverged]
        .into_iter()
        .find(|r| r.name() == s)
}
