//! One learner for both representations: Q(s, a) = Σᵢ wᵢ qᵢᵃ over sparse activations (eq. 18), the
//! TD error of eqs. (4)/(14), and the trace update of eqs. (7)/(20) followed by the parameter update
//! of eqs. (6)/(21). A crisp table is the special case of one active feature of weight 1, and Q(0)
//! is exactly λ = 0: the traces then hold only the current activation, so the update is eq. (5)/(19).
//!
//! Parameters are laid out rule-major (`q[feature · n_actions + action]`) so all actions of a rule
//! are contiguous. Traces that decay below `trace_cutoff` are dropped (set to exactly 0). The
//! traces are stored already decayed for the next step: the decay e ← γλe of step t+1 depends on
//! nothing learned at step t+1, so it is done in the same pass that applies step t's update.
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
//! - applying the update and decaying the traces for the next step is one pass, not two;
//! - a single active feature (every crisp step) extends, applies and decays in that same pass, and
//!   crisp steps hand the learner a [`OneHot`] row instead of a one-entry list ([`Features`]);
//! - small tables where most traces are live anyway sweep the dense trace array (vectorisable)
//!   instead of an active list; large ones keep the active list, so a step costs O(active traces).

use super::config::{LearnerConfig, TraceKind};
use super::repr::{Activations, OneHot};

/// Dense traces when the table has at most this many parameters (features × actions) per feature a
/// single state can activate, and at most [`DENSE_MAX_PARAMS`] in all: then most traces are live in
/// practice and a linear sweep beats list bookkeeping. A step extends the traces of one action
/// only, so the rule counts parameters, not features: by features alone a 10-action table swept
/// ten times the parameters its traces use, which made Cart-Pole fuzzy Q(λ) 6⁴ × 10 actions (the
/// costliest cell of `paper.yaml`) 3.6× slower than the sparse list. Measured on real trials
/// (docs/speed.md): 3⁴ × 10, 4⁴ × 8 and 5⁴ × 4 actions faster dense; 6⁴ × 4, 7⁴ × 2, 5⁴ × 10 sparse.
/// Either layout gives bit-identical results.
pub const DENSE_TRACE_RATIO: usize = 10;

/// The most parameters a dense trace sweep covers (see [`DENSE_TRACE_RATIO`]).
pub const DENSE_MAX_PARAMS: usize = 4096;

/// Action counts up to this get a Q(s, ·) kernel with every action's sum in registers.
const MAX_UNROLLED_ACTIONS: usize = 16;

/// Q parameters and eligibility traces of one trial.
#[derive(Debug, Clone)]
pub struct Learner {
    n_actions: usize,
    q: Vec<f64>,
    traces: Traces,
    rule: TraceRule,
    alpha: f64,
}

/// How traces decay and grow (eqs. 7 and 20 with the cutoff), shared by every layout.
#[derive(Debug, Clone, Copy)]
struct TraceRule {
    decay: f64,
    cutoff: f64,
    /// The least trace that stays live, for [`keeps`](Self::keeps): the cutoff, or the least
    /// positive f64 when the cutoff is 0 (a trace is dropped below the cutoff and at exactly 0).
    floor: f64,
    replacing: bool,
}

impl TraceRule {
    /// The rule of a learner configuration (γλ, the cutoff, the trace kind).
    fn of(cfg: &LearnerConfig) -> Self {
        let cutoff = cfg.trace_cutoff;
        Self {
            decay: cfg.gamma * cfg.lambda,
            cutoff,
            floor: if cutoff > 0.0 { cutoff } else { f64::from_bits(1) },
            replacing: cfg.traces == TraceKind::Replacing,
        }
    }

    /// `e · γλ`, dropped to exactly 0 below the cutoff. (The original test `e < cutoff || e == 0`
    /// is the same for traces, which are never negative or NaN: with cutoff 0, a zero stays 0.)
    #[inline(always)]
    fn decayed(self, e: f64) -> f64 {
        let e = e * self.decay;
        if e < self.cutoff {
            0.0
        } else {
            e
        }
    }

