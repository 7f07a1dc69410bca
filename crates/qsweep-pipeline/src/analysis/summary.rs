//! Descriptive statistics of one cell's episode counts: mean, sample standard deviation
//! (ddof = 1), min, median, max, interquartile mean and a seeded percentile-bootstrap 95%
//! confidence interval of the mean. Everything is a pure function of its inputs.

use qsweep_engine::rng::{below_from, TrialRng};

/// A summary a test needs: mean, sample std (`None` below two values) and sample size.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Moments {
    /// Mean.
    pub mean: f64,
    /// Sample standard deviation (ddof = 1).
    pub std: Option<f64>,
    /// Sample size.
    pub n: usize,
}

impl Moments {
    /// The moments of a sample.
    pub fn of(values: &[f64]) -> Self {
        Self { mean: mean(values), std: sample_std(values), n: values.len() }
    }
}

/// Bootstrap resamples per cell.
pub const BOOTSTRAP_RESAMPLES: usize = 2000;

/// Summary of a sample of episode counts. Every statistic is `None` for an empty sample; `std`
/// is also `None` for a single value (the sample standard deviation needs two).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Summary {
    /// Sample size.
    pub n: usize,
    /// Arithmetic mean.
    pub mean: Option<f64>,
    /// Sample standard deviation, √(Σ(xᵢ − x̄)² / (n − 1)).
    pub std: Option<f64>,
    /// Smallest value.
    pub min: Option<f64>,
    /// Median (mean of the two middle values for even n).
    pub median: Option<f64>,
    /// Largest value.
    pub max: Option<f64>,
    /// Interquartile mean: the mean of the values left after dropping ⌊n/4⌋ from each end of the
    /// sorted sample (`scipy.stats.trim_mean(x, 0.25)`).
    pub iqm: Option<f64>,
    /// Lower end of the 95% percentile-bootstrap interval of the mean.
    pub ci_lo: Option<f64>,
    /// Upper end of the 95% percentile-bootstrap interval of the mean.
    pub ci_hi: Option<f64>,
}

impl Summary {
    /// Summarise `values`; `seed` seeds the bootstrap (same values and seed, same interval).
    pub fn of(values: &[f64], seed: u64) -> Self {
        Self::with_interval(values, Some(seed))
    }

    /// Summarise `values`, with the bootstrap interval only when `seed` is given (a summary that
    /// no page shows skips its resamples; `ci_lo`/`ci_hi` are then `None`).
    pub fn with_interval(values: &[f64], seed: Option<u64>) -> Self {
        Self::with_interval_by(values, seed, bootstrap_ci)
    }

    /// [`Summary::with_interval`], its interval given by `ci` (the same function as
    /// [`bootstrap_ci`], e.g. memoized: [`super::derived::StatsMemo::bootstrap_ci`]).
    pub fn with_interval_by(
        values: &[f64],
        seed: Option<u64>,
        ci: impl FnOnce(&[f64], usize, u64) -> (f64, f64),
    ) -> Self {
        if values.is_empty() {
            return Self::default();
        }
        let mut sorted = values.to_vec();
        sorted.sort_by(f64::total_cmp);
        let ci = seed.map(|s| ci(values, BOOTSTRAP_RESAMPLES, s));
        Self {
            n: values.len(),
            mean: Some(mean(values)),
            std: sample_std(values),
            min: sorted.first().copied(),
            median: Some(quantile_sorted(&sorted, 0.5)),
            max: sorted.last().copied(),
            iqm: Some(iqm_sorted(&sorted)),
            ci_lo: ci.map(|c| c.0),
            ci_hi: ci.map(|c| c.1),
        }
    }
}

/// Arithmetic mean (NaN for an empty slice).
pub fn mean(values: &[f64]) -> f64 {
    values.iter().sum::<f64>() / values.len() as f64
}

