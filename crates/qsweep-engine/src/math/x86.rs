//! [`exp_lanes`](super::exp_lanes)'s branch-free pass for four lanes in AVX2 vectors: the same
//! operations in the same order as [`exp_reduce`](super::exp_reduce), `exp_table` and `pow2`, lane
//! by lane (no fused multiply-add), with the table read by one gather per column, so the same bits.

use super::{EXP2_J32, EXP_LANE_BOUND, INV_LN2_32, LN2_32_HI, LN2_32_LO, TO_INT};
use std::arch::x86_64::{
    __m256d, _mm256_add_epi64, _mm256_add_pd, _mm256_and_si256, _mm256_castpd_si256, _mm256_castsi256_pd,
    _mm256_cmp_pd, _mm256_i64gather_pd, _mm256_movemask_pd, _mm256_mul_pd, _mm256_set1_epi64x,
    _mm256_set1_pd, _mm256_slli_epi64, _mm256_srli_epi64, _mm256_sub_epi64, _mm256_sub_pd, _mm_cvttsd_si64,
    _mm_set_sd, _CMP_GE_OQ,
};

/// Whether every lane of `x` lies at or above −[`EXP_LANE_BOUND`] (NaN does not): where [`exp4`]
/// applies for lanes that are never above 0, as a membership's argument −d²/(2σ²) is (one
/// comparison, where the whole range ±[`EXP_LANE_BOUND`] takes two).
///
/// # Safety
/// AVX2.
#[inline]
#[target_feature(enable = "avx2")]
pub(crate) unsafe fn exp4_applies_at_most_zero(x: __m256d) -> bool {
    let lo = _mm256_cmp_pd::<_CMP_GE_OQ>(x, _mm256_set1_pd(-EXP_LANE_BOUND));
    _mm256_movemask_pd(lo) == 0b1111
}

/// `y` truncated toward zero by `cvttsd2si` (SSE2, which every x86-64 has): i64::MIN for NaN and
/// outside ±2⁶³, where `as` would saturate with a few more instructions.
#[inline(always)]
pub(crate) fn trunc_i64(y: f64) -> i64 {
    // SAFETY: SSE2 is part of x86-64.
    unsafe { _mm_cvttsd_si64(_mm_set_sd(y)) }
}

/// e^x in every lane, for lanes within ±[`EXP_LANE_BOUND`] ([`exp4_applies_at_most_zero`] for
/// lanes never above 0): the bits of
/// [`exp`](super::exp) lane by lane.
///
/// # Safety
/// AVX2.
#[inline]
#[target_feature(enable = "avx2")]
pub(crate) unsafe fn exp4(x: __m256d) -> __m256d {
    let to_int = _mm256_set1_pd(TO_INT);
    let shifted = _mm256_add_pd(_mm256_mul_pd(x, _mm256_set1_pd(INV_LN2_32)), to_int);
    let k = _mm256_sub_epi64(_mm256_castpd_si256(shifted), _mm256_castpd_si256(to_int));
    let kd = _mm256_sub_pd(shifted, to_int);
    let r = _mm256_sub_pd(
        _mm256_sub_pd(x, _mm256_mul_pd(kd, _mm256_set1_pd(LN2_32_HI))),
        _mm256_mul_pd(kd, _mm256_set1_pd(LN2_32_LO)),
    );
    let c = _mm256_set1_pd;
    let r2 = _mm256_mul_pd(r, r);
    // r + r2·((0.5 + r/6) + r2·((1/24 + r/120) + r2/720)), as exp_reduce groups it.
    let inner = _mm256_add_pd(
        _mm256_add_pd(c(1.0 / 24.0), _mm256_mul_pd(r, c(1.0 / 120.0))),
        _mm256_mul_pd(r2, c(1.0 / 720.0)),
    );
    let outer =
        _mm256_add_pd(_mm256_add_pd(c(0.5), _mm256_mul_pd(r, c(1.0 / 6.0))), _mm256_mul_pd(r2, inner));
    let p = _mm256_add_pd(r, _mm256_mul_pd(r2, outer));
    // The table's (hi, lo) pairs as 64 values: hi at 2j, lo at 2j + 1.
    let j2 = _mm256_slli_epi64::<1>(_mm256_and_si256(k, _mm256_set1_epi64x(31)));
    let table = EXP2_J32.as_ptr() as *const f64;
    // SAFETY: 2j + 1 < 64, inside the table.
    let (hi, lo) =
        unsafe { (_mm256_i64gather_pd::<8>(table, j2), _mm256_i64gather_pd::<8>(table.add(1), j2)) };
    let v = _mm256_add_pd(hi, _mm256_add_pd(_mm256_mul_pd(hi, p), lo));
    // pow2(k >> 5): (1023 + ⌊k/32⌋) << 52, with ⌊k/32⌋ + 1023 = (k + 1023·32) >> 5 on the
    // non-negative k + 1023·32 (|k| ≤ 700·32/ln 2 < 1023·32), a logical shift.
    let m = _mm256_srli_epi64::<5>(_mm256_add_epi64(k, _mm256_set1_epi64x(1023 * 32)));
    _mm256_mul_pd(v, _mm256_castsi256_pd(_mm256_slli_epi64::<52>(m)))
}
