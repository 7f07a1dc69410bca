//! The engine's own transcendental functions: `sin`, `cos`, `sin_cos` and `exp`, computed from
//! IEEE-754 binary64 additions, multiplications, comparisons and bit operations only, so that a
//! trial's outcome is the same on every IEEE-754 platform (x86-64 with or without FMA/AVX,
//! aarch64), whatever its C library. Rust never contracts `a * b + c` into a fused multiply-add and
//! never reassociates floating-point expressions, so each function below is one fixed sequence of
//! correctly rounded operations. (The platform's `sin`/`cos`/`exp` pick code paths at run time by
//! CPU feature, e.g. glibc's FMA variants, and their last bits differ between paths.)
//!
//! `sin`/`cos` are fdlibm's (as musl has them): its minimax kernels on [−π/4, π/4] (which take
//! Cart-Pole's pole angle and Ball-Beam's tilt without any reduction; `sin_cos` shares one call)
//! and its three-stage Cody–Waite reduction by π/2 for |x| < 2²⁰·π/2 (Mountain Car's 3x), written
//! out here so that the hot cases inline. On the kernel range they return musl's values bit for
//! bit; above it musl takes special reductions for |x| ≤ 9π/4 that pick another multiple of π/2
//! in narrow bands just above 3π/4, 5π/4, 7π/4 and 9π/4 (and one stage fewer within about 2⁻¹⁶
//! of multiples of π/2), where the last bit can differ from musl's; both stay below 1 ulp (tested
//! against the reference). Larger arguments, which no system reaches in practice, call the
//! `libm` crate's (musl's) Payne–Hanek reduction, itself plain arithmetic.
//!
//! [`cos_lanes`] and [`sin_cos_lanes`] compute them for several values at once (the systems of
//! trials in lockstep, `crate::lanes`): the common cases for every lane without branches, with
//! the operations of the scalar functions lane by lane, so the same bits.
//!
//! `exp` reduces x = (32m + j)·ln2/32 + r with |r| ≤ ln2/64, evaluates e^r − 1 by its degree-6
//! Taylor polynomial (truncation error < 4·10⁻¹⁸, evaluated in Estrin's order) and multiplies by
//! a table of 2^(j/32) held to double-double precision, so a normal result is within about half
//! an ulp of the truth; a result just above or in the subnormal range (x < −707.7) is rounded twice
//! and can be off by up to about 0.75 ulp.
//! [`exp_lanes`] computes it for several values at once (the fuzzy memberships of a window) with
//! the same operations in each lane, so the same bits.
//!
//! Worst errors against a 420-digit reference (`tests/fixtures/math/reference.csv` in this crate, made by
//! `scripts/math_reference.py`; the test `errors_against_the_high_precision_reference` measures
//! them): see [`MAX_ULPS`].
//!
//! `ln` is only used while building a representation (the fuzzy window's half-width), never per
//! step; it is the `libm` crate's (musl's) `log`.

/// Largest error, in ulps of the correctly rounded result, that the reference test allows; the
/// measured worst cases are below these (sin 0.719, cos 0.714, exp 0.542 on the 12,844 reference
/// inputs; `cargo test --lib math -- --nocapture` prints them).
pub const MAX_ULPS: [(&str, f64); 3] = [("sin", 1.0), ("cos", 1.0), ("exp", 1.0)];

