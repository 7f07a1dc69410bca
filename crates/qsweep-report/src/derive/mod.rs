//! The report's numbers for any pipeline: what a plan's trials say per cell (its statistics, the
//! best cells, a cell's estimate on fresh seeds: [`report_data`]; a program pipeline's cells:
//! [`program`]), the cell tables as
//! format-neutral tables ([`table`]) and the rank statistics of the raced heatmaps' labels
//! ([`rank`]). Expensive statistics come through the memo ([`crate::memo::stats`]); nothing here
//! writes a file, knows a file format, or knows the paper (that is [`crate::replication`]).

pub mod program;
pub mod rank;
pub mod report_data;
pub mod table;

#[cfg(test)]
mod fresh_tests;
