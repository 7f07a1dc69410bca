//! A program pipeline file: a pipeline that declares `program:` (a researcher's own command)
//! instead of the engine's `systems:`, read, typed and checked. Every error is
//! `FILE:LINE:COL: PATH: MESSAGE` with the fix (exit 2), found before anything runs; the engine
//! loader's machinery (positions by path, `--set` overrides applied to the document before it is
//! typed) is shared, so both kinds of pipeline read and fail alike.
//!
//! ```yaml
//! name: my-sweep
//! seeds: 5                                    # a count (0..n-1) or a list
//! program:
//!   command: [python3, agents/q_learning.py]  # argv, no shell
//!   inputs: [agents/*.py]                     # globs: each file's contents join every key
//!   protocol: process                         # or worker
//!   timeout: 10m                              # 30s, 10m, 2h or seconds (default 1h)
//!   metrics: { episodes: int, solved: bool, returns: list<float> }
//!   objective: { metric: episodes, goal: minimize }
//!   provenance: [[python3, --version], { command: [pip, freeze], key: true }]
//! params: { env: CartPole-v1, alpha: 0.1, bins: 6 }   # each param's default fixes its type
//! experiments:                                # none: one cell of the defaults, id `default`
//!   - { id: bins-alpha, vary: { bins: 2..10, alpha: [0.05, 0.1] }, fixed: { env: Acrobot-v1 } }
//! variants:
//!   - { id: mountain-car, set: { params.env: MountainCar-v0 } }   # params.* only
//! ```
//!
//! The shape of each section and value is checked while it is read ([`spec`], [`values`]), the
//! rules between fields after ([`check`]), giving a [`ProgramDecl`] ([`checked`]).

mod check;
mod checked;
mod spec;
mod values;

#[cfg(test)]
pub(crate) mod tests;

pub use checked::{ExperimentDecl, ProgramDecl, VariantDecl, DEFAULT_EXPERIMENT, DEFAULT_TIMEOUT};
pub use values::MAX_TIMEOUT;

use crate::declared::{located, one_kind, read_text, typed, with_sets, Failure, Override, Problem};
use crate::error::user_error;
use spec::ProgramFile;
use std::path::{Path, PathBuf};

/// Whether pipeline text declares a program (its top level has `program:`): such a file is
/// loaded by [`load`], not by the engine's `crate::declared::load`.
pub fn is_program(text: &str) -> bool {
    crate::declared::locate(text, &["program".to_string()]).is_some()
}

/// A loaded program pipeline: the checked pipeline, the file it came from (its text, to place
/// errors found later, such as a glob that matches nothing) and the `--set` overrides applied.
#[derive(Debug, Clone)]
pub struct LoadedProgram {
    /// The checked pipeline.
    pub decl: ProgramDecl,
    /// The file.
    pub path: PathBuf,
    /// The file's text.
    pub text: String,
    /// The command line's `--set` overrides, applied.
    pub overrides: Vec<Override>,
}

impl LoadedProgram {
    /// The file as messages name it.
    pub fn origin(&self) -> String {
        self.path.display().to_string()
    }

    /// The user error (exit 2) about the field at `path` (keys, and list indices as numbers):
    /// `FILE:LINE:COL: PATH: MESSAGE`, or naming the `--set` that gave the field its value.
    pub fn error_at(&self, path: &[&str], message: &str) -> anyhow::Error {
        let p = Problem { path: path.iter().map(|s| s.to_string()).collect(), message: message.to_string() };
        problem_error(&self.text, &self.origin(), &self.overrides, p)
    }
}

/// Read, type and check a program pipeline file, with `--set` overrides applied.
pub fn load(path: &Path, overrides: &[Override]) -> anyhow::Result<LoadedProgram> {
    let text = read_text(path)?;
    let decl = load_str(&text, &path.display().to_string(), overrides)?;
    Ok(LoadedProgram { decl, path: path.to_path_buf(), text, overrides: overrides.to_vec() })
}

/// Type and check program pipeline text; `origin` names it in messages.
pub fn load_str(text: &str, origin: &str, overrides: &[Override]) -> anyhow::Result<ProgramDecl> {
    if text.lines().all(|l| l.trim().is_empty() || l.trim_start().starts_with('#')) {
        return Err(user_error(format!(
            "{origin}: the file is empty; a program pipeline needs at least name, seeds and program \
             (its command and metrics)"
        )));
    }
    one_kind(text, origin)?;
    // The file as written first, so every error in it has a position, and each param's type is
    // its default's in the file whatever a --set gives.
    let file: ProgramFile =
        typed(serde_yaml::Deserializer::from_str(text)).map_err(|e| located(text, origin, e))?;
    let overridden = match overrides {
        [] => None,
        _ => {
            let mut doc: serde_yaml::Value =
                serde_yaml::from_str(text).map_err(|e| located(text, origin, Failure::from(e)))?;
            for o in overrides {
                o.apply(&mut doc).map_err(user_error)?;
            }
            Some(typed::<ProgramFile, _>(doc).map_err(|e| with_sets(origin, overrides, e))?)
        }
    };
    let raw = overridden.as_ref().unwrap_or(&file);
    let set_by_cli: Vec<String> = overrides
        .iter()
        .flat_map(|o| match o.path.as_slice() {
            [p] if p == "params" => raw.params.0.iter().map(|(n, _)| n.clone()).collect(),
            [p, name] if p == "params" => vec![name.clone()],
            _ => Vec::new(),
        })
        .collect();
    check::check(raw, &file.params, &set_by_cli).map_err(|p| problem_error(text, origin, overrides, p))
}

/// The user error of a broken rule: at its field's line and column, or, when a `--set` touches
/// the field (its value has no line in the file), naming the `--set`.
fn problem_error(text: &str, origin: &str, overrides: &[Override], p: Problem) -> anyhow::Error {
    let touched = overrides.iter().any(|o| o.path.starts_with(&p.path) || p.path.starts_with(&o.path));
    if touched {
        with_sets(origin, overrides, p.into())
    } else {
        located(text, origin, p.into())
    }
}
