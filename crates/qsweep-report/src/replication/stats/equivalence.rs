//! Equivalence of a Table III row with its published value: two one-sided Welch t-tests (TOST)
//! of ours − paper against a margin on the ratio of the means, declared in
//! `docs/preregistration.md` before it was computed. The paper never states how many runs its
//! means average, so the test takes that number as an argument and the report shows both
//! assumptions ([`PAPER_N`]). The test itself is the statistics layer's
//! ([`qsweep_pipeline::analysis::tost_ratio`]); this file holds the paper's margins and level.

use qsweep_pipeline::analysis::tost_ratio;

/// The equivalence margin on ours / paper: the conventional average-bioequivalence limits
/// (FDA 2001), symmetric on the log scale.
pub const MARGIN: (f64, f64) = (0.80, 1.25);

/// The margin of "within 2×" on ours / paper (`docs/preregistration.md`, the verdict scale).
pub const MARGIN_2X: (f64, f64) = (0.5, 2.0);

/// Level of each one-sided test.
pub const ALPHA: f64 = 0.05;

/// The assumed numbers of runs behind each published mean: the fit measure's 10, and 100.
pub const PAPER_N: [usize; 2] = [10, 100];

/// The rule, as stated in captions.
pub const EQUIVALENCE_RULE: &str = "Equivalent: ours/paper within [0.80, 1.25] by two one-sided \
Welch t-tests (TOST, α = 0.05, p the larger), the paper's std over an assumed n = 10 or 100 runs \
(unstated in the paper; docs/preregistration.md).";

/// A summary a test needs, and the outcome of one TOST: the generic test's own types
/// ([`qsweep_pipeline::analysis::equivalence`]).
pub use qsweep_pipeline::analysis::{Moments, Tost};

/// TOST of `ours` against the published `paper` mean and std over `paper_n` runs, with the margin
/// [`MARGIN`] on ours / paper. `None` when it cannot be decided: ours has a single trial (no
/// std), the paper's mean is not positive, or a sample is too small for degrees of freedom.
pub fn tost(ours: Moments, paper: Moments) -> Option<Tost> {
    tost_within(ours, paper, MARGIN)
}

/// [`tost`] with another margin `(lo, hi)` on ours / paper (e.g. [`MARGIN_2X`]).
pub fn tost_within(ours: Moments, paper: Moments, margin: (f64, f64)) -> Option<Tost> {
    // The generic test on the ratio (the statistics layer's, shared with `qsweep compare`).
    tost_ratio(ours, paper, margin, ALPHA)
}

