//! Reading a pipeline file: every failure becomes one message `FILE:LINE:COL: PATH: MESSAGE`
//! naming the file, the line and column of the field's key, the field's dotted path and what is
//! allowed. serde_path_to_error gives the path; `locate` finds it in the text.

use super::fields::{improve, split_location};
use super::fields::{FIELD, SEP};
use super::locate::locate_prefix;
use super::overrides::Override;
use super::pipeline::PipelineSpec;
use super::variant_load::LoadedVariant;
use crate::error::user_error;
use serde_path_to_error::Segment;
use std::path::{Path, PathBuf};

/// Largest pipeline file accepted.
const MAX_BYTES: u64 = 4 << 20;

/// A parsed pipeline with where it came from.
#[derive(Debug, Clone)]
pub struct LoadedSpec {
    /// The typed pipeline.
    pub spec: PipelineSpec,
    /// The file it was read from.
    pub path: PathBuf,
    /// Its variants, resolved (empty when the pipeline declares none).
    pub variants: Vec<LoadedVariant>,
}

/// Read, parse and type a pipeline file, then apply `--set` overrides.
pub fn load(path: &Path, overrides: &[Override]) -> anyhow::Result<LoadedSpec> {
    let shown = path.display();
    let text = read_text(path)?;
    let spec = load_str(&text, &shown.to_string(), overrides)?;
    let variants = super::variant_load::resolve(&spec, &text, &shown.to_string(), overrides)?;
    Ok(LoadedSpec { spec, path: path.to_path_buf(), variants })
}

/// A pipeline file's text: refused (as a user error naming the file) when it cannot be read, is a
/// directory, is over 4 MiB or is not UTF-8.
pub(crate) fn read_text(path: &Path) -> anyhow::Result<String> {
    let shown = path.display();
    let meta = std::fs::metadata(path)
        .map_err(|e| user_error(format!("{shown}: cannot read pipeline file: {e}")))?;
    if meta.is_dir() {
        return Err(user_error(format!(
            "{shown}: is a directory; give a pipeline file such as pipelines/quick.yaml"
        )));
    }
    if meta.len() > MAX_BYTES {
        return Err(user_error(format!(
            "{shown}: {} bytes is too large for a pipeline file (limit 4 MiB)",
            meta.len()
        )));
    }
    let bytes =
        std::fs::read(path).map_err(|e| user_error(format!("{shown}: cannot read pipeline file: {e}")))?;
    String::from_utf8(bytes).map_err(|e| {
        let at = e.utf8_error().valid_up_to();
        let line = e.as_bytes()[..at].iter().filter(|&&b| b == b'\n').count() + 1;
        user_error(format!("{shown}:{line}: the file is not valid UTF-8 (byte {at}); save it as UTF-8"))
    })
}

/// Parse pipeline text; `origin` names it in messages.
pub fn load_str(text: &str, origin: &str, overrides: &[Override]) -> anyhow::Result<PipelineSpec> {
    if text.lines().all(|l| l.trim().is_empty() || l.trim_start().starts_with('#')) {
        return Err(user_error(format!(
            "{origin}: the file is empty; a pipeline needs at least name, seeds and systems"
        )));
    }
    let here = |e: Failure| located(text, origin, e);
    one_kind(text, origin)?;
    // Typed parse of the text itself first, so every error has a position.
    let spec: PipelineSpec = typed(serde_yaml::Deserializer::from_str(text)).map_err(here)?;
    if spec.systems.kinds().is_empty() {
        let msg = format!("the section is empty; add {}", qsweep_engine::env::SystemKind::listed());
        return Err(here(Failure::at(&["systems"], &msg)));
    }
    if overrides.is_empty() {
        if let Err(p) = super::check::check_whole(&spec) {
            return Err(here(p.into()));
        }
        return Ok(spec);
    }
    let doc: serde_yaml::Value = serde_yaml::from_str(text).map_err(|e| here(Failure::from(e)))?;
    load_value(doc, origin, overrides)
}

