//! The resolved plan: a pipeline expanded into experiments → cells (one fully resolved
//! configuration each) × seeds → trials with their cache keys. Every default is filled in here,
//! before hashing, so a changed default changes exactly the keys it affects.

mod resolve;

pub use resolve::{plan, plan_variants, DEFAULT_MAX_TRIALS};

use crate::cache::Key;
use crate::exec::Job;
use crate::sim::env::SystemKind;
use crate::sim::repr::ReprKind;
use crate::sim::{Algorithm, TrialConfig};
use crate::spec::{Axis, RaceSpec, Reference, Target};
use std::collections::BTreeMap;
use std::path::PathBuf;

/// A pipeline, expanded.
#[derive(Debug, Clone)]
pub struct Plan {
    /// Pipeline name (report folder).
    pub name: String,
    /// Free text from the pipeline.
    pub description: Option<String>,
    /// The pipeline file.
    pub source: PathBuf,
    /// Where reference values come from.
    pub reference_source: Option<String>,
    /// Seeds of every cell.
    pub seeds: Vec<u64>,
    /// Experiments in report order: variants in file order, then systems as in the paper's
    /// figures, then experiments in file order.
    pub experiments: Vec<Experiment>,
    /// The planned variants, in file order (empty when the pipeline declares none).
    pub variants: Vec<Variant>,
    /// Only some of the pipeline's variants were selected (`--variant`): reports then leave the
    /// comparison of all variants alone.
    pub variant_subset: bool,
    /// Notes for the user found while planning (e.g. a variant that changes no trial).
    pub warnings: Vec<String>,
    /// Whether some experiment of the whole pipeline (any variant) races: its reports then carry
    /// the race columns, in every variant's files alike, so they concatenate.
    pub raced: bool,
}

/// A variant of a pipeline: the whole pipeline with some fields set differently.
#[derive(Debug, Clone, PartialEq)]
pub struct Variant {
    /// Identifier (report folder).
    pub id: String,
    /// Title.
    pub title: Option<String>,
    /// Description.
    pub description: Option<String>,
    /// Its `set` entries as `PATH=VALUE`.
    pub set: Vec<String>,
    /// Seeds of its cells (a variant may set `seeds`).
    pub seeds: Vec<u64>,
}

/// One experiment of one system, expanded into cells.
#[derive(Debug, Clone)]
pub struct Experiment {
    /// The variant this experiment belongs to (`None` for a pipeline without variants).
    pub variant: Option<String>,
    /// The system.
    pub system: SystemKind,
    /// Identifier (Table I's "Exp." number).
    pub id: String,
    /// Optional title.
    pub title: Option<String>,
    /// Crisp or fuzzy.
    pub repr: ReprKind,
    /// Algorithms (figure columns).
    pub algorithms: Vec<Algorithm>,
    /// Varied axes: first = heatmap rows, second = columns.
    pub axes: Vec<Axis>,
    /// Constants (including the resolved action count when it is not varied).
    pub fixed: Vec<(Target, u32)>,
    /// Published values per algorithm.
    pub reference: BTreeMap<Algorithm, Reference>,
    /// Its race, if any: seeds go round by round to the cells that can still be the best
    /// ([`crate::race`]); the cells' trials then hold every round resolved so far.
    pub race: Option<RaceSpec>,
    /// Cells: every algorithm × every grid point, algorithm-major, grid in axis order.
    pub cells: Vec<Cell>,
}

/// One resolved configuration and its trials.
#[derive(Debug, Clone)]
pub struct Cell {
    /// The algorithm.
    pub algorithm: Algorithm,
    /// One value per axis of the experiment.
    pub coords: Vec<f64>,
    /// The fully resolved configuration.
    pub config: TrialConfig,
    /// One trial per seed.
    pub trials: Vec<PlannedTrial>,
    /// In a raced experiment, once its race is resolved against the cache: whether the cell is
    /// still a contender (not significantly worse than the best); `None` without a race.
    pub contender: Option<bool>,
}

/// A trial: a seed and its key.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PlannedTrial {
    /// The seed.
    pub seed: u64,
    /// Cache key of (config, seed).
    pub key: Key,
}

impl Plan {
    /// Every (experiment, cell, trial) of the plan, in plan order.
    pub fn trials(&self) -> impl Iterator<Item = (&Experiment, &Cell, &PlannedTrial)> {
        self.experiments
            .iter()
            .flat_map(|e| e.cells.iter().flat_map(move |c| c.trials.iter().map(move |t| (e, c, t))))
    }

    /// Number of trials, counting a trial shared by two cells twice.
    pub fn trial_count(&self) -> usize {
        self.experiments.iter().flat_map(|e| &e.cells).map(|c| c.trials.len()).sum()
    }

    /// Distinct trials by key, first occurrence wins, in plan order.
    pub fn unique_trials(&self) -> Vec<Job<'_>> {
        let mut seen = std::collections::HashSet::new();
        self.trials()
            .filter(|(_, _, t)| seen.insert(t.key))
            .map(|(_, c, t)| Job { config: &c.config, seed: t.seed, key: t.key })
            .collect()
    }
}

impl Plan {
    /// The variant a report of this plan shows: its only variant, when it has exactly one (the
    /// plan of one variant, [`Plan::only_variant`]).
    pub fn report_variant(&self) -> Option<&Variant> {
        match self.variants.as_slice() {
            [v] => Some(v),
            _ => None,
        }
    }

    /// What a report of this plan shows, for titles: `paper`, or `paper / gym-v0-reset`.
    pub fn report_name(&self) -> String {
        match self.report_variant() {
            Some(v) => format!("{} / {}", self.name, v.id),
            None => self.name.clone(),
        }
    }

    /// The plan of one variant alone (experiments of other variants dropped).
    pub fn only_variant(&self, id: &str) -> Plan {
        Plan {
            experiments: self
                .experiments
                .iter()
                .filter(|e| e.variant.as_deref() == Some(id))
                .cloned()
                .collect(),
            variants: self.variants.iter().filter(|v| v.id == id).cloned().collect(),
            warnings: Vec::new(),
            seeds: self
                .variants
                .iter()
                .find(|v| v.id == id)
                .map_or_else(|| self.seeds.clone(), |v| v.seeds.clone()),
            ..self.clone_header()
        }
    }

    fn clone_header(&self) -> Plan {
        Plan {
            name: self.name.clone(),
            description: self.description.clone(),
            source: self.source.clone(),
            reference_source: self.reference_source.clone(),
            seeds: self.seeds.clone(),
            experiments: Vec::new(),
            variants: Vec::new(),
            variant_subset: false,
            warnings: Vec::new(),
            raced: self.raced,
        }
    }
}

impl Experiment {
    /// Label like "Cart-Pole, Exp. 1 (crisp)".
    pub fn label(&self) -> String {
        format!("{}, Exp. {} ({})", self.system.title(), self.id, self.repr.name())
    }
}
