//! The paper's conclusions as tests: each claim is a statistic over a variant's cells with a null
//! value and a direction, and a percentile-bootstrap interval that redraws every cell's trials.
//! The definitions ([`CLAIMS`]) were fixed in `docs/preregistration.md` before any was computed;
//! a claim **holds** when its interval lies entirely on the claimed side of the null, is
//! **reversed** when it lies entirely on the other side, and is **undecided** otherwise.

mod definitions;
mod groups;
mod statistic;

pub use definitions::{
    result, Claim, ClaimCell, ClaimResult, ClaimVerdict, Side, CLAIMS, CLAIM_RESAMPLES, CLAIM_RULE,
    PAPER_SYSTEMS,
};

use crate::memo::stats::{put_params, put_values, StatsMemo};
use definitions::View;
use groups::Groups;
use qsweep_engine::rng::{below_from, TrialRng};
use qsweep_pipeline::analysis::{interval_95, resample_mean};
use rayon::prelude::*;
use statistic::statistics;

/// [`evaluate`], memoized in the statistics' memo (kind `claims`): the estimate and interval of
/// every claim, reused while no input the claims read has changed.
pub fn evaluate_memoized(memo: &StatsMemo, cells: &[ClaimCell]) -> Vec<ClaimResult> {
    let inputs = |h: &mut blake3::Hasher| {
        put_params(h, CLAIM_RESAMPLES, CLAIMS.len() as u64);
        for c in cells {
            // Every field the claims read (ClaimCell's, in order).
            h.update(c.system.name().as_bytes());
            h.update(b"\0");
            h.update(&(c.experiment as u64).to_le_bytes());
            h.update(c.experiment_id.as_bytes());
            h.update(b"\0");
            h.update(&[u8::from(c.fuzzy), c.algorithm as u8]);
            h.update(&(c.resolution.len() as u64).to_le_bytes());
            for r in &c.resolution {
                h.update(&r.to_le_bytes());
            }
            h.update(&c.actions.to_le_bytes());
            put_values(h, &c.counted);
            h.update(&(c.converged.len() as u64).to_le_bytes());
            h.update(&c.converged.iter().map(|&b| u8::from(b)).collect::<Vec<u8>>());
            h.update(&c.seed.to_le_bytes());
        }
    };
    let v = memo.entry("claims", inputs, || {
        let mut out = Vec::with_capacity(CLAIMS.len() * 5);
        for r in evaluate(cells) {
            out.push(u64::from(r.estimate.is_some()));
            out.push(r.estimate.unwrap_or(0.0).to_bits());
            out.push(u64::from(r.interval.is_some()));
            let (lo, hi) = r.interval.unwrap_or((0.0, 0.0));
            out.extend([lo.to_bits(), hi.to_bits()]);
        }
        out
    });
    CLAIMS
        .iter()
        .zip(v.chunks_exact(5))
        .map(|(claim, e)| {
            let estimate = (e[0] == 1).then(|| f64::from_bits(e[1]));
            let interval = (e[2] == 1).then(|| (f64::from_bits(e[3]), f64::from_bits(e[4])));
            result(claim, estimate, interval)
        })
        .collect()
}

/// Every claim of [`CLAIMS`] over `cells`.
pub fn evaluate(cells: &[ClaimCell]) -> Vec<ClaimResult> {
    let point: Vec<View> = cells
        .iter()
        .map(|c| View {
            mean: (!c.counted.is_empty()).then(|| c.counted.iter().sum::<f64>() / c.counted.len() as f64),
            successes: c.converged.iter().filter(|&&b| b).count(),
            n: c.counted.len(),
        })
        .collect();
    let g = Groups::of(cells);
    let estimates = statistics(cells, &g, &point);
    // Each cell's resamples come from its own stream, consumed in order, so drawing them a block
    // at a time gives the same resamples on any number of threads, with one block in memory
    // instead of every cell's thousand.
    let mut streams: Vec<TrialRng> = cells.iter().map(|c| TrialRng::new(c.seed)).collect();
    let mut reps: Vec<[Option<f64>; CLAIMS.len()]> = Vec::with_capacity(CLAIM_RESAMPLES);
    for start in (0..CLAIM_RESAMPLES).step_by(RESAMPLE_BLOCK) {
        let len = RESAMPLE_BLOCK.min(CLAIM_RESAMPLES - start);
        let draws: Vec<Vec<View>> =
            cells.par_iter().zip(streams.par_iter_mut()).map(|(c, rng)| resample(c, rng, len)).collect();
        // All claims of one resample at once: its view, best cells and correlations are shared.
        let block: Vec<[Option<f64>; CLAIMS.len()]> = (0..len)
            .into_par_iter()
            .map(|r| {
                let view: Vec<View> = draws.iter().map(|d| d[r]).collect();
                statistics(cells, &g, &view)
            })
            .collect();
        reps.extend(block);
    }
    CLAIMS
        .iter()
        .enumerate()
        .map(|(k, claim)| {
            let estimate = estimates[k];
            let mut values: Vec<f64> = reps.iter().filter_map(|r| r[k]).collect();
            let interval =
                (estimate.is_some() && values.len() * 2 > CLAIM_RESAMPLES).then(|| interval_95(&mut values));
            result(claim, estimate, interval)
        })
        .collect()
}

/// Resamples drawn at once per cell ([`evaluate`]).
const RESAMPLE_BLOCK: usize = 100;

/// A cell's next `len` resamples from its stream: each redraws its trials with replacement.
fn resample(c: &ClaimCell, rng: &mut TrialRng, len: usize) -> Vec<View> {
    let n = c.counted.len();
    if n == 0 {
        return vec![View { mean: None, successes: 0, n: 0 }; len];
    }
    let mut draws = vec![0u64; n * len];
    rng.fill_u64(&mut draws);
    draws
        .chunks_exact(n)
        .map(|r| View {
            mean: Some(resample_mean(&c.counted, r)),
            successes: r.iter().filter(|&&x| c.converged[below_from(x, n)]).count(),
            n,
        })
        .collect()
}

#[cfg(test)]
mod tests;