/// Refuse a pipeline file that declares both `systems:` and `program:` (a program pipeline,
/// `crate::program`), at the `program:` line.
pub(crate) fn one_kind(text: &str, origin: &str) -> anyhow::Result<()> {
    let top = |key: &str| super::locate::locate(text, &[key.to_string()]);
    if let (Some(_), Some((line, col))) = (top("systems"), top("program")) {
        return Err(user_error(format!(
            "{origin}:{line}:{col}: program: a pipeline declares either `systems:` (the built-in engine) or \
             `program:` (your own program), not both; put each in a pipeline file of its own"
        )));
    }
    Ok(())
}

/// The user error of a typed-parse failure of `text` (the file `origin`): `FILE:LINE:COL: PATH:
/// MESSAGE`, at the field's key (serde_yaml's own position for a syntax error).
pub(crate) fn located(text: &str, origin: &str, mut e: Failure) -> anyhow::Error {
    if serde_yaml::from_str::<serde_yaml::Value>(text).err().map(|v| split_location(&v))
        == Some((e.msg.clone(), e.yaml_at))
    {
        // A syntax error: serde_yaml's position is exact and the path means little.
        e.path.clear();
    }
    let at = if e.path.is_empty() { None } else { locate_prefix(text, &e.path).map(|(_, p)| p) };
    let mut msg = e.message();
    match at.or(e.yaml_at) {
        Some((line, col)) => {
            let src = text.lines().nth(line.saturating_sub(1)).unwrap_or("");
            if src.contains('\t') && msg.contains("cannot start any token") {
                msg.push_str("; YAML does not allow tabs for indentation, use spaces");
            }
            user_error(format!("{origin}:{line}:{col}: {msg}"))
        }
        None => user_error(format!("{origin}: {msg}")),
    }
}

/// Check a pipeline given as a YAML value (built in code, so it has no lines to point at) with
/// `--set` overrides applied in order: errors name the field and the overrides that touch it.
pub fn load_value(
    mut doc: serde_yaml::Value,
    origin: &str,
    overrides: &[Override],
) -> anyhow::Result<PipelineSpec> {
    for o in overrides {
        o.apply(&mut doc).map_err(user_error)?;
    }
    let named = |e: Failure| with_sets(origin, overrides, e);
    let spec = typed(doc).map_err(named)?;
    super::check::check_whole(&spec).map_err(|p| named(p.into()))?;
    Ok(spec)
}

/// The user error of a failure of a document that `overrides` changed: the overridden values
/// have no line in the file, so it names the field and the `--set` arguments that put it there
/// (all of them when the error is about a section they only touch).
pub(crate) fn with_sets(origin: &str, overrides: &[Override], e: Failure) -> anyhow::Error {
    let from: Vec<&Override> =
        overrides.iter().filter(|o| o.path.starts_with(&e.path) || e.path.starts_with(&o.path)).collect();
    let from = if from.is_empty() { overrides.iter().collect() } else { from };
    let sets: Vec<&str> = from.iter().map(|o| o.raw.as_str()).collect();
    if sets.is_empty() {
        user_error(format!("{origin}: {}", e.message()))
    } else {
        user_error(format!("{origin} with --set {}: {}", sets.join(" --set "), e.message()))
    }
}

/// A typed-parse failure: the dotted path of the field (keys, and sequence indices as decimal
/// numbers), the message, and serde_yaml's own position (exact only for syntax and key errors).
pub(crate) struct Failure {
    path: Vec<String>,
    /// How many segments of `path` the message shows: all, but the key itself where the message
    /// names it (an unknown or duplicate key: `systems.cart-pole: unknown field `mass``).
    shown: usize,
    msg: String,
    yaml_at: Option<(usize, usize)>,
}

impl Failure {
    /// A failure of the field at `path` (keys, and sequence indices as decimal numbers).
    pub(crate) fn at(path: &[&str], msg: &str) -> Self {
        let path: Vec<String> = path.iter().map(|s| s.to_string()).collect();
        Self { shown: path.len(), path, msg: msg.to_string(), yaml_at: None }
    }

