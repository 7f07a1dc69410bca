//! The report's numbers: what a plan's trials say (per-cell statistics, the best cells, Table III
//! as a format-neutral table) and how each variant compares with the paper (fit, verdicts,
//! selection, consistency, conclusions). Expensive statistics come through the memo
//! ([`crate::memo::stats`]); nothing here writes a file or knows a file format.

pub mod compare;
pub mod judgement;
pub mod model;
pub mod table;

#[cfg(test)]
mod fresh_tests;
