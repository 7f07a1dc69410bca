//! `cargo bench --bench cores`: whether this machine's CPUs have adders of their own. A loop of
//! independent floating-point additions, bound by the core's adders and nothing else, runs on one
//! thread, then on two at once, and each prints additions per second. Two CPUs that share one
//! core's adders (the two hardware threads of an SMT core, or two virtual CPUs time-sharing one)
//! get about half the one-thread rate each; two cores each keep it. That decides what running
//! trials in lockstep can gain (docs/speed.md). Read it on an idle machine: a busy second CPU
//! also halves the rate. The threads are not pinned, so on a machine with more than two CPUs the
//! system may place them on two cores (pin with `taskset -c 0,N`).

use std::hint::black_box;
use std::time::Instant;

/// Independent accumulators: at the build's baseline (SSE2, two per register) enough additions in
/// flight to keep the adders busy, few enough to stay in registers. A run with half as many
/// chains at the same rate shows that the loop is bound by the adders, not by waiting.
const CHAINS: usize = 24;
const ADDITIONS: u64 = 3_600_000_000;

/// `ADDITIONS` additions on `N` chains; returns additions per second of wall time.
fn adds_per_second<const N: usize>() -> f64 {
    let x = black_box(1e-12);
    let mut acc = [0.0f64; N];
    for (i, a) in acc.iter_mut().enumerate() {
        *a = black_box(i as f64);
    }
    let start = Instant::now();
    for _ in 0..ADDITIONS / N as u64 {
        // Floating-point addition is not associative, so the compiler must perform every one.
        for a in &mut acc {
            *a += x;
        }
    }
    black_box(&acc);
    ADDITIONS as f64 / start.elapsed().as_secs_f64()
}

fn main() {
    let cpus = std::thread::available_parallelism().map_or(1, |n| n.get());
    let siblings = std::fs::read_to_string("/sys/devices/system/cpu/cpu0/topology/thread_siblings_list");
    println!(
        "CPUs: {cpus}; CPU 0's hardware threads (as the system reports them): {}",
        siblings.as_deref().map_or("unknown", str::trim)
    );
    let (mut alone, mut half, mut paired) = (0.0f64, 0.0f64, 0.0f64);
    for _ in 0..3 {
        alone = alone.max(adds_per_second::<CHAINS>());
        half = half.max(adds_per_second::<{ CHAINS / 2 }>());
        let both: Vec<f64> = std::thread::scope(|s| {
            let t: Vec<_> = (0..2).map(|_| s.spawn(adds_per_second::<CHAINS>)).collect();
            t.into_iter().map(|h| h.join().expect("bench thread")).collect()
        });
        paired = paired.max(both.iter().copied().fold(f64::INFINITY, f64::min));
    }
    println!("one thread, {CHAINS} chains          {:6.2} G additions/s", alone / 1e9);
    let bound = if half >= 0.9 * alone {
        "about as many: the loop is bound by the adders"
    } else {
        "fewer: the loop waits on its chains, so the ratio below cannot tell"
    };
    println!("one thread, {} chains          {:6.2} G additions/s ({bound})", CHAINS / 2, half / 1e9);
    println!("each of two threads, {CHAINS} chains {:6.2} G additions/s", paired / 1e9);
    println!(
        "two threads / one thread        {:6.2}  (≈ 1: two cores; ≈ 0.5: one core's adders shared)",
        paired / alone
    );
}
