//! End-to-end tests of the `qsweep` binary (one test binary; helpers in `helpers.rs`).

mod bad_pipelines;
mod bench;
mod cache;
mod error_locations;
mod exit_codes;
mod explore;
mod feasible;
mod fresh;
mod helpers;
mod json_formats;
mod layering;
mod library;
mod memo;
mod mutations;
mod no_overwrite;
mod pipeline;
mod race;
mod readings;
mod report_files;
mod report_guard;
mod schemas;
mod simulate;
mod slurm;
mod trial;
mod variants;
