//! Pipeline files: the raw, typed form of a YAML pipeline (`pipelines/*.yaml`), parsed with
//! serde_yaml. Unknown keys are rejected, and every value is range-checked while parsing so errors
//! carry the file, line and column. Nothing here resolves defaults: that is `plan`'s job.
//!
//! ```yaml
//! name: quick                     # report folder name: reports/<name>/
//! seeds: 2                        # a count (seeds 0..n-1) or a list [0, 7, 9]
//! defaults: { max_episodes: 500 } # settings for every system (see Settings)
//! systems:
//!   cart-pole:
//!     params: { gravity: 9.81 }   # physical parameters (defaults: the paper's)
//!     ranges: { x_dot: [-2, 2] }  # bin range / first and last fuzzy centre per variable
//!     success: { steps: 100000 }  # survival: steps; mountain-car: {within, streak, max_episode_steps};
//!                                 # either, with {window, mean_length}: Gym's solved rule
//!     crisp: { epsilon: 0.01 }    # settings for crisp experiments of this system (Table II)
//!     fuzzy: { width: 0.4247 }    # settings for fuzzy experiments of this system
//!     experiments:
//!       - id: 1
//!         repr: crisp
//!         algorithms: [q0, q-lambda]
//!         vary: { x == theta: 2..10, x_dot == theta_dot: 2..10 }   # Table I: v(x == θ), v(ẋ == θ̇)
//!         fixed: { actions: 2 }                                     # Table I: c(Actions)
//!         race: { confidence: 0.95, batch: 5, max_seeds: 40 }       # optional (or pipeline-wide)
//! fresh: { first_seed: 1000, seeds: 20 }  # optional: best cells re-estimated on fresh seeds
//! ```

// No file imports one that imports it back (tests/cli/layering.rs checks it); rustfmt keeps
// the list in alphabetical order.
mod check;
mod experiment;
pub mod explore;
mod fields;
mod fresh;
pub mod grid;
mod load;
pub mod locate;
mod overrides;
pub(crate) mod pipeline;
mod race;
mod settings;
mod system;
mod values;
mod variant_load;
mod variants;

pub use check::{check_fresh_seeds, check_one as check_race, Problem};
pub use experiment::{format_value, target_name, Axis, ExperimentSpec, Reference, Target, AXIS_SETTINGS};
pub use fields::{safe_folder_name, suggest, variable_index};
pub use fresh::FreshSpec;
pub use load::{load, load_str, load_value, LoadedSpec};
// The program pipeline's loader (`crate::program::declared`) reads its file the same way.
pub(crate) use load::{located, one_kind, read_text, typed, with_sets, Failure};
pub use locate::locate;
pub use overrides::Override;
pub(crate) use pipeline::each_system;
pub use pipeline::{is_report_setting, PipelineSpec, Systems};
pub use race::RaceSpec;
pub use settings::{
    setting_level, BalanceSpec, BallBeamM, CartPoleM, MountainCarM, Ranges, ReachSpec, Settings, SystemMarker,
};
pub use system::SystemSpec;
pub use values::{
    AtLeastOne, AxisValues, Bounds, Confidence, Finite, Positive, Seeds, SubUnit, Unit, Values,
};
pub use variant_load::LoadedVariant;
pub use variants::VariantSpec;
