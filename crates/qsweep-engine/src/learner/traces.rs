//! Eligibility traces, eqs. (7)/(20) with the cutoff, in three layouts: one trace per parameter,
//! swept every step; the same, swept only in the chunks of parameters that hold a live trace
//! (rule bases, with vector kernels); or the live traces as a packed list (crisp tables). All
//! apply exactly the literal rule, trace by trace: each trace is decayed by one multiplication by
//! γλ per step and dropped when the decayed value falls below the cutoff, so the layouts give
//! bit-identical results.
//!
//! The traces are stored already decayed for the next step: the decay e ← γλe of step t+1 depends
//! on nothing learned at step t+1, so it is done in the same pass that applies step t's update.

use crate::config::{LearnerConfig, TraceKind};
use crate::repr::GridView;
use crate::simd::{dispatch, Simd};

/// How traces decay and grow (eqs. 7 and 20 with the cutoff), shared by every layout.
#[derive(Debug, Clone, Copy)]
pub(super) struct TraceRule {
    /// γλ.
    pub(super) decay: f64,
    cutoff: f64,
    /// The least trace that stays live, for [`keeps`](Self::keeps): the cutoff, or the least
    /// positive f64 when the cutoff is 0 (a trace is dropped below the cutoff and at exactly 0).
    floor: f64,
    replacing: bool,
}

impl TraceRule {
    /// The rule of a learner configuration (γλ, the cutoff, the trace kind).
    pub(super) fn of(cfg: &LearnerConfig) -> Self {
        let cutoff = cfg.trace_cutoff;
        Self {
            decay: cfg.gamma * cfg.lambda,
            cutoff,
            floor: if cutoff > 0.0 { cutoff } else { f64::from_bits(1) },
            replacing: cfg.traces == TraceKind::Replacing,
        }
    }

    /// `e · γλ`, dropped to exactly 0 below the cutoff. (The test `e < cutoff || e == 0` is the
    /// same for traces, which are never negative or NaN: with cutoff 0, a zero stays 0.)
    #[inline(always)]
    pub(super) fn decayed(self, e: f64) -> f64 {
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
    pub(super) fn keeps(self, x: f64) -> bool {
        !(x < self.floor)
    }

    /// The trace after adding activation `w` to a (decayed) trace `e`: eq. (20), or replacing.
    #[inline(always)]
    pub(super) fn extend(self, e: f64, w: f64) -> f64 {
        if self.replacing {
            e.max(w)
        } else {
            e + w
        }
    }
}

/// One trace per parameter (0 where none is live).
#[derive(Debug, Clone)]
pub(super) struct DenseTraces {
    /// The traces, then padding that stays 0 ([`padded`](Self::padded)).
    e: Vec<f64>,
    /// Parameters in the table.
    n: usize,
}

impl DenseTraces {
    pub(super) fn new(n: usize) -> Self {
        Self::padded(n, 0)
    }

    /// Traces for `n` parameters, then `pad` more that a grid update extends by 0
    /// ([`update_grid`](Self::update_grid)).
    pub(super) fn padded(n: usize, pad: usize) -> Self {
        Self { e: vec![0.0; n + pad], n }
    }

    pub(super) fn clear(&mut self) {
        self.e.fill(0.0);
    }

    /// Every trace as it enters the next update.
    pub(super) fn values(&self) -> Vec<f64> {
        self.e[..self.n].to_vec()
    }

    /// Extend the activation's traces, then sweep every parameter: q ← q + step·e and decay e.
    /// Parameters without a live trace have trace exactly 0, so decaying them is a no-op, and q
    /// moves exactly where the list-based update moves it (see the comment on the sweep).
    #[inline(never)]
    #[allow(clippy::too_many_arguments)] // the sparse layout's signature plus the vector level
    pub(super) fn update(
        &mut self,
        q: &mut [f64],
        na: usize,
        rule: TraceRule,
        (index, weight): (&[u32], &[f64]),
        action: usize,
        step: f64,
        simd: Simd,
    ) {
        extend(&mut self.e, na, rule, (index, weight), action, |_| {});
        self.sweep_all(q, na, rule, index, action, step, simd);
    }