    /// Whether a trace decayed to `x = e · γλ` stays live, i.e. `decayed(e) != 0`, in one
    /// comparison: traces are never negative, so `x < cutoff || x == 0` is `x < floor` (and a NaN
    /// stays live in both).
    #[inline(always)]
    #[allow(clippy::neg_cmp_op_on_partial_ord)] // deliberately true for NaN, as the literal rule is
    fn keeps(self, x: f64) -> bool {
        !(x < self.floor)
    }

    /// The trace after adding activation `w` to a (decayed) trace `e`: eq. (20), or replacing.
    #[inline(always)]
    fn extend(self, e: f64, w: f64) -> f64 {
        if self.replacing {
            e.max(w)
        } else {
            e + w
        }
    }
}

/// Where the eligibility traces live.
#[derive(Debug, Clone)]
enum Traces {
    /// γλ = 0 (Q(0)): a trace never outlives its step, so none is stored.
    None,
    /// One trace per parameter, swept in full every step.
    Dense(Vec<f64>),
    /// Only the live traces, packed.
    Sparse(SparseTraces),
}

/// The live traces as a packed list, plus a map from parameter to list position. Traces are summed
/// and decayed in list order, which never matters: every trace and parameter update is per entry.
#[derive(Debug, Clone)]
struct SparseTraces {
    /// (parameter index, trace) of every live trace: every non-zero trace, plus any entry extended
    /// by a zero weight this step, exactly the entries a list-based update touches. One list of
    /// pairs, not two lists, so the pass over it checks one bound.
    live: Vec<(u32, f64)>,
    /// Per parameter: 1 + its position in `live`, or 0 when it has no live trace.
    slot: Vec<u32>,
}

impl SparseTraces {
    fn new(n: usize) -> Self {
        Self { live: Vec::new(), slot: vec![0; n] }
    }

    #[inline]
    fn clear(&mut self) {
        for &(k, _) in &self.live {
            self.slot[k as usize] = 0;
        }
        self.live.clear();
    }

    /// Apply `step · e` to every live trace's parameter and decay the trace for the next step,
    /// dropping those that vanish. A vanishing trace is replaced by the last one (not yet visited),
    /// so only moved traces rewrite their slot: most traces stay where they are, and rewriting
    /// every slot was a random store per live trace per step.
    #[inline(always)]
    fn apply_and_decay(&mut self, q: &mut [f64], rule: TraceRule, step: f64) {
        let Self { live, slot } = self;
        let mut r = 0;
        while let Some(&(k, e)) = live.get(r) {
            q[k as usize] += step * e;
            let next = e * rule.decay;
            if rule.keeps(next) {
                live[r].1 = next;
                r += 1;
            } else {
                slot[k as usize] = 0;
                live.swap_remove(r);
                if let Some(&(moved, _)) = live.get(r) {
                    slot[moved as usize] = r as u32 + 1;
                }
            }
        }
    }
}

impl Learner {
    /// A learner over `n_features × n_actions` parameters, all set to `cfg.q_init`, for a
    /// representation that activates at most `max_active` features per state (chooses the trace
    /// layout; results do not depend on it).
    pub fn new(n_features: usize, n_actions: usize, max_active: usize, cfg: &LearnerConfig) -> Self {
        let n = n_features * n_actions;
        if std::env::var_os("QSWEEP_DEBUG_LAYOUT").is_some() {
            eprintln!("layout nf={n_features} na={n_actions} max_active={max_active} n={n}");
        }
        let rule = TraceRule::of(cfg);
        let traces = if rule.decay == 0.0 {
            Traces::None
        } else if max_active > 1 && n <= DENSE_MAX_PARAMS && n <= DENSE_TRACE_RATIO * max_active {
            Traces::Dense(vec![0.0; n])
        } else {
            Traces::Sparse(SparseTraces::new(n))
        };
        Self { n_actions, q: vec![cfg.q_init; n], traces, rule, alpha: cfg.alpha }
    }

    /// Q(s, ·) for the activations of s, eq. (18), written into `out` (one value per action): for
    /// each action, `0 + w₀q₀ + w₁q₁ + …` in activation order.
    #[inline(always)]
    pub fn q_values<F: Features>(&self, phi: &F, out: &mut [f64]) {
        phi.q_values(self, out);
    }

