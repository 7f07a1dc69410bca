//! What choosing the best of several variants is worth (docs/preregistration.md, "Choosing the
//! reading honestly"): a permutation yardstick for the largest count of rows that any one
//! variant matches, if all variants were equally good. The leave-one-row-out choice itself needs
//! the fit measure and lives beside it (`report::compare::selection`).

use qsweep_engine::rng::TrialRng;

/// Permutations of the yardstick.
pub const PERMUTATIONS: usize = 10_000;

/// The yardstick's seed (ChaCha8, qsweep's own integer mapping).
pub const SEED: u64 = 46;

/// The largest count of matched rows over the variants, against its permutation distribution.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Yardstick {
    /// The observed largest count.
    pub observed: usize,
    /// The permutations' median largest count.
    pub median: usize,
    /// Their 95th percentile.
    pub p95: usize,
    /// (1 + #{permutations with a largest count ≥ observed}) / (1 + permutations).
    pub p: f64,
}

/// The yardstick of `outcomes` (one `Vec` per row, one entry per variant: whether that variant
/// matches the row): each of `permutations` shuffles every row's outcomes among the variants
/// independently (Fisher–Yates from [`TrialRng`] seeded with `seed`) and records the largest count
/// of matched rows of any one variant. `None` without rows or variants.
pub fn yardstick(outcomes: &[Vec<bool>], permutations: usize, seed: u64) -> Option<Yardstick> {
    let variants = outcomes.first()?.len();
    if variants == 0 || outcomes.iter().any(|r| r.len() != variants) {
        return None;
    }
    let largest =
        |rows: &[Vec<bool>]| (0..variants).map(|k| rows.iter().filter(|r| r[k]).count()).max().unwrap_or(0);
    let observed = largest(outcomes);
    let mut rng = TrialRng::new(seed);
    let mut rows = outcomes.to_vec();
    let mut maxima: Vec<usize> = (0..permutations)
        .map(|_| {
            for row in rows.iter_mut() {
                for i in (1..row.len()).rev() {
                    row.swap(i, rng.below(i + 1));
                }
            }
            largest(&rows)
        })
        .collect();
    maxima.sort_unstable();
    // The q-quantile: the smallest value with at least q of the permutations at or below it.
    let quantile = |q: f64| maxima[((q * permutations as f64).ceil() as usize).clamp(1, permutations) - 1];
    let at_least = maxima.iter().filter(|&&m| m >= observed).count();
    Some(Yardstick {
        observed,
        median: quantile(0.5),
        p95: quantile(0.95),
        p: (1 + at_least) as f64 / (1 + permutations) as f64,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn equal_variants_are_what_chance_gives() {
        // Every row matched by exactly one of four variants, a different one each time round:
        // the observed largest count (3 of 12) is no better than permutations give.
        let rows: Vec<Vec<bool>> = (0..12).map(|i| (0..4).map(|k| k == i % 4).collect()).collect();
        let y = yardstick(&rows, 2_000, SEED).unwrap();
        assert_eq!(y.observed, 3);
        assert!(y.median >= 4 && y.p > 0.9, "{y:?}");
    }

    #[test]
    fn one_variant_that_matches_everything_stands_out() {
        // Variant 0 matches all 12 rows, the other 4 none: every row's one match falls to
        // variant 0 with probability 1/5, so a count of 12 essentially never happens by chance.
        let rows: Vec<Vec<bool>> = (0..12).map(|_| (0..5).map(|k| k == 0).collect()).collect();
        let y = yardstick(&rows, 2_000, SEED).unwrap();
        assert_eq!((y.observed, y.p), (12, 1.0 / 2_001.0));
        assert!(y.p95 < 12 && y.median < 8, "{y:?}");
        // Rows that every variant matches (or none) do not change with the shuffle.
        let all = vec![vec![true; 3]; 5];
        let y = yardstick(&all, 100, SEED).unwrap();
        assert_eq!((y.observed, y.median, y.p95, y.p), (5, 5, 5, 1.0));
        assert_eq!(yardstick(&[], 10, SEED), None);
        // Seeded: the same numbers on every run.
        assert_eq!(yardstick(&rows, 500, 7), yardstick(&rows, 500, 7));
    }
}
