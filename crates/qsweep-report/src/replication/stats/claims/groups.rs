//! The index structures every resample of the claims shares: each heatmap with its state counts,
//! the cells paired across algorithms and representations, and the groups some claims average
//! over.

use super::definitions::ClaimCell;
use crate::derive::rank::average_ranks;
use qsweep_engine::env::SystemKind;
use qsweep_engine::Algorithm;
use std::collections::BTreeMap;

/// A heatmap: its cells and their state counts.
pub(super) struct Heatmap {
    pub(super) system: SystemKind,
    pub(super) fuzzy: bool,
    pub(super) experiment: usize,
    pub(super) algorithm: Algorithm,
    pub(super) cells: Vec<usize>,
    pub(super) states: Vec<f64>,
    /// Ranks of `states` (fixed: only the means are resampled).
    pub(super) state_ranks: Vec<f64>,
}

/// Two paired cells and their state count.
pub(super) type StatePair = (usize, usize, f64);

/// Index structures shared by every resample.
pub(super) struct Groups {
    /// One per (experiment, algorithm), in that order.
    pub(super) heatmaps: Vec<Heatmap>,
    /// Per system (in order), pairs (Q(0) cell, Q(λ) cell) of one experiment and configuration.
    pub(super) algorithm_pairs: Vec<Vec<(usize, usize)>>,
    /// Per (system, algorithm), pairs (crisp Exp. 1 cell, fuzzy Exp. 3 cell) of one configuration,
    /// with the pair's state count.
    pub(super) repr_pairs: Vec<Vec<StatePair>>,
    /// Cart-Pole cells; Mountain Car cells of Q(0) and of Q(λ).
    pub(super) cart_pole: Vec<usize>,
    pub(super) mountain_car: [Vec<usize>; 2],
    /// Cells with a compact configuration.
    pub(super) compact: Vec<bool>,
    /// The experiments and the systems present, in order.
    pub(super) experiments: Vec<usize>,
    pub(super) systems: Vec<SystemKind>,
}

impl Groups {
    /// The structures of `cells`.
    pub(super) fn of(cells: &[ClaimCell]) -> Self {
        let mut by_heatmap: BTreeMap<(usize, Algorithm), Vec<usize>> = BTreeMap::new();
        type Config = (Vec<u32>, u32);
        let mut by_config: BTreeMap<(usize, Config, Algorithm), usize> = BTreeMap::new();
        let mut by_exp_id: BTreeMap<(SystemKind, String, Config, Algorithm), usize> = BTreeMap::new();
        for (i, c) in cells.iter().enumerate() {
            by_heatmap.entry((c.experiment, c.algorithm)).or_default().push(i);
            let cfg = (c.resolution.clone(), c.actions);
            by_config.insert((c.experiment, cfg.clone(), c.algorithm), i);
            by_exp_id.insert((c.system, c.experiment_id.clone(), cfg, c.algorithm), i);
        }
        let heatmaps: Vec<Heatmap> = by_heatmap
            .into_iter()
            .map(|((experiment, algorithm), idx)| Heatmap {
                system: cells[idx[0]].system,
                fuzzy: cells[idx[0]].fuzzy,
                experiment,
                algorithm,
                states: idx.iter().map(|&i| cells[i].states()).collect(),
                state_ranks: average_ranks(&idx.iter().map(|&i| cells[i].states()).collect::<Vec<_>>()),
                cells: idx,
            })
            .collect();
        let mut algorithm_pairs: BTreeMap<SystemKind, Vec<(usize, usize)>> = BTreeMap::new();
        for ((e, cfg, a), &i) in &by_config {
            if *a == Algorithm::Q0 {
                if let Some(&j) = by_config.get(&(*e, cfg.clone(), Algorithm::QLambda)) {
                    algorithm_pairs.entry(cells[i].system).or_default().push((i, j));
                }
            }
        }
        let mut repr_pairs: BTreeMap<(SystemKind, Algorithm), Vec<StatePair>> = BTreeMap::new();
        for ((s, id, cfg, a), &i) in &by_exp_id {
            if id == "1" && !cells[i].fuzzy {
                if let Some(&j) = by_exp_id.get(&(*s, "3".to_string(), cfg.clone(), *a)) {
                    if cells[j].fuzzy {
                        repr_pairs.entry((*s, *a)).or_default().push((i, j, cells[i].states()));
                    }
                }
            }
        }
        // Heatmaps are in (experiment, algorithm) order, so one experiment's are adjacent.
        let mut experiments: Vec<usize> = heatmaps.iter().map(|h| h.experiment).collect();
        experiments.dedup();
        let mut systems: Vec<SystemKind> = heatmaps.iter().map(|h| h.system).collect();
        systems.sort();
        systems.dedup();
        let of = |pred: &dyn Fn(&ClaimCell) -> bool| (0..cells.len()).filter(|&i| pred(&cells[i])).collect();
        Self {
            heatmaps,
            algorithm_pairs: algorithm_pairs.into_values().collect(),
            repr_pairs: repr_pairs.into_values().collect(),
            cart_pole: of(&|c| c.system == SystemKind::CartPole),
            mountain_car: [
                of(&|c| c.system == SystemKind::MountainCar && c.algorithm == Algorithm::Q0),
                of(&|c| c.system == SystemKind::MountainCar && c.algorithm == Algorithm::QLambda),
            ],
            compact: cells.iter().map(ClaimCell::compact).collect(),
            experiments,
            systems,
        }
    }
}
