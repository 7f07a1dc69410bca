//! Every console example is a test. A ```console block in README.md or the guide holds
//! `$ qsweep …` lines, each followed by an optional `? CODE` line (the exit status; 0 when absent)
//! and the output it prints, stdout and stderr as a terminal interleaves them. The runner
//! executes each command with the built binary in a scratch directory holding a copy of the
//! repository's `pipelines/` (the
//! commands of one block share it, so a `run` can be followed by a `status`), and compares the
//! output line by line. A block may also write a file, as a shell here-document does:
//! `$ cat > FILE <<'EOF'` (or `>>` to append), the file's lines, then `EOF`. A block right after
//! the line `<!-- same directory as the example above -->` (an HTML comment: no reader sees it)
//! continues the page's previous block in its directory, so a tutorial's steps can have prose
//! between them. Two elisions keep examples honest about what varies (times, paths,
//! progress): a line `...` stands for any number of lines, and `[..]` within a line for any text.
//! Commands that cannot run in a test (Slurm, a long run) are written as ```sh blocks instead.
//!
//! A mismatch fails naming the file and the line of the example, with the expected and the
//! actual output.

use crate::markdown::{fences, guide_docs, repo};
use std::path::Path;
use std::process::Command;

/// The line before a ```console block that makes it continue the page's previous block.
const CONTINUES: &str = "<!-- same directory as the example above -->";

/// What one `$` line does.
enum Action {
    /// `$ qsweep ARGS`: run the binary.
    Qsweep(Vec<String>),
    /// `$ cat > PATH <<'EOF'` (`>>`: append) and the lines up to `EOF`: write them to PATH.
    Write { path: String, append: bool, text: String },
}

/// One `$` line of an example, with what it should print.
struct Example {
    /// Where the `$` line is, as `FILE:LINE`.
    at: String,
    action: Action,
    status: i32,
    expected: Vec<String>,
    /// The line of each expected line in the file, to name the one that differs.
    expected_lines: Vec<usize>,
}

/// The examples of one ```console block, in order.
fn parse_block(file: &Path, first_line: usize, lines: &[String]) -> Vec<Example> {
    let mut out: Vec<Example> = Vec::new();
    let mut i = 0;
    while i < lines.len() {
        let line = &lines[i];
        if let Some(cmd) = line.strip_prefix("$ ") {
            let at = format!("{}:{}", file.display(), first_line + i);
            let args = split_words(cmd);
            let action = if let Some((path, append, end)) = here_document(&args) {
                assert!(
                    !path.starts_with('/') && !path.split('/').any(|c| c == ".."),
                    "{at}: a here-document writes inside the example's directory"
                );
                let body = &lines[i + 1..];
                let n = body
                    .iter()
                    .position(|l| *l == end)
                    .unwrap_or_else(|| panic!("{at}: the here-document has no closing `{end}` line"));
                let text = body[..n].iter().map(|l| format!("{l}\n")).collect();
                i += n + 1;
                Action::Write { path, append, text }
            } else {
                assert_eq!(
                    args.first().map(String::as_str),
                    Some("qsweep"),
                    "{at}: a console example runs `qsweep` or writes a file (`cat > FILE <<'EOF'`); \
                     write other commands as a ```sh block"
                );
                Action::Qsweep(args[1..].to_vec())
            };
            out.push(Example { at, action, status: 0, expected: Vec::new(), expected_lines: Vec::new() });
        } else if let Some(ex) = out.last_mut() {
            match line.strip_prefix("? ") {
                Some(code) if ex.expected.is_empty() => {
                    ex.status = code.trim().parse().unwrap_or_else(|_| panic!("{}: bad status line", ex.at))
                }
                _ => {
                    ex.expected.push(line.trim_end().to_string());
                    ex.expected_lines.push(first_line + i);
                }
            }
        } else {
            panic!("{}:{}: a console block starts with a `$ ` line", file.display(), first_line + i);
        }
        i += 1;
    }
    out
}

/// `cat > PATH <<EOF` or `cat >> PATH <<EOF` (quotes already removed): the path, whether it
/// appends, and the closing word.
fn here_document(words: &[String]) -> Option<(String, bool, String)> {
    match words {
        [cat, op, path, end] if cat == "cat" && (op == ">" || op == ">>") => {
            let end = end.strip_prefix("<<")?;
            Some((path.clone(), op == ">>", end.to_string()))
        }
        _ => None,
    }
}

