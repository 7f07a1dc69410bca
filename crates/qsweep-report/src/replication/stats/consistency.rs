//! Where the paper contradicts itself: pairs of Table III rows whose grids overlap, tested from the
//! published numbers alone (pre-registered in docs/preregistration.md, issue #40).
//!
//! A Table III value is the minimum over its experiment's grid. When row A's published
//! configuration is a cell of row B's grid (the same system, representation and algorithm, the
//! same bins or sets per variable and the same action count, hence the same action set A_n of
//! eq. 22), B's minimum cannot exceed A's value; where the two configurations coincide the means
//! must agree. The two published means (an assumed n_paper runs each: the paper never states it)
//! are compared by a two-sided Welch test at [`ALPHA`]; a pair is contradictory when the test
//! rejects in a direction the grids forbid, and then costs one row: the one whose published
//! minimum is undercut by a cell of its own grid ([`Pair::designated`]).

use qsweep_engine::env::SystemKind;
use qsweep_engine::repr::ReprKind;
use qsweep_engine::Algorithm;
use qsweep_pipeline::analysis::welch::student_t_sf;

/// The test's level (two-sided).
pub const ALPHA: f64 = 0.05;

/// The rule, as stated in captions.
pub const CONSISTENCY_RULE: &str = "Comparable pair: two Table III rows of the same system, \
representation and algorithm where one row's published configuration is a cell of the other row's \
grid, so the other's published minimum cannot exceed it. Welch's t-test of the two published means \
(10 runs each assumed), two-sided, α = 0.05; contradictory: significant in a direction the grids \
forbid. The pair costs one row: the minimum undercut by a cell of its own grid.";

/// A configuration: bins or sets per state variable, and the action count.
pub type Config = (Vec<u32>, u32);

/// One published Table III row and its experiment's grid.
#[derive(Debug, Clone, PartialEq)]
pub struct Published {
    /// The system.
    pub system: SystemKind,
    /// Crisp or fuzzy.
    pub repr: ReprKind,
    /// The experiment id.
    pub experiment: String,
    /// The algorithm.
    pub algorithm: Algorithm,
    /// The published mean.
    pub mean: f64,
    /// The published std.
    pub std: f64,
    /// The published best configuration (`None` where the paper gives none).
    pub config: Option<Config>,
    /// Every configuration of this row's grid (the experiment's cells of the algorithm).
    pub grid: Vec<Config>,
}

impl Published {
    /// Whether this row's published configuration is a cell of `other`'s grid.
    fn within(&self, other: &Published) -> bool {
        self.config.as_ref().is_some_and(|c| other.grid.contains(c))
    }
}

/// What the grids imply about a pair's two means.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Implied {
    /// A's configuration is in B's grid: B's mean ≤ A's.
    BAtMostA,
    /// B's configuration is in A's grid: A's mean ≤ B's.
    AAtMostB,
    /// Each lies in the other's grid: equal means.
    Equal,
}

impl Implied {
    /// As the report writes it.
    pub fn label(self) -> &'static str {
        match self {
            Self::BAtMostA => "b ≤ a",
            Self::AAtMostB => "a ≤ b",
            Self::Equal => "a = b",
        }
    }
}

/// Welch's t-test from two samples' summaries: t of (m_b − m_a), the Welch–Satterthwaite degrees of
/// freedom and the two-sided p. Without spread in either sample, p is 0 for different means and 1
/// for equal ones (df is then infinite).
pub fn welch_summary(a: (f64, f64, f64), b: (f64, f64, f64)) -> (f64, f64, f64) {
    let ((ma, sa, na), (mb, sb, nb)) = (a, b);
    let (va, vb) = (sa * sa / na, sb * sb / nb);
    let se2 = va + vb;
    if se2 == 0.0 {
        let p = if ma == mb { 1.0 } else { 0.0 };
        let t = if ma == mb { 0.0 } else { (mb - ma).signum() * f64::INFINITY };
        return (t, f64::INFINITY, p);
    }
    let t = (mb - ma) / se2.sqrt();
    let term = |v: f64, n: f64| if v == 0.0 { 0.0 } else { v * v / (n - 1.0) };
    let df = se2 * se2 / (term(va, na) + term(vb, nb));
    (t, df, (2.0 * student_t_sf(t.abs(), df)).min(1.0))
}