    /// Bring `qs`, Q(s, ·) computed just before [`update`](Self::update) for `action`, up to date
    /// after it. Under Q(0) (no traces) the update moved only `action`'s parameters, so every other
    /// action's value is already right, the same sum over the same parameters in the same order,
    /// and only `action`'s sum is redone (in activation order from 0, as
    /// [`q_values`](Self::q_values) sums it: bit-identical). With traces, every action may have
    /// moved and all are recomputed.
    #[inline(always)]
    pub fn refresh_after_update<F: Features>(&self, phi: &F, action: usize, qs: &mut [f64]) {
        if matches!(self.traces, Traces::None) {
            qs[action] = phi.q_value(self, action);
        } else {
            phi.q_values(self, qs);
        }
    }

    /// One learning step for the pair (s_t, a_t) with TD error δ_t: decay every trace by γλ, add the
    /// activation of (s_t, a_t) to its traces (eq. 20), then q ← q + α·δ·e (eq. 21). (The decay was
    /// done at the end of the previous step; this step's traces are decayed for the next.)
    #[inline(always)]
    pub fn update<F: Features>(&mut self, phi: &F, action: usize, delta: f64) {
        phi.update(self, action, delta);
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
        match &mut self.traces {
            Traces::None => {}
            Traces::Dense(e) => e.fill(0.0),
            Traces::Sparse(t) => t.clear(),
        }
    }

    /// The parameter vector q (rule-major).
    pub fn params(&self) -> &[f64] {
        &self.q
    }

    /// Number of traces currently non-zero.
    pub fn active_traces(&self) -> usize {
        match &self.traces {
            Traces::None => 0,
            Traces::Dense(e) => e.iter().filter(|&&e| e != 0.0).count(),
            Traces::Sparse(t) => t.live.iter().filter(|&&(_, e)| e != 0.0).count(),
        }
    }

    /// Every stored trace, one per parameter, as decayed for the next step (for tests).
    #[cfg(test)]
    fn dense_traces(&self) -> Vec<f64> {
        match &self.traces {
            Traces::None => vec![0.0; self.q.len()],
            Traces::Dense(e) => e.clone(),
            Traces::Sparse(t) => {
                let mut e = vec![0.0; self.q.len()];
                for &(k, v) in &t.live {
                    e[k as usize] = v;
                }
                e
            }
        }
    }
}

/// A state's activations in the form the learner evaluates and updates: the general sparse list
/// ([`Activations`], fuzzy rule bases) or a crisp table's single row ([`OneHot`], weight 1). Both
/// compute exactly what the list form computes for the same activations.
pub trait Features {
    /// Q(s, ·) into `out`, summed in activation order from 0.
    fn q_values(&self, l: &Learner, out: &mut [f64]);
    /// Q(s, action) alone, summed as [`q_values`](Self::q_values) sums it.
    fn q_value(&self, l: &Learner, action: usize) -> f64;
    /// One learning step (see [`Learner::update`]).
    fn update(&self, l: &mut Learner, action: usize, delta: f64);
}

impl Features for Activations {
    #[inline(always)]
    fn q_values(&self, l: &Learner, out: &mut [f64]) {
        if let ([i], [w]) = (&self.index[..], &self.weight[..]) {
            // One feature: small enough to inline into the trial loop.
            let na = l.n_actions;
            for (o, &v) in out.iter_mut().zip(&l.q[*i as usize * na..][..na]) {
                *o = 0.0 + w * v;
            }
        } else {
            l.q_values_many(self, out);
        }
    }

    #[inline(always)]
    fn q_value(&self, l: &Learner, action: usize) -> f64 {
        let na = l.n_actions;
        let mut sum = 0.0;
        for (&i, &w) in self.index.iter().zip(&self.weight) {
            sum += w * l.q[i as usize * na + action];
        }
        sum
    }

