//! The simulation core (Section III of the paper): systems, representations, the learner and the
//! trial loop. Pure and deterministic; knows nothing of pipelines or caches.
//!
//! Deterministic on every machine, too: nothing here may call the platform's `sin`, `cos`, `exp`,
//! … or `mul_add` (clippy's `disallowed-methods`, denied below; `math` has the engine's own).
//! The random stream is ChaCha (`rng`), integer arithmetic, the same everywhere whichever SIMD
//! path `rand_chacha` picks at run time.

#![deny(clippy::disallowed_methods)]
// The README's example runs as a doctest.
#![doc = include_str!("../README.md")]

pub mod actions;
pub mod config;
pub mod dense_path;
pub mod env;
pub mod feasible;
pub mod lanes;
pub mod learner;
pub mod math;
pub mod repr;
pub mod rng;
pub mod rules;
pub mod simd;
pub mod solved;
pub mod trial;

pub use config::{Algorithm, TrialConfig};
pub use trial::{run_trial, run_trial_at, Counting, Outcome, StopReason};

#[cfg(test)]
mod dense_tests;
#[cfg(test)]
mod pinned_tests;
#[cfg(test)]
mod reference_tests;
