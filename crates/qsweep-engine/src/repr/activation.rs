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

/// A two-variable rule base's activation over every rule, in rule order (`k0 · n1 + k1`): the
/// windows' rules weigh what the sparse list gives them, every other rule exactly 0. The sparse
/// list is the window's rules in the same order (variable 0's window outer), so the learner can
/// rebuild it ([`DenseView::sparse`]) for the rare cases that need the literal list.
#[derive(Debug, Clone, Copy)]
pub struct DenseView<'a> {
    /// One weight per rule (`n0 · n1` of them).
    pub weight: &'a [f64],
    /// Sets of the first variable (the rows).
    pub n0: u32,
    /// Sets of the last variable (the row length).
    pub n1: u32,
    /// Each variable's window: its first set and its length.
    pub first: [u32; 2],
    /// See `first`.
    pub len: [u32; 2],
    /// The rules in the order Q(s, ·)'s two partial sums take them (for its window's length).
    pub order: &'a PairOrder,
}

/// The rules of a two-variable rule base in the order that Q(s, ·)'s two interleaved partial sums
/// take them, for one parity of the last variable's window length: rule (k0, k1) sits at position
/// j = (k0 − first₀)·len₁ + (k1 − first₁) of the windows' list and goes to partial sum j mod 2,
/// which is (k0·len₁ + k1) mod 2 up to a constant that only exchanges the two sums (their final
/// addition cannot tell). Pairs first (one rule for each sum), then the longer sum's rest.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PairOrder {
    /// Rule indices: `pairs` pairs (first sum, second sum), then the first sum's remaining rules;
    /// each rule of the base once (a kernel relies on it to skip bounds checks).
    rules: [u8; DENSE_MAX_RULES],
    /// How many pairs lead `rules`.
    pairs: u8,
    /// How many rules `rules` holds (every rule of the base).
    len: u8,
}

impl PairOrder {
    /// The order for `n0 × n1` rules (at most [`DENSE_MAX_RULES`]) and a window length of the
    /// last variable whose parity is `odd`.
    pub fn new(n0: usize, n1: usize, odd: bool) -> Self {
        assert!(n0 * n1 <= DENSE_MAX_RULES, "{n0}×{n1} rules");
        let p = usize::from(odd);
        let (mut even, mut other) = (Vec::new(), Vec::new());
        for k0 in 0..n0 {
            for k1 in 0..n1 {
                let list = if (k0 * p + k1) % 2 == 0 { &mut even } else { &mut other };
                list.push((k0 * n1 + k1) as u8);
            }
        }
        // The sums' names do not matter (their addition commutes): the longer one is "first".
        let (first, second) = if even.len() >= other.len() { (even, other) } else { (other, even) };
        let mut rules = [0u8; DENSE_MAX_RULES];
        let mut at = 0;
        for (&a, &b) in first.iter().zip(&second) {
            (rules[at], rules[at + 1]) = (a, b);
            at += 2;
        }
        for &a in &first[second.len()..] {
            rules[at] = a;
            at += 1;
        }
        Self { rules, pairs: second.len() as u8, len: at as u8 }
    }

    /// The pairs (first sum's rule, second sum's rule), then the first sum's remaining rules: a
    /// permutation of `0..self.rules()`.
    #[inline(always)]
    pub fn split(&self) -> (&[[u8; 2]], &[u8]) {
        let (pairs, rest) = self.rules[..self.len as usize].split_at(2 * self.pairs as usize);
        (pairs.as_chunks::<2>().0, rest)
    }

    /// How many rules the order holds (every rule of its base).
    #[inline(always)]
    pub fn rules(&self) -> usize {
        self.len as usize
    }
}

/// Most rules a [`DenseView`] holds.
pub const DENSE_MAX_RULES: usize = 36;

impl DenseView<'_> {
    /// The sparse list of the windows' rules in activation order: (count, indices, weights).
    pub fn sparse(&self) -> (usize, [u32; DENSE_MAX_RULES], [f64; DENSE_MAX_RULES]) {
        let (mut index, mut weight) = ([0u32; DENSE_MAX_RULES], [0.0f64; DENSE_MAX_RULES]);
        let mut n = 0;
        for k0 in self.first[0]..self.first[0] + self.len[0] {
            for k1 in self.first[1]..self.first[1] + self.len[1] {
                let i = k0 * self.n1 + k1;
                (index[n], weight[n]) = (i, self.weight[i as usize]);
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
    /// Whether this is a two-variable rule base's weight over every rule ([`DenseView`]), which
    /// the learner reads through [`dense`](Self::dense) instead of [`rules`](Self::rules).
    const DENSE: bool = false;
    /// The active features and their weights, in activation order (not for a `DENSE` form).
    fn rules(&self) -> (&[u32], &[f64]);
    /// The weights of every rule (only for a `DENSE` form).
    fn dense(&self) -> DenseView<'_> {
        unreachable!("only a dense activation has a dense view")
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
