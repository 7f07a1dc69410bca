//! A program pipeline's rows as typed Parquet: one row per trial, one column per param and per
//! declared metric in their own Arrow types, so pandas, polars and DuckDB read them without
//! parsing JSON. The rows of one schema (the same params and metrics, `model::schema_id`) live in
//! a store folder of their own, `<cache>/_programs/<schema-id>/` ([`folder`]), so a segment never
//! mixes schemas; each segment is marked as a program's (`cache::rows::PROGRAM_ROWS`), so the
//! store scans it for its keys like any other.
//!
//! | column | type | meaning |
//! |---|---|---|
//! | `key` | utf8 | the trial's key, 64 hex characters |
//! | `seed` | uint64 | its seed |
//! | one per param | int64, float64, bool or utf8 | the param's value |
//! | `status` | utf8 | `ok` or `failed` |
//! | one per metric | int64, float64, bool, utf8, list<float64> or list<uint32>, null | the metric (null when failed) |
//! | `exit_code` | int32, null | the exit code of a failed trial (null: it exited 0 with a bad result) |
//! | `error` | utf8, null | why it failed, naming the line and the field for a bad result |
//! | `stderr_tail` | utf8, null | the end of a failed trial's stderr |
//! | `seconds` | float64 | wall-clock seconds |
//! | `cpu_seconds` | float64, null | CPU seconds of the program and its waited-for children |
//! | `command` | utf8 | the command as run (JSON array) |
//! | `inputs` | utf8 | the input files' blake3 digests (JSON object) |
//! | `provenance` | utf8 | the provenance commands' outputs (JSON array) |

use super::model::{Failure, MetricType, MetricValue, ParamType, ParamValue, ProgramRow};
use crate::cache::rows::PROGRAM_ROWS;
use crate::cache::store::Store;
use crate::cache::Key;
use arrow::array::{
    Array, ArrayRef, BooleanArray, BooleanBuilder, Float64Array, Float64Builder, Int32Array, Int64Array,
    Int64Builder, ListArray, ListBuilder, StringArray, StringBuilder, UInt32Array, UInt32Builder,
    UInt64Array,
};
use arrow::datatypes::{DataType, Field, Schema, SchemaRef};
use arrow::record_batch::RecordBatch;
use parquet::arrow::arrow_reader::ParquetRecordBatchReaderBuilder;
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

pub use super::model::FIXED_COLUMNS;

/// The typed columns of one schema: its params and metrics, in declared order.
#[derive(Debug, Clone, PartialEq)]
pub struct RowSchema {
    /// Params with their types.
    pub params: Vec<(String, ParamType)>,
    /// Metrics with their types.
    pub metrics: Vec<(String, MetricType)>,
}

impl RowSchema {
    /// Its id (`model::schema_id`).
    pub fn id(&self) -> String {
        super::model::schema_id(&self.params, &self.metrics)
    }

    /// The Arrow schema of its rows, marked as a program's.
    pub fn arrow(&self) -> SchemaRef {
        let mut fields =
            vec![Field::new("key", DataType::Utf8, false), Field::new("seed", DataType::UInt64, false)];
        fields.extend(self.params.iter().map(|(n, t)| Field::new(n, param_type(*t), false)));
        fields.push(Field::new("status", DataType::Utf8, false));
        fields.extend(self.metrics.iter().map(|(n, t)| Field::new(n, metric_type(*t), true)));
        fields.extend([
            Field::new("exit_code", DataType::Int32, true),
            Field::new("error", DataType::Utf8, true),
            Field::new("stderr_tail", DataType::Utf8, true),
            Field::new("seconds", DataType::Float64, false),
            Field::new("cpu_seconds", DataType::Float64, true),
            Field::new("command", DataType::Utf8, false),
            Field::new("inputs", DataType::Utf8, false),
            Field::new("provenance", DataType::Utf8, false),
        ]);
        let meta = HashMap::from([(PROGRAM_ROWS.to_string(), self.id())]);
        Arc::new(Schema::new_with_metadata(fields, meta))
    }
}

/// The Arrow type of a param's column.
pub fn param_type(t: ParamType) -> DataType {
    match t {
        ParamType::Int => DataType::Int64,
        ParamType::Float => DataType::Float64,
        ParamType::Bool => DataType::Boolean,
        ParamType::Str => DataType::Utf8,
    }
}

