//! qsweep: declarative, cached, deterministic sweeps of tabular and fuzzy Q-learning, reproducing
//! "Performance analysis of tabular and Fuzzy Q-learning under varying state and action space
//! resolution".
//!
//! This crate is the command line ([`cli`]) and its stable machine-readable outputs
//! ([`json`]); the work is done by three library crates, each built only on those below it:
//! `qsweep-engine` (one trial), `qsweep-pipeline` (specs, plans, the cache, racing, execution,
//! statistics) and `qsweep-report` (derived numbers, then tables, figures and pages).

#![allow(clippy::disallowed_methods)]

pub mod cli;
pub mod json;
