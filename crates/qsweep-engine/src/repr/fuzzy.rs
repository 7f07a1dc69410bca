//! Fuzzy representation: Gaussian membership functions (eq. 9) per variable with centres evenly
//! spaced over `[lo, hi]` (endpoints included) and spread `σ = width · spacing`; the rule base is the
//! Cartesian product of the per-variable sets (eq. 8), firing strength the product (eq. 10),
//! normalised to sum 1 (eq. 11).
//!
//! For a grid rule base the normaliser of eq. (11) factorises, `Σ_m Π_j μ_j = Π_j Σ_k μ_jk`, so the
//! normalised strengths are the outer product of per-variable normalised memberships; that is how
//! they are computed. Values outside `[lo, hi]` are clamped to the range first (the fuzzy analogue of
//! the crisp edge bin), and sets whose membership is below `prune` are skipped (`prune = 0` is exact).

use super::activation::{strides, Activations, Encode, Representation};
use crate::math;
use crate::simd::{dispatch, Simd};

/// Most fuzzy sets a single variable may have.
pub const MAX_SETS: usize = 64;

/// Most state variables a rule base may have (Cart-Pole's four).
const MAX_VARS: usize = 4;

/// Windows up to this many sets (every variable, as with the default prune) take the activation
/// path with small scratch arrays.
const SMALL_WINDOW: usize = 8;

/// Memberships whose exponentials are computed together ([`math::exp_lanes`]); every window's
/// scratch holds a multiple of it.
const EXP_LANES: usize = 4;
const _: () = assert!(SMALL_WINDOW.is_multiple_of(EXP_LANES) && MAX_SETS.is_multiple_of(EXP_LANES));

/// `width` that makes neighbouring memberships cross at 0.5: `1 / (2·sqrt(2·ln 2))`.
pub const HALF_CROSSING_WIDTH: f64 = 0.424_660_900_144_009_5;

#[derive(Debug, Clone)]
pub(super) struct Variable {
    pub(super) lo: f64,
    pub(super) hi: f64,
    pub(super) n: usize,
    /// 1 / spacing (the window position is a product, not a division).
    pub(super) inv_spacing: f64,
    pub(super) inv_two_sigma_sq: f64,
    /// Half-width of the window of sets that can exceed `prune`, in units of `spacing`: at most n.
    pub(super) reach: f64,
    /// Every set's centre, `lo + k·spacing` (the midpoint for a single set).
    pub(super) centres: Vec<f64>,
}

impl Variable {
    /// Most sets a window can hold: ⌊2·reach⌋ + 1 centres lie within ±reach spacings of a point,
    /// plus one for rounding in the window edges.
    fn max_window(&self) -> usize {
        ((2.0 * self.reach) as usize).saturating_add(2).min(self.n)
    }

    /// The set nearest to window position `pos` (≥ 0 or NaN): ⌊pos + ½⌋ with halves rounded up,
    /// as `pos.round()` rounds them (exact for pos < 2⁵², without a library call).
    #[inline(always)]
    pub(super) fn nearest(&self, pos: f64) -> usize {
        let t = pos as usize;
        let up = pos - t as f64 >= 0.5;
        (t + usize::from(up)).min(self.n - 1)
    }

    /// The prune window of `value`: the value clamped to the range, its position in set
    /// spacings, and the first and last set within reach (the nearest set alone when none is).
    /// The one rule of the windowed and the dense activations.
    #[inline(always)]
    pub(super) fn window(&self, value: f64) -> (f64, f64, usize, usize) {
        let x = value.clamp(self.lo, self.hi);
        let pos = (x - self.lo) * self.inv_spacing;
        // The reach is at most n (`Fuzzy::new`), so both edges lie within ±2n, and truncation is
        // floor for the non-negative upper one; only a NaN position truncates out of range, and
        // either meaning of that (`math::trunc_i64`) gives the first set alone.
        let first = ceil_to_index(pos - self.reach);
        let last = (math::trunc_i64(pos + self.reach).max(0) as usize).min(self.n - 1);
        if first > last {
            let nearest = self.nearest(pos);
            (x, pos, nearest, nearest)
        } else {
            (x, pos, first, last)
        }
    }
}

