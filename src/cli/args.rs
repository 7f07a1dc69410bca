//! Value parsers shared by subcommands: finite numbers, comma lists, NAME=VALUE pairs. Range
//! rules come from `qsweep_engine::rules`, the same ones pipeline files and `TrialConfig::validate` use.

use qsweep_engine::env::SystemKind;
use qsweep_engine::rules::{self, Real};

/// A system name.
pub fn system(s: &str) -> Result<SystemKind, String> {
    SystemKind::parse(s).ok_or_else(|| format!("unknown system '{s}'; use {}", SystemKind::listed()))
}

/// A finite floating-point number.
pub fn finite(s: &str) -> Result<f64, String> {
    let v: f64 = s.trim().parse().map_err(|_| format!("'{s}' is not a number"))?;
    rules::FINITE.check(v)
}

fn ruled(rule: Real, s: &str) -> Result<f64, String> {
    let v: f64 = s.trim().parse().map_err(|_| format!("'{s}' is not a number; expected {}", rule.expect))?;
    rule.check(v)
}

/// A comma-separated list of finite numbers.
#[derive(Debug, Clone)]
pub struct Floats(pub Vec<f64>);

/// Parse a comma-separated list of finite numbers.
pub fn finite_list(s: &str) -> Result<Floats, String> {
    if s.trim().is_empty() {
        return Err("expected a comma-separated list of numbers, got nothing".into());
    }
    s.split(',').map(finite).collect::<Result<_, _>>().map(Floats)
}

/// A comma-separated list of positive integers (bins or fuzzy sets per variable).
#[derive(Debug, Clone)]
pub struct Counts(pub Vec<u32>);

/// Parse a comma-separated list of positive integers.
pub fn count_list(s: &str) -> Result<Counts, String> {
    s.split(',')
        .map(|p| match p.trim().parse::<u32>() {
            Ok(v) => rules::resolution(v, None),
            Err(_) => Err(format!("'{p}' is not a positive integer")),
        })
        .collect::<Result<_, _>>()
        .map(Counts)
}

/// A `NAME=VALUE` pair with a finite value.
pub fn param(s: &str) -> Result<(String, f64), String> {
    let (name, value) = s.split_once('=').ok_or_else(|| format!("'{s}' is not NAME=VALUE"))?;
    Ok((name.trim().to_string(), finite(value)?))
}

/// A probability-like value in [0, 1] (ε, γ, λ).
pub fn unit(s: &str) -> Result<f64, String> {
    ruled(rules::UNIT, s)
}

/// A finite value > 0 (α, width).
pub fn positive(s: &str) -> Result<f64, String> {
    ruled(rules::POSITIVE, s)
}

/// A cutoff in [0, 1) (prune, trace cutoff).
pub fn sub_unit(s: &str) -> Result<f64, String> {
    ruled(rules::SUB_UNIT, s)
}

/// A cap or count ≥ 1 (max episodes, max total steps).
pub fn at_least_one(s: &str) -> Result<u64, String> {
    let v: u64 = s.trim().parse().map_err(|_| format!("'{s}' is not an integer ≥ 1"))?;
    rules::at_least_one(v)
}

/// An episode cap: 1 to 2^32 − 1.
pub fn episodes(s: &str) -> Result<u32, String> {
    let v = at_least_one(s)?;
    u32::try_from(v)
        .map_err(|_| format!("{v} is not allowed here; expected an integer from 1 to {}", u32::MAX))
}

/// A step count held in 32 bits (balance steps): 1 to 2^32 − 1.
pub fn steps(s: &str) -> Result<u64, String> {
    let v: u64 = s.trim().parse().map_err(|_| format!("'{s}' is not an integer ≥ 1"))?;
    rules::steps(v)
}

/// An action count n ≥ 2.
pub fn action_count(s: &str) -> Result<u32, String> {
    match s.trim().parse::<u32>() {
        Ok(n) => rules::actions(n),
        Err(_) => Err(format!("'{s}' is not an integer ≥ 2")),
    }
}
