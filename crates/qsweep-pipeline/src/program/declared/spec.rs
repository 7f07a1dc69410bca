//! A program pipeline file as written: its sections as serde types that check each field's
//! shape while it is read (so a wrong shape is an error at that field's path, which the loader
//! turns into its line and column), the values inside them in the sibling `values`. What the
//! fields mean together (names known, values of their param's type) is checked by `check`.

use super::values::{Argv, Globs, MetricName, ProvenanceEntry, Scalar, Timeout, Vary};
use crate::declared::{FreshSpec, RaceSpec, Seeds};
use serde::de::{self, Deserializer, MapAccess, Visitor};
use serde::Deserialize;
use std::fmt;

/// The whole file.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ProgramFile {
    /// Pipeline name (`reports/<name>/`).
    #[serde(deserialize_with = "safe_name")]
    pub name: String,
    /// Free text shown in reports.
    #[serde(default)]
    pub description: Option<String>,
    /// Seeds per cell: a count or a list.
    pub seeds: Seeds,
    /// The program.
    pub program: ProgramSection,
    /// Every param with its default, in file order.
    #[serde(default)]
    pub params: Named<Scalar>,
    /// The experiments (none: one cell of the defaults).
    #[serde(default)]
    pub experiments: Option<Vec<ExperimentEntry>>,
    /// The variants.
    #[serde(default)]
    pub variants: Option<Vec<VariantEntry>>,
    /// Race seeds into the cells that can still be their experiment's best (every experiment).
    #[serde(default)]
    pub race: Option<RaceSpec>,
    /// Each experiment's best cell again, on seeds that took no part in choosing it.
    #[serde(default)]
    pub fresh: Option<FreshSpec>,
}

/// `program:`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ProgramSection {
    /// argv.
    pub command: Argv,
    /// Globs of the files whose contents join every key.
    #[serde(default)]
    pub inputs: Globs,
    /// `process` or `worker`.
    #[serde(default)]
    pub protocol: ProtocolName,
    /// Per-trial timeout (default 1 h).
    #[serde(default)]
    pub timeout: Option<Timeout>,
    /// Metric name → type, in file order.
    pub metrics: Named<MetricName>,
    /// The objective.
    #[serde(default)]
    pub objective: Option<ObjectiveEntry>,
    /// Provenance commands.
    #[serde(default)]
    pub provenance: Vec<ProvenanceEntry>,
}

/// `protocol:` as written.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ProtocolName {
    /// One process per trial.
    #[default]
    Process,
    /// One process per worker slot.
    Worker,
}

/// `goal:` as written.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum GoalName {
    /// Smaller is better.
    Minimize,
    /// Larger is better.
    Maximize,
}

/// `objective:` as written.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ObjectiveEntry {
    /// A declared int or float metric.
    pub metric: String,
    /// Its goal.
    pub goal: GoalName,
}

/// One entry of `experiments:`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ExperimentEntry {
    /// Identifier (a number or a short name).
    #[serde(deserialize_with = "id_string")]
    pub id: String,
    /// Title shown in reports.
    #[serde(default)]
    pub title: Option<String>,
    /// Param → values, the grid's axes in file order.
    #[serde(default)]
    pub vary: Named<Vary>,
    /// Param → value for every cell of this experiment.
    #[serde(default)]
    pub fixed: Named<Scalar>,
    /// This experiment's race (instead of the pipeline-wide one).
    #[serde(default)]
    pub race: Option<RaceSpec>,
}

/// One entry of `variants:`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct VariantEntry {
    /// Identifier.
    #[serde(deserialize_with = "id_string")]
    pub id: String,
    /// Title shown in reports.
    #[serde(default)]
    pub title: Option<String>,
    /// `params.NAME` → value (checked against the params by `check`).
    #[serde(default)]
    pub set: Named<serde_yaml::Value>,
}

/// A mapping read in file order, every entry kept (a key given twice is refused by `check`,
/// which can point at its second use).
#[derive(Debug, Clone, PartialEq)]
pub struct Named<V>(pub Vec<(String, V)>);

impl<V> Default for Named<V> {
    fn default() -> Self {
        Self(Vec::new())
    }
}

impl<'de, V: Deserialize<'de>> Deserialize<'de> for Named<V> {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct N<V>(std::marker::PhantomData<V>);
        impl<'de, V: Deserialize<'de>> Visitor<'de> for N<V> {
            type Value = Named<V>;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("a mapping of names to values")
            }
            fn visit_unit<E: de::Error>(self) -> Result<Named<V>, E> {
                Ok(Named(Vec::new()))
            }
            fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<Named<V>, A::Error> {
                let mut out = Vec::new();
                while let Some(k) = map.next_key::<String>()? {
                    let v = map.next_value::<V>()?;
                    out.push((k, v));
                }
                Ok(Named(out))
            }
        }
        d.deserialize_any(N(std::marker::PhantomData))
    }
}

/// The pipeline's name, safe as a folder name.
fn safe_name<'de, D: Deserializer<'de>>(d: D) -> Result<String, D::Error> {
    let s = String::deserialize(d)?;
    crate::declared::safe_folder_name(&s)
        .map_err(|why| de::Error::custom(format!("name `{s}` is not allowed; {why}")))?;
    Ok(s)
}

/// An experiment's or variant's id: text, or a number taken as its digits (`id: 1`).
fn id_string<'de, D: Deserializer<'de>>(d: D) -> Result<String, D::Error> {
    struct V;
    impl Visitor<'_> for V {
        type Value = String;
        fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
            f.write_str("an id (a number or a short name)")
        }
        fn visit_u64<E: de::Error>(self, v: u64) -> Result<String, E> {
            Ok(v.to_string())
        }
        fn visit_i64<E: de::Error>(self, v: i64) -> Result<String, E> {
            Ok(v.to_string())
        }
        fn visit_str<E: de::Error>(self, v: &str) -> Result<String, E> {
            crate::declared::safe_folder_name(v)
                .map_err(|why| E::custom(format!("id `{v}` is not allowed; {why}")))?;
            Ok(v.to_string())
        }
    }
    d.deserialize_any(V)
}