// fdlibm's kernel coefficients (|x| ≤ π/4): sin x ≈ x + S1x³ + … + S6x¹³, cos x ≈ 1 − x²/2 + C1x⁴ + ….
const S1: f64 = f64::from_bits(0xbfc5_5555_5555_5549); // -0.16666666666666632
const S2: f64 = f64::from_bits(0x3f81_1111_1110_f8a6); // 0.00833333333332249
const S3: f64 = f64::from_bits(0xbf2a_01a0_19c1_61d5); // -0.0001984126982985795
const S4: f64 = f64::from_bits(0x3ec7_1de3_57b1_fe7d); // 2.7557313707070068e-06
const S5: f64 = f64::from_bits(0xbe5a_e5e6_8a2b_9ceb); // -2.5050760253406863e-08
const S6: f64 = f64::from_bits(0x3de5_d93a_5acf_d57c); // 1.58969099521155e-10
const C1: f64 = f64::from_bits(0x3fa5_5555_5555_554c); // 0.0416666666666666
const C2: f64 = f64::from_bits(0xbf56_c16c_16c1_5177); // -0.001388888888887411
const C3: f64 = f64::from_bits(0x3efa_01a0_19cb_1590); // 2.480158728947673e-05
const C4: f64 = f64::from_bits(0xbe92_7e4f_809c_52ad); // -2.7557314351390663e-07
const C5: f64 = f64::from_bits(0x3e21_ee9e_bdb4_b1c4); // 2.087572321298175e-09
const C6: f64 = f64::from_bits(0xbda8_fae9_be88_38d4); // -1.1359647557788195e-11

// π/2 in pieces for the reduction: PIO2_1 has 33 bits, so n·PIO2_1 is exact for |n| < 2²⁰.
const INV_PIO2: f64 = f64::from_bits(0x3fe4_5f30_6dc9_c883); // 0.6366197723675814
const PIO2_1: f64 = f64::from_bits(0x3ff9_21fb_5440_0000); // 1.5707963267341256
const PIO2_1T: f64 = f64::from_bits(0x3dd0_b461_1a62_6331); // 6.077100506506192e-11
const PIO2_2: f64 = f64::from_bits(0x3dd0_b461_1a60_0000); // 6.077100506303966e-11
const PIO2_2T: f64 = f64::from_bits(0x3ba3_198a_2e03_7073); // 2.0222662487959506e-21
const PIO2_3: f64 = f64::from_bits(0x3ba3_198a_2e00_0000); // 2.0222662487111665e-21
const PIO2_3T: f64 = f64::from_bits(0x397b_839a_2520_49c1); // 8.4784276603689e-32
/// Adding and subtracting 1.5·2⁵² rounds a float of magnitude < 2⁵¹ to the nearest integer.
const TO_INT: f64 = 6_755_399_441_055_744.0;
/// Below this magnitude the kernels take x as it is (fdlibm's bound, just above π/4).
const KERNEL_MAX: f64 = f64::from_bits(0x3fe9_21fc_0000_0000); // 0.7853984832763672
/// Below this magnitude sin x rounds to x and cos x to 1 (2⁻²⁶, fdlibm's bound).
const TINY: f64 = f64::from_bits(0x3e50_0000_0000_0000); // 1.4901161193847656e-08
/// Below this magnitude the Cody–Waite reduction is exact enough (2²⁰·π/2).
const MEDIUM_MAX: f64 = f64::from_bits(0x4139_21fb_0000_0000); // 1647099.0

/// fdlibm's `__kernel_sin(x, y, iy)`: sin(x + y) for |x + y| ≤ π/4, y the tail of a reduced
/// argument (`tail == false`: y = 0).
#[inline(always)]
fn k_sin(x: f64, y: f64, tail: bool) -> f64 {
    let z = x * x;
    let w = z * z;
    let r = S2 + z * (S3 + z * S4) + z * w * (S5 + z * S6);
    let v = z * x;
    if tail {
        x - ((z * (0.5 * y - v * r) - y) - v * S1)
    } else {
        x + v * (S1 + z * r)
    }
}

/// fdlibm's `__kernel_cos(x, y)`: cos(x + y) for |x + y| ≤ π/4.
#[inline(always)]
fn k_cos(x: f64, y: f64) -> f64 {
    let z = x * x;
    let w = z * z;
    let r = z * (C1 + z * (C2 + z * C3)) + w * w * (C4 + z * (C5 + z * C6));
    let hz = 0.5 * z;
    let w = 1.0 - hz;
    w + (((1.0 - w) - hz) + (z * r - x * y))
}

