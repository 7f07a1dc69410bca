//! The program folders of a cache, `<cache>/_programs/<schema-id>/`, one per row schema, as the
//! commands that look at every folder (`verify`, `gc`, `status`) find them; and a segment's
//! schema read back from its own Arrow schema (the columns between `seed` and `status` are the
//! params, those between `status` and `exit_code` the metrics), so a folder can be compacted or
//! checked without the pipeline that wrote it.

use super::model::{MetricType, ParamType};
use super::rows::{metric_type, param_type, RowSchema, PROGRAMS_DIR};
use crate::cache::rows::PROGRAM_ROWS;
use crate::cache::store::Store;
use arrow::datatypes::Schema;
use parquet::arrow::arrow_reader::ParquetRecordBatchReaderBuilder;
use std::path::{Path, PathBuf};

/// One program folder of a cache.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Folder {
    /// Its schema id (the folder's name).
    pub id: String,
    /// The folder.
    pub path: PathBuf,
}

impl Folder {
    /// Its store (the folder exists: nothing is created).
    pub fn store(&self) -> std::io::Result<Store> {
        Store::open(&self.path)
    }

    /// Its segment files, sorted.
    pub fn segments(&self) -> anyhow::Result<Vec<PathBuf>> {
        self.store()?.segments()
    }
}

/// Every program folder of the cache at `cache`, sorted by id (none when it has no `_programs/`).
pub fn list(cache: &Path) -> anyhow::Result<Vec<Folder>> {
    let dir = cache.join(PROGRAMS_DIR);
    let entries = match std::fs::read_dir(&dir) {
        Ok(e) => e,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(Vec::new()),
        Err(e) => anyhow::bail!("cannot list {}: {e}", dir.display()),
    };
    let mut out = Vec::new();
    for entry in entries {
        let entry = entry?;
        let name = entry.file_name().to_string_lossy().into_owned();
        // `_`-names are qsweep's own (as in the cache); a stray file is no folder.
        if !name.starts_with(['_', '.']) && entry.file_type()?.is_dir() {
            out.push(Folder { id: name, path: entry.path() });
        }
    }
    out.sort_by(|a, b| a.id.cmp(&b.id));
    Ok(out)
}

/// The row schema of the segment at `path`, read from its Parquet footer alone.
pub fn schema_of(path: &Path) -> anyhow::Result<RowSchema> {
    let builder = ParquetRecordBatchReaderBuilder::try_new(std::fs::File::open(path)?)?;
    schema_from_arrow(builder.schema())
}

/// The row schema an Arrow schema of program rows holds: it must be marked as a program's
/// ([`PROGRAM_ROWS`]), with the marker naming the schema its columns make, and have exactly the
/// columns and types that schema's rows have.
pub fn schema_from_arrow(arrow: &Schema) -> anyhow::Result<RowSchema> {
    let marker = arrow.metadata().get(PROGRAM_ROWS).ok_or_else(|| {
        anyhow::anyhow!("not marked as a program's rows (no `{PROGRAM_ROWS}` in its Arrow schema)")
    })?;
    let names: Vec<&str> = arrow.fields().iter().map(|f| f.name().as_str()).collect();
    let at = |name: &str| {
        names.iter().position(|n| *n == name).ok_or_else(|| anyhow::anyhow!("column `{name}` is missing"))
    };
    let (seed, status, exit) = (at("seed")?, at("status")?, at("exit_code")?);
    anyhow::ensure!(seed < status && status < exit, "columns `seed`, `status`, `exit_code` out of order");
    let params = arrow.fields()[seed + 1..status]
        .iter()
        .map(|f| {
            let t = [ParamType::Int, ParamType::Float, ParamType::Bool, ParamType::Str]
                .into_iter()
                .find(|t| param_type(*t) == *f.data_type())
                .ok_or_else(|| anyhow::anyhow!("param column `{}` has type {}", f.name(), f.data_type()))?;
            Ok((f.name().clone(), t))
        })
        .collect::<anyhow::Result<Vec<_>>>()?;
    let metrics = arrow.fields()[status + 1..exit]
        .iter()
        .map(|f| {
            let t = MetricType::ALL
                .into_iter()
                .find(|t| metric_type(*t) == *f.data_type())
                .ok_or_else(|| anyhow::anyhow!("metric column `{}` has type {}", f.name(), f.data_type()))?;
            Ok((f.name().clone(), t))
        })
        .collect::<anyhow::Result<Vec<_>>>()?;
    let schema = RowSchema { params, metrics };
    let expected = schema.arrow();
    for (want, got) in expected.fields().iter().zip(arrow.fields()) {
        anyhow::ensure!(
            want.name() == got.name() && want.data_type() == got.data_type(),
            "column `{}` ({}) where `{}` ({}) belongs",
            got.name(),
            got.data_type(),
            want.name(),
            want.data_type()
        );
    }
    anyhow::ensure!(
        expected.fields().len() == arrow.fields().len(),
        "{} columns, where a program's rows have {}",
        arrow.fields().len(),
        expected.fields().len()
    );
    anyhow::ensure!(
        *marker == schema.id(),
        "marked as rows of schema {marker}, but its columns make schema {}",
        schema.id()
    );
    Ok(schema)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::program::rows::{folder, to_batch};

    fn schema() -> RowSchema {
        RowSchema {
            params: vec![("env".into(), ParamType::Str), ("alpha".into(), ParamType::Float)],
            metrics: vec![
                ("episodes".into(), MetricType::Int),
                ("solved".into(), MetricType::Bool),
                ("returns".into(), MetricType::ListFloat),
                ("lengths".into(), MetricType::ListU32),
            ],
        }
    }

    #[test]
    fn a_segments_schema_reads_back_from_its_columns() {
        let s = schema();
        assert_eq!(schema_from_arrow(&s.arrow()).unwrap(), s);
        let empty = RowSchema { params: vec![], metrics: vec![("x".into(), MetricType::Float)] };
        assert_eq!(schema_from_arrow(&empty.arrow()).unwrap(), empty);
        let dir = tempfile::tempdir().unwrap();
        let store = Store::open(&folder(dir.path(), &s)).unwrap();
        let path = store.write_batch(&[], &to_batch(&s, &[]).unwrap());
        assert!(path.is_err(), "an empty segment is refused");
        let found = list(dir.path()).unwrap();
        assert_eq!(found, vec![Folder { id: s.id(), path: folder(dir.path(), &s) }]);
        assert!(list(&dir.path().join("nowhere")).unwrap().is_empty());
    }

    #[test]
    fn an_unmarked_or_mislabelled_schema_is_refused() {
        let s = schema();
        let unmarked = Schema::new(s.arrow().fields().clone());
        assert!(schema_from_arrow(&unmarked).unwrap_err().to_string().contains("not marked"));
        let mut meta = s.arrow().metadata().clone();
        meta.insert(PROGRAM_ROWS, "0000000000000000");
        let wrong = Schema::new_with_metadata(s.arrow().fields().clone(), meta);
        assert!(schema_from_arrow(&wrong).unwrap_err().to_string().contains("its columns make schema"));
    }
}