/// A grid of Gaussian fuzzy sets with normalised product firing strengths.
#[derive(Debug, Clone)]
pub struct Fuzzy {
    pub(super) vars: Vec<Variable>,
    strides: Vec<u32>,
    n_features: usize,
    /// Largest window of any variable.
    max_window: usize,
    /// The vector instructions the activation uses (never changes a result; [`crate::simd`]).
    pub(super) simd: Simd,
}

impl Fuzzy {
    /// `sets[j]` Gaussians over `ranges[j]` (1 to 4 state variables) with σ = `width` × centre
    /// spacing; memberships below `prune` are skipped (0 keeps every rule).
    pub fn new(sets: &[u32], ranges: &[[f64; 2]], width: f64, prune: f64) -> Self {
        assert_eq!(sets.len(), ranges.len());
        assert!((1..=MAX_VARS).contains(&sets.len()), "1 to {MAX_VARS} state variables");
        let vars: Vec<Variable> = sets
            .iter()
            .zip(ranges)
            .map(|(&n, r)| {
                let n = n as usize;
                assert!((1..=MAX_SETS).contains(&n));
                let spacing = if n > 1 { (r[1] - r[0]) / (n - 1) as f64 } else { r[1] - r[0] };
                let sigma = width * spacing;
                // exp(−d²/2σ²) ≥ prune  ⇔  d ≤ σ·sqrt(2 ln(1/prune)); no prune reaches every set.
                // Capped at n spacings, which reach every set from anywhere in the range (the same
                // windows, and finite window edges for `window`).
                let reach =
                    if prune > 0.0 { width * (2.0 * math::ln(1.0 / prune)).sqrt() } else { f64::INFINITY };
                let reach = reach.min(n as f64);
                let centres = if n == 1 {
                    vec![(r[0] + r[1]) / 2.0]
                } else {
                    (0..n).map(|k| r[0] + k as f64 * spacing).collect()
                };
                Variable {
                    lo: r[0],
                    hi: r[1],
                    n,
                    inv_spacing: 1.0 / spacing,
                    inv_two_sigma_sq: 1.0 / (2.0 * sigma * sigma),
                    reach,
                    centres,
                }
            })
            .collect();
        let n_features = sets.iter().map(|&s| s as usize).product();
        let max_window = vars.iter().map(Variable::max_window).max().unwrap_or(1);
        Self { vars, strides: strides(sets), n_features, max_window, simd: crate::simd::level() }
    }

    /// The same rule base with its activation at `simd` (capped by what the CPU has).
    pub fn with_simd(mut self, simd: Simd) -> Self {
        self.simd = simd.capped();
        self
    }

    /// Centre of set `k` of variable `j`.
    pub fn centre(&self, j: usize, k: usize) -> f64 {
        self.vars[j].centres[k]
    }

    /// Normalised memberships of variable `j` at `value`: writes the window's memberships into
    /// `mu` and returns (its first set, its length), the length at most the variable's
    /// `max_window`, which `mu` must hold.
    #[inline(always)]
    fn memberships<const W: usize>(&self, j: usize, value: f64, mu: &mut [f64; W]) -> (usize, usize) {
        let v = &self.vars[j];
        if v.n == 1 {
            mu[0] = 1.0;
            return (0, 1);
        }
        let (x, pos, first, last) = v.window(value);
        let m = last + 1 - first;
        for (w, &c) in mu[..m].iter_mut().zip(&v.centres[first..=last]) {
            let d = x - c;
            *w = -(d * d) * v.inv_two_sigma_sq;
        }
        // The exponentials EXP_LANES at a time, then their sum in window order. The lanes past
        // the window are never read; zeros there keep them on exp_lanes' fast path (written one
        // by one: a fill of a run-time length becomes a memset call).
        let lanes = m.div_ceil(EXP_LANES) * EXP_LANES;
        for k in 1..EXP_LANES {
            if m + k <= lanes {
                mu[m + k - 1] = 0.0;
            }
        }
        for chunk in mu[..lanes].as_chunks_mut::<EXP_LANES>().0 {
            math::exp_lanes(chunk);
        }
        let mut sum = 0.0;
        for &w in &mu[..m] {
            sum += w;
        }
        if sum.is_nan() || sum <= 0.0 {
            // Every membership underflowed (a very narrow width): the nearest set takes it all.
            mu[0] = 1.0;
            return (v.nearest(pos), 1);
        }
        let inv = 1.0 / sum;
        for w in &mut mu[..m] {
            *w *= inv;
        }
        (first, m)
    }
}

