//! Checks of the production learner against a literal, dense implementation of the paper's
//! equations: Q(s,a) = Σ wᵢ qᵢᵃ (18), δ (4)/(14), traces e ← γλe (+w for the taken action) (7)/(20),
//! q ← q + αδe (6)/(21), and eq. (5)/(19) for Q(0). The literal loop drives a trajectory (its own
//! ε-greedy choices from the trial's random stream); at every step the production learner, fed the
//! same activations and actions and its own TD errors, must hold the same Q table up to rounding.
//! (Whole trials cannot be compared bit for bit any more: the engine's scaled traces and split sums
//! round differently, and a chaotic system amplifies a last-bit difference into another trajectory.)

use super::actions::action_set;
use super::config::{Algorithm, Success, TieBreak, TrialConfig};
use super::env::{with_env, Environment, SystemKind, TaskKind};
use super::learner::Learner;
use super::repr::{Activations, Crisp, Fuzzy, ReprKind, Representation};
use super::rng::TrialRng;
use super::run_trial;

/// Equal up to rounding accumulated over a trial: within 10⁻⁹ relative (absolute below 1).
fn close(ours: f64, literal: f64) -> bool {
    (ours - literal).abs() <= 1e-9 * literal.abs().max(1.0)
}

/// Run the literal dense algorithm for `cfg` and `seed`, checking the production learner against
/// it at every step; returns the steps checked.
fn check_against_dense_equations(cfg: &TrialConfig, seed: u64) -> u64 {
    fn go<E: Environment>(cfg: &TrialConfig, seed: u64, mut env: E, repr: &dyn Representation) -> u64 {
        assert_eq!(E::TASK, TaskKind::Survival, "survival tasks only");
        let l = &cfg.learner;
        let acts = action_set(cfg.env.action_max(), cfg.actions);
        let na = acts.len();
        let nf = repr.n_features();
        let mut q = vec![vec![l.q_init; na]; nf];
        let mut e = vec![vec![0.0f64; na]; nf];
        let mut ours = Learner::new(nf, na, repr.max_active(), l);
        let mut rng = TrialRng::new(seed);
        let qv = |q: &Vec<Vec<f64>>, phi: &Activations| -> Vec<f64> {
            let mut out = vec![0.0; na];
            for (i, w) in phi.index.iter().zip(&phi.weight) {
                for a in 0..na {
                    out[a] += w * q[*i as usize][a];
                }
            }
            out
        };
        let mut checked = 0;
        for _ in 0..cfg.limits.max_episodes {
            env.reset();
            e.iter_mut().for_each(|r| r.fill(0.0));
            ours.clear_traces();
            let mut phi = Activations::default();
            repr.activate(env.state(), &mut phi);
            let mut len = 0u64;
            let failed = loop {
                let qs = qv(&q, &phi);
                let mut our_qs = vec![0.0; na];
                ours.q_values(&phi, &mut our_qs);
                for (o, l) in our_qs.iter().zip(&qs) {
                    assert!(close(*o, *l), "step {checked}: Q(s, ·) {our_qs:?} vs {qs:?}");
                }
                let best = qs.iter().copied().fold(f64::NEG_INFINITY, f64::max);
                let ties: Vec<usize> = (0..na).filter(|&a| qs[a] == best).collect();
                let a = if rng.unit() < l.epsilon {
                    rng.below(na)
                } else if ties.len() == 1 || l.tie_break == TieBreak::First {
                    ties[0]
                } else {
                    ties[rng.below(ties.len())]
                };
                let t = env.step(acts[a]);
                len += 1;
                let mut phi2 = Activations::default();
                let (target, our_target) = if t.terminal {
                    (t.reward, t.reward)
                } else {
                    repr.activate(env.state(), &mut phi2);
                    let mut next = vec![0.0; na];
                    ours.q_values(&phi2, &mut next);
                    let max = |v: &[f64]| v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
                    (t.reward + l.gamma * max(&qv(&q, &phi2)), t.reward + l.gamma * max(&next))
                };
                let delta = target - qs[a];
                ours.update(&phi, a, our_target - our_qs[a]);
                match l.algorithm {
                    Algorithm::Q0 => {
                        // Eq. (5)/(19): only the taken action's active parameters move.
                        for (i, w) in phi.index.iter().zip(&phi.weight) {
                            q[*i as usize][a] += l.alpha * delta * w;
                        }
                    }
                    Algorithm::QLambda => {
                        let decay = l.gamma * l.lambda;
                        for row in e.iter_mut() {
                            for v in row.iter_mut() {
                                *v *= decay;
                            }
                        }
                        for (i, w) in phi.index.iter().zip(&phi.weight) {
                            e[*i as usize][a] += w;
                        }
                        let step = l.alpha * delta;
                        for (qr, er) in q.iter_mut().zip(&e) {
                            for (qv, ev) in qr.iter_mut().zip(er) {
                                *qv += step * ev;
                            }
                        }
                    }
                }
                for (k, v) in ours.params().iter().enumerate() {
                    let literal = q[k / na][k % na];
                    assert!(close(*v, literal), "step {checked}: q[{k}] {v:e} vs {literal:e}");
                }
                checked += 1;
                if t.terminal || len >= cfg.limits.episode_cap() {
                    break t.terminal;
                }
                phi = phi2;
            };
            if !failed {
                break;
            }
        }
        checked
    }
    let r = &cfg.repr;
    let repr: Box<dyn Representation> = match r.kind {
        ReprKind::Crisp => Box::new(Crisp::new(&r.resolution, &r.ranges)),
        ReprKind::Fuzzy => Box::new(Fuzzy::new(&r.resolution, &r.ranges, r.width, r.prune)),
    };
    with_env!(&cfg.env, |env: E| go(cfg, seed, env, repr.as_ref()))
}