/// x = n·π/2 + (y0 + y1) with |y0 + y1| ≤ π/4 (about), for finite |x| < [`MEDIUM_MAX`]: fdlibm's
/// medium case, a second and third stage taken only when the first cancels too many bits.
#[inline(always)]
fn rem_pio2_medium(x: f64) -> (i32, f64, f64) {
    let f_n = (x * INV_PIO2 + TO_INT) - TO_INT;
    let n = f_n as i32;
    let mut r = x - f_n * PIO2_1;
    let mut w = f_n * PIO2_1T;
    let mut y0 = r - w;
    let exponent = |v: f64| ((v.to_bits() >> 52) & 0x7ff) as i32;
    let ex = exponent(x);
    if ex - exponent(y0) > 16 {
        let t = r;
        w = f_n * PIO2_2;
        r = t - w;
        w = f_n * PIO2_2T - ((t - r) - w);
        y0 = r - w;
        if ex - exponent(y0) > 49 {
            let t = r;
            w = f_n * PIO2_3;
            r = t - w;
            w = f_n * PIO2_3T - ((t - r) - w);
            y0 = r - w;
        }
    }
    (n, y0, (r - y0) - w)
}

/// sin x.
#[inline]
pub fn sin(x: f64) -> f64 {
    let a = x.abs();
    if a < KERNEL_MAX {
        // The kernel would give +0 for −0; below 2⁻²⁶ sin x rounds to x anyway.
        return if a < TINY { x } else { k_sin(x, 0.0, false) };
    }
    if a < MEDIUM_MAX {
        let (n, y0, y1) = rem_pio2_medium(x);
        return match n & 3 {
            0 => k_sin(y0, y1, true),
            1 => k_cos(y0, y1),
            2 => -k_sin(y0, y1, true),
            _ => -k_cos(y0, y1),
        };
    }
    if x.is_finite() {
        libm::sin(x)
    } else {
        f64::NAN
    }
}

/// cos x.
#[inline]
pub fn cos(x: f64) -> f64 {
    let a = x.abs();
    if a < KERNEL_MAX {
        return k_cos(x, 0.0);
    }
    if a < MEDIUM_MAX {
        let (n, y0, y1) = rem_pio2_medium(x);
        return match n & 3 {
            0 => k_cos(y0, y1),
            1 => -k_sin(y0, y1, true),
            2 => -k_cos(y0, y1),
            _ => k_sin(y0, y1, true),
        };
    }
    if x.is_finite() {
        libm::cos(x)
    } else {
        f64::NAN
    }
}

/// [`cos`] of each of `N` values, the same bits lane by lane. The common cases, the kernel
/// range and a one-stage reduction by π/2, are computed for every lane together without branches
/// (both kernels, then a choice by the quadrant), so that they run as vector instructions when
/// several trials step at once (`crate::lanes`); a lane outside them is recomputed by [`cos`].
#[inline(always)]
pub fn cos_lanes<const N: usize>(x: [f64; N]) -> [f64; N] {
    let exponent = |v: f64| ((v.to_bits() >> 52) & 0x7ff) as i32;
    let (mut y0, mut y1, mut n, mut slow) = ([0.0; N], [0.0; N], [0i32; N], [false; N]);
    for k in 0..N {
        let x = x[k];
        let a = x.abs();
        // rem_pio2_medium's first stage, as there.
        let f_n = (x * INV_PIO2 + TO_INT) - TO_INT;
        let r = x - f_n * PIO2_1;
        let w = f_n * PIO2_1T;
        let m0 = r - w;
        let small = a < KERNEL_MAX;
        slow[k] = !(small || (a < MEDIUM_MAX && exponent(x) - exponent(m0) <= 16));
        // In the kernel range cos takes k_cos(x, 0), which is quadrant 0 with (y0, y1) = (x, 0).
        y0[k] = if small { x } else { m0 };
        y1[k] = if small { 0.0 } else { (r - m0) - w };
        n[k] = if small { 0 } else { f_n as i32 };
    }
    let mut out = [0.0; N];
    for k in 0..N {
        let c = k_cos(y0[k], y1[k]);
        let s = k_sin(y0[k], y1[k], true);
        // Quadrants 0, 1, 2, 3: c, −s, −c, s (a sign flip is exact).
        let quadrant = n[k] & 3;
        let v = if quadrant & 1 == 0 { c } else { s };
        out[k] = if quadrant == 1 || quadrant == 2 { -v } else { v };
    }
    for k in 0..N {
        if slow[k] {
            out[k] = cos(x[k]);
        }
    }
    out
}