impl Representation for Fuzzy {
    fn n_features(&self) -> usize {
        self.n_features
    }

    fn max_active(&self) -> usize {
        self.vars.iter().map(Variable::max_window).product()
    }

    fn activate(&self, state: &[f64], out: &mut Activations) {
        if self.max_window <= SMALL_WINDOW {
            activate_small(self.simd, self, state, out);
        } else {
            activate_large(self.simd, self, state, out);
        }
    }
}

impl Encode for Fuzzy {
    type Active = Activations;

    #[inline(always)]
    fn encode(&self, state: &[f64], out: &mut Activations) {
        self.activate(state, out);
    }
}

impl Fuzzy {
    /// [`activate`](Representation::activate) with scratch room for `W` sets per variable, the
    /// loops compiled for the rule base's number of variables.
    #[inline(always)]
    fn activate_with<const W: usize>(&self, state: &[f64], out: &mut Activations) {
        const _: () = assert!(MAX_VARS == 4);
        match self.vars.len() {
            1 => self.activate_vars::<W, 1>(state, out),
            2 => self.activate_vars::<W, 2>(state, out),
            3 => self.activate_vars::<W, 3>(state, out),
            // `new` admits 1 to MAX_VARS variables.
            _ => self.activate_vars::<W, 4>(state, out),
        }
    }

    /// The activation of `NV` variables. Every variable's memberships are computed first: they
    /// are independent, so their latency chains (the exponentials, the normalising division)
    /// overlap. The weights are the outer product, each rule's the product of its memberships in
    /// variable order, ((μ₀·μ₁)·μ₂)·μ₃, with the last variable (stride 1) innermost so that a run of
    /// rules is a run of table rows.
    #[inline(always)]
    fn activate_vars<const W: usize, const NV: usize>(&self, state: &[f64], out: &mut Activations) {
        let Activations { index, weight, factors: f } = out;
        let mut len = [0usize; NV];
        let mut stride = [0u32; NV];
        let mut base = 0u32;
        f.vars = NV;
        f.width = W;
        // The same length every step (a rule base's W and NV are fixed): this allocates once.
        f.mu.resize(NV * W, 0.0);
        let mu: &mut [[f64; W]] = f.mu.as_chunks_mut::<W>().0;
        for j in 0..NV {
            let (first, m) = self.memberships(j, state[j], &mut mu[j]);
            len[j] = m;
            stride[j] = self.strides[j];
            base += first as u32 * stride[j];
            f.first[j] = first as u32;
            f.len[j] = m as u32;
        }
        let total: usize = len.iter().product();
        // Resizing from the last step's length writes only the difference.
        index.resize(total, 0);
        weight.resize(total, 0.0);
        let (mu_last, s_last) = (&mu[NV - 1][..len[NV - 1]], stride[NV - 1]);
        let mut rows = index.chunks_exact_mut(mu_last.len()).zip(weight.chunks_exact_mut(mu_last.len()));
        // One run of rules: the last variable's sets after the others' product `p` at offset `o`.
        let mut run = |p: f64, o: u32| {
            let Some((ri, rw)) = rows.next() else { unreachable!("total rows") };
            for (k, ((i, w), &m)) in ri.iter_mut().zip(rw.iter_mut()).zip(mu_last).enumerate() {
                *i = o + k as u32 * s_last;
                *w = p * m;
            }
        };
        // A single variable's weight is 1·μ = μ exactly, as the products below are for more.
        let mu_of = |j: usize| &mu[j][..len[j]];
        match NV {
            1 => run(1.0, base),
            2 => {
                for (k0, &p0) in mu_of(0).iter().enumerate() {
                    run(p0, base + k0 as u32 * stride[0]);
                }
            }
            3 => {
                for (k0, &p0) in mu_of(0).iter().enumerate() {
                    let o0 = base + k0 as u32 * stride[0];
                    for (k1, &p1) in mu_of(1).iter().enumerate() {
                        run(p0 * p1, o0 + k1 as u32 * stride[1]);
                    }
                }
            }
            _ => {
                for (k0, &p0) in mu_of(0).iter().enumerate() {
                    let o0 = base + k0 as u32 * stride[0];
                    for (k1, &p1) in mu_of(1).iter().enumerate() {
                        let (p01, o01) = (p0 * p1, o0 + k1 as u32 * stride[1]);
                        for (k2, &p2) in mu_of(2).iter().enumerate() {
                            run(p01 * p2, o01 + k2 as u32 * stride[2]);
                        }
                    }
                }
            }
        }
    }
}

