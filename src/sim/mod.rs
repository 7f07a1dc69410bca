//! The simulation core (Section III of the paper): systems, representations, the learner and the
//! trial loop. Pure and deterministic; knows nothing of pipelines or caches.

pub mod actions;
pub mod config;
pub mod env;
pub mod feasible;
pub mod learner;
pub mod repr;
pub mod rng;
pub mod rules;
pub mod trial;

pub use config::{Algorithm, TrialConfig};
pub use trial::{run_trial, Outcome, StopReason};

#[cfg(test)]
mod pinned_tests;
#[cfg(test)]
mod reference_tests;
#[cfg(test)]
mod settings_tests;
