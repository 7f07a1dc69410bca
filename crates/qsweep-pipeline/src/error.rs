//! Error kinds that decide the exit code: bad user input exits 2, everything else 1.

use thiserror::Error;

/// Bad input from the user (arguments, pipeline files): exit code 2.
#[derive(Debug, Error)]
#[error("{0}")]
pub struct UserError(pub String);

impl UserError {
    /// A user error with this message.
    pub fn new(msg: impl Into<String>) -> Self {
        Self(msg.into())
    }
}

/// Shorthand: `Err(user_error(...))?`.
pub fn user_error(msg: impl Into<String>) -> anyhow::Error {
    UserError::new(msg).into()
}

/// A command stopped by Ctrl-C or SIGTERM before it was done, saying what is left: exit 130.
#[derive(Debug, Error)]
#[error("interrupted (Ctrl-C or SIGTERM): {0}")]
pub struct Interrupted(pub String);

/// Exit codes, as documented in docs/commands.md.
pub mod exit {
    /// Success.
    pub const OK: u8 = 0;
    /// A runtime failure (I/O, diverged trials, damaged cache found by `verify`).
    pub const FAILURE: u8 = 1;
    /// Bad input: arguments or pipeline file.
    pub const USAGE: u8 = 2;
    /// Interrupted by Ctrl-C or SIGTERM (a run after flushing finished trials, a report before
    /// its next file).
    pub const INTERRUPTED: u8 = 130;
}
