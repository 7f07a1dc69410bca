//! Value parsers shared by subcommands: finite numbers, comma lists, NAME=VALUE pairs.

use crate::sim::env::SystemKind;

/// A system name.
pub fn system(s: &str) -> Result<SystemKind, String> {
    SystemKind::parse(s)
        .ok_or_else(|| format!("unknown system '{s}'; use ball-beam, cart-pole or mountain-car"))
}

/// A finite floating-point number.
pub fn finite(s: &str) -> Result<f64, String> {
    let v: f64 = s.trim().parse().map_err(|_| format!("'{s}' is not a number"))?;
    if v.is_finite() {
        Ok(v)
    } else {
        Err(format!("'{s}' is not a finite number"))
    }
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
            Ok(0) => Err("0 is not allowed; each variable needs at least 1 bin or fuzzy set".to_string()),
            Ok(v) => Ok(v),
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

/// A probability-like value in [0, 1].
pub fn unit(s: &str) -> Result<f64, String> {
    let v = finite(s)?;
    if (0.0..=1.0).contains(&v) {
        Ok(v)
    } else {
        Err(format!("{v} is outside [0, 1]"))
    }
}

/// A finite value > 0.
pub fn positive(s: &str) -> Result<f64, String> {
    let v = finite(s)?;
    if v > 0.0 {
        Ok(v)
    } else {
        Err(format!("{v} must be > 0"))
    }
}

/// An action count n ≥ 2.
pub fn action_count(s: &str) -> Result<u32, String> {
    match s.trim().parse::<u32>() {
        Ok(n) if n >= 2 => Ok(n),
        Ok(n) => Err(format!("{n} actions is too few; A_n needs n ≥ 2")),
        Err(_) => Err(format!("'{s}' is not an integer ≥ 2")),
    }
}
