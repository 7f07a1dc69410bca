//! The binomial tail: how likely `k` or more successes are in `n` independent trials of
//! probability `p`. `qsweep compare` asks it whether the share of cells with p < 0.05 is more
//! than the 5 % that chance alone gives (an exact one-sided binomial test).

use super::welch::ln_gamma;

/// P(X ≥ `k`) for X ~ Binomial(`n`, `p`), summed exactly over the terms k..=n (each taken through
/// ln Γ, so no term under- or overflows for large `n`). 1 for `k` = 0, 0 for `k` > `n`.
pub fn binomial_sf(k: u64, n: u64, p: f64) -> f64 {
    if k == 0 {
        return 1.0;
    }
    if k > n {
        return 0.0;
    }
    if p <= 0.0 {
        return 0.0;
    }
    if p >= 1.0 {
        return 1.0;
    }
    let nf = n as f64;
    let ln_n = ln_gamma(nf + 1.0);
    let (lp, lq) = (p.ln(), (-p).ln_1p());
    // The terms past the mode shrink; summing from the smallest keeps the sum's rounding small.
    let total: f64 = (k..=n)
        .rev()
        .map(|j| {
            let j = j as f64;
            (ln_n - ln_gamma(j + 1.0) - ln_gamma(nf - j + 1.0) + j * lp + (nf - j) * lq).exp()
        })
        .sum();
    total.min(1.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn binomial_tail_matches_exact_sums() {
        // sum(comb(n, j) p^j (1-p)^(n-j) for j in k..n), Python's exact math.comb.
        for (k, n, p, want) in [
            (3, 40, 0.05, 0.323_264_239_251_352_6),
            (5, 40, 0.05, 0.048_028_260_254_215_3),
            (1, 20, 0.05, 0.641_514_077_591_457_1),
            (10, 40, 0.05, 2.068_330_541_218_524_2e-5),
            (40, 40, 0.05, 9.094_947_017_729_302e-53),
            (2, 100, 0.05, 0.962_918_790_672_641_3),
        ] {
            let got = binomial_sf(k, n, p);
            assert!((got - want).abs() <= 1e-11 * want, "P(X ≥ {k} | Bin({n}, {p})) = {got}, want {want}");
        }
    }

    #[test]
    fn binomial_tail_edges() {
        assert_eq!(binomial_sf(0, 10, 0.05), 1.0);
        assert_eq!(binomial_sf(0, 0, 0.05), 1.0, "no cells: nothing beyond chance");
        assert_eq!(binomial_sf(11, 10, 0.05), 0.0);
        assert_eq!(binomial_sf(1, 10, 0.0), 0.0);
        assert_eq!(binomial_sf(10, 10, 1.0), 1.0);
        // Large n: no term underflows to a wrong total.
        let p = binomial_sf(500, 10_000, 0.05);
        assert!(p > 0.4 && p < 0.6, "{p}");
        // The tail falls as k grows.
        let tails: Vec<f64> = (0..=40).map(|k| binomial_sf(k, 40, 0.05)).collect();
        assert!(tails.windows(2).all(|w| w[1] <= w[0]), "{tails:?}");
    }
}
