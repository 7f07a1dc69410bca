//! The grid form of a two-variable fuzzy rule base (Mountain Car, Ball-Beam): each variable's
//! prune window as [`GRID`] fixed slots (the default width and prune give windows of 3–4 sets,
//! whatever the number of sets), the memberships a vector of [`GRID`] lanes with the window a
//! branch-free mask, every slot's weight a product, so the activation and the learner's sums run
//! over fixed-size arrays with no per-step list bookkeeping.
//!
//! The same bits as [`Fuzzy`]'s windowed activation: each membership inside the window is the
//! same exponential of the same argument ([`math::exp_lanes`] is `exp` lane by lane), the
//! normaliser the same sum in window order (the masked lanes add +0, which changes no sum: a sum
//! of non-negative terms started at +0 is never −0), each rule's weight the same product
//! `μ₀·μ₁`; every slot outside the windows weighs exactly 0. An empty window (the nearest set) and
//! a zero normaliser (the nearest set takes it all) are the windowed path's own rules.

use super::activation::{Activations, Encode, Features, GridView, Representation, GRID};
use super::fuzzy::{Fuzzy, Variable};
use crate::math;
use crate::simd::Simd;

/// A variable's memberships as the grid keeps them: [`GRID`] zeros, the window's [`GRID`] lanes
/// (0 past its length), [`GRID`] zeros; the zeros let two activations' windows be lined up by a
/// shift of at most [`GRID`] ([`Features::overlap`]).
type Lanes = [f64; 3 * GRID];

/// One variable with its centres padded by [`GRID`] − 1 past the last (never unmasked), so that
/// a window's [`GRID`] lanes always read centres.
#[derive(Debug, Clone)]
struct Padded {
    var: Variable,
    centres: Vec<f64>,
}

/// A two-variable fuzzy rule base whose prune windows hold at most [`GRID`] sets, activated as a
/// grid ([`DenseActive`]); built from the windowed [`Fuzzy`] it mirrors bit for bit.
#[derive(Debug, Clone)]
pub struct DenseFuzzy {
    vars: [Padded; 2],
    /// The learner's actions: a rule's row starts at rule · actions.
    actions: u32,
    /// A row of rules' length in the table: n₁ · actions.
    stride: u32,
    /// Each slot row's offset from the first: i0 · stride (added as one vector).
    row_steps: [u32; GRID],
    /// Where the last row of rules starts: (n₀ − 1) · stride.
    last_row: u32,
    windowed: Fuzzy,
}

/// A state's activation in grid form ([`GridView`]), and each variable's memberships ([`Lanes`]).
///
/// Boxed so that the trial loop's swap of φ(s) and φ(s′) moves a pointer.
#[derive(Debug, Clone, Default)]
pub struct DenseActive(Box<Grid>);

#[derive(Debug, Clone, Default)]
struct Grid {
    mu: [Lanes; 2],
    first: [u32; 2],
    view: GridView,
}

impl DenseFuzzy {
    /// Whether `fuzzy` fits the grid form: two variables, each of one set or of a window that
    /// never holds more than [`GRID`] sets. A window spans the sets within ±reach of a point, at
    /// most ⌊2·reach⌋ + 1 of them; 2·reach ≤ 3.5 leaves room for the rounding of its edges.
    pub fn fits(fuzzy: &Fuzzy) -> bool {
        const _: () = assert!(GRID == 4);
        fuzzy.vars.len() == 2 && fuzzy.vars.iter().all(|v| v.n == 1 || 2.0 * v.reach <= 3.5)
    }

    /// The grid form of `fuzzy`, which must [`fit`](Self::fits), for a learner of `actions`.
    pub fn new(fuzzy: Fuzzy, actions: usize) -> Self {
        assert!(Self::fits(&fuzzy), "the rule base does not fit the grid form");
        let pad = |j: usize| {
            let var = fuzzy.vars[j].clone();
            let mut centres = var.centres.clone();
            centres.resize(var.n + GRID - 1, 0.0);
            Padded { var, centres }
        };
        let rows = fuzzy.n_features() + GRID;
        assert!(rows * actions <= u32::MAX as usize, "a table of {rows} rules × {actions} actions");
        let stride = (fuzzy.vars[1].n * actions) as u32;
        let last_row = (fuzzy.vars[0].n as u32 - 1) * stride;
        let row_steps = std::array::from_fn(|i0| i0 as u32 * stride);
        Self { vars: [pad(0), pad(1)], actions: actions as u32, stride, row_steps, last_row, windowed: fuzzy }
    }

