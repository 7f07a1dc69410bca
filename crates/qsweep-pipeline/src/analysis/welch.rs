//! The race's test, defined once: a one-sided Welch t-test of "this cell's mean is higher than the
//! best cell's" on the episodes Table III averages, and Holm's step-down correction over the cells
//! tested in one round. Student's t distribution is evaluated through the regularised incomplete
//! beta function (a continued fraction), so no statistics crate is needed; the values are checked
//! against SciPy's in the tests.

use super::summary::{mean, sample_std, Moments};

/// One-sided p-value of Welch's t-test for H₀: μ_worse ≤ μ_best against H₁: μ_worse > μ_best.
///
/// Both samples need at least two values. With no spread in either sample the means are known
/// exactly: p = 0 when `worse`'s is higher, else 1.
pub fn welch_p_greater(worse: &[f64], best: &[f64]) -> f64 {
    let (n1, n2) = (worse.len() as f64, best.len() as f64);
    let (m1, m2) = (mean(worse), mean(best));
    let v1 = sample_std(worse).map_or(0.0, |s| s * s) / n1;
    let v2 = sample_std(best).map_or(0.0, |s| s * s) / n2;
    let se2 = v1 + v2;
    if se2 == 0.0 {
        return if m1 > m2 { 0.0 } else { 1.0 };
    }
    let t = (m1 - m2) / se2.sqrt();
    // Welch–Satterthwaite degrees of freedom; a sample without spread contributes no term.
    let term = |v: f64, n: f64| if v == 0.0 { 0.0 } else { v * v / (n - 1.0) };
    let df = se2 * se2 / (term(v1, n1) + term(v2, n2));
    student_t_sf(t, df)
}

/// Two-sided p-value of Welch's t-test for H₀: μ_a = μ_b, or `None` when a sample has fewer than
/// two values (no variance to test with).
///
/// Without spread in either sample the means are known exactly: p = 1 when they are equal (the
/// same values on both sides are no evidence of a difference), else 0.
pub fn welch_p_two_sided(a: &[f64], b: &[f64]) -> Option<f64> {
    welch_p_two_sided_moments(Moments::of(a), Moments::of(b))
}

/// [`welch_p_two_sided`] from each sample's moments (mean, sample std, n) alone, as a report's
/// `cells.parquet` keeps them: the same test, the same numbers.
pub fn welch_p_two_sided_moments(a: Moments, b: Moments) -> Option<f64> {
    if a.n < 2 || b.n < 2 {
        return None;
    }
    let (n1, n2) = (a.n as f64, b.n as f64);
    let (m1, m2) = (a.mean, b.mean);
    let v1 = a.std.map_or(0.0, |s| s * s) / n1;
    let v2 = b.std.map_or(0.0, |s| s * s) / n2;
    let se2 = v1 + v2;
    if se2 == 0.0 {
        return Some(if m1 == m2 { 1.0 } else { 0.0 });
    }
    let t = (m1 - m2) / se2.sqrt();
    let term = |v: f64, n: f64| if v == 0.0 { 0.0 } else { v * v / (n - 1.0) };
    let df = se2 * se2 / (term(v1, n1) + term(v2, n2));
    Some((2.0 * student_t_sf(t.abs(), df)).min(1.0))
}

/// Holm's step-down procedure at family-wise level `level`: which of the hypotheses with these
/// p-values are rejected. The family-wise error rate stays ≤ `level` under any dependence between
/// the tests.
/// Ties in p keep their input order, so the answer is a pure function of the input.
pub fn holm_reject(p: &[f64], level: f64) -> Vec<bool> {
    let m = p.len();
    let mut order: Vec<usize> = (0..m).collect();
    order.sort_by(|&a, &b| p[a].total_cmp(&p[b]).then(a.cmp(&b)));
    let mut out = vec![false; m];
    for (k, &i) in order.iter().enumerate() {
        if p[i] <= level / (m - k) as f64 {
            out[i] = true;
        } else {
            break;
        }
    }
    out
}

/// P(T > t) for Student's t with `df` > 0 degrees of freedom (df may be fractional).
pub fn student_t_sf(t: f64, df: f64) -> f64 {
    if t.is_nan() || df.is_nan() || df <= 0.0 {
        return f64::NAN;
    }
    if t.is_infinite() {
        return if t > 0.0 { 0.0 } else { 1.0 };
    }
    // P(|T| > |t|) = I_x(df/2, 1/2) with x = df / (df + t²).
    let x = df / (df + t * t);
    let tail = 0.5 * incomplete_beta(0.5 * df, 0.5, x);
    if t > 0.0 {
        tail
    } else {
        1.0 - tail
    }
}

/// P(F ≤ x) for Fisher's F with `d1`, `d2` > 0 degrees of freedom.
pub fn f_cdf(x: f64, d1: f64, d2: f64) -> f64 {
    if x <= 0.0 {
        return 0.0;
    }
    incomplete_beta(0.5 * d1, 0.5 * d2, d1 * x / (d1 * x + d2))
}

