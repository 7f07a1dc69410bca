//! A comparison's `trials.parquet` when a variant's first experiment has no trials stored yet but
//! a later one has: the report writes the rows it has, it does not fail on the empty experiment.

use crate::helpers::Sandbox;

/// Regression: `PartWriter` took its schema from the first experiment's batch even when that
/// batch was empty (no `variant` column), so the next experiment's rows failed with `Arrow: Found
/// null at index 0 for required field 'repr'`.
#[test]
fn a_part_whose_first_experiment_has_no_trials_still_writes_the_others() {
    let sb = Sandbox::new();
    // tiny.yaml's trials are some of variants.yaml's: its variant's first experiment stays empty.
    let tiny = sb.fixture("tiny.yaml");
    sb.run_json(&tiny, &[]);
    let variants = sb.fixture("variants.yaml");
    let out = sb
        .qsweep(&["report", variants.to_str().unwrap(), "--formats", "trials", "--out", "rep", "--quiet"])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(0), "{stderr}");
    assert!(!stderr.contains("required field"), "{stderr}");
    let file = std::fs::File::open(sb.path("rep/trials.parquet")).expect("trials.parquet written");
    let reader = parquet::file::reader::SerializedFileReader::new(file).unwrap();
    use parquet::file::reader::FileReader;
    let rows: i64 = reader.metadata().row_groups().iter().map(|g| g.num_rows()).sum();
    assert!(rows > 0, "the stored trials' rows are written");
}
