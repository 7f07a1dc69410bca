//! Tests of the engine's own sin, cos, exp and ln: errors against a high-precision reference
//! table, special values, musl's results, exp's monotonicity, and the lane forms against the scalar
//! functions, bit for bit, at every vector level.

use super::*;

/// Distance in ulps of `ours` from the exact value `reference + frac·ulp(reference)`.
fn ulps(ours: f64, reference: f64, frac: f64) -> f64 {
    if ours == reference && frac == 0.0 {
        return 0.0;
    }
    let ulp = {
        let a = reference.abs();
        if a == 0.0 {
            f64::from_bits(1)
        } else {
            f64::from_bits(a.to_bits() + 1) - a
        }
    };
    ((ours - reference) / ulp - frac).abs()
}

fn reference() -> Vec<(String, f64, f64, f64)> {
    let text = include_str!("../../tests/fixtures/math/reference.csv");
    let bits = |s: &str| f64::from_bits(u64::from_str_radix(s, 16).expect("hex bits"));
    text.lines()
        .skip(1)
        .map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            (f[0].to_string(), bits(f[1]), bits(f[2]), f[3].parse().expect("frac"))
        })
        .collect()
}

#[test]
fn errors_against_the_high_precision_reference() {
    let rows = reference();
    assert!(rows.len() > 10_000, "{} rows", rows.len());
    for (name, bound) in MAX_ULPS {
        let f: fn(f64) -> f64 = match name {
            "sin" => sin,
            "cos" => cos,
            _ => exp,
        };
        let mut worst = (0.0f64, 0.0f64);
        let mut n = 0;
        for (_, x, r, frac) in rows.iter().filter(|r| r.0 == name) {
            let e = ulps(f(*x), *r, *frac);
            if e > worst.0 {
                worst = (e, *x);
            }
            n += 1;
        }
        eprintln!("{name}: worst error {:.3} ulp at x = {:e} over {n} inputs", worst.0, worst.1);
        assert!(worst.0 <= bound, "{name}: {:.3} ulp at x = {:e} (bound {bound})", worst.0, worst.1);
    }
}

#[test]
fn sin_cos_is_sin_and_cos() {
    for (_, x, _, _) in reference().iter().filter(|r| r.0 == "sin") {
        let (s, c) = sin_cos(*x);
        assert_eq!((s.to_bits(), c.to_bits()), (sin(*x).to_bits(), cos(*x).to_bits()), "{x}");
    }
}

#[test]
fn special_values() {
    assert!(sin(f64::NAN).is_nan() && cos(f64::INFINITY).is_nan() && sin(f64::NEG_INFINITY).is_nan());
    assert_eq!(sin(0.0).to_bits(), 0.0f64.to_bits());
    assert_eq!(sin(-0.0).to_bits(), (-0.0f64).to_bits());
    assert_eq!(cos(0.0), 1.0);
    assert_eq!(exp(0.0), 1.0);
    assert_eq!(exp(f64::NEG_INFINITY), 0.0);
    assert_eq!(exp(f64::INFINITY), f64::INFINITY);
    assert!(exp(f64::NAN).is_nan());
    assert_eq!(exp(710.0), f64::INFINITY);
    assert_eq!(exp(-746.0), 0.0);
    assert_eq!(exp(-745.0), f64::from_bits(1) * 1.0, "exp(−745) is the least subnormal");
    assert!(exp(709.78) < f64::INFINITY && exp(709.78) > 1e308);
    assert_eq!(ln(1.0), 0.0);
    assert!((ln(1000.0) - 6.907_755_278_982_137).abs() < 1e-15);
}

/// Symmetries hold bit for bit, and the functions agree with the `libm` crate (musl, < 1 ulp)
/// within 2 ulps over a wide sweep that the reference file samples only sparsely.
#[test]
fn symmetries_and_agreement_with_musl() {
    let mut x = -40.0;
    while x < 40.0 {
        assert_eq!(sin(-x).to_bits(), (-sin(x)).to_bits(), "{x}");
        assert_eq!(cos(-x).to_bits(), cos(x).to_bits(), "{x}");
        for (ours, musl) in [(sin(x), libm::sin(x)), (cos(x), libm::cos(x))] {
            assert!(ulps(ours, musl, 0.0) <= 2.0, "{x}: {ours} vs {musl}");
        }
        let e = -x * 18.0;
        assert!(ulps(exp(e), libm::exp(e), 0.0) <= 2.0, "exp({e})");
        x += 0.000_731;
    }
}