dispatch! {
    /// [`Fuzzy::activate_with`] for windows of up to [`SMALL_WINDOW`] sets, at `simd`'s width.
    fn activate_small => activate_with_small(f: &Fuzzy, state: &[f64], out: &mut Activations)
}

dispatch! {
    /// [`Fuzzy::activate_with`] for any window, at `simd`'s width.
    fn activate_large => activate_with_large(f: &Fuzzy, state: &[f64], out: &mut Activations)
}

#[inline(always)]
fn activate_with_small(f: &Fuzzy, state: &[f64], out: &mut Activations) {
    f.activate_with::<SMALL_WINDOW>(state, out);
}

#[inline(always)]
fn activate_with_large(f: &Fuzzy, state: &[f64], out: &mut Activations) {
    f.activate_with::<MAX_SETS>(state, out);
}

/// `y.ceil().max(0.0) as usize` without the `ceil` library call: 0 for y ≤ 0 and NaN, else the
/// smallest integer ≥ y (exact for the small y of a window edge, which is below `MAX_SETS`).
#[inline]
fn ceil_to_index(y: f64) -> usize {
    // Truncation is the ceiling for y ≤ 0, raised to 0 below; NaN and −∞ truncate to i64::MIN or
    // saturate (`math::trunc_i64`), and either is raised to 0.
    let t = math::trunc_i64(y);
    (t + i64::from((t as f64) < y)).max(0) as usize
}

#[cfg(test)]
mod tests {
    use super::*;

    fn eq_9_to_11(f: &Fuzzy, sets: &[u32], state: &[f64], width: f64, ranges: &[[f64; 2]]) -> Vec<f64> {
        // Literal eqs. (9)–(11): every rule's product of Gaussians, divided by the sum over rules.
        let n: usize = sets.iter().map(|&s| s as usize).product();
        let mut raw = vec![0.0; n];
        for (rule, w) in raw.iter_mut().enumerate() {
            let mut rem = rule;
            let mut prod = 1.0;
            for j in (0..sets.len()).rev() {
                let k = rem % sets[j] as usize;
                rem /= sets[j] as usize;
                let spacing = (ranges[j][1] - ranges[j][0]) / (sets[j] - 1) as f64;
                let sigma = width * spacing;
                let x = state[j].clamp(ranges[j][0], ranges[j][1]);
                let c = f.centre(j, k);
                prod *= libm::exp(-((x - c) * (x - c)) / (2.0 * sigma * sigma));
            }
            *w = prod;
        }
        let total: f64 = raw.iter().sum();
        raw.iter().map(|w| w / total).collect()
    }

    #[test]
    fn exact_rule_base_matches_equations_9_to_11() {
        let sets = [3, 2, 4, 5];
        let ranges = [[-2.4, 2.4], [-2.0, 2.0], [-0.2, 0.2], [-3.0, 3.0]];
        let f = Fuzzy::new(&sets, &ranges, HALF_CROSSING_WIDTH, 0.0);
        let mut a = Activations::default();
        for state in [[0.1, -0.3, 0.05, 1.0], [2.0, 5.0, -0.19, -2.9], [-9.0, 0.0, 0.0, 0.0]] {
            f.activate(&state, &mut a);
            assert_eq!(a.len(), 3 * 2 * 4 * 5);
            let reference = eq_9_to_11(&f, &sets, &state, HALF_CROSSING_WIDTH, &ranges);
            let mut dense = vec![0.0; f.n_features()];
            for (i, w) in a.index.iter().zip(&a.weight) {
                dense[*i as usize] += w;
            }
            for (ours, theirs) in dense.iter().zip(&reference) {
                assert!((ours - theirs).abs() < 1e-14, "{ours} vs {theirs}");
            }
        }
    }