/// The `q`-quantile (0 < q < 1) of Fisher's F with `d1`, `d2` degrees of freedom: the x with
/// [`f_cdf`] = q, by bisection on x / (1 + x) (a fixed number of halvings, so the same bits on
/// every run).
pub fn f_quantile(q: f64, d1: f64, d2: f64) -> f64 {
    // u = x / (1 + x) ∈ (0, 1) maps the half-line onto an interval that bisection can halve.
    let (mut lo, mut hi) = (0.0_f64, 1.0_f64);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if mid == lo || mid == hi {
            break;
        }
        if f_cdf(mid / (1.0 - mid), d1, d2) < q {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let u = 0.5 * (lo + hi);
    u / (1.0 - u)
}

/// The regularised incomplete beta function I_x(a, b) for a, b > 0 and x in [0, 1], by its
/// continued fraction (modified Lentz), using the symmetry I_x(a, b) = 1 − I_{1−x}(b, a) where
/// the fraction converges faster.
pub fn incomplete_beta(a: f64, b: f64, x: f64) -> f64 {
    if x <= 0.0 {
        return 0.0;
    }
    if x >= 1.0 {
        return 1.0;
    }
    let ln_front = ln_gamma(a + b) - ln_gamma(a) - ln_gamma(b) + a * x.ln() + b * (1.0 - x).ln();
    if x < (a + 1.0) / (a + b + 2.0) {
        ln_front.exp() * beta_fraction(a, b, x) / a
    } else {
        1.0 - ln_front.exp() * beta_fraction(b, a, 1.0 - x) / b
    }
}

fn beta_fraction(a: f64, b: f64, x: f64) -> f64 {
    const TINY: f64 = 1e-300;
    const EPS: f64 = 1e-15;
    // Lentz's method: a denominator that reaches 0 is replaced by a tiny one.
    let nz = |v: f64| if v.abs() < TINY { TINY } else { v };
    let (qab, qap, qam) = (a + b, a + 1.0, a - 1.0);
    let mut c = 1.0;
    let mut d = 1.0 / nz(1.0 - qab * x / qap);
    let mut h = d;
    for m in 1..=10_000 {
        let m = f64::from(m);
        let m2 = 2.0 * m;
        let aa = m * (b - m) * x / ((qam + m2) * (a + m2));
        d = 1.0 / nz(1.0 + aa * d);
        c = nz(1.0 + aa / c);
        h *= d * c;
        let aa = -(a + m) * (qab + m) * x / ((a + m2) * (qap + m2));
        d = 1.0 / nz(1.0 + aa * d);
        c = nz(1.0 + aa / c);
        let del = d * c;
        h *= del;
        if (del - 1.0).abs() < EPS {
            break;
        }
    }
    h
}

/// ln Γ(x) for x > 0 (Lanczos, g = 7, 9 terms; relative error below 1e-14 on the range used).
pub fn ln_gamma(x: f64) -> f64 {
    const G: f64 = 7.0;
    const C: [f64; 9] = [
        0.999_999_999_999_809_9,
        676.520_368_121_885_1,
        -1_259.139_216_722_402_8,
        771.323_428_777_653_1,
        -176.615_029_162_140_6,
        12.507_343_278_686_905,
        -0.138_571_095_265_720_12,
        9.984_369_578_019_572e-6,
        1.505_632_735_149_311_6e-7,
    ];
    if x < 0.5 {
        // Reflection: Γ(x) Γ(1 − x) = π / sin(πx).
        return (std::f64::consts::PI / (std::f64::consts::PI * x).sin()).ln() - ln_gamma(1.0 - x);
    }
    let x = x - 1.0;
    let mut sum = C[0];
    for (i, c) in C.iter().enumerate().skip(1) {
        sum += c / (x + i as f64);
    }
    let t = x + G + 0.5;
    0.5 * (2.0 * std::f64::consts::PI).ln() + (x + 0.5) * t.ln() - t + sum.ln()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: f64, b: f64, rel: f64) -> bool {
        (a - b).abs() <= rel * b.abs().max(1e-300)
    }

    #[test]
    fn f_quantiles_match_scipy() {
        // scipy.stats.f.ppf(q, d1, d2), SciPy 1.17.1.
        for (q, d1, d2, want) in [
            (0.975, 19.0, 9.0, 3.683_338_083_218_051_6),
            (0.025, 19.0, 9.0, 0.347_215_947_412_324_5),
            (0.975, 9.0, 9.0, 4.025_994_158_282_978),
            (0.025, 1.0, 2.0, 0.001_250_781_738_586_616_6),
        ] {
            let got = f_quantile(q, d1, d2);
            assert!(close(got, want, 1e-9), "F({q}; {d1}, {d2}) = {got}, want {want}");
        }
    }

    #[test]
    fn ln_gamma_matches_factorials_and_half_integers() {
        for n in 1..20u32 {
            let fact: f64 = (1..n).map(f64::from).product();
            assert!((ln_gamma(f64::from(n)) - fact.ln()).abs() < 1e-12 * fact.ln().max(1.0), "Γ({n})");
        }
        // Γ(1/2) = √π.
        assert!(close(ln_gamma(0.5), std::f64::consts::PI.sqrt().ln(), 1e-13));
    }

    #[test]
    fn student_t_matches_scipy() {
        // scipy.stats.t.sf(t, df), SciPy 1.17.1.
        for (t, df, want) in GOLDEN_T {
            let got = student_t_sf(t, df);
            assert!(close(got, want, 1e-9), "t = {t}, df = {df}: {got} vs {want}");
        }
        assert_eq!(student_t_sf(0.0, 7.0), 0.5);
        assert_eq!(student_t_sf(f64::INFINITY, 3.0), 0.0);
        assert!(student_t_sf(1.0, 0.0).is_nan());
    }

    #[test]
    fn welch_matches_scipy_one_sided() {
        // scipy.stats.ttest_ind(a, b, equal_var=False, alternative="greater").pvalue, SciPy 1.17.1
        for (a, b, want) in GOLDEN_WELCH {
            let got = welch_p_greater(a, b);
            assert!(close(got, *want, 1e-9), "{a:?} vs {b:?}: {got} vs {want}");
        }
    }

    #[test]
    fn two_sided_welch_doubles_the_smaller_one_sided_tail() {
        // Two-sided p = 2·min(p_greater, 1 − p_greater): the SciPy values above, doubled.
        for (a, b, one) in GOLDEN_WELCH {
            let want = 2.0 * one.min(1.0 - one);
            let got = welch_p_two_sided(a, b).unwrap();
            assert!(close(got, want, 1e-9), "{a:?} vs {b:?}: {got} vs {want}");
            assert!(close(welch_p_two_sided(b, a).unwrap(), want, 1e-9), "symmetric");
        }
        assert_eq!(welch_p_two_sided(&[5.0; 4], &[5.0; 3]), Some(1.0), "identical, no spread");
        assert_eq!(welch_p_two_sided(&[5.0; 4], &[6.0; 3]), Some(0.0));
        assert_eq!(welch_p_two_sided(&[5.0], &[6.0, 7.0]), None, "one value: no test");
    }

    #[test]
    fn welch_without_spread_knows_the_answer() {
        assert_eq!(welch_p_greater(&[1000.0; 5], &[1000.0; 5]), 1.0, "a tie is never worse");
        assert_eq!(welch_p_greater(&[1000.0; 5], &[4.0; 5]), 0.0);
        assert_eq!(welch_p_greater(&[4.0; 5], &[1000.0; 5]), 1.0);
        // One sample without spread: the other's variance alone, df = n − 1.
        let p = welch_p_greater(&[10.0, 12.0, 14.0], &[5.0; 4]);
        assert!(close(p, student_t_sf(7.0 / (4.0f64 / 3.0).sqrt(), 2.0), 1e-12));
    }

    #[test]
    fn holm_steps_down_and_stops_at_the_first_keep() {
        // α = 0.05, m = 4: thresholds 0.0125, 0.01667, 0.025, 0.05 in p order.
        assert_eq!(holm_reject(&[0.01, 0.04, 0.012, 0.2], 0.05), vec![true, false, true, false]);
        // 0.02 > 0.0125 stops everything, although 0.02 < 0.05.
        assert_eq!(holm_reject(&[0.02, 0.02, 0.02, 0.02], 0.05), vec![false; 4]);
        assert_eq!(holm_reject(&[0.0, 0.0], 0.05), vec![true, true]);
        assert!(holm_reject(&[], 0.05).is_empty());
    }

    const GOLDEN_T: [(f64, f64, f64); 8] = [
        (2.5, 3.0, 0.04385332350403278),
        (-1.2, 7.5, 0.866665538603389),
        (0.3, 1.0, 0.4072264209222577),
        (4.0, 18.0, 0.00041991465870428043),
        (1.96, 1000.0, 0.025136592477874368),
        (10.0, 2.5, 0.0022207478836537117),
        (0.75, 0.6, 0.32370045548311166),
        (3.3, 9.73, 0.004154933301078428),
    ];
    const GOLDEN_WELCH: &[(&[f64], &[f64], f64)] = &[
        (&[12.0, 15.0, 11.0, 19.0, 14.0], &[5.0, 7.0, 6.0, 9.0, 8.0], 0.0018808708183109064),
        (&[100.0, 90.0, 120.0, 80.0, 1000.0, 1000.0], &[40.0, 60.0, 55.0, 70.0], 0.06613459709144195),
        (&[3.0, 4.0, 5.0], &[4.0, 4.5, 5.5, 3.5], 0.6854202044591307),
        (
            &[200.0, 210.0, 190.0, 205.0, 220.0, 199.0, 201.0, 230.0, 180.0, 215.0],
            &[150.0, 300.0, 100.0, 250.0, 200.0, 175.0, 225.0, 120.0, 280.0, 160.0],
            0.3436312881192974,
        ),
    ];
}