/// Sample standard deviation with Bessel's correction (ddof = 1); `None` below two values.
pub fn sample_std(values: &[f64]) -> Option<f64> {
    if values.len() < 2 {
        return None;
    }
    let m = mean(values);
    let ss: f64 = values.iter().map(|v| (v - m) * (v - m)).sum();
    Some((ss / (values.len() - 1) as f64).sqrt())
}

/// Quantile `q` ∈ [0, 1] of a sorted, non-empty slice by linear interpolation between order
/// statistics (type 7, NumPy's default).
pub fn quantile_sorted(sorted: &[f64], q: f64) -> f64 {
    let h = (sorted.len() - 1) as f64 * q.clamp(0.0, 1.0);
    let lo = h.floor() as usize;
    let hi = h.ceil() as usize;
    sorted[lo] + (h - lo as f64) * (sorted[hi] - sorted[lo])
}

/// Interquartile mean of a sorted, non-empty slice: drop ⌊n/4⌋ values from each end, average
/// the rest.
pub fn iqm_sorted(sorted: &[f64]) -> f64 {
    let cut = sorted.len() / 4;
    mean(&sorted[cut..sorted.len() - cut])
}

/// The type-7 quantile `q` of `values` (as [`quantile_sorted`] of the sorted slice), by selection
/// instead of a full sort: the same two order statistics, so the same value. Reorders `values`.
pub fn quantile_select(values: &mut [f64], q: f64) -> f64 {
    let h = (values.len() - 1) as f64 * q.clamp(0.0, 1.0);
    let lo = h.floor() as usize;
    let (_, &mut a, rest) = values.select_nth_unstable_by(lo, f64::total_cmp);
    let b =
        if h.ceil() as usize == lo { a } else { rest.iter().copied().min_by(f64::total_cmp).unwrap_or(a) };
    a + (h - lo as f64) * (b - a)
}

/// The 2.5 % and 97.5 % quantiles of `values` ([`quantile_select`]).
pub fn interval_95(values: &mut [f64]) -> (f64, f64) {
    (quantile_select(values, 0.025), quantile_select(values, 0.975))
}

/// Percentile-bootstrap 95% interval of the mean: `resamples` resamples with replacement drawn
/// from a [`TrialRng`] seeded with `seed`, then the 2.5% and 97.5% quantiles of their means.
pub fn bootstrap_ci(values: &[f64], resamples: usize, seed: u64) -> (f64, f64) {
    let n = values.len();
    if n == 1 || resamples == 0 {
        return (values[0], values[0]);
    }
    let mut means = over_resamples(&mut TrialRng::new(seed), n, resamples, |r| resample_mean(values, r));
    interval_95(&mut means)
}

/// Resamples whose draws are read from the stream at once by the bootstraps.
const RESAMPLE_CHUNK: usize = 64;

/// `stat` of each of `resamples` resamples, the k-th given the stream's k-th run of `per` u64s
/// (read in order, a chunk of resamples at a time).
fn over_resamples(
    rng: &mut TrialRng,
    per: usize,
    resamples: usize,
    stat: impl Fn(&[u64]) -> f64,
) -> Vec<f64> {
    let mut out = Vec::with_capacity(resamples);
    let mut raw = vec![0u64; per * RESAMPLE_CHUNK];
    for start in (0..resamples).step_by(RESAMPLE_CHUNK) {
        let draws = &mut raw[..per * RESAMPLE_CHUNK.min(resamples - start)];
        rng.fill_u64(draws);
        out.extend(draws.chunks_exact(per).map(&stat));
    }
    out
}

/// The mean of `values` resampled by `draws` (one u64 of the stream per value, in order: what
/// `TrialRng::below(values.len())` would pick).
#[inline]
pub fn resample_mean(values: &[f64], draws: &[u64]) -> f64 {
    let n = values.len();
    draws.iter().map(|&x| values[below_from(x, n)]).sum::<f64>() / n as f64
}