    /// [`update`](Self::update) for a window grid and a finite step: each slot's trace extended
    /// by its weight (a slot outside the windows by 0, which leaves a trace as it is: traces are
    /// never negative, so e + 0 and max(e, 0) are e; the slots past the last rule extend the
    /// padding), then the same sweep of the table's `q.len()` parameters. `rows`: with AVX2 row
    /// vectors (rows of whole vectors).
    #[inline(always)]
    pub(super) fn update_grid(
        &mut self,
        q: &mut [f64],
        rule: TraceRule,
        v: &GridView,
        action: usize,
        step: f64,
        rows: bool,
    ) {
        debug_assert!(step.is_finite());
        let e = &mut self.e[..];
        // The rule's kind chosen once, not per trace.
        if cfg!(target_arch = "x86_64") && rows {
            super::slots::check_slots(e, v, action);
            // SAFETY: AVX2 (the caller's `rows`), and the bound checked above.
            #[cfg(target_arch = "x86_64")]
            unsafe {
                super::grid_x86::extend_traces(e, v, action, rule.replacing)
            };
        } else if rule.replacing {
            super::slots::each_slot(e, v, action, |t, w| *t = t.max(w));
        } else {
            super::slots::each_slot(e, v, action, |t, w| *t += w);
        }
        // Not dispatched: a grid trial's whole loop is compiled for its level (trial.rs).
        let n = q.len();
        sweep(q, &mut self.e[..n], rule, step);
    }

