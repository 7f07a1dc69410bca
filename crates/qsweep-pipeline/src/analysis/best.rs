//! Table III's rules, defined once for the report and the race: the episodes a trial counts and
//! which cell of a heatmap is best.
//!
//! Episodes counted: a converged trial counts its `episodes_to_goal` (or, under the exploratory
//! `counting: failures`, the `episodes_to_goal − 1` failed episodes before it; under
//! `counting: window-start` and Gym's solved rule, the window's first episode
//! `episodes_to_goal − window + 1`); a trial that never reached the goal is kept and counted at
//! the episode cap `max_episodes` (right-censored), so failures raise a cell's mean instead of
//! vanishing from it.

use qsweep_engine::config::Limits;
use qsweep_engine::{Counting, Outcome};

/// The Table III rule, as stated in every caption.
pub const BEST_RULE: &str = "Best cell: the lowest mean among the cells where every seed reached the \
learning goal; if no cell qualifies, the cell with the most successes, then the lowest mean (marked †).";

/// How a race changes the rule and the counts, as stated in the captions of raced reports.
pub const RACE_RULE: &str = "Raced: seeds went round by round only to the cells not significantly worse \
than the best (one-sided Welch t-test against the best cell, Holm-corrected over the cells of the heatmap, \
at the pipeline's confidence); n is the seeds a cell got, the best cell is chosen among the final \
contenders, and contenders = how many cells are still tied with it.";

/// How non-converged trials enter the statistics, as stated in every caption.
pub const CENSORING: &str = "Trials that never reached the goal are not dropped: they count at the \
episode cap (max_episodes), so those means are lower bounds. std is the sample standard deviation \
(n − 1).";

/// Episodes a trial contributes to its cell's statistics, under its `limits` (the episode cap
/// `max_episodes`, and the success criterion's window) and the pipeline's `counting`.
pub fn episodes_counted(outcome: &Outcome, limits: &Limits, counting: Counting) -> u32 {
    match (outcome.converged, outcome.episodes_to_goal, counting) {
        (true, Some(e), Counting::Episodes) => e,
        (true, Some(e), Counting::Failures) => e.saturating_sub(1),
        // The solved rule's goal episode ends a full window, so e ≥ window; window 1 otherwise.
        (true, Some(e), Counting::WindowStart) => {
            e.saturating_sub(limits.success.solved_window().unwrap_or(1) - 1)
        }
        _ => limits.max_episodes,
    }
}

/// The chosen best cell of one algorithm in one experiment.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Best {
    /// Index into the experiment's cells.
    pub cell: usize,
    /// Whether every present seed of that cell reached the goal (false: fallback, marked †).
    pub all_converged: bool,
}

/// What the best-cell rule looks at.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Candidate {
    /// Cell index.
    pub index: usize,
    /// Present trials.
    pub n: usize,
    /// Trials that reached the goal.
    pub successes: usize,
    /// Mean counted episodes (`None` without trials).
    pub mean: Option<f64>,
}

/// The best-cell rule ([`BEST_RULE`]). Cells without trials never win; ties keep the earlier cell.
pub fn best_cell(candidates: impl IntoIterator<Item = Candidate>) -> Option<Best> {
    let mut best: Option<(Candidate, bool)> = None;
    for c in candidates {
        let Some(mean) = c.mean.filter(|_| c.n > 0) else { continue };
        let all = c.successes == c.n;
        let better = match best {
            None => true,
            Some((b, b_all)) => {
                let b_mean = b.mean.expect("kept candidates have a mean");
                match (all, b_all) {
                    (true, false) => true,
                    (false, true) => false,
                    (true, true) => mean < b_mean,
                    (false, false) => {
                        c.successes > b.successes || (c.successes == b.successes && mean < b_mean)
                    }
                }
            }
        };
        if better {
            best = Some((c, all));
        }
    }
    best.map(|(c, all)| Best { cell: c.index, all_converged: all })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_counting_counts_a_converged_trial_its_way_and_a_failed_one_at_the_cap() {
        use qsweep_engine::config::{Success, Truncation};
        use qsweep_engine::StopReason;
        let outcome = |goal: Option<u32>| Outcome {
            converged: goal.is_some(),
            episodes_to_goal: goal,
            episodes: goal.unwrap_or(500),
            total_steps: 0,
            stop: if goal.is_some() { StopReason::Goal } else { StopReason::MaxEpisodes },
            failure: None,
            episode_lengths: Vec::new(),
        };
        let limits = |success| Limits {
            success,
            max_episodes: 500,
            max_total_steps: 1,
            truncation: Truncation::Bootstrap,
        };
        let solved = limits(Success::Solved { window: 100, mean_length: 195.0, episode_steps: 200 });
        let balance = limits(Success::Balance { steps: 200 });
        let reach = limits(Success::Reach { within: 200, streak: 3, max_episode_steps: 200 });
        let count = |goal, l: &Limits, c| episodes_counted(&outcome(goal), l, c);
        // Solved at episode 130: the window is episodes 31..=130.
        assert_eq!(count(Some(130), &solved, Counting::Episodes), 130);
        assert_eq!(count(Some(130), &solved, Counting::Failures), 129);
        assert_eq!(count(Some(130), &solved, Counting::WindowStart), 31);
        assert_eq!(count(Some(100), &solved, Counting::WindowStart), 1, "the earliest possible");
        // Any other criterion has a window of 1 (a streak is not a solved window).
        assert_eq!(count(Some(130), &balance, Counting::WindowStart), 130);
        assert_eq!(count(Some(130), &reach, Counting::WindowStart), 130);
        for c in [Counting::Episodes, Counting::Failures, Counting::WindowStart] {
            assert_eq!(count(None, &solved, c), 500);
            assert_eq!(count(None, &balance, c), 500);
        }
    }

    fn c(index: usize, n: usize, successes: usize, mean: Option<f64>) -> Candidate {
        Candidate { index, n, successes, mean }
    }

    #[test]
    fn lowest_mean_among_fully_converged_cells_wins() {
        let cands = [
            c(0, 10, 9, Some(1.0)), // lower mean but one seed failed
            c(1, 10, 10, Some(5.0)),
            c(2, 10, 10, Some(3.0)),
            c(3, 10, 10, Some(3.0)), // tie: the earlier cell stays
            c(4, 0, 0, None),
        ];
        assert_eq!(best_cell(cands), Some(Best { cell: 2, all_converged: true }));
    }

    #[test]
    fn all_failed_falls_back_to_most_successes_then_lowest_mean() {
        let cands = [
            c(0, 10, 3, Some(50.0)),
            c(1, 10, 7, Some(90.0)),
            c(2, 10, 7, Some(80.0)),
            c(3, 10, 0, Some(1.0)),
        ];
        assert_eq!(best_cell(cands), Some(Best { cell: 2, all_converged: false }));
        // No trial converged anywhere: the lowest (censored) mean.
        let none = [c(0, 4, 0, Some(200.0)), c(1, 4, 0, Some(150.0))];
        assert_eq!(best_cell(none), Some(Best { cell: 1, all_converged: false }));
    }

    #[test]
    fn no_trials_no_best() {
        assert_eq!(best_cell([c(0, 0, 0, None), c(1, 0, 0, None)]), None);
        assert_eq!(best_cell([]), None);
        // A cell whose only present trials all converged qualifies even if others are missing.
        assert_eq!(
            best_cell([c(0, 0, 0, None), c(1, 2, 2, Some(4.0))]),
            Some(Best { cell: 1, all_converged: true })
        );
    }
}
