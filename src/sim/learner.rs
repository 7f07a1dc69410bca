//! One learner for both representations: Q(s, a) = Σᵢ wᵢ qᵢᵃ over sparse activations (eq. 18), the
//! TD error of eqs. (4)/(14), and the trace update of eqs. (7)/(20) followed by the parameter update
//! of eqs. (6)/(21). A crisp table is the special case of one active feature of weight 1, and Q(0)
//! is exactly λ = 0: the traces then hold only the current activation, so the update is eq. (5)/(19).
//!
//! Parameters are laid out rule-major (`q[feature · n_actions + action]`) so all actions of a rule
//! are contiguous. Traces that decay below `trace_cutoff` are dropped (set to exactly 0).
//!
//! # Exactness
//! Every result is bit-for-bit that of the literal algorithm (the tests in `reference_tests.rs` and
//! `pinned_tests.rs` hold it to that), so the fast paths below only ever reorder work that is
//! independent per parameter: each trace and each q is updated by the same floating-point operations
//! as before, and Q(s, ·) is still summed over the active features in activation order, starting
//! from 0 (a different summation order would change results, so the sums are never split or
//! reassociated). What changes is bookkeeping:
//! - Q(s, ·) keeps all actions' running sums in registers ([`q_values`](Learner::q_values));
//! - Q(0) touches only the current activation's parameters, with no trace bookkeeping;
//! - a single active feature (every crisp step) decays, extends and applies the traces in one pass;
//! - small tables where most traces are live anyway sweep the dense trace array (vectorisable)
//!   instead of an active list; large ones keep the active list, so a step costs O(active traces).

use super::config::{LearnerConfig, TraceKind};
use super::repr::Activations;

/// Dense traces when the table has at most this many features per feature a single state can
/// activate: then most traces are live in practice and a linear sweep beats list bookkeeping.
pub const DENSE_TRACE_RATIO: usize = 4;

/// Action counts up to this get a Q(s, ·) kernel with every action's sum in registers.
const MAX_UNROLLED_ACTIONS: usize = 16;

/// Q parameters and eligibility traces of one trial.
#[derive(Debug, Clone)]
pub struct Learner {
    n_actions: usize,
    q: Vec<f64>,
    trace: Vec<f64>,
    /// Sparse mode: every index with a non-zero trace (plus any entry added this step with weight 0).
    active: Vec<u32>,
    /// Dense mode: traces are swept in full and `active` is unused.
    dense: bool,
    alpha: f64,
    decay: f64,
    cutoff: f64,
    replacing: bool,
}

impl Learner {
    /// A learner over `n_features × n_actions` parameters, all set to `cfg.q_init`, for a
    /// representation that activates at most `max_active` features per state (chooses the trace
    /// layout; results do not depend on it).
    pub fn new(n_features: usize, n_actions: usize, max_active: usize, cfg: &LearnerConfig) -> Self {
        let n = n_features * n_actions;
        Self {
            n_actions,
            q: vec![cfg.q_init; n],
            trace: vec![0.0; n],
            active: Vec::new(),
            dense: max_active > 1 && n_features <= DENSE_TRACE_RATIO * max_active,
            alpha: cfg.alpha,
            decay: cfg.gamma * cfg.lambda,
            cutoff: cfg.trace_cutoff,
            replacing: cfg.traces == TraceKind::Replacing,
        }
    }

    /// Q(s, ·) for the activations of s, eq. (18), written into `out` (one value per action): for
    /// each action, `0 + w₀q₀ + w₁q₁ + …` in activation order.
    #[inline(always)]
    pub fn q_values(&self, phi: &Activations, out: &mut [f64]) {
        if let ([i], [w]) = (&phi.index[..], &phi.weight[..]) {
            // One feature (every crisp state): small enough to inline into the trial loop.
            let na = self.n_actions;
            for (o, &v) in out.iter_mut().zip(&self.q[*i as usize * na..][..na]) {
                *o = 0.0 + w * v;
            }
        } else {
            self.q_values_many(phi, out);
        }
    }

    /// [`q_values`](Self::q_values) for several active features.
    #[inline(never)]
    fn q_values_many(&self, phi: &Activations, out: &mut [f64]) {
        macro_rules! unrolled {
            ($($n:literal)*) => {
                match self.n_actions {
                    $($n => q_values_fixed::<$n>(&self.q, phi, out),)*
                    _ => q_values_any(&self.q, self.n_actions, phi, out),
                }
            };
        }
        const _: () = assert!(MAX_UNROLLED_ACTIONS == 16);
        unrolled!(1 2 3 4 5 6 7 8 9 10 11 12 13 14 15 16);
    }

    /// Clear every trace (episode start; Watkins's cut).
    #[inline]
    pub fn clear_traces(&mut self) {
        if self.dense {
            self.trace.fill(0.0);
        } else {
            for &k in &self.active {
                self.trace[k as usize] = 0.0;
            }
            self.active.clear();
        }
    }