/// A Table III row's TOST under each assumed number of paper runs in [`PAPER_N`]: our best
/// cell's mean, std and n against the published mean and std.
pub fn against_paper(
    mean: f64,
    std: Option<f64>,
    n: usize,
    paper_mean: f64,
    paper_std: f64,
) -> [Option<Tost>; 2] {
    let ours = Moments { mean, std, n };
    PAPER_N.map(|pn| tost(ours, Moments { mean: paper_mean, std: Some(paper_std), n: pn }))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn m(mean: f64, std: f64, n: usize) -> Moments {
        Moments { mean, std: Some(std), n }
    }

    #[test]
    fn tost_matches_two_scipy_welch_tests() {
        // Oracle: scipy.stats.ttest_ind_from_stats(m1, s1, n1, m2·(1+b), s2, n2, equal_var=False,
        // alternative=…) for the two bounds, SciPy 1.17.1: ours 95 ± 20 (n 10) vs paper 90.5 ± 25.8.
        // lower: alternative="greater" against 90.5·0.80 → p = 0.021432 (t = 2.1893)
        // upper: alternative="less" against 90.5·1.25 → p = 0.048590 (t = −1.7558)
        let t = tost(m(95.0, 20.0, 10), m(90.5, 25.8, 10)).unwrap();
        assert!((t.p - 0.048590_0937).abs() < 1e-9, "{}", t.p);
        assert!(t.equivalent);
    }

    #[test]
    fn more_paper_runs_can_only_sharpen_the_test() {
        // A small shift with a wide paper std: undecided at n = 10, equivalent at n = 100.
        let ours = m(46.0, 10.0, 40);
        let t10 = tost(ours, m(42.4, 13.8, 10)).unwrap();
        let t100 = tost(ours, m(42.4, 13.8, 100)).unwrap();
        // SciPy as above: p = 0.079280 (n = 10), 6.0081e-4 (n = 100).
        assert!(!t10.equivalent && t100.equivalent, "{t10:?} {t100:?}");
        assert!((t10.p - 0.079_279_823_2).abs() < 1e-9 && (t100.p - 6.008_092_787e-4).abs() < 1e-12);
        assert!(t100.p < t10.p);
    }

    #[test]
    fn a_mean_at_either_edge_of_the_margin_is_not_equivalent() {
        // ours / paper exactly 1.25 or 0.80: that one-sided t is 0, so p = 0.5 whatever the
        // spreads (SciPy as above gives 0.5 at both edges), however many runs.
        for (ours, paper) in [(62.5, 50.0), (40.0, 50.0)] {
            for pn in PAPER_N {
                let t = tost(m(ours, 10.0, 20), m(paper, 5.0, pn)).unwrap();
                assert!((t.p - 0.5).abs() < 1e-12 && !t.equivalent, "{ours} {paper} {pn}: {t:?}");
            }
        }
        // With the spreads small, a mean well inside the margin is equivalent; SciPy's two
        // one-sided p-values for 50 ± 1 (n 20) against 50 ± 1 (n 10) are 4.9e-16 and 9.3e-18.
        let inside = tost(m(50.0, 1.0, 20), m(50.0, 1.0, 10)).unwrap();
        assert!(inside.equivalent && inside.p < 1e-15, "{inside:?}");
        // Without spread, a value on the edge is outside: the margin's bounds are strict.
        assert!(!tost(m(62.5, 0.0, 10), m(50.0, 0.0, 10)).unwrap().equivalent);
        assert!(!tost(m(40.0, 0.0, 10), m(50.0, 0.0, 10)).unwrap().equivalent);
    }

    #[test]
    fn the_twofold_margin_matches_two_scipy_welch_tests() {
        // SciPy 1.17.1, ttest_ind_from_stats(34.85, 95.1, 20, 4.54·b, S, 10, equal_var=False)
        // against the bounds 4.54·0.5 (alternative="greater") and 4.54·2 ("less"), S = 1.0:
        // p = 0.0710 and 0.8798 (the upper bound's p is the larger: not shown within 2×).
        let t = tost_within(m(34.85, 95.1, 20), m(4.54, 1.0, 10), MARGIN_2X).unwrap();
        assert!(!t.equivalent && (t.p - 0.879_765_339_197).abs() < 1e-9, "{t:?}");
        // 95 ± 20 (n 20) against 90.5 ± 25.8 (n 10) is well within 2×: p = 4.4666e-5 and 8.7e-8.
        let t = tost_within(m(95.0, 20.0, 20), m(90.5, 25.8, 10), MARGIN_2X).unwrap();
        assert!(t.equivalent && (t.p - 4.466_593_937e-5).abs() < 1e-12, "{t:?}");
        // The bounds are strict without spread.
        assert!(!tost_within(m(2.0, 0.0, 10), m(1.0, 0.0, 10), MARGIN_2X).unwrap().equivalent);
        assert!(tost_within(m(1.99, 0.0, 10), m(1.0, 0.0, 10), MARGIN_2X).unwrap().equivalent);
        assert!(!tost_within(m(0.5, 0.0, 10), m(1.0, 0.0, 10), MARGIN_2X).unwrap().equivalent);
    }

    #[test]
    fn far_values_are_not_equivalent_and_one_trial_is_undecided() {
        assert!(!tost(m(4.5, 1.6, 10), m(90.5, 25.8, 10)).unwrap().equivalent);
        let single = Moments { mean: 90.0, std: None, n: 1 };
        assert_eq!(tost(single, m(90.5, 25.8, 10)), None);
        // No spread anywhere: the point estimate decides, at the margin's asymmetric bounds.
        assert!(tost(m(2.4, 0.0, 10), m(2.0, 0.0, 10)).unwrap().equivalent);
        assert!(!tost(m(2.6, 0.0, 10), m(2.0, 0.0, 10)).unwrap().equivalent);
    }
}
