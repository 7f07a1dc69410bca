//! Fuzzy representation: Gaussian membership functions (eq. 9) per variable with centres evenly
//! spaced over `[lo, hi]` (endpoints included) and spread `σ = width · spacing`; the rule base is the
//! Cartesian product of the per-variable sets (eq. 8), firing strength the product (eq. 10),
//! normalised to sum 1 (eq. 11).
//!
//! For a grid rule base the normaliser of eq. (11) factorises, `Σ_m Π_j μ_j = Π_j Σ_k μ_jk`, so the
//! normalised strengths are the outer product of per-variable normalised memberships; that is how
//! they are computed. Values outside `[lo, hi]` are clamped to the range first (the fuzzy analogue of
//! the crisp edge bin), and sets whose membership is below `prune` are skipped (`prune = 0` is exact).

use super::{strides, Activations, Encode, Representation};

/// Most fuzzy sets a single variable may have.
pub const MAX_SETS: usize = 64;

/// Most state variables a rule base may have (Cart-Pole's four).
const MAX_VARS: usize = 4;

/// Windows up to this many sets (every variable, as with the default prune) take the activation
/// path with small scratch arrays.
const SMALL_WINDOW: usize = 8;

/// `width` that makes neighbouring memberships cross at 0.5: `1 / (2·sqrt(2·ln 2))`.
pub const HALF_CROSSING_WIDTH: f64 = 0.424_660_900_144_009_5;

#[derive(Debug, Clone)]
struct Variable {
    lo: f64,
    hi: f64,
    n: usize,
    spacing: f64,
    inv_two_sigma_sq: f64,
    /// Half-width of the window of sets that can exceed `prune`, in units of `spacing`.
    reach: f64,
}

impl Variable {
    /// Most sets a window can hold: ⌊2·reach⌋ + 1 centres lie within ±reach spacings of a point,
    /// plus one for rounding in the window edges.
    fn max_window(&self) -> usize {
        if self.reach.is_finite() {
            ((2.0 * self.reach) as usize + 2).min(self.n)
        } else {
            self.n
        }
    }
}

/// A grid of Gaussian fuzzy sets with normalised product firing strengths.
#[derive(Debug, Clone)]
pub struct Fuzzy {
    vars: Vec<Variable>,
    strides: Vec<u32>,
    n_features: usize,
    /// Largest window of any variable.
    max_window: usize,
}

impl Fuzzy {
    /// `sets[j]` Gaussians over `ranges[j]` with σ = `width` × centre spacing; memberships below
    /// `prune` are skipped (0 keeps every rule).
    pub fn new(sets: &[u32], ranges: &[[f64; 2]], width: f64, prune: f64) -> Self {
        assert_eq!(sets.len(), ranges.len());
        assert!(sets.len() <= MAX_VARS, "at most {MAX_VARS} state variables");
        let vars: Vec<Variable> = sets
            .iter()
            .zip(ranges)
            .map(|(&n, r)| {
                let n = n as usize;
                assert!((1..=MAX_SETS).contains(&n));
                let spacing = if n > 1 { (r[1] - r[0]) / (n - 1) as f64 } else { r[1] - r[0] };
                let sigma = width * spacing;
                let reach = if prune > 0.0 {
                    // exp(−d²/2σ²) ≥ prune  ⇔  d ≤ σ·sqrt(2 ln(1/prune)).
                    width * (2.0 * (1.0 / prune).ln()).sqrt()
                } else {
                    f64::INFINITY
                };
                Variable {
                    lo: r[0],
                    hi: r[1],
                    n,
                    spacing,
                    inv_two_sigma_sq: 1.0 / (2.0 * sigma * sigma),
                    reach,
                }
            })
            .collect();
        let n_features = sets.iter().map(|&s| s as usize).product();
        let max_window = vars.iter().map(Variable::max_window).max().unwrap_or(1);
        Self { vars, strides: strides(sets), n_features, max_window }
    }

    /// Centre of set `k` of variable `j`.
    pub fn centre(&self, j: usize, k: usize) -> f64 {
        let v = &self.vars[j];
        if v.n == 1 {
            (v.lo + v.hi) / 2.0
        } else {
            v.lo + k as f64 * v.spacing
        }
    }

