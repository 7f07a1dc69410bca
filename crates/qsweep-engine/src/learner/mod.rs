//! One learner for both representations: Q(s, a) = Σᵢ wᵢ qᵢᵃ over sparse activations (eq. 18), the
//! TD error of eqs. (4)/(14), and the trace update of eqs. (7)/(20) followed by the parameter update
//! of eqs. (6)/(21). A crisp table is the special case of one active feature of weight 1, and Q(0)
//! is exactly λ = 0: the traces then hold only the current activation, so the update is eq. (5)/(19).
//!
//! Parameters are laid out rule-major (`q[feature · n_actions + action]`) so all actions of a rule
//! are contiguous. Where the traces live (a full sweep, chunks or a list; the private `traces`
//! module) is chosen per table and vector level ([`Learner::new`]); the layouts give
//! bit-identical results. Q(s, ·)'s kernels, sparse and dense, are the private `sums` module.
//!
//! # Rounding (engine 2)
//! Engine 1 summed Q(s, ·) strictly in activation order and re-summed Q(s′, a) after a Q(0)
//! update. Engine 2 keeps the paper's arithmetic, per trace and per parameter, exactly as before,
//! and changes only the order of two sums, so results agree with the literal equations up to
//! rounding (every Q value within 10⁻⁹ relative of the literal dense algorithm along whole trials,
//! `reference_tests`):
//! - Q(s, ·) over an activation is summed in two (3–4 actions) or four (1–2 actions) interleaved
//!   partial sums per action, so that the additions of a long fuzzy activation do not each wait on
//!   the one before (with more actions the actions' own sums already overlap);
//! - after a Q(0) update of s, Q(s′, a) grows by α·δ·⟨w(s′), w(s)⟩ ([`Features::overlap`]), which
//!   is the re-summed value in exact arithmetic and for a fuzzy grid a product of one short dot per
//!   variable, instead of a second sum over every active rule (for a crisp row it is bit for bit
//!   the re-summed value: q + α·δ).
//!
//! Every operation is a fixed sequence of IEEE-754 additions and multiplications, so the results
//! are the same on every machine.

#[cfg(target_arch = "x86_64")]
mod grid_x86;
mod slots;
mod sums;
mod traces;

use super::config::LearnerConfig;
use super::repr::Features;
use super::simd::{dispatch, Simd};
use crate::repr::{GridView, GRID};
use slots::{check_slots, each_slot};
pub use sums::grid_row_len;
use sums::{grid_q_values_by_count, q_values_at, MAX_UNROLLED_ACTIONS};
use traces::{ChunkTraces, DenseTraces, SparseTraces, TraceRule};

/// At the baseline vector level, the most parameters a dense trace sweep covers: larger tables
/// keep their traces in a list ([`Learner::new`]).
pub const DENSE_MAX_PARAMS: usize = 4096;

/// At the baseline vector level, dense traces when the table has at most this many parameters
/// per feature a single state can activate (and at most [`DENSE_MAX_PARAMS`]); else a list. A
/// step extends the traces of one action only, so the rule counts parameters, not features.
pub const DENSE_TRACE_RATIO: usize = 10;

/// Values past the end of the Q table, so that the grid kernels can read and update any slot
/// (up to [`GRID`] − 1 rules past the last) and read every rule's row as a whole vector (the
/// lanes past the row's own are never read back, and the slots past the last rule weigh 0).
const Q_PAD: usize = (GRID - 1) * MAX_UNROLLED_ACTIONS + MAX_UNROLLED_ACTIONS;

/// Q parameters and eligibility traces of one trial.
#[derive(Debug, Clone)]
pub struct Learner {
    n_actions: usize,
    /// The most features one state activates (with the vector level, chooses the trace layout).
    max_active: usize,
    /// The table (rule-major), then [`Q_PAD`] values no kernel reads back.
    q: Vec<f64>,
    traces: Traces,
    rule: TraceRule,
    alpha: f64,
    /// α·δ of the last update.
    last_step: f64,
    /// The vector instructions the kernels use (never changes a result; [`crate::simd`]).
    simd: Simd,
}

