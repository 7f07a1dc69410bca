//! Command-line interface: one file per subcommand, each a thin layer over the library.

mod args;
mod bench;
mod feasible;
mod gc;
mod pipeline_args;
mod progress;
mod report;
mod run;
mod simulate;
mod slurm;
mod status;
mod trial;
mod verify;

use clap::{Parser, Subcommand};

/// Declarative, cached, deterministic sweeps of tabular and fuzzy Q-learning.
#[derive(Debug, Parser)]
#[command(name = "qsweep", version, about, long_about = None)]
pub struct Cli {
    /// The command to run.
    #[command(subcommand)]
    pub command: Command,
}

/// The subcommands.
#[derive(Debug, Subcommand)]
pub enum Command {
    /// Measure the engine's steps per second on the standard configurations.
    Bench(bench::BenchArgs),
    /// Longest survival over every deterministic policy of a small crisp table, from the start state.
    Feasible(feasible::FeasibleArgs),
    /// Roll a system forward under given action values and print the trajectory as CSV.
    Simulate(simulate::SimulateArgs),
    /// Run one trial (one configuration, one seed) and print its outcome.
    Trial(trial::TrialArgs),
    /// Run a pipeline's missing trials in parallel, store them in the cache, then write the report.
    Run(run::RunArgs),
    /// Show how many of a pipeline's trials are cached and missing, without running anything.
    Status(status::StatusArgs),
    /// Write a pipeline's report (Table III, Figures 5-7, Parquet data, index.html) from the cache.
    Report(report::ReportArgs),
    /// Check every cache segment (readable, schema, keys match configurations); quarantine damage.
    Verify(verify::VerifyArgs),
    /// Compact the cache; with pipelines given, drop rows none of them references.
    Gc(gc::GcArgs),
    /// Print a script that submits a pipeline to Slurm: a job array of shards, then a report job.
    Slurm(slurm::SlurmArgs),
}

/// Run a parsed command line; returns the process exit code.
pub fn dispatch(cli: Cli) -> anyhow::Result<u8> {
    match cli.command {
        Command::Bench(a) => bench::run(a),
        Command::Feasible(a) => feasible::run(a),
        Command::Simulate(a) => simulate::run(a),
        Command::Trial(a) => trial::run(a),
        Command::Run(a) => run::run(a),
        Command::Status(a) => status::run(a),
        Command::Report(a) => report::run(a),
        Command::Verify(a) => verify::run(a),
        Command::Gc(a) => gc::run(a),
        Command::Slurm(a) => slurm::run(a),
    }
}
