//! The dense form of a small two-variable fuzzy rule base (Mountain Car, Ball-Beam): every set of
//! both variables in fixed-size arrays padded to `P` lanes, the prune window a branch-free mask,
//! so the activation has no per-step list bookkeeping and the learner's sums run over every rule.
//!
//! The same bits as [`Fuzzy`]'s windowed activation: each membership inside the window is the
//! same exponential of the same argument ([`math::exp_lanes`] is `exp` lane by lane), the
//! normaliser the same sum in window order (the masked sets add +0, which changes no sum: a sum
//! of non-negative terms started at +0 is never −0), each rule's weight the same product
//! `μ₀·μ₁`; every set outside the window weighs exactly 0. An empty window (the nearest set) and
//! a zero normaliser (the nearest set takes it all) are the windowed path's own rules.

use super::activation::{
    Activations, DenseView, Encode, Features, PairOrder, Representation, DENSE_MAX_RULES,
};
use super::fuzzy::{Fuzzy, Variable};
use crate::math;

/// Most lanes a variable is padded to.
const MAX_LANES: usize = 16;

/// The weights' length: a weight a rule, then room for a row of [`MAX_LANES`] past the last.
const WEIGHTS: usize = DENSE_MAX_RULES + MAX_LANES;

/// Memberships whose exponentials are computed together, as the windowed activation does.
const EXP_LANES: usize = 4;

/// One variable's sets padded to `P` lanes (the centres past `n` are never unmasked).
#[derive(Debug, Clone)]
struct Padded<const P: usize> {
    var: Variable,
    centres: [f64; P],
}

/// A two-variable fuzzy rule base of at most [`DENSE_MAX_RULES`] rules and `P` sets a variable,
/// activated densely ([`DenseActive`]); built from the windowed [`Fuzzy`] it mirrors bit for bit.
#[derive(Debug, Clone)]
pub struct DenseFuzzy<const P: usize> {
    vars: [Padded<P>; 2],
    /// Q(s, ·)'s order of the rules for an even and an odd window length of the last variable.
    orders: [PairOrder; 2],
    windowed: Fuzzy,
}

/// A state's activation in dense form: per variable its normalised memberships over every set (0
/// outside the window) and its window, and every rule's weight.
///
/// The arrays are boxed so that the trial loop's swap of φ(s) and φ(s′) moves two pointers.
#[derive(Debug, Clone)]
pub struct DenseActive<const P: usize> {
    mu: Box<[[f64; P]; 2]>,
    first: [u32; 2],
    len: [u32; 2],
    n0: u32,
    n1: u32,
    /// One weight a rule, then spare lanes for a whole row's store past the last rule.
    weight: Box<[f64; WEIGHTS]>,
    order: PairOrder,
}

impl<const P: usize> Default for DenseActive<P> {
    fn default() -> Self {
        Self {
            mu: Box::new([[0.0; P]; 2]),
            first: [0; 2],
            len: [0; 2],
            n0: 1,
            n1: 1,
            weight: Box::new([0.0; WEIGHTS]),
            order: PairOrder::new(1, 1, false),
        }
    }
}

impl<const P: usize> DenseFuzzy<P> {
    /// Whether `sets` (per variable) fit the dense form with `P` lanes.
    pub fn fits(sets: &[u32]) -> bool {
        sets.len() == 2
            && sets.iter().all(|&n| n as usize <= P)
            && sets.iter().map(|&n| n as usize).product::<usize>() <= DENSE_MAX_RULES
    }

    /// The dense form of `fuzzy`, which must [`fit`](Self::fits).
    pub fn new(fuzzy: Fuzzy) -> Self {
        const { assert!(P.is_multiple_of(EXP_LANES) && P <= MAX_LANES) };
        let sets: Vec<u32> = fuzzy.vars.iter().map(|v| v.n as u32).collect();
        assert!(Self::fits(&sets), "{sets:?} does not fit {P} lanes");
        let pad = |j: usize| {
            let var = fuzzy.vars[j].clone();
            let mut centres = [0.0; P];
            centres[..var.n].copy_from_slice(&var.centres);
            Padded { var, centres }
        };
        let (n0, n1) = (sets[0] as usize, sets[1] as usize);
        let orders = [PairOrder::new(n0, n1, false), PairOrder::new(n0, n1, true)];
        Self { vars: [pad(0), pad(1)], orders, windowed: fuzzy }
    }

