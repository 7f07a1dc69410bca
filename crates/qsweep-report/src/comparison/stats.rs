//! Each matched cell tested, and the cells together: the numbers of `qsweep compare`, every one a
//! pure function of the cells' values (the bootstrap is seeded from the cell's shared values), so
//! a rerun gives the same bytes.
//!
//! B ÷ A's 95 % interval is the seeded percentile bootstrap when both sides have every trial's
//! value (pipelines), and the delta method on the log ratio when a side has only its moments (a
//! report folder's `cells.parquet`): [`RatioInterval`] says which. Welch's test and TOST need the
//! moments alone, so they are the same tests either way.
//!
//! A cell's verdict, in the project's vocabulary: `equivalent` when TOST shows B ÷ A within the
//! margin; `differs` when Welch's two-sided p < 0.05 and it is not equivalent; `undecided`
//! otherwise, including a cell where a test cannot be computed (fewer than two values on a side,
//! or a mean of A that is not positive for the ratio), whose `note` says why. Overall, k of the m
//! cells with a Welch p have p < 0.05; chance alone gives 5 %, so P(X ≥ k | Binomial(m, 0.05))
//! < 0.05 is "beyond chance".

use super::cells::Sample;
use super::matching::{cell_label, CellSamples, Matched};
use qsweep_pipeline::analysis::welch::welch_p_two_sided_moments;
use qsweep_pipeline::analysis::{
    binomial_sf, bootstrap_ratio_ci, ratio_ci_delta, tost_ratio, Tost, BOOTSTRAP_RESAMPLES,
};
use qsweep_pipeline::program::model::ParamValue;

/// The level of Welch's test, of each one-sided test of TOST, and of the binomial test.
pub const ALPHA: f64 = 0.05;

/// A cell's verdict.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Verdict {
    /// TOST shows B ÷ A within the margin.
    Equivalent,
    /// Welch's p < 0.05 and not equivalent.
    Differs,
    /// Neither (or no test could be computed).
    Undecided,
}

impl Verdict {
    /// The word in every output.
    pub fn word(self) -> &'static str {
        match self {
            Self::Equivalent => "equivalent",
            Self::Differs => "differs",
            Self::Undecided => "undecided",
        }
    }
}

/// How a cell's interval of B ÷ A was computed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RatioInterval {
    /// The seeded percentile bootstrap (2,000 resamples) of both sides' trials.
    Bootstrap,
    /// From the moments alone: the delta method on the log ratio, `ratio · exp(±1.96 · se)`
    /// ([`qsweep_pipeline::analysis::ratio_ci_delta`]).
    DeltaLog,
}

impl RatioInterval {
    /// The word in every output.
    pub fn word(self) -> &'static str {
        match self {
            Self::Bootstrap => "bootstrap",
            Self::DeltaLog => "delta-log",
        }
    }
}

/// One matched cell with trials on both sides, tested.
#[derive(Debug, Clone, PartialEq)]
pub struct CellComparison {
    /// The shared params' values (A's).
    pub values: Vec<ParamValue>,
    /// `name=value …` by A's names.
    pub label: String,
    /// Succeeded trials of A and of B.
    pub n: (usize, usize),
    /// Means of A and of B.
    pub mean: (f64, f64),
    /// Sample stds (`None` below two values).
    pub std: (Option<f64>, Option<f64>),
    /// mean B ÷ mean A (`None` when mean A is not positive).
    pub ratio: Option<f64>,
    /// Its 95 % interval.
    pub ratio_ci: Option<(f64, f64)>,
    /// How that interval was computed.
    pub interval: RatioInterval,
    /// Welch's two-sided p (`None` with fewer than two values on a side).
    pub p: Option<f64>,
    /// TOST of B against A at the margin (`None` when it cannot be computed).
    pub tost: Option<Tost>,
    /// The verdict.
    pub verdict: Verdict,
    /// Why a test could not be computed, when one could not.
    pub note: Option<String>,
}

/// A matched cell without trials on a side.
#[derive(Debug, Clone, PartialEq)]
pub struct MissingCell {
    /// `name=value …` by A's names.
    pub label: String,
    /// Which side lacks rows: `A`, `B` or `both`.
    pub side: &'static str,
}

