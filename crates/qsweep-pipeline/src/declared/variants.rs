//! Variants: the pipeline with some settings changed, several declared side by side.
//!
//! ```yaml
//! variants:
//!   - id: as-written                 # no `set`: the pipeline as written
//!     title: The paper's text
//!   - id: gym-time-limits
//!     title: Episodes cut at Gymnasium's registered TimeLimits
//!     set: { systems.cart-pole.success.steps: 200 }
//! ```
//!
//! Every variant is the whole pipeline with its `set` applied: each entry is a dotted path and a
//! value, exactly like `--set PATH=VALUE` ([`Override`]), applied to the parsed document before it
//! is typed, so a variant is checked by the same parser as the file itself. Command-line `--set`
//! overrides are applied after a variant's own, so they win. Trials that two variants share have
//! the same key and run once.

use super::fields::safe_folder_name;
use serde::de::{self, Deserializer};
use serde::Deserialize;

/// One entry of `variants:`, as written.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct VariantSpec {
    /// Identifier; names the variant's report folder `reports/<name>/<id>/`.
    #[serde(deserialize_with = "variant_id")]
    pub id: String,
    /// Short title shown in reports.
    #[serde(default)]
    pub title: Option<String>,
    /// Free text: what this variant stands for and its source.
    #[serde(default)]
    pub description: Option<String>,
    /// Dotted path → value, applied to the pipeline (empty: the pipeline as written).
    #[serde(default)]
    pub set: serde_yaml::Mapping,
    /// A variant suggested by the data rather than declared before it ran: labelled exploratory,
    /// ranked after the declared variants, and its folder written only on demand (`--variant ID`).
    #[serde(default)]
    pub exploratory: bool,
}

fn variant_id<'de, D: Deserializer<'de>>(d: D) -> Result<String, D::Error> {
    let s = String::deserialize(d)?;
    safe_folder_name(&s)
        .map_err(|why| de::Error::custom(format!("variant id `{s}` is not allowed: {why}")))?;
    if s == "figures" {
        return Err(de::Error::custom(
            "variant id `figures` is not allowed: the comparison report keeps its figures there",
        ));
    }
    Ok(s)
}

/// Check the list: ids unique.
pub(super) fn variants<'de, D: Deserializer<'de>>(d: D) -> Result<Vec<VariantSpec>, D::Error> {
    let v = Vec::<VariantSpec>::deserialize(d)?;
    if v.is_empty() {
        return Err(de::Error::custom(
            "variants: the list is empty; remove `variants:` or give at least one",
        ));
    }
    for (i, e) in v.iter().enumerate() {
        if v[..i].iter().any(|o| o.id == e.id) {
            return Err(de::Error::custom(format!(
                "variants[{i}]: id `{}` is used twice; variant ids must be unique",
                e.id
            )));
        }
    }
    Ok(v)
}