/// The Arrow type of a metric's column.
pub fn metric_type(t: MetricType) -> DataType {
    match t {
        MetricType::Int => DataType::Int64,
        MetricType::Float => DataType::Float64,
        MetricType::Bool => DataType::Boolean,
        MetricType::Str => DataType::Utf8,
        MetricType::ListFloat => DataType::List(Arc::new(Field::new_list_field(DataType::Float64, false))),
        MetricType::ListU32 => DataType::List(Arc::new(Field::new_list_field(DataType::UInt32, false))),
    }
}

/// The folder of the cache that holds program pipelines' rows: its leading `_` keeps pandas, polars
/// and pyarrow, reading the cache folder as a dataset of engine rows, from taking these too.
pub const PROGRAMS_DIR: &str = "_programs";

/// The store folder of rows of `schema` in the cache at `cache`: `<cache>/_programs/<schema-id>/`.
pub fn folder(cache: &Path, schema: &RowSchema) -> PathBuf {
    cache.join(PROGRAMS_DIR).join(schema.id())
}

/// `rows` as one Arrow batch of `schema`.
pub fn to_batch(schema: &RowSchema, rows: &[ProgramRow]) -> anyhow::Result<RecordBatch> {
    let mut cols: Vec<ArrayRef> = vec![
        Arc::new(StringArray::from_iter_values(rows.iter().map(|r| r.key.hex()))),
        Arc::new(UInt64Array::from_iter_values(rows.iter().map(|r| r.seed))),
    ];
    for (j, (name, t)) in schema.params.iter().enumerate() {
        cols.push(param_column(name, *t, rows.iter().map(|r| r.params.get(j)))?);
    }
    cols.push(Arc::new(StringArray::from_iter_values(rows.iter().map(|r| {
        if r.result.is_ok() {
            "ok"
        } else {
            "failed"
        }
    }))));
    for (j, (name, t)) in schema.metrics.iter().enumerate() {
        let values = rows.iter().map(|r| r.result.as_ref().ok().and_then(|m| m.get(j)));
        cols.push(metric_column(name, *t, values)?);
    }
    cols.push(Arc::new(rows.iter().map(|r| failure(r).and_then(|f| f.exit_code)).collect::<Int32Array>()));
    cols.push(Arc::new(rows.iter().map(|r| failure(r).map(|f| f.reason.as_str())).collect::<StringArray>()));
    cols.push(Arc::new(
        rows.iter().map(|r| failure(r).map(|f| f.stderr_tail.as_str())).collect::<StringArray>(),
    ));
    cols.push(Arc::new(Float64Array::from_iter_values(rows.iter().map(|r| r.seconds))));
    cols.push(Arc::new(rows.iter().map(|r| r.cpu_seconds).collect::<Float64Array>()));
    cols.push(Arc::new(StringArray::from_iter_values(rows.iter().map(|r| r.command_json.as_str()))));
    cols.push(Arc::new(StringArray::from_iter_values(rows.iter().map(|r| r.inputs_json.as_str()))));
    cols.push(Arc::new(StringArray::from_iter_values(rows.iter().map(|r| r.provenance_json.as_str()))));
    Ok(RecordBatch::try_new(schema.arrow(), cols)?)
}

/// A failed row's failure.
fn failure(r: &ProgramRow) -> Option<&Failure> {
    r.result.as_ref().err()
}

/// A column of `t` holding `values` (an int accepted where a float is declared); an error names the param.
pub fn param_column<'a>(
    name: &str,
    t: ParamType,
    values: impl Iterator<Item = Option<&'a ParamValue>>,
) -> anyhow::Result<ArrayRef> {
    let wrong = |v: Option<&ParamValue>| anyhow::anyhow!("param `{name}`: {v:?} is not a {}", t.name());
    Ok(match t {
        ParamType::Int => {
            let mut b = Int64Builder::new();
            for v in values {
                let ParamValue::Int(i) = v.ok_or_else(|| wrong(v))? else { return Err(wrong(v)) };
                b.append_value(*i);
            }
            Arc::new(b.finish())
        }
        ParamType::Float => {
            let mut b = Float64Builder::new();
            for v in values {
                match v {
                    Some(ParamValue::Float(x)) => b.append_value(*x),
                    Some(ParamValue::Int(i)) => b.append_value(*i as f64),
                    other => return Err(wrong(other)),
                }
            }
            Arc::new(b.finish())
        }
        ParamType::Bool => {
            let mut b = BooleanBuilder::new();
            for v in values {
                let Some(ParamValue::Bool(x)) = v else { return Err(wrong(v)) };
                b.append_value(*x);
            }
            Arc::new(b.finish())
        }
        ParamType::Str => {
            let mut b = StringBuilder::new();
            for v in values {
                let Some(ParamValue::Str(x)) = v else { return Err(wrong(v)) };
                b.append_value(x);
            }
            Arc::new(b.finish())
        }
    })
}