/// The cells together.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Overall {
    /// Cells with a Welch p (m).
    pub tested: usize,
    /// Of those, with p < 0.05 (k).
    pub significant: usize,
    /// What chance alone gives: 0.05 m.
    pub expected: f64,
    /// P(X ≥ k | Binomial(m, 0.05)).
    pub binomial_p: f64,
    /// Whether that p < 0.05.
    pub beyond_chance: bool,
    /// Cells per verdict: equivalent, differs, undecided.
    pub verdicts: (usize, usize, usize),
}

impl Overall {
    /// "beyond chance" or "within chance".
    pub fn statement(&self) -> &'static str {
        if self.beyond_chance {
            "beyond chance"
        } else {
            "within chance"
        }
    }

    /// The one line that answers: `3 of 40 cells with p < 0.05 (2.0 expected by chance): binomial p = 0.32, within chance`.
    pub fn line(&self) -> String {
        format!(
            "{} of {} cells with p < 0.05 ({:.1} expected by chance): binomial p = {}, {}",
            self.significant,
            self.tested,
            self.expected,
            p_text(self.binomial_p),
            self.statement()
        )
    }
}

/// A p-value as text: three decimals, two significant digits below 0.001, and `0` for exactly 0
/// (two samples without spread and with different means), never `0.000`, which reads as rounded.
pub fn p_text(p: f64) -> String {
    if p == 0.0 {
        "0".into()
    } else if p < 0.001 && p > 0.0 {
        format!("{p:.1e}")
    } else {
        format!("{p:.3}")
    }
}

/// The comparison: every matched cell tested, the cells lacking trials, and the overall answer.
#[derive(Debug, Clone, PartialEq)]
pub struct Comparison {
    /// The sides' labels (A, B).
    pub labels: (String, String),
    /// The shared params: (A's name, B's name).
    pub shared: Vec<(String, String)>,
    /// The metric: (A's name, B's name).
    pub metric: (String, String),
    /// The equivalence margin on B ÷ A.
    pub margin: (f64, f64),
    /// The matched cells with trials on both sides, in A's plan order.
    pub cells: Vec<CellComparison>,
    /// The matched cells lacking trials on a side.
    pub missing: Vec<MissingCell>,
    /// Cells only A plans, and only B plans (labels by A's names).
    pub only: (Vec<String>, Vec<String>),
    /// The overall answer.
    pub overall: Overall,
}

/// Test every cell of `m` at `margin`, and the cells together.
pub fn compare_matched(m: Matched, margin: (f64, f64)) -> Comparison {
    let mut cells = Vec::new();
    let mut missing = Vec::new();
    for c in &m.cells {
        let label = cell_label(&m.shared, &c.values);
        match (c.a.n() == 0, c.b.n() == 0) {
            (false, false) => cells.push(cell(c, label, margin)),
            (a, b) => missing.push(MissingCell {
                label,
                side: match (a, b) {
                    (true, true) => "both",
                    (true, false) => "A",
                    _ => "B",
                },
            }),
        }
    }
    let overall = overall(&cells);
    let labels_of = |v: &[Vec<ParamValue>]| v.iter().map(|x| cell_label(&m.shared, x)).collect();
    Comparison {
        only: (labels_of(&m.only_a), labels_of(&m.only_b)),
        labels: m.labels,
        shared: m.shared,
        metric: m.metric,
        margin,
        cells,
        missing,
        overall,
    }
}

/// The bootstrap's seed for a cell: blake3 over its label, so a cell's interval depends on its
/// values alone, not on its position or on other cells.
fn seed_of(label: &str) -> u64 {
    let h = blake3::hash(format!("qsweep-compare\0{label}").as_bytes());
    u64::from_le_bytes(h.as_bytes()[..8].try_into().expect("8 bytes"))
}

