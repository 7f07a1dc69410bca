//! The range rule of every setting, defined once. The pipeline parser (`qsweep_pipeline::declared`), `TrialConfig::validate`
//! and the command-line parsers (`cli::args`) all call these, so a value is accepted or refused the
//! same way, in the same words, wherever it is given. Messages say what was given and what is
//! allowed; the caller adds the field's name (or the file position).

use super::repr::ReprKind;

/// The rule of a real-valued setting.
#[derive(Debug, Clone, Copy)]
pub struct Real {
    /// What is allowed, for messages ("a number in [0, 1]").
    pub expect: &'static str,
    ok: fn(f64) -> bool,
}

impl Real {
    /// `Ok(v)` if allowed, else a message naming the value and what is allowed.
    pub fn check(&self, v: f64) -> Result<f64, String> {
        if (self.ok)(v) {
            Ok(v)
        } else {
            Err(format!("{v} is not allowed here; expected {}", self.expect))
        }
    }
}

/// ε, γ, λ: a number in [0, 1].
pub const UNIT: Real = Real { expect: "a number in [0, 1]", ok: |v| (0.0..=1.0).contains(&v) };
/// α, fuzzy width, positive physical parameters: a finite number > 0.
pub const POSITIVE: Real = Real { expect: "a finite number > 0", ok: |v| v.is_finite() && v > 0.0 };
/// Initial Q value and other physical parameters: any finite number.
pub const FINITE: Real = Real { expect: "a finite number", ok: f64::is_finite };
/// Pruning and trace cutoffs: a number in [0, 1) (1 would drop everything).
pub const SUB_UNIT: Real = Real { expect: "a number in [0, 1)", ok: |v| (0.0..1.0).contains(&v) };

/// A race's confidence level: strictly between 0 and 1 (0 drops nothing, 1 nothing ever).
pub const CONFIDENCE: Real =
    Real { expect: "a number strictly between 0 and 1, e.g. 0.95", ok: |v| v > 0.0 && v < 1.0 };

/// Caps and counts (`max_episodes`, `max_total_steps`, `within`, `streak`): an integer ≥ 1.
pub fn at_least_one(v: u64) -> Result<u64, String> {
    if v >= 1 {
        Ok(v)
    } else {
        Err("0 is not allowed here; expected an integer ≥ 1".into())
    }
}

/// Step counts the simulation holds in 32 bits (`steps`, `max_episode_steps`): 1 to 2^32 − 1.
pub fn steps(v: u64) -> Result<u64, String> {
    if (1..=u64::from(u32::MAX)).contains(&v) {
        Ok(v)
    } else {
        Err(format!("{v} is not allowed here; expected an integer from 1 to {}", u32::MAX))
    }
}

/// Largest action count n of A_n.
pub const MAX_ACTIONS: u32 = 1024;

/// The action count n of A_n: 2 to [`MAX_ACTIONS`].
pub fn actions(n: u32) -> Result<u32, String> {
    if (2..=MAX_ACTIONS).contains(&n) {
        Ok(n)
    } else if n < 2 {
        Err(format!("{n} actions is not allowed; A_n needs n ≥ 2"))
    } else {
        Err(format!("{n} actions is not allowed; use 2 to {MAX_ACTIONS}"))
    }
}

/// Largest number of bins or fuzzy sets per variable for a representation.
pub fn max_resolution(kind: ReprKind) -> u32 {
    match kind {
        ReprKind::Crisp => 1 << 20,
        ReprKind::Fuzzy => super::repr::MAX_SETS as u32,
    }
}

/// Bins or fuzzy sets of one variable: at least 1, at most [`max_resolution`] (of either kind when
/// `kind` is not known yet).
pub fn resolution(v: u32, kind: Option<ReprKind>) -> Result<u32, String> {
    let (max, what) = match kind {
        Some(ReprKind::Fuzzy) => (max_resolution(ReprKind::Fuzzy), "fuzzy sets"),
        Some(ReprKind::Crisp) => (max_resolution(ReprKind::Crisp), "bins"),
        None => (max_resolution(ReprKind::Crisp), "bins"),
    };
    if v < 1 {
        Err(format!("{v} is not allowed; every variable needs at least 1 bin or fuzzy set"))
    } else if v > max {
        Err(format!("{v} is not allowed; each variable has 1 to {max} {what}"))
    } else {
        Ok(v)
    }
}

/// A variable's range `[lo, hi]`: two finite numbers with lo < hi.
pub fn bounds(lo: f64, hi: f64) -> Result<[f64; 2], String> {
    if lo.is_finite() && hi.is_finite() && lo < hi {
        Ok([lo, hi])
    } else {
        Err(format!("[{lo}, {hi}] is not allowed; expected two finite numbers with lo < hi"))
    }
}

/// Most seeds per cell.
pub const MAX_SEEDS: u64 = 100_000;

/// A seed count: 1 to [`MAX_SEEDS`].
pub fn seed_count(n: u64) -> Result<u64, String> {
    match n {
        0 => Err("0 is not allowed; use at least 1".into()),
        n if n > MAX_SEEDS => Err(format!("{n} is more than {MAX_SEEDS}")),
        n => Ok(n),
    }
}

/// The success criterion form each task takes in a pipeline file, for messages.
pub const BALANCE_SYNTAX: &str = "success: { steps: N }";
/// The goal-reaching form, for messages.
pub const REACH_SYNTAX: &str = "success: { within: N, streak: K, max_episode_steps: M }";
/// Gym's solved rule on a survival task (CartPole-v0), for messages.
pub const SOLVED_BALANCE_SYNTAX: &str = "success: { steps: 200, window: 100, mean_length: 195 }";
/// Gym's solved rule on a goal-reaching task (MountainCar-v0), for messages.
pub const SOLVED_REACH_SYNTAX: &str = "success: { max_episode_steps: 200, window: 100, mean_length: 110 }";

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rules_accept_their_ranges_and_name_them_otherwise() {
        assert_eq!(UNIT.check(1.0), Ok(1.0));
        assert_eq!(UNIT.check(-0.1).unwrap_err(), "-0.1 is not allowed here; expected a number in [0, 1]");
        assert!(POSITIVE.check(0.0).is_err() && POSITIVE.check(f64::INFINITY).is_err());
        assert!(SUB_UNIT.check(0.0).is_ok() && SUB_UNIT.check(1.0).is_err());
        assert!(FINITE.check(f64::NAN).is_err());
        assert!(at_least_one(0).is_err() && at_least_one(1).is_ok());
        assert!(steps(u64::from(u32::MAX) + 1).is_err() && steps(u64::from(u32::MAX)).is_ok());
        assert!(actions(1).unwrap_err().contains("n ≥ 2") && actions(MAX_ACTIONS + 1).is_err());
        assert!(resolution(0, None).unwrap_err().contains("at least 1 bin"));
        assert!(
            resolution(65, Some(ReprKind::Fuzzy)).is_err() && resolution(65, Some(ReprKind::Crisp)).is_ok()
        );
        assert!(bounds(1.0, 0.0).unwrap_err().contains("lo < hi"));
        assert!(seed_count(0).is_err() && seed_count(MAX_SEEDS + 1).is_err());
    }
}