/// One comparable pair of rows (indices into the rows given to [`pairs`], `a` before `b`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pair {
    /// The first row.
    pub a: usize,
    /// The second row.
    pub b: usize,
    /// What the grids imply.
    pub implied: Implied,
    /// Welch's t of mean_b − mean_a.
    pub t: f64,
    /// Its degrees of freedom.
    pub df: f64,
    /// Its two-sided p.
    pub p: f64,
    /// Significant at [`ALPHA`] in a direction the grids forbid.
    pub contradictory: bool,
}

impl Pair {
    /// The row a contradictory pair costs (`None` for a consistent pair): the one whose published
    /// value is the minimum of a grid containing the other's configuration, undercut by it; where
    /// each lies in the other's grid, the later experiment's (`b`).
    pub fn designated(&self) -> Option<usize> {
        self.contradictory.then_some(match self.implied {
            Implied::AAtMostB => self.a,
            Implied::BAtMostA | Implied::Equal => self.b,
        })
    }
}

/// Every comparable pair of `rows`, in row order, each published mean taken over `paper_n` runs.
pub fn pairs(rows: &[Published], paper_n: usize) -> Vec<Pair> {
    let n = paper_n as f64;
    let mut out = Vec::new();
    for (i, a) in rows.iter().enumerate() {
        for (j, b) in rows.iter().enumerate().skip(i + 1) {
            if (a.system, a.repr, a.algorithm) != (b.system, b.repr, b.algorithm)
                || a.experiment == b.experiment
            {
                continue;
            }
            let implied = match (a.within(b), b.within(a)) {
                (true, true) => Implied::Equal,
                (true, false) => Implied::BAtMostA,
                (false, true) => Implied::AAtMostB,
                (false, false) => continue,
            };
            let (t, df, p) = welch_summary((a.mean, a.std, n), (b.mean, b.std, n));
            let forbidden = match implied {
                Implied::Equal => true,
                Implied::BAtMostA => b.mean > a.mean,
                Implied::AAtMostB => a.mean > b.mean,
            };
            out.push(Pair { a: i, b: j, implied, t, df, p, contradictory: p < ALPHA && forbidden });
        }
    }
    out
}

/// Whether row `i` belongs to a contradictory pair.
pub fn in_contradiction(pairs: &[Pair], i: usize) -> bool {
    pairs.iter().any(|p| p.contradictory && (p.a == i || p.b == i))
}

