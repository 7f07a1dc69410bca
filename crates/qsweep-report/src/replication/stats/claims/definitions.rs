//! The claims as declared: the ten claims of the paper ([`CLAIMS`], fixed in
//! `docs/preregistration.md` before any was computed), what a claim reads of a cell, and how one
//! came out (its estimate, interval and verdict, [`result`]).

use qsweep_engine::env::SystemKind;
use qsweep_engine::Algorithm;

/// The systems of the paper's study: its claims speak of these three, whatever other systems the
/// engine runs.
pub const PAPER_SYSTEMS: [SystemKind; 3] =
    [SystemKind::BallBeam, SystemKind::CartPole, SystemKind::MountainCar];

/// Bootstrap resamples per claim.
pub const CLAIM_RESAMPLES: usize = 1000;

/// The verdict rule, as stated in captions.
pub const CLAIM_RULE: &str = "Each claim is a statistic over the variant's cells (definitions in \
docs/preregistration.md) with a 95 % percentile-bootstrap interval (1,000 resamples, each redrawing \
every cell's trials with replacement). holds: the interval lies entirely on the claimed side of the \
null value; reversed: entirely on the other side; undecided: otherwise; — : not computable here.";

/// Which side of the null a claim asserts.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Side {
    /// The statistic is claimed to exceed the null.
    Above,
    /// The statistic is claimed to lie below the null.
    Below,
}

/// One claim of the paper, as declared.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Claim {
    /// Identifier (a `conclusions.csv` key).
    pub id: &'static str,
    /// The paper's words, shortened, and where they are.
    pub text: &'static str,
    /// What the statistic measures.
    pub statistic: &'static str,
    /// The null value.
    pub null: f64,
    /// The claimed side.
    pub side: Side,
    /// Whether the null itself is on the claimed side (a threshold to reach, like "at least 95 %
    /// converged"), rather than the boundary of a strict inequality.
    pub at_null_holds: bool,
}

/// The ten claims, in the order of `docs/preregistration.md`.
pub const CLAIMS: [Claim; 10] = [
    Claim {
        id: "qlambda-beats-q0",
        text: "Q(λ) outperforms Q(0) in all environments (Conclusion)",
        statistic: "smallest over systems of P(Q(λ) cell mean < Q(0) cell mean), paired cells",
        null: 0.5,
        side: Side::Above,
        at_null_holds: false,
    },
    Claim {
        id: "traces-delayed-reward",
        text: "traces overcome Mountain Car's delayed reward (Conclusion)",
        statistic: "Mountain Car: success rate of Q(λ) trials − of Q(0) trials",
        null: 0.0,
        side: Side::Above,
        at_null_holds: false,
    },
    Claim {
        id: "compact-best",
        text: "compact configurations (2–4 bins/sets, 2–4 actions) are often optimal (§V)",
        statistic: "fraction of the best cells that are compact − fraction of all cells",
        null: 0.0,
        side: Side::Above,
        at_null_holds: false,
    },
    Claim {
        id: "excessive-hinders",
        text: "excessive discretisation or fuzzy granularity hinders learning (Conclusion)",
        statistic: "mean over heatmaps of Spearman ρ(state count, cell mean)",
        null: 0.0,
        side: Side::Above,
        at_null_holds: false,
    },
    Claim {
        id: "qlambda-robust",
        text: "Q(λ) is more robust to representation complexity (§V)",
        statistic: "mean over experiments of ρ(Q(0)) − ρ(Q(λ))",
        null: 0.0,
        side: Side::Above,
        at_null_holds: false,
    },
    Claim {
        id: "fuzzy-qlambda-fastest",
        text: "fuzzy Q(λ) converges fastest (Abstract, §V)",
        statistic: "mean over systems of ln(best of the other three ÷ best fuzzy Q(λ))",
        null: 0.0,
        side: Side::Above,
        at_null_holds: false,
    },
    Claim {
        id: "fuzzy-benefit-low-granularity",
        text: "the fuzzy benefit is largest at low to moderate granularity (Discussion)",
        statistic: "mean over systems and algorithms of ρ(state count, ln(crisp ÷ fuzzy)), Exp. 1 vs 3",
        null: 0.0,
        side: Side::Below,
        at_null_holds: false,
    },
    Claim {
        id: "mountain-car-gap-narrowed",
        text: "in Mountain Car the gap between methods narrowed (Discussion)",
        statistic: "mean |ln(best Q(0) ÷ best Q(λ))|: Mountain Car − the other systems",
        null: 0.0,
        side: Side::Below,
        at_null_holds: false,
    },
    Claim {
        id: "qlambda-richer-fuzzy",
        text: "Q(λ) favours slightly richer fuzzy representations than Q(0) (§V)",
        statistic: "mean over fuzzy experiments of ln(states of best Q(λ) ÷ of best Q(0))",
        null: 0.0,
        side: Side::Above,
        at_null_holds: false,
    },
    Claim {
        id: "cart-pole-converged",
        text: "in Cart-Pole all algorithms ultimately converged (§V)",
        statistic: "fraction of Cart-Pole trials that reached the goal",
        null: 0.95,
        side: Side::Above,
        at_null_holds: true,
    },
];