    /// `PATH: MESSAGE`, with a "did you mean" where one helps.
    fn message(&self) -> String {
        match self.shown.min(self.path.len()) {
            0 => improve(&self.msg),
            n => format!("{}: {}", self.path[..n].join("."), improve(&self.msg)),
        }
    }
}

impl From<super::check::Problem> for Failure {
    /// A whole-pipeline check's problem, at its field's path.
    fn from(p: super::check::Problem) -> Self {
        Self { shown: p.path.len(), path: p.path, msg: p.message, yaml_at: None }
    }
}

impl From<serde_yaml::Error> for Failure {
    fn from(e: serde_yaml::Error) -> Self {
        let (msg, yaml_at) = split_location(&e);
        Self { path: Vec::new(), shown: 0, msg, yaml_at }
    }
}

/// Deserialise a pipeline file (the engine's, or a program pipeline), keeping the path of a
/// failing field.
pub(crate) fn typed<'de, T, D>(d: D) -> Result<T, Failure>
where
    T: serde::Deserialize<'de>,
    D: serde::Deserializer<'de, Error = serde_yaml::Error>,
{
    serde_path_to_error::deserialize(d).map_err(|e| {
        let mut path: Vec<String> = Vec::new();
        let mut is_index: Vec<bool> = Vec::new();
        for seg in e.path().iter() {
            match seg {
                Segment::Map { key } | Segment::Enum { variant: key } => path.push(key.clone()),
                Segment::Seq { index } => path.push(index.to_string()),
                Segment::Unknown => break,
            }
            is_index.push(matches!(seg, Segment::Seq { .. }));
        }
        let mut f = Failure::from(e.into_inner());
        // serde_yaml starts the message with the path of the section where it noticed the error
        // (`systems.ball-beam.experiments[0]: `): drop it, the full path replaces it.
        let shown = |n: usize| {
            path[..n].iter().enumerate().fold(String::new(), |mut out, (i, seg)| {
                match &is_index[i] {
                    true => out.push_str(&format!("[{seg}]")),
                    false if out.is_empty() => out.push_str(seg),
                    false => out.push_str(&format!(".{seg}")),
                }
                out
            })
        };
        if let Some(n) = (1..=path.len()).rev().find(|&n| f.msg.starts_with(&format!("{}: ", shown(n)))) {
            f.msg = f.msg[shown(n).len() + 2..].to_string();
        }
        if let Some((_, rest)) = f.msg.split_once(FIELD) {
            if let Some((sub, msg)) = rest.split_once(FIELD) {
                path.extend(sub.split(SEP).map(String::from));
                f.msg = msg.to_string();
            }
        }
        // serde's "duplicate field" is raised by the section: name the field given twice.
        if let Some(field) = f.msg.strip_prefix("duplicate field `").and_then(|r| r.split('`').next()) {
            path.push(field.to_string());
        }
        let names_key = ["unknown field `", "duplicate field `"].iter().any(|p| f.msg.starts_with(p));
        f.shown = path.len() - usize::from(names_key && !path.is_empty());
        f.path = path;
        f
    })
}

#[cfg(test)]
mod tests {
    use super::super::fields::{at_field, message};
    use super::*;

    #[test]
    fn field_markers_read_as_paths_where_no_path_is_tracked() {
        let e: serde_yaml::Error = at_field(&["params", "tau"], "-1 is not allowed here");
        assert_eq!(message(&e), "params.tau: -1 is not allowed here");
    }

    #[test]
    fn unknown_fields_get_a_suggestion() {
        let m = improve("unknown field `sedes`, expected one of `name`, `seeds`, `systems`");
        assert!(m.ends_with("did you mean `seeds`?"), "{m}");
        let m = improve("unknown variant `q-lamda`, expected `q0` or `q-lambda`");
        assert!(m.ends_with("did you mean `q-lambda`?"), "{m}");
    }
}
