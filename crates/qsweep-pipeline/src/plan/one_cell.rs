//! One cell as a plan: the configuration `qsweep trial` runs, resolved by the same path as a
//! pipeline's cell (spec → plan, every default filled in), so that a trial and a pipeline cell with
//! the same settings have the same configuration and the same cache key.

use super::variants::plan;
use crate::declared::{load_value, LoadedSpec, Override};
use qsweep_engine::env::SystemKind;
use qsweep_engine::repr::ReprKind;
use qsweep_engine::{Algorithm, TrialConfig};
use serde::Serialize;
use std::collections::BTreeMap;

/// The cell to resolve: its grid point, its seed, and settings as pipeline overrides.
#[derive(Debug, Clone)]
pub struct CellRequest {
    /// The system.
    pub system: SystemKind,
    /// Bins or fuzzy sets.
    pub repr: ReprKind,
    /// Per state variable, in state order.
    pub resolution: Vec<u32>,
    /// Number of actions n of A_n.
    pub actions: u32,
    /// Q(0) or Q(λ).
    pub algorithm: Algorithm,
    /// The seed (part of the pipeline, so seed-dependent settings resolve as in a pipeline).
    pub seed: u64,
    /// Settings, applied as `--set` overrides of the one-cell pipeline, in order.
    pub overrides: Vec<Override>,
}

/// The one-cell pipeline, as typed values.
#[derive(Serialize)]
struct Pipeline<'a> {
    name: &'a str,
    seeds: [u64; 1],
    systems: BTreeMap<&'a str, System<'a>>,
}

#[derive(Serialize)]
struct System<'a> {
    experiments: [Experiment<'a>; 1],
}

#[derive(Serialize)]
struct Experiment<'a> {
    id: &'a str,
    repr: ReprKind,
    algorithms: [Algorithm; 1],
    vary: BTreeMap<&'a str, u32>,
    fixed: BTreeMap<&'a str, u32>,
}

/// Resolve one cell: the request becomes a one-cell pipeline (typed values, no YAML text) plus its
/// overrides, which `spec`
/// checks and `plan` resolves exactly as it does a pipeline file's.
pub fn one_cell(r: &CellRequest) -> anyhow::Result<TrialConfig> {
    let fixed = r.system.variables().iter().copied().zip(r.resolution.iter().copied()).collect();
    let pipeline = Pipeline {
        name: "trial",
        seeds: [r.seed],
        systems: BTreeMap::from([(
            r.system.name(),
            System {
                experiments: [Experiment {
                    id: "trial",
                    repr: r.repr,
                    algorithms: [r.algorithm],
                    vary: BTreeMap::from([("actions", r.actions)]),
                    fixed,
                }],
            },
        )]),
    };
    let spec = load_value(serde_yaml::to_value(&pipeline)?, "qsweep trial", &r.overrides)?;
    let loaded = LoadedSpec { spec, path: "qsweep trial".into(), variants: Vec::new() };
    let planned = plan(&loaded, None)?;
    planned
        .experiments
        .into_iter()
        .flat_map(|e| e.cells)
        .next()
        .map(|c| c.config)
        .ok_or_else(|| anyhow::anyhow!("the one-cell pipeline planned no cell"))
}