    /// One learning step for the pair (s_t, a_t) with TD error δ_t: decay every trace by γλ, add the
    /// activation of (s_t, a_t) to its traces (eq. 20), then q ← q + α·δ·e (eq. 21).
    #[inline(always)]
    pub fn update(&mut self, phi: &Activations, action: usize, delta: f64) {
        let step = self.alpha * delta;
        if self.decay == 0.0 {
            self.update_q0(phi, action, step);
        } else if self.dense {
            self.update_dense(phi, action, step);
        } else if phi.len() == 1 {
            self.update_single(phi.index[0], phi.weight[0], action, step);
        } else {
            self.update_sparse(phi, action, step);
        }
    }

    /// The trace after adding activation `w` to a trace `e` (after its decay): eq. (20), or the
    /// replacing variant.
    #[inline(always)]
    fn extend(&self, e: f64, w: f64) -> f64 {
        if self.replacing {
            e.max(w)
        } else {
            e + w
        }
    }

    /// `e · γλ`, dropped to exactly 0 below the cutoff. Returns the new trace.
    #[inline(always)]
    fn decayed(&self, e: f64) -> f64 {
        let e = e * self.decay;
        if e < self.cutoff || e == 0.0 {
            0.0
        } else {
            e
        }
    }

    /// γλ = 0: every trace from the previous step is gone, so the traces are exactly the current
    /// activation (0 extended by w) and only those parameters move. No trace is stored: the trace
    /// array stays all zero and the active list empty, which is what clearing them would leave.
    #[inline(always)]
    fn update_q0(&mut self, phi: &Activations, action: usize, step: f64) {
        let na = self.n_actions;
        for (&i, &w) in phi.index.iter().zip(&phi.weight) {
            let e = self.extend(0.0, w);
            self.q[i as usize * na + action] += step * e;
        }
    }

    /// One active feature (crisp tables), sparse traces: decay, extend and apply in a single pass
    /// over the active list; the extended entry stays where it is in the list (list order never
    /// affects a value).
    #[inline(always)]
    fn update_single(&mut self, feature: u32, w: f64, action: usize, step: f64) {
        let target = feature as usize * self.n_actions + action;
        let mut kept = 0;
        let mut found = false;
        for r in 0..self.active.len() {
            let k = self.active[r] as usize;
            let mut e = self.decayed(self.trace[k]);
            let is_target = k == target;
            if is_target {
                // Dropped or not, the target is extended and stays active (as a re-push would).
                e = self.extend(e, w);
                found = true;
            } else if e == 0.0 {
                self.trace[k] = 0.0;
                continue;
            }
            self.trace[k] = e;
            self.q[k] += step * e;
            self.active[kept] = k as u32;
            kept += 1;
        }
        self.active.truncate(kept);
        if !found {
            let e = self.extend(0.0, w);
            self.trace[target] = e;
            self.q[target] += step * e;
            self.active.push(target as u32);
        }
    }

    /// Several active features, small table: sweep every trace. Entries outside the active list
    /// have trace exactly 0, so decaying them is a no-op, and q moves exactly where the list-based
    /// update moves it (see the comment on the parameter pass).
    #[inline(never)]
    fn update_dense(&mut self, phi: &Activations, action: usize, step: f64) {
        let (decay, cutoff) = (self.decay, self.cutoff);
        for e in &mut self.trace {
            let d = *e * decay;
            *e = if d < cutoff || d == 0.0 { 0.0 } else { d };
        }
        let na = self.n_actions;
        for (&i, &w) in phi.index.iter().zip(&phi.weight) {
            let k = i as usize * na + action;
            self.trace[k] = self.extend(self.trace[k], w);
        }
        // The list-based update adds step·e to every non-zero trace and to the current activation's
        // entries; skipping zero traces elsewhere is exact (q + step·0 = q, up to the sign of a zero
        // q, which no sum can see: sums start from +0). Only a non-finite step (an overflowing α·δ)
        // makes step·0 a NaN that the list-based update writes into the activation's zero entries.
        for (q, &e) in self.q.iter_mut().zip(&self.trace) {
            *q = if e != 0.0 { *q + step * e } else { *q };
        }
        if !step.is_finite() {
            for &i in &phi.index {
                let k = i as usize * na + action;
                if self.trace[k] == 0.0 {
                    self.q[k] += step * self.trace[k];
                }
            }
        }
    }

