//! A program's declared input files: each `inputs:` glob expanded against a base directory
//! (qsweep's working directory, where the program runs), the files sorted and deduplicated, and
//! each one's contents digested with blake3, so that editing any of them changes every trial's
//! key. Globs: `*` and `?` within one path segment, `[abc]`/`[a-z]`/`[!a]` classes, `**` for any
//! number of directories, `\` before a character to take it literally. As in a shell, a wildcard
//! does not match a name starting with `.` unless the pattern's segment starts with `.` (so
//! `**/*.py` leaves `.venv/` and `.git/` alone), and `**` does not follow links to directories.

use crate::program::model::InputFile;
use rayon::prelude::*;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// The most files the globs together may match.
pub const MAX_FILES: usize = 100_000;

/// Why a glob could not be resolved: its index in `inputs:` and the message.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct InputError {
    /// The glob's index in `inputs:`.
    pub glob: usize,
    /// What is wrong, with the fix.
    pub message: String,
}

/// Every file the `globs` match under `base` (a relative glob is taken from `base`; an absolute
/// one as it is), sorted by path and deduplicated, with its digest. A glob that matches no file
/// is an error.
pub fn resolve(globs: &[String], base: &Path) -> Result<Vec<InputFile>, InputError> {
    let mut found: BTreeMap<String, (PathBuf, usize)> = BTreeMap::new();
    for (i, g) in globs.iter().enumerate() {
        let matched = expand(g, base).map_err(|message| InputError { glob: i, message })?;
        for (shown, path) in matched {
            found.entry(shown).or_insert((path, i));
        }
        if found.len() > MAX_FILES {
            return Err(InputError {
                glob: i,
                message: format!("the inputs match more than {MAX_FILES} files; narrow the globs"),
            });
        }
    }
    found
        .into_par_iter()
        .map(|(shown, (path, glob))| match digest(&path) {
            Ok(digest) => Ok(InputFile { path: shown, digest }),
            Err(e) => Err(InputError { glob, message: format!("cannot read input `{shown}`: {e}") }),
        })
        .collect()
}

/// blake3 of a file's contents, hex.
pub fn digest(path: &Path) -> std::io::Result<String> {
    let mut file = std::fs::File::open(path)?;
    let mut h = blake3::Hasher::new();
    std::io::copy(&mut file, &mut h)?;
    Ok(h.finalize().to_hex().to_string())
}

/// The files `glob` matches under `base`: each as shown in keys and messages (`/` separators,
/// relative to `base` when the glob is, `.` segments dropped) with its path on disk.
pub fn expand(glob: &str, base: &Path) -> Result<Vec<(String, PathBuf)>, String> {
    let absolute = glob.starts_with('/');
    let mut segs: Vec<&str> = glob.split('/').filter(|s| !s.is_empty() && *s != ".").collect();
    if segs.is_empty() {
        return Err(format!("`{glob}` names no file; give a file or a glob such as agents/*.py"));
    }
    // `dir/**` is every file below `dir`.
    if segs.last() == Some(&"**") {
        segs.push("*");
    }
    let root =
        if absolute { ("/".to_string(), PathBuf::from("/")) } else { (String::new(), base.to_path_buf()) };
    let mut here = vec![root];
    for seg in &segs {
        let mut next = Vec::new();
        for (shown, dir) in here {
            if *seg == "**" {
                dirs_below(shown, dir, &mut next);
            } else if is_wild(seg) {
                let Ok(entries) = std::fs::read_dir(&dir) else { continue };
                for e in entries.flatten() {
                    let name = e.file_name().to_string_lossy().into_owned();
                    if matches(seg, &name) {
                        next.push((join(&shown, &name), dir.join(&name)));
                    }
                }
            } else {
                next.push((join(&shown, &unescape(seg)), dir.join(unescape(seg))));
            }
        }
        here = next;
    }
    let (files, dirs): (Vec<_>, Vec<_>) = here.into_iter().partition(|(_, p)| p.is_file());
    if files.is_empty() {
        return Err(match dirs.iter().find(|(_, p)| p.is_dir()) {
            Some((d, _)) if !is_wild(glob) => {
                format!("`{d}` is a directory; write `{d}/**` to take every file in it")
            }
            _ if absolute => format!("`{glob}` matches no file; fix the glob or remove it"),
            _ => format!("`{glob}` matches no file (in {}); fix the glob or remove it", base.display()),
        });
    }
    Ok(files)
}