    /// Variable `j`'s normalised memberships at `value` into the window's lanes of its [`Lanes`]
    /// (whose zeros on either side stay), and its window (first set, length), as [`Fuzzy`]'s
    /// `memberships` gives them.
    #[inline(always)]
    fn memberships(&self, j: usize, value: f64, out: &mut Lanes) -> (usize, usize) {
        let Padded { var: v, centres } = &self.vars[j];
        let mid: &mut [f64; GRID] = (&mut out[GRID..2 * GRID]).try_into().expect("the window's lanes");
        if v.n == 1 {
            *mid = [1.0, 0.0, 0.0, 0.0];
            return (0, 1);
        }
        #[cfg(target_arch = "x86_64")]
        if self.windowed.simd != Simd::Baseline {
            // SAFETY: the level is capped by what the CPU has (AVX-512 includes AVX2), and the
            // centres are padded.
            return unsafe { super::dense_x86::memberships(v, centres, value, mid) };
        }
        let (x, pos, first, last) = v.window(value);
        let len = last + 1 - first;
        debug_assert!(len <= GRID, "a window of {len} sets");
        // Lane k is inside the window when k < len: a mask of all ones or zeros a lane, which
        // clears an outside lane's bits (+0).
        let mask: [u64; GRID] = std::array::from_fn(|k| 0u64.wrapping_sub(u64::from(k < len)));
        let keep = |v: f64, k: usize| f64::from_bits(v.to_bits() & mask[k]);
        let c: &[f64; GRID] = centres[first..first + GRID].try_into().expect("padded centres");
        let mut raw = [0.0; GRID];
        for k in 0..GRID {
            let d = x - c[k];
            // Outside the window exp(+0) (its fast path), masked again below.
            raw[k] = keep(-(d * d) * v.inv_two_sigma_sq, k);
        }
        math::exp_lanes(&mut raw);
        let mut sum = 0.0;
        for (k, r) in raw.iter_mut().enumerate() {
            *r = keep(*r, k);
            sum += *r;
        }
        if sum.is_nan() || sum <= 0.0 {
            *mid = [1.0, 0.0, 0.0, 0.0];
            return (v.nearest(pos), 1);
        }
        let inv = 1.0 / sum;
        for (k, m) in mid.iter_mut().enumerate() {
            // Masked after the product too: 0·inv is NaN when the sum is subnormal.
            *m = keep(raw[k] * inv, k);
        }
        (first, len)
    }
}

impl Representation for DenseFuzzy {
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

impl Encode for DenseFuzzy {
    type Active = DenseActive;

    #[inline(always)]
    fn encode(&self, state: &[f64], out: &mut DenseActive) {
        let g = &mut *out.0;
        // Both variables written out, not a loop of two, so that their chains interleave.
        let [x0, x1] = *state.first_chunk::<2>().expect("two state variables");
        let (first0, len0) = self.memberships(0, x0, &mut g.mu[0]);
        let (first1, len1) = self.memberships(1, x1, &mut g.mu[1]);
        g.first = [first0 as u32, first1 as u32];
        g.view.len = [len0 as u32, len1 as u32];
        // Each slot's weight μ₀·μ₁, as the windowed activation multiplies it (outside a window
        // one factor is +0, and so is the product).
        let (mu0, mu1) = (&g.mu[0][GRID..2 * GRID], &g.mu[1][GRID..2 * GRID]);
        for (row, &m0) in g.view.weight.iter_mut().zip(mu0) {
            for (w, &m1) in row.iter_mut().zip(mu1) {
                *w = m0 * m1;
            }
        }
        // Slot row i0 starts at rule (first₀ + i0)·n₁ + first₁, clamped to the last row of sets.
        let base = g.first[0] * self.stride + g.first[1] * self.actions;
        let last = self.last_row + g.first[1] * self.actions;
        g.view.row = std::array::from_fn(|i0| (base + self.row_steps[i0]).min(last));
        g.view.rule_len = self.actions;
        g.view.swap = 0u64.wrapping_sub(u64::from(g.view.len[1] & 1));
    }
}

impl Features for DenseActive {
    const ONE_HOT: bool = false;
    const GRID: bool = true;