    /// The pass of [`update`](Self::update) after the extension of `index`'s traces for `action`.
    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    pub(super) fn sweep_all(
        &mut self,
        q: &mut [f64],
        na: usize,
        rule: TraceRule,
        index: &[u32],
        action: usize,
        step: f64,
        simd: Simd,
    ) {
        let trace = &mut self.e[..];
        // The list-based update adds step·e to every non-zero trace and to the current
        // activation's entries. Adding step·0 = ±0 everywhere else is exact too, up to the sign of
        // a zero q, which no sum can see. Only a non-finite step (an overflowing α·δ) makes step·0
        // a NaN: then exactly the list-based entries move.
        if step.is_finite() {
            dense_sweep(simd, q, trace, rule, step);
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
}

dispatch! {
    /// The dense pass at `simd`'s vector width: per parameter q ← q + step·e, then e decayed.
    fn dense_sweep => sweep(q: &mut [f64], trace: &mut [f64], rule: TraceRule, step: f64)
}

/// [`dense_sweep`]'s body: every element on its own, so any vector width gives the same bits.
#[inline(always)]
fn sweep(q: &mut [f64], trace: &mut [f64], rule: TraceRule, step: f64) {
    for (q, e) in q.iter_mut().zip(trace.iter_mut()) {
        *q += step * *e;
        *e = rule.decayed(*e);
    }
}

/// Parameters per chunk of [`ChunkTraces`]: one AVX-512 register of f64, two AVX2 ones.
const CHUNK: usize = 8;

/// One trace per parameter, as in [`DenseTraces`], but swept only where a chunk of [`CHUNK`]
/// parameters holds a live trace: a fuzzy activation's traces lie in short runs of the table
/// (the last variable's window), so most chunks of a large table hold none and a full sweep would
/// add step·0 to them. The listed chunks are swept whole, parameter by parameter as the dense
/// sweep does, so the layouts give the same bits. Once [`FULL_SHARE`] of the chunks are listed
/// the whole table is swept, as [`DenseTraces`] does, until the traces are cleared: a small table
/// (or a long episode's wide trajectory) fills its chunks, and then the list only costs.
#[derive(Debug, Clone)]
pub(super) struct ChunkTraces {
    /// The traces, one per parameter (0 where none is live).
    dense: DenseTraces,
    /// The chunks holding a live trace, or one extended this step, in no particular order
    /// (while not `full`).
    live: Vec<u32>,
    /// Per chunk: whether it is in `live`.
    listed: Vec<bool>,
    /// Whether every chunk is swept (and the list no longer kept) until the next clear.
    full: bool,
}

/// The share of chunks listed at which [`ChunkTraces`] sweeps the whole table instead.
const FULL_SHARE: (usize, usize) = (3, 4);

impl ChunkTraces {
    pub(super) fn new(n: usize) -> Self {
        let listed = vec![false; n.div_ceil(CHUNK)];
        Self { dense: DenseTraces::new(n), live: Vec::new(), listed, full: false }
    }

    pub(super) fn clear(&mut self) {
        if self.full {
            self.dense.clear();
            self.listed.fill(false);
            self.full = false;
        } else {
            let e = &mut self.dense.e;
            let n = e.len();
            for &c in &self.live {
                e[chunk(c, n)].fill(0.0);
                self.listed[c as usize] = false;
            }
        }
        self.live.clear();
    }

    /// Every trace as it enters the next update.
    pub(super) fn values(&self) -> Vec<f64> {
        self.dense.values()
    }

    /// Whether the next update sweeps every chunk (most were listed since the last clear).
    #[cfg(test)]
    pub(super) fn sweeps_all(&self) -> bool {
        self.full
    }

    /// Extend the activation's traces, listing their chunks, then sweep the listed chunks: q ←
    /// q + step·e and decay e, element by element, and unlist a chunk whose traces all vanished.
    /// Exactly the dense layout's operations on the parameters it could move (elsewhere every
    /// trace is 0), including its treatment of a non-finite step; once [`FULL_SHARE`] of the
    /// chunks are listed, the dense layout's update itself.
    #[inline(never)]
    #[allow(clippy::too_many_arguments)] // the dense layout's signature
    pub(super) fn update(
        &mut self,
        q: &mut [f64],
        na: usize,
        rule: TraceRule,
        (index, weight): (&[u32], &[f64]),
        action: usize,
        step: f64,
        simd: Simd,
    ) {
        if self.full {
            return self.dense.update(q, na, rule, (index, weight), action, step, simd);
        }
        let Self { dense, live, listed, .. } = self;
        extend(&mut dense.e, na, rule, (index, weight), action, |k| {
            let c = k / CHUNK;
            if !listed[c] {
                listed[c] = true;
                live.push(c as u32);
            }
        });
        if live.len() * FULL_SHARE.1 >= listed.len() * FULL_SHARE.0 {
            // The extension is done; the dense layout's pass over every parameter follows.
            self.full = true;
            dense.sweep_all(q, na, rule, index, action, step, simd);
        } else if step.is_finite() {
            chunk_sweep(simd, q, &mut dense.e, live, listed, rule, step);
        } else {
            // Rare (an overflowing α·δ): the dense layout's literal pass, which moves only the
            // non-zero traces and this step's entries, all of them in listed chunks.
            dense.sweep_all(q, na, rule, index, action, step, simd);
            unlist_empty(&dense.e, live, listed);
        }
    }
}

/// eq. (20) (or replacing) for the activation's traces of `action`, calling `touched` with each
/// parameter extended.
#[inline(always)]
fn extend(
    e: &mut [f64],
    na: usize,
    rule: TraceRule,
    (index, weight): (&[u32], &[f64]),
    action: usize,
    mut touched: impl FnMut(usize),
) {
    for (&i, &w) in index.iter().zip(weight) {
        let k = i as usize * na + action;
        e[k] = rule.extend(e[k], w);
        touched(k);
    }
}

/// The parameters of chunk `c` in a table of `n` (the last chunk may be short).
fn chunk(c: u32, n: usize) -> std::ops::Range<usize> {
    let c = c as usize;
    c * CHUNK..((c + 1) * CHUNK).min(n)
}

/// Drop from `live` the chunks whose traces are all 0.
fn unlist_empty(e: &[f64], live: &mut Vec<u32>, listed: &mut [bool]) {
    live.retain(|&c| {
        let keep = e[chunk(c, e.len())].iter().any(|&x| x != 0.0);
        listed[c as usize] = keep;
        keep
    });
}

dispatch! {
    /// [`sweep_listed`] at `simd`'s vector width.
    fn chunk_sweep => sweep_listed(q: &mut [f64], e: &mut [f64], live: &mut Vec<u32>, listed: &mut [bool], rule: TraceRule, step: f64)
}

/// The dense sweep over the listed chunks only; a chunk left with no live trace is unlisted
/// (replaced by the last listed one, not yet visited).
#[inline(always)]
fn sweep_listed(
    q: &mut [f64],
    e: &mut [f64],
    live: &mut Vec<u32>,
    listed: &mut [bool],
    rule: TraceRule,
    step: f64,
) {
    let ((qc, q_tail), (ec, e_tail)) = (q.as_chunks_mut::<CHUNK>(), e.as_chunks_mut::<CHUNK>());
    let full = ec.len();
    let mut r = 0;
    while let Some(&c) = live.get(r) {
        let c = c as usize;
        let any = if c < full {
            let (q, e) = (&mut qc[c], &mut ec[c]);
            let mut any = false;
            for j in 0..CHUNK {
                q[j] += step * e[j];
                e[j] = rule.decayed(e[j]);
                any |= e[j] != 0.0;
            }
            any
        } else {
            // The last, partial chunk.
            sweep(q_tail, e_tail, rule, step);
            e_tail.iter().any(|&x| x != 0.0)
        };
        if any {
            r += 1;
        } else {
            listed[c] = false;
            live.swap_remove(r);
        }
    }
}

/// The live traces as a packed list, plus a map from parameter to list position. Traces are
/// applied and decayed in list order, which never matters: every trace and parameter update is
/// per entry.
#[derive(Debug, Clone)]
pub(super) struct SparseTraces {
    /// (parameter index, trace) of every live trace: every non-zero trace, plus any entry extended
    /// by a zero weight this step, exactly the entries a list-based update touches. One list of
    /// pairs, not two lists, so the pass over it checks one bound.
    live: Vec<(u32, f64)>,
    /// Per parameter: 1 + its position in `live`, or 0 when it has no live trace.
    slot: Vec<u32>,
}

impl SparseTraces {
    pub(super) fn new(n: usize) -> Self {
        Self { live: Vec::new(), slot: vec![0; n] }
    }

    pub(super) fn clear(&mut self) {
        for &(k, _) in &self.live {
            self.slot[k as usize] = 0;
        }
        self.live.clear();
    }

    /// Every trace as it enters the next update.
    pub(super) fn values(&self, n: usize) -> Vec<f64> {
        let mut e = vec![0.0; n];
        for &(k, v) in &self.live {
            e[k as usize] = v;
        }
        e
    }

    /// One update: extend the activation's traces for `action` (a single feature, every crisp
    /// step, through the slot map; several through a branch-free pass), then apply and decay.
    #[inline(always)]
    pub(super) fn update(
        &mut self,
        q: &mut [f64],
        na: usize,
        rule: TraceRule,
        (index, weight): (&[u32], &[f64]),
        action: usize,
        step: f64,
    ) {
        if let ([i], [w]) = (index, weight) {
            let target = *i as usize * na + action;
            match self.slot[target] as usize {
                0 => {
                    self.live.push((target as u32, rule.extend(0.0, *w)));
                    self.slot[target] = self.live.len() as u32;
                }
                p => self.live[p - 1].1 = rule.extend(self.live[p - 1].1, *w),
            }
            self.apply_and_decay(q, rule, step);
        } else {
            self.update_many(q, na, rule, (index, weight), action, step);
        }
    }

    /// Several active features: extend the current activation's traces (branch-free: which are
    /// new is data-dependent; a parameter without a live trace gets the next free position, whose
    /// trace the resize set to 0, so extending it gives extend(0, w) exactly as for a new trace),
    /// then apply and decay every live trace in one pass.
    #[inline(never)]
    fn update_many(
        &mut self,
        q: &mut [f64],
        na: usize,
        rule: TraceRule,
        (index, weight): (&[u32], &[f64]),
        action: usize,
        step: f64,
    ) {
        let Self { live, slot } = self;
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
        self.apply_and_decay(q, rule, step);
    }

    /// Apply `step · e` to every live trace's parameter and decay the trace for the next step,
    /// dropping those that vanish. A vanishing trace is replaced by the last one (not yet visited),
    /// so only moved traces rewrite their slot: most traces stay where they are.
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
