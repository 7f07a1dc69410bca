//! One learner for both representations: Q(s, a) = Σᵢ wᵢ qᵢᵃ over sparse activations (eq. 18), the
//! TD error of eqs. (4)/(14), and the trace update of eqs. (7)/(20) followed by the parameter update
//! of eqs. (6)/(21). A crisp table is the special case of one active feature of weight 1, and Q(0)
//! is exactly λ = 0: the traces then hold only the current activation, so the update is eq. (5)/(19).
//!
//! Parameters are laid out rule-major (`q[feature · n_actions + action]`) so all actions of a rule
//! are contiguous. Traces are a dense array plus a list of the non-zero entries, so a step costs
//! O(active traces), not O(table); traces that decay below `trace_cutoff` are dropped.

use super::config::{LearnerConfig, TraceKind};
use super::repr::Activations;

/// Q parameters and eligibility traces of one trial.
#[derive(Debug, Clone)]
pub struct Learner {
    n_actions: usize,
    q: Vec<f64>,
    trace: Vec<f64>,
    active: Vec<u32>,
    alpha: f64,
    decay: f64,
    cutoff: f64,
    replacing: bool,
}

impl Learner {
    /// A learner over `n_features × n_actions` parameters, all set to `cfg.q_init`.
    pub fn new(n_features: usize, n_actions: usize, cfg: &LearnerConfig) -> Self {
        let n = n_features * n_actions;
        Self {
            n_actions,
            q: vec![cfg.q_init; n],
            trace: vec![0.0; n],
            active: Vec::new(),
            alpha: cfg.alpha,
            decay: cfg.gamma * cfg.lambda,
            cutoff: cfg.trace_cutoff,
            replacing: cfg.traces == TraceKind::Replacing,
        }
    }

    /// Q(s, ·) for the activations of s, eq. (18), written into `out` (one value per action).
    #[inline]
    pub fn q_values(&self, phi: &Activations, out: &mut [f64]) {
        let na = self.n_actions;
        out.fill(0.0);
        for (&i, &w) in phi.index.iter().zip(&phi.weight) {
            let row = &self.q[i as usize * na..(i as usize + 1) * na];
            for (o, q) in out.iter_mut().zip(row) {
                *o += w * q;
            }
        }
    }

    /// Clear every trace (episode start; Watkins's cut).
    #[inline]
    pub fn clear_traces(&mut self) {
        for &k in &self.active {
            self.trace[k as usize] = 0.0;
        }
        self.active.clear();
    }

    /// One learning step for the pair (s_t, a_t) with TD error δ_t: decay every trace by γλ, add the
    /// activation of (s_t, a_t) to its traces (eq. 20), then q ← q + α·δ·e (eq. 21).
    #[inline]
    pub fn update(&mut self, phi: &Activations, action: usize, delta: f64) {
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
        let na = self.n_actions;
        for (&i, &w) in phi.index.iter().zip(&phi.weight) {
            let k = i as usize * na + action;
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

    /// The parameter vector q (rule-major).
    pub fn params(&self) -> &[f64] {
        &self.q
    }

    /// Number of traces currently non-zero.
    pub fn active_traces(&self) -> usize {
        self.active.len()
    }
}
