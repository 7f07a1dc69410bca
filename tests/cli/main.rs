//! End-to-end tests of the `qsweep` binary (one test binary; helpers in `helpers.rs`).

mod bad_pipelines;
mod bench;
mod cache;
mod helpers;
mod json_formats;
mod mutations;
mod pipeline;
mod report_files;
mod schemas;
mod simulate;
mod slurm;
mod trial;
mod variants;