/// Percentile-bootstrap 95% interval of `mean(b) − mean(a)`: each resample draws `a` and `b`
/// independently with replacement (from one [`TrialRng`] seeded with `seed`, `a` first), then the
/// 2.5% and 97.5% quantiles of the differences. Both samples must be non-empty.
pub fn bootstrap_diff_ci(a: &[f64], b: &[f64], resamples: usize, seed: u64) -> (f64, f64) {
    let d = mean(b) - mean(a);
    if resamples == 0 {
        return (d, d);
    }
    let mut diffs = over_resamples(&mut TrialRng::new(seed), a.len() + b.len(), resamples, |r| {
        let (ra, rb) = r.split_at(a.len());
        resample_mean(b, rb) - resample_mean(a, ra)
    });
    interval_95(&mut diffs)
}

/// Percentile-bootstrap 95% interval of the ratio of means `mean(b) / mean(a)`: each resample
/// draws `a` and `b` independently with replacement (as [`bootstrap_diff_ci`], `a` first), then
/// the 2.5% and 97.5% quantiles of the ratios. `None` when `mean(a)` is not positive (a ratio
/// to it is no scale) or a sample is empty. A resample whose `a` mean is 0 (every draw a zero)
/// has an infinite ratio, so the upper end can be infinite: the data cannot bound the ratio.
pub fn bootstrap_ratio_ci(a: &[f64], b: &[f64], resamples: usize, seed: u64) -> Option<(f64, f64)> {
    if a.is_empty() || b.is_empty() || mean(a) <= 0.0 {
        return None;
    }
    let r = mean(b) / mean(a);
    if resamples == 0 {
        return Some((r, r));
    }
    let mut ratios = over_resamples(&mut TrialRng::new(seed), a.len() + b.len(), resamples, |d| {
        let (ra, rb) = d.split_at(a.len());
        let ma = resample_mean(a, ra);
        let mb = resample_mean(b, rb);
        if ma > 0.0 {
            mb / ma
        } else if mb == 0.0 {
            // 0 / 0: no evidence either way; the point estimate stands in.
            r
        } else {
            f64::INFINITY.copysign(mb)
        }
    });
    Some(interval_95(&mut ratios))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: f64, b: f64) -> bool {
        (a - b).abs() < 1e-12
    }

    #[test]
    fn selected_quantiles_equal_sorted_ones() {
        let mut rng = TrialRng::new(3);
        for n in [1usize, 2, 3, 7, 40, 2000] {
            let v: Vec<f64> = (0..n).map(|_| (rng.below(50) as f64) * 0.5).collect();
            let mut sorted = v.clone();
            sorted.sort_by(f64::total_cmp);
            for q in [0.0, 0.025, 0.5, 0.975, 1.0] {
                let mut w = v.clone();
                assert_eq!(
                    quantile_select(&mut w, q).to_bits(),
                    quantile_sorted(&sorted, q).to_bits(),
                    "{n} {q}"
                );
            }
        }
    }

    #[test]
    fn mean_std_median_iqm_on_fixed_inputs() {
        let v = [2.0, 4.0, 4.0, 4.0, 5.0, 5.0, 7.0, 9.0];
        assert!(close(mean(&v), 5.0));
        // Σ(x − 5)² = 32; 32 / 7.
        assert!(close(sample_std(&v).unwrap(), (32.0f64 / 7.0).sqrt()));
        let s = Summary::of(&v, 1);
        assert_eq!(s.n, 8);
        assert_eq!(s.median, Some(4.5));
        assert_eq!((s.min, s.max), (Some(2.0), Some(9.0)));
        // Drop 2 from each end: [4, 4, 5, 5].
        assert_eq!(s.iqm, Some(4.5));
        // Odd n: median is the middle value, IQM drops ⌊7/4⌋ = 1 from each end.
        let odd = [10.0, 1.0, 3.0, 2.0, 100.0, 4.0, 5.0];
        let s = Summary::of(&odd, 1);
        assert_eq!(s.median, Some(4.0));
        assert!(close(s.iqm.unwrap(), (2.0 + 3.0 + 4.0 + 5.0 + 10.0) / 5.0));
        // Fewer than 4 values: nothing is trimmed.
        assert!(close(iqm_sorted(&[1.0, 2.0, 6.0]), 3.0));
        assert!(close(quantile_sorted(&[1.0, 2.0, 3.0, 4.0], 0.25), 1.75));
    }

    #[test]
    fn empty_and_single_samples() {
        assert_eq!(Summary::of(&[], 0), Summary::default());
        let s = Summary::of(&[7.0], 0);
        assert_eq!((s.n, s.mean, s.std), (1, Some(7.0), None));
        assert_eq!((s.ci_lo, s.ci_hi), (Some(7.0), Some(7.0)));
        assert_eq!(s.iqm, Some(7.0));
    }

    #[test]
    fn bootstrap_is_seeded_and_brackets_the_mean() {
        let v: Vec<f64> = (1..=20).map(|i| f64::from(i * i % 17)).collect();
        let a = bootstrap_ci(&v, 2000, 42);
        assert_eq!(a, bootstrap_ci(&v, 2000, 42), "same seed, same interval");
        assert_ne!(a, bootstrap_ci(&v, 2000, 43), "another seed, another interval");
        let m = mean(&v);
        assert!(a.0 < m && m < a.1, "{a:?} should bracket {m}");
        // A constant sample has a degenerate interval.
        assert_eq!(bootstrap_ci(&[3.0; 5], 100, 9), (3.0, 3.0));
    }

    #[test]
    fn ratio_bootstrap_is_seeded_and_brackets_the_ratio() {
        let a = [10.0, 12.0, 9.0, 11.0, 8.0, 10.0];
        let b = [12.0, 13.0, 11.0, 12.5, 14.0, 11.5];
        let ci = bootstrap_ratio_ci(&a, &b, 2000, 7).unwrap();
        assert_eq!(Some(ci), bootstrap_ratio_ci(&a, &b, 2000, 7), "same seed, same interval");
        assert_ne!(Some(ci), bootstrap_ratio_ci(&a, &b, 2000, 8));
        let r = mean(&b) / mean(&a);
        assert!(ci.0 < r && r < ci.1 && ci.0 > 1.0, "{ci:?} around {r}");
        // Each resample's ratio is the difference bootstrap's draw seen as a ratio: with `a`
        // constant the ratio interval is the difference interval over that constant, plus 1.
        let flat = [10.0; 6];
        let (rlo, rhi) = bootstrap_ratio_ci(&flat, &b, 2000, 3).unwrap();
        let (dlo, dhi) = bootstrap_diff_ci(&flat, &b, 2000, 3);
        assert!(close(rlo, 1.0 + dlo / 10.0) && close(rhi, 1.0 + dhi / 10.0), "{rlo} {rhi} {dlo} {dhi}");
        // Identical constant samples: the ratio is exactly 1.
        assert_eq!(bootstrap_ratio_ci(&[4.0; 3], &[4.0; 5], 500, 1), Some((1.0, 1.0)));
        assert_eq!(bootstrap_ratio_ci(&[0.0, 0.0], &b, 500, 1), None, "no positive scale");
        assert_eq!(bootstrap_ratio_ci(&[], &b, 500, 1), None);
    }

    #[test]
    fn difference_bootstrap_is_seeded_and_brackets_the_difference() {
        let a = [10.0, 12.0, 9.0, 14.0, 11.0];
        let b = [20.0, 25.0, 18.0, 22.0, 30.0];
        let ci = bootstrap_diff_ci(&a, &b, 2000, 7);
        assert_eq!(ci, bootstrap_diff_ci(&a, &b, 2000, 7));
        let d = mean(&b) - mean(&a);
        assert!(ci.0 < d && d < ci.1 && ci.0 > 0.0, "{ci:?} around {d}");
        let (lo, hi) = bootstrap_diff_ci(&b, &a, 2000, 7);
        assert!(hi < 0.0 && lo < hi);
        // Constant samples: a degenerate interval at the difference.
        assert_eq!(bootstrap_diff_ci(&[3.0; 4], &[5.0; 2], 100, 1), (2.0, 2.0));
    }
}
