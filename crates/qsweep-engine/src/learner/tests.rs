//! Tests of the learner: every trace layout against the literal list-based algorithm, the
//! layout rule, the one-hot path, the Q(0) refresh and the Q(s, ·) kernels.

use super::*;
use crate::config::{Algorithm, TraceKind, TrialConfig};
use crate::env::SystemKind;
use crate::math;
use crate::repr::{Activations, OneHot, ReprKind};
use crate::simd::Simd;
use sums::{lanes, q_values_any};
use traces::{ChunkTraces, DenseTraces, SparseTraces, TraceRule};

fn config(lambda: f64, replacing: bool, cutoff: f64) -> LearnerConfig {
    let mut c =
        TrialConfig::paper(SystemKind::CartPole, ReprKind::Fuzzy, Algorithm::QLambda, vec![2; 4], 3).learner;
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

/// A learner at `simd` with its traces in `layout` (under Q(0) none, whatever the layout).
fn with_layout(layout: &str, nf: usize, na: usize, cfg: &LearnerConfig, simd: Simd) -> Learner {
    let mut l = Learner::new(nf, na, 2, cfg).with_simd(simd);
    let n = nf * na;
    if l.rule.decay != 0.0 {
        l.traces = match layout {
            "dense" => Traces::Dense(DenseTraces::new(n)),
            "sparse" => Traces::Sparse(SparseTraces::new(n)),
            "chunked" => Traces::Chunked(ChunkTraces::new(n)),
            _ => unreachable!("{layout}"),
        };
    }
    l
}

const LAYOUTS: [&str; 3] = ["dense", "sparse", "chunked"];

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
        // 23 features: 69 parameters, eight full chunks and a partial one.
        let (nf, na) = (23, 3);
        let mut oracle = ListLearner::new(nf, na, &cfg);
        let mut learners = LAYOUTS.map(|lay| with_layout(lay, nf, na, &cfg, crate::simd::level()));
        // Steps the chunked layout took listing its chunks, and sweeping every one.
        let mut chunk_modes = [0, 0];
        let (mut want, mut got) = (vec![0.0; na], vec![0.0; na]);
        for step in 0..400 {
            // Single-feature steps (the crisp path) mixed with several-feature ones.
            let phi = activations(step, nf, if step % 3 == 0 { 1 } else { 1 + step % 6 });
            let delta = math::sin((step as f64) * 0.37) * if alpha > 1.0 { 10.0 } else { 1.0 };
            oracle.update(&phi, step % na, delta);
            let what = format!("λ {lambda} replacing {replacing} α {alpha} step {step}");
            // Ours are stored decayed for the next step; the oracle decays at its start.
            let next: Vec<f64> = oracle.trace.iter().map(|&e| learners[0].rule.decayed(e)).collect();
            // Signs of zero may differ where q stays 0 (no sum can tell); nothing else may.
            let zero_sign =
                |v: &[f64]| bits(&v.iter().map(|x| if *x == 0.0 { 0.0 } else { *x }).collect::<Vec<_>>());
            for (k, l) in learners.iter_mut().enumerate() {
                l.update(&phi, step % na, delta);
                if let Traces::Chunked(t) = &l.traces {
                    chunk_modes[usize::from(t.sweeps_all())] += 1;
                }
                let what = format!("{} layout, {what}", layout(l));
                if lambda > 0.0 {
                    assert_eq!(l.traces_for_next_step(), next, "{what}");
                }
                assert_eq!(zero_sign(l.params()), zero_sign(&oracle.q), "{what}");
                l.q_values(&phi, if k == 0 { &mut want } else { &mut got });
                if k > 0 {
                    assert_eq!(bits(&got), bits(&want), "{what}");
                }
            }
            if step % 97 == 0 {
                learners.iter_mut().for_each(Learner::clear_traces);
                oracle.clear_traces();
            }
        }
        if lambda > 0.0 {
            assert!(chunk_modes[0] > 0 && chunk_modes[1] > 0, "both chunked modes ran: {chunk_modes:?}");
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
                let (up, down) = (f64::from_bits(c.to_bits() + 1), f64::from_bits(c.to_bits().max(1) - 1));
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
/// `paper.yaml`, ran 3.6× the instructions it needs). With vector kernels a rule base sweeps only
/// its live chunks (all of them once most are live); at the baseline level parameters per active
/// feature choose between a full sweep and a list.
#[test]
fn many_action_tables_sweep_only_their_live_traces() {
    let rule = TraceRule::of(&config(0.5, false, 1e-10));
    let layout = |nf: usize, na: usize, active, simd| match Traces::for_table(nf * na, active, rule, simd) {
        Traces::Dense(_) => "dense",
        Traces::Sparse(_) => "sparse",
        Traces::Chunked(_) => "chunked",
        Traces::None => "none",
    };
    let cases = [
        // features, actions, most active, with vector kernels, at the baseline
        (1296, 10, 625, "chunked", "sparse", "6⁴ × 10"),
        (1296, 4, 625, "chunked", "sparse", "6⁴ × 4"),
        (625, 10, 625, "chunked", "sparse", "5⁴ × 10: over DENSE_MAX_PARAMS"),
        (2401, 2, 625, "chunked", "sparse", "7⁴ × 2"),
        (1296, 2, 625, "chunked", "dense", "6⁴ × 2"),
        (1600, 2, 400, "chunked", "dense", "10×4×10×4 × 2"),
        (100, 10, 25, "chunked", "sparse", "10² × 10"),
        (256, 8, 256, "chunked", "dense", "4⁴ × 8: chunks until most are live, then the full sweep"),
        (81, 10, 81, "chunked", "dense", "3⁴ × 10"),
        (16, 3, 16, "chunked", "dense", "4² × 3"),
        (100, 3, 1, "sparse", "sparse", "crisp: one feature a step"),
    ];
    for (nf, na, active, vector, baseline, what) in cases {
        assert_eq!(layout(nf, na, active, Simd::Avx2), vector, "{what}");
        assert_eq!(layout(nf, na, active, Simd::Avx512), vector, "{what}");
        assert_eq!(layout(nf, na, active, Simd::Baseline), baseline, "{what}");
    }
    assert!(matches!(Learner::new(1296, 10, 625, &config(0.0, false, 1e-10)).traces, Traces::None));
}

/// Equal up to rounding: within 10⁻¹² relative (absolute below 1).
fn close(ours: f64, other: f64) -> bool {
    (ours - other).abs() <= 1e-12 * other.abs().max(1.0)
}

fn layout(l: &Learner) -> &'static str {
    match l.traces {
        Traces::Dense(_) => "dense",
        Traces::Sparse(_) => "sparse",
        Traces::Chunked(_) => "chunked",
        Traces::None => "none",
    }
}

/// The crisp path: a one-hot row must compute exactly what the one-entry list of weight 1 computes,
/// under every trace layout a crisp table can get (none, lazy) and both trace kinds.
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
                let one = Activations { index: vec![f], weight: vec![1.0], ..Default::default() };
                let a = (step * 3) % na;
                let delta = math::sin((step as f64) * 0.37) * 2.0;
                list.q_values(&one, &mut ql);
                hot.q_values(&OneHot(f), &mut qh);
                assert_eq!(bits(&ql), bits(&qh), "λ {lambda} na {na} step {step}");
                list.update(&one, a, delta);
                hot.update(&OneHot(f), a, delta);
                list.refresh_after_update(&one, &one, a, &mut ql);
                hot.refresh_after_update(&OneHot(f), &OneHot(f), a, &mut qh);
                assert_eq!(bits(&ql), bits(&qh), "λ {lambda} na {na} step {step}");
                assert_eq!(bits(list.params()), bits(hot.params()), "λ {lambda} na {na} step {step}");
                assert_eq!(list.traces_for_next_step(), hot.traces_for_next_step(), "λ {lambda} na {na}");
                if step % 41 == 0 {
                    list.clear_traces();
                    hot.clear_traces();
                }
            }
        }
    }
}

