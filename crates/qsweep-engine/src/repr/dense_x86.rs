//! The grid form's memberships ([`super::dense`]) in AVX2 vectors, for the vector levels that
//! have them: the same operations in the same order, lane by lane, as the portable code (the
//! exponentials by [`math::x86::exp4`], the bits of `exp`), so the same bits. Left to the
//! compiler, the portable code's masks and table lookups cost about three times the instructions.

use super::activation::GRID;
use super::fuzzy::Variable;
use crate::math;
use std::arch::x86_64::{
    _mm256_and_pd, _mm256_castsi256_pd, _mm256_cmpgt_epi64, _mm256_loadu_pd, _mm256_mul_pd,
    _mm256_set1_epi64x, _mm256_set1_pd, _mm256_set_epi64x, _mm256_storeu_pd, _mm256_sub_pd, _mm256_xor_pd,
};

/// Variable `v`'s normalised memberships at `value` into `mid` (the [`GRID`] lanes of its window,
/// 0 past its length), and its window (first set, length): the portable `DenseFuzzy::memberships`
/// for a variable of several sets.
///
/// Not compiled for AVX2 itself (a function that is cannot be inlined without fail): inlined into
/// a caller that is, its intrinsics are too.
///
/// # Safety
/// AVX2, and `centres` holds `v`'s centres and [`GRID`] − 1 more.
#[inline(always)]
pub(super) unsafe fn memberships(
    v: &Variable,
    centres: &[f64],
    value: f64,
    mid: &mut [f64; GRID],
) -> (usize, usize) {
    const { assert!(GRID == 4) };
    let (x, pos, first, last) = v.window(value);
    let len = last + 1 - first;
    debug_assert!(len <= GRID && first + GRID <= centres.len());
    // Lane k is inside the window when k < len: all ones or zeros.
    let mask = _mm256_castsi256_pd(_mm256_cmpgt_epi64(
        _mm256_set1_epi64x(len as i64),
        _mm256_set_epi64x(3, 2, 1, 0),
    ));
    // SAFETY: first + GRID ≤ centres.len() (the caller's padding; first < n).
    let c = unsafe { _mm256_loadu_pd(centres.as_ptr().add(first)) };
    let d = _mm256_sub_pd(_mm256_set1_pd(x), c);
    // −(d·d)·(1/2σ²), the negation a flip of the sign bit as `-` is; +0 outside the window.
    let neg = _mm256_xor_pd(_mm256_mul_pd(d, d), _mm256_set1_pd(-0.0));
    let raw = _mm256_and_pd(_mm256_mul_pd(neg, _mm256_set1_pd(v.inv_two_sigma_sq)), mask);
    // SAFETY: AVX2 (this function's); −d²·(1/2σ²) is never above 0.
    let e = if unsafe { math::x86::exp4_applies_at_most_zero(raw) } {
        unsafe { math::x86::exp4(raw) }
    } else {
        let mut lanes = [0.0; GRID];
        // SAFETY: four values.
        unsafe { _mm256_storeu_pd(lanes.as_mut_ptr(), raw) };
        math::exp_lanes(&mut lanes);
        // SAFETY: four values.
        unsafe { _mm256_loadu_pd(lanes.as_ptr()) }
    };
    let e = _mm256_and_pd(e, mask);
    let mut lanes = [0.0; GRID];
    // SAFETY: four values.
    unsafe { _mm256_storeu_pd(lanes.as_mut_ptr(), e) };
    // The normaliser in window order; the portable sum starts at +0, which adds nothing here (no
    // lane is −0: an exponential is +0 or more, a masked lane +0).
    let sum = lanes[0] + lanes[1] + lanes[2] + lanes[3];
    if sum.is_nan() || sum <= 0.0 {
        *mid = [1.0, 0.0, 0.0, 0.0];
        return (v.nearest(pos), 1);
    }
    // Masked after the product too: 0·(1/sum) is NaN when the sum is subnormal.
    let mu = _mm256_and_pd(_mm256_mul_pd(e, _mm256_set1_pd(1.0 / sum)), mask);
    // SAFETY: `mid` is four values.
    unsafe { _mm256_storeu_pd(mid.as_mut_ptr(), mu) };
    (first, len)
}
