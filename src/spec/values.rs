//! Range-checked scalar types for pipeline files. Validating inside `Deserialize` lets serde_yaml
//! attach the file position to every "value out of range" error.

use serde::de::{self, Deserializer, Visitor};
use serde::{Deserialize, Serialize};
use std::fmt;

macro_rules! checked_f64 {
    ($name:ident, $doc:literal, $ok:expr, $expect:literal) => {
        #[doc = $doc]
        #[derive(Debug, Clone, Copy, PartialEq, Serialize)]
        #[serde(transparent)]
        pub struct $name(pub f64);

        impl<'de> Deserialize<'de> for $name {
            fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
                let v = f64::deserialize(d)?;
                let ok: fn(f64) -> bool = $ok;
                if ok(v) {
                    Ok(Self(v))
                } else {
                    Err(de::Error::custom(format!("{v} is not allowed here; expected {}", $expect)))
                }
            }
        }
    };
}

checked_f64!(Unit, "A number in [0, 1] (ε, γ, λ).", |v| (0.0..=1.0).contains(&v), "a number in [0, 1]");
checked_f64!(
    Positive,
    "A finite number > 0 (α, width).",
    |v| v.is_finite() && v > 0.0,
    "a finite number > 0"
);
checked_f64!(Finite, "Any finite number.", |v| v.is_finite(), "a finite number");
checked_f64!(
    SubUnit,
    "A number in [0, 1) (pruning and trace cutoffs).",
    |v| (0.0..1.0).contains(&v),
    "a number in [0, 1)"
);

/// A list of grid values: an integer, a list of integers, or an inclusive range `"A..B"`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Values(pub Vec<u32>);

impl Serialize for Values {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        self.0.serialize(s)
    }
}

impl<'de> Deserialize<'de> for Values {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = Values;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("an integer, a list of integers, or a range like \"2..10\"")
            }
            fn visit_u64<E: de::Error>(self, v: u64) -> Result<Values, E> {
                u32::try_from(v).map(|v| Values(vec![v])).map_err(|_| E::custom(format!("{v} is too large")))
            }
            fn visit_i64<E: de::Error>(self, v: i64) -> Result<Values, E> {
                u32::try_from(v)
                    .map(|v| Values(vec![v]))
                    .map_err(|_| E::custom(format!("{v} is not allowed; expected a positive integer")))
            }
            fn visit_str<E: de::Error>(self, s: &str) -> Result<Values, E> {
                let bad = || {
                    E::custom(format!("\"{s}\" is not a range; write \"A..B\" (inclusive), e.g. \"2..10\""))
                };
                let (a, b) = s.split_once("..").ok_or_else(bad)?;
                let a: u32 = a.trim().parse().map_err(|_| bad())?;
                let b: u32 = b.trim().parse().map_err(|_| bad())?;
                if a > b {
                    return Err(E::custom(format!(
                        "range \"{s}\" is empty; the first bound must be ≤ the second"
                    )));
                }
                if b - a > 10_000 {
                    return Err(E::custom(format!("range \"{s}\" has more than 10000 values")));
                }
                Ok(Values((a..=b).collect()))
            }
            fn visit_seq<A: de::SeqAccess<'de>>(self, mut seq: A) -> Result<Values, A::Error> {
                let mut out = Vec::new();
                while let Some(v) = seq.next_element::<u32>()? {
                    if out.contains(&v) {
                        return Err(de::Error::custom(format!("value {v} is listed twice")));
                    }
                    out.push(v);
                }
                if out.is_empty() {
                    return Err(de::Error::custom("the list of values is empty; give at least one"));
                }
                Ok(Values(out))
            }
        }
        d.deserialize_any(V)
    }
}

/// Values of a `vary` axis: a number, a list of numbers, or an inclusive integer range `"A..B"`.
/// Bins, sets and actions are checked to be whole numbers where the axis is known.
#[derive(Debug, Clone, PartialEq)]
pub struct AxisValues(pub Vec<f64>);

impl<'de> Deserialize<'de> for AxisValues {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = AxisValues;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("a number, a list of numbers, or a range like \"2..10\"")
            }
            fn visit_u64<E: de::Error>(self, v: u64) -> Result<AxisValues, E> {
                self.visit_f64(v as f64)
            }
            fn visit_i64<E: de::Error>(self, v: i64) -> Result<AxisValues, E> {
                self.visit_f64(v as f64)
            }
            fn visit_f64<E: de::Error>(self, v: f64) -> Result<AxisValues, E> {
                if v.is_finite() {
                    Ok(AxisValues(vec![v]))
                } else {
                    Err(E::custom(format!("{v} is not allowed; expected a finite number")))
                }
            }
            fn visit_str<E: de::Error>(self, s: &str) -> Result<AxisValues, E> {
                Values::deserialize(de::value::StrDeserializer::<E>::new(s))
                    .map(|v| AxisValues(v.0.into_iter().map(f64::from).collect()))
            }
            fn visit_seq<A: de::SeqAccess<'de>>(self, mut seq: A) -> Result<AxisValues, A::Error> {
                let mut out: Vec<f64> = Vec::new();
                while let Some(v) = seq.next_element::<f64>()? {
                    if !v.is_finite() {
                        return Err(de::Error::custom(format!(
                            "{v} is not allowed; expected a finite number"
                        )));
                    }
                    if out.contains(&v) {
                        return Err(de::Error::custom(format!("value {v} is listed twice")));
                    }
                    out.push(v);
                }
                if out.is_empty() {
                    return Err(de::Error::custom("the list of values is empty; give at least one"));
                }
                Ok(AxisValues(out))
            }
        }
        d.deserialize_any(V)
    }
}

/// The seeds of every cell: a count `n` (seeds 0..n−1) or an explicit list.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Seeds(pub Vec<u64>);

impl<'de> Deserialize<'de> for Seeds {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = Seeds;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("a number of seeds (≥ 1) or a list of seeds")
            }
            fn visit_u64<E: de::Error>(self, n: u64) -> Result<Seeds, E> {
                match n {
                    0 => Err(E::custom("seeds: 0 is not allowed; use at least 1")),
                    n if n > 100_000 => Err(E::custom(format!("seeds: {n} is more than 100000"))),
                    n => Ok(Seeds((0..n).collect())),
                }
            }
            fn visit_i64<E: de::Error>(self, n: i64) -> Result<Seeds, E> {
                if n < 0 {
                    return Err(E::custom(format!("seeds: {n} is negative; use a count ≥ 1 or a list")));
                }
                self.visit_u64(n as u64)
            }
            fn visit_seq<A: de::SeqAccess<'de>>(self, mut seq: A) -> Result<Seeds, A::Error> {
                let mut out = Vec::new();
                while let Some(v) = seq.next_element::<u64>()? {
                    if out.contains(&v) {
                        return Err(de::Error::custom(format!("seed {v} is listed twice")));
                    }
                    out.push(v);
                }
                if out.is_empty() {
                    return Err(de::Error::custom("seeds: the list is empty; give at least one seed"));
                }
                Ok(Seeds(out))
            }
        }
        d.deserialize_any(V)
    }
}

impl Serialize for Seeds {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        self.0.serialize(s)
    }
}
