//! Gym's "solved" rule as a learning goal: the first episode E at which the mean episode length
//! over the last `window` consecutive episodes (E − window + 1 ..= E, so E ≥ window) reaches a
//! threshold. Gym's rule is on the mean return over 100 episodes: CartPole's return is the
//! episode length (the failing step included), so a survival task needs mean ≥ threshold
//! (CartPole-v0: 195); MountainCar's is −length (a cut-off episode counts at its cut length), so a
//! goal task needs mean ≤ threshold (MountainCar-v0: −110 → 110).
//!
//! The comparison is on integers made exact in f64: the window's sum of lengths against
//! `mean_length × window`, one fixed product computed once, so the rule is the same on every
//! machine (no division, no fused multiply-add).

use super::env::TaskKind;

/// The sliding window of the solved rule, fed one episode length at a time.
#[derive(Debug, Clone)]
pub struct SolvedWindow {
    window: usize,
    /// `mean_length × window`: what the window's sum is compared with.
    threshold: f64,
    /// Survival tasks need the sum at least the threshold; goal tasks at most.
    at_least: bool,
    /// Sum of the last `window` lengths (fewer while the trial is younger).
    sum: u64,
}

impl SolvedWindow {
    /// The rule for `task` over `window` ≥ 1 episodes with threshold `mean_length`.
    pub fn new(window: u32, mean_length: f64, task: TaskKind) -> Self {
        assert!(window >= 1, "validated: window ≥ 1");
        Self {
            window: window as usize,
            threshold: mean_length * f64::from(window),
            at_least: task == TaskKind::Survival,
            sum: 0,
        }
    }

    /// Take the newest episode, the last of `lengths` (every episode so far, in order): whether the
    /// last `window` episodes now reach the threshold (false while fewer than `window` have run).
    pub fn push(&mut self, lengths: &[u32]) -> bool {
        let n = lengths.len();
        self.sum += u64::from(lengths[n - 1]);
        if n > self.window {
            self.sum -= u64::from(lengths[n - 1 - self.window]);
        }
        n >= self.window && self.reached(self.sum)
    }

    fn reached(&self, sum: u64) -> bool {
        // Exact: a sum of at most 2^32 lengths below 2^32 each is below 2^64, and the sums that
        // occur (window × episode cap) are far below 2^53.
        let sum = sum as f64;
        if self.at_least {
            sum >= self.threshold
        } else {
            sum <= self.threshold
        }
    }
}

/// The episode (1-based) at which `lengths` first meets the rule, if any: the direct definition
/// that [`SolvedWindow`] computes incrementally.
pub fn solved_at(lengths: &[u32], window: u32, mean_length: f64, task: TaskKind) -> Option<u32> {
    let w = window as usize;
    let rule = SolvedWindow::new(window, mean_length, task);
    (w..=lengths.len())
        .find(|&e| rule.reached(lengths[e - w..e].iter().map(|&l| u64::from(l)).sum()))
        .map(|e| e as u32)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn incremental(lengths: &[u32], window: u32, mean_length: f64, task: TaskKind) -> Option<u32> {
        let mut w = SolvedWindow::new(window, mean_length, task);
        (1..=lengths.len()).find(|&n| w.push(&lengths[..n])).map(|n| n as u32)
    }

    #[test]
    fn survival_needs_the_mean_at_least_the_threshold_over_a_full_window() {
        // Window 3, threshold 195 (sum ≥ 585): episode 1 alone is 200 ≥ 195, but the window is
        // full only at episode 3, where episodes 1–3 sum 590. With a first episode of 10 and a
        // window of 4 (sum ≥ 780), episodes 1–4 sum 600 and episodes 2–5 sum 785: episode 5,
        // also for the threshold 196.25 (785 exactly), not for 196.26 (785.04).
        let lengths = [200, 190, 200, 195, 200];
        assert_eq!(solved_at(&lengths, 3, 195.0, TaskKind::Survival), Some(3));
        assert_eq!(solved_at(&lengths[..2], 3, 195.0, TaskKind::Survival), None, "E ≥ window");
        assert_eq!(solved_at(&[10, 200, 190, 200, 195], 4, 195.0, TaskKind::Survival), Some(5));
        assert_eq!(solved_at(&[10, 200, 190, 200, 195], 4, 196.25, TaskKind::Survival), Some(5));
        assert_eq!(solved_at(&[10, 200, 190, 200, 195], 4, 196.26, TaskKind::Survival), None);
        // Exactly at the threshold counts (Gym: `>=`).
        assert_eq!(solved_at(&[195, 195], 2, 195.0, TaskKind::Survival), Some(2));
    }

    #[test]
    fn goal_tasks_need_the_mean_at_most_the_threshold_cut_episodes_counting_at_the_cut() {
        // MountainCar-v0-like: cut at 200; window 2, threshold 110 (sum ≤ 220).
        let lengths = [200, 200, 90, 140, 80, 100];
        // Episodes 3–4: 230 > 220; 4–5: 220 ≤ 220.
        assert_eq!(solved_at(&lengths, 2, 110.0, TaskKind::GoalReaching), Some(5));
        assert_eq!(solved_at(&lengths, 1, 110.0, TaskKind::GoalReaching), Some(3));
        assert_eq!(solved_at(&lengths, 6, 110.0, TaskKind::GoalReaching), None);
    }

    #[test]
    fn the_sliding_window_agrees_with_the_definition() {
        // A fixed pseudo-random sequence of lengths 1..=200.
        let mut x = 12345u64;
        let lengths: Vec<u32> = (0..500)
            .map(|_| {
                x = x.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
                (x >> 33) as u32 % 200 + 1
            })
            .collect();
        for window in [1, 2, 7, 100] {
            for t in [60.0, 100.0, 110.5, 140.0] {
                for task in [TaskKind::Survival, TaskKind::GoalReaching] {
                    assert_eq!(
                        incremental(&lengths, window, t, task),
                        solved_at(&lengths, window, t, task),
                        "window {window}, threshold {t}, {task:?}"
                    );
                }
            }
        }
    }
}
