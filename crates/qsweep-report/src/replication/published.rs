//! What the report's generic data ([`ReportData`]) holds of the paper, as the replication reads it:
//! whether a pipeline gives published values, the plan's published Table III rows and the pairs
//! the paper's own numbers contradict, each experiment's cell at the paper's configuration, every
//! cell as the claims read it, and a Table III estimate's Kaplan–Meier median.

use crate::derive::report_data::{seed_of, Estimate, ExpData, ReportData};
use crate::replication::stats::claims::{ClaimCell, PAPER_SYSTEMS};
use crate::replication::stats::consistency::{designated, in_contradiction, pairs, Published};
use qsweep_engine::repr::ReprKind;
use qsweep_engine::Algorithm;
use qsweep_pipeline::plan::Plan;

/// Whether `data` covers every system of the paper's study ([`PAPER_SYSTEMS`]).
pub fn covers_the_paper(data: &ReportData) -> bool {
    let systems = data.systems();
    PAPER_SYSTEMS.iter().all(|s| systems.contains(s))
}

/// Whether any experiment of `data` carries published reference values.
pub fn has_reference(data: &ReportData) -> bool {
    data.experiments.iter().any(|e| !e.exp.reference.is_empty())
}

/// The cell of `algorithm` in `e` with the reference's configuration (bins or sets per variable and
/// action count), when the experiment has a reference that gives one and runs it.
pub fn reference_cell(e: &ExpData, algorithm: Algorithm) -> Option<usize> {
    let r = e.exp.reference.get(&algorithm)?;
    let (res, actions) = (r.resolution.as_ref()?, r.actions?);
    e.cells.iter().position(|c| {
        c.cell.algorithm == algorithm
            && &c.cell.config.repr.resolution == res
            && c.cell.config.actions == actions
    })
}

/// Kaplan–Meier median of the sample's counted episodes, trials that never reached the goal
/// censored at the cap ([`crate::replication::stats::survival::km_median`]).
pub fn km_median(est: &Estimate) -> Option<f64> {
    let times: Vec<(f64, bool)> =
        est.trials.iter().map(|t| (f64::from(t.counted), t.outcome.converged)).collect();
    crate::replication::stats::survival::km_median(&times)
}

/// Every cell of `data` as the claims read it (cells without trials included, with none).
pub fn claim_cells(data: &ReportData) -> Vec<ClaimCell> {
    let mut out = Vec::new();
    for (k, e) in data.experiments.iter().enumerate() {
        for c in &e.cells {
            let cfg = &c.cell.config;
            out.push(ClaimCell {
                system: e.exp.system,
                experiment: k,
                experiment_id: e.exp.id.clone(),
                fuzzy: e.exp.repr == ReprKind::Fuzzy,
                algorithm: c.cell.algorithm,
                resolution: cfg.repr.resolution.clone(),
                actions: cfg.actions,
                counted: c.trials.iter().map(|t| f64::from(t.counted)).collect(),
                converged: c.trials.iter().map(|t| t.outcome.converged).collect(),
                seed: seed_of(b"qsweep-claims\0", c.trials.iter().map(|t| &t.planned.key)),
            });
        }
    }
    out
}

/// Table III rows (experiment index, algorithm) in contradictory pairs, and those the pairs
/// designate ([`contradictions`]).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Contradictions {
    /// Rows that belong to a contradictory pair.
    pub in_pair: Vec<(usize, Algorithm)>,
    /// Rows a contradictory pair designates (one per pair).
    pub designated: Vec<(usize, Algorithm)>,
}

/// Table III's rows of `data` that belong to a pair the paper's own numbers contradict, and the
/// rows those pairs designate ([`crate::replication::stats::consistency`]), each published mean
/// taken over `paper_n` runs.
pub fn contradictions(data: &ReportData, paper_n: usize) -> Contradictions {
    let mut out = Contradictions::default();
    for rows in published_rows(data.plan) {
        let published: Vec<Published> = rows.iter().map(|r| r.2.clone()).collect();
        let pairs = pairs(&published, paper_n);
        for (i, r) in rows.iter().enumerate() {
            if in_contradiction(&pairs, i) {
                out.in_pair.push((r.0, r.1));
            }
            if designated(&pairs, i) {
                out.designated.push((r.0, r.1));
            }
        }
    }
    out
}

/// A published Table III row with its experiment's index and its algorithm.
pub type PublishedRow = (usize, Algorithm, Published);

/// The plan's Table III rows that have a published value, as the consistency check reads them
/// ([`crate::replication::stats::consistency`]): each with its experiment's index and its grid (the
/// experiment's cells of the algorithm), in plan order, one group per variant (a plan of several
/// variants holds each variant's copy of the paper's values; pairs are sought within one).
pub fn published_rows(plan: &Plan) -> Vec<Vec<PublishedRow>> {
    let mut groups: Vec<(Option<&str>, Vec<PublishedRow>)> = Vec::new();
    for (ei, e) in plan.experiments.iter().enumerate() {
        let variant = e.variant.as_deref();
        if !groups.iter().any(|g| g.0 == variant) {
            groups.push((variant, Vec::new()));
        }
        let group = &mut groups.iter_mut().find(|g| g.0 == variant).expect("just added").1;
        for &alg in &e.algorithms {
            let Some(r) = e.reference.get(&alg) else { continue };
            let grid = e
                .cells
                .iter()
                .filter(|c| c.algorithm == alg)
                .map(|c| (c.config.repr.resolution.clone(), c.config.actions))
                .collect();
            let row = Published {
                system: e.system,
                repr: e.repr,
                experiment: e.id.clone(),
                algorithm: alg,
                mean: r.mean,
                std: r.std,
                config: r.resolution.clone().zip(r.actions),
                grid,
            };
            group.push((ei, alg, row));
        }
    }
    groups.into_iter().map(|g| g.1).filter(|g| !g.is_empty()).collect()
}
