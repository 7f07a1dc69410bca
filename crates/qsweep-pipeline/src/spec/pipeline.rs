//! A whole pipeline file: name, seeds, systems, race, fresh seeds, variants, exploratory block.

use super::explore::Exploratory;
use super::fields::safe_folder_name;
use super::race::RaceSpec;
use super::settings::{BallBeamM, CartPoleM, MountainCarM, Settings};
use super::system::SystemSpec;
use super::values::Seeds;
use super::variants::VariantSpec;
use serde::de::{self, Deserializer};
use serde::Deserialize;

/// Top-level fields that only change how the report counts, never a trial: a variant whose `set`
/// touches only these plans the same trials as the pipeline as written.
pub const REPORT_SETTINGS: [&str; 1] = ["counting"];

/// Whether a variant's `set` entry (`PATH=VALUE`) is one of the [`REPORT_SETTINGS`].
pub fn is_report_setting(entry: &str) -> bool {
    entry.split_once('=').is_some_and(|(path, _)| REPORT_SETTINGS.contains(&path))
}

/// A whole pipeline file.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PipelineSpec {
    /// Pipeline name; reports go to `reports/<name>/`.
    #[serde(deserialize_with = "safe_name")]
    pub name: String,
    /// Free text shown in reports.
    #[serde(default)]
    pub description: Option<String>,
    /// Seeds per cell.
    pub seeds: Seeds,
    /// Race seeds into the cells that can still be the best (every experiment; see [`race`]).
    #[serde(default)]
    pub race: Option<RaceSpec>,
    /// Re-estimate every heatmap's best cell on fresh seeds (see [`super::fresh`]).
    #[serde(default)]
    pub fresh: Option<super::fresh::FreshSpec>,
    /// Where the experiments' `reference:` values come from (shown in reports).
    #[serde(default)]
    pub reference_source: Option<String>,
    /// How a trial's outcome counts in Table III: `episodes` (the paper's text, default) or the
    /// exploratory `failures` (`episodes_to_goal − 1`). A report setting: no trial key depends on it.
    #[serde(default)]
    pub counting: qsweep_engine::Counting,
    /// Settings for every system and experiment.
    #[serde(default)]
    pub defaults: Settings,
    /// The systems and their experiments.
    pub systems: Systems,
    /// Alternative readings or settings of the whole pipeline (see [`variants`]).
    #[serde(default, deserialize_with = "opt_variants")]
    pub variants: Option<Vec<VariantSpec>>,
    /// Variants generated as a product of value lists (see [`grid`]).
    #[serde(default)]
    pub variant_grid: Option<super::grid::VariantGrid>,
    /// An exploratory search: the Table III rows that choose the best reading (see [`explore`]).
    #[serde(default)]
    pub exploratory: Option<Exploratory>,
}

pub(super) fn opt_variants<'de, D: Deserializer<'de>>(d: D) -> Result<Option<Vec<VariantSpec>>, D::Error> {
    super::variants::variants(d).map(Some)
}

/// The systems a pipeline covers; at least one.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Systems {
    /// Ball-Beam.
    #[serde(rename = "ball-beam", default)]
    pub ball_beam: Option<SystemSpec<BallBeamM>>,
    /// Cart-Pole.
    #[serde(rename = "cart-pole", default)]
    pub cart_pole: Option<SystemSpec<CartPoleM>>,
    /// Mountain Car.
    #[serde(rename = "mountain-car", default)]
    pub mountain_car: Option<SystemSpec<MountainCarM>>,
}

pub(super) fn safe_name<'de, D: Deserializer<'de>>(d: D) -> Result<String, D::Error> {
    let s = String::deserialize(d)?;
    safe_folder_name(&s).map_err(|why| de::Error::custom(format!("name `{s}` is not allowed; {why}")))?;
    Ok(s)
}