    #[test]
    fn memberships_sum_to_one_and_pruning_keeps_the_big_ones() {
        let ranges = [[-1.0, 1.0], [-1.0, 1.0]];
        for n in 1..=10u32 {
            for prune in [0.0, 1e-6] {
                let f = Fuzzy::new(&[n, 10], &ranges, HALF_CROSSING_WIDTH, prune);
                let mut a = Activations::default();
                for i in 0..50 {
                    let x = -1.3 + 0.053 * f64::from(i);
                    f.activate(&[x, -x * 0.7], &mut a);
                    let s: f64 = a.weight.iter().sum();
                    assert!((s - 1.0).abs() < 1e-12, "sum {s}");
                    assert!(a.weight.iter().all(|w| *w > 0.0));
                    let mut idx = a.index.clone();
                    idx.sort_unstable();
                    idx.dedup();
                    assert_eq!(idx.len(), a.len(), "rules are distinct");
                }
            }
        }
    }

    #[test]
    fn neighbours_cross_at_one_half_with_the_default_width() {
        let f = Fuzzy::new(&[2], &[[0.0, 1.0]], HALF_CROSSING_WIDTH, 0.0);
        let mut a = Activations::default();
        f.activate(&[0.5], &mut a);
        assert!((a.weight[0] - 0.5).abs() < 1e-15 && (a.weight[1] - 0.5).abs() < 1e-15);
        let v = &f.vars[0];
        let raw = math::exp(-(0.5f64 * 0.5) * v.inv_two_sigma_sq);
        assert!((raw - 0.5).abs() < 1e-12);
    }

    #[test]
    fn window_edges_match_ceil_and_floor() {
        for y in [-3.0, -0.5, -0.0, 0.0, 1e-300, 0.3, 1.0, 1.0 + f64::EPSILON, 2.5, 62.999, 63.0, f64::NAN] {
            assert_eq!(ceil_to_index(y), y.ceil().max(0.0) as usize, "{y}");
            assert_eq!((y as i64).max(0) as usize, y.floor().max(0.0) as usize, "{y}");
        }
        assert_eq!(f64::INFINITY as i64 as usize, f64::INFINITY.floor() as usize >> 1);
        assert_eq!(ceil_to_index(f64::NEG_INFINITY), 0);
    }

    #[test]
    fn max_active_bounds_every_activation() {
        let ranges = [[-1.0, 1.0], [-2.0, 2.0]];
        for (sets, prune) in [([10, 4], 1e-6), ([7, 64], 1e-3), ([5, 3], 0.0)] {
            let f = Fuzzy::new(&sets, &ranges, HALF_CROSSING_WIDTH, prune);
            let mut a = Activations::default();
            let mut most = 0;
            for i in 0..400 {
                let x = -1.2 + 0.006 * f64::from(i);
                f.activate(&[x, 1.7 * x], &mut a);
                most = most.max(a.len());
            }
            assert!(most <= f.max_active(), "{sets:?}: {most} > {}", f.max_active());
        }
    }

    /// The factorised overlap (a product of per-variable dots) is the rule-by-rule sum
    /// Σᵢ wᵢ(s)·wᵢ(s′), for neighbouring, distant and clamped states, pruned or not.
    #[test]
    fn overlap_factorises_over_variables() {
        let ranges = [[-2.4, 2.4], [-2.0, 2.0], [-0.2, 0.2], [-3.0, 3.0]];
        for (sets, prune) in [([4, 4, 4, 4], 1e-3), ([7, 3, 9, 2], 0.0), ([10, 10, 10, 10], 1e-3)] {
            let f = Fuzzy::new(&sets, &ranges, HALF_CROSSING_WIDTH, prune);
            let (mut a, mut b) = (Activations::default(), Activations::default());
            for i in 0..60 {
                let t = f64::from(i) * 0.37;
                let s =
                    [math::sin(t) * 2.0, math::cos(t), 0.15 * math::sin(3.0 * t), 2.5 * math::cos(0.7 * t)];
                let s2 = [
                    s[0] + 0.01 * f64::from(i % 7),
                    s[1] - 0.3,
                    s[2] * 0.9,
                    if i % 5 == 0 { 9.0 } else { s[3] },
                ];
                f.activate(&s, &mut a);
                f.activate(&s2, &mut b);
                let mut by_rule = 0.0;
                for (k, w) in a.index.iter().zip(&a.weight) {
                    if let Some(p) = b.index.iter().position(|j| j == k) {
                        by_rule += w * b.weight[p];
                    }
                }
                let factored = a.overlap(&b);
                assert!((factored - by_rule).abs() <= 1e-15, "{sets:?} {i}: {factored} vs {by_rule}");
                assert!((a.overlap(&a) - a.weight.iter().map(|w| w * w).sum::<f64>()).abs() <= 1e-15);
            }
        }
    }