fn metric_column<'a>(
    name: &str,
    t: MetricType,
    values: impl Iterator<Item = Option<&'a MetricValue>>,
) -> anyhow::Result<ArrayRef> {
    let wrong = |v: &MetricValue| anyhow::anyhow!("metric `{name}`: {v:?} is not a {}", t.name());
    macro_rules! build {
        ($builder:expr, $variant:ident, |$b:ident, $x:ident| $append:expr) => {{
            let mut $b = $builder;
            for v in values {
                match v {
                    None => $b.append_null(),
                    Some(MetricValue::$variant($x)) => $append,
                    Some(other) => return Err(wrong(other)),
                }
            }
            Arc::new($b.finish()) as ArrayRef
        }};
    }
    Ok(match t {
        MetricType::Int => build!(Int64Builder::new(), Int, |b, x| b.append_value(*x)),
        MetricType::Float => build!(Float64Builder::new(), Float, |b, x| b.append_value(*x)),
        MetricType::Bool => build!(BooleanBuilder::new(), Bool, |b, x| b.append_value(*x)),
        MetricType::Str => build!(StringBuilder::new(), Str, |b, x| b.append_value(x)),
        MetricType::ListFloat => {
            let field = Arc::new(Field::new_list_field(DataType::Float64, false));
            build!(ListBuilder::new(Float64Builder::new()).with_field(field), ListFloat, |b, x| {
                b.values().append_slice(x);
                b.append(true)
            })
        }
        MetricType::ListU32 => {
            let field = Arc::new(Field::new_list_field(DataType::UInt32, false));
            build!(ListBuilder::new(UInt32Builder::new()).with_field(field), ListU32, |b, x| {
                b.values().append_slice(x);
                b.append(true)
            })
        }
    })
}

/// Store `rows` (of `schema`) as one new segment of `store` (the schema's folder).
pub fn write_segment(store: &Store, schema: &RowSchema, rows: &[ProgramRow]) -> anyhow::Result<PathBuf> {
    let keys: Vec<Key> = rows.iter().map(|r| r.key).collect();
    store.write_batch(&keys, &to_batch(schema, rows)?)
}

/// The rows of one segment of `schema` whose key `keep` accepts, in row order. A segment of
/// another schema (a column missing or of another type) is an error naming the column.
pub fn read_segment(
    path: &Path,
    schema: &RowSchema,
    keep: &dyn Fn(&Key) -> bool,
) -> anyhow::Result<Vec<ProgramRow>> {
    let builder = ParquetRecordBatchReaderBuilder::try_new(std::fs::File::open(path)?)?;
    let expected = schema.arrow();
    for f in expected.fields() {
        let found = builder.schema().field_with_name(f.name()).map_err(|_| {
            anyhow::anyhow!("column `{}` is missing (a segment of another schema?)", f.name())
        })?;
        anyhow::ensure!(
            found.data_type() == f.data_type(),
            "column `{}` has type {}, expected {}",
            f.name(),
            found.data_type(),
            f.data_type()
        );
    }
    let mut out = Vec::new();
    for batch in builder.build()? {
        out.extend(from_batch(schema, &batch?)?.into_iter().filter(|r| keep(&r.key)));
    }
    Ok(out)
}

