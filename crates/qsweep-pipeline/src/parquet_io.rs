//! Parquet as qsweep writes it: one column builder and one set of writer settings for every file
//! (cache segments, `cells.parquet`, `trials.parquet`), so a column of the same name has the same
//! Arrow type wherever it appears.
//!
//! A file's schema is the sequence of [`Cols`] calls that encodes it: name, type (the method) and
//! nullability (the `_opt` methods) are written once, and the schema of an empty table is the
//! file's schema ([`Cols::schema`]). Types are plain ones pandas, polars and DuckDB all read: utf8,
//! uint32, uint64, int64, float64, bool and list<uint32>.

use arrow::array::{
    Array, ArrayRef, BooleanArray, Float64Array, Int64Array, ListBuilder, StringArray, UInt32Array,
    UInt32Builder, UInt64Array,
};
use arrow::datatypes::{Field, Schema};
use arrow::record_batch::RecordBatch;
use parquet::arrow::ArrowWriter;
use parquet::basic::{Compression, ZstdLevel};
use parquet::file::properties::WriterProperties;
use std::sync::Arc;

/// Columns under construction: name, values and whether nulls are allowed, in file order.
#[derive(Default)]
pub struct Cols(Vec<(&'static str, ArrayRef, bool)>);

impl Cols {
    fn push(&mut self, name: &'static str, array: impl Array + 'static, nullable: bool) {
        self.0.push((name, Arc::new(array), nullable));
    }
    /// A utf8 column.
    pub fn str<'a, T, S: AsRef<str>>(&mut self, name: &'static str, rows: &'a [T], f: impl Fn(&'a T) -> S) {
        self.push(name, StringArray::from_iter_values(rows.iter().map(f)), false);
    }
    /// A nullable utf8 column.
    pub fn str_opt<'a, T, S: AsRef<str>>(
        &mut self,
        name: &'static str,
        rows: &'a [T],
        f: impl Fn(&'a T) -> Option<S>,
    ) {
        self.push(name, rows.iter().map(f).collect::<StringArray>(), true);
    }
    /// A uint32 column.
    pub fn u32<'a, T>(&mut self, name: &'static str, rows: &'a [T], f: impl Fn(&'a T) -> u32) {
        self.push(name, UInt32Array::from_iter_values(rows.iter().map(f)), false);
    }
    /// A nullable uint32 column.
    pub fn u32_opt<'a, T>(&mut self, name: &'static str, rows: &'a [T], f: impl Fn(&'a T) -> Option<u32>) {
        self.push(name, rows.iter().map(f).collect::<UInt32Array>(), true);
    }
    /// A uint64 column.
    pub fn u64<'a, T>(&mut self, name: &'static str, rows: &'a [T], f: impl Fn(&'a T) -> u64) {
        self.push(name, UInt64Array::from_iter_values(rows.iter().map(f)), false);
    }
    /// An int64 column.
    pub fn i64<'a, T>(&mut self, name: &'static str, rows: &'a [T], f: impl Fn(&'a T) -> i64) {
        self.push(name, Int64Array::from_iter_values(rows.iter().map(f)), false);
    }
    /// A float64 column.
    pub fn f64<'a, T>(&mut self, name: &'static str, rows: &'a [T], f: impl Fn(&'a T) -> f64) {
        self.push(name, Float64Array::from_iter_values(rows.iter().map(f)), false);
    }
    /// A nullable float64 column.
    pub fn f64_opt<'a, T>(&mut self, name: &'static str, rows: &'a [T], f: impl Fn(&'a T) -> Option<f64>) {
        self.push(name, rows.iter().map(f).collect::<Float64Array>(), true);
    }
    /// A bool column.
    pub fn bool<'a, T>(&mut self, name: &'static str, rows: &'a [T], f: impl Fn(&'a T) -> bool) {
        self.push(name, rows.iter().map(|r| Some(f(r))).collect::<BooleanArray>(), false);
    }
    /// A nullable bool column.
    pub fn bool_opt<'a, T>(&mut self, name: &'static str, rows: &'a [T], f: impl Fn(&'a T) -> Option<bool>) {
        self.push(name, rows.iter().map(f).collect::<BooleanArray>(), true);
    }
    /// A list<uint32> column (the list items are declared nullable, as Arrow's builders make them
    /// and as every cache segment ever written declares them).
    pub fn list_u32<'a, T>(&mut self, name: &'static str, rows: &'a [T], f: impl Fn(&'a T) -> &'a [u32]) {
        let total = rows.iter().map(|r| f(r).len()).sum();
        let mut b = ListBuilder::new(UInt32Builder::with_capacity(total));
        for r in rows {
            b.values().append_slice(f(r));
            b.append(true);
        }
        self.push(name, b.finish(), false);
    }

    /// The schema these columns make (for an empty table: the file type's schema).
    pub fn schema(&self) -> Schema {
        Schema::new(
            self.0
                .iter()
                .map(|(name, a, nullable)| Field::new(*name, a.data_type().clone(), *nullable))
                .collect::<Vec<_>>(),
        )
    }

    /// The columns as one record batch.
    pub fn into_batch(self) -> anyhow::Result<RecordBatch> {
        Ok(RecordBatch::try_from_iter_with_nullable(self.0)?)
    }

    /// The columns as the bytes of a Parquet file ([`to_parquet`]).
    pub fn into_parquet(self) -> anyhow::Result<Vec<u8>> {
        to_parquet(&self.into_batch()?)
    }
}

