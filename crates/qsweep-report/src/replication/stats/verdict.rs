//! The replication verdict of one Table III row against its published value, defined once: the
//! best cell's and the cell at the paper's configuration are judged by the same rule, for Table
//! III's columns, the comparison and the answer alike; and the cause of a row that does not
//! replicate. Both as pre-registered in docs/preregistration.md: the scale that needs closeness
//! ([`Verdict`], [`judge`], [`Cause`]) and, kept for comparison and because the fit measure that
//! ranks the variants is defined on it, the older rule of two standard errors ([`FitVerdict`],
//! [`cause_2se`]).

use super::equivalence::{tost, tost_within, Moments, MARGIN_2X};

/// Runs behind each published value for the fit measure and the old rule (the paper never
/// states its n; docs/preregistration.md): the headline assumption.
pub const REFERENCE_N: f64 = 10.0;

/// The assumed numbers of paper runs of the sensitivity analysis, the headline last.
pub const PAPER_N_SET: [usize; 3] = [3, 5, 10];

/// The headline assumed number of paper runs (`REFERENCE_N` as a count).
pub const HEADLINE_N: usize = 10;

/// The factor within which a row that does not replicate still counts as "within 2×" under the
/// old rule: 1/TWOFOLD ≤ ours/reference ≤ TWOFOLD.
pub const TWOFOLD: f64 = 2.0;

/// The old rule (the fit measure's), as stated in captions.
pub const VERDICT_RULE: &str = "A Table III row is within 2 SE of its reference when |ours − \
reference| ≤ 2·√(s_ref²/10 + s_ours²/n) (two standard errors; the reference has 10 runs, a row with \
a single trial has no std and is not); it is within 2× by ratio when it is not but 0.5 ≤ \
ours/reference ≤ 2. Not shown different is not shown close: the verdict scale decides replication.";

/// The verdict scale, as stated in captions.
pub const SCALE_RULE: &str = "Verdict (docs/preregistration.md), the first that applies: undecided \
(a single trial, or no positive reference); equivalent (TOST, ours/paper within [0.80, 1.25]); \
within-2x (the same two one-sided Welch tests with the margin [0.5, 2]); consistent-but-wide (within \
two standard errors but not shown within 2×); differs. The paper's std is taken over an assumed \
n_paper = 10 runs (verdicts_by_n.csv: 3, 5, 10). Only equivalent and within-2x replicate.";

/// The old rule's verdict of one Table III row (the fit measure's; `verdict_2se` in table3.csv).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FitVerdict {
    /// Within two standard errors.
    Replicates,
    /// Not within two standard errors, but ours/reference ∈ [1/TWOFOLD, TWOFOLD].
    Within2x,
    /// Neither.
    DoesNotReplicate,
}

impl FitVerdict {
    /// The verdict as a table value: `replicates`, `within-2x` or `no`.
    pub fn label(self) -> &'static str {
        match self {
            Self::Replicates => "replicates",
            Self::Within2x => "within-2x",
            Self::DoesNotReplicate => "no",
        }
    }
}

/// The old rule's verdict for our mean and std over `n` trials against a reference mean and std.
pub fn fit_verdict(ours: f64, ours_std: Option<f64>, n: usize, ref_mean: f64, ref_std: f64) -> FitVerdict {
    if within_2se(ours, ours_std, n, ref_mean, ref_std, REFERENCE_N) {
        FitVerdict::Replicates
    } else if ref_mean > 0.0 && (1.0 / TWOFOLD..=TWOFOLD).contains(&(ours / ref_mean)) {
        FitVerdict::Within2x
    } else {
        FitVerdict::DoesNotReplicate
    }
}

/// |ours − reference| ≤ 2·√(s_ref²/n_ref + s_ours²/n); false without our std.
fn within_2se(ours: f64, ours_std: Option<f64>, n: usize, ref_mean: f64, ref_std: f64, n_ref: f64) -> bool {
    ours_std.is_some_and(|s| {
        let se = (ref_std * ref_std / n_ref + s * s / n as f64).sqrt();
        (ours - ref_mean).abs() <= 2.0 * se
    })
}

/// The verdict of one Table III row on the scale that needs closeness.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum Verdict {
    /// Shown within [0.80, 1.25] of the paper (TOST).
    Equivalent,
    /// Shown within [0.5, 2] of the paper (TOST), not within [0.80, 1.25].
    Within2x,
    /// Within two standard errors, not shown within 2×.
    ConsistentButWide,
    /// None of the above.
    Differs,
    /// A single trial (no std), or no positive reference.
    Undecided,
}

impl Verdict {
    /// Every verdict, closest first (the order [`Ord`] gives, which the closest variant uses).
    pub const ALL: [Verdict; 5] =
        [Self::Equivalent, Self::Within2x, Self::ConsistentButWide, Self::Differs, Self::Undecided];

