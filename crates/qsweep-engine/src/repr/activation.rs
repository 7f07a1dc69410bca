//! What a representation produces and the learner consumes: sparse activations (the general list,
//! a crisp table's one-hot row), the traits that make and read them, and the grid strides.

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
/// `first[j] .. first[j] + len[j]` with memberships `mu[j · width ..][.. len[j]]`.
#[derive(Debug, Clone, Default)]
pub(crate) struct Factors {
    /// Variables (0: unknown).
    pub(crate) vars: usize,
    pub(crate) first: [u32; 4],
    pub(crate) len: [u32; 4],
    /// Room per variable in `mu` (the activation's scratch width).
    pub(crate) width: usize,
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
            for j in 0..a.vars {
                let (fa, fb) = (a.first[j] as usize, b.first[j] as usize);
                let (ea, eb) = (fa + a.len[j] as usize, fb + b.len[j] as usize);
                let (oa, ob) = (j * a.width, j * b.width);
                let mut dot = 0.0;
                for k in fa.max(fb)..ea.min(eb) {
                    dot += a.mu[oa + k - fa] * b.mu[ob + k - fb];
                }
                product *= dot;
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
    type Active: Default + Features;
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

/// Slots per variable of a [`GridView`]: the most sets a two-variable rule base's prune window
/// may hold to take the grid form (`DenseFuzzy::fits`).
pub const GRID: usize = 4;

/// A two-variable rule base's activation as a fixed grid of [`GRID`] × [`GRID`] slots over its
/// windows: slot (i0, i1) is rule (first₀ + i0, first₁ + i1), whose row starts at
/// [`at`](Self::at)`(i0, i1)`, and weighs what the sparse list gives that rule where both lie
/// inside their windows, exactly 0 elsewhere (a slot past a window may name any rule, up to
/// [`GRID`] − 1 past the table's last: the learner's table is padded for it). The sparse list is
/// the windows' slots in the same order (variable 0's window outer), so the learner can rebuild it
/// ([`GridView::sparse`]) for the rare cases that need the literal list.
///
/// Read by reference ([`Features::grid`]): the learner's kernels take one pointer.
#[derive(Debug, Clone, Default)]
pub struct GridView {
    /// Each slot's weight, μ₀[i0]·μ₁[i1].
    pub weight: [[f64; GRID]; GRID],
    /// Where slot row i0's first slot's row starts in the learner's table: rule
    /// (first₀ + i0)·n₁ + first₁ times the row length, with first₀ + i0 clamped to the last set of
    /// variable 0 (past its window, where the slots weigh 0). The last is the greatest.
    pub row: [u32; GRID],
    /// A rule's row length in the learner's table: slot (i0, i1)'s row starts `i1` rows past
    /// `row[i0]`.
    pub rule_len: u32,
    /// Each variable's window length.
    pub len: [u32; 2],
    /// All ones when the last variable's window is odd: Q(s, ·)'s two interleaved partial sums
    /// then trade places from one slot row to the next.
    pub swap: u64,
}

impl GridView {
    /// Where slot (i0, i1)'s row starts in the learner's table.
    #[inline(always)]
    pub fn at(&self, i0: usize, i1: usize) -> usize {
        self.row[i0] as usize + i1 * self.rule_len as usize
    }

    /// Where the last slot's row starts: the greatest of any slot's.
    #[inline(always)]
    pub fn last_at(&self) -> usize {
        self.at(GRID - 1, GRID - 1)
    }

    /// The sparse list of the windows' rules in activation order, for `actions` actions (the
    /// table's row length): (count, indices, weights).
    pub fn sparse(&self, actions: usize) -> (usize, [u32; GRID * GRID], [f64; GRID * GRID]) {
        let (mut index, mut weight) = ([0u32; GRID * GRID], [0.0f64; GRID * GRID]);
        let mut n = 0;
        for i0 in 0..self.len[0] as usize {
            for i1 in 0..self.len[1] as usize {
                (index[n], weight[n]) = ((self.at(i0, i1) / actions) as u32, self.weight[i0][i1]);
                n += 1;
            }
        }
        (n, index, weight)
    }
}

/// A state's activations in the form the learner evaluates and updates: the general sparse list
/// ([`Activations`], fuzzy rule bases) or a crisp table's single row ([`OneHot`], weight 1).
pub trait Features {
    /// Whether this is always one feature of weight 1 (lets the learner skip the sum).
    const ONE_HOT: bool;
    /// Whether this is a two-variable rule base's window grid ([`GridView`]), which the learner
    /// reads through [`grid`](Self::grid) instead of [`rules`](Self::rules).
    const GRID: bool = false;
    /// The active features and their weights, in activation order (not for a `GRID` form).
    fn rules(&self) -> (&[u32], &[f64]);
    /// The window grid (only for a `GRID` form).
    fn grid(&self) -> &GridView {
        unreachable!("only a grid activation has a grid view")
    }
    /// Σᵢ wᵢ(self)·wᵢ(other) over the features both activate.
    fn overlap(&self, other: &Self) -> f64;
}

impl Features for Activations {
    const ONE_HOT: bool = false;

    #[inline(always)]
    fn rules(&self) -> (&[u32], &[f64]) {
        (&self.index, &self.weight)
    }

    #[inline(always)]
    fn overlap(&self, other: &Self) -> f64 {
        Activations::overlap(self, other)
    }
}

/// A crisp row: the list of one feature of weight 1 (`w · q = q` exactly, so Q(s, ·) is the row).
impl Features for OneHot {
    const ONE_HOT: bool = true;

    #[inline(always)]
    fn rules(&self) -> (&[u32], &[f64]) {
        (std::slice::from_ref(&self.0), &[1.0])
    }

    /// 1 for the same row, else 0: the Q(0) refresh adds α·δ to exactly the entry the update
    /// moved, the same addition on the same values (bit for bit).
    #[inline(always)]
    fn overlap(&self, other: &Self) -> f64 {
        if self.0 == other.0 {
            1.0
        } else {
            0.0
        }
    }
}
