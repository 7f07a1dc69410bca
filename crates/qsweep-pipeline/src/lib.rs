//! qsweep's pipeline: the YAML pipeline as written ([`declared`]), the resolved plan of every cell and
//! trial ([`plan`]), the content-addressed trial store ([`cache`]), which cells get more seeds
//! ([`fresh`], [`race`]), running the missing trials in parallel ([`exec`], [`run`]), a
//! pipeline's cache status ([`status`]), Slurm arrays ([`slurm`]), `qsweep bench` ([`bench`]),
//! and the statistics that race and report share ([`analysis`]).
//!
//! Built on [`qsweep_engine`], which runs one trial; the report ([`qsweep-report`]) is built on
//! this crate, never the other way round.

// clippy.toml lists the platform's transcendental functions; only the trial path (the engine,
// which denies the lint) must do without them.
#![allow(clippy::disallowed_methods)]

pub mod analysis;
pub mod atomic;
pub mod bench;
pub mod cache;
pub mod declared;
pub mod error;
pub mod exec;
pub mod fresh;
pub mod parquet_io;
pub mod plan;
pub mod program;
pub mod race;
pub mod run;
pub mod slurm;
pub mod status;
#[cfg(any(test, feature = "test-support"))]
pub mod testing;

#[cfg(test)]
mod settings_tests;
#[cfg(test)]
mod variants_tests;
