//! The append-only Parquet store: one directory of segment files, each a batch of trial rows.
//!
//! A segment is written to a hidden temp file (`.tmp-*`) in the cache directory and renamed into
//! place, so a trial is stored exactly when its row is in a renamed `seg-*.parquet`. Nothing is ever
//! rewritten in place; several processes may append at once (segment names are unique), and a trial
//! stored twice is identical by determinism, so duplicates are dropped on read. Reading which keys
//! exist reads only the `key` column.
//!
//! A segment that cannot be read (truncated, garbage, wrong schema) is reported as damaged and its
//! rows are treated as missing, so they are recomputed rather than served.
//!
//! The cache reads as one table in pandas (`pd.read_parquet("cache")`), polars
//! (`pl.read_parquet("cache/seg-*.parquet")`) and DuckDB (`read_parquet('cache/seg-*.parquet')`);
//! the schema is [`schema`].

use super::record::TrialRecord;
use super::Key;
use crate::sim::config::TrialConfig;
use crate::sim::{Outcome, StopReason};
use arrow::array::{
    Array, ArrayRef, BooleanArray, BooleanBuilder, Float64Array, Float64Builder, ListArray, ListBuilder,
    StringArray, StringBuilder, UInt32Array, UInt32Builder, UInt64Array, UInt64Builder,
};
use arrow::datatypes::{DataType, Field, Schema, SchemaRef};
use arrow::record_batch::RecordBatch;
use parquet::arrow::arrow_reader::ParquetRecordBatchReaderBuilder;
use parquet::arrow::{ArrowWriter, ProjectionMask};
use parquet::basic::{Compression, ZstdLevel};
use parquet::file::properties::WriterProperties;
use std::collections::HashSet;
use std::fs::File;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::{Arc, OnceLock};

/// Segment file names start with this and end with `.parquet`.
pub const SEGMENT_PREFIX: &str = "seg-";

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
pub fn schema() -> SchemaRef {
    static SCHEMA: OnceLock<SchemaRef> = OnceLock::new();
    SCHEMA
        .get_or_init(|| {
            let list = || DataType::List(Arc::new(Field::new("item", DataType::UInt32, true)));
            let f = |name: &str, t: DataType, null: bool| Field::new(name, t, null);
            Arc::new(Schema::new(vec![
                f("key", DataType::Utf8, false),
                f("engine_version", DataType::UInt32, false),
                f("system", DataType::Utf8, false),
                f("repr", DataType::Utf8, false),
                f("algorithm", DataType::Utf8, false),
                f("resolution", list(), false),
                f("actions", DataType::UInt32, false),
                f("epsilon", DataType::Float64, false),
                f("gamma", DataType::Float64, false),
                f("alpha", DataType::Float64, false),
                f("lambda", DataType::Float64, false),
                f("q_init", DataType::Float64, false),
                f("tie_break", DataType::Utf8, false),
                f("seed", DataType::UInt64, false),
                f("config_json", DataType::Utf8, false),
                f("converged", DataType::Boolean, false),
                f("episodes_to_goal", DataType::UInt32, true),
                f("episodes", DataType::UInt32, false),
                f("total_steps", DataType::UInt64, false),
                f("stop", DataType::Utf8, false),
                f("failure", DataType::Utf8, true),
                f("episode_lengths", list(), false),
                f("seconds", DataType::Float64, false),
            ]))
        })
        .clone()
}

/// A segment that could not be read, and why.
#[derive(Debug, Clone, PartialEq)]
pub struct Damaged {
    /// The segment file.
    pub path: PathBuf,
    /// What went wrong.
    pub error: String,
}

impl std::fmt::Display for Damaged {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}: {}", self.path.display(), self.error)
    }
}

/// The keys present in the cache, and the segments that could not be read.
#[derive(Debug, Default)]
pub struct KeyScan {
    /// Every stored key.
    pub keys: HashSet<Key>,
    /// Unreadable segments (their rows count as missing).
    pub damaged: Vec<Damaged>,
}

/// A cache directory.
#[derive(Debug, Clone)]
pub struct Store {
    dir: PathBuf,
}

