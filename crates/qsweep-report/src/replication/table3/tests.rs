//! Table III's columns follow the systems' own variables: a system whose state holds a variable
//! none of today's systems has (here Cart-Pole's third variable renamed `phi`) gets a column of
//! its own, named after it, in Table III (its CSV, its pages and the paper's configuration) and in
//! `cells.parquet`, with the cell's sets in it.

use super::{table3, table3_parts};
use crate::derive::report_data::{ReportData, Variables};
use crate::derive::table::Value;
use crate::render::datasets::cells_batch;
use crate::render::table::{render, Csv};
use arrow::array::{Array, UInt32Array};
use qsweep_engine::env::SystemKind;
use qsweep_pipeline::cache::rows::StoredTrial;
use qsweep_pipeline::cache::Key;
use qsweep_pipeline::declared::{load_str, LoadedSpec};
use qsweep_pipeline::plan::plan;
use qsweep_pipeline::testing::{outcome, planted};
use std::collections::HashMap;

const PIPELINE: &str = "\
name: vars
seeds: 3
systems:
  cart-pole:
    settings: { max_episodes: 50 }
    experiments:
      - id: 1
        repr: crisp
        algorithms: [q0]
        vary: { theta: [2, 3] }
        fixed: { x: 2, x_dot: 4, theta_dot: 5, actions: 2 }
        reference:
          q0: { mean: 20.0, std: 5.0, resolution: [2, 4, 3, 5], actions: 2 }
";

/// Cart-Pole's variables with its third one named `phi`, every other system's as they are.
fn renamed(s: SystemKind) -> &'static [&'static str] {
    match s {
        SystemKind::CartPole => &["x", "x_dot", "phi", "theta_dot"],
        other => other.variables(),
    }
}

#[test]
fn a_variable_outside_todays_four_gets_its_own_column() {
    let spec = load_str(PIPELINE, "vars.yaml", &[]).unwrap();
    let plan = plan(&LoadedSpec { spec, path: "vars.yaml".into(), variants: Vec::new() }, None).unwrap();
    let records: HashMap<Key, StoredTrial> = plan
        .trials()
        .enumerate()
        .map(|(i, (_, _, t))| {
            (t.key, StoredTrial { outcome: outcome(planted(i, t.seed)), seconds: 0.0, cpu_seconds: None })
        })
        .collect();
    let mut data = ReportData::build(&plan, &records);
    assert_eq!(data.variables.columns, ["x", "x_dot", "theta", "theta_dot"], "the engine's variables");
    data.variables = Variables::from(renamed);
    assert_eq!(data.variables.columns, ["x", "x_dot", "phi", "theta_dot"]);

    // Table III: a column named `phi` (its symbol is its name), its value the best cell's sets,
    // and the paper's configuration spelled with it.
    let t = table3(&data);
    let at = |csv: &str| t.columns.iter().position(|c| c.csv[0] == csv).unwrap_or_else(|| panic!("{csv}"));
    let phi = at("phi");
    assert_eq!(t.columns[phi].title, "phi");
    assert_eq!(t.columns[phi].latex.as_deref(), Some("$\\mathrm{phi}$"));
    assert!(!t.columns.iter().any(|c| c.csv[0] == "theta"), "no system has `theta` now");
    let best = data.experiments[0].best_of(qsweep_engine::Algorithm::Q0).unwrap().cell;
    let sets = data.experiments[0].cells[best].cell.config.repr.resolution[2];
    assert_eq!(t.rows[0].values[phi], Value::Int(u64::from(sets)));
    let config = &t.columns[at("paper_x")];
    assert_eq!(config.title, "Paper config (x, ẋ, phi, θ̇, actions)");
    assert_eq!(config.csv, ["paper_x", "paper_x_dot", "paper_phi", "paper_theta_dot", "paper_actions"]);
    assert_eq!(
        t.rows[0].values[at("paper_x")],
        Value::List(vec![Some(2), Some(4), Some(3), Some(5), Some(2)])
    );
    let csv = render(&t, &Csv);
    assert!(csv.lines().next().unwrap().contains(",x_dot,phi,theta_dot,actions,"), "{csv}");
    // The pages show it in the table of best configurations.
    assert!(table3_parts(&data)[0].columns.iter().any(|c| c.csv[0] == "phi"));

    // cells.parquet: a `phi` column with each cell's sets, no `theta`.
    let cells = cells_batch(&data).unwrap();
    let col =
        cells.column_by_name("phi").expect("a phi column").as_any().downcast_ref::<UInt32Array>().unwrap();
    let want: Vec<u32> = data.experiments[0].cells.iter().map(|c| c.cell.config.repr.resolution[2]).collect();
    assert_eq!((0..col.len()).map(|i| col.value(i)).collect::<Vec<_>>(), want);
    assert_eq!(want, [2, 3]);
    assert!(cells.column_by_name("theta").is_none());
}
