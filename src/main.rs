//! The `qsweep` binary: parse arguments, run the command, print the error chain, exit.

use std::process::ExitCode;

fn main() -> ExitCode {
    let cli = <qsweep::cli::Cli as clap::Parser>::parse();
    match qsweep::cli::run(cli) {
        Ok(code) => ExitCode::from(code),
        Err(err) => {
            eprintln!("error: {err}");
            for cause in err.chain().skip(1) {
                eprintln!("  caused by: {cause}");
            }
            let usage = err.chain().any(|c| c.downcast_ref::<qsweep::error::UserError>().is_some());
            ExitCode::from(if usage { qsweep::error::exit::USAGE } else { qsweep::error::exit::FAILURE })
        }
    }
}
