//! The values of a program pipeline file as written, each checked while it is read: a param's
//! value (one scalar), a `vary` axis, a command's argv, the input globs, a metric's type, a
//! timeout, a provenance entry. Wrong shapes are errors at the value's own path.

use crate::program::model::MetricType;
use serde::de::{self, Deserializer, MapAccess, SeqAccess, Visitor};
use serde::Deserialize;
use std::fmt;
use std::time::Duration;

/// The longest per-trial timeout accepted: 30 days.
pub const MAX_TIMEOUT: Duration = Duration::from_secs(30 * 24 * 3600);

/// One value as written: a param's default, a fixed value, one value of an axis.
#[derive(Debug, Clone, PartialEq)]
pub enum Scalar {
    /// A whole number.
    Int(i64),
    /// A finite number with a fraction or exponent.
    Float(f64),
    /// `true` or `false`.
    Bool(bool),
    /// Text.
    Str(String),
}

impl fmt::Display for Scalar {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Int(i) => write!(f, "{i}"),
            Self::Float(x) => write!(f, "{x:?}"),
            Self::Bool(b) => write!(f, "{b}"),
            Self::Str(s) => write!(f, "`{s}`"),
        }
    }
}

/// What a scalar visitor accepts; `expecting` is shared by the types that read scalars.
struct ScalarVisitor;

impl<'de> Visitor<'de> for ScalarVisitor {
    type Value = Scalar;
    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str("one value: a number, true/false or text")
    }
    fn visit_i64<E: de::Error>(self, v: i64) -> Result<Scalar, E> {
        Ok(Scalar::Int(v))
    }
    fn visit_u64<E: de::Error>(self, v: u64) -> Result<Scalar, E> {
        i64::try_from(v)
            .map(Scalar::Int)
            .map_err(|_| E::custom(format!("{v} is too large; integers go up to {}", i64::MAX)))
    }
    fn visit_f64<E: de::Error>(self, v: f64) -> Result<Scalar, E> {
        if v.is_finite() {
            Ok(Scalar::Float(v))
        } else {
            Err(E::custom(format!("{v} is not allowed; give a finite number (JSON has no {v})")))
        }
    }
    fn visit_bool<E: de::Error>(self, v: bool) -> Result<Scalar, E> {
        Ok(Scalar::Bool(v))
    }
    fn visit_str<E: de::Error>(self, v: &str) -> Result<Scalar, E> {
        Ok(Scalar::Str(v.to_string()))
    }
    fn visit_unit<E: de::Error>(self) -> Result<Scalar, E> {
        Err(E::custom(
            "no value is given (null); write a number, true/false or text (quote text such as \"null\")",
        ))
    }
}

impl<'de> Deserialize<'de> for Scalar {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        d.deserialize_any(ScalarVisitor)
    }
}

/// The values of a `vary` axis as written: one value, a list, or (as text) a range `"A..B"`.
#[derive(Debug, Clone, PartialEq)]
pub enum Vary {
    /// One value (a range `"A..B"` is text here; `check` reads it against the param's type).
    One(Scalar),
    /// A list of values, at least one.
    List(Vec<Scalar>),
}