    #[inline(always)]
    fn update(&self, l: &mut Learner, action: usize, delta: f64) {
        let step = l.alpha * delta;
        let (q, na, rule) = (&mut l.q[..], l.n_actions, l.rule);
        let (index, weight) = (&self.index[..], &self.weight[..]);
        match &mut l.traces {
            Traces::None => update_q0(q, na, rule, (index, weight), action, step),
            Traces::Dense(e) => update_dense(q, e, na, rule, (index, weight), action, step),
            Traces::Sparse(t) => match (index, weight) {
                ([i], [w]) => update_single(q, t, rule, *i as usize * na + action, *w, step),
                _ => update_sparse(q, t, na, rule, (index, weight), action, step),
            },
        }
    }
}

/// The list form's one-feature case with the weight fixed at 1: `0 + 1·q = 0 + q` and a trace
/// extended by 1, the same operations on the same values.
impl Features for OneHot {
    #[inline(always)]
    fn q_values(&self, l: &Learner, out: &mut [f64]) {
        let na = l.n_actions;
        for (o, &v) in out.iter_mut().zip(&l.q[self.0 as usize * na..][..na]) {
            *o = 0.0 + v;
        }
    }

    #[inline(always)]
    fn q_value(&self, l: &Learner, action: usize) -> f64 {
        0.0 + l.q[self.0 as usize * l.n_actions + action]
    }

    #[inline(always)]
    fn update(&self, l: &mut Learner, action: usize, delta: f64) {
        let step = l.alpha * delta;
        let (q, na, rule) = (&mut l.q[..], l.n_actions, l.rule);
        let k = self.0 as usize * na + action;
        match &mut l.traces {
            Traces::None => update_q0(q, na, rule, (&[self.0], &[1.0]), action, step),
            Traces::Dense(e) => update_dense(q, e, na, rule, (&[self.0], &[1.0]), action, step),
            Traces::Sparse(t) => update_single(q, t, rule, k, 1.0, step),
        }
    }
}

/// γλ = 0: every trace from the previous step is gone, so the traces are exactly the current
/// activation (0 extended by w) and only those parameters move.
#[inline(always)]
fn update_q0(
    q: &mut [f64],
    na: usize,
    rule: TraceRule,
    (index, weight): (&[u32], &[f64]),
    action: usize,
    step: f64,
) {
    for (&i, &w) in index.iter().zip(weight) {
        q[i as usize * na + action] += step * rule.extend(0.0, w);
    }
}

/// One active feature (crisp tables), sparse traces: extend the target's trace (found through the
/// slot map, or a new entry), then apply and decay every live trace.
#[inline(always)]
fn update_single(q: &mut [f64], t: &mut SparseTraces, rule: TraceRule, target: usize, w: f64, step: f64) {
    match t.slot[target] as usize {
        0 => {
            t.live.push((target as u32, rule.extend(0.0, w)));
            t.slot[target] = t.live.len() as u32;
        }
        p => t.live[p - 1].1 = rule.extend(t.live[p - 1].1, w),
    }
    t.apply_and_decay(q, rule, step);
}

/// Several active features, small table: sweep every trace. Parameters without a live trace have
/// trace exactly 0, so decaying them is a no-op, and q moves exactly where the list-based update
/// moves it (see the comment on the parameter pass).
#[inline(never)]
fn update_dense(
    q: &mut [f64],
    trace: &mut [f64],
    na: usize,
    rule: TraceRule,
    (index, weight): (&[u32], &[f64]),
    action: usize,
    step: f64,
) {
    for (&i, &w) in index.iter().zip(weight) {
        let k = i as usize * na + action;
        trace[k] = rule.extend(trace[k], w);
    }
    // The list-based update adds step·e to every non-zero trace and to the current activation's
    // entries. Adding step·0 = ±0 everywhere else is exact too, up to the sign of a zero q, which no
    // sum can see (sums start from +0, and ±0 terms never change a running sum). Only a non-finite
    // step (an overflowing α·δ) makes step·0 a NaN: then exactly the list-based entries move.
    if step.is_finite() {
        for (q, e) in q.iter_mut().zip(trace.iter_mut()) {
            *q += step * *e;
            *e = rule.decayed(*e);
        }
    } else {
        for &i in index {
            let k = i as usize * na + action;
            if trace[k] == 0.0 {
                q[k] += step * trace[k];
            }
        }
        for (q, e) in q.iter_mut().zip(trace.iter_mut()) {
            if *e != 0.0 {
                *q += step * *e;
            }
            *e = rule.decayed(*e);
        }
    }
}

