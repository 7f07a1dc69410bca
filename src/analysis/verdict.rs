//! The replication verdict of one Table III row against its published value, defined once: the
//! best cell's and the cell at the paper's configuration are judged by the same rule, for the fit
//! measure (`report::compare::fit`) and Table III's columns alike. And the cause of a row that does
//! not replicate, by the rule pre-registered in docs/preregistration.md (issue #40).

/// Seeds behind each reference value (the paper's ten runs), for the standard error.
pub const REFERENCE_N: f64 = 10.0;

/// The factor within which a row that does not replicate still counts as "within 2×":
/// 1/TWOFOLD ≤ ours/reference ≤ TWOFOLD.
pub const TWOFOLD: f64 = 2.0;

/// The verdict rule, as stated in the caption.
pub const VERDICT_RULE: &str = "A Table III row replicates its reference when |ours − reference| ≤ \
2·√(s_ref²/10 + s_ours²/n) (two standard errors; the reference has 10 runs, a row with a single \
trial has no std and does not replicate); it is within 2× when it does not replicate but 0.5 ≤ \
ours/reference ≤ 2.";

/// Verdict of one Table III row against its reference.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Verdict {
    /// Within two standard errors.
    Replicates,
    /// Not replicating, but ours/reference ∈ [1/TWOFOLD, TWOFOLD].
    Within2x,
    /// Neither.
    DoesNotReplicate,
}

impl Verdict {
    /// The verdict as a table value: `replicates`, `within-2x` or `no`.
    pub fn label(self) -> &'static str {
        match self {
            Self::Replicates => "replicates",
            Self::Within2x => "within-2x",
            Self::DoesNotReplicate => "no",
        }
    }
}

/// The verdict for our mean and std over `n` trials against a reference mean and std.
pub fn verdict(ours: f64, ours_std: Option<f64>, n: usize, ref_mean: f64, ref_std: f64) -> Verdict {
    let replicates = ours_std.is_some_and(|s| {
        let se = (ref_std * ref_std / REFERENCE_N + s * s / n as f64).sqrt();
        (ours - ref_mean).abs() <= 2.0 * se
    });
    if replicates {
        Verdict::Replicates
    } else if ref_mean > 0.0 && (1.0 / TWOFOLD..=TWOFOLD).contains(&(ours / ref_mean)) {
        Verdict::Within2x
    } else {
        Verdict::DoesNotReplicate
    }
}

/// Why a Table III row does or does not replicate (the pre-registered rule, first that applies).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Cause {
    /// The best cell replicates.
    Replicates,
    /// The row is in a pair of Table III rows that contradict each other
    /// ([`crate::analysis::consistency`]).
    PaperInconsistent,
    /// Ours at the paper's configuration replicates, the best cell does not: our grid picks
    /// another configuration.
    Argmin,
    /// Ours at the paper's configuration does not replicate: the learner differs there.
    Learner,
    /// Neither comparison is available.
    Unexplained,
}

impl Cause {
    /// Every cause, in the rule's order.
    pub const ALL: [Cause; 5] =
        [Self::Replicates, Self::Argmin, Self::PaperInconsistent, Self::Learner, Self::Unexplained];

    /// The cause as a table value.
    pub fn label(self) -> &'static str {
        match self {
            Self::Replicates => "replicates",
            Self::PaperInconsistent => "paper-inconsistent",
            Self::Argmin => "argmin",
            Self::Learner => "learner",
            Self::Unexplained => "unexplained",
        }
    }
}

/// The cause rule, as stated in captions.
pub const CAUSE_RULE: &str = "Cause (pre-registered in docs/preregistration.md), the first that \
applies: replicates (the best cell replicates); paper-inconsistent (the row is in a pair of Table \
III rows the paper's own numbers contradict); argmin (ours at the paper's configuration replicates, \
the best cell does not: our grid picks another configuration); learner (ours at the paper's \
configuration does not replicate); unexplained (no trials at the paper's configuration).";

/// The cause of a row from the best cell's verdict, whether the row is in a contradictory pair, and
/// the verdict of the cell at the paper's configuration (`None`: no such cell with trials).
pub fn cause(best: Verdict, inconsistent: bool, paper_cell: Option<Verdict>) -> Cause {
    match (best, inconsistent, paper_cell) {
        (Verdict::Replicates, _, _) => Cause::Replicates,
        (_, true, _) => Cause::PaperInconsistent,
        (_, _, Some(Verdict::Replicates)) => Cause::Argmin,
        (_, _, Some(_)) => Cause::Learner,
        (_, _, None) => Cause::Unexplained,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn verdicts_follow_the_replication_rule() {
        // se = √(3²/10 + 2²/4) = √1.9 ≈ 1.378; 2·se ≈ 2.757.
        assert_eq!(verdict(8.7, Some(2.0), 4, 6.0, 3.0), Verdict::Replicates);
        assert_eq!(verdict(8.8, Some(2.0), 4, 6.0, 3.0), Verdict::Within2x);
        assert_eq!(verdict(12.0, Some(2.0), 4, 6.0, 3.0), Verdict::Within2x);
        assert_eq!(verdict(12.1, Some(2.0), 4, 6.0, 3.0), Verdict::DoesNotReplicate);
        assert_eq!(verdict(3.0, None, 1, 6.0, 3.0), Verdict::Within2x, "no std: cannot replicate");
        assert_eq!(verdict(2.9, None, 1, 6.0, 3.0), Verdict::DoesNotReplicate);
        assert_eq!(Verdict::Within2x.label(), "within-2x");
    }

    #[test]
    fn cause_takes_the_first_rule_that_applies() {
        use Verdict::*;
        assert_eq!(cause(Replicates, true, Some(DoesNotReplicate)), Cause::Replicates);
        assert_eq!(cause(Within2x, true, Some(Replicates)), Cause::PaperInconsistent);
        assert_eq!(cause(DoesNotReplicate, false, Some(Replicates)), Cause::Argmin);
        assert_eq!(cause(Within2x, false, Some(Within2x)), Cause::Learner);
        assert_eq!(cause(DoesNotReplicate, false, Some(DoesNotReplicate)), Cause::Learner);
        assert_eq!(cause(DoesNotReplicate, false, None), Cause::Unexplained);
        assert_eq!(Cause::PaperInconsistent.label(), "paper-inconsistent");
    }
}