    fn rules(&self) -> (&[u32], &[f64]) {
        unreachable!("a grid activation is read through `grid`")
    }

    #[inline(always)]
    fn grid(&self) -> &GridView {
        &self.0.view
    }

    /// The windowed activation's factorised overlap, each variable's dot over the two windows'
    /// common sets in set order: this window's lanes against the other's shifted to the same
    /// sets, where the sets outside either window add +0, which changes no sum of non-negative
    /// terms (windows more than [`GRID`] sets apart meet only zeros).
    #[inline(always)]
    fn overlap(&self, other: &Self) -> f64 {
        let (a, b) = (&*self.0, &*other.0);
        let mut product = 1.0;
        for j in 0..2 {
            let shift = (i64::from(a.first[j]) - i64::from(b.first[j])).clamp(-(GRID as i64), GRID as i64);
            let at = (GRID as i64 + shift) as usize;
            let theirs: &[f64; GRID] = b.mu[j][at..at + GRID].try_into().expect("in the lanes");
            let mut dot = 0.0;
            for (mine, theirs) in a.mu[j][GRID..2 * GRID].iter().zip(theirs) {
                dot += mine * theirs;
            }
            product *= dot;
        }
        product
    }
}

#[cfg(test)]
mod tests {
    use super::super::fuzzy::HALF_CROSSING_WIDTH;
    use super::*;

    /// Each variable's memberships and window at every vector level equal the portable code's,
    /// bit for bit, and the windowed activation's window: across the range, at its edges, past
    /// them, at the window edges' rounding, and at ±∞ and NaN (where a step's state stops being
    /// finite and the trial ends, the window must still lie inside the table).
    #[test]
    fn memberships_and_windows_agree_at_every_level_for_any_value() {
        let mut checked = 0;
        for (sets, prune) in [([2, 3], 1e-3), ([4, 4], 1e-3), ([7, 10], 1e-3), ([12, 5], 1e-2), ([3, 9], 0.3)]
        {
            let ranges = [[-1.2, 0.6], [-0.07, 0.07]];
            let fuzzy = |simd| Fuzzy::new(&sets, &ranges, HALF_CROSSING_WIDTH, prune).with_simd(simd);
            if !DenseFuzzy::fits(&fuzzy(Simd::Baseline)) {
                continue;
            }
            let portable = DenseFuzzy::new(fuzzy(Simd::Baseline), 4);
            for (j, [lo, hi]) in ranges.into_iter().enumerate() {
                let spacing = (hi - lo) / f64::from(sets[j] - 1);
                let mut values: Vec<f64> =
                    (0..=4000).map(|i| lo - 0.1 + f64::from(i) * (hi - lo + 0.2) / 4000.0).collect();
                // The window edges' rounding: each centre ± reach, and a step either side.
                let reach = portable.vars[j].var.reach;
                for k in 0..sets[j] {
                    let edge = lo + (f64::from(k) + reach) * spacing;
                    values.extend([edge, edge.next_up(), edge.next_down(), edge - 2.0 * reach * spacing]);
                }
                values.extend([lo, hi, f64::INFINITY, f64::NEG_INFINITY, f64::NAN, f64::MAX, -f64::MAX]);
                for simd in Simd::available() {
                    let dense = DenseFuzzy::new(fuzzy(simd), 4);
                    for &x in &values {
                        let (mut want, mut got) = ([7.0; 3 * GRID], [7.0; 3 * GRID]);
                        let w = portable.memberships(j, x, &mut want);
                        let g = dense.memberships(j, x, &mut got);
                        assert_eq!(g, w, "{sets:?} variable {j} at {x:e}, {simd:?}: window");
                        let bits = |l: &Lanes| l.map(f64::to_bits);
                        assert_eq!(bits(&got), bits(&want), "{sets:?} variable {j} at {x:e}, {simd:?}");
                        let (_, _, first, last) = portable.vars[j].var.window(x);
                        if x.is_finite() {
                            assert_eq!((first, last + 1 - first), w, "the windowed path's window at {x:e}");
                        }
                        assert!(w.0 + GRID <= portable.vars[j].centres.len(), "inside the padding");
                        checked += 1;
                    }
                }
            }
        }
        assert!(checked > 20_000, "{checked}");
    }
}
