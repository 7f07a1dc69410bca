//! The grid sums of Q(s, ·) ([`super::sums`]) written with AVX2 vectors, for the vector levels
//! that have them: the same additions and multiplications in the same order, lane by lane, as the
//! portable kernels (no fused multiply-add), so the same bits. The compiler, left to vectorise the
//! portable kernels' sixteen unrolled slots, regroups rows across slots (a row of three actions
//! overlaps the next one's) and spends about twice the instructions.

use crate::repr::{GridView, GRID};
use std::arch::x86_64::{
    __m256d, _mm256_add_pd, _mm256_and_pd, _mm256_blendv_pd, _mm256_broadcast_sd, _mm256_castsi256_pd,
    _mm256_cmp_pd, _mm256_cmpeq_epi64, _mm256_loadu_pd, _mm256_max_pd, _mm256_movemask_pd, _mm256_mul_pd,
    _mm256_set1_epi64x, _mm256_set1_pd, _mm256_set_epi64x, _mm256_setzero_pd, _mm256_storeu_pd, _CMP_UNORD_Q,
};

/// Slot (i0, i1)'s row as `K` vectors of four, times the slot's weight, added to `acc`; `row0`
/// is where the slot row's first slot's row starts (a row of rules is `N` values a rule, so
/// the slots of a slot row lie at constant offsets from it).
///
/// # Safety
/// AVX2, and the row's `4·K` values lie inside `q` ([`super::sums`] checks the last slot's).
#[inline]
#[target_feature(enable = "avx2")]
unsafe fn add_slot<const N: usize, const K: usize>(
    acc: &mut [__m256d; K],
    row0: *const f64,
    v: &GridView,
    i0: usize,
    i1: usize,
) {
    let w = _mm256_broadcast_sd(&v.weight[i0][i1]);
    // SAFETY: the caller's bound (a slot row's slots are consecutive rules).
    let row = unsafe { row0.add(i1 * N) };
    for (k, a) in acc.iter_mut().enumerate() {
        // SAFETY: as above.
        let r = unsafe { _mm256_loadu_pd(row.add(4 * k)) };
        *a = _mm256_add_pd(*a, _mm256_mul_pd(w, r));
    }
}

/// [`super::sums`]'s two interleaved partial sums over the grid for three or four actions, added
/// at the end, written into `out[..4]` (the fourth lane scratch for three actions); whether one
/// of the `N` is NaN.
///
/// Sum x takes the slots at even positions j = i0·len₁ + i1 of the sparse list, y the odd ones:
/// in even slot rows the even columns go to x, in odd ones too unless len₁ is odd, when each
/// pair of columns trades places (a bit blend of the two products, off the sums' chains of
/// additions).
///
/// # Safety
/// AVX2, and `v.last_at() + 4 ≤ q.len()`.
#[inline]
#[target_feature(enable = "avx2")]
pub(super) unsafe fn pair_sums<const N: usize>(q: &[f64], v: &GridView, out: &mut [f64; 4]) -> bool {
    const { assert!(GRID == 4) };
    let q = q.as_ptr();
    let (mut x, mut y) = (_mm256_setzero_pd(), _mm256_setzero_pd());
    let swap = _mm256_castsi256_pd(_mm256_set1_epi64x(v.swap as i64));
    // The slot rows past variable 0's window weigh 0: skipped, which shortens the sums' chains.
    for i0 in 0..(v.len[0] as usize).min(GRID) {
        // SAFETY: the caller's bound (a slot row's slots are consecutive rules).
        let row0 = unsafe { q.add(v.row[i0] as usize) };
        // SAFETY: as above.
        let term = |i1: usize| unsafe {
            _mm256_mul_pd(_mm256_broadcast_sd(&v.weight[i0][i1]), _mm256_loadu_pd(row0.add(i1 * N)))
        };
        for i1 in (0..GRID).step_by(2) {
            let (a, b) = (term(i1), term(i1 + 1));
            let (a, b) = if i0 % 2 == 1 {
                (_mm256_blendv_pd(a, b, swap), _mm256_blendv_pd(b, a, swap))
            } else {
                (a, b)
            };
            x = _mm256_add_pd(x, a);
            y = _mm256_add_pd(y, b);
        }
    }
    let s = _mm256_add_pd(x, y);
    // SAFETY: `out` holds four values.
    unsafe { _mm256_storeu_pd(out.as_mut_ptr(), s) };
    nan_in::<N>(s, 0)
}

/// Whether one of lanes `4·k ..` of `s` that hold actions (below `N`) is NaN.
#[inline]
#[target_feature(enable = "avx2")]
fn nan_in<const N: usize>(s: __m256d, k: usize) -> bool {
    let lanes = N.saturating_sub(4 * k).min(4);
    (_mm256_movemask_pd(_mm256_cmp_pd::<_CMP_UNORD_Q>(s, s)) & ((1 << lanes) - 1)) != 0
}

