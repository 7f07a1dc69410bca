//! qsweep: declarative, cached, deterministic sweeps of tabular and fuzzy Q-learning, reproducing
//! "Performance analysis of tabular and Fuzzy Q-learning under varying state and action space
//! resolution".

// clippy.toml lists the platform's transcendental functions; only the trial path (src/sim, which
// denies the lint) must do without them.
#![allow(clippy::disallowed_methods)]

pub mod analysis;
pub mod atomic;
pub mod bench;
pub mod cache;
pub mod fresh;
pub mod parquet_io;
pub mod pipeline;
pub mod plan;
pub mod race;
pub mod report;
pub mod sim;
pub mod slurm;
pub mod spec;
pub mod status;

pub mod cli;
pub mod error;
pub mod exec;
pub mod formats;