/// The rows of `batch`, a batch of `schema`.
pub fn from_batch(schema: &RowSchema, batch: &RecordBatch) -> anyhow::Result<Vec<ProgramRow>> {
    use crate::parquet_io::column;
    let n = batch.num_rows();
    let keys = column::<StringArray>(batch, "key")?;
    let seeds = column::<UInt64Array>(batch, "seed")?;
    let status = column::<StringArray>(batch, "status")?;
    let exit = column::<Int32Array>(batch, "exit_code")?;
    let error = column::<StringArray>(batch, "error")?;
    let stderr = column::<StringArray>(batch, "stderr_tail")?;
    let seconds = column::<Float64Array>(batch, "seconds")?;
    let cpu = column::<Float64Array>(batch, "cpu_seconds")?;
    let command = column::<StringArray>(batch, "command")?;
    let inputs = column::<StringArray>(batch, "inputs")?;
    let provenance = column::<StringArray>(batch, "provenance")?;
    let params: Vec<Vec<ParamValue>> =
        schema.params.iter().map(|(name, t)| read_params(batch, name, *t)).collect::<anyhow::Result<_>>()?;
    let metrics: Vec<Vec<Option<MetricValue>>> = schema
        .metrics
        .iter()
        .map(|(name, t)| read_metrics(batch, name, *t))
        .collect::<anyhow::Result<_>>()?;
    (0..n)
        .map(|i| {
            let key = keys.value(i);
            let result = if status.value(i) == "ok" {
                let values: Option<Vec<MetricValue>> = metrics.iter().map(|m| m[i].clone()).collect();
                Ok(values.ok_or_else(|| anyhow::anyhow!("row {key}: a metric of an `ok` row is null"))?)
            } else {
                Err(Failure {
                    exit_code: (!exit.is_null(i)).then(|| exit.value(i)),
                    reason: text_or_empty(error, i),
                    stderr_tail: text_or_empty(stderr, i),
                })
            };
            Ok(ProgramRow {
                key: Key::parse_hex(key).ok_or_else(|| anyhow::anyhow!("malformed key `{key}`"))?,
                seed: seeds.value(i),
                params: params.iter().map(|p| p[i].clone()).collect(),
                result,
                seconds: seconds.value(i),
                cpu_seconds: cpu.is_valid(i).then(|| cpu.value(i)),
                command_json: command.value(i).to_string(),
                inputs_json: inputs.value(i).to_string(),
                provenance_json: provenance.value(i).to_string(),
            })
        })
        .collect()
}

/// Row `i` of a nullable text column, a null as empty.
fn text_or_empty(c: &StringArray, i: usize) -> String {
    if c.is_valid(i) {
        c.value(i).to_string()
    } else {
        String::new()
    }
}

fn read_params(batch: &RecordBatch, name: &str, t: ParamType) -> anyhow::Result<Vec<ParamValue>> {
    use crate::parquet_io::column;
    let n = batch.num_rows();
    Ok(match t {
        ParamType::Int => {
            let c = column::<Int64Array>(batch, name)?;
            (0..n).map(|i| ParamValue::Int(c.value(i))).collect()
        }
        ParamType::Float => {
            let c = column::<Float64Array>(batch, name)?;
            (0..n).map(|i| ParamValue::Float(c.value(i))).collect()
        }
        ParamType::Bool => {
            let c = column::<BooleanArray>(batch, name)?;
            (0..n).map(|i| ParamValue::Bool(c.value(i))).collect()
        }
        ParamType::Str => {
            let c = column::<StringArray>(batch, name)?;
            (0..n).map(|i| ParamValue::Str(c.value(i).to_string())).collect()
        }
    })
}

