//! `qsweep __supervise -- PROGRAM [ARGS…]` (hidden): the parent qsweep gives every program of a
//! program pipeline, so that the program's whole process group dies with qsweep
//! (`qsweep_pipeline::program::supervise`). qsweep runs it; people do not.

use clap::Args;
use std::ffi::OsString;

/// Arguments of `qsweep __supervise`.
#[derive(Debug, Args)]
pub struct SuperviseArgs {
    /// The program and its arguments (after `--`).
    #[arg(required = true, trailing_var_arg = true, allow_hyphen_values = true)]
    pub argv: Vec<OsString>,
}

/// Run the program under supervision and exit as it did (never returns).
pub fn run(args: SuperviseArgs) -> anyhow::Result<u8> {
    qsweep_pipeline::program::supervise::supervise(&args.argv)
}