/// The shortcut after a Q(0) update (Q(s′, a) += α·δ·⟨w(s′), w(s)⟩) equals a full evaluation up
/// to rounding, whatever was updated (the same state, an overlapping one, a disjoint one, one
/// feature or many); for a crisp row it is bit for bit.
#[test]
fn q_values_after_a_q0_update_equal_a_full_evaluation() {
    for na in [1, 2, 3, 10, 17] {
        let cfg = config(0.0, false, 0.0);
        let nf = 40;
        let mut l = Learner::new(nf, na, 8, &cfg);
        assert_eq!(layout(&l), "none");
        let (mut full, mut fast) = (vec![0.0; na], vec![0.0; na]);
        for step in 0..500 {
            let phi = activations(step, nf, 1 + step % 7);
            let next = activations(step + 1 + step % 3, nf, 1 + (step * 5) % 8);
            let a = (step * 7) % na;
            l.q_values(&next, &mut fast);
            l.update(&phi, a, math::cos((step as f64) * 0.61) * 3.0);
            l.q_values(&next, &mut full);
            l.refresh_after_update(&next, &phi, a, &mut fast);
            for (x, y) in fast.iter().zip(&full) {
                assert!(close(*x, *y), "na {na} step {step}: {fast:?} vs {full:?}");
            }
            let (row, prev) = (OneHot((step % 5) as u32), OneHot((step % 3) as u32));
            l.q_values(&row, &mut fast);
            l.update(&prev, a, 0.5);
            l.q_values(&row, &mut full);
            l.refresh_after_update(&row, &prev, a, &mut fast);
            assert_eq!(bits(&fast), bits(&full), "na {na} step {step}");
        }
    }
}

