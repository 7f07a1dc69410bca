//! Fresh seeds end to end (`tests/fixtures/pipelines/fresh.yaml`): `run` executes the grid, then
//! each heatmap's best cell on the fresh seeds; a rerun executes nothing; the reports show the
//! fresh estimate beside the selection and judge the row on it; `trials.parquet` flags the fresh
//! trials, and their mean is `fresh_mean`.

use crate::helpers::{csv_rows, stdout, Sandbox};
use arrow::array::{Array, BooleanArray, StringArray, UInt32Array};
use parquet::arrow::arrow_reader::ParquetRecordBatchReaderBuilder;

/// Per row of `trials.parquet`: (algorithm, x, x_dot, seed-is-fresh, episodes_counted).
fn trials(path: &std::path::Path) -> Vec<(String, u32, u32, bool, u32)> {
    let reader = ParquetRecordBatchReaderBuilder::try_new(std::fs::File::open(path).unwrap())
        .unwrap()
        .build()
        .unwrap();
    let mut out = Vec::new();
    for b in reader {
        let b = b.unwrap();
        let col = |n: &str| b.column(b.schema().index_of(n).unwrap()).clone();
        let (alg, x, xd, fresh, counted) =
            (col("algorithm"), col("x"), col("x_dot"), col("fresh"), col("episodes_counted"));
        let alg = alg.as_any().downcast_ref::<StringArray>().unwrap();
        let x = x.as_any().downcast_ref::<UInt32Array>().unwrap();
        let xd = xd.as_any().downcast_ref::<UInt32Array>().unwrap();
        let fresh = fresh.as_any().downcast_ref::<BooleanArray>().unwrap();
        let counted = counted.as_any().downcast_ref::<UInt32Array>().unwrap();
        for i in 0..b.num_rows() {
            out.push((alg.value(i).to_string(), x.value(i), xd.value(i), fresh.value(i), counted.value(i)));
        }
    }
    out
}

#[test]
fn fresh_seeds_rerun_each_best_cell_after_the_grid_and_the_row_is_judged_on_them() {
    let sb = Sandbox::new();
    let p = sb.fixture("fresh.yaml");
    let ps = p.to_str().unwrap();
    let first = sb.run_json(&p, &["--jobs", "1"]);
    // 2 algorithms × 4 cells × 3 seeds, then 2 best cells × 5 fresh seeds.
    assert_eq!(first["executed"].as_u64(), Some(24 + 10), "{first}");
    let again = sb.run_json(&p, &[]);
    assert_eq!(again["executed"].as_u64(), Some(0), "{again}");
    let status = stdout(&mut sb.qsweep(&["status", ps]));
    assert!(status.contains("total: 34 trials, 34 cached, 0 missing"), "{status}");

    stdout(&mut sb.qsweep(&["report", ps, "--out", "rep"]));
    let table = std::fs::read_to_string(sb.path("rep/table3.csv")).unwrap();
    let header = table.lines().next().unwrap();
    assert!(
        header.contains(",ci_lo,ci_hi,fresh_mean,fresh_std,fresh_n,fresh_ci_lo,fresh_ci_hi,censored,"),
        "{header}"
    );
    let rows = csv_rows(&table);
    let got = trials(&sb.path("rep/trials.parquet"));
    assert_eq!(got.iter().filter(|t| t.3).count(), 10);
    for (row, alg) in rows.iter().zip(["q0", "q-lambda"]) {
        assert_eq!(row["fresh_n"], "5", "{row:?}");
        // The fresh trials are those of the row's best cell, and their mean is fresh_mean.
        let (x, xd): (u32, u32) = (row["x"].parse().unwrap(), row["x_dot"].parse().unwrap());
        let fresh: Vec<f64> = got
            .iter()
            .filter(|t| t.3 && t.0 == alg)
            .inspect(|t| assert_eq!((t.1, t.2), (x, xd), "fresh trials belong to the best cell"))
            .map(|t| f64::from(t.4))
            .collect();
        let mean = fresh.iter().sum::<f64>() / fresh.len() as f64;
        assert!((row["fresh_mean"].parse::<f64>().unwrap() - mean).abs() < 1e-9, "{row:?} vs {mean}");
        // The selection estimate stays the grid's: n is the cell's 3 seeds.
        assert_eq!(row["n"], "3");
    }
    // The reference row's ratio is the fresh mean over the paper's.
    let ratio: f64 = rows[0]["ratio"].parse().unwrap();
    let fresh_mean: f64 = rows[0]["fresh_mean"].parse().unwrap();
    assert!((ratio - fresh_mean / 4.0).abs() < 1e-3, "ratio {ratio}, fresh {fresh_mean}");
}

#[test]
fn fresh_seeds_that_overlap_the_grid_are_refused_with_the_line() {
    let sb = Sandbox::new();
    let text = std::fs::read_to_string(sb.fixture("fresh.yaml"))
        .unwrap()
        .replace("first_seed: 100", "first_seed: 1");
    let p = sb.write("overlap.yaml", &text);
    let out = sb.qsweep(&["run", p.to_str().unwrap()]).output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(err.contains("overlap.yaml:5") && err.contains("fresh.first_seed"), "{err}");
    assert_eq!(sb.segments(), 0);
}