/// [`sin_cos`] of each of `N` values, the same bits lane by lane: the kernel range (Cart-Pole's
/// pole angle, Ball-Beam's tilt) for every lane together without branches, a lane outside it
/// recomputed by [`sin_cos`].
#[inline(always)]
pub fn sin_cos_lanes<const N: usize>(x: [f64; N]) -> ([f64; N], [f64; N]) {
    let (mut sin, mut cos) = ([0.0; N], [0.0; N]);
    for k in 0..N {
        let s = k_sin(x[k], 0.0, false);
        sin[k] = if x[k].abs() < TINY { x[k] } else { s };
        cos[k] = k_cos(x[k], 0.0);
    }
    for k in 0..N {
        // NaN is not in the kernel range either.
        let kernel = x[k].abs() < KERNEL_MAX;
        if !kernel {
            (sin[k], cos[k]) = sin_cos(x[k]);
        }
    }
    (sin, cos)
}

/// (sin x, cos x), each exactly what [`sin`] and [`cos`] return.
#[inline]
pub fn sin_cos(x: f64) -> (f64, f64) {
    let a = x.abs();
    if a < KERNEL_MAX {
        return (if a < TINY { x } else { k_sin(x, 0.0, false) }, k_cos(x, 0.0));
    }
    (sin(x), cos(x))
}

