//! Range-checked scalar types for pipeline files, each applying its rule from `qsweep_engine::rules`.
//! Validating inside `Deserialize` puts every "value out of range" error at the value's own path,
//! which `load` turns into the file position of the field.

use qsweep_engine::rules;
use serde::de::{self, Deserializer, Visitor};
use serde::{Deserialize, Serialize};
use std::fmt;

macro_rules! checked_f64 {
    ($name:ident, $doc:literal, $rule:expr) => {
        #[doc = $doc]
        #[derive(Debug, Clone, Copy, PartialEq, Serialize)]
        #[serde(transparent)]
        pub struct $name(pub f64);

        impl<'de> Deserialize<'de> for $name {
            fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
                $rule.check(f64::deserialize(d)?).map(Self).map_err(de::Error::custom)
            }
        }
    };
}

checked_f64!(Unit, "A number in [0, 1] (ε, γ, λ).", rules::UNIT);
checked_f64!(Positive, "A finite number > 0 (α, width).", rules::POSITIVE);
checked_f64!(Finite, "Any finite number.", rules::FINITE);
checked_f64!(SubUnit, "A number in [0, 1) (pruning and trace cutoffs).", rules::SUB_UNIT);
checked_f64!(Confidence, "A number in (0, 1) (a race's confidence level).", rules::CONFIDENCE);

/// An integer ≥ 1 (caps and counts), checked by `rules::at_least_one`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct AtLeastOne(pub u64);

impl<'de> Deserialize<'de> for AtLeastOne {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        rules::at_least_one(u64::deserialize(d)?).map(Self).map_err(de::Error::custom)
    }
}

/// A variable's `[lo, hi]` range, checked by `rules::bounds`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Bounds(pub [f64; 2]);

impl<'de> Deserialize<'de> for Bounds {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let [lo, hi] = <[f64; 2]>::deserialize(d)?;
        rules::bounds(lo, hi).map(Self).map_err(de::Error::custom)
    }
}

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
                rules::seed_count(n).map(|n| Seeds((0..n).collect())).map_err(E::custom)
            }
            fn visit_i64<E: de::Error>(self, n: i64) -> Result<Seeds, E> {
                if n < 0 {
                    return Err(E::custom(format!("{n} is negative; use a count ≥ 1 or a list")));
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
                    return Err(de::Error::custom("the list is empty; give at least one seed"));
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

/// A map key checked by a function while it is read, so a bad key's error carries the key's own
/// path (serde_path_to_error records a key only for errors raised while reading it).
pub(super) struct CheckedKey<F>(pub F);

impl<'de, T, F: FnOnce(String) -> Result<T, String>> de::DeserializeSeed<'de> for CheckedKey<F> {
    type Value = T;
    fn deserialize<D: Deserializer<'de>>(self, d: D) -> Result<T, D::Error> {
        (self.0)(String::deserialize(d)?).map_err(de::Error::custom)
    }
}

/// A map value of type `T` checked by a function while it is read, so the error carries the path
/// of the value's key rather than of the whole map.
pub(super) struct CheckedValue<T, F>(pub F, pub std::marker::PhantomData<T>);

impl<'de, T: Deserialize<'de>, U, F: FnOnce(T) -> Result<U, String>> de::DeserializeSeed<'de>
    for CheckedValue<T, F>
{
    type Value = U;
    fn deserialize<D: Deserializer<'de>>(self, d: D) -> Result<U, D::Error> {
        (self.0)(T::deserialize(d)?).map_err(de::Error::custom)
    }
}
