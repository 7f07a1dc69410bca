//! The small part of Markdown the documentation tests need: which files are documentation,
//! fenced blocks with their line numbers, headings and their GitHub anchors, and inline links.
//! Shared by the example runner, the link check and the field tables, so all three agree on what
//! is code and what is prose.

use std::path::{Path, PathBuf};

/// The repository root (where Cargo.toml is).
pub fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// A Markdown file, read once: its path relative to the repository and its text.
pub struct Doc {
    pub path: PathBuf,
    pub text: String,
}

impl Doc {
    pub fn read(rel: &Path) -> Doc {
        let text =
            std::fs::read_to_string(repo().join(rel)).unwrap_or_else(|e| panic!("{}: {e}", rel.display()));
        Doc { path: rel.to_path_buf(), text }
    }
}

/// The documentation a reader is sent to: README.md, ARCHITECTURE.md, the crates' READMEs and the
/// guide (docs/**/*.md).
pub fn guide_docs() -> Vec<Doc> {
    let mut paths = vec![PathBuf::from("README.md"), PathBuf::from("ARCHITECTURE.md")];
    paths.extend(crate_readmes());
    paths.extend(markdown_under(Path::new("docs")));
    paths.iter().map(|p| Doc::read(p)).collect()
}

/// The committed reports' Markdown: the folders `.gitignore` keeps (`!/reports/NAME/`), so scratch
/// reports written by other runs on this machine are not checked.
pub fn report_docs() -> Vec<Doc> {
    let ignore = std::fs::read_to_string(repo().join(".gitignore")).unwrap();
    let kept = ignore.lines().filter_map(|l| l.strip_prefix("!/reports/")?.strip_suffix('/'));
    let mut paths = Vec::new();
    for name in kept {
        paths.extend(markdown_under(&Path::new("reports").join(name)));
    }
    paths.iter().map(|p| Doc::read(p)).collect()
}

/// Every crate's README (`crates/*/README.md`, relative to the repository), sorted.
pub fn crate_readmes() -> Vec<PathBuf> {
    let mut out: Vec<PathBuf> = std::fs::read_dir(repo().join("crates"))
        .unwrap()
        .map(|e| Path::new("crates").join(e.unwrap().file_name()).join("README.md"))
        .collect();
    out.sort();
    out
}

/// Every `.md` file under `dir` (relative to the repository), sorted.
fn markdown_under(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        let Ok(entries) = std::fs::read_dir(repo().join(&d)) else { continue };
        for e in entries.flatten() {
            let rel = d.join(e.file_name());
            if e.file_type().is_ok_and(|t| t.is_dir()) {
                stack.push(rel);
            } else if rel.extension().is_some_and(|x| x == "md") {
                out.push(rel);
            }
        }
    }
    out.sort();
    out
}

/// A fenced code block: its info string and its lines, the first being on `first_line` (1-based).
pub struct Fence {
    pub info: String,
    pub first_line: usize,
    pub lines: Vec<String>,
}

/// Every fenced block (``` or ~~~, indented fences included, as in list items).
pub fn fences(text: &str) -> Vec<Fence> {
    let mut out = Vec::new();
    // The open fence's marker and indentation, and the block so far.
    let mut open: Option<(String, usize, Fence)> = None;
    for (i, line) in text.lines().enumerate() {
        let t = line.trim_start();
        let indent = line.len() - t.len();
        match &mut open {
            None => {
                if let Some(marker) = fence_marker(t) {
                    let info = t[marker.len()..].trim().to_string();
                    open = Some((marker, indent, Fence { info, first_line: i + 2, lines: Vec::new() }));
                }
            }
            Some((marker, fence_indent, fence)) => {
                if t.starts_with(marker.as_str()) && t[marker.len()..].trim().is_empty() {
                    out.push(open.take().unwrap().2);
                } else {
                    // Strip the fence's own indentation (a block inside a list item), no more.
                    fence.lines.push(line[indent.min(*fence_indent)..].to_string());
                }
            }
        }
    }
    out
}