    /// The verdict as a table value.
    pub fn label(self) -> &'static str {
        match self {
            Self::Equivalent => "equivalent",
            Self::Within2x => "within-2x",
            Self::ConsistentButWide => "consistent-but-wide",
            Self::Differs => "differs",
            Self::Undecided => "undecided",
        }
    }

    /// Whether the verdict counts as replicating (`equivalent` or `within-2x`).
    pub fn replicates(self) -> bool {
        matches!(self, Self::Equivalent | Self::Within2x)
    }
}

/// A row judged on the scale: the verdict and the two TOSTs' p-values (`None`: undecidable).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Judged {
    /// The verdict.
    pub verdict: Verdict,
    /// The equivalence TOST's p (margin [0.80, 1.25]).
    pub tost_p: Option<f64>,
    /// The within-2× TOST's p (margin [0.5, 2]).
    pub tost2x_p: Option<f64>,
}

/// Our estimate (mean, std, n) against the published mean and std over `paper_n` runs, on the
/// scale: the first that applies of undecided, equivalent, within-2x, consistent-but-wide, differs.
pub fn judge(ours: Moments, paper_mean: f64, paper_std: f64, paper_n: usize) -> Judged {
    let paper = Moments { mean: paper_mean, std: Some(paper_std), n: paper_n };
    let (eq, twofold) = (tost(ours, paper), tost_within(ours, paper, MARGIN_2X));
    let (tost_p, tost2x_p) = (eq.map(|t| t.p), twofold.map(|t| t.p));
    let verdict = if ours.std.is_none() || ours.n < 2 || paper_mean <= 0.0 {
        Verdict::Undecided
    } else if eq.is_some_and(|t| t.equivalent) {
        Verdict::Equivalent
    } else if twofold.is_some_and(|t| t.equivalent) {
        Verdict::Within2x
    } else if within_2se(ours.mean, ours.std, ours.n, paper_mean, paper_std, paper_n as f64) {
        Verdict::ConsistentButWide
    } else {
        Verdict::Differs
    };
    Judged { verdict, tost_p, tost2x_p }
}

/// Why a Table III row does or does not replicate (the pre-registered rule, first that applies).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Cause {
    /// The best cell replicates (`equivalent` or `within-2x`).
    Replicates,
    /// The rule designates this row of a pair of Table III rows that contradict each other
    /// ([`crate::replication::stats::consistency`]).
    PaperInconsistent,
    /// Ours at the paper's configuration replicates, the best cell does not: our grid picks
    /// another configuration.
    Argmin,
    /// Ours at the paper's configuration has trials and is not shown within 2× (a difference of
    /// the learner or of the protocol: how episodes are counted, success, start states).
    DiffersAtPaperConfig,
    /// No cell at the paper's configuration with trials.
    Unexplained,
}

impl Cause {
    /// Every cause, in the rule's order.
    pub const ALL: [Cause; 5] = [
        Self::Replicates,
        Self::Argmin,
        Self::PaperInconsistent,
        Self::DiffersAtPaperConfig,
        Self::Unexplained,
    ];

    /// The cause as a table value.
    pub fn label(self) -> &'static str {
        match self {
            Self::Replicates => "replicates",
            Self::PaperInconsistent => "paper-inconsistent",
            Self::Argmin => "argmin",
            Self::DiffersAtPaperConfig => "differs-at-paper-config",
            Self::Unexplained => "unexplained",
        }
    }
}

/// The cause rule, as stated in captions.
pub const CAUSE_RULE: &str = "Cause (docs/preregistration.md), the first that applies: replicates \
(the best cell is equivalent or within-2x); paper-inconsistent (the row a contradictory pair costs); \
argmin (ours at the paper's configuration replicates: our grid picks another configuration); \
differs-at-paper-config (ours there is not shown within 2×: the learner or the protocol differs); \
unexplained (no trials at the paper's configuration).";

/// The cause of a row from the best cell's verdict, whether the contradiction rule designates the
/// row, and the verdict of the cell at the paper's configuration (`None`: no such cell with trials).
pub fn cause(best: Verdict, designated: bool, paper_cell: Option<Verdict>) -> Cause {
    match (best.replicates(), designated, paper_cell) {
        (true, _, _) => Cause::Replicates,
        (_, true, _) => Cause::PaperInconsistent,
        (_, _, Some(v)) if v.replicates() => Cause::Argmin,
        (_, _, Some(_)) => Cause::DiffersAtPaperConfig,
        (_, _, None) => Cause::Unexplained,
    }
}

