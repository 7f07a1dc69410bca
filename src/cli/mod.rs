//! Command-line interface: one file per subcommand, each a thin layer over the library.

mod args;
mod bench;
mod simulate;
mod trial;

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
    /// Roll a system forward under given action values and print the trajectory as CSV.
    Simulate(simulate::SimulateArgs),
    /// Run one trial (one configuration, one seed) and print its outcome.
    Trial(trial::TrialArgs),
}

/// Run a parsed command line; returns the process exit code.
pub fn run(cli: Cli) -> anyhow::Result<u8> {
    match cli.command {
        Command::Bench(a) => bench::run(a),
        Command::Simulate(a) => simulate::run(a),
        Command::Trial(a) => trial::run(a),
    }
}