/// Shell-like word splitting: whitespace separates, '…' and "…" quote.
fn split_words(s: &str) -> Vec<String> {
    let mut words = Vec::new();
    let mut cur = String::new();
    let mut quote: Option<char> = None;
    let mut any = false;
    for c in s.chars() {
        match quote {
            Some(q) if c == q => quote = None,
            Some(_) => cur.push(c),
            None if c == '\'' || c == '"' => {
                quote = Some(c);
                any = true;
            }
            None if c.is_whitespace() => {
                if any || !cur.is_empty() {
                    words.push(std::mem::take(&mut cur));
                }
                any = false;
            }
            None => cur.push(c),
        }
    }
    if any || !cur.is_empty() {
        words.push(cur);
    }
    words
}

/// Whether one expected line matches one actual line (`[..]` matches any text).
fn line_matches(expected: &str, actual: &str) -> bool {
    let parts: Vec<&str> = expected.split("[..]").collect();
    if parts.len() == 1 {
        return expected == actual;
    }
    let (first, last) = (parts[0], parts[parts.len() - 1]);
    if !actual.starts_with(first) || actual.len() < first.len() + last.len() || !actual.ends_with(last) {
        return false;
    }
    let mut rest = &actual[first.len()..actual.len() - last.len()];
    for part in &parts[1..parts.len() - 1] {
        match rest.find(part) {
            Some(k) => rest = &rest[k + part.len()..],
            None => return false,
        }
    }
    true
}

/// Whether the expected lines match the actual ones (`...` lines match any number of lines).
fn lines_match(expected: &[String], actual: &[String]) -> bool {
    match expected.split_first() {
        None => actual.is_empty(),
        Some((e, rest)) if e == "..." => (0..=actual.len()).any(|k| lines_match(rest, &actual[k..])),
        Some((e, rest)) => {
            actual.split_first().is_some_and(|(a, more)| line_matches(e, a) && lines_match(rest, more))
        }
    }
}

/// The first expected line that a greedy reading cannot match (each `...` taking the fewest
/// lines), to point at in a failure; None when every expected line matched but lines are left.
fn first_mismatch(expected: &[String], actual: &[String]) -> Option<usize> {
    let mut a = 0;
    let mut i = 0;
    while i < expected.len() {
        if expected[i] == "..." {
            let next = expected.get(i + 1)?;
            match actual[a..].iter().position(|l| line_matches(next, l)) {
                Some(k) => a += k,
                None => return Some(i + 1),
            }
        } else {
            match actual.get(a) {
                Some(l) if line_matches(&expected[i], l) => a += 1,
                _ => return Some(i),
            }
        }
        i += 1;
    }
    None
}

/// Copies `from` into `to` recursively (the scratch directory's `pipelines/`).
fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for e in std::fs::read_dir(from).unwrap().flatten() {
        let target = to.join(e.file_name());
        if e.file_type().unwrap().is_dir() {
            copy_dir(&e.path(), &target);
        } else {
            std::fs::copy(e.path(), target).unwrap();
        }
    }
}

/// Runs one block's examples in a fresh scratch directory; returns a report per mismatch.
fn run_block(examples: &[Example]) -> Vec<String> {
    let scratch = tempfile::tempdir().unwrap();
    copy_dir(&repo().join("pipelines"), &scratch.path().join("pipelines"));
    let mut failures = Vec::new();
    for ex in examples {
        let args = match &ex.action {
            Action::Qsweep(args) => args,
            Action::Write { path, append, text } => {
                use std::io::Write;
                let mut f = std::fs::OpenOptions::new()
                    .create(true)
                    .write(true)
                    .append(*append)
                    .truncate(!*append)
                    .open(scratch.path().join(path))
                    .unwrap_or_else(|e| panic!("{}: {path}: {e}", ex.at));
                f.write_all(text.as_bytes()).unwrap();
                if !ex.expected.is_empty() || ex.status != 0 {
                    failures.push(format!("{}: a here-document prints nothing and exits 0", ex.at));
                }
                continue;
            }
        };
        // stdout and stderr share one pipe (`2>&1`), so the lines come in the order a terminal
        // shows them (progress lines on stderr, the summary on stdout).
        let out = Command::new("sh")
            .arg("-c")
            .arg("exec \"$0\" \"$@\" 2>&1")
            .arg(env!("CARGO_BIN_EXE_qsweep"))
            .args(args)
            .current_dir(scratch.path())
            .env_remove("QSWEEP_CACHE")
            .env("NO_COLOR", "1")
            .output()
            .unwrap();
        let actual: Vec<String> =
            String::from_utf8_lossy(&out.stdout).lines().map(|l| l.trim_end().to_string()).collect();
        let status = out.status.code().unwrap_or(-1);
        if status != ex.status || !lines_match(&ex.expected, &actual) {
            let file = ex.at.split(':').next().unwrap_or("");
            let at = match first_mismatch(&ex.expected, &actual) {
                Some(k) => format!("{file}:{}: this expected line differs", ex.expected_lines[k]),
                None if status != ex.status => format!("{}: the exit status differs", ex.at),
                None => format!("{}: the command prints more lines than expected", ex.at),
            };
            failures.push(format!(
                "{at}\n{}: `qsweep {}`\n  exit status: expected {}, got {status}\n  expected output:\n{}\n  actual output:\n{}",
                ex.at,
                args.join(" "),
                ex.status,
                indent(&ex.expected),
                indent(&actual)
            ));
        }
    }
    failures
}