    /// Several active features, large table: decay the active list (compacting out dropped
    /// traces), extend the current activation's traces, then apply.
    #[inline(never)]
    fn update_sparse(&mut self, phi: &Activations, action: usize, step: f64) {
        let mut kept = 0;
        for r in 0..self.active.len() {
            let k = self.active[r];
            let e = self.decayed(self.trace[k as usize]);
            self.trace[k as usize] = e;
            self.active[kept] = k;
            kept += usize::from(e != 0.0);
        }
        self.active.truncate(kept);
        let na = self.n_actions;
        for (&i, &w) in phi.index.iter().zip(&phi.weight) {
            let k = i as usize * na + action;
            let e = self.trace[k];
            if e == 0.0 {
                self.active.push(k as u32);
            }
            self.trace[k] = self.extend(e, w);
        }
        for &k in &self.active {
            self.q[k as usize] += step * self.trace[k as usize];
        }
    }

    /// The parameter vector q (rule-major).
    pub fn params(&self) -> &[f64] {
        &self.q
    }

    /// Number of traces currently non-zero.
    pub fn active_traces(&self) -> usize {
        self.trace.iter().filter(|&&e| e != 0.0).count()
    }
}

/// Q(s, ·) with `N` actions: all `N` running sums stay in registers across the activation.
#[inline(always)]
fn q_values_fixed<const N: usize>(q: &[f64], phi: &Activations, out: &mut [f64]) {
    let mut acc = [0.0f64; N];
    for (&i, &w) in phi.index.iter().zip(&phi.weight) {
        let row: &[f64; N] = q[i as usize * N..][..N].try_into().expect("row of N actions");
        for (s, &v) in acc.iter_mut().zip(row) {
            *s += w * v;
        }
    }
    out[..N].copy_from_slice(&acc);
}

/// Q(s, ·) for any action count, summing in `out` directly.
fn q_values_any(q: &[f64], na: usize, phi: &Activations, out: &mut [f64]) {
    out.fill(0.0);
    for (&i, &w) in phi.index.iter().zip(&phi.weight) {
        let row = &q[i as usize * na..(i as usize + 1) * na];
        for (o, v) in out.iter_mut().zip(row) {
            *o += w * v;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sim::config::{Algorithm, TrialConfig};
    use crate::sim::env::SystemKind;
    use crate::sim::repr::ReprKind;

    fn config(lambda: f64, replacing: bool, cutoff: f64) -> LearnerConfig {
        let mut c =
            TrialConfig::paper(SystemKind::CartPole, ReprKind::Fuzzy, Algorithm::QLambda, vec![2; 4], 3)
                .learner;
        c.lambda = lambda;
        c.trace_cutoff = cutoff;
        if replacing {
            c.traces = TraceKind::Replacing;
        }
        c
    }

    /// Deterministic pseudo-random activations over `nf` features (distinct indices).
    fn activations(step: usize, nf: usize, len: usize) -> Activations {
        let mut a = Activations::default();
        let start = (step * 7919) % nf;
        for j in 0..len {
            a.index.push(((start + j * 3) % nf) as u32);
            a.weight.push(if j % 5 == 4 { 0.0 } else { 1.0 / (1.0 + (step + j) as f64 % 7.0) });
        }
        a
    }

    #[test]
    fn dense_and_sparse_traces_give_identical_parameters() {
        for (lambda, replacing, cutoff) in [(0.9, false, 1e-10), (0.5, true, 1e-3), (0.7, false, 0.0)] {
            let cfg = config(lambda, replacing, cutoff);
            let (nf, na) = (24, 3);
            let mut dense = Learner::new(nf, na, nf, &cfg);
            let mut sparse = Learner::new(nf, na, 1, &cfg);
            assert!(dense.dense && !sparse.dense);
            let (mut qd, mut qs) = (vec![0.0; na], vec![0.0; na]);
            for step in 0..400 {
                let phi = activations(step, nf, 1 + step % 6);
                let delta = ((step as f64) * 0.37).sin();
                dense.update(&phi, step % na, delta);
                sparse.update(&phi, step % na, delta);
                assert_eq!(dense.trace, sparse.trace, "step {step}");
                assert_eq!(dense.q, sparse.q, "step {step}");
                assert_eq!(
                    dense.active_traces(),
                    sparse.active.iter().filter(|&&k| sparse.trace[k as usize] != 0.0).count()
                );
                dense.q_values(&phi, &mut qd);
                sparse.q_values(&phi, &mut qs);
                assert_eq!(qd, qs);
                if step % 97 == 0 {
                    dense.clear_traces();
                    sparse.clear_traces();
                }
            }
        }
    }

    #[test]
    fn unrolled_q_values_match_the_generic_sum() {
        for na in 1..=20 {
            let cfg = config(0.0, false, 0.0);
            let mut l = Learner::new(10, na, 4, &cfg);
            for (k, q) in l.q.iter_mut().enumerate() {
                *q = (k as f64 * 0.731).sin() * 1e3;
            }
            let phi = activations(3, 10, 7);
            let (mut fast, mut slow) = (vec![0.0; na], vec![0.0; na]);
            l.q_values(&phi, &mut fast);
            q_values_any(&l.q, na, &phi, &mut slow);
            assert_eq!(fast, slow, "{na} actions");
        }
    }
}
