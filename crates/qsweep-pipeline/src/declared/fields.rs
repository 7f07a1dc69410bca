//! Small rules of the pipeline file's names: an error about a field below the value being read
//! ([`at_field`]), "did you mean" suggestions, safe folder names and variable names.

use qsweep_engine::env::SystemKind;

/// Marks the sub-path that [`at_field`] puts before a message.
pub(super) const FIELD: char = '\u{1f}';

/// Separates the sub-path's segments.
pub(super) const SEP: char = '\u{1e}';

/// An error about a field below the value being deserialised (a check that sees the whole
/// section, e.g. one parameter of `params`, or the `id` of one experiment in the list): `sub` is
/// the field's path relative to that value, which `load_str` adds to the error's path.
pub(super) fn at_field<E: serde::de::Error>(sub: &[&str], msg: impl std::fmt::Display) -> E {
    E::custom(format!("{FIELD}{}{FIELD}{msg}", sub.join(&SEP.to_string())))
}

/// Index of a state variable by name, or an error listing the valid names.
pub fn variable_index(system: SystemKind, name: &str) -> Result<usize, String> {
    let vars = system.variables();
    vars.iter().position(|v| *v == name).ok_or_else(|| {
        let hint = suggest(name, vars.iter().copied().chain(["actions"]))
            .map(|s| format!("; did you mean `{s}`?"))
            .unwrap_or_default();
        format!("unknown variable `{name}` for {system}; its variables are {}{hint}", vars.join(", "))
    })
}

/// The closest candidate to `word` by edit distance, if reasonably close.
pub fn suggest<'a>(word: &str, candidates: impl IntoIterator<Item = &'a str>) -> Option<&'a str> {
    candidates
        .into_iter()
        .map(|c| (edit_distance(word, c), c))
        .filter(|(d, c)| *d <= (c.len().max(word.len()) / 3).max(2))
        .min_by_key(|(d, _)| *d)
        .map(|(_, c)| c)
}

pub(super) fn edit_distance(a: &str, b: &str) -> usize {
    let b: Vec<char> = b.chars().collect();
    let mut prev: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.chars().enumerate() {
        let mut cur = vec![i + 1; b.len() + 1];
        for (j, cb) in b.iter().enumerate() {
            cur[j + 1] = (prev[j] + usize::from(ca != *cb)).min(prev[j + 1] + 1).min(cur[j] + 1);
        }
        prev = cur;
    }
    prev[b.len()]
}

/// Whether `s` is safe as one folder name on every platform: 1-100 letters, digits, '-', '_' or
/// '.', not starting with '.'.
pub fn safe_folder_name(s: &str) -> Result<(), String> {
    let ok = !s.is_empty()
        && s.len() <= 100
        && s.chars().all(|c| c.is_ascii_alphanumeric() || "-_.".contains(c))
        && !s.starts_with('.');
    if ok {
        Ok(())
    } else {
        Err("use 1-100 letters, digits, '-', '_' or '.', not starting with '.' (it names the report folder)"
            .into())
    }
}

/// A typing error's message without its position, with "did you mean" where it helps.
pub(super) fn message(e: &serde_yaml::Error) -> String {
    let msg = split_location(e).0;
    // A field marker from `at_field` (no path tracking here): show the sub-path as words.
    let msg = match msg.split_once(FIELD).and_then(|(head, rest)| Some((head, rest.split_once(FIELD)?))) {
        Some((head, (sub, tail))) => format!("{head}{}: {tail}", sub.replace(SEP, ".")),
        None => msg,
    };
    improve(&msg)
}

/// serde_yaml's message without its " at line L column C" suffix, and the location.
pub(super) fn split_location(e: &serde_yaml::Error) -> (String, Option<(usize, usize)>) {
    let full = e.to_string();
    let loc = e.location().map(|l| (l.line(), l.column()));
    let msg = match full.rfind(" at line ") {
        Some(i) if loc.is_some() => full[..i].to_string(),
        _ => full,
    };
    (msg, loc)
}

/// Add "did you mean" to unknown-field and unknown-variant messages.
pub(super) fn improve(msg: &str) -> String {
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