fn indent(lines: &[String]) -> String {
    lines.iter().map(|l| format!("    | {l}")).collect::<Vec<_>>().join("\n")
}

/// Every console block of README.md and the guide, with its file; a block marked [`CONTINUES`]
/// is appended to the page's previous block (one directory, one thread).
fn blocks() -> Vec<Vec<Example>> {
    let mut out: Vec<Vec<Example>> = Vec::new();
    for doc in guide_docs() {
        let text: Vec<&str> = doc.text.lines().collect();
        let mut previous: Option<usize> = None;
        for f in fences(&doc.text) {
            if f.info == "console" {
                let examples = parse_block(&doc.path, f.first_line, &f.lines);
                // The fence's own line is `first_line - 1` (1-based); the marker is the last
                // non-blank line before it.
                let before = text[..f.first_line - 2].iter().rev().find(|l| !l.trim().is_empty());
                if before.is_some_and(|l| l.trim() == CONTINUES) {
                    let k = previous.unwrap_or_else(|| {
                        panic!(
                            "{}:{}: no earlier console block to continue",
                            doc.path.display(),
                            f.first_line
                        )
                    });
                    out[k].extend(examples);
                } else {
                    out.push(examples);
                    previous = Some(out.len() - 1);
                }
            }
        }
    }
    out
}

#[test]
fn every_console_example_prints_what_it_says() {
    let blocks = blocks();
    let n: usize = blocks.iter().map(Vec::len).sum();
    assert!(n >= 5, "expected the guide's console examples, found {n}");
    // The blocks are independent (each has its own scratch directory): run them two at a time.
    let failures: Vec<String> = std::thread::scope(|s| {
        let handles: Vec<_> = blocks
            .chunks(blocks.len().div_ceil(2))
            .map(|chunk| s.spawn(move || chunk.iter().flat_map(|b| run_block(b)).collect::<Vec<_>>()))
            .collect();
        handles.into_iter().flat_map(|h| h.join().unwrap()).collect()
    });
    eprintln!("{n} console examples in {} blocks run", blocks.len());
    assert!(
        failures.is_empty(),
        "{} of {n} console examples differ:\n\n{}",
        failures.len(),
        failures.join("\n\n")
    );
}

#[test]
fn elisions_match_what_they_say() {
    let l = |v: &[&str]| v.iter().map(|s| s.to_string()).collect::<Vec<_>>();
    assert!(lines_match(&l(&["a", "...", "d"]), &l(&["a", "b", "c", "d"])));
    assert!(lines_match(&l(&["a", "...", "b"]), &l(&["a", "b"])));
    assert!(!lines_match(&l(&["a", "c"]), &l(&["a", "b"])));
    assert!(lines_match(&l(&["executed 2 in [..] s"]), &l(&["executed 2 in 0.4 s"])));
    assert!(!lines_match(&l(&["executed 2 in [..] s"]), &l(&["executed 3 in 0.4 s"])));
    assert!(line_matches("[..]", "anything"));
    assert!(!line_matches("ab[..]ba", "aba"));
    assert_eq!(first_mismatch(&l(&["a", "...", "x", "d"]), &l(&["a", "b", "c", "d"])), Some(2));
    assert_eq!(first_mismatch(&l(&["a", "q"]), &l(&["a", "b"])), Some(1));
    assert_eq!(split_words("report 'a b' --x=\"c\" ''"), vec!["report", "a b", "--x=c", ""]);
}

#[test]
fn a_here_document_writes_its_lines() {
    let l = |v: &[&str]| v.iter().map(|s| s.to_string()).collect::<Vec<_>>();
    let block = l(&[
        "$ cat > a.yaml <<'EOF'",
        "name: a",
        "$ x",
        "EOF",
        "$ cat >> a.yaml <<EOF",
        "EOF",
        "$ qsweep status a.yaml",
        "ok",
    ]);
    let ex = parse_block(Path::new("t.md"), 1, &block);
    assert_eq!(ex.len(), 3);
    assert!(
        matches!(&ex[0].action, Action::Write { path, append: false, text } if path == "a.yaml" && text == "name: a\n$ x\n")
    );
    assert!(matches!(&ex[1].action, Action::Write { append: true, text, .. } if text.is_empty()));
    assert!(matches!(&ex[2].action, Action::Qsweep(a) if a == &l(&["status", "a.yaml"])));
    assert_eq!(ex[2].expected, l(&["ok"]));
}