impl<'de> Deserialize<'de> for Vary {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = Vary;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("a value, a list of values, or a range like \"2..10\"")
            }
            fn visit_i64<E: de::Error>(self, v: i64) -> Result<Vary, E> {
                ScalarVisitor.visit_i64(v).map(Vary::One)
            }
            fn visit_u64<E: de::Error>(self, v: u64) -> Result<Vary, E> {
                ScalarVisitor.visit_u64(v).map(Vary::One)
            }
            fn visit_f64<E: de::Error>(self, v: f64) -> Result<Vary, E> {
                ScalarVisitor.visit_f64(v).map(Vary::One)
            }
            fn visit_bool<E: de::Error>(self, v: bool) -> Result<Vary, E> {
                ScalarVisitor.visit_bool(v).map(Vary::One)
            }
            fn visit_str<E: de::Error>(self, v: &str) -> Result<Vary, E> {
                ScalarVisitor.visit_str(v).map(Vary::One)
            }
            fn visit_unit<E: de::Error>(self) -> Result<Vary, E> {
                ScalarVisitor.visit_unit().map(Vary::One)
            }
            fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Vary, A::Error> {
                let mut out = Vec::new();
                while let Some(v) = seq.next_element::<Scalar>()? {
                    out.push(v);
                }
                if out.is_empty() {
                    return Err(de::Error::custom("the list of values is empty; give at least one"));
                }
                Ok(Vary::List(out))
            }
        }
        d.deserialize_any(V)
    }
}

/// A command's argv: a non-empty list of arguments (text, or integers taken as their digits).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Argv(pub Vec<String>);

/// How a command must be written, for messages.
const ARGV_HINT: &str =
    "write it as a list of arguments, e.g. [python3, agents/q_learning.py]; no shell runs it";

impl<'de> Deserialize<'de> for Argv {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        d.deserialize_any(ArgvVisitor)
    }
}

struct ArgvVisitor;

impl<'de> Visitor<'de> for ArgvVisitor {
    type Value = Argv;
    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str("a list of arguments, e.g. [python3, agents/q_learning.py]")
    }
    fn visit_str<E: de::Error>(self, v: &str) -> Result<Argv, E> {
        Err(E::custom(format!("the command `{v}` is one text; {ARGV_HINT}")))
    }
    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Argv, A::Error> {
        let mut out = Vec::new();
        while let Some(a) = seq.next_element::<Arg>()? {
            out.push(a.0);
        }
        match out.first() {
            None => Err(de::Error::custom(format!("the command is empty; {ARGV_HINT}"))),
            Some(p) if p.is_empty() => {
                Err(de::Error::custom("the program (the command's first argument) is empty text"))
            }
            Some(_) => Ok(Argv(out)),
        }
    }
}

/// One argument: text, or an integer taken as its digits (`[sleep, 1]`).
struct Arg(String);

impl<'de> Deserialize<'de> for Arg {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl Visitor<'_> for V {
            type Value = Arg;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("an argument (text; quote numbers with a fraction, e.g. \"0.5\")")
            }
            fn visit_str<E: de::Error>(self, v: &str) -> Result<Arg, E> {
                Ok(Arg(v.to_string()))
            }
            fn visit_i64<E: de::Error>(self, v: i64) -> Result<Arg, E> {
                Ok(Arg(v.to_string()))
            }
            fn visit_u64<E: de::Error>(self, v: u64) -> Result<Arg, E> {
                Ok(Arg(v.to_string()))
            }
        }
        d.deserialize_any(V)
    }
}

/// `inputs:`: a list of globs (one glob alone is taken as a list of one).
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct Globs(pub Vec<String>);

impl<'de> Deserialize<'de> for Globs {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = Globs;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("a list of file globs, e.g. [agents/*.py, lib/**/*.py]")
            }
            fn visit_unit<E: de::Error>(self) -> Result<Globs, E> {
                Ok(Globs(Vec::new()))
            }
            fn visit_str<E: de::Error>(self, v: &str) -> Result<Globs, E> {
                Ok(Globs(vec![v.to_string()]))
            }
            fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Globs, A::Error> {
                let mut out = Vec::new();
                while let Some(g) = seq.next_element::<String>()? {
                    out.push(g);
                }
                Ok(Globs(out))
            }
        }
        d.deserialize_any(V)
    }
}

/// A metric's type as written (`int`, `list<float>`, …).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct MetricName(pub MetricType);

