//! Tests of the claims: clear effects hold and their opposites reverse; a failure to converge
//! reverses a convergence claim; evaluation is deterministic.

use super::*;
use qsweep_engine::env::SystemKind;
use qsweep_engine::Algorithm;

/// A two-experiment, one-system variant where Q(λ) is better everywhere and more states cost
/// more episodes.
fn cells(system: SystemKind, q_lambda_gain: f64) -> Vec<ClaimCell> {
    let mut out = Vec::new();
    for (e, (id, fuzzy)) in [("1", false), ("3", true)].into_iter().enumerate() {
        for alg in [Algorithm::Q0, Algorithm::QLambda] {
            for r in 2..=6u32 {
                let base = f64::from(r * r) * if fuzzy { 0.5 } else { 1.0 } + 10.0;
                let m = if alg == Algorithm::QLambda { base - q_lambda_gain } else { base };
                out.push(ClaimCell {
                    system,
                    experiment: e,
                    experiment_id: id.into(),
                    fuzzy,
                    algorithm: alg,
                    resolution: vec![r, r],
                    actions: 3,
                    counted: vec![m - 1.0, m, m + 1.0],
                    converged: vec![true; 3],
                    seed: u64::from(r) * 7 + e as u64,
                });
            }
        }
    }
    out
}

fn verdict(results: &[ClaimResult], id: &str) -> ClaimVerdict {
    results.iter().find(|r| r.claim.id == id).unwrap().verdict
}

#[test]
fn clear_effects_hold_and_their_opposites_reverse() {
    let r = evaluate(&cells(SystemKind::CartPole, 3.0));
    assert_eq!(verdict(&r, "excessive-hinders"), ClaimVerdict::Holds);
    assert_eq!(verdict(&r, "cart-pole-converged"), ClaimVerdict::Holds);
    // Fewer than three systems: the all-environments claim is not computable.
    assert_eq!(verdict(&r, "qlambda-beats-q0"), ClaimVerdict::Missing);
    let mut all = cells(SystemKind::CartPole, 3.0);
    all.extend(cells(SystemKind::BallBeam, 3.0).into_iter().map(|mut c| {
        c.experiment += 2;
        c
    }));
    all.extend(cells(SystemKind::MountainCar, -3.0).into_iter().map(|mut c| {
        c.experiment += 4;
        c
    }));
    let r = evaluate(&all);
    // Q(λ) worse in Mountain Car: the smallest probability of improvement is 0.
    assert_eq!(verdict(&r, "qlambda-beats-q0"), ClaimVerdict::Reversed);
    let est = r.iter().find(|x| x.claim.id == "qlambda-beats-q0").unwrap().estimate;
    assert_eq!(est, Some(0.0));
}

#[test]
fn failures_reverse_cart_pole_convergence_and_resamples_are_deterministic() {
    let mut c = cells(SystemKind::CartPole, 3.0);
    for cell in &mut c {
        cell.converged = vec![false, true, false];
    }
    let a = evaluate(&c);
    assert_eq!(verdict(&a, "cart-pole-converged"), ClaimVerdict::Reversed);
    assert_eq!(a, evaluate(&c));
}