/// On the kernel range (Cart-Pole's angle, Ball-Beam's tilt) sin and cos are musl's values bit
/// for bit; above it, where musl's small-argument reductions differ in narrow bands (math.rs's
/// module docs), within 1 ulp of musl's, including just above 3π/4 and 5π/4 where the two pick
/// different multiples of π/2.
#[test]
fn sin_and_cos_are_musls_on_the_kernel_range_and_within_an_ulp_above() {
    let mut inputs: Vec<f64> = reference().iter().map(|r| r.1).filter(|x| x.abs() < MEDIUM_MAX).collect();
    let mut x = -40.0;
    while x < 40.0 {
        inputs.push(x);
        x += 0.000_731;
    }
    for band in [0x4002_d97c_8000_0000u64, 0x400f_6a7a_8000_0000] {
        for d in 0..2000 {
            let x = f64::from_bits(band + d * 997);
            inputs.extend([x, -x]);
        }
    }
    for x in inputs {
        if x.abs() < KERNEL_MAX {
            assert_eq!(sin(x).to_bits(), libm::sin(x).to_bits(), "sin({x:e})");
            assert_eq!(cos(x).to_bits(), libm::cos(x).to_bits(), "cos({x:e})");
        } else {
            assert!(ulps(sin(x), libm::sin(x), 0.0) <= 1.0, "sin({x:e})");
            assert!(ulps(cos(x), libm::cos(x), 0.0) <= 1.0, "cos({x:e})");
        }
    }
}

#[test]
fn exp_is_monotone_on_the_membership_range() {
    let mut prev = 0.0;
    let mut x = -20.0;
    while x <= 0.0 {
        let e = exp(x);
        assert!(e >= prev, "exp({x}) = {e} < {prev}");
        prev = e;
        x += 1.0 / 1024.0 / 3.0;
    }
}

crate::simd::dispatch! {
    /// sin_cos_lanes over four lanes compiled at `simd`'s width.
    fn sin_cos_lanes_at => sin_cos_lanes_4(x: &mut [f64; 4], c: &mut [f64; 4])
}

#[inline(always)]
fn sin_cos_lanes_4(x: &mut [f64; 4], c: &mut [f64; 4]) {
    (*x, *c) = sin_cos_lanes(*x);
}

/// sin_cos_lanes is sin_cos (so sin and cos), bit for bit, lane by lane, at every level: over
/// the pole's and the beam's angles, at the kernel range's and the tiny range's edges, and
/// beyond them.
#[test]
fn sin_cos_lanes_gives_the_bits_of_sin_cos_at_every_level() {
    let mut inputs: Vec<f64> = (0..20_000).map(|i| -1.0 + f64::from(i) * 0.000_100_007).collect();
    for e in [KERNEL_MAX, TINY, MEDIUM_MAX] {
        for u in 0..4u64 {
            let v = f64::from_bits(e.to_bits() - 2 + u);
            inputs.extend([v, -v]);
        }
    }
    inputs.extend([0.0, -0.0, f64::NAN, f64::INFINITY, f64::NEG_INFINITY, 1e10, 5e-324, 3.0, -7.0]);
    while !inputs.len().is_multiple_of(4) {
        inputs.push(0.5);
    }
    for simd in crate::simd::Simd::available() {
        for chunk in inputs.chunks_exact(4) {
            let (mut s, mut c): ([f64; 4], [f64; 4]) = (chunk.try_into().unwrap(), [0.0; 4]);
            let input = s;
            sin_cos_lanes_at(simd, &mut s, &mut c);
            for k in 0..4 {
                let (ws, wc) = sin_cos(input[k]);
                assert_eq!(
                    (s[k].to_bits(), c[k].to_bits()),
                    (ws.to_bits(), wc.to_bits()),
                    "{simd:?}: {}",
                    input[k]
                );
                assert_eq!((ws.to_bits(), wc.to_bits()), (sin(input[k]).to_bits(), cos(input[k]).to_bits()));
            }
        }
    }
}

crate::simd::dispatch! {
    /// cos_lanes over four lanes compiled at `simd`'s width.
    fn cos_lanes_at => cos_lanes_4(x: &mut [f64; 4])
}

#[inline(always)]
fn cos_lanes_4(x: &mut [f64; 4]) {
    *x = cos_lanes(*x);
}

/// cos_lanes is cos, bit for bit, lane by lane, at every vector level: across Mountain Car's
/// range of 3x and beyond, at the kernel range's edge, near multiples of π/2 (where cos takes
/// a second reduction stage), and for values that only cos's slow paths take.
#[test]
fn cos_lanes_gives_the_bits_of_cos_at_every_level() {
    let mut inputs: Vec<f64> = (0..40_000).map(|i| -8.0 + f64::from(i) * 0.000_400_013).collect();
    for m in -6..=6 {
        let c = f64::from(m) * std::f64::consts::FRAC_PI_2;
        for d in [0.0, 1e-300, 1e-17, 1e-12, 2e-6, 1.5e-5, 3e-5, 1e-3] {
            inputs.extend([
                c + d,
                c - d,
                f64::from_bits(c.to_bits() + 1),
                f64::from_bits(c.to_bits().wrapping_sub(1)),
            ]);
        }
    }
    for e in [KERNEL_MAX, std::f64::consts::FRAC_PI_4, TINY, MEDIUM_MAX] {
        for u in 0..4u64 {
            let v = f64::from_bits(e.to_bits() - 2 + u);
            inputs.extend([v, -v]);
        }
    }
    inputs.extend([0.0, -0.0, f64::NAN, f64::INFINITY, f64::NEG_INFINITY, 1e10, -3e7, 5e-324]);
    while !inputs.len().is_multiple_of(4) {
        inputs.push(1.0);
    }
    for simd in crate::simd::Simd::available() {
        for chunk in inputs.chunks_exact(4) {
            let mut lanes: [f64; 4] = chunk.try_into().unwrap();
            let (input, want) = (lanes, lanes.map(cos));
            cos_lanes_at(simd, &mut lanes);
            for (got, want) in lanes.iter().zip(&want) {
                assert_eq!(got.to_bits(), want.to_bits(), "{simd:?}: {input:?} → {got:e} vs {want:e}");
            }
        }
    }
}

