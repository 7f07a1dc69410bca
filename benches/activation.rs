//! `cargo bench --bench activation`: how long one fuzzy activation takes (the memberships'
//! exponentials, their normalisers and the outer product of Gaussian rule bases, as the paper's
//! configurations build them), with each state fed from the last activation's weights, as a trial
//! feeds its next state from the action those weights chose: the chain of dependent operations a
//! trial waits on every step, not the throughput of independent activations. Thread CPU time, best
//! of 5 runs of 2,000,000 activations each (docs/speed.md).

use qsweep_engine::config::TrialConfig;
use qsweep_engine::env::SystemKind;
use qsweep_engine::math;
use qsweep_engine::repr::{Activations, Fuzzy, ReprKind, Representation};
use qsweep_engine::Algorithm;

const ACTIVATIONS: usize = 2_000_000;

fn cpu_seconds() -> f64 {
    let mut ts = libc::timespec { tv_sec: 0, tv_nsec: 0 };
    // SAFETY: clock_gettime writes into the timespec we own.
    unsafe { libc::clock_gettime(libc::CLOCK_THREAD_CPUTIME_ID, &mut ts) };
    ts.tv_sec as f64 + ts.tv_nsec as f64 * 1e-9
}

fn main() {
    let cases = [
        (SystemKind::CartPole, vec![4, 4, 4, 4]),
        (SystemKind::CartPole, vec![10, 5, 10, 5]),
        (SystemKind::CartPole, vec![10, 10, 10, 10]),
        (SystemKind::MountainCar, vec![2, 5]),
        (SystemKind::MountainCar, vec![4, 4]),
        (SystemKind::MountainCar, vec![10, 10]),
        (SystemKind::BallBeam, vec![4, 4]),
    ];
    println!("| rule base | active rules (mean) | ns per activation |");
    println!("|---|---:|---:|");
    for (system, res) in cases {
        let cfg = TrialConfig::paper(system, ReprKind::Fuzzy, Algorithm::QLambda, res.clone(), 2);
        let r = &cfg.repr;
        let f = Fuzzy::new(&r.resolution, &r.ranges, r.width, r.prune);
        // States that sweep the middle 70 % of each variable's range at its own pace.
        let states: Vec<[f64; 4]> = (0..4096)
            .map(|i| {
                let mut s = [0.0; 4];
                for (j, (v, [lo, hi])) in s.iter_mut().zip(&r.ranges).enumerate() {
                    let t = f64::from(i) * 0.0137 * (1.0 + 0.37 * j as f64);
                    *v = (lo + hi) / 2.0 + 0.35 * (hi - lo) * math::sin(t);
                }
                s
            })
            .collect();
        let mut a = Activations::default();
        let (mut best, mut rules, mut carry) = (f64::INFINITY, 0usize, 0.0);
        for _ in 0..5 {
            rules = 0;
            let t = cpu_seconds();
            for i in 0..ACTIVATIONS {
                let mut s = states[i % states.len()];
                // A dependency on the last activation that leaves the state as it is.
                s[0] += carry * 1e-300;
                f.activate(&s[..r.ranges.len()], &mut a);
                carry = a.weight[a.len() / 2];
                rules += a.len();
            }
            best = best.min(cpu_seconds() - t);
        }
        let name = res.iter().map(u32::to_string).collect::<Vec<_>>().join("x");
        let mean = rules as f64 / ACTIVATIONS as f64;
        println!("| {system} `{name}` | {mean:.1} | {:.1} |", best * 1e9 / ACTIVATIONS as f64);
    }
}