fn read_metrics(batch: &RecordBatch, name: &str, t: MetricType) -> anyhow::Result<Vec<Option<MetricValue>>> {
    use crate::parquet_io::column;
    let n = batch.num_rows();
    macro_rules! read {
        ($array:ty, |$c:ident, $i:ident| $value:expr) => {{
            let $c = column::<$array>(batch, name)?;
            (0..n).map(|$i| $c.is_valid($i).then(|| $value)).collect()
        }};
    }
    fn list<T: Array + Clone + 'static>(c: &ListArray, i: usize) -> T {
        c.value(i).as_any().downcast_ref::<T>().expect("the list's item type is the schema's").clone()
    }
    Ok(match t {
        MetricType::Int => read!(Int64Array, |c, i| MetricValue::Int(c.value(i))),
        MetricType::Float => read!(Float64Array, |c, i| MetricValue::Float(c.value(i))),
        MetricType::Bool => read!(BooleanArray, |c, i| MetricValue::Bool(c.value(i))),
        MetricType::Str => read!(StringArray, |c, i| MetricValue::Str(c.value(i).to_string())),
        MetricType::ListFloat => {
            read!(ListArray, |c, i| MetricValue::ListFloat(list::<Float64Array>(c, i).values().to_vec()))
        }
        MetricType::ListU32 => {
            read!(ListArray, |c, i| MetricValue::ListU32(list::<UInt32Array>(c, i).values().to_vec()))
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn schema() -> RowSchema {
        RowSchema {
            params: vec![
                ("env".into(), ParamType::Str),
                ("alpha".into(), ParamType::Float),
                ("bins".into(), ParamType::Int),
                ("fast".into(), ParamType::Bool),
            ],
            metrics: vec![
                ("episodes".into(), MetricType::Int),
                ("loss".into(), MetricType::Float),
                ("solved".into(), MetricType::Bool),
                ("note".into(), MetricType::Str),
                ("returns".into(), MetricType::ListFloat),
                ("lengths".into(), MetricType::ListU32),
            ],
        }
    }

    fn row(seed: u64, ok: bool) -> ProgramRow {
        let key = Key(*blake3::hash(&seed.to_le_bytes()).as_bytes());
        let result = if ok {
            Ok(vec![
                MetricValue::Int(42),
                MetricValue::Float(0.25),
                MetricValue::Bool(true),
                MetricValue::Str("fine ✓".into()),
                MetricValue::ListFloat(vec![1.0, -2.5]),
                MetricValue::ListU32(vec![]),
            ])
        } else {
            Err(Failure { exit_code: Some(3), reason: "exit 3".into(), stderr_tail: "Traceback…".into() })
        };
        ProgramRow {
            key,
            seed,
            params: vec![
                ParamValue::Str("CartPole-v1".into()),
                ParamValue::Float(0.1),
                ParamValue::Int(6),
                ParamValue::Bool(false),
            ],
            result,
            seconds: 0.5,
            cpu_seconds: ok.then_some(0.4),
            command_json: r#"["python3","agent.py"]"#.into(),
            inputs_json: r#"{"agent.py":"ab"}"#.into(),
            provenance_json: "[]".into(),
        }
    }

    #[test]
    fn rows_round_trip_through_a_segment_with_their_types() {
        let dir = tempfile::tempdir().unwrap();
        let s = schema();
        let store = Store::open(&folder(dir.path(), &s)).unwrap();
        let rows = vec![row(1, true), row(2, false), row(3, true)];
        let path = write_segment(&store, &s, &rows).unwrap();
        assert!(path.starts_with(dir.path().join(PROGRAMS_DIR).join(s.id())));
        assert_eq!(read_segment(&path, &s, &|_| true).unwrap(), rows);
        assert_eq!(read_segment(&path, &s, &|k| *k == rows[1].key).unwrap(), vec![rows[1].clone()]);
        // The store scans it for its keys like any segment, whatever its columns.
        let scan = store.keys().unwrap();
        assert!(scan.damaged.is_empty(), "{:?}", scan.damaged);
        assert_eq!(scan.keys.len(), 3);
        // Typed columns: what a reader of the Parquet sees.
        let batch = to_batch(&s, &rows).unwrap();
        assert_eq!(batch.schema().field_with_name("alpha").unwrap().data_type(), &DataType::Float64);
        assert_eq!(batch.schema().field_with_name("episodes").unwrap().data_type(), &DataType::Int64);
        assert!(matches!(batch.schema().field_with_name("returns").unwrap().data_type(), DataType::List(_)));
        assert_eq!(batch.schema().metadata()[PROGRAM_ROWS], s.id());
    }

    #[test]
    fn a_segment_of_another_schema_is_an_error_naming_the_column() {
        let dir = tempfile::tempdir().unwrap();
        let s = schema();
        let store = Store::open(dir.path()).unwrap();
        let path = write_segment(&store, &s, &[row(1, true)]).unwrap();
        let mut other = schema();
        other.metrics[0].1 = MetricType::Float;
        let e = read_segment(&path, &other, &|_| true).unwrap_err().to_string();
        assert!(e.contains("column `episodes` has type Int64, expected Float64"), "{e}");
        assert_ne!(s.id(), other.id(), "another schema has another folder");
    }

    #[test]
    fn a_value_of_the_wrong_type_is_refused_not_written() {
        let s = schema();
        let mut r = row(1, true);
        r.params[2] = ParamValue::Str("six".into());
        assert!(to_batch(&s, &[r]).unwrap_err().to_string().contains("param `bins`"));
    }
}
