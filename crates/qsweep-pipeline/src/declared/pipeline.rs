//! A whole pipeline file: name, seeds, systems, race, fresh seeds, variants, exploratory block.

use super::explore::Exploratory;
use super::fields::safe_folder_name;
use super::race::RaceSpec;
use super::settings::{BallBeamM, CartPoleM, MountainCarM, Settings, SystemMarker};
use super::system::SystemSpec;
use super::values::Seeds;
use super::variants::VariantSpec;
use qsweep_engine::env::SystemKind;
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
    /// Variants: the whole pipeline with some settings changed (see [`variants`]).
    #[serde(default, deserialize_with = "opt_variants")]
    pub variants: Option<Vec<VariantSpec>>,
    /// Variants generated as a product of value lists (see [`grid`]).
    #[serde(default)]
    pub variant_grid: Option<super::grid::VariantGrid>,
    /// An exploratory search: the Table III rows that choose the best variant (see [`explore`]).
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

/// Runs `$body` once for each system a [`Systems`] declares, in the pipeline's order (Ball-Beam,
/// Cart-Pole, Mountain Car), with `$s` bound to its `&SystemSpec<M>`. Each system has its own
/// settings type, so the body is expanded once per system instead of called through a common
/// type; generic helpers (`fn f<M: SystemMarker>(s: &SystemSpec<M>)`) take it from there. With
/// [`with_system`], the one place that names the systems' fields: the destructuring is
/// exhaustive, so a field added to [`Systems`] and not here does not compile, and no system is
/// silently left out anywhere else.
macro_rules! each_system {
    ($systems:expr, |$s:ident| $body:expr) => {{
        let $crate::declared::pipeline::Systems { ball_beam, cart_pole, mountain_car } = $systems;
        if let Some($s) = ball_beam.as_ref() {
            $body;
        }
        if let Some($s) = cart_pole.as_ref() {
            $body;
        }
        if let Some($s) = mountain_car.as_ref() {
            $body;
        }
    }};
}
pub(crate) use each_system;

/// `$body` for the section of system `$kind` (with `$s` bound to its `&SystemSpec<M>`), `None`
/// when the pipeline does not declare it. Exhaustive over [`Systems`]' fields and over
/// `SystemKind` (see [`each_system`]).
macro_rules! with_system {
    ($systems:expr, $kind:expr, |$s:ident| $body:expr) => {{
        let $crate::declared::pipeline::Systems { ball_beam, cart_pole, mountain_car } = $systems;
        match $kind {
            qsweep_engine::env::SystemKind::BallBeam => ball_beam.as_ref().map(|$s| $body),
            qsweep_engine::env::SystemKind::CartPole => cart_pole.as_ref().map(|$s| $body),
            qsweep_engine::env::SystemKind::MountainCar => mountain_car.as_ref().map(|$s| $body),
        }
    }};
}
pub(crate) use with_system;

impl Systems {
    /// The systems declared, in the pipeline's order (Ball-Beam, Cart-Pole, Mountain Car).
    pub fn kinds(&self) -> Vec<SystemKind> {
        let mut out = Vec::new();
        each_system!(self, |s| out.push(system_of(s)));
        out
    }
}

/// The system a section is for.
fn system_of<M: SystemMarker>(_: &SystemSpec<M>) -> SystemKind {
    M::SYSTEM
}

pub(super) fn safe_name<'de, D: Deserializer<'de>>(d: D) -> Result<String, D::Error> {
    let s = String::deserialize(d)?;
    safe_folder_name(&s).map_err(|why| de::Error::custom(format!("name `{s}` is not allowed; {why}")))?;
    Ok(s)
}