    /// Normalised memberships of variable `j` at `value`: writes `(set, μ)` pairs, returns their
    /// count (at most the variable's `max_window`, which `sets` and `mu` must hold).
    #[inline(always)]
    fn memberships(&self, j: usize, value: f64, sets: &mut [u32], mu: &mut [f64]) -> usize {
        let v = &self.vars[j];
        if v.n == 1 {
            sets[0] = 0;
            mu[0] = 1.0;
            return 1;
        }
        let x = value.clamp(v.lo, v.hi);
        let pos = (x - v.lo) / v.spacing;
        let first = ceil_to_index(pos - v.reach);
        // A saturating cast is floor for every input here (negatives and NaN give 0 either way).
        let last = ((pos + v.reach) as usize).min(v.n - 1);
        let (first, last) = if first > last {
            let nearest = (pos.round() as usize).min(v.n - 1);
            (nearest, nearest)
        } else {
            (first, last)
        };
        let mut sum = 0.0;
        let mut m = 0;
        for k in first..=last {
            let d = x - (v.lo + k as f64 * v.spacing); // `centre(j, k)`, inlined
            let w = (-(d * d) * v.inv_two_sigma_sq).exp();
            sets[m] = k as u32;
            mu[m] = w;
            sum += w;
            m += 1;
        }
        if sum <= 0.0 || sum.is_nan() {
            // Every membership underflowed (a very narrow width): the nearest set takes it all.
            let nearest = (pos.round() as usize).min(v.n - 1);
            sets[0] = nearest as u32;
            mu[0] = 1.0;
            return 1;
        }
        let inv = 1.0 / sum;
        for w in &mut mu[..m] {
            *w *= inv;
        }
        m
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
            self.activate_with::<SMALL_WINDOW>(state, out);
        } else {
            self.activate_with::<MAX_SETS>(state, out);
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
    /// [`activate`](Representation::activate) with scratch room for `W` sets per variable. Every
    /// variable's memberships are computed first: they are independent, so their latency chains
    /// (a division, the exponentials, the normalising division) overlap.
    #[inline(always)]
    fn activate_with<const W: usize>(&self, state: &[f64], out: &mut Activations) {
        // Missing variables (two-variable systems) are padded with one set of membership 1 at
        // offset 0, which leaves every index and product unchanged (x · 1 = x exactly).
        let mut offset = [[0u32; W]; MAX_VARS];
        let mut mu = [[1.0f64; W]; MAX_VARS];
        let mut count = [1usize; MAX_VARS];
        for (j, &value) in state[..self.vars.len()].iter().enumerate() {
            count[j] = self.memberships(j, value, &mut offset[j], &mut mu[j]);
            for o in &mut offset[j][..count[j]] {
                *o *= self.strides[j];
            }
        }
        let total = count.iter().product();
        out.index.resize(total, 0);
        out.weight.resize(total, 0.0);
        // Rule order and every product exactly as eq. (10) evaluated variable by variable (what an
        // outer product built one variable at a time gives): variable 0 varies fastest, and a
        // weight is ((1·μ₀)·μ₁)·μ₂)·μ₃, where 1·μ₀ = μ₀.
        let [m0, m1, m2, m3] = count;
        let (mu0, o0) = (&mu[0][..m0], &offset[0][..m0]);
        let mut p = 0;
        for (&mu3, &o3) in mu[3][..m3].iter().zip(&offset[3][..m3]) {
            for (&mu2, &o2) in mu[2][..m2].iter().zip(&offset[2][..m2]) {
                for (&mu1, &o1) in mu[1][..m1].iter().zip(&offset[1][..m1]) {
                    let o123 = o1 + o2 + o3;
                    let row = out.index[p..p + m0].iter_mut().zip(&mut out.weight[p..p + m0]);
                    for ((i, w), (&m, &o)) in row.zip(mu0.iter().zip(o0)) {
                        *i = o + o123;
                        *w = ((m * mu1) * mu2) * mu3;
                    }
                    p += m0;
                }
            }
        }
    }
}

/// `y.ceil().max(0.0) as usize` without the `ceil` library call: 0 for y ≤ 0 and NaN, else the
/// smallest integer ≥ y (exact for the small y of a window edge, which is below `MAX_SETS`).
#[inline]
fn ceil_to_index(y: f64) -> usize {
    if y > 0.0 {
        let t = y as usize;
        if (t as f64) < y {
            t + 1
        } else {
            t
        }
    } else {
        0
    }
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
                prod *= (-(x - c).powi(2) / (2.0 * sigma * sigma)).exp();
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
        let raw = (-(0.5f64 * 0.5) * v.inv_two_sigma_sq).exp();
        assert!((raw - 0.5).abs() < 1e-12);
    }

    #[test]
    fn window_edges_match_ceil_and_floor() {
        for y in [-3.0, -0.5, -0.0, 0.0, 1e-300, 0.3, 1.0, 1.0 + f64::EPSILON, 2.5, 62.999, 63.0, f64::NAN] {
            assert_eq!(ceil_to_index(y), y.ceil().max(0.0) as usize, "{y}");
            assert_eq!(y as usize, y.floor() as usize, "{y}");
        }
        assert_eq!(f64::INFINITY as usize, f64::INFINITY.floor() as usize);
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

    #[test]
    fn tiny_width_never_divides_by_zero() {
        let f = Fuzzy::new(&[5], &[[0.0, 1.0]], 1e-6, 0.0);
        let mut a = Activations::default();
        f.activate(&[0.37], &mut a);
        assert_eq!(a.index, vec![1]);
        assert_eq!(a.weight, vec![1.0]);
    }
}