/// Whether a contradictory pair designates row `i` ([`Pair::designated`]).
pub fn designated(pairs: &[Pair], i: usize) -> bool {
    pairs.iter().any(|p| p.designated() == Some(i))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(exp: &str, mean: f64, std: f64, config: Config, grid: Vec<Config>) -> Published {
        Published {
            system: SystemKind::BallBeam,
            repr: ReprKind::Crisp,
            experiment: exp.into(),
            algorithm: Algorithm::Q0,
            mean,
            std,
            config: Some(config),
            grid,
        }
    }

    /// Ball-Beam's two crisp Q(0) rows: Exp. 2's best cell (3 × 3, 3 actions) lies in Exp. 1's
    /// 9 × 9 grid with 3 actions, whose published minimum (90.5 ± 25.8) is far above it
    /// (43.2 ± 20.4). Values checked against SciPy: `ttest_ind_from_stats(90.5, 25.8, 10, 43.2,
    /// 20.4, 10, equal_var=False)` gives t = 4.5477, p = 2.816e-4 (two-sided).
    #[test]
    fn ball_beam_q0_rows_contradict_each_other() {
        let square = |a: u32| (2..=10).map(move |k| (vec![k, k], a));
        let full: Vec<Config> = (2..=10).flat_map(|x| (2..=10).map(move |v| (vec![x, v], 3))).collect();
        let rows = [
            row("1", 90.5, 25.8, (vec![5, 3], 3), full),
            row("2", 43.2, 20.4, (vec![3, 3], 3), (2..=10).flat_map(square).collect()),
        ];
        let p = pairs(&rows, 10);
        assert_eq!(p.len(), 1);
        let p = p[0];
        assert_eq!((p.a, p.b, p.implied), (0, 1, Implied::AAtMostB));
        assert!((p.t + 4.5476).abs() < 1e-3, "t = {}", p.t);
        assert!((p.df - 17.09).abs() < 0.01, "df = {}", p.df);
        assert!((p.p - 2.816e-4).abs() < 0.001e-4, "p = {}", p.p);
        assert!(p.contradictory);
        let all = [p];
        assert!(in_contradiction(&all, 0) && in_contradiction(&all, 1));
        // It costs one row: Exp. 1's minimum, undercut by a cell of its own grid.
        assert_eq!(p.designated(), Some(0));
        assert!(designated(&all, 0) && !designated(&all, 1));
        // With fewer paper runs the pair is no longer shown contradictory: SciPy gives
        // p = 0.0131998 at n = 5 (still below α) and 0.0707449 at n = 3.
        let at = |n| pairs(&rows, n)[0];
        assert!((at(5).p - 0.013_199_795).abs() < 1e-8 && at(5).contradictory, "{:?}", at(5));
        assert!((at(3).p - 0.070_744_936).abs() < 1e-8 && !at(3).contradictory, "{:?}", at(3));
        assert_eq!(at(3).designated(), None);
    }

    #[test]
    fn allowed_direction_and_coinciding_rows() {
        let g = vec![(vec![2, 2], 3), (vec![4, 4], 3), (vec![4, 4], 2)];
        // Mountain Car fuzzy Q(0): Exp. 3's 4 × 4 with 3 actions lies in Exp. 4's grid, whose
        // minimum (116.6) is below it (125.9): significant, but the direction the grids allow.
        let rows = [
            row("3", 125.9, 11.2, (vec![4, 4], 3), vec![(vec![4, 4], 3)]),
            row("4", 116.6, 2.9, (vec![4, 4], 2), g.clone()),
        ];
        let p = pairs(&rows, 10)[0];
        assert_eq!(p.implied, Implied::BAtMostA);
        assert!(p.p < ALPHA && !p.contradictory);
        // The same configuration and the same numbers: a = b, p = 1.
        let rows =
            [row("1", 42.4, 13.8, (vec![2, 2], 3), g.clone()), row("2", 42.4, 13.8, (vec![2, 2], 3), g)];
        let p = pairs(&rows, 10)[0];
        assert_eq!((p.implied, p.t, p.p, p.contradictory), (Implied::Equal, 0.0, 1.0, false));
        // Coinciding configurations with different means: the later experiment's row is marked.
        let mut later = rows[1].clone();
        later.mean = 80.0;
        let p = pairs(&[rows[0].clone(), later], 10)[0];
        assert!(p.contradictory && p.designated() == Some(1), "{p:?}");
        // Different experiments only; another algorithm never pairs.
        let mut other = rows[1].clone();
        other.algorithm = Algorithm::QLambda;
        assert!(pairs(&[rows[0].clone(), other], 10).is_empty());
        assert!(pairs(&[rows[0].clone(), rows[0].clone()], 10).is_empty());
    }

    #[test]
    fn welch_without_spread() {
        assert_eq!(welch_summary((1.0, 0.0, 10.0), (1.0, 0.0, 10.0)).2, 1.0);
        assert_eq!(welch_summary((1.0, 0.0, 10.0), (2.0, 0.0, 10.0)).2, 0.0);
    }
}
