//! One schema per file type, and one type per column name across files: the cache segments,
//! `cells.parquet` and `trials.parquet` that a run writes agree on every column they share.

use crate::helpers::Sandbox;
use arrow::datatypes::Schema;
use parquet::arrow::arrow_reader::ParquetRecordBatchReaderBuilder;
use std::path::Path;

fn schema_of(path: &Path) -> Schema {
    let file = std::fs::File::open(path).unwrap();
    ParquetRecordBatchReaderBuilder::try_new(file).unwrap().schema().as_ref().clone()
}

#[test]
fn the_cache_and_the_report_files_agree_on_every_shared_column() {
    let sb = Sandbox::new();
    let p = sb.fixture("tiny.yaml");
    let out = sb.path("report");
    sb.qsweep(&["run", p.to_str().unwrap(), "--quiet", "--set", "seeds=1", "--out", out.to_str().unwrap()])
        .assert()
        .success();
    let segment = schema_of(&sb.segment_paths()[0]);
    assert_eq!(
        segment,
        *qsweep_pipeline::cache::rows::schema(),
        "segments are written with the documented schema"
    );
    let files = [
        ("cache", segment),
        ("cells", schema_of(&out.join("cells.parquet"))),
        ("trials", schema_of(&out.join("trials.parquet"))),
    ];
    let mut shared = 0;
    for (i, (a, sa)) in files.iter().enumerate() {
        for (b, sb) in &files[i + 1..] {
            for f in sa.fields() {
                if let Ok(g) = sb.field_with_name(f.name()) {
                    shared += 1;
                    assert_eq!(f.data_type(), g.data_type(), "`{}`: {a} vs {b}", f.name());
                    assert_eq!(f.is_nullable(), g.is_nullable(), "`{}` nullability: {a} vs {b}", f.name());
                }
            }
        }
    }
    // cache/trials: 19 columns (identity, outcome, learner settings, seconds, cpu_seconds); cells/trials: the
    // 17 cell-identity columns; cache/cells: system, repr, algorithm, actions.
    assert_eq!(shared, 19 + 17 + 4);
    let trials = &files[2].1;
    for name in ["total_steps", "seed"] {
        assert_eq!(trials.field_with_name(name).unwrap().data_type(), &arrow::datatypes::DataType::UInt64);
    }
}
