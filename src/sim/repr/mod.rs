//! State representations (Section III-C): each maps a state to sparse feature activations
//! `(feature index, weight)`. A crisp bin is a one-hot "membership" of weight 1; a fuzzy rule base
//! activates several rules with normalised firing strengths (eqs. 9–11) that sum to 1.

mod crisp;
mod fuzzy;

pub use crisp::{Binning, Crisp};
pub use fuzzy::{Fuzzy, HALF_CROSSING_WIDTH, MAX_SETS};

use serde::{Deserialize, Serialize};

/// Crisp bins or fuzzy sets.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum ReprKind {
    /// Uniform bins per variable (tabular Q).
    Crisp,
    /// Gaussian fuzzy sets per variable, zero-order Takagi–Sugeno rule base.
    Fuzzy,
}

impl ReprKind {
    /// Command-line / YAML name.
    pub fn name(self) -> &'static str {
        match self {
            Self::Crisp => "crisp",
            Self::Fuzzy => "fuzzy",
        }
    }
}

/// Sparse feature activations of one state; reused across steps to avoid allocation.
#[derive(Debug, Clone, Default)]
pub struct Activations {
    /// Feature (rule or bin) indices.
    pub index: Vec<u32>,
    /// Weights, parallel to `index`.
    pub weight: Vec<f64>,
}

impl Activations {
    /// Remove all activations, keeping capacity.
    #[inline]
    pub fn clear(&mut self) {
        self.index.clear();
        self.weight.clear();
    }

    /// Number of active features.
    pub fn len(&self) -> usize {
        self.index.len()
    }

    /// Whether no feature is active.
    pub fn is_empty(&self) -> bool {
        self.index.is_empty()
    }
}

/// The one feature (table row) a crisp state activates, with weight exactly 1: the trial loop's
/// form of a crisp activation, so a step does no list bookkeeping for a single entry.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct OneHot(pub u32);

/// A map from states to sparse feature activations over a fixed number of features.
pub trait Representation {
    /// Total number of features (bins or rules).
    fn n_features(&self) -> usize;
    /// Most features a single state can activate (the learner sizes its trace strategy by it).
    fn max_active(&self) -> usize;
    /// Write the activations of `state` (its first `dim` entries) into `out`.
    fn activate(&self, state: &[f64], out: &mut Activations);
}

/// The form of a state's activations the trial loop works with, and how it is computed:
/// [`OneHot`] for crisp tables, [`Activations`] for fuzzy rule bases. Both denote the same sparse
/// activations as [`Representation::activate`].
pub trait Encode: Representation {
    /// The activation type the learner consumes.
    type Active: Default + crate::sim::learner::Features;
    /// Write the activations of `state` into `out`.
    fn encode(&self, state: &[f64], out: &mut Self::Active);
}

/// Row-major strides for a grid with `counts` cells per variable.
pub(crate) fn strides(counts: &[u32]) -> Vec<u32> {
    let mut s = vec![1u32; counts.len()];
    for j in (0..counts.len().saturating_sub(1)).rev() {
        s[j] = s[j + 1] * counts[j + 1];
    }
    s
}