impl Store {
    /// Open (creating if needed) the cache directory.
    pub fn open(dir: &Path) -> std::io::Result<Self> {
        std::fs::create_dir_all(dir)?;
        if !std::fs::metadata(dir)?.is_dir() {
            return Err(std::io::Error::other("not a directory"));
        }
        Ok(Self { dir: dir.to_path_buf() })
    }

    /// The cache directory.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// Every segment file, sorted by name (so reads are deterministic).
    pub fn segments(&self) -> anyhow::Result<Vec<PathBuf>> {
        let mut out = Vec::new();
        let entries = std::fs::read_dir(&self.dir)
            .map_err(|e| anyhow::anyhow!("cannot list cache {}: {e}", self.dir.display()))?;
        for entry in entries {
            let entry = entry?;
            let name = entry.file_name();
            let name = name.to_string_lossy();
            if name.starts_with(SEGMENT_PREFIX) && name.ends_with(".parquet") && entry.file_type()?.is_file()
            {
                out.push(entry.path());
            }
        }
        out.sort();
        Ok(out)
    }

    /// Append `records` as one new segment (temp file + fsync + rename); returns its path.
    pub fn write_segment(&self, records: &[TrialRecord]) -> anyhow::Result<PathBuf> {
        anyhow::ensure!(!records.is_empty(), "refusing to write an empty segment");
        let batch = to_batch(records)?;
        let name = segment_name(records);
        let path = self.dir.join(&name);
        let tmp = self.dir.join(format!(".tmp-{name}"));
        let result = (|| -> anyhow::Result<()> {
            let file = File::create(&tmp)?;
            let props = WriterProperties::builder()
                .set_compression(Compression::ZSTD(ZstdLevel::try_new(3)?))
                .set_created_by(format!("qsweep {}", env!("CARGO_PKG_VERSION")))
                .build();
            let mut w = ArrowWriter::try_new(file, batch.schema(), Some(props))?;
            w.write(&batch)?;
            let mut file = w.into_inner()?;
            file.flush()?;
            file.sync_all()?;
            std::fs::rename(&tmp, &path)?;
            Ok(())
        })();
        if let Err(e) = result {
            let _ = std::fs::remove_file(&tmp);
            return Err(e.context(format!("cannot write cache segment in {}", self.dir.display())));
        }
        // Make the rename durable too; best effort (not every filesystem allows opening a dir).
        if let Ok(d) = File::open(&self.dir) {
            let _ = d.sync_all();
        }
        Ok(path)
    }

    /// Every stored key, reading only the `key` column of each segment.
    pub fn keys(&self) -> anyhow::Result<KeyScan> {
        let mut scan = KeyScan::default();
        for path in self.segments()? {
            match read_keys(&path) {
                Ok(keys) => scan.keys.extend(keys),
                Err(e) => scan.damaged.push(Damaged { path, error: format!("{e:#}") }),
            }
        }
        Ok(scan)
    }

    /// The stored records whose key is in `wanted`, one per key (duplicates dropped), in segment
    /// order. Unreadable segments are skipped (see [`Store::keys`] to list them).
    pub fn read(&self, wanted: &HashSet<Key>) -> anyhow::Result<Vec<TrialRecord>> {
        self.read_filtered(|k| wanted.contains(k))
    }

    /// Every stored record, one per key.
    pub fn read_all(&self) -> anyhow::Result<Vec<TrialRecord>> {
        self.read_filtered(|_| true)
    }

    fn read_filtered(&self, keep: impl Fn(&Key) -> bool) -> anyhow::Result<Vec<TrialRecord>> {
        let mut seen = HashSet::new();
        let mut out = Vec::new();
        for path in self.segments()? {
            let Ok(records) = read_segment(&path, &|k| keep(k) && !seen.contains(k)) else { continue };
            for r in records {
                if seen.insert(r.key) {
                    out.push(r);
                }
            }
        }
        Ok(out)
    }
}

/// A name no other writer picks: a hash of the batch's keys, the process and the time.
fn segment_name(records: &[TrialRecord]) -> String {
    let mut h = blake3::Hasher::new();
    for r in records {
        h.update(&r.key.0);
    }
    h.update(&std::process::id().to_le_bytes());
    let nanos =
        std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).map_or(0, |d| d.as_nanos());
    h.update(&nanos.to_le_bytes());
    format!("{SEGMENT_PREFIX}{}.parquet", &h.finalize().to_hex()[..32])
}

