//! What the comparison keeps of each variant once its folder is written: its identity, and per
//! experiment and cell the few numbers the comparison and the fit need.

use crate::derive::report_data::ReportData;
use crate::memo::stats::StatsMemo;
use crate::replication::compare::fit::{rows_of, Fit, RowFit};
pub use crate::replication::compare::info::VariantInfo;
use crate::replication::compare::ratios::ForestRow;
use crate::replication::published::{claim_cells, covers_the_paper, has_reference};
use crate::replication::stats::claims::ClaimResult;
use qsweep_engine::env::SystemKind;
use qsweep_engine::Algorithm;
use qsweep_pipeline::cache::Key;
use qsweep_pipeline::plan::{Cell, Experiment, Plan};

/// What the comparison keeps of one cell: its present trials' keys (for the bootstrap seed) and
/// counted episodes, and their mean.
#[derive(Debug, Clone)]
pub struct CellDigest<'p> {
    /// The planned cell.
    pub cell: &'p Cell,
    /// Keys of the present trials, in seed order.
    pub keys: Vec<Key>,
    /// Their counted episodes.
    pub values: Vec<f64>,
    /// Mean of `values`.
    pub mean: Option<f64>,
}

/// What the comparison keeps of one experiment.
#[derive(Debug, Clone)]
pub struct ExpDigest<'p> {
    /// The planned experiment.
    pub exp: &'p Experiment,
    /// Its cells, in plan order.
    pub cells: Vec<CellDigest<'p>>,
}

impl AsRef<Experiment> for ExpDigest<'_> {
    fn as_ref(&self) -> &Experiment {
        self.exp
    }
}

impl ExpDigest<'_> {
    /// The index of the cell with this algorithm and coordinates.
    pub fn find(&self, algorithm: Algorithm, coords: &[f64]) -> Option<usize> {
        self.cells.iter().position(|c| c.cell.algorithm == algorithm && c.cell.coords == coords)
    }
}

/// What the comparison keeps of one variant's report.
#[derive(Debug, Clone)]
pub struct VariantDigest<'p> {
    /// The variant.
    pub info: VariantInfo,
    /// Its fit to the reference values.
    pub fit: Fit,
    /// Its Table III rows scored one by one (what `fit` tallies).
    pub rows: Vec<RowFit>,
    /// Its Table III rows as the forest plot draws them (`table3.csv`'s ratios).
    pub forest: Vec<ForestRow>,
    /// Planned (cell, seed) trials.
    pub trials_planned: usize,
    /// Of those, present.
    pub trials_cached: usize,
    /// Its experiments.
    pub exps: Vec<ExpDigest<'p>>,
    /// The paper's claims tested on its cells (empty unless the pipeline has reference values and
    /// covers every system).
    pub claims: Vec<ClaimResult>,
}

impl<'p> VariantDigest<'p> {
    /// The digest of `data`, the report data of `plan` (whose cells the digest borrows, so it
    /// outlives the trials `data` borrows).
    pub fn of(info: VariantInfo, plan: &'p Plan, data: &ReportData, memo: &StatsMemo) -> Self {
        let exps = plan
            .experiments
            .iter()
            .zip(&data.experiments)
            .map(|(exp, e)| ExpDigest {
                exp,
                cells: exp
                    .cells
                    .iter()
                    .zip(&e.cells)
                    .map(|(cell, c)| CellDigest {
                        cell,
                        keys: c.trials.iter().map(|t| t.planned.key).collect(),
                        values: c.trials.iter().map(|t| f64::from(t.counted)).collect(),
                        mean: c.summary.mean,
                    })
                    .collect(),
            })
            .collect();
        let rows = rows_of(data);
        // The claims speak of the paper's whole study: every system, with the published values.
        let claims = if has_reference(data) && covers_the_paper(data) {
            crate::replication::stats::claims::evaluate_memoized(memo, &claim_cells(data))
        } else {
            Vec::new()
        };
        Self {
            info,
            fit: Fit::from_rows(&rows),
            rows,
            forest: crate::replication::compare::ratios::rows_of(data),
            trials_planned: data.trials_planned,
            trials_cached: data.trials_cached,
            exps,
            claims,
        }
    }

    /// Systems present, in report order.
    pub fn systems(&self) -> Vec<SystemKind> {
        SystemKind::ALL.into_iter().filter(|s| self.exps.iter().any(|e| e.exp.system == *s)).collect()
    }
}