/// [`super::sums`]'s one sum per action over the grid's slots in order, rows read as `K` vectors
/// of four (five to sixteen actions), written into `out[..4·K]`; whether one of the `N` is NaN.
///
/// # Safety
/// AVX2, `out` holds `4·K` values, and `v.last_at() + 4·K ≤ q.len()`.
#[inline]
#[target_feature(enable = "avx2")]
pub(super) unsafe fn sum<const N: usize, const K: usize>(q: &[f64], v: &GridView, out: &mut [f64]) -> bool {
    debug_assert!(out.len() >= 4 * K);
    let q = q.as_ptr();
    let mut acc = [_mm256_setzero_pd(); K];
    // The slot rows past variable 0's window weigh 0: skipped, which shortens the sum's chain.
    for i0 in 0..(v.len[0] as usize).min(GRID) {
        // SAFETY: the caller's bound.
        let row0 = unsafe { q.add(v.row[i0] as usize) };
        for i1 in 0..GRID {
            // SAFETY: the caller's bound.
            unsafe { add_slot::<N, K>(&mut acc, row0, v, i0, i1) };
        }
    }
    let mut nan = false;
    for (k, a) in acc.iter().enumerate() {
        // SAFETY: the caller's bound on `out`.
        unsafe { _mm256_storeu_pd(out.as_mut_ptr().add(4 * k), *a) };
        nan |= nan_in::<N>(*a, k);
    }
    nan
}

/// Lane `action mod 4` of four: all ones there, zeros elsewhere.
#[inline]
#[target_feature(enable = "avx2")]
fn lane_mask(action: usize) -> __m256d {
    let lanes = _mm256_set_epi64x(3, 2, 1, 0);
    _mm256_castsi256_pd(_mm256_cmpeq_epi64(_mm256_set1_epi64x((action % 4) as i64), lanes))
}

/// For each slot of the windows' slot rows (past variable 0's window they weigh 0), `x[at + a]`
/// ← `f(x[at + a], s·w)` for the action's lane a and `f(x, +0)` for the three lanes beside it in
/// its vector of four: a row's vector read and written whole, so that the next whole-vector read
/// of it takes the value from the store (a read that spans a narrower store waits for it).
///
/// # Safety
/// AVX2, and `v.last_at() + 4·⌊action / 4⌋ + 4 ≤ x.len()`.
#[inline]
#[target_feature(enable = "avx2")]
unsafe fn each_slot_row(
    x: &mut [f64],
    v: &GridView,
    action: usize,
    s: f64,
    f: impl Fn(__m256d, __m256d) -> __m256d,
) {
    let (mask, at) = (lane_mask(action), action / 4 * 4);
    let s = _mm256_set1_pd(s);
    let x = x.as_mut_ptr();
    for i0 in 0..(v.len[0] as usize).min(GRID) {
        for i1 in 0..GRID {
            let w = _mm256_and_pd(_mm256_mul_pd(s, _mm256_broadcast_sd(&v.weight[i0][i1])), mask);
            // SAFETY: the caller's bound.
            unsafe {
                let p = x.add(v.at(i0, i1) + at);
                _mm256_storeu_pd(p, f(_mm256_loadu_pd(p), w));
            }
        }
    }
}

/// The traces' extension of a grid update: e + w (`replacing`: max(e, w)) in the action's
/// lane, e + 0 = e (max(e, 0) = e: traces are never negative) beside it. The weight is taken
/// as 1·w, which is w.
///
/// # Safety
/// As [`each_slot_row`]'s.
#[inline]
#[target_feature(enable = "avx2")]
pub(super) unsafe fn extend_traces(e: &mut [f64], v: &GridView, action: usize, replacing: bool) {
    // SAFETY: the caller's.
    unsafe {
        if replacing {
            each_slot_row(e, v, action, 1.0, |e, w| _mm256_max_pd(e, w));
        } else {
            each_slot_row(e, v, action, 1.0, |e, w| _mm256_add_pd(e, w));
        }
    }
}

/// The Q(0) update of a grid: q + step·w in the action's lane, q + 0 beside it (exact, up to a
/// zero's sign, which no sum sees).
///
/// # Safety
/// As [`each_slot_row`]'s.
#[inline]
#[target_feature(enable = "avx2")]
pub(super) unsafe fn q0_update(q: &mut [f64], v: &GridView, action: usize, step: f64) {
    // SAFETY: the caller's.
    unsafe { each_slot_row(q, v, action, step, |q, w| _mm256_add_pd(q, w)) };
}