/// Encode records as one Arrow batch with [`schema`].
pub fn to_batch(records: &[TrialRecord]) -> anyhow::Result<RecordBatch> {
    let n = records.len();
    let mut key = StringBuilder::new();
    let mut version = UInt32Builder::with_capacity(n);
    let (mut system, mut repr, mut algorithm) =
        (StringBuilder::new(), StringBuilder::new(), StringBuilder::new());
    let mut resolution = ListBuilder::new(UInt32Builder::new());
    let mut actions = UInt32Builder::with_capacity(n);
    let mut hyper: [Float64Builder; 5] = std::array::from_fn(|_| Float64Builder::with_capacity(n));
    let mut tie = StringBuilder::new();
    let mut seed = UInt64Builder::with_capacity(n);
    let mut config_json = StringBuilder::new();
    let mut converged = BooleanBuilder::with_capacity(n);
    let mut to_goal = UInt32Builder::with_capacity(n);
    let mut episodes = UInt32Builder::with_capacity(n);
    let mut total_steps = UInt64Builder::with_capacity(n);
    let mut stop = StringBuilder::new();
    let mut failure = StringBuilder::new();
    let mut lengths = ListBuilder::new(UInt32Builder::new());
    let mut seconds = Float64Builder::with_capacity(n);
    for r in records {
        let c = &r.config;
        key.append_value(r.key.hex());
        version.append_value(r.engine_version);
        system.append_value(c.system().name());
        repr.append_value(c.repr.kind.name());
        algorithm.append_value(c.learner.algorithm.name());
        resolution.values().append_slice(&c.repr.resolution);
        resolution.append(true);
        actions.append_value(c.actions);
        let l = &c.learner;
        for (b, v) in hyper.iter_mut().zip([l.epsilon, l.gamma, l.alpha, l.lambda, l.q_init]) {
            b.append_value(v);
        }
        tie.append_value(match l.tie_break {
            crate::sim::config::TieBreak::Random => "random",
            crate::sim::config::TieBreak::First => "first",
        });
        seed.append_value(r.seed);
        config_json.append_value(r.config_json());
        let o = &r.outcome;
        converged.append_value(o.converged);
        to_goal.append_option(o.episodes_to_goal);
        episodes.append_value(o.episodes);
        total_steps.append_value(o.total_steps);
        stop.append_value(o.stop.name());
        failure.append_option(o.failure.as_deref());
        lengths.values().append_slice(&o.episode_lengths);
        lengths.append(true);
        seconds.append_value(r.seconds);
    }
    let [eps, gamma, alpha, lambda, q_init] = hyper.map(|mut b| Arc::new(b.finish()) as ArrayRef);
    let columns: Vec<ArrayRef> = vec![
        Arc::new(key.finish()),
        Arc::new(version.finish()),
        Arc::new(system.finish()),
        Arc::new(repr.finish()),
        Arc::new(algorithm.finish()),
        Arc::new(resolution.finish()),
        Arc::new(actions.finish()),
        eps,
        gamma,
        alpha,
        lambda,
        q_init,
        Arc::new(tie.finish()),
        Arc::new(seed.finish()),
        Arc::new(config_json.finish()),
        Arc::new(converged.finish()),
        Arc::new(to_goal.finish()),
        Arc::new(episodes.finish()),
        Arc::new(total_steps.finish()),
        Arc::new(stop.finish()),
        Arc::new(failure.finish()),
        Arc::new(lengths.finish()),
        Arc::new(seconds.finish()),
    ];
    // Builders make nullable list items; cast the batch to the declared schema's exact fields.
    let schema = schema();
    let columns = columns
        .into_iter()
        .zip(schema.fields())
        .map(
            |(c, f)| {
                if c.data_type() == f.data_type() {
                    Ok(c)
                } else {
                    arrow::compute::cast(&c, f.data_type())
                }
            },
        )
        .collect::<Result<Vec<_>, _>>()?;
    Ok(RecordBatch::try_new(schema, columns)?)
}