crate::simd::dispatch! {
    /// exp_lanes over four lanes compiled at `simd`'s width, as the activation inlines it.
    fn exp_lanes_at => exp_lanes_4(x: &mut [f64; 4])
}

#[inline(always)]
fn exp_lanes_4(x: &mut [f64; 4]) {
    exp_lanes(x);
}

/// exp_lanes is exp, bit for bit, lane by lane, at every vector level: on its fast path
/// (every lane within ±EXP_LANE_BOUND, its edges included), and on the element-by-element
/// path that one special lane (NaN, ±∞, overflow, underflow, subnormal results) sends all
/// four lanes down.
#[test]
fn exp_lanes_gives_the_bits_of_exp_at_every_level() {
    let mut inputs: Vec<f64> = (0..20_000).map(|i| -EXP_LANE_BOUND + f64::from(i) * 0.0700037).collect();
    inputs.extend((0..4000).map(|i| -f64::from(i) * 1e-3 / 3.0));
    inputs.extend([0.0, -0.0, 1e-300, -1e-300, EXP_LANE_BOUND, -EXP_LANE_BOUND]);
    let special =
        [f64::NAN, f64::INFINITY, f64::NEG_INFINITY, 709.9, -708.5, -720.0, -745.2, 700.000001, -700.000001];
    for simd in crate::simd::Simd::available() {
        for (c, chunk) in inputs.chunks_exact(4).enumerate() {
            let mut lanes: [f64; 4] = chunk.try_into().unwrap();
            if c % 7 == 0 {
                lanes[c % 4] = special[c / 7 % special.len()];
            }
            let (input, want) = (lanes, lanes.map(exp));
            exp_lanes_at(simd, &mut lanes);
            for (got, want) in lanes.iter().zip(&want) {
                assert_eq!(got.to_bits(), want.to_bits(), "{simd:?}: {input:?} → {got:e} vs {want:e}");
            }
        }
    }
}

/// The AVX2 exp of four lanes is exp, bit for bit, wherever it applies (every lane within
/// ±EXP_LANE_BOUND, its edges included), and its check for lanes never above 0 passes exactly
/// where every lane is at or above −EXP_LANE_BOUND.
#[cfg(target_arch = "x86_64")]
#[test]
fn avx2_exp_of_four_lanes_gives_the_bits_of_exp() {
    use std::arch::x86_64::{_mm256_loadu_pd, _mm256_storeu_pd};
    if crate::simd::Simd::Avx2.capped() == crate::simd::Simd::Baseline {
        return;
    }
    let mut inputs: Vec<f64> = (0..40_000).map(|i| -EXP_LANE_BOUND + f64::from(i) * 0.0350019).collect();
    inputs.extend((0..4000).map(|i| -f64::from(i) * 1e-3 / 3.0));
    inputs.extend([0.0, -0.0, 1e-300, -1e-300, EXP_LANE_BOUND, -EXP_LANE_BOUND, -3.7e-5, 2.5e-9]);
    let special = [f64::NAN, f64::INFINITY, 709.9, -708.5, 700.000001, -700.000001];
    let (mut applied, mut refused) = (0, 0);
    for (c, chunk) in inputs.chunks_exact(4).enumerate() {
        let mut lanes: [f64; 4] = chunk.try_into().unwrap();
        if c % 11 == 0 {
            lanes[c % 4] = special[c / 11 % special.len()];
        }
        let within = lanes.iter().all(|v| (-EXP_LANE_BOUND..=EXP_LANE_BOUND).contains(v));
        let above_bound = lanes.iter().all(|&v| v >= -EXP_LANE_BOUND);
        // SAFETY: the CPU has AVX2 (checked above); the lanes are four values.
        let (applies, got) = unsafe {
            let x = _mm256_loadu_pd(lanes.as_ptr());
            let mut got = [0.0; 4];
            _mm256_storeu_pd(got.as_mut_ptr(), super::x86::exp4(x));
            (super::x86::exp4_applies_at_most_zero(x), got)
        };
        assert_eq!(applies, above_bound, "{lanes:?}");
        if !within {
            refused += 1;
            continue;
        }
        applied += 1;
        for (g, &x) in got.iter().zip(&lanes) {
            assert_eq!(g.to_bits(), exp(x).to_bits(), "exp({x:e}): {g:e} vs {:e}", exp(x));
        }
    }
    assert!(applied > 10_000 && refused > 100, "{applied} applied, {refused} refused");
}
