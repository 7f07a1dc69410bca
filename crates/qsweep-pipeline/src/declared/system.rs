//! One system's section of a pipeline: its settings and its experiments.

use super::experiment::ExperimentSpec;
use super::fields::at_field;
use super::settings::{valid_params, Ranges, Settings, SystemMarker};
use serde::de::{self, Deserializer};
use serde::Deserialize;

/// One system's section.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields, bound = "")]
pub struct SystemSpec<M: SystemMarker> {
    /// Physical parameters (unset ones keep the paper's values), checked while parsing.
    #[serde(default, deserialize_with = "valid_params::<M, _>")]
    pub params: M::Params,
    /// Per-variable `[lo, hi]` ranges (unset ones keep the defaults).
    #[serde(default)]
    pub ranges: Ranges<M>,
    /// Learning-goal criterion (unset: the default for the system).
    #[serde(default)]
    pub success: Option<M::Success>,
    /// Settings for all of this system's experiments.
    #[serde(default)]
    pub settings: Settings,
    /// Settings for this system's crisp experiments (Table II, "Discrete").
    #[serde(default)]
    pub crisp: Settings,
    /// Settings for this system's fuzzy experiments (Table II, "Fuzzy").
    #[serde(default)]
    pub fuzzy: Settings,
    /// Experiments (Table I rows), at least one, ids unique.
    #[serde(deserialize_with = "experiments::<M, _>")]
    pub experiments: Vec<ExperimentSpec<M>>,
}

pub(super) fn experiments<'de, M: SystemMarker, D: Deserializer<'de>>(
    d: D,
) -> Result<Vec<ExperimentSpec<M>>, D::Error> {
    let v = Vec::<ExperimentSpec<M>>::deserialize(d)?;
    if v.is_empty() {
        return Err(de::Error::custom("the list is empty; give at least one experiment"));
    }
    for (i, e) in v.iter().enumerate() {
        if v[..i].iter().any(|o| o.id == e.id) {
            return Err(at_field(
                &[&i.to_string(), "id"],
                format!("id {} is used twice; ids must be unique per system", e.id),
            ));
        }
    }
    Ok(v)
}
