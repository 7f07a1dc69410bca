//! Episodes to goal as a survival time: trials that hit the episode cap without reaching the goal
//! are right-censored there, not counted as if they had succeeded at the cap. The Kaplan–Meier
//! estimator gives a median that uses them correctly.

/// The caption's sentence for the censoring columns.
pub const SURVIVAL_RULE: &str = "Censored: share of trials cut at the episode cap; KM median: \
Kaplan–Meier median with them right-censored there.";

/// The Kaplan–Meier median of `times`, where `event` says whether the time is an observed event
/// (true) or a right-censoring (false): the smallest event time at which the estimated survival
/// falls to 0.5 or below; `None` when it never does (or without times). At a tie, events come
/// before censorings (a trial censored at t was still at risk at t).
pub fn km_median(times: &[(f64, bool)]) -> Option<f64> {
    let mut sorted = times.to_vec();
    sorted.sort_by(|a, b| a.0.total_cmp(&b.0).then(b.1.cmp(&a.1)));
    let mut at_risk = sorted.len();
    let mut survival = 1.0;
    let mut i = 0;
    while i < sorted.len() {
        let t = sorted[i].0;
        let same = sorted[i..].iter().take_while(|x| x.0 == t).count();
        let events = sorted[i..i + same].iter().filter(|x| x.1).count();
        if events > 0 {
            survival *= 1.0 - events as f64 / at_risk as f64;
            if survival <= 0.5 {
                return Some(t);
            }
        }
        at_risk -= same;
        i += same;
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn without_censoring_it_is_the_lower_median() {
        let v: Vec<(f64, bool)> = [5.0, 1.0, 3.0, 2.0].iter().map(|&t| (t, true)).collect();
        // S: 0.75 at 1, 0.5 at 2.
        assert_eq!(km_median(&v), Some(2.0));
        let odd: Vec<(f64, bool)> = [4.0, 1.0, 9.0].iter().map(|&t| (t, true)).collect();
        assert_eq!(km_median(&odd), Some(4.0));
    }

    #[test]
    fn censored_trials_leave_the_risk_set_without_a_step() {
        // Times [1, 2, 2, 3, 4], events [1, 0, 1, 1, 0]: S = 0.8 at 1, 0.6 at 2 (one event of the
        // four at risk; the censored 2 was still at risk), 0.3 at 3 (one of two).
        let v = [(1.0, true), (2.0, false), (2.0, true), (3.0, true), (4.0, false)];
        assert_eq!(km_median(&v), Some(3.0));
    }

    #[test]
    fn mostly_censored_has_no_median() {
        let v = [(3.0, true), (100.0, false), (100.0, false)];
        assert_eq!(km_median(&v), None);
        assert_eq!(km_median(&[]), None);
    }
}