/// The old cause rule's label (`cause_2se`): on the old verdicts, with every row of a
/// contradictory pair `paper-inconsistent` and `learner` for a paper's cell that is not within
/// 2 SE.
pub fn cause_2se(best: FitVerdict, in_pair: bool, paper_cell: Option<FitVerdict>) -> &'static str {
    match (best, in_pair, paper_cell) {
        (FitVerdict::Replicates, _, _) => "replicates",
        (_, true, _) => "paper-inconsistent",
        (_, _, Some(FitVerdict::Replicates)) => "argmin",
        (_, _, Some(_)) => "learner",
        (_, _, None) => "unexplained",
    }
}

/// The ratio of our std to the paper's, with its 95 % interval (F distribution).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Spread {
    /// s_ours / s_paper.
    pub ratio: f64,
    /// The interval's lower end.
    pub lo: f64,
    /// Its upper end.
    pub hi: f64,
}

impl Spread {
    /// Whether the interval excludes 1.
    pub fn differs(&self) -> bool {
        self.lo > 1.0 || self.hi < 1.0
    }
}

/// The spread rule, as stated in captions.
pub const SPREAD_RULE: &str = "Std ratio: our std ÷ the paper's; spread differs when its 95 % F \
interval (in table3.csv) excludes 1.";