/// Where the eligibility traces live.
#[derive(Debug, Clone)]
enum Traces {
    /// γλ = 0 (Q(0)): a trace never outlives its step, so none is stored.
    None,
    /// One trace per parameter, swept in full every step (at the baseline level, rule bases whose
    /// traces are mostly live).
    Dense(DenseTraces),
    /// Only the live traces, packed: crisp tables, which start one trace a step (and at the
    /// baseline level, large rule bases).
    Sparse(SparseTraces),
    /// One trace per parameter, swept only in the chunks that hold a live one, or in full once
    /// most do: rule bases, whose live traces lie in runs around the recent states.
    Chunked(ChunkTraces),
}

impl Traces {
    /// The layout for a table of `n` parameters whose states activate at most `max_active`
    /// features, with kernels at `simd`: none under Q(0); a list for one feature a
    /// state (crisp tables); else chunks (which turn into a full sweep once most are live),
    /// except at the baseline level, whose 2-wide vectors make a chunk cost more than the few
    /// live traces it may hold in a table of many actions: there the [`DENSE_TRACE_RATIO`] rule
    /// chooses a full sweep or a list. Every layout gives the same results; the rule is measured
    /// speed (docs/speed.md).
    fn for_table(n: usize, max_active: usize, rule: TraceRule, simd: Simd) -> Self {
        if rule.decay == 0.0 {
            Self::None
        } else if max_active <= 1 {
            Self::Sparse(SparseTraces::new(n))
        } else if simd == Simd::Baseline {
            if n <= DENSE_MAX_PARAMS && n <= DENSE_TRACE_RATIO * max_active {
                Self::Dense(DenseTraces::padded(n, Q_PAD))
            } else {
                Self::Sparse(SparseTraces::new(n))
            }
        } else {
            Self::Chunked(ChunkTraces::new(n))
        }
    }
}

impl Learner {
    /// A learner over `n_features × n_actions` parameters, all set to `cfg.q_init`, for a
    /// representation that activates at most `max_active` features per state, which with the
    /// vector level chooses the trace layout: none under Q(0), a list for one feature a state,
    /// else chunks of parameters, swept where they hold a live trace (at the baseline level a
    /// full sweep or a list, by [`DENSE_TRACE_RATIO`]).
    pub fn new(n_features: usize, n_actions: usize, max_active: usize, cfg: &LearnerConfig) -> Self {
        let rule = TraceRule::of(cfg);
        let simd = crate::simd::level();
        let n = n_features * n_actions;
        let traces = Traces::for_table(n, max_active, rule, simd);
        // Padded past the table so that a dense kernel can read any row as a whole vector.
        let q = vec![cfg.q_init; n + Q_PAD];
        Self { n_actions, max_active, q, traces, rule, alpha: cfg.alpha, last_step: 0.0, simd }
    }

    /// The same learner with its kernels at `simd` (capped by what the CPU has), and the trace
    /// layout that suits them. Only before the first update: the traces start empty again.
    pub fn with_simd(mut self, simd: Simd) -> Self {
        self.simd = simd.capped();
        self.traces = Traces::for_table(self.n_params(), self.max_active, self.rule, self.simd);
        self
    }

    /// The same learner with one trace per parameter swept in full every step, whatever the
    /// vector level (the layouts give the same bits): for a small table on the grid path, whose
    /// traces it extends slot by slot (padded as the table is). Only before the first update.
    pub fn with_dense_traces(mut self) -> Self {
        if self.rule.decay != 0.0 {
            self.traces = Traces::Dense(DenseTraces::padded(self.n_params(), Q_PAD));
        }
        self
    }

    /// Values a rule's row holds (its actions', then for a grid learner values that no action
    /// reads, [`grid_row_len`]).
    pub fn row_len(&self) -> usize {
        self.n_actions
    }

    /// How many values a Q(s, ·) buffer for this learner holds: at least one per action, and
    /// room for the grid kernels' whole vectors (the values past the actions are scratch).
    pub fn q_out_len(&self) -> usize {
        sums::grid_out_len(self.n_actions)
    }

