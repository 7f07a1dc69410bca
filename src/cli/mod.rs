//! Command-line interface: one file per subcommand, each a thin layer over the library.

mod args;
mod bench;
mod cache;
mod compare;
mod feasible;
mod gc;
mod pipeline_args;
mod program;
mod progress;
mod report;
mod run;
mod simulate;
mod slurm;
mod status;
mod supervise;
mod trial;
mod trial_args;
mod trial_config;
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
    ///
    /// The learner's and the fuzzy activation's kernels run with the vector instructions that
    /// `QSWEEP_SIMD` names: `auto` (default: AVX2 where the CPU has it), `off` (the build's
    /// baseline), `avx2` or `avx512`, capped by the CPU. The level never changes a result, only
    /// the speed; the table's last line names it.
    Bench(bench::BenchArgs),
    /// Longest survival over every deterministic policy of a small crisp table, from the start state.
    Feasible(feasible::FeasibleArgs),
    /// Roll a system forward under given action values and print the trajectory as CSV.
    Simulate(simulate::SimulateArgs),
    /// Run one trial (one configuration, one seed) and print its outcome.
    Trial(trial_args::TrialArgs),
    /// Run a pipeline's missing trials in parallel, store them in the cache, then write the report.
    ///
    /// Each thread runs crisp trials four at a time, as lanes of one loop, and so fuzzy rule bases
    /// of two variables whose prune windows hold at most 4 sets (the default width and prune;
    /// under Q(λ), tables of up to 256 values), which take a dense step; `QSWEEP_LOCKSTEP=off`
    /// runs every trial alone, `QSWEEP_DENSE=off` takes the windowed fuzzy step. Either way every
    /// trial's row is the same, only the speed differs.
    Run(run::RunArgs),
    /// Show how many of a pipeline's trials are cached and missing, without running anything.
    Status(status::StatusArgs),
    /// Write a pipeline's report (Table III, Figures 5-7, Parquet data, index.html) from the cache.
    Report(report::ReportArgs),
    /// Check every cache segment (readable, schema, keys match configurations); quarantine damage.
    Verify(verify::VerifyArgs),
    /// Compact the cache; with pipelines given, drop rows none of them references.
    Gc(gc::GcArgs),
    /// Copy trials between a cache directory and a bucket (or another directory), by key.
    ///
    /// Only the trials the destination lacks are copied, each segment in one write, so a copy
    /// interrupted at any point is simply run again. Buckets need a build with `--features s3`.
    Cache(cache::CacheCommand),
    /// Print a script that submits a pipeline to Slurm: a job array of shards, then a report job.
    Slurm(slurm::SlurmArgs),
    /// Compare two program pipelines cell by cell: did a change move the results beyond chance?
    ///
    /// A and B are program pipeline files (PATH@VARIANT for a variant's cells). Cells match on
    /// the params both declare (--map renames); each matched cell's trials in the cache are
    /// compared on one metric: B ÷ A with a 95 % interval, Welch's p, equivalence (TOST) at the
    /// margin, a verdict; then whether the share of cells with p < 0.05 is beyond the 5 % chance
    /// gives. Exits 0 when compared, 1 when the cache holds no trial of any matched cell, 2 on
    /// bad input.
    Compare(compare::CompareArgs),
    /// Run a program as qsweep's child, its process group dying with qsweep (qsweep's own).
    #[command(name = "__supervise", hide = true)]
    Supervise(supervise::SuperviseArgs),
}

/// The guide chapter of each subcommand: its long help (`--help`) ends with "Guide: CHAPTER",
/// so a reader goes from the flags to the explanation. `tests/docs` checks every chapter exists.
pub const GUIDE: &[(&str, &str)] = &[
    ("bench", "docs/speed.md"),
    ("feasible", "docs/replication.md#feasibility"),
    ("simulate", "docs/commands.md"),
    ("trial", "docs/commands.md"),
    ("run", "docs/pipelines.md"),
    ("status", "docs/commands.md"),
    ("report", "docs/reports.md"),
    ("verify", "docs/reproducibility.md"),
    ("gc", "docs/commands.md"),
    ("slurm", "docs/cluster.md"),
    ("cache", "docs/cache-in-a-bucket.md"),
    ("compare", "docs/programs.md#did-my-change-move-the-results"),
];

/// The guide's table of contents, named at the end of `qsweep --help`.
pub const GUIDE_INDEX: &str = "docs/SUMMARY.md";

/// The command-line definition, each long help ending with its guide chapter ([`GUIDE`]).
pub fn command() -> clap::Command {
    let mut cmd = <Cli as clap::CommandFactory>::command().after_long_help(format!("Guide: {GUIDE_INDEX}"));
    for (name, chapter) in GUIDE {
        cmd = cmd.mut_subcommand(name, |s| {
            let pointer = format!("Guide: {chapter}");
            // A subcommand's own examples (`after_help`) stay, with the pointer after them.
            let text = match s.get_after_help() {
                Some(h) => format!("{h}\n\n{pointer}"),
                None => pointer,
            };
            s.after_long_help(text)
        });
    }
    cmd
}

/// Parse the process's arguments against [`command`] (exits with clap's usage error on bad ones).
pub fn parse() -> Cli {
    let matches = command().get_matches();
    <Cli as clap::FromArgMatches>::from_arg_matches(&matches).unwrap_or_else(|e| e.exit())
}

/// Run a parsed command line; returns the process exit code. A pipeline that declares
/// `program:` goes to [`program`] (its commands' own file), every other to the command's file.
pub fn dispatch(cli: Cli) -> anyhow::Result<u8> {
    match cli.command {
        Command::Run(a) if program::is_program(&a.pipeline) => program::run(a),
        Command::Status(a) if program::is_program(&a.pipeline) => program::status(a),
        Command::Report(a) if program::is_program(&a.pipeline) => program::report(a),
        Command::Slurm(a) if program::is_program(&a.pipeline) => program::slurm(a),
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
        Command::Cache(a) => cache::run(a),
        Command::Compare(a) => compare::run(a),
        Command::Supervise(a) => supervise::run(a),
    }
}
