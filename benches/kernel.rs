//! `cargo bench --bench kernel`: the production trial loop against a hand-written kernel doing the
//! same work on `cart-pole/crisp/q0/2^4/2a` — Cart-Pole's Euler step (eq. 2, the engine's own
//! sin/cos), 2 midpoint bins per variable, ε-greedy over 2 actions from the trial's ChaCha stream,
//! the Q(0) update — in one function with a fixed-size table and no generality. The ratio
//! production / kernel (steps per second) shows what the engine's layering costs; the target is
//! ≥ 1.0 (docs/speed.md). Both are timed by thread CPU time, alternating, 5 runs each, best kept.

use qsweep_engine::config::TrialConfig;
use qsweep_engine::env::SystemKind;
use qsweep_engine::repr::ReprKind;
use qsweep_engine::rng::TrialRng;
use qsweep_engine::{math, run_trial, Algorithm};
use qsweep_pipeline::bench;
use qsweep_pipeline::exec::thread_cpu_seconds;

const STEPS: u64 = 3_000_000;

/// The thread's CPU seconds: these benches run only where the clock exists.
fn cpu_seconds() -> f64 {
    thread_cpu_seconds().expect("a thread CPU clock (CLOCK_THREAD_CPUTIME_ID)")
}

/// The hand-written kernel: returns the steps it ran (at least `steps`, ending with an episode).
fn kernel(cfg: &TrialConfig, steps: u64, seed: u64) -> u64 {
    let l = &cfg.learner;
    let ranges = &cfg.repr.ranges;
    let (g, mc, mp, hl, tau, force) = (9.81, 1.0, 0.1, 0.5, 0.02, 10.0);
    let (total_mass, pml) = (mc + mp, mp * hl);
    let theta_limit = 12.0 * 2.0 * std::f64::consts::PI / 360.0;
    let bin = |v: f64, r: [f64; 2]| -> usize { usize::from((v - r[0]) * (2.0 / (r[1] - r[0])) >= 1.0) };
    let cell = |s: &[f64; 4]| -> usize {
        8 * bin(s[0], ranges[0]) + 4 * bin(s[1], ranges[1]) + 2 * bin(s[2], ranges[2]) + bin(s[3], ranges[3])
    };
    let mut q = [[0.0f64; 2]; 16];
    let mut rng = TrialRng::new(seed);
    let mut total = 0;
    while total < steps {
        let mut s = [0.0f64; 4];
        let mut c = cell(&s);
        loop {
            let row = q[c];
            // Explore, or break a tie, uniformly.
            let a = if rng.unit() < l.epsilon || row[0] == row[1] {
                rng.below(2)
            } else {
                usize::from(row[1] > row[0])
            };
            let f = if a == 0 { -force } else { force };
            let (sin, cos) = math::sin_cos(s[2]);
            let temp = (f + pml * s[3] * s[3] * sin) / total_mass;
            let th_acc = (g * sin - cos * temp) / (hl * (4.0 / 3.0 - mp * cos * cos / total_mass));
            let x_acc = temp - pml * th_acc * cos / total_mass;
            s = [s[0] + tau * s[1], s[1] + tau * x_acc, s[2] + tau * s[3], s[3] + tau * th_acc];
            total += 1;
            let failed = s[0].abs() > 2.4 || s[2].abs() > theta_limit;
            let c2 = cell(&s);
            let target = if failed { -1.0 } else { l.gamma * q[c2][0].max(q[c2][1]) };
            q[c][a] += l.alpha * (target - q[c][a]);
            if failed || total >= steps {
                break;
            }
            c = c2;
        }
    }
    total
}

fn main() {
    let cfg = TrialConfig::paper(SystemKind::CartPole, ReprKind::Crisp, Algorithm::Q0, vec![2; 4], 2);
    let budget = bench::with_budget(cfg.clone(), STEPS);
    let (mut best_prod, mut best_kernel) = (0.0f64, 0.0f64);
    for round in 0..5 {
        let t = cpu_seconds();
        let o = run_trial(&budget, round);
        best_prod = best_prod.max(o.total_steps as f64 / (cpu_seconds() - t));
        let t = cpu_seconds();
        let n = kernel(&cfg, STEPS, round);
        best_kernel = best_kernel.max(n as f64 / (cpu_seconds() - t));
    }
    println!("cart-pole/crisp/q0/2^4/2a, {STEPS} steps, best of 5 by thread CPU time");
    println!("production trial loop   {:8.2} M steps/s", best_prod / 1e6);
    println!("hand-written kernel     {:8.2} M steps/s", best_kernel / 1e6);
    println!("production / kernel     {:8.2}", best_prod / best_kernel);
}
