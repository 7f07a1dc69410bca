//! `cargo bench --bench cores`: whether this machine's CPUs have execution units of their own.
//! A loop of independent vector additions, bound by the core's adders and nothing else, runs on
//! one thread, then on two at once; each prints additions per second. Two CPUs that are the two
//! hardware threads of one core share its adders, so each gets about half the one-thread rate;
//! two cores each keep it. Which of the two a machine is decides what running trials in lockstep
//! can gain there (docs/speed.md).

use std::hint::black_box;
use std::time::Instant;

/// Independent accumulators: enough additions in flight to keep every adder busy, few enough to
/// stay in registers at the baseline vector width (12 SSE2 registers).
const CHAINS: usize = 24;
const ROUNDS: u64 = 150_000_000;

/// Runs `ROUNDS` × `CHAINS` additions; returns additions per second of wall time.
fn adds_per_second() -> f64 {
    let x = black_box(1e-12);
    let mut acc = [0.0f64; CHAINS];
    for (i, a) in acc.iter_mut().enumerate() {
        *a = black_box(i as f64);
    }
    let start = Instant::now();
    for _ in 0..ROUNDS {
        // Floating-point addition is not associative, so the compiler must perform every one.
        for a in &mut acc {
            *a += x;
        }
    }
    let seconds = start.elapsed().as_secs_f64();
    black_box(acc);
    (ROUNDS * CHAINS as u64) as f64 / seconds
}

fn main() {
    let cpus = std::thread::available_parallelism().map_or(1, |n| n.get());
    println!("CPUs: {cpus}; {CHAINS} independent chains of f64 additions");
    let (mut alone, mut paired) = (0.0f64, 0.0f64);
    for _ in 0..3 {
        alone = alone.max(adds_per_second());
        let both: Vec<f64> = std::thread::scope(|s| {
            let t: Vec<_> = (0..2).map(|_| s.spawn(adds_per_second)).collect();
            t.into_iter().map(|h| h.join().expect("bench thread")).collect()
        });
        paired = paired.max(both.iter().copied().fold(f64::INFINITY, f64::min));
    }
    println!("one thread                {:6.2} G additions/s", alone / 1e9);
    println!("each of two threads       {:6.2} G additions/s", paired / 1e9);
    println!(
        "two threads / one thread  {:6.2}  (≈ 1: two cores; ≈ 0.5: two threads of one core)",
        paired / alone
    );
}
