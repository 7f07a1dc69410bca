//! The `qsweep` binary: parse arguments, run the command, print the error chain, exit.

use std::process::ExitCode;

fn main() -> ExitCode {
    #[cfg(unix)]
    // SAFETY: sets a signal disposition before any other thread exists.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
    // A program's supervisor starts once per trial: straight to it, without building the whole
    // command line parser (`qsweep __supervise -- PROGRAM [ARGS…]`, qsweep's own use only).
    let mut args = std::env::args_os().skip(1);
    if args.next().is_some_and(|a| a == "__supervise") {
        let mut argv: Vec<std::ffi::OsString> = args.collect();
        if argv.first().is_some_and(|a| a == "--") {
            argv.remove(0);
        }
        qsweep_pipeline::program::supervise::supervise(&argv);
    }
    let cli = qsweep::cli::parse();
    match qsweep::cli::dispatch(cli) {
        Ok(code) => ExitCode::from(code),
        Err(err) => {
            // Not an error: what was asked stopped early, and says what is left.
            if let Some(stop) =
                err.chain().find_map(|c| c.downcast_ref::<qsweep_pipeline::error::Interrupted>())
            {
                eprintln!("{stop}");
                return ExitCode::from(qsweep_pipeline::error::exit::INTERRUPTED);
            }
            eprintln!("error: {err}");
            for cause in err.chain().skip(1) {
                eprintln!("  caused by: {cause}");
            }
            let usage = err.chain().any(|c| c.downcast_ref::<qsweep_pipeline::error::UserError>().is_some());
            ExitCode::from(if usage {
                qsweep_pipeline::error::exit::USAGE
            } else {
                qsweep_pipeline::error::exit::FAILURE
            })
        }
    }
}
