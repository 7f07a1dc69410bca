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
    /// For a fuzzy grid, the per-variable memberships whose outer product the weights are (none
    /// for lists built otherwise): they make [`overlap`](Self::overlap) a product of short dots.
    pub(crate) factors: Factors,
}

/// Per-variable windows of normalised memberships: variable j activates sets
/// `first[j] .. first[j] + len[j]` with memberships `mu[offset_j ..][.. len[j]]`, the offsets
/// being the running sum of `len`.
#[derive(Debug, Clone, Default)]
pub(crate) struct Factors {
    /// Variables (0: unknown).
    pub(crate) vars: usize,
    pub(crate) first: [u32; 4],
    pub(crate) len: [u32; 4],
    pub(crate) mu: Vec<f64>,
}

impl Activations {
    /// Remove all activations, keeping capacity.
    #[inline]
    pub fn clear(&mut self) {
        self.index.clear();
        self.weight.clear();
        self.factors.vars = 0;
        self.factors.mu.clear();
    }

    /// Σᵢ wᵢ(self)·wᵢ(other) over the features both activate: what one Q(0) update at `other`
    /// adds, per unit step, to Q(self, a). For two fuzzy grid activations the sum factorises into
    /// one short dot per variable, Πⱼ Σₖ μⱼₖ·μ′ⱼₖ; otherwise it is summed rule by rule.
    pub fn overlap(&self, other: &Self) -> f64 {
        let (a, b) = (&self.factors, &other.factors);
        if a.vars > 0 && a.vars == b.vars {
            let mut product = 1.0;
            let (mut oa, mut ob) = (0, 0);
            for j in 0..a.vars {
                let (fa, fb) = (a.first[j] as usize, b.first[j] as usize);
                let (ea, eb) = (fa + a.len[j] as usize, fb + b.len[j] as usize);
                let mut dot = 0.0;
                for k in fa.max(fb)..ea.min(eb) {
                    dot += a.mu[oa + k - fa] * b.mu[ob + k - fb];
                }
                product *= dot;
                oa += a.len[j] as usize;
                ob += b.len[j] as usize;
            }
            return product;
        }
        let mut sum = 0.0;
        for (i, w) in self.index.iter().zip(&self.weight) {
            if let Some(p) = other.index.iter().position(|j| j == i) {
                sum += w * other.weight[p];
            }
        }
        sum
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