/// Our std over `n` trials against the paper's over `paper_n` runs: `None` when n < 2 or the
/// paper's std is not positive.
pub fn spread(std: Option<f64>, n: usize, paper_std: f64, paper_n: usize) -> Option<Spread> {
    let s = std?;
    if n < 2 || paper_n < 2 || paper_std <= 0.0 || !paper_std.is_finite() {
        return None;
    }
    let r2 = (s / paper_std) * (s / paper_std);
    let (d1, d2) = ((n - 1) as f64, (paper_n - 1) as f64);
    let f = |q: f64| qsweep_pipeline::analysis::welch::f_quantile(q, d1, d2);
    Some(Spread { ratio: s / paper_std, lo: (r2 / f(0.975)).sqrt(), hi: (r2 / f(0.025)).sqrt() })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn m(mean: f64, std: f64, n: usize) -> Moments {
        Moments { mean, std: Some(std), n }
    }

    #[test]
    fn fit_verdicts_follow_the_old_rule() {
        // se = √(3²/10 + 2²/4) = √1.9 ≈ 1.378; 2·se ≈ 2.757.
        assert_eq!(fit_verdict(8.7, Some(2.0), 4, 6.0, 3.0), FitVerdict::Replicates);
        assert_eq!(fit_verdict(8.8, Some(2.0), 4, 6.0, 3.0), FitVerdict::Within2x);
        assert_eq!(fit_verdict(12.0, Some(2.0), 4, 6.0, 3.0), FitVerdict::Within2x);
        assert_eq!(fit_verdict(12.1, Some(2.0), 4, 6.0, 3.0), FitVerdict::DoesNotReplicate);
        assert_eq!(fit_verdict(3.0, None, 1, 6.0, 3.0), FitVerdict::Within2x, "no std: not within 2 SE");
        assert_eq!(fit_verdict(2.9, None, 1, 6.0, 3.0), FitVerdict::DoesNotReplicate);
        assert_eq!(FitVerdict::Within2x.label(), "within-2x");
    }

    #[test]
    fn the_scale_needs_closeness_not_just_non_rejection() {
        // Cart-Pole Exp. 4 Q(0) at the paper's configuration: 34.85 ± 95.1 against 4.54 ± 1.0 is
        // within two standard errors (the old rule's "replicates") but far from within 2×.
        let wide = judge(m(34.85, 95.1, 20), 4.54, 1.0, 10);
        assert_eq!(fit_verdict(34.85, Some(95.1), 20, 4.54, 1.0), FitVerdict::Replicates);
        assert_eq!(wide.verdict, Verdict::ConsistentButWide);
        // Close and tight: equivalent; close but loose: within 2×; far and tight: differs.
        assert_eq!(judge(m(50.0, 1.0, 20), 50.0, 1.0, 10).verdict, Verdict::Equivalent);
        assert_eq!(judge(m(60.0, 5.0, 20), 50.0, 5.0, 10).verdict, Verdict::Within2x);
        assert_eq!(judge(m(150.0, 5.0, 20), 50.0, 5.0, 10).verdict, Verdict::Differs);
        assert!(Verdict::Equivalent.replicates() && Verdict::Within2x.replicates());
        assert!(!Verdict::ConsistentButWide.replicates() && !Verdict::Undecided.replicates());
    }

    #[test]
    fn edge_cases_single_trial_zero_std_and_censored_cells() {
        // A single trial has no std: undecided whatever its mean, and neither p-value exists.
        let one = judge(Moments { mean: 50.0, std: None, n: 1 }, 50.0, 5.0, 10);
        assert_eq!((one.verdict, one.tost_p, one.tost2x_p), (Verdict::Undecided, None, None));
        // No positive reference: undecided.
        assert_eq!(judge(m(3.0, 1.0, 10), 0.0, 1.0, 10).verdict, Verdict::Undecided);
        // Zero spread on both sides: the point estimate decides, strictly inside the bounds.
        assert_eq!(judge(m(2.4, 0.0, 10), 2.0, 0.0, 10).verdict, Verdict::Equivalent);
        assert_eq!(judge(m(3.0, 0.0, 10), 2.0, 0.0, 10).verdict, Verdict::Within2x);
        assert_eq!(judge(m(4.0, 0.0, 10), 2.0, 0.0, 10).verdict, Verdict::Differs, "2× is outside");
        assert_eq!(judge(m(2.0, 0.0, 10), 2.0, 0.0, 10).verdict, Verdict::Equivalent);
        // A censored cell (every trial at a cap of 1,000 episodes, std 0) against a paper value
        // of 600 ± 50: judged on the capped values like any sample; its mean is a lower bound.
        let capped = judge(m(1000.0, 0.0, 20), 600.0, 50.0, 10);
        assert_eq!(capped.verdict, Verdict::Within2x);
        assert!(capped.tost_p.unwrap() > 0.05 && capped.tost2x_p.unwrap() < 0.05);
    }

    #[test]
    fn fewer_paper_runs_widen_every_test() {
        // 80 ± 10 (n 20) against 50 ± 20: within 2× at n_paper = 10 and 5 (SciPy's TOST p =
        // 0.0061, 0.0441), not at 3 (0.1111), where it is not within two standard errors either
        // (|30| > 2·√(400/3 + 100/20) = 23.5).
        assert_eq!(judge(m(80.0, 10.0, 20), 50.0, 20.0, 10).verdict, Verdict::Within2x);
        assert_eq!(judge(m(80.0, 10.0, 20), 50.0, 20.0, 5).verdict, Verdict::Within2x);
        assert_eq!(judge(m(80.0, 10.0, 20), 50.0, 20.0, 3).verdict, Verdict::Differs);
        // 60 ± 10 stays within 2× at every n (p = 0.0001, 0.0077, 0.0443).
        assert_eq!(judge(m(60.0, 10.0, 20), 50.0, 20.0, 3).verdict, Verdict::Within2x);
    }

    #[test]
    fn cause_takes_the_first_rule_that_applies() {
        use Verdict::*;
        assert_eq!(cause(Within2x, true, Some(Differs)), Cause::Replicates);
        assert_eq!(cause(ConsistentButWide, true, Some(Equivalent)), Cause::PaperInconsistent);
        assert_eq!(cause(Differs, false, Some(Within2x)), Cause::Argmin);
        assert_eq!(cause(ConsistentButWide, false, Some(ConsistentButWide)), Cause::DiffersAtPaperConfig);
        assert_eq!(cause(Differs, false, Some(Undecided)), Cause::DiffersAtPaperConfig);
        assert_eq!(cause(Undecided, false, None), Cause::Unexplained);
        assert_eq!(Cause::DiffersAtPaperConfig.label(), "differs-at-paper-config");
        use FitVerdict as F;
        assert_eq!(cause_2se(F::Replicates, true, None), "replicates");
        assert_eq!(cause_2se(F::Within2x, true, Some(F::Replicates)), "paper-inconsistent");
        assert_eq!(cause_2se(F::Within2x, false, Some(F::Replicates)), "argmin");
        assert_eq!(cause_2se(F::Within2x, false, Some(F::Within2x)), "learner");
        assert_eq!(cause_2se(F::DoesNotReplicate, false, None), "unexplained");
    }

    #[test]
    fn spread_interval_from_the_f_distribution() {
        // s = 130 over 20 trials against S = 13.8 over 10 runs: ratio 9.42; SciPy:
        // sqrt(r² / f.ppf(0.975, 19, 9)) = 4.908440, sqrt(r² / f.ppf(0.025, 19, 9)) = 15.98691.
        let s = spread(Some(130.0), 20, 13.8, 10).unwrap();
        assert!((s.ratio - 130.0 / 13.8).abs() < 1e-12);
        assert!((s.lo - 4.908_439_860).abs() < 1e-8 && (s.hi - 15.986_906_463).abs() < 1e-8, "{s:?}");
        assert!(s.differs());
        let same = spread(Some(10.0), 20, 10.0, 10).unwrap();
        assert!(!same.differs() && same.lo < 1.0 && same.hi > 1.0);
        assert_eq!(spread(None, 1, 10.0, 10), None);
        assert_eq!(spread(Some(1.0), 10, 0.0, 10), None);
    }
}