    /// The activation is the same bits at every vector level, and does not depend on what the
    /// reused buffers held before (the memberships' scratch persists between steps): a state
    /// activated after a run of others gives what it gives into fresh buffers.
    #[test]
    fn activation_is_the_same_at_every_level_and_after_any_history() {
        let ranges = [[-2.4, 2.4], [-2.0, 2.0], [-0.2, 0.2], [-3.0, 3.0]];
        let bases: [(&[u32], f64); 7] = [
            (&[4, 4], 1e-3),
            (&[10, 10], 1e-3),
            (&[3], 0.0),
            (&[5, 2, 7], 1e-6),
            (&[4, 4, 4, 4], 1e-3),
            (&[10, 4, 10, 4], 0.0),
            (&[64, 3], 1e-12),
        ];
        for (sets, prune) in bases {
            let r = &ranges[..sets.len()];
            let states: Vec<[f64; 4]> = (0..300)
                .map(|i| {
                    let t = f64::from(i) * 0.731;
                    let far = if i % 17 == 0 { 40.0 } else { 1.0 };
                    [
                        far * 2.6 * math::sin(t),
                        2.2 * math::cos(1.3 * t),
                        0.25 * math::sin(2.1 * t),
                        3.3 * math::cos(t),
                    ]
                })
                .collect();
            let levels: Vec<Fuzzy> = Simd::available()
                .into_iter()
                .map(|simd| Fuzzy::new(sets, r, HALF_CROSSING_WIDTH, prune).with_simd(simd))
                .collect();
            let mut reused: Vec<Activations> = levels.iter().map(|_| Activations::default()).collect();
            let mut prev = Activations::default();
            for state in &states {
                let mut fresh = Activations::default();
                levels[0].activate(state, &mut fresh);
                let bits = |a: &Activations| {
                    (a.index.clone(), a.weight.iter().map(|w| w.to_bits()).collect::<Vec<_>>())
                };
                for (f, a) in levels.iter().zip(&mut reused) {
                    f.activate(state, a);
                    assert_eq!(bits(a), bits(&fresh), "{sets:?} at {:?}, state {state:?}", f.simd);
                    assert_eq!(a.overlap(&prev).to_bits(), fresh.overlap(&prev).to_bits());
                }
                prev = fresh;
            }
        }
    }

    /// Regression: a huge width made the window bound `(2·reach) as usize + 2` overflow (a panic
    /// in debug builds, a one-set window and an out-of-bounds write in release).
    #[test]
    fn huge_width_overflows_no_window_bound() {
        let f = Fuzzy::new(&[10, 3], &[[0.0, 1.0], [-1.0, 1.0]], 1e19, 1e-3);
        assert_eq!(f.max_active(), 30);
        let mut a = Activations::default();
        f.activate(&[0.3, 0.2], &mut a);
        assert_eq!(a.len(), 30);
        assert!((a.weight.iter().sum::<f64>() - 1.0).abs() < 1e-12);
    }

    #[test]
    fn tiny_width_never_divides_by_zero() {
        let f = Fuzzy::new(&[5], &[[0.0, 1.0]], 1e-6, 0.0);
        let mut a = Activations::default();
        f.activate(&[0.37], &mut a);
        assert_eq!(a.index, vec![1]);
        assert_eq!(a.weight, vec![1.0]);
    }
}
