//! Rank statistics: average ranks with ties and Spearman's ρ, for the claims that say "more
//! states, more episodes".

/// Ranks 1..=n of `values`, ties sharing their average rank (`scipy.stats.rankdata`).
pub fn average_ranks(values: &[f64]) -> Vec<f64> {
    let mut order: Vec<(f64, usize)> = values.iter().copied().zip(0..).collect();
    // A total order (ties by index), so the unstable sort is deterministic.
    order.sort_unstable_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    let mut ranks = vec![0.0; values.len()];
    let mut i = 0;
    while i < order.len() {
        let tie = order[i..].iter().take_while(|p| p.0 == order[i].0).count();
        // Positions i..i+tie hold ranks i+1..=i+tie; their average.
        let r = i as f64 + (tie as f64 + 1.0) / 2.0;
        for &(_, j) in &order[i..i + tie] {
            ranks[j] = r;
        }
        i += tie;
    }
    ranks
}

/// Spearman's ρ of paired samples: Pearson's correlation of their average ranks
/// (`scipy.stats.spearmanr`). `None` below three pairs or when either sample is constant.
pub fn spearman(x: &[f64], y: &[f64]) -> Option<f64> {
    if x.len() != y.len() || x.len() < 3 {
        return None;
    }
    pearson(&average_ranks(x), &average_ranks(y))
}

/// Pearson's correlation of two equally long samples (`None` when either is constant): Spearman's
/// ρ when they are ranks, so a caller with fixed x ranks them once.
pub fn pearson(rx: &[f64], ry: &[f64]) -> Option<f64> {
    if rx.len() != ry.len() || rx.len() < 3 {
        return None;
    }
    let n = rx.len() as f64;
    let (mx, my) = (rx.iter().sum::<f64>() / n, ry.iter().sum::<f64>() / n);
    let (mut sxy, mut sxx, mut syy) = (0.0, 0.0, 0.0);
    for (a, b) in rx.iter().zip(ry) {
        sxy += (a - mx) * (b - my);
        sxx += (a - mx) * (a - mx);
        syy += (b - my) * (b - my);
    }
    if sxx == 0.0 || syy == 0.0 {
        return None;
    }
    Some(sxy / (sxx * syy).sqrt())
}

/// One-sided p-value of the Mann–Whitney U test for H₁: `worse` tends to be larger than `best`
/// (`scipy.stats.mannwhitneyu(worse, best, alternative="greater", method="asymptotic")`: normal
/// approximation with the tie correction and a continuity correction). A rank test: unlike
/// Welch's t, one huge value cannot hide a consistent shift. 1 without spread or values.
pub fn mann_whitney_p_greater(worse: &[f64], best: &[f64]) -> f64 {
    let (n1, n2) = (worse.len(), best.len());
    if n1 == 0 || n2 == 0 {
        return 1.0;
    }
    let all: Vec<f64> = worse.iter().chain(best).copied().collect();
    let ranks = average_ranks(&all);
    let r1: f64 = ranks[..n1].iter().sum();
    let (a, b, n) = (n1 as f64, n2 as f64, (n1 + n2) as f64);
    let u1 = r1 - a * (a + 1.0) / 2.0;
    // Σ(t³ − t) over groups of tied values.
    let mut sorted = all.clone();
    sorted.sort_by(f64::total_cmp);
    let mut ties = 0.0;
    let mut i = 0;
    while i < sorted.len() {
        let t = sorted[i..].iter().take_while(|&&v| v == sorted[i]).count() as f64;
        ties += t * t * t - t;
        i += t as usize;
    }
    let var = a * b / 12.0 * ((n + 1.0) - ties / (n * (n - 1.0)));
    if var <= 0.0 {
        return 1.0;
    }
    let z = (u1 - a * b / 2.0 - 0.5) / var.sqrt();
    0.5 * libm::erfc(z / std::f64::consts::SQRT_2)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ranks_average_over_ties() {
        assert_eq!(average_ranks(&[10.0, 20.0, 10.0, 5.0]), vec![2.5, 4.0, 2.5, 1.0]);
    }

    #[test]
    fn spearman_matches_scipy() {
        // scipy.stats.spearmanr([1, 2, 3, 4, 5, 6], [2, 1, 4, 3, 6, 6]).statistic, SciPy 1.17.1.
        let rho = spearman(&[1.0, 2.0, 3.0, 4.0, 5.0, 6.0], &[2.0, 1.0, 4.0, 3.0, 6.0, 6.0]).unwrap();
        assert!((rho - 0.869_656_553_5).abs() < 1e-9, "{rho}");
        assert_eq!(spearman(&[1.0, 2.0, 3.0], &[3.0, 2.0, 1.0]), Some(-1.0));
        assert_eq!(spearman(&[1.0, 2.0, 3.0], &[1.0, 1.0, 1.0]), None);
    }

    #[test]
    fn mann_whitney_matches_scipy() {
        // scipy.stats.mannwhitneyu(x, y, alternative="greater", method="asymptotic").pvalue, 1.17.1.
        let p = mann_whitney_p_greater(&[5.0, 6.0, 7.0, 8.0, 9.0, 9.0], &[1.0, 2.0, 3.0, 3.0, 4.0]);
        assert!((p - 0.003_913_514_148_145_887).abs() < 1e-12, "{p}");
        let p = mann_whitney_p_greater(&[3.0, 3.0, 4.0, 5.0], &[3.0, 3.0, 3.0, 4.0]);
        assert!((p - 0.252_492_537_546_922_9).abs() < 1e-12, "{p}");
        assert_eq!(mann_whitney_p_greater(&[2.0, 2.0], &[2.0, 2.0]), 1.0);
    }
}
