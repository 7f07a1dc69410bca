//! `cargo bench --bench activation`: how long one fuzzy activation takes (the memberships'
//! exponentials, their normalisers and the outer product of Gaussian rule bases, as the paper's
//! configurations build them), with each state fed from the last activation's weights, as a trial
//! feeds its next state from the action those weights chose: the chain of dependent operations a
//! trial waits on every step; then the same activations independent of each other, which a core
//! may overlap. Thread CPU time, best of 5 runs of 2,000,000 activations each (docs/speed.md).

use qsweep_engine::config::TrialConfig;
use qsweep_engine::env::SystemKind;
use qsweep_engine::math;
use qsweep_engine::repr::{Activations, Fuzzy, ReprKind, Representation};
use qsweep_engine::Algorithm;
use qsweep_pipeline::exec::thread_cpu_seconds;

const ACTIVATIONS: usize = 2_000_000;

/// The thread's CPU seconds: these benches run only where the clock exists.
fn cpu_seconds() -> f64 {
    thread_cpu_seconds().expect("a thread CPU clock (CLOCK_THREAD_CPUTIME_ID)")
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
    println!("| rule base | active rules (mean) | ns per activation, chained | independent |");
    println!("|---|---:|---:|---:|");
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
        let (mut chained, mut apart, mut rules) = (f64::INFINITY, f64::INFINITY, 0usize);
        for _ in 0..5 {
            let (t, n) = time_activations(&f, &states, r.ranges.len(), &mut a, true);
            chained = chained.min(t);
            rules = n;
            apart = apart.min(time_activations(&f, &states, r.ranges.len(), &mut a, false).0);
        }
        let name = res.iter().map(u32::to_string).collect::<Vec<_>>().join("x");
        let mean = rules as f64 / ACTIVATIONS as f64;
        let ns = |t: f64| t * 1e9 / ACTIVATIONS as f64;
        println!("| {system} `{name}` | {mean:.1} | {:.1} | {:.1} |", ns(chained), ns(apart));
    }
}

/// Thread CPU seconds for [`ACTIVATIONS`] activations over `states` in turn, and the rules they
/// activated. `chained`: every variable of each state waits on the last activation's weights (a
/// dependency that leaves it as it is), as in a trial; else the activations are independent, and
/// the core may overlap one with the next.
fn time_activations(
    f: &Fuzzy,
    states: &[[f64; 4]],
    dim: usize,
    a: &mut Activations,
    chained: bool,
) -> (f64, usize) {
    // Zero, but not to the compiler: `carry · zero` makes every variable of the next state wait
    // on the last activation without changing it (and without subnormal products).
    let zero = std::hint::black_box(0.0);
    let (mut rules, mut carry) = (0usize, 0.0);
    let t = cpu_seconds();
    for i in 0..ACTIVATIONS {
        let mut s = states[i % states.len()];
        if chained {
            for v in &mut s[..dim] {
                *v += carry * zero;
            }
        }
        f.activate(&s[..dim], a);
        carry = a.weight[a.len() / 2];
        rules += a.len();
    }
    (cpu_seconds() - t, rules)
}
