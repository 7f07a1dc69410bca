//! A program pipeline file, checked: every name known, every value of its param's type, the
//! experiments' axes and the variants' params resolved. What the loader gives the plan.

use crate::declared::RaceSpec;
use crate::program::model::{MetricType, Objective, ParamType, ParamValue, Protocol, Provenance};
use std::time::Duration;

/// The per-trial timeout when `timeout:` is not given.
pub const DEFAULT_TIMEOUT: Duration = Duration::from_secs(3600);

/// The id of the one experiment of a pipeline that declares none: one cell of the defaults.
pub const DEFAULT_EXPERIMENT: &str = "default";

/// A program pipeline, checked.
#[derive(Debug, Clone, PartialEq)]
pub struct ProgramDecl {
    /// The pipeline's name.
    pub name: String,
    /// Its description.
    pub description: Option<String>,
    /// The seeds of every cell.
    pub seeds: Vec<u64>,
    /// The program's argv.
    pub command: Vec<String>,
    /// The input globs, as written.
    pub inputs: Vec<String>,
    /// The protocol.
    pub protocol: Protocol,
    /// The per-trial timeout.
    pub timeout: Duration,
    /// The metrics, in file order.
    pub metrics: Vec<(String, MetricType)>,
    /// The objective.
    pub objective: Option<Objective>,
    /// The provenance commands.
    pub provenance: Vec<Provenance>,
    /// Every param and its default, in file order (a param's type is its default's).
    pub params: Vec<(String, ParamValue)>,
    /// The experiments: those declared, or the one [`DEFAULT_EXPERIMENT`].
    pub experiments: Vec<ExperimentDecl>,
    /// The variants.
    pub variants: Vec<VariantDecl>,
    /// The fresh seeds of every experiment's best cell (`fresh:`), in order; empty without.
    pub fresh: Vec<u64>,
}

impl ProgramDecl {
    /// Every param's name and type, in file order.
    pub fn param_types(&self) -> Vec<(String, ParamType)> {
        self.params.iter().map(|(n, v)| (n.clone(), v.kind())).collect()
    }

    /// The defaults' values, in file order.
    pub fn defaults(&self) -> Vec<ParamValue> {
        self.params.iter().map(|(_, v)| v.clone()).collect()
    }
}

/// An experiment, checked.
#[derive(Debug, Clone, PartialEq)]
pub struct ExperimentDecl {
    /// Its id.
    pub id: String,
    /// Its title.
    pub title: Option<String>,
    /// Each varied param with its values (typed as the param), in file order: the first axis
    /// is the outermost of the grid.
    pub axes: Vec<(String, Vec<ParamValue>)>,
    /// The params it fixes, with their values.
    pub fixed: Vec<(String, ParamValue)>,
    /// Its race: its own `race:` block, else the pipeline's (`None`: its full grid runs).
    pub race: Option<RaceSpec>,
}

impl ExperimentDecl {
    /// How many cells its grid has.
    pub fn cell_count(&self) -> u128 {
        self.axes.iter().map(|(_, v)| v.len() as u128).product()
    }
}

/// A variant, checked.
#[derive(Debug, Clone, PartialEq)]
pub struct VariantDecl {
    /// Its id.
    pub id: String,
    /// Its title.
    pub title: Option<String>,
    /// Its `set` entries as `params.NAME=VALUE`, in file order.
    pub set: Vec<String>,
    /// Every param's default under this variant, in [`ProgramDecl::params`] order: the
    /// pipeline's defaults with the variant's `set` applied, then the command line's `--set`
    /// (which wins, as for the engine's variants).
    pub defaults: Vec<ParamValue>,
}
