//! Benchmarks of real work: the most expensive cells of a pipeline's plan, run with their real
//! seeds to their real stop (`qsweep bench --pipeline P --top N`).
//!
//! A cell's cost is what its trials cost when they were computed: the sum of their cached
//! `cpu_seconds` (their wall-clock `seconds` for rows cached before CPU time was recorded). Where
//! the cache lacks some of the plan's trials, every cell is ranked by the engine's own estimate
//! ([`crate::exec::estimated_cost`]) instead, so one ranking never mixes units. Each chosen cell's
//! trials then run one after another on the calling thread, timed by that thread's CPU clock,
//! which load on the machine does not inflate.

use crate::cache::store::{KeySet, Store};
use crate::cache::Key;
use crate::exec::{estimated_cost, thread_cpu_seconds};
use crate::plan::{Cell, Plan};
use qsweep_engine::run_trial;
use serde::{Deserialize, Serialize};
use std::collections::{HashMap, HashSet};

/// How a cell's cost was ranked.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum CostBasis {
    /// The cached trials' CPU seconds (wall-clock seconds where none were recorded).
    Cached,
    /// The engine's estimate (some trials are not cached).
    Estimated,
}

/// One distinct cell of a plan (variants share cells with the same configuration and seeds).
#[derive(Debug, Clone)]
pub struct CellCost<'p> {
    /// `variant:system/repr/algorithm/resolution/actions`.
    pub name: String,
    /// The cell.
    pub cell: &'p Cell,
    /// Its cost in the ranking's unit.
    pub cost: f64,
}

/// The measured cost of one cell.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CellBench {
    /// The cell's name ([`CellCost::name`]).
    pub cell: String,
    /// Seeds run.
    pub seeds: usize,
    /// Steps over all its trials.
    pub steps: u64,
    /// CPU seconds of the thread that ran them.
    pub cpu_seconds: f64,
    /// `steps / cpu_seconds`.
    pub steps_per_s: f64,
    /// The cell's share of the whole plan's cost, by the ranking's basis.
    pub share: f64,
}

/// A cell's name: where it is and what it computes ([`Cell::name`]).
pub fn cell_name(plan_variant: Option<&str>, cell: &Cell) -> String {
    cell.name(plan_variant)
}

/// Every distinct cell of `plan` with its cost, most expensive first (ties in plan order), and the
/// basis of the ranking.
/// Without a cache (`None`), the ranking is the estimate.
pub fn ranked_cells<'p>(
    plan: &'p Plan,
    cache: Option<(&Store, &KeySet)>,
) -> anyhow::Result<(Vec<CellCost<'p>>, CostBasis)> {
    let mut seen: HashSet<Vec<Key>> = HashSet::new();
    let mut cells = Vec::new();
    for e in &plan.experiments {
        for c in &e.cells {
            let keys: Vec<Key> = c.trials.iter().map(|t| t.key).collect();
            if seen.insert(keys) {
                cells.push((e.variant.as_deref(), c));
            }
        }
    }
    let wanted: HashSet<Key> = cells.iter().flat_map(|(_, c)| c.trials.iter().map(|t| t.key)).collect();
    let complete = cache.filter(|(_, scan)| wanted.iter().all(|k| scan.keys.contains(k)));
    let (costs, basis): (HashMap<Key, f64>, CostBasis) = match complete {
        Some((store, scan)) => {
            let got = store.read_outcomes(scan, &wanted, false)?;
            (
                got.into_iter().map(|(k, o)| (k, o.cpu_seconds.unwrap_or(o.seconds))).collect(),
                CostBasis::Cached,
            )
        }
        None => (HashMap::new(), CostBasis::Estimated),
    };
    let mut out: Vec<CellCost> = cells
        .into_iter()
        .map(|(v, c)| {
            let cost = match basis {
                CostBasis::Cached => c.trials.iter().map(|t| costs[&t.key]).sum(),
                CostBasis::Estimated => estimated_cost(&c.config) * c.trials.len() as f64,
            };
            CellCost { name: cell_name(v, c), cell: c, cost }
        })
        .collect();
    out.sort_by(|a, b| b.cost.total_cmp(&a.cost));
    Ok((out, basis))
}

/// Run every trial of `cell` (its real seeds, to its real stop) on this thread and time it.
pub fn time_cell(cell: &CellCost, total_cost: f64) -> CellBench {
    let mut steps = 0;
    let mut cpu = 0.0;
    for t in &cell.cell.trials {
        let before = thread_cpu_seconds().unwrap_or(0.0);
        let o = run_trial(&cell.cell.config, t.seed);
        cpu += thread_cpu_seconds().unwrap_or(0.0) - before;
        steps += o.total_steps;
    }
    CellBench {
        cell: cell.name.clone(),
        seeds: cell.cell.trials.len(),
        steps,
        cpu_seconds: cpu,
        steps_per_s: if cpu > 0.0 { steps as f64 / cpu } else { 0.0 },
        share: if total_cost > 0.0 { cell.cost / total_cost } else { 0.0 },
    }
}

/// The table header of [`format_row`].
pub fn header() -> String {
    format!("{:<58} {:>5} {:>13} {:>9} {:>11} {:>7}", "cell", "seeds", "steps", "CPU s", "M steps/s", "share")
}

/// One printed row.
pub fn format_row(r: &CellBench) -> String {
    format!(
        "{:<58} {:>5} {:>13} {:>9.2} {:>11.3} {:>6.2}%",
        r.cell,
        r.seeds,
        r.steps,
        r.cpu_seconds,
        r.steps_per_s / 1e6,
        100.0 * r.share
    )
}