fn open_reader(path: &Path) -> anyhow::Result<ParquetRecordBatchReaderBuilder<File>> {
    let file = File::open(path)?;
    let builder = ParquetRecordBatchReaderBuilder::try_new(file)?;
    let expected = schema();
    let found = builder.schema();
    for f in expected.fields() {
        match found.field_with_name(f.name()) {
            Ok(g) if g.data_type() == f.data_type() => {}
            Ok(g) => {
                anyhow::bail!("column `{}` has type {}, expected {}", f.name(), g.data_type(), f.data_type())
            }
            Err(_) => anyhow::bail!("column `{}` is missing (not a qsweep segment?)", f.name()),
        }
    }
    Ok(builder)
}

fn read_keys(path: &Path) -> anyhow::Result<Vec<Key>> {
    let builder = open_reader(path)?;
    let idx = builder.schema().index_of("key")?;
    let mask = ProjectionMask::roots(builder.parquet_schema(), [idx]);
    let mut out = Vec::new();
    for batch in builder.with_projection(mask).build()? {
        let batch = batch?;
        let col = downcast::<StringArray>(&batch, "key")?;
        for s in col.iter() {
            let s = s.ok_or_else(|| anyhow::anyhow!("null key"))?;
            out.push(Key::parse_hex(s).ok_or_else(|| anyhow::anyhow!("malformed key `{s}`"))?);
        }
    }
    Ok(out)
}

