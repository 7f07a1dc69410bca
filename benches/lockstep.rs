//! `cargo bench --bench lockstep`: crisp trials run alone against the same trials run in lockstep,
//! [`lanes::LANES`] as lanes of one loop (`qsweep_engine::lanes`, what `qsweep run` does unless
//! `QSWEEP_LOCKSTEP=off`). Per system and algorithm: one cell of the paper's grid, 32 seeds, run
//! to their real stop; both ways alternate, 3 rounds, by thread CPU time, best kept; the outcomes
//! must be identical. Prints CPU seconds and the ratio lockstep / alone (docs/speed.md).

use qsweep_engine::config::TrialConfig;
use qsweep_engine::env::SystemKind;
use qsweep_engine::repr::ReprKind;
use qsweep_engine::{lanes, run_trial, Algorithm, Outcome};
use qsweep_pipeline::exec::thread_cpu_seconds;

/// The thread's CPU seconds: these benches run only where the clock exists.
fn cpu_seconds() -> f64 {
    thread_cpu_seconds().expect("a thread CPU clock (CLOCK_THREAD_CPUTIME_ID)")
}

fn main() {
    let filter = std::env::args().skip(1).find(|a| !a.starts_with('-')).unwrap_or_default();
    println!("| cell, 32 seeds | steps | alone (CPU s) | lockstep (CPU s) | lockstep / alone |");
    println!("|---|---:|---:|---:|---:|");
    for (system, res) in
        [(SystemKind::MountainCar, 10), (SystemKind::CartPole, 6), (SystemKind::BallBeam, 10)]
    {
        for algorithm in [Algorithm::Q0, Algorithm::QLambda] {
            let actions = system.default_actions();
            let name = format!("{system}/crisp/{}/{res}^{}/{actions}a", algorithm.name(), system.dim());
            if !name.contains(&filter) {
                continue;
            }
            let cfg =
                TrialConfig::paper(system, ReprKind::Crisp, algorithm, vec![res; system.dim()], actions);
            let seeds: Vec<u64> = (1..=32).collect();
            let (mut alone, mut together) = (f64::INFINITY, f64::INFINITY);
            let mut steps = 0;
            for _ in 0..3 {
                let t = cpu_seconds();
                let want: Vec<Outcome> = seeds.iter().map(|&s| run_trial(&cfg, s)).collect();
                alone = alone.min(cpu_seconds() - t);
                let t = cpu_seconds();
                let mut got = vec![None; seeds.len()];
                let mut next = seeds.iter().enumerate();
                lanes::run_lockstep(
                    system,
                    || next.next().map(|(i, &s)| (i, &cfg, s)),
                    |i, o| got[i] = Some(o),
                );
                together = together.min(cpu_seconds() - t);
                assert!(got.iter().zip(&want).all(|(g, w)| g.as_ref() == Some(w)), "{name}: outcomes differ");
                steps = want.iter().map(|o| o.total_steps).sum::<u64>();
            }
            println!("| {name} | {steps} | {alone:.3} | {together:.3} | {:.2} |", together / alone);
        }
    }
}