fn small(system: SystemKind, repr: ReprKind, algorithm: Algorithm, res: u32, actions: u32) -> TrialConfig {
    let mut c = TrialConfig::paper(system, repr, algorithm, vec![res; system.dim()], actions);
    c.limits.max_episodes = 40;
    c.limits.success = Success::Balance { steps: 3_000 };
    c.learner.trace_cutoff = 0.0;
    c.normalize();
    c
}

#[test]
fn crisp_learner_matches_the_dense_equations() {
    for system in [SystemKind::BallBeam, SystemKind::CartPole] {
        for algorithm in [Algorithm::Q0, Algorithm::QLambda] {
            for (res, actions) in [(2, 2), (3, 3), (5, 4)] {
                let c = small(system, ReprKind::Crisp, algorithm, res, actions);
                for seed in 0..3 {
                    assert!(check_against_dense_equations(&c, seed) > 100, "{system} {algorithm:?} {res}");
                }
            }
        }
    }
}

#[test]
fn fuzzy_learner_matches_the_dense_equations() {
    for system in [SystemKind::BallBeam, SystemKind::CartPole] {
        for algorithm in [Algorithm::Q0, Algorithm::QLambda] {
            for (res, actions, prune) in [(3, 2, 0.0), (4, 3, 1e-3)] {
                let mut c = small(system, ReprKind::Fuzzy, algorithm, res, actions);
                c.repr.prune = prune;
                for seed in 0..2 {
                    assert!(check_against_dense_equations(&c, seed) > 100, "{system} {algorithm:?} {res}");
                }
            }
        }
    }
}

#[test]
fn q0_is_exactly_q_lambda_with_lambda_zero() {
    for system in SystemKind::ALL {
        for repr in [ReprKind::Crisp, ReprKind::Fuzzy] {
            let mut q0 = TrialConfig::paper(system, repr, Algorithm::Q0, vec![3; system.dim()], 3);
            q0.limits.max_episodes = 30;
            let mut ql = q0.clone();
            ql.learner.algorithm = Algorithm::QLambda;
            ql.learner.lambda = 0.0;
            ql.learner.trace_cutoff = 1e-10;
            for seed in 0..3 {
                let (a, b) = (run_trial(&q0, seed), run_trial(&ql, seed));
                assert_eq!(a, b, "{system} {repr:?} seed {seed}");
            }
        }
    }
}

#[test]
fn trials_are_deterministic_and_seeds_matter() {
    let c =
        TrialConfig::paper(SystemKind::CartPole, ReprKind::Fuzzy, Algorithm::QLambda, vec![3, 2, 3, 2], 2);
    let mut c = c;
    c.limits.max_episodes = 20;
    let a = run_trial(&c, 5);
    let from_thread = std::thread::spawn({
        let c = c.clone();
        move || run_trial(&c, 5)
    })
    .join()
    .unwrap();
    assert_eq!(a, from_thread);
    assert_ne!(a.episode_lengths, run_trial(&c, 6).episode_lengths);
}

#[test]
fn outcome_bookkeeping_is_consistent() {
    for system in SystemKind::ALL {
        let mut c = TrialConfig::paper(system, ReprKind::Crisp, Algorithm::QLambda, vec![4; system.dim()], 3);
        c.limits.max_episodes = 50;
        let o = run_trial(&c, 1);
        assert_eq!(o.episodes as usize, o.episode_lengths.len());
        assert_eq!(o.total_steps, o.episode_lengths.iter().map(|&l| u64::from(l)).sum::<u64>());
        assert_eq!(o.converged, o.episodes_to_goal.is_some());
        if let Some(n) = o.episodes_to_goal {
            assert_eq!(n, o.episodes);
        } else {
            assert!(o.episodes == 50 || o.total_steps >= c.limits.max_total_steps);
        }
    }
}

#[test]
fn absurd_gravity_diverges_with_a_reason_instead_of_panicking() {
    let mut c = TrialConfig::paper(SystemKind::CartPole, ReprKind::Crisp, Algorithm::Q0, vec![2; 4], 2);
    c.env.set_param("gravity", 1e308).unwrap();
    c.env.set_param("theta_limit_deg", 1e300).unwrap();
    c.env.set_param("x_limit", 1e300).unwrap();
    let o = run_trial(&c, 0);
    assert_eq!(o.stop, super::StopReason::Diverged);
    assert!(o.failure.as_deref().unwrap().contains("non-finite"));
}