/// Several active features, large table: extend the current activation's traces (branch-free:
/// which activations are new is data-dependent), then apply and decay every live trace in one
/// pass, dropping those that vanish.
#[inline(never)]
fn update_sparse(
    q: &mut [f64],
    t: &mut SparseTraces,
    na: usize,
    rule: TraceRule,
    (index, weight): (&[u32], &[f64]),
    action: usize,
    step: f64,
) {
    // Extend: a parameter without a live trace gets the next free position, whose trace the
    // resize set to 0, so extending it gives extend(0, w) exactly as for a new trace.
    let SparseTraces { live, slot } = t;
    let mut len = live.len();
    live.resize(len + index.len(), (0, 0.0));
    for (&i, &w) in index.iter().zip(weight) {
        let k = i as usize * na + action;
        let p = slot[k] as usize;
        let dest = if p == 0 { len } else { p - 1 };
        live[dest] = (k as u32, rule.extend(live[dest].1, w));
        slot[k] = dest as u32 + 1;
        len += usize::from(p == 0);
    }
    live.truncate(len);
    t.apply_and_decay(q, rule, step);
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

    /// The list-based learner qsweep shipped before the fast paths, verbatim: the oracle.
    struct ListLearner {
        na: usize,
        q: Vec<f64>,
        trace: Vec<f64>,
        active: Vec<u32>,
        alpha: f64,
        decay: f64,
        cutoff: f64,
        replacing: bool,
    }

    impl ListLearner {
        fn new(nf: usize, na: usize, cfg: &LearnerConfig) -> Self {
            Self {
                na,
                q: vec![cfg.q_init; nf * na],
                trace: vec![0.0; nf * na],
                active: Vec::new(),
                alpha: cfg.alpha,
                decay: cfg.gamma * cfg.lambda,
                cutoff: cfg.trace_cutoff,
                replacing: cfg.traces == TraceKind::Replacing,
            }
        }

        fn clear_traces(&mut self) {
            for &k in &self.active {
                self.trace[k as usize] = 0.0;
            }
            self.active.clear();
        }

        fn update(&mut self, phi: &Activations, action: usize, delta: f64) {
            if self.decay == 0.0 {
                self.clear_traces();
            } else {
                let (decay, cutoff, trace) = (self.decay, self.cutoff, &mut self.trace);
                self.active.retain(|&k| {
                    let e = &mut trace[k as usize];
                    *e *= decay;
                    if *e < cutoff || *e == 0.0 {
                        *e = 0.0;
                        false
                    } else {
                        true
                    }
                });
            }
            for (&i, &w) in phi.index.iter().zip(&phi.weight) {
                let k = i as usize * self.na + action;
                let e = &mut self.trace[k];
                if *e == 0.0 {
                    self.active.push(k as u32);
                }
                *e = if self.replacing { e.max(w) } else { *e + w };
            }
            let step = self.alpha * delta;
            for &k in &self.active {
                self.q[k as usize] += step * self.trace[k as usize];
            }
        }
    }

    fn bits(v: &[f64]) -> Vec<u64> {
        v.iter().map(|x| x.to_bits()).collect()
    }

    #[test]
    fn every_trace_layout_matches_the_list_based_learner_bit_for_bit() {
        let settings = [
            (0.9, false, 1e-10, 0.1),
            (0.5, true, 1e-3, 0.1),
            (0.7, false, 0.0, 0.1),
            (0.0, false, 0.0, 0.1),
            (0.0, true, 0.0, 0.1),
            // α·δ overflows: step·0 is NaN wherever the list-based update touches a zero trace.
            (0.6, false, 1e-10, 1e308),
        ];
        for (lambda, replacing, cutoff, alpha) in settings {
            let mut cfg = config(lambda, replacing, cutoff);
            cfg.alpha = alpha;
            let (nf, na) = (24, 3);
            let mut oracle = ListLearner::new(nf, na, &cfg);
            let mut dense = Learner::new(nf, na, nf, &cfg);
            let mut sparse = Learner::new(nf, na, 1, &cfg);
            if lambda > 0.0 {
                assert!(matches!(dense.traces, Traces::Dense(_)));
                assert!(matches!(sparse.traces, Traces::Sparse(_)));
            }
            let (mut qd, mut qs) = (vec![0.0; na], vec![0.0; na]);
            for step in 0..400 {
                // Single-feature steps (the crisp path) mixed with several-feature ones.
                let phi = activations(step, nf, if step % 3 == 0 { 1 } else { 1 + step % 6 });
                let delta = ((step as f64) * 0.37).sin() * if alpha > 1.0 { 10.0 } else { 1.0 };
                for l in [&mut dense, &mut sparse] {
                    l.update(&phi, step % na, delta);
                }
                oracle.update(&phi, step % na, delta);
                let what = format!("λ {lambda} replacing {replacing} α {alpha} step {step}");
                if lambda > 0.0 {
                    // Ours are stored decayed for the next step; the oracle decays at its start.
                    let next: Vec<f64> = oracle.trace.iter().map(|&e| dense.rule.decayed(e)).collect();
                    assert_eq!(dense.dense_traces(), next, "{what}");
                    assert_eq!(sparse.dense_traces(), next, "{what}");
                }
                // Signs of zero may differ where q stays 0 (no sum can tell); nothing else may.
                let zero_sign =
                    |v: &[f64]| bits(&v.iter().map(|x| if *x == 0.0 { 0.0 } else { *x }).collect::<Vec<_>>());
                assert_eq!(zero_sign(&dense.q), zero_sign(&oracle.q), "{what}");
                assert_eq!(zero_sign(&sparse.q), zero_sign(&oracle.q), "{what}");
                dense.q_values(&phi, &mut qd);
                sparse.q_values(&phi, &mut qs);
                assert_eq!(bits(&qd), bits(&qs), "{what}");
                if step % 97 == 0 {
                    dense.clear_traces();
                    sparse.clear_traces();
                    oracle.clear_traces();
                }
            }
        }
    }

    /// The sparse passes drop a trace when `keeps(e · γλ)` is false; that must be exactly when the
    /// literal rule decays it to 0, at the cutoff, at underflow (cutoff 0) and for odd values.
    #[test]
    fn keeps_is_the_literal_decay_is_non_zero() {
        let tiny = f64::from_bits(1);
        for cutoff in [0.0, 1e-10, 1e-3, 0.5, tiny, 2.0 * tiny] {
            for decay in [0.95 * 0.6, 0.5, 1e-300, 1.0] {
                let mut cfg = config(decay, false, cutoff);
                cfg.gamma = 1.0;
                let rule = TraceRule::of(&cfg);
                let mut values = vec![0.0, tiny, 2.0 * tiny, 3.0 * tiny, f64::MIN_POSITIVE, 1e-300, 1.0, 7.5];
                values.extend([f64::INFINITY, f64::NAN, f64::MAX]);
                for c in [cutoff, cutoff / decay] {
                    let c = if c.is_finite() { c } else { 1.0 };
                    let (up, down) =
                        (f64::from_bits(c.to_bits() + 1), f64::from_bits(c.to_bits().max(1) - 1));
                    values.extend([c, up, down, c * 0.999, c * 1.001]);
                }
                for e in values {
                    assert_eq!(
                        rule.keeps(e * rule.decay),
                        rule.decayed(e) != 0.0,
                        "e {e:e} cutoff {cutoff:e} decay {decay}"
                    );
                }
            }
        }
    }

    /// Regression: the layout was chosen by features alone, so a 10-action table swept every
    /// parameter each step (Cart-Pole fuzzy Q(λ) 6⁴ × 10 actions, the costliest cell of
    /// `paper.yaml`, ran 3.6× the instructions it needs). The choice counts parameters now.
    #[test]
    fn many_action_tables_keep_their_traces_in_a_list() {
        let cfg = config(0.5, false, 1e-10);
        let layout = |nf, na, active| match Learner::new(nf, na, active, &cfg).traces {
            Traces::Dense(_) => "dense",
            Traces::Sparse(_) => "sparse",
            Traces::None => "none",
        };
        assert_eq!(layout(1296, 10, 625), "sparse", "6⁴ × 10");
        assert_eq!(layout(1296, 4, 625), "sparse", "6⁴ × 4");
        assert_eq!(layout(625, 10, 625), "sparse", "5⁴ × 10");
        assert_eq!(layout(2401, 2, 625), "sparse", "7⁴ × 2");
        assert_eq!(layout(1296, 2, 625), "dense", "6⁴ × 2");
        assert_eq!(layout(256, 8, 256), "dense", "4⁴ × 8");
        assert_eq!(layout(81, 10, 81), "dense", "3⁴ × 10");
        assert_eq!(layout(100, 3, 1), "sparse", "crisp: one feature a step");
        assert!(matches!(Learner::new(1296, 10, 625, &config(0.0, false, 1e-10)).traces, Traces::None));
    }

    /// The crisp path: a one-hot row must compute exactly what the one-entry list of weight 1 computes,
    /// under every trace layout a crisp table can get (none, sparse) and both trace kinds.
    #[test]
    fn one_hot_rows_match_one_entry_lists_bit_for_bit() {
        for (lambda, replacing) in [(0.0, false), (0.9, false), (0.9, true), (0.5, true)] {
            for na in [1, 2, 3, 10] {
                let cfg = config(lambda, replacing, 1e-10);
                let nf = 25;
                let (mut list, mut hot) = (Learner::new(nf, na, 1, &cfg), Learner::new(nf, na, 1, &cfg));
                let (mut ql, mut qh) = (vec![0.0; na], vec![0.0; na]);
                for step in 0..600 {
                    let f = ((step * 7919) % nf) as u32;
                    let one = Activations { index: vec![f], weight: vec![1.0] };
                    let a = (step * 3) % na;
                    let delta = ((step as f64) * 0.37).sin() * 2.0;
                    list.q_values(&one, &mut ql);
                    hot.q_values(&OneHot(f), &mut qh);
                    assert_eq!(bits(&ql), bits(&qh), "λ {lambda} na {na} step {step}");
                    assert_eq!(one.q_value(&list, a).to_bits(), OneHot(f).q_value(&hot, a).to_bits());
                    list.update(&one, a, delta);
                    hot.update(&OneHot(f), a, delta);
                    list.refresh_after_update(&one, a, &mut ql);
                    hot.refresh_after_update(&OneHot(f), a, &mut qh);
                    assert_eq!(bits(&ql), bits(&qh), "λ {lambda} na {na} step {step}");
                    assert_eq!(bits(&list.q), bits(&hot.q), "λ {lambda} na {na} step {step}");
                    assert_eq!(list.dense_traces(), hot.dense_traces(), "λ {lambda} na {na} step {step}");
                    if step % 41 == 0 {
                        list.clear_traces();
                        hot.clear_traces();
                    }
                }
            }
        }
    }

    /// The shortcut after a Q(0) update equals a full evaluation, bit for bit, whatever was
    /// updated (the same state, an overlapping one, a disjoint one, one feature or many).
    #[test]
    fn q_values_after_a_q0_update_equal_a_full_evaluation() {
        for na in [1, 2, 3, 10, 17] {
            let cfg = config(0.0, false, 0.0);
            let nf = 40;
            let mut l = Learner::new(nf, na, 8, &cfg);
            assert!(matches!(l.traces, Traces::None));
            let (mut full, mut fast) = (vec![0.0; na], vec![0.0; na]);
            for step in 0..500 {
                let phi = activations(step, nf, 1 + step % 7);
                let next = activations(step + 1 + step % 3, nf, 1 + (step * 5) % 8);
                let a = (step * 7) % na;
                l.q_values(&next, &mut fast);
                l.update(&phi, a, ((step as f64) * 0.61).cos() * 3.0);
                l.q_values(&next, &mut full);
                l.refresh_after_update(&next, a, &mut fast);
                assert_eq!(bits(&fast), bits(&full), "na {na} step {step}");
            }
            // With traces the shortcut is never taken.
            let lam = Learner::new(nf, na, 8, &config(0.9, false, 1e-10));
            let phi = activations(3, nf, 4);
            lam.q_values(&phi, &mut full);
            fast.fill(f64::NAN);
            lam.refresh_after_update(&phi, 0, &mut fast);
            assert_eq!(bits(&fast), bits(&full));
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
