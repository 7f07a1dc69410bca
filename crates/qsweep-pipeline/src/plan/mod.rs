//! The resolved plan: a pipeline expanded into experiments → cells (one fully resolved
//! configuration each) × seeds → trials with their cache keys. Every default is filled in here,
//! before hashing, so a changed default changes exactly the keys it affects. What a plan is:
//! [`resolved`]; how a pipeline becomes one: [`variants`] (which variants, within the
//! confirmation [`limits`]), each expanded by [`resolve`]; how its trials are keyed: [`keys`].

mod keys;
mod limits;
mod one_cell;
mod resolve;
mod resolved;
mod variants;

pub use limits::DEFAULT_MAX_TRIALS;
pub use one_cell::{one_cell, CellRequest};
pub use resolved::{Cell, Experiment, Plan, PlannedTrial, ReadOutcomes, TrialBrief, Variant};
pub use variants::{plan, plan_variants};