/// `dir` itself and every directory below it, skipping hidden ones and links.
fn dirs_below(shown: String, dir: PathBuf, out: &mut Vec<(String, PathBuf)>) {
    let mut stack = vec![(shown, dir)];
    while let Some((shown, dir)) = stack.pop() {
        if let Ok(entries) = std::fs::read_dir(&dir) {
            for e in entries.flatten() {
                let name = e.file_name().to_string_lossy().into_owned();
                if !name.starts_with('.') && e.file_type().is_ok_and(|t| t.is_dir()) {
                    stack.push((join(&shown, &name), dir.join(&name)));
                }
            }
        }
        out.push((shown, dir));
    }
}

/// `prefix/name` as shown (`prefix` empty for the base, `/` for the root).
fn join(prefix: &str, name: &str) -> String {
    match prefix {
        "" => name.to_string(),
        p if p.ends_with('/') => format!("{p}{name}"),
        p => format!("{p}/{name}"),
    }
}

/// Whether a pattern has a wildcard (an unescaped `*`, `?` or `[`).
fn is_wild(pattern: &str) -> bool {
    let mut escaped = false;
    for c in pattern.chars() {
        match c {
            _ if escaped => escaped = false,
            '\\' => escaped = true,
            '*' | '?' | '[' => return true,
            _ => {}
        }
    }
    false
}

/// A literal segment with its escapes removed.
fn unescape(seg: &str) -> String {
    let mut out = String::with_capacity(seg.len());
    let mut escaped = false;
    for c in seg.chars() {
        if c == '\\' && !escaped {
            escaped = true;
        } else {
            out.push(c);
            escaped = false;
        }
    }
    out
}

/// Whether one path segment `name` matches the segment pattern `pattern`.
pub fn matches(pattern: &str, name: &str) -> bool {
    if name.starts_with('.') && !pattern.starts_with('.') {
        return false;
    }
    let p: Vec<char> = pattern.chars().collect();
    let n: Vec<char> = name.chars().collect();
    match_at(&p, &n)
}

fn match_at(p: &[char], n: &[char]) -> bool {
    match p.first() {
        None => n.is_empty(),
        Some('*') => {
            let rest = &p[p.iter().take_while(|c| **c == '*').count()..];
            (0..=n.len()).any(|k| match_at(rest, &n[k..]))
        }
        Some('?') => !n.is_empty() && match_at(&p[1..], &n[1..]),
        Some('[') => match class(&p[1..]) {
            Some(c) => n.first().is_some_and(|ch| c.contains(*ch)) && match_at(&p[1 + c.used..], &n[1..]),
            None => n.first() == Some(&'[') && match_at(&p[1..], &n[1..]),
        },
        Some('\\') if p.len() > 1 => n.first() == Some(&p[1]) && match_at(&p[2..], &n[1..]),
        Some(c) => n.first() == Some(c) && match_at(&p[1..], &n[1..]),
    }
}

/// A character class (`[abc]`, `[a-z]`, `[!a]`).
struct Class {
    /// Single characters as `(c, c)`, ranges as `(a, b)`.
    items: Vec<(char, char)>,
    /// `[!…]`.
    negated: bool,
    /// How many pattern characters it used after its `[`, the closing `]` included.
    used: usize,
}

impl Class {
    fn contains(&self, c: char) -> bool {
        self.items.iter().any(|(a, b)| (*a..=*b).contains(&c)) != self.negated
    }
}