fn fence_marker(t: &str) -> Option<String> {
    for c in ['`', '~'] {
        let n = t.chars().take_while(|&x| x == c).count();
        if n >= 3 {
            return Some(c.to_string().repeat(n));
        }
    }
    None
}

/// The text's lines with fenced blocks blanked (so prose checks skip code), numbering kept.
pub fn prose_lines(text: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut marker: Option<String> = None;
    for line in text.lines() {
        let t = line.trim_start();
        match &marker {
            None => {
                if let Some(m) = fence_marker(t) {
                    marker = Some(m);
                    out.push(String::new());
                } else {
                    out.push(line.to_string());
                }
            }
            Some(m) => {
                if t.starts_with(m.as_str()) && t[m.len()..].trim().is_empty() {
                    marker = None;
                }
                out.push(String::new());
            }
        }
    }
    out
}

/// The anchors GitHub gives the text's headings (`#` lines outside code), duplicates numbered
/// `-1`, `-2`, … as GitHub does; HTML `id="…"`/`name="…"` attributes count too.
pub fn anchors(text: &str) -> Vec<String> {
    let mut out: Vec<String> = Vec::new();
    for line in prose_lines(text) {
        let hashes = line.chars().take_while(|&c| c == '#').count();
        if (1..=6).contains(&hashes) && line[hashes..].starts_with(' ') {
            let base = slug(line[hashes..].trim());
            let mut s = base.clone();
            let mut k = 1;
            while out.contains(&s) {
                s = format!("{base}-{k}");
                k += 1;
            }
            out.push(s);
        }
        for attr in ["id=\"", "name=\""] {
            for part in line.split(attr).skip(1) {
                if let Some(end) = part.find('"') {
                    out.push(part[..end].to_string());
                }
            }
        }
    }
    out
}

/// GitHub's heading slug: link text kept and link targets dropped, lower case, every character
/// that is not a letter, digit, space, `-` or `_` removed, spaces to `-`.
pub fn slug(heading: &str) -> String {
    let mut text = String::new();
    let mut rest = heading;
    // `[text](target)` → `text`.
    while let Some(i) = rest.find("](") {
        let Some(j) = rest[i..].find(')') else { break };
        text.push_str(&rest[..i]);
        rest = &rest[i + j + 1..];
    }
    text.push_str(rest);
    text.chars()
        .flat_map(char::to_lowercase)
        .filter(|c| c.is_alphanumeric() || matches!(c, ' ' | '-' | '_'))
        .map(|c| if c == ' ' { '-' } else { c })
        .collect()
}

/// Every inline link or image target `](target)` in the prose (outside code fences and inline
/// code spans), with its 1-based line.
pub fn links(text: &str) -> Vec<(usize, String)> {
    let mut out = Vec::new();
    for (i, line) in prose_lines(text).iter().enumerate() {
        let mut in_code = false;
        let mut prose = String::new();
        for c in line.chars() {
            if c == '`' {
                in_code = !in_code;
            } else if !in_code {
                prose.push(c);
            }
        }
        let mut rest = prose.as_str();
        while let Some(k) = rest.find("](") {
            let after = &rest[k + 2..];
            let Some(end) = after.find(')') else { break };
            let target = after[..end].split_whitespace().next().unwrap_or("").to_string();
            out.push((i + 1, target));
            rest = &after[end..];
        }
    }
    out
}

#[test]
fn slugs_follow_github() {
    assert_eq!(slug("Fresh seeds (the winner's curse)"), "fresh-seeds-the-winners-curse");
    assert_eq!(slug("Table III with uncertainty"), "table-iii-with-uncertainty");
    assert_eq!(
        slug("Exploratory: the Ball-Beam question (`pipelines/explore-ball-beam.yaml`)"),
        "exploratory-the-ball-beam-question-pipelinesexplore-ball-beamyaml"
    );
    assert_eq!(slug("Engine 2 (issue #26): the same speed"), "engine-2-issue-26-the-same-speed");
}