/// The unrolled kernels (partial sums interleaved for few actions) against a plain sum in
/// activation order: equal up to rounding, and bit for bit where one partial sum is used.
#[test]
fn unrolled_q_values_match_the_plain_sum() {
    for na in 1..=20 {
        let cfg = config(0.0, false, 0.0);
        let mut l = Learner::new(10, na, 4, &cfg);
        for (k, q) in l.q.iter_mut().enumerate() {
            *q = math::sin(k as f64 * 0.731) * 1e3;
        }
        for len in [1, 2, 3, 5, 7, 8, 9] {
            let phi = activations(3, 10, len);
            let (mut fast, mut plain) = (vec![0.0; na], vec![0.0; na]);
            l.q_values(&phi, &mut fast);
            q_values_any(&l.q, na, &phi.index, &phi.weight, &mut plain);
            for a in 0..na {
                assert!((fast[a] - plain[a]).abs() <= 1e-12 * 1e3, "{na} actions, {len} rules");
            }
            if lanes(na) == 1 || len == 1 {
                assert_eq!(bits(&fast), bits(&plain), "{na} actions, {len} rules");
            }
        }
    }
}

/// The bits of a learner's parameters, its traces and one Q(s, ·).
type Bits = (Vec<u64>, Vec<u64>, Vec<u64>);

/// Every vector level gives the baseline's bits: parameters, traces and Q(s, ·), for every
/// action-count kernel (1–16 unrolled, more through the general one), every trace layout, long
/// activations and an overflowing α·δ.
#[test]
fn every_simd_level_gives_the_baselines_bits() {
    use crate::simd::Simd;
    for na in (1..=18).chain([25]) {
        for (lambda, alpha) in [(0.9, 0.1), (0.0, 0.1), (0.6, 1e308)] {
            let cfg = config(lambda, false, 1e-10);
            let cfg = LearnerConfig { alpha, ..cfg };
            let nf = 400;
            let mut learners: Vec<(Simd, Learner)> = Simd::available()
                .into_iter()
                .flat_map(|s| LAYOUTS.map(|lay| (s, with_layout(lay, nf, na, &cfg, s))))
                .collect();
            let mut qs = vec![0.0; na];
            for step in 0..150 {
                let phi = activations(step, nf, if step % 4 == 0 { 1 } else { 1 + (step * 13) % 257 });
                let delta = math::sin(step as f64 * 0.61) * if alpha > 1.0 { 10.0 } else { 1.0 };
                // Per layout (the layouts may differ in the sign of a zero q; `every_trace_layout…`).
                let mut seen: [Option<Bits>; 3] = [None, None, None];
                for (k, (simd, l)) in learners.iter_mut().enumerate() {
                    l.update(&phi, step % na, delta);
                    l.q_values(&phi, &mut qs);
                    let got = (bits(&l.q), bits(&l.traces_for_next_step()), bits(&qs));
                    match &seen[k % 3] {
                        None => seen[k % 3] = Some(got),
                        Some(want) => assert!(
                            got == *want,
                            "{simd:?}, {na} actions, λ {lambda}, α {alpha}, step {step}"
                        ),
                    }
                }
            }
        }
    }
}