/// The class after a `[`; `None` when it does not close (the `[` is then literal).
fn class(p: &[char]) -> Option<Class> {
    let negated = p.first() == Some(&'!');
    let mut i = usize::from(negated);
    let mut items = Vec::new();
    // A `]` right after the opening is a member, not the end.
    let mut first = true;
    while i < p.len() {
        if p[i] == ']' && !first {
            return Some(Class { items, negated, used: i + 1 });
        }
        first = false;
        if i + 2 < p.len() && p[i + 1] == '-' && p[i + 2] != ']' {
            items.push((p[i], p[i + 2]));
            i += 3;
        } else {
            items.push((p[i], p[i]));
            i += 1;
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tree(files: &[&str]) -> tempfile::TempDir {
        let dir = tempfile::tempdir().unwrap();
        for f in files {
            let p = dir.path().join(f);
            std::fs::create_dir_all(p.parent().unwrap()).unwrap();
            std::fs::write(&p, f.as_bytes()).unwrap();
        }
        dir
    }

    fn shown(glob: &str, base: &Path) -> Vec<String> {
        let mut v: Vec<String> = expand(glob, base).unwrap().into_iter().map(|(s, _)| s).collect();
        v.sort();
        v
    }

    #[test]
    fn segment_patterns() {
        assert!(matches("*.py", "q_learning.py"));
        assert!(!matches("*.py", "q_learning.pyc"));
        assert!(matches("q?.py", "q1.py"));
        assert!(!matches("q?.py", "q.py"));
        assert!(matches("[ab]*", "agent"));
        assert!(!matches("[!ab]*", "agent"));
        assert!(matches("v[0-9]", "v7"));
        assert!(!matches("v[0-9]", "vx"));
        assert!(matches("a\\*b", "a*b"));
        assert!(!matches("a\\*b", "axb"));
        assert!(matches("[]]", "]"));
        assert!(matches("[x", "[x"));
        // Hidden names only for a pattern that starts with a dot.
        assert!(!matches("*", ".env"));
        assert!(matches(".*", ".env"));
    }

    #[test]
    fn globs_expand_sorted_with_slash_paths() {
        let d =
            tree(&["agents/q.py", "agents/b.py", "agents/notes.txt", "agents/sub/deep.py", "agents/.h.py"]);
        assert_eq!(shown("agents/*.py", d.path()), ["agents/b.py", "agents/q.py"]);
        assert_eq!(shown("./agents/q.py", d.path()), ["agents/q.py"]);
        assert_eq!(shown("agents/**/*.py", d.path()), ["agents/b.py", "agents/q.py", "agents/sub/deep.py"]);
        assert_eq!(
            shown("agents/**", d.path()),
            ["agents/b.py", "agents/notes.txt", "agents/q.py", "agents/sub/deep.py"]
        );
        assert_eq!(shown("**/deep.py", d.path()), ["agents/sub/deep.py"]);
    }

    #[test]
    fn hidden_directories_are_not_searched_by_double_star() {
        let d = tree(&["a.py", ".venv/lib/x.py", "src/.cache/y.py"]);
        assert_eq!(shown("**/*.py", d.path()), ["a.py"]);
        assert_eq!(shown(".venv/**/*.py", d.path()), [".venv/lib/x.py"]);
    }

    #[test]
    fn resolve_sorts_dedupes_and_digests() {
        let d = tree(&["agents/q.py", "agents/b.py", "lib/u.py"]);
        let globs = vec!["agents/q.py".to_string(), "agents/*.py".into(), "lib/*.py".into()];
        let files = resolve(&globs, d.path()).unwrap();
        let paths: Vec<&str> = files.iter().map(|f| f.path.as_str()).collect();
        assert_eq!(paths, ["agents/b.py", "agents/q.py", "lib/u.py"]);
        assert_eq!(files[1].digest, blake3::hash(b"agents/q.py").to_hex().to_string());
        assert_eq!(files[1].digest.len(), 64);
    }

    #[test]
    fn absolute_globs_keep_their_absolute_paths() {
        let d = tree(&["x/a.py"]);
        let glob = format!("{}/x/*.py", d.path().display());
        let got = shown(&glob, Path::new("/nonexistent"));
        assert_eq!(got, [format!("{}/x/a.py", d.path().display())]);
    }

    #[test]
    fn a_glob_that_matches_nothing_says_so() {
        let d = tree(&["agents/q.py"]);
        let e = resolve(&["agents/q.py".into(), "agent/*.py".into()], d.path()).unwrap_err();
        assert_eq!(e.glob, 1);
        assert!(e.message.starts_with("`agent/*.py` matches no file (in "), "{}", e.message);
        let e = expand("agents", d.path()).unwrap_err();
        assert_eq!(e, "`agents` is a directory; write `agents/**` to take every file in it");
        assert!(expand("./", d.path()).unwrap_err().contains("names no file"));
    }
}