impl<'de> Deserialize<'de> for MetricName {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let s = String::deserialize(d)?;
        let names: Vec<&str> = MetricType::ALL.iter().map(|t| t.name()).collect();
        MetricType::parse(s.trim()).map(MetricName).ok_or_else(|| {
            let hint = crate::declared::suggest(&s, names.iter().copied())
                .map(|n| format!("; did you mean `{n}`?"))
                .unwrap_or_default();
            de::Error::custom(format!("unknown metric type `{s}`; the types are {}{hint}", names.join(", ")))
        })
    }
}

/// A per-trial timeout: `30s`, `10m`, `2h`, or a number of seconds.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Timeout(pub Duration);

impl Timeout {
    /// Parse the written form (see [`Timeout`]).
    pub fn parse(s: &str) -> Result<Duration, String> {
        let bad = || format!("`{s}` is not a duration; write e.g. 30s, 10m, 2h or a number of seconds");
        let t = s.trim();
        let (num, unit) = match t.char_indices().last() {
            Some((i, 's')) => (&t[..i], 1.0),
            Some((i, 'm')) => (&t[..i], 60.0),
            Some((i, 'h')) => (&t[..i], 3600.0),
            _ => (t, 1.0),
        };
        let n: f64 = num.trim().parse().map_err(|_| bad())?;
        Self::seconds(n * unit).map_err(|why| format!("`{s}`: {why}"))
    }

    /// `secs` seconds, if positive and within [`MAX_TIMEOUT`].
    fn seconds(secs: f64) -> Result<Duration, String> {
        if secs.is_nan() || secs <= 0.0 {
            return Err("a timeout must be more than 0 seconds".into());
        }
        if secs > MAX_TIMEOUT.as_secs_f64() {
            return Err("a timeout must be at most 30 days (720h)".into());
        }
        Ok(Duration::from_secs_f64(secs))
    }
}

impl<'de> Deserialize<'de> for Timeout {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl Visitor<'_> for V {
            type Value = Timeout;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("a duration: 30s, 10m, 2h or a number of seconds")
            }
            fn visit_u64<E: de::Error>(self, v: u64) -> Result<Timeout, E> {
                self.visit_f64(v as f64)
            }
            fn visit_i64<E: de::Error>(self, v: i64) -> Result<Timeout, E> {
                self.visit_f64(v as f64)
            }
            fn visit_f64<E: de::Error>(self, v: f64) -> Result<Timeout, E> {
                Timeout::seconds(v).map(Timeout).map_err(E::custom)
            }
            fn visit_str<E: de::Error>(self, v: &str) -> Result<Timeout, E> {
                Timeout::parse(v).map(Timeout).map_err(E::custom)
            }
        }
        d.deserialize_any(V)
    }
}

/// One `provenance:` entry: an argv list, or `{command: [...], key: true}`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ProvenanceEntry {
    /// argv.
    pub command: Argv,
    /// Whether its output joins the key.
    pub key: bool,
}

/// The mapping form of a provenance entry.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ProvenanceMap {
    command: Argv,
    #[serde(default)]
    key: bool,
}

impl<'de> Deserialize<'de> for ProvenanceEntry {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = ProvenanceEntry;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("a command (a list of arguments) or {command: [...], key: true}")
            }
            fn visit_str<E: de::Error>(self, v: &str) -> Result<ProvenanceEntry, E> {
                ArgvVisitor.visit_str(v).map(|command| ProvenanceEntry { command, key: false })
            }
            fn visit_seq<A: SeqAccess<'de>>(self, seq: A) -> Result<ProvenanceEntry, A::Error> {
                ArgvVisitor.visit_seq(seq).map(|command| ProvenanceEntry { command, key: false })
            }
            fn visit_map<A: MapAccess<'de>>(self, map: A) -> Result<ProvenanceEntry, A::Error> {
                let m = ProvenanceMap::deserialize(de::value::MapAccessDeserializer::new(map))?;
                Ok(ProvenanceEntry { command: m.command, key: m.key })
            }
        }
        d.deserialize_any(V)
    }
}