    /// Q(s, ·) for the activations of s, eq. (18), written into `out` (one value per action).
    #[inline(always)]
    pub fn q_values<F: Features>(&self, phi: &F, out: &mut [f64]) {
        if F::GRID {
            // Not dispatched: a grid trial's whole loop is compiled for its level (trial.rs).
            return grid_q_values_by_count(&self.q, self.n_actions, phi.grid(), out, self.simd);
        }
        let (index, weight) = phi.rules();
        if F::ONE_HOT {
            // 0 + q, not a copy: LLVM turns a copy of a run-time length into a memcpy call.
            let row = &self.q[index[0] as usize * self.n_actions..][..self.n_actions];
            for (o, &v) in out.iter_mut().zip(row) {
                *o = 0.0 + v;
            }
        } else {
            self.q_values_many(index, weight, out);
        }
    }

    /// Bring `qs`, Q(s, ·) for the activation `phi` computed just before the
    /// [`update`](Self::update) of `prev` for `action`, up to date after it. Under Q(0) the update
    /// added α·δ·w(prev) to `action`'s parameters, so Q(s, action) grows by α·δ·⟨w(s), w(prev)⟩
    /// ([`Features::overlap`]) and nothing else moves; with traces every action may have moved,
    /// and all are recomputed.
    #[inline(always)]
    pub fn refresh_after_update<F: Features>(&self, phi: &F, prev: &F, action: usize, qs: &mut [f64]) {
        match &self.traces {
            Traces::None => {
                // Skipped when nothing is shared, so that an overflowing α·δ cannot turn an
                // untouched value into ∞·0 = NaN.
                let shared = phi.overlap(prev);
                if shared != 0.0 {
                    qs[action] += self.last_step * shared;
                }
            }
            Traces::Dense(_) | Traces::Sparse(_) | Traces::Chunked(_) => self.q_values(phi, qs),
        }
    }

    /// One learning step for the pair (s_t, a_t) with TD error δ_t: decay every trace by γλ, add the
    /// activation of (s_t, a_t) to its traces (eq. 20), then q ← q + α·δ·e (eq. 21).
    #[inline(always)]
    pub fn update<F: Features>(&mut self, phi: &F, action: usize, delta: f64) {
        let step = self.alpha * delta;
        self.last_step = step;
        if F::GRID {
            let v = phi.grid();
            let n = self.n_params();
            // The slots past the table's last rule write into its padding.
            let (q, rule, na) = (&mut self.q[..], self.rule, self.n_actions);
            // The AVX2 row updates where rows are whole vectors (`simd` is capped by the CPU).
            let rows = cfg!(target_arch = "x86_64") && self.simd != Simd::Baseline && na % 4 == 0;
            match &mut self.traces {
                // Adding step·0 to a slot outside the windows is exact (up to a zero's sign, which
                // no sum sees) while the step is finite; an overflowing α·δ takes the literal list.
                Traces::None if step.is_finite() => return grid_q0_update(q, v, action, step, rows),
                Traces::Dense(t) if step.is_finite() => {
                    return t.update_grid(&mut q[..n], rule, v, action, step, rows);
                }
                _ => {}
            }
            let (count, index, weight) = v.sparse(self.n_actions);
            return self.update_rules(&index[..count], &weight[..count], false, action, step);
        }
        let (index, weight) = phi.rules();
        self.update_rules(index, weight, F::ONE_HOT, action, step)
    }

    /// [`update`](Self::update) over a list of active rules and their weights (`one_hot`: one
    /// rule of weight 1, a constant where it is inlined), with `step` = α·δ.
    #[inline(always)]
    fn update_rules(&mut self, index: &[u32], weight: &[f64], one_hot: bool, action: usize, step: f64) {
        let n = self.n_params();
        let (q, na, rule, simd) = (&mut self.q[..n], self.n_actions, self.rule, self.simd);
        match &mut self.traces {
            // Q(0): the trace of this step is extend(0, w) = w (weights are never negative).
            // A crisp row is one addition, cheaper inline than through a kernel call.
            Traces::None if one_hot => q[index[0] as usize * na + action] += step * weight[0],
            Traces::None => q0_update_at(simd, q, na, index, weight, action, step),
            Traces::Dense(t) => t.update(q, na, rule, (index, weight), action, step, simd),
            Traces::Sparse(t) => t.update(q, na, rule, (index, weight), action, step),
            Traces::Chunked(t) => t.update(q, na, rule, (index, weight), action, step, simd),
        }
    }

