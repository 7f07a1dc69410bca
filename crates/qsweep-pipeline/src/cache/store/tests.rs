//! Tests of the segment store: writing, scanning, reading outcomes, damage, re-listing.

use super::super::rows::*;
use super::*;
use crate::parquet_io::column;
use arrow::array::{Array, ListArray, StringArray, UInt32Array, UInt64Array};
use arrow::datatypes::{DataType, Field, Schema};
use arrow::record_batch::RecordBatch;
use parquet::arrow::arrow_reader::ParquetRecordBatchReaderBuilder;
use parquet::arrow::ArrowWriter;
use qsweep_engine::config::TrialConfig;
use qsweep_engine::env::SystemKind;
use qsweep_engine::repr::ReprKind;
use qsweep_engine::{run_trial, Algorithm};
use std::fs::File;
use std::sync::Arc;

fn records() -> Vec<TrialRecord> {
    let mut out = Vec::new();
    for (sys, res) in [(SystemKind::BallBeam, vec![3, 2]), (SystemKind::MountainCar, vec![2, 2])] {
        for repr in [ReprKind::Crisp, ReprKind::Fuzzy] {
            let mut c = TrialConfig::paper(sys, repr, Algorithm::QLambda, res.clone(), 3);
            c.limits.max_episodes = 5;
            for seed in 0..2 {
                let o = run_trial(&c, seed);
                out.push(
                    TrialRecord::new(c.clone(), seed, o, 0.5).with_cpu_seconds(Some(0.25 + seed as f64)),
                );
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
    // The report's read: only some rows of some segments, in any order of segments.
    let some: HashSet<_> = [recs[0].key, recs[2].key, recs[5].key, recs[7].key].into();
    for lengths in [true, false] {
        let got = store.read_outcomes(&scan, &some, lengths).unwrap();
        assert_eq!(got.len(), 4);
        for r in recs.iter().filter(|r| some.contains(&r.key)) {
            let mut want = r.outcome.clone();
            if !lengths {
                want.episode_lengths.clear();
            }
            assert_eq!((&got[&r.key].outcome, got[&r.key].seconds), (&want, r.seconds));
            assert_eq!(got[&r.key].cpu_seconds, r.cpu_seconds);
        }
    }
    // No temp files are left behind.
    let names: Vec<_> = std::fs::read_dir(dir.path()).unwrap().map(|e| e.unwrap().file_name()).collect();
    assert!(names.iter().all(|n| n.to_string_lossy().starts_with(SEGMENT_PREFIX)), "{names:?}");
}

#[test]
fn a_segment_holds_every_column_exactly_as_encoded() {
    let dir = tempfile::tempdir().unwrap();
    let store = Store::open(dir.path()).unwrap();
    let mut recs = records();
    recs[1].outcome.failure = Some("diverged: x is NaN".into());
    let path = store.write_segment(&recs).unwrap();
    let reader = ParquetRecordBatchReaderBuilder::try_new(File::open(&path).unwrap()).unwrap();
    assert_eq!(reader.schema(), &schema());
    let back: Vec<RecordBatch> = reader.build().unwrap().map(Result::unwrap).collect();
    let want = to_batch(&recs).unwrap();
    assert_eq!(back, std::slice::from_ref(&want));
    assert_eq!(want.num_columns(), 24);
    // Spot checks of columns derived from the configuration rather than decoded back.
    let res = column::<ListArray>(&want, "resolution").unwrap().value(0);
    assert_eq!(res.as_any().downcast_ref::<UInt32Array>().unwrap().values(), &[3, 2]);
    assert_eq!(column::<StringArray>(&want, "tie_break").unwrap().value(0), "random");
    assert_eq!(column::<StringArray>(&want, "system").unwrap().value(3), "ball-beam");
    assert_eq!(column::<StringArray>(&want, "failure").unwrap().value(1), "diverged: x is NaN");
    assert!(column::<StringArray>(&want, "failure").unwrap().is_null(0));
    assert_eq!(read_segment(&path, &|_| true).unwrap(), recs);
}

/// `tests/fixtures/cache/seg-previous-layout.parquet` was written by qsweep before the cache
/// schema was derived from the shared column builder (main at 458cd01: tiny.yaml with one seed,
/// plus absurd.yaml's diverged trials, compacted by `gc`), and before `cpu_seconds` existed. The
/// cache on users' disks must stay readable: the same columns but the later ones, every row
/// decodes (without CPU time) and re-hashes to its key.
#[test]
fn a_segment_in_the_previous_layout_still_reads() {
    let path =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/fixtures/cache/seg-previous-layout.parquet");
    let reader = ParquetRecordBatchReaderBuilder::try_new(File::open(&path).unwrap()).unwrap();
    let now = schema();
    let without_later: Vec<_> =
        now.fields().iter().filter(|f| !LATER_COLUMNS.contains(&f.name().as_str())).cloned().collect();
    assert_eq!(reader.schema().fields().to_vec(), without_later, "names, types, nullability and order");
    let recs = read_segment(&path, &|_| true).unwrap();
    assert_eq!(recs.len(), 30);
    for r in &recs {
        assert_eq!(Key::from_canonical(&r.config_json(), r.seed, r.engine_version), r.key);
        assert_eq!(r.cpu_seconds, None);
    }
    assert_eq!(recs.iter().filter(|r| r.outcome.failure.is_some()).count(), 2);
    assert!(recs.iter().any(|r| r.outcome.episodes_to_goal.is_some()));
    // Re-encoding what was read gives the stored columns back, bit for bit, and nulls for the rest.
    let stored: Vec<RecordBatch> = ParquetRecordBatchReaderBuilder::try_new(File::open(&path).unwrap())
        .unwrap()
        .build()
        .unwrap()
        .map(Result::unwrap)
        .collect();
    let stored = arrow::compute::concat_batches(&stored[0].schema(), &stored).unwrap();
    let again = to_batch(&recs).unwrap();
    for f in stored.schema().fields() {
        assert_eq!(
            again.column_by_name(f.name()).unwrap(),
            stored.column_by_name(f.name()).unwrap(),
            "{}",
            f.name()
        );
    }
    assert_eq!(again.column_by_name("cpu_seconds").unwrap().null_count(), 30);
    // Its outcomes read through the report's projected read too.
    let store = Store { dir: path.parent().unwrap().to_path_buf(), writer: None, remote: None };
    let scan =
        KeySet { segments: vec![(path.clone(), recs.iter().map(|r| r.key).collect())], ..KeySet::default() };
    let wanted: HashSet<Key> = recs.iter().map(|r| r.key).collect();
    let got = store.read_outcomes(&scan, &wanted, true).unwrap();
    assert_eq!(got.len(), 30);
    for r in &recs {
        let o = &got[&r.key];
        assert_eq!((&o.outcome, o.seconds, o.cpu_seconds), (&r.outcome, r.seconds, None));
    }
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
