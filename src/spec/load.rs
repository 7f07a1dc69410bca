//! Reading a pipeline file: every failure becomes one message naming the file, line and column,
//! the field, and what is allowed.

use super::{suggest, LoadedVariant, Override, PipelineSpec};
use crate::error::user_error;
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
    let text = String::from_utf8(bytes).map_err(|e| {
        let at = e.utf8_error().valid_up_to();
        let line = e.as_bytes()[..at].iter().filter(|&&b| b == b'\n').count() + 1;
        user_error(format!("{shown}:{line}: the file is not valid UTF-8 (byte {at}); save it as UTF-8"))
    })?;
    let spec = load_str(&text, &shown.to_string(), overrides)?;
    let variants = super::variants::resolve(&spec, &text, &shown.to_string(), overrides)?;
    Ok(LoadedSpec { spec, path: path.to_path_buf(), variants })
}

/// Parse pipeline text; `origin` names it in messages.
pub fn load_str(text: &str, origin: &str, overrides: &[Override]) -> anyhow::Result<PipelineSpec> {
    if text.lines().all(|l| l.trim().is_empty() || l.trim_start().starts_with('#')) {
        return Err(user_error(format!(
            "{origin}: the file is empty; a pipeline needs at least name, seeds and systems"
        )));
    }
    let located = |e: serde_yaml::Error| {
        let (msg, loc) = split_location(&e);
        let mut msg = improve(&msg);
        if let Some((line, col)) = loc {
            if let Some(src) = text.lines().nth(line.saturating_sub(1)) {
                if src.contains('\t') && msg.contains("cannot start any token") {
                    msg.push_str("; YAML does not allow tabs for indentation, use spaces");
                }
            }
            user_error(format!("{origin}:{line}:{col}: {msg}"))
        } else {
            user_error(format!("{origin}: {msg}"))
        }
    };
    // Typed parse of the text itself first, so every error has a position.
    let spec: PipelineSpec = serde_yaml::from_str(text).map_err(located)?;
    if spec.systems.ball_beam.is_none()
        && spec.systems.cart_pole.is_none()
        && spec.systems.mountain_car.is_none()
    {
        return Err(user_error(format!(
            "{origin}: systems is empty; add ball-beam, cart-pole or mountain-car"
        )));
    }
    if overrides.is_empty() {
        return Ok(spec);
    }
    let mut doc: serde_yaml::Value = serde_yaml::from_str(text).map_err(located)?;
    for o in overrides {
        o.apply(&mut doc).map_err(user_error)?;
    }
    let sets: Vec<&str> = overrides.iter().map(|o| o.raw.as_str()).collect();
    serde_yaml::from_value(doc).map_err(|e| {
        let (msg, _) = split_location(&e);
        user_error(format!("{origin} with --set {}: {}", sets.join(" --set "), improve(&msg)))
    })
}

/// A typing error's message without its position, with "did you mean" where it helps.
pub(super) fn message(e: &serde_yaml::Error) -> String {
    improve(&split_location(e).0)
}

/// serde_yaml's message without its " at line L column C" suffix, and the location.
fn split_location(e: &serde_yaml::Error) -> (String, Option<(usize, usize)>) {
    let full = e.to_string();
    let loc = e.location().map(|l| (l.line(), l.column()));
    let msg = match full.rfind(" at line ") {
        Some(i) if loc.is_some() => full[..i].to_string(),
        _ => full,
    };
    (msg, loc)
}

/// Add "did you mean" to unknown-field and unknown-variant messages.
fn improve(msg: &str) -> String {
    for kind in ["unknown field `", "unknown variant `"] {
        if let Some(start) = msg.find(kind) {
            let rest = &msg[start + kind.len()..];
            let Some(end) = rest.find('`') else { continue };
            let word = &rest[..end];
            let expected: Vec<&str> = rest[end..].split('`').skip(2).step_by(2).collect();
            if let Some(s) = suggest(word, expected.iter().copied()) {
                return format!("{msg}; did you mean `{s}`?");
            }
        }
    }
    msg.to_string()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unknown_fields_get_a_suggestion() {
        let m = improve("unknown field `sedes`, expected one of `name`, `seeds`, `systems`");
        assert!(m.ends_with("did you mean `seeds`?"), "{m}");
        let m = improve("unknown variant `q-lamda`, expected `q0` or `q-lambda`");
        assert!(m.ends_with("did you mean `q-lambda`?"), "{m}");
    }
}