    /// Q(s, ·) for several active features: a kernel per action count, at the learner's vector
    /// width.
    #[inline(never)]
    fn q_values_many(&self, index: &[u32], weight: &[f64], out: &mut [f64]) {
        q_values_at(self.simd, &self.q, self.n_actions, index, weight, out);
    }

    /// Clear every trace (episode start; Watkins's cut), after applying what they still owe.
    #[inline]
    pub fn clear_traces(&mut self) {
        match &mut self.traces {
            Traces::None => {}
            Traces::Dense(t) => t.clear(),
            Traces::Sparse(t) => t.clear(),
            Traces::Chunked(t) => t.clear(),
        }
    }

    /// The parameter vector q (rule-major).
    pub fn params(&self) -> &[f64] {
        &self.q[..self.n_params()]
    }

    /// Parameters in the table (features × actions).
    fn n_params(&self) -> usize {
        self.q.len() - Q_PAD
    }

    /// Number of traces that take part in the next update.
    pub fn active_traces(&self) -> usize {
        self.traces_for_next_step().iter().filter(|&&e| e != 0.0).count()
    }

    /// Every trace, one per parameter, as it enters the next update (decayed, before extension).
    pub fn traces_for_next_step(&self) -> Vec<f64> {
        match &self.traces {
            Traces::None => vec![0.0; self.n_params()],
            Traces::Dense(t) => t.values(),
            Traces::Sparse(t) => t.values(self.n_params()),
            Traces::Chunked(t) => t.values(),
        }
    }
}

dispatch! {
    /// [`q0_update_by_count`] at `simd`'s vector width.
    fn q0_update_at => q0_update_by_count(q: &mut [f64], na: usize, index: &[u32], weight: &[f64], action: usize, step: f64)
}

/// The Q(0) update q[i·na + action] += step·w over an activation, with the row width a constant
/// for up to [`MAX_UNROLLED_ACTIONS`] actions (one bounds check per rule, no multiplication).
#[inline(always)]
fn q0_update_by_count(q: &mut [f64], na: usize, index: &[u32], weight: &[f64], action: usize, step: f64) {
    #[inline(always)]
    fn fixed<const N: usize>(q: &mut [f64], index: &[u32], weight: &[f64], action: usize, step: f64) {
        let rows = q.as_chunks_mut::<N>().0;
        // Checked once here, so the loop checks only the row.
        assert!(action < N, "action {action} of {N}");
        for (&i, &w) in index.iter().zip(weight) {
            rows[i as usize][action] += step * w;
        }
    }
    macro_rules! unrolled {
        ($($n:literal)*) => {
            match na {
                $($n => fixed::<$n>(q, index, weight, action, step),)*
                _ => {
                    for (&i, &w) in index.iter().zip(weight) {
                        q[i as usize * na + action] += step * w;
                    }
                }
            }
        };
    }
    unrolled!(1 2 3 4 5 6 7 8 9 10 11 12 13 14 15 16);
}

/// The Q(0) update over a window grid's slots: q[r·na + action] += step·w (the slots outside the
/// windows weigh 0; `q` is the padded table).
#[inline(always)]
fn grid_q0_update(q: &mut [f64], v: &GridView, action: usize, step: f64, rows: bool) {
    #[cfg(target_arch = "x86_64")]
    if rows {
        check_slots(q, v, action);
        // SAFETY: AVX2 (the caller's `rows`), and the bound checked above.
        return unsafe { grid_x86::q0_update(q, v, action, step) };
    }
    let _ = rows;
    each_slot(q, v, action, |q, w| *q += step * w);
}

#[cfg(test)]
mod tests;