/// One cell tested.
fn cell(c: &CellSamples, label: String, margin: (f64, f64)) -> CellComparison {
    let (a, b) = (c.a.moments(), c.b.moments());
    let ratio = (a.mean > 0.0).then(|| b.mean / a.mean);
    let (ratio_ci, interval) = match (&c.a, &c.b) {
        (Sample::Values(va), Sample::Values(vb)) => {
            (bootstrap_ratio_ci(va, vb, BOOTSTRAP_RESAMPLES, seed_of(&label)), RatioInterval::Bootstrap)
        }
        _ => (ratio.and_then(|_| ratio_ci_delta(a, b)), RatioInterval::DeltaLog),
    };
    let p = welch_p_two_sided_moments(a, b);
    let tost = tost_ratio(b, a, margin, ALPHA);
    let verdict = match (tost, p) {
        (Some(t), _) if t.equivalent => Verdict::Equivalent,
        (_, Some(p)) if p < ALPHA => Verdict::Differs,
        _ => Verdict::Undecided,
    };
    let note = if a.n < 2 || b.n < 2 {
        Some(format!("no test: {} and {} trials (each side needs 2)", a.n, b.n))
    } else if a.mean <= 0.0 {
        Some("no ratio or equivalence test: the mean of A is not positive".to_string())
    } else {
        None
    };
    CellComparison {
        values: c.values.clone(),
        label,
        n: (a.n, b.n),
        mean: (a.mean, b.mean),
        std: (a.std, b.std),
        ratio,
        ratio_ci,
        interval,
        p,
        tost,
        verdict,
        note,
    }
}