    /// Variable `j`'s normalised memberships over all `P` lanes at `value` (0 outside its window),
    /// and its window (first set, length), as [`Fuzzy`]'s `memberships` gives them.
    #[inline(always)]
    fn memberships(&self, j: usize, value: f64, mu: &mut [f64; P]) -> (usize, usize) {
        let Padded { var: v, centres } = &self.vars[j];
        if v.n == 1 {
            *mu = [0.0; P];
            mu[0] = 1.0;
            return (0, 1);
        }
        let (x, pos, first, last) = v.window(value);
        // Set k is inside the window when k − first (wrapping) is at most its span: one
        // comparison a lane, as a mask of all ones or zeros that clears a lane's bits (+0).
        let span = (last - first) as u64;
        let mask: [u64; P] = std::array::from_fn(|k| {
            0u64.wrapping_sub(u64::from((k as u64).wrapping_sub(first as u64) <= span))
        });
        let keep = |v: f64, k: usize| f64::from_bits(v.to_bits() & mask[k]);
        let mut raw = [0.0; P];
        for k in 0..P {
            let d = x - centres[k];
            // Outside the window exp(+0) (its fast path), masked again below.
            raw[k] = keep(-(d * d) * v.inv_two_sigma_sq, k);
        }
        for chunk in raw.as_chunks_mut::<EXP_LANES>().0 {
            math::exp_lanes(chunk);
        }
        let mut sum = 0.0;
        for (k, r) in raw.iter_mut().enumerate() {
            *r = keep(*r, k);
            sum += *r;
        }
        if sum.is_nan() || sum <= 0.0 {
            let nearest = v.nearest(pos);
            *mu = [0.0; P];
            mu[nearest] = 1.0;
            return (nearest, 1);
        }
        let inv = 1.0 / sum;
        for k in 0..P {
            // Masked after the product too: 0·inv is NaN when the sum is subnormal.
            mu[k] = keep(raw[k] * inv, k);
        }
        (first, last + 1 - first)
    }
}

impl<const P: usize> Representation for DenseFuzzy<P> {
    fn n_features(&self) -> usize {
        self.windowed.n_features()
    }

    fn max_active(&self) -> usize {
        self.windowed.max_active()
    }

    fn activate(&self, state: &[f64], out: &mut Activations) {
        self.windowed.activate(state, out);
    }
}

impl<const P: usize> Encode for DenseFuzzy<P> {
    type Active = DenseActive<P>;

    #[inline(always)]
    fn encode(&self, state: &[f64], out: &mut DenseActive<P>) {
        let mu = &mut *out.mu;
        for j in 0..2 {
            let (first, len) = self.memberships(j, state[j], &mut mu[j]);
            out.first[j] = first as u32;
            out.len[j] = len as u32;
        }
        let (n0, n1) = (self.vars[0].var.n, self.vars[1].var.n);
        (out.n0, out.n1) = (n0 as u32, n1 as u32);
        out.order = self.orders[out.len[1] as usize & 1];
        // Each rule's weight μ₀·μ₁, as the windowed activation multiplies it: a row of `P` products
        // at a time, each row written over the last one's lanes past n1 (products with sets that
        // do not exist, +0 as μ₁ is there), the last row's into the weights' spare lanes.
        let weight = &mut *out.weight;
        for (k0, &m0) in mu[0][..n0].iter().enumerate() {
            let row: &mut [f64; P] = (&mut weight[k0 * n1..][..P]).try_into().expect("P lanes");
            for k1 in 0..P {
                row[k1] = m0 * mu[1][k1];
            }
        }
    }
}

impl<const P: usize> Features for DenseActive<P> {
    const ONE_HOT: bool = false;
    const DENSE: bool = true;

    fn rules(&self) -> (&[u32], &[f64]) {
        unreachable!("a dense activation is read through `dense`")
    }

    #[inline(always)]
    fn dense(&self) -> DenseView<'_> {
        let rules = (self.n0 * self.n1) as usize;
        DenseView {
            weight: &self.weight[..rules],
            n0: self.n0,
            n1: self.n1,
            first: self.first,
            len: self.len,
            order: &self.order,
        }
    }

    /// The windowed activation's factorised overlap, each variable's dot over every set: the sets
    /// outside either window add +0, which changes no sum of non-negative terms.
    #[inline(always)]
    fn overlap(&self, other: &Self) -> f64 {
        let mut product = 1.0;
        for j in 0..2 {
            let mut dot = 0.0;
            for k in 0..P {
                dot += self.mu[j][k] * other.mu[j][k];
            }
            product *= dot;
        }
        product
    }
}