fn downcast<'a, T: 'static>(batch: &'a RecordBatch, name: &str) -> anyhow::Result<&'a T> {
    batch
        .column_by_name(name)
        .ok_or_else(|| anyhow::anyhow!("column `{name}` is missing"))?
        .as_any()
        .downcast_ref::<T>()
        .ok_or_else(|| anyhow::anyhow!("column `{name}` has an unexpected type"))
}

/// Decode the rows of one segment whose key passes `keep`.
pub fn read_segment(path: &Path, keep: &dyn Fn(&Key) -> bool) -> anyhow::Result<Vec<TrialRecord>> {
    let reader = open_reader(path)?.build()?;
    let mut out = Vec::new();
    for batch in reader {
        let b = batch?;
        let key = downcast::<StringArray>(&b, "key")?;
        let version = downcast::<UInt32Array>(&b, "engine_version")?;
        let seed = downcast::<UInt64Array>(&b, "seed")?;
        let config = downcast::<StringArray>(&b, "config_json")?;
        let converged = downcast::<BooleanArray>(&b, "converged")?;
        let to_goal = downcast::<UInt32Array>(&b, "episodes_to_goal")?;
        let episodes = downcast::<UInt32Array>(&b, "episodes")?;
        let total = downcast::<UInt64Array>(&b, "total_steps")?;
        let stop = downcast::<StringArray>(&b, "stop")?;
        let failure = downcast::<StringArray>(&b, "failure")?;
        let lengths = downcast::<ListArray>(&b, "episode_lengths")?;
        let seconds = downcast::<Float64Array>(&b, "seconds")?;
        for i in 0..b.num_rows() {
            let k = Key::parse_hex(key.value(i)).ok_or_else(|| anyhow::anyhow!("row {i}: malformed key"))?;
            if !keep(&k) {
                continue;
            }
            let cfg: TrialConfig = serde_json::from_str(config.value(i))
                .map_err(|e| anyhow::anyhow!("row {i}: config_json does not parse: {e}"))?;
            let stop = parse_stop(stop.value(i)).ok_or_else(|| anyhow::anyhow!("row {i}: unknown stop"))?;
            let lens = lengths.value(i);
            let lens = lens
                .as_any()
                .downcast_ref::<UInt32Array>()
                .ok_or_else(|| anyhow::anyhow!("episode_lengths has an unexpected type"))?;
            out.push(TrialRecord {
                key: k,
                engine_version: version.value(i),
                config: cfg,
                seed: seed.value(i),
                outcome: Outcome {
                    converged: converged.value(i),
                    episodes_to_goal: to_goal.is_valid(i).then(|| to_goal.value(i)),
                    episodes: episodes.value(i),
                    total_steps: total.value(i),
                    stop,
                    failure: failure.is_valid(i).then(|| failure.value(i).to_string()),
                    episode_lengths: lens.values().to_vec(),
                },
                seconds: seconds.value(i),
            });
        }
    }
    Ok(out)
}

fn parse_stop(s: &str) -> Option<StopReason> {
    [StopReason::Goal, StopReason::MaxEpisodes, StopReason::MaxTotalSteps, StopReason::Diverged]
        .into_iter()
        .find(|r| r.name() == s)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sim::env::SystemKind;
    use crate::sim::repr::ReprKind;
    use crate::sim::{run_trial, Algorithm};

    fn records() -> Vec<TrialRecord> {
        let mut out = Vec::new();
        for (sys, res) in [(SystemKind::BallBeam, vec![3, 2]), (SystemKind::MountainCar, vec![2, 2])] {
            for repr in [ReprKind::Crisp, ReprKind::Fuzzy] {
                let mut c = TrialConfig::paper(sys, repr, Algorithm::QLambda, res.clone(), 3);
                c.limits.max_episodes = 5;
                for seed in 0..2 {
                    let o = run_trial(&c, seed);
                    out.push(TrialRecord::new(c.clone(), seed, o, 0.5));
                }
            }
        }
        out
    }

    #[test]
    fn segments_round_trip_every_field() {
        let dir = tempfile::tempdir().unwrap();
        let store = Store::open(dir.path()).unwrap();
        let recs = records();
        store.write_segment(&recs[..3]).unwrap();
        store.write_segment(&recs[3..]).unwrap();
        // A duplicate segment (another process computed the same trials) is dropped on read.
        store.write_segment(&recs[..2]).unwrap();
        assert_eq!(store.segments().unwrap().len(), 3);
        let scan = store.keys().unwrap();
        assert!(scan.damaged.is_empty());
        assert_eq!(scan.keys, recs.iter().map(|r| r.key).collect());
        let mut back = store.read_all().unwrap();
        back.sort_by_key(|r| r.key);
        let mut want = recs.clone();
        want.sort_by_key(|r| r.key);
        assert_eq!(back, want);
        let one: HashSet<_> = [recs[4].key].into();
        assert_eq!(store.read(&one).unwrap(), vec![recs[4].clone()]);
        // No temp files are left behind.
        let names: Vec<_> = std::fs::read_dir(dir.path()).unwrap().map(|e| e.unwrap().file_name()).collect();
        assert!(names.iter().all(|n| n.to_string_lossy().starts_with(SEGMENT_PREFIX)), "{names:?}");
    }

    #[test]
    fn a_segment_with_the_wrong_schema_is_damaged() {
        let dir = tempfile::tempdir().unwrap();
        let store = Store::open(dir.path()).unwrap();
        let schema = Arc::new(Schema::new(vec![Field::new("key", DataType::UInt64, false)]));
        let batch =
            RecordBatch::try_new(schema.clone(), vec![Arc::new(UInt64Array::from(vec![1u64, 2]))]).unwrap();
        let file = File::create(dir.path().join("seg-other.parquet")).unwrap();
        let mut w = ArrowWriter::try_new(file, schema, None).unwrap();
        w.write(&batch).unwrap();
        w.close().unwrap();
        let scan = store.keys().unwrap();
        assert!(scan.keys.is_empty());
        assert_eq!(scan.damaged.len(), 1);
        assert!(scan.damaged[0].error.contains("column `key` has type UInt64"), "{}", scan.damaged[0].error);
    }

    #[test]
    fn a_garbage_segment_is_reported_and_its_rows_count_as_missing() {
        let dir = tempfile::tempdir().unwrap();
        let store = Store::open(dir.path()).unwrap();
        let recs = records();
        store.write_segment(&recs[..2]).unwrap();
        std::fs::write(dir.path().join("seg-garbage.parquet"), b"not parquet at all").unwrap();
        let scan = store.keys().unwrap();
        assert_eq!(scan.keys.len(), 2);
        assert_eq!(scan.damaged.len(), 1);
        assert!(scan.damaged[0].path.ends_with("seg-garbage.parquet"));
        assert_eq!(store.read_all().unwrap().len(), 2);
    }
}