/// What a claim needs of one cell.
#[derive(Debug, Clone, PartialEq)]
pub struct ClaimCell {
    /// The system.
    pub system: SystemKind,
    /// Index of the cell's experiment in the variant (cells of one heatmap share it and the
    /// algorithm).
    pub experiment: usize,
    /// The experiment's id as written ("1" … "4" in the paper's pipelines).
    pub experiment_id: String,
    /// Fuzzy sets (true) or crisp bins.
    pub fuzzy: bool,
    /// The algorithm.
    pub algorithm: Algorithm,
    /// Bins or fuzzy sets per state variable.
    pub resolution: Vec<u32>,
    /// Number of actions.
    pub actions: u32,
    /// Episodes each present trial counts (Table III's rule).
    pub counted: Vec<f64>,
    /// Whether each present trial reached the goal.
    pub converged: Vec<bool>,
    /// Seed of this cell's resamples.
    pub seed: u64,
}

impl ClaimCell {
    /// Its number of states (bins or sets per variable, multiplied).
    pub(super) fn states(&self) -> f64 {
        self.resolution.iter().map(|&r| f64::from(r)).product()
    }

    /// At most 4 bins or sets per variable and at most 4 actions.
    pub(super) fn compact(&self) -> bool {
        self.resolution.iter().all(|&r| r <= 4) && self.actions <= 4
    }
}

/// How one claim came out in one variant.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ClaimResult {
    /// The claim.
    pub claim: &'static Claim,
    /// The statistic on the cells as they are (`None`: not computable, e.g. a system missing).
    pub estimate: Option<f64>,
    /// 95 % bootstrap interval (`None` with the estimate, or when most resamples are undefined).
    pub interval: Option<(f64, f64)>,
    /// The verdict.
    pub verdict: ClaimVerdict,
}

/// A claim's verdict in one variant.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ClaimVerdict {
    /// The interval lies on the claimed side of the null.
    Holds,
    /// The interval lies on the other side.
    Reversed,
    /// The interval contains the null.
    Undecided,
    /// Not computable from these cells.
    Missing,
}

impl ClaimVerdict {
    /// The word the reports print.
    pub fn word(self) -> &'static str {
        match self {
            Self::Holds => "holds",
            Self::Reversed => "reversed",
            Self::Undecided => "undecided",
            Self::Missing => "—",
        }
    }
}

/// One resample's view of a cell: its mean and its successes out of n.
#[derive(Debug, Clone, Copy)]
pub(super) struct View {
    pub(super) mean: Option<f64>,
    pub(super) successes: usize,
    pub(super) n: usize,
}

/// A claim's result from its estimate and interval (the verdict follows from the interval).
pub fn result(claim: &'static Claim, estimate: Option<f64>, interval: Option<(f64, f64)>) -> ClaimResult {
    ClaimResult { claim, estimate, interval, verdict: verdict(claim, interval) }
}

/// The verdict rule ([`CLAIM_RULE`]) for one interval.
fn verdict(claim: &Claim, interval: Option<(f64, f64)>) -> ClaimVerdict {
    let Some((lo, hi)) = interval else { return ClaimVerdict::Missing };
    let above = if claim.at_null_holds { lo >= claim.null } else { lo > claim.null };
    let below = hi < claim.null;
    match (claim.side, above, below) {
        (Side::Above, true, _) | (Side::Below, _, true) => ClaimVerdict::Holds,
        (Side::Above, _, true) | (Side::Below, true, _) => ClaimVerdict::Reversed,
        _ => ClaimVerdict::Undecided,
    }
}