// exp: 2^(j/32), j = 0..31, as (hi, lo): hi = 2^(j/32) rounded, lo = the rest rounded.
// Generated by scripts/math_reference.py tables (Python decimal, 420 digits).
const EXP2_J32: [(f64, f64); 32] = [
    (f64::from_bits(0x3ff0000000000000), f64::from_bits(0x0000000000000000)),
    (f64::from_bits(0x3ff059b0d3158574), f64::from_bits(0x3c8d73e2a475b465)),
    (f64::from_bits(0x3ff0b5586cf9890f), f64::from_bits(0x3c98a62e4adc610b)),
    (f64::from_bits(0x3ff11301d0125b51), f64::from_bits(0xbc96c51039449b3a)),
    (f64::from_bits(0x3ff172b83c7d517b), f64::from_bits(0xbc819041b9d78a76)),
    (f64::from_bits(0x3ff1d4873168b9aa), f64::from_bits(0x3c9e016e00a2643c)),
    (f64::from_bits(0x3ff2387a6e756238), f64::from_bits(0x3c99b07eb6c70573)),
    (f64::from_bits(0x3ff29e9df51fdee1), f64::from_bits(0x3c8612e8afad1255)),
    (f64::from_bits(0x3ff306fe0a31b715), f64::from_bits(0x3c86f46ad23182e4)),
    (f64::from_bits(0x3ff371a7373aa9cb), f64::from_bits(0xbc963aeabf42eae2)),
    (f64::from_bits(0x3ff3dea64c123422), f64::from_bits(0x3c8ada0911f09ebc)),
    (f64::from_bits(0x3ff44e086061892d), f64::from_bits(0x3c489b7a04ef80d0)),
    (f64::from_bits(0x3ff4bfdad5362a27), f64::from_bits(0x3c7d4397afec42e2)),
    (f64::from_bits(0x3ff5342b569d4f82), f64::from_bits(0xbc807abe1db13cad)),
    (f64::from_bits(0x3ff5ab07dd485429), f64::from_bits(0x3c96324c054647ad)),
    (f64::from_bits(0x3ff6247eb03a5585), f64::from_bits(0xbc9383c17e40b497)),
    (f64::from_bits(0x3ff6a09e667f3bcd), f64::from_bits(0xbc9bdd3413b26456)),
    (f64::from_bits(0x3ff71f75e8ec5f74), f64::from_bits(0xbc816e4786887a99)),
    (f64::from_bits(0x3ff7a11473eb0187), f64::from_bits(0xbc841577ee04992f)),
    (f64::from_bits(0x3ff82589994cce13), f64::from_bits(0xbc9d4c1dd41532d8)),
    (f64::from_bits(0x3ff8ace5422aa0db), f64::from_bits(0x3c96e9f156864b27)),
    (f64::from_bits(0x3ff93737b0cdc5e5), f64::from_bits(0xbc675fc781b57ebc)),
    (f64::from_bits(0x3ff9c49182a3f090), f64::from_bits(0x3c7c7c46b071f2be)),
    (f64::from_bits(0x3ffa5503b23e255d), f64::from_bits(0xbc9d2f6edb8d41e1)),
    (f64::from_bits(0x3ffae89f995ad3ad), f64::from_bits(0x3c97a1cd345dcc81)),
    (f64::from_bits(0x3ffb7f76f2fb5e47), f64::from_bits(0xbc75584f7e54ac3b)),
    (f64::from_bits(0x3ffc199bdd85529c), f64::from_bits(0x3c811065895048dd)),
    (f64::from_bits(0x3ffcb720dcef9069), f64::from_bits(0x3c7503cbd1e949db)),
    (f64::from_bits(0x3ffd5818dcfba487), f64::from_bits(0x3c82ed02d75b3707)),
    (f64::from_bits(0x3ffdfc97337b9b5f), f64::from_bits(0xbc91a5cd4f184b5c)),
    (f64::from_bits(0x3ffea4afa2a490da), f64::from_bits(0xbc9e9c23179c2893)),
    (f64::from_bits(0x3fff50765b6e4540), f64::from_bits(0x3c99d3e12dd8a18b)),
];
/// 32/ln 2.
const INV_LN2_32: f64 = f64::from_bits(0x4047_1547_652b_82fe);
/// ln2/32 with its low 32 significand bits cleared, so k·LN2_32_HI is exact for |k| < 2³².
const LN2_32_HI: f64 = f64::from_bits(0x3f96_2e42_0000_0000);
/// ln2/32 − LN2_32_HI.
const LN2_32_LO: f64 = f64::from_bits(0x3e4f_df47_3de6_af28);
/// Above this, e^x overflows (ln of the largest finite float).
const EXP_OVERFLOW: f64 = f64::from_bits(0x4086_2e42_fefa_39ef); // 709.782712893384
/// Below this, e^x rounds to 0 (ln of half the least subnormal).
const EXP_UNDERFLOW: f64 = f64::from_bits(0xc087_4910_d52d_3052); // -745.1332191019412

/// 2^m as a float, for −1022 ≤ m ≤ 1023.
#[inline(always)]
fn pow2(m: i64) -> f64 {
    f64::from_bits(((1023 + m) as u64) << 52)
}

/// e^x.
#[inline]
pub fn exp(x: f64) -> f64 {
    if x.is_nan() {
        return x;
    }
    if x > EXP_OVERFLOW {
        return f64::INFINITY;
    }
    if x < EXP_UNDERFLOW {
        return 0.0;
    }
    let (v, m) = exp_parts(x);
    if m > 1023 {
        (v * 2.0) * pow2(m - 1)
    } else if m >= -1022 {
        v * pow2(m)
    } else {
        // Subnormal result: the first product is exact, so only the second one rounds.
        (v * pow2(m + 1000)) * pow2(-1000)
    }
}

