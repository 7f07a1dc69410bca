//! Equivalence on the ratio of two means: two one-sided Welch t-tests (TOST) of x − reference
//! against a margin `(lo, hi)` on x / reference. The replication judges a Table III row against
//! the paper's published value with it (`qsweep_report::replication::stats::equivalence`), and
//! `qsweep compare` one pipeline's cell against another's.

pub use super::summary::Moments;
use super::welch::student_t_sf;

/// The 97.5 % quantile of the standard normal distribution.
const Z_975: f64 = 1.959_963_984_540_054;

/// A 95 % interval of the ratio of means `b.mean / a.mean` from the moments alone (what a report's
/// `cells.parquet` keeps of a cell): the delta method on the log ratio, whose standard error is
/// √(s_a² / (n_a m_a²) + s_b² / (n_b m_b²)), so the interval is `ratio · exp(±1.96 · se)`
/// (normal quantile), asymmetric like the ratio itself. `None` when a mean is not positive (no log)
/// or a side has no std (fewer than two values).
pub fn ratio_ci_delta(a: Moments, b: Moments) -> Option<(f64, f64)> {
    let (sa, sb) = (a.std?, b.std?);
    if a.mean <= 0.0 || b.mean <= 0.0 || a.n < 2 || b.n < 2 {
        return None;
    }
    let r = b.mean / a.mean;
    let var = sa * sa / (a.n as f64 * a.mean * a.mean) + sb * sb / (b.n as f64 * b.mean * b.mean);
    let half = Z_975 * var.sqrt();
    Some((r * (-half).exp(), r * half.exp()))
}

/// The outcome of one TOST.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Tost {
    /// The larger of the two one-sided p-values (equivalence is shown when it is ≤ the level).
    pub p: f64,
    /// Whether both one-sided tests reject at the level.
    pub equivalent: bool,
}

/// TOST of `x` against `reference` with the margin `(lo, hi)` on x / reference, each one-sided
/// test at level `alpha`. `None` when it cannot be decided: a side without a std (a single
/// value), fewer than two values on a side, or a reference mean that is not positive (the margin
/// on a ratio means nothing then). Without spread on either side the means are known exactly and
/// the point estimate decides, the margin's bounds strict.
pub fn tost_ratio(x: Moments, reference: Moments, margin: (f64, f64), alpha: f64) -> Option<Tost> {
    let s_x = x.std?;
    let s_ref = reference.std?;
    if reference.mean <= 0.0 || x.n < 2 || reference.n < 2 {
        return None;
    }
    let lo = (margin.0 - 1.0) * reference.mean;
    let hi = (margin.1 - 1.0) * reference.mean;
    let d = x.mean - reference.mean;
    let v1 = s_x * s_x / x.n as f64;
    let v2 = s_ref * s_ref / reference.n as f64;
    let se2 = v1 + v2;
    if se2 == 0.0 {
        // Both means known exactly: the point estimate decides.
        let inside = lo < d && d < hi;
        return Some(Tost { p: if inside { 0.0 } else { 1.0 }, equivalent: inside });
    }
    let se = se2.sqrt();
    let term = |v: f64, n: usize| if v == 0.0 { 0.0 } else { v * v / (n as f64 - 1.0) };
    let df = se2 * se2 / (term(v1, x.n) + term(v2, reference.n));
    // H₀¹: d ≤ lo against d > lo; H₀²: d ≥ hi against d < hi.
    let p_lower = student_t_sf((d - lo) / se, df);
    let p_upper = student_t_sf((hi - d) / se, df);
    let p = p_lower.max(p_upper);
    Some(Tost { p, equivalent: p <= alpha })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn m(mean: f64, std: f64, n: usize) -> Moments {
        Moments { mean, std: Some(std), n }
    }

    #[test]
    fn tost_ratio_matches_two_scipy_welch_tests() {
        // scipy.stats.ttest_ind_from_stats against 90.5·0.80 ("greater") and 90.5·1.25 ("less"),
        // SciPy 1.17.1: p = 0.021432 and 0.048590; the larger decides.
        let t = tost_ratio(m(95.0, 20.0, 10), m(90.5, 25.8, 10), (0.8, 1.25), 0.05).unwrap();
        assert!((t.p - 0.048_590_093_7).abs() < 1e-9 && t.equivalent, "{t:?}");
        // The same at a stricter level is not shown.
        assert!(!tost_ratio(m(95.0, 20.0, 10), m(90.5, 25.8, 10), (0.8, 1.25), 0.01).unwrap().equivalent);
    }

    #[test]
    fn ratio_ci_delta_is_the_log_normal_interval() {
        // se² = 10²/(10·100²) + 20²/(10·200²) = 0.002; ratio 2, interval 2·exp(±1.96·√0.002).
        let (lo, hi) = ratio_ci_delta(m(100.0, 10.0, 10), m(200.0, 20.0, 10)).unwrap();
        let half = Z_975 * 0.002f64.sqrt();
        assert!((lo - 2.0 * (-half).exp()).abs() < 1e-12 && (hi - 2.0 * half.exp()).abs() < 1e-12);
        assert!((lo * hi - 4.0).abs() < 1e-12, "symmetric on a log scale");
        assert_eq!(ratio_ci_delta(m(5.0, 0.0, 3), m(5.0, 0.0, 3)), Some((1.0, 1.0)));
        assert_eq!(ratio_ci_delta(m(0.0, 1.0, 3), m(5.0, 1.0, 3)), None);
        assert_eq!(ratio_ci_delta(Moments { mean: 1.0, std: None, n: 1 }, m(5.0, 1.0, 3)), None);
    }

    #[test]
    fn tost_ratio_is_undecided_without_enough_data_or_a_positive_reference() {
        let one = Moments { mean: 1.0, std: None, n: 1 };
        assert_eq!(tost_ratio(one, m(1.0, 1.0, 5), (0.8, 1.25), 0.05), None);
        assert_eq!(tost_ratio(m(1.0, 1.0, 5), m(0.0, 1.0, 5), (0.8, 1.25), 0.05), None);
        assert_eq!(tost_ratio(m(-1.0, 1.0, 5), m(-1.0, 1.0, 5), (0.8, 1.25), 0.05), None);
        // Identical values without spread: equivalent, p = 0.
        assert_eq!(
            tost_ratio(m(7.0, 0.0, 4), m(7.0, 0.0, 4), (0.8, 1.25), 0.05),
            Some(Tost { p: 0.0, equivalent: true })
        );
    }
}