/// The cells together (see the module documentation).
fn overall(cells: &[CellComparison]) -> Overall {
    let tested = cells.iter().filter(|c| c.p.is_some()).count();
    let significant = cells.iter().filter(|c| c.p.is_some_and(|p| p < ALPHA)).count();
    let binomial_p = binomial_sf(significant as u64, tested as u64, ALPHA);
    let count = |v: Verdict| cells.iter().filter(|c| c.verdict == v).count();
    Overall {
        tested,
        significant,
        expected: ALPHA * tested as f64,
        binomial_p,
        beyond_chance: binomial_p < ALPHA,
        verdicts: (count(Verdict::Equivalent), count(Verdict::Differs), count(Verdict::Undecided)),
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn p_values_read_as_what_they_are() {
        assert_eq!(p_text(0.0), "0");
        assert_eq!(p_text(0.00012), "1.2e-4");
        assert_eq!(p_text(0.0421), "0.042");
        assert_eq!(p_text(1.0), "1.000");
    }

    use super::*;
    use qsweep_pipeline::analysis::Moments;

    fn matched(cells: Vec<(Vec<f64>, Vec<f64>)>) -> Matched {
        Matched {
            labels: ("a.yaml".into(), "b.yaml".into()),
            shared: vec![("x".into(), "x".into())],
            metric: ("v".into(), "v".into()),
            cells: cells
                .into_iter()
                .enumerate()
                .map(|(i, (a, b))| CellSamples {
                    values: vec![ParamValue::Int(i as i64)],
                    a: Sample::Values(a),
                    b: Sample::Values(b),
                })
                .collect(),
            only_a: vec![],
            only_b: vec![],
        }
    }

    #[test]
    fn verdicts_follow_tost_then_welch() {
        // 20 % apart and tight is within the margin 0.80–1.25: equivalent, although p < 0.05.
        let within = compare_matched(
            matched(vec![(vec![100.0, 101.0, 99.0, 100.5, 99.5], vec![120.0, 121.0, 119.0, 120.5, 119.5])]),
            (0.8, 1.25),
        );
        assert_eq!(within.cells[0].verdict, Verdict::Equivalent);
        assert!(within.cells[0].p.unwrap() < 1e-6);
        let c = compare_matched(
            matched(vec![
                // Close and tight: equivalent.
                (vec![100.0, 101.0, 99.0, 100.5, 99.5], vec![100.2, 100.8, 99.4, 100.1, 99.9]),
                // 50 % apart and tight: differs.
                (vec![100.0, 101.0, 99.0, 100.5, 99.5], vec![150.0, 151.0, 149.0, 150.5, 149.5]),
                // Too noisy to say: undecided.
                (vec![100.0, 150.0, 60.0], vec![90.0, 170.0, 50.0]),
                // One trial on a side: undecided, and said why.
                (vec![100.0], vec![100.0, 101.0]),
                // Identical values without spread: p = 1, equivalent.
                (vec![5.0; 3], vec![5.0; 4]),
                // No rows on B: missing.
                (vec![1.0, 2.0], vec![]),
            ]),
            (0.8, 1.25),
        );
        let v: Vec<&str> = c.cells.iter().map(|c| c.verdict.word()).collect();
        assert_eq!(v, ["equivalent", "differs", "undecided", "undecided", "equivalent"]);
        assert!(c.cells[3].note.as_deref().unwrap().contains("1 and 2 trials"), "{:?}", c.cells[3].note);
        assert_eq!(c.cells[4].p, Some(1.0));
        assert_eq!(c.cells[4].ratio_ci, Some((1.0, 1.0)));
        assert_eq!(c.missing, [MissingCell { label: "x=5".into(), side: "B" }]);
        let r = c.cells[1].ratio.unwrap();
        let (lo, hi) = c.cells[1].ratio_ci.unwrap();
        assert!((r - 1.5).abs() < 1e-12 && lo < r && r < hi && lo > 1.45 && hi < 1.55, "{r} [{lo}, {hi}]");
        // 1 of 4 tested cells with p < 0.05: P(X ≥ 1 | Bin(4, 0.05)) = 1 − 0.95⁴.
        assert_eq!((c.overall.tested, c.overall.significant), (4, 1));
        assert!((c.overall.binomial_p - (1.0 - 0.95f64.powi(4))).abs() < 1e-12);
        assert_eq!(c.overall.statement(), "within chance");
        assert_eq!(c.overall.verdicts, (2, 1, 2));
    }

    #[test]
    fn the_ratio_interval_depends_on_the_cell_alone() {
        let a = vec![10.0, 12.0, 9.0, 11.0];
        let b = vec![11.0, 13.0, 12.0, 10.0];
        let one = compare_matched(matched(vec![(a.clone(), b.clone())]), (0.8, 1.25));
        let two = compare_matched(matched(vec![(a.clone(), b.clone()), (b.clone(), a.clone())]), (0.8, 1.25));
        assert_eq!(one.cells[0], two.cells[0], "another cell beside it changes nothing");
        assert_eq!(one, compare_matched(matched(vec![(a, b)]), (0.8, 1.25)), "a rerun is identical");
    }

    #[test]
    fn moments_give_the_same_tests_and_a_delta_interval() {
        let a = vec![100.0, 101.0, 99.0, 100.5, 99.5];
        let b = vec![150.0, 151.0, 149.0, 150.5, 149.5];
        let values = compare_matched(matched(vec![(a.clone(), b.clone())]), (0.8, 1.25));
        let mut m = matched(vec![(a.clone(), b.clone())]);
        m.cells[0].a = Sample::Moments(Moments::of(&a));
        let moments = compare_matched(m, (0.8, 1.25));
        let (v, x) = (&values.cells[0], &moments.cells[0]);
        assert_eq!((v.p, v.tost, v.ratio, v.verdict), (x.p, x.tost, x.ratio, x.verdict), "the same tests");
        assert_eq!((v.interval, x.interval), (RatioInterval::Bootstrap, RatioInterval::DeltaLog));
        assert_eq!(x.ratio_ci, ratio_ci_delta(Moments::of(&a), Moments::of(&b)));
        let ((lo, hi), r) = (x.ratio_ci.unwrap(), x.ratio.unwrap());
        assert!(lo < r && r < hi && lo > 1.48 && hi < 1.52, "{r} [{lo}, {hi}]");
    }

    #[test]
    fn many_cells_all_shifted_are_beyond_chance() {
        let base: Vec<f64> = (0..8).map(|i| 100.0 + f64::from(i)).collect();
        let moved: Vec<f64> = base.iter().map(|v| v * 1.3).collect();
        let c = compare_matched(matched(vec![(base, moved); 10]), (0.8, 1.25));
        assert_eq!((c.overall.significant, c.overall.tested), (10, 10));
        assert!(c.overall.beyond_chance && c.overall.binomial_p < 1e-12);
        assert!(c.overall.line().ends_with("beyond chance"), "{}", c.overall.line());
    }
}