/// e^x = v · 2^m for a finite x in exp's range: v = 2^(j/32)·e^r, m = ⌊k/32⌋.
#[inline(always)]
fn exp_parts(x: f64) -> (f64, i64) {
    let (k, p) = exp_reduce(x);
    (exp_table(k, p), k >> 5)
}

/// x = k·ln2/32 + r: k, and e^r − 1.
#[inline(always)]
fn exp_reduce(x: f64) -> (i64, f64) {
    // k = round(x·32/ln2): adding 1.5·2⁵² rounds it into the low bits of the sum's significand.
    let shifted = x * INV_LN2_32 + TO_INT;
    let k = (shifted.to_bits() as i64).wrapping_sub(TO_INT.to_bits() as i64);
    let kd = shifted - TO_INT;
    let r = (x - kd * LN2_32_HI) - kd * LN2_32_LO;
    // e^r − 1 = r + r²(1/2 + r/6 + …): the high powers in parallel with the low ones (Estrin).
    let r2 = r * r;
    (k, r + r2 * ((0.5 + r * (1.0 / 6.0)) + r2 * ((1.0 / 24.0 + r * (1.0 / 120.0)) + r2 * (1.0 / 720.0))))
}

/// 2^(j/32)·(1 + p) for j = k mod 32, from the table held to double-double precision.
#[inline(always)]
fn exp_table(k: i64, p: f64) -> f64 {
    let (hi, lo) = EXP2_J32[(k & 31) as usize];
    hi + (hi * p + lo)
}

/// Where [`exp_lanes`] takes its branch-free path: e^x is a normal float (−1022 ≤ m ≤ 1023 in
/// [`exp_parts`]) for every x in [−EXP_LANE_BOUND, EXP_LANE_BOUND].
const EXP_LANE_BOUND: f64 = 700.0;

/// [`exp`] of every element, bit for bit: when all of them lie within ±700 (as fuzzy memberships'
/// arguments do), one branch-free pass that the compiler can run as vector lanes; otherwise
/// element by element.
#[inline(always)]
pub fn exp_lanes<const N: usize>(x: &mut [f64; N]) {
    // A NaN fails both comparisons and takes the element-by-element path.
    if x.iter().all(|&v| (-EXP_LANE_BOUND..=EXP_LANE_BOUND).contains(&v)) {
        // exp_parts in two loops over the lanes: the arithmetic of the first is the same in
        // every lane (vector code); only the second's table lookup is lane by lane.
        let (mut k, mut p) = ([0i64; N], [0.0f64; N]);
        for i in 0..N {
            (k[i], p[i]) = exp_reduce(x[i]);
        }
        for i in 0..N {
            x[i] = exp_table(k[i], p[i]) * pow2(k[i] >> 5);
        }
    } else {
        for v in x.iter_mut() {
            *v = exp(*v);
        }
    }
}

/// ln x (setup only: musl's `log`, via the `libm` crate).
pub fn ln(x: f64) -> f64 {
    libm::log(x)
}

#[cfg(test)]
mod tests;

#[cfg(target_arch = "x86_64")]
pub(crate) mod x86;

/// `y` truncated toward zero, for `y` within ±2⁶³; outside that, and for NaN, either i64::MIN
/// (x86-64's `cvttsd2si`, one instruction) or the saturated value (`as`, elsewhere), so a caller
/// must give both the same meaning.
#[inline(always)]
pub(crate) fn trunc_i64(y: f64) -> i64 {
    #[cfg(target_arch = "x86_64")]
    return x86::trunc_i64(y);
    #[cfg(not(target_arch = "x86_64"))]
    return y as i64;
}