/// The writer settings of every qsweep Parquet file: zstd level 3, `created_by` naming qsweep.
pub fn writer_properties() -> anyhow::Result<WriterProperties> {
    Ok(WriterProperties::builder()
        .set_compression(Compression::ZSTD(ZstdLevel::try_new(3)?))
        .set_created_by(format!("qsweep {}", env!("CARGO_PKG_VERSION")))
        .build())
}

/// Encode `batch` as the bytes of a Parquet file with [`writer_properties`].
pub fn to_parquet(batch: &RecordBatch) -> anyhow::Result<Vec<u8>> {
    let mut buf = Vec::new();
    let mut w = ArrowWriter::try_new(&mut buf, batch.schema(), Some(writer_properties()?))?;
    w.write(batch)?;
    w.close()?;
    Ok(buf)
}

/// The column `name` of `batch` as the array type `T`, or an error naming the column.
pub fn column<'a, T: 'static>(batch: &'a RecordBatch, name: &str) -> anyhow::Result<&'a T> {
    batch
        .column_by_name(name)
        .ok_or_else(|| anyhow::anyhow!("column `{name}` is missing"))?
        .as_any()
        .downcast_ref::<T>()
        .ok_or_else(|| anyhow::anyhow!("column `{name}` has an unexpected type"))
}

#[cfg(test)]
mod tests {
    use super::*;
    use arrow::array::ListArray;
    use arrow::datatypes::DataType;
    use parquet::arrow::arrow_reader::ParquetRecordBatchReaderBuilder;

    #[test]
    fn every_column_kind_round_trips_through_parquet() {
        let rows = [(1u32, Some(2u32), vec![3u32, 4]), (5, None, vec![])];
        let mut c = Cols::default();
        c.str("s", &rows, |r| r.0.to_string());
        c.str_opt("so", &rows, |r| r.1.map(|v| v.to_string()));
        c.u32("u", &rows, |r| r.0);
        c.u32_opt("uo", &rows, |r| r.1);
        c.u64("w", &rows, |r| u64::from(r.0) << 40);
        c.i64("i", &rows, |r| -i64::from(r.0));
        c.f64("f", &rows, |r| f64::from(r.0) / 2.0);
        c.f64_opt("fo", &rows, |r| r.1.map(f64::from));
        c.bool("b", &rows, |r| r.1.is_some());
        c.list_u32("l", &rows, |r| &r.2);
        let schema = c.schema();
        let batch = c.into_batch().unwrap();
        assert_eq!(*batch.schema(), schema);
        let nullable: Vec<_> = schema.fields().iter().filter(|f| f.is_nullable()).map(|f| f.name()).collect();
        assert_eq!(nullable, ["so", "uo", "fo"]);
        assert_eq!(schema.field_with_name("w").unwrap().data_type(), &DataType::UInt64);
        let bytes = to_parquet(&batch).unwrap();
        let mut file = tempfile::tempfile().unwrap();
        std::io::Write::write_all(&mut file, &bytes).unwrap();
        let reader = ParquetRecordBatchReaderBuilder::try_new(file).unwrap();
        let meta = reader.metadata().file_metadata().created_by().unwrap().to_string();
        assert!(meta.starts_with("qsweep "), "{meta}");
        let back: Vec<_> = reader.build().unwrap().map(Result::unwrap).collect();
        assert_eq!(back, std::slice::from_ref(&batch));
        let l = column::<ListArray>(&back[0], "l").unwrap();
        assert_eq!(l.value(0).as_any().downcast_ref::<UInt32Array>().unwrap().values(), &[3, 4]);
        assert!(column::<UInt32Array>(&back[0], "s").unwrap_err().to_string().contains("`s`"));
        assert!(column::<UInt32Array>(&back[0], "nope").is_err());
    }
}
